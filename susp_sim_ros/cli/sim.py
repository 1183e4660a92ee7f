"""``susp sim``: offline run of a paper maneuver, or of a recorded test drive (``--drive``), in lockstep.

Both modes feed the drive's input messages into the node's own simulation core (``SimCore``) as fast as
possible; ``--out`` writes the simulated MCAP the node would record (inputs, ``/sim`` topics,
``test_drive`` metadata with ``source: simulated:<variant>``). A paper maneuver becomes a test drive with
inputs at the integration step (so it equals the offline :func:`simulate` run), a recorded drive uses its
recorded message times.

Exit 1 (after writing ``--out`` up to the last good sample) when the divergence guard stopped the run
(non-finite or absurd state, e.g. from an absurd vehicle parameter file); the message says when and
which outputs left the envelope.
"""
from __future__ import annotations

import numpy as np

from ..control.controllers import CONTROLLERS
from ..control.ride import RideSpec, parse_road, run_ride
from ..errors import SuspInputError
from ..io.drive import parse_oil, read_drive
from ..io.topic_map import add_topic_map_argument
from ..runtime.lockstep import maneuver_drive, run_lockstep
from ..model import Model
from ..model.maneuvers import STATES, paper_maneuver, vehicle_state
from ..model.paper import DEFAULT_MANEUVER, INTACT, MANEUVER_CHOICES, maneuver_kind
from ..runtime.sim_core import DivergenceError
from ..model.params import DEFAULT_VEHICLE


def add_arguments(p) -> None:
    p.add_argument("--maneuver", choices=MANEUVER_CHOICES, default=None,
                   help=f"paper maneuver (default {maneuver_kind(DEFAULT_MANEUVER).aliases[0]} when no --drive "
                        "is given)")
    p.add_argument("--drive", metavar="X.MCAP", help="recorded test drive to run in lockstep (MCAP file, rosbag2 "
                   "directory or .db3 file)")
    p.add_argument("--state", choices=STATES, default=None,
                   help=f"vehicle state (damper oil levels); default: {INTACT} for a maneuver, the drive's "
                        "damper_oil_level metadata for --drive")
    p.add_argument("--oil", metavar="FL,FR,RL,RR", help="damper oil levels, overrides --state")
    p.add_argument("--variant", default="full", help="friction variant name or YAML path")
    p.add_argument("--config", default=DEFAULT_VEHICLE, help="vehicle parameter set name or YAML path")
    p.add_argument("--step", type=float, default=0.001, help="integration step [s]")
    p.add_argument("--rate", type=float, default=100.0, help="publish rate of the /sim topics [Hz]")
    p.add_argument("--out", metavar="SIM.MCAP", help="write the simulated MCAP here")
    p.add_argument("--overwrite", action="store_true", help="overwrite --out if it exists")
    add_topic_map_argument(p)
    ride = p.add_argument_group("ride on a random road (semi-active dampers; interface.md 'Semi-active and ride')")
    ride.add_argument("--road", metavar="iso8608:CLASS", help="drive straight over a seeded ISO 8608 random road "
                      "of this class (A-H) and report ride and road-holding metrics")
    ride.add_argument("--speed", type=float, default=80.0, help="constant speed on --road [km/h] (default 80)")
    ride.add_argument("--duration", type=float, default=20.0, help="length of the --road run [s] (default 20)")
    ride.add_argument("--seed", type=int, default=0, help="seed of the --road profile (default 0)")
    ride.add_argument("--controller", default="passive", help="damper controller on --road: passive (no "
                      "command, default), skyhook, skyhook_onoff, groundhook, add, sh_add; also in the loop of a "
                      "--maneuver or --drive run, at the --rate samples")


