"""The model as named stages: the linear model is the kernel's right-hand side linearised (it agrees with
the matrices derived by hand), ``body_accelerations`` is pure, and every layout slot has its SI unit."""
import numpy as np
import pytest

from susp_sim_ros.model import Model
from susp_sim_ros.model import _kernel_template as K
from susp_sim_ros.model import layout as L
from susp_sim_ros.model.linear import linearise, mass_stiffness, modes


def _hand_derived(vp):
    """The mass and stiffness matrices as linear.py derived them by hand before it linearised the
    kernel (kept here as the independent reference): deflection d = D q, springs and anti-roll bars on
    d, tyres on the wheels, gravity destabilising roll and pitch about their centres."""
    x = np.array([vp.a, vp.a, -vp.b, -vp.b])
    tf, tr = vp.track
    y = np.array([tf / 2, -tf / 2, tr / 2, -tr / 2])
    k = np.array([vp.wheel_rate[0]] * 2 + [vp.wheel_rate[1]] * 2)
    mu = np.array([vp.unsprung_mass[0]] * 2 + [vp.unsprung_mass[1]] * 2)
    M = np.diag([vp.sprung_mass, vp.roll_inertia, vp.pitch_inertia, *mu])
    D = np.zeros((4, 7))
    D[:, 0] = -1.0
    D[:, 1] = -y
    D[:, 2] = x
    D[:, 3:] = np.eye(4)
    Km = D.T @ np.diag(k) @ D
    for axle, (lft, rgt) in enumerate(((0, 1), (2, 3))):
        e = D[lft] - D[rgt]
        Km += vp.arb_rate[axle] * np.outer(e, e)
    Km[3:, 3:] += vp.tyre_stiffness * np.eye(4)
    g, ms = vp.gravity, vp.sprung_mass
    Km[1, 1] -= ms * g * (vp.cg_height - 0.5 * sum(vp.roll_centre_height))
    Km[2, 2] -= ms * g * (vp.cg_height - vp.pitch_centre_height)
    return M, Km, D


def _vehicles():
    vp = Model().vehicle
    # an asymmetric one too: heave and pitch coupled (a*k_f != b*k_r), different bars and roll centres
    return [vp, vp.replace(wheel_rate=(31000.0, 24000.0), arb_rate=(9000.0, 2000.0),
                           roll_centre_height=(0.05, 0.12), unsprung_mass=(48.0, 41.0))]


@pytest.mark.parametrize("which", [0, 1])
def test_linearised_rhs_equals_hand_derived_matrices(which):
    vp = _vehicles()[which]
    M_ref, K_ref, _ = _hand_derived(vp)
    M, Kl = mass_stiffness(vp)
    np.testing.assert_array_equal(M, M_ref)
    np.testing.assert_allclose(Kl, K_ref, rtol=0, atol=1e-12 * np.abs(K_ref).max())  # measured 2e-16
    w2_ref = np.sort(np.linalg.eigvals(np.linalg.solve(M_ref, K_ref)).real)
    np.testing.assert_allclose(modes(vp).freq_hz, np.sqrt(w2_ref) / (2 * np.pi), rtol=1e-9)  # measured 4e-15


def test_linearised_damping_is_tyres_and_dampers():
    """C = D^T diag(c) D + c_t on the wheels, c the dampers' slope at zero velocity. The vehicle's own
    hydraulic curves are flat for |v| <= 1 mm/s (the friction holds there: model-spec 1), so at rest
    only the tyres damp; with linear curves of different slope per corner, C has the dampers too."""
    m = Model()
    vp = m.vehicle
    _, _, D = _hand_derived(vp)
    tyres = np.zeros((7, 7))
    tyres[3:, 3:] = vp.tyre_damping * np.eye(4)
    np.testing.assert_allclose(linearise(vp).C, tyres, rtol=0, atol=1e-6 * vp.tyre_damping)
    P = m.params()
    c = np.array([2100.0, 2300.0, 1700.0, 1500.0])  # N*s/m
    for i in range(4):
        P[L.P_H_INTACT + i * L.N_GRID:L.P_H_INTACT + (i + 1) * L.N_GRID] = c[i] * L.DAMPER_GRID
    C = linearise(vp, P).C
    C_ref = D.T @ np.diag(c) @ D + tyres
    np.testing.assert_allclose(C, C_ref, rtol=0, atol=1e-6 * np.abs(C_ref).max())
    np.testing.assert_allclose(linearise(vp, P).K, linearise(vp).K, rtol=0, atol=0)  # damping only


