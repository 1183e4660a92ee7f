"""``susp validate``: compare a simulated recording with a measured one, or run the paper-style study.

    susp validate --measured drive.mcap --simulated sim.mcap [--json]
    susp validate --study bags --out report/ [--json]

The first form aligns both recordings in time (log time), resamples them onto a common grid without
extrapolating, and reports RMSE, maximum error, mean error, correlation and phase lag of roll, pitch and
yaw rate (deg/s) over the whole overlap and over the measured drive's analysis windows (bump, steering).
The simulated IMU is ``/sim/imu/data`` if the file has it, else ``/imu/data`` (``--simulated-topic``).
It also reports ``ride`` (:mod:`susp_sim_ros.analysis.ride_recording`): over the time both recordings
cover, the simulated recording's ride and road-holding metrics from its IMU and ``/sim/suspension``
(static tyre loads of its vehicle) and the measured drive's Wk comfort from its IMU (a measured drive has
no suspension travel or tyre loads).

The second form (see :mod:`susp_sim_ros.analysis.validation_study`) simulates every drive in the folder with all four
friction variants in lockstep and writes tables, overlay plots and a Markdown report. Its JSON holds
``{"tables": {MANEUVER: {STATE: {VARIANT: rmse_deg_s}}}, "elapsed_s": ..., ...}`` (interface.md).

Exit 2 with a message naming the file for unreadable, truncated-beyond-use, junk or topic-less
recordings and for recordings without time overlap.
"""
from __future__ import annotations

import time

from ..analysis import ride_recording as rr
from ..analysis import validation as va
from ..analysis.ride_recording import summary_line
from ..analysis.validation_study import run_validation_study, validation_summary_text
from ..errors import ConfigError, RecordingError, SuspInputError
from ..io.drive import IMU, SIM_IMU, imu_from_recording, read_drive
from ..io.integrity import drive_vehicle, require_live_imu
from ..io.reader import read_recording
from ..io.suspension import SIM_SUSPENSION, suspension_from_recording
from ..io.topic_map import add_topic_map_argument
from ..model.paper import VARIANTS
from ..model.params import load_vehicle


def add_arguments(p) -> None:
    p.add_argument("--measured", help="recorded test drive (MCAP, rosbag2 directory or .db3) with the measured "
                   "/imu/data (or the IMU of --topic-map)")
    p.add_argument("--simulated", help="simulated recording (MCAP) with /sim/imu/data (or /imu/data)")
    p.add_argument("--simulated-topic", default="auto",
                   help="IMU topic of --simulated (default: /sim/imu/data if present, else /imu/data)")
    p.add_argument("--rate", type=float, default=None,
                   help="common resampling rate [Hz] (default: the lower rate of the two recordings)")
    p.add_argument("--study", metavar="DIR", help="run the paper-style study over every *.mcap in DIR")
    p.add_argument("--out", metavar="DIR", help="output directory of the study (report, plots, JSON)")
    p.add_argument("--variants", default=",".join(VARIANTS),
                   help="comma-separated friction variants of the study")
    p.add_argument("--no-plots", action="store_true", help="study without PNG plots")
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    add_topic_map_argument(p)  # applies to --measured and to the drives of --study


def run(args) -> dict:
    if args.study is not None:
        if args.measured or args.simulated:
            raise SuspInputError("give either --study DIR --out DIR or --measured A --simulated B, not both")
        if not args.out:
            raise SuspInputError("--study needs --out DIR for the report, plots and tables")
        return _study(args)
    if not (args.measured and args.simulated):
        raise SuspInputError("give --measured A --simulated B, or --study DIR --out DIR")
    return _pair(args)


def _study(args) -> dict:
    variants = tuple(v.strip() for v in args.variants.split(",") if v.strip())
    if not variants:
        raise SuspInputError("--variants: give at least one friction variant")
    res = run_validation_study(args.study, args.out, variants=variants, plots=not args.no_plots,
                               progress=not args.no_progress, topic_map=args.topic_map)
    res["summary"] = validation_summary_text(res)
    return res


def _simulated_imu(path: str, topic: str, with_recording: bool = False):
    rec = read_recording(path)
    if topic != "auto":
        return (topic, imu_from_recording(rec, topic)) + ((rec,) if with_recording else ())
    for t in (SIM_IMU, IMU):
        if rec.by_topic(t):
            return (t, imu_from_recording(rec, t)) + ((rec,) if with_recording else ())
    why = f"; file damaged: {rec.error}" if rec.truncated else ""
    raise RecordingError(f"{path}: no IMU messages on {SIM_IMU} or {IMU} (topics: "
                         f"{', '.join(sorted(rec.topics())) or 'none'}{why})")


