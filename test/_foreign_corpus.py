"""A corpus of recordings in layouts nobody here chose, written with the real writers the project has.

Each function converts a :class:`~susp_sim_ros.io.drive.TestDrive` into a "typical car" layout: speed in a
``nav_msgs/msg/Odometry`` on ``/odom`` (body twist), the steering-wheel angle in degrees as a
``std_msgs/msg/Float64`` on ``/can/steering_wheel_angle``, the IMU in forward-right-down axes on
``/imu/data_raw`` (or mounted at a given roll-pitch-yaw), the road profile unchanged on ``/road/profile``
(latched). Messages are serialised by rclpy; containers are written by ``mcap`` (single files with or
without summary/index, zstd/lz4 chunks, rosbag2-style split directories) and by ``rosbags``' rosbag2
writer (MCAP and sqlite3 storage). ``config/topic_maps/car_odom_can_frd.yaml`` reads them all.
"""
from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np

from susp_sim_ros.io import messages as M
from susp_sim_ros.io.recorder import qos_yaml
from susp_sim_ros.io.topic_map import rotation_rpy

CAR_MAP = Path(__file__).resolve().parents[1] / "config" / "topic_maps" / "car_odom_can_frd.yaml"
ODOM, STEER, IMU_RAW, ROAD = "/odom", "/can/steering_wheel_angle", "/imu/data_raw", "/road/profile"


def car_messages(drive, *, mount_rpy_deg=None) -> list[tuple[int, str, str, bytes]]:
    """``(log_time_ns, topic, msgtype, CDR bytes)`` of ``drive`` in the car layout, serialised by rclpy.
    The IMU vectors are expressed in FRD axes, or in the axes of a sensor mounted at ``mount_rpy_deg``
    (v_sensor = R.T @ v_body)."""
    from nav_msgs.msg import Odometry
    from rclpy.serialization import serialize_message
    from sensor_msgs.msg import Imu
    from std_msgs.msg import Float64, Float64MultiArray, MultiArrayDimension

    out = []
    if drive.road is not None:
        r = drive.road
        m = Float64MultiArray()
        n = len(r.s)
        m.layout.dim = [MultiArrayDimension(label="channel", size=3, stride=3 * n),
                        MultiArrayDimension(label="sample", size=n, stride=n)]
        m.data = np.concatenate([r.s, r.zl, r.zr]).tolist()
        out.append((drive.t0_ns, ROAD, M.FLOAT64_ARRAY, serialize_message(m)))
    for t, v in zip(drive.speed.t_ns.tolist(), drive.speed.values.tolist()):
        o = Odometry()
        o.header.stamp.sec, o.header.stamp.nanosec = divmod(t, 1_000_000_000)
        o.header.frame_id, o.child_frame_id = "odom", "base_link"
        o.twist.twist.linear.x = v
        out.append((t, ODOM, M.ODOMETRY, serialize_message(o)))
    for t, v in zip(drive.steering.t_ns.tolist(), drive.steering.values.tolist()):
        out.append((t, STEER, M.FLOAT64, serialize_message(Float64(data=math.degrees(v)))))
    rot = np.diag([1.0, -1.0, -1.0]) if mount_rpy_deg is None else rotation_rpy(*np.radians(mount_rpy_deg))
    gyro, accel = drive.imu.gyro @ rot, drive.imu.accel @ rot  # rows: (R.T @ v).T = v.T @ R
    for t, g, a in zip(drive.imu.t_ns.tolist(), gyro.tolist(), accel.tolist()):
        i = Imu()
        i.header.stamp.sec, i.header.stamp.nanosec = divmod(t, 1_000_000_000)
        i.header.frame_id = "imu_link"
        i.orientation_covariance[0] = -1.0
        i.angular_velocity.x, i.angular_velocity.y, i.angular_velocity.z = g
        i.linear_acceleration.x, i.linear_acceleration.y, i.linear_acceleration.z = a
        out.append((t, IMU_RAW, M.IMU, serialize_message(i)))
    out.sort(key=lambda r: r[0])
    return out


def _mcap(path: Path, msgs, *, compression="zstd", index=True, chunk_size=64 * 1024, metadata=None,
          profile="ros2", schema_encoding="ros2msg", message_encoding="cdr") -> Path:
    from mcap.writer import CompressionType, IndexType, Writer
    comp = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4, "none": CompressionType.NONE}[compression]
    with open(path, "wb") as f:
        kw = {} if index else dict(index_types=IndexType.NONE, repeat_schemas=False, repeat_channels=False,
                                   use_statistics=False, use_summary_offsets=False)
        w = Writer(f, compression=comp, chunk_size=chunk_size, **kw)
        w.start(profile=profile, library="susp_sim_ros test corpus")
        if metadata:
            w.add_metadata("test_drive", metadata)
        chans: dict[str, int] = {}
        for seq, (t, topic, mt, data) in enumerate(msgs):
            if topic not in chans:
                sid = w.register_schema(mt, schema_encoding, M.full_definition(mt).encode())
                chans[topic] = w.register_channel(topic, message_encoding, sid,
                                                  {"offered_qos_profiles": qos_yaml(topic == ROAD)})
            w.add_message(chans[topic], log_time=t, publish_time=t, data=data, sequence=seq)
        w.finish()
    return path


