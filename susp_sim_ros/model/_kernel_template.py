"""Compiled five-mass vehicle kernel (template; see :mod:`susp_sim_ros.model.kernel`).

This file is the source of the generated kernel modules: :mod:`.kernel` replaces the block between the
TERMS markers with calls to the configured physics terms and imports the result. It is also importable
as it is (no terms), which keeps it linted and testable.

Equations: model-spec section 2 (heave, roll, pitch, lateral, yaw of the body; four wheels), forces
measured from static equilibrium, small angles, SI units, REP-103 axes. Integration: semi-implicit
(symplectic) Euler at a fixed step; Dahl elements and tyre relaxation use their exact solutions over the
step, which keeps them stable at any step (model-spec 1).

One stepping function, :func:`step`, serves everything. It advances a block of up to :data:`LANES`
vehicles held as columns (structure of arrays), so every loop over the vehicles of a block compiles to
SIMD instructions: :func:`run_one` runs one vehicle as a block of one (the node calls it every publish
period with the few steps due; offline runs call it once for a whole drive) and :func:`run_batch` runs
blocks in parallel with ``prange``. A vehicle's numbers do not depend on its block or lane.

:func:`step` is a sequence of named stages, each inlined into it: :func:`road_under_wheels`,
:func:`corner_kinematics`, :func:`suspension_forces`, :func:`body_accelerations` (the pure right-hand
side, which :mod:`.linear` linearises), :func:`integrate`, :func:`update_term_states`,
:func:`state_is_finite`, :func:`corner_outputs` and :func:`imu_outputs`.
"""
import math

import numpy as np
from numba import njit, prange, types
from numba.core import cgutils
from numba.extending import intrinsic

from susp_sim_ros.model.inline_math import TINY, expm1_nonpos, tanh
from susp_sim_ros.model.friction_scaling import velocity_scaling_factor
from susp_sim_ros.model.layout import (C_INDEX, N_CTX, N_GRID, N_P_FIXED, N_S_FIXED, N_Y, P_GRID,
                                       P_H_EMPTY, P_H_HARD, P_H_INTACT, P_H_SOFT, P_INDEX, P_SEMI_ACTIVE,
                                       P_VALVE_TAU, S_INDEX, U_INDEX, Y_INDEX)

# ---- named indices, frozen into the compiled code as constants ---------------------------------------
_G, _M_S, _M_TOT = P_INDEX["G"], P_INDEX["M_S"], P_INDEX["M_TOT"]
_IXX, _IYY, _IZZ = P_INDEX["IXX"], P_INDEX["IYY"], P_INDEX["IZZ"]
_A, _B, _H_CG, _H_RC, _H_PC = P_INDEX["A"], P_INDEX["B"], P_INDEX["H_CG"], P_INDEX["H_RC"], P_INDEX["H_PC"]
_STEER_RATIO, _MU, _RELAX_LEN, _V_FADE = (P_INDEX["STEER_RATIO"], P_INDEX["MU"], P_INDEX["RELAX_LEN"],
                                          P_INDEX["V_FADE"])
_KT, _CT, _K_STOP, _STOP_EP = P_INDEX["KT"], P_INDEX["CT"], P_INDEX["K_STOP"], P_INDEX["STOP_EP"]
_DRIVE_FRONT, _BRAKE_FRONT = P_INDEX["DRIVE_FRONT"], P_INDEX["BRAKE_FRONT"]
_USE_V, _USE_OIL, _USE_H = P_INDEX["USE_V"], P_INDEX["USE_OIL"], P_INDEX["USE_H"]
_SV_REF, _SV_INF, _SV_VS = P_INDEX["SV_REF"], P_INDEX["SV_INF"], P_INDEX["SV_VS"]
_X_I, _Y_I, _M_U, _K_S = P_INDEX["X_I"], P_INDEX["Y_I"], P_INDEX["M_U"], P_INDEX["K_S"]
_STOP_BUMP, _STOP_REB, _K_ARB = P_INDEX["STOP_BUMP"], P_INDEX["STOP_REB"], P_INDEX["K_ARB"]
_TRACK, _H_RC_AXLE, _C_ALPHA, _FZ0 = (P_INDEX["TRACK"], P_INDEX["H_RC_AXLE"], P_INDEX["C_ALPHA"],
                                      P_INDEX["FZ0"])
_OIL, _SOIL_EMPTY, _SH_X, _SH_Y = P_INDEX["OIL"], P_INDEX["SOIL_EMPTY"], P_INDEX["SH_X"], P_INDEX["SH_Y"]

_Z, _PHI, _THETA, _ZD, _PHID, _THETAD = (S_INDEX["Z"], S_INDEX["PHI"], S_INDEX["THETA"], S_INDEX["ZD"],
                                         S_INDEX["PHID"], S_INDEX["THETAD"])
_VY, _R, _X, _Y, _PSI, _SPATH = (S_INDEX["VY"], S_INDEX["R"], S_INDEX["X"], S_INDEX["Y"], S_INDEX["PSI"],
                                 S_INDEX["SPATH"])
_ZW, _ZWD, _FYT, _ZR_PREV = S_INDEX["ZW"], S_INDEX["ZWD"], S_INDEX["FYT"], S_INDEX["ZR_PREV"]
_VALVE = S_INDEX["VALVE"]

_U_V, _U_AX, _U_SWA, _U_ZR = U_INDEX["V"], U_INDEX["AX"], U_INDEX["SWA"], U_INDEX["ZR_IN"]
_U_CMD = U_INDEX["CMD"]

