"""Synthetic-truth benchmark of ``susp inspect`` (issue 14, "Must show").

Truth drives of slow bump crossings from two generators, written as MCAP drives (``damper_oil_level``
kept in the file but withheld from the estimator) and read back by
:func:`susp_sim_ros.analysis.inspection.inspect_drives`:

- the independent simulator (:mod:`truth_generators.independent_sim`, not our model: own
  integrator, damper-curve shape, friction scalings and values, ``docs/independent_sim.md``): the car
  ``TruthCar().perturbed(rng, 0.0, PERTURB)`` (sprung mass, inertias, cornering stiffnesses, wheel rates
  and tyre stiffness each up to +-10 % off, within the vehicle file's class ranges) and
  ``TruthFriction().perturbed(rng)`` (levels +-2 N);
- the project's own generator (:mod:`susp_sim_ros.analysis.synthetic`, our model plus hidden physics and
  its own parameter differences) on the paper's bump crossing in its three states (``--own``; its IMU
  noise, 0.05 deg/s, is its own).

Maneuver: ``TruthManeuver.bump(speed, height)`` with speed 6-12 km/h and height 4-8 cm; IMU 200 Hz,
gyro noise 0.1 deg/s per axis, accelerometer noise 0.02 m/s^2. Oil states cycle through intact, one
damper empty, one damper half, an axle empty, and random levels per wheel.

Scores: |estimate - truth| per identified axle (the truth axle value = mean of its wheels) and per wheel
where identified per wheel; coverage of the 95 % intervals; states (intact must read ``ok``, an empty
damper ``empty`` or ``degraded``, never ``ok``); run time.

    PYTHONPATH=. .venv/bin/python benchmarks/bench_inspect.py [N] [--own]

Over the truth-generator family (issue 27, ``--family development|held_out``, the two always reported
apart): the family's forms that hide no physics (``effect: none``: integrators and steps, damper-curve
shapes, friction velocity scalings, oil law, roll-centre handling, tyre lag, cars within and beyond the
vehicle file's ranges; ``--effects all`` adds the hidden-physics forms), each driving ``--cars`` cars
(default 3) over one bump each (:func:`truth_generators.family.bump_crossing`): a form's own car band,
its nominal car moved within the priors otherwise, friction levels +-2 N, gyro noise 0.1 deg/s. The
crossings are stratified over three speed bands of 5-15 km/h and three bump bands of 4-8 cm (car i of
form f: speed band i mod 3, bump band (i + f) mod 3, uniform within the band), oil states cycling as
above (car i of form f: state f + i, so a run with fewer cars is a prefix of one with more). Scores per
damper (a wheel's own figures where the drive tells left from right, else its axle's against the axle's
mean truth), per speed band, per bump band and overall: share with |error| <= 0.10,
mean (signed) error, 95 % interval coverage, wrong states (a called state ``ok``/``degraded``/``empty``
whose band misses the truth by more than 0.10; ``unknown`` is never wrong), the peak damper velocity and
the model-form sd the inspection used. The left-against-right comparison per axle (issue 27 item 1,
``left_right``): ``false_asymmetry_rate`` (axles whose two dampers hold the same oil level, flagged
``asymmetric``) and ``asymmetry_detection_rate`` (axles whose sides differ by >= 0.4, flagged; an axle the
drive does not tell left from right counts as missed), with counts, the difference's error and coverage
under ``left_right``. ``--wheel-loads``: every car weighed as a workshop would (the truth car's static
wheel loads, each read with a relative error at ``wheel_loads.scale_accuracy`` of ``config/inspection.yaml``;
:func:`weighed_wheel_loads`), passed to the inspection (``susp inspect --wheel-loads``).

    PYTHONPATH=. .venv/bin/python benchmarks/bench_inspect.py --family development [--cars 3] [--wheel-loads] [--json]
        [--effects all] [--inspection-config FILE] [--declared-oil-law] [--first-seed 5000]

``--declared-oil-law``: each form's damper type rig-tested (:func:`rig_oil_law`: the generator's own damper
on a virtual rig, drained in quarter steps, each force read to 1 %) and its oil law given to the inspection
(``susp inspect --oil-law``); without it the inspection reads the fitted force fractions by the model's own
law, and a form whose damper loses force otherwise with its oil (``structure/combined``: quadratic) reads the
law's difference, which no drive can show.

``--inspection-config``: another ``config/inspection.yaml``, e.g. ``benchmarks/inspection_before_issue27.yaml``
(the estimator as it was before issue 27: no signal model-form fractions, the curve beyond its measured points
held, a constant model-form sd of 0.05), to measure before and after on the same crossings.
"""
from __future__ import annotations

