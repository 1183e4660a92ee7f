"""What one run of a study is: its vehicle, model, parameter vector and maneuver (cached per process).

Pure functions of the normalised study description (``spec.data``) and the run's parameters; the study
spec (:mod:`.spec`, grouping runs into chunks), the batch tasks (:mod:`.tasks`) and the ride study
(:mod:`.ride`) all build runs through here.
"""
from __future__ import annotations

import json
import threading
from collections.abc import Mapping

import numpy as np

from ...model import Model
from ...model.layout import P_INDEX
from ...model.maneuvers import build_maneuver
from ...model.paper import MANEUVER_PARAMETERS, maneuver_kind
from ...model.params import DEFAULT_VEHICLE, load_vehicle

#: the maneuver geometry a run may set (per run, in ``parameters``)
MANEUVER_KEYS = MANEUVER_PARAMETERS

_cache: dict = {}
_lock = threading.RLock()


def vehicle_key(data: Mapping, run: Mapping) -> str:
    """What identifies the vehicle parameter set of a run (a name/path or a class definition)."""
    if "vehicle_class" in run:
        c = run["vehicle_class"]
        return "class:" + json.dumps({c: data["vehicle_classes"][c]}, sort_keys=True)
    return "vehicle:" + run.get("vehicle", DEFAULT_VEHICLE)


# ---- run parameters -> model, parameter vector, maneuver ------------------------------------------------
def vehicle_params(data: Mapping, run: Mapping):
    key = ("vp", vehicle_key(data, run))
    with _lock:
        if key not in _cache:
            if "vehicle_class" in run:
                cls = dict(data["vehicle_classes"][run["vehicle_class"]])
                base = load_vehicle(cls.pop("base"))
                over = {k: tuple(v) if isinstance(v, list) else v for k, v in cls.items()}
                _cache[key] = base.replace(name=f"{base.name}:{run['vehicle_class']}", **over)
            else:
                _cache[key] = load_vehicle(run.get("vehicle", DEFAULT_VEHICLE))
        return _cache[key]


def model_of(data: Mapping, run: Mapping):
    """``(Model, base parameter vector)`` of a run's vehicle and friction variant (cached)."""
    key = ("model", vehicle_key(data, run), run.get("variant", "full"))
    vp = vehicle_params(data, run)
    with _lock:
        if key not in _cache:
            m = Model(vp, run.get("variant", "full"))
            _cache[key] = (m, m.params((1.0, 1.0, 1.0, 1.0)))
        return _cache[key]


def oil_of(run: Mapping) -> tuple[float, float, float, float]:
    """Oil levels FL, FR, RL, RR: ``oil_<wheel>``, else ``oil_front``/``oil_rear``, else 1."""
    front, rear = run.get("oil_front", 1.0), run.get("oil_rear", 1.0)
    return (float(run.get("oil_FL", front)), float(run.get("oil_FR", front)),
            float(run.get("oil_RL", rear)), float(run.get("oil_RR", rear)))


def params_of(data: Mapping, run: Mapping, base: np.ndarray | None = None) -> np.ndarray:
    """The run's parameter vector: the (vehicle, variant) base with the run's oil levels."""
    p = (model_of(data, run)[1] if base is None else base).copy()
    k = P_INDEX["OIL"]
    p[k:k + 4] = oil_of(run)
    return p


def maneuver_of(data: Mapping, run: Mapping, wheelbase: float):
    """The run's maneuver (cached: building one reads config/maneuvers.yaml)."""
    geo = tuple(run.get(k) for k in MANEUVER_KEYS)
    key = ("maneuver", data["maneuver"], geo, wheelbase)
    with _lock:
        if key not in _cache:
            kind = maneuver_kind(data["maneuver"])
            _cache[key] = build_maneuver(kind.name, wheelbase,
                                         **{arg: run.get(k) for k, arg in kind.sweep_arguments})
        return _cache[key]


def inputs_of(man, dt: float) -> np.ndarray:
    """Per-step inputs of a maneuver (cached per process; never written to)."""
    key = ("inputs", man.name, man.speed, man.steer_amplitude, man.steer_frequency, man.steer_start,
           man.steer_periods, man.duration, dt)
    with _lock:
        if key not in _cache:
            _cache[key] = man.to_inputs(dt)
        return _cache[key]


