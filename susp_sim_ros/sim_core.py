"""The simulation core shared by the ROS 2 node and the offline lockstep runner (pure; no rclpy).

:class:`SimCore` holds the latest inputs (validated), steps the model's :class:`Stepper` exactly as far
as time moved and returns the output samples at the publish ticks it passed. Time is integer
nanoseconds of ROS time (wall or ``/clock``), so a replay at 10x speed yields the same samples as at 1x:
the caller only has to call :meth:`SimCore.advance_to` with the message time before applying an input.

Tick ``k`` (k >= 1) is at ``t_start + k * period``; the sample of a tick is the model output after the
last whole step at or before it. Inputs are zero-order held between messages; the longitudinal
acceleration is derived from successive speed messages and held as well.
"""
from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from .errors import SuspInputError
from .io import messages as M
from .model.road import RoadProfile
from .model.vehicle import Model, Stepper, check_oil

MAX_STEERING = 4.0 * math.pi  # rad, steering-wheel angle beyond which an input is absurd
MAX_SPEED = 100.0             # m/s
MAX_WHEEL_HEIGHT = 1.0        # m

#: Topic names of the interface (the node may be remapped; the core does not care).
SIM_IMU, SIM_ODOM, SIM_SUSPENSION, DIAGNOSTICS = "/sim/imu/data", "/sim/odom", "/sim/suspension", "/diagnostics"


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
                 oil: Sequence[float] = (1.0, 1.0, 1.0, 1.0), input_timeout_s: float = 0.5):
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
        self.road: RoadProfile | None = None
        self._last_speed_t: int | None = None
        self.last_input_ns: dict[str, int] = {}
        self.rejections: Counter[str] = Counter()
        self.last_rejection = ""
        self.t_start_ns: int | None = None
        self.t_ns: int | None = None
        self.next_tick_ns = 0
        self.steps_done = 0
        self.samples_out = 0
        self.total_steps = 0  # over the whole life, across restarts
        self.restarts = 0

    # -- state ----------------------------------------------------------------------------------------
    @property
    def started(self) -> bool:
        return self.t_start_ns is not None

    @property
    def healthy(self) -> bool:
        return self.stepper.healthy

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
        """Back to rest (e.g. time jumped backwards when a replay loops); inputs are kept."""
        model, oil, road = self.model, self.stepper.oil, self.stepper.road
        self.stepper = Stepper(model, dt=self.step_ns * 1e-9, road=road, oil=oil)
        self.t_start_ns = self.t_ns = None
        self.steps_done = 0
        self._last_speed_t = None
        self.accel = 0.0

    # -- run-time parameter changes -------------------------------------------------------------------
    def set_oil(self, oil: Sequence[float]) -> None:
        """New damper oil levels FL, FR, RL, RR; take effect at the next step (SuspInputError if bad)."""
        self.stepper.set_oil(check_oil(oil))

    def set_model(self, model: Model) -> None:
        """Switch vehicle/friction variant while running; states carry over (Stepper.set_model)."""
        self.stepper.set_model(model)
        self.model = model

    # -- inputs ---------------------------------------------------------------------------------------
    def _reject(self, cause: str, reason: str) -> str:
        self.rejections[cause] += 1
        self.last_rejection = reason
        return reason

    def set_speed(self, t_ns: int, v: float) -> str | None:
        v = float(v)
        if not math.isfinite(v):
            return self._reject("non_finite", f"/vehicle/speed: rejected non-finite value {v}")
        if v < 0:
            return self._reject("speed_negative", f"/vehicle/speed: rejected negative speed {v} m/s")
        if v > MAX_SPEED:
            return self._reject("speed_range", f"/vehicle/speed: rejected absurd speed {v} m/s (> {MAX_SPEED})")
        t_ns = int(t_ns)
        if self._last_speed_t is not None and t_ns > self._last_speed_t:
            self.accel = (v - self.speed) / ((t_ns - self._last_speed_t) * 1e-9)
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
                                                  f"(|angle| > 4 pi)")
        self.steering = a
        self.last_input_ns["/vehicle/steering_wheel_angle"] = int(t_ns)
        return None

    def set_road_profile(self, t_ns: int, data: Sequence[float], dims: Sequence[tuple[str, int]]) -> str | None:
        """``/road/profile`` from its data and layout dims ``[(label, size), ...]`` (interface layout)."""
        try:
            arr = np.asarray(data, dtype=float)
            if len(dims) != 2 or int(dims[0][1]) != 3:
                raise SuspInputError(f"expected layout dims [channel 3, sample N], got {list(dims)}")
            n = int(dims[1][1])
            if n < 2:
                raise SuspInputError(f"need at least 2 samples, got {n}")
            road = RoadProfile.from_flat_array(arr, n)
        except (SuspInputError, ValueError, TypeError) as exc:
            return self._reject("road_profile", f"/road/profile: rejected: {exc}")
        self.road = road
        if self.wheel_heights is None:
            self.stepper.set_road(road)
        self.last_input_ns["/road/profile"] = int(t_ns)
        return None

    def set_wheel_heights(self, t_ns: int, z: Sequence[float]) -> str | None:
        arr = np.asarray(z, dtype=float)
        if arr.shape != (4,):
            return self._reject("wheel_heights", f"/road/wheel_heights: rejected: expected 4 values "
                                                 f"[FL, FR, RL, RR], got {arr.size}")
        if not np.all(np.isfinite(arr)):
            return self._reject("non_finite", "/road/wheel_heights: rejected non-finite value")
        if np.any(np.abs(arr) > MAX_WHEEL_HEIGHT):
            return self._reject("wheel_heights", f"/road/wheel_heights: rejected absurd heights {arr.tolist()} m")
        if self.wheel_heights is None:
            self.stepper.set_road(None)  # per-wheel heights override the profile from now on
        self.wheel_heights = arr
        self.last_input_ns["/road/wheel_heights"] = int(t_ns)
        return None

    def stale_inputs(self, t_ns: int) -> list[str]:
        """Input topics that have not been refreshed for ``input_timeout_s`` (never-seen speed/steering
        count as stale once the core has run longer than the timeout). The latched road profile never
        goes stale."""
        out = []
        for topic in ("/vehicle/speed", "/vehicle/steering_wheel_angle", "/road/wheel_heights"):
            last = self.last_input_ns.get(topic)
            if last is None:
                if topic != "/road/wheel_heights" and self.t_start_ns is not None \
                        and t_ns - self.t_start_ns > self.timeout_ns:
                    out.append(topic)
            elif t_ns - last > self.timeout_ns:
                out.append(topic)
        return out

    # -- stepping -------------------------------------------------------------------------------------
    def _step_until(self, t_ns: int) -> None:
        target = (t_ns - self.t_start_ns) // self.step_ns
        n = target - self.steps_done
        if n > 0:
            self.stepper.advance(int(n), self.speed, self.steering, self.accel, self.wheel_heights)
            self.steps_done = target
            self.total_steps += int(n)

    def advance_to(self, t_ns: int, *, allow_restart: bool = True) -> list[Sample]:
        """Step to ROS time ``t_ns`` with the held inputs; the samples of the publish ticks passed.

        The first call only fixes the time origin. Time going backwards restarts the core from rest at
        ``t_ns`` (a looped replay) when ``allow_restart``, else it is a no-op (wall time: a callback that
        read the clock just before another one stepped further; a clock adjustment).
        """
        t_ns = int(t_ns)
        if self.t_start_ns is None:
            self.start(t_ns)
            return []
        if t_ns < self.t_ns:
            if not allow_restart:
                return []
            self.reset()
            self.start(t_ns)
            self.restarts += 1
            return []
        out = []
        while self.next_tick_ns <= t_ns:
            self._step_until(self.next_tick_ns)
            out.append(Sample(self.next_tick_ns, self.stepper.y.copy()))
            self.next_tick_ns += self.period_ns
        self._step_until(t_ns)
        self.t_ns = t_ns
        self.samples_out += len(out)
        return out


__all__ = ["SimCore", "Sample", "sample_messages", "SIM_IMU", "SIM_ODOM", "SIM_SUSPENSION", "DIAGNOSTICS",
           "MAX_STEERING"]
