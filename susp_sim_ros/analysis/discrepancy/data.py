"""Drive preparation for the discrepancy finder: model inputs, comparison grid, measured signals.

Each recorded test drive becomes a :class:`DriveCase`: the per-step model inputs exactly as the lockstep
runner / node would apply them (inputs held from their message time on, acceleration from successive
speed messages), its road, oil levels, and the measured gyro rates resampled onto the validator's common
grid (:mod:`susp_sim_ros.analysis.validation`: integer-ns grid at the lower of the two sample rates, linear
interpolation, never extrapolating) inside the drive's analysis window (bump window / pitch rate for bump
crossings, steering window / roll rate for sine steering, as in the paper's tables).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from collections.abc import Sequence

import numpy as np

from ...errors import RecordingError, SuspInputError
from ...io.drive import TestDrive, read_drive
from ...io.integrity import IntegrityError, require_live_imu
from ...model.layout import N_U, U_INDEX
from ...model.paper import IMU_OUTPUTS, IMU_SIGNALS, classify_maneuver
from ...model.road import RoadProfile
from ...runtime.sim_core import accel_between
from .. import validation as va
from ..validation_study import classify_state

NS = va.NS
SIM_RATE_HZ = 1000.0  # the model's 1 ms step


@dataclass
class DriveCase:
    """One drive prepared for batch simulation and comparison.

    ``U`` (n_steps, N_U) per-step inputs; ``grid_ns`` comparison times [ns] (the measured IMU sample
    times in the analysis window); ``y_meas`` (n_grid, n_sig) measured signals there (rates [deg/s],
    specific forces [m/s^2]), ``axes`` their columns in :data:`SIGNALS`; ``quiet`` mask of grid samples before the
    drive's first excitation (set after the base simulation, see :func:`mark_quiet`).
    """

    name: str
    path: str
    maneuver: str | None
    state: str
    oil: np.ndarray
    U: np.ndarray
    road: RoadProfile | None
    t0_ns: int
    dt: float
    signals: tuple[str, ...]
    axes: np.ndarray
    window: va.Window
    grid_ns: np.ndarray
    y_meas: np.ndarray
    drive: object = field(repr=False, default=None)
    quiet: np.ndarray | None = None
    quiet_raw: np.ndarray | None = None      # the same over every recorded sample (t_raw_s)
    metadata: dict = field(default_factory=dict)
    t_raw_s: np.ndarray | None = None       # every measured sample time within the simulated span [s since t0]
    y_raw: np.ndarray | None = None         # all six measured signals there (SIGNALS order), for the noise
    resample_factor: float = 1.0            # noise variance factor of resampling (1: compared as sampled)
    holes_s: tuple[tuple[float, float], ...] = ()  # excluded spans of the measured IMU [s since t0] (gaps)

    @property
    def n_steps(self) -> int:
        return self.U.shape[0]

    @property
    def t_grid_s(self) -> np.ndarray:
        """Grid times [s] since the drive's first input message."""
        return (self.grid_ns - self.t0_ns) / NS

    @property
    def t_sim_s(self) -> np.ndarray:
        """Times [s] (since the first input) of the simulation outputs: after each step."""
        return self.dt * np.arange(1, self.n_steps + 1)


def _held(t_msg_ns: np.ndarray, values: np.ndarray, t0_ns: int, n_steps: int, step_ns: int) -> np.ndarray:
    """Per-step value held from each message on (a message at t applies from step floor((t-t0)/dt))."""
    first_step = (np.asarray(t_msg_ns, np.int64) - t0_ns) // step_ns
    k = np.arange(n_steps)
    idx = np.searchsorted(first_step, k, side="right") - 1
    out = np.zeros((n_steps,) + values.shape[1:])
    ok = idx >= 0
    out[ok] = values[idx[ok]]
    return out


