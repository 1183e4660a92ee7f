"""The damper type's oil law in ``susp inspect`` (issue 27): a drive shows a damper's remaining force
fraction; the oil level follows from it only through how the damper type loses force with its oil, which
a rig test of a damper drained in steps gives (``--oil-law``)."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, strategies as st

from truth_generators import independent_sim as ind
from susp_sim_ros.analysis.inspection import inspect_drives
from susp_sim_ros.analysis.inspection.oil_law import OilLaw
from susp_sim_ros.errors import ConfigError

BAGS = Path(__file__).resolve().parents[1] / "bags"
RIG_OILS = tuple(float(v) for v in np.linspace(0.0, 1.0, 11))


def rig_law(friction) -> OilLaw:
    """The truth damper on a virtual rig at 0.3 m/s, drained in steps of 0.1, forces read exactly."""
    return OilLaw(*ind.damper_rig_oil_law(friction, RIG_OILS, 0.3), "test rig")


@pytest.fixture(scope="module")
def square_law_drive(tmp_path_factory):
    """A car of the independent simulator whose dampers keep the square of their oil as force fraction, FL
    half-filled, the others intact, over a 6 cm bump at 9 km/h."""
    car = ind.TruthCar().perturbed(11, 0.0, 0.05)
    friction = ind.TruthFriction(oil_law="quadratic").perturbed(12)
    drive = ind.make_drive(car, friction, None, ind.TruthManeuver.bump(speed_kmh=9.0, height_m=0.06,
                                                                       wheelbase_m=car.wheelbase),
                           ind.TruthSensor(gyro_noise_deg_s=(0.1, 0.1, 0.1)), (0.5, 1.0, 1.0, 1.0), seed=13)
    path = tmp_path_factory.mktemp("oil_law") / "square_law.mcap"
    ind.write_drive(path, drive, overwrite=True)
    return path, friction


def test_rig_law_of_the_square_law_damper_is_the_square():
    law = rig_law(ind.TruthFriction(oil_law="quadratic"))
    assert np.allclose(law.force_fraction, np.square(RIG_OILS), atol=1e-12)
    assert not law.is_model_law and rig_law(ind.TruthFriction()).is_model_law


def test_a_half_filled_square_law_damper_reads_its_force_fraction_without_its_law_and_its_oil_with_it(
        square_law_drive):
    path, friction = square_law_drive
    plain = inspect_drives([path])
    declared = inspect_drives([path], oil_law=rig_law(friction))
    # without the law the drive shows what the damper keeps: about a quarter of its force
    assert plain.wheels_["FL"]["oil_level"] == pytest.approx(0.25, abs=0.1)
    assert plain.to_json()["oil_law"]["model_law"] is True
    # read through its rig-tested law: half its oil, the interval holding it, the intact ones unchanged
    fl = declared.wheels_["FL"]
    assert fl["oil_level"] == pytest.approx(0.5, abs=0.1)
    assert fl["ci95"][0] <= 0.5 <= fl["ci95"][1] and fl["state"] in ("degraded", "unknown")
    for w in ("FR", "RL", "RR"):
        assert declared.wheels_[w]["oil_level"] == pytest.approx(plain.wheels_[w]["oil_level"], abs=0.02), w
    # the left-right difference is read in oil too: about -0.5 (left the lower), not -0.75
    front = next(e for e in declared.left_right_ if e["axle"] == "front")
    assert front["difference"] == pytest.approx(-0.5, abs=0.1) and front["ci95"][0] <= -0.5 <= front["ci95"][1]
    assert declared.to_json()["oil_law"]["source"] == "test rig"


def test_the_settings_law_is_the_model_own_unless_measured():
    law = OilLaw.from_settings({})
    assert law.is_model_law and law.level(0.37) == pytest.approx(0.37) and law.slope(0.37) == pytest.approx(1.0)
    measured = OilLaw.from_settings({"damper_type": {"oil_law": {"oil": [0, 0.5, 1], "force_fraction": [0, 0.3, 1]}}})
    assert measured.level(0.3) == pytest.approx(0.5) and not measured.is_model_law
    with pytest.raises(ConfigError, match="damper_type.oil_law"):
        OilLaw.from_settings({"damper_type": {"oil_law": [0, 1]}})


@given(st.text(max_size=40))
def test_oil_law_parser_gives_a_law_or_a_config_error(text):
    try:
        law = OilLaw.parse(text)
    except ConfigError as e:
        assert "--oil-law" in str(e)
        return
    assert law.oil[0] == 0.0 and law.oil[-1] == 1.0


@given(st.lists(st.floats(0.01, 1.0), min_size=1, max_size=8), st.lists(st.floats(0.01, 1.0), min_size=1, max_size=8))
def test_a_rising_table_reads_back_its_points_and_stays_monotone(steps_o, steps_f):
    n = min(len(steps_o), len(steps_f))
    oil = np.concatenate([[0.0], np.cumsum(steps_o[:n])]) / sum(steps_o[:n])
    frac = np.concatenate([[0.0], np.cumsum(steps_f[:n])]) / sum(steps_f[:n])
    oil[-1] = frac[-1] = 1.0
    if np.any(np.diff(oil) <= 0) or np.any(np.diff(frac) <= 0):
        return
    law = OilLaw(tuple(oil), tuple(frac), "hypothesis")
    assert [law.level(f) for f in frac] == pytest.approx(list(oil), abs=1e-9)
    grid = np.linspace(0.0, 1.0, 101)
    assert np.all(np.diff([law.level(w) for w in grid]) >= -1e-12)


def test_cli_takes_a_rig_law_and_refuses_a_falling_one(tmp_path):
    cmd = [sys.executable, "-m", "susp_sim_ros.cli.main", "inspect", str(BAGS / "bump_crossing_intact.mcap")]
    bad = subprocess.run(cmd + ["--oil-law", "0:0,0.5:0.7,0.8:0.6,1:1"], capture_output=True, text=True)
    assert bad.returncode == 2 and "--oil-law" in bad.stderr and "force fractions must rise" in bad.stderr
    ok = subprocess.run(cmd + ["--oil-law", "0:0,0.5:0.25,1:1", "--json", "--out", str(tmp_path)],
                        capture_output=True, text=True)
    assert ok.returncode == 0, ok.stderr
    out = json.loads(ok.stdout)
    assert out["oil_law"]["force_fraction"] == [0.0, 0.25, 1.0] and out["oil_law"]["model_law"] is False
    assert all(out["axles"][a]["state"] == "ok" for a in ("front", "rear"))   # intact is intact under any law
    assert "Oil law of the damper type (force fraction kept" in (tmp_path / "inspection.md").read_text()
