"""The offline validator: compare a simulated recording with a measured one.

Pure numpy, no ROS runtime. The steps, each its own function so each can be tested:

1. **Align** (:func:`common_grid`): both recordings carry ROS log times (a simulated recording made by the
   node replaying a drive with ``/clock``, or by the lockstep runner, has the drive's time base). The
   comparison runs only over the time both recordings cover (their overlap), optionally cut to an analysis
   window, on a uniform grid of integer nanoseconds ``k * step_ns``: the grid depends on nothing but the
   overlap and the rate, so the result is exactly reproducible.
2. **Resample** (:func:`resample`): linear interpolation onto the grid. It never extrapolates: a grid time
   outside a recording's first..last sample raises :class:`ExtrapolationError`.
3. **Metrics** (:func:`compare`): RMSE, maximum absolute error, mean error, Pearson correlation and phase
   lag (cross-correlation peak, refined by a parabola; positive = the simulation lags the measurement).
4. **Windows** (:func:`analysis_windows`): the bump window (from shortly before the front axle reaches the
   first road unevenness until the end of the ring-out after the rear axle left it) and the steering
   window (from shortly before the first steering input until the end of the ring-out after the last one).

Rates are rad/s on the wire; :func:`validate` reports them in deg/s, and every key says so.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from collections.abc import Mapping, Sequence

import numpy as np

from ..errors import RecordingError, SuspInputError
from ..model.paper import IMU_SIGNALS, MANEUVER_KINDS, PRIMARY_SIGNAL

NS = 1_000_000_000
RATE_SIGNALS = IMU_SIGNALS[:3]  # gyro axes x, y, z (REP-103)
SIGNAL_AXIS = {s: i for i, s in enumerate(RATE_SIGNALS)}
# signal the paper's tables use per maneuver (model-spec 4)
MANEUVER_SIGNAL = PRIMARY_SIGNAL  # the signal each of the paper's maneuvers is compared on
MANEUVER_WINDOW = {m: k.window for m, k in MANEUVER_KINDS.items()}  # the analysis window of each

WINDOW_LEAD_S = 0.5        # window starts this long before the first excitation
WINDOW_RINGOUT_S = 3.0     # and ends this long after the last excitation (or at the end of the data)
STEER_THRESHOLD_RAD = math.radians(1.0)   # steering-wheel angle counted as a steering input
MAX_LAG_S = 0.25           # phase-lag search range


class ExtrapolationError(SuspInputError):
    """A resampling request outside the data: the validator never invents data beyond a recording."""


class NoOverlapError(RecordingError):
    """The two recordings (or a recording and an analysis window) share no time span."""


# ---- time series checks -------------------------------------------------------------------------------
def check_series(t_ns: np.ndarray, y: np.ndarray, what: str) -> tuple[np.ndarray, np.ndarray]:
    """``t_ns`` as int64 strictly increasing, ``y`` finite with the same length; errors name ``what``."""
    t_ns = np.asarray(t_ns)
    y = np.asarray(y, dtype=float)
    if t_ns.ndim != 1 or y.shape[:1] != t_ns.shape:
        raise SuspInputError(f"{what}: times and values must have the same length, got {t_ns.shape} "
                             f"and {y.shape}")
    if t_ns.size < 2:
        raise RecordingError(f"{what}: needs at least 2 samples, got {t_ns.size}")
    t_ns = t_ns.astype(np.int64)
    bad = np.nonzero(np.diff(t_ns) <= 0)[0]
    if bad.size:
        k = int(bad[0])
        raise RecordingError(f"{what}: times must be strictly increasing; sample {k + 1} at "
                             f"{t_ns[k + 1]} ns follows {t_ns[k]} ns")
    if not np.all(np.isfinite(y)):
        k = int(np.nonzero(~np.isfinite(y).reshape(len(y), -1).all(axis=1))[0][0])
        raise RecordingError(f"{what}: non-finite value at sample {k} (t = {t_ns[k]} ns)")
    return t_ns, y


# ---- alignment and resampling ---------------------------------------------------------------------------
def overlap(*spans: tuple[int, int], what: Sequence[str] | None = None) -> tuple[int, int]:
    """Intersection ``(start_ns, end_ns)`` of closed time spans; :class:`NoOverlapError` when empty."""
    lo = max(s[0] for s in spans)
    hi = min(s[1] for s in spans)
    if hi < lo:
        names = what or [f"span {k}" for k in range(len(spans))]
        desc = ", ".join(f"{n} [{s[0] / NS:.3f}, {s[1] / NS:.3f}] s" for n, s in zip(names, spans))
        raise NoOverlapError(f"no time overlap: {desc}")
    return int(lo), int(hi)


def common_grid(span: tuple[int, int], rate_hz: float) -> np.ndarray:
    """Uniform grid ``k * step_ns`` [ns] inside the closed span, ``step_ns = round(1e9 / rate_hz)``.

    Grid times are whole multiples of the step counted from time zero, so two runs over the same span
    and rate give the same grid to the nanosecond.
    """
    if not (rate_hz > 0 and math.isfinite(rate_hz)):
        raise SuspInputError(f"rate_hz: expected a positive rate, got {rate_hz}")
    step = int(round(NS / rate_hz))
    k0 = -((-span[0]) // step)  # ceil
    k1 = span[1] // step        # floor
    if k1 < k0:
        return np.zeros(0, np.int64)
    return np.arange(k0, k1 + 1, dtype=np.int64) * step


def resample(t_ns: np.ndarray, y: np.ndarray, t_new_ns: np.ndarray) -> np.ndarray:
    """Linear interpolation of ``y`` (samples at ``t_ns``) at ``t_new_ns``; no extrapolation.

    Raises :class:`ExtrapolationError` if any requested time lies before the first or after the last
    sample. Works on 1-D ``y`` or on columns of 2-D ``y``. Times are handled relative to the first sample
    in float64 seconds, so nanosecond log times lose no precision.
    """
    t_ns = np.asarray(t_ns, dtype=np.int64)
    t_new_ns = np.asarray(t_new_ns, dtype=np.int64)
    y = np.asarray(y, dtype=float)
    if t_new_ns.size == 0:
        return np.zeros((0,) + y.shape[1:])
    if t_new_ns.min() < t_ns[0] or t_new_ns.max() > t_ns[-1]:
        raise ExtrapolationError(
            f"resampling would extrapolate: requested [{t_new_ns.min() / NS:.6f}, {t_new_ns.max() / NS:.6f}] s, "
            f"data covers [{t_ns[0] / NS:.6f}, {t_ns[-1] / NS:.6f}] s")
    x = (t_ns - t_ns[0]) / NS
    xn = (t_new_ns - t_ns[0]) / NS
    if y.ndim == 1:
        return np.interp(xn, x, y)
    return np.column_stack([np.interp(xn, x, y[:, j]) for j in range(y.shape[1])])


def median_rate(t_ns: np.ndarray) -> float:
    """Median sample rate [Hz] of a time series."""
    steps_ns: np.ndarray = np.diff(np.asarray(t_ns, dtype=np.int64))
    return float(NS / np.median(steps_ns))


# ---- metrics ----------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Metrics:
    """Agreement of a simulated with a measured signal on a common grid (units of the inputs).

    ``phase_lag_s`` > 0: the simulation lags the measurement. ``correlation`` and ``phase_lag_s`` are
    ``nan`` when a signal is constant (undefined).
    """

    n: int
    rmse: float
    max_error: float
    mean_error: float
    correlation: float
    phase_lag_s: float
    start_s: float
    end_s: float

    def as_dict(self, unit: str = "") -> dict:
        sfx = f"_{unit}" if unit else ""
        d = asdict(self)
        out = {"n": d["n"], f"rmse{sfx}": d["rmse"], f"max_error{sfx}": d["max_error"],
               f"mean_error{sfx}": d["mean_error"], "correlation": d["correlation"],
               "phase_lag_s": d["phase_lag_s"], "start_s": d["start_s"], "end_s": d["end_s"]}
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in out.items()}


def rmse(a: np.ndarray, b: np.ndarray) -> float:
    """Root mean square of ``a - b``."""
    e = np.asarray(a, float) - np.asarray(b, float)
    return float(np.sqrt(np.mean(e * e)))


def correlation(a: np.ndarray, b: np.ndarray) -> float:
    """Pearson correlation; ``nan`` when either signal is constant."""
    a = np.asarray(a, float) - np.mean(a)
    b = np.asarray(b, float) - np.mean(b)
    den = math.sqrt(float(np.dot(a, a)) * float(np.dot(b, b)))
    if den == 0.0:
        return math.nan
    return float(np.clip(np.dot(a, b) / den, -1.0, 1.0))


def phase_lag(measured: np.ndarray, simulated: np.ndarray, dt: float, max_lag_s: float = MAX_LAG_S) -> float:
    """Lag [s] of ``simulated`` behind ``measured`` (both on the same grid of step ``dt``).

    The integer lag maximising the Pearson correlation between a fixed central segment of ``measured``
    and the equally long segment of ``simulated`` shifted by the lag (every lag compares the same
    measured samples, so segment ends bias nothing), searched within ``+-max_lag_s`` (at most a quarter of
    the record), refined by a parabola through the peak and its neighbours. ``nan`` if a signal is
    constant.
    """
    m = np.asarray(measured, float)
    s = np.asarray(simulated, float)
    n = m.size
    kmax = min(int(max_lag_s / dt), n // 4)
    if kmax < 1 or np.ptp(m) == 0.0 or np.ptp(s) == 0.0:
        return math.nan
    seg = m[kmax:n - kmax] - np.mean(m[kmax:n - kmax])
    L = seg.size
    lags = np.arange(-kmax, kmax + 1)
    c = np.empty(lags.size)
    for j, k in enumerate(lags):
        b = s[kmax + k:kmax + k + L]
        b = b - np.mean(b)
        den = math.sqrt(float(np.dot(seg, seg)) * float(np.dot(b, b)))
        c[j] = np.dot(seg, b) / den if den > 0 else -math.inf
    j = int(np.argmax(c))
    if not math.isfinite(c[j]):
        return math.nan
    frac = 0.0
    if 0 < j < len(c) - 1 and math.isfinite(c[j - 1]) and math.isfinite(c[j + 1]):
        den = c[j - 1] - 2 * c[j] + c[j + 1]
        if den < 0:
            frac = 0.5 * (c[j - 1] - c[j + 1]) / den
    return float((lags[j] + frac) * dt)


def compare(t_meas_ns, y_meas, t_sim_ns, y_sim, *, window: tuple[int, int] | None = None,
            rate_hz: float | None = None, max_lag_s: float = MAX_LAG_S,
            names: tuple[str, str] = ("measured", "simulated"),
            exclude: Sequence[tuple[int, int]] = ()) -> Metrics:
    """Metrics of one signal: align, resample both onto the common grid, compare.

    ``rate_hz`` defaults to the lower of the two recordings' median sample rates (never inventing
    detail one recording lacks). ``window`` (ns) cuts the comparison further. Grid points inside an
    ``exclude`` span (ns, e.g. a gap of the measured IMU, io/integrity.py) are left out, never
    interpolated across; the phase lag is then not computed (NaN).
    """
    t_m, y_m = check_series(t_meas_ns, y_meas, names[0])
    t_s, y_s = check_series(t_sim_ns, y_sim, names[1])
    spans = [(int(t_m[0]), int(t_m[-1])), (int(t_s[0]), int(t_s[-1]))]
    labels = list(names)
    if window is not None:
        spans.append((int(window[0]), int(window[1])))
        labels.append("analysis window")
    span = overlap(*spans, what=labels)
    rate = rate_hz if rate_hz is not None else min(median_rate(t_m), median_rate(t_s))
    grid = common_grid(span, rate)
    if grid.size < 2:
        raise NoOverlapError(f"{names[0]} and {names[1]} overlap for {(span[1] - span[0]) / NS:.4f} s only: "
                             f"fewer than 2 samples at {rate:g} Hz")
    a = resample(t_m, y_m, grid)
    b = resample(t_s, y_s, grid)
    keep = np.ones(grid.size, bool)
    for lo, hi in exclude:
        keep &= ~((grid > lo) & (grid < hi))
    if keep.sum() < 2:
        raise NoOverlapError(f"{names[0]}: fewer than 2 samples left outside its excluded spans (gaps)")
    lag = phase_lag(a, b, 1.0 / rate, max_lag_s) if keep.all() else math.nan
    a, b = a[keep], b[keep]
    e = b - a
    return Metrics(n=int(a.size), rmse=rmse(b, a), max_error=float(np.max(np.abs(e))),
                   mean_error=float(np.mean(e)), correlation=correlation(a, b),
                   phase_lag_s=lag,
                   start_s=float(grid[0] / NS), end_s=float(grid[-1] / NS))


# ---- analysis windows --------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Window:
    """A named analysis window [start_ns, end_ns] with the reason it starts and ends where it does."""

    name: str
    start_ns: int
    end_ns: int
    why: str = ""

    @property
    def span(self) -> tuple[int, int]:
        return self.start_ns, self.end_ns


def _path(speed_t_ns: np.ndarray, speed: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Front-axle path s(t) [m] from the speed series (trapezoid; zero-order before the first sample)."""
    t = (np.asarray(speed_t_ns, np.int64) - int(speed_t_ns[0])) / NS
    v = np.asarray(speed, float)
    s = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))])
    return np.asarray(speed_t_ns, np.int64), s


