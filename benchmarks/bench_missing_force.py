"""The missing force against a known hidden force (issue 26, "Must show": correlation >= 0.9 in the
body-mode band, RMS within 20 %, loop height within 20 % of the friction level).

Truth: :mod:`truth_generators.hidden_force` (the model's kernel with an axle friction element the
estimating model lacks: model-made truth, a test of the estimator's mechanics). Bump crossings with the
dampers intact, front-empty and rear-empty; per axle the band correlation and RMS ratio of the estimate
against the hidden force, its loop half height against the truth's, and the estimate's run time.

    .venv/bin/python benchmarks/bench_missing_force.py [--json] [--level N]

JSON: ``{"cases": [{"oil": [...], "front"|"rear": {"band_corr", "band_rms_ratio", "loop_half_height_N",
"truth_loop_half_height_N"}, "elapsed_s"}], "targets": {...}}``.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import susp_sim_ros  # noqa: F401  before numpy: idle worker threads sleep (susp_sim_ros/idle_threads.py)
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # truth_generators/ beside the package

from susp_sim_ros.analysis.discrepancy import missing_force as mf  # noqa: E402
from truth_generators.hidden_force import hidden_axle_friction  # noqa: E402

OILS = {"intact": (1.0, 1.0, 1.0, 1.0), "front_empty": (0.0, 0.0, 1.0, 1.0), "rear_empty": (1.0, 1.0, 0.0, 0.0)}
TARGETS = {"band_corr_min": 0.9, "band_rms_ratio_within": 0.2, "loop_within": 0.2}


def run_case(state: str, level: float) -> dict:
    d = hidden_axle_friction("bump_crossing", level, OILS[state])
    c = d.model_corner
    t0 = time.perf_counter()
    est = mf.estimate_on_model(d.model_vehicle, d.P, c["DEFL"], c["DEFL_VEL"], c["F_DAMPER"] + c["F_FRICTION"],
                               d.t_imu, d.measured - d.simulated, d.sigma)
    elapsed = time.perf_counter() - t0
    dt = float(est.t[1] - est.t[0])
    out: dict = {"state": state, "oil": list(OILS[state]), "elapsed_s": elapsed}
    for j, (axle, ij) in enumerate((("front", slice(0, 2)), ("rear", slice(2, 4)))):
        hidden = np.interp(est.t, d.t, d.hidden[:, ij].sum(axis=1))
        vel = np.interp(est.t, d.t, d.truth_velocity[:, ij].mean(axis=1))
        a, b = mf.band_passed(est.force[:, j], dt), mf.band_passed(hidden, dt)
        out[axle] = {"band_corr": float(np.corrcoef(a, b)[0, 1]), "band_rms_ratio": float(np.std(a) / np.std(b)),
                     "loop_half_height_N": mf.loop_half_height(est.force[:, j], vel),
                     "truth_loop_half_height_N": mf.loop_half_height(hidden, vel)}
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--level", type=float, default=150.0, help="hidden axle friction per corner [N]")
    a = ap.parse_args(argv)
    cases = [run_case(s, a.level) for s in OILS]
    res = {"level_n_per_corner": a.level, "cases": cases, "targets": TARGETS}
    if a.json:
        print(json.dumps(res, indent=1))
        return 0
    print("| dampers | axle | band corr | band RMS est/truth | loop half height est / truth [N] | s |")
    print("|---|---|---|---|---|---|")
    for c in cases:
        for axle in ("front", "rear"):
            e = c[axle]
            print(f"| {c['state']} | {axle} | {e['band_corr']:.3f} | {e['band_rms_ratio']:.2f} | "
                  f"{e['loop_half_height_N']:.0f} / {e['truth_loop_half_height_N']:.0f} | {c['elapsed_s']:.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
