"""Recorded test drives (interface.md, "A recorded test drive"): read and write them as time series.

:func:`read_drive` turns an MCAP file into a :class:`TestDrive` (speed, steering, road profile or
per-wheel heights, measured IMU, ``test_drive`` metadata); :func:`write_drive` writes one in the
interface format. Times are integer nanoseconds (MCAP log time = ROS time).
"""
from __future__ import annotations

import logging
import os
from typing import Any

import numpy as np

from ..errors import RecordingError, SuspInputError, UnknownMessageTypeError
from ..model.road import RoadProfile
from . import integrity as _integrity
# what a drive is lives in drive_data (integrity imports it too); re-exported here: the drive API
from .drive_data import (DAMPER_COMMAND, IMU, MAX_SPEED, MAX_STEERING, MAX_WHEEL_HEIGHT,  # noqa: F401
                         OIL_UNKNOWN, ROAD_PROFILE, SIM_IMU, SPEED, STEERING, WHEEL_HEIGHTS, ImuSeries, Series,
                         TestDrive, oil_unknown, parse_oil)
from . import messages as M
from .reader import RawMessage, Recording, read_recording
from .recorder import McapRecorder, qos_yaml
from .topic_map import MappedImu, TopicMap, get_field, load_topic_map
from ..model.params import DEFAULT_VEHICLE

log = logging.getLogger(__name__)

#: the order :func:`drive_from_recording` reads the input series in: as stored (the integrity check sorts
#: them, with a ``stamp_order`` or ``clock_jump`` finding where the file is out of log-time order)
INPUT_ORDER = "file"

TOPIC_TYPES = {SPEED: M.FLOAT64, STEERING: M.FLOAT64, ROAD_PROFILE: M.FLOAT64_ARRAY,
               WHEEL_HEIGHTS: M.FLOAT64_ARRAY, IMU: M.IMU, SIM_IMU: M.IMU, DAMPER_COMMAND: M.FLOAT64_ARRAY}


def check_topic(rec: Recording, topic: str, msgtype: str | None = None) -> None:
    """RecordingError naming the file and topic unless every channel of ``topic`` carries ``msgtype``
    (default :data:`TOPIC_TYPES`; None there: any type) as a ``ros2msg`` schema with ``cdr`` messages."""
    want = msgtype or TOPIC_TYPES.get(topic)
    for ch in rec.channels.values():
        if ch.topic != topic:
            continue
        sc = rec.schemas.get(ch.schema_id)
        name = sc.name if sc is not None else "(no schema)"
        if want is not None and name != want:
            raise RecordingError(f"{rec.path}: topic {topic} has type {name}, expected {want}")
        if sc is None or sc.encoding not in ("ros2msg", "ros2idl") or ch.message_encoding != "cdr":
            enc = sc.encoding if sc is not None else None
            err = UnknownMessageTypeError if want is None else RecordingError
            raise err(f"{rec.path}: topic {topic}: unsupported schema encoding "
                      f"{enc!r} / message encoding {ch.message_encoding!r} "
                      f"(expected ros2msg / cdr)")


def _fields(rec: Recording, topic: str, extract, msgtype: str | None = None, order: str = "log") -> list:
    """``[(log_time_ns, extract(msg)), ...]`` in ``order`` (:meth:`~.reader.Recording.decode_topic`: ``"log"``
    sorted by log time, ``"file"`` as stored); a message without the expected fields is a named error."""
    check_topic(rec, topic, msgtype)
    out = []
    for t, m in rec.decode_topic(topic, order=order):
        try:
            out.append((t, extract(m)))
        except (AttributeError, TypeError, ValueError, IndexError, KeyError) as exc:
            raise RecordingError(f"{rec.path}: topic {topic}: malformed message at log time {t} ns "
                                 f"({type(exc).__name__}: {exc})") from None
    return out


def _field_error(rec: Recording, mi, exc: Exception) -> RecordingError:
    return RecordingError(f"{rec.path}: topic {mi.topic}: field {mi.field_text or '(message)'} "
                          f"({mi.name}) not readable as a number: {type(exc).__name__}: {exc}")


def _scalar_series(rec: Recording, mi, order: str = "log") -> Series:
    """A mapped scalar input (``MappedInput``) as a Series in SI, its messages in ``order`` (see :func:`_fields`)."""
    f = mi.factor
    if mi.field == ("data",) and f == 1.0:
        extract = lambda m: float(m.data)  # noqa: E731 - the interface layout: exactly as before
    else:
        extract = lambda m: float(get_field(m, mi.field)) * f  # noqa: E731
    items = _fields(rec, mi.topic, extract, mi.msgtype, order)
    t = np.array([t for t, _ in items], dtype=np.int64)
    v = np.array([v for _, v in items], dtype=float)
    return Series(t, v)


