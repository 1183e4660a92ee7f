"""Run time of the full diagnosis on the bundled drives (issue 13, "Must show": under 90 s on this machine).

``susp diagnose bags/*.mcap --variant V`` as the command runs it: the six bundled drives, calibration,
discovery, the leave-one-drive-out check of the result; from each base variant given (default ``full``
and ``dahl_only``, the two bundled-drive stories). Each run is a fresh process (as a user starts it), so
the figure includes reading the recordings and the numba cache load; a first run on a machine compiles the
kernel and is not counted (``--warm`` runs one untimed diagnosis first).

    .venv/bin/python benchmarks/bench_diagnose.py [--json] [--variants full,dahl_only] [--repeat N] [--warm]

JSON: per variant the wall times [s] of the runs, their best, the vehicle runs and simulated
vehicle-seconds, the physics named, and ``target_s`` with ``met`` (every run under it).
"""
from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TARGET_S = 90.0
MEASUREMENT_TERMS = {"sensor_bias", "time_offset", "steering_offset"}


def _susp() -> list[str]:
    exe = Path(sys.executable).with_name("susp")
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "susp_sim_ros.cli.main"]


def diagnose_once(variant: str) -> dict:
    """One ``susp diagnose --json`` run in its own process: wall time, runs, named physics."""
    bags = sorted(str(p) for p in (ROOT / "bags").glob("*.mcap"))
    t0 = time.perf_counter()
    proc = subprocess.run(_susp() + ["diagnose", *bags, "--variant", variant, "--json"], cwd=ROOT,
                          capture_output=True, text=True, check=False)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"bench_diagnose: susp diagnose --variant {variant} exited {proc.returncode}:\n"
                         f"{proc.stderr[-2000:]}")
    out = json.loads(proc.stdout)
    runs = re.findall(r"vehicle runs: (\d+) run", proc.stderr)
    return {"wall_s": wall, "vehicle_runs": int(runs[-1]) if runs else None,
            "named": [t["name"] for t in out["terms"] if t["name"] not in MEASUREMENT_TERMS],
            "verdict": out["verdict"]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--variants", default="full,dahl_only", help="base variants, comma-separated")
    ap.add_argument("--repeat", type=int, default=1, help="timed runs per variant")
    ap.add_argument("--warm", action="store_true", help="one untimed run first (compiles the kernel)")
    args = ap.parse_args(argv)
    variants = [v for v in args.variants.split(",") if v]
    if args.warm:
        diagnose_once(variants[0])
    result: dict = {"target_s": TARGET_S, "variants": {}}
    for v in variants:
        runs = []
        for k in range(args.repeat):
            r = diagnose_once(v)
            runs.append(r)
            if not args.json:
                print(f"{v}: run {k + 1}: {r['wall_s']:.1f} s, {r['vehicle_runs']} vehicle runs, "
                      f"named {', '.join(r['named']) or 'none'}", file=sys.stderr)
        walls = [r["wall_s"] for r in runs]
        result["variants"][v] = {"wall_s": walls, "best_s": min(walls), "vehicle_runs": runs[-1]["vehicle_runs"],
                                 "named": runs[-1]["named"], "verdict": runs[-1]["verdict"],
                                 "met": max(walls) < TARGET_S}
    result["met"] = all(r["met"] for r in result["variants"].values())
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        for v, r in result["variants"].items():
            print(f"{v}: best {r['best_s']:.1f} s of {len(r['wall_s'])} (target < {TARGET_S:.0f} s: "
                  f"{'met' if r['met'] else 'NOT met'})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
