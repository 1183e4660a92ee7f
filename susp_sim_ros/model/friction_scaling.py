"""The damper friction's velocity scaling s_v (model-spec 1), written once: the compiled kernel inlines
:func:`velocity_scaling_factor` per corner and step, and :func:`~.vehicle.velocity_scaling` (the
hydraulic curves, rigs, tests) evaluates it over numpy arrays through :func:`velocity_scaling_array`.

``s_v(|v|) = 1 - (s_inf - 1) expm1(-max(|v| - v_ref, 0) / v_s)``: 1 up to the reference speed ``v_ref``,
rising towards the plateau ``s_inf`` over the speed ``v_s``. The exponential is
:func:`~.inline_math.expm1_nonpos` (the kernel's, so the loops over vehicles vectorise).
"""
from __future__ import annotations

import numpy as np
from numba import njit

from .inline_math import expm1_nonpos


@njit(cache=True, inline="always")
def velocity_scaling_factor(v, v_ref, plateau, inv_v_s):
    """s_v [-] at the damper velocity ``v`` [m/s] (its magnitude counts), reference speed ``v_ref``
    [m/s], plateau ``plateau`` [-] and the inverse ``inv_v_s`` [s/m] of the rise speed v_s."""
    excess = abs(v) - v_ref
    return 1.0 - (plateau - 1.0) * expm1_nonpos(-max(excess, 0.0) * inv_v_s)


@njit(cache=True)
def velocity_scaling_array(v, v_ref, plateau, inv_v_s):
    """:func:`velocity_scaling_factor` [-] of every velocity of the 1-d array ``v`` [m/s]."""
    out = np.empty(v.shape[0])
    for k in range(v.shape[0]):
        out[k] = velocity_scaling_factor(v[k], v_ref, plateau, inv_v_s)
    return out


__all__ = ["velocity_scaling_array", "velocity_scaling_factor"]
