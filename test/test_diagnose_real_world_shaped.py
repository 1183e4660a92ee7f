"""The finder on a real-world-shaped recording (issue 13, "Must show"): a drive of another car on a rough
road with no road profile in the bag, written by another tool (the rosbags library, rosbag2 directory,
sqlite3 storage) in a typical car's layout (odometry speed, CAN steering angle in degrees, an IMU mounted
forward-right-down, converted on import by ``config/topic_maps/car_odom_can_frd.yaml``), with a gyro bias
and a steering-sensor offset. The truth comes from the independent simulator, not from our model
(``docs/independent_sim.md``), with a car whose mass, inertias, wheel rates, tyre and cornering
stiffnesses differ from the parameter set by 5-15 %.

It must say that the road is not in the recording (``unmeasured_input``, with the road's ISO 8608 class),
invent no physics, and the calibration must bring the yaw rate of the held-out half of the drive to within
1.5x its noise floor.
"""
from __future__ import annotations

import numpy as np
import pytest

from _cli_helpers import cli_json
from _foreign_corpus import CAR_MAP, car_rosbags
from susp_sim_ros.analysis.discrepancy.candidates import BY_NAME, PHYSICS
from truth_generators.independent_roads import TruthManeuver
from truth_generators.independent_sim import TruthCar, TruthFriction, TruthHidden, TruthSensor, make_drive

GYRO_NOISE_DEG_S = 0.1


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("real_world_shaped")
    car = TruthCar().perturbed(np.random.default_rng(7))
    sensor = TruthSensor(imu_rate_hz=200, gyro_noise_deg_s=(GYRO_NOISE_DEG_S,) * 3,
                         gyro_bias_deg_s=(0.15, -0.1, 0.08), steering_offset_rad=0.015)
    man = TruthManeuver.rough(road_class="C", speed_kmh=80, duration_s=30, seed=3, steer="sine",
                              steer_amplitude_deg=20, steer_freq_hz=0.3)
    drive = make_drive(car, TruthFriction(), TruthHidden(), man, sensor, seed=4, record_road=False)
    bag = car_rosbags(tmp / "car_drive", drive)
    return cli_json(["diagnose", bag, "--topic-map", CAR_MAP, "--variant", "full", "--out", tmp / "report"])


def test_the_missing_road_is_named_with_its_class(report):
    assert report["verdict"] == "unmeasured_input"
    u = report["unmeasured_input"]
    assert u["kind"] == "road" and "accel_z" in u["signals"]
    assert u["iso8608_class"] in ("B", "C", "D")  # truth C; one class is a factor 4 in Gd(n0)
    assert not [t for t in report["terms"] if BY_NAME[t["name"]].kind == PHYSICS]


def test_calibration_brings_the_held_out_yaw_rate_to_the_noise(report):
    yaw = report["heldout_rmse_by_signal"]["yaw_rate"]
    floor = report["noise_floors"]["yaw_rate"]
    assert floor == pytest.approx(GYRO_NOISE_DEG_S, rel=0.10)
    assert yaw["after"] <= 1.5 * floor, (yaw, floor)
    assert yaw["after"] < 0.5 * yaw["before"]  # the gyro bias and the other car's values were calibrated
