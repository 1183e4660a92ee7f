"""Vehicle parameter sets and friction variants, loaded from ``config/`` and validated on load.

A vehicle file (``config/vehicles/<name>.yaml``) holds every physical parameter as
``key: {value: ..., unit: ..., source: ...}``; ``value`` is a number, a ``{front: .., rear: ..}`` pair
(per wheel of that axle) or a list. Values are SI. A variant file (``config/variants/<name>.yaml``)
switches the paper's friction scalings and adds physics terms (:mod:`.terms`).

Errors name the file and the key and say what was expected (:class:`ConfigError`).
"""
from __future__ import annotations

import dataclasses
import importlib
import math
import os
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from collections.abc import Mapping

import numpy as np
import yaml

from ..errors import ConfigError
from .terms import PhysicsTerm, get_term

#: the parameter set used when none is named (config/vehicles/passat_b8_like.yaml: the paper's car)
DEFAULT_VEHICLE = "passat_b8_like"
AXLES = ("front", "rear")
CORNER_AXLE = (0, 0, 1, 1)  # FL, FR, RL, RR -> front, rear
CORNER_NAMES = ("FL", "FR", "RL", "RR")
#: axle -> its corners' indices (front: FL, FR; rear: RL, RR), from CORNER_AXLE
AXLE_CORNERS = {a: tuple(i for i, k in enumerate(CORNER_AXLE) if k == j) for j, a in enumerate(AXLES)}


def config_dir() -> Path:
    """The directory holding ``vehicles/``, ``variants/`` and ``studies/``.

    ``$SUSP_SIM_CONFIG`` if set; else the source checkout's ``config/`` (editable install or running
    from the tree); else ``<prefix>/share/susp_sim_ros/config`` (pip install, or a ROS 2 workspace via
    the ament index).
    """
    env = os.environ.get("SUSP_SIM_CONFIG")
    if env:
        return Path(env)
    tree = Path(__file__).resolve().parents[2] / "config"
    if (tree / "vehicles").is_dir():
        return tree
    share = Path(sys.prefix) / "share" / "susp_sim_ros" / "config"
    if share.is_dir():
        return share
    try:
        from ament_index_python.packages import get_package_share_directory
        return Path(get_package_share_directory("susp_sim_ros")) / "config"
    except Exception as exc:  # ament_index missing or package not indexed
        raise ConfigError(f"cannot find the susp_sim_ros config directory (looked in {tree} and "
                          f"{share}); set SUSP_SIM_CONFIG") from exc


def _resolve(kind: str, name_or_path: str | os.PathLike) -> Path:
    p = Path(name_or_path)
    # a path when it looks like one; a bare name is looked up in config/ even if a folder of that
    # name happens to exist in the working directory
    if p.suffix in (".yaml", ".yml") or len(p.parts) > 1 or p.is_file():
        if not p.is_file():
            raise ConfigError(f"{p}: no such {kind} file")
        return p
    cand = config_dir() / f"{kind}s" / f"{name_or_path}.yaml"
    if not cand.is_file():
        known = sorted(q.stem for q in (config_dir() / f"{kind}s").glob("*.yaml"))
        raise ConfigError(f"unknown {kind} {str(name_or_path)!r}: expected a YAML path or one of "
                          f"{', '.join(known)} (in {cand.parent})")
    return cand


def _load_yaml(path: Path) -> dict:
    try:
        data = yaml.safe_load(path.read_text())
    except yaml.YAMLError as exc:
        raise ConfigError(f"{path}: not valid YAML: {exc}") from None
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected a mapping at the top level, got {type(data).__name__}")
    return data


_SETTINGS_CACHE: dict[str, dict[str, Any]] = {}


