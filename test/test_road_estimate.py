"""The road of a drive that did not record it, estimated from the body motion (analysis/discrepancy/
road_estimate.py), against the true road of the independent simulator (not our model: another integrator,
another car 5-15 % off, its own road generator with left/right coherence; docs/independent_sim.md)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy import signal as sps

from susp_sim_ros.analysis.discrepancy import DiscrepancyFinder
from susp_sim_ros.analysis.discrepancy.data import has_road_input, load_cases
from susp_sim_ros.analysis.discrepancy.report import write_outputs
from truth_generators.independent_sim import (TruthCar, TruthFriction, TruthHidden, TruthManeuver,
                                                   TruthSensor, make_drive)
from susp_sim_ros.io.drive import read_drive, write_drive


@pytest.fixture(scope="module")
def rough_fit(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("rough")
    car = TruthCar().perturbed(np.random.default_rng(5))
    sensor = TruthSensor(imu_rate_hz=200, gyro_noise_deg_s=(0.1,) * 3, gyro_bias_deg_s=(0.1, -0.1, 0.05))
    man = TruthManeuver.rough(road_class="C", speed_kmh=80, duration_s=20, seed=2, steer="sine",
                              steer_amplitude_deg=20, steer_freq_hz=0.3)
    p = tmp / "rough_no_profile.mcap"
    write_drive(p, make_drive(car, TruthFriction(), TruthHidden(), man, sensor, seed=1, record_road=False))
    f = DiscrepancyFinder(variant="full", heldout=False, max_steps=0, calibrate=False).fit([p])
    return f, man.road(car.wheelbase), tmp


def _band(z, s, speed, band_hz=(0.5, 20.0)):
    """``z`` (on the path ``s``) band-passed to the estimation band, in time at ``speed``."""
    fs = 1.0 / float(np.median(np.diff(s)))
    b, a = sps.butter(2, [band_hz[0] / speed, band_hz[1] / speed], btype="band", fs=fs)
    return sps.filtfilt(b, a, z)


def test_the_estimated_road_follows_the_true_one(rough_fit):
    f, (s_true, zl_true, zr_true), _ = rough_fit
    u = f.report()["unmeasured_input"]
    name = u["drives"][0]
    road = f.estimated_roads_[name]
    est = u["road_estimates"][name]
    speed = f.unmeasured_[0]["mean_speed_m_s"]
    inner = slice(road.s.size // 10, -road.s.size // 10)  # away from the drive's ends (tapers)
    for z_est, z_true in ((road.zl, zl_true), (road.zr, zr_true)):
        t = _band(np.interp(road.s, s_true, z_true), road.s, speed)[inner]
        e = _band(z_est, road.s, speed)[inner]
        assert np.corrcoef(t, e)[0, 1] > 0.8  # measured 0.92 / 0.90
        assert np.std(e) == pytest.approx(np.std(t), rel=0.25)  # the road's roughness, not the noise's
    # the estimated road explains most of the vertical motion the flat road left
    for sig, flat in est["rmse_flat_road"].items():
        assert est["rmse_estimated_road"][sig] < 0.6 * flat, sig
    # and the vertical specific force, which the gyro-only estimate never saw, is predicted too
    cc = est["cross_check"]
    assert cc["estimated_from"] == ["pitch_rate", "roll_rate"]
    assert cc["rmse_estimated_road"]["accel_z"] < 0.75 * cc["rmse_flat_road"]["accel_z"]


def test_the_drive_is_written_again_with_its_estimated_road(rough_fit):
    f, _, tmp = rough_fit
    paths = write_outputs(f, tmp / "out", "diag", plots=False)
    (p,) = paths["estimated_roads"]
    d = read_drive(p)
    road = f.estimated_roads_[f.cases_[0].name]
    np.testing.assert_allclose(d.road.s, road.s)
    np.testing.assert_allclose(d.road.zl, road.zl)
    assert "estimated" in d.metadata["road_source"]
    (case,) = load_cases([p], wheelbase=f.model_.vehicle.wheelbase)
    assert has_road_input(case)
    assert "Road estimated from the body motion" in (tmp / "out" / "diag.md").read_text()