_C_D, _C_DD, _C_FX, _C_FY, _C_FZ = C_INDEX["D"], C_INDEX["DD"], C_INDEX["FX"], C_INDEX["FY"], C_INDEX["FZ"]
_C_OIL, _C_AXLE, _C_SIDE = C_INDEX["OIL"], C_INDEX["AXLE"], C_INDEX["SIDE"]
_C_SV, _C_SOIL, _C_SH, _C_V, _C_DT = (C_INDEX["SV"], C_INDEX["SOIL"], C_INDEX["SH"], C_INDEX["V"],
                                      C_INDEX["DT"])

_Y_ROLL_RATE, _Y_PITCH_RATE, _Y_YAW_RATE = Y_INDEX["ROLL_RATE"], Y_INDEX["PITCH_RATE"], Y_INDEX["YAW_RATE"]
_Y_AX, _Y_AY, _Y_AZ = Y_INDEX["AX_SF"], Y_INDEX["AY_SF"], Y_INDEX["AZ_SF"]
_Y_ROLL, _Y_PITCH, _Y_YAW = Y_INDEX["ROLL"], Y_INDEX["PITCH"], Y_INDEX["YAW"]
_Y_PX, _Y_PY, _Y_VX, _Y_VY = Y_INDEX["POS_X"], Y_INDEX["POS_Y"], Y_INDEX["VEL_X"], Y_INDEX["VEL_Y"]
_Y_HEAVE, _Y_PATH = Y_INDEX["HEAVE"], Y_INDEX["PATH_S"]
_Y_DEFL, _Y_DEFL_VEL, _Y_F_SPRING = Y_INDEX["DEFL"], Y_INDEX["DEFL_VEL"], Y_INDEX["F_SPRING"]
_Y_F_DAMPER, _Y_F_FRICTION, _Y_F_ARB = Y_INDEX["F_DAMPER"], Y_INDEX["F_FRICTION"], Y_INDEX["F_ARB"]
_Y_F_Z, _Y_F_X, _Y_F_Y, _Y_Z_ROAD = Y_INDEX["F_Z"], Y_INDEX["F_X"], Y_INDEX["F_Y"], Y_INDEX["Z_ROAD"]

MASK_AXLE = 1
MASK_DAMPER = 2
MASK_ALL = 3

# vehicles per block: AVX-512 holds 8 doubles, AVX2 4; 16 lets the compiler unroll the vector loops
LANES = 16
#: whether the step carries the semi-active damper (command clamp, valve lag, curve family). The generator
#: (:mod:`.kernel`) sets it per kernel: passive batches run a kernel without that code, which keeps the
#: corner loop as fast as before the semi-active damper (numba removes the dead branches).
SEMI_ACTIVE_CODE = True
# scratch rows per block: per corner (W[_W_x + i]), then per vehicle
_W_ZR, _W_ZRD, _W_SLOPE, _W_D, _W_DD, _W_FZ, _W_WF, _W_FX, _W_FS = 0, 4, 8, 12, 16, 20, 24, 28, 32
_W_V, _W_AX, _W_DELTA, _W_ZDD, _W_AY, _W_OK = 36, 37, 38, 39, 40, 41
_W_CMD = 42  # 4: the valve command of the step per corner, limited to [0, 1]
# accelerations of the step (:func:`body_accelerations`): roll, pitch, lateral velocity, yaw, then per wheel
_W_PHIDD, _W_THDD, _W_VYD, _W_RD, _W_ZWDD = 46, 47, 48, 49, 50
_W_FT, _W_DX = 54, 58  # 4 each: the physics terms' force and the deflection increment of the step
N_SCRATCH = 62

# reciprocals of constant parameters, computed once per run (:func:`derive`): the step then
# multiplies instead of dividing, and a parameter changed between runs is always seen
_D_INV_MS, _D_INV_M, _D_INV_IXX, _D_INV_IYY, _D_INV_IZZ, _D_INV_RATIO = 0, 1, 2, 3, 4, 5
_D_INV_EP, _D_INV_VS, _D_INV_RELAX, _D_INV_FADE = 6, 7, 8, 9
_D_INV_MU, _D_DFZ = 10, 14  # 4 each
_D_INV_CELL = 18  # N_GRID - 1 inverse grid cell widths
_D_VALVE_ALPHA = _D_INV_CELL + N_GRID - 1  # 1 - exp(-dt / tau) of the valve lag (set per run: needs dt)
N_DERIVED = _D_VALVE_ALPHA + 1


@njit(cache=True, inline="always")
def derive(p, dv):
    dv[_D_INV_MS] = 1.0 / p[_M_S]
    dv[_D_INV_M] = 1.0 / p[_M_TOT]
    dv[_D_INV_IXX] = 1.0 / p[_IXX]
    dv[_D_INV_IYY] = 1.0 / p[_IYY]
    dv[_D_INV_IZZ] = 1.0 / p[_IZZ]
    dv[_D_INV_RATIO] = 1.0 / p[_STEER_RATIO]
    dv[_D_INV_EP] = 1.0 / p[_STOP_EP]
    dv[_D_INV_VS] = 1.0 / p[_SV_VS]
    dv[_D_INV_RELAX] = 1.0 / p[_RELAX_LEN]
    dv[_D_INV_FADE] = 1.0 / p[_V_FADE]
    for i in range(4):
        dv[_D_INV_MU + i] = 1.0 / p[_M_U + i]
        dv[_D_DFZ + i] = p[_H_RC_AXLE + i] / p[_TRACK + i]
    for k in range(N_GRID - 1):
        dv[_D_INV_CELL + k] = 1.0 / (p[P_GRID + k + 1] - p[P_GRID + k])