def _linear(t_msg_ns: np.ndarray, values: np.ndarray, t0_ns: int, n_steps: int, dt: float) -> np.ndarray:
    """Per-step value linearly interpolated between messages at the step start times (held outside)."""
    t = (np.asarray(t_msg_ns, np.int64) - t0_ns) / NS
    k = dt * np.arange(n_steps)
    v = np.asarray(values, float)
    if v.ndim == 1:
        return np.interp(k, t, v)
    return np.column_stack([np.interp(k, t, v[:, j]) for j in range(v.shape[1])])


def speed_accelerations(t_ns, v) -> np.ndarray:
    """Longitudinal acceleration [m/s^2] in effect after each speed message, by the node's rule
    (:func:`~susp_sim_ros.runtime.sim_core.accel_between`, as :meth:`~susp_sim_ros.runtime.sim_core.SimCore.set_speed`):
    a message at the same time as the previous one (or earlier) changes the speed but keeps the
    acceleration; 0 before the second message."""
    t = np.asarray(t_ns, np.int64)
    v = np.asarray(v, float)
    acc = np.zeros(len(v))
    a, t_last, v_last = 0.0, None, 0.0
    for k in range(len(v)):
        step = accel_between(t_last, v_last, int(t[k]), float(v[k]))
        if step is not None:
            a = step[0]
        acc[k] = a
        t_last, v_last = int(t[k]), float(v[k])
    return acc


