"""Plug-in of the inspection ROC study (``truth_generator: "truth_generators.roc:bump_crossing"``): each
car's bump crossing from the independent simulator (:mod:`.independent_sim`, not the product's model).

The study calls ``bump_crossing(draw, roc)`` with the car's draw (``values`` of the varied vehicle-file
fields, ``speed_kmh``, ``bump_height`` in m, ``gyro_noise_deg_s``, ``oil``, ``noise_seed``) and the
study's ``roc`` section, and takes ``(drive, k_after, pitch_rate_deg_s)``: the drive, the IMU sample index
once both axles have left the bump, and the measured pitch rate in deg/s.
"""
from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from . import independent_sim as ind

#: vehicle-file fields -> the independent simulator's car (TruthCar) and friction (TruthFriction) fields
TRUTH_CAR = {"sprung_mass": "sprung_mass", "unsprung_mass": "unsprung_mass", "cg_height": "cg_height",
             "roll_inertia": "roll_inertia", "pitch_inertia": "pitch_inertia", "tyre_stiffness": "tyre_stiffness",
             "wheel_rate": "wheel_rate", "arb_rate": "arb_rate"}
TRUTH_FRICTION = {"axle_friction": "axle_level", "damper_friction_intact": "damper_intact",
                  "damper_friction_empty": "damper_empty"}


def bump_crossing(draw: Mapping, roc: Mapping):
    """The car's bump crossing from the independent simulator, the car's drawn values replacing its
    defaults; same outputs as ``susp_sim_ros.analysis.inspection.roc.bump_drive``."""
    car_kw = {TRUTH_CAR[f]: v for f, v in draw["values"].items() if f in TRUTH_CAR}
    fr_kw = {TRUTH_FRICTION[f]: v for f, v in draw["values"].items() if f in TRUTH_FRICTION}
    car = ind.TruthCar(**car_kw)
    man = ind.TruthManeuver.bump(speed_kmh=draw["speed_kmh"], height_m=draw["bump_height"], wheelbase_m=car.wheelbase)
    sensor = ind.TruthSensor(imu_rate_hz=roc["imu_rate_hz"], gyro_noise_deg_s=(draw["gyro_noise_deg_s"],) * 3,
                             accel_noise_m_s2=(roc["accel_noise_m_s2"],) * 3, exact_rms=False)
    drive = ind.make_drive(car, ind.TruthFriction(**fr_kw), None, man, sensor, draw["oil"], seed=draw["noise_seed"])
    t = (drive.imu.t_ns - drive.imu.t_ns[0]) * 1e-9
    t_after = man.lead_in_s + (man.bump_length_m + car.wheelbase) / man.speed_mps
    return drive, int(np.searchsorted(t, t_after)), np.degrees(drive.imu.gyro[:, 1])