def bump_window(speed_t_ns, speed, road_s, road_zl, road_zr, wheelbase: float, *, end_ns: int,
                lead_s: float = WINDOW_LEAD_S, ringout_s: float = WINDOW_RINGOUT_S) -> Window | None:
    """From ``lead_s`` before the front axle reaches the first uneven road sample until ``ringout_s``
    after the rear axle leaves the last one (or ``end_ns``). ``None`` on a flat road."""
    road_s = np.asarray(road_s, float)
    uneven = np.nonzero((np.abs(np.asarray(road_zl, float)) > 1e-6) | (np.abs(np.asarray(road_zr, float)) > 1e-6))[0]
    if road_s.size < 2 or uneven.size == 0:
        return None
    s_on = road_s[max(uneven[0] - 1, 0)]
    s_off = road_s[min(uneven[-1] + 1, road_s.size - 1)] + wheelbase
    t, s = _path(speed_t_ns, speed)
    if s[-1] < s_on:
        return None
    k_on = int(np.searchsorted(s, s_on))
    k_off = int(np.searchsorted(s, s_off))
    t_on = int(t[min(k_on, t.size - 1)])
    t_off = int(t[k_off]) if k_off < t.size else int(t[-1])
    return Window("bump", max(int(t[0]), t_on - int(lead_s * NS)), min(end_ns, t_off + int(ringout_s * NS)),
                  f"{lead_s} s before the front axle reaches the road unevenness at s = {s_on:.2f} m until "
                  f"{ringout_s} s after the rear axle leaves it")


