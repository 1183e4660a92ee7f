"""Physics of the five-mass model: equilibrium, symmetry, energy, natural frequencies, reference values.

Reference values: model-spec section 5 (an independent implementation of the same specification).
"""
import numpy as np
import pytest

from susp_sim_ros.model import Model, RoadProfile, Stepper, cosine_bump, make_inputs, simulate
from susp_sim_ros.model.layout import OUTPUT_LABELS, P_H_EMPTY, N_GRID
from susp_sim_ros.model.linear import mechanical_energy, modes, state_from_q
from susp_sim_ros.model.maneuvers import bump_crossing, vehicle_state

DT = 1e-3


def test_static_equilibrium_no_drift(model_full):
    for speed in (0.0, 50 / 3.6):
        res = simulate(model_full, make_inputs(5000, speed, 0.0), dt=DT, road=RoadProfile.flat())
        for label in ("HEAVE", "ROLL", "PITCH", "ROLL_RATE", "PITCH_RATE", "YAW_RATE", "VEL_Y"):
            assert np.max(np.abs(res[label])) == 0.0, (speed, label)
        np.testing.assert_allclose(res["AZ_SF"], model_full.vehicle.gravity, rtol=0, atol=1e-12)
        fz = np.stack([res[f"F_Z_{w}"] for w in ("FL", "FR", "RL", "RR")], axis=1)
        np.testing.assert_allclose(fz[-1].sum(), model_full.vehicle.total_mass * model_full.vehicle.gravity,
                                   rtol=1e-12)


def _mirror_pairs():
    pairs = []
    for lab in OUTPUT_LABELS:
        if lab.endswith(("_FL", "_RL")):
            other = lab[:-2] + ("FR" if lab.endswith("FL") else "RR")
            pairs.append((lab, other, 1.0))
    return pairs


def test_left_right_mirror_symmetry(model_full):
    """Mirrored inputs (left track bump -> right track, steering negated) give mirrored outputs."""
    road = cosine_bump(0.05, 0.5, 2.0, both_tracks=False)
    n = 6000
    t = DT * np.arange(n)
    steer = 0.4 * np.sin(2 * np.pi * 0.7 * t)
    a = simulate(model_full, make_inputs(n, 8.0, steer), dt=DT, road=road, oil=(1, 0.3, 0.6, 0.0))
    b = simulate(model_full, make_inputs(n, 8.0, -steer), dt=DT, road=road.mirrored(), oil=(0.3, 1, 0.0, 0.6))
    assert np.max(np.abs(a["ROLL_RATE"])) > 0.05  # the case excites roll
    tol = dict(rtol=1e-9, atol=1e-12)
    for lab in ("ROLL_RATE", "YAW_RATE", "ROLL", "YAW", "POS_Y", "VEL_Y", "AY_SF"):
        np.testing.assert_allclose(a[lab], -b[lab], **tol, err_msg=lab)
    for lab in ("PITCH_RATE", "PITCH", "HEAVE", "AZ_SF", "AX_SF", "POS_X"):
        np.testing.assert_allclose(a[lab], b[lab], **tol, err_msg=lab)
    for l_lab, r_lab, _ in _mirror_pairs():
        sign = -1.0 if l_lab.startswith("F_Y") else 1.0
        np.testing.assert_allclose(a[l_lab], sign * b[r_lab], **tol, err_msg=l_lab)


def _energy_trace(model, oil, n_after):
    """Total energy (elastic + kinetic + Dahl storage) every 10 steps once the road is flat again."""
    man = bump_crossing(wheelbase=model.vehicle.wheelbase)
    st = Stepper(model, dt=DT, road=man.road, oil=oil)
    t_flat = (man.road.s[-1] + model.vehicle.wheelbase) / man.speed + 0.05
    st.advance(int(t_flat / DT), man.speed, 0.0)
    e = []
    for _ in range(n_after):
        st.advance(10, man.speed, 0.0)
        e.append(mechanical_energy(model.vehicle, st.P, st.S) + model.stored_energy(st.P, st.S))
    return np.array(e)


@pytest.mark.parametrize("state", ["intact", "rear_empty"])
def test_energy_never_rises_after_bump(model_full, state):
    e = _energy_trace(model_full, vehicle_state(state), 400)
    assert e[-1] < 0.05 * e[0], "oscillation must decay"
    rises = np.diff(e)
    # semi-implicit Euler carries an O(dt) modified energy: allow rises at round-off level only
    assert np.max(rises) <= 1e-6 * e[0], f"energy rose by {np.max(rises):.3g} J (E0 {e[0]:.3g} J)"