def load_settings(file_name: str, path: str | os.PathLike | None = None) -> dict[str, Any]:
    """A settings table of ``config/`` (``file_name``, or ``path``) as ``{"section.key": value}``: every
    entry a mapping with ``value``, ``unit`` and ``source`` (as the vehicle files), read once per path;
    ConfigError naming the file and entry when malformed. The one loader of the analysis settings
    (``integrity.yaml``, ``missing_force.yaml``)."""
    p = Path(path) if path is not None else config_dir() / file_name
    key = str(p)
    if key in _SETTINGS_CACHE:
        return _SETTINGS_CACHE[key]
    if not p.is_file():
        raise ConfigError(f"{p}: no such settings file (expected {file_name})")
    data = _load_yaml(p)
    out: dict[str, Any] = {}
    for sec, entries in data.items():
        if not isinstance(entries, dict):
            raise ConfigError(f"{p}: section {sec} must be a mapping")
        for k, e in entries.items():
            if not isinstance(e, dict) or not {"value", "unit", "source"} <= set(e):
                raise ConfigError(f"{p}: {sec}.{k} must be a mapping with value, unit and source, got {e!r}")
            out[f"{sec}.{k}"] = e["value"]
    _SETTINGS_CACHE[key] = out
    return out


class _Reader:
    """Reads ``section.key`` entries of one vehicle file with checks and clear errors."""

    def __init__(self, path: Path, data: dict):
        self.path, self.data = path, data
        self.sources: dict[str, tuple[str, str]] = {}

    def _entry(self, section: str, key: str) -> dict:
        sec = self.data.get(section)
        if not isinstance(sec, dict) or key not in sec:
            raise ConfigError(f"{self.path}: missing parameter {section}.{key}")
        e = sec[key]
        if not isinstance(e, dict) or "value" not in e or "unit" not in e or "source" not in e:
            raise ConfigError(f"{self.path}: {section}.{key} must be a mapping with value, unit and "
                              f"source, got {e!r}")
        self.sources[f"{section}.{key}"] = (e["unit"], e["source"])
        return e

    def _num(self, section: str, key: str, x: Any, positive: bool, nonneg: bool) -> float:
        if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
            raise ConfigError(f"{self.path}: {section}.{key} must be a finite number, got {x!r}")
        if positive and x <= 0:
            raise ConfigError(f"{self.path}: {section}.{key} must be > 0, got {x}")
        if nonneg and x < 0:
            raise ConfigError(f"{self.path}: {section}.{key} must be >= 0, got {x}")
        return float(x)

    def scalar(self, section: str, key: str, positive=False, nonneg=False) -> float:
        return self._num(section, key, self._entry(section, key)["value"], positive, nonneg)

    def axle(self, section: str, key: str, positive=False, nonneg=False) -> tuple[float, float]:
        v = self._entry(section, key)["value"]
        if not isinstance(v, dict) or set(v) != set(AXLES):
            raise ConfigError(f"{self.path}: {section}.{key}.value must be {{front: .., rear: ..}}, got {v!r}")
        front, rear = (self._num(section, f"{key}.{a}", v[a], positive, nonneg) for a in AXLES)
        return front, rear

    def table(self, section: str, key: str, n: int | None = None) -> tuple:
        v = self._entry(section, key)["value"]
        if isinstance(v, dict):
            if set(v) != set(AXLES):
                raise ConfigError(f"{self.path}: {section}.{key}.value must be {{front: [..], rear: [..]}}")
            return tuple(self._list(section, f"{key}.{a}", v[a], n) for a in AXLES)
        return self._list(section, key, v, n)

    def _list(self, section, key, v, n):
        if not isinstance(v, list) or (n is not None and len(v) != n):
            raise ConfigError(f"{self.path}: {section}.{key} must be a list of {n or 'some'} numbers, "
                              f"got {v!r}")
        return tuple(self._num(section, key, x, False, False) for x in v)


