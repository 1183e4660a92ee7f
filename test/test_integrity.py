"""Input integrity (issue 28): one check of every recording a command reads; findings, never silence.

Damaged copies of the bundled drives (a dead gyro, a missing road profile, a gap, a clock jump, a spike,
steering in degrees, NaN samples) are detected, worked around and reported, or refused with a named
error (exit 2); the undamaged drives give no finding at all."""
from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from _cli_helpers import run_cli
from susp_sim_ros.analysis import csv_import
from susp_sim_ros.analysis.discrepancy.data import load_cases
from susp_sim_ros.io.drive import (MAX_SPEED, MAX_STEERING, MAX_WHEEL_HEIGHT, ImuSeries, Series, TestDrive,
                                   drive_from_recording, drive_messages, read_drive, write_drive)
from susp_sim_ros.io.integrity import (KINDS, IntegrityError, check_drive_integrity, load_policy,
                                       require_live_imu)
from susp_sim_ros.io.reader import read_recording
from susp_sim_ros.io.recorder import McapRecorder
from susp_sim_ros.model.params import load_vehicle
from susp_sim_ros.runtime import sim_core as core_limits

BAGS = Path(__file__).resolve().parents[1] / "bags"
BUMP = BAGS / "bump_crossing_intact.mcap"
SINE = BAGS / "sine_steer_intact.mcap"
NS = 1_000_000_000


def raw(path: Path) -> TestDrive:
    """The drive as recorded, before the integrity check."""
    return drive_from_recording(read_recording(path))


def with_imu(drive: TestDrive, t_ns, gyro, accel) -> TestDrive:
    return dataclasses.replace(drive, imu=ImuSeries(t_ns, gyro, accel))


def kinds(res) -> list[str]:
    return [f.kind for f in res.findings]


@pytest.fixture(scope="module")
def bump() -> TestDrive:
    return raw(BUMP)


@pytest.fixture(scope="module")
def sine() -> TestDrive:
    return raw(SINE)


# ---- clean drives ------------------------------------------------------------------------------------
@pytest.mark.parametrize("path", sorted(BAGS.glob("*.mcap")), ids=lambda p: p.stem)
def test_bundled_drives_give_no_finding(path):
    res = check_drive_integrity(raw(path), str(path))
    assert res.findings == [] and res.unusable == set()
    d = read_drive(path)
    assert d.extra["input_findings"] == [] and d.extra["unusable_signals"] == []


def test_policy_has_value_unit_source_for_every_entry():
    pol = load_policy()
    assert pol["limits.steering_max"] == pytest.approx(4 * np.pi) and pol["spikes.window"] >= 3


def test_the_input_limits_are_declared_once_and_used_by_the_node_and_the_check():
    """One limit per input (config/integrity.yaml, ``limits``): the node (SimCore), the CSV import and the
    drive API read the check's values; the node rejects just beyond the steering limit and names it."""
    pol = load_policy()
    assert (MAX_SPEED, MAX_STEERING, MAX_WHEEL_HEIGHT) == (pol["limits.speed_max"], pol["limits.steering_max"],
                                                           pol["limits.wheel_height_max"])
    assert (core_limits.MAX_SPEED, core_limits.MAX_STEERING, core_limits.MAX_WHEEL_HEIGHT) == (
        MAX_SPEED, MAX_STEERING, MAX_WHEEL_HEIGHT)
    assert (csv_import.MAX_SPEED, csv_import.MAX_STEERING) == (MAX_SPEED, MAX_STEERING)


# ---- each kind on a damaged copy ----------------------------------------------------------------------
def test_dead_gyro_is_found_and_marks_every_axis_unusable(sine):
    imu = sine.imu
    res = check_drive_integrity(with_imu(sine, imu.t_ns, np.zeros_like(imu.gyro), imu.accel), "dead.mcap")
    assert kinds(res).count("dead_sensor") == 3 and res.unusable == {"roll_rate", "pitch_rate", "yaw_rate"}
    assert all(f.action == "excluded" and f.topic == "/imu/data" for f in res.findings)
    with pytest.raises(IntegrityError, match="dead_sensor"):
        require_live_imu(res.drive, "dead.mcap", "diagnose")


def test_gyro_that_dies_mid_drive_is_a_dead_span(sine):
    imu = sine.imu
    g = imu.gyro.copy()
    g[800:, 0] = g[800, 0]
    res = check_drive_integrity(with_imu(sine, imu.t_ns, g, imu.accel), "dies.mcap")
    (f,) = res.findings
    assert f.kind == "dead_sensor" and "roll_rate" in f.detail and f.from_s == pytest.approx(
        (imu.t_ns[800] - sine.t0_ns) / NS, abs=0.01)