def car_mcap(path, drive, **kw) -> Path:
    """One MCAP file (``index=False``: no summary section and no chunk indexes)."""
    meta = {k: str(v) for k, v in drive.metadata.items()}
    return _mcap(Path(path), car_messages(drive), metadata=meta, **kw)


def car_split_dir(path, drive, parts=3) -> Path:
    """A rosbag2 directory as ``ros2 bag record --max-bag-duration`` leaves it: ``metadata.yaml`` and
    ``<name>_0.mcap`` ... split by time, alternately zstd and lz4, the last one without summary/index."""
    path = Path(path)
    path.mkdir()
    msgs = car_messages(drive)
    bounds = np.linspace(msgs[0][0], msgs[-1][0] + 1, parts + 1)
    files = []
    for k in range(parts):
        chunk = [m for m in msgs if bounds[k] <= m[0] < bounds[k + 1]]
        if k == 0 or chunk and chunk[0][1] != ROAD:  # the latched profile is re-recorded in every split
            chunk = [m for m in msgs if m[1] == ROAD][:1] * (k > 0) + chunk
        name = f"{path.name}_{k}.mcap"
        _mcap(path / name, chunk, compression=("zstd", "lz4")[k % 2], index=k < parts - 1,
              metadata={kk: str(v) for kk, v in drive.metadata.items()})
        files.append((name, chunk))
    _metadata_yaml(path, "mcap", files, msgs)
    return path


def _metadata_yaml(path: Path, storage: str, files, msgs) -> None:
    topics = {}
    for _t, topic, mt, _ in msgs:
        topics.setdefault(topic, [mt, 0])[1] += 1
    t0, t1 = msgs[0][0], msgs[-1][0]
    lines = ["rosbag2_bagfile_information:", "  version: 9", f"  storage_identifier: {storage}",
             "  duration:", f"    nanoseconds: {t1 - t0}", "  starting_time:",
             f"    nanoseconds_since_epoch: {t0}", f"  message_count: {len(msgs)}", "  topics_with_message_count:"]
    for topic, (mt, n) in topics.items():
        lines += ["    - topic_metadata:", f"        name: {topic}", f"        type: {mt}",
                  "        serialization_format: cdr", '        offered_qos_profiles: ""',
                  "        type_description_hash: \"\"", f"      message_count: {n}"]
    lines += ['  compression_format: ""', '  compression_mode: ""', "  relative_file_paths:"]
    lines += [f"    - {name}" for name, _ in files]
    lines += ["  files:"]
    for name, chunk in files:
        lines += [f"    - path: {name}", "      starting_time:", f"        nanoseconds_since_epoch: {chunk[0][0]}",
                  "      duration:", f"        nanoseconds: {chunk[-1][0] - chunk[0][0]}",
                  f"      message_count: {len(chunk)}"]
    lines += ["  custom_data: ~", "  ros_distro: jazzy"]
    (path / "metadata.yaml").write_text("\n".join(lines) + "\n")


def car_rosbags(path, drive, storage="sqlite3") -> Path:
    """A rosbag2 directory written by ``rosbags``' writer (``storage``: sqlite3 or mcap), rclpy's CDR bytes."""
    from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore
    ts = get_typestore(Stores.ROS2_JAZZY)
    never = QosTime(sec=9223372036, nsec=854775807)
    latched = Qos(QosHistory.KEEP_LAST, 1, QosReliability.RELIABLE, QosDurability.TRANSIENT_LOCAL, never, never,
                  QosLiveliness.AUTOMATIC, never, False)
    plugin = {"sqlite3": StoragePlugin.SQLITE3, "mcap": StoragePlugin.MCAP}[storage]
    with Writer(Path(path), version=9, storage_plugin=plugin) as w:
        conns = {}
        for t, topic, mt, data in car_messages(drive):
            if topic not in conns:
                conns[topic] = w.add_connection(topic, mt, typestore=ts,
                                                offered_qos_profiles=[latched] if topic == ROAD else [])
            w.write(conns[topic], t, data)
    return Path(path)


def bare_db3(path, drive) -> Path:
    """The single ``.db3`` file of a sqlite3 rosbag2 (no ``metadata.yaml`` beside it)."""
    d = car_rosbags(Path(path).with_suffix(".bagdir"), drive, "sqlite3")
    db = next(d.glob("*.db3"))
    shutil.copy(db, path)
    return Path(path)
