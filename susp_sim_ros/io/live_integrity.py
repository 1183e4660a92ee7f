"""Input integrity of the live node (issue 28, item 4): the offline policy, message by message.

The offline tools check a whole recording at once (:mod:`.integrity`); the simulation node sees one
message at a time and must judge it on arrival. :class:`LiveIntegrity` applies the same policy table
(``config/integrity.yaml``, read with :func:`.integrity.load_policy`; no limit is repeated here) to each
input message and returns one :class:`LiveFinding` per defect, with the ``kind`` strings of the offline
``input_findings`` (:data:`.integrity.KINDS`). :class:`FindingBoard` keeps them per (topic, kind) for
``/diagnostics``. Pure: no rclpy; the node (:mod:`susp_sim_ros.ros.inputs`) passes the ROS time at which it
applies a message (its log time in the node's recording) and the message's numbers.

Kinds judged live (``level``: 1 WARN, 2 ERROR where the offline policy raises its named error):

* ``non_finite`` -- a NaN/inf value (the node rejects the message, the last value holds: ``excluded``);
  on ``/road/profile`` (one latched message: nothing left to work on) ERROR.
* ``implausible_unit`` -- speed beyond ``limits.speed_max`` m/s that fits it as km/h, steering beyond
  ``limits.steering_max`` rad that fits it as degrees (the offline rule on the magnitude): ERROR,
  ``excluded``. It needs the evidence the offline check needs: offline, samples far from the running
  median are dropped as spikes before the unit is judged, so one outlier in a signal recorded in the right
  unit is a ``spike``, never a unit mistake. Live, once a topic has ``spikes.window`` - 1 earlier messages,
  a value beyond the limit is judged against them (:meth:`LiveIntegrity.check`): far from the value the
  last two predict (beyond ``spikes.mad_factor`` robust sd of their second differences and at least the
  ``spikes.floor_*`` of the signal) it is a ``spike`` (WARN, ``excluded``: the node rejects it, the last
  value holds); in line with them (a signal that really lives there: recorded in the other unit) it is
  ``implausible_unit``. With fewer earlier messages the magnitude alone decides, as offline on a series
  shorter than the spike window.
* ``out_of_range`` -- a value outside what the node accepts and no unit mistake: speed outside
  [0, ``limits.speed_max``] m/s, a steering angle beyond +-``limits.steering_max`` rad, a wheel height beyond
  +-``limits.wheel_height_max`` m, a damper command outside [0, 1] (WARN, ``excluded``); a road profile
  elevation beyond +-``limits.wheel_height_max`` m (ERROR, as offline).
* ``stamp_order`` -- the message's time is before the previous message's on that topic by at most
  ``stamps.backward_jump_s``; ``clock_jump`` -- back by more than that, or forward by more than
  ``stamps.clock_jump_s`` (WARN, ``kept``: the node applies the message at its time).
* ``gap`` -- no message on an input topic for longer than ``stamps.gap_periods`` times its median
  interval (over the last ``stamps.rate_window`` positive intervals) and at least ``stamps.gap_min_s``:
  reported while it lasts (:meth:`LiveIntegrity.check_gaps`, the held value is stale) and when the next
  message ends it (WARN, ``kept``: the last value is held over it). The latched road profile has no gaps.

Not judged live: ``duplicate_stamp`` (a message's time is the ROS time at which the node applies it; with
a ``/clock`` slower than the input several messages share one), ``spike`` within the limits and
``rate_change`` (both need the samples after the one judged; the node holds each value at once; a spike
beyond the limit is judged, above), ``dead_sensor``,
``saturated_sensor`` (the node subscribes to no measured IMU), ``missing_topic`` and ``bad_metadata``
(no recording metadata live).
"""
from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from .drive_data import DAMPER_COMMAND, DAMPER_COMMAND_RANGE, ROAD_PROFILE, SPEED, STEERING, WHEEL_HEIGHTS
from .integrity import KINDS, load_policy
from .units import FACTORS