@dataclass(frozen=True)
class VehicleParams:
    """A vehicle parameter set in SI units. Pairs are (front, rear), per wheel of that axle."""

    name: str
    gravity: float
    sprung_mass: float
    unsprung_mass: tuple[float, float]
    a: float
    b: float
    track: tuple[float, float]
    cg_height: float
    roll_inertia: float
    pitch_inertia: float
    yaw_inertia: float
    roll_centre_height: tuple[float, float]
    pitch_centre_height: float
    wheel_rate: tuple[float, float]
    bump_stop_travel: tuple[float, float]
    rebound_stop_travel: tuple[float, float]
    stop_rate: float
    stop_progression: float
    arb_rate: tuple[float, float]
    tyre_stiffness: float
    tyre_damping: float
    cornering_stiffness: tuple[float, float]
    mu: float
    relaxation_length: float
    slip_fade_speed: float
    #: dynamic rolling radius [m]: path / rolling_radius is the wheel's rotation angle [rad] (the discrepancy
    #: finder's input features, :mod:`susp_sim_ros.model.input_force`); the dynamics do not use it
    rolling_radius: float
    steering_ratio: float
    drive_front_share: float
    brake_front_share: float
    dahl_stiffness: float
    axle_friction: tuple[float, float]
    damper_friction_intact: tuple[float, float]
    damper_friction_empty: tuple[float, float]
    sv_reference: float
    sv_plateau: float
    sv_speed: float
    sh_longitudinal: tuple[float, float]
    sh_lateral: tuple[float, float]
    damper_velocity: tuple[float, ...]
    damper_measured_intact: tuple[tuple[float, ...], tuple[float, ...]]
    damper_measured_empty: tuple[tuple[float, ...], tuple[float, ...]]
    source_file: str = ""
    sources: Mapping[str, tuple[str, str]] = field(default_factory=dict, compare=False, repr=False)
    priors: Mapping[str, "Prior"] = field(default_factory=dict, compare=False, repr=False)

    @property
    def wheelbase(self) -> float:
        return self.a + self.b

    @property
    def total_mass(self) -> float:
        return self.sprung_mass + 2.0 * sum(self.unsprung_mass)

    def replace(self, **changes) -> "VehicleParams":
        return dataclasses.replace(self, **changes)

    def static_wheel_loads(self) -> np.ndarray:
        """Static tyre loads FL, FR, RL, RR [N] (sprung share by the lever rule plus unsprung weight)."""
        g, L = self.gravity, self.wheelbase
        f = 0.5 * self.sprung_mass * self.b / L * g + self.unsprung_mass[0] * g
        r = 0.5 * self.sprung_mass * self.a / L * g + self.unsprung_mass[1] * g
        return np.array([f, f, r, r])


#: The parameter table: every vehicle parameter once, as (field of :class:`VehicleParams`, YAML section,
#: YAML key, shape, check). Shape ``scalar`` (one number), ``axle`` ({front, rear}, per wheel of that axle)
#: or ``table`` (damper curves, one list per axle); check ``positive``, ``nonneg`` or ``""``. Value, unit,
#: source and plausible range live in the YAML file (:class:`Prior`); the kernel's parameter vector
#: (:meth:`~susp_sim_ros.model.vehicle.Model.params`), the linear model and the calibration read the
#: :class:`VehicleParams` made from it.
PARAMETER_TABLE: tuple[tuple[str, str, str, str, str], ...] = (
    ("gravity", "constants", "gravity", "scalar", "positive"),
    ("sprung_mass", "body", "sprung_mass", "scalar", "positive"),
    ("unsprung_mass", "body", "unsprung_mass", "axle", "positive"),
    ("a", "body", "cg_to_front_axle", "scalar", "positive"),
    ("b", "body", "cg_to_rear_axle", "scalar", "positive"),
    ("track", "body", "track", "axle", "positive"),
    ("cg_height", "body", "cg_height", "scalar", "positive"),
    ("roll_inertia", "body", "roll_inertia", "scalar", "positive"),
    ("pitch_inertia", "body", "pitch_inertia", "scalar", "positive"),
    ("yaw_inertia", "body", "yaw_inertia", "scalar", "positive"),
    ("roll_centre_height", "body", "roll_centre_height", "axle", ""),
    ("pitch_centre_height", "body", "pitch_centre_height", "scalar", ""),
    ("wheel_rate", "suspension", "wheel_rate", "axle", "positive"),
    ("bump_stop_travel", "suspension", "bump_stop_travel", "axle", "positive"),
    ("rebound_stop_travel", "suspension", "rebound_stop_travel", "axle", "positive"),
    ("stop_rate", "suspension", "stop_rate", "scalar", "nonneg"),
    ("stop_progression", "suspension", "stop_progression", "scalar", "positive"),
    ("arb_rate", "suspension", "anti_roll_bar_rate", "axle", "nonneg"),
    ("tyre_stiffness", "tyre", "vertical_stiffness", "scalar", "positive"),
    ("tyre_damping", "tyre", "vertical_damping", "scalar", "nonneg"),
    ("cornering_stiffness", "tyre", "cornering_stiffness", "axle", "positive"),
    ("mu", "tyre", "friction_coefficient", "scalar", "positive"),
    ("relaxation_length", "tyre", "relaxation_length", "scalar", "positive"),
    ("slip_fade_speed", "tyre", "slip_fade_speed", "scalar", "positive"),
    ("rolling_radius", "tyre", "rolling_radius", "scalar", "positive"),
    ("steering_ratio", "steering", "ratio", "scalar", "positive"),
    ("drive_front_share", "drivetrain", "drive_front_share", "scalar", "nonneg"),
    ("brake_front_share", "drivetrain", "brake_front_share", "scalar", "nonneg"),
    ("dahl_stiffness", "friction", "dahl_stiffness", "scalar", "positive"),
    ("axle_friction", "friction", "axle_level", "axle", "nonneg"),
    ("damper_friction_intact", "friction", "damper_level_intact", "axle", "positive"),
    ("damper_friction_empty", "friction", "damper_level_empty", "axle", "nonneg"),
    ("sv_reference", "friction", "velocity_scaling_reference", "scalar", "positive"),
    ("sv_plateau", "friction", "velocity_scaling_plateau", "scalar", "positive"),
    ("sv_speed", "friction", "velocity_scaling_speed", "scalar", "positive"),
    ("sh_longitudinal", "friction", "horizontal_scaling_longitudinal", "axle", "nonneg"),
    ("sh_lateral", "friction", "horizontal_scaling_lateral", "axle", "nonneg"),
    ("damper_velocity", "dampers", "velocity", "table", ""),
    ("damper_measured_intact", "dampers", "measured_intact", "table", ""),
    ("damper_measured_empty", "dampers", "measured_empty", "table", ""),
)


