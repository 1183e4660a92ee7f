"""Locate the mismatch: the noise floor of every signal from the data itself, and the windows where
the residual exceeds it.

Noise floor: the white-noise RMS per sample of each IMU signal. The model error is smooth (body modes of
1-15 Hz), sensor noise is white, so the third difference of the residual at the measured sample times
(base simulation minus measurement over the whole recording), ``e[k+2] - 3 e[k+1] + 3 e[k] - e[k-1]``,
is noise-dominated with variance ``20 sigma^2`` for white noise. Where a drive has a quiet lead-in (the
base simulation still at rest, at least :data:`MIN_QUIET` samples), the spread of the measurement there is
a second estimate; both can only overstate the noise (road or model content adds to them). The lead-in's
replaces the differences' only when that is :data:`CONTAMINATED` times higher (taking the smaller of two
noisy estimates every time would bias the floor low): on a rough road sampled at 100 Hz the wheel-hop
response reaches the differences. ``sigma`` is estimated robustly and
efficiently: a first estimate from the median absolute deviation, then the standard deviation of the
differences within +-3 of those sigmas, corrected for the truncation (a Gaussian truncated at 3 sigma
keeps 97.3 % of its variance). The comparison is made at the measured sample times (no resampling), so
this is the noise the RMSE figures contain. The standard deviation of the measurement over each drive's
quiet lead-in (before the first excitation) is reported next to it as a cross-check. No fitted model
enters.

Windows: sliding windows of ``WINDOW_S`` over each drive's comparison samples; a window is significant
when its residual mean square exceeds what noise alone gives with probability 1e-3
(``sigma^2 * chi2.ppf(0.999, n) / n``, with the signal's own sigma). Overlapping significant windows are
merged, and each gets the operating conditions there from the base simulation (deflection amplitude and
velocity per axle, horizontal wheel forces, oil levels) and the residual's dominant frequency; it names an
axle only where the road excited one (a drive with road input, deflection velocity above
:data:`AXLE_EXCITED_M_S`).
"""
from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy import stats

from ...model import simulate
from ...model.layout import WHEELS
from .data import SIGNAL_UNIT, SIGNALS, DriveCase, has_road_input, primary_signals, segment_starts, unsound_signals

WINDOW_S = 0.5
HOP_S = 0.25
P_FALSE = 1e-3
DIFF_ORDER = 3
MIN_QUIET = 30            # samples of quiet lead-in that make its spread a noise estimate of its own
CONTAMINATED = 1.3        # a difference estimate this far above the lead-in's is contaminated by content
AXLE_EXCITED_M_S = 0.01   # RMS deflection velocity [m/s] above which an axle counts as excited there
_TRUNC = 3.0
_TRUNC_VAR = 1.0 - 2 * _TRUNC * stats.norm.pdf(_TRUNC) / (2 * stats.norm.cdf(_TRUNC) - 1)


def noise_sigma(e: np.ndarray, order: int = DIFF_ORDER, breaks: Sequence[int] = ()) -> float:
    """Robust white-noise RMS of a residual column from its ``order``-th differences (module doc);
    ``breaks``: indices where a new stretch of samples starts after an excluded span (a gap of the
    measurement), no difference reaches across one."""
    e = np.asarray(e, float)
    pieces = np.split(e, [k for k in breaks if 0 < k < e.size])
    d = np.concatenate([np.diff(p, order) for p in pieces if p.size > order] or [np.zeros(0)])
    if d.size < 8:
        return math.nan
    scale = math.sqrt(math.comb(2 * order, order))
    med = np.median(d)
    s0 = 1.4826 * np.median(np.abs(d - med))
    if not s0 > 0:
        return float(s0 / scale)
    keep = np.abs(d - med) <= _TRUNC * s0
    s1 = float(np.std(d[keep], ddof=1)) / math.sqrt(_TRUNC_VAR)
    return s1 / scale


