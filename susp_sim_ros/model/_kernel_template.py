"""Compiled five-mass vehicle kernel (template; see :mod:`susp_sim_ros.model.kernel`).

This file is the source of the generated kernel modules: :mod:`.kernel` replaces the block between the
TERMS markers with calls to the configured physics terms and imports the result. It is also importable
as it is (no terms), which keeps it linted and testable.

Equations: model-spec section 2 (heave, roll, pitch, lateral, yaw of the body; four wheels), forces
measured from static equilibrium, small angles, SI units, REP-103 axes. Integration: semi-implicit
(symplectic) Euler at a fixed step; Dahl elements and tyre relaxation use their exact solutions over the
step, which keeps them stable at any step (model-spec 1).

One stepping function, :func:`step`, serves everything: :func:`run_one` loops it over time for one
vehicle (the node calls this every publish period with the few steps due; offline runs call it once for
a whole drive) and :func:`run_batch` runs many vehicles in parallel with ``prange``.
"""
import math

import numpy as np
from numba import njit, prange, types
from numba.core import cgutils
from numba.extending import intrinsic

from susp_sim_ros.model.layout import (C_INDEX, N_CTX, N_GRID, N_Y, P_GRID, P_H_EMPTY, P_H_INTACT,
                                       P_INDEX, S_INDEX, U_INDEX, Y_INDEX)

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

_U_V, _U_AX, _U_SWA, _U_ZR = U_INDEX["V"], U_INDEX["AX"], U_INDEX["SWA"], U_INDEX["ZR_IN"]

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

# scratch slots per corner (w[k*4 + i])
_W_ZR, _W_ZRD, _W_SLOPE, _W_D, _W_DD, _W_FZ, _W_WF, _W_FX, _W_FS, _W_CELL = 0, 4, 8, 12, 16, 20, 24, 28, 32, 36
_W_VLAST, _W_RELAX = 40, 41
N_SCRATCH = 42

# reciprocals of constant parameters, computed once per run (:func:`derive`): the step then
# multiplies instead of dividing, and a parameter changed between runs is always seen
_D_INV_MS, _D_INV_M, _D_INV_IXX, _D_INV_IYY, _D_INV_IZZ, _D_INV_RATIO = 0, 1, 2, 3, 4, 5
_D_INV_EP, _D_INV_VS, _D_INV_RELAX, _D_INV_FADE = 6, 7, 8, 9
_D_INV_MU, _D_DFZ = 10, 14  # 4 each
_D_INV_CELL = 18  # N_GRID - 1 inverse grid cell widths
N_DERIVED = _D_INV_CELL + N_GRID - 1


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


def _stack_array(shape):
    """An intrinsic returning a C-contiguous float64 array of ``shape`` on the stack of the calling
    function (no allocation, no reference counting; valid while that function runs)."""
    arrty = types.Array(types.float64, len(shape), "C")
    n = int(np.prod(shape))
    strides = [8 * int(np.prod(shape[k + 1:])) for k in range(len(shape))]

    @intrinsic
    def stack(typingctx):
        def codegen(context, builder, sig, args):
            intp = lambda v: context.get_constant(types.intp, v)  # noqa: E731
            ptr = cgutils.alloca_once(builder, context.get_value_type(types.float64), size=intp(n))
            ary = context.make_array(arrty)(context, builder)
            context.populate_array(ary, data=ptr, shape=[intp(d) for d in shape],
                                   strides=[intp(st) for st in strides], itemsize=intp(8), meminfo=None)
            return ary._getvalue()
        return arrty(), codegen
    return stack


_stack_c, _stack_w, _stack_y = _stack_array((4, N_CTX)), _stack_array((N_SCRATCH,)), _stack_array((N_Y,))


# @@BEGIN TERMS@@
@njit(cache=True)
def terms_force(p, s, i, c, mask):
    return 0.0


@njit(cache=True)
def terms_update(p, s, i, c, dx, mask):
    pass
# @@END TERMS@@


