"""The five-mass vehicle: parameter packing, offline runs, batch runs and the real-time stepper.

Everything here drives the same compiled :func:`step` (generated from ``_kernel_template.py``):

- :func:`simulate` runs one vehicle over a whole input series (offline, lockstep);
- :func:`simulate_batch` runs many parameter sets / drives at once on all cores;
- :class:`Stepper` advances one vehicle a few steps at a time with held inputs (the ROS node).

Units SI, axes REP-103, wheel order FL, FR, RL, RR.
"""
from __future__ import annotations

from collections.abc import Iterable, Sequence

from types import ModuleType

import numpy as np
from numba import get_num_threads

from ..errors import SuspInputError
from .friction_scaling import velocity_scaling_array
from .kernel import load_kernel
from .layout import (DAMPER_GRID, N_GRID, N_U, OUTPUT_LABELS, P_GRID, P_H_EMPTY, P_H_HARD,
                     P_H_INTACT, P_H_SOFT, P_INDEX, P_SEMI_ACTIVE, P_VALVE_TAU, S_INDEX, U_INDEX,
                     KernelLayout)
from .params import CORNER_AXLE, FrictionVariant, VehicleParams, load_variant, load_vehicle
from .response import Response, selected_labels
from .road import RoadProfile
from .semiactive import load_damper_family
from .terms import AXLE_FRICTION, BUILTIN_TERMS, DAMPER_FRICTION, PhysicsTerm
from .params import DEFAULT_VEHICLE

INTACT = (1.0, 1.0, 1.0, 1.0)


def _extrap_interp(x: np.ndarray, xp: Sequence[float] | np.ndarray, fp: Sequence[float] | np.ndarray) -> np.ndarray:
    """Linear interpolation with linear extrapolation beyond both ends."""
    xp, fp = np.asarray(xp, float), np.asarray(fp, float)
    y = np.interp(x, xp, fp)
    lo, hi = x < xp[0], x > xp[-1]
    y[lo] = fp[0] + (x[lo] - xp[0]) * (fp[1] - fp[0]) / (xp[1] - xp[0])
    y[hi] = fp[-1] + (x[hi] - xp[-1]) * (fp[-1] - fp[-2]) / (xp[-1] - xp[-2])
    return y


def velocity_scaling(vp: VehicleParams, v_abs: np.ndarray) -> np.ndarray:
    """s_v(|v|) [-] of the damper friction (model-spec 1) at the damper velocities ``v_abs`` [m/s] (any
    shape; their magnitude counts): 1 up to the reference speed, rising to a plateau. The kernel's
    formula, :func:`~.friction_scaling.velocity_scaling_factor`."""
    v = np.asarray(v_abs, float)
    sv = velocity_scaling_array(np.ascontiguousarray(v.ravel()), float(vp.sv_reference), float(vp.sv_plateau),
                                1.0 / float(vp.sv_speed))
    return sv.reshape(v.shape)


def hydraulic_curves(vp: VehicleParams) -> tuple[np.ndarray, np.ndarray]:
    """Hydraulic damper curves (intact, oil-empty) per axle on :data:`DAMPER_GRID`, shape (2, N_GRID).

    The measured curves contain the damper's own velocity-dependent friction, so the full model's
    damper friction at that velocity is subtracted (model-spec 1; the paper does this). The result is
    zero for |v| <= the 1 mm/s reference speed and never changes sign against the velocity.
    """
    def flat(v):
        return tuple(flat(x) for x in v) if isinstance(v, (tuple, list, np.ndarray)) else float(v)
    key = flat((vp.damper_velocity, vp.damper_measured_intact, vp.damper_measured_empty, vp.damper_friction_intact,
                vp.damper_friction_empty, vp.sv_reference, vp.sv_plateau, vp.sv_speed))
    h = _HYDRAULIC.get(key)
    if h is None:
        if len(_HYDRAULIC) > 256:
            _HYDRAULIC.clear()
        h = _HYDRAULIC[key] = (
            hydraulic_from_measured(vp, vp.damper_velocity, vp.damper_measured_intact, vp.damper_friction_intact),
            hydraulic_from_measured(vp, vp.damper_velocity, vp.damper_measured_empty, vp.damper_friction_empty))
    return h[0].copy(), h[1].copy()


