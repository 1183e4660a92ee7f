"""The paper-style validation study over a folder of recorded test drives.

For every drive (``*.mcap``) in a folder: simulate it with all four friction variants of the paper's
Table 5 in lockstep (:func:`susp_sim_ros.runtime.lockstep.run_lockstep`, the very code path that equals the
node replaying the drive), validate each simulation against the measured IMU
(:mod:`.validation`), and write

- the paper's tables: pitch-rate RMSE for bump crossings (bump window), roll-rate RMSE for sine
  steering (steering window), deg/s, variants x vehicle states;
- overlay plots, measured vs each variant, one PNG per maneuver and state;
- a Markdown report (``report.md``) and the full result as JSON (``study.json``);
- per drive, the ride and road-holding metrics (:mod:`.ride_recording`) of each variant's simulation and
  the measured Wk comfort over the same time (``drives[].ride``, a table in the report);
- the input findings of every drive read (:mod:`susp_sim_ros.io.integrity`, issue 28): ``input_findings``
  in ``study.json`` (and per drive, ``drives[].input_findings``) and an ``## Input findings`` section in the
  report. A drive the check refuses (nothing sound left, or the table signal of its maneuver dead) is left
  out of the tables and named, with the check's error, in ``refused_drives`` and in that section; the study
  stops with that error only when it refuses every drive. IMU gaps are left out of every comparison
  (``exclude``), dead gyro axes get no metric, and a drive whose ``vehicle`` has no parameter set is
  simulated as the reference car (a ``bad_metadata`` finding).

The maneuver of a drive comes from its ``test_drive`` metadata (``maneuver`` starting with a name or
alias of the maneuver registry, :func:`~susp_sim_ros.model.paper.classify_maneuver`: ``bump_crossing``
or ``sine_steer``), the vehicle state from ``damper_oil_level``. Drives of other maneuvers are validated
and reported but stay out of the paper tables.

Speed: the four variants share one compiled kernel; a lockstep run of a bundled drive takes a few tens
of milliseconds, so the whole study over ``bags/`` takes a few seconds (most of it plotting). Batch runs
(:func:`~susp_sim_ros.model.simulate_batch`) would only pay off for hundreds of drives.
"""
from __future__ import annotations

import json
import math
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from collections.abc import Sequence

import numpy as np

from ..errors import RecordingError, SuspInputError
from ..io.drive import TestDrive, read_drive
from ..io.integrity import IntegrityError, drive_vehicle, markdown, require_live_imu
from ..io.messages import SUSPENSION_COLUMNS
from ..model import Model
from ..model.maneuvers import vehicle_state
from ..model.paper import (HEADLINE_MANEUVER, MANEUVERS, STATES, VARIANT_LABEL, VARIANTS,
                           classify_maneuver)
from ..progress import progress as make_progress
from ..runtime.lockstep import run_lockstep
from . import validation as va
from . import ride_recording as rr
from .synthetic import SOURCE

PAPER_RATIO = 65.0  # paper: rear dampers oil-empty, bump crossing, RMSE dahl_only / full
# measured with the generator (bags/README.md, "How much each ingredient costs"); valid for its version
ABLATION_NOTE = ("For this generator version, the same chain without any hidden physics gives a ratio of about "
                 "6.4, with only the amplitude-dependent friction about 2.7, with only the parameter "
                 "differences about 3.5 (bags/README.md). ")
COLORS = {"full": "tab:blue", "no_horizontal": "tab:orange", "no_velocity": "tab:green",
          "dahl_only": "tab:red"}


def _synthetic_source() -> str:
    return SOURCE


def classify_state(oil: Sequence[float] | np.ndarray) -> str:
    """Vehicle state name of oil levels FL, FR, RL, RR; ``oil_<levels>`` for other combinations."""
    for name in STATES:
        if tuple(float(x) for x in oil) == vehicle_state(name):
            return name
    return "oil_" + "_".join(f"{x:g}" for x in oil)