def _stack_array(shape, dtype=types.float64):
    """An intrinsic returning a C-contiguous array of ``shape`` on the stack of the calling function
    (no allocation, no reference counting; valid while that function runs)."""
    arrty = types.Array(dtype, len(shape), "C")
    n = int(np.prod(shape))
    itemsize = dtype.bitwidth // 8
    strides = [itemsize * int(np.prod(shape[k + 1:])) for k in range(len(shape))]

    @intrinsic
    def stack(typingctx):
        def codegen(context, builder, sig, args):
            intp = lambda v: context.get_constant(types.intp, v)  # noqa: E731
            ptr = cgutils.alloca_once(builder, context.get_value_type(dtype), size=intp(n))
            ary = context.make_array(arrty)(context, builder)
            context.populate_array(ary, data=ptr, shape=[intp(d) for d in shape],
                                   strides=[intp(st) for st in strides], itemsize=intp(itemsize), meminfo=None)
            return ary._getvalue()
        return arrty(), codegen
    return stack


# @@BEGIN TERMS@@
N_P = N_P_FIXED
N_S = N_S_FIXED


@njit(cache=True)
def terms_force(p, s, i, c, mask):
    return 0.0


@njit(cache=True)
def terms_update(p, s, i, c, dx, mask):
    pass


@njit(cache=True)
def active_terms(P, nl):
    return 0


@njit(cache=True)
def terms_force_lanes(P, S, C, W, r, i, nl, act):
    for l in range(nl):
        W[r, l] = 0.0


@njit(cache=True)
def terms_update_lanes(P, S, C, W, r, i, nl, act):
    pass
# @@END TERMS@@


_stack_p, _stack_dv, _stack_s = (_stack_array((N_P, LANES)), _stack_array((N_DERIVED, LANES)),
                                 _stack_array((N_S, LANES)))
_stack_c, _stack_w, _stack_y = (_stack_array((4, N_CTX, LANES)), _stack_array((N_SCRATCH, LANES)),
                                _stack_array((N_Y, LANES)))
_stack_i = _stack_array((LANES,), types.int64)


@njit(cache=True, inline="always")
def grid_cell(p, x):
    """Cell ``k`` of the velocity grid holding ``x``: ``grid[k] <= x < grid[k+1]``, the end cells
    extended (linear extrapolation). Counted without branches, so it vectorises across vehicles."""
    k = 0.0
    for g in range(1, N_GRID - 1):
        k += 1.0 if p[P_GRID + g] <= x else 0.0
    return int(k)


@njit(cache=True, inline="always")
def _interp_cell(p, dv, off, x, k):
    """Piecewise-linear curve p[off:off+N_GRID] over the velocity grid, evaluated in cell k."""
    y0 = p[off + k]
    return y0 + (p[off + k + 1] - y0) * (x - p[P_GRID + k]) * dv[_D_INV_CELL + k]


@njit(cache=True, inline="always")
def road_at(rs, rz, n, x):
    """Elevation [m] and slope dz/ds [-] of one track at path coordinate x; flat outside the profile."""
    if n < 2 or x <= rs[0] or x >= rs[n - 1]:
        return 0.0, 0.0
    lo, hi = 0, n - 1
    while hi - lo > 1:
        mid = (lo + hi) >> 1
        if rs[mid] <= x:
            lo = mid
        else:
            hi = mid
    slope = (rz[hi] - rz[lo]) / (rs[hi] - rs[lo])
    return rz[lo] + slope * (x - rs[lo]), slope


@njit(cache=True, inline="always")
def spring_force(p, dv, i, d):
    """Wheel-rate spring plus progressive bump/rebound stops [N], deflection d [m] from static."""
    e_b = max(d - p[_STOP_BUMP + i], 0.0)
    e_r = max(-d - p[_STOP_REB + i], 0.0)
    return (p[_K_S + i] * d + p[_K_STOP] * e_b * (1.0 + e_b * dv[_D_INV_EP])
            - p[_K_STOP] * e_r * (1.0 + e_r * dv[_D_INV_EP]))


@njit(cache=True, inline="always")
def hydraulic_force(p, dv, i, dd, k):
    """Hydraulic damper force [N] at deflection velocity dd [m/s], blended by the corner's oil level;
    ``k`` is the grid cell of dd (:func:`grid_cell`)."""
    oil = p[_OIL + i]
    return (oil * _interp_cell(p, dv, P_H_INTACT + i * N_GRID, dd, k)
            + (1.0 - oil) * _interp_cell(p, dv, P_H_EMPTY + i * N_GRID, dd, k))


@njit(cache=True, inline="always")
def semi_active_force(p, dv, i, dd, k, valve):
    """Hydraulic force [N] of a semi-active damper at valve setting ``valve`` in [0, 1]: linear between
    the softest (0) and hardest (1) curve at deflection velocity dd, then blended by the oil level with
    the oil-empty curve exactly as the passive damper (:func:`hydraulic_force`)."""
    oil = p[_OIL + i]
    soft = _interp_cell(p, dv, P_H_SOFT + i * N_GRID, dd, k)
    hard = _interp_cell(p, dv, P_H_HARD + i * N_GRID, dd, k)
    return (oil * (soft + valve * (hard - soft))
            + (1.0 - oil) * _interp_cell(p, dv, P_H_EMPTY + i * N_GRID, dd, k))


