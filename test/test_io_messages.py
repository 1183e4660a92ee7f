"""Embedded ROS 2 message definitions: equal to the Jazzy .msg files, encodable, readable by rosbags."""
from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np
import pytest

from susp_sim_ros.io import messages as M
from susp_sim_ros.model.layout import OUTPUT_LABELS, WHEELS, output_index

SHARE = Path(sys.prefix) / "share"


def _strip(text: str) -> str:
    out = []
    for line in text.splitlines():
        s = line.split("#", 1)[0].strip()
        if s:
            out.append(re.sub(r"\s+", " ", s))
    return "\n".join(out) + "\n"


@pytest.mark.parametrize("msgtype", sorted(M.MSG_DEFS))
def test_embedded_definition_matches_the_installed_msg_file(msgtype):
    pkg, _, name = msgtype.split("/")
    f = SHARE / pkg / "msg" / f"{name}.msg"
    if not f.exists():
        pytest.skip(f"{f} not installed")
    assert M.MSG_DEFS[msgtype] == _strip(f.read_text())


@pytest.mark.parametrize("msgtype", [M.FLOAT64, M.FLOAT64_ARRAY, M.IMU, M.ODOMETRY, M.DIAGNOSTIC_ARRAY, M.CLOCK])
def test_full_definition_parses_in_rosbags_and_mcap_ros2(msgtype):
    from rosbags.typesys import Stores, get_typestore
    from rosbags.typesys.msg import get_types_from_msg
    text = M.full_definition(msgtype)
    assert text.count("=" * 80) == text.count("\nMSG: ")
    ts = get_typestore(Stores.EMPTY)
    ts.register(get_types_from_msg(text, msgtype))
    assert msgtype in ts.types
    M.decode(msgtype, M.encode(msgtype, {}))  # defaults encode and decode


def test_imu_builder_round_trip_and_orientation():
    y = np.zeros(len(OUTPUT_LABELS))
    y[output_index("ROLL_RATE")], y[output_index("PITCH_RATE")], y[output_index("YAW_RATE")] = 0.1, -0.2, 0.3
    y[output_index("AZ_SF")] = 9.81
    y[output_index("YAW")] = np.pi / 2
    msg = M.decode(M.IMU, M.encode(M.IMU, M.imu_msg(1_500_000_001, y)))
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (1, 500_000_001)
    assert (msg.angular_velocity.x, msg.angular_velocity.y, msg.angular_velocity.z) == (0.1, -0.2, 0.3)
    assert msg.linear_acceleration.z == 9.81
    # yaw 90 deg about z: q = (0, 0, sin 45, cos 45)
    np.testing.assert_allclose([msg.orientation.x, msg.orientation.y, msg.orientation.z, msg.orientation.w],
                               [0, 0, np.sqrt(0.5), np.sqrt(0.5)], atol=1e-15)


