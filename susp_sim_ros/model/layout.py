"""Named indices of the flat arrays the compiled kernel works on.

The kernel sees one vehicle as four float64 vectors: parameters ``P``, state ``S``, the input of one step
``U`` and the output of one step ``Y``. Their layouts are fixed here, by name, so no code (kernel,
Python wrappers, tests) uses a bare index. Per-corner quantities take four consecutive slots in the wheel
order of the interface: FL, FR, RL, RR. Term blocks (see :mod:`susp_sim_ros.model.terms`) are appended
to ``P`` and ``S`` at offsets computed by :class:`KernelLayout`.

All quantities SI, axes REP-103 (x forward, y left, z up; roll positive = left side up, pitch positive =
nose down). Suspension deflection is positive in bump (compression); suspension forces act on the body,
positive upwards.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

WHEELS = ("FL", "FR", "RL", "RR")
N_CORNER = 4


def _enumerate(spec: list[tuple[str, int]]) -> tuple[dict[str, int], int]:
    index, k = {}, 0
    for name, size in spec:
        index[name] = k
        k += size
    return index, k


# ---- parameters (scalars, then per-corner blocks of 4) ---------------------------------------------
_P_SPEC = [
    ("G", 1), ("M_S", 1), ("M_TOT", 1), ("IXX", 1), ("IYY", 1), ("IZZ", 1), ("A", 1), ("B", 1),
    ("H_CG", 1), ("H_RC", 1), ("H_PC", 1), ("STEER_RATIO", 1), ("MU", 1), ("RELAX_LEN", 1),
    ("V_FADE", 1), ("KT", 1), ("CT", 1), ("K_STOP", 1), ("STOP_EP", 1),
    ("DRIVE_FRONT", 1), ("BRAKE_FRONT", 1),
    ("USE_V", 1), ("USE_OIL", 1), ("USE_H", 1), ("SV_REF", 1), ("SV_INF", 1), ("SV_VS", 1),
    # per corner
    ("X_I", 4), ("Y_I", 4), ("M_U", 4), ("K_S", 4), ("STOP_BUMP", 4), ("STOP_REB", 4), ("K_ARB", 4),
    ("TRACK", 4), ("H_RC_AXLE", 4), ("C_ALPHA", 4), ("FZ0", 4), ("OIL", 4), ("SOIL_EMPTY", 4),
    ("SH_X", 4), ("SH_Y", 4),
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

# ---- state -----------------------------------------------------------------------------------------
_S_SPEC = [
    ("Z", 1), ("PHI", 1), ("THETA", 1), ("ZD", 1), ("PHID", 1), ("THETAD", 1),
    ("VY", 1), ("R", 1), ("X", 1), ("Y", 1), ("PSI", 1), ("SPATH", 1),
    ("ZW", 4), ("ZWD", 4), ("FYT", 4), ("ZR_PREV", 4),
    ("VALVE", 4),  # semi-active valve setting after the actuator lag [0..1] (unused by a passive damper)
]
S_INDEX, N_S_FIXED = _enumerate(_S_SPEC)
STATE_LABELS = tuple(
    name if size == 1 else f"{name}_{WHEELS[i]}" for name, size in _S_SPEC for i in range(size))

# ---- inputs of one step ----------------------------------------------------------------------------
_U_SPEC = [("V", 1), ("AX", 1), ("SWA", 1), ("ZR_IN", 4),
           ("CMD", 4)]  # semi-active valve command [0..1] per corner (read only when P_SEMI_ACTIVE is 1)
U_INDEX, N_U = _enumerate(_U_SPEC)

# ---- outputs of one step ---------------------------------------------------------------------------
_Y_SPEC = [
    ("ROLL_RATE", 1), ("PITCH_RATE", 1), ("YAW_RATE", 1), ("AX_SF", 1), ("AY_SF", 1), ("AZ_SF", 1),
    ("ROLL", 1), ("PITCH", 1), ("YAW", 1), ("POS_X", 1), ("POS_Y", 1), ("VEL_X", 1), ("VEL_Y", 1),
    ("HEAVE", 1), ("PATH_S", 1),
    ("DEFL", 4), ("DEFL_VEL", 4), ("F_SPRING", 4), ("F_DAMPER", 4), ("F_FRICTION", 4), ("F_ARB", 4),
    ("F_Z", 4), ("F_X", 4), ("F_Y", 4), ("Z_ROAD", 4),
]
Y_INDEX, N_Y = _enumerate(_Y_SPEC)
OUTPUT_LABELS = tuple(
    name if size == 1 else f"{name}_{WHEELS[i]}" for name, size in _Y_SPEC for i in range(size))
OUTPUT_UNITS = {
    "ROLL_RATE": "rad/s", "PITCH_RATE": "rad/s", "YAW_RATE": "rad/s", "AX_SF": "m/s^2",
    "AY_SF": "m/s^2", "AZ_SF": "m/s^2", "ROLL": "rad", "PITCH": "rad", "YAW": "rad", "POS_X": "m",
    "POS_Y": "m", "VEL_X": "m/s", "VEL_Y": "m/s", "HEAVE": "m", "PATH_S": "m", "DEFL": "m",
    "DEFL_VEL": "m/s", "F_SPRING": "N", "F_DAMPER": "N", "F_FRICTION": "N", "F_ARB": "N", "F_Z": "N",
    "F_X": "N", "F_Y": "N", "Z_ROAD": "m",
}

# ---- per-corner context handed to physics terms ----------------------------------------------------
_C_SPEC = [
    ("D", 1), ("DD", 1), ("FX", 1), ("FY", 1), ("FZ", 1), ("OIL", 1), ("AXLE", 1), ("SIDE", 1),
    ("SV", 1), ("SOIL", 1), ("SH", 1), ("V", 1), ("DT", 1),
]
C_INDEX, N_CTX = _enumerate(_C_SPEC)


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