def test_energy_conserved_without_dissipation():
    """Dampers, friction and tyre damping off: energy stays constant (checks the equations are
    consistent with the potential of the linear model)."""
    vp = Model().vehicle.replace(tyre_damping=0.0, axle_friction=(0.0, 0.0))
    m = Model(vp, "dahl_only")
    P = m.params()
    P[P_H_EMPTY - 4 * N_GRID:P_H_EMPTY + 4 * N_GRID] = 0.0
    P[m.term_param_slice("damper_friction", "level")] = 0.0
    S = state_from_q(m.initial_state(), np.array([0.01, 0.004, -0.003, 0, 0.002, 0, 0]))
    e0 = mechanical_energy(vp, P, S)
    res = simulate(m, make_inputs(3000, 0.0, 0.0), dt=DT, road=RoadProfile.flat(), P=P, S=S)
    assert res.ok
    e1 = mechanical_energy(vp, P, res.state)
    assert abs(e1 - e0) < 0.01 * e0


@pytest.mark.parametrize("coord,name,ref_hz", [(0, "bounce", 1.251), (2, "pitch", 1.492), (1, "roll", 2.125)])
def test_natural_frequencies_match_linear_model(coord, name, ref_hz):
    """Free vibration started in a mode shape of the linear model oscillates at its frequency."""
    vp = Model().vehicle.replace(tyre_damping=0.0, axle_friction=(0.0, 0.0))
    m = Model(vp, "dahl_only")
    P = m.params()
    P[P_H_EMPTY - 4 * N_GRID:P_H_EMPTY + 4 * N_GRID] = 0.0
    P[m.term_param_slice("damper_friction", "level")] = 0.0
    f_lin, shape = modes(vp).body_mode(coord)
    np.testing.assert_allclose(f_lin, ref_hz, rtol=0.005, err_msg="analytic value vs model-spec 5")
    q0 = 0.01 * shape / np.max(np.abs(shape[:3]))
    res = simulate(m, make_inputs(8000, 0.0, 0.0), dt=DT, road=RoadProfile.flat(), P=P,
                   S=state_from_q(m.initial_state(), q0), outputs=["HEAVE", "ROLL", "PITCH"])
    sig = res.y[:, coord]
    crossings = np.nonzero(np.diff(np.signbit(sig)))[0]
    t_cross = res.t[crossings] - sig[crossings] * DT / (sig[crossings + 1] - sig[crossings])
    f_sim = 0.5 * (len(t_cross) - 1) / (t_cross[-1] - t_cross[0])
    # semi-implicit Euler shifts frequencies by ~(w dt)^2/24 = 4e-6: 0.2 % is the resolution of the count
    np.testing.assert_allclose(f_sim, f_lin, rtol=0.002, err_msg=name)


def test_steady_state_cornering_reference_values(model_full):
    vp = model_full.vehicle
    v = 50 / 3.6
    small = simulate(model_full, make_inputs(15000, v, 0.01 * vp.steering_ratio), dt=DT, road=RoadProfile.flat())
    np.testing.assert_allclose(small["YAW_RATE"][-1] / 0.01, 4.25, rtol=0.01)
    big = simulate(model_full, make_inputs(15000, v, np.radians(60)), dt=DT, road=RoadProfile.flat())
    np.testing.assert_allclose(np.degrees(big["YAW_RATE"][-1]), 16.2, rtol=0.02)
    np.testing.assert_allclose(v * big["YAW_RATE"][-1], 3.90, rtol=0.02)  # kinematic a_y = v r
    roll = np.degrees(big["ROLL"][-1])
    assert roll > 0, "left steer rolls the body left side up (REP-103)"
    np.testing.assert_allclose(roll, 1.58, rtol=0.10)  # ours 1.69: tyre compliance in series, see README
    assert big["AY_SF"][-1] > 0 and big["YAW_RATE"][-1] > 0


def test_bump_crossing_reference_values(models):
    out = {}
    for var in ("full", "dahl_only"):
        for state in ("intact", "rear_empty"):
            man = bump_crossing(wheelbase=models[var].vehicle.wheelbase)
            r = simulate(models[var], man.to_inputs(DT), dt=DT, road=man.road, oil=vehicle_state(state))
            q = np.degrees(r["PITCH_RATE"])
            first = q[np.argmax(np.abs(q) > 0.05)]
            t_leave = (man.road.s[-1] + models[var].vehicle.wheelbase) / man.speed
            above = np.nonzero(np.abs(q) > 0.3)[0]
            out[var, state] = (np.sign(first), np.max(np.abs(q)), r.t[above[-1]] - t_leave)
    assert out["full", "intact"][0] < 0, "front rises first: nose up = negative pitch rate"
    np.testing.assert_allclose(out["full", "intact"][1], 8.7, rtol=0.05)
    np.testing.assert_allclose(out["full", "rear_empty"][1], 9.0, rtol=0.05)
    np.testing.assert_allclose(out["full", "intact"][2], 0.6, atol=0.15)
    np.testing.assert_allclose(out["full", "rear_empty"][2], 1.6, rtol=0.25)
    np.testing.assert_allclose(out["dahl_only", "rear_empty"][2], 2.5, rtol=0.15)
