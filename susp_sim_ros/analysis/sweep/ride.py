"""Ride studies (``kind: ride``, issue 15): damper controllers x oil levels x ISO 8608 road classes x
friction variants, each run a closed-loop ride over a seeded random road (:mod:`susp_sim_ros.control.ride`).

One run is one chunk and one task (a ride run steps the car with the controller in the loop, it does not
batch), stored as a JSON row like a drive study's, so a killed study resumes where it stopped. The
finished study writes ``ride.csv`` (every run), ``ride_benefit.csv`` (each controller's change of comfort
and road holding against the passive car on the same road, oil level and variant) and a figure of
comfort (Wk RMS) against road holding (dynamic tyre load).

Study keys::

    kind: ride
    speed_kmh: 80          # constant speed
    duration_s: 20         # length of each run
    seed: 7                # road seed (same road for every run of a class)
    parameters:            # cartesian product, in this order
      controller: [passive, skyhook, ...]
      oil: [[1, 1, 1, 1], [1, 1, 0, 0]]      # FL, FR, RL, RR
      road_class: [B, C, D]
      variant: [full, dahl_only]
"""
from __future__ import annotations

import itertools
import math
from pathlib import Path
from typing import Any
from collections.abc import Mapping

import numpy as np

from ...control.controllers import CONTROLLERS
from ...control.ride import RideSpec, run_ride
from ...errors import ConfigError, SuspInputError
from ...model import Model
from ...model.iso8608 import CLASSES
from .runs import _cache, _lock
from .spec import Chunk, StudySpec
from ...model.params import DEFAULT_VEHICLE, load_variant

RIDE_KEYS = ("controller", "oil", "road_class", "variant")
WHEELS = ("FL", "FR", "RL", "RR")
COLUMNS = ["run_id", "controller", "oil", "road_class", "variant", "comfort_wk_rms_m_s2",
           "dynamic_tyre_load_rms_rel_mean", *[f"dynamic_tyre_load_rms_rel_{w}" for w in WHEELS],
           *[f"suspension_travel_rms_m_{w}" for w in WHEELS], "stop_contacts", "pitch_acceleration_rms_rad_s2",
           "roll_acceleration_rms_rad_s2", "mean_command", "error"]


def ride_study(data: Mapping, source: str, name: str) -> StudySpec:
    allowed = {"name", "description", "kind", "speed_kmh", "duration_s", "seed", "parameters", "step_s"}
    unknown = set(data) - allowed
    if unknown:
        raise ConfigError(f"{source}: unknown key(s) for a ride study: {', '.join(sorted(unknown))}; "
                          f"known: {', '.join(sorted(allowed))}")

    def num(key, default, lo, hi):
        v = data.get(key, default)
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or not lo <= v <= hi:
            raise ConfigError(f"{source}: {key}: expected a number in [{lo}, {hi}], got {v!r}")
        return float(v)
    speed = num("speed_kmh", 80.0, 3.6, 250.0)
    duration = num("duration_s", 20.0, 3.0, 3600.0)
    step = num("step_s", 0.001, 1e-5, 0.002)
    seed = data.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ConfigError(f"{source}: seed: expected an integer >= 0, got {seed!r}")
    params = data.get("parameters") or {}
    if not isinstance(params, dict) or set(params) - set(RIDE_KEYS):
        raise ConfigError(f"{source}: parameters: expected a mapping of {', '.join(RIDE_KEYS)}")
    defaults = {"controller": ["passive"], "oil": [[1.0, 1.0, 1.0, 1.0]], "road_class": ["C"], "variant": ["full"]}
    swept = []
    for k in RIDE_KEYS:
        vals = params.get(k, defaults[k])
        single_oil = k == "oil" and isinstance(vals, list) and vals and not isinstance(vals[0], list)
        vals = vals if isinstance(vals, list) and not single_oil else [vals]
        if not vals:
            raise ConfigError(f"{source}: parameters.{k}: empty list")
        out = []
        for v in vals:
            where = f"{source}: parameters.{k}"
            if k == "controller" and v not in CONTROLLERS:
                raise ConfigError(f"{where}: {v!r} is not one of {', '.join(CONTROLLERS)}")
            if k == "road_class" and (not isinstance(v, str) or v not in CLASSES):
                raise ConfigError(f"{where}: {v!r} is not an ISO 8608 class ({', '.join(CLASSES)})")
            if k == "variant":
                try:
                    load_variant(v)
                except ConfigError as exc:
                    raise ConfigError(f"{where}: {exc}") from None
            if k == "oil":
                if (not isinstance(v, list) or len(v) != 4
                        or any(isinstance(x, bool) or not isinstance(x, (int, float)) or not 0 <= x <= 1 for x in v)):
                    raise ConfigError(f"{where}: expected four oil levels [FL, FR, RL, RR] in [0, 1], got {v!r}")
                v = ",".join(f"{float(x):g}" for x in v)
            out.append(v)
        swept.append([k, out])
    norm = {"name": name, "kind": "ride", "speed_kmh": speed, "duration_s": duration, "seed": seed,
            "step_s": step, "parameters": swept, "description": str(data.get("description", "")).strip(),
            "results": "csv"}
    spec = StudySpec(source, norm)
    spec.runs = [dict(zip(RIDE_KEYS, combo)) for combo in itertools.product(*[v for _, v in swept])]
    spec.chunks = [Chunk(i, (i,)) for i in range(len(spec.runs))]
    return spec


