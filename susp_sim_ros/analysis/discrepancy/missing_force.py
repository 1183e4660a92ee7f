"""The force the model lacks, estimated from a recording (issue 26: "see the missing force").

What the body IMU says and the model does not is a force. Write the measured motion as the simulated
one plus an error ``e = q_meas - q_sim`` in the seven vertical coordinates of :mod:`~susp_sim_ros.model.linear`
(heave, roll, pitch, four wheels). To first order it obeys the model's linearised dynamics driven by the
generalised force of what is missing::

    M e'' + C e' + K e = B d,      d = [F_front, F_rear, M_roll]

``F_front``/``F_rear`` [N]: vertical force between body and axle (both wheels together), positive when it
pushes the body up and the wheels down, like the model's own suspension force; ``M_roll`` [N*m]: roll
moment on the body about x (REP-103, positive rolls the left side up), carried half by each axle as
opposite forces on its two corners. ``d`` is a first-order Gauss-Markov process (time constant and
intensity in ``config/missing_force.yaml``); the measurements are the residuals measured - simulated of
roll rate, pitch rate [rad/s] and vertical specific force [m/s^2] at the IMU's sample times, with the
finder's per-drive noise floors as their noise. A Kalman filter and Rauch-Tung-Striebel smoother over
the augmented state ``[e, e', d]`` give ``d(t)`` and its standard deviation.

Why hand-written recursions on scipy.linalg (``expm`` for the exact discretisation, Van Loan 1978)
rather than filterpy: the model is 17 states and a few thousand samples per drive, the filter also runs
over missing samples (gaps excluded by the integrity check) and returns the innovations' likelihood that
chooses the intensity; filterpy's ``KalmanFilter``/``rts_smoother`` would need the same loop around it
and is unmaintained since 2018.

Sources: Rauch, Tung and Striebel (1965), AIAA J. 3(8); Van Loan (1978), IEEE TAC 23(3) (discretisation);
Harvey (1989), Forecasting, structural time series models and the Kalman filter, ch. 3.4 (likelihood
of the innovations); the unknown-input idea as in Friedland (1969), IEEE TAC 14(4) (augmented state).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.signal
from numba import njit

from ...model.layout import P_INDEX
from ...model.linear import LinearModel, linearise
from ...model.params import load_settings

#: columns of the estimated force, in the order of ``d`` and of the CSV (interface.md)
CHANNELS = ("front_N", "rear_N", "roll_Nm")
#: measured signals the estimate uses, with their kernel output names
MEASURED = ("ROLL_RATE", "PITCH_RATE", "AZ_SF")
_N_Q = 7   # vertical coordinates of model/linear.py
_N_D = len(CHANNELS)
_N_X = 2 * _N_Q + _N_D
_LOG_2PI = float(np.log(2 * np.pi))


def settings(path=None) -> dict:
    """``config/missing_force.yaml`` as ``{"section.key": value}``."""
    return load_settings("missing_force.yaml", path)


@dataclass(frozen=True)
class Corners:
    """Corner positions in the body frame [m] (FL FR RL RR; x forward, y left) from a parameter row."""

    x: np.ndarray
    y: np.ndarray

    @classmethod
    def of(cls, P: np.ndarray) -> "Corners":
        P = np.asarray(P, float).ravel()
        return cls(P[P_INDEX["X_I"]:P_INDEX["X_I"] + 4].copy(), P[P_INDEX["Y_I"]:P_INDEX["Y_I"] + 4].copy())

    @property
    def roll_arm_m(self) -> float:
        """Half the mean track [m]: the lever of a corner force about the roll axis."""
        return float(np.mean(np.abs(self.y)))


def corner_forces(corners: Corners) -> np.ndarray:
    """(4, 3): the corner forces [N] (FL FR RL RR, positive up on the body) of a unit ``d`` component
    (1 N front, 1 N rear, 1 N*m roll, the roll moment half on each axle)."""
    T = np.zeros((4, _N_D))
    T[0:2, 0] = 0.5
    T[2:4, 1] = 0.5
    for left, right in ((0, 1), (2, 3)):
        track = corners.y[left] - corners.y[right]
        T[left, 2] = 0.5 / track
        T[right, 2] = -0.5 / track
    return T


def input_matrix(corners: Corners) -> np.ndarray:
    """(7, 3) generalised forces in the coordinates of ``model/linear.py`` of a unit ``d`` component: a
    corner force ``f`` (up on the body) acts on heave with ``f``, on roll with ``y f``, on pitch with
    ``-x f`` and on its wheel with ``-f`` (``_kernel_template.body_accelerations``)."""
    return -deflection_jacobian(corners).T @ corner_forces(corners)


def deflection_jacobian(corners: Corners) -> np.ndarray:
    """(4, 7) ``d(deflection)/dq``: deflection ``zw - (z - x theta + y phi)`` (positive in bump,
    ``_kernel_template.corner_kinematics``)."""
    J = np.zeros((4, _N_Q))
    J[:, 0] = -1.0
    J[:, 1] = -corners.y
    J[:, 2] = corners.x
    J[:, 3:] = np.eye(4)
    return J


def equivalent_linear(lin: LinearModel, corners: Corners, deflection: np.ndarray, velocity: np.ndarray,
                      force: np.ndarray) -> LinearModel:
    """``lin`` with each corner's damper and friction force replaced by its equivalent linearisation
    over the drive (Caughey 1963; Roberts and Spanos, Random Vibration and Statistical Linearization,
    2003): the least-squares ``force ~ a + k deflection + c velocity`` of the simulated (n, 4) series.
    At standstill the model's damper has no slope (its friction takes the first millimetres per second)
    and its friction elements are not in ``lin`` at all; along a drive both act as a damping ``c`` and a
    hysteretic stiffness ``k``, which the error dynamics must carry."""
    J = deflection_jacobian(corners)
    c0 = -lin.C[0, 3:]   # the corners' damper slopes at standstill in lin (C = J^T diag(c0) J + tyres)
    k = np.zeros(4)
    c = np.zeros(4)
    for i in range(4):
        X = np.column_stack([np.ones(len(force)), deflection[:, i] - deflection[:, i].mean(),
                             velocity[:, i] - velocity[:, i].mean()])
        coef = np.linalg.lstsq(X, force[:, i], rcond=None)[0]
        k[i], c[i] = max(coef[1], 0.0), max(coef[2], 0.0)
    return LinearModel(lin.M, lin.C + J.T @ np.diag(c - c0) @ J, lin.K + J.T @ np.diag(k) @ J)


@dataclass(frozen=True)
class ErrorModel:
    """The discretised augmented model ``x[k+1] = F x[k] + w``, ``y[k] = H x[k] + v`` (``x = [e, e', d]``)
    at step ``dt`` [s] for a unit intensity; ``Qe`` and ``Qd`` the process noise of the error states and of
    ``d`` per unit intensity (``Q = Qe + intensity * Qd``)."""

    F: np.ndarray
    H: np.ndarray
    Qe: np.ndarray
    Qd: np.ndarray
    dt: float
    d_scale: np.ndarray


def error_model(lin: LinearModel, B: np.ndarray, dt: float, *, tau_s: float, state_sd: float,
                roll_arm_m: float) -> ErrorModel:
    """:class:`ErrorModel` of ``M e'' + C e' + K e = B d`` with ``d`` a Gauss-Markov process of time
    constant ``tau_s``; the roll moment's intensity is that of a corner force at ``roll_arm_m``."""
    Minv = np.linalg.inv(lin.M)
    A = np.zeros((_N_X, _N_X))
    A[:_N_Q, _N_Q:2 * _N_Q] = np.eye(_N_Q)
    A[_N_Q:2 * _N_Q, :_N_Q] = -Minv @ lin.K
    A[_N_Q:2 * _N_Q, _N_Q:2 * _N_Q] = -Minv @ lin.C
    A[_N_Q:2 * _N_Q, 2 * _N_Q:] = Minv @ B
    A[2 * _N_Q:, 2 * _N_Q:] = -np.eye(_N_D) / tau_s
    d_scale = np.array([1.0, 1.0, roll_arm_m])
    Qc_d = np.zeros((_N_X, _N_X))
    Qc_d[2 * _N_Q:, 2 * _N_Q:] = np.diag(d_scale ** 2)
    Qc_e = np.zeros((_N_X, _N_X))
    Qc_e[:2 * _N_Q, :2 * _N_Q] = state_sd ** 2 * np.eye(2 * _N_Q)
    F, Qe = _van_loan(A, Qc_e, dt)
    _, Qd = _van_loan(A, Qc_d, dt)
    H = np.zeros((len(MEASURED), _N_X))
    H[0, _N_Q + 1] = 1.0     # roll rate error = e'_phi
    H[1, _N_Q + 2] = 1.0     # pitch rate error = e'_theta
    H[2] = A[_N_Q]           # vertical specific force error = e''_z (IMU at the centre of gravity)
    return ErrorModel(F, H, Qe, Qd, dt, d_scale)


def _van_loan(A: np.ndarray, Qc: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact discretisation of ``x' = A x + w`` (white ``w`` of intensity ``Qc``) over ``dt``."""
    n = A.shape[0]
    V = np.zeros((2 * n, 2 * n))
    V[:n, :n] = -A
    V[:n, n:] = Qc
    V[n:, n:] = A.T
    E = scipy.linalg.expm(V * dt)
    F = E[n:, n:].T
    Q = F @ E[:n, n:]
    return F, 0.5 * (Q + Q.T)


@dataclass
class Smoothed:
    """The smoother's ``d`` estimate (n, 3) and its sd (n, 3), and the innovations' log-likelihood."""

    d: np.ndarray
    sd: np.ndarray
    loglik: float


def smooth(em: ErrorModel, intensity: float, y: np.ndarray, valid: np.ndarray, R: np.ndarray,
           *, smooth_back: bool = True) -> Smoothed:
    """Kalman filter (and, with ``smooth_back``, RTS smoother) of ``y`` (n, 3) where ``valid`` (n,) is
    true; ``R`` (3,) measurement variances. Missing samples are predicted through, never interpolated."""
    Q = em.Qe + intensity * em.Qd
    P = np.zeros((_N_X, _N_X))
    tau = -em.dt / np.log(em.F[-1, -1])
    P[2 * _N_Q:, 2 * _N_Q:] = np.diag(intensity * em.d_scale ** 2 * tau / 2)  # stationary d
    F, H = (np.ascontiguousarray(a, dtype=np.float64) for a in (em.F, em.H))  # one compiled layout
    y = np.ascontiguousarray(y, dtype=np.float64)
    xp, Pp, xf, Pf, loglik = _kalman_filter(F, H, np.ascontiguousarray(Q), np.diag(R).astype(np.float64), P, y,
                                            np.ascontiguousarray(valid, dtype=np.bool_))
    if not smooth_back:
        return Smoothed(xf[:, 2 * _N_Q:], np.sqrt(np.maximum(np.diagonal(Pf, axis1=1, axis2=2)[:, 2 * _N_Q:], 0)),
                        loglik)
    xs, Ps = _rts_smoother(F, xp, Pp, xf, Pf)
    var = np.diagonal(Ps, axis1=1, axis2=2)[:, 2 * _N_Q:]
    return Smoothed(xs[:, 2 * _N_Q:], np.sqrt(np.maximum(var, 0.0)), loglik)


@njit(cache=True)
def _kalman_filter(F, H, Q, Rm, P, y, valid):
    """The filter pass of :func:`smooth` (compiled: a Python loop of small matrix products took 60 ms a
    drive, 9 intensities a drive): predicted and filtered means and covariances, innovations'
    log-likelihood. ``P`` is the initial covariance."""
    n, nx = y.shape[0], F.shape[0]
    FT, HT = np.ascontiguousarray(F.T), np.ascontiguousarray(H.T)
    x = np.zeros(nx)
    xp = np.empty((n, nx))
    Pp = np.empty((n, nx, nx))
    xf = np.empty((n, nx))
    Pf = np.empty((n, nx, nx))
    loglik = 0.0
    for k in range(n):
        if k:
            x = F @ x
            P = F @ P @ FT + Q
        xp[k], Pp[k] = x, P
        if valid[k]:
            HP = H @ P
            PHT = np.ascontiguousarray(HP.T)
            Si = np.linalg.inv(HP @ HT + Rm)
            nu = y[k] - H @ x
            G = PHT @ Si
            x = x + G @ nu
            P = P - G @ HP
            P = 0.5 * (P + np.ascontiguousarray(P.T))
            loglik -= 0.5 * (nu @ (Si @ nu) - np.linalg.slogdet(Si)[1] + _LOG_2PI * nu.shape[0])
        xf[k], Pf[k] = x, P
    return xp, Pp, xf, Pf, loglik


@njit(cache=True)
def _rts_smoother(F, xp, Pp, xf, Pf):
    """The Rauch-Tung-Striebel backward pass of :func:`smooth` over the filter's output."""
    xs, Ps = xf.copy(), Pf.copy()
    for k in range(xf.shape[0] - 2, -1, -1):
        GT = np.linalg.solve(Pp[k + 1], F @ Pf[k])   # the gain, transposed
        G = np.ascontiguousarray(GT.T)
        xs[k] = xf[k] + G @ (xs[k + 1] - xp[k + 1])
        Ps[k] = Pf[k] + G @ (Ps[k + 1] - Pp[k + 1]) @ GT
    return xs, Ps


@dataclass
class MissingForce:
    """The estimated missing force of one drive on a uniform grid ``t`` [s since the drive's first
    input]: ``force`` and ``sd`` (n, 3) in :data:`CHANNELS` units; ``intensity`` [N^2/s] chosen by the
    likelihood; ``valid`` the grid samples with a measurement."""

    t: np.ndarray
    force: np.ndarray
    sd: np.ndarray
    intensity: float
    valid: np.ndarray


def uniform_grid(t_meas: np.ndarray) -> tuple[np.ndarray, float]:
    """A uniform grid [s] at the median sampling interval over the measured span, and the interval."""
    dt = float(np.median(np.diff(t_meas)))
    n = int(np.floor((t_meas[-1] - t_meas[0]) / dt + 1e-9)) + 1
    return t_meas[0] + dt * np.arange(n), dt


def on_grid(t_meas: np.ndarray, y_meas: np.ndarray, grid: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """The measured residual at the grid times: each grid time takes the nearest measured sample within
    half an interval, else it is missing (``valid`` false); nothing is interpolated across a gap."""
    j = np.clip(np.searchsorted(t_meas, grid), 1, len(t_meas) - 1)
    j = np.where(np.abs(t_meas[j - 1] - grid) <= np.abs(t_meas[j] - grid), j - 1, j)
    valid = np.abs(t_meas[j] - grid) <= 0.5 * dt + 1e-9
    return y_meas[j], valid


def estimate(lin: LinearModel, corners: Corners, t_meas: np.ndarray, resid: np.ndarray, sigma: np.ndarray,
             cfg: dict | None = None) -> MissingForce:
    """The missing force from the residuals measured - simulated ``resid`` (n, 3) of :data:`MEASURED`
    (SI) at the measured times ``t_meas`` [s] with noise sd ``sigma`` (3,) (SI); ``lin`` the model
    linearised at the drive's parameters. The intensity is the grid point of largest likelihood."""
    cfg = settings() if cfg is None else cfg
    grid, dt = uniform_grid(np.asarray(t_meas, float))
    y, valid = on_grid(np.asarray(t_meas, float), np.asarray(resid, float), grid, dt)
    em = error_model(lin, input_matrix(corners), dt, tau_s=float(cfg["force.time_constant_s"]),
                     state_sd=float(cfg["force.state_sd"]), roll_arm_m=corners.roll_arm_m)
    lo, hi, k = cfg["force.intensity_grid"]
    R = np.maximum(np.asarray(sigma, float), 1e-12) ** 2
    best = max(np.geomspace(float(lo), float(hi), int(k)),
               key=lambda q: smooth(em, q, y, valid, R, smooth_back=False).loglik)
    s = smooth(em, float(best), y, valid, R)
    return MissingForce(grid, s.d, s.sd, float(best), valid)


def estimate_on_model(vehicle, P: np.ndarray, deflection: np.ndarray, velocity: np.ndarray,
                      force: np.ndarray, t_meas: np.ndarray, resid: np.ndarray, sigma: np.ndarray,
                      cfg: dict | None = None) -> MissingForce:
    """:func:`estimate` with the model linearised at the drive's parameter row ``P`` of ``vehicle``, its
    damper and friction replaced by their equivalent linearisation along the simulated corner series
    (n_steps, 4): ``deflection`` [m], ``velocity`` [m/s], damper plus friction ``force`` [N]."""
    corners = Corners.of(P)
    lin = equivalent_linear(linearise(vehicle, P), corners, deflection, velocity, force)
    return estimate(lin, corners, t_meas, resid, sigma, cfg)


#: per-corner kernel outputs a suspension force is re-evaluated along (:func:`suspension_force_along`)
TRAJECTORY = ("DEFL", "DEFL_VEL", "F_X", "F_Y", "F_Z")
_ARB_PARTNER = (1, 0, 3, 2)   # the other wheel of a corner's axle (FL FR RL RR)


def suspension_force_along(kernel, P: np.ndarray, deflection: np.ndarray, velocity: np.ndarray,
                           fx: np.ndarray, fy: np.ndarray, fz: np.ndarray) -> np.ndarray:
    """(n_steps, 4) suspension force [N] per corner (FL FR RL RR; positive up on the body) of the parameter
    row ``P`` along a simulated trajectory: spring with stops, hydraulic damper, every physics term (the
    friction elements with their Dahl history along the trajectory) and anti-roll bar, i.e. the kernel
    outputs ``F_SPRING + F_DAMPER + F_FRICTION + F_ARB`` that ``P`` would give at the trajectory's
    deflections, velocities and wheel forces.

    The trajectory is a run's per-step kernel outputs (n_steps, 4 each): ``deflection`` ``DEFL`` [m],
    ``velocity`` ``DEFL_VEL`` [m/s], wheel forces ``fx``, ``fy``, ``fz`` (``F_X``, ``F_Y``, ``F_Z``) [N],
    from rest. The corner's force comes from the kernel's own code (``rig_run`` of ``kernel``: spring,
    damper and terms of the vehicle's step), one sample per call so the wheel forces follow the
    trajectory; the anti-roll bar is ``K_ARB (d_i - d_partner)`` as in the step. A step's forces act at
    the deflection it starts from (the previous step's output, rest before the first), and the terms
    advance over the step's increment, as in the step. Not reproduced (``rig_run`` holds them at zero):
    the speed and the step in the terms' context (no built-in term reads them; the amplitude term's
    ``memory`` does) and the semi-active valve. :func:`calibration_force` checks the reproduction."""
    P = np.ascontiguousarray(P, float)
    n = len(deflection)
    d = np.vstack([np.zeros((1, 4)), np.asarray(deflection, float)[:-1]])
    dd = np.vstack([np.zeros((1, 4)), np.asarray(velocity, float)[:-1]])
    out = np.zeros((n, 4))
    S = np.zeros(int(kernel.N_S))   # rest: every term unloaded, as a run starts
    two = np.zeros(2)
    rig_run, mask = kernel.rig_run, kernel.MASK_ALL
    for i in range(4):
        di, ddi = np.ascontiguousarray(d[:, i]), np.ascontiguousarray(dd[:, i])
        fxi, fyi, fzi = (np.asarray(a, float)[:, i].tolist() for a in (fx, fy, fz))
        col = out[:, i]
        for k in range(n):   # force at d[k], then the terms over d[k+1] - d[k] with this step's wheel forces
            rig_run(P, S, i, di[k:k + 2], ddi[k:k + 2], fxi[k], fyi[k], fzi[k], mask, True, two)
            col[k] = two[0]
    k_arb = P[P_INDEX["K_ARB"]:P_INDEX["K_ARB"] + 4]
    return out + k_arb * (d - d[:, list(_ARB_PARTNER)])


@dataclass
class CalibrationForce:
    """What the calibration supplied as corner force along the calibrated model's trajectory:
    ``corner`` (n_steps, 4) [N] the calibrated model's suspension force minus the base model's at the
    same deflections, velocities and wheel forces; ``check_N`` the largest deviation of the re-evaluated
    calibrated force from the kernel's own outputs over the run (0 up to rounding when the reproduction
    holds)."""

    corner: np.ndarray
    check_N: float


def calibration_force(kernel, P_calibrated: np.ndarray, P_base: np.ndarray, trajectory: dict[str, np.ndarray],
                      kernel_force: np.ndarray | None = None) -> CalibrationForce:
    """:class:`CalibrationForce` along ``trajectory`` (:data:`TRAJECTORY` names -> (n_steps, 4) outputs of
    the calibrated run); ``kernel_force`` (n_steps, 4) the run's ``F_SPRING + F_DAMPER + F_FRICTION +
    F_ARB``, to check the re-evaluation against. Body-level values (masses, inertias, centre of gravity,
    tyres) are no corner force: they shape the trajectory but their difference is not in here (the mass and
    inertia change's inertial force is :func:`body_force`)."""
    args = [trajectory[k] for k in TRAJECTORY]
    cal = suspension_force_along(kernel, P_calibrated, *args)
    base = suspension_force_along(kernel, P_base, *args) if not np.array_equal(P_calibrated, P_base) else cal
    check = float(np.max(np.abs(cal - kernel_force))) if kernel_force is not None and len(cal) else 0.0
    return CalibrationForce(cal - base, check)


#: body-level values of the parameter row whose calibration is no corner force, with the body coordinate
#: (of ``model/linear.py``: 0 heave, 1 roll, 2 pitch) whose inertia they are: sprung mass [kg], roll and
#: pitch inertia [kg*m^2]
BODY_VALUES = (("M_S", 0), ("IXX", 1), ("IYY", 2))
#: kernel outputs the body's accelerations are read from (:func:`body_accelerations`)
BODY_OUTPUTS = ("AZ_SF", "ROLL_RATE", "PITCH_RATE")


def body_accelerations(P: np.ndarray, az_sf: np.ndarray, roll_rate: np.ndarray, pitch_rate: np.ndarray,
                       dt: float) -> np.ndarray:
    """(n_steps, 3) the body's accelerations of a run of the parameter row ``P`` at step ``dt`` [s], from its
    per-step kernel outputs: heave [m/s^2] ``AZ_SF - G`` (the kernel writes the vertical specific force at
    the centre of gravity as ``g + z''`` of the step), roll and pitch [rad/s^2] the backward difference of
    ``ROLL_RATE`` and ``PITCH_RATE`` over the step, from rest before the first (the kernel integrates the
    rates by semi-implicit Euler, ``rate[k] = rate[k-1] + acc[k] dt``, so the difference is the step's
    angular acceleration itself, not an approximation of it)."""
    P = np.asarray(P, float).ravel()
    zdd = np.asarray(az_sf, float) - P[P_INDEX["G"]]
    rates = np.column_stack([roll_rate, pitch_rate]).astype(float)
    angular = np.diff(rates, axis=0, prepend=np.zeros((1, 2))) / dt
    return np.column_stack([zdd, angular])


def body_force(P_calibrated: np.ndarray, P_base: np.ndarray, accelerations: np.ndarray,
               corners: Corners) -> np.ndarray:
    """(n, 3) the :data:`CHANNELS` (front, rear [N], roll moment [N*m]) of the body-level part of a
    calibration: the inertial force of its sprung-mass and inertia change (:data:`BODY_VALUES`) along the
    calibrated run's body ``accelerations`` (n, 3: heave, roll, pitch; :func:`body_accelerations`),
    ``-(m_cal - m_file) z''``, ``-(Ixx_cal - Ixx_file) phi''``, ``-(Iyy_cal - Iyy_file) theta''``: what the
    base model's body, with the file's mass and inertias, lacks to move as the calibrated one does. Split
    onto the channels by statics: the (front, rear, roll) triple whose generalised force on heave, roll
    and pitch (:func:`input_matrix`, as the estimate's ``d`` acts on the body) equals that inertial force.
    Left out: the mass change's share of the kernel's pendulum terms (``m (h_cg - h_rc) a_y`` in roll,
    ``m (h_cg - h_pc) (g theta - a_x)`` in pitch) and a calibrated centre-of-gravity height, a few N*m on
    a bump crossing against hundreds of the inertia term."""
    dP = np.asarray(P_calibrated, float).ravel() - np.asarray(P_base, float).ravel()
    acc = np.asarray(accelerations, float)
    gen = np.zeros_like(acc)
    for name, j in BODY_VALUES:
        gen[:, j] = -dP[P_INDEX[name]] * acc[:, j]
    return np.linalg.solve(input_matrix(corners)[:3], gen.T).T


def axle_channels(corner: np.ndarray, corners: Corners) -> np.ndarray:
    """(n, 3) the :data:`CHANNELS` of per-corner forces ``corner`` (n, 4; positive up on the body): front
    and rear axle sums [N] and the roll moment on the body ``sum y_i f_i`` [N*m] (as the kernel applies
    suspension forces; the estimate's ``d``)."""
    corner = np.asarray(corner, float)
    return np.column_stack([corner[:, 0] + corner[:, 1], corner[:, 2] + corner[:, 3], corner @ corners.y])


def band_passed(x: np.ndarray, dt: float, cfg: dict | None = None) -> np.ndarray:
    """``x`` (n, ...) band-passed to the body-mode band of the settings (zero-phase Butterworth)."""
    cfg = settings() if cfg is None else cfg
    sos = scipy.signal.butter(2, [float(cfg["band.low_hz"]), float(cfg["band.high_hz"])], btype="band",
                              fs=1.0 / dt, output="sos")
    pad = 3 * int(round(1.0 / (dt * float(cfg["band.low_hz"]))))  # three periods of the lowest frequency
    return scipy.signal.sosfiltfilt(sos, x, axis=0, padlen=min(len(x) - 1, pad))


def loop_half_height(force: np.ndarray, deflection_velocity: np.ndarray, cfg: dict | None = None) -> float:
    """Half the height of a force-deflection loop [N]: half the difference between the mean force in
    compression and in rebound where the deflection moves faster than the settings' saturation velocity
    (a friction element has slid there). The friction level of a Coulomb or Dahl element, zero for a
    spring, small for a slow viscous one; blind to a constant offset (which a body IMU cannot see)."""
    cfg = settings() if cfg is None else cfg
    v_min = float(cfg["loops.saturated_velocity_m_s"])
    up, down = deflection_velocity > v_min, deflection_velocity < -v_min
    if not (np.any(up) and np.any(down)):
        return float("nan")
    return float(0.5 * (np.mean(force[up]) - np.mean(force[down])))
