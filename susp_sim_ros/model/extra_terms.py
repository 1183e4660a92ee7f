"""Physics terms beyond the paper, added through the term interface (:mod:`.terms`).

They are not in any built-in variant; a variant file switches them on (``terms: [{name: ..., params:
{...}}]``) and the discrepancy finder uses them as candidate explanations. Parameters default to zero
effect. Each has a one-line physical meaning.
"""
from __future__ import annotations

from numba import njit

from .layout import C_INDEX
from .terms import PhysicsTerm, TermParam, register_term

_C_DD, _C_D = C_INDEX["DD"], C_INDEX["D"]


@njit(cache=True, inline="always")
def viscous_force(p, po, s, so, i, c):
    v, n = c[i, _C_DD], p[po + 4 + i]
    if n == 1.0:  # the linear law exactly (variant files of the linear term give the same numbers)
        return p[po + i] * v
    v_ref = p[po + 8 + i]
    f = p[po + i] * v_ref * (abs(v) / v_ref) ** n
    return f if v >= 0.0 else -f


@njit(cache=True, inline="always")
def no_update(p, po, s, so, i, c, dx):
    pass


EXTRA_VISCOUS_DAMPING = register_term(PhysicsTerm(
    name="extra_viscous_damping", component="damper",
    meaning="additional damping c*v_ref*sgn(v)*|v/v_ref|^n in parallel with the damper (e.g. bushings, "
            "residual oil; n = 1 linear, n < 1 digressive like a valve-controlled damper, n > 1 progressive "
            "like orifice flow, Dixon, The Shock Absorber Handbook, 2007, ch. 5)",
    params=(TermParam("c", "N s/m", "viscous coefficient: the secant damping rate at v_ref", 0.0, -2000.0, 5000.0),
            TermParam("n", "1", "exponent of the force-velocity law (1: linear)", 1.0, 0.1, 3.0),
            TermParam("v_ref", "m/s", "reference stroke velocity of c (a body-mode damper velocity)", 0.1, 1e-3,
                      10.0)),
    n_states=0, force=viscous_force, update=no_update, gains=("c",)))


@njit(cache=True, inline="always")
def gas_force(p, po, s, so, i, c):
    return p[po + i] + p[po + 4 + i] * c[i, _C_D]


DAMPER_GAS_PRELOAD = register_term(PhysicsTerm(
    name="damper_gas_preload", component="damper",
    meaning="gas-spring force of a pressurised damper: preload change F0 plus gas stiffness k*d",
    params=(TermParam("f0", "N", "force change at static deflection (positive pushes the body up)",
                      0.0, -500.0, 500.0),
            TermParam("k", "N/m", "gas stiffness over deflection", 0.0, -20000.0, 20000.0)),
    n_states=0, force=gas_force, update=no_update, gains=("f0", "k")))
