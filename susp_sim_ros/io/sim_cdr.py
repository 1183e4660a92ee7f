"""CDR bytes of the node's ``/sim`` messages straight from an output vector (no rclpy, no message objects).

The wall-time node publishes and records every sample's three messages from its tick thread. Filling
rclpy message objects (whose setters check every element of the 9- and 36-element covariances), then
serialising them twice (once by ``publish``, once for the recording) made the publishing part of a tick
0.6-0.8 ms (p90) on this 2-vCPU VM (an instrumented soak, 2026-11-29), most of a tick's work and all of
it under the interpreter lock the node's other threads wait for. Here each message is one precompiled
``struct`` pack (the constant parts, frame ids and array layouts, are encoded once): a few microseconds;
the node publishes these bytes as they are (``Publisher.publish(bytes)``) and records the same bytes.

The content is that of :func:`~susp_sim_ros.io.messages.imu_msg`, :func:`~.messages.odom_msg` and
:func:`~.messages.suspension_msg` (the message builders the offline runner records), which the tests
check field by field for any output vector, and against rclpy's own deserialiser. Little-endian CDR
(encapsulation ``00 01 00 00``), padding bytes zero.
"""
from __future__ import annotations

import math
import struct

import numpy as np

from ..model.layout import output_index
from .messages import SUSPENSION_COLUMNS, encode_float64_multiarray, quaternion_from_rpy, suspension_msg

__all__ = ["imu_cdr", "odom_cdr", "suspension_cdr"]

_ENCAPSULATION = b"\x00\x01\x00\x00"
_NS = 1_000_000_000


def _string(s: str, offset: int) -> bytes:
    """A CDR string (aligned to 4 from ``offset``, the byte count after the encapsulation header)."""
    b = s.encode("utf-8") + b"\x00"
    return b"\x00" * (-offset % 4) + struct.pack("<I", len(b)) + b


def _after_stamp(*strings: str) -> bytes:
    """The constant bytes between a header's stamp and the first double: the strings, then padding to 8."""
    out = b""
    for s in strings:
        out += _string(s, 8 + len(out))
    return out + b"\x00" * (-(8 + len(out)) % 8)


class _Stamped:
    """``encapsulation, stamp (sec, nanosec), constant strings, n doubles`` as one precompiled pack."""

    def __init__(self, n_doubles: int, *strings: str):
        mid = _after_stamp(*strings)
        self._s = struct.Struct(f"<4siI{len(mid)}s{n_doubles}d")
        self._mid = mid

    def pack(self, t_ns: int, values) -> bytes:
        t_ns = int(t_ns)
        return self._s.pack(_ENCAPSULATION, t_ns // _NS, t_ns % _NS, self._mid, *values)


_IMU: dict[str, _Stamped] = {}
_ODOM = _Stamped(3 + 4 + 36 + 6 + 36, "odom", "base_link")
_Z9, _Z36 = (0.0,) * 9, (0.0,) * 36
_I = {k: output_index(k) for k in ("ROLL", "PITCH", "YAW", "POS_X", "POS_Y", "VEL_X", "VEL_Y", "YAW_RATE")}
_RATES = [output_index(k) for k in ("ROLL_RATE", "PITCH_RATE", "YAW_RATE")]
_ACCEL = [output_index(k) for k in ("AX_SF", "AY_SF", "AZ_SF")]


def imu_cdr(t_ns: int, y: np.ndarray, frame_id: str = "base_link") -> bytes:
    """``sensor_msgs/msg/Imu`` as :func:`~.messages.imu_msg` builds it, in CDR."""
    enc = _IMU.get(frame_id)
    if enc is None:
        enc = _IMU[frame_id] = _Stamped(4 + 9 + 3 + 9 + 3 + 9, frame_id)
    q = quaternion_from_rpy(y[_I["ROLL"]], y[_I["PITCH"]], y[_I["YAW"]])
    rates, acc = y[_RATES].tolist(), y[_ACCEL].tolist()
    return enc.pack(t_ns, (*q, *_Z9, *rates, *_Z9, *acc, *_Z9))


def odom_cdr(t_ns: int, y: np.ndarray) -> bytes:
    """``nav_msgs/msg/Odometry`` as :func:`~.messages.odom_msg` builds it, in CDR."""
    yaw = float(y[_I["YAW"]])
    return _ODOM.pack(t_ns, (float(y[_I["POS_X"]]), float(y[_I["POS_Y"]]), 0.0,
                             0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2), *_Z36,
                             float(y[_I["VEL_X"]]), float(y[_I["VEL_Y"]]), 0.0, 0.0, 0.0, float(y[_I["YAW_RATE"]]),
                             *_Z36))


_N_SUSP = len(SUSPENSION_COLUMNS)
_SUSP_LAYOUT = suspension_msg(np.zeros(int(SUSPENSION_COLUMNS.max()) + 1))["layout"]  # the builder's layout
#: everything of the builder's message before its data
_SUSP_PREFIX = encode_float64_multiarray([(d["label"], d["size"], d["stride"]) for d in _SUSP_LAYOUT["dim"]],
                                         _SUSP_LAYOUT["data_offset"], np.zeros(_N_SUSP))[:-8 * _N_SUSP]


def suspension_cdr(y: np.ndarray) -> bytes:
    """``std_msgs/msg/Float64MultiArray`` as :func:`~.messages.suspension_msg` builds it, in CDR."""
    return _SUSP_PREFIX + np.asarray(y, dtype="<f8")[SUSPENSION_COLUMNS].tobytes()
