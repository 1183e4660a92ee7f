"""Reliability of reading recordings: truncation at every byte, corrupt chunks, unknown schemas.

A small test drive (0.12 s of the bundled bump crossing: speed, steering, road profile, IMU; small chunks,
so a truncation can fall in any kind of record) is cut at every byte offset. The reading layer
(:func:`read_recording`, :func:`read_drive`) must give exactly the messages of the complete chunks before
the cut (the readable prefix) or a named RecordingError; the three entry points ``susp validate``,
``susp replay --dry-run`` and ``susp diagnose --dry-run`` (in-process ``cli.main.main``) must exit 0 with
the prefix or 2 with a message naming the file, never 1 or a traceback, at every 64th offset and at
every record boundary (and one byte before it). A few subprocess runs prove no traceback is printed.
Corrupted chunk CRCs, undecodable chunks and unknown schemas/encodings give named errors (exit 2).
"""
from __future__ import annotations

import io
import json
import logging
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from mcap.stream_reader import StreamReader, breakup_chunk
from mcap.records import Chunk, Message

from _cli_helpers import run_cli
from susp_sim_ros.errors import RecordingError
from susp_sim_ros.io import messages as M
from susp_sim_ros.io.drive import ImuSeries, Series, TestDrive, drive_messages, read_drive
from susp_sim_ros.io.reader import read_recording
from susp_sim_ros.io.recorder import McapRecorder

BAGS = Path(__file__).resolve().parents[1] / "bags"
STRIDE = 64
FIGURES: dict = {}


def small_drive(duration_s=0.12) -> TestDrive:
    d = read_drive(BAGS / "bump_crossing_intact.mcap")
    t_end = d.t0_ns + int(duration_s * 1e9)
    cut = lambda s: Series(s.t_ns[s.t_ns <= t_end], s.values[s.t_ns <= t_end])
    m = d.imu.t_ns <= t_end
    return TestDrive({"maneuver": "bump_crossing_8kmh", "damper_oil_level": "1,1,1,1", "source": "measured",
                      "vehicle": "passat_b8_like"}, cut(d.speed), cut(d.steering), d.road, None,
                     ImuSeries(d.imu.t_ns[m], d.imu.gyro[m], d.imu.accel[m]))


def write(path, drive, **kw) -> Path:
    with McapRecorder(path, metadata=drive.metadata, **kw) as rec:
        for t, topic, mt, msg, latched in drive_messages(drive):
            rec.write(topic, mt, t, msg, latched=latched)
    return Path(path)


def layout(data: bytes):
    """Top-level records of an MCAP: ``[(start, end, opcode)]`` and, per chunk end, its message count."""
    recs, pos = [], 8
    while pos + 9 <= len(data) - 8:
        op, ln = data[pos], struct.unpack_from("<Q", data, pos + 1)[0]
        recs.append((pos, pos + 9 + ln, op))
        pos += 9 + ln
    chunks = [r for r in StreamReader(io.BytesIO(data), emit_chunks=True).records if isinstance(r, Chunk)]
    ends = [e for s, e, op in recs if op == 0x06]
    assert len(ends) == len(chunks)
    counts = [sum(isinstance(x, Message) for x in breakup_chunk(c)) for c in chunks]
    return recs, list(zip(ends, counts))


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    p = write(tmp_path_factory.mktemp("trunc") / "small.mcap", small_drive(), chunk_size=2048)
    data = p.read_bytes()
    recs, chunk_ends = layout(data)
    full = read_recording(p)
    assert full.finalised and not full.truncated and len(full.messages) == sum(c for _, c in chunk_ends)
    return p, data, recs, chunk_ends, full


def prefix_count(chunk_ends, n: int) -> int:
    return sum(c for end, c in chunk_ends if end <= n)


