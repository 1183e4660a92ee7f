"""The public API changes none of its inputs, and the discrepancy finder is an estimator that takes data
(``fit(drives)``, ``score(drives)``, ``predict(drive)`` with paths, TestDrive or DriveCase objects)."""
from __future__ import annotations

import copy
import dataclasses
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from susp_sim_ros.analysis.discrepancy import DiscrepancyFinder
from susp_sim_ros.analysis.discrepancy.data import as_cases
from susp_sim_ros.io.drive import read_drive
from susp_sim_ros.runtime.lockstep import maneuver_drive, run_lockstep
from susp_sim_ros.model import Response, simulate, simulate_batch
from susp_sim_ros.model.layout import N_U, S_INDEX, U_INDEX
from susp_sim_ros.model.maneuvers import bump_crossing, vehicle_state

DT = 0.001
N_STEPS = 400
BAG = Path(__file__).resolve().parents[1] / "bags" / "bump_crossing_rear_empty.mcap"

oil = st.tuples(*[st.floats(0.0, 1.0)] * 4)
offset = st.floats(-0.02, 0.02)   # initial body heave [m] / wheel-road heights [m]


def _snapshot(*arrays):
    return [np.array(a, copy=True) for a in arrays]


def _same(before, arrays):
    return all(np.array_equal(b, a) and b.dtype == a.dtype for b, a in zip(before, arrays))


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(oil=oil, z0=offset, zr=offset)
def test_simulate_changes_none_of_its_inputs(model_full, oil, z0, zr):
    U = np.zeros((N_STEPS, N_U))
    U[:, U_INDEX["ZR_IN"]:U_INDEX["ZR_IN"] + 4] = zr  # four-poster road (the state takes the first row)
    P = model_full.params(oil)
    S = model_full.initial_state()
    S[S_INDEX["Z"]] = z0
    before = _snapshot(U, P, S)
    r1 = simulate(model_full, U, dt=DT, P=P, S=S)
    assert _same(before, (U, P, S))
    r2 = simulate(model_full, U, dt=DT, P=P, S=S)           # so the same call gives the same answer
    np.testing.assert_array_equal(r1.values, r2.values)
    np.testing.assert_array_equal(r1.state, r2.state)
    assert not np.shares_memory(r1.state, S)
    if z0 != 0.0:                                          # the state moved: the result holds it, not S
        assert not np.array_equal(r1.state, S)


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(oils=st.lists(oil, min_size=1, max_size=4), z0=offset)
def test_simulate_batch_changes_none_of_its_inputs(model_full, oils, z0):
    man = bump_crossing()
    U = man.to_inputs(DT)[:N_STEPS][None]
    P = np.stack([model_full.params(o) for o in oils])
    S = np.tile(model_full.initial_state(), (len(oils), 1))
    S[:, S_INDEX["Z"]] = z0
    u_row = np.zeros(len(oils), np.int64)
    before = _snapshot(U, P, S, u_row)
    r = simulate_batch(model_full, P, U, dt=DT, roads=[man.road], S=S, u_row=u_row)
    assert _same(before, (U, P, S, u_row))
    again = simulate_batch(model_full, P, U, dt=DT, roads=[man.road], S=S, u_row=u_row)
    np.testing.assert_array_equal(r.values, again.values)
    for b in range(len(oils)):  # and each vehicle is its single run from the same (unchanged) start
        one = simulate(model_full, U[0], dt=DT, road=man.road, P=P[b], S=S[b])
        np.testing.assert_array_equal(r.values[b], one.values)


def test_run_lockstep_changes_nothing_of_the_drive(model_full):
    drive = maneuver_drive(bump_crossing(), oil=vehicle_state("front_empty"))
    before = copy.deepcopy(drive)
    r = run_lockstep(drive, model=model_full)
    assert r.ok
    assert drive.metadata == before.metadata and drive.extra == before.extra
    for name in ("speed", "steering"):
        a, b = getattr(drive, name), getattr(before, name)
        assert np.array_equal(a.t_ns, b.t_ns) and np.array_equal(a.values, b.values)
    assert np.array_equal(drive.road.s, before.road.s) and np.array_equal(drive.road.zl, before.road.zl)


# -- the finder as an estimator --------------------------------------------------------------------------
QUICK = {"candidates": ["damper_friction_oil", "friction_amplitude"], "calibrate": False, "heldout": False}


@pytest.fixture(scope="module")
def fitted():
    return DiscrepancyFinder(**QUICK).fit([read_drive(BAG)])


def test_finder_fits_read_drives_as_it_fits_paths(fitted):
    by_path = DiscrepancyFinder(**QUICK).fit([BAG])
    def terms(f):  # the evidence names the drive (a read drive has no file name), the figures agree
        return [{k: t[k] for k in ("name", "where", "params", "ci95")} for t in f.report()["terms"]]
    assert terms(by_path) == terms(fitted) and terms(fitted)
    assert by_path.score() == fitted.score()
    # the bundled rear-empty bump drive has the oil-dependent friction amplitude the base model lacks
    assert fitted.report()["verdict"] == "missing_physics"


def test_predict_and_score_take_new_data(fitted):
    pred = fitted.predict(BAG)
    assert isinstance(pred, Response) and pred.units["pitch_rate"] == "rad/s"
    # the same drive as new data: the same prediction as the fitted drive's, signal by signal
    seen = fitted.predict(0)
    assert set(seen.labels) <= set(pred.labels)
    for label in seen.labels:
        np.testing.assert_allclose(pred[label], seen[label], rtol=0, atol=1e-12)
    np.testing.assert_array_equal(fitted.predict(fitted.cases_[0].name).values, seen.values)
    # the fitted model explains most of the base model's pitch-rate residual on this drive
    s = fitted.score([BAG])
    assert 0.5 < s <= 1.0
    assert fitted.score([read_drive(BAG), str(BAG)]) == pytest.approx(s, rel=1e-12)
    # the prediction follows the measurement far closer than its spread
    drive = read_drive(BAG)
    meas = np.interp(pred.t_ns, drive.imu.t_ns, drive.imu.gyro[:, 1])
    assert np.sqrt(np.mean((pred["pitch_rate"] - meas) ** 2)) < 0.2 * np.std(meas)


def test_fit_and_predict_leave_given_cases_as_they_were(fitted):
    cases = as_cases([BAG], wheelbase=fitted.model_.vehicle.wheelbase)
    before = dataclasses.replace(cases[0])
    DiscrepancyFinder(**QUICK).fit(cases)
    fitted.predict(cases[0])
    c = cases[0]
    assert c.quiet is None and c.signals == before.signals and c.name == before.name
    assert np.array_equal(c.y_meas, before.y_meas)


def test_predict_and_score_before_fit_raise():
    with pytest.raises(RuntimeError, match="fit"):
        DiscrepancyFinder().predict(BAG)
    with pytest.raises(RuntimeError, match="fit"):
        DiscrepancyFinder().score([BAG])