def road_from_msg(msg: Any, where: str) -> RoadProfile:
    """A :class:`RoadProfile` from a decoded ``/road/profile`` message; RecordingError if malformed."""
    try:
        dims = list(msg.layout.dim)
        data = np.asarray(list(msg.data), dtype=float)
        sizes = [int(d.size) for d in dims]
    except (AttributeError, TypeError, ValueError):
        raise RecordingError(f"{where}: not a Float64MultiArray") from None
    if len(sizes) != 2 or sizes[0] != 3:
        raise RecordingError(f"{where}: malformed road profile: expected layout dims [channel 3, sample N], "
                             f"got {[(d.label, int(d.size)) for d in dims]}")
    n = sizes[1]
    if n < 2 or data.size != 3 * n:
        raise RecordingError(f"{where}: malformed road profile: {data.size} values for N = {n} samples "
                             f"(want 3*N, N >= 2)")
    try:
        return RoadProfile.from_flat_array(data, n)
    except SuspInputError as exc:
        raise RecordingError(f"{where}: malformed road profile: {exc}") from None


def _imu_series(rec: Recording, topic: str, mapping: MappedImu | None = None, order: str = "log") -> ImuSeries:
    """The IMU samples of ``topic`` (gyro [rad/s], specific force [m/s^2], body axes through ``mapping``),
    its messages in ``order`` (see :func:`_fields`)."""
    mapping = mapping if mapping is not None and mapping.topic == topic else MappedImu(topic, msgtype=M.IMU)
    if mapping.angular_velocity == ("angular_velocity",) and mapping.linear_acceleration == ("linear_acceleration",):
        def extract(m):
            return (float(m.angular_velocity.x), float(m.angular_velocity.y), float(m.angular_velocity.z),
                    float(m.linear_acceleration.x), float(m.linear_acceleration.y), float(m.linear_acceleration.z))
    else:
        def extract(m):
            g, a = get_field(m, mapping.angular_velocity), get_field(m, mapping.linear_acceleration)
            return (float(g.x), float(g.y), float(g.z), float(a.x), float(a.y), float(a.z))
    items = _fields(rec, topic, extract, mapping.msgtype, order)
    t = np.array([t for t, _ in items], dtype=np.int64)
    v = np.array([x for _, x in items], dtype=float).reshape(-1, 6)
    gyro, accel = mapping.to_body(v[:, :3], v[:, 3:])
    return ImuSeries(t, gyro, accel)


def read_imu(path: str | os.PathLike, topic: str = IMU) -> ImuSeries:
    """The IMU samples of ``topic`` (``/imu/data`` measured, ``/sim/imu/data`` simulated)."""
    return imu_from_recording(read_recording(path), topic)


def imu_from_recording(rec: Recording, topic: str = IMU, mapping: MappedImu | None = None) -> ImuSeries:
    """The IMU samples of ``topic`` in an already read recording (RecordingError if none); ``mapping``
    (a topic map's IMU entry for that topic) converts fields, units and frame."""
    if not rec.by_topic(topic):
        why = f"; file damaged: {rec.error}" if rec.truncated else ""
        raise RecordingError(f"{rec.path}: no messages on topic {topic} (topics: "
                             f"{', '.join(sorted(rec.topics())) or 'none'}{why})")
    return _imu_series(rec, topic, mapping)


def _warn_unreadable_channels(rec: Recording, needed: set[str]) -> None:
    """One warning per channel that is not needed and whose messages could not be decoded here."""
    for ch in rec.channels.values():
        if ch.topic in needed:
            continue
        sc = rec.schemas.get(ch.schema_id)
        name = sc.name if sc is not None else ""
        if sc is None or ch.message_encoding != "cdr" or sc.encoding not in ("ros2msg", "ros2idl") or (
                not sc.data and name not in M.MSG_DEFS):
            log.warning("%s: skipping channel %s of unknown or undecodable type %r (encoding %r)", rec.path,
                        ch.topic, name or "(no schema)", ch.message_encoding)


def _road_profile(rec: Recording, rp) -> RoadProfile | None:
    """The road profile of ``rec`` (the first message on the mapped topic ``rp``, scaled), or None."""
    check_topic(rec, rp.topic, rp.msgtype)
    prof = rec.decode_topic(rp.topic)
    if not prof:
        return None
    msg = prof[0][1]
    if rp.field:
        try:
            msg = get_field(msg, rp.field)
        except (AttributeError, TypeError, IndexError, KeyError) as exc:
            raise _field_error(rec, rp, exc) from None
    road = road_from_msg(msg, f"{rec.path}: topic {rp.topic}")
    if rp.factor != 1.0:
        road = RoadProfile(road.s, road.zl * rp.factor, road.zr * rp.factor)
    return road


