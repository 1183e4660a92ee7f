"""Recordings nobody here chose, read by every command through a topic map (issue 16, items 2 and 3).

The bundled bump crossing (and, for the degree steering, the sine steer) is rewritten into a typical car's
layout (odometry speed, CAN steering in degrees, FRD or rotated IMU; test/_foreign_corpus.py) with the real
writers: rclpy serialisation + mcap (no summary/index, zstd, lz4, rosbag2 split directories), rosbags'
rosbag2 writer (MCAP and sqlite3 directories, a bare .db3). Every command (sim --drive, validate, diagnose,
replay) reads each through config/topic_maps/car_odom_can_frd.yaml and gives the same numbers as the
original file in the interface layout. Non-ROS-2 files, truncated/corrupt files and files with none of the
mapped topics exit 2 with a named error, never a traceback.
"""
from __future__ import annotations

import logging
import shutil
from pathlib import Path

import numpy as np
import pytest

from _foreign_corpus import CAR_MAP, bare_db3, car_mcap, car_messages, car_rosbags, car_split_dir, _mcap
from _cli_helpers import cli_json, run_cli
from susp_sim_ros.errors import NotRos2RecordingError, RecordingError, UnknownMessageTypeError
from susp_sim_ros.io import messages as M
from susp_sim_ros.io.drive import read_drive
from susp_sim_ros.io.reader import read_recording

BAGS = Path(__file__).resolve().parents[1] / "bags"
BUMP = BAGS / "bump_crossing_intact.mcap"
LAYOUTS = ("noindex_zstd.mcap", "lz4.mcap", "split", "rosbags_mcap", "rosbags_db3", "bare.db3")


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    d = tmp_path_factory.mktemp("corpus")
    drive = read_drive(BUMP)
    paths = {"noindex_zstd.mcap": car_mcap(d / "noindex_zstd.mcap", drive, index=False),
             "lz4.mcap": car_mcap(d / "lz4.mcap", drive, compression="lz4"),
             "split": car_split_dir(d / "split", drive),
             "rosbags_mcap": car_rosbags(d / "rosbags_mcap", drive, "mcap"),
             "rosbags_db3": car_rosbags(d / "rosbags_db3", drive, "sqlite3"),
             "bare.db3": bare_db3(d / "bare.db3", drive)}
    own_sim = d / "own_sim.mcap"
    cli_json(["sim", "--drive", BUMP, "--out", own_sim])
    own = cli_json(["validate", "--measured", BUMP, "--simulated", own_sim])
    return d, paths, own_sim, own


def _metrics(res: dict) -> dict:
    return {w: {s: {k: v for k, v in m.items()} for s, m in win["signals"].items()}
            for w, win in res["windows"].items()}


def test_every_layout_reads_as_the_interface_layout(corpus):
    d, paths, _, _ = corpus
    ref = read_drive(BUMP)
    for name, p in paths.items():
        x = read_drive(p, topic_map=CAR_MAP)
        # odometry speed and the FRD IMU (sign flips) are exact; degrees -> radians within a rounding
        np.testing.assert_array_equal(x.speed.values, ref.speed.values, err_msg=name)
        np.testing.assert_array_equal(x.speed.t_ns, ref.speed.t_ns, err_msg=name)
        np.testing.assert_array_equal(x.imu.gyro, ref.imu.gyro, err_msg=name)
        np.testing.assert_array_equal(x.imu.accel, ref.imu.accel, err_msg=name)
        np.testing.assert_array_equal(x.imu.t_ns, ref.imu.t_ns, err_msg=name)
        np.testing.assert_allclose(x.steering.values, ref.steering.values, rtol=1e-15, atol=0, err_msg=name)
        np.testing.assert_array_equal(x.road.zl, ref.road.zl, err_msg=name)
        assert read_recording(p).latched("/road/profile"), name  # the latch survives every container
        assert x.extra.get("input_findings", []) == [], name  # undamaged in any container: no finding (issue 28)


@pytest.mark.parametrize("layout", LAYOUTS)
def test_validate_gives_the_same_numbers_through_the_topic_map(corpus, layout):
    d, paths, own_sim, own = corpus
    res = cli_json(["validate", "--measured", paths[layout], "--topic-map", CAR_MAP, "--simulated", own_sim])
    assert _metrics(res) == _metrics(own)  # same samples in, same figures out, exactly
    assert res["rmse_deg_s"]["bump"]["pitch_rate"] == own["rmse_deg_s"]["bump"]["pitch_rate"] > 0


