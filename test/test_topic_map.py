"""Topic maps (susp_sim_ros.io.topic_map): the parser refuses every malformed map with a TopicMapError naming
the file and key (hypothesis), units and frames convert to SI / REP-103 as documented, and the shipped maps
load (the identity map is exactly the interface layout)."""
from __future__ import annotations

import math

import numpy as np
import pytest
import yaml
from hypothesis import given, settings, strategies as st

from susp_sim_ros.errors import TopicMapError
from susp_sim_ros.io.topic_map import (FRAMES, TopicMap, get_field, load_topic_map, parse_field_path, parse_frame,
                                       parse_topic_map, rotation_rpy)


def test_identity_map_is_the_interface_layout():
    tm = load_topic_map("interface")
    assert tm == TopicMap(source=tm.source)
    assert tm.conversions() == {}


def test_car_map_converts_degrees_odometry_and_frd():
    tm = load_topic_map("car_odom_can_frd")
    assert tm.speed.topic == "/odom" and tm.speed.field == ("twist", "twist", "linear", "x")
    assert tm.steering_wheel_angle.factor == pytest.approx(math.pi / 180)  # deg -> rad
    g, a = tm.imu.to_body(np.array([[0.1, 0.2, 0.3]]), np.array([[1.0, 2.0, -9.81]]))
    # FRD -> FLU: y and z change sign (x forward in both)
    np.testing.assert_array_equal(g, [[0.1, -0.2, -0.3]])
    np.testing.assert_array_equal(a, [[1.0, -2.0, 9.81]])


def test_frd_is_a_180_degree_roll_and_yawed_mount_rotates_axes():
    r, _ = parse_frame({"rpy_deg": [180, 0, 0]}, "t")
    np.testing.assert_allclose(r, FRAMES["frd"], atol=1e-15)  # same rotation, rounding only
    r, _ = parse_frame({"rpy_deg": [0, 0, 90]}, "t")
    # sensor x axis points to the body's left: a reading along sensor x is a body +y vector
    np.testing.assert_allclose(r @ [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], atol=1e-15)
    r, _ = parse_frame({"rpy_deg": [0, 90, 0]}, "t")
    # pitched 90 deg (nose down, REP-103): sensor x points down
    np.testing.assert_allclose(r @ [1.0, 0.0, 0.0], [0.0, 0.0, -1.0], atol=1e-15)


@given(st.floats(-360, 360), st.floats(-360, 360), st.floats(-360, 360))
def test_every_mounting_rotation_is_proper(r, p, y):
    m = rotation_rpy(*np.radians([r, p, y]))
    np.testing.assert_allclose(m @ m.T, np.eye(3), atol=1e-12)  # orthonormal (round-off only)
    assert np.linalg.det(m) == pytest.approx(1.0, abs=1e-12)  # no reflection


def test_field_paths():
    assert parse_field_path("twist.twist.linear.x", "t") == ("twist", "twist", "linear", "x")
    assert parse_field_path("data[2]", "t") == ("data", 2) == parse_field_path("data.2", "t")
    assert get_field({"a": [1.0, {"b": 7.0}]}, parse_field_path("a[1].b", "t")) == 7.0
    for bad in ("a..b", ".a", "a.", "a[x]", "a-b", "1a", 3):
        with pytest.raises(TopicMapError, match="field"):
            parse_field_path(bad, "t")


@pytest.mark.parametrize("data, needle", [
    ([1, 2], "expected a mapping of inputs"),
    ({"sped": {"topic": "/odom"}}, "unknown input.*sped"),
    ({"speed": {"field": "data"}}, "speed: missing topic"),
    ({"speed": {"topic": "odom"}}, "speed: topic"),
    ({"speed": {"topic": "/odom", "unit": "deg"}}, "speed: unit: 'deg' is not a unit of speed"),
    ({"steering_wheel_angle": {"topic": "/s", "scale": 0}}, "steering_wheel_angle: scale: must not be 0"),
    ({"steering_wheel_angle": {"topic": "/s", "scale": "x"}}, "scale: expected a finite number"),
    ({"steering_wheel_angle": {"topic": "/s", "scale": float("nan")}}, "scale: expected a finite number"),
    ({"imu": {"topic": "/imu", "frame": "ned"}}, "imu: frame: 'ned' is not a frame"),
    ({"imu": {"topic": "/imu", "frame": {"rpy_deg": [1, 2]}}}, "imu: frame.rpy_deg: expected three"),
    ({"imu": {"topic": "/imu", "frame": {"rpy_deg": [1, 2, 1e9]}}}, "within"),
    ({"imu": {"topic": "/imu", "gyro_unit": "deg"}}, "gyro_unit"),
    ({"imu": {"topic": "/imu", "fram": "frd"}}, "imu: unknown key"),
    ({"speed": {"topic": "/o", "type": "Odometry"}}, "type: expected pkg/msg/Type"),
    ({"speed": 5}, "speed: expected a mapping"),
    ({"version": 2}, "version"),
])
def test_malformed_maps_are_named_errors(data, needle):
    with pytest.raises(TopicMapError, match=needle) as ei:
        parse_topic_map(data, "my_map.yaml")
    assert str(ei.value).startswith("my_map.yaml")


