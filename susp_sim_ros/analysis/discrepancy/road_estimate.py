"""The road along the path of a drive that did not record it, estimated from the measured body motion.

A drive without road profile whose vertical signals carry the road (:mod:`.unmeasured`) is not usable
for the vertical dynamics: the model runs on a flat road. The road is estimated back from what the body
did, so the drive can be simulated on it:

1. **The model's response to each wheel track.** The model is driven at the drive's mean speed over a
   random road of the estimated ISO 8608 class under one track (the other flat), once per track; the
   frequency responses ``H(f)`` [signal unit / m] from the track height under the front axle to each
   vertical signal (the rear axle following the same track a wheelbase later) are the cross- over the
   auto-spectra (Welch, 8 s segments). At the class's amplitude the friction is linearised where the
   drive has it (a describing function), not at zero amplitude.
2. **Wiener deconvolution.** Per frequency, the two track heights ``U = S_u H^H (H S_u H^H + N)^-1 Y``:
   ``Y`` the discrete Fourier transform of what the flat-road model leaves (measured minus simulated),
   ``S_u`` the class's road spectrum in time at the drive's speed (``Gd(n) / v`` at ``n = f / v``, the
   two tracks independent a priori), ``N`` the signals' white noise (their noise floors). Where the
   signals say little (noise, or a frequency the body does not feel) the estimate falls back to zero, not
   to the noise divided by a small response. Only :data:`ESTIMATION_BAND_HZ` is estimated: slower
   waves do not move the body against the car, faster ones are lost in the wheel hop and the sample rate.
3. **Along the path.** The time series becomes ``zl(s)``, ``zr(s)`` with ``s`` the front axle's path
   (0 when the drive starts, ``/road/profile``'s convention, :mod:`susp_sim_ros.model.road`).

How good it is shows in two figures (:func:`road_usability`): the vertical signals' RMSE on the flat road
against the estimated one, and a cross-signal check that cannot fit itself: the road estimated from the
gyro signals alone predicts the vertical specific force it never saw. Checked against the independent
simulator's true road in ``test/test_road_estimate.py``.

References: Wiener deconvolution as the minimum-mean-square-error linear estimate with a prior spectrum
(e.g. Kay, *Fundamentals of Statistical Signal Processing*, vol. 1, ch. 12); road-profile estimation
from vehicle response by inverse frequency-response filtering (e.g. Doumiati et al. 2011; Gonzalez et
al. 2008, "The use of vehicle acceleration measurements to estimate road roughness").
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy import signal as sps

from ...model import simulate
from ...model.inline_math import TINY
from ...model.iso8608 import CLASS_GD_N0, N0, WAVINESS, random_road
from ...model.layout import U_INDEX
from ...model.road import RoadProfile
from ...model.vehicle import make_inputs
from .data import SIGNAL_OF_OUTPUT, DriveCase
from .engine import Evaluator, Structure
from .unmeasured import VERTICAL

#: band [Hz] of the estimated road (in time, at the drive's speed)
ESTIMATION_BAND_HZ = (0.5, 20.0)
#: duration [s] and step [s] of each model run that measures the frequency responses; Welch segment [s]
FRF_RUN_S, FRF_DT_S, FRF_SEGMENT_S = 64.0, 0.001, 8.0
#: settling time [s] dropped from each such run
FRF_SETTLE_S = 3.0
#: the random road of those runs (its seed: any fixed one; its class: the drive's estimate), starting
#: this far [m] behind the front axle and ending as far beyond the run
FRF_SEED, FRF_ROAD_MARGIN_M = 8608, 10.0
#: the gyro signals a cross-check estimates the road from (two signals for two tracks)
GYRO_VERTICAL = ("pitch_rate", "roll_rate")


@dataclasses.dataclass(frozen=True)
class RoadEstimate:
    """An estimated road: the profile along the front axle's path and how it was made."""

    road: RoadProfile
    signals: tuple[str, ...]   # the vertical signals it was estimated from
    speed_m_s: float           # the drive's mean speed [m/s]
    gd_n0_m3: float            # the prior road spectrum's Gd(n0) [m^3]
    band_hz: tuple[float, float]
    responses: tuple = dataclasses.field(repr=False, default=())  # (f, H, signals) it used


def track_responses(model, speed: float, gd_n0: float, oil, signals) -> tuple[np.ndarray, np.ndarray]:
    """Frequencies ``f`` [Hz] and responses ``H`` (n_f, n_sig, 2), complex, [signal unit / m] of the
    ``signals`` to the left and right track height under the front axle at ``speed`` [m/s] (module doc,
    step 1), over a random road of spectrum ``Gd(n0) = gd_n0`` [m^3]."""
    n = int(FRF_RUN_S / FRF_DT_S)
    base = random_road("A", speed * FRF_RUN_S + 2 * FRF_ROAD_MARGIN_M, seed=FRF_SEED, start=-FRF_ROAD_MARGIN_M)
    z = base.zl * math.sqrt(gd_n0 / CLASS_GD_N0["A"])
    t = np.arange(1, n + 1) * FRF_DT_S
    u = np.interp(speed * t, base.s, z)
    keep = t >= FRF_SETTLE_S
    nper = int(FRF_SEGMENT_S / FRF_DT_S)
    f, puu = sps.welch(u[keep], fs=1.0 / FRF_DT_S, nperseg=nper)
    H = np.zeros((f.size, len(signals), 2), complex)
    zero = np.zeros_like(z)
    for k in range(2):
        road = RoadProfile(base.s, z if k == 0 else zero, zero if k == 0 else z)
        res = simulate(model, make_inputs(n, speed, 0.0), dt=FRF_DT_S, road=road, oil=oil,
                       outputs=[SIGNAL_OF_OUTPUT[s][0] for s in signals])
        for j, s in enumerate(signals):
            y = res.y[keep, j] * SIGNAL_OF_OUTPUT[s][1]
            _, puy = sps.csd(u[keep], y, fs=1.0 / FRF_DT_S, nperseg=nper)
            H[:, j, k] = puy / np.maximum(puu, TINY)
    return f, H