def test_reader_at_every_byte_offset(small, tmp_path):
    """Every cut gives exactly the messages of the complete chunks before it, or a named error."""
    p, data, recs, chunk_ends, full = small
    meta_end = next(e for s, e, op in recs if op == 0x0C)
    footer_end = next(e for s, e, op in recs if op == 0x02)
    # read_drive (decodes every message: slower) at every 64th offset and around every record boundary
    drive_offsets = set(range(0, len(data) + 1, STRIDE)) | {e for _, e, _ in recs} | {e - 1 for _, e, _ in recs}
    cut = tmp_path / "cut.mcap"
    speeds = small_drive().speed.values
    logging.disable(logging.WARNING)
    outcomes = {"prefix": 0, "named_error": 0, "drive": 0, "drive_named_error": 0}
    try:
        for n in range(len(data) + 1):
            cut.write_bytes(data[:n])
            try:
                rec = read_recording(cut)
            except RecordingError as exc:
                assert n < 8 and "cut.mcap" in str(exc) and "not an MCAP" in str(exc), (n, exc)
                outcomes["named_error"] += 1
                continue
            k = prefix_count(chunk_ends, n)
            assert len(rec.messages) == k, (n, len(rec.messages), k)
            assert [(m.topic, m.log_time_ns, m.data) for m in rec.messages] == \
                [(m.topic, m.log_time_ns, m.data) for m in full.messages[:k]], n
            assert not rec.corrupt and rec.truncated == (n < len(data)) and rec.finalised == (n >= footer_end)
            assert ("test_drive" in rec.metadata) == (n >= meta_end), n
            outcomes["prefix"] += 1
            if n not in drive_offsets:
                continue
            try:
                d = read_drive(cut)
            except RecordingError as exc:
                assert "cut.mcap" in str(exc), (n, exc)
                outcomes["drive_named_error"] += 1
            else:
                ns = len(d.speed)
                np.testing.assert_array_equal(d.speed.values, speeds[:ns])
                outcomes["drive"] += 1
    finally:
        logging.disable(logging.NOTSET)
    FIGURES["reader_offsets"] = len(data) + 1
    print(f"\nreader: {len(data) + 1} truncation offsets of a {len(data)}-byte drive ({len(recs)} records, "
          f"{len(chunk_ends)} chunks), read_drive at {len(drive_offsets)} of them: {outcomes}")


def test_entry_points_at_every_64th_byte_and_every_record_boundary(small, tmp_path):
    p, data, recs, chunk_ends, full = small
    offsets = sorted(set(range(0, len(data) + 1, STRIDE)) | {e for _, e, _ in recs} |
                     {e - 1 for _, e, _ in recs} | {len(data)})
    cut = tmp_path / "cut.mcap"
    inputs = {"/vehicle/speed", "/vehicle/steering_wheel_angle", "/road/profile", "/imu/data"}
    tally = {c: {0: 0, 2: 0} for c in ("validate", "replay", "diagnose")}
    logging.disable(logging.WARNING)
    try:
        for n in offsets:
            cut.write_bytes(data[:n])
            k = prefix_count(chunk_ends, n) if n >= 8 else 0
            for cmd, argv in (("validate", ["validate", "--measured", str(cut), "--simulated", str(cut), "--json"]),
                              ("replay", ["replay", str(cut), "--dry-run", "--json"]),
                              ("diagnose", ["diagnose", str(cut), "--dry-run", "--json"])):
                rc, out, err = run_cli(argv)
                assert rc in (0, 2) and "Traceback" not in err, (cmd, n, rc, err)
                if rc == 2:
                    assert f"susp {cmd}: error:" in err and "cut.mcap" in err, (cmd, n, err)
                else:
                    res = json.loads(out)
                    if cmd == "replay":
                        assert res["messages"] == sum(1 for m in full.messages[:k] if m.topic in inputs)
                    elif cmd == "validate":
                        assert res["measured_truncated"] == (n < len(data))
                tally[cmd][rc] += 1
    finally:
        logging.disable(logging.NOTSET)
    FIGURES["entry_point_offsets"] = len(offsets)
    print(f"\nentry points: {len(offsets)} truncation offsets each (every {STRIDE}th byte and each of the "
          f"{len(recs)} record boundaries and one byte before): exit codes {tally}")
    for cmd, t in tally.items():
        assert t[0] > 0 and t[2] > 0, (cmd, t)  # both outcomes were exercised


@pytest.mark.parametrize("fraction", [0.62])
def test_no_traceback_from_real_processes(small, tmp_path, fraction):
    p, data, *_ = small
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[:int(len(data) * fraction)])
    for argv in (["validate", "--measured", str(cut), "--simulated", str(p)], ["replay", str(cut), "--dry-run"],
                 ["diagnose", str(cut), "--dry-run"]):
        r = subprocess.run([sys.executable, "-m", "susp_sim_ros.cli.main", *argv], capture_output=True, text=True,
                           timeout=120)
        assert r.returncode in (0, 2) and "Traceback" not in r.stderr, (argv, r.returncode, r.stderr)
        if r.returncode == 2:
            assert "cut.mcap" in r.stderr