def noise_floor(cases: Sequence[DriveCase], sims: Sequence[np.ndarray]) -> dict:
    """Noise floors per drive and signal (native units: deg/s, m/s^2), pooled per signal over the drives,
    and the legacy gyro figure (pooled over each drive's primary gyro signal); ``sims`` are the base
    simulation's six IMU signals per drive (n_steps, 6) at the step times.

    A signal the integrity check found unfit on a drive (a dead axis, ``drive.extra["unusable_signals"]``,
    or one clipped by the sensor range: :func:`~.data.unsound_signals`) has no noise of its own there: its
    per-drive figure is NaN (the pooled floor stands in for it) and it stays out of the pool, as does a
    zero figure (no noise estimate); only a signal no drive measures soundly is pooled from those figures
    (so that every signal has a floor; no drive compares it). No difference of the residual reaches across
    an excluded span of the measurement (``case.holes_s``)."""
    per: dict[str, dict[str, float]] = {}
    quiet: dict[str, float] = {}
    pooled: dict[str, list[tuple[float, int]]] = {s: [] for s in SIGNALS}
    unsound_pool: dict[str, list[tuple[float, int]]] = {s: [] for s in SIGNALS}  # the fallback (doc)
    for c, y in zip(cases, sims):
        assert c.t_raw_s is not None and c.y_raw is not None  # set by data.prepare_case
        t = c.dt * np.arange(1, y.shape[0] + 1)
        per[c.name] = {}
        q = c.quiet_raw if c.quiet_raw is not None else np.zeros(c.t_raw_s.size, bool)
        unsound = unsound_signals(c.drive)
        breaks = segment_starts(c.t_raw_s, c.holes_s)
        for j, sig in enumerate(SIGNALS):
            e = np.interp(c.t_raw_s, t, y[:, j]) - c.y_raw[:, j]
            sd = noise_sigma(e, breaks=breaks)
            if sig in unsound:  # no measurement: no noise floor of its own, none in the pool
                per[c.name][sig] = math.nan
                if math.isfinite(sd) and sd > 0:
                    unsound_pool[sig].append((sd, e.size))
                continue
            if q.sum() >= MIN_QUIET:  # both overstate the noise at worst; the lead-in replaces a clearly
                sd_q = float(np.std(c.y_raw[q, j], ddof=1))  # contaminated difference estimate only
                if sd > CONTAMINATED * sd_q:
                    sd = sd_q
            per[c.name][sig] = sd
            if math.isfinite(sd) and sd > 0:  # a zero floor is no noise estimate (it would divide by zero)
                pooled[sig].append((sd, e.size))
        if c.quiet is not None and c.quiet.sum() >= 10:
            prim = [j for j, s in enumerate(c.signals) if s in primary_signals(c.maneuver)]
            if prim:
                quiet[c.name] = float(np.sqrt(np.mean(np.var(c.y_meas[c.quiet][:, prim], axis=0, ddof=1))))
    for s in SIGNALS:
        if not pooled[s]:
            pooled[s] = unsound_pool[s]
    floors = {s: float(np.sqrt(sum(v * v * n for v, n in pooled[s]) / sum(n for _, n in pooled[s])))
              for s in SIGNALS if pooled[s]}
    # legacy deg/s figure: each drive's primary gyro signal(s), weighted by their comparison samples
    num = den = 0.0
    for c in cases:
        for s in primary_signals(c.maneuver):
            v = per[c.name].get(s, math.nan)
            if math.isfinite(v):
                num += v * v * c.y_meas.shape[0]
                den += c.y_meas.shape[0]
    legacy = math.sqrt(num / den) if den else floors.get("pitch_rate", math.nan)
    qv = list(quiet.values())
    return {"noise_floor_deg_s": legacy, "noise_floors": floors, "per_drive": per,
            "units": dict(zip(SIGNALS, SIGNAL_UNIT)),
            "quiet_lead_in_std_deg_s": quiet,
            "quiet_lead_in_pooled_deg_s": float(np.sqrt(np.mean(np.square(qv)))) if qv else None,
            "method": f"robust std of {DIFF_ORDER}rd differences of the residual (base simulation - "
                      f"measurement, every sample of the recording, as sampled) / sqrt(20), pooled over "
                      f"drives per signal; cross-check: std over each drive's quiet lead-in"}


def _threshold(sigma: float, n: int) -> float:
    return sigma * math.sqrt(stats.chi2.ppf(1.0 - P_FALSE, n) / n)


def base_outputs(model, case: DriveCase, P: np.ndarray) -> dict:
    """Operating-condition signals of the base model on a drive (at the step times)."""
    labels = [f"{q}_{w}" for q in ("DEFL", "DEFL_VEL", "F_X", "F_Y") for w in WHEELS]
    res = simulate(model, case.U, dt=case.dt, road=case.road, oil=case.oil, P=P.copy(), outputs=labels)
    return {k: res[k] for k in labels} | {"t": case.t_sim_s}