@dataclass(frozen=True)
class Prior:
    """The plausible range of one parameter (``range:`` in the vehicle file): the calibration's prior.

    ``lo``/``hi`` per axle (front, rear) for ``axle`` parameters, one value for scalars; for damper
    tables a factor on the whole curve (``unit`` then says so). ``calibrate``: the calibration may
    re-estimate it from drives.
    """

    field: str
    key: str
    unit: str
    source: str
    shape: str
    lo: tuple[float, ...]
    hi: tuple[float, ...]
    reason: str
    calibrate: bool


def _read_prior(r: "_Reader", fld: str, section: str, key: str, shape: str) -> Prior | None:
    e = r.data[section][key]
    if "range" not in e:
        return None
    rng = e["range"]
    where = f"{r.path}: {section}.{key}.range"

    def pair(x, what):
        if (not isinstance(x, list) or len(x) != 2
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in x)
                or x[0] > x[1]):
            raise ConfigError(f"{what} must be [lo, hi] with lo <= hi, got {x!r}")
        return float(x[0]), float(x[1])

    if shape == "axle":
        if not isinstance(rng, dict) or set(rng) != set(AXLES):
            raise ConfigError(f"{where} must be {{front: [lo, hi], rear: [lo, hi]}}, got {rng!r}")
        lohi = [pair(rng[a], f"{where}.{a}") for a in AXLES]
    else:
        lohi = [pair(rng, where)]
    unit = "1 (factor on the curve)" if shape == "table" else str(e["unit"])
    return Prior(field=fld, key=f"{section}.{key}", unit=unit, source=str(e["source"]), shape=shape,
                 lo=tuple(x[0] for x in lohi), hi=tuple(x[1] for x in lohi),
                 reason=str(e.get("range_source", "")), calibrate=bool(e.get("calibrate", False)))


