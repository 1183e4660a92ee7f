"""Topic maps (interface.md, "Topic maps"): how a recording with other topic names, message types, units
or sensor frames is read as a test drive.

A topic map is a small YAML file (``config/topic_maps/*.yaml``); each key is one input of the model::

    speed:                {topic: /odom, field: twist.twist.linear.x}        # m/s
    steering_wheel_angle: {topic: /can/steering, field: data, unit: deg}    # unit or scale (or both)
    imu:                  {topic: /imu/data, frame: frd}                    # flu | frd | {rpy_deg: [r, p, y]}
    road_profile:         {topic: /road/profile}                            # optional
    wheel_heights:        {topic: /rig/heights, field: data, unit: mm}      # optional, 4 values FL FR RL RR
    damper_oil_level:     {topic: /service/oil, field: data}                # optional, 4 fractions

Every key is optional: a key left out means the interface's own topic (``/vehicle/speed`` ...). An entry is
a mapping (or just the topic name as a string) with

- ``topic``: the topic name (starting with ``/``);
- ``field``: a dotted path into the message, with list indices as ``data[0]`` or ``data.0`` (default
  ``data``; for the IMU ``angular_velocity`` and ``linear_acceleration`` name the two vectors);
- ``unit``: the unit the field is recorded in (per input: angles ``rad``/``deg``, speeds ``m/s``/``km/h``/
  ``mph``, lengths ``m``/``cm``/``mm``, for the IMU ``gyro_unit`` ``rad/s``/``deg/s`` and ``accel_unit``
  ``m/s^2``/``g``, fractions ``1``/``%``); the SI value is ``raw * scale * unit factor``;
- ``scale``: a finite non-zero factor (e.g. ``-1`` for a steering angle recorded positive to the right);
- ``type``: optional ``pkg/msg/Type`` the topic must carry (checked; the identity map sets it);
- for ``imu`` only, ``frame``: the sensor axes: ``flu`` (x forward, y left, z up: REP-103; alias
  ``iso8855``), ``frd`` (x forward, y right, z down: aerospace IMUs; alias ``sae_j670``) or
  ``{rpy_deg: [roll, pitch, yaw]}``, the
  sensor's mounting rotation relative to the vehicle body (REP-103 roll-pitch-yaw, Z-Y-X, in degrees:
  the rotation that turns the body axes onto the sensor axes). A vector measured in sensor axes is
  ``v_body = R(roll, pitch, yaw) @ v_sensor``, so ``frd`` is ``rpy_deg: [180, 0, 0]``. Rates and specific
  forces are rotated; lever-arm effects of an IMU away from the centre of gravity are not corrected.

:func:`load_topic_map` parses a file (:class:`~susp_sim_ros.errors.TopicMapError` naming the file and the
key for anything malformed); :func:`add_topic_map_argument` adds ``--topic-map`` to a command's parser;
:func:`~susp_sim_ros.io.drive.read_drive` takes ``topic_map=`` (a path, a :class:`TopicMap` or None).
"""
from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from collections.abc import Collection, Mapping

import numpy as np

from ..errors import TopicMapError
from ..model.params import config_dir
from .units import G_STANDARD, UNITS  # SI factor of each unit, per kind of quantity (io/units.py)

#: The inputs a topic map can name: kind of quantity, the interface's topic, message type, default field.
INPUTS: dict[str, tuple[str, str, str, str]] = {
    "speed": ("speed", "/vehicle/speed", "std_msgs/msg/Float64", "data"),
    "steering_wheel_angle": ("angle", "/vehicle/steering_wheel_angle", "std_msgs/msg/Float64", "data"),
    "road_profile": ("length", "/road/profile", "std_msgs/msg/Float64MultiArray", ""),
    "wheel_heights": ("length", "/road/wheel_heights", "std_msgs/msg/Float64MultiArray", "data"),
    "damper_oil_level": ("fraction", "/vehicle/damper_oil_level", "std_msgs/msg/Float64MultiArray", "data"),
    "imu": ("", "/imu/data", "sensor_msgs/msg/Imu", ""),
}
_OPTIONAL_INPUTS = ("damper_oil_level",)  # not read unless the map names it
_TOP_KEYS = set(INPUTS) | {"version", "description"}
_ENTRY_KEYS = {"topic", "field", "unit", "scale", "type"}
_IMU_KEYS = {"topic", "type", "frame", "angular_velocity", "linear_acceleration", "gyro_unit", "accel_unit",
             "gyro_scale", "accel_scale"}
