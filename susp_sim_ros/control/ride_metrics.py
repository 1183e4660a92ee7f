"""Ride comfort and road-holding metrics (issue 15): ISO 2631-1 Wk weighting, dynamic tyre load,
suspension travel and stop contacts, from the model's outputs.

Wk (ISO 2631-1:1997, Annex A, Table A.2): the product of a band limit (second-order Butterworth
high-pass at f1 = 0.4 Hz and low-pass at f2 = 100 Hz), an acceleration-velocity transition
``(1 + s/w3) / (1 + s/(Q4 w4) + s^2/w4^2)`` (f3 = f4 = 12.5 Hz, Q4 = 0.63) and an upward step
``(1 + s/(Q5 w5) + s^2/w5^2) / (1 + s/(Q6 w6) + s^2/w6^2) (w5/w6)^2`` (f5 = 2.37 Hz, Q5 = 0.91,
f6 = 3.35 Hz, Q6 = 0.91). :data:`WK_TABLE` holds the standard's tabulated weighting factors (ISO 2631-1,
Table 3) for the test. The digital filter is the bilinear transform of the analogue one at the
sampling rate (use >= 500 Hz: the warping is then below 0.2 dB up to 80 Hz).

The vertical acceleration is taken at the centre of gravity (the model has no seat); pitch and roll
accelerations are reported unweighted as RMS (ISO 2631-1 weights them with We for a seat back, which a
body-fixed point does not have).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import signal

from ..model.layout import OUTPUT_LABELS, WHEELS

#: ISO 2631-1 Wk filter constants (Annex A): frequencies [Hz] and quality factors [-]
WK_F1, WK_F2, WK_Q1 = 0.4, 100.0, 1.0 / np.sqrt(2.0)
WK_F3, WK_F4, WK_Q4 = 12.5, 12.5, 0.63
WK_F5, WK_Q5, WK_F6, WK_Q6 = 2.37, 0.91, 3.35, 0.91
#: ISO 2631-1 Table 3: Wk weighting factors at the one-third-octave centre frequencies [Hz]
WK_TABLE = {0.5: 0.418, 0.63: 0.459, 0.8: 0.477, 1.0: 0.482, 1.25: 0.484, 1.6: 0.494, 2.0: 0.531,
            2.5: 0.631, 3.15: 0.804, 4.0: 0.967, 5.0: 1.039, 6.3: 1.054, 8.0: 1.036, 10.0: 0.988,
            12.5: 0.902, 16.0: 0.768, 20.0: 0.636, 25.0: 0.513, 31.5: 0.405, 40.0: 0.314, 50.0: 0.246,
            63.0: 0.186, 80.0: 0.132}


def wk_analog() -> tuple[np.ndarray, np.ndarray]:
    """Numerator and denominator (descending powers of s) of the analogue Wk weighting."""
    w = lambda f: 2.0 * np.pi * f  # noqa: E731
    w1, w2, w3, w4, w5, w6 = (w(f) for f in (WK_F1, WK_F2, WK_F3, WK_F4, WK_F5, WK_F6))
    num = np.polymul([1.0, 0.0, 0.0], [w2 ** 2])                                       # band limit
    den = np.polymul([1.0, w1 / WK_Q1, w1 ** 2], [1.0, w2 / WK_Q1, w2 ** 2])
    num = np.polymul(num, [1.0 / w3, 1.0])                                             # a-v transition
    den = np.polymul(den, [1.0 / w4 ** 2, 1.0 / (WK_Q4 * w4), 1.0])
    num = np.polymul(num, np.array([1.0 / w5 ** 2, 1.0 / (WK_Q5 * w5), 1.0]) * (w5 / w6) ** 2)  # step
    den = np.polymul(den, [1.0 / w6 ** 2, 1.0 / (WK_Q6 * w6), 1.0])
    return num, den


def wk_response(f: np.ndarray) -> np.ndarray:
    """|Wk| of the analogue weighting at frequencies ``f`` [Hz]."""
    _, h = signal.freqs(*wk_analog(), worN=2.0 * np.pi * np.asarray(f, float))
    return np.abs(h)


def wk_sos(fs: float) -> np.ndarray:
    """Second-order sections of the digital Wk filter at sampling rate ``fs`` [Hz] (bilinear)."""
    z, p, k = signal.tf2zpk(*wk_analog())
    zd, pd, kd = signal.bilinear_zpk(z, p, k, fs)
    return signal.zpk2sos(zd, pd, kd)


def wk_weighted(a: np.ndarray, fs: float) -> np.ndarray:
    """Wk-weighted acceleration [m/s^2] of ``a`` [m/s^2] sampled at ``fs`` [Hz] (mean removed first)."""
    a = np.asarray(a, float)
    return signal.sosfilt(wk_sos(fs), a - a.mean())


#: Tolerance [dB] of :func:`wk_accurate_to_hz`: how far the digital Wk may depart from the analogue one
WK_ACCURACY_DB = 1.0


def wk_accurate_to_hz(fs: float, tol_db: float = WK_ACCURACY_DB) -> float:
    """Highest frequency [Hz] up to which the digital Wk at sampling rate ``fs`` [Hz] stays within
    ``tol_db`` of the analogue weighting (bilinear warping grows towards the Nyquist frequency): about
    19 Hz at 100 Hz, 35 Hz at 200 Hz, 74 Hz at 500 Hz for 1 dB (15, 26, 58 Hz for 0.5 dB)."""
    f = np.linspace(0.05 * WK_F1, 0.999 * fs / 2.0, 4000)
    _, h = signal.sosfreqz(wk_sos(fs), worN=f, fs=fs)
    bad = np.nonzero(np.abs(20.0 * np.log10(np.abs(h) / wk_response(f))) > tol_db)[0]
    return float(f[bad[0] - 1] if bad.size and bad[0] > 0 else (f[0] if bad.size else f[-1]))


def comfort_wk_rms(az_sf: np.ndarray, fs: float, gravity: float) -> float:
    """ISO 2631-1 Wk-weighted RMS vertical acceleration [m/s^2] of a vertical specific force series
    ``az_sf`` [m/s^2] (gravity included, as an IMU measures it) sampled at ``fs`` [Hz]."""
    return rms(wk_weighted(np.asarray(az_sf) - gravity, fs))


def rms(x: np.ndarray) -> float:
    x = np.asarray(x, float)
    return float(np.sqrt(np.mean(x * x))) if x.size else float("nan")


def stop_contacts(defl: np.ndarray, bump_travel: float, rebound_travel: float) -> int:
    """Number of times a deflection series [m] enters the bump (d > bump_travel) or rebound
    (d < -rebound_travel) stop."""
    d = np.asarray(defl, float)
    n = 0
    for inside in (d > bump_travel, d < -rebound_travel):
        n += int(np.count_nonzero(inside[1:] & ~inside[:-1])) + int(inside[:1].sum())
    return n


@dataclass(frozen=True)
class RideMetrics:
    """The interface's ride metrics of one series; :meth:`to_dict` gives its JSON keys, in this order.
    Per-wheel values are dicts keyed FL, FR, RL, RR."""

    comfort_wk_rms_m_s2: float                   #: ISO 2631-1 Wk-weighted RMS vertical acceleration [m/s^2]
    vertical_acceleration_rms_m_s2: float        #: RMS vertical acceleration, mean removed [m/s^2]
    pitch_acceleration_rms_rad_s2: float         #: RMS pitch acceleration [rad/s^2]
    roll_acceleration_rms_rad_s2: float          #: RMS roll acceleration [rad/s^2]
    dynamic_tyre_load_rms_rel: dict[str, float]  #: RMS tyre load change over the static load [-]
    suspension_travel_rms_m: dict[str, float]    #: RMS suspension deflection [m]
    stop_contacts: dict[str, int]                #: entries into the bump or rebound stop [-]

    def to_dict(self) -> dict:
        """The JSON object (per-wheel dicts copied)."""
        return {"comfort_wk_rms_m_s2": self.comfort_wk_rms_m_s2,
                "vertical_acceleration_rms_m_s2": self.vertical_acceleration_rms_m_s2,
                "pitch_acceleration_rms_rad_s2": self.pitch_acceleration_rms_rad_s2,
                "roll_acceleration_rms_rad_s2": self.roll_acceleration_rms_rad_s2,
                "dynamic_tyre_load_rms_rel": dict(self.dynamic_tyre_load_rms_rel),
                "suspension_travel_rms_m": dict(self.suspension_travel_rms_m),
                "stop_contacts": dict(self.stop_contacts)}


def ride_metrics(y: dict[str, np.ndarray], fs: float, *, gravity: float, static_loads,
                 bump_travel, rebound_travel) -> RideMetrics:
    """The interface's ride metrics from output series ``y`` (OUTPUT_LABELS keys: AZ_SF, ROLL_RATE,
    PITCH_RATE, F_Z_*, DEFL_*) sampled at ``fs`` [Hz]. ``static_loads`` [N], ``bump_travel`` and
    ``rebound_travel`` [m] per wheel FL, FR, RL, RR."""
    tyre_load: dict[str, float] = {}
    travel: dict[str, float] = {}
    stops: dict[str, int] = {}
    for i, w in enumerate(WHEELS):
        fz0 = float(static_loads[i])
        tyre_load[w] = rms((np.asarray(y[f"F_Z_{w}"]) - fz0) / fz0)
        travel[w] = rms(y[f"DEFL_{w}"])
        stops[w] = stop_contacts(y[f"DEFL_{w}"], bump_travel[i], rebound_travel[i])
    return RideMetrics(
        comfort_wk_rms_m_s2=comfort_wk_rms(y["AZ_SF"], fs, gravity),
        vertical_acceleration_rms_m_s2=rms(np.asarray(y["AZ_SF"]) - np.mean(y["AZ_SF"])),
        pitch_acceleration_rms_rad_s2=rms(np.gradient(np.asarray(y["PITCH_RATE"]), 1.0 / fs)),
        roll_acceleration_rms_rad_s2=rms(np.gradient(np.asarray(y["ROLL_RATE"]), 1.0 / fs)),
        dynamic_tyre_load_rms_rel=tyre_load, suspension_travel_rms_m=travel, stop_contacts=stops)


@dataclass(frozen=True)
class RunningRideMetrics:
    """:class:`RideMonitor`'s metrics since its start or last reset; :meth:`to_dict` gives the keys.
    Per-wheel values are dicts keyed FL, FR, RL, RR."""

    comfort_wk_rms_m_s2: float                   #: Wk-weighted RMS vertical acceleration [m/s^2]
    dynamic_tyre_load_rms_rel: dict[str, float]  #: RMS tyre load change over the static load [-]
    suspension_travel_rms_m: dict[str, float]    #: RMS suspension deflection [m]
    stop_contacts: dict[str, int]                #: entries into the bump or rebound stop [-]
    samples: int                                 #: samples fed [-]

    def to_dict(self) -> dict:
        """The values as a dict (per-wheel dicts copied)."""
        return {"comfort_wk_rms_m_s2": self.comfort_wk_rms_m_s2,
                "dynamic_tyre_load_rms_rel": dict(self.dynamic_tyre_load_rms_rel),
                "suspension_travel_rms_m": dict(self.suspension_travel_rms_m),
                "stop_contacts": dict(self.stop_contacts), "samples": self.samples}


class RideMonitor:
    """Running ride metrics over a stream of full output vectors (OUTPUT_LABELS) sampled at ``fs`` [Hz],
    since the start or the last :meth:`reset`: the node's diagnostics. The Wk filter keeps its state
    across calls, so feeding samples in pieces gives the same result as all at once. At a publish rate
    of 100 Hz the weighting is accurate to about 20 Hz (bilinear warping; the body and wheel modes
    lie below)."""

    def __init__(self, fs: float, *, gravity: float, static_loads, bump_travel, rebound_travel):
        idx = {k: i for i, k in enumerate(OUTPUT_LABELS)}
        self._az = idx["AZ_SF"]
        self._fz = [idx[f"F_Z_{w}"] for w in WHEELS]
        self._d = [idx[f"DEFL_{w}"] for w in WHEELS]
        self.sos = wk_sos(fs)
        self.g = float(gravity)
        self.fz0 = np.asarray(static_loads, float)
        self.bump, self.rebound = np.asarray(bump_travel, float), np.asarray(rebound_travel, float)
        self.reset()

    def reset(self) -> None:
        self.zi = np.zeros((self.sos.shape[0], 2))
        self.n = 0
        self.sum_wk2 = 0.0
        self.sum_dtl2 = np.zeros(4)
        self.sum_d2 = np.zeros(4)
        self.contacts = np.zeros(4, int)
        self._inside = np.zeros((2, 4), bool)

    def update(self, Y: np.ndarray) -> None:
        Y = np.atleast_2d(np.asarray(Y, float))
        if not Y.shape[0]:
            return
        wk, self.zi = signal.sosfilt(self.sos, Y[:, self._az] - self.g, zi=self.zi)
        self.sum_wk2 += float(wk @ wk)
        dtl = (Y[:, self._fz] - self.fz0) / self.fz0
        d = Y[:, self._d]
        self.sum_dtl2 += np.sum(dtl * dtl, axis=0)
        self.sum_d2 += np.sum(d * d, axis=0)
        for k, inside in enumerate((d > self.bump, d < -self.rebound)):
            prev = np.vstack([self._inside[k][None], inside[:-1]])
            self.contacts += np.sum(inside & ~prev, axis=0)
            self._inside[k] = inside[-1]
        self.n += Y.shape[0]

    def values(self) -> RunningRideMetrics:
        n = max(self.n, 1)
        return RunningRideMetrics(
            comfort_wk_rms_m_s2=float(np.sqrt(self.sum_wk2 / n)),
            dynamic_tyre_load_rms_rel=dict(zip(WHEELS, np.sqrt(self.sum_dtl2 / n).tolist())),
            suspension_travel_rms_m=dict(zip(WHEELS, np.sqrt(self.sum_d2 / n).tolist())),
            stop_contacts=dict(zip(WHEELS, self.contacts.tolist())), samples=self.n)


__all__ = ["RideMetrics", "RideMonitor", "RunningRideMetrics", "WK_TABLE", "WK_ACCURACY_DB", "comfort_wk_rms",
           "wk_accurate_to_hz", "wk_analog", "wk_response", "wk_sos", "wk_weighted", "ride_metrics", "rms",
           "stop_contacts"]
