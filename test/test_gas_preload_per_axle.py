"""``damper_gas_preload`` per axle (``candidates.gas_preload_per_axle`` in config/discrepancy.yaml): a preload
change and a gas rate of its own on each axle. With equal values on both axles it is the one-pair candidate to
the bit; with unequal ones each axle's corners carry their own, and the written variant carries what was
simulated."""
import numpy as np
import pytest

from susp_sim_ros.analysis.discrepancy import candidates
from susp_sim_ros.analysis.discrepancy.candidates import gas_preload_candidate
from susp_sim_ros.analysis.discrepancy.finder import extended_model
from susp_sim_ros.model.layout import N_U, U_INDEX
from susp_sim_ros.model.params import load_settings
from susp_sim_ros.model.vehicle import simulate_batch


@pytest.fixture(scope="module")
def model():
    return extended_model("passat_b8_like", "full")


def _rows(model, cand, x):
    P0 = model.params()[None]
    P = P0.copy()
    cand.apply(P, P0, np.asarray(x, float), model)
    return P


def test_the_shipped_candidate_follows_the_switch():
    per_axle = load_settings("discrepancy.yaml")["candidates.gas_preload_per_axle"]
    assert candidates.BY_NAME["damper_gas_preload"].n_params == (4 if per_axle else 2)


def test_equal_axles_are_the_one_pair_candidate_to_the_bit(model):
    one, two = gas_preload_candidate(False), gas_preload_candidate(True)
    assert two.n_params == 4 and two.axle_of == ("front", "front", "rear", "rear")
    assert [p.name for p in two.params] == ["f0_front", "k_front", "f0_rear", "k_rear"]
    np.testing.assert_array_equal(_rows(model, one, [120.0, 3000.0]),
                                  _rows(model, two, [120.0, 3000.0, 120.0, 3000.0]))


def test_each_axle_carries_its_own_gas_force_and_the_variant_writes_it(model):
    """A front charge only (260 N, 3750 N/m; rear none): the front corners carry it, the rear ones stay at zero
    effect, the written term says so per axle, and on a drive the pitch differs from that of the same charge
    on all four corners (what one pair for the car must assume)."""
    two = gas_preload_candidate(True)
    x = [260.0, 3750.0, 0.0, 0.0]
    P = _rows(model, two, x)[0]
    sl = model.term_param_slice
    np.testing.assert_array_equal(P[sl("damper_gas_preload", "f0")], [260.0, 260.0, 0.0, 0.0])
    np.testing.assert_array_equal(P[sl("damper_gas_preload", "k")], [3750.0, 3750.0, 0.0, 0.0])
    written = two.variant_term(np.asarray(x), model.vehicle)["params"]
    assert written == {"f0": {"front": 260.0, "rear": 0.0}, "k": {"front": 3750.0, "rear": 0.0}}
    n = 3000
    U = np.zeros((n, N_U))
    U[:, U_INDEX["V"]] = 3.0
    U[:, U_INDEX["AX"]] = 1.5 * np.sin(np.arange(n) * 0.003)   # pitching the body: the axles deflect apart
    rows = np.stack([P, _rows(model, gas_preload_candidate(False), [260.0, 3750.0])[0], model.params()])
    front_only, all_four, none = simulate_batch(model, rows, U, dt=0.001).values
    assert not np.allclose(front_only, none) and not np.allclose(front_only, all_four)
