"""Study descriptions (``config/studies/*.yaml``): loading, validation, expansion into runs and chunks.

A *sweep* study runs one paper maneuver over the cartesian product of its ``parameters`` (every value a
scalar, a list, or a range ``{from: A, to: B, num: N}``, inclusive), in the order the keys are written;
run ``i`` is the ``i``-th combination. Runs that share a compiled kernel and a step count (friction
variant, maneuver length) are cut into chunks of ``chunk_size``; one chunk is one batched simulation
(:func:`susp_sim_ros.model.simulate_batch`) and one task on the cluster. Everything here is
deterministic, so a resumed study gets the same runs, chunks and chunk ids.

A *drives* study validates every recorded test drive (``*.mcap``) of a folder, one task per drive.

Errors are :class:`~susp_sim_ros.errors.ConfigError` naming the file and the key.
"""
from __future__ import annotations

import dataclasses
import hashlib
import itertools
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from collections.abc import Mapping

import numpy as np

from ...errors import ConfigError, SuspInputError
from ...model.layout import OUTPUT_LABELS
from ...model.paper import DEFAULT_MANEUVER, MANEUVER_KINDS, MANEUVERS, PRIMARY_OUTPUT, VARIANTS
from .runs import MANEUVER_KEYS, maneuver_of, vehicle_key, vehicle_params
from ...model.params import DEFAULT_VEHICLE, VehicleParams, load_variant, load_vehicle

ENGINE_VERSION = 2          # bump when a change alters results, so old stores are not resumed into
OIL_KEYS = ("oil_front", "oil_rear", "oil_FL", "oil_FR", "oil_RL", "oil_RR")


def _owner(parameter: str) -> str | None:
    """The maneuver a geometry parameter belongs to (registry ``sweep_arguments``); None when shared."""
    owners = [k.name for k in MANEUVER_KINDS.values() if parameter in dict(k.sweep_arguments)]
    return owners[0] if len(owners) == 1 else None


# parameter -> (kind, maneuver it belongs to or None, what it is)
PARAMETERS: dict[str, tuple[str, str | None, str]] = {
    "vehicle": ("name", None, "vehicle parameter set name or YAML path"),
    "vehicle_class": ("name", None, "a class defined under vehicle_classes"),
    "variant": ("name", None, "friction variant name or YAML path"),
    **{k: ("fraction", None, f"damper oil level {k[4:]} (1 intact, 0 oil-empty)") for k in OIL_KEYS},
    "speed": ("positive", None, "vehicle speed [m/s]"),
    "bump_height": ("number", _owner("bump_height"), "bump height [m]"),
    "bump_length": ("positive", _owner("bump_length"), "bump length [m]"),
    "steer_amplitude": ("number", _owner("steer_amplitude"), "steering-wheel amplitude [rad]"),
    "steer_frequency": ("positive", _owner("steer_frequency"), "steering frequency [Hz]"),
}
# geometry keys a reference run may not change (it must drive the same maneuver)
METRICS = ("peak_rate", "decay_ratio", "damping_ratio", "ring_out", "rms_after", "rmse_ref")
GENERIC_METRICS = ("peak", "rms")      # {peak: OUTPUT_LABEL}: max |x|, {rms: OUTPUT_LABEL}: RMS, SI units
RESULT_FORMATS = ("csv", "parquet")
TOP_KEYS = {"name", "description", "kind", "maneuver", "step_s", "output_rate_hz", "chunk_size",
            "parameters", "vehicle_classes", "outputs", "reference", "after_window_s",
            "ring_out_threshold_deg_s", "results", "plot", "folder", "variants", "diagnose", "roc"}


@dataclass(frozen=True)
class Chunk:
    """One task: the ids of its runs (sweep) or the drive file (drives)."""

    id: int
    runs: tuple[int, ...]
    group: tuple = ()


@dataclass
class StudySpec:
    """A validated study. ``data`` is the normalised, JSON-ready description shipped to workers."""

    path: str
    data: dict
    runs: list[dict] = field(default_factory=list, repr=False)
    chunks: list[Chunk] = field(default_factory=list, repr=False)

    @property
    def name(self) -> str:
        return self.data["name"]

    @property
    def kind(self) -> str:
        return self.data["kind"]

    @property
    def hash(self) -> str:
        text = json.dumps({"engine": ENGINE_VERSION, "spec": self.data}, sort_keys=True, default=str)
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    @property
    def swept(self) -> list[str]:
        """Parameter names in table order."""
        return [k for k, _ in self.data.get("parameters", [])]

    @property
    def n_runs(self) -> int:
        return len(self.runs)

    def metric_columns(self) -> list[str]:
        return [metric_column(m, self.data.get("maneuver", DEFAULT_MANEUVER)) for m in self.data["outputs"]]