def test_files(tmp_path):
    with pytest.raises(TopicMapError, match="no such topic map"):
        load_topic_map(tmp_path / "none.yaml")
    (tmp_path / "bad.yaml").write_text("speed: {topic: /a\n")
    with pytest.raises(TopicMapError, match="bad.yaml: not valid YAML"):
        load_topic_map(tmp_path / "bad.yaml")
    (tmp_path / "bin.yaml").write_bytes(b"\xff\xfe\x00")
    with pytest.raises(TopicMapError, match="bin.yaml"):
        load_topic_map(tmp_path / "bin.yaml")


_scalars = st.one_of(st.none(), st.booleans(), st.integers(), st.floats(allow_nan=True),
                     st.text(max_size=12), st.sampled_from(["/odom", "deg", "frd", "flu", "data", "km/h", "g",
                                                            "twist.twist.linear.x", "std_msgs/msg/Float64"]))
_values = st.recursive(_scalars, lambda kids: st.one_of(st.lists(kids, max_size=4),
                                                        st.dictionaries(st.sampled_from(
                                                            ["topic", "field", "unit", "scale", "type", "frame",
                                                             "rpy_deg", "gyro_unit", "accel_scale", "x"]), kids,
                                                            max_size=5)), max_leaves=12)
_maps = st.one_of(_values, st.dictionaries(st.sampled_from(["speed", "steering_wheel_angle", "imu", "road_profile",
                                                            "wheel_heights", "damper_oil_level", "version", "bogus"]),
                                           _values, max_size=6))


@settings(max_examples=300, deadline=None)
@given(_maps)
def test_parser_accepts_or_names_the_error(data):
    """Any YAML-shaped value: a TopicMap or a TopicMapError naming the source; nothing else escapes."""
    try:
        tm = parse_topic_map(data, "fuzz.yaml")
    except TopicMapError as exc:
        assert str(exc).startswith("fuzz.yaml")
        return
    assert isinstance(tm, TopicMap)
    for mi in tm.inputs().values():
        assert math.isfinite(mi.factor) and mi.factor != 0 and mi.topic.startswith("/")
    r = np.asarray(tm.imu.rotation)
    np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-12)


@settings(max_examples=100, deadline=None)
@given(st.text(max_size=60))
def test_yaml_text_fuzz(tmp_path_factory, text):
    p = tmp_path_factory.mktemp("m") / "m.yaml"
    p.write_text(text, encoding="utf-8")
    try:
        load_topic_map(p)
    except TopicMapError as exc:
        assert str(p) in str(exc)


_cmaps = st.one_of(_values, st.dictionaries(st.sampled_from(["speed", "steering_wheel_angle", "imu", "wheel_heights",
                                                             "bogus"]), st.one_of(_values, st.dictionaries(
    st.sampled_from(["channel", "unit", "scale", "frame", "gyro_x", "gyro_y", "gyro_z", "accel_x", "fl", "x"]),
    _values, max_size=6)), max_size=5))


@settings(max_examples=300, deadline=None)
@given(_cmaps)
def test_channel_map_parser_accepts_or_names_the_error(data):
    """The MDF4 channel-map parser (susp import --channel-map): a map or a TopicMapError naming the source."""
    from susp_sim_ros.analysis.measurement_import import parse_channel_map
    try:
        cm = parse_channel_map(data, "chan.yaml")
    except TopicMapError as exc:
        assert str(exc).startswith("chan.yaml")
        return
    assert {"speed", "steering_wheel_angle", "imu"} <= set(cm)
    assert all(ax in cm["imu"] for ax in ("gyro_x", "gyro_y", "gyro_z"))


def test_channel_map_example():
    from susp_sim_ros.analysis.measurement_import import parse_channel_map
    cm = parse_channel_map(yaml.safe_load("""
speed: {channel: VehSpd, unit: km/h}
steering_wheel_angle: {channel: SteerWhlAng, unit: deg, scale: -1}
imu: {frame: sae_j670, gyro_x: GyroX, gyro_y: GyroY, gyro_z: {channel: GyroZ, unit: deg/s}}
"""), "m.yaml")
    assert cm["steering_wheel_angle"]["scale"] == -1.0 and cm["imu"]["gyro_z"]["unit"] == "deg/s"
    np.testing.assert_array_equal(cm["imu"]["frame"][0], FRAMES["frd"])
    with pytest.raises(TopicMapError, match="m.yaml: imu: accel_x, accel_y, accel_z come all together"):
        parse_channel_map({"speed": "a", "steering_wheel_angle": "b",
                           "imu": {"gyro_x": "x", "gyro_y": "y", "gyro_z": "z", "accel_x": "ax"}}, "m.yaml")