def _per_wheel_series(rec: Recording, topic: str, extract, msgtype: str | None = None,
                      order: str = "log") -> Series | None:
    """A series of four values [FL, FR, RL, RR] per message on ``topic`` (``extract(msg)`` gives them,
    messages in ``order``, see :func:`_fields`), or None when the topic has no message."""
    items = _fields(rec, topic, extract, msgtype, order)
    if not items:
        return None
    if any(len(v) != 4 for _, v in items):
        raise RecordingError(f"{rec.path}: topic {topic}: expected 4 values [FL, FR, RL, RR] per message")
    return Series(np.array([t for t, _ in items], dtype=np.int64), np.array([v for _, v in items], dtype=float))


def drive_from_recording(rec: Recording, *, imu_topic: str = IMU,
                         topic_map: TopicMap | str | os.PathLike | None = None) -> TestDrive:
    """The test drive in ``rec``, as recorded; ``topic_map`` (module :mod:`~susp_sim_ros.io.topic_map`; None =
    the interface's topics) says where each input is and how to convert it.

    The input series (speed, steering, wheel heights, damper command, measured IMU) hold their samples in
    the order the file stores them (:data:`INPUT_ORDER`), so that the integrity check
    (:func:`~susp_sim_ros.io.integrity.check_drive_integrity`, which every reader of a drive runs next)
    sees stamps out of log-time order and backward clock jumps and repairs them with a finding; for a file
    stored in log-time order that is log-time order. The road profile, oil levels and ``extra["sim_imu"]``
    are read in log-time order."""
    path = rec.path
    mapped = topic_map is not None
    tm = load_topic_map(topic_map)
    if mapped and imu_topic == IMU:
        imu_topic = tm.imu.topic
    if not rec.messages:
        why = f" (file damaged: {rec.error})" if rec.truncated else ""
        raise RecordingError(f"{path}: no readable messages{why}")
    if mapped:
        _warn_unreadable_channels(rec, tm.topics() | {SIM_IMU})
    for mi in (tm.speed, tm.steering_wheel_angle):
        if not rec.by_topic(mi.topic):
            why = f"; file damaged: {rec.error}" if rec.truncated else ""
            via = f" (the {mi.name} of topic map {tm.source})" if mapped else ""
            raise RecordingError(f"{path}: missing topic {mi.topic}{via} (topics: "
                                 f"{', '.join(sorted(rec.topics())) or 'none'}{why})")
    speed = _scalar_series(rec, tm.speed, INPUT_ORDER)
    steering = _scalar_series(rec, tm.steering_wheel_angle, INPUT_ORDER)
    rp, whm = tm.road_profile, tm.wheel_heights
    road = _road_profile(rec, rp)
    wh = _per_wheel_series(rec, whm.topic, lambda m: [float(x) * whm.factor if whm.factor != 1.0 else float(x)
                                                      for x in get_field(m, whm.field)], whm.msgtype, INPUT_ORDER)
    cmd = _per_wheel_series(rec, DAMPER_COMMAND, lambda m: [float(x) for x in m.data], order=INPUT_ORDER)
    imu = _imu_series(rec, imu_topic, tm.imu, INPUT_ORDER) if rec.by_topic(imu_topic) else None
    metadata = dict(rec.metadata.get("test_drive", {}))
    if tm.damper_oil_level is not None and rec.by_topic(tm.damper_oil_level.topic):
        om = tm.damper_oil_level
        oil = _fields(rec, om.topic, lambda m: [float(x) * om.factor for x in get_field(m, om.field)], om.msgtype)
        metadata["damper_oil_level"] = ",".join(f"{x:.6g}" for x in oil[0][1])
    extra: dict[str, Any] = {"topics": rec.topics(), "truncated": rec.truncated}
    if mapped:
        extra["topic_map"] = tm.source
        extra["input_topics"] = {"speed": tm.speed.topic, "steering": tm.steering_wheel_angle.topic,
                                 "wheel_heights": whm.topic, "road_profile": rp.topic, "imu": imu_topic}
        extra["conversions"] = tm.conversions()
    if imu_topic != SIM_IMU and rec.by_topic(SIM_IMU):
        extra["sim_imu"] = _imu_series(rec, SIM_IMU)
    drive = TestDrive(metadata, speed, steering, road, wh, imu, extra, damper_command=cmd)
    _integrity.check_oil_metadata(metadata, path)  # bad_metadata: a named error (exit 2), as before
    return drive


