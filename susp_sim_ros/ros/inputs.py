"""The node's input half: the subscription callbacks and when an input takes effect.

Wall time: an input is stamped with its arrival time and applied by the next tick, which steps to that
instant first (the callback itself does no stepping or publishing, so it never delays a tick). Sim time:
``/clock`` and the inputs go through the reorder queue (:mod:`.sim_time`) and are processed in publish
order; each released ``/clock`` steps the core that far, each released input steps to the current time
and is then applied.

:class:`InputCallbacks` is mixed into :class:`~.node.SuspSimNode` and uses its ``core``, ``lock``,
``sim_time``, ``orderer``, ``semiactive``, ``tick``, ``now_ns``, ``_start_core``, ``_publish_samples``,
``_record`` and ``_check_failure``; :meth:`InputCallbacks._subscribe_inputs` creates the subscriptions.
"""
from __future__ import annotations

import time

from rclpy.clock import Clock as RosClock, ClockType
from rosgraph_msgs.msg import Clock
from std_msgs.msg import Float64, Float64MultiArray

from ..io import messages as M
from ..sim_core import DAMPER_COMMAND
from .conversion import clock_time_ns, input_cdr, layout_dims
from .qos import CLOCK_QOS, INPUT_QOS, LATCHED_QOS
from .rclpy_workarounds import guard_time_source, take_pending
from .sim_time import CLOCK, INPUT, SimTimeOrderer

DRAIN_PERIOD_S = 0.002  # sim time: how often the reorder queue is checked for due events (steady clock) [s]