@njit(cache=True, inline="always")
def _grid_cell(p, x, k):
    """Cell k of the velocity grid holding x (linear extrapolation cells at the ends), found by
    walking from the previous cell ``k``: velocities change little per step, so this is O(1)."""
    if k < 0 or k > N_GRID - 2:
        k = N_GRID // 2
    while k > 0 and x < p[P_GRID + k]:
        k -= 1
    while k < N_GRID - 2 and x >= p[P_GRID + k + 1]:
        k += 1
    return k


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
    f = p[_K_S + i] * d
    e = d - p[_STOP_BUMP + i]
    if e > 0.0:
        f += p[_K_STOP] * e * (1.0 + e * dv[_D_INV_EP])
    e = -d - p[_STOP_REB + i]
    if e > 0.0:
        f -= p[_K_STOP] * e * (1.0 + e * dv[_D_INV_EP])
    return f


@njit(cache=True, inline="always")
def hydraulic_force(p, dv, i, dd, k):
    """Hydraulic damper force [N] at deflection velocity dd [m/s], blended by the corner's oil level;
    ``k`` is the grid cell of dd (:func:`_grid_cell`)."""
    oil = p[_OIL + i]
    f = 0.0
    if oil > 0.0:
        f += oil * _interp_cell(p, dv, P_H_INTACT + i * N_GRID, dd, k)
    if oil < 1.0:
        f += (1.0 - oil) * _interp_cell(p, dv, P_H_EMPTY + i * N_GRID, dd, k)
    return f


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
    sv = 1.0
    if p[_USE_V] > 0.5 and abs(dd) > p[_SV_REF]:
        sv = 1.0 + (p[_SV_INF] - 1.0) * (1.0 - math.exp(-(abs(dd) - p[_SV_REF]) * dv[_D_INV_VS]))
    c[i, _C_SV] = sv
    sh = 1.0
    if p[_USE_H] > 0.5:
        sh = 1.0 + p[_SH_X + i] * abs(fx) + p[_SH_Y + i] * abs(fy)
    c[i, _C_SH] = sh


