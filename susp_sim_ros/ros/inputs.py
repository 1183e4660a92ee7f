"""The node's input half: the subscription callbacks and when an input takes effect.

Wall time: an input is stamped with its arrival time and applied by the next tick, which steps to that
instant first (the callback itself does no stepping or publishing, so it never delays a tick). Sim time:
``/clock`` and the inputs go through the reorder queue (:mod:`.sim_time`) and are processed in publish
order; each released ``/clock`` steps the core that far, each released input steps to the current time
and is then applied.

:class:`InputHandler` is owned by :class:`~.node.SuspSimNode` (its ``inputs``): it creates the input
subscriptions on the node and is given the core, the node's lock and the few node operations it needs
(tick, step to a time, record, check for a divergence, note an applied damper command) and, optionally, a
``judge(topic, t_ns, numbers)`` called with each applied message's numbers (:func:`message_numbers`) and
the ROS time it took effect: the node's live input-integrity check (:mod:`susp_sim_ros.io.live_integrity`).
"""
from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from typing import Any

from rclpy.clock import Clock as RosClock, ClockType
from rclpy.node import Node
from rclpy.qos import QoSProfile
from rclpy.subscription import Subscription
from rosgraph_msgs.msg import Clock
from std_msgs.msg import Float64, Float64MultiArray

from ..io import messages as M
from ..runtime.sim_core import DAMPER_COMMAND, SimCore
from .conversion import clock_time_ns, input_cdr, layout_dims
from .qos import CLOCK_QOS, INPUT_QOS, LATCHED_QOS
from .rclpy_workarounds import guard_time_source, take_pending
from .sim_time import CLOCK, INPUT, SimTimeOrderer

DRAIN_PERIOD_S = 0.002  # sim time: how often the reorder queue is checked for due events (steady clock) [s]

#: an input waiting to be applied: (topic, message type, message, apply(t_ns) -> rejection or None, latched)
Payload = tuple[str, str, Any, Callable[[int], Any], bool]
#: writes a message to the recording: (topic, message type, log time [ns], CDR data, latched)
RecordFn = Callable[[str, str, int, Any, bool], None]
#: judges an applied input message: (topic, ROS time [ns] it took effect, its numbers)
JudgeFn = Callable[[str, int, Any], None]


def message_numbers(topic: str, msgtype: str, msg: Any) -> Any:
    """The numbers of an input message the integrity check judges: ``[data]`` of a ``Float64``; the data
    after ``data_offset`` of a ``Float64MultiArray``, for ``/road/profile`` only when its layout is the
    interface's [channel 3, sample N] with 3 N values, for the four-wheel arrays only when the layout (if
    any) describes 4 values (else nothing: the core rejects the layout, which is no integrity kind)."""
    if msgtype == M.FLOAT64:
        return [msg.data]
    off = int(msg.layout.data_offset)
    data = msg.data
    dims = layout_dims(msg)
    if topic == "/road/profile":
        if len(dims) != 2 or int(dims[0][1]) != 3 or len(data) - off != 3 * int(dims[1][1]):
            return []
    elif dims and math.prod(int(d[1]) for d in dims) != 4:  # [FL, FR, RL, RR] or nothing
        return []
    return data[off:]


def _subscribe(node: Node, msg_type: Any, topic: str, callback: Callable[[Any, Any], None],
               qos: QoSProfile) -> Subscription:
    """``node.create_subscription`` for a callback taking ``(message, message info)``: rclpy (Jazzy)
    passes the info to such callbacks (it inspects their signature) but annotates ``callback`` as taking
    the message alone."""
    return node.create_subscription(msg_type, topic, callback, qos)  # type: ignore[arg-type]  # see above


