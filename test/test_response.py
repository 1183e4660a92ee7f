"""The one result type: labels in the interface's spelling, SI units, the same numbers as the kernel's
output columns, and exports that keep every value and unit."""
from __future__ import annotations

import csv
import io

import numpy as np
import pytest

from susp_sim_ros.io import messages as M
from susp_sim_ros.runtime.lockstep import LockstepRun, maneuver_drive, run_lockstep
from susp_sim_ros.model import Response, simulate, simulate_batch
from susp_sim_ros.model.layout import OUTPUT_LABELS, OUTPUT_UNITS, WHEELS
from susp_sim_ros.model.maneuvers import bump_crossing, sine_steer, vehicle_state
from susp_sim_ros.model.response import SIGNAL_NAMES, SIGNAL_UNITS, output_label, signal_name

DT = 0.001


@pytest.fixture(scope="module")
def bump_run(model_full):
    man = bump_crossing()
    return man, simulate(model_full, man.to_inputs(DT), dt=DT, road=man.road, oil=vehicle_state("rear_empty"))


def test_signal_names_are_the_interface_spelling_one_per_output():
    assert len(set(SIGNAL_NAMES)) == len(OUTPUT_LABELS)
    # the IMU signals as interface.md's SIGNAL list names them, in the kernel's output order
    assert SIGNAL_NAMES[:6] == ("roll_rate", "pitch_rate", "yaw_rate", "accel_x", "accel_y", "accel_z")
    # the /sim/suspension quantities per wheel
    for q in M.SUSPENSION_QUANTITIES:
        assert all(f"{q}_{w.lower()}" in SIGNAL_NAMES for w in WHEELS), q
    assert all(x == x.lower() for x in SIGNAL_NAMES)
    for label in OUTPUT_LABELS:
        assert output_label(signal_name(label)) == label
        assert signal_name(signal_name(label)) == signal_name(label)
    with pytest.raises(KeyError, match="unknown output 'pitchrate'"):
        signal_name("pitchrate")


def test_units_are_si_and_come_from_the_layout():
    assert SIGNAL_UNITS["pitch_rate"] == "rad/s" and SIGNAL_UNITS["accel_z"] == "m/s^2"
    assert SIGNAL_UNITS["damper_force_rl"] == "N" and SIGNAL_UNITS["deflection_fl"] == "m"
    assert set(SIGNAL_UNITS.values()) <= set(OUTPUT_UNITS.values())
    assert set(SIGNAL_UNITS.values()) == {"rad/s", "m/s^2", "rad", "m", "m/s", "N"}


def test_simulate_returns_labelled_si_signals(model_full, bump_run):
    man, r = bump_run
    assert isinstance(r, Response) and not r.is_batch and r.ok
    assert r.labels == SIGNAL_NAMES and r.values.shape == (man.n_steps(DT), len(SIGNAL_NAMES))
    assert r.t[0] == pytest.approx(DT) and np.all(np.diff(r.t) > 0)
    # a label is a column of the kernel outputs; the kernel's spelling is an alias of the same column
    j = OUTPUT_LABELS.index("PITCH_RATE")
    assert np.shares_memory(r["pitch_rate"], r.values) and np.array_equal(r["pitch_rate"], r.values[:, j])
    assert np.array_equal(r["PITCH_RATE"], r["pitch_rate"]) and "PITCH_RATE" in r and "pitch" in r
    assert r.units["pitch_rate"] == "rad/s" and list(r.signals) == list(r.labels)
    with pytest.raises(TypeError, match="not a tuple"):  # the old batch tuple's unpacking fails loudly
        _, _, _ = r
    with pytest.raises(TypeError, match="signal name"):
        r[0]
    # physics: the bump makes the body pitch by a fraction of a rad/s and the rear dampers work
    assert 0.01 < np.max(np.abs(r["pitch_rate"])) < 1.0
    assert np.max(np.abs(r["damper_force_rl"])) > 100.0
    with pytest.raises(KeyError, match="not recorded"):
        simulate(model_full, man.to_inputs(DT)[:10], dt=DT, road=man.road, outputs=["roll_rate"])["pitch_rate"]


def test_selection_takes_either_spelling_and_keeps_the_numbers(model_full, bump_run):
    man, full = bump_run
    U = man.to_inputs(DT)
    a = simulate(model_full, U, dt=DT, road=man.road, oil=vehicle_state("rear_empty"),
                 outputs=["pitch_rate", "F_DAMPER_RL"])
    assert a.labels == ("pitch_rate", "damper_force_rl")
    np.testing.assert_array_equal(a.values, np.column_stack([full["pitch_rate"], full["damper_force_rl"]]))