def wheel_heights_window(t_ns, heights, *, end_ns: int, lead_s: float = WINDOW_LEAD_S,
                         ringout_s: float = WINDOW_RINGOUT_S) -> Window | None:
    """Bump window from per-wheel road heights (four-poster style input); ``None`` if all flat."""
    h = np.asarray(heights, float).reshape(len(t_ns), -1)
    on = np.nonzero(np.any(np.abs(h) > 1e-6, axis=1))[0]
    if on.size == 0:
        return None
    t = np.asarray(t_ns, np.int64)
    return Window("bump", max(int(t[0]), int(t[on[0]]) - int(lead_s * NS)),
                  min(end_ns, int(t[on[-1]]) + int(ringout_s * NS)),
                  f"{lead_s} s before the first non-zero wheel height until {ringout_s} s after the last")


def steering_window(t_ns, steering, *, end_ns: int, threshold: float = STEER_THRESHOLD_RAD,
                    lead_s: float = WINDOW_LEAD_S, ringout_s: float = WINDOW_RINGOUT_S) -> Window | None:
    """From ``lead_s`` before the steering-wheel angle first exceeds ``threshold`` [rad] until ``ringout_s``
    after it last does (or ``end_ns``). ``None`` without steering input."""
    t = np.asarray(t_ns, np.int64)
    on = np.nonzero(np.abs(np.asarray(steering, float)) > threshold)[0]
    if on.size == 0:
        return None
    return Window("steering", max(int(t[0]), int(t[on[0]]) - int(lead_s * NS)),
                  min(end_ns, int(t[on[-1]]) + int(ringout_s * NS)),
                  f"{lead_s} s before the steering-wheel angle first exceeds {math.degrees(threshold):g} deg "
                  f"until {ringout_s} s after it last does")


