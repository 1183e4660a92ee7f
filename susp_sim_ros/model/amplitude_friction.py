"""Amplitude-dependent suspension friction: a physics term beyond the paper (its outlook).

The paper's rig measurements end with the observation that the suspension friction grows with the
deflection amplitude (rear axle: 43 N half hysteresis at +-5 mm, 65 N at +-25 mm) and leave modelling it
to future work. This term models it as an extra Dahl element per wheel whose level grows with the stroke
amplitude. It is the hidden physics of the synthetic measurement vehicle behind ``bags/``
(:mod:`susp_sim_ros.analysis.synthetic`) and a candidate of the discrepancy finder.

Parameters per corner (``p[po + 4*j + i]``): 0 ``extra_level`` [N], 1 ``onset`` [m], 2 ``scale`` [m],
3 ``band`` [m], 4 ``sigma`` [N/m], 5 ``horizontal`` [1], 6 ``memory`` [s], 7 ``stroke_weight`` [1]. States
per corner
(``s[so + 4*k + i]``): 0 Dahl force [N], 1 deflection [m] (sum of the increments from static
equilibrium), 2 deflection at the last reversal [m], 3 extreme deflection of the current stroke [m],
4 stroke direction (+1, -1, 0 before the first move), 5 amplitude of the last completed stroke [m],
6 remembered peak deflection from the static position [m] (used with ``memory`` > 0).
"""
from __future__ import annotations

import numpy as np
from numba import njit

from .inline_math import TINY, expm1_nonpos
from .layout import C_INDEX
from .terms import PhysicsTerm, TermParam, dahl_exact, register_term

_F, _DEF, _REV, _EXT, _DIR, _ALAST, _PEAK = 0, 4, 8, 12, 16, 20, 24
_C_SH, _C_DT = C_INDEX["SH"], C_INDEX["DT"]


@njit(cache=True, inline="always")
def friction_amplitude_force(p, po, s, so, i, c):
    """Force of the extra Dahl element [N] (its state)."""
    return s[so + _F + i]


@njit(cache=True, inline="always")
def friction_amplitude_level(extra, onset, scale, amplitude):
    """Extra friction level [N] at deflection amplitude ``amplitude`` [m]:
    ``extra * (1 - exp(-max(A - onset, 0) / scale))``: zero up to the onset, saturating smoothly."""
    excess = amplitude - onset
    level = -extra * expm1_nonpos(-max(excess, 0.0) / scale)
    return level if excess > 0.0 else 0.0


@njit(cache=True, inline="always")
def friction_amplitude_update(p, po, s, so, i, c, dx):
    """Track the stroke amplitude (half the travel between reversals; a reversal counts once the
    deflection has come back by more than ``band`` from the stroke's extreme, so wheel-hop ripple on a
    body stroke does not reset it), then the exact Dahl update at the level of
    ``max(last completed stroke, current stroke)`` amplitude, times the axle friction's horizontal-force
    scaling ``s_h`` (model-spec 1) where ``horizontal`` is set: the extra friction sits in the same
    joints as the axle friction, so wheel forces that load those joints load it too.

    Written with selects only (no branches, no libm call), like :func:`~.terms.dahl_exact`, so the
    kernel's loop over the term updates stays vectorised across vehicles (``docs/kernel_design.md``)."""
    d = s[so + _DEF + i] + dx
    direction = s[so + _DIR + i]
    ext = s[so + _EXT + i]
    rev = s[so + _REV + i]
    last = s[so + _ALAST + i]
    band = p[po + 12 + i]
    moving = direction != 0.0
    start = (not moving) and dx != 0.0  # the first move sets the stroke direction
    goes_on = moving and (d - ext) * direction > 0.0
    reversal = moving and (not goes_on) and (ext - d) * direction > band  # the stroke REV..EXT is complete
    s[so + _DEF + i] = d
    s[so + _DIR + i] = (1.0 if dx > 0.0 else -1.0) if start else (-direction if reversal else direction)
    ext_new = d if (start or goes_on or reversal) else ext
    rev_new = ext if reversal else rev
    last_new = 0.5 * abs(ext - rev) if reversal else last
    s[so + _EXT + i] = ext_new
    s[so + _REV + i] = rev_new
    s[so + _ALAST + i] = last_new
    memory = p[po + 24 + i]
    remembers = memory > 0.0
    # peak deflection from the static position, forgotten with time constant ``memory``
    decay = 1.0 + expm1_nonpos(-c[i, _C_DT] / max(memory, TINY))
    peak = max(s[so + _PEAK + i] * decay, abs(d))
    s[so + _PEAK + i] = peak if remembers else s[so + _PEAK + i]
    stroke = max(0.5 * abs(ext_new - rev_new), last_new)
    w = p[po + 28 + i]
    amp = (w * stroke + (1.0 - w) * peak) if remembers else stroke
    level = friction_amplitude_level(p[po + i], p[po + 4 + i], p[po + 8 + i], amp)
    level = level * c[i, _C_SH] if p[po + 20 + i] > 0.5 else level
    s[so + _F + i] = dahl_exact(s[so + _F + i], level, p[po + 16 + i], dx)


def _amplitude_energy(params: np.ndarray, states: np.ndarray) -> float:
    """Energy stored in the extra Dahl element, F^2 / (2 sigma) [J]."""
    return float(np.sum(states[0] ** 2 / (2.0 * params[4])))


FRICTION_AMPLITUDE = register_term(PhysicsTerm(
    name="friction_amplitude", component="axle",
    meaning=("amplitude-dependent suspension friction (elastomer mounts, bushings): an extra Dahl element "
             "whose level grows with the deflection amplitude of the current/last stroke; zero up to the "
             "onset amplitude, so the +-5 mm axle rig still reads the paper's small-amplitude values"),
    params=(TermParam("extra_level", "N", "extra friction level at large amplitude (saturation)", 0.0, 0.0),
            TermParam("onset", "m", "stroke amplitude below which there is no extra friction", 0.005, 0.0),
            TermParam("scale", "m", "amplitude scale of the saturation above the onset", 0.008, 1e-6),
            TermParam("band", "m", "return travel that counts as a stroke reversal", 0.001, 0.0),
            TermParam("sigma", "N/m", "Dahl stiffness", 1e5, 1.0),
            TermParam("horizontal", "1", "1: the level is scaled by the axle friction's horizontal-force "
                      "scaling s_h, 0: not", 0.0, 0.0, 1.0),
            TermParam("memory", "s", "0: the amplitude is that of the current or last stroke; > 0: the peak "
                      "deflection from the static position, forgotten with this time constant", 0.0, 0.0),
            TermParam("stroke_weight", "1", "with memory > 0: the amplitude is this weight times the stroke "
                      "amplitude plus (1 - weight) times the remembered peak deflection (0: the peak only)",
                      0.0, 0.0, 1.0)),
    n_states=7, force=friction_amplitude_force, update=friction_amplitude_update, gains=("extra_level",),
    stored_energy=_amplitude_energy))
