"""Lockstep runner: equals the offline model run, writes the simulated MCAP, is fast."""
from __future__ import annotations

import time

import numpy as np
import pytest

from susp_sim_ros.io import read_drive, read_imu, write_drive
from susp_sim_ros.io.reader import read_recording
from susp_sim_ros.runtime.lockstep import maneuver_drive, run_lockstep
from susp_sim_ros.model import simulate
from susp_sim_ros.model.maneuvers import bump_crossing, sine_steer, vehicle_state


@pytest.mark.parametrize("state", ["intact", "rear_empty"])
def test_maneuver_lockstep_equals_simulate(model_full, state):
    man = bump_crossing()
    oil = vehicle_state(state)
    d = maneuver_drive(man, oil, rate_hz=1000.0)  # inputs at every step: same zero-order hold
    res = run_lockstep(d, model=model_full)
    ref = simulate(model_full, man.to_inputs(0.001), dt=0.001, road=man.road, oil=oil)
    n = min(len(res.t_ns), len(ref.t) // 10)
    np.testing.assert_allclose(res.values[:n], ref.y[9::10][:n], rtol=0, atol=1e-12)
    assert res.metadata["damper_oil_level"] == ",".join(f"{x:g}" for x in oil)


def test_recorded_drive_lockstep_and_output_file(tmp_path, model_full):
    d = maneuver_drive(sine_steer(), (1, 1, 0, 0))
    src = tmp_path / "drive.mcap"
    write_drive(src, d)
    drive = read_drive(src)
    out = tmp_path / "sim.mcap"
    res = run_lockstep(drive, out_path=out, model=model_full, variant="full")
    assert res.metadata["source"] == "simulated:full" and res.metadata["damper_oil_level"] == "1,1,0,0"
    rec = read_recording(out)
    assert rec.metadata["test_drive"]["source"] == "simulated:full"
    assert set(rec.topics()) == {"/vehicle/speed", "/vehicle/steering_wheel_angle", "/sim/imu/data",
                                 "/sim/odom", "/sim/suspension"}
    imu = read_imu(out, "/sim/imu/data")
    np.testing.assert_array_equal(imu.t_ns, res.t_ns)
    np.testing.assert_array_equal(imu.gyro, res.imu.gyro)
    from rosbags.highlevel import AnyReader
    with AnyReader([out]) as r:
        n = sum(1 for c, _, raw in r.messages() if r.deserialize(raw, c.msgtype) is not None)
    assert n == len(rec.messages)
    # the simulated file is itself a valid test drive
    again = read_drive(out, imu_topic="/sim/imu/data")
    np.testing.assert_array_equal(again.imu.gyro, res.imu.gyro)


def test_twenty_second_drive_is_fast(model_full):
    d = maneuver_drive(sine_steer(duration=20.0))
    run_lockstep(d, model=model_full)  # warm
    t = time.perf_counter()
    res = run_lockstep(d, model=model_full)
    elapsed = time.perf_counter() - t
    assert len(res.t_ns) == 2000
    assert elapsed < 0.5, elapsed  # "well under 1 s" for a 20 s drive


def test_cli_sim_drive_and_maneuver(tmp_path, capsys):
    import json
    from susp_sim_ros.cli.main import main
    src = tmp_path / "d.mcap"
    write_drive(src, maneuver_drive(bump_crossing(), (1, 1, 1, 1)))
    assert main(["sim", "--drive", str(src), "--out", str(tmp_path / "s.mcap"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["ok"] and out["peak_pitch_rate_deg_s"] > 0.5 and out["out"].endswith("s.mcap")
    assert main(["sim", "--maneuver", "sine", "--state", "front_empty", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert {"maneuver", "state", "variant", "vehicle", "duration_s", "ok", "peak_pitch_rate_deg_s",
            "peak_roll_rate_deg_s", "peak_yaw_rate_deg_s", "peak_lateral_acceleration_m_s2"} <= set(out)
    assert out["state"] == "front_empty"
    assert main(["sim", "--drive", str(tmp_path / "nope.mcap"), "--json"]) == 2
    assert main(["sim", "--drive", str(src), "--out", str(tmp_path / "s.mcap")]) == 2  # exists already