@njit(cache=True, inline="always")
def fill_context_const(p, i, c, dt):
    """The parts of corner ``i``'s context that stay constant over a run (set once per run): oil
    level, axle, side, step ``dt`` [s] and the oil scaling ``s_oil`` of the damper friction."""
    oil = p[_OIL + i]
    c[i, _C_OIL] = oil
    c[i, _C_AXLE] = 0.0 if i < 2 else 1.0
    c[i, _C_SIDE] = float(i % 2)
    c[i, _C_DT] = dt
    soil = 1.0
    if p[_USE_OIL] > 0.5:
        soil = 1.0 + (p[_SOIL_EMPTY + i] - 1.0) * (1.0 - oil)
    c[i, _C_SOIL] = soil


@njit(cache=True, inline="always")
def fill_context(p, dv, i, c, d, dd, fx, fy, fz, v):
    """Corner context for the physics terms, including the paper's friction scalings (model-spec 1);
    the constant part is set by :func:`fill_context_const`."""
    c[i, _C_D] = d
    c[i, _C_DD] = dd
    c[i, _C_FX] = fx
    c[i, _C_FY] = fy
    c[i, _C_FZ] = fz
    c[i, _C_V] = v
    sv = velocity_scaling_factor(dd, p[_SV_REF], p[_SV_INF], dv[_D_INV_VS])
    c[i, _C_SV] = sv if p[_USE_V] > 0.5 else 1.0
    sh = 1.0 + p[_SH_X + i] * abs(fx) + p[_SH_Y + i] * abs(fy)
    c[i, _C_SH] = sh if p[_USE_H] > 0.5 else 1.0


# ---- the stages of one step ----------------------------------------------------------------------------
# Each stage works on the ``nl`` lanes of a block (column ``l`` of every array is one vehicle) and is
# inlined into :func:`step`, so the compiled step is one function whose loops over lanes vectorise. Every
# arithmetic expression is written in the order the kernel has always evaluated it (the results are the
# same bit for bit as the single-function step they replaced).
@njit(cache=True, inline="always")
def road_under_wheels(P, DV, S, U, urow, k, RS, RZL, RZR, RN, rrow, mode, dt, W, nl):
    """Inputs of step row ``k`` (speed, longitudinal acceleration, road-wheel steer angle, the valve
    command limited to [0, 1]) and the road under each wheel: height [m], its rate [m/s] and slope [-]
    from the tracks (``mode`` 0, binary search: per vehicle) or the per-wheel heights of the inputs
    (``mode`` 1). Writes scratch rows ``_W_V``, ``_W_AX``, ``_W_DELTA``, ``_W_ZR``, ``_W_ZRD``,
    ``_W_SLOPE``, ``_W_CMD``."""
    for l in range(nl):
        u = urow[l]
        v = U[u, k, _U_V]
        W[_W_V, l] = v
        W[_W_AX, l] = U[u, k, _U_AX]
        W[_W_DELTA, l] = U[u, k, _U_SWA] * DV[_D_INV_RATIO, l]
        rr = rrow[l]
        for i in range(4):
            if mode[l] == 1:
                zr = U[u, k, _U_ZR + i]
                zrd = (zr - S[_ZR_PREV + i, l]) / dt
                slope = zrd / v if v > P[_V_FADE, l] else 0.0
            else:
                si = S[_SPATH, l] if i < 2 else S[_SPATH, l] - (P[_A, l] + P[_B, l])
                if i % 2 == 0:
                    zr, slope = road_at(RS[rr], RZL[rr], RN[rr], si)
                else:
                    zr, slope = road_at(RS[rr], RZR[rr], RN[rr], si)
                zrd = v * slope
            W[_W_ZR + i, l] = zr
            W[_W_ZRD + i, l] = zrd
            W[_W_SLOPE + i, l] = slope
            if SEMI_ACTIVE_CODE:
                W[_W_CMD + i, l] = min(max(U[u, k, _U_CMD + i], 0.0), 1.0)


@njit(cache=True, inline="always")
def corner_kinematics(P, DV, S, W, nl):
    """Suspension deflection [m] and its rate [m/s] per corner (positive in bump), the tyre's vertical
    load [N] (spring and damper on the road, lateral load transfer through the axle's roll centre,
    lift-off), the net vertical tyre force on the wheel from static [N] and the horizontal wheel force
    [N] (drive/brake share, bump reaction). Writes ``_W_D``, ``_W_DD``, ``_W_FZ``, ``_W_WF``, ``_W_FX``."""
    for i in range(4):
        for l in range(nl):
            z = S[_Z, l]
            phi = S[_PHI, l]
            th = S[_THETA, l]
            xi = P[_X_I + i, l]
            yi = P[_Y_I + i, l]
            W[_W_D + i, l] = S[_ZW + i, l] - (z - xi * th + yi * phi)
            W[_W_DD + i, l] = S[_ZWD + i, l] - (S[_ZD, l] - xi * S[_THETAD, l] + yi * S[_PHID, l])
            ft = (P[_KT, l] * (W[_W_ZR + i, l] - S[_ZW + i, l])
                  + P[_CT, l] * (W[_W_ZRD + i, l] - S[_ZWD + i, l]))
            # geometric load transfer of the axle's lateral force through its roll centre: wheels only
            fy_axle = S[_FYT, l] + S[_FYT + 1, l] if i < 2 else S[_FYT + 2, l] + S[_FYT + 3, l]
            dfz = fy_axle * DV[_D_DFZ + i, l]
            if i % 2 == 0:
                dfz = -dfz
            fz = max(P[_FZ0 + i, l] + ft + dfz, 0.0)  # lift-off: the tyre cannot pull
            W[_W_FZ + i, l] = fz
            W[_W_WF + i, l] = fz - P[_FZ0 + i, l] - dfz
            ax = W[_W_AX, l]
            share_f = P[_DRIVE_FRONT, l] if ax >= 0.0 else P[_BRAKE_FRONT, l]
            fx_drive = P[_M_TOT, l] * ax * (share_f if i < 2 else 1.0 - share_f) * 0.5
            W[_W_FX + i, l] = fx_drive - fz * W[_W_SLOPE + i, l]  # bump reaction while climbing/leaving