def _pair(args) -> dict:
    t_start = time.perf_counter()
    drive = read_drive(args.measured, topic_map=args.topic_map)
    imu_topic = drive.extra.get("input_topics", {}).get("imu", "/imu/data")
    if drive.imu is None or len(drive.imu) < 2:
        raise RecordingError(f"{args.measured}: no measured IMU samples on {imu_topic} (topics: "
                             f"{', '.join(sorted(drive.extra.get('topics', {}))) or 'none'})")
    topic, sim, sim_rec = _simulated_imu(args.simulated, args.simulated_topic, with_recording=True)
    if len(sim) < 2:
        raise RecordingError(f"{args.simulated}: fewer than 2 IMU samples on {topic}")
    windows = va.analysis_windows(drive, _wheelbase_of(drive, args.measured))
    # input integrity (io/integrity.py): a dead gyro axis gives no metric, an IMU gap is left out
    dead = set(drive.extra.get("unusable_signals", ()))
    signals = [s for s in va.RATE_SIGNALS if s not in dead]
    if not signals:
        require_live_imu(drive, args.measured, "validate", need="at least one live gyro axis")
    try:
        res = va.validate(drive.imu.t_ns, drive.imu.gyro, sim.t_ns, sim.gyro, windows=windows, signals=signals,
                          rate_hz=args.rate, names=(f"{args.measured} {imu_topic}", f"{args.simulated} {topic}"),
                          exclude=drive.extra.get("excluded_spans", {}).get(imu_topic, ()))
    except RecordingError as exc:
        raise RecordingError(f"{args.measured} vs {args.simulated}: {exc}") from None
    if not res.metrics:
        raise va.NoOverlapError(f"{args.measured} vs {args.simulated}: no analysis window overlaps both "
                                f"recordings: {res.skipped}")
    out = {"measured": str(args.measured), "simulated": str(args.simulated), "simulated_topic": topic,
           "measured_truncated": bool(drive.extra.get("truncated", False)),
           "source_measured": drive.metadata.get("source", ""), **res.as_dict(),
           "rmse_deg_s": {w: {s: m.rmse for s, m in ms.items()} for w, ms in res.metrics.items()},
           "ride": _ride(args, drive, sim, sim_rec),
           "elapsed_s": time.perf_counter() - t_start}
    lines = [f"{args.measured} (measured) vs {args.simulated} ({topic})"
             + (" [measured file truncated: readable prefix used]" if out["measured_truncated"] else "")]
    for w, ms in res.metrics.items():
        win = res.windows[w]
        lines.append(f"  {w} window {win.start_ns / 1e9:.2f}-{win.end_ns / 1e9:.2f} s:")
        for s, m in ms.items():
            lag = "n/a" if m.phase_lag_s != m.phase_lag_s else f"{m.phase_lag_s * 1e3 + 0.0:+.1f} ms"
            corr = "n/a" if m.correlation != m.correlation else f"{m.correlation:.3f}"
            lines.append(f"    {s:<10} RMSE {m.rmse:.3f} deg/s, max {m.max_error:.3f} deg/s, "
                         f"correlation {corr}, lag {lag}")
    for w, why in res.skipped.items():
        lines.append(f"  {w} window skipped: {why}")
    lines.append("  " + summary_line(out["ride"]))
    out["summary"] = "\n".join(lines)
    return out


def _wheelbase_of(drive, path) -> float:
    """Wheelbase [m] of the drive's vehicle (its ``vehicle`` metadata, as the validation study reads it);
    the reference vehicle's where the drive names none or one without a parameter set here (then a
    ``bad_metadata`` finding, :func:`~susp_sim_ros.io.integrity.drive_vehicle`)."""
    return load_vehicle(drive_vehicle(drive, path)).wheelbase


def _ride(args, drive, sim, sim_rec) -> dict:
    """The ``ride`` object: over the overlap of both IMUs (and ``/sim/suspension``), the simulated
    recording's ride metrics and the measured drive's Wk comfort (see the module docstring)."""
    import logging

    vehicle = sim_rec.metadata.get("test_drive", {}).get("vehicle", "")
    try:
        vargs = rr.vehicle_ride_args(load_vehicle(vehicle)) if vehicle else None
    except ConfigError:
        vargs = None
    if vargs is None:  # unknown vehicle: gravity from the reference car (Wk removes the mean anyway)
        vargs = {**rr.vehicle_ride_args(load_vehicle()), "static_loads": None}
    spans = [(int(drive.imu.t_ns[0]), int(drive.imu.t_ns[-1])), (int(sim.t_ns[0]), int(sim.t_ns[-1]))]
    names = [f"{args.measured} IMU", f"{args.simulated} IMU"]
    susp, why = None, ""
    if sim_rec.by_topic(SIM_SUSPENSION):
        try:
            susp = suspension_from_recording(sim_rec)
            va.check_series(susp.t_ns, susp.values.reshape(len(susp), -1), f"{args.simulated} {SIM_SUSPENSION}")
            spans.append((int(susp.t_ns[0]), int(susp.t_ns[-1])))
            names.append(f"{args.simulated} {SIM_SUSPENSION}")
            va.overlap(*spans, what=names)
        except RecordingError as exc:
            susp, why = None, str(exc)
            spans, names = spans[:2], names[:2]
            logging.getLogger(__name__).warning("ride metrics without %s: %s", SIM_SUSPENSION, why)
    else:
        why = f"{args.simulated}: no {SIM_SUSPENSION}"
    span = va.overlap(*spans, what=names)
    g = vargs["gravity"]
    try:
        measured = rr.comfort_of_series(drive.imu.t_ns, drive.imu.accel, span, gravity=g,
                                        what=f"{args.measured} IMU")
        if susp is not None:
            simulated = rr.ride_of_series(sim.t_ns, sim.gyro, sim.accel, susp.t_ns, susp.values, span,
                                          what=str(args.simulated), **vargs)
            if vargs["static_loads"] is None:
                simulated["static_load_source"] += f" (vehicle {vehicle!r})" if vehicle else " (no vehicle metadata)"
        else:
            simulated = rr.comfort_of_series(sim.t_ns, sim.accel, span, gravity=g, what=f"{args.simulated} IMU")
            simulated["note"] = f"comfort only: {why}"
    except RecordingError as exc:  # the rate comparison stands; the ride metrics say why they are missing
        logging.getLogger(__name__).warning("no ride metrics: %s", exc)
        return {"error": f"{args.measured} vs {args.simulated}: ride metrics: {exc}"}
    return {"measured": measured, "simulated": simulated, "start_s": span[0] / va.NS, "end_s": span[1] / va.NS}
