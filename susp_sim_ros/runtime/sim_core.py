"""The simulation core shared by the ROS 2 node and the offline lockstep runner (pure; no rclpy).

:class:`SimCore` holds the latest inputs (validated), steps the model's :class:`Stepper` exactly as far
as time moved and returns the output samples at the publish ticks it passed. Time is integer
nanoseconds of ROS time (wall or ``/clock``), so a replay at 10x speed yields the same samples as at 1x:
the caller only has to call :meth:`SimCore.advance_to` with the message time before applying an input.

Tick ``k`` (k >= 1) is at ``t_start + k * period``; the sample of a tick is the model output after the
last whole step at or before it. Inputs are zero-order held between messages; the longitudinal
acceleration is derived from successive speed messages (limited to +-``MAX_ACCEL``) and held as well.

Reliability rules (each counted per cause in :attr:`SimCore.rejections` and reported on ``/diagnostics``):

- a rejected input (non-finite, out of range, mis-shaped layout, non-increasing profile) is never
  integrated: the previous value is held;
- time going back by at most ``STALE_CLOCK_NS`` (a stale or reordered ``/clock``) is ignored; further
  back (a looped replay) restarts the simulation from rest; a jump forward by more than
  ``max_time_jump_s`` is not stepped through (that would take as long as the gap): the simulation
  continues from the new time with its state held over the gap;
- a semi-active damper command (``/vehicle/damper_command``, [FL, FR, RL, RR] in [0, 1]) switches the
  dampers from their passive curve to the valve family; when no valid command arrived for
  ``input_timeout_s`` it is stale: the dampers fall back to the passive curve (counted once per stale
  spell as ``damper_command_stale``) until a fresh command arrives;
- divergence guard: after every publish tick the output vector must be finite and inside
  :data:`OUTPUT_ENVELOPE` (far beyond anything physical); otherwise the core stops for good
  (:attr:`SimCore.diverged` says why and when) and returns no further samples, so nothing non-finite or
  absurd is ever published or recorded; only a restart from rest (:meth:`SimCore.reset`, a looped
  replay) clears it.
"""
from __future__ import annotations

import math
import time
from collections import Counter
from dataclasses import dataclass
from collections.abc import Callable, Hashable, Sequence

import numpy as np

from ..errors import SuspInputError
from ..io import messages as M
from ..io.drive import MAX_SPEED, MAX_STEERING, MAX_WHEEL_HEIGHT
from ..model.layout import OUTPUT_LABELS
from ..model.road import RoadProfile
from ..model.vehicle import Model, Stepper, check_oil

MAX_ACCEL = 20.0              # m/s^2 (2 g): longitudinal acceleration derived from speed messages is limited to this
MAX_PATH = 1.0e7              # m, |s| of a road profile sample
MAX_PROFILE_SAMPLES = 2_000_000
#: time going back by at most this (jitter, a reordered /clock) is a stale reading, not a restart
STALE_CLOCK_NS = 10_000_000


def _envelope() -> np.ndarray:
    """Per output, the magnitude beyond which the state is numerical garbage (inf: finiteness only)."""
    lim = np.full(len(OUTPUT_LABELS), np.inf)
    for k, name in enumerate(OUTPUT_LABELS):
        if name.endswith("_RATE"):
            lim[k] = 50.0          # rad/s
        elif name.endswith("_SF"):
            lim[k] = 1000.0        # m/s^2 (100 g)
        elif name in ("ROLL", "PITCH"):
            lim[k] = 1.0           # rad (the small-angle model means nothing beyond)
        elif name in ("VEL_X", "VEL_Y"):
            lim[k] = 200.0         # m/s
        elif name == "HEAVE" or name.startswith("Z_ROAD"):
            lim[k] = 10.0          # m
        elif name.startswith("DEFL_VEL"):
            lim[k] = 100.0         # m/s
        elif name.startswith("DEFL"):
            lim[k] = 1.0           # m
        elif name.startswith("F_"):
            lim[k] = 1.0e7         # N
    return lim


#: Divergence guard: |output| must stay within these (and finite); see the module docstring.
OUTPUT_ENVELOPE = _envelope()


class DivergenceError(RuntimeError):
    """The simulation left the physical envelope (non-finite or absurd state) and was stopped."""