def check_drive(drive: TestDrive, where: str | os.PathLike) -> TestDrive:
    """Refuse a drive the offline tools cannot simulate faithfully: per input topic, log times strictly
    increasing and values finite and within the node's limits (speed in [0, MAX_SPEED], |steering| <=
    MAX_STEERING, |wheel heights| <= MAX_WHEEL_HEIGHT), the IMU finite with increasing times.
    RecordingError naming the file, topic, sample and time; returns ``drive``."""
    def series(topic, t, v, lo=None, hi=None, absmax=None):
        t = np.asarray(t, np.int64)
        v = np.asarray(v, float).reshape(len(t), -1)
        back = np.nonzero(np.diff(t) <= 0)[0]
        if back.size:
            k = int(back[0]) + 1
            raise RecordingError(f"{where}: topic {topic}: log times not strictly increasing at message "
                                 f"{k} ({t[k]} ns after {t[k - 1]} ns)")
        bad = ~np.isfinite(v).all(axis=1)
        why = "non-finite value"
        if lo is not None:
            bad |= (v < lo).any(axis=1) | (v > hi).any(axis=1)
            why = f"value outside [{lo:g}, {hi:g}] or non-finite"
        if absmax is not None:
            bad |= (np.abs(v) > absmax).any(axis=1)
            why = f"value beyond +-{absmax:g} or non-finite"
        if bad.any():
            k = int(np.nonzero(bad)[0][0])
            raise RecordingError(f"{where}: topic {topic}: {why} at message {k} (t = {t[k]} ns): "
                                 f"{v[k].tolist()}")
    names = drive.extra.get("input_topics", {})  # a topic map's topics, if the drive was read through one
    series(names.get("speed", SPEED), drive.speed.t_ns, drive.speed.values, 0.0, MAX_SPEED)
    series(names.get("steering", STEERING), drive.steering.t_ns, drive.steering.values, absmax=MAX_STEERING)
    if drive.wheel_heights is not None:
        series(names.get("wheel_heights", WHEEL_HEIGHTS), drive.wheel_heights.t_ns, drive.wheel_heights.values,
               absmax=MAX_WHEEL_HEIGHT)
    if drive.damper_command is not None:
        series(DAMPER_COMMAND, drive.damper_command.t_ns, drive.damper_command.values, 0.0, 1.0)
    if drive.road is not None and len(drive.road) and (
            np.abs(drive.road.zl).max() > MAX_WHEEL_HEIGHT or np.abs(drive.road.zr).max() > MAX_WHEEL_HEIGHT):
        raise RecordingError(f"{where}: topic {names.get('road_profile', ROAD_PROFILE)}: elevation beyond "
                             f"+-{MAX_WHEEL_HEIGHT:g} m")
    if drive.imu is not None:
        series(names.get("imu", IMU), drive.imu.t_ns, np.hstack([drive.imu.gyro, drive.imu.accel]))
    return drive


def read_drive(path: str | os.PathLike, *, imu_topic: str = IMU,
               topic_map: TopicMap | str | os.PathLike | None = None) -> TestDrive:
    """Read a recorded test drive (an MCAP file, a rosbag2 directory or a ``.db3`` file, see
    :func:`~susp_sim_ros.io.reader.read_recording`); a truncated file gives its readable prefix (with a
    warning). ``topic_map`` (a YAML path, a :class:`~susp_sim_ros.io.topic_map.TopicMap`, or None for the
    interface's own topics) maps other topic names, fields, units and IMU frames onto the model's inputs.

    Every drive read here passes the input integrity check (:mod:`~susp_sim_ros.io.integrity`, issue 28):
    defects it can work around are worked around and reported (one stderr line each, ``drive.extra
    ["input_findings"]``); one that leaves nothing sound is an
    :class:`~susp_sim_ros.io.integrity.IntegrityError` (exit 2)."""
    drive = drive_from_recording(read_recording(path), imu_topic=imu_topic, topic_map=topic_map)
    res = _integrity.check_drive_integrity(drive, str(path))
    _integrity.report(res.findings)
    return res.drive