def estimate_road(case: DriveCase, resid: np.ndarray, noise: dict, model, gd_n0: float,
                  signals=VERTICAL, responses: tuple | None = None) -> RoadEstimate:
    """The road under ``case`` (module doc) from ``resid`` (the flat-road model minus the measurement on
    the case's comparison samples, native units, columns ``case.signals``), the signals' noise sigma
    ``noise`` and the prior spectrum ``Gd(n0) = gd_n0`` [m^3]; from the ``signals`` among the case's.
    ``responses``: ``(f, H, signals)`` of :func:`track_responses` for this drive, if already measured
    (for a superset of the signals)."""
    sig = tuple(s for s in signals if s in case.signals and math.isfinite(noise.get(s, math.nan)))
    if not sig:
        raise ValueError(f"{case.name}: none of {signals} is recorded with a noise floor; no road to estimate")
    t = case.t_grid_s
    fs = 1.0 / float(np.median(np.diff(t)))
    speed = float(np.mean(case.U[:, U_INDEX["V"]]))
    if responses is None:
        responses = (*track_responses(model, speed, gd_n0, case.oil, sig), sig)
    f_h, H_all, sig_all = responses
    H = H_all[:, [sig_all.index(s) for s in sig], :]
    y = -np.column_stack([resid[:, case.signals.index(s)] for s in sig])  # measured minus flat-road model
    y = y - y.mean(axis=0)
    n = y.shape[0]
    nfft = 2 * n  # zero padding: no wrap-around of the deconvolution
    taper = sps.windows.tukey(n, alpha=min(1.0, 2.0 * fs / n))  # 1 s cosine ends
    Y = np.fft.rfft(y * taper[:, None], nfft, axis=0)
    f = np.fft.rfftfreq(nfft, 1.0 / fs)
    lo, hi = ESTIMATION_BAND_HZ[0], min(ESTIMATION_BAND_HZ[1], 0.45 * fs)
    band = (f >= lo) & (f <= hi)
    fb = f[band]
    Hf = np.stack([np.interp(fb, f_h, col.real) + 1j * np.interp(fb, f_h, col.imag)
                   for col in H.reshape(f_h.size, -1).T], axis=1).reshape(fb.size, len(sig), 2)
    su = gd_n0 * (fb / (speed * N0)) ** -WAVINESS / speed  # one-sided road PSD in time [m^2/Hz]
    nn = np.array([2.0 * noise[s] ** 2 / fs for s in sig])  # one-sided white noise PSD [unit^2/Hz]
    Hh = np.conj(np.swapaxes(Hf, 1, 2))                      # (nb, 2, n_sig)
    G = su[:, None, None] * Hh @ np.linalg.inv(su[:, None, None] * Hf @ Hh + np.diag(nn))  # (nb, 2, n_sig)
    U = np.zeros((f.size, 2), complex)
    U[band] = np.einsum("bks,bs->bk", G, Y[band])
    u = np.fft.irfft(U, nfft, axis=0)[:n]
    # along the front axle's path at the comparison times
    t_steps = np.arange(case.U.shape[0]) * case.dt
    path = np.concatenate([[0.0], np.cumsum(case.U[:-1, U_INDEX["V"]] * case.dt)])
    s = np.interp(t, t_steps, path)
    keep = np.concatenate([[True], np.diff(s) > 0])
    road = RoadProfile(s[keep], u[keep, 0], u[keep, 1])
    return RoadEstimate(road, sig, speed, gd_n0, (lo, hi), (f_h, H, sig))


def road_usability(case: DriveCase, model, est: RoadEstimate, resid_flat: np.ndarray,
                   cross: RoadEstimate | None = None) -> dict:
    """How much of the vertical signals the estimated road explains: per signal the RMSE [native units]
    on the flat road and on ``est``; with ``cross`` (a road estimated without some signal), that road's
    RMSE on the signals it was not estimated from (a check that cannot fit itself)."""
    def vertical_rmse(e: np.ndarray) -> dict:
        return {s: float(np.sqrt(np.mean(e[:, j] ** 2))) for j, s in enumerate(case.signals) if s in VERTICAL}

    def rmse_on(road: RoadProfile) -> dict:
        ev = Evaluator(model, [dataclasses.replace(case, road=road, quiet=None, quiet_raw=None)])
        sims = ev.simulate(Structure([]), np.zeros((1, 0)), to_end=True)[0]
        return vertical_rmse(ev.case_residual(0, sims[0], 0.0, False))

    flat = vertical_rmse(resid_flat)
    out = {"rmse_flat_road": flat, "rmse_estimated_road": rmse_on(est.road)}
    if cross is not None:
        unseen = [s for s in flat if s not in cross.signals]
        with_cross = rmse_on(cross.road)
        out["cross_check"] = {"estimated_from": list(cross.signals),
                              "rmse_flat_road": {s: flat[s] for s in unseen},
                              "rmse_estimated_road": {s: with_cross[s] for s in unseen}}
    return out
