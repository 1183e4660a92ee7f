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
    return p[po + i] * c[i, _C_DD]


@njit(cache=True, inline="always")
def no_update(p, po, s, so, i, c, dx):
    pass


EXTRA_VISCOUS_DAMPING = register_term(PhysicsTerm(
    name="extra_viscous_damping", component="damper",
    meaning="additional linear damping c*v in parallel with the damper (e.g. bushings, residual oil)",
    params=(TermParam("c", "N s/m", "viscous coefficient", 0.0, -2000.0, 5000.0),),
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
