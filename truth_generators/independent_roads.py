"""Maneuvers and roads for the independent truth simulator (:mod:`.independent_sim`).

Written from ``model-spec.md`` section 4 and ISO 8608 only; shares no code with ``susp_sim_ros.model``
(``RoadProfile`` is used by the simulator only as the container a ``TestDrive`` needs).

A :class:`TruthManeuver` gives the longitudinal speed [m/s], its derivative [m/s^2] and the
steering-wheel angle [rad] as functions of time, and the road (s, zl, zr) along the path. The front axle
is at s = 0 at t = 0; the rear axle trails by the wheelbase (interface.md).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

#: wheelbase [m] the maneuvers' durations assume when none is given: model-spec section 3 (a + b = 1.10 +
#: 1.69 m, wheelbase 2.79 m published). Declared here, not read from the model's vehicle config, so the
#: truth generator stays independent of the model it checks.
SPEC_WHEELBASE_M = 2.79

#: ISO 8608 classes: Gd(n0) [m^3] at n0 = 0.1 cycles/m, geometric mean of each class (A = 16e-6, x4 per class).
ISO8608_N0 = 0.1
ISO8608_CLASSES = "ABCDEFGH"


def iso8608_gd0(road_class: str) -> float:
    """Gd(n0) [m^3] of an ISO 8608 class ``A``..``H``."""
    c = str(road_class).upper()
    if len(c) != 1 or c not in ISO8608_CLASSES:
        raise ValueError(f"ISO 8608 class must be one of {ISO8608_CLASSES}, got {road_class!r}")
    return 16e-6 * 4.0 ** ISO8608_CLASSES.index(c)


def iso8608_psd(n, road_class: str) -> np.ndarray:
    """One-sided displacement PSD Gd(n) = Gd(n0) (n/n0)^-2 [m^3] at spatial frequencies n [cycles/m]."""
    n = np.asarray(n, dtype=float)
    return iso8608_gd0(road_class) * (n / ISO8608_N0) ** -2.0


def coherence(n, n_c: float) -> np.ndarray:
    """Left/right track coherence gamma(n) = 1 / (1 + (n/n_c)^2) (amplitude coherence; |gamma|^2 is the
    magnitude-squared coherence): long waves are shared by both tracks, short ones independent."""
    n = np.asarray(n, dtype=float)
    return 1.0 / (1.0 + (n / n_c) ** 2)


def iso8608_road(length_m: float, road_class: str, seed: int, *, ds: float = 0.02, n_min: float = 0.01,
                 n_max: float | None = None, n_c: float = 0.2) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A seeded random road of ISO 8608 class ``road_class``: (s, zl, zr) from s = 0, spacing ``ds``.

    Each track is a sum of cosines on the FFT grid n_k = k/(N ds) with deterministic amplitudes
    ``sqrt(2 Gd(n_k) dn)`` (so each track's PSD follows the class exactly up to the coherence mixing) and
    random phases; a share ``gamma(n)`` of each component's amplitude is common to both tracks and the rest
    independent (equal power split: ``sqrt(gamma)`` common, ``sqrt(1 - gamma)`` own), which gives
    cross-spectrum = gamma * Gd. Frequencies outside [n_min, n_max] are left out (n_max default: 0.4/ds).
    """
    rng = np.random.default_rng(seed)
    N = int(np.ceil(length_m / ds)) + 1
    N += N % 2
    n = np.fft.rfftfreq(N, ds)
    dn = 1.0 / (N * ds)
    n_hi = 0.4 / ds if n_max is None else n_max
    keep = (n >= n_min) & (n <= n_hi)
    amp = np.zeros_like(n)
    amp[keep] = np.sqrt(2.0 * iso8608_psd(n[keep], road_class) * dn)
    g = np.zeros_like(n)
    g[keep] = coherence(n[keep], n_c)
    ph = rng.uniform(0.0, 2.0 * np.pi, size=(3, n.size))
    common = np.sqrt(g) * np.exp(1j * ph[0])
    own = np.sqrt(1.0 - g)
    Xl = amp * (common + own * np.exp(1j * ph[1]))
    Xr = amp * (common + own * np.exp(1j * ph[2]))
    zl = np.fft.irfft(Xl * (N / 2.0), N)
    zr = np.fft.irfft(Xr * (N / 2.0), N)
    s = np.arange(N) * ds
    return s, zl, zr


