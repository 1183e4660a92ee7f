"""Random road profiles of the ISO 8608 roughness classes.

ISO 8608:2016 describes road unevenness by the displacement power spectral density
``Gd(n) = Gd(n0) (n / n0)^-w`` over the spatial frequency ``n`` [cycles/m], with ``n0 = 0.1`` cycles/m
and waviness ``w = 2``; each class A-H has a geometric-mean ``Gd(n0)`` four times the previous one's
(A: 16e-6 m^3, B: 64e-6, ..., H: 262,144e-6; :data:`CLASS_GD_N0`). A profile is the sum of
cosines with random phases whose amplitudes ``sqrt(2 Gd(n_i) dn)`` give that spectrum (the classic
harmonic superposition, e.g. Tyan et al. 2009; Agostinacchio et al. 2014).

Left and right tracks: a common part plus an independent part, mixed with the coherence
``gamma(n) = 1 / (1 + (n / n_c)^2)``, ``n_c`` = :data:`COHERENCE_CORNER` cycles/m (assumed: long waves are
the same under both wheels, short ones independent; measured coherences fall off around 0.1-0.5 cycles/m
for a track of ~1.5 m, e.g. Bogsjo 2007). Each track keeps the class's spectrum in expectation (the
mix of common and own part makes each line's power random around it).

:func:`fft_road` (the ride runs of issue 15) draws the same spectrum and coherence on an inverse-FFT grid:
each track has the class's amplitude at every line exactly, and the right track's phase differs from the
left's by a random angle whose spread gives the squared coherence ``gamma(n)^2`` as above.
"""
from __future__ import annotations

import math

import numpy as np

from .road import RoadProfile

N0 = 0.1                   # reference spatial frequency [cycles/m] (ISO 8608)
WAVINESS = 2.0             # exponent w (ISO 8608)
CLASSES = "ABCDEFGH"
#: geometric mean Gd(n0) of each class [m^3] (ISO 8608, Table 2)
CLASS_GD_N0 = {c: 16e-6 * 4.0 ** k for k, c in enumerate(CLASSES)}
COHERENCE_CORNER = 0.2     # cycles/m, assumed (module doc)
N_MIN, N_MAX = 0.011, 20.0  # spatial frequencies generated [cycles/m] (ISO 8608's range is 0.011-2.83)


def displacement_psd(road_class: str, n: np.ndarray) -> np.ndarray:
    """Gd(n) [m^3] of an ISO 8608 class at spatial frequencies ``n`` [cycles/m]."""
    return CLASS_GD_N0[road_class] * (np.asarray(n, float) / N0) ** -WAVINESS


def class_of(gd_n0: float) -> str | None:
    """The ISO 8608 class whose band (geometric mean x/÷ 2) holds ``Gd(n0)`` [m^3]; None if not finite."""
    if not math.isfinite(gd_n0) or gd_n0 <= 0:
        return None
    k = int(round(math.log(gd_n0 / CLASS_GD_N0["A"], 4.0)))
    return CLASSES[min(max(k, 0), len(CLASSES) - 1)]


def random_road(road_class: str, length: float, *, seed: int = 0, spacing: float = 0.02,
                n_waves: int = 2000, start: float = 0.0) -> RoadProfile:
    """A seeded random profile of class ``road_class`` over ``length`` [m] from path ``start`` [m]."""
    if road_class not in CLASS_GD_N0:
        raise ValueError(f"ISO 8608 class must be one of {CLASSES}, got {road_class!r}")
    rng = np.random.Generator(np.random.PCG64(seed))
    edges = np.geomspace(N_MIN, N_MAX, n_waves + 1)
    n = np.sqrt(edges[1:] * edges[:-1])
    amp = np.sqrt(2.0 * displacement_psd(road_class, n) * np.diff(edges))
    s = start + np.arange(0.0, length + spacing, spacing)
    gamma = 1.0 / (1.0 + (n / COHERENCE_CORNER) ** 2)
    ph_common, ph_l, ph_r = (rng.uniform(0, 2 * np.pi, n.size) for _ in range(3))
    a_c, a_i = amp * np.sqrt(gamma), amp * np.sqrt(1.0 - gamma)

    def track(ph_own):
        z = np.zeros_like(s)
        for lo in range(0, n.size, 200):  # chunks keep the temporary (n_s x 200) small
            sl = slice(lo, lo + 200)
            arg = 2 * np.pi * np.outer(s - start, n[sl])
            z += np.cos(arg + ph_common[sl]) @ a_c[sl] + np.cos(arg + ph_own[sl]) @ a_i[sl]
        return z

    return RoadProfile(s, track(ph_l), track(ph_r))