@dataclass
class DriveResult:
    """One drive of the study: what it is, and each variant's validation."""

    path: str
    maneuver: str | None
    state: str
    vehicle: str
    source: str
    signal: str
    window: str
    drive: TestDrive = field(repr=False)
    results: dict[str, va.ValidationResult] = field(default_factory=dict)
    sims: dict = field(default_factory=dict, repr=False)
    plot: str | None = None
    ride: dict = field(default_factory=dict)  # {"measured": {...}, "simulated": {variant: {...}}}
    input_findings: list = field(default_factory=list)  # io/integrity.py findings of the drive

    def rmse(self, variant: str) -> float:
        return self.results[variant].rmse_deg_s(self.window, self.signal)

    def as_dict(self) -> dict:
        return {"file": self.path, "maneuver": self.maneuver, "state": self.state, "vehicle": self.vehicle,
                "source": self.source, "signal": self.signal, "window": self.window,
                "rmse_deg_s": {v: self.rmse(v) for v in self.results},
                "validation": {v: r.as_dict() for v, r in self.results.items()}, "plot": self.plot,
                "ride": self.ride, "input_findings": [dict(f) for f in self.input_findings]}


def _find_drives(folder: Path) -> list[Path]:
    if not folder.is_dir():
        raise SuspInputError(f"--study {folder}: not a directory")
    drives = sorted(folder.glob("*.mcap"))
    # rosbag2 as on disk too: sqlite3 files and bag directories (metadata.yaml), after the MCAP files
    drives += sorted(folder.glob("*.db3")) + sorted(p.parent for p in folder.glob("*/metadata.yaml"))
    if not drives:
        raise SuspInputError(f"--study {folder}: no recorded test drives (*.mcap, *.db3, rosbag2 directories) in it")
    return drives


def simulate_and_validate(path: str | Path, drive, variants: Sequence[str], models: dict, progress=None) -> DriveResult:
    """Lockstep-simulate one drive with every variant and validate each against its measured IMU."""
    if drive.imu is None or len(drive.imu) < 2:
        raise RecordingError(f"{path}: no measured IMU samples on /imu/data: nothing to validate against")
    meta = drive.metadata
    maneuver = classify_maneuver(meta.get("maneuver", ""))
    vehicle = drive_vehicle(drive, path)  # the reference car for a vehicle without parameters (bad_metadata)
    signal = va.MANEUVER_SIGNAL.get(maneuver or "", "pitch_rate")
    # input integrity (io/integrity.py): the table signal must be live; other dead gyro axes get no metric,
    # IMU gaps are left out of every comparison (never interpolated across)
    require_live_imu(drive, path, "the validation study", signals=(signal,),
                     need=f"the table signal {signal} of the drive's maneuver live")
    dead = set(drive.extra.get("unusable_signals", ()))
    signals = [x for x in va.RATE_SIGNALS if x not in dead]
    imu_topic = drive.extra.get("input_topics", {}).get("imu", "/imu/data")
    exclude = _imu_gaps(drive)
    wheelbase = _model(models, vehicle, variants[0]).vehicle.wheelbase
    windows = va.analysis_windows(drive, wheelbase)
    window = va.MANEUVER_WINDOW.get(maneuver or "", "whole")
    if window not in windows:
        window = "whole"
    state = classify_state(drive.oil_levels()) if drive.oil_known else "unknown (simulated intact)"
    res = DriveResult(str(path), maneuver, state, vehicle,
                      meta.get("source", ""), signal, window, drive=drive,
                      input_findings=list(drive.extra.get("input_findings", ())))
    for v in variants:
        sim = run_lockstep(drive, vehicle=vehicle, variant=v, model=_model(models, vehicle, v))
        if not sim.healthy or len(sim.imu) < 2:
            raise RecordingError(f"{path}: the {v} simulation produced no valid output "
                                 f"(rejected inputs: {sim.rejections or 'none'})")
        try:
            r = va.validate(drive.imu.t_ns, drive.imu.gyro, sim.imu.t_ns, sim.imu.gyro, windows=windows,
                            signals=signals, names=(f"{path} {imu_topic}", f"{v} simulation"), exclude=exclude)
        except RecordingError as exc:
            raise RecordingError(f"{path}: {exc}") from None
        if window not in r.metrics:
            why = r.skipped.get(window, "")
            if exclude:  # the damage left nothing of the window: the check's refusal, named
                t0 = drive.t0_ns
                gaps = ", ".join(f"{(a - t0) / va.NS:.3f}-{(b - t0) / va.NS:.3f} s" for a, b in exclude)
                raise IntegrityError(f"{path}: topic {imu_topic}: gap {gaps} (log time from the recording's "
                                     f"first message): the {window} window has too few IMU samples outside the "
                                     f"gaps ({why}); expected IMU samples over the window")
            raise RecordingError(f"{path}: analysis window {window!r} has no overlap with the {v} "
                                 f"simulation: {why}")
        res.results[v] = r
        res.sims[v] = sim.imu
        _add_ride(res, drive, sim, v, _model(models, vehicle, v).vehicle)
        if progress is not None:
            progress.update(1)
    return res


