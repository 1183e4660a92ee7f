"""Locate the mismatch: the noise floor from the data itself, and the windows where the residual exceeds it.

Noise floor: the white-noise RMS of the gyro as the comparison sees it (after resampling onto the
validator's grid). The model error is smooth (body modes of 1-15 Hz seen at 200 Hz), sensor noise is
white, so the second difference of the residual at the measured sample times (base simulation minus
measurement, before any resampling), ``e[k+1] - 2 e[k] + e[k-1]``, is noise-dominated and has variance
``6 sigma^2`` for white noise; ``sigma`` is estimated robustly from its median absolute deviation. Linear
resampling onto the comparison grid averages neighbouring samples, which lowers the noise variance by
``mean(w^2 + (1 - w)^2)`` (``w``: each grid point's position between its two samples); the floor is
``sigma`` times the root of that factor, i.e. the noise RMS the RMSE figures actually contain. (Taking
second differences of the already resampled residual would underestimate it: interpolation correlates
neighbouring grid samples.) The standard deviation of the resampled measurement over each drive's quiet
lead-in (before the first excitation) is reported next to it as a cross-check. No fitted model enters.

Windows: sliding windows of ``WINDOW_S`` over each drive's comparison grid; a window is significant when
its residual mean square exceeds what noise alone gives with probability 1e-3
(``sigma^2 * chi2.ppf(0.999, n) / n``). Overlapping significant windows are merged, and each gets the
operating conditions there from the base simulation (deflection amplitude and velocity per axle,
horizontal wheel forces, oil levels) and the residual's dominant frequency.
"""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np
from scipy import stats

from ...model import simulate
from ...model.layout import WHEELS
from .data import DriveCase

WINDOW_S = 0.5
HOP_S = 0.25
P_FALSE = 1e-3


def noise_sigma(e: np.ndarray) -> float:
    """Robust white-noise RMS of a residual column from its second differences (see module doc)."""
    e = np.asarray(e, float)
    if e.size < 5:
        return math.nan
    d2 = e[2:] - 2.0 * e[1:-1] + e[:-2]
    mad = np.median(np.abs(d2 - np.median(d2)))
    return float(1.4826 * mad / math.sqrt(6.0))


def noise_floor(cases: Sequence[DriveCase], rates: Sequence[np.ndarray]) -> dict:
    """Pooled noise floor [deg/s] over drives and compared signals, with per-drive values and the
    quiet-lead-in cross-check; ``rates`` are the base simulation's gyro rates [deg/s] per drive
    (n_steps, 3) at the step times."""
    per, quiet, weights, raw = {}, {}, [], {}
    var = []
    for c, y in zip(cases, rates):
        t = c.dt * np.arange(1, y.shape[0] + 1)
        e = np.column_stack([np.interp(c.t_raw_s, t, y[:, a]) for a in c.axes]) - c.y_raw
        s = [noise_sigma(e[:, j]) for j in range(e.shape[1])]
        raw[c.name] = float(np.sqrt(np.mean(np.square(s))))
        per[c.name] = raw[c.name] * math.sqrt(c.resample_factor)
        var.append(per[c.name] ** 2)
        weights.append(c.y_meas.shape[0])
        if c.quiet is not None and c.quiet.sum() >= 10:
            quiet[c.name] = float(np.sqrt(np.mean(np.var(c.y_meas[c.quiet], axis=0, ddof=1))))
    w = np.array(weights, float)
    floor = float(np.sqrt(np.sum(w * np.array(var)) / np.sum(w)))
    q = list(quiet.values())
    return {"noise_floor_deg_s": floor, "per_drive_deg_s": per, "raw_sample_noise_deg_s": raw,
            "resample_variance_factor": {c.name: c.resample_factor for c in cases},
            "quiet_lead_in_std_deg_s": quiet,
            "quiet_lead_in_pooled_deg_s": float(np.sqrt(np.mean(np.square(q)))) if q else None,
            "method": "MAD of second differences of the raw-sample residual / sqrt(6), times the root of the "
                      "linear-resampling variance factor, pooled over drives (white-noise RMS on the "
                      "comparison grid); cross-check: std over each drive's quiet lead-in"}


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


def locate(cases: Sequence[DriveCase], residuals: Sequence[np.ndarray], sigma: float,
           outputs: Sequence[dict] | None = None) -> list[dict]:
    """Significant windows (merged), each with drive, signal, time span, RMS, conditions."""
    found = []
    for ci, (c, e) in enumerate(zip(cases, residuals)):
        t = c.t_grid_s
        rate = 1.0 / float(np.median(np.diff(t)))
        nwin = max(int(round(WINDOW_S * rate)), 10)
        hop = max(int(round(HOP_S * rate)), 1)
        thr = _threshold(sigma, nwin)
        for j, sig in enumerate(c.signals):
            flags = []
            for s in range(0, max(e.shape[0] - nwin, 0) + 1, hop):
                seg = e[s:s + nwin, j]
                if np.sqrt(np.mean(seg * seg)) > thr:
                    flags.append((s, s + nwin))
            merged = []
            for a, b in flags:
                if merged and a <= merged[-1][1]:
                    merged[-1][1] = b
                else:
                    merged.append([a, b])
            for a, b in merged:
                seg = e[a:b, j]
                t0, t1 = float(t[a]), float(t[min(b, len(t)) - 1])
                w = {"drive": c.name, "signal": sig, "start_s": t0, "end_s": t1,
                     "rms_deg_s": float(np.sqrt(np.mean(seg * seg))),
                     "mean_deg_s": float(np.mean(seg)), "peak_deg_s": float(np.max(np.abs(seg))),
                     "threshold_deg_s": thr, "ratio_to_noise": float(np.sqrt(np.mean(seg * seg)) / sigma),
                     "dominant_frequency_hz": _dominant_frequency(seg, rate),
                     "maneuver": c.maneuver, "state": c.state}
                if outputs is not None:
                    cond = _conditions(c, outputs[ci], t0, t1)
                    w["conditions"] = cond
                    w["axle"] = max(cond, key=lambda a: cond[a]["deflection_velocity_rms_m_s"]
                                    * (2.0 - sum(cond[a]["oil_level"]) / 2.0))
                found.append(w)
    return found
