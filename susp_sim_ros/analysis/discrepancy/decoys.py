"""Decoys: the acceptance threshold of a physics term calibrated on what its own form explains by chance
(issue 24, item 3).

A term is fitted to the residual the calibrated model leaves; its effect on the (whitened, stacked)
residual is ``delta = r_before - r_after``. A *decoy* has the term's form but no physical reason to act:
its effect with the timing destroyed, each drive's and signal's block time-reversed or circularly shifted
(the same shift for every block of a drive, so the decoy keeps the term's pattern across signals and its
spectrum, its smoothness and its size). A decoy is scaled to the residual by least squares, acting in the
term's direction (scale >= 0: a half-period shift of a periodic effect is the effect reversed, not a
decoy). The term is named only when its criterion beats the best decoy's by
:data:`~.finder.MIN_DELTA_BIC`: a term that explains a smooth misfit no better than its time-shuffled
self explains it by its smoothness, not its physics.

This is the knockoff idea of Barber and Candes (2015, "Controlling the false discovery rate via
knockoffs", Ann. Statist. 43(5)) for a model that is nonlinear in its terms: the knockoff copies of a
term are built from its fitted effect (the model is simulated once per term, not once per decoy), so the
threshold costs no simulation. The shifts are golden-ratio fractions of each block's length, so that no
two decoys, nor a decoy and a periodic maneuver's period, line up by construction.
"""
from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

#: circularly shifted decoys per term (besides the time-reversed one)
N_SHIFTS = 8
_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0
#: shifts as fractions of each block's length: frac(k * golden ratio), k = 1 .. N_SHIFTS
SHIFT_FRACTIONS = tuple((k * _GOLDEN) % 1.0 for k in range(1, N_SHIFTS + 1))


def decoy_effects(delta: np.ndarray, blocks: Sequence[tuple[int, int, int]]) -> np.ndarray:
    """The decoys of a term's effect ``delta`` (n_res,): the time-reversed one, then one per
    :data:`SHIFT_FRACTIONS`; ``blocks`` lists each drive's ``(offset, n_samples, n_signals)`` in the
    stacked vector (row-major: samples x signals). Returns (n_decoys, n_res)."""
    out = np.zeros((1 + len(SHIFT_FRACTIONS), delta.size))
    for o, n, s in blocks:
        blk = delta[o:o + n * s].reshape(n, s)
        out[0, o:o + n * s] = blk[::-1].ravel()
        for i, frac in enumerate(SHIFT_FRACTIONS, start=1):
            out[i, o:o + n * s] = np.roll(blk, int(round(frac * n)), axis=0).ravel()
    return out


def best_decoy_rss(residual: np.ndarray, decoys: np.ndarray) -> np.ndarray:
    """Residual sum of squares of ``residual - a * decoy`` for each decoy (row of ``decoys``), its scale
    ``a >= 0`` by least squares (a decoy acts in its term's direction or not at all)."""
    dot = decoys @ residual
    norm = np.einsum("ij,ij->i", decoys, decoys)
    gain = np.where((dot > 0) & (norm > 0), dot * dot / np.maximum(norm, 1e-300), 0.0)
    return float(residual @ residual) - gain


def decoy_margin(r_before: np.ndarray, r_after: np.ndarray, n_eff: float,
                 blocks: Sequence[tuple[int, int, int]]) -> dict:
    """How clearly a term beats its decoys: ``decoy_margin`` = criterion of the best decoy minus the
    term's (``n_eff ln(rss_decoy / rss_term)``; both pay the same parameters), and the number of
    ``decoys``. The term lowered ``r_before`` by its effect
    ``delta = r_before - r_after``; a decoy lowers it by ``a * decoy(delta)``."""
    rss_d = best_decoy_rss(r_before, decoy_effects(r_before - r_after, blocks))
    rss_t = float(r_after @ r_after)
    margin = max(n_eff, 1.0) * math.log(max(float(rss_d.min()), 1e-300) / max(rss_t, 1e-300))
    return {"decoy_margin": margin, "decoys": int(rss_d.size)}