NS = 1_000_000_000
WARN, ERROR = 1, 2  # diagnostic_msgs/DiagnosticStatus levels
LEVEL_NAMES = {WARN: "WARN", ERROR: "ERROR"}
#: the input topics whose messages come as a stream (gaps and stamp order are judged on them)
STREAM_TOPICS = (SPEED, STEERING, WHEEL_HEIGHTS, DAMPER_COMMAND)
#: unit-mistake factors (the other unit to the interface's SI unit), from the one units table
KMH_TO_M_S = FACTORS["km/h"]
DEG_TO_RAD = FACTORS["deg"]


@dataclass(frozen=True)
class LiveFinding:
    """One defect of a live input message (or of an input topic's timing) and what the node does."""

    topic: str
    kind: str        # one of integrity.KINDS
    t_ns: int        # ROS time of the message (or of the check, for a gap still open) [ns]
    level: int       # WARN or ERROR
    action: str      # "excluded" (the message is rejected, the last value holds) or "kept"
    value: str       # what was seen
    expected: str    # what was expected
    detail: str = ""
    from_ns: int | None = None  # start of the span (the previous message) for stamp and gap findings

    def __post_init__(self) -> None:
        assert self.kind in KINDS, self.kind

    def values(self) -> dict[str, str]:
        """The key/values of its ``/diagnostics`` status."""
        out = {"topic": self.topic, "kind": self.kind, "time_s": f"{self.t_ns / NS:.9f}",
               "value": self.value, "expected": self.expected, "action": self.action,
               "severity": LEVEL_NAMES[self.level], "detail": self.detail}
        if self.from_ns is not None:
            out["from_s"] = f"{self.from_ns / NS:.9f}"
        return out

    def line(self) -> str:
        """The log line: ``input integrity: TOPIC KIND at T s: value V, expected E (ACTION); DETAIL``."""
        return (f"input integrity: {self.topic} {self.kind} at {self.t_ns / NS:.3f} s: value {self.value}, "
                f"expected {self.expected} ({self.action})" + (f"; {self.detail}" if self.detail else ""))


@dataclass(frozen=True)
class LivePolicy:
    """The entries of the policy table the live checks use (from ``config/integrity.yaml``)."""

    speed_max: float
    steering_max: float
    wheel_height_max: float
    command_range: tuple[float, float]
    gap_periods: float
    gap_min_ns: int
    clock_jump_ns: int
    backward_jump_ns: int
    rate_window: int
    spike_window: int = 11
    mad_factor: float = 25.0
    spike_floor: dict[str, float] = field(default_factory=dict)  # topic -> spikes.floor_* [its unit]

    @classmethod
    def from_table(cls, policy: dict[str, Any] | None = None) -> "LivePolicy":
        """From :func:`.integrity.load_policy`'s table (loaded when ``policy`` is None)."""
        p = policy if policy is not None else load_policy()
        return cls(speed_max=float(p["limits.speed_max"]), steering_max=float(p["limits.steering_max"]),
                   wheel_height_max=float(p["limits.wheel_height_max"]),
                   command_range=(float(DAMPER_COMMAND_RANGE[0]), float(DAMPER_COMMAND_RANGE[1])),
                   gap_periods=float(p["stamps.gap_periods"]), gap_min_ns=int(float(p["stamps.gap_min_s"]) * NS),
                   clock_jump_ns=int(float(p["stamps.clock_jump_s"]) * NS),
                   backward_jump_ns=int(float(p["stamps.backward_jump_s"]) * NS),
                   rate_window=int(p["stamps.rate_window"]), spike_window=int(p["spikes.window"]),
                   mad_factor=float(p["spikes.mad_factor"]),
                   spike_floor={SPEED: float(p["spikes.floor_speed"]), STEERING: float(p["spikes.floor_steering"])})