#: :func:`hydraulic_curves` by the vehicle values they are built from: a calibration builds the parameter
#: vector once per value tried, and most values tried leave the damper untouched
_HYDRAULIC: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}


def hydraulic_from_measured(vp: VehicleParams, velocity, measured, levels,
                            grid: np.ndarray | None = None) -> np.ndarray:
    """Hydraulic curves per axle, shape (2, len(grid)), from measured curves (front, rear) at ``velocity``
    [m/s] that contain the damper friction of ``levels`` [N] (front, rear), at the damper velocities
    ``grid`` [m/s] (default :data:`DAMPER_GRID`, the kernel's). The one construction of the hydraulic
    curve: the measured curve (linear between its points, extrapolated linearly) minus the full model's
    damper friction level x s_v(|v|), never against the velocity, zero within the reference speed."""
    g = DAMPER_GRID if grid is None else np.asarray(grid, float)
    sign = np.sign(g)
    fric_shape = velocity_scaling(vp, np.abs(g))
    rows = []
    for axle in range(2):
        f = _extrap_interp(g, velocity, measured[axle]) - sign * levels[axle] * fric_shape
        f = sign * np.maximum(sign * f, 0.0)
        f[np.abs(g) <= vp.sv_reference] = 0.0
        rows.append(f)
    return np.array(rows)


