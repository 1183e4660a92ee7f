"""Unmeasured inputs: a road the recording does not contain.

A drive without a road profile or wheel heights is simulated on a flat road. If the car really drove
over an uneven road, its vertical signals (pitch rate, roll rate, vertical specific force) carry
broadband power the flat-road model cannot have: in the body-mode band (:data:`BODY_BAND_HZ`, bounce,
pitch and roll at 1-2 Hz) AND in the wheel-hop band (:data:`WHEEL_BAND_HZ`, 10-15 Hz). A model error of
the car itself (mass, damping, friction) shows at the modes the inputs excite, not as a broad floor in
both bands on a drive whose inputs excite neither. Power is compared with what the signal's own white
noise puts in the band (Welch periodogram of the residual, one-sided PSD ``2 sigma^2 / fs`` for white
noise); both bands above :data:`EXCESS` times that is the verdict.

The road's roughness class (ISO 8608) follows from the residual: the model is driven over a random road
of class A (:func:`susp_sim_ros.model.iso8608.random_road`) at the drive's mean speed; the response
power of the vertical specific force (or the pitch rate, when the accelerometer is not there) scales with
the road's ``Gd(n0)``, so ``Gd(n0) = Gd_A(n0) * P_measured / P_model,A`` (band 0.5-20 Hz, the noise's
share removed), and the class is the one whose band holds it.

The drive's handling signals (yaw rate, lateral specific force) stay in the fit: the steering drives
them. What the road adds to them in its band (from the body modes up; lateral tyre-force ripple, and roll
through ``g phi`` in the lateral specific force) is counted as noise there (``extra_noise_variance``), so
it does not pull the calibration.
"""
from __future__ import annotations

import math

import numpy as np
from scipy import signal as sps

from ...model import simulate
from ...model.iso8608 import CLASS_GD_N0, class_of, random_road
from ...model.layout import U_INDEX
from ...model.vehicle import make_inputs
from .data import SIGNAL_OF_OUTPUT, DriveCase

VERTICAL = ("accel_z", "pitch_rate", "roll_rate")
HANDLING = ("yaw_rate", "accel_y")  # kept in the fit; their road-band content counts as noise there
BODY_BAND_HZ = (0.7, 3.0)
WHEEL_BAND_HZ = (7.0, 20.0)
CLASS_BAND_HZ = (0.5, 20.0)
EXCESS = 4.0


def _band_power(f: np.ndarray, p: np.ndarray, band: tuple[float, float]) -> float:
    m = (f >= band[0]) & (f <= band[1])
    return float(np.trapezoid(p[m], f[m])) if m.sum() >= 2 else math.nan


def _psd(e: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """One-sided Welch PSD of a residual column (4 s segments, or the whole record)."""
    return sps.welch(e - e.mean(), fs=fs, nperseg=int(min(e.size, round(4 * fs))))


def detect_unmeasured_road(case: DriveCase, resid: np.ndarray, noise: dict, model) -> dict | None:
    """The ``unmeasured_input`` finding of a drive without road input, or None.

    ``resid``: base simulation minus measurement on the drive's comparison samples for its signals
    (native units); ``noise``: the drive's noise sigma per signal."""
    t = case.t_grid_s
    if t.size < 64:
        return None
    fs = 1.0 / float(np.median(np.diff(t)))
    hits, evidence, powers = [], {}, {}
    for sig in VERTICAL:
        if sig not in case.signals or not math.isfinite(noise.get(sig, math.nan)):
            continue
        f, p = _psd(resid[:, case.signals.index(sig)], fs)
        white = 2.0 * noise[sig] ** 2 / fs
        ratios = {}
        for name, band in (("body", BODY_BAND_HZ), ("wheel", WHEEL_BAND_HZ)):
            hi = min(band[1], 0.45 * fs)
            bp = _band_power(f, p, (band[0], hi))
            ratios[name] = bp / (white * (hi - band[0])) if math.isfinite(bp) and hi > band[0] else math.nan
        evidence[sig] = {f"{k}_band_power_x_noise": v for k, v in ratios.items()}
        wheel_ok = ratios["wheel"] > EXCESS if math.isfinite(ratios["wheel"]) else True
        if ratios["body"] > EXCESS and wheel_ok:
            hits.append(sig)
            hi = min(CLASS_BAND_HZ[1], 0.45 * fs)
            powers[sig] = max(_band_power(f, p, (CLASS_BAND_HZ[0], hi)) - white * (hi - CLASS_BAND_HZ[0]), 0.0)
    if not hits:
        return None
    # handling signals stay, but what the road puts into them (lateral force and roll through g*phi, in
    # the road band) is not the model's to explain: it joins their noise
    extra = {}
    for sig in HANDLING:
        if sig not in case.signals:
            continue
        f, p = _psd(resid[:, case.signals.index(sig)], fs)
        hi = min(CLASS_BAND_HZ[1], 0.45 * fs)
        white = 2.0 * noise[sig] ** 2 / fs
        lo = BODY_BAND_HZ[0]
        extra[sig] = max(_band_power(f, p, (lo, hi)) - white * (hi - lo), 0.0)
    ref_sig = next(s for s in VERTICAL if s in hits)
    speed = float(np.mean(case.U[:, U_INDEX["V"]]))
    klass, gd = _roughness_class(model, speed, fs, ref_sig, powers[ref_sig], case.oil)
    return {"kind": "road", "drive": case.name, "signals": hits, "iso8608_class": klass,
            "extra_noise_variance": extra,
            "gd_n0_m3": gd, "class_from": ref_sig, "mean_speed_m_s": speed, "evidence": evidence,
            "statement": (f"{case.name}: no road in the recording, yet {', '.join(hits)} carry broadband "
                          f"power at the body and wheel modes far above their noise; the road is not in the "
                          f"recording" + (f" (ISO 8608 class {klass} estimated from {ref_sig})" if klass else ""))}


def _roughness_class(model, speed: float, fs: float, sig: str, p_meas: float, oil) -> tuple[str | None, float | None]:
    """ISO 8608 class of the road behind the band power ``p_meas`` of ``sig`` at ``speed`` (module doc)."""
    if not (speed > 1.0 and p_meas > 0):
        return None, None
    dt, duration = 0.001, 30.0
    n = int(duration / dt)
    road = random_road("A", speed * duration + 10.0, seed=8608, start=-5.0)
    res = simulate(model, make_inputs(n, speed, 0.0), dt=dt, road=road, oil=oil, outputs=[SIGNAL_OF_OUTPUT[sig][0]])
    y = res.y[:, 0] * SIGNAL_OF_OUTPUT[sig][1]
    y = y[int(3.0 / dt):]  # settle
    f, p = _psd(y, 1.0 / dt)
    hi = min(CLASS_BAND_HZ[1], 0.45 * fs)
    p_model = _band_power(f, p, (CLASS_BAND_HZ[0], hi))
    if not p_model > 0:
        return None, None
    gd = CLASS_GD_N0["A"] * p_meas / p_model
    return class_of(gd), float(gd)
