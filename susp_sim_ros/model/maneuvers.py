"""The paper's validation maneuvers and vehicle states (model-spec 4; values in config/maneuvers.yaml).

A :class:`Maneuver` is what a test drive feeds the model: speed and steering-wheel angle over time and
a road profile. ``to_inputs(dt)`` samples it on the model's step.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import yaml

from ..errors import ConfigError
from .params import config_dir, load_vehicle
from .road import RoadProfile, cosine_bump
from .vehicle import make_inputs
from .paper import (BUMP_CROSSING, MANEUVERS, SINE_STEER, STATES,  # noqa: F401  (MANEUVERS, STATES re-exported)
                    ManeuverKind, maneuver_kind)



def _maneuver_config(path: Path | None = None) -> dict:
    path = path or config_dir() / "maneuvers.yaml"
    try:
        data = yaml.safe_load(path.read_text())
    except (OSError, yaml.YAMLError) as exc:
        raise ConfigError(f"{path}: cannot read maneuver config: {exc}") from None
    return data


def _value(cfg: dict, section: str, key: str, path="config/maneuvers.yaml"):
    try:
        return cfg[section][key]["value"]
    except (KeyError, TypeError):
        raise ConfigError(f"{path}: missing {section}.{key}.value") from None


def _arguments(kind: ManeuverKind, given: dict) -> dict[str, float]:
    """The factory keywords of ``kind`` (its ``config_keys``, in order): each given value, else its default
    from ``config/maneuvers.yaml``."""
    cfg = _maneuver_config()
    return {kw: float(given[kw] if given[kw] is not None else _value(cfg, kind.config_section, key))
            for kw, key in kind.config_keys}


def maneuver_defaults(name: str) -> dict[str, float]:
    """The default values of a maneuver's factory keywords (name or alias; ``config/maneuvers.yaml``)."""
    kind = maneuver_kind(name)
    return _arguments(kind, {kw: None for kw, _ in kind.config_keys})


def vehicle_state(name: str) -> tuple[float, float, float, float]:
    """Oil levels FL, FR, RL, RR of a named vehicle state (intact, front_empty, rear_empty)."""
    cfg = _maneuver_config()
    if name not in cfg.get("states", {}):
        raise ConfigError(f"unknown vehicle state {name!r}: expected one of {', '.join(cfg['states'])}")
    oil = tuple(float(x) for x in cfg["states"][name]["value"])
    if len(oil) != 4:
        raise ConfigError(f"maneuvers.yaml: states.{name}: expected four oil levels FL, FR, RL, RR, got {oil}")
    return oil[0], oil[1], oil[2], oil[3]


@dataclass(frozen=True)
class Maneuver:
    """A drive: ``name``, duration [s], speed(t) [m/s] and steering-wheel angle(t) [rad], road."""

    name: str
    duration: float
    speed: float
    road: RoadProfile
    steer_amplitude: float = 0.0
    steer_frequency: float = 0.0
    steer_start: float = 0.0
    steer_periods: float = 0.0

    def steering(self, t: np.ndarray) -> np.ndarray:
        tt = np.asarray(t, float) - self.steer_start
        on = (tt >= 0) & (tt <= self.steer_periods / max(self.steer_frequency, 1e-300))
        return np.where(on, self.steer_amplitude * np.sin(2 * np.pi * self.steer_frequency * tt), 0.0)

    def speed_at(self, t: np.ndarray) -> np.ndarray:
        return np.full(np.shape(t), self.speed)

    def n_steps(self, dt: float) -> int:
        return int(round(self.duration / dt))

    def to_inputs(self, dt: float) -> np.ndarray:
        """Per-step inputs; step k uses the inputs at time k*dt (zero-order hold)."""
        t = dt * np.arange(self.n_steps(dt))
        v = self.speed_at(t)
        return make_inputs(t.size, v, self.steering(t), np.gradient(v, dt) if t.size > 1 else 0.0)

    def mirrored(self) -> "Maneuver":
        return replace(self, steer_amplitude=-self.steer_amplitude, road=self.road.mirrored())


def reference_wheelbase() -> float:
    """Wheelbase [m] of the reference vehicle (``config/vehicles/passat_b8_like.yaml``, its
    ``cg_to_front_axle + cg_to_rear_axle``): the maneuvers' length when no vehicle is given."""
    return load_vehicle().wheelbase


def bump_crossing(*, speed=None, height=None, length=None, start=None, settle_time=None,
                  wheelbase: float | None = None) -> Maneuver:
    """Slow crossing of a single cosine bump on both tracks; lasts until ``settle_time`` after the rear
    axle has left the bump. ``wheelbase`` [m]: the simulated vehicle's (``model.vehicle.wheelbase``);
    default :func:`reference_wheelbase`."""
    if wheelbase is None:
        wheelbase = reference_wheelbase()
    v = _arguments(BUMP_CROSSING, dict(speed=speed, height=height, length=length, start=start,
                                       settle_time=settle_time))
    duration = (v["start"] + v["length"] + wheelbase) / v["speed"] + v["settle_time"]
    return Maneuver(BUMP_CROSSING.name, duration, v["speed"], cosine_bump(v["height"], v["length"], v["start"]))


def sine_steer(*, speed=None, amplitude=None, frequency=None, periods=None, lead_time=None,
               settle_time=None, duration=None) -> Maneuver:
    """Sinusoidal steering at constant speed on a flat road (``duration`` overrides the length)."""
    v = _arguments(SINE_STEER, dict(speed=speed, amplitude=amplitude, frequency=frequency, periods=periods,
                                    lead_time=lead_time, settle_time=settle_time))
    freq, periods, lead = v["frequency"], v["periods"], v["lead_time"]
    if freq <= 0 or periods <= 0:
        raise ConfigError(f"{SINE_STEER.name}: frequency and periods must be > 0, got {freq}, {periods}")
    total = duration if duration is not None else lead + periods / freq + v["settle_time"]
    return Maneuver(SINE_STEER.name, total, v["speed"], RoadProfile.flat(), v["amplitude"], freq, lead, periods)


def paper_maneuver(name: str, wheelbase: float | None = None) -> Maneuver:
    """``bump_crossing`` (``bump``) or ``sine_steer`` (``sine``) with the values of
    ``config/maneuvers.yaml``; ``wheelbase`` [m] as for :func:`bump_crossing`."""
    return build_maneuver(name, wheelbase)


def build_maneuver(name: str, wheelbase: float | None = None, **overrides) -> Maneuver:
    """The maneuver of a registry name or alias (``model/paper.py`` ``MANEUVER_KINDS``), built by its
    ``factory`` with ``overrides`` (the factory's keywords; ``None`` keeps the config value) and, when the
    kind uses it, ``wheelbase``."""
    kind = maneuver_kind(name)
    factory = globals()[kind.factory]
    if kind.uses_wheelbase:
        overrides["wheelbase"] = wheelbase
    return factory(**overrides)


def excitation_end(man: Maneuver, wheelbase: float) -> float:
    """When the excitation of a paper maneuver is over [s]: the rear axle has left the road profile (a
    kind that ``needs_road_profile``) or the last steer has ended."""
    if maneuver_kind(man.name).needs_road_profile:
        return (float(man.road.s[-1]) + wheelbase) / man.speed
    return man.steer_start + man.steer_periods / man.steer_frequency