class InputCallbacks:
    """Subscription callbacks ``on_*(message, info)``: ``info`` is rclpy's message info (its
    ``source_timestamp`` orders sim-time events) or None; tests may call them directly. (``info`` has no
    default: rclpy passes it only to callbacks that cannot be called with the message alone.)"""

    def _subscribe_inputs(self, reorder_window_s: float) -> None:
        """The input state and subscriptions; in sim time also ``/clock`` and the timer that drains the
        reorder queue (``reorder_window_s``: :class:`~.sim_time.SimTimeOrderer`'s window [s])."""
        self._sim_now = 0
        self.inputs_received = 0  # applied
        self.inputs_taken = 0     # taken from DDS (in sim time possibly waiting for the next /clock)
        self._wall_inputs: list = []  # wall time: (arrival ns, input) for the next tick
        self.orderer = SimTimeOrderer(int(round(reorder_window_s * 1e9)))
        self._pulling = False  # taking queued messages straight from DDS (see _pull_pending)
        self._sim_clock_sub = None
        if self.sim_time:
            guard_time_source(self)
            # Our own /clock subscription, reliable and deep (rclpy's time source keeps only the latest
            # /clock, so a busy node would see the clock skip ahead of queued inputs): every clock value
            # is seen, in order, and each one steps the core exactly that far.
            self._sim_clock_sub = self.create_subscription(Clock, "/clock", self.on_clock, CLOCK_QOS)
            self.create_timer(DRAIN_PERIOD_S, self._drain, clock=RosClock(clock_type=ClockType.STEADY_TIME))
        self._input_subs = [
            self.create_subscription(Float64, "/vehicle/speed", self.on_speed, INPUT_QOS),
            self.create_subscription(Float64, "/vehicle/steering_wheel_angle", self.on_steering, INPUT_QOS),
            self.create_subscription(Float64MultiArray, "/road/profile", self.on_profile, LATCHED_QOS),
            self.create_subscription(Float64MultiArray, "/road/wheel_heights", self.on_wheel_heights, INPUT_QOS),
            self.create_subscription(Float64MultiArray, DAMPER_COMMAND, self.on_damper_command, INPUT_QOS)]

    def _input(self, topic: str, msgtype: str, msg, apply, info=None, latched: bool = False) -> None:
        """An input message. Wall time: stamped with its arrival time and handed to the tick, which steps
        to that instant and applies it (the callback does no stepping or publishing, so it never delays a
        tick). Sim time: queued with ``/clock`` in the reorder queue."""
        self.inputs_taken += 1
        payload = (topic, msgtype, msg, apply, latched)
        if self.sim_time:
            self._push(info, INPUT, payload)
        else:
            with self.lock:
                self._wall_inputs.append((self.get_clock().now().nanoseconds, payload))

    def _push(self, info, kind: int, payload) -> None:
        with self.lock:
            self.orderer.push(int(info["source_timestamp"]) if info else 0, kind, payload)
        if not self._pulling:
            self._drain()

    def _pull_pending(self) -> None:
        """Take every message DDS already holds for the input and ``/clock`` subscriptions into the queue."""
        self._pulling = True
        try:
            take_pending((*self._input_subs, self._sim_clock_sub))
        finally:
            self._pulling = False

    def _drain(self) -> None:
        now = time.time_ns()
        with self.lock:
            self.orderer.drain(now, self._clock_due, lambda payload: self._apply_input(*payload),
                               self._pull_pending)

    def _clock_due(self, t_ns: int) -> None:
        self._sim_now = t_ns
        if self.core.started:  # sim time starts with the first input (as lockstep)
            self.tick()
            if self.core.t_ns is not None:  # a stale /clock leaves the time where it was
                self._sim_now = self.core.t_ns

    def _apply_input(self, topic: str, msgtype: str, msg, apply, latched: bool, t: int | None = None) -> None:
        """Step to the input's time ``t`` (default: now), publishing the ticks passed, then apply it."""
        with self.lock:
            t = self.now_ns() if t is None else t
            if t > 0:
                if not self.core.started:
                    self._start_core(t)
                else:
                    self._publish_samples(self.core.advance_to(t, allow_restart=self.sim_time))
                    t = max(t, self.core.t_ns)
            try:
                apply(t)  # a rejection is counted and logged (rate-limited) by the core's on_reject
            except Exception as exc:  # a bug must not take the node down; counted, logged, tested for
                self.handler_errors += 1
                self.core.reject(topic, "handler_error", f"{topic}: internal error handling a message "
                                 f"({type(exc).__name__}: {exc}); message dropped")
            self.inputs_received += 1
            self._record(topic, msgtype, max(t, 0), input_cdr(msg), latched)
            self._check_failure()

    def on_speed(self, msg: Float64, info) -> None:
        self._input("/vehicle/speed", M.FLOAT64, msg, lambda t: self.core.set_speed(t, msg.data), info)

    def on_steering(self, msg: Float64, info) -> None:
        self._input("/vehicle/steering_wheel_angle", M.FLOAT64, msg,
                    lambda t: self.core.set_steering(t, msg.data), info)

    def on_profile(self, msg: Float64MultiArray, info) -> None:
        dims, off = layout_dims(msg), msg.layout.data_offset
        self._input("/road/profile", M.FLOAT64_ARRAY, msg,
                    lambda t: self.core.set_road_profile(t, msg.data, dims, off), info, latched=True)

    def on_wheel_heights(self, msg: Float64MultiArray, info) -> None:
        dims, off = layout_dims(msg), msg.layout.data_offset
        self._input("/road/wheel_heights", M.FLOAT64_ARRAY, msg,
                    lambda t: self.core.set_wheel_heights(t, msg.data, dims, off), info)

    def on_damper_command(self, msg: Float64MultiArray, info) -> None:
        dims, off = layout_dims(msg), msg.layout.data_offset
        src = int(info["source_timestamp"]) if info else 0

        def apply(t):
            reason = self.core.set_damper_command(t, msg.data, dims, off)
            if reason is None:
                self.semiactive.command_applied(t, src)
            return reason
        self._input(DAMPER_COMMAND, M.FLOAT64_ARRAY, msg, apply, info)

    def on_clock(self, msg: Clock, info) -> None:
        t_ns = clock_time_ns(msg)
        if not t_ns:  # invalid, or 0 (no time yet)
            with self.lock:
                self.core.reject("/clock", "clock_invalid", f"/clock: rejected invalid time sec={msg.clock.sec} "
                                 f"nanosec={msg.clock.nanosec} (need sec >= 0, 0 <= nanosec < 1e9, not 0)")
            return
        self._push(info, CLOCK, t_ns)
