"""Test drives: write/read round trip, named errors for bad files, truncated-file prefix."""
from __future__ import annotations

import logging

import numpy as np
import pytest

from susp_sim_ros.errors import RecordingError
from susp_sim_ros.io import ImuSeries, Series, TestDrive, read_drive, read_imu, write_drive
from susp_sim_ros.io import messages as M
from susp_sim_ros.io.recorder import McapRecorder
from susp_sim_ros.model import cosine_bump

T0 = 2_000_000_000


def make_drive(n=1500, with_heights=False, with_imu=True, road=True):
    t = T0 + np.arange(n, dtype=np.int64) * 10_000_000
    rng = np.random.default_rng(3)
    return TestDrive(
        {"vehicle": "passat_b8_like", "maneuver": "unit", "damper_oil_level": "1,1,0,0.5",
         "source": "synthetic:test", "notes": "äöü, commas, = signs"},
        Series(t, 2.0 + rng.random(n)), Series(t + 1, rng.normal(size=n)),
        cosine_bump(0.05, 0.5, 2.0) if road else None,
        Series(t, rng.normal(size=(n, 4)) * 0.01) if with_heights else None,
        ImuSeries(t + 2, rng.normal(size=(n, 3)), rng.normal(size=(n, 3))) if with_imu else None)


@pytest.mark.parametrize("with_heights", [False, True])
@pytest.mark.parametrize("with_imu", [False, True])
@pytest.mark.parametrize("road", [False, True])
def test_write_read_round_trip_exact(tmp_path, with_heights, with_imu, road):
    d = make_drive(with_heights=with_heights, with_imu=with_imu, road=road)
    path = tmp_path / "d.mcap"
    write_drive(path, d)
    r = read_drive(path)
    assert r.metadata == d.metadata
    assert r.oil_levels() == (1.0, 1.0, 0.0, 0.5)
    for a, b in ((r.speed, d.speed), (r.steering, d.steering)):
        np.testing.assert_array_equal(a.t_ns, b.t_ns)
        np.testing.assert_array_equal(a.values, b.values)
    if road:
        np.testing.assert_array_equal(r.road.s, d.road.s)
        np.testing.assert_array_equal(r.road.zl, d.road.zl)
    else:
        assert r.road is None
    if with_heights:
        np.testing.assert_array_equal(r.wheel_heights.values, d.wheel_heights.values)
    if with_imu:
        np.testing.assert_array_equal(r.imu.t_ns, d.imu.t_ns)
        np.testing.assert_array_equal(r.imu.gyro, d.imu.gyro)
        np.testing.assert_array_equal(read_imu(path).accel, d.imu.accel)
    assert r.t0_ns == T0 and r.duration_s == pytest.approx(14.99 + 1e-9)
    with pytest.raises(Exception, match="exists already"):
        write_drive(path, d)


def test_rosbags_reads_a_drive(tmp_path):
    from rosbags.highlevel import AnyReader
    path = tmp_path / "d.mcap"
    write_drive(path, make_drive(n=50))
    with AnyReader([path]) as r:
        topics = {c.topic: c.msgtype for c in r.connections}
        for c, _, raw in r.messages():
            r.deserialize(raw, c.msgtype)
    assert topics == {"/vehicle/speed": M.FLOAT64, "/vehicle/steering_wheel_angle": M.FLOAT64,
                      "/road/profile": M.FLOAT64_ARRAY, "/imu/data": M.IMU}


def test_not_mcap(tmp_path):
    p = tmp_path / "x.mcap"
    p.write_text("hello")
    with pytest.raises(RecordingError, match=r"x\.mcap.*not an MCAP"):
        read_drive(p)
    with pytest.raises(RecordingError, match="cannot open"):
        read_drive(tmp_path / "missing.mcap")


def test_no_messages(tmp_path):
    p = tmp_path / "empty.mcap"
    McapRecorder(p, metadata={"source": "measured"}).close()
    with pytest.raises(RecordingError, match="no readable messages"):
        read_drive(p)


def test_missing_topic_named(tmp_path):
    p = tmp_path / "m.mcap"
    with McapRecorder(p) as rec:
        rec.write("/vehicle/speed", M.FLOAT64, 1, {"data": 1.0})
    with pytest.raises(RecordingError, match="/vehicle/steering_wheel_angle"):
        read_drive(p)


@pytest.mark.parametrize("data,dims,match", [
    ([0.0, 1.0, 0.5, 0, 0, 0, 0, 0, 0], [("channel", 3, 9), ("sample", 3, 3)], "strictly increasing"),
    ([0.0, 1.0, 0, 0], [("channel", 3, 6), ("sample", 2, 2)], "values"),
    ([0.0, 1.0], [("sample", 2, 2)], "layout"),
    ([0.0, float("nan"), 2.0, 0, 0, 0, 0, 0, 0], [("channel", 3, 9), ("sample", 3, 3)], "finite"),
])
def test_malformed_road_profile(tmp_path, data, dims, match):
    p = tmp_path / "r.mcap"
    with McapRecorder(p) as rec:
        rec.write("/road/profile", M.FLOAT64_ARRAY, 0, {
            "layout": {"dim": [{"label": l, "size": s, "stride": st} for l, s, st in dims]}, "data": data},
            latched=True)
        rec.write("/vehicle/speed", M.FLOAT64, 1, {"data": 1.0})
        rec.write("/vehicle/steering_wheel_angle", M.FLOAT64, 1, {"data": 0.0})
    with pytest.raises(RecordingError, match=rf"r\.mcap.*/road/profile.*{match}"):
        read_drive(p)


def test_bad_oil_metadata(tmp_path):
    d = make_drive(n=10)
    d.metadata["damper_oil_level"] = "1,1,2"
    write_drive(tmp_path / "o.mcap", d)
    with pytest.raises(RecordingError, match="damper_oil_level"):
        read_drive(tmp_path / "o.mcap")


@pytest.mark.parametrize("fraction", [0.05, 0.3, 0.6, 0.9, 0.999])
def test_truncated_file_yields_readable_prefix(tmp_path, fraction, caplog):
    full = tmp_path / "full.mcap"
    d = make_drive(n=3000)
    from susp_sim_ros.io.drive import drive_messages
    with McapRecorder(full, metadata=d.metadata, chunk_size=4096) as rec:
        for t, topic, mt, msg, latched in drive_messages(d):
            rec.write(topic, mt, t, msg, latched=latched)
    data = full.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[:int(len(data) * fraction)])
    with caplog.at_level(logging.WARNING):
        try:
            r = read_drive(cut)
        except RecordingError as exc:  # too little left: a named error, never a crash
            assert "cut.mcap" in str(exc)
            return
    assert "truncated" in caplog.text
    n = len(r.speed)
    assert 0 < n <= 3000  # a cut in the summary section loses no messages
    np.testing.assert_array_equal(r.speed.values, d.speed.values[:n])
    assert r.extra["truncated"]


def test_garbage_inside_a_chunk(tmp_path):
    p = tmp_path / "g.mcap"
    write_drive(p, make_drive(n=2000))
    b = bytearray(p.read_bytes())
    b[len(b) // 2:len(b) // 2 + 64] = b"\xff" * 64
    p.write_bytes(bytes(b))
    try:
        r = read_drive(p)
        assert len(r.speed) <= 2000
    except RecordingError as exc:
        assert "g.mcap" in str(exc)
