"""Reference semi-active damper controllers: skyhook (two-state and continuous), groundhook, ADD and the
mixed skyhook-ADD. Parameters in ``config/semiactive.yaml`` (``controllers``), each with its source.

Every controller sees what a car's sensors give and the node publishes (``/sim/imu/data`` at the centre
of gravity, ``/sim/suspension``): the vertical specific force and roll/pitch rates of the body, and per
corner the suspension deflection and its rate (:class:`Measurement`). A :class:`BodyEstimator` turns
them into the body's vertical velocity and acceleration over each corner (a leaky integrator of the
vertical acceleration, REP-103 axes; corner height ``z - x theta + y phi`` as in the kernel). A
controller returns the valve command in [0, 1] per corner (FL, FR, RL, RR); continuous controllers
invert the damper map (soft and hard curves of the family) to get the command that gives the force
they want, which the valve can only approximate (the force must have the sign of the deflection rate).

Signs: deflection ``d`` positive in bump (wheel towards body), ``dd`` its rate; the damper force on
the body is positive upwards and has the sign of ``dd``. With body velocity ``vb`` (up) at a corner and
wheel velocity ``vw = vb + dd``:

- skyhook wants ``F = -c_sky vb`` (Karnopp et al. 1974): two-state: hard when ``vb dd < 0``;
- groundhook wants the wheel force ``-c_gnd vw``, i.e. ``F = c_gnd vw`` on the body (Valasek et al. 1997);
- ADD: hard when ``ab dd < 0`` (body acceleration ``ab``; Savaresi et al. 2005);
- SH-ADD: the skyhook rule where ``ab^2 <= alpha^2 vb^2``, the ADD rule elsewhere (Savaresi, Spelta 2007).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from collections.abc import Callable

import numpy as np

from ..errors import ConfigError, SuspInputError
from ..model.params import CORNER_AXLE, VehicleParams
from ..model.semiactive import DamperFamily, axle_pair, number, semiactive_config

CONTROLLERS = ("passive", "skyhook", "skyhook_onoff", "groundhook", "add", "sh_add")


@dataclass(frozen=True)
class ControllerParams:
    """Controller constants (config ``controllers``): rate [s], filter corners [Hz], gains per corner."""

    sample_time: float
    velocity_corner: float
    acceleration_corner: float
    skyhook_gain: np.ndarray    # N s/m, FL FR RL RR
    groundhook_gain: np.ndarray  # N s/m
    add_gain: np.ndarray        # kg (unused by the two-state ADD rule; kept for a continuous variant)
    sh_add_alpha: float         # rad/s
    deadband: float             # m/s


def load_controller_params(path: str | Path | None = None) -> ControllerParams:
    path, data = semiactive_config(path)
    sec = "controllers"
    corners = lambda k: np.array([axle_pair(path, data, sec, k)[a] for a in CORNER_AXLE])  # noqa: E731
    p = ControllerParams(
        sample_time=number(path, data, sec, "sample_time", positive=True),
        velocity_corner=number(path, data, sec, "velocity_estimate_corner", positive=True),
        acceleration_corner=number(path, data, sec, "acceleration_filter_corner", positive=True),
        skyhook_gain=corners("skyhook_gain"), groundhook_gain=corners("groundhook_gain"),
        add_gain=corners("add_gain"), sh_add_alpha=number(path, data, sec, "sh_add_alpha"),
        deadband=number(path, data, sec, "deadband"))
    if p.sample_time > 0.1:
        raise ConfigError(f"{path}: controllers.sample_time: expected at most 0.1 s, got {p.sample_time}")
    return p


@dataclass
class Measurement:
    """One sensor sample: vertical specific force ``az_sf`` [m/s^2] (gravity included) and roll/pitch
    rates [rad/s] of the body at the centre of gravity; per corner FL, FR, RL, RR the suspension
    deflection ``defl`` [m] (bump positive) and its rate ``defl_vel`` [m/s]."""

    az_sf: float
    roll_rate: float
    pitch_rate: float
    defl: np.ndarray
    defl_vel: np.ndarray


class BodyEstimator:
    """Body vertical velocity and acceleration over each corner from :class:`Measurement` samples."""

    def __init__(self, vehicle: VehicleParams, params: ControllerParams):
        tf, tr = vehicle.track
        self.x = np.array([vehicle.a, vehicle.a, -vehicle.b, -vehicle.b])
        self.y = np.array([tf / 2, -tf / 2, tr / 2, -tr / 2])
        self.g, self.dt = vehicle.gravity, params.sample_time
        self.k_v = 2.0 * math.pi * params.velocity_corner
        self.k_a = -math.expm1(-2.0 * math.pi * params.acceleration_corner * params.sample_time)
        self.zd = 0.0
        self.a = np.zeros(4)
        self._rates: tuple[float, float] | None = None

    def update(self, m: Measurement) -> tuple[np.ndarray, np.ndarray]:
        """(body velocity [m/s], filtered body acceleration [m/s^2]) over each corner, up positive."""
        zdd = m.az_sf - self.g
        self.zd += self.dt * (zdd - self.k_v * self.zd)   # leaky integrator: drift-free heave velocity
        if self._rates is None:
            self._rates = (m.roll_rate, m.pitch_rate)
        phidd = (m.roll_rate - self._rates[0]) / self.dt
        thdd = (m.pitch_rate - self._rates[1]) / self.dt
        self._rates = (m.roll_rate, m.pitch_rate)
        vb = self.zd - self.x * m.pitch_rate + self.y * m.roll_rate
        self.a += self.k_a * ((zdd - self.x * thdd + self.y * phidd) - self.a)
        return vb, self.a.copy()


class DamperMap:
    """The controller's map of the valve: soft and hard force [N] (on the body) at a deflection rate, per
    corner, from the damper family's curves (as measured, friction included: what an ECU would hold)."""

    def __init__(self, family: DamperFamily):
        v = np.asarray(family.velocity)
        self.v = v
        self.soft = [np.asarray(family.soft[a]) for a in CORNER_AXLE]
        self.hard = [np.asarray(family.hard[a]) for a in CORNER_AXLE]

    def command_for(self, force: np.ndarray, dd: np.ndarray) -> np.ndarray:
        """Valve command in [0, 1] whose force at ``dd`` [m/s] is nearest ``force`` [N] per corner."""
        u = np.zeros(4)
        for i in range(4):
            fs = float(np.interp(dd[i], self.v, self.soft[i]))
            fh = float(np.interp(dd[i], self.v, self.hard[i]))
            span = fh - fs
            if abs(span) > 1e-9:
                u[i] = (force[i] - fs) / span
        return np.clip(u, 0.0, 1.0)