@njit(cache=True, inline="always")
def suspension_forces(P, DV, S, C, W, Y, nl, out, act):
    """Force of each suspension on the body [N], positive up: wheel-rate spring and stops, hydraulic
    damper (passive curve by oil level, or the semi-active family at the lagged valve setting, which
    this stage advances: ``S[_VALVE]``), the physics terms (the paper's friction elements with their
    scalings, added terms; context filled by :func:`fill_context`) and the anti-roll bar. Writes
    ``_W_FS``, the corner context ``C`` and, when ``out``, the force outputs of ``Y``. ``act``: the
    terms the block runs (:func:`active_terms`), each in its own loop over the lanes."""
    for i in range(4):
        j = i + 1 if i % 2 == 0 else i - 1
        for l in range(nl):
            fill_context(P[:, l], DV[:, l], i, C[:, :, l], W[_W_D + i, l], W[_W_DD + i, l], W[_W_FX + i, l],
                         S[_FYT + i, l], W[_W_FZ + i, l], W[_W_V, l])
        terms_force_lanes(P, S, C, W, _W_FT + i, i, nl, act)
        for l in range(nl):
            p = P[:, l]
            dv = DV[:, l]
            d = W[_W_D + i, l]
            dd = W[_W_DD + i, l]
            f_spring = spring_force(p, dv, i, d)
            if SEMI_ACTIVE_CODE and p[P_SEMI_ACTIVE] > 0.5:
                # first-order valve lag, exact over the step; the force uses the setting at the step's end
                valve = S[_VALVE + i, l] + dv[_D_VALVE_ALPHA] * (W[_W_CMD + i, l] - S[_VALVE + i, l])
                S[_VALVE + i, l] = valve
                f_damper = semi_active_force(p, dv, i, dd, grid_cell(p, dd), valve)
            else:
                f_damper = hydraulic_force(p, dv, i, dd, grid_cell(p, dd))
            f_terms = W[_W_FT + i, l]
            f_arb = P[_K_ARB + i, l] * (d - W[_W_D + j, l])
            W[_W_FS + i, l] = f_spring + f_damper + f_terms + f_arb
            if out:
                Y[_Y_F_SPRING + i, l] = f_spring
                Y[_Y_F_DAMPER + i, l] = f_damper
                Y[_Y_F_FRICTION + i, l] = f_terms
                Y[_Y_F_ARB + i, l] = f_arb


@njit(cache=True, inline="always")
def body_accelerations(P, DV, S, W, nl):
    """The right-hand side of the equations of motion (model-spec 2): from the state ``S``, the inputs
    (``_W_V``, ``_W_AX``), the suspension forces ``_W_FS`` and the net vertical tyre forces ``_W_WF``,
    the accelerations of heave [m/s^2] (``_W_ZDD``), roll and pitch [rad/s^2] (``_W_PHIDD``,
    ``_W_THDD``), lateral acceleration [m/s^2] (``_W_AY``) and lateral velocity rate [m/s^2]
    (``_W_VYD``), yaw [rad/s^2] (``_W_RD``) and of the four wheels [m/s^2] (``_W_ZWDD``). Pure: it
    changes nothing but those scratch rows."""
    for l in range(nl):
        v = W[_W_V, l]
        ax = W[_W_AX, l]
        g = P[_G, l]
        ms = P[_M_S, l]
        fs0 = W[_W_FS, l]
        fs1 = W[_W_FS + 1, l]
        fs2 = W[_W_FS + 2, l]
        fs3 = W[_W_FS + 3, l]
        fy0 = S[_FYT, l]
        fy1 = S[_FYT + 1, l]
        fy2 = S[_FYT + 2, l]
        fy3 = S[_FYT + 3, l]
        phi = S[_PHI, l]
        th = S[_THETA, l]
        r = S[_R, l]
        # body: heave, roll, pitch
        zdd = ((fs0 + fs1) + (fs2 + fs3)) * DV[_D_INV_MS, l]
        ay = ((fy0 + fy1) + (fy2 + fy3)) * DV[_D_INV_M, l]
        roll_moment = ((P[_Y_I, l] * fs0 + P[_Y_I + 1, l] * fs1)
                       + (P[_Y_I + 2, l] * fs2 + P[_Y_I + 3, l] * fs3))
        pitch_moment = -((P[_X_I, l] * fs0 + P[_X_I + 1, l] * fs1)
                         + (P[_X_I + 2, l] * fs2 + P[_X_I + 3, l] * fs3))
        phidd = (roll_moment + ms * (P[_H_CG, l] - P[_H_RC, l]) * (ay + g * phi)) * DV[_D_INV_IXX, l]
        thdd = (pitch_moment + ms * (P[_H_CG, l] - P[_H_PC, l]) * (g * th - ax)) * DV[_D_INV_IYY, l]
        W[_W_ZDD, l] = zdd
        W[_W_AY, l] = ay
        W[_W_PHIDD, l] = phidd
        W[_W_THDD, l] = thdd
        # planar: lateral and yaw
        W[_W_VYD, l] = ay - v * r
        W[_W_RD, l] = (P[_A, l] * (fy0 + fy1) - P[_B, l] * (fy2 + fy3)) * DV[_D_INV_IZZ, l]
    # wheels: tyre force (from static) against the suspension force
    for i in range(4):
        for l in range(nl):
            W[_W_ZWDD + i, l] = (W[_W_WF + i, l] - W[_W_FS + i, l]) * DV[_D_INV_MU + i, l]