def test_saturated_axis_is_reported(sine):
    imu = sine.imu
    g = imu.gyro.copy()
    g[:, 2] = np.clip(g[:, 2], -0.1, 0.1)
    res = check_drive_integrity(with_imu(sine, imu.t_ns, g, imu.accel), "clip.mcap")
    assert "saturated_sensor" in kinds(res)


def test_missing_road_on_a_bump_crossing_is_a_named_error(bump):
    with pytest.raises(IntegrityError, match=r"missing_topic.*/road/profile"):
        check_drive_integrity(dataclasses.replace(bump, road=None), "noroad.mcap")


def test_imu_gap_is_excluded_not_interpolated(bump):
    imu = bump.imu
    keep = (imu.t_ns < imu.t_ns[200]) | (imu.t_ns > imu.t_ns[200] + 2 * NS)
    res = check_drive_integrity(with_imu(bump, imu.t_ns[keep], imu.gyro[keep], imu.accel[keep]), "gap.mcap")
    (f,) = res.findings
    assert f.kind == "gap" and f.action == "excluded" and f.to_s - f.from_s == pytest.approx(2.0, abs=0.02)
    assert res.drive.extra["excluded_spans"]["/imu/data"]


def test_clock_jump_is_repaired(bump):
    imu = bump.imu
    t = imu.t_ns.copy()
    t[500:] += 1000 * NS
    res = check_drive_integrity(with_imu(bump, t, imu.gyro, imu.accel), "jump.mcap")
    (f,) = res.findings
    assert f.kind == "clock_jump" and f.action == "repaired"
    assert np.array_equal(res.drive.imu.t_ns[:500], imu.t_ns[:500]) and res.drive.imu.t_ns[-1] < t[499] + 10 * NS


def test_stamp_order_and_duplicate_stamps(bump):
    t, v = bump.speed.t_ns.copy(), bump.speed.values.copy()
    t[100], t[101] = t[101], t[100]
    t[300] = t[299]
    res = check_drive_integrity(dataclasses.replace(bump, speed=Series(t, v)), "order.mcap")
    assert kinds(res) == ["stamp_order", "duplicate_stamp"]
    assert np.all(np.diff(res.drive.speed.t_ns) > 0)


def _write_messages(path: Path, drive: TestDrive, msgs) -> Path:
    """Write ``msgs`` (``drive_messages`` rows) in the order given: a recorder that stored them so."""
    with McapRecorder(path, metadata={str(k): str(v) for k, v in drive.metadata.items()}, overwrite=True) as rec:
        for t, topic, mt, msg, latched in msgs:
            rec.write(topic, mt, t, msg, latched=latched)
    return path


def test_messages_stored_out_of_log_time_order_are_a_stamp_order_finding(bump, tmp_path):
    """Two speed messages stored in the file in swapped order (each with its own log time): the check sees
    the file order, reports stamp_order (repaired) where it is and reads the series sorted, as a clean
    copy reads."""
    msgs = drive_messages(bump)
    slots = [i for i, m in enumerate(msgs) if m[1] == "/vehicle/speed"]
    i, j = slots[200], slots[201]
    msgs[i], msgs[j] = msgs[j], msgs[i]
    path = _write_messages(tmp_path / "order.mcap", bump, msgs)
    d = read_drive(path)
    (f,) = d.extra["input_findings"]
    assert f["kind"] == "stamp_order" and f["topic"] == "/vehicle/speed" and f["action"] == "repaired"
    assert (f["from_s"], f["to_s"]) == (pytest.approx(_t(bump, bump.speed.t_ns[200]), abs=1e-6),
                                        pytest.approx(_t(bump, bump.speed.t_ns[201]), abs=1e-6))
    clean = read_drive(_write_messages(tmp_path / "clean.mcap", bump, drive_messages(bump)))
    assert clean.extra["input_findings"] == []
    np.testing.assert_array_equal(d.speed.t_ns, clean.speed.t_ns)
    np.testing.assert_array_equal(d.speed.values, clean.speed.values)


def test_backward_clock_jump_stored_in_file_order_is_a_clock_jump(bump, tmp_path):
    """The IMU clock steps 2 s back half way, the messages stored as they came: one clock_jump (repaired,
    the later samples moved to follow the earlier ones), not the interleaved samples that sorting by log
    time would make (rate_change, duplicate_stamp)."""
    imu = bump.imu
    k = len(imu) // 2
    t = imu.t_ns.copy()
    t[k + 1:] -= 2 * NS
    rows = [m for m in drive_messages(dataclasses.replace(bump, imu=None))]
    rows += [m for m in drive_messages(with_imu(dataclasses.replace(bump, speed=Series([], []),
                                                                    steering=Series([], []), road=None),
                                                t, imu.gyro, imu.accel)) if m[1] == "/imu/data"]
    order = np.argsort(t, kind="stable")  # drive_messages sorted the IMU by log time: back to file order
    imu_rows = [m for m in rows if m[1] == "/imu/data"]
    rows = [m for m in rows if m[1] != "/imu/data"] + [imu_rows[int(np.nonzero(order == n)[0][0])]
                                                       for n in range(len(t))]
    d = read_drive(_write_messages(tmp_path / "back.mcap", bump, rows))
    kinds_found = [f["kind"] for f in d.extra["input_findings"]]
    assert kinds_found == ["clock_jump"], d.extra["input_findings"]
    assert len(d.imu) == len(imu) and np.all(np.diff(d.imu.t_ns) > 0)
    np.testing.assert_array_equal(d.imu.gyro, imu.gyro)  # every sample kept, in the order measured


