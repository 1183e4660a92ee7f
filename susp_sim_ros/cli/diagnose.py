"""``susp diagnose``: the discrepancy finder over one or more recorded test drives.

    susp diagnose bags/*.mcap --variant dahl_only [--out results/diagnose] [--name NAME] [--json]
        [--wheel-loads FL,FR,RL,RR]

Locates where the measured IMU signals leave the base model's simulation by more than the sensor noise
(estimated from the data, per signal), calibrates the base model's uncertain parameters within their
priors, tests the physics candidates on the calibrated model, fits the chosen terms jointly across all
drives, proves the fit leave-one-drive-out, and writes the extended model (``NAME.yaml`` variant, plus
``NAME_vehicle.yaml`` when vehicle values were fitted), overlay plots, a JSON with every detail and a
Markdown report into ``--out``. ``--json`` prints the interface object (interface.md, JSON outputs).

Every drive is read and checked first (readable, the input topics present with increasing times and
values the model accepts, enough measured IMU samples): a bad drive is a named error (exit 2) before any
fitting starts. ``--dry-run`` stops after that check.

``--wheel-loads``: the car's static wheel loads [N] as weighed. Drives that record motion only do not tell
the car's overall force scale (every mass and rate scaled by one factor moves the car the same, except
the friction levels held in newtons), so a calibrated scale can stand in for a friction effect; the
weighed sprung mass (the inspection settings' ``wheel_loads.scale_accuracy``) pins it.
"""
from __future__ import annotations

from pathlib import Path

from ..analysis.discrepancy import DiscrepancyFinder
from ..analysis.discrepancy.calibration import outside_statement
from ..analysis.discrepancy.data import cases_of_read
from ..analysis.discrepancy.report import verdict, write_outputs
from ..analysis.inspection import scale_accuracy
from ..errors import RecordingError, SuspInputError
from ..io.drive import TestDrive, check_drive, read_drive
from ..io.integrity import append_to_report
from ..io.topic_map import add_topic_map_argument
from .inspect import wheel_loads
from ..model import load_vehicle
from ..model.params import DEFAULT_VEHICLE