def run(args) -> dict:
    if args.drive and args.maneuver:
        raise SuspInputError("give either --maneuver or --drive, not both")
    if getattr(args, "road", None):
        return run_ride_cli(args)
    if args.controller not in CONTROLLERS:
        raise SuspInputError(f"--controller: expected one of {', '.join(CONTROLLERS)}, got {args.controller!r}")
    model = Model(args.config, args.variant)
    if args.oil:
        oil, state = parse_oil(args.oil, "--oil"), "custom"
    elif args.state:
        oil, state = vehicle_state(args.state), args.state
    else:
        oil, state = None, ("from_metadata" if args.drive else INTACT)
    if not (np.isfinite(args.step) and 0 < args.step <= 0.01):
        raise SuspInputError(f"--step: expected a step in (0, 0.01] s, got {args.step}")
    if args.drive:
        drive = read_drive(args.drive, topic_map=args.topic_map)
        name = drive.metadata.get("maneuver", "") or str(args.drive)
    else:
        man = paper_maneuver(args.maneuver or DEFAULT_MANEUVER, model.vehicle.wheelbase)
        oil = oil if oil is not None else vehicle_state(INTACT)
        drive = maneuver_drive(man, oil, rate_hz=1.0 / args.step, vehicle=model.vehicle.name)
        name = man.name
    res = run_lockstep(drive, vehicle=args.config, variant=args.variant, oil=oil, step_s=args.step,
                       publish_rate_hz=args.rate, out_path=args.out, overwrite=args.overwrite, model=model,
                       controller=args.controller)
    if res.diverged:
        raise DivergenceError(f"{name}: {res.diverged} (variant {model.variant.name}, vehicle "
                              f"{model.vehicle.name}, step {args.step} s"
                              + (f"; {args.out} holds the samples before" if args.out else "") + ")")
    deg = np.degrees
    peak = lambda label: float(np.max(np.abs(res[label]))) if len(res) else 0.0
    out = {
        "maneuver": name, "state": state, "variant": model.variant.name,
        "vehicle": model.vehicle.name, "duration_s": drive.duration_s, "ok": bool(res.healthy),
        "peak_pitch_rate_deg_s": float(deg(peak("PITCH_RATE"))),
        "peak_roll_rate_deg_s": float(deg(peak("ROLL_RATE"))),
        "peak_yaw_rate_deg_s": float(deg(peak("YAW_RATE"))),
        "peak_lateral_acceleration_m_s2": peak("AY_SF"),
        "damper_oil_level": [float(x) for x in res.metadata["damper_oil_level"].split(",")],
        "samples": len(res), "rejected_inputs": res.rejections, "out": res.out_path,
    }
    if args.drive:
        out["drive"] = str(args.drive)
    out["summary"] = (f"{name} ({state}, {model.variant.name}, {out['duration_s']:.1f} s): "
                      f"peak pitch rate {out['peak_pitch_rate_deg_s']:.2f} deg/s, roll rate "
                      f"{out['peak_roll_rate_deg_s']:.2f} deg/s, yaw rate {out['peak_yaw_rate_deg_s']:.2f} deg/s"
                      + (f"; wrote {args.out}" if args.out else ""))
    return out


def run_ride_cli(args) -> dict:
    """``susp sim --road iso8608:C --speed 80 ...``: the ride metrics of one controller."""
    if args.drive or args.maneuver:
        raise SuspInputError("--road drives its own maneuver: give no --drive or --maneuver with it")
    if args.controller not in CONTROLLERS:
        raise SuspInputError(f"--controller: expected one of {', '.join(CONTROLLERS)}, got {args.controller!r}")
    if args.out:
        raise SuspInputError("--out is not available with --road (the ride run writes no recording)")
    if not (np.isfinite(args.step) and 0 < args.step <= 0.001):
        # the Wk weighting is computed at the step's rate: >= 1 kHz keeps it within 0.3 dB to 80 Hz
        raise SuspInputError(f"--step: expected a step in (0, 0.001] s for a ride run, got {args.step}")
    cls = parse_road(args.road)
    model = Model(args.config, args.variant)
    if args.oil:
        oil, state = parse_oil(args.oil, "--oil"), "custom"
    else:
        state = args.state or INTACT
        oil = vehicle_state(state)
    spec = RideSpec(cls, args.speed / 3.6, args.duration, args.seed)
    res = run_ride(model, spec, controller=args.controller, oil=oil, step_s=args.step)
    out = {"maneuver": f"iso8608:{cls}", "road_class": cls, "speed_kmh": args.speed, "duration_s": args.duration,
           "seed": args.seed, "controller": args.controller, "state": state, "variant": model.variant.name,
           "vehicle": model.vehicle.name, "damper_oil_level": [float(x) for x in oil], **res.to_dict()}
    m = res.metrics
    dtl = sum(m.dynamic_tyre_load_rms_rel.values()) / 4
    out["summary"] = (f"iso8608:{cls} at {args.speed:g} km/h, {args.duration:g} s, seed {args.seed}, "
                      f"{args.controller} ({state}, {model.variant.name}): Wk RMS "
                      f"{m.comfort_wk_rms_m_s2:.3f} m/s^2, dynamic tyre load RMS {dtl:.3f} (mean of wheels), "
                      f"travel RMS {1000 * max(m.suspension_travel_rms_m.values()):.1f} mm (max wheel), "
                      f"stop contacts {sum(m.stop_contacts.values())}")
    return out