def _smoothstep(x):
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


@dataclass
class TruthManeuver:
    """One truth maneuver. Build with :meth:`bump`, :meth:`sine`, :meth:`rough`, :meth:`brake`, :meth:`rest`.

    kind: ``bump`` | ``sine`` | ``rough`` | ``brake`` | ``rest``; all lengths m, speeds m/s, angles rad.
    """

    kind: str
    speed_mps: float
    duration_s: float
    lead_in_s: float = 1.5
    # bump
    bump_height_m: float = 0.06
    bump_length_m: float = 0.5
    # steering (sine / highway)
    steer: str = "none"                 # none | sine | random
    steer_amplitude_rad: float = 0.0    # steering-wheel amplitude (sine) or RMS (random)
    steer_freq_hz: float = 0.5          # sine frequency, or the random steering's upper band edge
    steer_periods: float = 2.0          # sine: number of periods (then straight); random: ignored
    steer_seed: int = 0
    # rough road
    road_class: str | None = None
    road_seed: int = 0
    road_ds_m: float = 0.02
    road_taper_m: float = 10.0          # the road fades in over this length after s = 0
    road_coherence_nc: float = 0.2      # cycles/m, see :func:`coherence`
    # braking
    decel_mps2: float = 0.0
    end_speed_mps: float = 0.0
    jerk_time_s: float = 0.3
    extra: dict = field(default_factory=dict)

    # ---- constructors ----
    @classmethod
    def bump(cls, speed_kmh: float = 8.0, height_m: float = 0.06, length_m: float = 0.5,
             lead_in_s: float = 1.5, ring_out_s: float = 3.0,
             wheelbase_m: float = SPEC_WHEELBASE_M) -> "TruthManeuver":
        v = speed_kmh / 3.6
        dur = lead_in_s + (length_m + wheelbase_m) / v + ring_out_s
        return cls("bump", v, dur, lead_in_s, bump_height_m=height_m, bump_length_m=length_m)

    @classmethod
    def sine(cls, speed_kmh: float = 50.0, amplitude_deg: float = 60.0, freq_hz: float = 0.5,
             periods: float = 2.0, lead_in_s: float = 1.5, ring_out_s: float = 3.0) -> "TruthManeuver":
        dur = lead_in_s + periods / freq_hz + ring_out_s
        return cls("sine", speed_kmh / 3.6, dur, lead_in_s, steer="sine",
                   steer_amplitude_rad=np.radians(amplitude_deg), steer_freq_hz=freq_hz, steer_periods=periods)

    @classmethod
    def rough(cls, road_class: str = "C", speed_kmh: float = 80.0, duration_s: float = 20.0, seed: int = 0,
              steer: str = "none", steer_amplitude_deg: float = 0.0, steer_freq_hz: float = 0.3,
              lead_in_s: float = 1.0) -> "TruthManeuver":
        """Straight (``steer="none"``) or "highway" (``sine``/``random`` steering) drive over an ISO 8608 road."""
        iso8608_gd0(road_class)
        return cls("rough", speed_kmh / 3.6, duration_s, lead_in_s, steer=steer,
                   steer_amplitude_rad=np.radians(steer_amplitude_deg), steer_freq_hz=steer_freq_hz,
                   steer_periods=1e9, steer_seed=seed + 7919, road_class=road_class.upper(), road_seed=seed)

    @classmethod
    def brake(cls, speed_kmh: float = 50.0, decel_mps2: float = 4.0, end_speed_kmh: float = 0.0,
              lead_in_s: float = 1.5, ring_out_s: float = 3.0) -> "TruthManeuver":
        v0 = speed_kmh / 3.6
        dur = lead_in_s + (v0 - end_speed_kmh / 3.6) / decel_mps2 + 0.3 + ring_out_s
        return cls("brake", v0, dur, lead_in_s, decel_mps2=decel_mps2, end_speed_mps=end_speed_kmh / 3.6)

    @classmethod
    def rest(cls, duration_s: float = 5.0) -> "TruthManeuver":
        return cls("rest", 0.0, duration_s, 0.0)

    # ---- inputs ----
    def _brake_profile(self, t):
        """(v, a) of the braking maneuver: deceleration ramps in over ``jerk_time_s``, held to end speed."""
        t = np.asarray(t, dtype=float)
        tt = np.linspace(0.0, self.duration_s + 1.0, int((self.duration_s + 1.0) * 2000) + 1)
        a = -self.decel_mps2 * _smoothstep((tt - self.lead_in_s) / self.jerk_time_s)
        v = self.speed_mps + np.concatenate([[0.0], np.cumsum(0.5 * (a[1:] + a[:-1]) * np.diff(tt))])
        stop = v <= self.end_speed_mps
        v[stop] = self.end_speed_mps
        a[stop] = 0.0
        return np.interp(t, tt, v), np.interp(t, tt, a)

    def speed(self, t) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        if self.kind == "brake":
            return self._brake_profile(t)[0]
        return np.full_like(t, self.speed_mps)

    def accel(self, t) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        if self.kind == "brake":
            return self._brake_profile(t)[1]
        return np.zeros_like(t)

    def steering(self, t) -> np.ndarray:
        """Steering-wheel angle [rad] (positive left) at times ``t``."""
        t = np.asarray(t, dtype=float)
        tau = t - self.lead_in_s
        if self.steer == "sine":
            on = (tau >= 0.0) & (tau <= self.steer_periods / self.steer_freq_hz)
            return np.where(on, self.steer_amplitude_rad * np.sin(2 * np.pi * self.steer_freq_hz * tau), 0.0)
        if self.steer == "random":
            # band-limited: 40 sines with random phases, 0.05 Hz .. steer_freq_hz, RMS = amplitude
            rng = np.random.default_rng(self.steer_seed)
            f = np.linspace(0.05, max(self.steer_freq_hz, 0.06), 40)
            ph = rng.uniform(0, 2 * np.pi, f.size)
            a = self.steer_amplitude_rad * np.sqrt(2.0 / f.size)
            x = (a * np.sin(2 * np.pi * f[None, :] * np.maximum(tau, 0.0)[:, None] + ph[None, :])).sum(axis=1)
            x -= (a * np.sin(ph)).sum()     # starts at zero
            return np.where(tau >= 0.0, x * _smoothstep(tau / 2.0), 0.0)
        return np.zeros_like(t)

    # ---- road ----
    def road(self, wheelbase_m: float = SPEC_WHEELBASE_M) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """(s, zl, zr) of the road, or None for a flat road."""
        if self.kind == "bump":
            s0 = self.speed_mps * self.lead_in_s
            x = np.linspace(0.0, self.bump_length_m, int(round(self.bump_length_m / 0.005)) + 1)
            z = 0.5 * self.bump_height_m * (1.0 - np.cos(2 * np.pi * x / self.bump_length_m))
            return s0 + x, z, z.copy()
        if self.kind == "rough":
            assert self.road_class is not None, "a rough-road maneuver has a road class (TruthManeuver.rough)"
            length = self.speed_mps * self.duration_s + 20.0
            s, zl, zr = iso8608_road(length, self.road_class, self.road_seed, ds=self.road_ds_m,
                                     n_c=self.road_coherence_nc)
            s = s + self.speed_mps * self.lead_in_s
            w = _smoothstep((s - s[0]) / self.road_taper_m)
            return s, (zl - zl[0]) * w, (zr - zr[0]) * w
        return None

    def text(self) -> str:
        """The ``maneuver`` metadata (prefix ``bump_crossing`` / ``sine_steer`` / ``rough_road`` / ``braking``)."""
        kmh = self.speed_mps * 3.6
        if self.kind == "bump":
            return (f"bump_crossing_{kmh:.0f}kmh_{self.bump_height_m * 1000:.0f}mm_x_"
                    f"{self.bump_length_m * 1000:.0f}mm")
        if self.kind == "sine":
            return (f"sine_steer_{kmh:.0f}kmh_{np.degrees(self.steer_amplitude_rad):.0f}deg_"
                    f"{self.steer_freq_hz:g}hz")
        if self.kind == "rough":
            st = "" if self.steer == "none" else f"_highway_{self.steer}_steer"
            return f"rough_road_iso8608_{self.road_class}_{kmh:.0f}kmh{st}"
        if self.kind == "brake":
            return f"braking_{kmh:.0f}kmh_{self.decel_mps2:g}mps2"
        return "rest"

    def to_dict(self) -> dict:
        return asdict(self)


__all__ = ["TruthManeuver", "iso8608_road", "iso8608_psd", "iso8608_gd0", "coherence", "ISO8608_N0"]