def _add_ride(res: DriveResult, drive, sim, variant: str, vp) -> None:
    """Ride metrics of one variant's lockstep simulation (its outputs are what /sim/suspension carries)
    and, once per drive, the measured Wk comfort, over the time both IMUs cover."""
    span = va.overlap((int(drive.imu.t_ns[0]), int(drive.imu.t_ns[-1])), (int(sim.imu.t_ns[0]), int(sim.imu.t_ns[-1])))
    vargs = rr.vehicle_ride_args(vp)
    susp = sim.values[:, SUSPENSION_COLUMNS].reshape(len(sim.t_ns), 4, -1)
    res.ride.setdefault("simulated", {})[variant] = rr.ride_of_series(
        sim.imu.t_ns, sim.imu.gyro, sim.imu.accel, sim.t_ns, susp, span, what=f"{res.path} {variant}", **vargs)
    if "measured" not in res.ride:
        res.ride["measured"] = rr.comfort_of_series(drive.imu.t_ns, drive.imu.accel, span, gravity=vargs["gravity"],
                                                    what=f"{res.path} /imu/data")


def _imu_gaps(drive) -> list:
    """The excluded spans [ns] of the drive's measured IMU (gaps, io/integrity.py)."""
    topic = drive.extra.get("input_topics", {}).get("imu", "/imu/data")
    return list(drive.extra.get("excluded_spans", {}).get(topic, ()))


def _model(models: dict, vehicle: str, variant: str):
    key = (vehicle, variant)
    if key not in models:
        models[key] = Model(vehicle, variant)
    return models[key]


def tables(drives: Sequence[DriveResult], variants: Sequence[str] = VARIANTS) -> dict:
    """``{maneuver: {state: {variant: rmse_deg_s}}}``; several drives of one cell are averaged."""
    cells: dict = {}
    for d in drives:
        if d.maneuver is None:
            continue
        for v in variants:
            cells.setdefault(d.maneuver, {}).setdefault(d.state, {}).setdefault(v, []).append(d.rmse(v))
    out = {m: {s: {v: float(np.mean(x)) for v, x in by_v.items()}
               for s, by_v in sorted(by_s.items(), key=lambda kv: _state_key(kv[0]))}
           for m, by_s in cells.items()}
    return {m: out[m] for m in MANEUVERS if m in out} | {m: out[m] for m in out if m not in MANEUVERS}


def _state_key(s: str):
    return (STATES.index(s), s) if s in STATES else (len(STATES), s)


