"""Message conversion between the plain-dict messages of :mod:`susp_sim_ros.io.messages` (pure) and rclpy
message objects, and CDR bytes for the recording."""
from __future__ import annotations

from collections.abc import Callable

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy.serialization import serialize_message
from std_msgs.msg import Float64MultiArray, MultiArrayDimension

from ..io import messages as M

NS_PER_S = 1_000_000_000


def clock_time_ns(msg) -> int | None:
    """The time of a ``rosgraph_msgs/Clock`` message [ns], None when it is no valid time (sec < 0 or
    nanosec outside [0, 1e9))."""
    sec, nsec = int(msg.clock.sec), int(msg.clock.nanosec)
    if sec < 0 or not 0 <= nsec < NS_PER_S:
        return None
    return sec * NS_PER_S + nsec


def fill(msg, d: dict):
    """Copy a plain-dict message (io.messages builders) into an rclpy message object."""
    for k, v in d.items():
        if isinstance(v, dict):
            fill(getattr(msg, k), v)
        elif k == "dim":
            msg.dim = [MultiArrayDimension(label=x["label"], size=int(x["size"]), stride=int(x["stride"]))
                       for x in v]
        else:
            setattr(msg, k, v)
    return msg


def layout_dims(msg: Float64MultiArray) -> list[tuple[str, int, int]]:
    """``(label, size, stride)`` of each layout dimension of a ``Float64MultiArray``."""
    return [(d.label, d.size, d.stride) for d in msg.layout.dim]


def input_cdr(msg) -> Callable[[], bytes]:
    """CDR bytes of a received input message, made later in the recording thread (arrays by the fast
    numpy encoder of :mod:`~susp_sim_ros.io.messages`)."""
    if isinstance(msg, Float64MultiArray):
        return lambda: M.encode_float64_multiarray(layout_dims(msg), msg.layout.data_offset, msg.data)
    return lambda: serialize_message(msg)


def diagnostic_array(t_ns: int, statuses: list[dict]) -> DiagnosticArray:
    """A ``diagnostic_msgs/DiagnosticArray`` stamped ``t_ns`` [ns] from status dicts (level, name,
    message, values) as :func:`~susp_sim_ros.io.messages.diagnostics_msg` takes them."""
    d = M.diagnostics_msg(t_ns, statuses)
    msg = DiagnosticArray()
    fill(msg.header, d["header"])
    msg.status = [DiagnosticStatus(level=bytes([s["level"]]), name=s["name"], message=s["message"],
                                   hardware_id=s["hardware_id"],
                                   values=[KeyValue(key=kv["key"], value=kv["value"]) for kv in s["values"]])
                  for s in d["status"]]
    return msg