import argparse
import functools
import json
import sys
import tempfile
import time
from pathlib import Path

import susp_sim_ros  # noqa: F401  before numpy: idle worker threads sleep (susp_sim_ros/idle_threads.py)
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from susp_sim_ros.analysis import synthetic  # noqa: E402
from susp_sim_ros.analysis.inspection import inspect_drives  # noqa: E402
from susp_sim_ros.analysis.inspection.oil_law import OilLaw  # noqa: E402
from susp_sim_ros.model.maneuvers import STATES, vehicle_state  # noqa: E402
from susp_sim_ros.analysis.inspection import load_config  # noqa: E402
from truth_generators import family as fam  # noqa: E402
from truth_generators import independent_sim as ind  # noqa: E402

PERTURB = 0.10
GYRO_NOISE = 0.1
WHEELS = ("FL", "FR", "RL", "RR")


def oil_state(k: int, rng) -> tuple[float, ...]:
    kind = k % 6
    if kind == 0:
        return (1.0, 1.0, 1.0, 1.0)
    if kind == 1:
        o = [1.0] * 4
        o[rng.integers(4)] = 0.0
        return tuple(o)
    if kind == 2:
        o = [1.0] * 4
        o[rng.integers(4)] = 0.5
        return tuple(o)
    if kind == 3:
        return (0.0, 0.0, 1.0, 1.0) if rng.random() < 0.5 else (1.0, 1.0, 0.0, 0.0)
    return tuple(float(x) for x in rng.uniform(0.0, 1.0, 4))


def truth_drive(k: int, out: Path, own: bool = False) -> tuple[Path, tuple]:
    rng = np.random.default_rng(1000 + k)
    oil = oil_state(k, rng)
    speed = float(rng.uniform(6.0, 12.0))
    height = float(rng.uniform(0.04, 0.08))
    path = out / f"truth_{k:03d}.mcap"
    if own:  # the paper's bump crossing and states only (8 km/h, 6 cm), seeds vary noise and bias
        state = STATES[k % 3]
        oil = vehicle_state(state)
        drive = synthetic.generate_drive("bump_crossing", state, seed=k)
    else:
        car = ind.TruthCar().perturbed(rng, 0.0, PERTURB)
        fr = ind.TruthFriction().perturbed(rng)
        man = ind.TruthManeuver.bump(speed_kmh=speed, height_m=height, wheelbase_m=car.wheelbase)
        sensor = ind.TruthSensor(gyro_noise_deg_s=(GYRO_NOISE,) * 3,
                                 gyro_bias_deg_s=tuple(rng.normal(0.0, 0.02, 3)))
        drive = ind.make_drive(car, fr, None, man, sensor, oil, seed=k)
    ind.write_drive(path, drive, overwrite=True)
    return path, oil


def score(res, oil) -> list[dict]:
    rows = []
    d = res.to_json()
    for axle, (l, r) in (("front", (0, 1)), ("rear", (2, 3))):
        a = d["axles"][axle]
        truth = 0.5 * (oil[l] + oil[r])
        rows.append({"what": axle, "kind": a["identifiable"], "truth": truth, "est": a["oil_level"],
                     "ci": a["ci95"], "state": a["state"], "truth_min": min(oil[l], oil[r])})
        if a["identifiable"] == "wheel":
            for w in (l, r):
                e = d["wheels"][WHEELS[w]]
                rows.append({"what": WHEELS[w], "kind": "wheel", "truth": oil[w], "est": e["oil_level"],
                             "ci": e["ci95"], "state": e["state"], "truth_min": oil[w]})
    return rows


