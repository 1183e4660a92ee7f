"""``susp_sim_node``: the ROS 2 node, a thin adapter around :class:`~susp_sim_ros.sim_core.SimCore`.

Subscribes to the test-drive input topics (interface.md), publishes ``/sim/imu/data``, ``/sim/odom``,
``/sim/suspension`` and ``/diagnostics``, optionally records everything to an MCAP file.

Timing:

- wall time (default): a dedicated thread wakes at each publish tick (absolute deadlines, no drift),
  steps the core to "now" and publishes; publish-period jitter, lateness and deadline misses (a tick
  published more than one period late) are measured and reported on ``/diagnostics``;
- sim time (``use_sim_time:=true``, a replay with ``/clock``): every ``/clock`` message steps the core
  exactly as far as the clock moved and publishes the ticks passed; ``/clock`` and the inputs are put
  back into publish order (source timestamps, ``sim_reorder_window_s``), so replays at any rate give
  the same outputs.

Every input first steps the core to the current time, then replaces the held value, so inputs take
effect at the instant they arrive. The callbacks only take inputs, step the shared core and publish.

Bad input never stops the node: a rejected message (non-finite, out of range, mis-shaped layout,
non-increasing profile, invalid or stale ``/clock``) is not integrated, counted per cause on
``/diagnostics`` (``rejected_<cause>``, ``rejected_by_topic``) and logged once per topic and cause, then
at most every ``REJECTION_LOG_INTERVAL_S`` with the number not logged in between. Divergence guard: if the
simulation leaves the physical envelope (:mod:`~susp_sim_ros.sim_core`), nothing more is published on
``/sim/...``; the node logs an error, publishes ``/diagnostics`` with the model status at ERROR level,
finalises the recording and (``on_divergence: exit``, the default) exits with code 1; with
``on_divergence: hold`` it stays up reporting ERROR.

Parameters (all with defaults; ``--ros-args --params-file config/susp_sim_node.yaml``):
``vehicle``, ``friction_variant``, ``damper_oil_level`` [FL, FR, RL, RR], ``step_s`` [s],
``publish_rate_hz`` [Hz], ``record_path`` (empty: no recording), ``record_overwrite``,
``record_flush_interval_s`` [s],
``input_timeout_s`` [s], ``diagnostics_rate_hz`` [Hz], ``max_time_jump_s`` [s], ``on_divergence``
(``exit``/``hold``). ``damper_oil_level``, ``friction_variant`` and
``vehicle`` may be changed while running; the others are fixed at start.
"""
from __future__ import annotations

import gc
import heapq
from collections import deque
import math
import os
import sys
import threading
import time

import numpy as np
import rclpy
from rcl_interfaces.msg import ParameterDescriptor, SetParametersResult
from rclpy.clock import Clock as RosClock, ClockType
from rclpy.exceptions import InvalidHandle
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.serialization import serialize_message

from diagnostic_msgs.msg import DiagnosticArray
from rosgraph_msgs.msg import Clock
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Imu
from std_msgs.msg import Float64, Float64MultiArray

from .errors import SuspInputError
from .io import messages as M
from .io.recorder import McapRecorder
from .analysis.host_stalls import format_miss_log
from .lockstep import simulated_metadata
from .model.vehicle import Model, check_oil
from .ride_diagnostics import SemiActiveDiagnostics
from .sim_core import DAMPER_COMMAND, DIAGNOSTICS, SIM_IMU, SIM_ODOM, SIM_SUSPENSION, RateLimitedLog, SimCore