def metric_column(m, maneuver: str) -> str:
    """Table column of a metric (units in the name; rates in deg/s as the paper reports them)."""
    sig = PRIMARY_OUTPUT[maneuver].lower()
    if isinstance(m, dict):
        (kind, label), = m.items()
        return f"{kind}_abs_{label}" if kind == "peak" else f"rms_{label}"
    return {"peak_rate": f"peak_{sig}_deg_s", "decay_ratio": f"{sig}_decay_ratio",
            "damping_ratio": f"{sig}_damping_ratio", "ring_out": "ring_out_s",
            "rms_after": f"rms_{sig}_after_deg_s", "rmse_ref": f"rmse_{sig}_vs_ref_deg_s"}[m]


def _number(source, key, v, *, positive=False, fraction=False) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise ConfigError(f"{source}: {key}: expected a finite number, got {v!r}")
    if positive and v <= 0:
        raise ConfigError(f"{source}: {key}: expected a number > 0, got {v!r}")
    if fraction and not 0.0 <= v <= 1.0:
        raise ConfigError(f"{source}: {key}: expected an oil level in [0, 1], got {v!r}")
    return float(v)


def _values(source: str, key: str, spec: Any) -> list:
    """Expand a scalar, list or ``{from, to, num}`` range."""
    where = f"parameters.{key}"
    if isinstance(spec, dict):
        if set(spec) != {"from", "to", "num"}:
            raise ConfigError(f"{source}: {where}: a range needs exactly from, to, num; got {sorted(spec)}")
        a = _number(source, f"{where}.from", spec["from"])
        b = _number(source, f"{where}.to", spec["to"])
        n = spec["num"]
        if isinstance(n, bool) or not isinstance(n, int) or n < 1:
            raise ConfigError(f"{source}: {where}.num: expected an integer >= 1, got {n!r}")
        # rounded so that 0.1 is 0.1 in the table and in plot selections
        return [float(round(x, 12)) + 0.0 for x in np.linspace(a, b, n)]
    vals = spec if isinstance(spec, list) else [spec]
    if not vals:
        raise ConfigError(f"{source}: {where}: empty list")
    return vals


def _check_value(source: str, key: str, v: Any, maneuver: str, classes: Mapping) -> Any:
    kind, _, _ = PARAMETERS[key]
    where = f"parameters.{key}"
    if kind == "name":
        if not isinstance(v, str) or not v:
            raise ConfigError(f"{source}: {where}: expected a name, got {v!r}")
        if key == "vehicle_class" and v not in classes:
            raise ConfigError(f"{source}: {where}: {v!r} is not defined under vehicle_classes "
                              f"(defined: {', '.join(classes) or 'none'})")
        return v
    return _number(source, where, v, positive=kind == "positive", fraction=kind == "fraction")


def _vehicle_classes(source: str, spec: Any) -> dict:
    if spec is None:
        return {}
    if not isinstance(spec, dict):
        raise ConfigError(f"{source}: vehicle_classes: expected a mapping name -> overrides")
    fields = {f.name: f for f in dataclasses.fields(VehicleParams)}
    out = {}
    for cname, over in spec.items():
        where = f"vehicle_classes.{cname}"
        if not isinstance(over, dict):
            raise ConfigError(f"{source}: {where}: expected a mapping of vehicle parameter overrides")
        cls = {"base": over.get("base", DEFAULT_VEHICLE)}
        base = _load(source, f"{where}.base", load_vehicle, cls["base"])
        for k, v in over.items():
            if k == "base":
                continue
            if k not in fields or k in ("name", "source_file", "sources"):
                raise ConfigError(f"{source}: {where}.{k}: not a vehicle parameter (e.g. sprung_mass, "
                                  f"pitch_inertia, wheel_rate, damper_friction_intact)")
            cur = getattr(base, k)
            if isinstance(cur, tuple):
                if not (isinstance(v, list) and len(v) == len(cur)) or any(isinstance(x, list) for x in v):
                    raise ConfigError(f"{source}: {where}.{k}: expected a list of {len(cur)} numbers "
                                      f"({'front, rear' if len(cur) == 2 else 'as in the vehicle file'}), got {v!r}")
                cls[k] = [_number(source, f"{where}.{k}", x) for x in v]
            else:
                cls[k] = _number(source, f"{where}.{k}", v, positive=True)
        out[str(cname)] = cls
    return out