def make_inputs_from_drive(drive, dt: float = 0.001, hold: bool = False) -> tuple[np.ndarray, int]:
    """Per-step inputs (n_steps, N_U) and the time origin [ns] of a recorded drive.

    Recorded inputs are samples of continuous signals; offline, the finder reconstructs them by linear
    interpolation between samples (``hold=False``). The node and the lockstep runner hold each message
    until the next one (``hold=True``), which delays the input by half a sample period on average (5 ms
    at 100 Hz): on a sine steer that shows as a spurious lag of several milliseconds that the
    ``time_offset`` term would otherwise have to absorb. Acceleration from successive speed messages."""
    step_ns = int(round(dt * NS))
    t0 = drive.t0_ns
    n_steps = int((drive.t_end_ns - t0) // step_ns)
    if n_steps < 10:
        raise RecordingError(f"drive too short to simulate: {n_steps} steps")
    U = np.zeros((n_steps, N_U))
    sp = drive.speed
    fill = (lambda tm, v: _held(tm, np.asarray(v, float), t0, n_steps, step_ns)) if hold else \
        (lambda tm, v: _linear(tm, v, t0, n_steps, dt))
    U[:, U_INDEX["V"]] = fill(sp.t_ns, sp.values)
    U[:, U_INDEX["AX"]] = _held(sp.t_ns, speed_accelerations(sp.t_ns, sp.values), t0, n_steps, step_ns)
    st = drive.steering
    U[:, U_INDEX["SWA"]] = fill(st.t_ns, st.values)
    if drive.wheel_heights is not None and len(drive.wheel_heights):
        wh = drive.wheel_heights
        U[:, U_INDEX["ZR_IN"]:U_INDEX["ZR_IN"] + 4] = fill(wh.t_ns, wh.values)
    return U, t0


#: Every IMU signal the finder can compare (interface.md, SIGNAL), its model output and unit.
SIGNALS = IMU_SIGNALS
SIGNAL_OUTPUT = IMU_OUTPUTS
SIGNAL_UNIT = ("deg/s", "deg/s", "deg/s", "m/s^2", "m/s^2", "m/s^2")
#: signal -> (model output, factor from the output's SI unit to the signal's unit)
SIGNAL_OF_OUTPUT = {s: (o, math.degrees(1.0) if u == "deg/s" else 1.0)
                    for s, o, u in zip(SIGNALS, SIGNAL_OUTPUT, SIGNAL_UNIT)}
GYRO = IMU_SIGNALS[:3]


def primary_signals(maneuver: str | None) -> tuple[str, ...]:
    """The gyro signal(s) a drive's legacy deg/s figures are about: the paper's comparison signal of its
    maneuver (pitch rate for bump crossings, roll rate for sine steering), else every gyro axis."""
    return (va.MANEUVER_SIGNAL[maneuver],) if maneuver in va.MANEUVER_SIGNAL else GYRO


#: what :func:`require_sound_imu` names as the user of the measured IMU (load_cases serves both)
USERS = "the discrepancy finder and the inspection"


def unsound_signals(drive) -> dict[str, str]:
    """The IMU signals (:data:`SIGNALS` names) the input integrity check (:mod:`susp_sim_ros.io.integrity`)
    found unfit to compare against, each with its finding's kind: ``dead_sensor`` (no noise, or one value
    repeated: ``drive.extra["unusable_signals"]``) or ``saturated_sensor`` (clipped by the sensor range,
    peaks lower than the motion: ``drive.extra["saturated_signals"]``). Empty for a drive that was not
    checked (built in memory)."""
    extra = getattr(drive, "extra", {}) or {}
    out = {s: "saturated_sensor" for s in extra.get("saturated_signals", ()) if s in SIGNALS}
    out.update({s: "dead_sensor" for s in extra.get("unusable_signals", ()) if s in SIGNALS})
    return out


def require_sound_imu(path: str | Path, drive) -> None:
    """IntegrityError (exit 2) when the drive leaves nothing sound to compare: a gyro axis the integrity
    check found dead (every gyro axis is a comparison signal of some maneuver, and the finder's fallback
    signal), or the maneuver's primary gyro signal(s) (:func:`primary_signals`, what the finder's deg/s
    figures are about) clipped by the sensor range. Other dead or saturated signals are left out
    (:func:`prepare_case`)."""
    require_live_imu(drive, path, USERS, verb="need")  # io/integrity.py: dead gyro axes
    maneuver = classify_maneuver(drive.metadata.get("maneuver", ""))
    prim = primary_signals(maneuver)
    require_live_imu(drive, path, USERS, signals=prim, saturated=True, verb="need",
                     need=f"the maneuver's primary signal{'s' if len(prim) > 1 else ''} {', '.join(prim)} "
                          f"within the sensor range")


def prepare_case(path: str | Path, drive, *, wheelbase: float, dt: float = 0.001,
                 signals: Sequence[str] | None = None) -> DriveCase:
    """A :class:`DriveCase` of a read drive (``drive`` from :func:`~susp_sim_ros.io.drive.read_drive`).

    The comparison is made at the measured IMU sample times inside the drive's analysis window (the
    simulation, at 1 kHz and smooth, is interpolated onto them; the measurement is never resampled, so
    the residual holds the sensor's noise exactly as sampled). Where the integrity check excluded a span of
    the measured IMU (``drive.extra["excluded_spans"]``: a gap, never interpolated across) no sample inside
    it is compared, and the span is kept as ``holes_s`` so that nothing downstream (noise differences,
    sliding windows) reaches across it. ``signals`` (default: all six IMU
    signals) are narrowed to the excited ones by the finder once the noise is known. A signal the
    integrity check found dead or saturated (:func:`unsound_signals`) is left out: not used as a
    measurement (``y_raw`` keeps all six columns, as recorded).
    """
    path = Path(path)
    if drive.imu is None or len(drive.imu) < 10:
        raise RecordingError(f"{path}: no measured IMU samples on /imu/data: nothing to diagnose against")
    meta = drive.metadata
    maneuver = classify_maneuver(meta.get("maneuver", ""))
    oil_text = str(meta.get("damper_oil_level", "")).strip().lower()
    oil = np.array(drive.oil_levels(), float) if oil_text not in ("", "unknown") else np.ones(4)
    U, t0 = make_inputs_from_drive(drive, dt)
    windows = va.analysis_windows(drive, wheelbase)
    wname = va.MANEUVER_WINDOW.get(maneuver, "whole") if maneuver is not None else "whole"
    window = windows.get(wname, windows["whole"])
    signals = tuple(signals) if signals is not None else SIGNALS
    unknown = [x for x in signals if x not in SIGNALS]
    if unknown:
        raise SuspInputError(f"unknown signals {unknown}; known: {', '.join(SIGNALS)}")
    unsound = unsound_signals(drive)
    signals = tuple(x for x in signals if x not in unsound)
    if not signals:
        topic = drive.extra.get("input_topics", {}).get("imu", "/imu/data")
        kinds = " or ".join(sorted(set(unsound.values())))
        raise IntegrityError(f"{path}: topic {topic}: every signal asked for is {kinds} (see the input findings): "
                             f"nothing sound to compare against")
    axes = np.array([SIGNALS.index(x) for x in signals])
    meas_all = np.column_stack([np.degrees(drive.imu.gyro), drive.imu.accel])
    t_meas, m_meas = va.check_series(drive.imu.t_ns, meas_all, f"{path} /imu/data")
    holes = excluded_imu_spans(drive)
    inside = np.zeros(t_meas.size, bool)
    for a, b in holes:  # strictly inside: the samples bounding a gap are measured and compared
        inside |= (t_meas > a) & (t_meas < b)
    t_meas, m_meas = t_meas[~inside], m_meas[~inside]
    sim_span = (t0 + int(round(dt * NS)), t0 + U.shape[0] * int(round(dt * NS)))
    span = va.overlap((int(t_meas[0]), int(t_meas[-1])), sim_span, window.span,
                      what=[f"{path} /imu/data", "simulation", f"{window.name} window"])
    inwin = (t_meas >= span[0]) & (t_meas <= span[1])
    if inwin.sum() < 20:
        raise RecordingError(f"{path}: only {int(inwin.sum())} IMU samples in the {window.name} window")
    grid = t_meas[inwin]
    y = m_meas[inwin][:, axes]
    insim = (t_meas >= sim_span[0]) & (t_meas <= sim_span[1])
    return DriveCase(name=path.stem, path=str(path), maneuver=maneuver, state=classify_state(oil),
                     oil=oil, U=U, road=drive.road, t0_ns=int(t0), dt=dt, signals=signals, axes=axes,
                     window=window, grid_ns=grid, y_meas=y, drive=drive, metadata=dict(meta),
                     t_raw_s=(t_meas[insim] - t0) / NS, y_raw=m_meas[insim], resample_factor=1.0,
                     holes_s=tuple(((a - t0) / NS, (b - t0) / NS) for a, b in holes))


def excluded_imu_spans(drive) -> list[tuple[int, int]]:
    """The spans [ns] of the measured IMU the integrity check excluded (``drive.extra["excluded_spans"]`` of
    the IMU topic, e.g. gaps), sorted; empty for a drive that was not checked."""
    extra = getattr(drive, "extra", {}) or {}
    topic = extra.get("input_topics", {}).get("imu", "/imu/data")
    return sorted((int(a), int(b)) for a, b in extra.get("excluded_spans", {}).get(topic, ()))


def segment_starts(t_s: np.ndarray, holes_s: Sequence[tuple[float, float]]) -> list[int]:
    """Indices into the sorted times ``t_s`` where a new stretch starts after an excluded span (the first
    sample past the span's middle, when samples lie on both sides of it)."""
    out = []
    for a, b in holes_s:
        k = int(np.searchsorted(t_s, 0.5 * (a + b)))
        if 0 < k < t_s.size:
            out.append(k)
    return sorted(set(out))


def select_signals(case: DriveCase, keep: Sequence[str]) -> None:
    """Narrow ``case`` to the signals ``keep`` (in its own order)."""
    cols = [j for j, s in enumerate(case.signals) if s in keep]
    case.signals = tuple(case.signals[j] for j in cols)
    case.axes = case.axes[cols]
    case.y_meas = case.y_meas[:, cols]


def has_road_input(case: DriveCase) -> bool:
    """Whether the recording gives the road under the wheels (a profile or wheel heights)."""
    zr = U_INDEX["ZR_IN"]
    return (case.road is not None and len(case.road) >= 2) or bool(np.any(case.U[:, zr:zr + 4] != 0))


def load_cases(paths: Sequence[str | Path], *, wheelbase: float, dt: float = 0.001,
               topic_map=None) -> list[DriveCase]:
    """Read and prepare drives (through ``topic_map``, see :mod:`susp_sim_ros.io.topic_map`, if given);
    :class:`SuspInputError` naming the file on unreadable input."""
    if not paths:
        raise SuspInputError("give at least one recorded test drive (MCAP)")
    read = []
    for p in paths:
        p = Path(p)
        if not p.exists():  # a file, or a rosbag2 directory
            raise SuspInputError(f"{p}: no such file")
        read.append((p, read_drive(p, topic_map=topic_map)))
    return cases_of_read(read, wheelbase=wheelbase, dt=dt)


def cases_of_read(read: Sequence[tuple[str | Path, TestDrive]], *, wheelbase: float,
                  dt: float = 0.001) -> list[DriveCase]:
    """:func:`load_cases` of drives already read: ``(path, drive from read_drive)`` pairs."""
    cases: list[DriveCase] = []
    names: set[str] = set()
    for p, drive in read:
        require_sound_imu(p, drive)  # io/integrity.py findings; other dead/saturated signals are left out
        case = prepare_case(p, drive, wheelbase=wheelbase, dt=dt)
        if case.name in names:
            case.name = f"{case.name}_{len(names)}"
        names.add(case.name)
        cases.append(case)
    return cases


def as_cases(drives, *, wheelbase: float, dt: float = 0.001, topic_map=None) -> list[DriveCase]:
    """Drives given as data -- paths of recordings, read :class:`~susp_sim_ros.io.drive.TestDrive`
    objects or prepared :class:`DriveCase` objects, one or a sequence, mixed -- as cases of their own:
    a case given is copied (the finder marks and narrows its cases; the caller's stay as they were). A
    read drive is named after its ``maneuver`` metadata and position."""
    items = [drives] if isinstance(drives, (str, Path, TestDrive, DriveCase)) else list(drives)
    if not items:
        raise SuspInputError("give at least one recorded test drive (MCAP)")
    cases = []
    for k, d in enumerate(items):
        if isinstance(d, DriveCase):
            cases.append(dataclasses.replace(d))
        elif isinstance(d, TestDrive):
            name = f"drive{k}_{d.metadata.get('maneuver') or 'unnamed'}"
            case = prepare_case(Path(name), d, wheelbase=wheelbase, dt=dt)
            case.name = name
            cases.append(case)
        else:
            cases.extend(load_cases([d], wheelbase=wheelbase, dt=dt, topic_map=topic_map))
    names: set[str] = set()
    for c in cases:
        if c.name in names:
            c.name = f"{c.name}_{len(names)}"
        names.add(c.name)
    return cases


def mark_quiet(case: DriveCase, sim_rates_deg_s: np.ndarray, *, threshold_deg_s: float = 0.005,
               margin_s: float = 0.05) -> None:
    """Mark the grid samples before the drive's first excitation: where the base simulation's body
    rates (all three gyro axes, [deg/s], at the simulation's step times) are still below
    ``threshold_deg_s``, minus a margin. Used for the standstill-style sensor-bias estimate."""
    active = np.nonzero(np.any(np.abs(sim_rates_deg_s) > threshold_deg_s, axis=1))[0]
    t_on = case.t_sim_s[active[0]] - margin_s if active.size else case.t_sim_s[-1]
    case.quiet = case.t_grid_s < t_on
    case.quiet_raw = case.t_raw_s < t_on


def excitation_onset_s(case: DriveCase) -> float:
    q = case.quiet
    if q is None or not q.any():
        return 0.0
    return float(case.t_grid_s[np.nonzero(q)[0][-1]])


def _finite(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None