def analysis_windows(drive, wheelbase: float) -> dict[str, Window]:
    """Windows of a test drive (:class:`~susp_sim_ros.io.drive.TestDrive`): ``whole`` (its IMU span) plus
    ``bump`` and/or ``steering`` where the drive has that excitation. ``wheelbase`` [m] of the drive's
    vehicle: the bump window ends after the rear axle has left the bump."""
    imu = drive.imu
    t0, t1 = int(imu.t_ns[0]), int(imu.t_ns[-1])
    out = {"whole": Window("whole", t0, t1, "the whole measured IMU record")}
    w = None
    if getattr(drive, "wheel_heights", None) is not None and len(drive.wheel_heights.t_ns):
        w = wheel_heights_window(drive.wheel_heights.t_ns, drive.wheel_heights.values, end_ns=t1)
    elif getattr(drive, "road", None) is not None and drive.speed is not None and len(drive.speed.t_ns) > 1:
        r = drive.road
        w = bump_window(drive.speed.t_ns, drive.speed.values, r.s, r.zl, r.zr, wheelbase, end_ns=t1)
    if w is not None and w.end_ns > w.start_ns:
        out["bump"] = w
    if drive.steering is not None and len(drive.steering.t_ns):
        w = steering_window(drive.steering.t_ns, drive.steering.values, end_ns=t1)
        if w is not None and w.end_ns > w.start_ns:
            out["steering"] = w
    return out