def load_vehicle(name_or_path: str | os.PathLike = DEFAULT_VEHICLE) -> VehicleParams:
    """Load and validate a vehicle parameter set by name (``config/vehicles/``) or YAML path."""
    path = _resolve("vehicle", name_or_path)
    r = _Reader(path, _load_yaml(path))
    vel = r.table("dampers", "velocity")
    if any(b <= a for a, b in zip(vel, vel[1:])) or 0.0 not in vel:
        raise ConfigError(f"{path}: dampers.velocity must be strictly increasing and contain 0.0")
    values: dict[str, Any] = {}
    priors: dict[str, Prior] = {}
    for fld, section, key, shape, check in PARAMETER_TABLE:
        if shape == "scalar":
            values[fld] = r.scalar(section, key, positive=check == "positive", nonneg=check == "nonneg")
        elif shape == "axle":
            values[fld] = r.axle(section, key, positive=check == "positive", nonneg=check == "nonneg")
        else:
            values[fld] = r.table(section, key, None if fld == "damper_velocity" else len(vel))
        prior = _read_prior(r, fld, section, key, shape)
        if prior is not None:
            priors[fld] = prior
    vp = VehicleParams(name=str(r.data.get("name", path.stem)), **values, source_file=str(path),
                       sources=r.sources, priors=priors)
    for share in ("drive_front_share", "brake_front_share"):
        if getattr(vp, share) > 1.0:
            raise ConfigError(f"{path}: drivetrain.{share} must be in [0, 1], got {getattr(vp, share)}")
    return vp


@dataclass(frozen=True)
class TermSetting:
    """A physics term added by a variant, with per-corner parameter values (FL, FR, RL, RR)."""

    term: PhysicsTerm
    values: Mapping[str, tuple[float, float, float, float]]


@dataclass(frozen=True)
class FrictionVariant:
    """Which of the paper's friction scalings are on (Table 5), plus extra physics terms."""

    name: str
    velocity_scaling: bool = True
    oil_scaling: bool = True
    horizontal_scaling: bool = True
    terms: tuple[TermSetting, ...] = ()
    source_file: str = ""


def corner_values(where: str, spec: Any, term: str, pname: str) -> tuple[float, float, float, float]:
    """Expand a parameter value given as a number, {front, rear}, or {FL, FR, RL, RR} to four corners."""
    if isinstance(spec, (int, float)) and not isinstance(spec, bool):
        return (float(spec),) * 4
    if isinstance(spec, dict) and set(spec) == set(AXLES):
        fl, fr, rl, rr = (float(spec[AXLES[a]]) for a in CORNER_AXLE)
        return fl, fr, rl, rr
    if isinstance(spec, dict) and set(spec) == set(CORNER_NAMES):
        fl, fr, rl, rr = (float(spec[c]) for c in CORNER_NAMES)
        return fl, fr, rl, rr
    raise ConfigError(f"{where}: term {term}: parameter {pname} must be a number, {{front, rear}} or "
                      f"{{FL, FR, RL, RR}}, got {spec!r}")


def load_variant(name_or_path: str | os.PathLike = "full") -> FrictionVariant:
    """Load a friction variant by name (``config/variants/``) or YAML path."""
    path = _resolve("variant", name_or_path)
    d = _load_yaml(path)
    flags = {}
    for key in ("velocity_scaling", "oil_scaling", "horizontal_scaling"):
        v = d.get(key)
        if not isinstance(v, bool):
            raise ConfigError(f"{path}: {key} must be true or false, got {v!r}")
        flags[key] = v
    settings = []
    for n, entry in enumerate(d.get("terms") or []):
        if not isinstance(entry, dict) or "name" not in entry:
            raise ConfigError(f"{path}: terms[{n}] must be a mapping with a name, got {entry!r}")
        if entry.get("module"):  # a term defined outside this package registers itself on import
            try:
                importlib.import_module(entry["module"])
            except ImportError as exc:
                raise ConfigError(f"{path}: terms[{n}]: cannot import module {entry['module']!r}: {exc}") from None
        try:
            term = get_term(entry["name"])
        except KeyError as exc:
            raise ConfigError(f"{path}: terms[{n}]: {exc.args[0]}") from None
        given = entry.get("params") or {}
        unknown = set(given) - {p.name for p in term.params}
        if unknown:
            raise ConfigError(f"{path}: term {term.name}: unknown parameters {sorted(unknown)}; it has "
                              f"{[p.name for p in term.params]}")
        values = {p.name: corner_values(str(path), given.get(p.name, p.default), term.name, p.name)
                  for p in term.params}
        settings.append(TermSetting(term, values))
    return FrictionVariant(name=str(d.get("name", path.stem)), terms=tuple(settings),
                           source_file=str(path), **flags)