@pytest.mark.parametrize("layout", ["noindex_zstd.mcap", "rosbags_db3"])
def test_sim_from_a_foreign_layout_equals_sim_from_the_interface_layout(corpus, layout):
    d, paths, own_sim, own = corpus
    out = d / f"sim_{layout.replace('.', '_')}.mcap"
    sim = cli_json(["sim", "--drive", paths[layout], "--topic-map", CAR_MAP, "--out", out])
    assert sim["ok"] and sim["samples"] > 0
    res = cli_json(["validate", "--measured", paths[layout], "--topic-map", CAR_MAP, "--simulated", out])
    assert _metrics(res) == _metrics(own)
    np.testing.assert_array_equal(read_drive(out, imu_topic="/sim/imu/data").imu.gyro,
                                  read_drive(own_sim, imu_topic="/sim/imu/data").imu.gyro)


def test_degree_steering_through_the_map_simulates_the_same_sine_steer(tmp_path):
    src = BAGS / "sine_steer_intact.mcap"
    foreign = car_mcap(tmp_path / "sine.mcap", read_drive(src), index=False)
    a = cli_json(["sim", "--drive", src, "--out", tmp_path / "a.mcap"])
    b = cli_json(["sim", "--drive", foreign, "--topic-map", CAR_MAP, "--out", tmp_path / "b.mcap"])
    # the steering differs by a rounding of deg -> rad (1e-16 relative): the roll rate peak agrees to 1e-9
    assert b["peak_roll_rate_deg_s"] == pytest.approx(a["peak_roll_rate_deg_s"], rel=1e-9)
    assert a["peak_roll_rate_deg_s"] > 1.0


def test_mounted_imu_is_rotated_back_onto_body_axes(tmp_path):
    ref = read_drive(BUMP)
    p = _mcap(tmp_path / "mounted.mcap", car_messages(ref, mount_rpy_deg=[10.0, -5.0, 90.0]))
    m = tmp_path / "mounted.yaml"
    m.write_text(CAR_MAP.read_text().replace("frame: frd", "frame: {rpy_deg: [10, -5, 90]}"))
    x = read_drive(p, topic_map=m)
    np.testing.assert_allclose(x.imu.gyro, ref.imu.gyro, rtol=0, atol=1e-15)  # rad/s: rotation round-off
    np.testing.assert_allclose(x.imu.accel, ref.imu.accel, rtol=0, atol=1e-13)  # m/s^2 (about 10 m/s^2)


@pytest.mark.parametrize("layout", LAYOUTS)
def test_diagnose_and_replay_read_every_layout(corpus, layout):
    d, paths, _, _ = corpus
    own_r = cli_json(["replay", BUMP, "--dry-run"])
    r = cli_json(["replay", paths[layout], "--dry-run", "--topic-map", CAR_MAP])
    assert r["counts"] == own_r["counts"]  # the mapped inputs, played on the interface's topics
    dg = cli_json(["diagnose", paths[layout], "--dry-run", "--topic-map", CAR_MAP])
    own_dg = cli_json(["diagnose", BUMP, "--dry-run"])
    assert dg["drives"][0]["imu_samples"] == own_dg["drives"][0]["imu_samples"]
    assert dg["drives"][0]["duration_s"] == own_dg["drives"][0]["duration_s"]


def test_inspect_reads_a_foreign_layout_through_the_map(corpus):
    """The damper inspection of the split rosbag2 directory (odometry speed, degree steering, FRD IMU)
    read through the car map equals the inspection of the same drive in the interface's layout."""
    d, paths, _, _ = corpus
    own = cli_json(["inspect", BUMP])
    r = cli_json(["inspect", paths["split"], "--topic-map", CAR_MAP])
    for w, e in own["wheels"].items():
        assert r["wheels"][w]["state"] == e["state"]
        assert r["wheels"][w]["oil_level"] == pytest.approx(e["oil_level"], abs=1e-6)
        assert r["wheels"][w]["ci95"] == pytest.approx(e["ci95"], abs=1e-6)