def accel_between(t_prev_ns: int | None, v_prev: float, t_ns: int, v: float) -> tuple[float, bool] | None:
    """Acceleration [m/s^2] from two successive speed messages and whether it was limited to
    +-``MAX_ACCEL`` (a glitch, or a jump after a restart, not a car); ``None`` when there is no earlier
    message or ``t_ns`` is not after it (the acceleration in effect stays)."""
    if t_prev_ns is None or t_ns <= t_prev_ns:
        return None
    a = (v - v_prev) / ((t_ns - t_prev_ns) * 1e-9)
    if abs(a) > MAX_ACCEL:
        return math.copysign(MAX_ACCEL, a), True
    return a, False


class RateLimitedLog:
    """Log each cause (any hashable key) the first time at once, then at most once per ``interval_s``
    with the number of occurrences not logged in between: a flood of bad messages gives one line per
    cause, not one per message. ``counts`` holds every occurrence, ``emitted`` the lines logged."""

    def __init__(self, emit: Callable[[str], None], interval_s: float = 10.0,
                 clock: Callable[[], float] = time.monotonic):
        self._emit, self.interval_s, self._clock = emit, float(interval_s), clock
        self._last: dict[Hashable, float] = {}
        self._suppressed: Counter = Counter()
        self.counts: Counter = Counter()
        self.emitted: Counter = Counter()

    def __call__(self, key: Hashable, message: str) -> bool:
        self.counts[key] += 1
        now = self._clock()
        last = self._last.get(key)
        if last is not None and now - last < self.interval_s:
            self._suppressed[key] += 1
            return False
        n = self._suppressed.pop(key, 0)
        self._last[key] = now
        self.emitted[key] += 1
        self._emit(message + (f" ({n} more like this since the last report)" if n else ""))
        return True

#: Topic names of the interface (the node may be remapped; the core does not care).
SIM_IMU, SIM_ODOM, SIM_SUSPENSION, DIAGNOSTICS = "/sim/imu/data", "/sim/odom", "/sim/suspension", "/diagnostics"
DAMPER_COMMAND = "/vehicle/damper_command"


@dataclass(frozen=True)
class Sample:
    """Model output at a publish tick: ROS time [ns] and the full output vector (``OUTPUT_LABELS``)."""

    t_ns: int
    y: np.ndarray


def sample_messages(sample: Sample) -> list[tuple[str, str, dict]]:
    """The ``/sim`` messages of one sample as ``(topic, msgtype, plain dict)``, in publish order."""
    return [(SIM_IMU, M.IMU, M.imu_msg(sample.t_ns, sample.y)),
            (SIM_ODOM, M.ODOMETRY, M.odom_msg(sample.t_ns, sample.y)),
            (SIM_SUSPENSION, M.FLOAT64_ARRAY, M.suspension_msg(sample.y))]