# ---- corruption -------------------------------------------------------------------------------------------
def _all_entry_points_refuse(path: Path, needle: str) -> None:
    for cmd, argv in (("validate", ["validate", "--measured", str(path), "--simulated", str(path)]),
                      ("replay", ["replay", str(path), "--dry-run"]),
                      ("diagnose", ["diagnose", str(path), "--dry-run"])):
        rc, out, err = run_cli(argv)
        assert rc == 2 and path.name in err and needle in err and "Traceback" not in err, (cmd, rc, err)


def test_corrupted_chunk_crc_is_a_named_error(tmp_path):
    p = write(tmp_path / "ok.mcap", small_drive(), chunk_size=2048, compression="none")
    data = bytearray(p.read_bytes())
    recs, _ = layout(bytes(data))
    starts = [s for s, e, op in recs if op == 0x06]
    # 1. a flipped bit in the chunk's payload (uncompressed: the records still parse, the CRC does not match)
    bad = bytearray(data)
    bad[starts[1] + 9 + 40 + 30] ^= 0x10
    (tmp_path / "payload.mcap").write_bytes(bad)
    with pytest.raises(RecordingError, match=r"payload.mcap: corrupt MCAP.*crc"):
        read_recording(tmp_path / "payload.mcap")
    _all_entry_points_refuse(tmp_path / "payload.mcap", "corrupt MCAP")
    # 2. the stored CRC itself damaged
    bad = bytearray(data)
    crc_at = starts[0] + 9 + 24
    bad[crc_at:crc_at + 4] = struct.pack("<I", struct.unpack_from("<I", data, crc_at)[0] ^ 0xFFFF)
    (tmp_path / "crc.mcap").write_bytes(bad)
    _all_entry_points_refuse(tmp_path / "crc.mcap", "corrupt MCAP")
    # 3. garbage in a compressed chunk
    p2 = write(tmp_path / "z.mcap", small_drive(), chunk_size=2048)
    bad = bytearray(p2.read_bytes())
    s2 = [s for s, e, op in layout(bytes(bad))[0] if op == 0x06][1]
    bad[s2 + 60:s2 + 90] = b"\xa5" * 30
    (tmp_path / "zgarbage.mcap").write_bytes(bad)
    _all_entry_points_refuse(tmp_path / "zgarbage.mcap", "corrupt MCAP")
    # susp recover salvages the chunks before the damage into a clean file
    rc, out, err = run_cli(["recover", str(tmp_path / "payload.mcap"), "--out", str(tmp_path / "fixed.mcap"), "--json"])
    res = json.loads(out)
    assert rc == 0 and res["was_corrupt"] and 0 < res["messages"]
    assert read_recording(tmp_path / "fixed.mcap").finalised


def _raw_mcap(path, channels):
    """An MCAP with hand-made schemas/channels: ``channels`` = [(topic, schema name, schema encoding,
    schema text, message encoding, [(t, bytes)])]."""
    from mcap.writer import Writer
    with open(path, "wb") as f:
        w = Writer(f)
        w.start(profile="ros2")
        w.add_metadata("test_drive", {"maneuver": "x", "source": "measured"})
        for topic, name, enc, text, menc, msgs in channels:
            sid = w.register_schema(name, enc, text.encode())
            cid = w.register_channel(topic, menc, sid)
            for t, b in msgs:
                w.add_message(cid, log_time=t, data=b, publish_time=t)
        w.finish()
    return Path(path)


def _good_inputs(n=40):
    t = [1_000_000_000 + k * 10_000_000 for k in range(n)]
    f64 = [(x, M.encode(M.FLOAT64, {"data": 5.0})) for x in t]
    imu = [(x, M.encode(M.IMU, {"header": {"stamp": M.stamp(x)}})) for x in t]
    return [("/vehicle/speed", M.FLOAT64, "ros2msg", M.full_definition(M.FLOAT64), "cdr", f64),
            ("/vehicle/steering_wheel_angle", M.FLOAT64, "ros2msg", M.full_definition(M.FLOAT64), "cdr", f64),
            ("/imu/data", M.IMU, "ros2msg", M.full_definition(M.IMU), "cdr", imu)]