# ---- writing -------------------------------------------------------------------------------------
def drive_messages(drive: TestDrive, *, imu_topic: str = IMU) -> list[tuple[int, str, str, dict, bool]]:
    """The drive as ``(log_time_ns, topic, msgtype, msg dict, latched)`` in log-time order."""
    out: list[tuple[int, str, str, dict, bool]] = []
    t0 = drive.t0_ns
    if drive.road is not None:
        out.append((t0, ROAD_PROFILE, M.FLOAT64_ARRAY,
                    M.road_profile_msg(drive.road.s, drive.road.zl, drive.road.zr), True))
    for t, v in zip(drive.speed.t_ns.tolist(), drive.speed.values.tolist()):
        out.append((t, SPEED, M.FLOAT64, {"data": v}, False))
    for t, v in zip(drive.steering.t_ns.tolist(), drive.steering.values.tolist()):
        out.append((t, STEERING, M.FLOAT64, {"data": v}, False))
    if drive.wheel_heights is not None:
        for t, v in zip(drive.wheel_heights.t_ns.tolist(), drive.wheel_heights.values.tolist()):
            out.append((t, WHEEL_HEIGHTS, M.FLOAT64_ARRAY, M.wheel_heights_msg(v), False))
    if drive.damper_command is not None:
        for t, v in zip(drive.damper_command.t_ns.tolist(), drive.damper_command.values.tolist()):
            out.append((t, DAMPER_COMMAND, M.FLOAT64_ARRAY, M.wheel_heights_msg(v), False))
    if drive.imu is not None:
        for t, g, a in zip(drive.imu.t_ns.tolist(), drive.imu.gyro.tolist(), drive.imu.accel.tolist()):
            out.append((t, imu_topic, M.IMU, {
                "header": {"stamp": M.stamp(t), "frame_id": "base_link"},
                "orientation_covariance": [-1.0] + [0.0] * 8,
                "angular_velocity": {"x": g[0], "y": g[1], "z": g[2]},
                "linear_acceleration": {"x": a[0], "y": a[1], "z": a[2]}}, False))
    out.sort(key=lambda r: r[0])  # stable: the road profile stays first at t0
    return out


def recording_from_drive(drive: TestDrive, path: str | os.PathLike, *, imu_topic: str = IMU) -> Recording:
    """An in-memory :class:`~susp_sim_ros.io.reader.Recording` of ``drive`` in the interface layout (what
    :func:`write_drive` would write, CDR-encoded, road profile latched), e.g. to replay a drive read through
    a topic map onto the interface's topics. ``path`` names it in messages."""
    from pathlib import Path

    from mcap.records import Channel, Schema

    rec = Recording(Path(path), profile="ros2", finalised=True, truncated=bool(drive.extra.get("truncated")))
    rec.metadata["test_drive"] = {str(k): str(v) for k, v in drive.metadata.items()}
    ids: dict[str, int] = {}
    for seq, (t, topic, mt, msg, latched) in enumerate(drive_messages(drive, imu_topic=imu_topic)):
        if topic not in ids:
            cid = ids[topic] = len(ids) + 1
            rec.schemas[cid] = Schema(id=cid, name=mt, encoding="ros2msg", data=M.full_definition(mt).encode())
            rec.channels[cid] = Channel(id=cid, schema_id=cid, topic=topic, message_encoding="cdr",
                                        metadata={"offered_qos_profiles": qos_yaml(latched)})
        rec.messages.append(RawMessage(topic, mt, t, t, seq, M.encode(mt, msg), ids[topic]))
    return rec


def write_drive(path: str | os.PathLike, drive: TestDrive, *, overwrite: bool = False,
                imu_topic: str = IMU) -> int:
    """Write ``drive`` in the interface format; returns the number of messages written."""
    meta = {"vehicle": DEFAULT_VEHICLE, "maneuver": "", "damper_oil_level": "1,1,1,1", "source": "measured"}
    meta.update({str(k): str(v) for k, v in drive.metadata.items()})
    msgs = drive_messages(drive, imu_topic=imu_topic)
    with McapRecorder(path, metadata=meta, overwrite=overwrite) as rec:
        for t, topic, mt, msg, latched in msgs:
            rec.write(topic, mt, t, msg, latched=latched)
    return len(msgs)


__all__ = ["Series", "ImuSeries", "TestDrive", "read_drive", "write_drive", "recording_from_drive", "read_imu",
           "parse_oil", "oil_unknown",
           "drive_from_recording", "drive_messages", "road_from_msg", "imu_from_recording", "check_topic",
           "TOPIC_TYPES", "check_drive", "MAX_SPEED", "MAX_STEERING", "MAX_WHEEL_HEIGHT", "SPEED", "STEERING",
           "ROAD_PROFILE",
           "WHEEL_HEIGHTS", "DAMPER_COMMAND", "IMU", "SIM_IMU"]
