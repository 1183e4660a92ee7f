"""Named indices of the flat arrays the compiled kernel works on.

The kernel sees one vehicle as four float64 vectors: parameters ``P``, state ``S``, the input of one step
``U`` and the output of one step ``Y``. Their layouts are fixed here, by name, so no code (kernel,
Python wrappers, tests) uses a bare index. Per-corner quantities take four consecutive slots in the wheel
order of the interface: FL, FR, RL, RR. Term blocks (see :mod:`susp_sim_ros.model.terms`) are appended
to ``P`` and ``S`` at offsets computed by :class:`KernelLayout`.

All quantities SI, axes REP-103 (x forward, y left, z up; roll positive = left side up, pitch positive =
nose down). Suspension deflection is positive in bump (compression); suspension forces act on the body,
positive upwards. Every slot carries its SI unit (:class:`Slot`; ``"1"`` for a dimensionless number, a
fraction, a switch or an index): ``P_SLOTS``, ``S_SLOTS``, ``U_SLOTS``, ``Y_SLOTS``, ``C_SLOTS`` and the
name -> unit maps ``P_UNITS``, ``S_UNITS``, ``U_UNITS``, ``OUTPUT_UNITS``, ``C_UNITS``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

WHEELS = ("FL", "FR", "RL", "RR")
N_CORNER = 4


@dataclass(frozen=True)
class Slot:
    """A named block of consecutive entries of one of the kernel's vectors: ``size`` entries from
    ``index`` (1 for a scalar, 4 per corner in the order FL, FR, RL, RR, or a curve table), each in SI
    ``unit`` (``"1"``: dimensionless)."""

    name: str
    index: int
    size: int
    unit: str


def _slots(spec: list[tuple[str, int, str]], start: int = 0) -> tuple[tuple[Slot, ...], int]:
    slots, k = [], start
    for name, size, unit in spec:
        slots.append(Slot(name, k, size, unit))
        k += size
    return tuple(slots), k


def _enumerate(spec: list[tuple[str, int, str]]) -> tuple[dict[str, int], int]:
    slots, n = _slots(spec)
    return {s.name: s.index for s in slots}, n


def slot_at(slots: tuple[Slot, ...], index: int) -> Slot:
    """The slot of ``slots`` holding entry ``index`` of its vector (KeyError if none does)."""
    for s in slots:
        if s.index <= index < s.index + s.size:
            return s
    raise KeyError(f"no slot holds entry {index}")


# ---- parameters (scalars, then per-corner blocks of 4) ---------------------------------------------
_P_SPEC = [
    ("G", 1, "m/s^2"), ("M_S", 1, "kg"), ("M_TOT", 1, "kg"), ("IXX", 1, "kg*m^2"), ("IYY", 1, "kg*m^2"),
    ("IZZ", 1, "kg*m^2"), ("A", 1, "m"), ("B", 1, "m"), ("H_CG", 1, "m"), ("H_RC", 1, "m"), ("H_PC", 1, "m"),
    ("STEER_RATIO", 1, "1"), ("MU", 1, "1"), ("RELAX_LEN", 1, "m"), ("V_FADE", 1, "m/s"),
    ("KT", 1, "N/m"), ("CT", 1, "N*s/m"), ("K_STOP", 1, "N/m"), ("STOP_EP", 1, "m"),
    ("DRIVE_FRONT", 1, "1"), ("BRAKE_FRONT", 1, "1"),
    ("USE_V", 1, "1"), ("USE_OIL", 1, "1"), ("USE_H", 1, "1"), ("SV_REF", 1, "m/s"), ("SV_INF", 1, "1"),
    ("SV_VS", 1, "m/s"),
    # per corner
    ("X_I", 4, "m"), ("Y_I", 4, "m"), ("M_U", 4, "kg"), ("K_S", 4, "N/m"), ("STOP_BUMP", 4, "m"),
    ("STOP_REB", 4, "m"), ("K_ARB", 4, "N/m"), ("TRACK", 4, "m"), ("H_RC_AXLE", 4, "m"),
    ("C_ALPHA", 4, "N/rad"), ("FZ0", 4, "N"), ("OIL", 4, "1"), ("SOIL_EMPTY", 4, "1"),
    ("SH_X", 4, "1/N"), ("SH_Y", 4, "1/N"),
]
P_INDEX, N_P_BASE = _enumerate(_P_SPEC)

# Damper hydraulic curves live after the base parameters on a fixed velocity grid: for each corner an
# intact and an oil-empty curve. The grid is numerical discretisation, not a physical parameter.
DAMPER_GRID = np.array(sorted({s * v for s in (-1.0, 1.0) for v in (
    0.0, 0.001, 0.002, 0.005, 0.01, 0.015, 0.02, 0.026, 0.035, 0.052, 0.075, 0.1, 0.15, 0.2, 0.3,
    0.4, 0.5, 0.75, 1.0, 1.5, 2.0)}))
N_GRID = len(DAMPER_GRID)
P_GRID = N_P_BASE                       # N_GRID velocities [m/s]
P_H_INTACT = P_GRID + N_GRID            # 4 x N_GRID hydraulic forces, intact [N]
P_H_EMPTY = P_H_INTACT + 4 * N_GRID     # 4 x N_GRID hydraulic forces, oil-empty [N]
# Semi-active damper (issue 15): the hydraulic curves at the softest and hardest valve command per corner,
# then whether the command input is used (1) or the passive curve above (0), and the valve's first-order
# time constant [s]. Appended after the passive block so every earlier offset stays as it was.
P_H_SOFT = P_H_EMPTY + 4 * N_GRID       # 4 x N_GRID hydraulic forces at command 0, intact oil [N]
P_H_HARD = P_H_SOFT + 4 * N_GRID        # 4 x N_GRID hydraulic forces at command 1, intact oil [N]
P_SEMI_ACTIVE = P_H_HARD + 4 * N_GRID   # 0: passive damper (command ignored), 1: command in use
P_VALVE_TAU = P_SEMI_ACTIVE + 1         # valve (actuator) time constant [s]
N_P_FIXED = P_VALVE_TAU + 1
#: every slot of the fixed parameter vector (base parameters, damper tables, semi-active switch and lag)
P_SLOTS = _slots(_P_SPEC)[0] + _slots([
    ("GRID", N_GRID, "m/s"), ("H_INTACT", 4 * N_GRID, "N"), ("H_EMPTY", 4 * N_GRID, "N"),
    ("H_SOFT", 4 * N_GRID, "N"), ("H_HARD", 4 * N_GRID, "N"), ("SEMI_ACTIVE", 1, "1"), ("VALVE_TAU", 1, "s"),
], N_P_BASE)[0]
P_UNITS = {s.name: s.unit for s in P_SLOTS}

# ---- state -----------------------------------------------------------------------------------------
_S_SPEC = [
    ("Z", 1, "m"), ("PHI", 1, "rad"), ("THETA", 1, "rad"), ("ZD", 1, "m/s"), ("PHID", 1, "rad/s"),
    ("THETAD", 1, "rad/s"), ("VY", 1, "m/s"), ("R", 1, "rad/s"), ("X", 1, "m"), ("Y", 1, "m"),
    ("PSI", 1, "rad"), ("SPATH", 1, "m"),
    ("ZW", 4, "m"), ("ZWD", 4, "m/s"), ("FYT", 4, "N"), ("ZR_PREV", 4, "m"),
    ("VALVE", 4, "1"),  # semi-active valve setting after the actuator lag [0..1] (unused by a passive damper)
]
S_INDEX, N_S_FIXED = _enumerate(_S_SPEC)
S_SLOTS = _slots(_S_SPEC)[0]
S_UNITS = {s.name: s.unit for s in S_SLOTS}
STATE_LABELS = tuple(
    name if size == 1 else f"{name}_{WHEELS[i]}" for name, size, _ in _S_SPEC for i in range(size))

# ---- inputs of one step ----------------------------------------------------------------------------
_U_SPEC = [("V", 1, "m/s"), ("AX", 1, "m/s^2"), ("SWA", 1, "rad"), ("ZR_IN", 4, "m"),
           ("CMD", 4, "1")]  # semi-active valve command [0..1] per corner (read only when P_SEMI_ACTIVE is 1)
U_INDEX, N_U = _enumerate(_U_SPEC)
U_SLOTS = _slots(_U_SPEC)[0]
U_UNITS = {s.name: s.unit for s in U_SLOTS}

# ---- outputs of one step ---------------------------------------------------------------------------
_Y_SPEC = [
    ("ROLL_RATE", 1, "rad/s"), ("PITCH_RATE", 1, "rad/s"), ("YAW_RATE", 1, "rad/s"), ("AX_SF", 1, "m/s^2"),
    ("AY_SF", 1, "m/s^2"), ("AZ_SF", 1, "m/s^2"), ("ROLL", 1, "rad"), ("PITCH", 1, "rad"), ("YAW", 1, "rad"),
    ("POS_X", 1, "m"), ("POS_Y", 1, "m"), ("VEL_X", 1, "m/s"), ("VEL_Y", 1, "m/s"), ("HEAVE", 1, "m"),
    ("PATH_S", 1, "m"),
    ("DEFL", 4, "m"), ("DEFL_VEL", 4, "m/s"), ("F_SPRING", 4, "N"), ("F_DAMPER", 4, "N"),
    ("F_FRICTION", 4, "N"), ("F_ARB", 4, "N"), ("F_Z", 4, "N"), ("F_X", 4, "N"), ("F_Y", 4, "N"),
    ("Z_ROAD", 4, "m"),
]
Y_INDEX, N_Y = _enumerate(_Y_SPEC)
Y_SLOTS = _slots(_Y_SPEC)[0]
OUTPUT_LABELS = tuple(
    name if size == 1 else f"{name}_{WHEELS[i]}" for name, size, _ in _Y_SPEC for i in range(size))
#: unit of each output slot (per-corner outputs: of each of its four labels ``NAME_FL`` ...)
OUTPUT_UNITS = {s.name: s.unit for s in Y_SLOTS}

# ---- per-corner context handed to physics terms ----------------------------------------------------
_C_SPEC = [
    ("D", 1, "m"), ("DD", 1, "m/s"), ("FX", 1, "N"), ("FY", 1, "N"), ("FZ", 1, "N"), ("OIL", 1, "1"),
    ("AXLE", 1, "1"), ("SIDE", 1, "1"), ("SV", 1, "1"), ("SOIL", 1, "1"), ("SH", 1, "1"), ("V", 1, "m/s"),
    ("DT", 1, "s"),
]
C_INDEX, N_CTX = _enumerate(_C_SPEC)
C_SLOTS = _slots(_C_SPEC)[0]
C_UNITS = {s.name: s.unit for s in C_SLOTS}


def output_unit(label: str) -> str:
    """SI unit of an output label such as ``'PITCH_RATE'`` or ``'DEFL_RL'``."""
    return slot_at(Y_SLOTS, output_index(label)).unit


def output_index(label: str) -> int:
    """Column of an output label such as ``'PITCH_RATE'`` or ``'DEFL_RL'`` in the full output vector."""
    try:
        return OUTPUT_LABELS.index(label)
    except ValueError:
        raise KeyError(f"unknown output {label!r}; known: {', '.join(OUTPUT_LABELS)}") from None


@dataclass(frozen=True)
class KernelLayout:
    """Offsets of the term blocks appended to ``P`` and ``S`` for one list of terms.

    ``param_offsets[k]``/``state_offsets[k]`` are where term ``k`` finds its per-corner parameters
    (``n_params * 4`` slots, parameter-major) and states (``n_states * 4`` slots, state-major).
    """

    param_offsets: tuple[int, ...]
    state_offsets: tuple[int, ...]
    n_p: int
    n_s: int

    @classmethod
    def for_terms(cls, terms) -> "KernelLayout":
        po, so, p, s = [], [], N_P_FIXED, N_S_FIXED
        for term in terms:
            po.append(p)
            so.append(s)
            p += len(term.params) * N_CORNER
            s += term.n_states * N_CORNER
        return cls(tuple(po), tuple(so), p, s)


def term_param_slots(terms) -> tuple[Slot, ...]:
    """The slots of the term blocks that :class:`KernelLayout` appends to ``P`` after the fixed ones
    (:data:`P_SLOTS`): one per term parameter, named ``term.param``, four entries (FL, FR, RL, RR) in the
    unit the term declares (:class:`~.terms.TermParam`). The terms' states declare no units yet."""
    layout = KernelLayout.for_terms(terms)
    return tuple(Slot(f"{t.name}.{p.name}", off + N_CORNER * j, N_CORNER, p.unit)
                 for t, off in zip(terms, layout.param_offsets) for j, p in enumerate(t.params))
