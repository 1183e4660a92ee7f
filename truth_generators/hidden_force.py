"""Truth drives whose hidden force is exposed: the yardstick of the missing-force estimate (issue 26).

A drive is simulated twice on the product's kernel: the *truth* carries an axle friction element the
*model* lacks (axle friction level 0 there). The hidden force is the truth's own friction output, known
exactly at every step. Both share a damper friction of 1 N per corner, so the hidden force is the axle
element's within 1 N (the same Dahl element on the same deflection history gives the same force).

This is model-made truth: it shares the model's structure everywhere but the hidden element, so it tests
the estimator's mechanics (the error dynamics, the filter, the loops), not robustness to structure the
model lacks; the independent simulator (:mod:`.independent_sim`) and the generator family of issue 24
are the yardsticks for that.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from susp_sim_ros.model import load_variant, load_vehicle
from susp_sim_ros.model.maneuvers import build_maneuver
from susp_sim_ros.model.vehicle import Model, simulate

#: model step [s]
DT = 0.001
#: IMU sample interval [s] (200 Hz, as the bundled drives)
IMU_DT = 0.005
#: gyro [rad/s] and accelerometer [m/s^2] noise sd, the bundled drives' order
SIGMA = np.array([np.deg2rad(0.04), np.deg2rad(0.04), 0.02])
#: a Dahl stiffness [N/m] that slides within 0.1 mm: a loop of the element's full height
SATURATING_DAHL = 2.0e6
#: damper friction [N] both share (small: the hidden force is then the axle element's)
SHARED_DAMPER_FRICTION = 1.0
_WHEELS = ("FL", "FR", "RL", "RR")
_IMU = ("ROLL_RATE", "PITCH_RATE", "AZ_SF")
_CORNER = ("DEFL", "DEFL_VEL", "F_DAMPER", "F_FRICTION")
_OUTPUTS = list(_IMU) + [f"{o}_{w}" for o in _CORNER for w in _WHEELS]


@dataclass
class HiddenForceDrive:
    """One truth drive: IMU sample times ``t_imu`` [s], the measured IMU signals ``measured`` (n, 3: roll
    rate, pitch rate [rad/s], vertical specific force [m/s^2], noise ``sigma`` added) and what the model
    simulates there ``simulated``; at the model steps ``t`` [s]: the hidden force per corner
    ``hidden`` (n_steps, 4) [N, positive up on the body] and the truth's deflection velocity
    ``truth_velocity`` (n_steps, 4) [m/s]; the model's own corner series ``model_corner`` {DEFL,
    DEFL_VEL, F_DAMPER, F_FRICTION: (n_steps, 4)}, its vehicle ``model_vehicle`` and parameter row ``P``."""

    t_imu: np.ndarray
    measured: np.ndarray
    simulated: np.ndarray
    sigma: np.ndarray
    t: np.ndarray
    hidden: np.ndarray
    truth_velocity: np.ndarray
    model_corner: dict
    model_vehicle: object
    P: np.ndarray


def hidden_axle_friction(maneuver: str = "bump_crossing", level_n: float = 150.0,
                         oil=(1.0, 1.0, 0.0, 0.0), seed: int = 0) -> HiddenForceDrive:
    """A drive of ``maneuver`` with ``oil`` levels (FL FR RL RR) whose truth hides an axle friction
    element of ``level_n`` [N] per corner (saturating Dahl stiffness), IMU noise of seed ``seed``."""
    vp = load_vehicle().replace(damper_friction_intact=(SHARED_DAMPER_FRICTION,) * 2,
                                damper_friction_empty=(SHARED_DAMPER_FRICTION,) * 2)
    truth_vp = vp.replace(axle_friction=(level_n, level_n), dahl_stiffness=SATURATING_DAHL)
    model_vp = vp.replace(axle_friction=(0.0, 0.0))
    variant = load_variant("dahl_only")
    man = build_maneuver(maneuver, vp.wheelbase)
    oil = np.asarray(oil, float)
    U = man.to_inputs(DT)
    truth = simulate(Model(truth_vp, variant), U, dt=DT, road=man.road, oil=oil, outputs=_OUTPUTS).values
    model_m = Model(model_vp, variant)
    sim = simulate(model_m, U, dt=DT, road=man.road, oil=oil, outputs=_OUTPUTS).values
    t = DT * np.arange(1, len(truth) + 1)
    ti = np.arange(IMU_DT, t[-1], IMU_DT)
    rng = np.random.default_rng(seed)
    at = lambda Y: np.column_stack([np.interp(ti, t, Y[:, j]) for j in range(len(_IMU))])  
    corner = {o: sim[:, 3 + 4 * k:7 + 4 * k] for k, o in enumerate(_CORNER)}
    return HiddenForceDrive(ti, at(truth) + rng.normal(size=(ti.size, 3)) * SIGMA, at(sim), SIGMA.copy(), t,
                            truth[:, 3 + 12:3 + 16], truth[:, 3 + 4:3 + 8], corner, model_vp,
                            model_m.params(oil))