def _load(source, where, loader, name):
    try:
        return loader(name)
    except ConfigError as exc:
        raise ConfigError(f"{source}: {where}: {exc}") from None


def _outputs(source: str, spec: Any, has_reference: bool) -> list[str | dict[str, str]]:
    spec = list(METRICS[:-1]) + (["rmse_ref"] if has_reference else []) if spec is None else spec
    if not isinstance(spec, list) or not spec:
        raise ConfigError(f"{source}: outputs: expected a non-empty list of metrics ({', '.join(METRICS)}, "
                          f"or {{peak: OUTPUT}} / {{rms: OUTPUT}})")
    out: list[str | dict[str, str]] = []
    for i, m in enumerate(spec):
        where = f"outputs[{i}]"
        if isinstance(m, str):
            if m not in METRICS:
                raise ConfigError(f"{source}: {where}: unknown metric {m!r}; known: {', '.join(METRICS)}")
            if m == "rmse_ref" and not has_reference:
                raise ConfigError(f"{source}: {where}: rmse_ref needs a 'reference:' (e.g. "
                                  f"{{oil_front: 1.0, oil_rear: 1.0}})")
            out.append(m)
        elif isinstance(m, dict) and len(m) == 1 and next(iter(m)) in GENERIC_METRICS:
            (k, label), = m.items()
            if label not in OUTPUT_LABELS:
                raise ConfigError(f"{source}: {where}.{k}: unknown output {label!r} (e.g. PITCH_RATE, F_Z_RL)")
            out.append({k: label})
        else:
            raise ConfigError(f"{source}: {where}: expected a metric name or {{peak: OUTPUT}}, got {m!r}")
    if len({json.dumps(m) for m in out}) != len(out):
        raise ConfigError(f"{source}: outputs: a metric is listed twice")
    return out


def _step_and_decimation(data: dict, source: str) -> tuple[float, int]:
    """The integration step [s] and the output decimation (steps per output sample) of a sweep."""
    step = _number(source, "step_s", data.get("step_s", 0.001), positive=True)
    if step > 0.01:
        raise ConfigError(f"{source}: step_s: expected a step in (0, 0.01] s, got {step}")
    rate = _number(source, "output_rate_hz", data.get("output_rate_hz", 100.0), positive=True)
    decim = int(round(1.0 / (rate * step)))
    if decim < 1 or abs(decim * step * rate - 1.0) > 1e-9:
        raise ConfigError(f"{source}: output_rate_hz: {rate} Hz is not an integer divisor of 1/step_s "
                          f"= {1 / step:g} Hz")
    return step, decim


def _swept_parameters(data: dict, source: str, maneuver: str, classes: dict) -> list:
    """``[[parameter, [values]], ...]`` of a sweep, checked (known, of this maneuver, not set twice) and
    their vehicles and variants loaded (before any cluster starts)."""
    params = data.get("parameters") or {}
    if not isinstance(params, dict):
        raise ConfigError(f"{source}: parameters: expected a mapping parameter -> value(s)")
    for k in params:
        if k not in PARAMETERS:
            raise ConfigError(f"{source}: parameters.{k}: unknown parameter; known: {', '.join(PARAMETERS)}")
        owner = PARAMETERS[k][1]
        if owner is not None and owner != maneuver:
            raise ConfigError(f"{source}: parameters.{k}: belongs to the {owner} maneuver, not {maneuver}")
    if "vehicle" in params and "vehicle_class" in params:
        raise ConfigError(f"{source}: parameters: give vehicle or vehicle_class, not both (a class names its base)")
    for k in (k for k in ("oil_front", "oil_rear") if k in params):
        for w in (("FL", "FR") if k == "oil_front" else ("RL", "RR")):
            if f"oil_{w}" in params:
                raise ConfigError(f"{source}: parameters: {k} and oil_{w} both set the {w} oil level")
    swept = []
    for k, spec in params.items():
        vals = [_check_value(source, k, v, maneuver, classes) for v in _values(source, k, spec)]
        swept.append([k, vals])
    for k, vals in swept:
        for v in set(vals) if k in ("vehicle", "variant") else ():
            _load(source, f"parameters.{k}", load_vehicle if k == "vehicle" else load_variant, v)
    return swept