@njit(cache=True, inline="always")
def step(p, dv, s, U, k, rs, rzl, rzr, rn, mode, dt, c, w, y, out):
    """Advance one vehicle by one step ``dt`` [s] with the inputs of row ``k`` of ``U``
    (layout.U_INDEX); writes outputs ``y`` when ``out`` (skipped on steps whose outputs nobody reads).

    ``p`` parameters (``dv`` their reciprocals, :func:`derive`), ``s`` state (updated in place), road tracks ``rs``/``rzl``/``rzr`` with ``rn``
    valid samples (``mode`` 0), or per-wheel road heights from ``U`` (``mode`` 1). Rows of 2-D
    arrays are indexed, never sliced: a slice is a new array object with reference counting. ``c`` (4 x N_CTX,
    constant part set by :func:`fill_context_const`) and ``w`` are scratch. Returns False when the state
    stopped being finite.
    """
    g = p[_G]
    ms = p[_M_S]
    m = p[_M_TOT]
    a = p[_A]
    b = p[_B]
    v = U[k, _U_V]
    ax = U[k, _U_AX]
    delta = U[k, _U_SWA] * dv[_D_INV_RATIO]
    z = s[_Z]
    phi = s[_PHI]
    th = s[_THETA]
    zd = s[_ZD]
    phid = s[_PHID]
    thd = s[_THETAD]
    vy = s[_VY]
    r = s[_R]
    kt = p[_KT]
    ct = p[_CT]

    # -- road under each wheel --------------------------------------------------------------------
    for i in range(4):
        if mode == 1:
            zr = U[k, _U_ZR + i]
            zrd = (zr - s[_ZR_PREV + i]) / dt
            slope = zrd / v if v > p[_V_FADE] else 0.0
        else:
            si = s[_SPATH] if i < 2 else s[_SPATH] - (a + b)
            if i % 2 == 0:
                zr, slope = road_at(rs, rzl, rn, si)
            else:
                zr, slope = road_at(rs, rzr, rn, si)
            zrd = v * slope
        w[_W_ZR + i] = zr
        w[_W_ZRD + i] = zrd
        w[_W_SLOPE + i] = slope

    # -- corner kinematics, tyre loads and horizontal wheel forces ----------------------------------
    fyf = s[_FYT] + s[_FYT + 1]
    fyr = s[_FYT + 2] + s[_FYT + 3]
    share_f = p[_DRIVE_FRONT] if ax >= 0.0 else p[_BRAKE_FRONT]
    for i in range(4):
        xi = p[_X_I + i]
        yi = p[_Y_I + i]
        w[_W_D + i] = s[_ZW + i] - (z - xi * th + yi * phi)
        w[_W_DD + i] = s[_ZWD + i] - (zd - xi * thd + yi * phid)
        ft = kt * (w[_W_ZR + i] - s[_ZW + i]) + ct * (w[_W_ZRD + i] - s[_ZWD + i])
        # geometric load transfer of the axle's lateral force through its roll centre: wheels only
        dfz = (fyf if i < 2 else fyr) * dv[_D_DFZ + i]
        if i % 2 == 0:
            dfz = -dfz
        fz = p[_FZ0 + i] + ft + dfz
        if fz < 0.0:
            fz = 0.0  # lift-off: the tyre cannot pull
        w[_W_FZ + i] = fz
        w[_W_WF + i] = fz - p[_FZ0 + i] - dfz
        fx_drive = m * ax * (share_f if i < 2 else 1.0 - share_f) * 0.5
        w[_W_FX + i] = fx_drive - fz * w[_W_SLOPE + i]  # bump reaction while climbing/leaving

    # -- suspension forces ---------------------------------------------------------------------------
    for i in range(4):
        fill_context(p, dv, i, c, w[_W_D + i], w[_W_DD + i], w[_W_FX + i], s[_FYT + i], w[_W_FZ + i], v)
        f_spring = spring_force(p, dv, i, w[_W_D + i])
        cell = _grid_cell(p, w[_W_DD + i], int(w[_W_CELL + i]))
        w[_W_CELL + i] = cell
        f_damper = hydraulic_force(p, dv, i, w[_W_DD + i], cell)
        f_terms = terms_force(p, s, i, c, MASK_ALL)
        j = i + 1 if i % 2 == 0 else i - 1
        f_arb = p[_K_ARB + i] * (w[_W_D + i] - w[_W_D + j])
        w[_W_FS + i] = f_spring + f_damper + f_terms + f_arb
        if out:
            y[_Y_F_SPRING + i] = f_spring
            y[_Y_F_DAMPER + i] = f_damper
            y[_Y_F_FRICTION + i] = f_terms
            y[_Y_F_ARB + i] = f_arb

    # -- equations of motion ------------------------------------------------------------------------
    fs0 = w[_W_FS]
    fs1 = w[_W_FS + 1]
    fs2 = w[_W_FS + 2]
    fs3 = w[_W_FS + 3]
    fy0 = s[_FYT]
    fy1 = s[_FYT + 1]
    fy2 = s[_FYT + 2]
    fy3 = s[_FYT + 3]
    # body: heave, roll, pitch
    zdd = ((fs0 + fs1) + (fs2 + fs3)) * dv[_D_INV_MS]
    ay = ((fy0 + fy1) + (fy2 + fy3)) * dv[_D_INV_M]
    roll_moment = (p[_Y_I] * fs0 + p[_Y_I + 1] * fs1) + (p[_Y_I + 2] * fs2 + p[_Y_I + 3] * fs3)
    pitch_moment = -((p[_X_I] * fs0 + p[_X_I + 1] * fs1) + (p[_X_I + 2] * fs2 + p[_X_I + 3] * fs3))
    phidd = (roll_moment + ms * (p[_H_CG] - p[_H_RC]) * (ay + g * phi)) * dv[_D_INV_IXX]
    thdd = (pitch_moment + ms * (p[_H_CG] - p[_H_PC]) * (g * th - ax)) * dv[_D_INV_IYY]
    # planar: lateral and yaw
    vyd = ay - v * r
    rd = (a * (fy0 + fy1) - b * (fy2 + fy3)) * dv[_D_INV_IZZ]

    # -- semi-implicit Euler ------------------------------------------------------------------------
    zd += zdd * dt
    phid += phidd * dt
    thd += thdd * dt
    z += zd * dt
    phi += phid * dt
    th += thd * dt
    vy += vyd * dt
    r += rd * dt
    psi = s[_PSI] + r * dt
    cpsi = math.cos(psi)
    spsi = math.sin(psi)
    s[_X] += (v * cpsi - vy * spsi) * dt
    s[_Y] += (v * spsi + vy * cpsi) * dt
    s[_PSI] = psi
    s[_SPATH] += v * dt
    s[_Z] = z
    s[_PHI] = phi
    s[_THETA] = th
    s[_ZD] = zd
    s[_PHID] = phid
    s[_THETAD] = thd
    s[_VY] = vy
    s[_R] = r

    # -- tyre lateral forces: steady tanh characteristic, first-order relaxation (exact) -------------
    vfade = p[_V_FADE]
    av = abs(v)
    fade = av * dv[_D_INV_FADE] if av < vfade else 1.0
    vden = av if av > vfade else vfade
    if av != w[_W_VLAST]:  # constant speed is common: keep the relaxation factor
        w[_W_VLAST] = av
        w[_W_RELAX] = -math.expm1(-av * dt * dv[_D_INV_RELAX])
    relax = w[_W_RELAX]
    alpha_f = (delta - (s[_VY] + a * s[_R]) / vden) * fade
    alpha_r = (-(s[_VY] - b * s[_R]) / vden) * fade
    mu = p[_MU]
    for i in range(4):
        alpha = alpha_f if i < 2 else alpha_r
        fz = w[_W_FZ + i]
        fss = 0.0
        if fz > 0.0:
            fss = mu * fz * math.tanh(p[_C_ALPHA + i] * alpha / (mu * fz))
        s[_FYT + i] += relax * (fss - s[_FYT + i])

    # -- wheels, then the terms' state over the deflection increment of the step --------------------
    ok = True
    for i in range(4):
        zwd_i = s[_ZWD + i] + (w[_W_WF + i] - w[_W_FS + i]) * dv[_D_INV_MU + i] * dt
        zw_i = s[_ZW + i] + zwd_i * dt
        s[_ZWD + i] = zwd_i
        s[_ZW + i] = zw_i
        d_new = zw_i - (z - p[_X_I + i] * th + p[_Y_I + i] * phi)
        terms_update(p, s, i, c, d_new - w[_W_D + i], MASK_ALL)
        s[_ZR_PREV + i] = w[_W_ZR + i]
        if out:
            y[_Y_DEFL + i] = d_new
            y[_Y_DEFL_VEL + i] = zwd_i - (zd - p[_X_I + i] * thd + p[_Y_I + i] * phid)
            y[_Y_F_Z + i] = w[_W_FZ + i]
            y[_Y_F_X + i] = w[_W_FX + i]
            y[_Y_F_Y + i] = fy0 if i == 0 else (fy1 if i == 1 else (fy2 if i == 2 else fy3))
            y[_Y_Z_ROAD + i] = w[_W_ZR + i]
        if not math.isfinite(zw_i):
            ok = False

    ok = ok and math.isfinite(z + phi + th + vy + r + zd + phid + thd)
    if not out:
        return ok
    # -- outputs: IMU at the centre of gravity (specific force incl. gravity, REP-145), pose --------
    y[_Y_ROLL_RATE] = phid
    y[_Y_PITCH_RATE] = thd
    y[_Y_YAW_RATE] = r
    y[_Y_AX] = ax - vy * r - g * th
    y[_Y_AY] = ay + g * phi
    y[_Y_AZ] = g + zdd
    y[_Y_ROLL] = phi
    y[_Y_PITCH] = th
    y[_Y_YAW] = psi
    y[_Y_PX] = s[_X]
    y[_Y_PY] = s[_Y]
    y[_Y_VX] = v
    y[_Y_VY] = vy
    y[_Y_HEAVE] = z
    y[_Y_PATH] = s[_SPATH]
    return ok