# ---- plots ---------------------------------------------------------------------------------------------
def plot_drive(d: DriveResult, path: Path) -> None:
    """Measured vs each variant (top) and each variant's error (bottom) of the table signal, deg/s."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ax_i = va.SIGNAL_AXIS[d.signal]
    imu = d.drive.imu
    assert imu is not None, "simulate_and_validate keeps only drives with a measured IMU"
    t0 = int(imu.t_ns[0])
    fig, (ax, ax_e) = plt.subplots(2, 1, figsize=(9, 6), sharex=True, height_ratios=[2, 1])
    ax.plot((imu.t_ns - t0) * 1e-9, np.degrees(imu.gyro[:, ax_i]), color="0.55", lw=0.8,
            label="measured (/imu/data)")
    for v, sim in d.sims.items():
        ts = (sim.t_ns - t0) * 1e-9
        ax.plot(ts, np.degrees(sim.gyro[:, ax_i]), color=COLORS.get(v), lw=1.2,
                label=f"{VARIANT_LABEL.get(v, v)}: RMSE {d.rmse(v):.3f} deg/s")
        grid = va.common_grid(va.overlap((int(imu.t_ns[0]), int(imu.t_ns[-1])),
                                         (int(sim.t_ns[0]), int(sim.t_ns[-1]))), 100.0)
        err = va.resample(sim.t_ns, np.degrees(sim.gyro[:, ax_i]), grid) - \
            va.resample(imu.t_ns, np.degrees(imu.gyro[:, ax_i]), grid)
        for a, b in _imu_gaps(d.drive):  # not drawn across an IMU gap (left out of every comparison)
            err[(grid > a) & (grid < b)] = np.nan
        ax_e.plot((grid - t0) * 1e-9, err, color=COLORS.get(v), lw=1.0)
    w = d.results[next(iter(d.results))].windows[d.window]
    for a in (ax, ax_e):
        a.axvspan((w.start_ns - t0) * 1e-9, (w.end_ns - t0) * 1e-9, color="0.92", zorder=0)
        a.grid(True, lw=0.3)
    name = d.signal.replace("_", " ")
    ax.set_ylabel(f"{name} [deg/s]")
    ax_e.set_ylabel("simulated - measured [deg/s]")
    ax_e.set_xlabel("time since the first IMU sample [s]")
    ax.set_title(f"{d.maneuver or 'drive'}, {d.state}: {name}, measured vs friction variants "
                 f"(shaded: {d.window} window)", fontsize=10)
    ax.legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


# ---- report --------------------------------------------------------------------------------------------
def _fmt(x: float) -> str:
    return "n/a" if x is None or not math.isfinite(x) else f"{x:.3f}"


def findings(tab: dict, variants: Sequence[str] = VARIANTS) -> dict:
    """Per maneuver and state: the dahl_only/full ratio and the spread max/min over variants."""
    out: dict = {}
    for m, by_s in tab.items():
        for s, row in by_s.items():
            vals = [row[v] for v in variants if v in row]
            f = {"spread_max_over_min": (max(vals) / min(vals)) if vals and min(vals) > 0 else math.inf}
            if "full" in row and "dahl_only" in row and row["full"] > 0:
                f["dahl_only_over_full"] = row["dahl_only"] / row["full"]
            out.setdefault(m, {})[s] = f
    return out


def _report_header(drives: Sequence[DriveResult], elapsed_s: float, variants: Sequence[str]) -> list[str]:
    """The report's title, what was run, and whether the drives are synthetic."""
    lines = ["# Validation study: friction variants against recorded test drives", "",
             f"{len(drives)} drives, {len(variants)} friction variants each, simulated in lockstep "
             f"(step 1 ms, output 100 Hz) and compared with the measured IMU; {elapsed_s:.1f} s in all.",
             "RMSE in deg/s over the analysis window of the maneuver (see below). Model 1 = `full`, "
             "2 = `no_horizontal`, 3 = `no_velocity`, 4 = `dahl_only` (paper Table 5).", ""]
    sources = sorted({d.source for d in drives})
    synthetic = [d for d in drives if d.source.startswith("synthetic:")]
    if synthetic:
        lines += ["> **The drives are synthetic**, not measurements (`source: " + ", ".join(sources) + "`). "
                  "Hidden physics of the generator: " + synthetic[0].drive.metadata.get("hidden_physics", "?"),
                  ""]
    return lines


def _report_tables(tab: dict, found: dict, variants: Sequence[str]) -> list[str]:
    """One RMSE table per maneuver: state x variant, with the ratios."""
    lines: list[str] = []
    for m in tab:
        sig = va.MANEUVER_SIGNAL.get(m, "pitch_rate").replace("_", " ")
        lines += [f"## {m}: {sig} RMSE [deg/s]", "",
                  "| state | " + " | ".join(f"{VARIANT_LABEL.get(v, v)}" for v in variants)
                  + " | dahl_only / full | max / min |",
                  "|---|" + "---|" * (len(variants) + 2)]
        for s, row in tab[m].items():
            f = found[m][s]
            lines.append(f"| {s} | " + " | ".join(_fmt(row.get(v)) for v in variants)
                         + f" | {_fmt(f.get('dahl_only_over_full'))} | {_fmt(f['spread_max_over_min'])} |")
        lines.append("")
    return lines