NODE_NAME = "susp_sim_node"
INPUT_QOS = QoSProfile(depth=100, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.RELIABLE)
LATCHED_QOS = QoSProfile(depth=1, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
CLOCK_QOS = QoSProfile(depth=1000, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.RELIABLE)
OUTPUT_QOS = QoSProfile(depth=50, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.RELIABLE)

DEFAULTS = {
    "vehicle": ("passat_b8_like", "vehicle parameter set name (config/vehicles) or YAML path"),
    "friction_variant": ("full", "friction variant: full, no_horizontal, no_velocity, dahl_only or a YAML path"),
    "damper_oil_level": ([1.0, 1.0, 1.0, 1.0], "damper oil level FL, FR, RL, RR in [0, 1] (1 = intact)"),
    "step_s": (0.001, "fixed internal integration step [s]"),
    "publish_rate_hz": (100.0, "publish rate of /sim topics [Hz]"),
    "record_path": ("", "MCAP file to record to (empty: no recording)"),
    "record_overwrite": (False, "overwrite an existing record_path"),
    "record_flush_interval_s": (1.0, "the recording's open chunk is put on disk at least this often; a killed "
                                     "node loses at most this much [s]"),
    "input_timeout_s": (0.5, "an input not refreshed for this long is reported stale [s]"),
    "diagnostics_rate_hz": (1.0, "publish rate of /diagnostics [Hz]"),
    "sim_reorder_window_s": (0.02, "sim time: /clock and inputs are put in publish order and processed "
                                    "this long after they were published (wall time) [s]"),
    "realtime_priority": (10, "SCHED_FIFO priority of the wall-time tick thread (0: normal scheduling; "
                              "falls back to normal scheduling when not permitted)"),
    "max_time_jump_s": (10.0, "a jump of ROS time forward by more than this is not stepped through; the "
                              "simulation continues from the new time [s]"),
    "on_divergence": ("exit", "when the divergence guard stops the simulation: exit (code 1, after an ERROR "
                              "diagnostic and finalising the recording) or hold (stay up reporting ERROR)"),
}
REJECTION_LOG_INTERVAL_S = 10.0
SWITCH_INTERVAL_S = 0.0001
RUNTIME = ("damper_oil_level", "friction_variant", "vehicle")


def fill(msg, d: dict):
    """Copy a plain-dict message (io.messages builders) into an rclpy message object."""
    for k, v in d.items():
        if isinstance(v, dict):
            fill(getattr(msg, k), v)
        elif k == "dim":
            msg.dim = [_dim(x) for x in v]
        else:
            setattr(msg, k, v)
    return msg


def _dim(x: dict):
    from std_msgs.msg import MultiArrayDimension
    return MultiArrayDimension(label=x["label"], size=int(x["size"]), stride=int(x["stride"]))


def warm_up(model: Model) -> None:
    """Run the compiled kernel once on a throwaway stepper (JIT compile before real time starts)."""
    from .model.vehicle import Stepper
    Stepper(model, dt=0.001).advance(2, 1.0, 0.0)


#: Log-time window [ns] within which the recording thread puts messages back into log-time order. They
#: come from two threads (tick thread, executor); /diagnostics is logged no earlier than the samples
#: recorded before it, and this window catches any other race (a preempted thread). A finalised file is
#: indexed, but a killed one is read in file order, and rosbags refuses one whose log times go backwards
#: (seen once in 80 killed recordings before both measures).
RECORD_REORDER_NS = 50_000_000


class RecordingQueue:
    """The node's recording, off the real-time path: the tick thread and the callbacks only enqueue
    ``(topic, type, time, CDR bytes or a function making them)``; a writer thread encodes input messages,
    writes (mcap, chunk compression, the kill-safe commits of :class:`McapRecorder`) and flushes. It
    holds each message until one at least :data:`RECORD_REORDER_NS` later (log time) is queued and writes
    in log-time order, so the file is sorted even where the producing threads raced (a kill loses at most
    that window more than the recorder's flush interval). A full queue (``max_items``, a disk that cannot
    keep up) drops messages, counted in ``dropped``; a write error (disk full) stops the recording with
    one error log (``error``) instead of the node."""

    def __init__(self, recorder: McapRecorder, log_error, max_items: int = 200_000):
        import queue
        self.recorder, self._log_error = recorder, log_error
        self._q: "queue.Queue" = queue.Queue(maxsize=max_items)
        self._full = queue.Full
        self.dropped = 0
        self.error = ""
        self.closed = False
        self._thread = threading.Thread(target=self._run, name="susp_sim_record", daemon=True)
        self._thread.start()

    def write(self, topic: str, msgtype: str, t_ns: int, data, latched: bool = False) -> None:
        if self.closed or self.error:
            return
        try:
            self._q.put_nowait((topic, msgtype, t_ns, data, latched))
        except self._full:
            self.dropped += 1

    def flush_if_due(self) -> None:
        if not self.closed:
            try:
                self._q.put_nowait(None)
            except self._full:
                pass

    def _run(self) -> None:
        held: list = []  # (log time, arrival number, item) heap
        arrived, newest = 0, None
        while True:
            item = self._q.get()
            if item is StopIteration:
                if not self.error:
                    self._write_held(held, None)
                return
            if self.error:
                continue
            if item is None:
                self._write_held([], None, flush=True)
                continue
            arrived += 1
            heapq.heappush(held, (item[2], arrived, item))
            newest = item[2] if newest is None else max(newest, item[2])
            self._write_held(held, newest - RECORD_REORDER_NS)

    def _write_held(self, held: list, upto: int | None, flush: bool = False) -> None:
        """Write the held messages with log time <= ``upto`` (all: ``None``), oldest first; then flush
        if due (``flush``). A write error stops the recording (disk full, file removed), not the node."""
        try:
            while held and (upto is None or held[0][0] <= upto):
                topic, msgtype, t_ns, data, latched = heapq.heappop(held)[2]
                self.recorder.write(topic, msgtype, t_ns, data() if callable(data) else data, latched=latched)
            if flush:
                self.recorder.flush_if_due()
        except Exception as exc:
            self.error = f"{type(exc).__name__}: {exc}"
            self._log_error(f"recording stopped: {self.error}")

    def close(self) -> None:
        """Write everything queued, then finalise the file (idempotent)."""
        if self.closed:
            return
        self.closed = True
        self._q.put(StopIteration)
        if self._thread is not threading.current_thread():
            self._thread.join()
        try:
            self.recorder.close()
        except Exception as exc:
            self.error = self.error or f"{type(exc).__name__}: {exc}"
            self._log_error(f"recording not finalised: {exc}")


def _input_cdr(msg):
    """CDR bytes of a received input message, made in the recording thread (arrays by the fast encoder)."""
    if isinstance(msg, Float64MultiArray):
        return lambda: M.encode_float64_multiarray([(d.label, d.size, d.stride) for d in msg.layout.dim],
                                                   msg.layout.data_offset, msg.data)
    return lambda: serialize_message(msg)


MISS_LOG_KEEP = 100  # recent deadline misses listed on /diagnostics (a 1 Hz reader loses none below 100/s)


class TimingStats:
    """Publish timing in wall-time mode: period deviation (jitter), lateness, deadline misses.

    The last :data:`MISS_LOG_KEEP` misses (deadline and lateness [ns], ``time.time_ns`` clock) are listed
    on ``/diagnostics`` as ``deadline_miss_log`` so a benchmark can set them beside host stalls
    (:mod:`~susp_sim_ros.analysis.host_stalls`).

    Ring buffers in numpy arrays: recording is one store, the summary never converts Python lists
    (a long C call would hold the GIL against the tick thread)."""

    def __init__(self, period_ns: int, keep: int = 360_000):
        self.period_ns = period_ns
        self._jit = np.zeros(keep, dtype=np.int64)
        self._late = np.zeros(keep, dtype=np.int64)
        self._jit.fill(0)  # touch every page now: memory is flat from the start, not growing for an hour
        self._late.fill(0)
        self._n_jit = 0
        self.deadline_misses = 0
        self.miss_log: deque[tuple[int, int]] = deque(maxlen=MISS_LOG_KEEP)  # (tick_ns, lateness_ns)
        self.ticks = 0
        self._last_pub: int | None = None

    def record(self, tick_ns: int, published_ns: int) -> None:
        keep = self._late.size
        late = published_ns - tick_ns
        self._late[self.ticks % keep] = late
        self.ticks += 1
        if late > self.period_ns:
            self.deadline_misses += 1
            self.miss_log.append((tick_ns, late))
        if self._last_pub is not None:
            self._jit[self._n_jit % keep] = abs(published_ns - self._last_pub - self.period_ns)
            self._n_jit += 1
        self._last_pub = published_ns

    def summary(self) -> dict[str, float]:
        j = self._jit[:min(self._n_jit, self._jit.size)] * 1e-6
        lt = self._late[:min(self.ticks, self._late.size)] * 1e-6
        q = lambda a, p: float(np.percentile(a, p)) if a.size else 0.0
        return {"jitter_p50_ms": q(j, 50), "jitter_p99_ms": q(j, 99), "jitter_max_ms": float(j.max()) if j.size else 0.0,
                "lateness_p50_ms": q(lt, 50), "lateness_p99_ms": q(lt, 99),
                "deadline_misses": self.deadline_misses, "ticks": self.ticks,
                "deadline_miss_log": format_miss_log(self.miss_log)}


def raise_priority(priority: int) -> str:
    """SCHED_FIFO ``priority`` for every thread of this process so far (executor, DDS receive threads),
    so other processes cannot preempt a thread that holds the GIL the tick thread needs. Returns a
    note if not permitted (then normal scheduling is kept)."""
    if priority <= 0:
        return "real-time scheduling off (realtime_priority 0)"
    try:
        tids = [int(t) for t in os.listdir("/proc/self/task")]
        for tid in tids:
            os.sched_setscheduler(tid, os.SCHED_FIFO, os.sched_param(priority))
    except (OSError, AttributeError, ValueError) as exc:
        return f"no real-time scheduling ({exc}); using normal priority"
    return ""


class SuspSimNode(Node):
    """The simulation node (see the module docstring). ``start_thread=False`` leaves wall-time
    stepping to the caller (:meth:`tick`), for deterministic in-process tests."""

    def __init__(self, *, start_thread: bool = True, **kwargs):
        super().__init__(NODE_NAME, **kwargs)
        for name, (default, text) in DEFAULTS.items():
            if not self.has_parameter(name):
                self.declare_parameter(name, default, ParameterDescriptor(description=text))
        p = {name: self.get_parameter(name).value for name in DEFAULTS}
        self.sim_time = bool(self.get_parameter("use_sim_time").value)
        oil = check_oil(p["damper_oil_level"], "parameter damper_oil_level")
        self._vehicle, self._variant = str(p["vehicle"]), str(p["friction_variant"])
        model = Model(self._vehicle, self._variant)
        self.on_divergence = str(p["on_divergence"])
        if self.on_divergence not in ("exit", "hold"):
            raise SuspInputError(f"parameter on_divergence: expected exit or hold, got {self.on_divergence!r}")
        self.core = SimCore(model, step_s=float(p["step_s"]), publish_rate_hz=float(p["publish_rate_hz"]),
                            oil=oil, input_timeout_s=float(p["input_timeout_s"]),
                            max_time_jump_s=float(p["max_time_jump_s"]))
        self.lock = threading.RLock()
        self.failure = ""  # the last divergence (set when the divergence guard stopped the simulation)
        self.divergences = 0
        self._failure_key: tuple | None = None
        self.handler_errors = 0
        self.tick_errors = 0
        self.rejection_log = RateLimitedLog(lambda text: self.get_logger().warning(text),
                                            REJECTION_LOG_INTERVAL_S)
        self.core.on_reject = self.rejection_log  # every rejection, once per cause and interval
        self._sim_now = 0
        self.inputs_received = 0  # applied
        self.inputs_taken = 0     # taken from DDS (in sim time possibly waiting for the next /clock)
        self._wall_inputs: list = []  # wall time: (arrival ns, input) for the next tick
        self._events: list = []   # sim time: (source timestamp, seq, kind, payload) heap
        self._seq = 0
        self._max_clock_src = 0
        self._pulling = False  # taking queued messages straight from DDS (see _pull_pending)
        self._sim_clock_sub = None
        self._reorder_ns = int(round(float(p["sim_reorder_window_s"]) * 1e9))
        self._rt_priority = int(p["realtime_priority"])
        warm_up(model)
        self.timing = TimingStats(self.core.period_ns)
        self.recorder: RecordingQueue | None = None
        if p["record_path"]:
            meta = simulated_metadata({"maneuver": "live", "node": NODE_NAME}, model.vehicle.name, model.variant.name, oil)
            self.recorder = RecordingQueue(
                McapRecorder(p["record_path"], metadata=meta, overwrite=bool(p["record_overwrite"]),
                             flush_interval_s=float(p["record_flush_interval_s"])),
                lambda text: self.get_logger().error(text))
        self._imu, self._odom, self._susp = Imu(), Odometry(), Float64MultiArray()
        self.pub_imu = self.create_publisher(Imu, SIM_IMU, OUTPUT_QOS)
        self.pub_odom = self.create_publisher(Odometry, SIM_ODOM, OUTPUT_QOS)
        self.pub_susp = self.create_publisher(Float64MultiArray, SIM_SUSPENSION, OUTPUT_QOS)
        self.pub_diag = self.create_publisher(DiagnosticArray, DIAGNOSTICS, 10)
        if self.sim_time:
            self._guard_time_source()
            # Our own /clock subscription, reliable and deep (rclpy's time source keeps only the latest
            # /clock, so a busy node would see the clock skip ahead of queued inputs): every clock value
            # is seen, in order, and each one steps the core exactly that far.
            self._sim_clock_sub = self.create_subscription(Clock, "/clock", self._on_clock, CLOCK_QOS)
            self.create_timer(0.002, self._drain, clock=RosClock(clock_type=ClockType.STEADY_TIME))
        self._input_subs = [
            self.create_subscription(Float64, "/vehicle/speed", self._on_speed, INPUT_QOS),
            self.create_subscription(Float64, "/vehicle/steering_wheel_angle", self._on_steering, INPUT_QOS),
            self.create_subscription(Float64MultiArray, "/road/profile", self._on_profile, LATCHED_QOS),
            self.create_subscription(Float64MultiArray, "/road/wheel_heights", self._on_heights, INPUT_QOS),
            self.create_subscription(Float64MultiArray, DAMPER_COMMAND, self._on_damper_command, INPUT_QOS)]
        self._semiactive = SemiActiveDiagnostics(model, self.core.period_ns)
        self.add_on_set_parameters_callback(self._on_params)
        self._stale: set[str] = set()
        self._wall0 = time.monotonic()
        self._sim0_ns: int | None = None
        self.published = 0
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        if start_thread and not self.sim_time:
            note = raise_priority(self._rt_priority)
            if note:
                self.get_logger().info(note)
            self._thread = threading.Thread(target=self._realtime_loop, name="susp_sim_tick", daemon=True)
            self._thread.start()
        self.create_timer(1.0 / float(p["diagnostics_rate_hz"]), self.publish_diagnostics)
        self.get_logger().info(
            f"{NODE_NAME}: vehicle {self._vehicle}, variant {self._variant}, oil {oil.tolist()}, "
            f"step {self.core.step_ns * 1e-9} s, publish {1e9 / self.core.period_ns:g} Hz, "
            f"{'sim' if self.sim_time else 'wall'} time"
            + (f", recording to {p['record_path']}" if self.recorder else ""))

    # -- time -----------------------------------------------------------------------------------------
    def _guard_time_source(self) -> None:
        """rclpy's own ``/clock`` subscription (``use_sim_time``) raises on a negative time, which would
        take the executor and the node down: let it see only valid times (our own ``/clock`` subscription
        rejects and counts the others)."""
        sub = getattr(getattr(self, "_time_source", None), "_clock_sub", None)
        if sub is None:
            return
        inner = sub.callback

        def guarded(msg: Clock) -> None:
            if msg.clock.sec >= 0 and msg.clock.nanosec < 1_000_000_000:
                inner(msg)
        sub.callback = guarded

    def now_ns(self) -> int:
        """ROS time [ns]: the last /clock value seen in sim time, else the wall clock."""
        if self.sim_time:
            return self._sim_now
        return self.get_clock().now().nanoseconds

    def _record(self, topic: str, msgtype: str, t_ns: int, data, latched: bool = False) -> None:
        """Queue a message for the recording: CDR bytes, or a function making them (see RecordingQueue)."""
        if self.recorder is not None:
            self.recorder.write(topic, msgtype, t_ns, data, latched=latched)

    # -- inputs ---------------------------------------------------------------------------------------
    def _input(self, topic: str, msgtype: str, msg, apply, info=None, latched: bool = False) -> None:
        """An input message. Wall time: stamped with its arrival time and handed to the tick, which
        steps to that instant and applies it (the callback itself does no stepping or publishing, so
        it never delays a tick). Sim time: queued with ``/clock`` (see :meth:`_drain`)."""
        self.inputs_taken += 1
        payload = (topic, msgtype, msg, apply, latched)
        if self.sim_time:
            self._push(info, 1, payload)
        else:
            with self.lock:
                self._wall_inputs.append((self.get_clock().now().nanoseconds, payload))

    # Sim time: ROS 2 gives no order across topics, and a busy executor may take an input before the
    # /clock message published just before it (or after the next one). So /clock and inputs go through
    # one queue ordered by the publishers' source timestamps. An input is processed once a /clock
    # published after it has arrived (per topic DDS keeps order, so every earlier /clock is in the queue
    # by then); a /clock once it is ``sim_reorder_window_s`` old (wall time), so that inputs published
    # before it can still be sorted in. An input published after /clock t and before the next /clock
    # thus takes effect exactly at t, as in lockstep, at any replay rate.
    # The window alone is not enough when the executor falls behind (a fast replay): an input published
    # before the due /clock may still wait in its subscription's DDS queue, because the executor takes
    # one message per subscription per round. So before a due /clock is processed, every message DDS
    # already holds for the input and /clock subscriptions is taken into the queue (_pull_pending): the
    # window then only has to cover DDS delivery, not the executor's backlog.
    INPUT_WAIT_MAX_NS = 500_000_000  # an input with no later /clock is processed after this anyway

    def _push(self, info, kind: int, payload) -> None:
        src = int(info["source_timestamp"]) if info else 0
        with self.lock:
            self._seq += 1
            heapq.heappush(self._events, (src, self._seq, kind, payload))
            if kind == 0:
                self._max_clock_src = max(self._max_clock_src, src)
        if not self._pulling:
            self._drain()

    def _pull_pending(self) -> None:
        """Take every message already delivered to the input and ``/clock`` subscriptions into the
        queue, through their callbacks (as the executor would, which then finds them empty)."""
        self._pulling = True
        try:
            for sub in (*self._input_subs, self._sim_clock_sub):
                while True:
                    with sub.handle:
                        got = sub.handle.take_message(sub.msg_type, sub.raw)
                    if got is None:
                        break
                    sub.callback(*got)
        except InvalidHandle:  # shutting down: a subscription is already destroyed
            pass
        finally:
            self._pulling = False

    def _drain(self) -> None:
        now = time.time_ns()
        with self.lock:
            pulled = False
            while self._events:
                src, _, kind, payload = self._events[0]
                if kind == 0:
                    if src > now - self._reorder_ns:
                        break
                    if not pulled:  # inputs published before this /clock may still wait in DDS
                        pulled = True
                        self._pull_pending()
                        continue
                elif not (src < self._max_clock_src or src <= now - self.INPUT_WAIT_MAX_NS):
                    break
                heapq.heappop(self._events)
                if kind == 0:
                    pulled = False
                    self._sim_now = payload
                    if self.core.started:  # sim time starts with the first input (as lockstep)
                        self.tick()
                        if self.core.t_ns is not None:  # a stale /clock leaves the time where it was
                            self._sim_now = self.core.t_ns
                else:
                    self._apply_input(*payload)

    def _apply_input(self, topic: str, msgtype: str, msg, apply, latched: bool, t: int | None = None) -> None:
        """Step to the input's time ``t`` (default: now), publishing the ticks passed, then apply it."""
        with self.lock:
            t = self.now_ns() if t is None else t
            if t > 0:
                if not self.core.started:
                    self.core.start(t)
                    self._sim0_ns = t
                    self._wall0 = time.monotonic()
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
            self._record(topic, msgtype, max(t, 0), _input_cdr(msg), latched)
            self._check_failure()

    def _on_speed(self, msg: Float64, info) -> None:
        self._input("/vehicle/speed", M.FLOAT64, msg, lambda t: self.core.set_speed(t, msg.data), info)

    def _on_steering(self, msg: Float64, info) -> None:
        self._input("/vehicle/steering_wheel_angle", M.FLOAT64, msg,
                    lambda t: self.core.set_steering(t, msg.data), info)

    def _on_profile(self, msg: Float64MultiArray, info) -> None:
        dims = [(d.label, d.size, d.stride) for d in msg.layout.dim]
        off = msg.layout.data_offset
        self._input("/road/profile", M.FLOAT64_ARRAY, msg,
                    lambda t: self.core.set_road_profile(t, msg.data, dims, off), info, latched=True)

    def _on_heights(self, msg: Float64MultiArray, info) -> None:
        dims = [(d.label, d.size, d.stride) for d in msg.layout.dim]
        off = msg.layout.data_offset
        self._input("/road/wheel_heights", M.FLOAT64_ARRAY, msg,
                    lambda t: self.core.set_wheel_heights(t, msg.data, dims, off), info)

    def _on_damper_command(self, msg: Float64MultiArray, info) -> None:
        dims = [(d.label, d.size, d.stride) for d in msg.layout.dim]
        off = msg.layout.data_offset
        src = int(info["source_timestamp"]) if info else 0

        def apply(t):
            reason = self.core.set_damper_command(t, msg.data, dims, off)
            if reason is None:
                self._semiactive.command_applied(t, src)
            return reason
        self._input(DAMPER_COMMAND, M.FLOAT64_ARRAY, msg, apply, info)

    # -- stepping and publishing ----------------------------------------------------------------------
    def _publish_samples(self, samples) -> None:
        if samples:
            self._semiactive.published(samples)
        for s in samples:
            imu = fill(self._imu, M.imu_msg(s.t_ns, s.y))
            odom = fill(self._odom, M.odom_msg(s.t_ns, s.y))
            susp = fill(self._susp, M.suspension_msg(s.y))
            self.pub_imu.publish(imu)
            if not self.sim_time:  # whichever thread published this tick (tick thread or an input)
                self.timing.record(s.t_ns, time.time_ns())
            self.pub_odom.publish(odom)
            self.pub_susp.publish(susp)
            self.published += 1
            if self.recorder is not None:  # the message objects are reused: serialise now
                self._record(SIM_IMU, M.IMU, s.t_ns, serialize_message(imu))
                self._record(SIM_ODOM, M.ODOMETRY, s.t_ns, serialize_message(odom))
                self._record(SIM_SUSPENSION, M.FLOAT64_ARRAY, s.t_ns, serialize_message(susp))

    def tick(self, t_ns: int | None = None) -> int:
        """Step to ``t_ns`` (default: now) and publish the samples passed; returns how many."""
        with self.lock:
            n0 = self.published
            if self._wall_inputs:  # wall time: inputs take effect at their arrival instants
                pending, self._wall_inputs = self._wall_inputs, []
                for t_in, payload in pending:
                    self._apply_input(*payload, t=t_in)
            t = self.now_ns() if t_ns is None else int(t_ns)
            if not self.core.started:
                if t <= 0:
                    return 0
                self.core.start(t)
                self._sim0_ns = t
                self._wall0 = time.monotonic()
                return 0
            self._publish_samples(self.core.advance_to(t, allow_restart=self.sim_time))
            self._check_failure()
            return self.published - n0

    def _check_failure(self) -> None:
        """After stepping: when the divergence guard has stopped the core, report it once (error log,
        ERROR diagnostics right away, recording finalised); ``main`` then exits with code 1 (with
        ``on_divergence: hold`` the node stays up; a restart from rest, a looped replay, clears it)."""
        key = (self.core.restarts, self.core.diverged_at_ns)
        if not self.core.diverged or key == self._failure_key:
            return
        self._failure_key = key
        self.divergences += 1
        self.failure = self.core.diverged
        self.get_logger().error(f"{self.failure}; nothing more is published on /sim"
                                + ("; exiting" if self.on_divergence == "exit" else ""))
        self.publish_diagnostics()
        if self.recorder is not None and self.on_divergence == "exit":
            self.recorder.close()

    def _on_clock(self, msg: Clock, info) -> None:
        sec, nsec = int(msg.clock.sec), int(msg.clock.nanosec)
        if sec < 0 or not 0 <= nsec < 1_000_000_000 or (sec == 0 and nsec == 0):
            with self.lock:
                self.core.reject("/clock", "clock_invalid", f"/clock: rejected invalid time sec={sec} "
                                 f"nanosec={nsec} (need sec >= 0, 0 <= nanosec < 1e9, not 0)")
            return
        self._push(info, 0, sec * 1_000_000_000 + nsec)

    def _realtime_loop(self) -> None:
        """Wall-time stepping: wake at each tick (absolute deadline), step, publish, measure."""
        period = self.core.period_ns
        ctx = self.context
        if self._rt_priority > 0:
            try:  # one above the process's other threads
                os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(self._rt_priority + 1))
            except (OSError, AttributeError) as exc:
                self.get_logger().info(f"tick thread: no real-time scheduling ({exc}); using normal priority")
        with self.lock:
            if not self.core.started:
                t0 = time.time_ns()
                self.core.start(t0)
                self._sim0_ns = t0
                self._wall0 = time.monotonic()
        while not self._stop.is_set() and ctx.ok():
            nxt = self.core.next_tick_ns
            wait = (nxt - time.time_ns()) * 1e-9
            if wait > 0:
                if self._stop.wait(wait):
                    break
            try:
                self.tick(time.time_ns())
            except Exception as exc:
                if self._stop.is_set() or not ctx.ok():
                    break  # shutting down (SIGINT): the context went away under a publish
                self.tick_errors += 1  # never let the tick thread die silently
                self.core.reject("tick", "tick_error", f"tick: {type(exc).__name__}: {exc}")

    # -- parameters -----------------------------------------------------------------------------------
    def _on_params(self, params) -> SetParametersResult:
        new = {p.name: p.value for p in params}
        fixed = [n for n in new if (n in DEFAULTS or n == "use_sim_time") and n not in RUNTIME
                 and new[n] != self.get_parameter(n).value]
        if fixed:
            return SetParametersResult(successful=False,
                                       reason=f"parameter(s) {', '.join(fixed)} are fixed after start; "
                                              f"run-time changes: {', '.join(RUNTIME)}")
        try:
            oil = check_oil(new["damper_oil_level"], "parameter damper_oil_level") \
                if "damper_oil_level" in new else None
            model = None
            vehicle = str(new.get("vehicle", self._vehicle))
            variant = str(new.get("friction_variant", self._variant))
            if (vehicle, variant) != (self._vehicle, self._variant):
                model = Model(vehicle, variant)
                warm_up(model)
        except (SuspInputError, ValueError, TypeError) as exc:
            self.get_logger().warning(f"rejected parameter change: {exc}")
            return SetParametersResult(successful=False, reason=str(exc))
        with self.lock:
            if oil is not None:
                self.core.set_oil(oil)
            if model is not None:
                self.core.set_model(model)
                self._vehicle, self._variant = vehicle, variant
        self.get_logger().info(f"parameters changed: {', '.join(f'{k}={v}' for k, v in new.items())}")
        return SetParametersResult(successful=True)

    # -- diagnostics ----------------------------------------------------------------------------------
    def diagnostics(self) -> list[dict]:
        t = self.now_ns()
        with self.lock:
            core = self.core
            stale = core.stale_inputs(t) if core.started else []
            rej = dict(core.rejections)
            by_topic = ",".join(f"{tp}:{c}={n}" for (tp, c), n in sorted(core.rejections_by_topic.items()))
            last_rej = core.last_rejection
            healthy = core.healthy
            diverged = core.diverged
            clamped, jumps = core.accel_clamped, core.time_jumps
            sim_s = core.total_sim_time_s
            restarts = core.restarts
            oil = core.oil.tolist()
        for topic in set(stale) - self._stale:
            self.get_logger().warning(f"input {topic} is stale (no message for more than "
                                      f"{core.timeout_ns * 1e-9:g} s); holding its last value")
        for topic in self._stale - set(stale):
            self.get_logger().info(f"input {topic} is fresh again")
        self._stale = set(stale)
        wall = time.monotonic() - self._wall0
        rtf = sim_s / wall if wall > 0 and core.started else 0.0
        tm = self.timing.summary()
        inputs = {"level": 1 if stale else 0, "name": f"{NODE_NAME}: inputs",
                  "message": ("stale: " + ", ".join(stale)) if stale else ("waiting for inputs" if not core.started else "fresh"),
                  "values": {"stale": ",".join(stale), "rejected_total": sum(rej.values()),
                             "queued_sim_events": len(self._events),
                             **{f"rejected_{k}": v for k, v in rej.items()}, "rejected_by_topic": by_topic,
                             "last_rejection": last_rej, "accel_clamped": clamped, "time_jumps": jumps,
                             "handler_errors": self.handler_errors}}
        timing = {"level": 1 if tm["deadline_misses"] else 0, "name": f"{NODE_NAME}: timing",
                  "message": f"real-time factor {rtf:.3f}, {tm['deadline_misses']} deadline misses",
                  "values": {"real_time_factor": f"{rtf:.6f}", "sim_time_s": f"{sim_s:.6f}",
                             "restarts": restarts,
                             "mode": "sim_time" if self.sim_time else "wall_time",
                             **{k: (f"{v:.6f}" if isinstance(v, float) else v) for k, v in tm.items()}}}
        model = {"level": 0 if healthy else 2, "name": f"{NODE_NAME}: model",
                 "message": "numerically healthy" if healthy else (diverged or "numerically unhealthy: stepping stopped"),
                 "values": {"healthy": healthy, "diverged": diverged, "on_divergence": self.on_divergence,
                            "divergences": self.divergences, "last_divergence": self.failure,
                            "vehicle": self._vehicle, "friction_variant": self._variant,
                            "damper_oil_level": ",".join(f"{x:g}" for x in oil),
                            "published_samples": self.published,
                            "recording_dropped": self.recorder.dropped if self.recorder else 0,
                            "recording_error": self.recorder.error if self.recorder else "",
                            "tick_errors": self.tick_errors}}
        if healthy and self.recorder is not None and (self.recorder.error or self.recorder.dropped):
            model["level"] = 1
            model["message"] = "numerically healthy; recording " + (
                f"stopped: {self.recorder.error}" if self.recorder.error else f"dropped {self.recorder.dropped} messages")
        with self.lock:  # semi-active damper and ride metrics: added values of the model status
            model["values"].update(self._semiactive.values(self.core))
        return [inputs, timing, model]

    def publish_diagnostics(self) -> None:
        t = self.now_ns()
        d = M.diagnostics_msg(t, self.diagnostics())
        msg = DiagnosticArray()
        fill(msg.header, d["header"])
        from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
        msg.status = [DiagnosticStatus(level=bytes([s["level"]]), name=s["name"], message=s["message"],
                                       hardware_id=s["hardware_id"],
                                       values=[KeyValue(key=kv["key"], value=kv["value"]) for kv in s["values"]])
                      for s in d["status"]]
        self.pub_diag.publish(msg)
        with self.lock:
            if self.recorder is not None:
                # logged no earlier than the samples recorded while this message was built (the tick
                # thread may have published meanwhile): the file stays in log-time order
                t_log = max(t, self.core.t_ns or 0, 0)
                self._record(DIAGNOSTICS, M.DIAGNOSTIC_ARRAY, t_log, serialize_message(msg))
                self.recorder.flush_if_due()  # idle periods (sim time paused) still reach the disk

    # -- shutdown -------------------------------------------------------------------------------------
    def close(self) -> None:
        """Stop the tick thread and finalise the recording (idempotent)."""
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout=2.0)
        with self.lock:
            if self.recorder is not None:
                self.recorder.close()

    def destroy_node(self):
        self.close()
        return super().destroy_node()


def main(args: list[str] | None = None) -> int:
    """Console entry point ``susp_sim_node [--ros-args ...]``. Exit 0 on SIGINT/SIGTERM."""
    # The tick thread must get the GIL promptly when its deadline comes, not after the default 5 ms
    # switch interval of a busy executor thread.
    sys.setswitchinterval(SWITCH_INTERVAL_S)
    rclpy.init(args=args if args is not None else sys.argv)
    node = None
    try:
        node = SuspSimNode()
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        gc.freeze()  # start-up objects out of the collector's way: shorter pauses in real time
        while rclpy.ok() and not (node.failure and node.on_divergence == "exit"):
            executor.spin_once(timeout_sec=0.1)
        if node.failure:
            end = time.monotonic() + 0.5  # let the ERROR diagnostic reach its subscribers
            while rclpy.ok() and time.monotonic() < end:
                executor.spin_once(timeout_sec=0.05)
            print(f"{NODE_NAME}: stopped: {node.failure}", file=sys.stderr)
            return 1
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except SuspInputError as exc:
        print(f"{NODE_NAME}: error: {exc}", file=sys.stderr)
        return 2
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