def main(n: int = 24, own: bool = False, cfg: dict | None = None, first: int = 0) -> dict:
    rows, times = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(first, first + n):
            path, oil = truth_drive(k, Path(tmp), own)
            t0 = time.perf_counter()
            res = inspect_drives([path], cfg=cfg)
            times.append(time.perf_counter() - t0)
            for r in score(res, oil):
                r["case"] = k
                rows.append(r)
            print(k, oil, [(r["what"], round(r["est"], 2) if r["est"] is not None else None, r["state"])
                           for r in score(res, oil)], f"{times[-1]:.1f} s", file=sys.stderr)
    est = [r for r in rows if r["est"] is not None]
    err = np.array([abs(r["est"] - r["truth"]) for r in est])
    cover = np.array([r["ci"][0] - 1e-9 <= r["truth"] <= r["ci"][1] + 1e-9 for r in est])
    intact = [r for r in est if r["truth_min"] == 1.0]
    empty = [r for r in est if r["kind"] == "wheel" and r["truth"] == 0.0] + \
            [r for r in est if r["kind"] == "axle" and r["truth"] == 0.0]
    summary = {"generator": "own synthetic" if own else "independent_sim", "cases": n, "estimates": len(est),
               "max_abs_error": float(err.max()), "share_within_0_15": float(np.mean(err <= 0.15)),
               "coverage_95": float(cover.mean()),
               "intact_called_ok": f"{sum(r['state'] == 'ok' for r in intact)}/{len(intact)}",
               "empty_called_ok": sum(r["state"] == "ok" for r in empty),
               "empty_called_empty_or_degraded":
                   f"{sum(r['state'] in ('empty', 'degraded') for r in empty)}/{len(empty)}",
               "time_s_max": float(max(times)), "time_s_mean": float(np.mean(times)), "seeds": [first, first + n - 1],
               "not_covered": [(r["case"], r["what"], round(r["truth"], 2), round(r["est"], 2),
                                [round(x, 2) for x in r["ci"]]) for r, c in zip(est, cover) if not c]}
    return summary


SPEED_BANDS_KMH = ((5.0, 25.0 / 3.0), (25.0 / 3.0, 35.0 / 3.0), (35.0 / 3.0, 15.0))
BUMP_BANDS_M = ((0.04, 0.16 / 3.0), (0.16 / 3.0, 0.2 / 3.0), (0.2 / 3.0, 0.08))
WITHIN = 0.10   # the error target per damper [oil fraction]


def _band_name(lo: float, hi: float, scale: float, unit: str) -> str:
    return f"{lo * scale:.1f}-{hi * scale:.1f} {unit}"


def family_crossings(split: str, cars: int, effects: str = "none", first_seed: int = 5000) -> list[dict]:
    """The benchmark's crossings of one split: form, seed, oil, speed [km/h], bump height [m], car band."""
    out = []
    fs = [f for f in fam.forms(split) if effects == "all" or f.effect == "none"]
    for fi, form in enumerate(fs):
        for i in range(cars):
            seed = first_seed + 1000 * fi + i
            rng = np.random.default_rng(seed)
            sb, bb = SPEED_BANDS_KMH[i % 3], BUMP_BANDS_M[(i + fi) % 3]
            out.append({"form": form.name, "seed": seed, "oil": oil_state(fi + i, rng),
                        "speed_kmh": float(rng.uniform(*sb)), "height_m": float(rng.uniform(*bb)),
                        "car_band": form.car_band if form.car_band != "nominal" else "within"})
    return out


def _state_wrong(state: str, truth: float, states_cfg: dict) -> bool:
    """A called state whose band misses the truth by more than :data:`WITHIN`."""
    ok, empty = states_cfg["ok_from"], states_cfg["empty_below"]
    band = {"ok": (ok, 1.0), "degraded": (empty, ok), "empty": (0.0, empty)}.get(state)
    return band is not None and not band[0] - WITHIN <= truth <= band[1] + WITHIN