def _fmt(values: Sequence[float]) -> str:
    return f"{values[0]:.6g}" if len(values) == 1 else "[" + ", ".join(f"{v:.6g}" for v in values) + "]"


def judge_value(topic: str, values: Sequence[float] | np.ndarray, pol: LivePolicy
                ) -> tuple[str, int, str, str] | None:
    """The value defect of one input message of ``topic`` (its numbers ``values``: the scalar of a
    ``Float64``, the four values of ``/road/wheel_heights`` or ``/vehicle/damper_command``, the data
    [s, zl, zr] of ``/road/profile`` after its data offset) as ``(kind, level, value, expected)``, or None
    when the values are sound. Messages of another shape (the node rejects them for their layout) are not
    judged here."""
    if topic == ROAD_PROFILE:
        return _judge_road(np.asarray(values, dtype=float), pol)
    if len(values) != (1 if topic in (SPEED, STEERING) else 4):
        return None
    vals = [float(v) for v in values]
    if not all(math.isfinite(v) for v in vals):
        return "non_finite", WARN, _fmt(vals), "finite values"
    if topic in (SPEED, STEERING):
        v = vals[0]
        if topic == SPEED:
            limit, factor, unit, other = pol.speed_max, KMH_TO_M_S, "m/s", "km/h"
            lo, hi, name = 0.0, pol.speed_max, "limits.speed_max"
        else:
            limit, factor, unit, other = pol.steering_max, DEG_TO_RAD, "rad", "degrees"
            lo, hi, name = -pol.steering_max, pol.steering_max, "limits.steering_max"
        if abs(v) > limit and abs(v) * factor <= limit:  # the offline rule (integrity._Checker.units)
            return ("implausible_unit", ERROR, f"{v:.6g} {unit}",
                    f"{unit} within {limit:.6g} {unit} ({name}); the value fits {other} (unit mistake)")
        if v < lo or v > hi:
            return "out_of_range", WARN, f"{v:.6g} {unit}", f"[{lo:.6g}, {hi:.6g}] {unit} ({name})"
        return None
    if topic == WHEEL_HEIGHTS:
        lim = pol.wheel_height_max
        if any(abs(v) > lim for v in vals):
            return ("out_of_range", WARN, f"{_fmt(vals)} m",
                    f"[{-lim:.6g}, {lim:.6g}] m (limits.wheel_height_max)")
        return None
    if topic == DAMPER_COMMAND:
        lo, hi = pol.command_range
        if any(v < lo or v > hi for v in vals):
            return "out_of_range", WARN, _fmt(vals), f"[{lo:.6g}, {hi:.6g}] (valve command range of interface.md)"
        return None
    return None


