"""``susp inspect --wheel-loads``: the car's weighed static wheel loads pin its mass (issue 27).

A bump crossing seen by a body IMU tells the car's ratios (spring rate and damping to mass) but hardly its
overall scale: a car heavier than the vehicle file read against the file's mass reads its intact dampers
weak by about the mass ratio (benchmarks/RESULTS.md, "Damper inspection over the truth-generator family").
"""
import subprocess
import sys

import numpy as np
import pytest

from susp_sim_ros.analysis.discrepancy.calibration import CalParam
from susp_sim_ros.analysis.inspection import inspect_drives, load_config
from susp_sim_ros.analysis.inspection.report import write_inspection_report
from susp_sim_ros.analysis.discrepancy.calibration import sprung_mass_from_wheel_loads
from susp_sim_ros.errors import ConfigError
from truth_generators import family
from truth_generators.independent_sim import truth_car_of
from susp_sim_ros.io.drive import write_drive

G = 9.81


def _cal():
    return [CalParam("sprung_mass", "mass.sprung", "all", None, "kg", 1400.0, 1300.0, 1600.0, "range"),
            CalParam("unsprung_mass", "mass.unsprung", "front", 0, "kg", 45.0, 38.0, 52.0, "range"),
            CalParam("unsprung_mass", "mass.unsprung", "rear", 1, "kg", 40.0, 34.0, 46.0, "range"),
            CalParam("wheel_rate", "suspension.wheel_rate", "front", 0, "N/m", 28000.0, 25000.0, 31000.0, "r")]


def test_the_sprung_mass_prior_comes_from_the_weighed_loads():
    loads = [4800.0, 4750.0, 3300.0, 3350.0]
    cal, entry = sprung_mass_from_wheel_loads(_cal(), loads, G, 0.01)
    sm = cal[0]
    total = sum(loads) / G
    assert entry["total_mass_kg"] == pytest.approx(total)
    assert sm.prior == pytest.approx(total - 2 * 45.0 - 2 * 40.0)
    # sd: the scale's error per wheel and the four unsprung masses' priors (range = +-2 sd)
    sd = np.sqrt((0.01 * np.sqrt(np.sum(np.square(loads))) / G) ** 2 + 4 * 3.5 ** 2 + 4 * 3.0 ** 2)
    assert sm.sd == pytest.approx(sd)
    assert sm.sd < 0.2 * _cal()[0].sd                       # far tighter than the vehicle file's range
    assert cal[1:] == _cal()[1:]                            # nothing else changes
    assert entry["front_share"] == pytest.approx(9550.0 / sum(loads))


@pytest.mark.parametrize("loads", [[4800.0, 4750.0, 3300.0], [4800.0, -1.0, 3300.0, 3300.0],
                                   [4800.0, float("nan"), 3300.0, 3300.0], [480.0, 475.0, 330.0, 335.0]])
def test_loads_that_are_not_a_cars_static_loads_are_a_named_error(loads):
    with pytest.raises(ConfigError, match="wheel loads"):
        sprung_mass_from_wheel_loads(_cal(), loads, G, 0.01)


def test_the_cli_rejects_malformed_loads_with_exit_2(tmp_path):
    r = subprocess.run([sys.executable, "-m", "susp_sim_ros.cli.main", "inspect", str(tmp_path / "x.mcap"),
                        "--wheel-loads", "4800,4750,3300"], capture_output=True, text=True)
    assert r.returncode == 2 and "--wheel-loads" in r.stderr and "FL,FR,RL,RR" in r.stderr


def test_a_heavy_car_weighed_reads_its_intact_dampers_intact(tmp_path):
    """A development-form car 14 % heavier than the vehicle file (1594 kg sprung), intact, 9 km/h over a
    4.4 cm bump: without its weight the fit keeps the mass near the file's and reads the dampers about
    0.88; weighed, within 0.07 of intact and the sprung mass within 2 % of the truth's."""
    drive = family.bump_crossing(family.FORMS["structure/velocity_scaling_ramp"], 7010, (1.0, 1.0, 1.0, 1.0),
                                 9.0, 0.044, gyro_noise_deg_s=0.1, car_band="within", friction_dev_N=2.0)
    car = truth_car_of(drive)
    path = tmp_path / "heavy.mcap"
    write_drive(path, drive, overwrite=True)
    front, _, rear, _ = car.static_wheel_loads()
    assert car.sprung_mass > 1.1 * 1400.0

    plain = inspect_drives([path])
    weighed = inspect_drives([path], wheel_loads_n=[front * 1.01, front * 0.99, rear * 1.005, rear * 0.995])
    low = [w["oil_level"] for w in plain.wheels_.values()]
    read = [w["oil_level"] for w in weighed.wheels_.values()]
    assert max(low) < 0.92                                  # the scale ridge: read weak by about the mass ratio
    assert min(read) > 0.93 and min(read) > max(low)
    mass = {n["param"]: n["value"] for n in weighed.nuisance_}["sprung_mass"]
    assert mass == pytest.approx(car.sprung_mass, rel=0.02)
    assert weighed.to_json()["wheel_loads"]["total_mass_kg"] == pytest.approx(
        (2 * front + 2 * rear) / G, rel=0.01)
    md = open(write_inspection_report(weighed, tmp_path / "out", load_config(), [path])["report"]).read()
    assert "Weighed: static wheel loads" in md and f"{weighed.wheel_loads_['total_mass_kg']:.0f} kg in all" in md