class Controller:
    """Base: ``controller(measurement) -> command [4]`` (``None`` for the passive damper)."""

    name = "passive"

    def __init__(self, vehicle: VehicleParams, family: DamperFamily, params: ControllerParams):
        self.params = params
        self.est = BodyEstimator(vehicle, params)
        self.map = DamperMap(family)

    def __call__(self, m: Measurement) -> np.ndarray | None:
        vb, ab = self.est.update(m)
        dd = np.asarray(m.defl_vel, float)
        moving = np.abs(dd) > self.params.deadband
        return np.where(moving, self.law(vb, ab, dd), 0.0)

    def law(self, vb, ab, dd) -> np.ndarray:
        raise NotImplementedError


class Passive(Controller):
    def __call__(self, m):
        return None


class Skyhook(Controller):
    """Continuous skyhook: force -c_sky vb where the valve can give it."""
    name = "skyhook"

    def law(self, vb, ab, dd):
        return self.map.command_for(-self.params.skyhook_gain * vb, dd)


class SkyhookOnOff(Controller):
    """Two-state skyhook: hard when vb dd < 0."""
    name = "skyhook_onoff"

    def law(self, vb, ab, dd):
        return (vb * dd < 0.0).astype(float)


class Groundhook(Controller):
    """Continuous groundhook: wheel force -c_gnd vw, i.e. c_gnd (vb + dd) on the body."""
    name = "groundhook"

    def law(self, vb, ab, dd):
        return self.map.command_for(self.params.groundhook_gain * (vb + dd), dd)


class Add(Controller):
    """Acceleration-driven damping (two-state): hard when ab dd < 0."""
    name = "add"

    def law(self, vb, ab, dd):
        return (ab * dd < 0.0).astype(float)


class SkyhookAdd(Controller):
    """Mixed SH-ADD: skyhook where ab^2 <= alpha^2 vb^2, ADD elsewhere (two-state)."""
    name = "sh_add"

    def law(self, vb, ab, dd):
        sky = ab * ab - (self.params.sh_add_alpha * vb) ** 2 <= 0.0
        return np.where(sky, vb * dd < 0.0, ab * dd < 0.0).astype(float)


_CLASSES: dict[str, Callable[..., Controller]] = {
    "passive": Passive, "skyhook": Skyhook, "skyhook_onoff": SkyhookOnOff, "groundhook": Groundhook,
    "add": Add, "sh_add": SkyhookAdd}


def make_controller(name: str, vehicle: VehicleParams, family: DamperFamily,
                    params: ControllerParams | None = None) -> Controller:
    """A fresh controller by name (:data:`CONTROLLERS`)."""
    if name not in _CLASSES:
        raise SuspInputError(f"--controller: unknown controller {name!r}; expected one of {', '.join(CONTROLLERS)}")
    return _CLASSES[name](vehicle, family, params or load_controller_params())


def measurement_from_outputs(y: np.ndarray, index: dict[str, int]) -> Measurement:
    """A :class:`Measurement` from a full output vector (``index``: label -> column)."""
    return Measurement(float(y[index["AZ_SF"]]), float(y[index["ROLL_RATE"]]), float(y[index["PITCH_RATE"]]),
                       y[[index[f"DEFL_{w}"] for w in ("FL", "FR", "RL", "RR")]],
                       y[[index[f"DEFL_VEL_{w}"] for w in ("FL", "FR", "RL", "RR")]])


__all__ = ["CONTROLLERS", "ControllerParams", "Measurement", "BodyEstimator", "DamperMap", "Controller",
           "load_controller_params", "make_controller", "measurement_from_outputs"]
