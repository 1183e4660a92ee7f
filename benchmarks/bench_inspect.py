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
"""
from __future__ import annotations

import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from susp_sim_ros.analysis import synthetic  # noqa: E402
from susp_sim_ros.analysis.inspection import inspect_drives  # noqa: E402
from susp_sim_ros.model.maneuvers import STATES, vehicle_state  # noqa: E402
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


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    print(json.dumps(main(int(args[0]) if args else 24, "--own" in sys.argv,
                          first=int(args[1]) if len(args) > 1 else 0), indent=1))