def _report_findings(drives: Sequence[DriveResult], tab: dict, found: dict) -> list[str]:
    """The findings against the paper, in words."""
    lines: list[str] = []
    synthetic = [d for d in drives if d.source.startswith("synthetic:")]
    lines += ["## Findings against the paper", ""]
    bi = found.get(HEADLINE_MANEUVER.name, {}).get("intact")
    br = found.get(HEADLINE_MANEUVER.name, {}).get("rear_empty")
    if bi:
        ok = bi["spread_max_over_min"] < 1.5
        lines.append(f"- Intact car, bump crossing: the variants are {'nearly equal' if ok else 'NOT equal'} "
                     f"(max/min RMSE {bi['spread_max_over_min']:.2f}); the paper: no visible difference, "
                     "hydraulic damping masks friction on the intact car.")
    for m in tab:
        if "intact" not in tab[m]:
            continue
        row = tab[m]["intact"]
        peaks = [float(np.max(np.abs(np.degrees(d.drive.imu.gyro[:, va.SIGNAL_AXIS[d.signal]]))))
                 for d in drives if d.maneuver == m and d.state == "intact" and d.drive.imu is not None]
        spread = max(row.values()) - min(row.values())
        rel = spread / max(peaks) if peaks and max(peaks) > 0 else math.inf
        lines.append(f"- Intact car, {m}: the variants' RMSE differ by at most {spread:.3f} deg/s, "
                     f"{100 * rel:.1f} % of the measured peak {va.MANEUVER_SIGNAL[m].replace('_', ' ')} "
                     f"({max(peaks, default=math.nan):.1f} deg/s)"
                     + (": hardly visible in the overlay plot." if rel < 0.05 else "."))
    if br and "dahl_only_over_full" in br:
        r = br["dahl_only_over_full"]
        row = tab[HEADLINE_MANEUVER.name]["rear_empty"]
        lines.append(f"- Rear dampers oil-empty, bump crossing: `dahl_only` has {r:.1f} times the RMSE of "
                     f"`full` ({row['dahl_only']:.3f} vs {row['full']:.3f} deg/s); the paper reports 65 times.")
        lines += ["", "Why the ratio differs from the paper's 65: a ratio of RMSEs is set by its denominator. "
                  "The paper's 65 means its full model reproduced the measured rear-empty bump crossing almost "
                  "exactly. Here `full` keeps an error floor of everything it does not model: "
                  + ("the generator's hidden physics (amplitude-dependent friction, about +22 N per rear wheel "
                     "at the bump's stroke amplitudes, and small mass/inertia/spring differences) plus sensor "
                     "noise, bias and bandwidth of the IMU. "
                     + (ABLATION_NOTE if any(d.source == _synthetic_source() for d in synthetic) else "")
                     + "The numerator, `dahl_only` missing the oil and velocity scaling of the "
                     "damper friction (10 N instead of up to 44 N per rear damper), is of the same size as "
                     "in the paper; the denominator is not, by design: the bundled drives must keep the "
                     "amplitude-dependent friction clearly visible for the discrepancy finder."
                     if synthetic else
                     "sensor noise and bias, parameter errors and physics no variant has (e.g. the "
                     "amplitude dependence of friction the paper names as its outlook)."), ""]
    return lines


def _report_windows_and_agreement(drives: Sequence[DriveResult]) -> list[str]:
    """The analysis window of each drive and the agreement of its table signal."""
    lines: list[str] = []
    lines += ["## Analysis windows", ""]
    for d in drives:
        w = d.results[next(iter(d.results))].windows[d.window]
        lines.append(f"- `{Path(d.path).name}`: {d.window} window {w.start_ns / 1e9:.2f}-{w.end_ns / 1e9:.2f} s "
                     f"(log time): {w.why}")
    lines += ["", "## Per drive: agreement of the table signal (`full` / `dahl_only`)", "",
              "| drive | signal | RMSE | max error | correlation | phase lag [ms] |", "|---|---|---|---|---|---|"]
    for d in drives:
        cells = []
        for k in ("rmse", "max_error", "correlation", "phase_lag_s"):
            vals = []
            for v in ("full", "dahl_only"):
                if v in d.results:
                    x = getattr(d.results[v].metrics[d.window][d.signal], k)
                    vals.append(_fmt(x * 1e3 if k == "phase_lag_s" else x))
            cells.append(" / ".join(vals))
        lines.append(f"| `{Path(d.path).name}` | {d.signal} | " + " | ".join(cells) + " |")
    return lines