def family_rows(res, cr: dict) -> list[dict]:
    """One row per damper of the crossing ``cr`` scored against the inspection ``res``."""
    d = res.to_json()
    seen = d["protocol"]["seen"][0]
    rows = []
    for axle, (l, r) in (("front", (0, 1)), ("rear", (2, 3))):
        for w in (l, r):
            e = d["wheels"][WHEELS[w]]
            if e["oil_level"] is None:
                continue
            truth = cr["oil"][w] if e["identifiable"] == "wheel" else 0.5 * (cr["oil"][l] + cr["oil"][r])
            rows.append({"form": cr["form"], "seed": cr["seed"], "damper": WHEELS[w], "axle": axle,
                         "kind": e["identifiable"], "truth": truth, "est": e["oil_level"], "ci": e["ci95"],
                         "sd_fit": e.get("sd_fit"), "model_form_sd_axle": d["protocol"].get(
                             "model_form_sd_per_axle", {}).get(axle, d["protocol"]["model_form_sd"]),
                         "state": e["state"], "speed_kmh": cr["speed_kmh"], "height_m": cr["height_m"],
                         "peak_damper_velocity_m_s": seen["peak_damper_velocity_m_s"][axle],
                         "model_form_sd": d["protocol"]["model_form_sd"],
                         "warnings": [x["quantity"] for x in d["protocol"]["warnings"]]})
    return rows


DETECT_DIFFERENCE = 0.4   # the left-right difference an axle comparison must detect [oil fraction]


def family_left_right(res, cr: dict) -> list[dict]:
    """One row per axle of the crossing ``cr``: the true left-minus-right oil level against the inspection's
    left-right comparison (``left_right``: difference, interval, ``asymmetric``)."""
    d = res.to_json()
    by_axle = {e["axle"]: e for e in d.get("left_right", [])}
    rows = []
    for axle, (l, r) in (("front", (0, 1)), ("rear", (2, 3))):
        e = by_axle.get(axle, {})
        rows.append({"form": cr["form"], "seed": cr["seed"], "axle": axle,
                     "truth_difference": cr["oil"][l] - cr["oil"][r], "difference": e.get("difference"),
                     "ci": e.get("ci95"), "asymmetric": bool(e.get("asymmetric", False)),
                     "kind": d["axles"][axle]["identifiable"], "speed_kmh": cr["speed_kmh"],
                     "height_m": cr["height_m"]})
    return rows


def left_right_scores(rows: list[dict]) -> dict:
    """False asymmetry (axles whose two dampers hold the same oil level, flagged) and detection (axles whose
    sides differ by >= :data:`DETECT_DIFFERENCE`, flagged; an axle without a comparison counts as missed)."""
    same = [r for r in rows if r["truth_difference"] == 0.0]
    differ = [r for r in rows if abs(r["truth_difference"]) >= DETECT_DIFFERENCE - 1e-12]
    dd = [r for r in rows if r["difference"] is not None]
    err = np.array([r["difference"] - r["truth_difference"] for r in dd]) if dd else np.zeros(0)
    cover = [r["ci"][0] - 1e-9 <= r["truth_difference"] <= r["ci"][1] + 1e-9 for r in dd]
    return {"same_axles": len(same), "false_asymmetry": sum(r["asymmetric"] for r in same),
            "differing_axles": len(differ), "detected": sum(r["asymmetric"] for r in differ),
            "without_comparison": sum(r["difference"] is None for r in rows),
            "difference_mean_abs_error": float(np.abs(err).mean()) if err.size else None,
            "difference_max_abs_error": float(np.abs(err).max()) if err.size else None,
            "difference_coverage_95": float(np.mean(cover)) if cover else None,
            "flagged_same": [(r["form"], r["seed"], r["axle"], round(r["difference"], 3)) for r in same
                             if r["asymmetric"]],
            "missed_differing": [(r["form"], r["seed"], r["axle"], round(r["truth_difference"], 3),
                                  None if r["difference"] is None else round(r["difference"], 3),
                                  None if r["ci"] is None else [round(x, 3) for x in r["ci"]])
                                 for r in differ if not r["asymmetric"]]}


def family_scores(rows: list[dict], states_cfg: dict) -> dict:
    """The issue's scores over ``rows``: n, share |error| <= 0.10, mean and max |error|, mean error,
    95 % coverage, wrong states."""
    if not rows:
        return {"n": 0}
    err = np.array([r["est"] - r["truth"] for r in rows])
    cover = np.array([r["ci"][0] - 1e-9 <= r["truth"] <= r["ci"][1] + 1e-9 for r in rows])
    return {"n": len(rows), "share_within_0_10": float(np.mean(np.abs(err) <= WITHIN)),
            "mean_error": float(err.mean()), "mean_abs_error": float(np.abs(err).mean()),
            "max_abs_error": float(np.abs(err).max()), "coverage_95": float(cover.mean()),
            "mean_ci_width": float(np.mean([r["ci"][1] - r["ci"][0] for r in rows])),
            "wrong_states": int(sum(_state_wrong(r["state"], r["truth"], states_cfg) for r in rows))}