class Model:
    """A vehicle parameter set plus a friction variant, with its compiled kernel.

    ``Model("passat_b8_like", "dahl_only")``; names or YAML paths or loaded objects. ``dampers``: the
    semi-active damper family (:class:`~.semiactive.DamperFamily`, default ``config/semiactive.yaml``,
    loaded when first needed), used only by ``params(..., semi_active=True)``.
    """

    def __init__(self, vehicle: VehicleParams | str = DEFAULT_VEHICLE,
                 variant: FrictionVariant | str = "full", dampers=None):
        self._dampers = dampers
        self.vehicle = vehicle if isinstance(vehicle, VehicleParams) else load_vehicle(vehicle)
        self.variant = variant if isinstance(variant, FrictionVariant) else load_variant(variant)
        self.terms: tuple[PhysicsTerm, ...] = BUILTIN_TERMS + tuple(t.term for t in self.variant.terms)
        self.layout = KernelLayout.for_terms(self.terms)
        self.kernel = load_kernel(self.terms)
        self._kernel_passive: ModuleType | None = None

    @property
    def kernel_passive(self):
        """The kernel without the semi-active damper code, for batches of passive vehicles (the same
        numbers as :attr:`kernel` on them, faster: benchmarks/RESULTS.md, "Model speed")."""
        if self._kernel_passive is None:
            self._kernel_passive = load_kernel(self.terms, semi_active=False)
        return self._kernel_passive

    @property
    def dampers(self):
        """The semi-active damper family (loaded on first use)."""
        if self._dampers is None:
            self._dampers = load_damper_family()
        return self._dampers

    # -- parameters -------------------------------------------------------------------------------
    def params(self, oil: Sequence[float] | np.ndarray = INTACT, semi_active: bool = False) -> np.ndarray:
        """The flat parameter vector ``P`` for oil levels FL, FR, RL, RR (1 intact, 0 oil-empty).

        ``semi_active``: the damper follows the valve command input (``U[:, CMD]``, [0, 1] per corner)
        through the soft/hard curves of :attr:`dampers` and the valve lag; otherwise (default) the
        passive curve, and the semi-active block of ``P`` stays zero (the passive vector is unchanged)."""
        oil = check_oil(oil)
        P = np.zeros(self.layout.n_p)
        self._put_body(P)
        self._put_corners(P, oil)
        self._put_damper_curves(P)
        self._put_friction_terms(P)
        if semi_active:
            set_semi_active(self, P, True)
        return P

    def _put_body(self, P: np.ndarray) -> None:
        """The whole-car slots of ``P`` (SI units as the vehicle file gives them): gravity, masses and
        inertias, geometry, tyre and stop rates, drive and brake shares, the variant's scaling switches
        and the velocity scaling's constants."""
        vp, var = self.vehicle, self.variant
        for name, value in (
                ("G", vp.gravity), ("M_S", vp.sprung_mass), ("M_TOT", vp.total_mass),
                ("IXX", vp.roll_inertia), ("IYY", vp.pitch_inertia), ("IZZ", vp.yaw_inertia),
                ("A", vp.a), ("B", vp.b), ("H_CG", vp.cg_height),
                ("H_RC", 0.5 * sum(vp.roll_centre_height)), ("H_PC", vp.pitch_centre_height),
                ("STEER_RATIO", vp.steering_ratio), ("MU", vp.mu), ("RELAX_LEN", vp.relaxation_length),
                ("V_FADE", vp.slip_fade_speed), ("KT", vp.tyre_stiffness), ("CT", vp.tyre_damping),
                ("K_STOP", vp.stop_rate), ("STOP_EP", vp.stop_progression),
                ("DRIVE_FRONT", vp.drive_front_share), ("BRAKE_FRONT", vp.brake_front_share),
                ("USE_V", float(var.velocity_scaling)), ("USE_OIL", float(var.oil_scaling)),
                ("USE_H", float(var.horizontal_scaling)),
                ("SV_REF", vp.sv_reference), ("SV_INF", vp.sv_plateau), ("SV_VS", vp.sv_speed)):
            P[P_INDEX[name]] = value

    def _put_corners(self, P: np.ndarray, oil: np.ndarray) -> None:
        """The per-corner slots of ``P`` (FL, FR, RL, RR): wheel positions [m], per-axle values spread
        to their corners, static wheel loads [N], the oil levels ``oil`` [-] and the friction scalings'
        oil-empty ratio and horizontal-force coefficients."""
        vp = self.vehicle

        def corners(name, pair):
            k = P_INDEX[name]
            P[k:k + 4] = [pair[a] for a in CORNER_AXLE]

        P[P_INDEX["X_I"]:P_INDEX["X_I"] + 4] = [vp.a, vp.a, -vp.b, -vp.b]
        tf, tr = vp.track
        P[P_INDEX["Y_I"]:P_INDEX["Y_I"] + 4] = [tf / 2, -tf / 2, tr / 2, -tr / 2]
        corners("M_U", vp.unsprung_mass)
        corners("K_S", vp.wheel_rate)
        corners("STOP_BUMP", vp.bump_stop_travel)
        corners("STOP_REB", vp.rebound_stop_travel)
        corners("K_ARB", vp.arb_rate)
        corners("TRACK", vp.track)
        corners("H_RC_AXLE", vp.roll_centre_height)
        corners("C_ALPHA", vp.cornering_stiffness)
        P[P_INDEX["FZ0"]:P_INDEX["FZ0"] + 4] = vp.static_wheel_loads()
        P[P_INDEX["OIL"]:P_INDEX["OIL"] + 4] = oil
        corners("SOIL_EMPTY", tuple(e / i for e, i in zip(vp.damper_friction_empty,
                                                           vp.damper_friction_intact)))
        corners("SH_X", vp.sh_longitudinal)
        corners("SH_Y", vp.sh_lateral)

    def _put_damper_curves(self, P: np.ndarray) -> None:
        """The passive damper's velocity grid [m/s] and its hydraulic curves [N], intact and oil-empty,
        per corner (the measured curves less the damper friction, :func:`hydraulic_curves`)."""
        P[P_GRID:P_GRID + N_GRID] = DAMPER_GRID
        h_int, h_emp = hydraulic_curves(self.vehicle)
        for i, a in enumerate(CORNER_AXLE):
            P[P_H_INTACT + i * N_GRID:P_H_INTACT + (i + 1) * N_GRID] = h_int[a]
            P[P_H_EMPTY + i * N_GRID:P_H_EMPTY + (i + 1) * N_GRID] = h_emp[a]

    def _put_friction_terms(self, P: np.ndarray) -> None:
        """The physics terms' blocks of ``P``: the built-in axle and damper friction (levels [N], Dahl
        stiffness [N/m]), then the variant's extra terms."""
        vp = self.vehicle
        self._put_term(P, AXLE_FRICTION, {"level": _corners(vp.axle_friction),
                                          "sigma": (vp.dahl_stiffness,) * 4})
        self._put_term(P, DAMPER_FRICTION, {"level": _corners(vp.damper_friction_intact),
                                            "sigma": (vp.dahl_stiffness,) * 4})
        for setting in self.variant.terms:
            self._put_term(P, setting.term, setting.values)

    def _put_term(self, P: np.ndarray, term: PhysicsTerm, values) -> None:
        k = self.terms.index(term)
        off = self.layout.param_offsets[k]
        for j, prm in enumerate(term.params):
            P[off + 4 * j:off + 4 * j + 4] = values.get(prm.name, (prm.default,) * 4)

    def term_param_slice(self, term_name: str, param: str) -> slice:
        """Where ``param`` of term ``term_name`` sits in ``P`` (four corners), for fitting."""
        for k, t in enumerate(self.terms):
            if t.name == term_name:
                j = t.param_index(param)
                off = self.layout.param_offsets[k] + 4 * j
                return slice(off, off + 4)
        raise KeyError(f"model has no term {term_name!r}; it has {[t.name for t in self.terms]}")

    def initial_state(self) -> np.ndarray:
        """Static equilibrium on a flat road: all deviations zero, friction unloaded."""
        return np.zeros(self.layout.n_s)

    def stored_energy(self, P: np.ndarray, S: np.ndarray) -> float:
        """Energy [J] stored in the terms' states (e.g. Dahl F^2/(2 sigma))."""
        e = 0.0
        for k, t in enumerate(self.terms):
            if t.stored_energy is None:
                continue
            po, so = self.layout.param_offsets[k], self.layout.state_offsets[k]
            e += t.stored_energy(P[po:po + 4 * len(t.params)].reshape(-1, 4),
                                 S[so:so + 4 * t.n_states].reshape(-1, 4))
        return e