_SEGMENT = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)((?:\[\d+\])*)$|^(\d+)$")
_TYPE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*/msg/[A-Za-z_][A-Za-z0-9_]*$")
_TOPIC = re.compile(r"^/[A-Za-z0-9_~{}/]*[A-Za-z0-9_}]$|^/$")


def parse_field_path(path: Any, where: str) -> tuple[str | int, ...]:
    """``"twist.twist.linear.x"`` -> ``("twist", "twist", "linear", "x")``; ``"data[2]"`` and ``"data.2"``
    -> ``("data", 2)``; ``""`` -> ``()`` (the message itself). TopicMapError naming ``where`` otherwise."""
    if not isinstance(path, str):
        raise TopicMapError(f"{where}: field: expected a dotted path such as twist.twist.linear.x, got "
                            f"{path!r}")
    if path == "":
        return ()
    out: list[str | int] = []
    for seg in path.split("."):
        m = _SEGMENT.match(seg)
        if m is None:
            raise TopicMapError(f"{where}: field {path!r}: segment {seg!r} is not a field name or index "
                                f"(expected e.g. twist.twist.linear.x or data[0])")
        if m.group(3) is not None:
            out.append(int(m.group(3)))
        else:
            out.append(m.group(1))
            out.extend(int(k) for k in re.findall(r"\[(\d+)\]", m.group(2)))
    return tuple(out)


def get_field(msg: Any, path: tuple[str | int, ...]) -> Any:
    """The value at ``path`` in a decoded message (attribute objects, dicts or sequences)."""
    v = msg
    for seg in path:
        if isinstance(seg, int):
            v = v[seg]
        elif isinstance(v, Mapping):
            v = v[seg]
        else:
            v = getattr(v, seg)
    return v


def rotation_rpy(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """3x3 rotation ``Rz(yaw) @ Ry(pitch) @ Rx(roll)`` [rad] (REP-103 fixed-axis roll-pitch-yaw)."""
    cr, sr, cp, sp, cy, sy = (math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch),
                              math.cos(yaw), math.sin(yaw))
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    return rz @ ry @ rx


#: Named sensor frames and their rotation onto REP-103 body axes (v_body = R @ v_sensor). ISO 8855 (and DIN
#: 70000) vehicle axes are x forward, y left, z up: REP-103's; SAE J670 vehicle axes are x forward, y right,
#: z down.
FRAMES: dict[str, np.ndarray] = {"flu": np.eye(3), "frd": np.diag([1.0, -1.0, -1.0]),
                                 "iso8855": np.eye(3), "sae_j670": np.diag([1.0, -1.0, -1.0])}


@dataclass(frozen=True)
class MappedInput:
    """One mapped scalar/array input: values are ``raw * factor`` in SI."""

    name: str
    topic: str
    field: tuple[str | int, ...]
    factor: float = 1.0
    msgtype: str | None = None
    described: str = ""  # the conversion in words, for metadata and messages

    @property
    def field_text(self) -> str:
        return ".".join(str(s) for s in self.field)