def test_replay_without_map_reads_rosbag2_containers(corpus):
    d, paths, _, _ = corpus
    for layout in ("split", "rosbags_db3", "bare.db3"):
        r = cli_json(["replay", paths[layout], "--dry-run"])
        assert set(r["topics"]) == {"/odom", "/can/steering_wheel_angle", "/imu/data_raw", "/road/profile"}


def test_diagnose_cases_through_the_map_equal_the_interface_cases(corpus):
    from susp_sim_ros.analysis.discrepancy.data import load_cases
    d, paths, _, _ = corpus
    a = load_cases([BUMP], wheelbase=2.79)[0]
    b = load_cases([paths["split"]], wheelbase=2.79, topic_map=CAR_MAP)[0]  # with test_drive metadata
    np.testing.assert_array_equal(a.U, b.U)
    np.testing.assert_array_equal(a.y_meas, b.y_meas)


def test_identity_map_changes_nothing(corpus):
    d, paths, own_sim, own = corpus
    res = cli_json(["validate", "--measured", BUMP, "--topic-map", "interface", "--simulated", own_sim])
    assert _metrics(res) == _metrics(own)


# ---- what must be refused, by every command --------------------------------------------------------------
def _every_command_refuses(p, needle, own_sim, topic_map=CAR_MAP, replay=True):
    tm = ["--topic-map", topic_map] if topic_map else []
    for argv in (["sim", "--drive", p, *tm], ["validate", "--measured", p, "--simulated", own_sim, *tm],
                 ["diagnose", p, "--dry-run", *tm], ["inspect", p, *tm],
                 *([["replay", p, "--dry-run", *tm]] if replay else [])):
        rc, out, err = run_cli(argv)
        assert rc == 2 and needle in err and "Traceback" not in err, (argv, rc, err)


def _json_mcap(path, profile):
    from mcap.writer import Writer
    with open(path, "wb") as f:
        w = Writer(f)
        w.start(profile=profile)
        sid = w.register_schema("Speed", "jsonschema", b'{"type": "object"}')
        cid = w.register_channel("/odom", "json", sid)
        for k in range(20):
            w.add_message(cid, log_time=k * 10_000_000, publish_time=k * 10_000_000, data=b'{"v": 1.0}')
        w.finish()
    return path


def test_non_ros2_recordings_are_named_errors(corpus, tmp_path):
    d, paths, own_sim, _ = corpus
    p = _json_mcap(tmp_path / "foxglove_json.mcap", "")
    with pytest.raises(NotRos2RecordingError, match="not a ROS 2 recording"):
        read_recording(p)
    _every_command_refuses(p, "not a ROS 2 recording", own_sim)
    p = _json_mcap(tmp_path / "ros1.mcap", "ros1")
    _every_command_refuses(p, "MCAP profile 'ros1' is not a ROS 2 recording", own_sim)
    ros1 = tmp_path / "old.bag"
    ros1.write_bytes(b"#ROSBAG V2.0\n" + b"\x00" * 64)
    _every_command_refuses(ros1, "a ROS 1 bag", own_sim, topic_map=None)
    # a ROS 2 profile with the speed as JSON: the needed topic is named
    from mcap.writer import Writer
    with open(tmp_path / "mixed.mcap", "wb") as f:
        w = Writer(f)
        w.start(profile="ros2")
        chans = {}
        for t, topic, mt, data in car_messages(read_drive(BUMP)):
            if topic not in chans:
                json_odom = topic == "/odom"
                sid = w.register_schema(mt, "jsonschema" if json_odom else "ros2msg",
                                        b"{}" if json_odom else M.full_definition(mt).encode())
                chans[topic] = w.register_channel(topic, "json" if json_odom else "cdr", sid)
            w.add_message(chans[topic], log_time=t, publish_time=t, data=b"{}" if topic == "/odom" else data)
        w.finish()
    with pytest.raises(UnknownMessageTypeError, match="/odom"):
        read_drive(tmp_path / "mixed.mcap", topic_map=CAR_MAP)
    _every_command_refuses(tmp_path / "mixed.mcap", "/odom", own_sim)


