"""A force that follows an input, not a state: the road under the wheel or the wheel's rotation
(issue 26, item 5).

Not physics of the model's states, and never offered as a physics term: the discrepancy finder's shape
regression (:mod:`susp_sim_ros.analysis.discrepancy.force_shape`) uses this term's simulated effect as
the columns of its *input features* beside the state features of
:mod:`~susp_sim_ros.model.learned_force`. A missing force that follows one of them (a tyre out of round,
a wheel imbalance, a road the recording has wrong) is an input the recording lacks
(``unmeasured_input``), not missing physics. Tests also use it as model-made truth with such a force.

The force at corner ``i`` (positive up on the body, acting between wheel and body like every term) is a
sum of coefficients [N] times dimensionless input features::

    F_i = sum_k  coef_k * psi_k(i)

==========================  =======================================================================
``road_height``             z_r / z_ref: the road height under the wheel [m] (one step old: the state
                            ``ZR_PREV`` the kernel keeps)
``road_rate``               (dz_r / dt) / zd_ref: its rate [m/s] over the last step
``rotation_sin1``,          sin(theta), cos(theta): the wheel's rotation, first harmonic;
``rotation_cos1``           ``theta = s / R`` [rad], ``s`` the travelled path [m] (state ``SPATH``),
                            ``R`` the rolling radius [m] (the vehicle file's ``tyre.rolling_radius``)
``rotation_sin2``,          sin(2 theta), cos(2 theta): second harmonic (an oval tyre)
``rotation_cos2``
==========================  =======================================================================

Every wheel's angle is taken from the same path: the wheels of a rigid car roll the same distance (up to
the small difference in a bend), so a wheel's own phase is a constant the sine/cosine pair absorbs. A
rolling radius <= 0 switches the rotation features off (0).

States per corner: 0 the road height at the last update [m], 1 its rate over that step [m/s], 2 whether a
step was seen (the first step has no rate).
"""
from __future__ import annotations

import math

from numba import njit

from .inline_math import TINY
from .layout import C_INDEX, S_INDEX
from .terms import PhysicsTerm, TermParam, register_term

INPUT_FEATURES = ("road_height", "road_rate", "rotation_sin1", "rotation_cos1", "rotation_sin2", "rotation_cos2")
#: what kind of input each feature follows (``unmeasured_input.kind`` of the discrepancy finder)
INPUT_KIND = {"road_height": "road", "road_rate": "road", "rotation_sin1": "wheel_rotation",
              "rotation_cos1": "wheel_rotation", "rotation_sin2": "wheel_rotation", "rotation_cos2": "wheel_rotation"}
N_INPUT_FEATURES = len(INPUT_FEATURES)
#: the shape parameters after the coefficients, in this order
SHAPES = ("rolling_radius", "road_ref", "road_rate_ref")
_O_SHAPE = 4 * N_INPUT_FEATURES
_RAD, _ZREF, _ZDREF = (_O_SHAPE + 4 * k for k in range(len(SHAPES)))
_LAST, _RATE, _SEEN = 0, 4, 8
_S_PATH, _S_ZR = S_INDEX["SPATH"], S_INDEX["ZR_PREV"]
_C_DT = C_INDEX["DT"]


@njit(cache=True, inline="always")
def input_force_force(p, po, s, so, i, c):
    """The sum of coefficients times input features at corner ``i`` [N]."""
    q = po + i
    rad = p[po + _RAD + i]
    on = 1.0 if rad > 0.0 else 0.0
    th = s[_S_PATH] / rad if rad > 0.0 else 0.0
    return (p[q] * s[_S_ZR + i] / p[po + _ZREF + i] + p[q + 4] * s[so + _RATE + i] / p[po + _ZDREF + i]
            + on * (p[q + 8] * math.sin(th) + p[q + 12] * math.cos(th)
                    + p[q + 16] * math.sin(2.0 * th) + p[q + 20] * math.cos(2.0 * th)))


@njit(cache=True, inline="always")
def input_force_update(p, po, s, so, i, c, dx):
    """The road height's rate over the step that just ended (the kernel has stored its road height)."""
    zr = s[_S_ZR + i]
    dt = c[i, _C_DT]
    on = 1.0 if s[so + _SEEN + i] > 0.0 and dt > 0.0 else 0.0   # no rate at the first step (or a rig's dt 0)
    s[so + _RATE + i] = on * (zr - s[so + _LAST + i]) / max(dt, TINY)
    s[so + _LAST + i] = zr
    s[so + _SEEN + i] = 1.0


_COEF_MEANING = {
    "road_height": "force at a road height z_ref under the wheel", "road_rate": "force at a road rate zd_ref",
    "rotation_sin1": "force amplitude of sin(theta)", "rotation_cos1": "force amplitude of cos(theta)",
    "rotation_sin2": "force amplitude of sin(2 theta)", "rotation_cos2": "force amplitude of cos(2 theta)"}

INPUT_FORCE = register_term(PhysicsTerm(
    name="input_force", component="axle",
    meaning="a force following the road under the wheel or the wheel's rotation (an input, not physics: the "
            "discrepancy finder's input features, model/input_force.py)",
    params=tuple(TermParam(f"c_{f}", "N", _COEF_MEANING[f], 0.0, -1e5, 1e5) for f in INPUT_FEATURES) + (
        # 0: unset (rotation features off); the finder sets the vehicle file's tyre.rolling_radius
        TermParam("rolling_radius", "m", "rolling radius: the wheel's angle is path / rolling_radius", 0.0, 0.0, 2.0),
        TermParam("road_ref", "m", "road-height scale of road_height", 0.01, 1e-4, 1.0),
        TermParam("road_rate_ref", "m/s", "road-rate scale of road_rate", 0.1, 1e-3, 10.0)),
    n_states=3, force=input_force_force, update=input_force_update,
    gains=tuple(f"c_{f}" for f in INPUT_FEATURES)))