def set_semi_active(model: "Model", P: np.ndarray, on: bool) -> None:
    """Switch parameter vector ``P`` between the passive damper and the semi-active damper family."""
    if on:
        fam = model.dampers
        for name, off in (("soft", P_H_SOFT), ("hard", P_H_HARD)):
            h = hydraulic_from_measured(model.vehicle, fam.velocity, getattr(fam, name),
                                        model.vehicle.damper_friction_intact)
            for i, a in enumerate(CORNER_AXLE):
                P[off + i * N_GRID:off + (i + 1) * N_GRID] = h[a]
        P[P_VALVE_TAU] = fam.valve_time_constant
    P[P_SEMI_ACTIVE] = 1.0 if on else 0.0


def _corners(pair) -> tuple[float, float, float, float]:
    fl, fr, rl, rr = (float(pair[a]) for a in CORNER_AXLE)
    return fl, fr, rl, rr


def check_oil(oil: Iterable[float], what: str = "damper_oil_level") -> np.ndarray:
    arr = np.asarray(list(oil), dtype=float)
    if arr.shape != (4,) or not np.all(np.isfinite(arr)) or np.any(arr < 0) or np.any(arr > 1):
        raise SuspInputError(f"{what}: expected four fractions FL, FR, RL, RR in [0, 1], got {list(arr)}")
    return arr


