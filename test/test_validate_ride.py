"""Ride and road-holding metrics in `susp validate` and the validation study (issue 15, item 4)."""
import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from susp_sim_ros.analysis import ride_recording as rr
from susp_sim_ros.analysis import validation_study
from susp_sim_ros.analysis import validation as va
from susp_sim_ros.control.ride_metrics import (
    comfort_wk_rms,
    ride_metrics,
    wk_accurate_to_hz,
    wk_response,
)
from susp_sim_ros.cli.main import main
from susp_sim_ros.io.drive import read_drive
from susp_sim_ros.io.reader import read_recording
from susp_sim_ros.io.suspension import (
    N_QUANTITIES,
    suspension_array,
    suspension_from_recording,
)
from susp_sim_ros.runtime.lockstep import run_lockstep
from susp_sim_ros.model import Model
from susp_sim_ros.model.layout import WHEELS
from susp_sim_ros.model.params import load_vehicle

BAGS = Path(__file__).resolve().parents[1] / "bags"
BUMP = BAGS / "bump_crossing_intact.mcap"


@pytest.fixture(scope="module")
def model():
    return Model("passat_b8_like", "full")


@pytest.fixture(scope="module")
def sims(tmp_path_factory, model):
    """The intact bump crossing simulated with intact and with oil-empty rear dampers, recorded."""
    d = tmp_path_factory.mktemp("ride")
    drive = read_drive(BUMP)
    out = {}
    for name, oil in (("intact", (1, 1, 1, 1)), ("rear_empty", (1, 1, 0, 0))):
        out[name] = d / f"{name}.mcap"
        run_lockstep(drive, oil=oil, model=model, out_path=out[name])
    return out


