"""``susp paper``: the paper's maneuvers x vehicle states x friction variants on the model."""
from __future__ import annotations

import sys
from pathlib import Path

from ..analysis.paper_study import STATES, VARIANTS, run_paper_study, write_report


def add_arguments(p) -> None:
    p.add_argument("--out", default="results/paper", help="output directory (report, plots, JSON)")
    p.add_argument("--config", default="passat_b8_like", help="vehicle parameter set name or YAML path")
    p.add_argument("--step", type=float, default=0.001, help="integration step [s]")


def run(args) -> dict:
    from tqdm import tqdm
    bar = tqdm(total=2 * len(STATES) * len(VARIANTS), desc="paper study", unit="run", file=sys.stderr)
    study = run_paper_study(args.config, args.step, progress=lambda _: bar.update())
    bar.close()
    result = write_report(study, Path(args.out))
    rows = []
    for m, by_state in study.rmse_vs_full.items():
        for s in STATES:
            rows.append(f"  {m:14s} {s:12s} " + "  ".join(f"{v}={by_state[s][v]:.3f}" for v in VARIANTS))
    result["summary"] = ("RMSE of each variant against full [deg/s]:\n" + "\n".join(rows)
                         + f"\nreport: {result['report']}")
    return result