def fft_road(road_class: str, length: float, *, seed: int = 0, spacing: float = 0.02) -> RoadProfile:
    """A seeded random profile of class ``road_class`` from path 0 over ``length`` [m], made like
    :func:`random_road` (cosines with random phases, amplitudes ``sqrt(2 Gd(n) dn)``, the same
    left/right coherence and band N_MIN-N_MAX) but on the uniform frequency grid ``dn = 1 / period`` of
    an inverse FFT (Cebon 1999, Handbook of Vehicle-Road Interaction, ch. 3): O(N log N) instead of
    O(N x waves), so a ride run's kilometre of road takes milliseconds. The profile repeats after its
    period (at least ``length``); each track has the class's spectrum at every grid line exactly (the
    left/right phase difference carries the coherence, see the code)."""
    if road_class not in CLASS_GD_N0:
        raise ValueError(f"ISO 8608 class must be one of {CLASSES}, got {road_class!r}")
    n_s = int(math.ceil(length / spacing)) + 1
    m = 2 * ((n_s + 1) // 2)  # even FFT length covering the road
    n = np.fft.rfftfreq(m, d=spacing)
    dn = n[1]
    band = (n >= N_MIN) & (n <= N_MAX)
    amp = np.zeros_like(n)
    amp[band] = np.sqrt(2.0 * displacement_psd(road_class, n[band]) * dn)
    # the right track's phase differs from the left's by delta, uniform in [-theta, theta] with
    # sin(theta)/theta = gamma: the cross-spectrum's expected magnitude is gamma of the auto-spectra, as in
    # random_road (squared coherence gamma^2), while each track keeps the class's amplitude at every line
    gamma = 1.0 / (1.0 + (n / COHERENCE_CORNER) ** 2)
    th = np.linspace(np.pi, 0.0, 4097)
    sinc = np.sinc(th / np.pi)  # sin(th)/th, rising from 0 at pi to 1 at 0
    theta = np.interp(gamma, sinc, th)
    rng = np.random.Generator(np.random.PCG64(seed))
    ph_l = rng.uniform(0, 2 * np.pi, n.size)
    delta = theta * rng.uniform(-1.0, 1.0, n.size)

    def track(ph):
        return np.fft.irfft(amp * np.exp(1j * ph) * (m / 2.0), n=m)[:n_s]

    return RoadProfile(spacing * np.arange(n_s), track(ph_l), track(ph_l + delta))


def faded_road(road_class: str, length: float, *, seed: int = 0, fade_in: float = 10.0,
               spacing: float = 0.02) -> RoadProfile:
    """:func:`fft_road` faded in with a half-cosine over the first ``fade_in`` [m], so that a car
    starting on the flat road before it meets no step (the random profile is not zero at its start).
    Beyond the fade-in the profile is :func:`fft_road`'s exactly."""
    road = fft_road(road_class, length, seed=seed, spacing=spacing)
    w = np.where(road.s < fade_in, 0.5 * (1.0 - np.cos(np.pi * np.clip(road.s / fade_in, 0.0, 1.0))), 1.0)
    return RoadProfile(road.s, road.zl * w, road.zr * w)