def _conditions(case: DriveCase, out: dict, t0: float, t1: float) -> dict:
    t = out["t"]
    m = (t >= t0) & (t <= t1)
    cond = {}
    for axle, wheels in (("front", ("FL", "FR")), ("rear", ("RL", "RR"))):
        d = np.concatenate([out[f"DEFL_{w}"][m] for w in wheels]) if m.any() else np.zeros(1)
        v = np.concatenate([out[f"DEFL_VEL_{w}"][m] for w in wheels]) if m.any() else np.zeros(1)
        amp = max(0.5 * float(np.ptp(out[f"DEFL_{w}"][m])) if m.any() else 0.0 for w in wheels)
        fx = max(float(np.max(np.abs(out[f"F_X_{w}"][m]))) if m.any() else 0.0 for w in wheels)
        fy = max(float(np.max(np.abs(out[f"F_Y_{w}"][m]))) if m.any() else 0.0 for w in wheels)
        k = 0 if axle == "front" else 2
        cond[axle] = {"deflection_amplitude_mm": 1e3 * amp,
                      "deflection_range_mm": [1e3 * float(d.min()), 1e3 * float(d.max())],
                      "deflection_velocity_max_m_s": float(np.max(np.abs(v))),
                      "deflection_velocity_rms_m_s": float(np.sqrt(np.mean(v * v))),
                      "max_abs_longitudinal_force_N": fx, "max_abs_lateral_force_N": fy,
                      "oil_level": [float(case.oil[k]), float(case.oil[k + 1])]}
    return cond


def _dominant_frequency(e: np.ndarray, rate: float) -> float:
    if e.size < 8:
        return math.nan
    x = e - e.mean()
    spec = np.abs(np.fft.rfft(x * np.hanning(x.size)))
    f = np.fft.rfftfreq(x.size, 1.0 / rate)
    spec[0] = 0.0
    return float(f[int(np.argmax(spec))])


def locate(cases: Sequence[DriveCase], residuals: Sequence[np.ndarray], sigmas: Sequence[np.ndarray],
           outputs: Sequence[dict] | None = None) -> list[dict]:
    """Significant windows (merged), each with drive, signal, time span, RMS (native units), conditions;
    ``sigmas`` per drive: the noise sigma of each of its signals. No window reaches across an excluded
    span of the measurement (``case.holes_s``, a gap): each stretch between them is searched on its own."""
    found = []
    for ci, (c, e) in enumerate(zip(cases, residuals)):
        t = c.t_grid_s
        rate = 1.0 / float(np.median(np.diff(t)))
        nwin = max(int(round(WINDOW_S * rate)), 10)
        hop = max(int(round(HOP_S * rate)), 1)
        cuts = [0, *segment_starts(t, c.holes_s), e.shape[0]]
        for j, sig in enumerate(c.signals):
            sigma = float(sigmas[ci][j])
            thr = _threshold(sigma, nwin)
            flags = []
            for lo, hi in zip(cuts[:-1], cuts[1:]):  # one stretch between excluded spans at a time
                for s in range(lo, max(hi - nwin, lo) + 1, hop):
                    seg = e[s:min(s + nwin, hi), j]
                    if np.sqrt(np.mean(seg * seg)) > thr:
                        flags.append((s, min(s + nwin, hi), lo))
            merged: list[list[int]] = []
            for a, b, lo in flags:
                if merged and a <= merged[-1][1] and lo == merged[-1][2]:
                    merged[-1][1] = b
                else:
                    merged.append([a, b, lo])
            for a, b, _ in merged:
                seg = e[a:b, j]
                t0, t1 = float(t[a]), float(t[min(b, len(t)) - 1])
                w = {"drive": c.name, "signal": sig, "unit": SIGNAL_UNIT[SIGNALS.index(sig)],
                     "start_s": t0, "end_s": t1, "rms": float(np.sqrt(np.mean(seg * seg))),
                     "mean": float(np.mean(seg)), "peak": float(np.max(np.abs(seg))),
                     "threshold": thr, "ratio_to_noise": float(np.sqrt(np.mean(seg * seg)) / sigma),
                     "dominant_frequency_hz": _dominant_frequency(seg, rate),
                     "maneuver": c.maneuver, "state": c.state}
                if outputs is not None:
                    cond = _conditions(c, outputs[ci], t0, t1)
                    w["conditions"] = cond
                    excited = [a for a in cond if cond[a]["deflection_velocity_rms_m_s"] > AXLE_EXCITED_M_S
                               and has_road_input(c)]
                    if excited:  # named only where the road excited an axle (never on a flat road)
                        w["axle"] = max(excited, key=lambda a: cond[a]["deflection_velocity_rms_m_s"]
                                        * (2.0 - sum(cond[a]["oil_level"]) / 2.0))
                found.append(w)
    return found