@njit(cache=True, _nrt=False, error_model="numpy", fastmath={"contract", "arcp", "nsz"})
def _run_steps(p, dv, s, U, rs, rzl, rzr, rn, mode, dt, decim, sel, Y):
    # compiled without the reference-counting runtime: with it, every array argument of the inlined
    # helpers costs an atomic incref/decref pair per step, which made up half of the step time.
    # Scratch, context and outputs live on this function's stack: the compiler then knows that they
    # overlap neither the parameters nor the state and keeps more of them in registers.
    c = _stack_c()
    w = _stack_w()
    y = _stack_y()
    for i in range(4):
        for j in range(N_CTX):
            c[i, j] = 0.0
    for j in range(N_SCRATCH):
        w[j] = 0.0
    w[_W_VLAST] = -1.0
    for j in range(N_Y):
        y[j] = 0.0
    n_sel = sel.shape[0]
    row = 0
    count = 0
    for i in range(4):
        fill_context_const(p, i, c, dt)
    for k in range(U.shape[0]):
        count += 1
        ok = step(p, dv, s, U, k, rs, rzl, rzr, rn, mode, dt, c, w, y, count == decim)
        if count == decim:
            count = 0
            if row < Y.shape[0]:
                for j in range(n_sel):
                    Y[row, j] = y[sel[j]]
                row += 1
        if not ok:
            return k + 1
    return U.shape[0]