def test_batch_response_has_a_leading_vehicle_axis(model_full):
    man = sine_steer(duration=2.0)
    U = man.to_inputs(DT)
    oils = [(1, 1, 1, 1), (0, 0, 1, 1), (1, 1, 0, 0)]
    P = np.stack([model_full.params(o) for o in oils])
    b = simulate_batch(model_full, P, U, dt=DT, roads=[man.road], decim=10, outputs=["roll_rate", "yaw_rate"])
    assert isinstance(b, Response) and b.is_batch and b.n_vehicles == 3 and b.ok
    assert b.values.shape == (3, U.shape[0] // 10, 2) and b["roll_rate"].shape == (3, U.shape[0] // 10)
    assert b.state.shape == (3, model_full.layout.n_s)
    for k, oil in enumerate(oils):
        one = simulate(model_full, U, dt=DT, road=man.road, oil=oil, decim=10, outputs=["roll_rate", "yaw_rate"])
        v = b.vehicle(k)
        np.testing.assert_array_equal(v.values, one.values)
        np.testing.assert_array_equal(v.state, one.state)
        assert v.steps_done == one.steps_done and v.labels == one.labels
    # oil-empty front dampers: the car rolls more in the sine steer than the intact one
    assert np.max(np.abs(b["roll_rate"][1])) > np.max(np.abs(b["roll_rate"][0]))


def test_lockstep_run_holds_the_same_response_type(model_full):
    """A lockstep run is a LockstepRun holding a Response (the one result type of every simulation);
    the response's signals read through."""
    drive = maneuver_drive(bump_crossing(), oil=vehicle_state("rear_empty"))
    r = run_lockstep(drive, model=model_full)
    assert isinstance(r, LockstepRun) and isinstance(r.response, Response)
    assert r.ok and r.labels == SIGNAL_NAMES and r.response.labels == SIGNAL_NAMES
    np.testing.assert_array_equal(r["pitch_rate"], r.response["pitch_rate"])
    assert r.t_ns.dtype == np.int64 and len(r.t_ns) == len(r) == r.values.shape[0]
    np.testing.assert_allclose(r.t, (r.t_ns - drive.t0_ns) * 1e-9, rtol=0, atol=1e-15)
    np.testing.assert_allclose(np.diff(r.t), 0.01, atol=1e-12)  # the 100 Hz publish ticks
    np.testing.assert_array_equal(r.imu.gyro, np.column_stack([r["roll_rate"], r["pitch_rate"], r["yaw_rate"]]))
    np.testing.assert_array_equal(r.imu.accel, np.column_stack([r["accel_x"], r["accel_y"], r["accel_z"]]))
    assert r.metadata["source"] == "simulated:full"


def test_to_csv_names_columns_with_units_and_keeps_every_value(model_full, bump_run, tmp_path):
    _, r = bump_run
    text = r.to_csv()
    rows = list(csv.reader(io.StringIO(text)))
    assert rows[0][:3] == ["time_s", "roll_rate_rad_s", "pitch_rate_rad_s"]
    assert "accel_z_m_s2" in rows[0] and "damper_force_rl_N" in rows[0] and "deflection_fl_m" in rows[0]
    data = np.array(rows[1:], dtype=float)
    np.testing.assert_array_equal(data[:, 0], r.t)
    np.testing.assert_array_equal(data[:, 1:], r.values)  # repr round trip: bit for bit
    out = tmp_path / "r.csv"
    assert r.to_csv(out) is None and out.read_text() == text


def test_to_pandas_single_and_batch(model_full, bump_run):
    pd = pytest.importorskip("pandas")
    _, r = bump_run
    df = r.to_pandas()
    assert isinstance(df, pd.DataFrame) and df.index.name == "time_s" and list(df.columns) == list(r.labels)
    np.testing.assert_array_equal(df["pitch_rate"].to_numpy(), r["pitch_rate"])
    assert df.attrs["units"]["pitch_rate"] == "rad/s"
    man = bump_crossing()
    P = np.stack([model_full.params(), model_full.params((1, 1, 0, 0))])
    b = simulate_batch(model_full, P, man.to_inputs(DT)[:500], dt=DT, roads=[man.road], outputs=["heave"])
    db = b.to_pandas()
    assert list(db.index.names) == ["vehicle", "time_s"] and db.shape == (2 * 500, 1)
    np.testing.assert_array_equal(db.loc[1, "heave"].to_numpy(), b["heave"][1])