def _validate(capsys, measured, simulated):
    assert main(["validate", "--measured", str(measured), "--simulated", str(simulated), "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_oil_empty_rear_axle_raises_the_rear_dynamic_tyre_load(sims, capsys):
    ride = {k: _validate(capsys, BUMP, p)["ride"]["simulated"] for k, p in sims.items()}
    dtl = {k: r["dynamic_tyre_load_rms_rel"] for k, r in ride.items()}
    for w in ("RL", "RR"):   # less rear damping: the rear wheel load swings more over the bump
        assert dtl["rear_empty"][w] > 1.05 * dtl["intact"][w]
    for w in ("FL", "FR"):   # the front axle hardly notices
        assert dtl["rear_empty"][w] == pytest.approx(dtl["intact"][w], rel=0.05)
    travel = {k: r["suspension_travel_rms_m"] for k, r in ride.items()}
    assert travel["rear_empty"]["RL"] > 1.3 * travel["intact"]["RL"]
    # a straight level drive: the mean tyre force is the static load the relative load is taken against
    for r in ride.values():
        assert r["static_load_source"].startswith("vehicle static")
        for w in WHEELS:
            assert r["mean_tyre_load_N"][w] == pytest.approx(r["static_tyre_load_N"][w], rel=1e-3)
        assert 0.0 < r["dynamic_tyre_load_rms_rel"]["RL"] < 0.5 and sum(r["stop_contacts"].values()) == 0


def test_validate_ride_equals_ride_metrics_on_the_same_samples(sims, capsys):
    res = _validate(capsys, BUMP, sims["rear_empty"])
    ride = res["ride"]
    rec = read_recording(sims["rear_empty"])
    imu = [(t, m) for t, m in rec.decode_topic("/sim/imu/data")]
    susp = suspension_from_recording(rec)
    t = np.array([t for t, _ in imu])
    keep = (t >= ride["start_s"] * va.NS - 1) & (t <= ride["end_s"] * va.NS + 1)
    assert np.array_equal(t, susp.t_ns) and keep.sum() == ride["simulated"]["samples"]
    y = {"AZ_SF": np.array([m.linear_acceleration.z for _, m in imu])[keep],
         "ROLL_RATE": np.array([m.angular_velocity.x for _, m in imu])[keep],
         "PITCH_RATE": np.array([m.angular_velocity.y for _, m in imu])[keep]}
    for i, w in enumerate(WHEELS):
        y[f"F_Z_{w}"] = susp.values[keep, i, 6]
        y[f"DEFL_{w}"] = susp.values[keep, i, 0]
    vp = load_vehicle("passat_b8_like")
    direct = ride_metrics(y, 100.0, **rr.vehicle_ride_args(vp)).to_dict()
    sim = ride["simulated"]
    for k in ("comfort_wk_rms_m_s2", "vertical_acceleration_rms_m_s2", "pitch_acceleration_rms_rad_s2"):
        assert sim[k] == pytest.approx(direct[k], rel=1e-12)
    for k in ("dynamic_tyre_load_rms_rel", "suspension_travel_rms_m", "stop_contacts"):
        assert sim[k] == pytest.approx(direct[k], rel=1e-12)
    # the measured drive: comfort only, at its own 200 Hz, and close to the model's over the same bump
    meas = ride["measured"]
    assert set(meas) >= {"comfort_wk_rms_m_s2", "note"} and "dynamic_tyre_load_rms_rel" not in meas
    assert meas["rate_hz"] == pytest.approx(200.0, rel=0.01) and sim["rate_hz"] == 100.0
    assert meas["comfort_wk_rms_m_s2"] == pytest.approx(sim["comfort_wk_rms_m_s2"], rel=0.1)
    assert 15.0 < sim["wk_accurate_to_hz"] < 25.0 < meas["wk_accurate_to_hz"]
    assert "ride: Wk RMS measured" in _summary(capsys, BUMP, sims["rear_empty"])


def _summary(capsys, measured, simulated):
    assert main(["validate", "--measured", str(measured), "--simulated", str(simulated)]) == 0
    return capsys.readouterr().out


def test_recordings_without_suspension_give_comfort_only(capsys):
    ride = _validate(capsys, BUMP, BUMP)["ride"]   # a measured drive as the "simulation": /imu/data only
    for side in ("measured", "simulated"):
        r = ride[side]
        assert "dynamic_tyre_load_rms_rel" not in r and "suspension_travel_rms_m" not in r
        assert "suspension" in r["note"]
    assert ride["measured"]["comfort_wk_rms_m_s2"] == ride["simulated"]["comfort_wk_rms_m_s2"] > 0.1
    assert "comfort only" in _summary(capsys, BUMP, BUMP)


def test_comfort_of_a_jittered_sine_is_its_wk_weighted_rms():
    """5 Hz, 1 m/s^2 on top of gravity, sampled at 200 Hz with 50 us jitter: RMS = |Wk(5 Hz)| / sqrt 2."""
    rng = np.random.default_rng(3)
    t = (np.arange(4000) * 5e6 + rng.uniform(-5e4, 5e4, 4000)).astype(np.int64) + 10**9
    acc = np.zeros((t.size, 3))
    acc[:, 2] = 9.81 + np.sin(2 * np.pi * 5.0 * t / 1e9)
    r = rr.comfort_of_series(t, acc, (int(t[0]), int(t[-1])), gravity=9.81, what="sine")
    assert r["comfort_wk_rms_m_s2"] == pytest.approx(wk_response([5.0])[0] / np.sqrt(2), rel=0.01)
    assert r["rate_hz"] == pytest.approx(200.0, rel=1e-3)
    cut = rr.comfort_of_series(t, acc, (int(t[400]), int(t[-1])), gravity=9.81, what="sine")  # a span cuts
    assert cut["samples"] < r["samples"] and cut["start_s"] >= t[400] / 1e9


def test_uniform_recording_is_taken_sample_for_sample():
    t = 10**9 + np.arange(500, dtype=np.int64) * 10_000_000
    a = np.random.default_rng(1).normal(9.81, 0.3, 500)
    grid, v, rate = rr.on_uniform_grid(t, a, (int(t[0]), int(t[-1])), "x")
    assert rate == 100.0 and np.array_equal(grid, t) and np.array_equal(v, a)
    assert rr.comfort_of_series(t, np.column_stack([a, a, a]), (int(t[0]), int(t[-1])), gravity=9.81,
                                what="x")["comfort_wk_rms_m_s2"] == comfort_wk_rms(a, 100.0, 9.81)


def test_without_a_vehicle_the_mean_tyre_force_is_the_static_load():
    n = 300
    t = 10**9 + np.arange(n, dtype=np.int64) * 10_000_000
    imu = np.zeros((n, 3))
    acc = np.tile([0.0, 0.0, 9.81], (n, 1))
    susp = np.zeros((n, 4, N_QUANTITIES))
    susp[:, :, 6] = [4000.0, 4000.0, 3000.0, 3000.0]
    susp[:, 2, 6] += 300.0 * np.sin(np.arange(n) * 0.3)     # RL: +-10 % swing -> RMS 0.1 / sqrt 2
    r = rr.ride_of_series(t, imu, acc, t, susp, (int(t[0]), int(t[-1])), gravity=9.81, static_loads=None,
                          bump_travel=[0.08] * 4, rebound_travel=[0.08] * 4)
    assert r["static_load_source"].startswith("mean tyre force")
    assert r["dynamic_tyre_load_rms_rel"]["FL"] == 0.0
    assert r["dynamic_tyre_load_rms_rel"]["RL"] == pytest.approx(0.1 / np.sqrt(2), rel=0.02)
    assert r["comfort_wk_rms_m_s2"] == 0.0


def test_wk_accuracy_grows_with_the_sample_rate():
    acc = [wk_accurate_to_hz(fs) for fs in (100.0, 200.0, 500.0)]
    assert 15.0 < acc[0] < 25.0 and acc[0] < acc[1] < acc[2] and acc[2] > 60.0


@settings(max_examples=60, deadline=None)
@given(st.lists(st.integers(0, 40), max_size=3), st.integers(0, 3),
       st.lists(st.floats(allow_nan=True, allow_infinity=True), max_size=45))
def test_suspension_parser_accepts_only_the_layout(sizes, offset, data):
    msg = SimpleNamespace(layout=SimpleNamespace(dim=[SimpleNamespace(size=s) for s in sizes], data_offset=offset),
                          data=data)
    good = sizes == [4, N_QUANTITIES] and len(data) - offset == 4 * N_QUANTITIES and np.all(np.isfinite(data[offset:]))
    if good:
        assert np.array_equal(suspension_array(msg), np.reshape(data[offset:], (4, N_QUANTITIES)))
    else:
        with pytest.raises(ValueError):
            suspension_array(msg)


def test_study_reports_ride_per_drive_as_validate_does(sims, capsys, model):
    drive = read_drive(BUMP)
    d = validation_study.simulate_and_validate(BUMP, drive, ["full"], {("passat_b8_like", "full"): model})
    ride = d.as_dict()["ride"]
    pair = _validate(capsys, BUMP, sims["intact"])["ride"]
    assert ride["simulated"]["full"]["comfort_wk_rms_m_s2"] == pytest.approx(
        pair["simulated"]["comfort_wk_rms_m_s2"], rel=1e-12)
    assert ride["simulated"]["full"]["dynamic_tyre_load_rms_rel"] == pytest.approx(
        pair["simulated"]["dynamic_tyre_load_rms_rel"], rel=1e-12)
    assert ride["measured"]["comfort_wk_rms_m_s2"] == pytest.approx(pair["measured"]["comfort_wk_rms_m_s2"], rel=1e-12)
