"""``susp paper``: the paper's maneuvers x vehicle states x friction variants on the model."""
from __future__ import annotations

from pathlib import Path

from ..analysis.paper_comparison import STATES, VARIANTS, run_paper_comparison, write_paper_comparison_report
from ..model import Model
from ..model.params import DEFAULT_VEHICLE
from ..model.rigs import axle_rig, damper_rig, plot_loops
from ..progress import progress


def add_arguments(p) -> None:
    p.add_argument("--out", default="results/paper", help="output directory (report, plots, JSON)")
    p.add_argument("--config", default=DEFAULT_VEHICLE, help="vehicle parameter set name or YAML path")
    p.add_argument("--step", type=float, default=0.001, help="integration step [s]")


def _rig_plots(vehicle: str, out: Path) -> list[str]:
    """The paper's rig procedures on the model: axle loops (with and without 1 kN lateral force) and
    damper loops (intact and oil-empty), one PNG each."""
    model = Model(vehicle, "full")
    paths = []
    for axle in ("front", "rear"):
        p = out / f"rig_axle_{axle}.png"
        plot_loops({"no horizontal force": axle_rig(model, axle),
                    "1 kN lateral": axle_rig(model, axle, fy=1000.0),
                    "1 kN longitudinal": axle_rig(model, axle, fx=1000.0)}, p,
                   f"{axle} axle friction rig, 1 mm/s, +-5 mm (paper: {60 if axle == 'front' else 43} N)")
        paths.append(str(p))
        p = out / f"rig_damper_{axle}.png"
        plot_loops({"intact": damper_rig(model, axle, 1.0), "oil-empty": damper_rig(model, axle, 0.0)}, p,
                   f"{axle} damper on the hydropulser, 1 mm/s ramp")
        paths.append(str(p))
    return paths


def run(args) -> dict:
    with progress(total=2 * len(STATES) * len(VARIANTS), desc="paper study", unit="run") as bar:
        study = run_paper_comparison(args.config, args.step, progress=lambda _: bar.update())
    result = write_paper_comparison_report(study, Path(args.out))
    result["rig_plots"] = _rig_plots(args.config, Path(args.out))
    rows = []
    for m, by_state in study.rmse_vs_full.items():
        for s in STATES:
            rows.append(f"  {m:14s} {s:12s} " + "  ".join(f"{v}={by_state[s][v]:.3f}" for v in VARIANTS))
    result["summary"] = ("RMSE of each variant against full [deg/s]:\n" + "\n".join(rows)
                         + f"\nreport: {result['report']}")
    return result