def test_out_of_range_inputs_are_dropped_with_a_finding(bump, sine):
    """Samples the node rejects (negative speed, steering beyond the limit that is no unit mistake, a damper
    command outside [0, 1], a wheel height beyond 1 m) are dropped with one out_of_range finding each, where
    they are; nothing is interpolated in their place."""
    v = bump.speed.values.copy()
    v[300:320] = -0.5
    n = len(bump.speed)
    cmd = np.full((n, 4), 0.5)
    cmd[100:110, 2] = 1.5
    wh = np.zeros((n, 4))
    wh[50:70, 0] = 1.2
    d = dataclasses.replace(bump, speed=Series(bump.speed.t_ns, v),
                            damper_command=Series(bump.speed.t_ns, cmd),
                            wheel_heights=Series(bump.speed.t_ns, wh))
    res = check_drive_integrity(d, "range.mcap")
    got = {f.topic: f for f in res.findings}
    assert kinds(res) == ["out_of_range"] * 3 and set(got) == {"/vehicle/speed", "/road/wheel_heights",
                                                                "/vehicle/damper_command"}
    assert all(f.action == "excluded" for f in res.findings)
    f = got["/vehicle/speed"]
    assert (f.from_s, f.to_s) == (pytest.approx(_t(bump, bump.speed.t_ns[300]), abs=1e-6),
                                  pytest.approx(_t(bump, bump.speed.t_ns[319]), abs=1e-6))
    assert len(res.drive.speed) == n - 20 and res.drive.speed.values.min() >= 0.0
    assert not np.isin(bump.speed.t_ns[300:320], res.drive.speed.t_ns).any()  # left out, not interpolated
    assert len(res.drive.damper_command) == n - 10 and res.drive.damper_command.values.max() <= 1.0
    assert len(res.drive.wheel_heights) == n - 20
    st_v = sine.steering.values.copy()
    st_v[300:320] = 800.0  # rad: beyond the limit, and no unit mistake (800 deg is beyond it too)
    res = check_drive_integrity(dataclasses.replace(sine, steering=Series(sine.steering.t_ns, st_v)), "st.mcap")
    (f,) = res.findings
    assert f.kind == "out_of_range" and f.topic == "/vehicle/steering_wheel_angle" and "12.57" in f.detail
    assert np.abs(res.drive.steering.values).max() <= MAX_STEERING


def test_inputs_with_nothing_in_range_are_a_named_error(bump):
    v = np.full(len(bump.speed), -1.0)
    with pytest.raises(IntegrityError, match=r"/vehicle/speed: out_of_range: every one of its"):
        check_drive_integrity(dataclasses.replace(bump, speed=Series(bump.speed.t_ns, v)), "neg.mcap")
    road = dataclasses.replace(bump.road, zl=bump.road.zl + 2.0)
    with pytest.raises(IntegrityError, match=r"/road/profile: out_of_range: road elevation"):
        check_drive_integrity(dataclasses.replace(bump, road=road), "road.mcap")


def test_speed_spike_is_excluded(bump):
    v = bump.speed.values.copy()
    v[250] = 500.0
    res = check_drive_integrity(dataclasses.replace(bump, speed=Series(bump.speed.t_ns, v)), "spike.mcap")
    (f,) = res.findings
    assert f.kind == "spike" and f.topic == "/vehicle/speed" and len(res.drive.speed) == len(v) - 1
    assert res.drive.speed.values.max() < 3.0


def test_non_finite_samples_are_excluded(sine):
    imu = sine.imu
    g = imu.gyro.copy()
    g[40:43, 1] = np.nan
    res = check_drive_integrity(with_imu(sine, imu.t_ns, g, imu.accel), "nan.mcap")
    assert kinds(res) == ["non_finite"] and len(res.drive.imu) == len(imu) - 3


def test_steering_in_degrees_is_an_implausible_unit(sine):
    st_deg = Series(sine.steering.t_ns, np.degrees(sine.steering.values))
    with pytest.raises(IntegrityError, match="implausible_unit.*degrees"):
        check_drive_integrity(dataclasses.replace(sine, steering=st_deg), "deg.mcap")