@njit(cache=True, inline="always")
def integrate(P, DV, S, W, dt, nl):
    """Advance the state by ``dt`` [s] with the accelerations of :func:`body_accelerations`: semi-implicit
    (symplectic) Euler for body, planar motion and wheels (velocities first, positions with the new
    velocities), the tyre lateral forces by the exact solution of their first-order relaxation toward the
    steady tanh characteristic, and the road height under each wheel remembered for the next step."""
    for l in range(nl):
        zd = S[_ZD, l] + W[_W_ZDD, l] * dt
        phid = S[_PHID, l] + W[_W_PHIDD, l] * dt
        thd = S[_THETAD, l] + W[_W_THDD, l] * dt
        r = S[_R, l] + W[_W_RD, l] * dt
        S[_ZD, l] = zd
        S[_PHID, l] = phid
        S[_THETAD, l] = thd
        S[_Z, l] += zd * dt
        S[_PHI, l] += phid * dt
        S[_THETA, l] += thd * dt
        S[_VY, l] += W[_W_VYD, l] * dt
        S[_R, l] = r
        S[_PSI, l] += r * dt
        S[_SPATH, l] += W[_W_V, l] * dt
    for l in range(nl):  # planar position (libm sin/cos: per vehicle)
        psi = S[_PSI, l]
        v = W[_W_V, l]
        vy = S[_VY, l]
        cpsi = math.cos(psi)
        spsi = math.sin(psi)
        S[_X, l] += (v * cpsi - vy * spsi) * dt
        S[_Y, l] += (v * spsi + vy * cpsi) * dt

    # tyre lateral forces: steady tanh characteristic, first-order relaxation (exact)
    for l in range(nl):
        vfade = P[_V_FADE, l]
        av = abs(W[_W_V, l])
        fade = av * DV[_D_INV_FADE, l] if av < vfade else 1.0
        vden = av if av > vfade else vfade
        relax = -expm1_nonpos(-av * dt * DV[_D_INV_RELAX, l])
        vy = S[_VY, l]
        r = S[_R, l]
        alpha_f = (W[_W_DELTA, l] - (vy + P[_A, l] * r) / vden) * fade
        alpha_r = (-(vy - P[_B, l] * r) / vden) * fade
        mu = P[_MU, l]
        for i in range(4):
            alpha = alpha_f if i < 2 else alpha_r
            fz = W[_W_FZ + i, l]
            mfz = mu * fz
            fss = mfz * tanh(P[_C_ALPHA + i, l] * alpha / max(mfz, TINY))
            fss = fss if fz > 0.0 else 0.0
            S[_FYT + i, l] += relax * (fss - S[_FYT + i, l])

    for i in range(4):
        for l in range(nl):
            zwd_i = S[_ZWD + i, l] + W[_W_ZWDD + i, l] * dt
            S[_ZWD + i, l] = zwd_i
            S[_ZW + i, l] += zwd_i * dt
            S[_ZR_PREV + i, l] = W[_W_ZR + i, l]


@njit(cache=True, inline="always")
def _deflection(P, S, i, l):
    """Suspension deflection [m] of corner ``i`` of lane ``l`` in state ``S``."""
    return S[_ZW + i, l] - (S[_Z, l] - P[_X_I + i, l] * S[_THETA, l] + P[_Y_I + i, l] * S[_PHI, l])


@njit(cache=True, inline="always")
def update_term_states(P, S, C, W, nl, act):
    """The physics terms' own states (e.g. Dahl elements) over the deflection increment of the step:
    from the deflection at its start (``_W_D``) to the one of the integrated state."""
    for i in range(4):
        for l in range(nl):
            W[_W_DX + i, l] = _deflection(P, S, i, l) - W[_W_D + i, l]
        terms_update_lanes(P, S, C, W, _W_DX + i, i, nl, act)


@njit(cache=True, inline="always")
def state_is_finite(S, W, nl):
    """Health check: ``W[_W_OK, l]`` becomes 0 when lane ``l``'s state stopped being finite."""
    for l in range(nl):
        ok = math.isfinite(S[_ZW, l] + S[_ZW + 1, l] + S[_ZW + 2, l] + S[_ZW + 3, l]
                           + S[_Z, l] + S[_PHI, l] + S[_THETA, l] + S[_VY, l] + S[_R, l]
                           + S[_ZD, l] + S[_PHID, l] + S[_THETAD, l])
        W[_W_OK, l] = 1.0 if ok else 0.0


@njit(cache=True, inline="always")
def corner_outputs(P, S, C, W, Y, nl):
    """Per-corner outputs after the step: deflection [m] and its rate [m/s], tyre forces [N] and the road
    height [m] (the suspension force components are written by :func:`suspension_forces`)."""
    for i in range(4):
        for l in range(nl):
            Y[_Y_DEFL + i, l] = _deflection(P, S, i, l)
            Y[_Y_DEFL_VEL + i, l] = S[_ZWD + i, l] - (S[_ZD, l] - P[_X_I + i, l] * S[_THETAD, l]
                                                      + P[_Y_I + i, l] * S[_PHID, l])
            Y[_Y_F_Z + i, l] = W[_W_FZ + i, l]
            Y[_Y_F_X + i, l] = W[_W_FX + i, l]
            Y[_Y_F_Y + i, l] = C[i, _C_FY, l]
            Y[_Y_Z_ROAD + i, l] = W[_W_ZR + i, l]