class InputHandler:
    """The input subscriptions of ``node`` and their callbacks ``on_*(message, info)``: ``info`` is
    rclpy's message info (its ``source_timestamp`` orders sim-time events) or None; tests may call them
    directly. (``info`` has no default: rclpy passes it only to callbacks that cannot be called with the
    message alone.)

    ``core`` and ``lock``: the node's simulation core and the lock guarding it; ``sim_time``: ROS time
    from ``/clock``; ``reorder_window_s``: :class:`~.sim_time.SimTimeOrderer`'s window [s]. What the
    handler asks of the node: ``tick()`` (step to now and publish), ``step_to(t_ns)`` (start the core at
    ``t_ns`` or step it there, publishing), ``record`` (:data:`RecordFn`), ``check_failure()`` (after
    stepping) and ``command_applied(t_ns, source_ns)`` (a damper command took effect)."""

    def __init__(self, node: Node, core: SimCore, lock: threading.RLock, *, sim_time: bool,
                 reorder_window_s: float, tick: Callable[[], object], step_to: Callable[[int], None],
                 record: RecordFn, check_failure: Callable[[], None],
                 command_applied: Callable[[int, int], None], refuse_shared: bool = False,
                 judge: JudgeFn | None = None) -> None:
        self.node, self.core, self.lock, self.sim_time = node, core, lock, sim_time
        self._judge = judge
        self._tick, self._step_to, self._record = tick, step_to, record
        self._check_failure, self._command_applied = check_failure, command_applied
        self._sim_now = 0
        self.refuse_shared = refuse_shared
        self.publishers: dict[str, int] = {}  # input topic -> its publishers at the last check_publishers()
        self.inputs_received = 0  # applied
        self.inputs_taken = 0     # taken from DDS (in sim time possibly waiting for the next /clock)
        self.handler_errors = 0   # exceptions raised while applying an input (the message is dropped)
        self._wall_inputs: list[tuple[int, Payload]] = []  # wall time: (arrival ns, input) for the next tick
        self.orderer = SimTimeOrderer(int(round(reorder_window_s * 1e9)))
        self._pulling = False  # taking queued messages straight from DDS (see _pull_pending)
        self._sim_clock_sub: Subscription | None = None
        if sim_time:
            guard_time_source(node)
            # Our own /clock subscription, reliable and deep (rclpy's time source keeps only the latest
            # /clock, so a busy node would see the clock skip ahead of queued inputs): every clock value
            # is seen, in order, and each one steps the core exactly that far.
            self._sim_clock_sub = _subscribe(node, Clock, "/clock", self.on_clock, CLOCK_QOS)
            node.create_timer(DRAIN_PERIOD_S, self._drain, clock=RosClock(clock_type=ClockType.STEADY_TIME))
        self._input_subs = [
            _subscribe(node, Float64, "/vehicle/speed", self.on_speed, INPUT_QOS),
            _subscribe(node, Float64, "/vehicle/steering_wheel_angle", self.on_steering, INPUT_QOS),
            _subscribe(node, Float64MultiArray, "/road/profile", self.on_profile, LATCHED_QOS),
            _subscribe(node, Float64MultiArray, "/road/wheel_heights", self.on_wheel_heights, INPUT_QOS),
            _subscribe(node, Float64MultiArray, DAMPER_COMMAND, self.on_damper_command, INPUT_QOS)]

    def check_publishers(self) -> list[str]:
        """Count the publishers of every input topic (DDS discovery); returns the topics more than one
        publisher feeds. Two publishers on one input (another process on the same ROS domain, a replay
        beside a driver) make the node follow both: with ``refuse_shared`` their messages are refused
        until one is gone."""
        counts = {sub.topic_name: self.node.count_publishers(sub.topic_name) for sub in self._input_subs}
        with self.lock:
            self.publishers = counts
        return sorted(t for t, n in counts.items() if n > 1)

    def now_ns(self) -> int:
        """ROS time [ns]: the last /clock value processed in sim time, else the node's (wall) clock."""
        if self.sim_time:
            return self._sim_now
        return self.node.get_clock().now().nanoseconds

    def apply_arrived(self) -> None:
        """Wall time: apply the inputs that arrived since the last call, each at its arrival instant
        (the tick calls this before stepping to now)."""
        with self.lock:
            if self._wall_inputs:
                pending, self._wall_inputs = self._wall_inputs, []
                for t_in, payload in pending:
                    self._apply_input(payload, t_in)

    def _input(self, topic: str, msgtype: str, msg: Any, apply: Callable[[int], Any], info: Any = None,
               latched: bool = False) -> None:
        """An input message. Wall time: stamped with its arrival time and handed to the tick, which steps
        to that instant and applies it (the callback does no stepping or publishing, so it never delays a
        tick). Sim time: queued with ``/clock`` in the reorder queue."""
        self.inputs_taken += 1
        if self.refuse_shared and self.publishers.get(topic, 0) > 1:
            with self.lock:
                self.core.reject(topic, "shared_input", f"{topic}: {self.publishers[topic]} publishers feed this "
                                 "input; message refused (parameter refuse_shared_inputs)")
            return
        payload: Payload = (topic, msgtype, msg, apply, latched)
        if self.sim_time:
            self._push(info, INPUT, payload)
        else:
            with self.lock:
                self._wall_inputs.append((self.node.get_clock().now().nanoseconds, payload))

    def _push(self, info: Any, kind: int, payload: Any) -> None:
        with self.lock:
            self.orderer.push(int(info["source_timestamp"]) if info else 0, kind, payload)
        if not self._pulling:
            self._drain()

    def _pull_pending(self) -> None:
        """Take every message DDS already holds for the input and ``/clock`` subscriptions into the queue."""
        self._pulling = True
        try:
            subs = list(self._input_subs)
            if self._sim_clock_sub is not None:  # always, in sim time (the only time this is called)
                subs.append(self._sim_clock_sub)
            take_pending(subs)
        finally:
            self._pulling = False

    def _drain(self) -> None:
        now = time.time_ns()
        with self.lock:
            self.orderer.drain(now, self._clock_due, self._apply_input, self._pull_pending)

    def _clock_due(self, t_ns: int) -> None:
        self._sim_now = t_ns
        if self.core.started:  # sim time starts with the first input (as lockstep)
            self._tick()
            if self.core.t_ns is not None:  # a stale /clock leaves the time where it was
                self._sim_now = self.core.t_ns

    def _apply_input(self, payload: Payload, t: int | None = None) -> None:
        """Step to the input's time ``t`` (default: now), publishing the ticks passed, then apply it."""
        topic, msgtype, msg, apply, latched = payload
        with self.lock:
            t = self.now_ns() if t is None else t
            if t > 0:
                self._step_to(t)  # starts the core at t, or steps it there (a stale t: it stays ahead)
                t = max(t, self.core.t_ns or 0)
            try:
                apply(t)  # a rejection is counted and logged (rate-limited) by the core's on_reject
                if self._judge is not None:  # the policy's findings (reported on /diagnostics)
                    self._judge(topic, t, message_numbers(topic, msgtype, msg))
            except Exception as exc:  # a bug must not take the node down; counted, logged, tested for
                self.handler_errors += 1
                self.core.reject(topic, "handler_error", f"{topic}: internal error handling a message "
                                 f"({type(exc).__name__}: {exc}); message dropped")
            self.inputs_received += 1
            self._record(topic, msgtype, max(t, 0), input_cdr(msg), latched)
            self._check_failure()

    def on_speed(self, msg: Float64, info: Any) -> None:
        self._input("/vehicle/speed", M.FLOAT64, msg, lambda t: self.core.set_speed(t, msg.data), info)

    def on_steering(self, msg: Float64, info: Any) -> None:
        self._input("/vehicle/steering_wheel_angle", M.FLOAT64, msg,
                    lambda t: self.core.set_steering(t, msg.data), info)

    def on_profile(self, msg: Float64MultiArray, info: Any) -> None:
        dims, off = layout_dims(msg), msg.layout.data_offset
        self._input("/road/profile", M.FLOAT64_ARRAY, msg,
                    lambda t: self.core.set_road_profile(t, msg.data, dims, off), info, latched=True)

    def on_wheel_heights(self, msg: Float64MultiArray, info: Any) -> None:
        dims, off = layout_dims(msg), msg.layout.data_offset
        self._input("/road/wheel_heights", M.FLOAT64_ARRAY, msg,
                    lambda t: self.core.set_wheel_heights(t, msg.data, dims, off), info)

    def on_damper_command(self, msg: Float64MultiArray, info: Any) -> None:
        dims, off = layout_dims(msg), msg.layout.data_offset
        src = int(info["source_timestamp"]) if info else 0

        def apply(t: int) -> str | None:
            reason = self.core.set_damper_command(t, msg.data, dims, off)
            if reason is None:
                self._command_applied(t, src)
            return reason
        self._input(DAMPER_COMMAND, M.FLOAT64_ARRAY, msg, apply, info)

    def on_clock(self, msg: Clock, info: Any) -> None:
        t_ns = clock_time_ns(msg)
        if not t_ns:  # invalid, or 0 (no time yet)
            with self.lock:
                self.core.reject("/clock", "clock_invalid", f"/clock: rejected invalid time sec={msg.clock.sec} "
                                 f"nanosec={msg.clock.nanosec} (need sec >= 0, 0 <= nanosec < 1e9, not 0)")
            return
        self._push(info, CLOCK, t_ns)