@njit(cache=True)
def run_one(p, s, U, rs, rzl, rzr, rn, mode, dt, decim, sel, Y):
    """Step one vehicle over every row of ``U`` (n_steps x N_U); every ``decim``-th step's outputs
    ``y[sel]`` go to the next row of ``Y``. Returns the number of steps done (< n_steps when the state
    became non-finite: the run stops there and the state is left as it was after the bad step)."""
    dv = np.zeros(N_DERIVED)
    derive(p, dv)
    return _run_steps(p, dv, s, U, rs, rzl, rzr, rn, mode, dt, decim, sel, Y)


@njit(cache=True, parallel=True, nogil=True)
def run_batch(P, S, U, u_row, RS, RZL, RZR, RN, road_row, mode, dt, decim, sel, Y, done):
    """Run vehicles ``b`` in parallel: parameters ``P[b]``, state ``S[b]`` (in place), inputs
    ``U[u_row[b]]``, road ``road_row[b]``, outputs to ``Y[b]``, steps done to ``done[b]``."""
    for b in prange(P.shape[0]):
        rr = road_row[b]
        done[b] = run_one(P[b], S[b], U[u_row[b]], RS[rr], RZL[rr], RZR[rr], RN[rr], mode[b], dt,
                          decim, sel, Y[b])


@njit(cache=True)
def rig_run(p, s, i, d, dd, fx, fy, fz, mask, with_spring, out):
    """Virtual rig: prescribe deflection ``d`` [m] and its rate ``dd`` [m/s] at corner ``i`` with the
    body held, quasi-static wheel forces ``fx``, ``fy``, ``fz`` [N]; ``out`` gets the suspension force
    [N] (spring if ``with_spring``, hydraulic damper, and the terms selected by ``mask``)."""
    c = np.zeros((4, N_CTX))
    dv = np.zeros(N_DERIVED)
    derive(p, dv)
    cell = -1
    fill_context_const(p, i, c, 0.0)
    for k in range(d.shape[0]):
        fill_context(p, dv, i, c, d[k], dd[k], fx, fy, fz, 0.0)
        cell = _grid_cell(p, dd[k], cell)
        f = hydraulic_force(p, dv, i, dd[k], cell) + terms_force(p, s, i, c, mask)
        if with_spring:
            f += spring_force(p, dv, i, d[k])
        out[k] = f
        if k + 1 < d.shape[0]:
            terms_update(p, s, i, c, d[k + 1] - d[k], mask)
