"""The decoy threshold (issue 24, item 3): a physics term is named only when it beats its own effect with
the timing destroyed (``analysis/discrepancy/decoys.py``)."""
from __future__ import annotations

import numpy as np

from _series import ar1
from susp_sim_ros.analysis.discrepancy.decoys import best_decoy_rss, decoy_effects, decoy_margin
from susp_sim_ros.analysis.discrepancy.finder import MIN_DELTA_BIC
from susp_sim_ros.analysis.discrepancy.fit import bic

N_T, N_SIG = 1000, 2  # one drive: 10 s at 100 Hz, two signals
BLOCKS = [(0, N_T, N_SIG)]
N = N_T * N_SIG
T = np.arange(N_T) * 0.01


def _bump_effect() -> np.ndarray:
    """A ring-out after a bump at 3 s on both signals (the second weaker, lagging)."""
    tau = np.clip(T - 3.0, 0.0, None)
    ring = np.where(T >= 3.0, np.exp(-tau / 0.4) * np.sin(2 * np.pi * 1.3 * tau), 0.0)
    return np.column_stack([ring, 0.4 * np.roll(ring, 5)]).ravel()


def _sine_steer_effect() -> np.ndarray:
    """Four periods of a 0.8 Hz response from 2 to 7 s (periodic: shifts by whole periods line up)."""
    w = (T > 2.0) & (T < 7.0)
    a = np.where(w, np.sin(2 * np.pi * 0.8 * T), 0.0)
    b = np.where(w, 0.5 * np.sin(2 * np.pi * 0.8 * T + 0.3), 0.0)
    return np.column_stack([a, b]).ravel()


def test_decoys_keep_the_terms_form_and_lose_its_timing():
    rng = np.random.default_rng(0)
    delta = rng.standard_normal(N) * np.repeat(np.linspace(0.5, 2.0, N_T), N_SIG)
    decoys = decoy_effects(delta, BLOCKS)
    blk = delta.reshape(N_T, N_SIG)
    assert np.array_equal(decoys[0].reshape(N_T, N_SIG), blk[::-1])
    for d in decoys:
        db = d.reshape(N_T, N_SIG)
        assert np.allclose(np.abs(np.fft.rfft(db, axis=0)), np.abs(np.fft.rfft(blk, axis=0)))  # same spectrum
        assert not np.allclose(db, blk)
    assert len({tuple(np.round(d[:20], 12)) for d in decoys}) == len(decoys)  # no two decoys alike


def test_a_decoy_acts_only_in_its_terms_direction():
    r = np.ones(10)
    rss = best_decoy_rss(r, np.vstack([np.ones(10), -np.ones(10)]))
    assert rss[0] < 1e-12 and rss[1] == 10.0


def test_genuine_transient_and_periodic_effects_beat_their_decoys():
    """A term whose effect is really in the residual (a third of it, on a smooth misfit and white noise)
    beats every decoy clearly, a bump's ring-out and a periodic sine-steer response alike."""
    for shape in (_bump_effect(), _sine_steer_effect()):
        effect = shape * np.sqrt(0.5 * 1.25 * N / float(shape @ shape))  # a third of the residual's energy
        for seed in range(15):
            rng = np.random.default_rng(seed)
            r = effect + 0.5 * ar1(rng, N, 0.98) + rng.standard_normal(N)
            after = r - effect
            n_eff = N / 10
            assert bic(float(r @ r), N, 0, n_eff) - bic(float(after @ after), N, 1, n_eff) > 2 * MIN_DELTA_BIC
            assert decoy_margin(r, after, n_eff, BLOCKS)["decoy_margin"] >= MIN_DELTA_BIC, seed


def test_chance_fits_of_a_smooth_misfit_are_refused_by_their_decoys():
    """A smooth feature with no physics in it, fitted to a smooth misfit: where the criterion alone (every
    sample counted) would name it, its decoys refuse it in most cases (without them: none refused)."""
    passed, refused = 0, 0
    for seed in range(80):
        rng = np.random.default_rng(seed)
        r = ar1(rng, N, 0.98) + rng.standard_normal(N)
        f = ar1(rng, N, 0.98)
        b = max(float(f @ r / (f @ f)), 0.0)
        after = r - b * f
        if bic(float(r @ r), N, 0, N) - bic(float(after @ after), N, 1, N) >= MIN_DELTA_BIC:
            passed += 1
            refused += decoy_margin(r, after, N, BLOCKS)["decoy_margin"] < MIN_DELTA_BIC
    assert passed >= 10, passed
    assert refused >= 0.6 * passed, (refused, passed)