def test_quaternion_matches_rotation_matrix():
    r, p, yw = 0.1, -0.3, 2.0
    x, y, z, w = M.quaternion_from_rpy(r, p, yw)
    Rz = np.array([[np.cos(yw), -np.sin(yw), 0], [np.sin(yw), np.cos(yw), 0], [0, 0, 1]])
    Ry = np.array([[np.cos(p), 0, np.sin(p)], [0, 1, 0], [-np.sin(p), 0, np.cos(p)]])
    Rx = np.array([[1, 0, 0], [0, np.cos(r), -np.sin(r)], [0, np.sin(r), np.cos(r)]])
    Rq = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                   [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                   [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    np.testing.assert_allclose(Rq, Rz @ Ry @ Rx, atol=1e-14)


def test_suspension_layout():
    y = np.arange(len(OUTPUT_LABELS), dtype=float)
    msg = M.suspension_msg(y)
    dims = msg["layout"]["dim"]
    q = len(M.SUSPENSION_QUANTITIES)
    assert [(d["label"], d["size"], d["stride"]) for d in dims] == [("wheel", 4, 4 * q), ("quantity", q, q)]
    data = np.array(msg["data"]).reshape(4, q)
    assert data[WHEELS.index("RL"), M.SUSPENSION_QUANTITIES.index("damper_force")] == output_index("F_DAMPER_RL")
    assert data[WHEELS.index("FR"), M.SUSPENSION_QUANTITIES.index("wheel_force_y")] == output_index("F_Y_FR")


def test_rclpy_serialization_is_compatible():
    pytest.importorskip("rclpy")
    from rclpy.serialization import deserialize_message, serialize_message
    from sensor_msgs.msg import Imu
    y = np.linspace(-1, 1, len(OUTPUT_LABELS))
    d = M.imu_msg(42, y)
    ros = deserialize_message(M.encode(M.IMU, d), Imu)
    assert ros.angular_velocity.z == d["angular_velocity"]["z"] and ros.header.frame_id == "base_link"
    back = M.decode(M.IMU, serialize_message(ros))
    assert M.to_dict(back) == M.to_dict(M.decode(M.IMU, M.encode(M.IMU, d)))


def test_io_sim_core_and_lockstep_never_import_rclpy():
    import subprocess
    code = ("import sys; import susp_sim_ros.io, susp_sim_ros.io.reader, susp_sim_ros.runtime.sim_core, "
            "susp_sim_ros.runtime.lockstep, susp_sim_ros.cli.sim, susp_sim_ros.cli.recover; "
            "bad = [m for m in sys.modules if m.split('.')[0] in ('rclpy', 'rosidl_runtime_py')]; "
            "print(bad); sys.exit(1 if bad else 0)")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert p.returncode == 0, p.stdout + p.stderr


# ---- schema text as rosbag2 writes it (Foxglove's parser resolves field types by section name) -------
_ROSBAG2_FIELD_TYPE = re.compile(r"(?:^|\n)\s*([a-zA-Z0-9_/]+)(?:\[[^\]]*\])?\s+")
_ROSBAG2_PRIMITIVES = {"bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16",
                       "int32", "uint32", "int64", "uint64", "string"}


def _sections(text: str) -> list[tuple[str, str]]:
    """(name, body) of each section of a concatenated definition; the root's name is ''."""
    parts = text.split("\n" + "=" * 80 + "\n")
    out = [("", parts[0])]
    for p in parts[1:]:
        head, _, body = p.partition("\n")
        assert head.startswith("MSG: "), head
        out.append((head[len("MSG: "):], body))
    return out


def _referenced(body: str, pkg: str) -> set[str]:
    """Complex field types of a .msg body as rosbag2 resolves them: as written, or ``pkg/Type``."""
    out = set()
    for m in _ROSBAG2_FIELD_TYPE.finditer(body):
        t = m.group(1)
        if t not in _ROSBAG2_PRIMITIVES:
            out.add(t if "/" in t else f"{pkg}/{t}")
    return out


@pytest.mark.parametrize("msgtype", sorted(M.MSG_DEFS))
def test_dependency_sections_are_named_as_the_fields_reference_them(msgtype):
    """``MSG: std_msgs/Header`` for a ``std_msgs/Header header`` field, never ``std_msgs/msg/Header``
    (@foxglove/rosmsg rejects that: "Expected 1 top level type definition for 'std_msgs/Header'")."""
    text = M.full_definition(msgtype)
    secs = _sections(text)
    names = [n for n, _ in secs[1:]]
    assert len(names) == len(set(names)), names
    assert all(n.count("/") == 1 for n in names), names
    assert secs[0][1] == M.MSG_DEFS[msgtype]
    needed: set[str] = set()
    for name, body in secs:
        needed |= _referenced(body, (name or msgtype).split("/")[0])
    assert needed == set(names)  # every referenced type has exactly its section, and nothing else
    if msgtype in (M.IMU, M.ODOMETRY, M.DIAGNOSTIC_ARRAY):
        assert "\nMSG: std_msgs/Header\n" in text and "/msg/" not in text


@pytest.mark.parametrize("msgtype", sorted(M.MSG_DEFS))
def test_full_definition_is_what_rosbag2_records(msgtype):
    """rosbag2_cpp's LocalMessageDefinitionSource::get_full_text over the installed Jazzy .msg files
    (comments stripped as in MSG_DEFS): dependencies depth first, each message's in sorted order, each
    once, every one after "\\n" + 80 "=" + "\\nMSG: pkg/Type\\n"."""
    def msg_file(name: str) -> Path:
        pkg, typ = name.split("/")
        return SHARE / pkg / "msg" / f"{typ}.msg"

    root = M.msg_name(msgtype)
    if not msg_file(root).exists():
        pytest.skip(f"{msg_file(root)} not installed")
    seen: set[str] = set()

    def append(name: str) -> str:
        text = _strip(msg_file(name).read_text())
        out = text
        for dep in sorted(_referenced(text, name.split("/")[0])):
            if dep not in seen:
                seen.add(dep)
                out += "\n" + "=" * 80 + "\nMSG: " + dep + "\n" + append(dep)
        return out

    assert M.full_definition(msgtype) == append(root)


@pytest.mark.parametrize("msgtype", [M.FLOAT64, M.FLOAT64_ARRAY, M.IMU, M.ODOMETRY, M.DIAGNOSTIC_ARRAY,
                                     M.CLOCK])
def test_section_names_and_types_agree_with_rosbags(msgtype):
    """rosbags' own generator (``generate_msgdef``, as it writes rosbag2 files) names the same sections,
    and our text parses to the same types as rosbags' bundled Jazzy store."""
    from rosbags.typesys import Stores, get_typestore
    from rosbags.typesys.msg import get_types_from_msg
    jazzy = get_typestore(Stores.ROS2_JAZZY)
    theirs, _ = jazzy.generate_msgdef(msgtype, ros_version=2)
    assert {n for n, _ in _sections(M.full_definition(msgtype))[1:]} == \
        {n for n, _ in _sections(theirs)[1:]}
    ours = get_types_from_msg(M.full_definition(msgtype), msgtype)
    for name, (consts, fields) in ours.items():
        want_consts, want_fields = jazzy.fielddefs[name]
        assert list(fields) == list(want_fields), name
        assert [(c[0], c[1], c[2]) for c in consts] == [(c[0], c[1], c[2]) for c in want_consts], name