def _reference(data: dict, source: str, maneuver: str, classes: dict) -> dict | None:
    """The sweep's reference run (parameter overrides of the same maneuver), checked, or None."""
    reference = data.get("reference")
    if reference is None:
        return None
    if not isinstance(reference, dict) or not reference:
        raise ConfigError(f"{source}: reference: expected a mapping of parameter overrides, "
                          f"e.g. {{oil_front: 1.0, oil_rear: 1.0}}")
    for k, v in reference.items():
        if k not in PARAMETERS or k in MANEUVER_KEYS:
            raise ConfigError(f"{source}: reference.{k}: a reference may override oil levels, vehicle, "
                              f"vehicle_class or variant (it drives the same maneuver)")
        v = _check_value(source, k, v, maneuver, classes)
        if k in ("vehicle", "variant"):
            _load(source, f"reference.{k}", load_vehicle if k == "vehicle" else load_variant, v)
        reference[k] = v
    return reference


def _results_format(data: dict, source: str) -> str:
    """``csv`` or ``parquet`` (which needs pyarrow)."""
    results = data.get("results", "csv")
    if results not in RESULT_FORMATS:
        raise ConfigError(f"{source}: results: expected csv or parquet, got {results!r}")
    if results == "parquet":
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            raise ConfigError(f"{source}: results: parquet needs pyarrow (pip install pyarrow), "
                              f"or use results: csv") from None
    return results


def _sweep(data: dict, source: str, name: str) -> StudySpec:
    maneuver = data.get("maneuver", DEFAULT_MANEUVER)
    if maneuver not in MANEUVERS:
        raise ConfigError(f"{source}: maneuver: expected one of {', '.join(MANEUVERS)}, got {maneuver!r}")
    step, decim = _step_and_decimation(data, source)
    chunk = data.get("chunk_size", 64)
    if isinstance(chunk, bool) or not isinstance(chunk, int) or chunk < 1:
        raise ConfigError(f"{source}: chunk_size: expected an integer >= 1, got {chunk!r}")
    classes = _vehicle_classes(source, data.get("vehicle_classes"))
    swept = _swept_parameters(data, source, maneuver, classes)
    reference = _reference(data, source, maneuver, classes)
    outputs = _outputs(source, data.get("outputs"), reference is not None)
    after = _number(source, "after_window_s", data.get("after_window_s", 1.0), positive=True)
    thr = _number(source, "ring_out_threshold_deg_s", data.get("ring_out_threshold_deg_s", 0.3), positive=True)
    results = _results_format(data, source)
    norm = {"name": name, "kind": "sweep", "maneuver": maneuver, "step_s": step, "decim": decim,
            "chunk_size": chunk, "parameters": swept, "vehicle_classes": classes, "outputs": outputs,
            "reference": reference, "after_window_s": after, "ring_out_threshold_deg_s": thr,
            "results": results, "description": str(data.get("description", "")).strip()}
    spec = StudySpec(source, norm)
    norm["plot"] = _plot(source, data.get("plot"), spec)
    _expand(spec)
    return spec


def _plot(source: str, plot: Any, spec: StudySpec) -> dict | None:
    if plot is None:
        return None
    if not isinstance(plot, dict):
        raise ConfigError(f"{source}: plot: expected a mapping (y, panels, lines)")
    unknown = set(plot) - {"y", "panels", "lines", "title"}
    if unknown:
        raise ConfigError(f"{source}: plot: unknown key(s) {', '.join(sorted(unknown))}; "
                          "known: y, panels, lines, title")
    names = {m if isinstance(m, str) else json.dumps(m): metric_column(m, spec.data["maneuver"])
             for m in spec.data["outputs"]}
    ys = plot.get("y", [next(iter(names))])
    ys = ys if isinstance(ys, list) else [ys]
    for y in ys:
        if y not in names:
            raise ConfigError(f"{source}: plot.y: {y!r} is not one of the study's outputs ({', '.join(names)})")
    swept = dict(spec.data["parameters"])
    lines = plot.get("lines")
    if lines is not None and lines not in swept:
        raise ConfigError(f"{source}: plot.lines: {lines!r} is not a swept parameter ({', '.join(swept)})")
    panels = plot.get("panels") or [{"x": next(iter(swept))}] if swept else []
    if not panels:
        raise ConfigError(f"{source}: plot: needs swept parameters to plot against")
    out_panels = []
    for i, p in enumerate(panels):
        where = f"plot.panels[{i}]"
        if not isinstance(p, dict) or "x" not in p or set(p) - {"x", "fixed", "title"}:
            raise ConfigError(f"{source}: {where}: expected {{x: PARAMETER, fixed: {{PARAMETER: VALUE}}, title: TEXT}}")
        if p["x"] not in swept:
            raise ConfigError(f"{source}: {where}.x: {p['x']!r} is not a swept parameter ({', '.join(swept)})")
        fixed = p.get("fixed") or {}
        for k, v in fixed.items():
            if k not in swept or v not in swept[k]:
                raise ConfigError(f"{source}: {where}.fixed.{k}: {v!r} is not among the swept values of {k}")
        out_panels.append({"x": p["x"], "fixed": dict(fixed), "title": str(p.get("title", ""))})
    return {"y": [names[y] for y in ys], "panels": out_panels, "lines": lines, "title": str(plot.get("title", ""))}