def test_files_without_the_mapped_topics(corpus):
    d, paths, own_sim, _ = corpus
    _every_command_refuses(BUMP, "missing topic /odom (the speed of topic map", own_sim)
    # without a map the interface's topics are needed (replay then plays what there is, as ros2 bag play)
    _every_command_refuses(paths["rosbags_db3"], "missing topic /vehicle/speed", own_sim, topic_map=None,
                           replay=False)


def test_truncated_and_corrupt_foreign_files(corpus, tmp_path):
    d, paths, own_sim, _ = corpus
    data = paths["noindex_zstd.mcap"].read_bytes()
    (tmp_path / "head.mcap").write_bytes(data[:200])  # header and schemas only: no messages
    _every_command_refuses(tmp_path / "head.mcap", "head.mcap", own_sim)
    (tmp_path / "half.mcap").write_bytes(data[:len(data) // 2])  # the complete chunks before the cut
    x = read_drive(tmp_path / "half.mcap", topic_map=CAR_MAP)
    assert x.extra["truncated"] and 0 < len(x.imu) < len(read_drive(BUMP).imu)
    db = paths["bare.db3"].read_bytes()
    for name, blob in (("cut.db3", db[:len(db) // 3]), ("junk.db3", db[:100] + b"\xa5" * (len(db) - 100))):
        (tmp_path / name).write_bytes(blob)
        with pytest.raises(RecordingError, match=name):
            read_drive(tmp_path / name, topic_map=CAR_MAP)
        _every_command_refuses(tmp_path / name, name, own_sim)
    # a split directory: a missing split, unreadable metadata, a corrupt chunk in one split
    for case in ("missing", "metadata", "corrupt"):
        s = tmp_path / f"split_{case}"
        shutil.copytree(paths["split"], s)
        if case == "missing":
            next(s.glob("*_1.mcap")).unlink()
            needle = "lacks the split file"
        elif case == "metadata":
            (s / "metadata.yaml").write_text("rosbag2_bagfile_information: [1, 2\n")
            needle = "metadata.yaml"
        else:
            f = next(s.glob("*_1.mcap"))
            b = bytearray(f.read_bytes())
            b[4000:4040] = b"\xa5" * 40
            f.write_bytes(bytes(b))
            needle = "corrupt MCAP"
        _every_command_refuses(s, needle, own_sim)
    empty = tmp_path / "empty_dir"
    empty.mkdir()
    _every_command_refuses(empty, "without metadata.yaml", own_sim)


def test_unknown_types_are_skipped_with_one_warning_per_channel(corpus, tmp_path, caplog):
    msgs = car_messages(read_drive(BUMP))
    p = tmp_path / "extra.mcap"
    from mcap.writer import Writer
    with open(p, "wb") as f:
        w = Writer(f)
        w.start(profile="ros2")
        chans = {}
        for t, topic, mt, data in msgs:
            if topic not in chans:
                sid = w.register_schema(mt, "ros2msg", M.full_definition(mt).encode())
                chans[topic] = w.register_channel(topic, "cdr", sid)
            w.add_message(chans[topic], log_time=t, publish_time=t, data=data)
        for topic in ("/camera/a", "/camera/b"):
            sid = w.register_schema("acme_msgs/msg/Blob", "", b"")
            cid = w.register_channel(topic, "cdr", sid)
            for k in range(5):
                w.add_message(cid, log_time=msgs[0][0] + k, publish_time=0, data=b"\x00\x01\x00\x00")
        w.finish()
    with caplog.at_level(logging.WARNING):
        x = read_drive(p, topic_map=CAR_MAP)
    warned = [r.getMessage() for r in caplog.records if "skipping channel" in r.getMessage()]
    assert len(warned) == 2 and any("/camera/a" in m for m in warned) and len(x.imu) > 0
    # needed but not decodable: the speed mapped onto one of them is a named error
    m = tmp_path / "bad.yaml"
    m.write_text(CAR_MAP.read_text().replace("topic: /odom", "topic: /camera/a"))
    with pytest.raises(UnknownMessageTypeError, match="/camera/a"):
        read_drive(p, topic_map=m)


def test_ros2idl_schemas_decode_with_the_ros2_definitions(tmp_path):
    """rosbag2 stores an IDL schema when it found no .msg: such channels decode with this package's or
    rosbags' Jazzy definitions (here a TwistStamped speed, a type this package does not embed)."""
    from geometry_msgs.msg import TwistStamped
    from mcap.writer import Writer
    from rclpy.serialization import serialize_message
    ref = read_drive(BUMP)
    msgs = [m for m in car_messages(ref) if m[1] != "/odom"]
    with open(tmp_path / "idl.mcap", "wb") as f:
        w = Writer(f)
        w.start(profile="ros2")
        chans = {}
        for t, topic, mt, data in msgs:
            if topic not in chans:
                sid = w.register_schema(mt, "ros2idl", b"module dummy { };")
                chans[topic] = w.register_channel(topic, "cdr", sid)
            w.add_message(chans[topic], log_time=t, publish_time=t, data=data)
        sid = w.register_schema("geometry_msgs/msg/TwistStamped", "ros2idl", b"module geometry_msgs { };")
        cid = w.register_channel("/vel", "cdr", sid)
        for t, v in zip(ref.speed.t_ns.tolist(), ref.speed.values.tolist()):
            m = TwistStamped()
            m.twist.linear.x = v
            w.add_message(cid, log_time=t, publish_time=t, data=serialize_message(m))
        w.finish()
    (tmp_path / "m.yaml").write_text(CAR_MAP.read_text().replace("{topic: /odom, field: twist.twist.linear.x",
                                                                 "{topic: /vel, field: twist.linear.x"))
    x = read_drive(tmp_path / "idl.mcap", topic_map=tmp_path / "m.yaml")
    np.testing.assert_array_equal(x.speed.values, ref.speed.values)
    np.testing.assert_array_equal(x.imu.gyro, ref.imu.gyro)


def test_replayed_messages_carry_the_converted_values(corpus):
    """What ``replay --topic-map`` publishes: the interface's topics, SI / REP-103, decodable by rclpy."""
    from rclpy.serialization import deserialize_message
    from sensor_msgs.msg import Imu
    from std_msgs.msg import Float64
    from susp_sim_ros.io.drive import recording_from_drive
    d, paths, _, _ = corpus
    ref = read_drive(BUMP)
    rec = recording_from_drive(read_drive(paths["bare.db3"], topic_map=CAR_MAP), paths["bare.db3"])
    speed = [deserialize_message(m.data, Float64).data for m in rec.by_topic("/vehicle/speed")]
    imu = [deserialize_message(m.data, Imu) for m in rec.by_topic("/imu/data")]
    np.testing.assert_array_equal(speed, ref.speed.values)
    np.testing.assert_array_equal([[i.angular_velocity.x, i.angular_velocity.y, i.angular_velocity.z] for i in imu],
                                  ref.imu.gyro)
    assert rec.latched("/road/profile") and not rec.latched("/vehicle/speed")


def test_bag_custom_data_and_a_mapped_oil_topic_give_the_damper_state(corpus, tmp_path):
    d, paths, _, _ = corpus
    bag = tmp_path / "bag"
    shutil.copytree(paths["rosbags_db3"], bag)
    meta = (bag / "metadata.yaml").read_text()
    assert "custom_data" in meta
    import yaml
    info = yaml.safe_load(meta)
    info["rosbag2_bagfile_information"]["custom_data"] = {"damper_oil_level": "1,1,0,0", "maneuver": "bump"}
    (bag / "metadata.yaml").write_text(yaml.safe_dump(info))
    assert read_drive(bag, topic_map=CAR_MAP).oil_levels() == (1.0, 1.0, 0.0, 0.0)
    # a topic with the oil levels in percent, named by the map, overrides the metadata
    from std_msgs.msg import Float64MultiArray
    from rclpy.serialization import serialize_message
    msgs = car_messages(read_drive(BUMP))
    oil = Float64MultiArray(data=[100.0, 100.0, 50.0, 0.0])
    p = _mcap(tmp_path / "oil.mcap", [(msgs[0][0], "/service/oil", M.FLOAT64_ARRAY, serialize_message(oil))] + msgs,
              metadata={"damper_oil_level": "1,1,1,1"})
    m = tmp_path / "oil.yaml"
    m.write_text(CAR_MAP.read_text() + "damper_oil_level: {topic: /service/oil, field: data, unit: '%'}\n")
    assert read_drive(p, topic_map=m).oil_levels() == (1.0, 1.0, 0.5, 0.0)