@njit(cache=True, inline="always")
def imu_outputs(P, S, W, Y, nl):
    """IMU at the centre of gravity (angular rates [rad/s], specific force incl. gravity [m/s^2],
    REP-145) and the pose, velocity, heave and path coordinate after the step."""
    for l in range(nl):
        g = P[_G, l]
        vy = S[_VY, l]
        r = S[_R, l]
        Y[_Y_ROLL_RATE, l] = S[_PHID, l]
        Y[_Y_PITCH_RATE, l] = S[_THETAD, l]
        Y[_Y_YAW_RATE, l] = r
        Y[_Y_AX, l] = W[_W_AX, l] - vy * r - g * S[_THETA, l]
        Y[_Y_AY, l] = W[_W_AY, l] + g * S[_PHI, l]
        Y[_Y_AZ, l] = g + W[_W_ZDD, l]
        Y[_Y_ROLL, l] = S[_PHI, l]
        Y[_Y_PITCH, l] = S[_THETA, l]
        Y[_Y_YAW, l] = S[_PSI, l]
        Y[_Y_PX, l] = S[_X, l]
        Y[_Y_PY, l] = S[_Y, l]
        Y[_Y_VX, l] = W[_W_V, l]
        Y[_Y_VY, l] = vy
        Y[_Y_HEAVE, l] = S[_Z, l]
        Y[_Y_PATH, l] = S[_SPATH, l]


@njit(cache=True, inline="always")
def step(P, DV, S, U, urow, k, RS, RZL, RZR, RN, rrow, mode, dt, C, W, Y, nl, out, act):
    """Advance the ``nl`` vehicles of a block by one step ``dt`` [s] with the inputs of row ``k`` of
    ``U[urow[l]]`` (layout.U_INDEX); writes outputs ``Y`` when ``out`` (skipped on steps whose outputs
    nobody reads).

    Vehicles are lanes: column ``l`` of ``P`` (parameters), ``DV`` (their reciprocals, :func:`derive`),
    ``S`` (state, updated in place), ``C`` (corner context, 4 x N_CTX per lane, constant part set by
    :func:`fill_context_const`), ``W`` (scratch) and ``Y`` (outputs). Every loop over lanes does the same
    arithmetic for each vehicle, so the compiler runs it on several vehicles per SIMD instruction; a
    single vehicle is a block of one. Road: tracks ``RS``/``RZL``/``RZR`` row ``rrow[l]`` with ``RN``
    valid samples (``mode`` 0), or per-wheel road heights from the inputs (``mode`` 1). ``W[_W_OK, l]``
    becomes 0 when lane ``l``'s state stopped being finite. ``act``: the physics terms the block runs
    (:func:`active_terms`).
    """
    road_under_wheels(P, DV, S, U, urow, k, RS, RZL, RZR, RN, rrow, mode, dt, W, nl)
    corner_kinematics(P, DV, S, W, nl)
    suspension_forces(P, DV, S, C, W, Y, nl, out, act)
    body_accelerations(P, DV, S, W, nl)
    integrate(P, DV, S, W, dt, nl)
    update_term_states(P, S, C, W, nl, act)
    state_is_finite(S, W, nl)
    if out:
        corner_outputs(P, S, C, W, Y, nl)
        imu_outputs(P, S, W, Y, nl)


@njit(cache=True, inline="always")
def _store_state(Sv, b, S, l):
    """Copy lane ``l`` of the block's state back to row ``b`` of the caller's states."""
    for q in range(N_S):
        Sv[b, q] = S[q, l]


@njit(cache=True, _nrt=False, error_model="numpy", fastmath={"arcp", "nsz"})  # type: ignore[call-overload]  # _nrt: a numba option its stubs do not declare
def _run_block(Pv, Sv, b0, nl, U, u_row, RS, RZL, RZR, RN, road_row, mode, dt, decim, sel, Yv, done):
    # compiled without the reference-counting runtime: with it, every array argument of the inlined
    # helpers costs an atomic incref/decref pair per step. The block's parameters, state, context,
    # scratch and outputs are copied into arrays on this function's stack (vehicle = column): the
    # compiler then knows that they overlap nothing else, keeps values in registers and vectorises
    # the loops over vehicles.
    P = _stack_p()
    DV = _stack_dv()
    S = _stack_s()
    C = _stack_c()
    W = _stack_w()
    Y = _stack_y()
    urow = _stack_i()
    rrow = _stack_i()
    mrow = _stack_i()
    for l in range(nl):
        b = b0 + l
        for q in range(N_P):
            P[q, l] = Pv[b, q]
        for q in range(N_S):
            S[q, l] = Sv[b, q]
        for q in range(N_SCRATCH):
            W[q, l] = 0.0
        for q in range(N_Y):
            Y[q, l] = 0.0
        for i in range(4):
            for q in range(N_CTX):
                C[i, q, l] = 0.0
            fill_context_const(P[:, l], i, C[:, :, l], dt)
        derive(P[:, l], DV[:, l])
        DV[_D_VALVE_ALPHA, l] = -expm1_nonpos(-dt / max(P[P_VALVE_TAU, l], TINY))
        urow[l] = u_row[b]
        rrow[l] = road_row[b]
        mrow[l] = mode[b]
        done[b] = U.shape[1]
    # the terms this block runs: a term at zero gain in every lane is skipped (its force is zero then);
    # most runs of a diagnosis carry most candidate terms at zero
    act = active_terms(P, nl)
    n_sel = sel.shape[0]
    row = 0
    count = 0
    alive = nl
    for k in range(U.shape[1]):
        count += 1
        out = count == decim
        step(P, DV, S, U, urow, k, RS, RZL, RZR, RN, rrow, mrow, dt, C, W, Y, nl, out, act)
        if out:
            count = 0
            if row < Yv.shape[1]:
                for l in range(nl):
                    if done[b0 + l] > k:
                        for j in range(n_sel):
                            Yv[b0 + l, row, j] = Y[sel[j], l]
                row += 1
        for l in range(nl):
            if W[_W_OK, l] == 0.0 and done[b0 + l] > k + 1:
                # this vehicle's state stopped being finite: it stops here, its state as after the step
                done[b0 + l] = k + 1
                _store_state(Sv, b0 + l, S, l)
                alive -= 1
        if alive == 0:
            break
    for l in range(nl):
        if done[b0 + l] == U.shape[1]:
            _store_state(Sv, b0 + l, S, l)


