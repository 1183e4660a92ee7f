"""The semi-active damper's curve family and valve lag, loaded from ``config/semiactive.yaml``.

A continuously variable damper has a valve whose command ``u`` in [0, 1] (0 softest, 1 hardest) selects
a force-velocity curve between a soft and a hard end curve; the kernel blends linearly between them and
lets the valve follow the command with a first-order lag (time constant ``valve_time_constant``). The
oil level scales the intact family against the oil-empty curve exactly as for the passive damper
(model-spec 1). Curves are given as measured (with the damper friction, like the vehicle file's
``dampers``) and turned into hydraulic curves by :func:`~.vehicle.hydraulic_from_measured`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from ..errors import ConfigError
from .params import AXLES, _load_yaml, config_dir


@dataclass(frozen=True)
class DamperFamily:
    """Soft and hard measured curves (front, rear) [N] at ``velocity`` [m/s]; valve lag [s]."""

    velocity: tuple[float, ...]
    soft: tuple[tuple[float, ...], tuple[float, ...]]
    hard: tuple[tuple[float, ...], tuple[float, ...]]
    valve_time_constant: float
    source_file: str = ""


def semiactive_config(path: str | Path | None = None) -> tuple[Path, dict]:
    path = Path(path) if path is not None else config_dir() / "semiactive.yaml"
    if not path.is_file():
        raise ConfigError(f"{path}: no such semi-active config file")
    return path, _load_yaml(path)


def entry(path: Path, data: dict, section: str, key: str) -> dict:
    """``section.key`` of a config mapping, checked to hold value, unit and source."""
    e = (data.get(section) or {}).get(key)
    if not isinstance(e, dict) or not {"value", "unit", "source"} <= set(e):
        raise ConfigError(f"{path}: {section}.{key} must be a mapping with value, unit and source")
    return e


def number(path: Path, data: dict, section: str, key: str, *, positive: bool = False) -> float:
    v = entry(path, data, section, key)["value"]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or (positive and v <= 0):
        raise ConfigError(f"{path}: {section}.{key} must be a finite{' positive' if positive else ''} "
                          f"number, got {v!r}")
    return float(v)


def axle_pair(path: Path, data: dict, section: str, key: str) -> tuple[float, float]:
    v = entry(path, data, section, key)["value"]
    if not isinstance(v, dict) or set(v) != set(AXLES):
        raise ConfigError(f"{path}: {section}.{key}.value must be {{front: .., rear: ..}}, got {v!r}")
    out = []
    for a in AXLES:
        x = v[a]
        if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
            raise ConfigError(f"{path}: {section}.{key}.{a} must be a finite number, got {x!r}")
        out.append(float(x))
    return out[0], out[1]


def load_damper_family(path: str | Path | None = None) -> DamperFamily:
    """The damper family of ``config/semiactive.yaml`` (or ``path``), validated."""
    path, data = semiactive_config(path)
    sec = "damper_family"
    vel = entry(path, data, sec, "velocity")["value"]
    if not isinstance(vel, list) or len(vel) < 3 or any(b <= a for a, b in zip(vel, vel[1:])):
        raise ConfigError(f"{path}: {sec}.velocity must be a strictly increasing list of velocities [m/s]")
    curves: dict[str, tuple[tuple[float, ...], tuple[float, ...]]] = {}
    for name in ("soft", "hard"):
        v = entry(path, data, sec, name)["value"]
        if not isinstance(v, dict) or set(v) != set(AXLES):
            raise ConfigError(f"{path}: {sec}.{name}.value must be {{front: [..], rear: [..]}}")
        pair: list[tuple[float, ...]] = []
        for a in AXLES:
            row = v[a]
            if (not isinstance(row, list) or len(row) != len(vel)
                    or not all(isinstance(x, (int, float)) and math.isfinite(x) for x in row)):
                raise ConfigError(f"{path}: {sec}.{name}.{a} must be {len(vel)} finite forces [N]")
            if any((x > 0) != (s > 0) for x, s in zip(row, vel) if s != 0 and x != 0):
                raise ConfigError(f"{path}: {sec}.{name}.{a}: a damper force must have the sign of the velocity")
            pair.append(tuple(float(x) for x in row))
        curves[name] = (pair[0], pair[1])
    for k in range(2):
        if any(abs(s) > abs(h) for s, h in zip(curves["soft"][k], curves["hard"][k])):
            raise ConfigError(f"{path}: {sec}: the soft curve must not exceed the hard one ({AXLES[k]})")
    tau = number(path, data, sec, "valve_time_constant", positive=True)
    if tau > 1.0:
        raise ConfigError(f"{path}: {sec}.valve_time_constant: expected a valve lag below 1 s, got {tau} s")
    return DamperFamily(tuple(float(x) for x in vel), curves["soft"], curves["hard"], tau, str(path))
