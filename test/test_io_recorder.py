"""MCAP recorder round trips (read back by mcap_ros2 and rosbags), overwrite refusal, killed recorder."""
from __future__ import annotations

import signal
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from susp_sim_ros.errors import RecordingError, RecordingExistsError
from susp_sim_ros.io import messages as M
from susp_sim_ros.io.reader import read_recording
from susp_sim_ros.io.recorder import McapRecorder
from susp_sim_ros.model.layout import OUTPUT_LABELS

META = {"vehicle": "passat_b8_like", "maneuver": "test", "damper_oil_level": "1,1,0.5,0", "source": "measured"}


def _messages(n=300):
    rng = np.random.default_rng(1)
    out = []
    for k in range(n):
        t = 1_000_000_000 + k * 10_000_000 + int(rng.integers(0, 5))
        y = rng.normal(size=len(OUTPUT_LABELS))
        out.append((t, "/vehicle/speed", M.FLOAT64, {"data": float(y[0])}, False))
        out.append((t, "/sim/imu/data", M.IMU, M.imu_msg(t, y), False))
        out.append((t, "/sim/suspension", M.FLOAT64_ARRAY, M.suspension_msg(y), False))
        if k % 50 == 0:
            out.append((t, "/sim/odom", M.ODOMETRY, M.odom_msg(t, y), False))
    out.insert(0, (1_000_000_000, "/road/profile", M.FLOAT64_ARRAY,
                   M.road_profile_msg([0.0, 1.0, 2.0], [0, 0.05, 0], [0, 0.04, 0]), True))
    return out


@pytest.mark.parametrize("compression", ["zstd", "lz4", "none"])
@pytest.mark.parametrize("chunk_size", [512, 256 * 1024])
@pytest.mark.parametrize("as_bytes", [False, True])
def test_round_trip_exact(tmp_path, compression, chunk_size, as_bytes):
    path = tmp_path / "r.mcap"
    msgs = _messages()
    with McapRecorder(path, metadata=META, chunk_size=chunk_size, compression=compression) as rec:
        for t, topic, mt, msg, latched in msgs:
            rec.write(topic, mt, t, M.encode(mt, msg) if as_bytes else msg, latched=latched)
    # mcap_ros2 decoder, through the summary/index
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        summary = reader.get_summary()
        assert reader.get_header().profile == "ros2"
        assert {s.encoding for s in summary.schemas.values()} == {"ros2msg"}
        assert {c.message_encoding for c in summary.channels.values()} == {"cdr"}
        assert summary.chunk_indexes  # chunked and indexed
        got = [(m.log_time, c.topic, m.sequence, M.to_dict(d))
               for _, c, m, d in reader.iter_decoded_messages(log_time_order=False)]
        meta = {r.name: r.metadata for r in reader.iter_metadata()}
    assert meta == {"test_drive": META}
    assert [(g[0], g[1]) for g in got] == [(m[0], m[1]) for m in msgs]
    seq: dict[str, int] = {}
    for (_t, topic, s, d), (_, _, mt, msg, _) in zip(got, msgs):
        seq[topic] = seq.get(topic, 0) + 1
        assert s == seq[topic]
        assert d == M.to_dict(M.decode(mt, M.encode(mt, msg)))
    # rosbags, an independent implementation
    from rosbags.highlevel import AnyReader
    with AnyReader([path]) as r:
        conns = {c.topic: c for c in r.connections}
        assert conns["/road/profile"].ext.offered_qos_profiles[0].durability.name == "TRANSIENT_LOCAL"
        assert conns["/sim/imu/data"].ext.offered_qos_profiles[0].durability.name == "VOLATILE"
        rb = [(ts, c.topic, r.deserialize(raw, c.msgtype)) for c, ts, raw in r.messages()]
    assert sorted((t, topic) for t, topic, _ in rb) == sorted((m[0], m[1]) for m in msgs)
    imu = [m for t, topic, m in rb if topic == "/sim/imu/data"]
    src = [m[3] for m in msgs if m[1] == "/sim/imu/data"]
    assert [m.angular_velocity.y for m in imu] == [d["angular_velocity"]["y"] for d in src]


def test_refuses_to_overwrite(tmp_path):
    path = tmp_path / "x.mcap"
    path.write_bytes(b"keep")
    with pytest.raises(RecordingExistsError, match="exists already, not overwriting"):
        McapRecorder(path)
    assert path.read_bytes() == b"keep"
    with McapRecorder(path, overwrite=True) as rec:
        rec.write("/vehicle/speed", M.FLOAT64, 1, {"data": 1.0})
    assert read_recording(path).messages[0].log_time_ns == 1


def test_topic_type_conflict(tmp_path):
    with McapRecorder(tmp_path / "c.mcap") as rec:
        rec.write("/a", M.FLOAT64, 1, {"data": 1.0})
        with pytest.raises(RecordingError, match="/a"):
            rec.write("/a", M.IMU, 2, {})


def test_sigkilled_recorder_leaves_a_readable_prefix_and_recover_finalises_it(tmp_path):
    path = tmp_path / "killed.mcap"
    code = textwrap.dedent(f"""
        import os, signal, sys, time
        from susp_sim_ros.io.recorder import McapRecorder
        rec = McapRecorder({str(path)!r}, metadata={{"source": "measured"}}, chunk_size=2048)
        for k in range(2000):
            rec.write("/vehicle/speed", "std_msgs/msg/Float64", k * 1000, {{"data": float(k)}})
        os.kill(os.getpid(), signal.SIGKILL)
    """)
    p = subprocess.run([sys.executable, "-c", code], capture_output=True)
    assert p.returncode == -signal.SIGKILL
    rec = read_recording(path)
    assert rec.metadata["test_drive"] == {"source": "measured"}
    n = len(rec.messages)
    assert 1500 < n < 2000  # everything up to the last complete chunk
    assert [m.log_time_ns for m in rec.messages] == [k * 1000 for k in range(n)]
    from rosbags.highlevel import AnyReader
    with AnyReader([path]) as r:  # the killed file is a complete MCAP as it is (recorder commits)
        assert [t for _, t, _ in r.messages()] == [k * 1000 for k in range(n)]
    from susp_sim_ros.cli.recover import recover
    out = tmp_path / "fixed.mcap"
    res = recover(path, out)
    assert res["messages"] == n and res["was_truncated"]
    fixed = read_recording(out)
    assert not fixed.truncated and len(fixed.messages) == n
    assert [m.sequence for m in fixed.messages] == [m.sequence for m in rec.messages]
    with AnyReader([out]) as r:
        assert sum(1 for _ in r.messages()) == n


def test_flush_interval_pushes_chunks(tmp_path):
    path = tmp_path / "f.mcap"
    rec = McapRecorder(path, flush_interval_s=0.0)
    rec.write("/vehicle/speed", M.FLOAT64, 5, {"data": 2.0})
    assert len(read_recording(path).messages) == 1  # already on disk before close
    rec.close()
    rec.close()  # idempotent