def ride_task(data: Mapping, run_id: int, run: Mapping) -> dict:
    """One ride run -> its table row (an error in the row instead of raising)."""
    row: dict[str, Any] = {"run_id": run_id, **run, "error": ""}
    try:
        with _lock:
            model = _cache.get(("ride_model", run["variant"]))
            if model is None:
                model = _cache[("ride_model", run["variant"])] = Model(DEFAULT_VEHICLE, run["variant"])
        oil = tuple(float(x) for x in run["oil"].split(","))
        spec = RideSpec(run["road_class"], data["speed_kmh"] / 3.6, data["duration_s"], data["seed"])
        r = run_ride(model, spec, controller=run["controller"], oil=oil, step_s=data["step_s"])
        m = r.metrics
        dtl = m.dynamic_tyre_load_rms_rel
        row.update({"comfort_wk_rms_m_s2": m.comfort_wk_rms_m_s2,
                    "dynamic_tyre_load_rms_rel_mean": float(np.mean(list(dtl.values()))),
                    **{f"dynamic_tyre_load_rms_rel_{w}": dtl[w] for w in WHEELS},
                    **{f"suspension_travel_rms_m_{w}": m.suspension_travel_rms_m[w] for w in WHEELS},
                    "stop_contacts": int(sum(m.stop_contacts.values())),
                    "pitch_acceleration_rms_rad_s2": m.pitch_acceleration_rms_rad_s2,
                    "roll_acceleration_rms_rad_s2": m.roll_acceleration_rms_rad_s2,
                    "mean_command": float(np.mean(list(r.mean_command.values()))) if r.mean_command else ""})
    except (SuspInputError, ValueError, RuntimeError) as exc:
        row["error"] = f"{type(exc).__name__}: {exc}"
    return row


def ride_benefit(rows: list[dict]) -> list[dict]:
    """Per controller, oil level, road class and variant: relative change of Wk RMS and of the mean
    dynamic tyre load against the passive run of the same oil level, road and variant (negative =
    better)."""
    base = {(r["oil"], r["road_class"], r["variant"]): r for r in rows
            if r["controller"] == "passive" and not r.get("error")}
    out = []
    for r in rows:
        b = base.get((r["oil"], r["road_class"], r["variant"]))
        if r.get("error") or b is None or r["controller"] == "passive":
            continue
        out.append({"controller": r["controller"], "oil": r["oil"], "road_class": r["road_class"],
                    "variant": r["variant"],
                    "comfort_change": r["comfort_wk_rms_m_s2"] / b["comfort_wk_rms_m_s2"] - 1.0,
                    "tyre_load_change":
                        r["dynamic_tyre_load_rms_rel_mean"] / b["dynamic_tyre_load_rms_rel_mean"] - 1.0})
    return out