def test_body_accelerations_is_pure():
    """The right-hand side stage writes its acceleration rows of the scratch and nothing else."""
    m = Model()
    rng = np.random.default_rng(3)
    P = np.ascontiguousarray(m.params()[:L.N_P_FIXED].reshape(-1, 1))
    DV = np.zeros((K.N_DERIVED, 1))
    K.derive(P[:, 0], DV[:, 0])
    S = rng.normal(0.0, 0.01, (L.N_S_FIXED, 1))
    W = rng.normal(0.0, 100.0, (K.N_SCRATCH, 1))
    P0, DV0, S0, W0 = P.copy(), DV.copy(), S.copy(), W.copy()
    K.body_accelerations(P, DV, S, W, 1)
    written = [K._W_ZDD, K._W_AY, K._W_PHIDD, K._W_THDD, K._W_VYD, K._W_RD, *range(K._W_ZWDD, K._W_ZWDD + 4)]
    keep = np.setdiff1d(np.arange(K.N_SCRATCH), written)
    np.testing.assert_array_equal(P, P0)
    np.testing.assert_array_equal(DV, DV0)
    np.testing.assert_array_equal(S, S0)
    np.testing.assert_array_equal(W[keep], W0[keep])
    # heave: the four suspension forces over the sprung mass; wheel: tyre minus suspension force
    fs = W0[K._W_FS:K._W_FS + 4, 0]
    assert W[K._W_ZDD, 0] == pytest.approx(fs.sum() / m.vehicle.sprung_mass, rel=1e-12)
    wf = W0[K._W_WF:K._W_WF + 4, 0]
    mu = P[L.P_INDEX["M_U"]:L.P_INDEX["M_U"] + 4, 0]
    np.testing.assert_allclose(W[K._W_ZWDD:K._W_ZWDD + 4, 0], (wf - fs) / mu, rtol=1e-12)


_SI = {"1", "m", "rad", "s", "kg", "N", "m/s", "rad/s", "m/s^2", "kg*m^2", "N/m", "N*s/m", "N/rad", "1/N"}


@pytest.mark.parametrize("slots,n", [(L.P_SLOTS, L.N_P_FIXED), (L.S_SLOTS, L.N_S_FIXED), (L.U_SLOTS, L.N_U),
                                     (L.Y_SLOTS, L.N_Y), (L.C_SLOTS, L.N_CTX)])
def test_every_layout_slot_has_an_si_unit(slots, n):
    assert all(isinstance(s.unit, str) and s.unit in _SI for s in slots), [s for s in slots if s.unit not in _SI]
    # the slots tile the vector: every entry has exactly one slot, hence one unit
    assert slots[0].index == 0 and slots[-1].index + slots[-1].size == n
    assert all(a.index + a.size == b.index for a, b in zip(slots, slots[1:]))


def test_units_follow_the_named_indices():
    assert L.slot_at(L.P_SLOTS, L.P_INDEX["K_S"] + 3).unit == "N/m"
    assert L.slot_at(L.P_SLOTS, L.P_H_HARD + 7).unit == "N"
    assert L.slot_at(L.P_SLOTS, L.P_VALVE_TAU).unit == "s"
    assert L.S_UNITS["PHID"] == "rad/s" and L.U_UNITS["SWA"] == "rad" and L.C_UNITS["DT"] == "s"
    assert [L.output_unit(x) for x in ("PITCH_RATE", "AZ_SF", "DEFL_RL", "F_DAMPER_FR")] == [
        "rad/s", "m/s^2", "m", "N"]
    assert set(L.OUTPUT_UNITS) == {s.name for s in L.Y_SLOTS}


def test_term_parameters_append_slots_with_their_units():
    """With a variant's terms, P is the fixed slots followed by one slot per term parameter."""
    from susp_sim_ros.model.extra_terms import EXTRA_VISCOUS_DAMPING
    from susp_sim_ros.model.terms import BUILTIN_TERMS
    terms = BUILTIN_TERMS + (EXTRA_VISCOUS_DAMPING,)
    slots = L.P_SLOTS + L.term_param_slots(terms)
    assert all(a.index + a.size == b.index for a, b in zip(slots, slots[1:]))
    assert slots[-1].index + slots[-1].size == L.KernelLayout.for_terms(terms).n_p
    assert [(s.name, s.unit) for s in slots[-7:]] == [
        ("axle_friction.level", "N"), ("axle_friction.sigma", "N/m"), ("damper_friction.level", "N"),
        ("damper_friction.sigma", "N/m"), ("extra_viscous_damping.c", "N s/m"), ("extra_viscous_damping.n", "1"),
        ("extra_viscous_damping.v_ref", "m/s")]