def test_speed_in_kmh_beyond_the_bound_is_an_implausible_unit(sine):
    v = Series(sine.speed.t_ns, sine.speed.values * 3.6 * 2.0)  # 100 km/h recorded in km/h
    with pytest.raises(IntegrityError, match="implausible_unit.*km/h"):
        check_drive_integrity(dataclasses.replace(sine, speed=v), "kmh.mcap")


def test_finding_json_has_the_interface_keys(bump):
    v = bump.speed.values.copy()
    v[250] = 500.0
    res = check_drive_integrity(dataclasses.replace(bump, speed=Series(bump.speed.t_ns, v)), "spike.mcap")
    j = res.findings[0].to_json()
    assert set(j) == {"file", "topic", "kind", "from_s", "to_s", "action", "detail"} and j["kind"] in KINDS
    assert res.findings[0].line().startswith("input: spike.mcap /vehicle/speed spike ")


def _t(drive: TestDrive, t_ns) -> float:
    return (int(t_ns) - drive.t0_ns) / NS


def test_imu_decimated_half_way_is_a_rate_change(sine):
    """A logger that drops to a fifth of the IMU rate half way: one rate_change, from where it changed to
    the end, saying from and to which rate; the samples are kept as recorded."""
    imu = sine.imu
    h = len(imu) // 2
    keep = np.r_[np.arange(h), np.arange(h, len(imu), 5)]
    res = check_drive_integrity(with_imu(sine, imu.t_ns[keep], imu.gyro[keep], imu.accel[keep]), "decim.mcap")
    (f,) = res.findings
    assert f.kind == "rate_change" and f.action == "kept" and f.topic == "/imu/data"
    assert f.from_s == pytest.approx(_t(sine, imu.t_ns[h]), abs=0.006)
    assert f.to_s == pytest.approx(_t(sine, imu.t_ns[keep][-1]), abs=1e-6)
    assert "from 200 Hz to 40 Hz" in f.detail
    assert len(res.drive.imu) == keep.size  # nothing dropped


def test_input_rate_change_in_the_middle_and_back(bump):
    """CAN speed at 100 Hz, 20 Hz between 1 and 3 s (the brief's decimating logger), 100 Hz again."""
    s = bump.speed
    i_a, i_b = 100, 300
    keep = np.r_[np.arange(i_a), np.arange(i_a, i_b, 5), np.arange(i_b, len(s))]
    res = check_drive_integrity(dataclasses.replace(bump, speed=Series(s.t_ns[keep], s.values[keep])), "can.mcap")
    (f,) = res.findings
    assert f.kind == "rate_change" and f.topic == "/vehicle/speed" and f.action == "kept"
    assert f.from_s == pytest.approx(_t(bump, s.t_ns[i_a]), abs=0.011)
    assert f.to_s == pytest.approx(_t(bump, s.t_ns[i_b]), abs=0.011)
    assert "from 100 Hz to 20 Hz" in f.detail and "back to 100 Hz" in f.detail


def test_rate_change_ignores_gaps_and_jitter(sine):
    """A hole of 2 s is a gap, not a rate change; stamps jittered by +-40 % of a period are no rate change."""
    imu = sine.imu
    keep = (imu.t_ns < imu.t_ns[600]) | (imu.t_ns > imu.t_ns[600] + 2 * NS)
    res = check_drive_integrity(with_imu(sine, imu.t_ns[keep], imu.gyro[keep], imu.accel[keep]), "gap.mcap")
    assert kinds(res) == ["gap"]
    period = int(np.median(np.diff(imu.t_ns)))
    jitter = np.random.default_rng(28).uniform(-0.4, 0.4, len(imu)) * period
    t = np.sort(imu.t_ns + jitter.astype(np.int64))
    res = check_drive_integrity(with_imu(sine, t, imu.gyro, imu.accel), "jitter.mcap")
    assert "rate_change" not in kinds(res)


def test_maneuver_that_names_a_maneuver_but_does_not_classify_is_bad_metadata(bump):
    meta = {**bump.metadata, "maneuver": "slow_bump_crossing_8kmh"}
    res = check_drive_integrity(dataclasses.replace(bump, metadata=meta), "meta.mcap")
    (f,) = res.findings
    assert f.kind == "bad_metadata" and f.action == "kept" and f.topic == "test_drive"
    assert "maneuver" in f.detail and "'slow_bump_crossing_8kmh'" in f.detail and "bump_crossing" in f.detail
    assert f.from_s == 0.0 and f.to_s == pytest.approx(bump.duration_s, abs=1e-6)
    # free text naming no maneuver of the registry is what the interface allows: no finding
    for text in ("highway_cruise", "cosine road", "Bump_Crossing_8kmh", ""):
        ok = check_drive_integrity(dataclasses.replace(bump, metadata={**bump.metadata, "maneuver": text}), "ok")
        assert ok.findings == [], text


