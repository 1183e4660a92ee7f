"""The "nothing missing" line of the discrepancy finder's verdict (issue 24, item 5), measured.

Reads the JSON of ``bench_discrepancy.py --family development ... --json`` on stdin and prints the level
the structure-only runs (truth forms that differ from the model in structure and values, nothing hidden)
leave held-out, as the line ``config/discrepancy.yaml`` (``verdict.structure_level_over_noise``) takes:
the one-sided 95 % upper prediction bound of one new structure-only run, from the runs' held-out RMSE
over the gyro noise floor taken as log-normal.

The runs are every development structure form at the same seeds, a crossed form x seed grid, and they
are not independent: a form leaves its own level at every seed, and a seed (its car, road and noise
draw) raises or lowers every form alike. A new recording is a new form at a new seed, so the bound is
that of the two-way crossed random-effects model on the logs (one run per cell, the interaction within
the residual; Montgomery, *Design and Analysis of Experiments*, 8th ed., 2013, sec. 13.2): the variance
of a new run less the grand mean, ``s_f^2 (1 + 1/a) + s_s^2 (1 + 1/b) + s_e^2 (1 + 1/(ab))`` for ``a``
forms and ``b`` seeds, from the mean squares, with Satterthwaite's degrees of freedom (Biometrics
Bulletin 2(6), 1946) for Student's t. Until 2026-11-29 the bound took the runs as independent (Hahn and
Meeker, *Statistical Intervals*, 1991, sec. 4.7), which counts 24 runs of 6 forms at 4 seeds as 24
independent draws and so set the line too low (1.154 against 1.167 on the same runs).

Only development forms may set the line: the script refuses held-out runs (the held-out forms are only
measured on, truth_generators/family_split.yaml).

Usage: ``python benchmarks/bench_discrepancy.py --family development --forms F --seeds 1,2,3,4 --json |
python benchmarks/structure_level.py [--json]`` (or the JSON files as arguments)
"""
from __future__ import annotations

import argparse
import json
import math
import sys

import susp_sim_ros  # noqa: F401  before numpy: idle worker threads sleep (susp_sim_ros/idle_threads.py)
import numpy as np
from scipy import stats

COVERAGE = 0.95  # one-sided: a new structure-only run stays below the line with this probability


def structure_level(cases: list[dict]) -> dict:
    """The line and its figures from the bench's per-case rows (development structure-only runs, every
    form at the same seeds)."""
    runs = [c for c in cases if c.get("effect") == "none"]
    held = sorted({c["family_form"] for c in runs if c.get("split") != "development"})
    if held:
        raise SystemExit(f"structure_level: held-out forms {held} may not set the line; run the development "
                         "split only")
    runs = [c for c in runs if c.get("heldout_after_over_noise")]
    forms = sorted({c["family_form"] for c in runs})
    seeds = sorted({c["seed"] for c in runs if c.get("seed") is not None})
    if len(forms) < 2 or len(seeds) < 2 or any(c.get("seed") is None for c in runs):
        raise SystemExit(f"structure_level: {len(runs)} structure-only runs of {len(forms)} forms at seeds {seeds}; "
                         "at least 2 forms at the same 2 or more seeds needed, each run with its seed")
    cell = {(c["family_form"], c["seed"]): c["heldout_after_over_noise"] for c in runs}
    missing = [f"{f}#{s}" for f in forms for s in seeds if (f, s) not in cell]
    if missing or len(cell) != len(runs):
        raise SystemExit(f"structure_level: the runs must be every form once at every seed (a form x seed grid); "
                         f"missing: {', '.join(missing) or 'none'}; repeated: {len(runs) - len(cell)}")
    ratios = np.array([[cell[f, s] for s in seeds] for f in forms])
    line, dof = _crossed_bound(np.log(ratios), COVERAGE)
    return {"structure_level_over_noise": line, "runs": ratios.size, "median": float(np.median(ratios)),
            "max": float(ratios.max()), "min": float(ratios.min()), "coverage": COVERAGE,
            "degrees_of_freedom": dof, "forms": forms, "seeds": seeds}


def _crossed_bound(y: np.ndarray, coverage: float) -> tuple[float, float]:
    """exp of the one-sided ``coverage`` upper prediction bound of one new cell of the crossed grid ``y``
    (forms x seeds, logs), and its Satterthwaite degrees of freedom (module docstring)."""
    a, b = y.shape
    grand = float(y.mean())
    rows, cols = y.mean(axis=1), y.mean(axis=0)
    ms_form = b * float(((rows - grand) ** 2).sum()) / (a - 1)
    ms_seed = a * float(((cols - grand) ** 2).sum()) / (b - 1)
    ms_res = float(((y - rows[:, None] - cols[None, :] + grand) ** 2).sum()) / ((a - 1) * (b - 1))
    # s_f^2 = (MS_f - MS_e) / b, s_s^2 = (MS_s - MS_e) / a: the new run's variance in mean squares
    c_form, c_seed = (1.0 + 1.0 / a) / b, (1.0 + 1.0 / b) / a
    parts = ((c_form, ms_form, a - 1), (c_seed, ms_seed, b - 1),
             (1.0 + 1.0 / (a * b) - c_form - c_seed, ms_res, (a - 1) * (b - 1)))
    var = sum(c * m for c, m, _ in parts)
    dof = var ** 2 / sum((c * m) ** 2 / d for c, m, d in parts if d > 0 and m > 0)
    return math.exp(grand + float(stats.t.ppf(coverage, dof)) * math.sqrt(var)), float(dof)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("files", nargs="*", help="bench JSON files (default: one on stdin)")
    ap.add_argument("--json", action="store_true", help="JSON on stdout instead of a line of text")
    a = ap.parse_args(argv)
    docs = [json.load(open(p)) for p in a.files] if a.files else [json.load(sys.stdin)]
    out = structure_level([c for d in docs for c in (d["cases"] if isinstance(d, dict) else d)])
    if a.json:
        print(json.dumps(out, indent=1))
    else:
        print(f"structure level {out['structure_level_over_noise']:.3f} x noise ({100 * COVERAGE:.0f} % upper "
              f"prediction bound of a new form at a new seed, {len(out['forms'])} forms x {len(out['seeds'])} seeds, "
              f"{out['degrees_of_freedom']:.1f} degrees of freedom; median {out['median']:.3f}, max {out['max']:.3f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