def add_arguments(p) -> None:
    p.add_argument("drives", nargs="+", metavar="DRIVE.mcap", help="recorded test drives (MCAP files, rosbag2 "
                   "directories or .db3 files)")
    p.add_argument("--variant", default="full", help="base friction variant (name or YAML path)")
    p.add_argument("--config", default=DEFAULT_VEHICLE, help="vehicle parameter set (name or YAML path)")
    p.add_argument("--out", default="results/diagnose", help="output directory (default results/diagnose)")
    p.add_argument("--name", default=None, help="name of the written variant (default diagnosed_<variant>)")
    p.add_argument("--candidates", default=None, help="comma-separated candidate terms (default: all)")
    p.add_argument("--no-plots", action="store_true", help="no overlay PNGs")
    p.add_argument("--no-heldout", action="store_true", help="skip leave-one-drive-out (faster)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    p.add_argument("--dry-run", action="store_true", help="read and check the drives only; no fitting")
    p.add_argument("--wheel-loads", type=wheel_loads, default=None, metavar="FL,FR,RL,RR",
                   help="the car's static wheel loads in N, as weighed (wheel-load scale): pins the sprung mass, "
                        "which drives recording motion only do not tell apart from the friction levels")
    add_topic_map_argument(p)


MIN_IMU_SAMPLES = 10  # the finder needs this many measured samples per drive


def check_drives(paths, topic_map=None) -> list[tuple[str, TestDrive]]:
    """Read and check every drive (RecordingError/SuspInputError naming the file): ``(path, drive)`` pairs,
    which the fit then uses (each drive is read once)."""
    out = []
    for d in paths:
        if not Path(d).exists():  # a file, or a rosbag2 directory
            raise SuspInputError(f"{d}: no such recorded test drive")
        drive = check_drive(read_drive(d, topic_map=topic_map), d)
        imu_topic = drive.extra.get("input_topics", {}).get("imu", "/imu/data")
        if drive.imu is None or len(drive.imu) < MIN_IMU_SAMPLES:
            raise RecordingError(f"{d}: fewer than {MIN_IMU_SAMPLES} measured IMU samples on {imu_topic} "
                                 f"(got {0 if drive.imu is None else len(drive.imu)}): nothing to diagnose "
                                 f"against" + ("; file truncated" if drive.extra.get("truncated") else ""))
        out.append((str(d), drive))
    return out


def drive_summaries(read: list[tuple[str, TestDrive]]) -> list[dict]:
    """One line's facts per checked ``(path, drive)``: maneuver, duration [s], IMU samples, truncation."""
    return [{"drive": path, "maneuver": drive.metadata.get("maneuver", ""), "duration_s": drive.duration_s,
             "imu_samples": 0 if drive.imu is None else len(drive.imu),
             "truncated": bool(drive.extra.get("truncated", False))}
            for path, drive in read]


def _weighed(loads: list[float] | None) -> dict:
    """The finder's arguments for a weighed car: the loads [N] and the scale's accuracy (inspection settings)."""
    return {} if loads is None else {"wheel_loads_n": loads, "scale_accuracy": scale_accuracy()}


def run(args) -> dict:
    topic_map = getattr(args, "topic_map", None)
    read = check_drives(args.drives, topic_map)
    if args.dry_run:
        checked = drive_summaries(read)
        return {"dry_run": True, "drives": checked,
                "summary": "\n".join(f"{c['drive']}: {c['maneuver'] or 'drive'}, {c['duration_s']:.2f} s, "
                                     f"{c['imu_samples']} IMU samples" + (" (truncated)" if c["truncated"] else "")
                                     for c in checked) + "\nchecked; nothing fitted (--dry-run)"}
    cands = [c.strip() for c in args.candidates.split(",") if c.strip()] if args.candidates else None
    f = DiscrepancyFinder(vehicle=args.config, variant=args.variant, candidates=cands,
                          heldout=not args.no_heldout, progress=not args.no_progress,
                          **_weighed(getattr(args, "wheel_loads", None)))
    f.fit(cases_of_read(read, wheelbase=load_vehicle(args.config).wheelbase))  # each drive read once
    base = Path(args.variant).stem
    name = args.name or f"diagnosed_{base}"
    paths = write_outputs(f, args.out, name, plots=not args.no_plots)
    append_to_report(paths["report"])  # the input findings (io/integrity.py), one line each
    rep = f.report()
    if getattr(args, "json", False):
        return rep
    v, why = verdict(f)
    lines = [f"verdict: {v} ({why})",
             f"noise floor {rep['noise_floor_deg_s']:.4f} deg/s; "
             f"{'in-sample' if args.no_heldout else 'held-out'} RMSE {rep['heldout_rmse_before_deg_s']:.4f}"
             f" -> {rep['heldout_rmse_after_deg_s']:.4f} deg/s"]
    informed = [c for c in rep["calibration"] if c["informed"]]
    lines.append(f"calibration: {len(informed)} of {len(rep['calibration'])} base-model parameters informed by "
                 f"the drives" + (": " + ", ".join(f"{c['param']}{'' if c['where'] == 'all' else '_' + c['where']} "
                                                    f"{c['prior']:.4g} -> {c['value']:.4g} {c['unit']}"
                                                    for c in informed[:6]) + (" ..." if len(informed) > 6 else "")
                                   if informed else ""))
    if rep.get("wheel_loads"):
        w = rep["wheel_loads"]
        lines.append(f"weighed: {w['total_mass_kg']:.0f} kg in all; sprung mass prior "
                     f"{w['sprung_mass_prior_kg']:.0f} +- {w['sprung_mass_prior_sd_kg']:.1f} kg "
                     f"(vehicle file {w['vehicle_file_sprung_mass_kg']:.0f} kg)")
    for c in rep["calibration"]:
        if c["outside_prior"]:
            lines.append(f"  finding: {outside_statement(c)}")
    if rep.get("unmeasured_input"):
        u = rep["unmeasured_input"]
        lines.append(f"unmeasured input ({u['kind']}) drives {', '.join(u['signals'])}; ISO 8608 class "
                     f"{u['iso8608_class'] or 'unknown'}")
    for t in rep["terms"]:
        lines.append(f"  {t['name']} ({t['where']}): {t['evidence'].get('statement', '')}")
    for s in rep["not_identifiable"]:
        lines.append(f"  not identifiable: {s['name']} -> reveal with {s['reveal_with']}")
    lines.append(f"{len(rep['windows'])} windows above noise; report {paths['report']}, variant {paths['variant']}"
                 f" ({f.elapsed_s_:.1f} s)")
    return {**rep, "summary": "\n".join(lines)}
