"""``susp_sim_node``: the ROS 2 node, a thin adapter around :class:`~susp_sim_ros.runtime.sim_core.SimCore`.

Subscribes to the test-drive input topics (interface.md), publishes ``/sim/imu/data``, ``/sim/odom``,
``/sim/suspension`` and ``/diagnostics``, optionally records everything to an MCAP file (:mod:`.recording`).

Timing: in wall time (default) a tick thread (:class:`~.timing.TickThread`) wakes at each publish tick,
steps the core to "now" and publishes; jitter, lateness and deadline misses go to ``/diagnostics``. In sim
time (``use_sim_time:=true``) every ``/clock`` message steps the core exactly as far as the clock moved;
``/clock`` and the inputs are put back into publish order first (:mod:`.sim_time`), so replays at any
rate give the same outputs. Every input first steps the core to its time, then replaces the held value.

Bad input never stops the node: a rejected message is not integrated, counted per cause on
``/diagnostics`` and logged rate-limited (``REJECTION_LOG_INTERVAL_S``). Every applied input message is also
judged by the input-integrity policy of the offline tools (``config/integrity.yaml``,
:class:`~susp_sim_ros.io.live_integrity.LiveIntegrity`): each finding (non-finite or out-of-range value,
unit mistake, stamp order, clock jump, gap) is a status of its own on ``/diagnostics`` (WARN, ERROR where
the policy names an error) and logged rate-limited per topic and kind. When the divergence guard of the
core trips, nothing more is published on ``/sim/...``; the node logs an error, publishes ERROR
diagnostics, finalises the recording and (``on_divergence: exit``) exits with code 1.

Parameters: :mod:`.parameters` (``--ros-args --params-file config/susp_sim_node.yaml``); ``vehicle``,
``friction_variant`` and ``damper_oil_level`` may change while running, the others are read-only.
"""
from __future__ import annotations

import sys
import threading
import time

import numpy as np

from rclpy.node import Node
from rclpy.timer import Timer
from rclpy.serialization import serialize_message

from diagnostic_msgs.msg import DiagnosticArray
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Imu
from std_msgs.msg import Float64MultiArray

from ..io import messages as M
from ..io.sim_cdr import imu_cdr, odom_cdr, suspension_cdr
from ..io.live_integrity import ERROR, FindingBoard, LiveFinding, LiveIntegrity
from ..runtime.lockstep import simulated_metadata
from ..model.vehicle import Model, check_oil
from .ride_diagnostics import SemiActiveDiagnostics
from ..runtime.sim_core import DIAGNOSTICS, SIM_IMU, SIM_ODOM, SIM_SUSPENSION, RateLimitedLog, Sample, SimCore
from .conversion import diagnostic_array
from .inputs import InputHandler
from .parameters import DEFAULTS, RuntimeChange, RuntimeParameters, declare_parameters, warm_up
from .qos import OUTPUT_QOS
from .recording import RecordingQueue, open_recording
from .run import run_node, usage
from .status import (NODE_NAME, CoreSnapshot, integrity_statuses, log_shared_inputs, log_stale_changes,
                     node_status)
from .timing import TickThread, TimingStats, raise_priority

REJECTION_LOG_INTERVAL_S = 10.0
ERROR_DIAGNOSTIC_GRACE_S = 0.5  # after a divergence, spin this long before exiting so the ERROR is heard [s]


