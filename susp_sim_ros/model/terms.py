"""Physics terms: the extension interface for per-corner suspension forces.

A physics term is a force that acts, at every corner, between wheel and body, in parallel with spring,
hydraulic damper and anti-roll bar. The paper's two friction elements are terms, and so is every
candidate term of the discrepancy finder; users add their own the same way, without touching the core.

A term declares:

- ``name``: the name used in variant YAML files and reports;
- ``component``: ``"axle"`` or ``"damper"``. The damper hydropulser rig (:mod:`.rigs`) sees only damper
  terms; the axle rig and the vehicle see all;
- ``params``: :class:`TermParam` entries. Every parameter has a value per corner (FL, FR, RL, RR) in the
  parameter vector, so fits can free it per axle or per wheel;
- ``n_states``: internal states per corner (a Dahl element has one: its force);
- ``force`` and ``update``: two numba ``@njit`` functions with the fixed signatures

  ``force(p, po, s, so, i, c) -> float``: force on the body [N] at corner ``i`` (positive up) from the
  term's state at the start of the step. ``p`` is the vehicle's parameter vector and the term's
  parameter ``j`` at corner ``i`` is ``p[po + 4*j + i]``; ``s`` the state vector with state ``k`` at
  ``s[so + 4*k + i]``; ``c`` the corner context, a (4 x N_CTX) array read as ``c[i, k]`` with ``k``
  from :data:`layout.C_INDEX`: deflection ``D``
  [m], deflection velocity ``DD`` [m/s], wheel forces ``FX``, ``FY``, ``FZ`` [N], oil level ``OIL``,
  ``AXLE`` (0 front, 1 rear), ``SIDE`` (0 left, 1 right), the paper's friction scalings ``SV``,
  ``SOIL``, ``SH`` (already 1 where the variant switches them off), speed ``V`` and step ``DT``).

  ``update(p, po, s, so, i, c, dx) -> None``: advance the term's states over the step, given the
  deflection increment ``dx`` [m] of the step. Must not touch anything but its own states.

The functions must live at module level in an importable module (the kernel is generated code that
imports them by name; see :mod:`.kernel`). The kernel calls them inside loops over the vehicles of a
block (``p``, ``s``, ``c`` are then one vehicle's column); written as arithmetic with selects rather
than branches, and with :mod:`.inline_math` instead of ``math.exp``/``math.tanh``, those loops compile
to SIMD instructions. A term that branches or calls libm still gives the same numbers; it only makes
the compiler step the vehicles of a block one after another.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

if TYPE_CHECKING:  # numba's stubs make the dispatcher generic; at run time it is not subscriptable
    from numba.core.dispatcher import Dispatcher

from .inline_math import TINY, expm1_nonpos
from .layout import C_INDEX

_C_SV, _C_SOIL, _C_SH, _C_D = C_INDEX["SV"], C_INDEX["SOIL"], C_INDEX["SH"], C_INDEX["D"]


@dataclass(frozen=True)
class TermParam:
    """One parameter of a physics term: default value (per axle) with unit, bounds and meaning."""

    name: str
    unit: str
    meaning: str
    default: float = 0.0
    lower: float = -math.inf
    upper: float = math.inf


@dataclass(frozen=True)
class PhysicsTerm:
    """A per-corner suspension force term (see the module docstring for the contract)."""

    name: str
    component: str
    meaning: str
    params: tuple[TermParam, ...]
    n_states: int
    force: Dispatcher[Callable[..., float]] = field(repr=False)
    update: Dispatcher[Callable[..., None]] = field(repr=False)
    stored_energy: Callable | None = field(default=None, repr=False)
    #: parameters whose being zero at every corner makes the term's force zero whatever its states: the
    #: kernel then skips the term (:func:`~.kernel.load_kernel`'s ``active_terms``; most runs of a
    #: diagnosis carry candidate terms at zero). Empty: the term always runs.
    gains: tuple[str, ...] = ()

    def __post_init__(self):
        if self.component not in ("axle", "damper"):
            raise ValueError(f"term {self.name}: component must be 'axle' or 'damper', "
                             f"got {self.component!r}")
        for fn in (self.force, self.update):
            if not hasattr(fn, "py_func"):
                raise TypeError(f"term {self.name}: {fn!r} must be a numba @njit function")
        for g in self.gains:
            self.param_index(g)  # a gain must be one of the term's parameters

    def param_index(self, name: str) -> int:
        for j, p in enumerate(self.params):
            if p.name == name:
                return j
        raise KeyError(f"term {self.name} has no parameter {name!r}; it has "
                       f"{', '.join(p.name for p in self.params)}")


@njit(cache=True, inline="always")
def dahl_exact(f, level, sigma, dx):
    """Exact position-domain Dahl update (exponent 1) over a deflection increment ``dx`` [m].

    ``F_new = s*Fc + (F - s*Fc) * exp(-sigma*|dx|/Fc)`` (evaluated as an increment), ``s = sign(dx)``;
    unconditionally stable and
    rate independent (model-spec 1). ``f`` is first clipped to the current level, so friction never
    exceeds its level when the level drops; a level <= 0 gives 0. Written without branches (selects
    only), so the kernel runs it on several vehicles per SIMD instruction.
    """
    lv = max(level, 0.0)
    f = min(max(f, -lv), lv)
    target = lv if dx > 0.0 else -lv
    # written as an increment with expm1: monotone in dx and accurate for tiny steps
    f_new = f - (target - f) * expm1_nonpos(-sigma * abs(dx) / max(lv, TINY))
    f_new = min(f_new, target) if dx > 0.0 else max(f_new, target)
    f_new = f if dx == 0.0 else f_new
    return f_new if level > 0.0 else 0.0


# ---- built-in term: axle friction (bearings, ball joints, elastomer mounts) ----------------------
@njit(cache=True, inline="always")
def axle_friction_force(p, po, s, so, i, c):
    return s[so + i]


@njit(cache=True, inline="always")
def axle_friction_update(p, po, s, so, i, c, dx):
    level = p[po + i] * c[i, _C_SH]
    s[so + i] = dahl_exact(s[so + i], level, p[po + 4 + i], dx)


def _dahl_energy(params: np.ndarray, states: np.ndarray) -> float:
    """Energy stored in Dahl elements, F^2 / (2 sigma) [J]; params/states as (n, 4) blocks."""
    sigma = params[1]
    return float(np.sum(states[0] ** 2 / (2.0 * sigma)))


AXLE_FRICTION = PhysicsTerm(
    name="axle_friction", component="axle",
    meaning="Dahl friction of bearings, ball joints and elastomer mounts; level scaled by s_h",
    params=(TermParam("level", "N", "nominal friction level Fc_axle", 0.0, 0.0),
            TermParam("sigma", "N/m", "Dahl stiffness", 1e5, 1.0)),
    n_states=1, force=axle_friction_force, update=axle_friction_update, stored_energy=_dahl_energy)


# ---- built-in term: shock-absorber friction (rod seal, piston band) --------------------------------
@njit(cache=True, inline="always")
def damper_friction_force(p, po, s, so, i, c):
    return s[so + i]


@njit(cache=True, inline="always")
def damper_friction_update(p, po, s, so, i, c, dx):
    level = p[po + i] * c[i, _C_SV] * c[i, _C_SOIL] * c[i, _C_SH]
    s[so + i] = dahl_exact(s[so + i], level, p[po + 4 + i], dx)


DAMPER_FRICTION = PhysicsTerm(
    name="damper_friction", component="damper",
    meaning="Dahl friction of rod seal and piston band; level scaled by s_v, s_oil and s_h",
    params=(TermParam("level", "N", "nominal (intact, 1 mm/s) friction level Fc_sa", 0.0, 0.0),
            TermParam("sigma", "N/m", "Dahl stiffness", 1e5, 1.0)),
    n_states=1, force=damper_friction_force, update=damper_friction_update,
    stored_energy=_dahl_energy)

BUILTIN_TERMS = (AXLE_FRICTION, DAMPER_FRICTION)

_REGISTRY: dict[str, PhysicsTerm] = {t.name: t for t in BUILTIN_TERMS}


def register_term(term: PhysicsTerm) -> PhysicsTerm:
    """Make a term known by name to variant files (``terms: [{name: ..., params: {...}}]``)."""
    existing = _REGISTRY.get(term.name)
    if existing is not None and existing is not term:
        raise ValueError(f"a different physics term named {term.name!r} is already registered")
    _REGISTRY[term.name] = term
    return term


def get_term(name: str) -> PhysicsTerm:
    try:
        return _REGISTRY[name]
    except KeyError:
        raise KeyError(f"unknown physics term {name!r}; known: {', '.join(sorted(_REGISTRY))}") from None


def registered_terms() -> dict[str, PhysicsTerm]:
    return dict(_REGISTRY)
