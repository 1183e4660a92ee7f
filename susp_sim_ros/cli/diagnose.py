"""``susp diagnose``: the discrepancy finder over one or more recorded test drives.

    susp diagnose bags/*.mcap --variant dahl_only [--out results/diagnose] [--name NAME] [--json]

Locates where the measured gyro rates leave the base model's simulation by more than the sensor noise
(estimated from the data), tests the candidate-term library, fits the chosen terms jointly across all
drives, proves the fit leave-one-drive-out, and writes the extended model (``NAME.yaml`` variant, plus
``NAME_vehicle.yaml`` when vehicle values were fitted), overlay plots, a JSON with every detail and a
Markdown report into ``--out``. ``--json`` prints the interface object (interface.md, JSON outputs).
"""
from __future__ import annotations

from pathlib import Path

from ..errors import SuspInputError


def add_arguments(p) -> None:
    p.add_argument("drives", nargs="+", metavar="DRIVE.mcap", help="recorded test drives")
    p.add_argument("--variant", default="full", help="base friction variant (name or YAML path)")
    p.add_argument("--config", default="passat_b8_like", help="vehicle parameter set (name or YAML path)")
    p.add_argument("--out", default="results/diagnose", help="output directory (default results/diagnose)")
    p.add_argument("--name", default=None, help="name of the written variant (default diagnosed_<variant>)")
    p.add_argument("--candidates", default=None, help="comma-separated candidate terms (default: all)")
    p.add_argument("--no-plots", action="store_true", help="no overlay PNGs")
    p.add_argument("--no-heldout", action="store_true", help="skip leave-one-drive-out (faster)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")


def run(args) -> dict:
    from ..analysis.discrepancy import DiscrepancyFinder
    from ..analysis.discrepancy.report import verdict, write_outputs
    for d in args.drives:
        if not Path(d).is_file():
            raise SuspInputError(f"{d}: no such recorded test drive")
    cands = [c.strip() for c in args.candidates.split(",") if c.strip()] if args.candidates else None
    f = DiscrepancyFinder(vehicle=args.config, variant=args.variant, candidates=cands,
                          heldout=not args.no_heldout, progress=not args.no_progress)
    f.fit(args.drives)
    base = Path(args.variant).stem
    name = args.name or f"diagnosed_{base}"
    paths = write_outputs(f, args.out, name, plots=not args.no_plots)
    rep = f.report()
    if getattr(args, "json", False):
        return rep
    v, why = verdict(f)
    lines = [f"verdict: {v} ({why})",
             f"noise floor {rep['noise_floor_deg_s']:.4f} deg/s; held-out RMSE {rep['heldout_rmse_before_deg_s']:.4f}"
             f" -> {rep['heldout_rmse_after_deg_s']:.4f} deg/s"]
    for t in rep["terms"]:
        lines.append(f"  {t['name']} ({t['where']}): {t['evidence'].get('statement', '')}")
    for s in rep["not_identifiable"]:
        lines.append(f"  not identifiable: {s['name']} -> reveal with {s['reveal_with']}")
    lines.append(f"{len(rep['windows'])} windows above noise; report {paths['report']}, variant {paths['variant']}"
                 f" ({f.elapsed_s_:.1f} s)")
    return {**rep, "summary": "\n".join(lines)}