class SuspSimNode(Node):
    """The simulation node (see the module docstring). In wall time its tick thread starts at the
    executor's first spin; ``start_thread=False`` leaves wall-time stepping to the caller (:meth:`tick`),
    for deterministic in-process tests. ``inputs`` (:class:`.inputs.InputHandler`)
    holds the input subscriptions; its ``on_*`` methods are their callbacks ``(message, message info or
    None)``, which tests may call directly."""

    def __init__(self, *, start_thread: bool = True, **kwargs):
        super().__init__(NODE_NAME, **kwargs)
        p = declare_parameters(self)
        self.sim_time = bool(self.get_parameter("use_sim_time").value)
        model, oil = self._init_core(p)
        self._init_guards_and_logs()
        warm_up(model)
        self.timing = TimingStats(self.core.period_ns)
        self.recorder: RecordingQueue | None = self._open_recording(p, model, oil)
        self._init_publishers()
        self.semiactive = SemiActiveDiagnostics(model, self.core.period_ns)
        self.inputs = InputHandler(self, self.core, self.lock, sim_time=self.sim_time,
                                   reorder_window_s=float(p["sim_reorder_window_s"]), tick=self.tick,
                                   step_to=self._step_to, record=self._record, check_failure=self._check_failure,
                                   command_applied=self.semiactive.command_applied,
                                   refuse_shared=bool(p["refuse_shared_inputs"]), judge=self._judge_input)
        self.parameters = RuntimeParameters(self, lambda: (self.vehicle, self.variant), self._apply_change)
        self._stale: set[str] = set()
        self.shared_inputs: list[str] = []  # input topics more than one publisher feeds (last diagnostics)
        self._wall0 = time.monotonic()
        self.published = 0
        self._ticker: TickThread | None = None
        self._start_timer: Timer | None = None
        if start_thread and not self.sim_time:
            # Real time begins when the executor first spins, not here: the first samples provoke inputs (a
            # controller's commands) that would otherwise wait in DDS while the process still starts up.
            priority = int(p["realtime_priority"])
            self._start_timer = self.create_timer(0.0, lambda: self._begin_real_time(priority))
        self.create_timer(1.0 / float(p["diagnostics_rate_hz"]), self.publish_diagnostics)
        self.get_logger().info(
            f"{NODE_NAME}: vehicle {self.vehicle}, variant {self.variant}, oil {oil.tolist()}, "
            f"step {self.core.step_ns * 1e-9} s, publish {1e9 / self.core.period_ns:g} Hz, "
            f"{'sim' if self.sim_time else 'wall'} time"
            + (f", recording to {p['record_path']}" if self.recorder else ""))

    def _init_core(self, p: dict) -> tuple[Model, np.ndarray]:
        """The model the parameters name and the :class:`SimCore` stepping it (step and publish period
        from ``step_s`` [s] and ``publish_rate_hz`` [Hz]); returns the model and the oil levels [-]."""
        oil = check_oil(p["damper_oil_level"], "parameter damper_oil_level")
        self.vehicle, self.variant = str(p["vehicle"]), str(p["friction_variant"])
        model = Model(self.vehicle, self.variant)
        self.on_divergence = str(p["on_divergence"])
        self.core = SimCore(model, step_s=float(p["step_s"]), publish_rate_hz=float(p["publish_rate_hz"]),
                            oil=oil, input_timeout_s=float(p["input_timeout_s"]),
                            max_time_jump_s=float(p["max_time_jump_s"]))
        return model, oil

    def _init_guards_and_logs(self) -> None:
        """The lock, the divergence guard's state, and the rate-limited logs of rejected inputs and of
        the live input-integrity findings (the offline policy table, message by message)."""
        self.lock = threading.RLock()
        self.failure = ""  # the last divergence (set when the divergence guard stopped the simulation)
        self.divergences = self.tick_errors = 0
        self._failure_key: tuple | None = None
        logger = self.get_logger()
        self.rejection_log = RateLimitedLog(lambda text: logger.warning(text), REJECTION_LOG_INTERVAL_S)
        self.core.on_reject = self.rejection_log  # every rejection, once per cause and interval
        self.integrity = LiveIntegrity()
        self.findings = FindingBoard()
        self.integrity_log = RateLimitedLog(lambda text: logger.warning(text), REJECTION_LOG_INTERVAL_S)
        self.integrity_error_log = RateLimitedLog(lambda text: logger.error(text), REJECTION_LOG_INTERVAL_S)

    def _open_recording(self, p: dict, model: Model, oil: np.ndarray) -> RecordingQueue | None:
        """The recording of ``record_path`` (None when empty), flushed every ``record_flush_interval_s``."""
        if not p["record_path"]:
            return None
        meta = simulated_metadata({"maneuver": "live", "node": NODE_NAME}, model.vehicle.name,
                                  model.variant.name, oil)
        return open_recording(p["record_path"], meta, bool(p["record_overwrite"]),
                              float(p["record_flush_interval_s"]), self.get_logger().error)

    def _init_publishers(self) -> None:
        """The ``/sim`` publishers (they publish CDR bytes, :mod:`~susp_sim_ros.io.sim_cdr`) and ``/diagnostics``."""
        self.pub_imu = self.create_publisher(Imu, SIM_IMU, OUTPUT_QOS)
        self.pub_odom = self.create_publisher(Odometry, SIM_ODOM, OUTPUT_QOS)
        self.pub_susp = self.create_publisher(Float64MultiArray, SIM_SUSPENSION, OUTPUT_QOS)
        self.pub_diag = self.create_publisher(DiagnosticArray, DIAGNOSTICS, 10)

    def _begin_real_time(self, priority: int) -> None:
        """The one-shot timer's callback at the executor's first spin: start the tick thread."""
        if self._cancel_start():
            self._start_ticker(priority)

    def _cancel_start(self) -> bool:
        """Destroy the one-shot start timer; whether it was still pending (False after close() or a
        first call)."""
        if self._start_timer is None:
            return False
        self.destroy_timer(self._start_timer)
        self._start_timer = None
        return True

    def _start_ticker(self, priority: int) -> None:
        """Wall time: the tick thread publishing at fixed deadlines, at SCHED_FIFO ``priority`` when
        permitted (0 = off; the fallback is logged)."""
        note = raise_priority(priority)
        if note:
            self.get_logger().info(note)
        self._ticker = TickThread(priority=priority, begin=self._begin_wall_time,
                                  next_tick_ns=lambda: self.core.next_tick_ns, tick=self.tick,
                                  ok=self.context.ok, on_error=self._on_tick_error,
                                  log=lambda text: self.get_logger().info(text))
        self._ticker.start()

    # -- time -----------------------------------------------------------------------------------------
    def now_ns(self) -> int:
        """ROS time [ns]: the last /clock value processed in sim time, else the wall clock."""
        return self.inputs.now_ns()

    def _start_core(self, t_ns: int) -> None:
        self.core.start(t_ns)
        self._wall0 = time.monotonic()

    def _begin_wall_time(self) -> None:
        with self.lock:
            if not self.core.started:
                self._start_core(time.time_ns())

    def _on_tick_error(self, exc: Exception) -> None:
        self.tick_errors += 1  # never let the tick thread die silently
        self.core.reject("tick", "tick_error", f"tick: {type(exc).__name__}: {exc}")

    def _record(self, topic: str, msgtype: str, t_ns: int, data, latched: bool = False) -> None:
        """Queue a message for the recording: CDR bytes, or a function making them (see RecordingQueue)."""
        if self.recorder is not None:
            self.recorder.write(topic, msgtype, t_ns, data, latched=latched)

    # -- stepping and publishing ----------------------------------------------------------------------
    def _step_to(self, t_ns: int) -> None:
        """Start the core at ``t_ns``, or step it there and publish the samples passed."""
        if not self.core.started:
            self._start_core(t_ns)
        else:
            self._publish_samples(self.core.advance_to(t_ns, allow_restart=self.sim_time))

    def _publish_samples(self, samples: list[Sample]) -> None:
        if samples:
            self.semiactive.published(samples)
        for s in samples:  # encoded once (sim_cdr), published and recorded as the same bytes
            imu, odom, susp = imu_cdr(s.t_ns, s.y), odom_cdr(s.t_ns, s.y), suspension_cdr(s.y)
            self.pub_imu.publish(imu)
            if not self.sim_time:  # whichever thread published this tick (tick thread or an input)
                self.timing.record(s.t_ns, time.time_ns())
            self.pub_odom.publish(odom)
            self.pub_susp.publish(susp)
            self.published += 1
            if self.recorder is not None:
                self._record(SIM_IMU, M.IMU, s.t_ns, imu)
                self._record(SIM_ODOM, M.ODOMETRY, s.t_ns, odom)
                self._record(SIM_SUSPENSION, M.FLOAT64_ARRAY, s.t_ns, susp)

    def tick(self, t_ns: int | None = None) -> int:
        """Step to ``t_ns`` (default: now) and publish the samples passed; returns how many."""
        with self.lock:
            n0 = self.published
            self.inputs.apply_arrived()  # wall time: inputs take effect at their arrival instants
            t = self.now_ns() if t_ns is None else int(t_ns)
            if not self.core.started:
                if t > 0:
                    self._start_core(t)
                return 0
            self._publish_samples(self.core.advance_to(t, allow_restart=self.sim_time))
            self._check_failure()
            if self.recorder is not None:
                self.recorder.kick()  # the writer works while this thread waits for its next tick
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

    # -- input integrity ------------------------------------------------------------------------------
    def _judge_input(self, topic: str, t_ns: int, numbers) -> None:
        """An applied input message (under the lock): the policy's findings, reported."""
        self._report_findings(self.integrity.check(topic, t_ns, numbers))

    def _report_findings(self, findings: list[LiveFinding]) -> None:
        """Keep findings for ``/diagnostics`` and log them, once per (topic, kind) and interval."""
        if not findings:
            return
        self.findings.add(findings)
        for f in findings:
            (self.integrity_error_log if f.level >= ERROR else self.integrity_log)((f.topic, f.kind), f.line())

    # -- parameters -----------------------------------------------------------------------------------
    def _apply_change(self, change: RuntimeChange) -> None:
        """Apply a run-time parameter change validated by :class:`.parameters.RuntimeParameters`."""
        with self.lock:
            if change.oil is not None:
                self.core.set_oil(change.oil)
            if change.model is not None:
                self.core.set_model(change.model)
                self.vehicle, self.variant = change.vehicle, change.variant

    # -- diagnostics ----------------------------------------------------------------------------------
    def diagnostics(self, *, mark: bool = False) -> list[dict]:
        """The three statuses (inputs, timing, model) of ``/diagnostics`` (:func:`.status.node_status`),
        then one per (input topic, integrity kind) found so far (:func:`.status.integrity_statuses`; an input
        gap still open is found here, while the simulation runs). ``mark``: this is the report that goes out
        (a finding's status is WARN/ERROR in the first report after it, OK with its figures later)."""
        t = self.now_ns()
        with self.lock:
            snap = CoreSnapshot.of(self.core, t)
            if self.core.started and not self.core.diverged:
                self._report_findings(self.integrity.check_gaps(t))
            found = integrity_statuses(self.findings.entries(), self.integrity.open_gaps())
            if mark:
                self.findings.mark_reported()
        self._stale = log_stale_changes(self.get_logger(), self._stale, snap.stale, self.core.timeout_ns)
        self.shared_inputs = log_shared_inputs(self.get_logger(), self.shared_inputs, self.inputs.check_publishers(),
                                               self.inputs.publishers, self.inputs.refuse_shared)
        return node_status(self, snap, time.monotonic() - self._wall0) + found

    def publish_diagnostics(self) -> None:
        t = self.now_ns()
        msg = diagnostic_array(t, self.diagnostics(mark=True))
        self.pub_diag.publish(msg)
        data = serialize_message(msg) if self.recorder is not None else b""  # not under the tick's lock
        with self.lock:
            if self.recorder is not None:
                # logged no earlier than the samples recorded while this message was built (the tick
                # thread may have published meanwhile): the file stays in log-time order
                t_log = max(t, self.core.t_ns or 0, 0)
                self._record(DIAGNOSTICS, M.DIAGNOSTIC_ARRAY, t_log, data)
                self.recorder.flush_if_due()  # idle periods (sim time paused) still reach the disk

    # -- shutdown -------------------------------------------------------------------------------------
    def close(self) -> None:
        """Stop the tick thread (or keep it from starting) and finalise the recording (idempotent)."""
        self._cancel_start()
        if self._ticker is not None:
            self._ticker.stop()
        with self.lock:
            if self.recorder is not None:
                self.recorder.close()

    def destroy_node(self):
        self.close()
        return super().destroy_node()


def main(args: list[str] | None = None) -> int:
    """Console entry point ``susp_sim_node [--ros-args ...]``. Exit 0 on SIGINT/SIGTERM, 2 on a bad
    parameter, 1 when the divergence guard stopped the simulation (``on_divergence: exit``)."""
    return run_node(SuspSimNode, NODE_NAME, args, realtime=True,
                    stop_when=lambda node: bool(node.failure) and node.on_divergence == "exit",
                    finish=_exit_code,
                    help_text=usage(NODE_NAME, "The five-mass vehicle with suspension friction in real time (or sim "
                                    "time from /clock): inputs /vehicle/*, /road/profile; outputs /sim/*, "
                                    "/diagnostics.", DEFAULTS))


def _exit_code(node: SuspSimNode, spin_for) -> int:
    """1 after a divergence (once the ERROR diagnostic has had time to reach its subscribers), else 0."""
    if not node.failure:
        return 0
    spin_for(ERROR_DIAGNOSTIC_GRACE_S)
    print(f"{NODE_NAME}: stopped: {node.failure}", file=sys.stderr)
    return 1


if __name__ == "__main__":
    sys.exit(main())