@njit(cache=True)
def run_one(p, s, U, rs, rzl, rzr, rn, mode, dt, decim, sel, Y):
    """Step one vehicle over every row of ``U`` (n_steps x N_U); every ``decim``-th step's outputs
    ``y[sel]`` go to the next row of ``Y``. Returns the number of steps done (< n_steps when the state
    became non-finite: the run stops there and the state is left as it was after the bad step).
    The vehicle runs as a block of one through the same :func:`step` as a batch."""
    zero = np.zeros(1, np.int64)
    done = np.zeros(1, np.int64)
    _run_block(p.reshape((1, p.shape[0])), s.reshape((1, s.shape[0])), 0, 1, U.reshape((1,) + U.shape),
               zero, rs.reshape((1, rs.shape[0])), rzl.reshape((1, rzl.shape[0])),
               rzr.reshape((1, rzr.shape[0])), np.full(1, rn, np.int64), zero, np.full(1, mode, np.int64),
               dt, decim, sel, Y.reshape((1,) + Y.shape), done)
    return done[0]


@njit(cache=True, parallel=True, nogil=True)
def run_batch(P, S, U, u_row, RS, RZL, RZR, RN, road_row, mode, dt, decim, sel, Y, done, block):
    """Run vehicles ``b`` in parallel, in blocks of ``block`` (at most :data:`LANES`): parameters
    ``P[b]``, state ``S[b]`` (in place), inputs ``U[u_row[b]]``, road ``road_row[b]``, outputs to
    ``Y[b]``, steps done to ``done[b]``."""
    n_blocks = (P.shape[0] + block - 1) // block
    for blk in prange(n_blocks):
        b0 = blk * block
        _run_block(P, S, b0, min(block, P.shape[0] - b0), U, u_row, RS, RZL, RZR, RN, road_row, mode, dt,
                   decim, sel, Y, done)


@njit(cache=True)
def rig_run(p, s, i, d, dd, fx, fy, fz, mask, with_spring, out):
    """Virtual rig: prescribe deflection ``d`` [m] and its rate ``dd`` [m/s] at corner ``i`` with the
    body held, quasi-static wheel forces ``fx``, ``fy``, ``fz`` [N]; ``out`` gets the suspension force
    [N] (spring if ``with_spring``, hydraulic damper, and the terms selected by ``mask``)."""
    c = np.zeros((4, N_CTX))
    dv = np.zeros(N_DERIVED)
    derive(p, dv)
    fill_context_const(p, i, c, 0.0)
    for k in range(d.shape[0]):
        fill_context(p, dv, i, c, d[k], dd[k], fx, fy, fz, 0.0)
        f = hydraulic_force(p, dv, i, dd[k], grid_cell(p, dd[k])) + terms_force(p, s, i, c, mask)
        if with_spring:
            f += spring_force(p, dv, i, d[k])
        out[k] = f
        if k + 1 < d.shape[0]:
            terms_update(p, s, i, c, d[k + 1] - d[k], mask)


#: scratch rows of :func:`body_accelerations` holding the vertical accelerations ``q''`` (heave, roll,
#: pitch [m/s^2, rad/s^2], then the four wheels [m/s^2]), the coordinates of ``model/linear.py``
VERTICAL_ACCELERATION_ROWS = np.array([_W_ZDD, _W_PHIDD, _W_THDD, _W_ZWDD, _W_ZWDD + 1, _W_ZWDD + 2, _W_ZWDD + 3])


def accelerations(P, S):
    """The pure right-hand side of a block of vehicles (parameters ``P`` (n_p, nl), states ``S`` (n_s,
    nl), one vehicle per column) standing on a flat road, without physics terms: the stages
    :func:`corner_kinematics`, :func:`suspension_forces` and :func:`body_accelerations` as the step runs
    them. Returns ``q''`` (7, nl) in the rows :data:`VERTICAL_ACCELERATION_ROWS` describe. The public way
    to evaluate the model's forces and accelerations outside a step (``model/linear.py`` linearises it);
    it reads and writes nothing of its arguments."""
    S = np.ascontiguousarray(S, dtype=np.float64).copy()
    nl = S.shape[1]
    DV = np.zeros((N_DERIVED, nl))
    C = np.zeros((4, N_CTX, nl))
    W = np.zeros((N_SCRATCH, nl))
    Y = np.zeros((N_Y, nl))
    for v in range(nl):
        derive(P[:, v], DV[:, v])
        for i in range(4):
            fill_context_const(P[:, v], i, C[:, :, v], 0.0)
    corner_kinematics(P, DV, S, W, nl)
    suspension_forces(P, DV, S, C, W, Y, nl, False, active_terms(P, nl))
    body_accelerations(P, DV, S, W, nl)
    return W[VERTICAL_ACCELERATION_ROWS, :].copy()