def weighed_wheel_loads(drive, seed: int, accuracy: float) -> list[float]:
    """The truth car's static wheel loads FL, FR, RL, RR [N] (``TruthCar.static_wheel_loads`` of the truth
    metadata of ``drive``) as a wheel-load scale of relative accuracy ``accuracy`` (sd, per wheel) reads them."""
    return ind.truth_car_of(drive).weighed_wheel_loads(accuracy, seed)


RIG_OILS = (0.0, 0.25, 0.5, 0.75, 1.0)   # a damper drained in quarter steps [-]
RIG_VELOCITY_M_S = 0.3   # the rig's test velocity: inside the measured curve points, above the friction's knee
RIG_FORCE_ACCURACY = 0.01   # relative sd of one rig force reading (assumed: a load cell's +-2 % at 2 sd)


@functools.cache
def rig_oil_law(form_name: str) -> OilLaw:
    """The form's damper type on a virtual damper rig (``independent_sim.damper_rig_force``, the generator's
    own damper): drained in quarter steps, each step's force at :data:`RIG_VELOCITY_M_S` read with a relative
    error of sd :data:`RIG_FORCE_ACCURACY` (seeded per form: one rig test per damper type, done once), as the fraction
    of the way from the oil-empty to the intact force -- the oil law a workshop would take from the damper
    type's rig test (``susp inspect --oil-law``); between the steps the inspection interpolates it."""
    form = fam.FORMS[form_name]
    oils, frac = ind.damper_rig_oil_law(form.friction, RIG_OILS, RIG_VELOCITY_M_S, RIG_FORCE_ACCURACY,
                                        np.random.default_rng(list(fam.FORMS).index(form.name) + 31))
    return OilLaw(oils, frac,
                  f"virtual rig test of {form.name}'s damper at {RIG_VELOCITY_M_S:g} m/s, quarter steps, "
                  f"force read to {RIG_FORCE_ACCURACY:.0%}")