def _report_ride(drives: Sequence[DriveResult]) -> list[str]:
    """Ride and road holding per drive."""
    lines: list[str] = []
    lines += ["", "## Ride and road holding per drive", "",
              ("ISO 2631-1 Wk-weighted RMS vertical acceleration at the centre of gravity (measured: the drive's "
               "IMU; it has no suspension travel or tyre loads), and from each simulation's suspension outputs the "
               "dynamic tyre load RMS (Fz - Fz0) / Fz0 against the static wheel loads, suspension travel RMS and "
               "stop contacts; over the time both recordings cover, Wk at the recordings' own rates."), "",
              ("| drive | variant | Wk RMS measured / simulated [m/s^2] | dyn. tyre load RMS FL / FR / RL / RR "
               "| travel RMS max [mm] | stop contacts |"), "|---|---|---|---|---|---|"]
    for d in drives:
        meas = d.ride.get("measured", {}).get("comfort_wk_rms_m_s2", math.nan)
        for v, r in d.ride.get("simulated", {}).items():
            dtl = " / ".join(_fmt(x) for x in r["dynamic_tyre_load_rms_rel"].values())
            lines.append(f"| `{Path(d.path).name}` | {v} | {_fmt(meas)} / {_fmt(r['comfort_wk_rms_m_s2'])} | {dtl} "
                         f"| {1e3 * max(r['suspension_travel_rms_m'].values()):.1f} "
                         f"| {sum(r['stop_contacts'].values())} |")
    return lines


def _report_plots(drives: Sequence[DriveResult]) -> list[str]:
    """The overlay plots."""
    lines: list[str] = []
    lines += ["", "## Plots (measured vs each variant)", ""]
    for d in drives:
        if d.plot:
            lines += [f"### {d.maneuver or Path(d.path).stem}, {d.state}", "",
                      f"![{Path(d.plot).name}]({Path(d.plot).name})", ""]
    return lines


def _report_inputs(findings: Sequence[dict], refused: Sequence[dict]) -> list[str]:
    """The ``## Input findings`` section: one line per finding of every drive read (io/integrity.py), one per
    drive the check refused (left out of the tables); nothing when there are neither."""
    text = markdown(list(findings))
    if not text and not refused:
        return []
    lines = text.rstrip("\n").split("\n") if text else ["", "## Input findings", ""]
    lines += [f"- refused, left out of the tables: {r['error']}" for r in refused]
    return lines


def write_validation_report(path: Path, drives: Sequence[DriveResult], tab: dict, found: dict, elapsed_s: float,
                 variants: Sequence[str] = VARIANTS, *, input_findings: Sequence[dict] = (),
                 refused: Sequence[dict] = ()) -> None:
    """The study's Markdown report at ``path``: tables, findings, windows, agreement, ride, plots, and the
    input findings (with the drives refused)."""
    lines = (_report_header(drives, elapsed_s, variants) + _report_tables(tab, found, variants)
             + _report_findings(drives, tab, found) + _report_windows_and_agreement(drives)
             + _report_ride(drives) + _report_plots(drives) + _report_inputs(input_findings, refused))
    path.write_text("\n".join(lines) + "\n")


