"""``susp inspect``: each damper's oil level with a 95 % interval from recorded drives.

    susp inspect DRIVE.mcap... [--config VEHICLE] [--wheel-loads FL,FR,RL,RR] [--oil-law OIL:FRACTION,...]
        [--json] [--out DIR]

A slow bump crossing (5-15 km/h) is the target case; any drive that excites the suspension works. The
drives' ``damper_oil_level`` metadata is never used (an inspection drive says ``unknown``). Exit 2 on bad
input (unreadable drive, missing topic, a vehicle file without the class ranges).
"""
from __future__ import annotations

import argparse
import math

from ..analysis.inspection import inspect_drives, load_config
from ..analysis.inspection.report import write_inspection_report
from ..analysis.inspection.oil_law import OilLaw
from ..errors import ConfigError, SuspInputError
from ..io.integrity import append_to_report
from ..io.topic_map import add_topic_map_argument


def wheel_loads(text: str) -> list[float]:
    """``FL,FR,RL,RR``: four positive static wheel loads [N] (argparse type)."""
    try:
        loads = [float(v) for v in text.split(",")]
    except ValueError:
        loads = []
    if len(loads) != 4 or not all(math.isfinite(v) and v > 0 for v in loads):
        raise argparse.ArgumentTypeError(f"expected four positive static wheel loads FL,FR,RL,RR in N, got {text!r}")
    return loads


def oil_law(text: str) -> OilLaw:
    """``OIL:FRACTION,...``: the damper type's rig-tested oil law (argparse type)."""
    try:
        return OilLaw.parse(text)
    except ConfigError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


def add_arguments(p) -> None:
    p.add_argument("drives", nargs="+", metavar="DRIVE.mcap", help="recorded drives of one car")
    p.add_argument("--config", default=None,
                   help="vehicle class (parameter set name or YAML path; default: the drives' vehicle "
                        "metadata when known, else passat_b8_like)")
    p.add_argument("--variant", default="full", help="friction variant of the fitted model")
    p.add_argument("--wheel-loads", type=wheel_loads, default=None, metavar="FL,FR,RL,RR",
                   help="the car's static wheel loads in N, as weighed (wheel-load scale or the EUSAMA tester's "
                        "static reading): pins the car's mass, which a bump crossing hardly tells")
    p.add_argument("--oil-law", type=oil_law, default=None, metavar="OIL:FRACTION,...",
                   help="the damper type's oil law from a rig test of a damper drained in steps: at each oil level "
                        "the fraction of the way from the oil-empty to the intact force it keeps (e.g. "
                        "0:0,0.5:0.25,1:1); default the inspection settings' damper_type.oil_law (the model's own, "
                        "the fraction equal to the oil level)")
    p.add_argument("--out", default=None, help="write inspection.md, inspection.json and PNGs here")
    add_topic_map_argument(p)


def run(args) -> dict:
    cfg = load_config()
    res = inspect_drives(args.drives, config=args.config, variant=args.variant, cfg=cfg, topic_map=args.topic_map,
                         wheel_loads_n=args.wheel_loads, oil_law=args.oil_law)
    out = res.to_json()
    if args.out:
        out["written"] = write_inspection_report(res, args.out, cfg, args.drives)
        append_to_report(out["written"]["report"])  # the input findings (io/integrity.py), one line each
    lines = [f"damper inspection of {len(args.drives)} drive(s), {res.elapsed_s_:.1f} s:"]
    for w, e in res.wheels_.items():
        if e["oil_level"] is None:
            lines.append(f"  {w}: unknown ({e['why']})")
        else:
            lines.append(f"  {w}: oil {e['oil_level']:.2f} [{e['ci95'][0]:.2f}, {e['ci95'][1]:.2f}] "
                         f"{e['state']:8s} ({e['identifiable']})")
    for a, e in res.identifiability_.items():
        lines.append(f"  {a}: {e['why']}")
    if res.wheel_loads_:
        w = res.wheel_loads_
        lines.append(f"  weighed: {w['total_mass_kg']:.0f} kg, sprung mass {w['sprung_mass_prior_kg']:.0f} "
                     f"+- {w['sprung_mass_prior_sd_kg']:.0f} kg (vehicle file {w['vehicle_file_sprung_mass_kg']:.0f})")
    for e in res.left_right_:  # the axle's two dampers against each other
        lines.append(f"  left against right: {'ASYMMETRIC ' if e['asymmetric'] else ''}{e['reason']}")
    lines += [f"  note: {n}" for n in res.notes_]
    if args.out:
        lines.append(f"  report: {out['written']['report']}")
    out["summary"] = "\n".join(lines)
    if not res.wheels_:
        raise SuspInputError("no dampers inspected")
    return out
