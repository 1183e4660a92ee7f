"""Linearised vertical dynamics: the exact reference the nonlinear kernel is checked against.

Seven degrees of freedom ``q = [z, phi, theta, zw_FL, zw_FR, zw_RL, zw_RR]`` around static equilibrium
(model-spec 2): ``M q'' + C q' + K q = 0``. The matrices are not derived by hand: they are the model's
own right-hand side (the kernel's public :func:`accelerations` of ``_kernel_template.py``: its stages
``corner_kinematics``, ``suspension_forces`` and ``body_accelerations``, without physics terms, so
without friction)
linearised by central differences about the static equilibrium on a flat road at standstill:
``K = -M d(q'')/dq`` holds the wheel-rate springs, anti-roll bars, tyres and the destabilising gravity
terms of the roll and pitch equations; ``C = -M d(q'')/dq'`` the hydraulic dampers' slopes at zero
velocity (mean of bump and rebound) and the tyre damping. ``M`` is the diagonal of the masses and
inertias. Heave and pitch are coupled when a*k_f != b*k_r.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import _kernel_template as rhs
from .layout import N_P_FIXED, N_S_FIXED, P_INDEX, S_INDEX
from .params import FrictionVariant, VehicleParams
from .vehicle import Model

#: state slots of q and of q' (layout.S_INDEX)
_Q = np.array([S_INDEX["Z"], S_INDEX["PHI"], S_INDEX["THETA"], *range(S_INDEX["ZW"], S_INDEX["ZW"] + 4)])
_QD = np.array([S_INDEX["ZD"], S_INDEX["PHID"], S_INDEX["THETAD"],
                *range(S_INDEX["ZWD"], S_INDEX["ZWD"] + 4)])
#: central-difference step [m, rad, m/s, rad/s]: the model is linear far beyond it (stops, lift-off and
#: the damper grid's first cell are millimetres away), and far above rounding
_H = 1e-6


@dataclass(frozen=True)
class Modes:
    """Natural frequencies [Hz] and mode shapes (columns, in q coordinates) sorted by frequency."""

    freq_hz: np.ndarray
    shapes: np.ndarray

    def body_mode(self, coordinate: int) -> tuple[float, np.ndarray]:
        """The body mode (among the three lowest) dominated by q[coordinate] (0 heave, 1 roll, 2 pitch)."""
        body = range(3)
        k = max(body, key=lambda j: abs(self.shapes[coordinate, j]) / np.linalg.norm(self.shapes[:3, j]))
        return float(self.freq_hz[k]), self.shapes[:, k]


@dataclass(frozen=True)
class LinearModel:
    """``M q'' + C q' + K q = 0`` in q coordinates: mass [kg, kg*m^2], damping [N*s/m, N*m*s/rad] and
    stiffness [N/m, N*m/rad] matrices (7 x 7)."""

    M: np.ndarray
    C: np.ndarray
    K: np.ndarray


def _parameters(vp: VehicleParams) -> np.ndarray:
    """The fixed parameter vector of ``vp`` (intact oil, passive damper), as a block of one vehicle."""
    P = Model(vp, FrictionVariant("linearised", False, False, False)).params()
    return np.ascontiguousarray(P[:N_P_FIXED].reshape(-1, 1))


def _accelerations(P: np.ndarray, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """q'' of the model's right-hand side at (q, q'), road flat, standstill, no physics terms."""
    S = np.zeros((N_S_FIXED, 1))
    S[_Q, 0] = q
    S[_QD, 0] = qd
    return rhs.accelerations(P, S)[:, 0]


def linearise(vp: VehicleParams, P: np.ndarray | None = None) -> LinearModel:
    """The model's vertical dynamics linearised about static equilibrium (module docstring). ``P``: a
    parameter vector of ``vp`` to linearise instead of its default one (intact oil, passive damper),
    e.g. with other damper curves; only its fixed part (``layout.N_P_FIXED``) is read."""
    P = _parameters(vp) if P is None else np.ascontiguousarray(np.asarray(P, float)[:N_P_FIXED].reshape(-1, 1))
    M = np.diag(P[[P_INDEX["M_S"], P_INDEX["IXX"], P_INDEX["IYY"], *range(P_INDEX["M_U"], P_INDEX["M_U"] + 4)], 0])
    zero = np.zeros(7)
    dq = np.empty((7, 7))
    dqd = np.empty((7, 7))
    for j in range(7):
        e = np.zeros(7)
        e[j] = _H
        dq[:, j] = (_accelerations(P, e, zero) - _accelerations(P, -e, zero)) / (2 * _H)
        dqd[:, j] = (_accelerations(P, zero, e) - _accelerations(P, zero, -e)) / (2 * _H)
    return LinearModel(M, -M @ dqd, -M @ dq)


def mass_stiffness(vp: VehicleParams) -> tuple[np.ndarray, np.ndarray]:
    """Mass and stiffness matrices ``(M, K)`` of :func:`linearise`."""
    lin = linearise(vp)
    return lin.M, lin.K


def modes(vp: VehicleParams) -> Modes:
    M, K = mass_stiffness(vp)
    w2, V = np.linalg.eig(np.linalg.solve(M, K))
    order = np.argsort(w2.real)
    return Modes(np.sqrt(w2.real[order]) / (2 * np.pi), V.real[:, order])


def state_from_q(S: np.ndarray, q: np.ndarray, qd: np.ndarray | None = None) -> np.ndarray:
    """Write q (and velocities qd) into a kernel state vector."""
    S = S.copy()
    qd = np.zeros(7) if qd is None else qd
    for j, name in enumerate(("Z", "PHI", "THETA")):
        S[S_INDEX[name]] = q[j]
    S[S_INDEX["ZW"]:S_INDEX["ZW"] + 4] = q[3:]
    for j, name in enumerate(("ZD", "PHID", "THETAD")):
        S[S_INDEX[name]] = qd[j]
    S[S_INDEX["ZWD"]:S_INDEX["ZWD"] + 4] = qd[3:]
    return S


def mechanical_energy(vp: VehicleParams, P: np.ndarray, S: np.ndarray, zr=np.zeros(4)) -> float:
    """Kinetic plus potential energy [J] of the vertical, roll and pitch motion and the planar motion,
    relative to static equilibrium, with the road at heights ``zr`` (elastic elements only: add the
    friction terms' stored energy separately). Assumes tyre contact and no stop contact."""
    q = np.array([S[S_INDEX["Z"]], S[S_INDEX["PHI"]], S[S_INDEX["THETA"]],
                  *S[S_INDEX["ZW"]:S_INDEX["ZW"] + 4]])
    qd = np.array([S[S_INDEX["ZD"]], S[S_INDEX["PHID"]], S[S_INDEX["THETAD"]],
                   *S[S_INDEX["ZWD"]:S_INDEX["ZWD"] + 4]])
    M, K = mass_stiffness(vp)
    # tyres act on (zw - zr): shift the wheel coordinates by the road
    K_body = K.copy()
    K_body[3:, 3:] -= vp.tyre_stiffness * np.eye(4)
    e_tyre = 0.5 * vp.tyre_stiffness * float(np.sum((q[3:] - zr) ** 2))
    planar = 0.5 * vp.total_mass * S[S_INDEX["VY"]] ** 2 + 0.5 * vp.yaw_inertia * S[S_INDEX["R"]] ** 2
    return 0.5 * qd @ M @ qd + 0.5 * q @ K_body @ q + e_tyre + planar


def plate_resonance_hz(vp: VehicleParams, corner: int, f_lo: float = 4.0, f_hi: float = 25.0,
                       damping_ratio: float = 0.01, n: int = 4201) -> float:
    """Frequency [Hz] of the largest dynamic tyre force when the road under ``corner`` (0..3, FL FR RL
    RR) moves sinusoidally and the others stay still: the linear model's answer to the EUSAMA bench's
    resonance. Small stiffness-proportional damping (``damping_ratio`` at the wheel-hop modes) keeps the
    peak finite; the wheel-hop modes of one axle (in phase, and against the anti-roll bar) both respond,
    so the peak sits between their frequencies."""
    M, K = mass_stiffness(vp)
    w_hop = 2 * np.pi * modes(vp).freq_hz[3]
    beta = 2 * damping_ratio / w_hop
    kt = vp.tyre_stiffness
    rhs = np.zeros(7)
    rhs[3 + corner] = kt
    f = np.linspace(f_lo, f_hi, n)
    amp = np.empty(n)
    for j, ff in enumerate(f):
        w = 2 * np.pi * ff
        x = np.linalg.solve(K - w ** 2 * M + 1j * w * beta * K, rhs)
        amp[j] = abs(kt * (1.0 - x[3 + corner]))
    return float(f[np.argmax(amp)])