@pytest.mark.parametrize("case", ["wrong_type", "protobuf_schema", "json_messages", "no_schema", "garbage_cdr"])
def test_unknown_schemas_on_needed_topics_are_named_errors(tmp_path, case):
    ch = _good_inputs()
    topic, name, enc, text, menc, msgs = ch[0]
    if case == "wrong_type":
        ch[0] = (topic, "acme_msgs/msg/Speed", enc, "float32 kmh\n", menc, msgs)
        needle = "/vehicle/speed has type acme_msgs/msg/Speed"
    elif case == "protobuf_schema":
        ch[0] = (topic, name, "protobuf", "\x00\x01", menc, msgs)
        needle = "/vehicle/speed"
    elif case == "json_messages":
        ch[0] = (topic, name, enc, text, "json", [(t, b'{"data": 5.0}') for t, _ in msgs])
        needle = "/vehicle/speed"
    elif case == "no_schema":
        ch[0] = (topic, "", "", "", menc, msgs)
        needle = "/vehicle/speed"
    else:
        ch[0] = (topic, name, enc, text, menc, [(t, b"\x00\x01\x00\x00\x01") for t, _ in msgs])
        needle = "/vehicle/speed"
    p = _raw_mcap(tmp_path / f"{case}.mcap", ch)
    with pytest.raises(RecordingError, match=needle.replace("/", ".")):
        read_drive(p)
    _all_entry_points_refuse(p, needle)


def test_unknown_extra_topics_are_ignored_or_skipped(tmp_path):
    """A topic nobody here needs, of a type nobody here knows: validate/diagnose ignore it, replay skips it
    with a warning (as ros2 bag play does) and refuses it by name when asked for explicitly."""
    ch = _good_inputs() + [("/camera/blob", "acme_msgs/msg/Blob", "ros2msg", "uint8[] pixels\n", "cdr",
                            [(1_000_000_000, b"\x00\x01\x00\x00\x00\x00\x00\x00")])]
    p = _raw_mcap(tmp_path / "extra.mcap", ch)
    assert read_drive(p).speed.values.size == 40
    rc, out, err = run_cli(["replay", str(p), "--dry-run", "--json"])
    assert rc == 0 and json.loads(out)["skipped_topics"] == ["/camera/blob"] and "acme_msgs/msg/Blob" in err
    rc, out, err = run_cli(["replay", str(p), "--dry-run", "--topics", "/camera/blob"])
    assert rc == 2 and "/camera/blob" in err and "unknown schema" in err
    rc, out, err = run_cli(["diagnose", str(p), "--dry-run"])
    assert rc == 0, err


# ---- recordings that are not ROS 2, and damaged rosbag2 containers (issue 16) ---------------------------
def test_not_ros2_and_damaged_rosbag2_containers_are_named_errors(tmp_path):
    from mcap.writer import Writer
    for profile, needle in (("ros1", "MCAP profile 'ros1' is not a ROS 2 recording"),
                            ("", "not a ROS 2 recording: no profile and no cdr channel")):
        p = tmp_path / f"profile_{profile or 'none'}.mcap"
        with open(p, "wb") as f:
            w = Writer(f)
            w.start(profile=profile)
            sid = w.register_schema("Speed", "jsonschema", b"{}")
            cid = w.register_channel("/vehicle/speed", "json", sid)
            w.add_message(cid, log_time=1, publish_time=1, data=b'{"data": 1}')
            w.finish()
        _all_entry_points_refuse(p, needle)
    (tmp_path / "old.bag").write_bytes(b"#ROSBAG V2.0\n" + bytes(100))
    _all_entry_points_refuse(tmp_path / "old.bag", "a ROS 1 bag")
    (tmp_path / "junk.db3").write_bytes(b"SQLite format 3\x00" + b"\xa5" * 4000)
    _all_entry_points_refuse(tmp_path / "junk.db3", "cannot read rosbag2 recording")
    bag = tmp_path / "bagdir"
    bag.mkdir()
    (bag / "metadata.yaml").write_text("rosbag2_bagfile_information:\n  storage_identifier: mcap\n"
                                       "  relative_file_paths: [bagdir_0.mcap]\n")
    _all_entry_points_refuse(bag, "lacks the split file(s) bagdir_0.mcap")
    write(bag / "bagdir_0.mcap", small_drive())  # now present: the directory reads as its one split
    assert read_drive(bag).speed.values.size == small_drive().speed.values.size