def plot_ride(rows: list[dict], path: Path, title: str = "") -> Path:
    """Comfort (Wk RMS) against road holding (mean dynamic tyre load): one panel per road class and
    friction variant, one marker per controller, one colour per oil level."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    good = [r for r in rows if not r.get("error")]
    panels = sorted({(r["road_class"], r["variant"]) for r in good})
    oils = sorted({r["oil"] for r in good}, reverse=True)
    ctrls = list(dict.fromkeys(r["controller"] for r in good))
    markers = dict(zip(ctrls, "osD^v<>p*"))
    colours = dict(zip(oils, plt.rcParams["axes.prop_cycle"].by_key()["color"]))
    ncol = min(len(panels), 2) or 1
    nrow = max(1, -(-len(panels) // ncol))
    fig, axes = plt.subplots(nrow, ncol, figsize=(6.0 * ncol, 4.6 * nrow), squeeze=False)
    for ax, (cls, var) in zip(axes.flat, panels):
        for r in good:
            if (r["road_class"], r["variant"]) != (cls, var):
                continue
            ax.scatter(r["comfort_wk_rms_m_s2"], r["dynamic_tyre_load_rms_rel_mean"], marker=markers[r["controller"]],
                       color=colours[r["oil"]], s=42)
        ax.set_title(f"ISO 8608 class {cls}, friction {var}", fontsize=10)
        ax.set_xlabel("comfort: Wk-weighted vertical acceleration RMS [m/s^2]")
        ax.set_ylabel("road holding: dynamic tyre load RMS / static [-]")
        ax.grid(alpha=0.3)
    for ax in list(axes.flat)[len(panels):]:
        ax.axis("off")
    from matplotlib.lines import Line2D
    handles = ([Line2D([], [], marker=markers[c], ls="", color="k", label=c) for c in ctrls]
               + [Line2D([], [], marker="s", ls="", color=colours[o], label=f"oil {o}") for o in oils])
    fig.legend(handles=handles, loc="lower center", ncol=min(len(handles), 5), fontsize=8, frameon=False)
    fig.suptitle(title or "Comfort vs road holding (lower-left is better)", fontsize=11)
    fig.tight_layout(rect=(0, 0.08, 1, 0.96))
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def finish_ride(spec: StudySpec, store, plot: bool) -> dict:
    rows = [dict(r) for r in store.drive_rows()]
    table = store.write_table(COLUMNS, [[r.get(h, "") for h in COLUMNS] for r in rows], "ride")
    ben = ride_benefit(rows)
    bcols = ["controller", "oil", "road_class", "variant", "comfort_change", "tyre_load_change"]
    benefit = store.write_table(bcols, [[b[h] for h in bcols] for b in ben], "ride_benefit")
    plots = [str(plot_ride(rows, store.out / f"{spec.name}.png",
                           f"{spec.name}: {spec.data['speed_kmh']:g} km/h, {spec.data['duration_s']:g} s, "
                           f"seed {spec.data['seed']}"))] if plot and rows else []
    failed = [{"run_id": r["run_id"], "error": r["error"]} for r in rows if r.get("error")]
    # mean benefit per controller and variant over oil levels and roads, for the summary
    mean: dict = {}
    for b in ben:
        mean.setdefault(f"{b['controller']}/{b['variant']}", []).append((b["comfort_change"], b["tyre_load_change"]))
    mean = {k: {"comfort_change": float(np.mean([x[0] for x in v])),
                "tyre_load_change": float(np.mean([x[1] for x in v]))}
            for k, v in mean.items()}
    return {"table": str(table), "benefit_table": str(benefit), "columns": COLUMNS, "plots": plots,
            "runs_ok": len(rows) - len(failed), "runs_failed": failed, "mean_benefit": mean}


def ride_summary(r: dict) -> list[str]:
    lines = [f"  {k}: Wk RMS {100 * v['comfort_change']:+.1f} %, "
             f"dynamic tyre load {100 * v['tyre_load_change']:+.1f} % "
             f"against passive (mean over oil levels and roads)" for k, v in r.get("mean_benefit", {}).items()]
    lines += [f"  FAILED run {f['run_id']}: {f['error']}" for f in r.get("runs_failed", [])]
    return lines