@dataclass(frozen=True)
class MappedImu:
    """The mapped IMU: two vector fields, their SI factors and the sensor-to-body rotation."""

    topic: str
    angular_velocity: tuple[str | int, ...] = ("angular_velocity",)
    linear_acceleration: tuple[str | int, ...] = ("linear_acceleration",)
    gyro_factor: float = 1.0
    accel_factor: float = 1.0
    rotation: tuple[tuple[float, ...], ...] = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))  # 3x3, rows
    frame: str = "flu"
    msgtype: str | None = None

    @property
    def identity(self) -> bool:
        return self.gyro_factor == 1.0 and self.accel_factor == 1.0 and np.array_equal(
            np.asarray(self.rotation), np.eye(3))

    def to_body(self, gyro: np.ndarray, accel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Rows of sensor-axis vectors in recorded units -> REP-103 body axes, SI."""
        if self.identity:
            return gyro, accel
        r = np.asarray(self.rotation)
        return (gyro * self.gyro_factor) @ r.T, (accel * self.accel_factor) @ r.T


@dataclass(frozen=True)
class TopicMap:
    """Where each model input is in a recording (module docstring). ``TopicMap()`` is the interface's
    own layout (with its message types checked)."""

    speed: MappedInput = field(default_factory=lambda: _default("speed"))
    steering_wheel_angle: MappedInput = field(default_factory=lambda: _default("steering_wheel_angle"))
    road_profile: MappedInput = field(default_factory=lambda: _default("road_profile"))
    wheel_heights: MappedInput = field(default_factory=lambda: _default("wheel_heights"))
    damper_oil_level: MappedInput | None = None
    imu: MappedImu = field(default_factory=lambda: MappedImu("/imu/data", msgtype="sensor_msgs/msg/Imu"))
    source: str = "(interface layout)"

    def inputs(self) -> dict[str, MappedInput]:
        out = {k: getattr(self, k) for k in ("speed", "steering_wheel_angle", "road_profile", "wheel_heights",
                                             "damper_oil_level")}
        return {k: v for k, v in out.items() if v is not None}

    def topics(self) -> set[str]:
        return {m.topic for m in self.inputs().values()} | {self.imu.topic}

    def conversions(self) -> dict[str, str]:
        """What the map did, per input, in words (kept in the ``test_drive`` metadata of an import)."""
        out = {k: m.described for k, m in self.inputs().items() if m.described}
        if not self.imu.identity or self.imu.topic != "/imu/data":
            out["imu"] = (f"{self.imu.topic} ({'.'.join(map(str, self.imu.angular_velocity))}, "
                          f"{'.'.join(map(str, self.imu.linear_acceleration))}), frame {self.imu.frame} -> "
                          f"REP-103 body axes, gyro x{self.imu.gyro_factor:.9g}, accel x{self.imu.accel_factor:.9g}")
        return out


def _default(name: str) -> MappedInput:
    _, topic, msgtype, fld = INPUTS[name]
    return MappedInput(name, topic, parse_field_path(fld, name), 1.0, msgtype)


def _number(x: Any, where: str, what: str) -> float:
    if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(float(x)):
        raise TopicMapError(f"{where}: {what}: expected a finite number, got {x!r}")
    return float(x)


def unit_factor(kind: str, unit: Any, scale: Any, where: str, *, unit_key: str = "unit",
                scale_key: str = "scale") -> tuple[float, str]:
    """SI factor of ``unit`` (of ``kind``, see :data:`UNITS`; None = SI) times ``scale`` (None = 1), and a
    description. TopicMapError naming ``where`` for an unknown unit or a bad scale."""
    units = UNITS[kind]
    f, parts = 1.0, []
    if unit is not None:
        if not isinstance(unit, (str, int)) or str(unit) not in units:
            raise TopicMapError(f"{where}: {unit_key}: {unit!r} is not a unit of {kind} (expected one of "
                                f"{', '.join(units)})")
        f = units[str(unit)]
        if f != 1.0:
            parts.append(f"{unit} -> SI")
    if scale is not None:
        s = _number(scale, where, scale_key)
        if s == 0.0:
            raise TopicMapError(f"{where}: {scale_key}: must not be 0")
        f *= s
        if s != 1.0:
            parts.append(f"scale {s:g}")
    return f, ", ".join(parts)


def parse_frame(frame: Any, where: str) -> tuple[np.ndarray, str]:
    """``flu`` | ``frd`` | ``{rpy_deg: [r, p, y]}`` -> (sensor-to-body rotation, description)."""
    if frame is None:
        return FRAMES["flu"], "flu"
    if isinstance(frame, str):
        key = frame.strip().lower()
        if key in FRAMES:
            return FRAMES[key], key
        raise TopicMapError(f"{where}: frame: {frame!r} is not a frame (expected {', '.join(FRAMES)} or "
                            f"{{rpy_deg: [roll, pitch, yaw]}})")
    if isinstance(frame, Mapping) and set(frame) == {"rpy_deg"}:
        rpy = frame["rpy_deg"]
        if not isinstance(rpy, (list, tuple)) or len(rpy) != 3:
            raise TopicMapError(f"{where}: frame.rpy_deg: expected three angles [roll, pitch, yaw] in "
                                f"degrees, got {rpy!r}")
        r, p, y = (_number(a, where, "frame.rpy_deg") for a in rpy)
        if max(abs(r), abs(p), abs(y)) > 360.0:
            raise TopicMapError(f"{where}: frame.rpy_deg: angles must be within +-360 deg, got {list(rpy)}")
        return rotation_rpy(*np.radians([r, p, y])), f"rpy_deg [{r:g}, {p:g}, {y:g}]"
    raise TopicMapError(f"{where}: frame: expected flu, frd or {{rpy_deg: [roll, pitch, yaw]}}, got {frame!r}")


def _topic(x: Any, where: str) -> str:
    if not isinstance(x, str) or not _TOPIC.match(x) or "//" in x:
        raise TopicMapError(f"{where}: topic: expected a ROS topic name such as /vehicle/speed, got {x!r}")
    return x


def _msgtype(x: Any, where: str) -> str | None:
    if x is None:
        return None
    if not isinstance(x, str) or not _TYPE.match(x):
        raise TopicMapError(f"{where}: type: expected pkg/msg/Type, got {x!r}")
    return x


def _entry_mapping(raw: Any, where: str, known: Collection[str], shape: str) -> Mapping:
    """An input's entry as a mapping: a bare topic name stands for ``{topic: NAME}``; only ``known``
    keys, ``topic`` among them (``shape`` describes the mapping in the error)."""
    if isinstance(raw, str):
        raw = {"topic": raw}
    if not isinstance(raw, Mapping):
        raise TopicMapError(f"{where}: expected a mapping {shape} or a topic name, got {raw!r}")
    unknown = sorted(str(k) for k in raw if k not in known)
    if unknown:
        raise TopicMapError(f"{where}: unknown key(s) {', '.join(unknown)} (known: {', '.join(sorted(known))})")
    if "topic" not in raw:
        raise TopicMapError(f"{where}: missing topic")
    return raw


def _entry(name: str, raw: Any, where: str) -> MappedInput:
    kind, _, _, default_field = INPUTS[name]
    raw = _entry_mapping(raw, where, _ENTRY_KEYS, "{topic: ..., field: ..., unit: ...}")
    topic = _topic(raw["topic"], where)
    path = parse_field_path(raw.get("field", default_field), where)
    factor, desc = unit_factor(kind, raw.get("unit"), raw.get("scale"), where)
    msgtype = _msgtype(raw.get("type"), where)
    default = INPUTS[name][1]
    described = ""
    if topic != default or factor != 1.0 or path != parse_field_path(default_field, name):
        described = f"{topic}" + (f" field {'.'.join(map(str, path))}" if path else "") + (f" ({desc})" if desc else "")
    return MappedInput(name, topic, path, factor, msgtype, described)


def _imu(raw: Any, where: str) -> MappedImu:
    raw = _entry_mapping(raw, where, _IMU_KEYS, "{topic: ..., frame: ...}")
    rot, frame = parse_frame(raw.get("frame"), where)
    gf, _ = unit_factor("rate", raw.get("gyro_unit"), raw.get("gyro_scale"), where, unit_key="gyro_unit",
                        scale_key="gyro_scale")
    af, _ = unit_factor("accel", raw.get("accel_unit"), raw.get("accel_scale"), where, unit_key="accel_unit",
                        scale_key="accel_scale")
    return MappedImu(_topic(raw["topic"], where),
                     parse_field_path(raw.get("angular_velocity", "angular_velocity"), f"{where}.angular_velocity"),
                     parse_field_path(raw.get("linear_acceleration", "linear_acceleration"),
                                      f"{where}.linear_acceleration"),
                     gf, af, tuple(tuple(float(x) for x in row) for row in rot), frame, _msgtype(raw.get("type"),
                                                                                                 where))


def parse_topic_map(data: Any, source: str = "topic map") -> TopicMap:
    """A :class:`TopicMap` from the loaded YAML ``data`` (``source`` names it in errors)."""
    if data is None:
        data = {}
    if not isinstance(data, Mapping):
        raise TopicMapError(f"{source}: expected a mapping of inputs ({', '.join(INPUTS)}), got "
                            f"{type(data).__name__}")
    unknown = sorted(str(k) for k in data if k not in _TOP_KEYS)
    if unknown:
        raise TopicMapError(f"{source}: unknown input(s) {', '.join(unknown)} (known: {', '.join(INPUTS)})")
    if "version" in data and data["version"] != 1:
        raise TopicMapError(f"{source}: version: expected 1, got {data['version']!r}")
    kw: dict[str, Any] = {"source": source}
    for name in INPUTS:
        if name in data:
            where = f"{source}: {name}"
            kw[name] = _imu(data[name], where) if name == "imu" else _entry(name, data[name], where)
    tm = TopicMap(**kw)
    topics = [m.topic for m in tm.inputs().values()]
    dup = sorted({t for t in topics if topics.count(t) > 1 and t not in ("/",)})
    if dup and any(_same_field(tm, t) for t in dup):
        raise TopicMapError(f"{source}: two inputs read the same field of {', '.join(dup)}")
    return tm


def _same_field(tm: TopicMap, topic: str) -> bool:
    fields = [m.field for m in tm.inputs().values() if m.topic == topic]
    return len(fields) != len(set(fields))


def load_topic_map(path: str | os.PathLike | TopicMap | None) -> TopicMap:
    """The topic map in ``path`` (a YAML file, or a name in ``config/topic_maps/``); None -> the interface
    layout; a :class:`TopicMap` is returned as it is."""
    if path is None:
        return TopicMap()
    if isinstance(path, TopicMap):
        return path
    import yaml
    p = Path(path)
    if not p.is_file() and p.suffix == "" and len(p.parts) == 1:
        cand = config_dir() / "topic_maps" / f"{p.name}.yaml"
        if cand.is_file():
            p = cand
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise TopicMapError(f"{path}: no such topic map file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise TopicMapError(f"{path}: cannot read topic map: {exc}") from None
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise TopicMapError(f"{path}: not valid YAML: {str(exc).splitlines()[0]}") from None
    return parse_topic_map(data, str(path))


def add_topic_map_argument(parser) -> None:
    """Add ``--topic-map FILE.yaml`` to an argparse parser (every command that reads recordings)."""
    parser.add_argument("--topic-map", metavar="FILE.yaml", default=None,
                        help="read recordings with other topic names, types, units or IMU frames through this "
                             "map (config/topic_maps/; default: the interface's own topics)")


__all__ = ["TopicMap", "MappedInput", "MappedImu", "load_topic_map", "parse_topic_map", "parse_field_path",
           "get_field", "parse_frame", "unit_factor", "rotation_rpy", "add_topic_map_argument", "UNITS",
           "INPUTS", "FRAMES", "G_STANDARD"]
