"""Helpers of the reliability tests (test_reliability_*.py): message strategies for fuzzing the node's
input handlers, publishers that check every outgoing message, finiteness checks of recordings."""
from __future__ import annotations

import math

import numpy as np
from hypothesis import strategies as st

from susp_sim_ros.runtime.sim_core import MAX_SPEED, MAX_STEERING, MAX_WHEEL_HEIGHT

NAN, INF = float("nan"), float("inf")

#: Values at and just beyond every limit, plus IEEE specials.
EDGE_FLOATS = [NAN, -NAN, INF, -INF, 1.7976931348623157e308, -1.7976931348623157e308, 5e-324, -5e-324,
               0.0, -0.0, 1e-300, -1.0, -1e-9, MAX_SPEED, math.nextafter(MAX_SPEED, INF), 1e6, -1e6,
               MAX_STEERING, -MAX_STEERING, math.nextafter(MAX_STEERING, INF), 2.0 ** 53, 1e20,
               MAX_WHEEL_HEIGHT, -MAX_WHEEL_HEIGHT, math.nextafter(MAX_WHEEL_HEIGHT, INF)]

any_float = st.one_of(st.sampled_from(EDGE_FLOATS), st.floats(), st.floats(-150.0, 150.0),
                      st.floats(0.0, MAX_SPEED))
uint32 = st.one_of(st.sampled_from([0, 1, 2, 3, 4, 5, 2 ** 31, 2 ** 32 - 1]), st.integers(0, 2 ** 32 - 1))
labels = st.sampled_from(["", "channel", "sample", "wheel", "x", "\u00e9\u00e8", "channel\x00"])


def expected_scalar_cause(topic: str, v: float) -> str | None:
    """The rejection cause SimCore must give a Float64 value on ``topic`` (None: accepted)."""
    if not math.isfinite(v):
        return "non_finite"
    if topic == "/vehicle/speed":
        return "speed_negative" if v < 0 else ("speed_range" if v > MAX_SPEED else None)
    return "steering_range" if abs(v) > MAX_STEERING else None


def _mad(Float64MultiArray, MultiArrayDimension, dims, data, offset=0):
    m = Float64MultiArray()
    m.layout.dim = [MultiArrayDimension(label=lb, size=sz, stride=sd) for lb, sz, sd in dims]
    m.layout.data_offset = offset
    m.data = [float(x) for x in data]
    return m


@st.composite
def profile_msgs(draw):
    """``/road/profile`` messages: valid ones, non-increasing s, bad values, random/empty/mis-shaped
    layouts, wrong strides and data offsets, swapped dims. Returns ``(msg, kind)``. Hypothesis draws the
    structure and the special values; the bulk numbers come from a drawn seed (fast)."""
    from std_msgs.msg import Float64MultiArray, MultiArrayDimension
    kind = draw(st.sampled_from(["valid", "valid", "nonincreasing", "bad_value", "empty", "random_layout",
                                 "wrong_count", "strides", "offset", "swapped", "one_dim", "huge_z"]))
    n = draw(st.integers(2, 24))
    rng = np.random.default_rng(draw(st.integers(0, 2 ** 32 - 1)))
    steps = rng.uniform(1e-3, 2.0, n)
    s = np.cumsum(steps) - steps[0] + rng.uniform(-5.0, 20.0)
    data = list(s) + list(rng.uniform(-0.08, 0.08, 2 * n))
    dims = [("channel", 3, 3 * n), ("sample", n, n)]
    off = 0
    if kind == "nonincreasing":
        i = draw(st.integers(1, n - 1))
        data[i] = data[i - 1] - draw(st.sampled_from([0.0, 1e-12, 0.5, 5.0]))
    elif kind == "bad_value":
        data[draw(st.integers(0, 3 * n - 1))] = draw(st.sampled_from(EDGE_FLOATS[:8] + [1e9, 2.0]))
    elif kind == "empty":
        dims, data = [], []
    elif kind == "random_layout":
        dims = draw(st.lists(st.tuples(labels, uint32, uint32), max_size=3))
        data = list(rng.choice(np.array(EDGE_FLOATS + [0.5, 1.0, 2.0, 3.0]), draw(st.integers(0, 40))))
        off = draw(uint32)
    elif kind == "wrong_count":
        data = data[:draw(st.integers(0, 3 * n - 1))] if draw(st.booleans()) else data + [0.0] * draw(st.integers(1, 5))
    elif kind == "strides":
        dims = [("channel", 3, draw(uint32)), ("sample", n, draw(uint32))]
    elif kind == "offset":
        off = draw(st.integers(0, 6))
        data = [0.0] * draw(st.integers(0, 6)) + data
    elif kind == "swapped":
        dims = [("sample", n, n), ("channel", 3, 3 * n)]
    elif kind == "one_dim":
        dims = [("channel", 3 * n, 3 * n)]
    elif kind == "huge_z":
        data[n + draw(st.integers(0, 2 * n - 1))] = draw(st.sampled_from([1.5, -3.0, 1e6]))
    return _mad(Float64MultiArray, MultiArrayDimension, dims, data, off), kind