def test_unknown_vehicle_state_is_bad_metadata_and_ignored(sine):
    meta = {**sine.metadata, "vehicle_state": "rear-empty"}
    res = check_drive_integrity(dataclasses.replace(sine, metadata=meta), "state.mcap")
    (f,) = res.findings
    assert f.kind == "bad_metadata" and "vehicle_state" in f.detail and "'rear-empty'" in f.detail
    assert "rear_empty" in f.detail and f.from_s == 0.0 and f.to_s == pytest.approx(sine.duration_s, abs=1e-6)
    assert res.drive.oil_levels() == (1.0, 1.0, 1.0, 1.0)  # the state comes from damper_oil_level


@pytest.mark.parametrize("oil", ["1,1,2,0", "1,1,empty,0", "1,1,1", "nan,1,1,1"])
def test_unusable_oil_level_is_a_named_bad_metadata_error(sine, tmp_path, oil):
    """Every simulation needs the oil levels: a damper_oil_level that is not four fractions in [0, 1] is a
    named error (exit 2), in memory and when the recording is read, as it was before the kind existed."""
    d = dataclasses.replace(sine, metadata={**sine.metadata, "damper_oil_level": oil})
    with pytest.raises(IntegrityError, match=r"damper_oil_level: bad_metadata: expected four"):
        check_drive_integrity(d, "oil.mcap")
    p = tmp_path / "oil.mcap"
    write_drive(p, d)
    with pytest.raises(IntegrityError, match=r"oil.mcap: test_drive metadata damper_oil_level: bad_metadata"):
        read_drive(p)


# ---- property: where and how much damage -------------------------------------------------------------
@settings(max_examples=10, deadline=None)
@given(start=st.floats(0.05, 0.8), length_s=st.floats(0.3, 3.0), spike=st.floats(5.0, 400.0),
       at=st.floats(0.05, 0.95))
def test_gap_and_spike_anywhere_are_found_where_they_are(bump, start, length_s, spike, at):
    imu = bump.imu
    t_a = int(imu.t_ns[0] + start * (imu.t_ns[-1] - imu.t_ns[0]))
    keep = (imu.t_ns <= t_a) | (imu.t_ns > t_a + int(length_s * NS))
    v = bump.speed.values.copy()
    k = int(at * (len(v) - 1))
    v[k] += spike
    d = dataclasses.replace(with_imu(bump, imu.t_ns[keep], imu.gyro[keep], imu.accel[keep]),
                            speed=Series(bump.speed.t_ns, v))
    res = check_drive_integrity(d, "prop.mcap")
    gaps = [f for f in res.findings if f.kind == "gap"]
    spikes = [f for f in res.findings if f.kind == "spike"]
    if imu.t_ns[keep][-1] > t_a + int(length_s * NS):  # the hole is inside the record
        assert len(gaps) == 1 and gaps[0].to_s - gaps[0].from_s == pytest.approx(length_s, abs=0.02)
    assert len(spikes) == 1 and spikes[0].from_s == pytest.approx((bump.speed.t_ns[k] - d.t0_ns) / NS, abs=1e-6)
    assert set(kinds(res)) <= {"gap", "spike"}


# ---- end to end through the command line -------------------------------------------------------------
@pytest.fixture(scope="module")
def copies(tmp_path_factory, bump, sine):
    tmp = tmp_path_factory.mktemp("integrity")
    imu = sine.imu
    out = {}
    out["dead"] = tmp / "sine_dead_gyro.mcap"
    write_drive(out["dead"], with_imu(sine, imu.t_ns, np.zeros_like(imu.gyro), imu.accel))
    g = imu.gyro.copy()
    g[:, 1] = 0.0  # pitch gyro dead only
    out["dead_pitch"] = tmp / "sine_dead_pitch.mcap"
    write_drive(out["dead_pitch"], with_imu(sine, imu.t_ns, g, imu.accel))
    out["noroad"] = tmp / "bump_no_road.mcap"
    write_drive(out["noroad"], dataclasses.replace(bump, road=None))
    keep = (imu.t_ns < imu.t_ns[600]) | (imu.t_ns > imu.t_ns[600] + 2 * NS)
    out["gap"] = tmp / "sine_gap.mcap"
    write_drive(out["gap"], with_imu(sine, imu.t_ns[keep], imu.gyro[keep], imu.accel[keep]))
    out["sim"] = tmp / "sine_sim.mcap"
    rc, _, err = run_cli(["sim", "--drive", SINE, "--out", out["sim"]])
    assert rc == 0, err
    return out


def _json_or_named_error(argv):
    rc, out, err = run_cli(argv + ["--json"])
    assert rc in (0, 2) and "Traceback" not in err, (argv, rc, err)
    return rc, (json.loads(out) if rc == 0 else None), err