# ---- the study -----------------------------------------------------------------------------------------
def run_validation_study(folder, out_dir, *, variants: Sequence[str] = VARIANTS, plots: bool = True,
                         progress: bool = True, topic_map=None) -> dict:
    """Run the study over ``folder``; write plots, ``report.md`` and ``study.json`` into ``out_dir``.
    ``topic_map`` (see :mod:`susp_sim_ros.io.topic_map`) is applied to every drive.

    Returns the JSON-ready dict (``tables``, ``elapsed_s``, ``findings``, ``drives``, ...)."""
    t_start = time.perf_counter()
    folder, out = Path(folder), Path(out_dir)
    paths = _find_drives(folder)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise SuspInputError(f"--out {out}: cannot create the directory: {exc.strerror or exc}") from None
    bar = make_progress(total=len(paths) * len(variants), desc="study", unit="run", enabled=progress)
    models: dict = {}
    results: list[DriveResult] = []
    refused: list[dict] = []
    inputs: list[dict] = []  # the input findings of every drive read
    try:
        for p in paths:
            bar.set_postfix_str(p.name)
            try:
                drive = read_drive(p, topic_map=topic_map)
                try:
                    results.append(simulate_and_validate(p, drive, variants, models, bar))
                finally:  # the check's findings and those of the study's own reading (the drive's vehicle)
                    inputs += [dict(f) for f in drive.extra.get("input_findings", ())]
            except IntegrityError as exc:  # nothing sound left of this drive: named, the others go on
                refused.append({"file": str(p), "error": str(exc)})
                print(f"study: {p}: refused, left out of the tables: {exc}", file=sys.stderr)
    finally:
        bar.close()
    if refused and not results:
        raise IntegrityError(f"--study {folder}: the input integrity check refused every drive: "
                             + "; ".join(r["error"] for r in refused))
    if plots:
        for d in results:
            name = f"{d.maneuver}_{d.state}" if d.maneuver else Path(d.path).stem
            if any(r.plot and Path(r.plot).stem == name for r in results):
                name = Path(d.path).stem
            d.plot = str(out / f"{name}.png")
            plot_drive(d, Path(d.plot))
    tab = tables(results, variants)
    found = findings(tab, variants)
    elapsed = time.perf_counter() - t_start
    report = out / "report.md"
    write_validation_report(report, results, tab, found, elapsed, variants, input_findings=inputs,
                            refused=refused)
    result = {"tables": tab, "elapsed_s": elapsed, "unit": "deg/s",
              "signals": {m: va.MANEUVER_SIGNAL[m] for m in MANEUVERS},
              "windows": {m: va.MANEUVER_WINDOW[m] for m in MANEUVERS},
              "findings": found, "paper_ratio_rear_empty_bump": PAPER_RATIO,
              "drives": [d.as_dict() for d in results], "report": str(report),
              "plots": [d.plot for d in results if d.plot], "variants": list(variants),
              "input_findings": inputs, "refused_drives": refused}
    (out / "study.json").write_text(json.dumps(result, indent=1, default=_jsonable))
    result["elapsed_s"] = time.perf_counter() - t_start
    return result


def _jsonable(x):
    if isinstance(x, np.generic):
        return x.item()
    return str(x)


def validation_summary_text(result: dict) -> str:
    """Human summary: the tables and the headline findings."""
    lines = []
    for m, by_s in result["tables"].items():
        sig = result["signals"].get(m, "")
        lines.append(f"{m} ({sig.replace('_', ' ')} RMSE, deg/s)")
        vs = result["variants"]
        lines.append("  " + f"{'state':<13}" + "".join(f"{v:>15}" for v in vs))
        for s, row in by_s.items():
            lines.append("  " + f"{s:<13}" + "".join(f"{row.get(v, math.nan):>15.3f}" for v in vs))
    m = HEADLINE_MANEUVER.name
    f = result["findings"].get(m, {})
    if "rear_empty" in f and "dahl_only_over_full" in f["rear_empty"]:
        lines.append(f"{m} rear_empty: dahl_only / full = {f['rear_empty']['dahl_only_over_full']:.2f} "
                     f"(paper: {PAPER_RATIO:g})")
    if "intact" in f:
        lines.append(f"{m} intact: max / min over variants = {f['intact']['spread_max_over_min']:.2f}")
    ride = [(Path(d["file"]).stem, d["ride"]) for d in result.get("drives", []) if d.get("ride")]
    if ride:
        v = result["variants"][0]
        lines.append(f"ride ({v}; Wk RMS measured/simulated m/s^2, dyn. tyre load RMS rear): " + ", ".join(
            f"{name} {r['measured']['comfort_wk_rms_m_s2']:.2f}/{r['simulated'][v]['comfort_wk_rms_m_s2']:.2f} "
            f"{max(r['simulated'][v]['dynamic_tyre_load_rms_rel'][w] for w in ('RL', 'RR')):.3f}"
            for name, r in ride if v in r.get("simulated", {})))
    found, refused = result.get("input_findings", []), result.get("refused_drives", [])
    if found or refused:
        lines.append(f"input: {len(found)} finding(s) in the drives read, {len(refused)} drive(s) refused "
                     f"and left out of the tables" + "".join(f"\n  refused: {r['error']}" for r in refused)
                     + " (see the report's Input findings)")
    lines.append(f"report: {result['report']}  ({result['elapsed_s']:.1f} s)")
    return "\n".join(lines)