# ---- inputs -------------------------------------------------------------------------------------------
def make_inputs(n_steps: int, speed, steering, accel=None, wheel_heights=None,
                damper_command=None) -> np.ndarray:
    """Per-step input array (n_steps x N_U) from per-step series or constants.

    ``speed`` [m/s], ``steering`` steering-wheel angle [rad], ``accel`` dv/dt [m/s^2] (default: the
    gradient of speed is the caller's job; 0 if omitted), ``wheel_heights`` (n_steps x 4) [m],
    ``damper_command`` (n_steps x 4 or 4) valve command [0, 1] (read only with semi-active parameters).
    """
    U = np.zeros((n_steps, N_U))
    U[:, U_INDEX["V"]] = speed
    U[:, U_INDEX["SWA"]] = steering
    if accel is not None:
        U[:, U_INDEX["AX"]] = accel
    if wheel_heights is not None:
        U[:, U_INDEX["ZR_IN"]:U_INDEX["ZR_IN"] + 4] = wheel_heights
    if damper_command is not None:
        U[:, U_INDEX["CMD"]:U_INDEX["CMD"] + 4] = damper_command
    return U


def simulate(model: Model, U: np.ndarray, *, dt: float, road: RoadProfile | None = None,
             oil: Sequence[float] | np.ndarray = INTACT, P: np.ndarray | None = None, S: np.ndarray | None = None,
             decim: int = 1, outputs: Sequence[str] | None = None, t0: float = 0.0) -> Response:
    """Run one vehicle over the input rows ``U`` at step ``dt`` [s]; record every ``decim``-th step.

    Road: a :class:`RoadProfile`, or ``None`` for per-wheel heights taken from ``U`` (four-poster).
    ``P``/``S``: parameters and initial state instead of ``model.params(oil)`` and rest; never written
    (the state after the last step is the response's ``state``). ``outputs``: signal names (or kernel
    labels) to record, default all. Returns a :class:`Response` of (n, k) values.
    """
    P = model.params(oil) if P is None else P
    S = model.initial_state() if S is None else np.array(S, dtype=float)
    rs, rzl, rzr, rn = (road or RoadProfile.flat()).kernel_arrays()
    mode = 0 if road is not None else 1
    if mode == 1:
        S[S_INDEX["ZR_PREV"]:S_INDEX["ZR_PREV"] + 4] = U[0, U_INDEX["ZR_IN"]:U_INDEX["ZR_IN"] + 4]
    if P[P_SEMI_ACTIVE] > 0.5 and U.shape[0]:
        S[S_INDEX["VALVE"]:S_INDEX["VALVE"] + 4] = np.clip(U[0, U_INDEX["CMD"]:U_INDEX["CMD"] + 4], 0.0, 1.0)
    labels, sel = selected_labels(outputs)
    Y = np.zeros((U.shape[0] // decim, len(sel)))
    done = model.kernel.run_one(P, S, np.ascontiguousarray(U), rs, rzl, rzr, rn, mode, dt, decim, sel, Y)
    t = t0 + dt * decim * np.arange(1, Y.shape[0] + 1)
    return Response(t, Y, labels, int(done), U.shape[0], S)


def batch_block(n_vehicles: int, lanes: int, threads: int) -> int:
    """Vehicles stepped side by side in one block of a batch of ``n_vehicles`` (the kernel runs its
    blocks in parallel, one per thread): ``lanes`` (the kernel's :data:`LANES`) when there are enough
    vehicles to give every thread its blocks, else the vehicles shared evenly among the threads (a
    diagnosis evaluates six drives at a time: one block of six kept one of two cores busy). A vehicle's
    numbers do not depend on its block."""
    if n_vehicles >= lanes * threads:
        return lanes
    return max(1, -(-n_vehicles // max(1, threads)))


def batch_cost(n_vehicles: int, n_steps: int, lanes: int, threads: int) -> int:
    """Vehicle-steps one thread runs for a batch (its time, nearly): blocks of :func:`batch_block`,
    shared among ``threads``."""
    block = batch_block(n_vehicles, lanes, threads)
    n_blocks = -(-n_vehicles // block)
    return -(-n_blocks // max(1, threads)) * block * n_steps


def simulate_batch(model: Model, P: np.ndarray, U: np.ndarray | Sequence[np.ndarray], *, dt: float,
                   roads: Sequence[RoadProfile | None] = (None,), u_row: np.ndarray | None = None,
                   road_row: np.ndarray | None = None, decim: int = 1,
                   outputs: Sequence[str] | None = None, S: np.ndarray | None = None) -> Response:
    """Run ``B = len(P)`` vehicles in parallel.

    ``P``: (B, n_p) parameters. ``U``: (R, n_steps, N_U) input sets (or a list of equal-length arrays);
    vehicle ``b`` uses ``U[u_row[b]]`` and ``roads[road_row[b]]`` (default row 0). ``S``: (B, n_s)
    initial states (default rest), never written. Returns a batch :class:`Response`: ``values``
    (B, n_out, n_sel), ``steps_done`` (B,), ``state`` (B, n_s) after the last step.
    """
    P = np.ascontiguousarray(np.atleast_2d(P), dtype=float)
    B = P.shape[0]
    U = np.ascontiguousarray(np.asarray(U, dtype=float))
    if U.ndim == 2:
        U = U[None]
    u_row = np.zeros(B, np.int64) if u_row is None else np.asarray(u_row, np.int64)
    road_row = np.zeros(B, np.int64) if road_row is None else np.asarray(road_row, np.int64)
    nmax = max(2, *(len(r) for r in roads if r is not None)) if any(r is not None for r in roads) else 2
    RS = np.zeros((len(roads), nmax))
    RZL = np.zeros_like(RS)
    RZR = np.zeros_like(RS)
    RN = np.zeros(len(roads), np.int64)
    mode_r = np.zeros(len(roads), np.int64)
    for k, r in enumerate(roads):
        rs, rzl, rzr, rn = (r or RoadProfile.flat()).kernel_arrays()
        RS[k, :len(rs)], RZL[k, :len(rs)], RZR[k, :len(rs)], RN[k] = rs, rzl, rzr, rn
        RS[k, len(rs):] = rs[-1]
        mode_r[k] = 0 if r is not None else 1
    mode = mode_r[road_row]
    S = np.zeros((B, model.layout.n_s)) if S is None else np.array(S, dtype=float)
    for b in np.nonzero(mode == 1)[0]:
        S[b, S_INDEX["ZR_PREV"]:S_INDEX["ZR_PREV"] + 4] = U[u_row[b], 0, U_INDEX["ZR_IN"]:U_INDEX["ZR_IN"] + 4]
    labels, sel = selected_labels(outputs)
    Y = np.zeros((B, U.shape[1] // decim, len(sel)))
    done = np.zeros(B, np.int64)
    kernel = model.kernel if bool(np.any(P[:, P_SEMI_ACTIVE] > 0.5)) else model.kernel_passive
    kernel.run_batch(P, S, U, u_row, RS, RZL, RZR, RN, road_row, mode, dt, decim, sel, Y, done,
                     batch_block(B, kernel.LANES, get_num_threads()))
    t = dt * decim * np.arange(1, Y.shape[1] + 1)
    return Response(t, Y, labels, done, U.shape[1], S)


class Stepper:
    """Real-time stepping of one vehicle: advance a few steps at a time with inputs held constant.

    The node calls :meth:`advance` once per publish period with the latest inputs; the lockstep
    runner calls it between recorded messages. Both run the same compiled :func:`step`.
    """

    def __init__(self, model: Model, *, dt: float, road: RoadProfile | None = None,
                 oil: Sequence[float] | np.ndarray = INTACT):
        if not (np.isfinite(dt) and 0 < dt <= 0.01):
            raise SuspInputError(f"step_s: expected a step in (0, 0.01] s, got {dt}")
        self.model, self.dt = model, float(dt)
        self.oil = check_oil(oil)
        self.P = model.params(self.oil)
        self.S = model.initial_state()
        self.y = np.zeros(len(OUTPUT_LABELS))
        self._sel = np.arange(len(OUTPUT_LABELS), dtype=np.int64)
        self._U = np.zeros((1, N_U))
        self._cmd = np.zeros(4)  # the held valve command
        self.steps = 0
        self.healthy = True
        self.set_road(road)

    @property
    def time(self) -> float:
        return self.steps * self.dt

    def set_road(self, road: RoadProfile | None) -> None:
        """Road profile (``None``: per-wheel heights from the inputs, flat until given)."""
        self.road = road
        self._road_arrays = (road or RoadProfile.flat()).kernel_arrays()
        self._mode = 0 if road is not None else 1

    @property
    def semi_active(self) -> bool:
        return bool(self.P[P_SEMI_ACTIVE] > 0.5)

    def set_semi_active(self, on: bool, command: Sequence[float] | np.ndarray | None = None) -> None:
        """Use the valve command (``on``) or the passive damper. Switching on sets the valve to
        ``command`` (default: its last setting) without lag: the valve starts where it is commanded."""
        if on and not self.semi_active and command is not None:
            self.S[S_INDEX["VALVE"]:S_INDEX["VALVE"] + 4] = np.clip(np.asarray(command, float), 0.0, 1.0)
        set_semi_active(self.model, self.P, on)

    def set_oil(self, oil: Sequence[float] | np.ndarray) -> None:
        self.oil = check_oil(oil)
        self.P[P_INDEX["OIL"]:P_INDEX["OIL"] + 4] = self.oil

    def set_model(self, model: Model) -> None:
        """Switch vehicle/variant while running: the body and wheel states carry over; the states of
        terms present in both models carry over, new terms start unloaded."""
        S_new = model.initial_state()
        S_new[:S_INDEX["VALVE"] + 4] = self.S[:S_INDEX["VALVE"] + 4]
        for k, t in enumerate(model.terms):
            if t in self.model.terms:
                j = self.model.terms.index(t)
                so_old, so_new, n = self.model.layout.state_offsets[j], model.layout.state_offsets[k], 4 * t.n_states
                S_new[so_new:so_new + n] = self.S[so_old:so_old + n]
        self.model, self.S = model, S_new
        self.P = model.params(self.oil, semi_active=self.semi_active)

    def advance(self, n_steps: int, speed: float, steering: float, accel: float = 0.0,
                wheel_heights: Sequence[float] | np.ndarray | None = None,
                damper_command: Sequence[float] | np.ndarray | None = None) -> np.ndarray:
        """Advance ``n_steps`` steps with held inputs; returns the full output vector of the last step.
        ``damper_command`` [0, 1] per corner is used when :attr:`semi_active` (else ignored)."""
        if n_steps <= 0 or not self.healthy:
            return self.y
        if self._U.shape[0] != n_steps:
            self._U = np.zeros((n_steps, N_U))
        U = self._U
        U[:, U_INDEX["V"]] = speed
        U[:, U_INDEX["AX"]] = accel
        U[:, U_INDEX["SWA"]] = steering
        if wheel_heights is not None:
            U[:, U_INDEX["ZR_IN"]:U_INDEX["ZR_IN"] + 4] = wheel_heights
            if self.steps == 0:
                self.S[S_INDEX["ZR_PREV"]:S_INDEX["ZR_PREV"] + 4] = wheel_heights
        if damper_command is not None:
            self._cmd = np.asarray(damper_command, float)
        U[:, U_INDEX["CMD"]:U_INDEX["CMD"] + 4] = self._cmd
        Y = np.zeros((n_steps, len(self._sel)))
        rs, rzl, rzr, rn = self._road_arrays
        done = self.model.kernel.run_one(self.P, self.S, U, rs, rzl, rzr, rn, self._mode, self.dt, 1,
                                         self._sel, Y)
        self.steps += done
        self.block = Y[:done]  # the outputs of every step of this call (OUTPUT_LABELS columns)
        self.y = Y[done - 1]
        if done < n_steps:
            self.healthy = False
        return self.y