def _drives(data: dict, source: str, name: str) -> StudySpec:
    folder = data.get("folder")
    if not isinstance(folder, str) or not folder:
        raise ConfigError(f"{source}: folder: a drives study needs the folder of recorded drives (*.mcap)")
    variants = data.get("variants", list(VARIANTS))
    if not isinstance(variants, list) or not variants:
        raise ConfigError(f"{source}: variants: expected a non-empty list of friction variants")
    for i, v in enumerate(variants):
        _load(source, f"variants[{i}]", load_variant, v)
    diagnose = data.get("diagnose", False)
    if not isinstance(diagnose, bool):
        raise ConfigError(f"{source}: diagnose: expected true or false, got {diagnose!r}")
    p = Path(folder)
    if not p.is_dir():
        raise SuspInputError(f"{source}: folder {folder}: not a directory")
    files = sorted(p.glob("*.mcap"))
    if not files:
        raise SuspInputError(f"{source}: folder {folder}: no recorded test drives (*.mcap) in it")
    # identity of each drive (name, size, mtime) enters the hash: a changed folder is a new study
    ident = [[f.name, f.stat().st_size, f.stat().st_mtime_ns] for f in files]
    norm = {"name": name, "kind": "drives", "folder": str(p.resolve()), "variants": list(variants),
            "diagnose": diagnose, "files": ident, "results": "csv"}
    spec = StudySpec(source, norm)
    spec.runs = [{"file": str(p.resolve() / f.name)} for f in files]
    spec.chunks = [Chunk(i, (i,)) for i in range(len(files))]
    return spec


# ---- expansion -----------------------------------------------------------------------------------------
def expand_runs(data: Mapping) -> list[dict]:
    """The runs of a normalised sweep description: the cartesian product of its ``parameters`` in the
    order written (run ``i`` is the ``i``-th combination)."""
    keys = [k for k, _ in data["parameters"]]
    vals = [v for _, v in data["parameters"]]
    return [dict(zip(keys, combo)) for combo in itertools.product(*vals)]


def _expand(spec: StudySpec) -> None:
    spec.runs = expand_runs(spec.data)
    groups: dict[tuple, list[int]] = {}
    wheelbase_cache: dict = {}
    for i, run in enumerate(spec.runs):
        groups.setdefault(group_key(spec.data, run, wheelbase_cache), []).append(i)
    size = spec.data["chunk_size"]
    chunks: list[Chunk] = []
    for key, ids in groups.items():
        for j in range(0, len(ids), size):
            chunks.append(Chunk(len(chunks), tuple(ids[j:j + size]), key))
    spec.chunks = chunks


def group_key(data: Mapping, run: Mapping, cache: dict) -> tuple:
    """Runs with equal keys run in one batched simulation: same kernel (variant) and step count."""
    vk = vehicle_key(data, run)
    if vk not in cache:
        cache[vk] = vehicle_params(data, run).wheelbase
    n = maneuver_of(data, run, cache[vk]).n_steps(data["step_s"])
    return (run.get("variant", "full"), n)


def reference_run(ref: Mapping, run: Mapping) -> dict:
    """The reference of ``run`` under the study's ``reference`` keys ``ref``: the run with those keys set
    (a reference vehicle replaces a vehicle class and the other way round)."""
    out = dict(run)
    out.update(ref)
    if "vehicle_class" in ref:
        out.pop("vehicle", None)
    if "vehicle" in ref:
        out.pop("vehicle_class", None)
    return out