def test_cli_validate_on_a_dead_gyro(copies):
    rc, res, err = _json_or_named_error(["validate", "--measured", copies["dead"], "--simulated", copies["sim"]])
    assert rc == 2 and "dead_sensor" in err and str(copies["dead"]) in err
    rc, res, err = _json_or_named_error(["validate", "--measured", copies["dead_pitch"], "--simulated", copies["sim"]])
    assert rc == 0 and [f["kind"] for f in res["input_findings"]] == ["dead_sensor"]
    assert "input: " in err and "pitch_rate" in err
    assert "pitch_rate" not in res["rmse_deg_s"]["whole"] and "roll_rate" in res["rmse_deg_s"]["whole"]


def test_cli_validate_leaves_an_imu_gap_out(copies):
    rc, res, err = _json_or_named_error(["validate", "--measured", copies["gap"], "--simulated", copies["sim"]])
    assert rc == 0 and [f["kind"] for f in res["input_findings"]] == ["gap"] and "gap" in err
    clean = _json_or_named_error(["validate", "--measured", SINE, "--simulated", copies["sim"]])[1]
    assert clean["input_findings"] == []
    assert res["windows"]["whole"]["signals"]["roll_rate"]["n"] < clean["windows"]["whole"]["signals"]["roll_rate"]["n"]


def test_cli_sim_and_diagnose_on_a_dead_gyro(copies, tmp_path):
    rc, res, err = _json_or_named_error(["sim", "--drive", copies["dead"]])
    assert rc == 0 and {f["kind"] for f in res["input_findings"]} == {"dead_sensor"}
    rc, res, err = _json_or_named_error(["diagnose", copies["dead"], "--dry-run", "--out", tmp_path])
    assert rc == 0 and {f["kind"] for f in res["input_findings"]} == {"dead_sensor"}  # read and checked only
    rc, res, err = _json_or_named_error(["diagnose", copies["dead"], "--no-heldout", "--no-plots", "--out", tmp_path])
    assert rc == 2 and "dead_sensor" in err and str(copies["dead"]) in err  # nothing sound to fit on


def test_cli_commands_on_a_bump_crossing_without_road(copies, tmp_path):
    for argv in (["sim", "--drive", copies["noroad"]],
                 ["validate", "--measured", copies["noroad"], "--simulated", copies["sim"]],
                 ["diagnose", copies["noroad"], "--dry-run", "--out", tmp_path],
                 ["inspect", copies["noroad"]]):
        rc, res, err = _json_or_named_error(argv)
        assert rc == 2 and "missing_topic" in err and "/road/profile" in err, (argv, err)


# ---- the discrepancy finder's (and the inspection's) measured signals ------------------------------------
def _case(path: Path, drive: TestDrive):
    write_drive(path, drive)
    (case,) = load_cases([path], wheelbase=load_vehicle().wheelbase)
    return case