def family_main(split: str, cars: int = 3, effects: str = "none", cfg: dict | None = None,
                wheel_loads: bool = False, declared_oil_law: bool = False, first_seed: int = 5000) -> dict:
    """Inspect the split's crossings; scores overall, per speed band, per bump band, per form. ``wheel_loads``:
    each car weighed too (:func:`weighed_wheel_loads`, at the scale accuracy of the inspection settings).
    ``declared_oil_law``: each form's damper type rig-tested (:func:`rig_oil_law`) and its law given to the
    inspection; else the inspection reads force fractions as oil levels by the model's own law. ``first_seed``:
    another set of cars, speeds and bumps (:func:`family_crossings`) than the default's."""
    cfg = load_config() if cfg is None else cfg
    rows, times, lr_rows = [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        for cr in family_crossings(split, cars, effects, first_seed):
            drive = fam.bump_crossing(fam.FORMS[cr["form"]], cr["seed"], cr["oil"], cr["speed_kmh"],
                                      cr["height_m"], gyro_noise_deg_s=GYRO_NOISE, car_band=cr["car_band"],
                                      friction_dev_N=2.0)
            path = Path(tmp) / f"{cr['seed']}.mcap"
            ind.write_drive(path, drive, overwrite=True)
            t0 = time.perf_counter()
            loads = weighed_wheel_loads(drive, cr["seed"], float(cfg["wheel_loads"]["scale_accuracy"])) \
                if wheel_loads else None
            law = rig_oil_law(cr["form"]) if declared_oil_law else None
            res = inspect_drives([path], cfg=cfg, wheel_loads_n=loads, oil_law=law)
            times.append(time.perf_counter() - t0)
            new = family_rows(res, cr)
            rows += new
            lr_rows += family_left_right(res, cr)
            print(cr["form"], cr["seed"], f"{cr['speed_kmh']:.1f} km/h {cr['height_m'] * 100:.1f} cm",
                  [(r["damper"], r["truth"], round(r["est"], 2), r["state"]) for r in new],
                  f"{times[-1]:.1f} s", file=sys.stderr, flush=True)
    st = cfg["states"]
    by_speed = {_band_name(lo, hi, 1.0, "km/h"): family_scores(
        [r for r in rows if lo <= r["speed_kmh"] <= hi], st) for lo, hi in SPEED_BANDS_KMH}
    by_bump = {_band_name(lo, hi, 100.0, "cm"): family_scores(
        [r for r in rows if lo <= r["height_m"] <= hi], st) for lo, hi in BUMP_BANDS_M}
    by_form = {f: family_scores([r for r in rows if r["form"] == f], st)
               for f in dict.fromkeys(r["form"] for r in rows)}
    intact = [r for r in rows if r["truth"] == 1.0]
    lr = left_right_scores(lr_rows)
    return {"false_asymmetry_rate": lr["false_asymmetry"] / lr["same_axles"] if lr["same_axles"] else None,
            "asymmetry_detection_rate": lr["detected"] / lr["differing_axles"] if lr["differing_axles"] else None,
            "left_right": dict(lr, detect_difference=DETECT_DIFFERENCE,
                               asymmetric_min_difference=cfg.get("left_right", {}).get("asymmetric_min_difference")),
            "left_right_rows": [{k: (round(v, 4) if isinstance(v, float) else v) for k, v in r.items()}
                                for r in lr_rows],
            "split": split, "first_seed": first_seed, "forms": list(by_form), "effects": effects, "cars_per_form": cars,
            "wheel_loads": "weighed (truth loads, scale error per wheel at wheel_loads.scale_accuracy)" if wheel_loads
            else "not given",
            "oil_law": (f"declared: each form's damper type rig-tested (virtual rig at {RIG_VELOCITY_M_S:g} m/s, "
                        f"quarter steps of oil, force read to {RIG_FORCE_ACCURACY:.0%})") if declared_oil_law
            else "not given (the settings' law)",
            "crossings": len(times), "overall": family_scores(rows, st),
            "intact_mean_error": float(np.mean([r["est"] - 1.0 for r in intact])) if intact else None,
            "by_speed_band": by_speed, "by_bump_band": by_bump, "by_form": by_form,
            "time_s_mean": float(np.mean(times)), "time_s_max": float(np.max(times)),
            "rows": [{k: (round(v, 4) if isinstance(v, float) else v) for k, v in r.items()} for r in rows]}


def parse_args(argv=None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description="susp inspect against synthetic truth drives (issue 14) or over the "
                                            "truth-generator family (issue 27); prints JSON")
    p.add_argument("n", nargs="?", type=int, default=24, help="drives of the synthetic run (default 24)")
    p.add_argument("first", nargs="?", type=int, default=0, help="index of the synthetic run's first drive")
    p.add_argument("--own", action="store_true", help="the project's own generator instead of independent_sim")
    p.add_argument("--family", choices=fam.SPLITS, default=None, help="the family's split to inspect")
    p.add_argument("--cars", type=int, default=3, help="cars per form (family)")
    p.add_argument("--first-seed", type=int, default=5000, help="seed of the first car (family; another set)")
    p.add_argument("--effects", choices=("none", "all"), default="none",
                   help="the forms that hide no physics, or all forms (family)")
    p.add_argument("--inspection-config", default=None, metavar="FILE", help="another config/inspection.yaml")
    p.add_argument("--wheel-loads", action="store_true", help="every car weighed (family)")
    p.add_argument("--declared-oil-law", action="store_true", help="each form's damper type rig-tested (family)")
    p.add_argument("--json", action="store_true", help="with the per-damper rows (family)")
    return p.parse_args(argv)


if __name__ == "__main__":
    a = parse_args()
    if a.family:
        out = family_main(a.family, a.cars, a.effects,
                          cfg=load_config(a.inspection_config) if a.inspection_config else None,
                          wheel_loads=a.wheel_loads, declared_oil_law=a.declared_oil_law, first_seed=a.first_seed)
        out["inspection_config"] = a.inspection_config or "config/inspection.yaml"
        if not a.json:
            out = {k: v for k, v in out.items() if k not in ("rows", "left_right_rows")}
        print(json.dumps(out, indent=1))
    else:
        print(json.dumps(main(a.n, a.own, first=a.first), indent=1))
