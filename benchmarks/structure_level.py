"""The "nothing missing" line of the discrepancy finder's verdict (issue 24, item 5), measured.

Reads the JSON of ``bench_discrepancy.py --family development ... --json`` on stdin and prints the level
the structure-only runs (truth forms that differ from the model in structure and values, nothing hidden)
leave held-out, as the line ``config/discrepancy.yaml`` (``verdict.structure_level_over_noise``) takes:
the one-sided 95 % upper prediction bound of one new structure-only run, from the runs' held-out RMSE
over the gyro noise floor taken as log-normal (Student t on the logs: Hahn and Meeker, *Statistical
Intervals*, 1991, sec. 4.7). A recording whose calibrated model leaves more than this is not called
"nothing missing".

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

import numpy as np
from scipy import stats

COVERAGE = 0.95  # one-sided: a new structure-only run stays below the line with this probability


def structure_level(cases: list[dict]) -> dict:
    """The line and its figures from the bench's per-case rows (development structure-only runs)."""
    runs = [c for c in cases if c.get("effect") == "none"]
    held = sorted({c["family_form"] for c in runs if c.get("split") != "development"})
    if held:
        raise SystemExit(f"structure_level: held-out forms {held} may not set the line; run the development "
                         "split only")
    ratios = np.array([c["heldout_after_over_noise"] for c in runs if c.get("heldout_after_over_noise")])
    if len(ratios) < 3:
        raise SystemExit(f"structure_level: {len(ratios)} structure-only runs in the input; at least 3 needed")
    logs = np.log(ratios)
    n = len(logs)
    t = stats.t.ppf(COVERAGE, n - 1)
    line = math.exp(float(logs.mean()) + t * float(logs.std(ddof=1)) * math.sqrt(1.0 + 1.0 / n))
    return {"structure_level_over_noise": line, "runs": n, "median": float(np.median(ratios)),
            "max": float(ratios.max()), "min": float(ratios.min()), "coverage": COVERAGE,
            "forms": sorted({c["family_form"] for c in runs})}


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
              f"prediction bound over {out['runs']} runs; median {out['median']:.3f}, max {out['max']:.3f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
