"""``susp diagnose --wheel-loads``: the car's weighed static wheel loads pin its overall force scale (issue 24).

Drives that record motion only do not tell the car's overall force scale: every mass, inertia and rate scaled
by one factor moves the car the same, except the friction levels held in newtons. A calibration free to move
the scale makes the held friction act stronger or weaker, which can stand in for a friction effect
(benchmarks/RESULTS.md, the probe of 2026-12-06 on ``amplitude/rms_power_separate`` #3); weighed, it cannot.
"""
import subprocess
import sys

import numpy as np
import pytest

from susp_sim_ros.analysis.discrepancy import DiscrepancyFinder
from susp_sim_ros.analysis.discrepancy.calibration import CalParam, reveal_for, with_scale_rival
from susp_sim_ros.analysis.discrepancy.report import markdown
from susp_sim_ros.analysis.inspection import load_config
from susp_sim_ros.errors import SuspInputError
from susp_sim_ros.io.drive import write_drive
from truth_generators.independent_sim import (TruthCar, TruthFriction, TruthHidden, TruthManeuver, TruthSensor,
                                              make_drive)

ACCURACY = float(load_config()["wheel_loads"]["scale_accuracy"])


@pytest.fixture(scope="module")
def heavy_car_drives(tmp_path_factory):
    """A car 12 % heavier than the vehicle file in everything that scales with it (masses, inertias, rates),
    a bump crossing with the rear dampers oil-empty and a sine steer, intact."""
    tmp = tmp_path_factory.mktemp("heavy")
    base = TruthCar()
    k = 1.12
    car = TruthCar(sprung_mass=k * base.sprung_mass, roll_inertia=k * base.roll_inertia,
                   pitch_inertia=k * base.pitch_inertia, yaw_inertia=k * base.yaw_inertia)
    sensor = TruthSensor(imu_rate_hz=200, gyro_noise_deg_s=(0.05,) * 3, accel_noise_m_s2=(0.02,) * 3)
    paths = []
    for name, man, oil, seed in (("bump", TruthManeuver.bump(), (1, 1, 0, 0), 4), ("sine", TruthManeuver.sine(),
                                                                                    (1, 1, 1, 1), 5)):
        p = tmp / f"{name}.mcap"
        write_drive(p, make_drive(car, TruthFriction(), TruthHidden(), man, sensor, oil=oil, seed=seed),
                    overwrite=True)
        paths.append(p)
    return car, paths


def _mass(rep: dict) -> dict:
    return next(e for e in rep["calibration"] if e["param"] == "sprung_mass")


def test_a_weighed_car_calibrates_its_sprung_mass_at_the_scale(heavy_car_drives):
    car, paths = heavy_car_drives
    loads = car.weighed_wheel_loads(ACCURACY, seed=3)
    weighed = DiscrepancyFinder(variant="full", heldout=False, max_steps=0, wheel_loads_n=loads,
                                scale_accuracy=ACCURACY).fit(paths)
    rep = weighed.report()
    m = _mass(rep)
    total = sum(loads) / car.gravity
    assert rep["wheel_loads"]["total_mass_kg"] == pytest.approx(total)
    assert m["prior"] == pytest.approx(rep["wheel_loads"]["sprung_mass_prior_kg"])
    assert m["prior"] == pytest.approx(car.sprung_mass, rel=0.02)   # the file says 1400 kg, the car is 1568
    assert m["value"] == pytest.approx(car.sprung_mass, rel=0.03)
    assert m["ci95"][1] - m["ci95"][0] < 0.1 * car.sprung_mass
    md = markdown(weighed, rep, {"report": "r.md", "variant": "v.yaml"}, "weighed")
    assert "Weighed: static wheel loads" in md and f"{total:.0f} kg in all" in md
    plain = DiscrepancyFinder(variant="full", heldout=False, max_steps=0).fit(paths).report()
    assert "wheel_loads" not in plain and _mass(plain)["prior"] == 1400.0


def test_wheel_loads_need_the_scale_accuracy_and_a_calibration():
    with pytest.raises(SuspInputError, match="accuracy"):
        DiscrepancyFinder(wheel_loads_n=[4800.0, 4800.0, 3300.0, 3300.0])
    with pytest.raises(SuspInputError, match="does not calibrate"):
        DiscrepancyFinder(wheel_loads_n=[4800.0, 4800.0, 3300.0, 3300.0], scale_accuracy=0.01, calibrate=False)


def test_a_competing_sprung_mass_is_revealed_by_weighing_the_car():
    p = CalParam("sprung_mass", "mass.sprung", "all", None, "kg", 1400.0, 1300.0, 1600.0, "range")
    text = reveal_for(p, "intact")
    assert "weighing the car" in text and "--wheel-loads" in text
    other = CalParam("yaw_inertia", "inertia.yaw", "all", None, "kg m^2", 2500.0, 2200.0, 2800.0, "range")
    assert reveal_for(other, "intact") == "a measurement of inertia.yaw"


def test_the_cli_rejects_malformed_loads_with_exit_2(tmp_path):
    r = subprocess.run([sys.executable, "-m", "susp_sim_ros.cli.main", "diagnose", str(tmp_path / "x.mcap"),
                        "--wheel-loads", "4800,4750,-3300,3300"], capture_output=True, text=True)
    assert r.returncode == 2 and "--wheel-loads" in r.stderr and "FL,FR,RL,RR" in r.stderr
    assert np.isfinite(ACCURACY) and 0 < ACCURACY < 0.05


def _entry(name: str) -> dict:
    return {"name": name, "competes_with": ["damper_measured_empty:rear"], "reveal_with": "the damper rig",
            "why": "explains the same residual."}


def _calibration(value: float) -> list[dict]:
    return [{"param": "sprung_mass", "where": "all", "prior": 1400.0, "prior_range": [1300.0, 1600.0],
             "value": value, "informed": True}]


def test_a_term_competing_beside_a_moved_car_scale_names_the_scale_and_weighing():
    """amplitude/rms_power_separate #3 as shipped: the calibration scaled the car down (sprung mass 1000 kg
    against the file's 1400, -5.3 prior sd) and the amplitude friction was listed competing with damper values
    only; the scale is a rival of any term whose force is in newtons, and weighing the car tells it."""
    physics = {"friction_amplitude", "unlisted_force"}.__contains__
    entries = [_entry("friction_amplitude"), {"name": "time_offset", "competes_with": ["b:all"],
                                              "reveal_with": "a timing test"}]
    out = with_scale_rival(entries, _calibration(1000.0), 1.0, False, physics)
    amp = out[0]
    assert amp["competes_with"] == ["damper_measured_empty:rear", "sprung_mass:all"]
    assert "weighing the car" in amp["reveal_with"] and amp["reveal_with"].endswith("the damper rig")
    assert "1000 kg" in amp["why"] and "-5.3 prior sd" in amp["why"]
    assert out[1] == entries[1]                                      # the measurement chain as it was
    assert entries[0]["competes_with"] == ["damper_measured_empty:rear"]   # the input untouched
    # a scale within one prior sd of its prior, or a weighed car: nothing added
    assert with_scale_rival(entries, _calibration(1450.0), 1.0, False, physics) == entries
    assert with_scale_rival(entries, _calibration(1000.0), 1.0, True, physics) == entries