@st.composite
def heights_msgs(draw):
    """``/road/wheel_heights`` messages: valid (mostly realistic, sometimes up to the 1 m limit), wrong
    counts, bad values, mis-shaped layouts and offsets. Returns ``(msg, kind)``."""
    from std_msgs.msg import Float64MultiArray, MultiArrayDimension
    kind = draw(st.sampled_from(["valid", "valid", "valid", "extreme", "count", "bad_value", "layout",
                                 "offset", "empty"]))
    rng = np.random.default_rng(draw(st.integers(0, 2 ** 32 - 1)))
    z = list(rng.uniform(-0.05, 0.05, 4))
    dims, off = [("wheel", 4, 4)] if draw(st.booleans()) else [], 0
    if kind == "extreme":
        z = list(rng.uniform(-MAX_WHEEL_HEIGHT, MAX_WHEEL_HEIGHT, 4))
    elif kind == "count":
        z = list(rng.uniform(-0.05, 0.05, draw(st.sampled_from([0, 1, 2, 3, 5, 6, 8, 9]))))
    elif kind == "bad_value":
        z[draw(st.integers(0, 3))] = draw(st.sampled_from(EDGE_FLOATS))
    elif kind == "layout":
        dims = draw(st.lists(st.tuples(labels, uint32, uint32), min_size=1, max_size=3))
    elif kind == "offset":
        off = draw(st.integers(0, 5))
        z = [0.0] * draw(st.integers(0, 5)) + z
    elif kind == "empty":
        z, dims = [], []
    return _mad(Float64MultiArray, MultiArrayDimension, dims, z, off), kind


class CheckingPublisher:
    """Stands in for an rclpy publisher: checks every message for non-finite numbers on the spot."""

    def __init__(self, kind: str):
        self.kind, self.count, self.bad = kind, 0, []

    def get_subscription_count(self) -> int:
        return 1

    def publish(self, msg) -> None:
        self.count += 1
        vals = message_numbers(msg)
        if not np.all(np.isfinite(vals)):
            self.bad.append((self.kind, vals))


def message_numbers(msg) -> np.ndarray:
    """Every number a /sim message carries (stamp included), as floats."""
    if hasattr(msg, "angular_velocity"):
        v = [msg.header.stamp.sec, msg.header.stamp.nanosec,
             msg.orientation.x, msg.orientation.y, msg.orientation.z, msg.orientation.w,
             msg.angular_velocity.x, msg.angular_velocity.y, msg.angular_velocity.z,
             msg.linear_acceleration.x, msg.linear_acceleration.y, msg.linear_acceleration.z]
        return np.array(v, float)
    if hasattr(msg, "pose"):
        p, tw = msg.pose.pose, msg.twist.twist
        v = [msg.header.stamp.sec, p.position.x, p.position.y, p.position.z, p.orientation.x, p.orientation.y,
             p.orientation.z, p.orientation.w, tw.linear.x, tw.linear.y, tw.linear.z, tw.angular.x,
             tw.angular.y, tw.angular.z]
        return np.array(v, float)
    if hasattr(msg, "data"):
        return np.asarray(msg.data, float)
    if hasattr(msg, "status"):  # DiagnosticArray: the numeric values must parse as finite numbers
        out = []
        for s in msg.status:
            for kv in s.values:
                if kv.key in ("real_time_factor", "sim_time_s", "jitter_p50_ms", "jitter_p99_ms",
                              "jitter_max_ms", "lateness_p50_ms", "lateness_p99_ms"):
                    out.append(float(kv.value))
        return np.array(out, float)
    return np.zeros(0)


def recorded_sim_numbers(path) -> tuple[int, int]:
    """(messages on /sim/... in the recording, how many of them carry a non-finite number); decoded with
    rclpy's C deserialiser (fast) and checked field by field as published."""
    from nav_msgs.msg import Odometry
    from rclpy.serialization import deserialize_message
    from sensor_msgs.msg import Imu
    from std_msgs.msg import Float64MultiArray
    from susp_sim_ros.io.reader import read_recording
    classes = {"/sim/imu/data": Imu, "/sim/odom": Odometry, "/sim/suspension": Float64MultiArray}
    rec = read_recording(path)
    n = bad = 0
    for m in rec.messages:
        cls = classes.get(m.topic)
        if cls is None:
            continue
        n += 1
        if not np.all(np.isfinite(message_numbers(deserialize_message(m.data, cls)))):
            bad += 1
    return n, bad
