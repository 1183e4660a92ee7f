"""A physics term at zero gain is skipped per block of vehicles (docs/kernel_design.md): every output
is the one of the kernel that runs it, a vehicle's numbers do not depend on its neighbours' terms, and
a gain must be one of the term's parameters."""
import numpy as np
import pytest

from susp_sim_ros.analysis.discrepancy.finder import extended_model
from susp_sim_ros.model.layout import N_U, U_INDEX
from susp_sim_ros.model.terms import PhysicsTerm, get_term
from susp_sim_ros.model.vehicle import simulate_batch


@pytest.fixture(scope="module")
def model():
    return extended_model("passat_b8_like", "full")


def _inputs(n=1500):
    U = np.zeros((n, N_U))
    k = np.arange(n)
    U[:, U_INDEX["V"]] = 3.0
    U[:, U_INDEX["SWA"]] = 0.5 * np.sin(k * 0.004)
    U[:, U_INDEX["AX"]] = 0.5 * np.cos(k * 0.002)
    return U


def _with_gain(model, P, name, value):
    k = [t.name for t in model.terms].index(name)
    t = model.terms[k]
    out = P.copy()
    for g in t.gains:
        j = model.layout.param_offsets[k] + 4 * t.param_index(g)
        out[j:j + 4] = value
    return out


def test_every_candidate_term_declares_the_gains_that_switch_it_off():
    for name in ("friction_amplitude", "extra_viscous_damping", "damper_gas_preload", "unlisted_force"):
        assert get_term(name).gains, name


def test_a_vehicle_gives_the_same_bits_beside_a_vehicle_whose_terms_act(model):
    """Vehicle 0 has every candidate term at zero: alone its block skips them, beside vehicle 1 (viscous
    damping and a learned constant acting) the block runs them at zero gain. Same outputs to the bit."""
    P0 = model.params()
    P1 = _with_gain(model, _with_gain(model, P0, "extra_viscous_damping", 300.0), "damper_gas_preload", 40.0)
    U = _inputs()
    alone = simulate_batch(model, P0[None], U, dt=0.001).values[0]
    both = simulate_batch(model, np.stack([P0, P1]), U, dt=0.001).values
    assert np.array_equal(alone, both[0])
    assert not np.allclose(both[0], both[1])  # the acting terms do act


def test_a_term_at_zero_gain_gives_the_outputs_of_the_model_without_it(model):
    """Skipping is exact: the extended model with its candidate terms at zero gives the base model's
    outputs (the same kernel arithmetic in the same order)."""
    from susp_sim_ros.model.vehicle import Model
    base = Model("passat_b8_like", "full")
    U = _inputs()
    a = simulate_batch(base, base.params()[None], U, dt=0.001).values[0]
    b = simulate_batch(model, model.params()[None], U, dt=0.001).values[0]
    assert np.array_equal(a, b)


def test_a_gain_must_be_a_parameter_of_the_term():
    t = get_term("extra_viscous_damping")
    with pytest.raises(KeyError, match="no parameter 'gain'"):
        PhysicsTerm(t.name, t.component, t.meaning, t.params, t.n_states, t.force, t.update, gains=("gain",))