def test_discrepancy_finder_leaves_out_dead_and_saturated_signals(bump, tmp_path):
    """Each of the six IMU signals the check found dead or saturated is not used as a measurement by the
    discrepancy finder (load_cases): an accelerometer axis that freezes, a yaw gyro clipped by its range;
    the live signals stay."""
    imu = bump.imu
    assert _case(tmp_path / "clean.mcap", bump).signals == ("roll_rate", "pitch_rate", "yaw_rate", "accel_x",
                                                             "accel_y", "accel_z")
    a = imu.accel.copy()
    a[:, 0] = a[0, 0]  # longitudinal accelerometer frozen
    a[len(imu) // 2:, 2] = a[len(imu) // 2, 2]  # vertical accelerometer dies half way
    g = imu.gyro.copy()
    c = float(np.quantile(np.abs(g[:, 2]), 0.6))
    g[:, 2] = np.clip(g[:, 2], -c, c)
    case = _case(tmp_path / "damaged.mcap", with_imu(bump, imu.t_ns, g, a))
    assert case.signals == ("roll_rate", "pitch_rate", "accel_y")
    assert case.y_meas.shape[1] == 3 and case.y_raw.shape[1] == 6


def test_discrepancy_finder_refuses_a_dead_gyro_or_a_saturated_primary_signal(bump, tmp_path):
    """A dead gyro axis is refused as before (said in plain grammar); the maneuver's primary gyro signal
    (pitch rate of a bump crossing) clipped by its range leaves nothing sound for its figures: refused."""
    imu = bump.imu
    g = imu.gyro.copy()
    g[:, 0] = 0.0
    with pytest.raises(IntegrityError, match=r"dead_sensor roll_rate .*the discrepancy finder and the inspection "
                                             r"need a live gyro on every axis"):
        _case(tmp_path / "dead.mcap", with_imu(bump, imu.t_ns, g, imu.accel))
    g = imu.gyro.copy()
    c = float(np.quantile(np.abs(g[:, 1]), 0.6))
    g[:, 1] = np.clip(g[:, 1], -c, c)
    with pytest.raises(IntegrityError, match=r"saturated_sensor pitch_rate .*need the maneuver's primary signal "
                                             r"pitch_rate within the sensor range"):
        _case(tmp_path / "clipped.mcap", with_imu(bump, imu.t_ns, g, imu.accel))


# ---- a vehicle without a parameter set ------------------------------------------------------------------
def test_unknown_vehicle_is_bad_metadata_where_the_vehicle_is_taken_from_the_drive(sine, copies, tmp_path):
    """A ``vehicle`` the commands have no parameters for is a ``bad_metadata`` finding (kept: the reference
    car's parameters are used, said so) where a command takes the vehicle from the drive (``validate``);
    the generic check finds nothing wrong with the drive itself (a drive of another car is not damaged)."""
    from susp_sim_ros.io.integrity import drive_vehicle
    from susp_sim_ros.model.params import DEFAULT_VEHICLE
    meta = {**sine.metadata, "vehicle": "independent"}
    other_car = dataclasses.replace(sine, metadata=meta, extra={})
    assert check_drive_integrity(other_car, "veh.mcap").findings == []
    assert drive_vehicle(other_car, "veh.mcap") == DEFAULT_VEHICLE
    (f,) = other_car.extra["input_findings"]
    assert (f["kind"], f["topic"], f["action"]) == ("bad_metadata", "test_drive", "kept")
    assert "vehicle 'independent'" in f["detail"] and f"reference car {DEFAULT_VEHICLE} is used" in f["detail"]
    assert f["from_s"] == 0.0 and f["to_s"] == pytest.approx(sine.duration_s, abs=1e-6)
    for known in (DEFAULT_VEHICLE, "", None):
        ok = dataclasses.replace(sine, metadata={**sine.metadata, "vehicle": known}, extra={})
        assert drive_vehicle(ok, "ok") == DEFAULT_VEHICLE or known == sine.metadata["vehicle"]
        assert "input_findings" not in ok.extra, known
    path = tmp_path / "independent.mcap"
    write_drive(path, dataclasses.replace(sine, metadata=meta))
    rc, out, err = _json_or_named_error(["validate", "--measured", path, "--simulated", copies["sim"]])
    assert rc == 0 and [x["kind"] for x in out["input_findings"]] == ["bad_metadata"]
    assert "'independent'" in err and f"input: {path} test_drive bad_metadata" in err
    clean = _json_or_named_error(["validate", "--measured", SINE, "--simulated", copies["sim"]])[1]
    assert out["rmse_deg_s"] == clean["rmse_deg_s"]  # the reference car's wheelbase: same windows, same figures


# ---- road-profile spikes --------------------------------------------------------------------------------
def _road(drive: TestDrive, zl, zr=None):
    from susp_sim_ros.model.road import RoadProfile
    r = drive.road
    return dataclasses.replace(drive, road=RoadProfile(r.s, np.asarray(zl, float),
                                                       np.asarray(r.zr if zr is None else zr, float)))


@settings(max_examples=15, deadline=None)
@given(at=st.floats(0.0, 1.0), height=st.floats(0.3, 0.9), right=st.booleans())
def test_a_single_sample_road_spike_is_dropped_and_the_profile_joined_over_it(bump, at, height, right):
    r = bump.road
    k = int(at * (len(r.s) - 1))
    z = (r.zr if right else r.zl).copy()
    z[k] += height
    d = _road(bump, r.zl, z) if right else _road(bump, z)
    res = check_drive_integrity(d, "road.mcap")
    (f,) = res.findings
    assert (f.kind, f.topic, f.action) == ("spike", "/road/profile", "excluded")
    assert f"s = {r.s[k]:.4g}-{r.s[k]:.4g} m" in f.detail
    out = res.drive.road
    keep = np.arange(len(r.s)) != k
    assert np.array_equal(out.s, r.s[keep]) and np.array_equal(out.zl, r.zl[keep])
    assert np.array_equal(out.zr, r.zr[keep])


@settings(max_examples=15, deadline=None)
@given(height=st.floats(0.005, 0.15), samples=st.integers(11, 300), spacing=st.sampled_from([0.01, 0.02, 0.05]),
       step=st.floats(-0.15, 0.15))
def test_a_smooth_bump_or_a_kerb_on_the_road_is_no_spike(bump, height, samples, spacing, step):
    """A smooth (cosine) bump of a few mm up to 15 cm that the profile resolves (at least ``spikes.window``
    samples across it, at the spacings of real road profiles), followed by a kerb (a step) of up to 15 cm:
    the road, not a spike."""
    from susp_sim_ros.model.road import RoadProfile
    length = samples * spacing
    s = np.arange(0.0, length + 2.0, spacing)
    z = (np.where(s < length, 0.5 * height * (1 - np.cos(2 * np.pi * s / length)), 0.0)
         + np.where(s > length + 1.0, step, 0.0))
    res = check_drive_integrity(dataclasses.replace(bump, road=RoadProfile(s, z, z)), "bump.mcap")
    assert res.findings == [] and np.array_equal(res.drive.road.zl, z)


def test_road_spike_goes_through_every_reader_as_a_finding(bump, tmp_path):
    z = bump.road.zl.copy()
    z[25] += 0.5
    path = tmp_path / "road_spike.mcap"
    write_drive(path, _road(bump, z))
    d = read_drive(path)
    assert [f["kind"] for f in d.extra["input_findings"]] == ["spike"] and len(d.road.s) == len(bump.road.s) - 1


# ---- the discrepancy finder: excluded spans and unusable axes --------------------------------------------
def _gap_case(bump, tmp_path):
    """A bump crossing with 0.3 s of IMU missing in the middle of its bump window, as the finder prepares it."""
    imu = bump.imu
    k = len(imu) // 3
    keep = (imu.t_ns <= imu.t_ns[k]) | (imu.t_ns > imu.t_ns[k] + int(0.3 * NS))
    d = with_imu(bump, imu.t_ns[keep], imu.gyro[keep], imu.accel[keep])
    return _case(tmp_path / "gap.mcap", d), d, (int(imu.t_ns[k]), int(imu.t_ns[keep][np.searchsorted(
        imu.t_ns[keep], imu.t_ns[k], side="right")]))


def test_discrepancy_finder_compares_measured_samples_only_never_across_a_gap(bump, tmp_path):
    """The finder compares at the measured IMU stamps: nothing inside an excluded span, the measured values
    as recorded (not resampled), the span kept so that no search window reaches across it."""
    from susp_sim_ros.analysis.discrepancy.locate import locate
    case, d, (a, b) = _gap_case(bump, tmp_path)
    assert case.grid_ns[0] < a < b < case.grid_ns[-1]  # the gap is inside the compared window
    assert not np.any((case.grid_ns > a) & (case.grid_ns < b)) and {a, b} <= set(case.grid_ns.tolist())
    idx = np.searchsorted(d.imu.t_ns, case.grid_ns)
    assert np.array_equal(d.imu.t_ns[idx], case.grid_ns)
    cols = [list(("roll_rate", "pitch_rate", "yaw_rate", "accel_x", "accel_y", "accel_z")).index(s)
            for s in case.signals]
    meas = np.column_stack([np.degrees(d.imu.gyro), d.imu.accel])[idx][:, cols]
    assert np.array_equal(case.y_meas, meas)
    ha, hb = ((a - case.t0_ns) / NS, (b - case.t0_ns) / NS)
    assert np.allclose(case.holes_s, [(ha, hb)], rtol=0, atol=1e-9)
    # a residual far above noise everywhere: the windows found stop at the gap and start again after it
    e = np.full((case.grid_ns.size, len(case.signals)), 10.0)
    found = locate([case], [e], [np.ones(len(case.signals))])
    assert found and all(w["end_s"] <= ha + 1e-9 or w["start_s"] >= hb - 1e-9 for w in found)
    assert {w["start_s"] >= hb - 1e-9 for w in found} == {True, False}


def test_noise_floor_leaves_a_dead_axis_of_one_drive_out_of_the_pool(bump, sine, tmp_path):
    """Pooled over drives, a gyro axis dead on one of them (``unusable_signals``) is the other drive's floor
    alone: not dragged towards 0, no division by zero; the dead drive's own figure is NaN."""
    import warnings
    from susp_sim_ros.analysis.discrepancy.data import as_cases
    from susp_sim_ros.analysis.discrepancy.locate import noise_floor
    wb = load_vehicle().wheelbase
    g = bump.imu.gyro.copy()
    g[:, 0] = 0.0  # roll gyro dead on the bump crossing
    dead = check_drive_integrity(with_imu(bump, bump.imu.t_ns, g, bump.imu.accel), "dead.mcap").drive
    assert dead.extra["unusable_signals"] == ["roll_rate"]
    live = check_drive_integrity(sine, "sine.mcap").drive
    cases = as_cases([live, dead], wheelbase=wb)
    sims = [np.zeros((c.n_steps, 6)) for c in cases]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        both = noise_floor(cases, sims)
        alone = noise_floor(cases[:1], sims[:1])
    name_dead = cases[1].name
    assert math.isnan(both["per_drive"][name_dead]["roll_rate"])
    assert both["noise_floors"]["roll_rate"] == pytest.approx(alone["noise_floors"]["roll_rate"], rel=1e-12)
    assert both["noise_floors"]["roll_rate"] > 0
    # the live axes of the dead drive still count
    assert both["noise_floors"]["pitch_rate"] != pytest.approx(alone["noise_floors"]["pitch_rate"], rel=1e-6)