def _judge_road(data: np.ndarray, pol: LivePolicy) -> tuple[str, int, str, str] | None:
    """A road profile (its data [s, zl, zr], 3 N values): one latched message, so a defect leaves nothing
    (ERROR)."""
    if not data.size or data.size % 3:
        return None
    finite = np.isfinite(data)
    if not finite.all():
        return "non_finite", ERROR, f"{int((~finite).sum())} non-finite value(s)", "finite values"
    peak = float(np.abs(data[data.size // 3:]).max())
    if peak > pol.wheel_height_max:
        lim = pol.wheel_height_max
        return ("out_of_range", ERROR, f"elevation up to {peak:.6g} m",
                f"elevations within [{-lim:.6g}, {lim:.6g}] m (limits.wheel_height_max)")
    return None


@dataclass
class _TopicClock:
    """What the stamp checks remember of one input topic."""

    last_ns: int | None = None
    intervals: deque = field(default_factory=deque)
    gap_open: bool = False


class LiveIntegrity:
    """Per-topic judgement of the live inputs under one policy (see the module docstring).

    :meth:`check` judges one message (value and stamp) and :meth:`check_gaps` the topics that have gone
    quiet; both return the new findings. Only messages with finite values count for the stamp checks (as
    offline, where non-finite samples are dropped first)."""

    def __init__(self, policy: dict[str, Any] | LivePolicy | None = None):
        self.policy = policy if isinstance(policy, LivePolicy) else LivePolicy.from_table(policy)
        self._clocks: dict[str, _TopicClock] = {}
        #: the last ``spikes.window`` - 1 finite values of speed and steering (the evidence of a unit mistake)
        self._recent: dict[str, deque] = {}

    def gap_limit_ns(self, topic: str) -> int | None:
        """The gap limit of ``topic`` now [ns]: ``stamps.gap_periods`` median intervals (of the last
        ``stamps.rate_window``), at least ``stamps.gap_min_s``; None until two intervals are known."""
        c = self._clocks.get(topic)
        if c is None or len(c.intervals) < 2:
            return None
        iv = sorted(c.intervals)
        n = len(iv)
        median = iv[n // 2] if n % 2 else (iv[n // 2 - 1] + iv[n // 2]) / 2
        return max(int(self.policy.gap_periods * median), self.policy.gap_min_ns)

    def check(self, topic: str, t_ns: int, values: Sequence[float]) -> list[LiveFinding]:
        """The findings of one message of ``topic`` applied at ROS time ``t_ns`` with numbers ``values``."""
        out: list[LiveFinding] = []
        t_ns = int(t_ns)
        judged = judge_value(topic, values, self.policy)
        if judged is not None and judged[0] == "implausible_unit":
            judged = self._outlier(topic, float(values[0])) or judged
        if topic in self.policy.spike_floor and len(values) == 1 and math.isfinite(float(values[0])):
            recent = self._recent.setdefault(topic, deque(maxlen=max(self.policy.spike_window - 1, 2)))
            recent.append(float(values[0]))
        if judged is not None:
            kind, level, value, expected = judged
            out.append(LiveFinding(topic, kind, t_ns, level, "excluded", value, expected,
                                   "message rejected, the last value holds" if topic != ROAD_PROFILE else
                                   "road profile rejected: the node keeps the road it had (flat without one)"))
        if topic in STREAM_TOPICS and (judged is None or judged[0] != "non_finite"):
            out.extend(self._stamp(topic, t_ns))
        return out

    def _outlier(self, topic: str, v: float) -> tuple[str, int, str, str] | None:
        """A value beyond the limit that fits the other unit, judged against the topic's earlier messages
        (module docstring): ``spike`` when it is far from what the last two predict (linear extrapolation;
        ``spikes.mad_factor`` robust sd of the earlier second differences, at least ``spikes.floor_*``),
        None (the unit mistake stands) when it is in line with them or too few are known."""
        pol = self.policy
        recent = self._recent.get(topic)
        if recent is None or len(recent) < pol.spike_window - 1 or len(recent) < 3:
            return None
        x = np.asarray(recent, dtype=float)
        with np.errstate(over="ignore", invalid="ignore"):  # earlier messages near the float limit
            pred = 2.0 * x[-1] - x[-2]
            sd = 1.4826 * float(np.median(np.abs(np.diff(x, 2))))
        if not (np.isfinite(pred) and np.isfinite(sd)):
            return None  # nothing to predict from: the size of the value alone decides
        limit = max(pol.mad_factor * sd, pol.spike_floor[topic])
        if abs(v - pred) <= limit:
            return None
        unit = "m/s" if topic == SPEED else "rad"
        return ("spike", WARN, f"{v:.6g} {unit}",
                f"a value near {pred:.6g} {unit} (what the last {len(x)} messages predict, within {limit:.4g} "
                f"{unit}: spikes.mad_factor robust sd, at least spikes.floor_*); one outlier, no unit mistake")

    def _stamp(self, topic: str, t_ns: int) -> list[LiveFinding]:
        c = self._clocks.setdefault(topic, _TopicClock(intervals=deque(maxlen=self.policy.rate_window)))
        last, c.last_ns = c.last_ns, t_ns
        was_open, c.gap_open = c.gap_open, False
        if last is None:
            return []
        dt = t_ns - last
        pol = self.policy
        step = f"{dt / NS:+.6g} s after the previous message"
        if dt < -pol.backward_jump_ns:
            return [LiveFinding(topic, "clock_jump", t_ns, WARN, "kept", step,
                                f"a time not more than {pol.backward_jump_ns / NS:g} s before the previous "
                                f"message (stamps.backward_jump_s)", "time went back (a restart or a looped "
                                "replay); the message is applied at its time", from_ns=last)]
        if dt < 0:
            return [LiveFinding(topic, "stamp_order", t_ns, WARN, "kept", step,
                                "a time not before the previous message's", "the message is applied at its time",
                                from_ns=last)]
        if dt > pol.clock_jump_ns:
            return [LiveFinding(topic, "clock_jump", t_ns, WARN, "kept", step,
                                f"a step of at most {pol.clock_jump_ns / NS:g} s (stamps.clock_jump_s)",
                                "time jumped forward; the last value was held over it", from_ns=last)]
        limit = self.gap_limit_ns(topic)
        if dt > 0:
            c.intervals.append(dt)
        if limit is not None and dt > limit:
            return [LiveFinding(topic, "gap", t_ns, WARN, "kept", f"no message for {dt / NS:.6g} s",
                                f"a message at least every {limit / NS:.6g} s (stamps.gap_periods median "
                                f"intervals, at least stamps.gap_min_s)",
                                "gap ended; the last value was held over it"
                                + (" (reported while open)" if was_open else ""), from_ns=last)]
        return []

    def check_gaps(self, now_ns: int) -> list[LiveFinding]:
        """``gap`` findings of the input topics with no message for longer than their gap limit at ROS
        time ``now_ns`` (once per gap, while it lasts: the node holds a stale value)."""
        out: list[LiveFinding] = []
        for topic, c in self._clocks.items():
            if c.gap_open or c.last_ns is None:
                continue
            limit = self.gap_limit_ns(topic)
            if limit is None or now_ns - c.last_ns <= limit:
                continue
            c.gap_open = True
            out.append(LiveFinding(topic, "gap", int(now_ns), WARN, "kept",
                                   f"no message for {(now_ns - c.last_ns) / NS:.6g} s",
                                   f"a message at least every {limit / NS:.6g} s (stamps.gap_periods median "
                                   f"intervals, at least stamps.gap_min_s)",
                                   "gap open: the held value is stale", from_ns=c.last_ns))
        return out

    def open_gaps(self) -> list[str]:
        """The topics in a gap reported by :meth:`check_gaps` that no message has ended yet."""
        return sorted(t for t, c in self._clocks.items() if c.gap_open)


@dataclass
class _Entry:
    last: LiveFinding
    count: int = 0
    reported: int = 0  # count at the last mark_reported()


class FindingBoard:
    """The live findings per (topic, kind) for ``/diagnostics``: the latest one, how many in all and how
    many since the last report."""

    def __init__(self) -> None:
        self._entries: dict[tuple[str, str], _Entry] = {}
        self.total = 0  # findings in all (a plain counter: readable without the node's lock)

    def add(self, findings: Iterable[LiveFinding]) -> None:
        for f in findings:
            e = self._entries.get((f.topic, f.kind))
            if e is None:
                e = self._entries[(f.topic, f.kind)] = _Entry(f)
            e.last = f
            e.count += 1
            self.total += 1

    def entries(self) -> list[tuple[LiveFinding, int, int]]:
        """``(latest finding, count, new since the last report)`` per (topic, kind), sorted."""
        return [(e.last, e.count, e.count - e.reported) for _, e in sorted(self._entries.items())]

    def mark_reported(self) -> None:
        for e in self._entries.values():
            e.reported = e.count


__all__ = ["LiveFinding", "LivePolicy", "LiveIntegrity", "FindingBoard", "judge_value", "STREAM_TOPICS",
           "WARN", "ERROR"]