class SimCore:
    """Latest inputs + the stepped model.

    Setters return ``None`` when an input is accepted, else the rejection reason (also counted in
    :attr:`rejections` per cause and kept in :attr:`last_rejection`); a rejected value is never
    integrated.
    """

    def __init__(self, model: Model, *, step_s: float = 0.001, publish_rate_hz: float = 100.0,
                 oil: Sequence[float] | np.ndarray = (1.0, 1.0, 1.0, 1.0), input_timeout_s: float = 0.5,
                 max_time_jump_s: float = 10.0):
        if not (math.isfinite(max_time_jump_s) and max_time_jump_s > 0):
            raise SuspInputError(f"max_time_jump_s: expected a time > 0 s, got {max_time_jump_s}")
        if not (math.isfinite(publish_rate_hz) and 0 < publish_rate_hz <= 1000.0):
            raise SuspInputError(f"publish_rate_hz: expected a rate in (0, 1000] Hz, got {publish_rate_hz}")
        if not (math.isfinite(input_timeout_s) and input_timeout_s > 0):
            raise SuspInputError(f"input_timeout_s: expected a time > 0 s, got {input_timeout_s}")
        self.step_ns = int(round(step_s * 1e9))
        self.period_ns = int(round(1e9 / publish_rate_hz))
        if self.step_ns <= 0 or self.period_ns < self.step_ns:
            raise SuspInputError(f"step_s: the step {step_s} s must be > 0 and not longer than the publish "
                                 f"period {1.0 / publish_rate_hz} s")
        self.model = model
        self.stepper = Stepper(model, dt=self.step_ns * 1e-9, road=RoadProfile.flat(), oil=oil)
        self.timeout_ns = int(round(input_timeout_s * 1e9))
        self.speed = 0.0
        self.steering = 0.0
        self.accel = 0.0
        self.wheel_heights: np.ndarray | None = None
        self.damper_command: np.ndarray | None = None  # the held valve command (None: passive damper)
        self.road: RoadProfile | None = None
        self._last_speed_t: int | None = None
        self.last_input_ns: dict[str, int] = {}
        self.max_jump_ns = int(round(max_time_jump_s * 1e9))
        self.rejections: Counter[str] = Counter()
        self.rejections_by_topic: Counter[tuple[str, str]] = Counter()
        self.last_rejection = ""
        self.last_cause: tuple[str, str] | None = None  # (topic, cause) of the last rejection
        self.on_reject: Callable[[tuple[str, str], str], object] | None = None  # e.g. a RateLimitedLog
        self.accel_clamped = 0
        self.time_jumps = 0
        self.diverged = ""  # why the divergence guard stopped the core ("" while healthy)
        self.diverged_at_ns: int | None = None
        self.t_start_ns: int | None = None
        self.t_ns: int | None = None
        self.next_tick_ns = 0
        self.steps_done = 0
        self.samples_out = 0
        self.total_steps = 0  # over the whole life, across restarts
        self.restarts = 0
        self._command_stale = False

    # -- state ----------------------------------------------------------------------------------------
    @property
    def started(self) -> bool:
        return self.t_start_ns is not None

    @property
    def healthy(self) -> bool:
        return self.stepper.healthy and not self.diverged

    @property
    def oil(self) -> np.ndarray:
        return self.stepper.oil

    @property
    def sim_time_s(self) -> float:
        """Simulated time since the last (re)start [s]."""
        return self.steps_done * self.step_ns * 1e-9

    @property
    def total_sim_time_s(self) -> float:
        """Simulated time over the core's life, across restarts [s]."""
        return self.total_steps * self.step_ns * 1e-9

    def start(self, t_ns: int) -> None:
        """Fix the time origin (the first tick is one period later)."""
        self.t_start_ns = self.t_ns = int(t_ns)
        self.next_tick_ns = self.t_start_ns + self.period_ns
        self.steps_done = 0

    def reset(self) -> None:
        """Back to rest (e.g. time jumped backwards when a replay loops); inputs are kept, a divergence
        is cleared."""
        model, oil, road = self.model, self.stepper.oil, self.stepper.road
        semi = self.stepper.semi_active
        self.stepper = Stepper(model, dt=self.step_ns * 1e-9, road=road, oil=oil)
        if semi and self.damper_command is not None:
            self.stepper.set_semi_active(True, self.damper_command)
        self.t_start_ns = self.t_ns = None
        self.steps_done = 0
        self._last_speed_t = None
        self.accel = 0.0
        self.diverged, self.diverged_at_ns = "", None  # a fresh start from rest is healthy again

    # -- run-time parameter changes -------------------------------------------------------------------
    def set_oil(self, oil: Sequence[float] | np.ndarray) -> None:
        """New damper oil levels FL, FR, RL, RR; take effect at the next step (SuspInputError if bad)."""
        self.stepper.set_oil(check_oil(oil))

    def set_model(self, model: Model) -> None:
        """Switch vehicle/friction variant while running; states carry over (Stepper.set_model)."""
        self.stepper.set_model(model)
        self.model = model

    # -- inputs ---------------------------------------------------------------------------------------
    def reject(self, topic: str, cause: str, reason: str, detail: str | None = None) -> str:
        """Count a rejected message of ``topic`` under ``cause`` (:attr:`rejections`) and under
        ``(topic, detail or cause)`` (:attr:`rejections_by_topic`, the key the node logs once per
        interval) and pass it to :attr:`on_reject` (the node's rate-limited log); returns ``reason``."""
        key = (topic, detail or cause)
        self.rejections[cause] += 1
        self.rejections_by_topic[key] += 1
        self.last_rejection = reason
        self.last_cause = key
        if self.on_reject is not None:
            self.on_reject(key, reason)
        return reason

    def _reject(self, cause: str, reason: str, detail: str | None = None) -> str:
        return self.reject(reason.split(":", 1)[0], cause, reason, detail)

    def set_speed(self, t_ns: int, v: float) -> str | None:
        v = float(v)
        if not math.isfinite(v):
            return self._reject("non_finite", f"/vehicle/speed: rejected non-finite value {v}")
        if v < 0:
            return self._reject("speed_negative", f"/vehicle/speed: rejected negative speed {v} m/s")
        if v > MAX_SPEED:
            return self._reject("speed_range", f"/vehicle/speed: rejected absurd speed {v} m/s (> {MAX_SPEED})")
        t_ns = int(t_ns)
        step = accel_between(self._last_speed_t, self.speed, t_ns, v)
        if step is not None:
            self.accel, clamped = step
            self.accel_clamped += clamped
        self._last_speed_t = t_ns
        self.speed = v
        self.last_input_ns["/vehicle/speed"] = t_ns
        return None

    def set_steering(self, t_ns: int, angle: float) -> str | None:
        a = float(angle)
        if not math.isfinite(a):
            return self._reject("non_finite", f"/vehicle/steering_wheel_angle: rejected non-finite value {a}")
        if abs(a) > MAX_STEERING:
            return self._reject("steering_range", f"/vehicle/steering_wheel_angle: rejected {a} rad "
                                                  f"(|angle| > {MAX_STEERING / math.pi:g} pi = "
                                                  f"{MAX_STEERING:.4g} rad)")
        self.steering = a
        self.last_input_ns["/vehicle/steering_wheel_angle"] = int(t_ns)
        return None

    def set_road_profile(self, t_ns: int, data: Sequence[float] | np.ndarray, dims: Sequence[tuple],
                         data_offset: int = 0) -> str | None:
        """``/road/profile`` from its data and layout dims ``[(label, size[, stride]), ...]`` (interface
        layout; a stride of 0 means "not given"); ``data_offset`` as in ``MultiArrayLayout``."""
        try:
            if len(dims) != 2 or int(dims[0][1]) != 3:
                raise SuspInputError(f"expected layout dims [channel 3, sample N], got {[tuple(d) for d in dims]}")
            if str(dims[0][0]) == "sample" and str(dims[1][0]) == "channel":
                raise SuspInputError("layout dims are swapped (sample before channel); the interface "
                                     "layout is [channel 3, sample N]")
            n = int(dims[1][1])
            if n < 2 or n > MAX_PROFILE_SAMPLES:
                raise SuspInputError(f"need 2 to {MAX_PROFILE_SAMPLES} samples, got {n}")
            strides = [int(d[2]) if len(d) > 2 else 0 for d in dims]
            if (strides[0] and strides[0] != 3 * n) or (strides[1] and strides[1] != n):
                raise SuspInputError(f"layout strides {strides} do not fit [channel 3, sample {n}] "
                                     f"(want [{3 * n}, {n}])")
            off = int(data_offset)
            if off < 0 or len(data) != off + 3 * n:
                raise SuspInputError(f"expected 3*{n} = {3 * n} values after data_offset {off}, got "
                                     f"{len(data) - off}")
            arr = np.asarray(data, dtype=float)[off:]
            road = RoadProfile.from_flat_array(arr, n)
            if np.abs(road.s).max() > MAX_PATH:
                raise SuspInputError(f"path coordinate beyond +-{MAX_PATH:g} m")
            if max(np.abs(road.zl).max(), np.abs(road.zr).max()) > MAX_WHEEL_HEIGHT:
                raise SuspInputError(f"elevation beyond +-{MAX_WHEEL_HEIGHT:g} m")
        except (SuspInputError, ValueError, TypeError, OverflowError, IndexError) as exc:
            text = str(exc)
            detail = ("non_increasing" if "strictly increasing" in text else
                      "non_finite" if "finite" in text else
                      "range" if "beyond" in text else "layout")
            return self._reject("road_profile", f"/road/profile: rejected: {exc}", detail)
        self.road = road
        if self.wheel_heights is None:
            self.stepper.set_road(road)
        self.last_input_ns["/road/profile"] = int(t_ns)
        return None

    def set_wheel_heights(self, t_ns: int, z: Sequence[float] | np.ndarray, dims: Sequence[tuple] = (),
                          data_offset: int = 0) -> str | None:
        """``/road/wheel_heights``: data [FL, FR, RL, RR] (after ``data_offset``); layout dims, if given,
        must describe 4 values."""
        sizes = [int(d[1]) for d in dims]
        if sizes and int(np.prod(sizes, dtype=np.int64)) != 4:
            return self._reject("wheel_heights", f"/road/wheel_heights: rejected: layout dims {sizes} do not "
                                                 f"describe 4 values [FL, FR, RL, RR]", "layout")
        off = int(data_offset)
        arr = np.asarray(z, dtype=float)[max(off, 0):]
        if off < 0 or arr.shape != (4,):
            return self._reject("wheel_heights", f"/road/wheel_heights: rejected: expected 4 values "
                                                 f"[FL, FR, RL, RR], got {arr.size}", "count")
        if not np.all(np.isfinite(arr)):
            return self._reject("non_finite", "/road/wheel_heights: rejected non-finite value")
        if np.any(np.abs(arr) > MAX_WHEEL_HEIGHT):
            return self._reject("wheel_heights", f"/road/wheel_heights: rejected absurd heights {arr.tolist()} m "
                                                 f"(beyond +-{MAX_WHEEL_HEIGHT:g} m)", "range")
        if self.wheel_heights is None:
            self.stepper.set_road(None)  # per-wheel heights override the profile from now on
        self.wheel_heights = arr
        self.last_input_ns["/road/wheel_heights"] = int(t_ns)
        return None

    def set_damper_command(self, t_ns: int, u: Sequence[float] | np.ndarray, dims: Sequence[tuple] = (),
                           data_offset: int = 0) -> str | None:
        """``/vehicle/damper_command``: data [FL, FR, RL, RR] valve commands in [0, 1] (after
        ``data_offset``); layout dims, if given, must describe 4 values. The first valid command switches
        the dampers to the semi-active family."""
        topic = DAMPER_COMMAND
        try:
            sizes = [int(d[1]) for d in dims]
            off = int(data_offset)
            arr = np.asarray(u, dtype=float)[max(off, 0):]
        except (ValueError, TypeError, IndexError, OverflowError) as exc:
            return self._reject("damper_command", f"{topic}: rejected: {exc}", "layout")
        if sizes and int(np.prod(sizes, dtype=np.int64)) != 4:
            return self._reject("damper_command", f"{topic}: rejected: layout dims {sizes} do not describe 4 "
                                                  f"values [FL, FR, RL, RR]", "layout")
        if off < 0 or arr.shape != (4,):
            return self._reject("damper_command", f"{topic}: rejected: expected 4 values [FL, FR, RL, RR], "
                                                  f"got {arr.size}", "count")
        if not np.all(np.isfinite(arr)):
            return self._reject("non_finite", f"{topic}: rejected non-finite value")
        if np.any(arr < 0.0) or np.any(arr > 1.0):
            return self._reject("damper_command", f"{topic}: rejected {arr.tolist()}: commands must be in "
                                                  f"[0, 1] (0 softest, 1 hardest)", "range")
        self.damper_command = arr
        self._command_stale = False
        if not self.stepper.semi_active:
            self.stepper.set_semi_active(True, arr)
        self.last_input_ns[topic] = int(t_ns)
        return None

    def _check_command_fresh(self, t_ns: int) -> None:
        """Back to the passive damper when the command went stale (module docstring)."""
        last = self.last_input_ns.get(DAMPER_COMMAND)
        if self.damper_command is None or last is None or t_ns - last <= self.timeout_ns:
            return
        if not self._command_stale:
            self._command_stale = True
            self.reject(DAMPER_COMMAND, "damper_command_stale",
                        f"{DAMPER_COMMAND}: no command for {(t_ns - last) * 1e-9:.3f} s (> input_timeout_s "
                        f"{self.timeout_ns * 1e-9:g} s): dampers back to the passive curve", "stale")
        self.damper_command = None
        self.stepper.set_semi_active(False)

    def stale_inputs(self, t_ns: int) -> list[str]:
        """Input topics that have not been refreshed for ``input_timeout_s`` (never-seen speed/steering
        count as stale once the core has run longer than the timeout). The latched road profile never
        goes stale."""
        out = []
        for topic in ("/vehicle/speed", "/vehicle/steering_wheel_angle", "/road/wheel_heights", DAMPER_COMMAND):
            last = self.last_input_ns.get(topic)
            if last is None:
                if topic not in ("/road/wheel_heights", DAMPER_COMMAND) and self.t_start_ns is not None \
                        and t_ns - self.t_start_ns > self.timeout_ns:
                    out.append(topic)
            elif t_ns - last > self.timeout_ns:
                out.append(topic)
        return out

    # -- stepping -------------------------------------------------------------------------------------
    def _step_until(self, t_ns: int) -> bool:
        """Step to ``t_ns``; False (and :attr:`diverged` set) if the state left the envelope."""
        t0 = self.t_start_ns
        assert t0 is not None, "stepping before the core started"
        target = (t_ns - t0) // self.step_ns
        n = target - self.steps_done
        if n > 0:
            self._check_command_fresh(t_ns)
            y = self.stepper.advance(int(n), self.speed, self.steering, self.accel, self.wheel_heights,
                                     self.damper_command)
            self.steps_done = target
            self.total_steps += int(n)
            if not self.stepper.healthy or not bool(np.all(np.abs(y) <= OUTPUT_ENVELOPE)):
                self._diverge(t_ns, y)
                return False
        return True

    def _diverge(self, t_ns: int, y: np.ndarray) -> None:
        bad = [f"{OUTPUT_LABELS[k]}={y[k]:.6g}" for k in np.nonzero(~(np.abs(y) <= OUTPUT_ENVELOPE))[0][:6]]
        self.diverged = (f"simulation diverged at t = {t_ns * 1e-9:.3f} s (sim time {self.sim_time_s:.3f} s): "
                         + (", ".join(bad) if bad else "non-finite state")
                         + f"; inputs speed {self.speed:g} m/s, steering {self.steering:g} rad, "
                           f"accel {self.accel:g} m/s^2; stepping stopped")
        self.diverged_at_ns = int(t_ns)

    def advance_to(self, t_ns: int, *, allow_restart: bool = True) -> list[Sample]:
        """Step to ROS time ``t_ns`` with the held inputs; the samples of the publish ticks passed.

        The first call only fixes the time origin. Time going backwards by more than
        ``STALE_CLOCK_NS`` restarts the core from rest at ``t_ns`` (a looped replay) when
        ``allow_restart``; a smaller step back is a stale reading and ignored (counted as a ``/clock``
        rejection when ``allow_restart``); without ``allow_restart`` any step back is a no-op (wall time:
        a callback that read the clock just before another one stepped further; a clock adjustment). A
        jump forward by more than ``max_time_jump_s`` is not stepped through (module docstring). After a
        divergence nothing is stepped or returned any more (the time is still followed) until a restart.
        """
        t_ns = int(t_ns)
        if self.t_start_ns is None or self.t_ns is None:
            self.start(t_ns)
            return []
        if t_ns < self.t_ns:
            if not allow_restart:
                return []
            if self.t_ns - t_ns <= STALE_CLOCK_NS:
                self.reject("/clock", "clock_stale", f"/clock: ignored a stale time {t_ns * 1e-9:.9f} s "
                            f"({(self.t_ns - t_ns) * 1e-6:.3f} ms behind the simulation)")
                return []
            self.reset()
            self.start(t_ns)
            self.restarts += 1
            return []
        if self.diverged:  # stopped: follow the time (a later restart is measured from here), step nothing
            self.t_ns = t_ns
            return []
        if t_ns - self.t_ns > self.max_jump_ns:
            self.time_jumps += 1
            self.reject("/clock", "time_jump", f"time jumped forward by {(t_ns - self.t_ns) * 1e-9:.3f} s "
                        f"(> max_time_jump_s {self.max_jump_ns * 1e-9:g} s): not stepped through, the "
                        f"simulation continues from {t_ns * 1e-9:.3f} s with its state held")
            self.t_start_ns = t_ns - self.steps_done * self.step_ns
            self.t_ns = t_ns
            self.next_tick_ns = t_ns + self.period_ns
            return []
        out = []
        while self.next_tick_ns <= t_ns:
            if not self._step_until(self.next_tick_ns):
                break
            out.append(Sample(self.next_tick_ns, self.stepper.y.copy()))
            self.next_tick_ns += self.period_ns
        else:
            self._step_until(t_ns)
        self.t_ns = t_ns
        self.samples_out += len(out)
        return out


__all__ = ["SimCore", "Sample", "sample_messages", "DAMPER_COMMAND", "SIM_IMU", "SIM_ODOM", "SIM_SUSPENSION",
           "DIAGNOSTICS",
           "MAX_STEERING", "MAX_SPEED", "MAX_WHEEL_HEIGHT", "MAX_ACCEL", "OUTPUT_ENVELOPE", "RateLimitedLog",
           "DivergenceError", "STALE_CLOCK_NS"]
