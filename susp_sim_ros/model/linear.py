"""Linearised vertical dynamics: the exact reference the nonlinear kernel is checked against.

Seven degrees of freedom ``q = [z, phi, theta, zw_FL, zw_FR, zw_RL, zw_RR]`` around static equilibrium,
with friction, dampers and tyre damping off: ``M q'' + K q = 0``. ``K`` holds the wheel-rate springs,
anti-roll bars, tyres and the destabilising gravity terms of the roll and pitch equations
(model-spec 2). Heave and pitch are coupled when a*k_f != b*k_r.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .layout import S_INDEX
from .params import VehicleParams


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


def mass_stiffness(vp: VehicleParams) -> tuple[np.ndarray, np.ndarray]:
    x = np.array([vp.a, vp.a, -vp.b, -vp.b])
    tf, tr = vp.track
    y = np.array([tf / 2, -tf / 2, tr / 2, -tr / 2])
    k = np.array([vp.wheel_rate[0]] * 2 + [vp.wheel_rate[1]] * 2)
    mu = np.array([vp.unsprung_mass[0]] * 2 + [vp.unsprung_mass[1]] * 2)
    M = np.diag([vp.sprung_mass, vp.roll_inertia, vp.pitch_inertia, *mu])
    # deflection d = D q with d_i = zw_i - z + x_i theta - y_i phi
    D = np.zeros((4, 7))
    D[:, 0] = -1.0
    D[:, 1] = -y
    D[:, 2] = x
    D[:, 3:] = np.eye(4)
    K = D.T @ np.diag(k) @ D
    for axle, (l, r) in enumerate(((0, 1), (2, 3))):  # anti-roll bar on d_l - d_r
        e = D[l] - D[r]
        K += vp.arb_rate[axle] * np.outer(e, e)
    K[3:, 3:] += vp.tyre_stiffness * np.eye(4)
    g, ms = vp.gravity, vp.sprung_mass
    K[1, 1] -= ms * g * (vp.cg_height - 0.5 * sum(vp.roll_centre_height))
    K[2, 2] -= ms * g * (vp.cg_height - vp.pitch_centre_height)
    return M, K


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