# ---- one recording against another ----------------------------------------------------------------------
@dataclass
class ValidationResult:
    """Metrics per window and signal, rates in deg/s: ``metrics[window][signal]``."""

    metrics: dict[str, dict[str, Metrics]] = field(default_factory=dict)
    windows: dict[str, Window] = field(default_factory=dict)
    skipped: dict[str, str] = field(default_factory=dict)

    def rmse_deg_s(self, window: str, signal: str) -> float:
        return self.metrics[window][signal].rmse

    def as_dict(self) -> dict:
        return {
            "unit": "deg/s",
            "windows": {name: {"start_s": w.start_ns / NS, "end_s": w.end_ns / NS, "why": w.why,
                               "signals": {sig: m.as_dict("deg_s") for sig, m in self.metrics[name].items()}}
                        for name, w in self.windows.items() if name in self.metrics},
            "skipped_windows": dict(self.skipped),
        }


def validate(meas_t_ns, meas_gyro, sim_t_ns, sim_gyro, *, windows: Mapping[str, Window] | None = None,
             signals: Sequence[str] = RATE_SIGNALS, rate_hz: float | None = None,
             names: tuple[str, str] = ("measured", "simulated"),
             exclude: Sequence[tuple[int, int]] = ()) -> ValidationResult:
    """Compare gyro rates (rad/s, columns x, y, z) of a measured and a simulated recording.

    Every window in ``windows`` (default: the overlap only, as ``whole``) and every signal in
    ``signals`` gets :class:`Metrics` in deg/s. A window that does not overlap both recordings is
    listed in ``skipped`` with the reason; :class:`NoOverlapError` if the recordings share no time.
    """
    tm, gm = check_series(meas_t_ns, meas_gyro, names[0])
    ts, gs = check_series(sim_t_ns, sim_gyro, names[1])
    gm, gs = np.degrees(gm.reshape(len(tm), -1)), np.degrees(gs.reshape(len(ts), -1))
    span = overlap((int(tm[0]), int(tm[-1])), (int(ts[0]), int(ts[-1])), what=list(names))
    wins = dict(windows) if windows else {}
    wins.setdefault("whole", Window("whole", span[0], span[1], "the overlap of both recordings"))
    res = ValidationResult()
    for name, w in wins.items():
        try:
            ms = {sig: compare(tm, gm[:, SIGNAL_AXIS[sig]], ts, gs[:, SIGNAL_AXIS[sig]], window=w.span,
                               rate_hz=rate_hz, names=names, exclude=exclude) for sig in signals}
        except NoOverlapError as exc:
            res.skipped[name] = str(exc)
            continue
        res.metrics[name] = ms
        res.windows[name] = w
    return res
