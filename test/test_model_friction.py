"""Friction: Dahl element shape and saturation, the paper's rig values, variants, scalings."""
import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from susp_sim_ros.model.rigs import axle_rig, damper_rig, half_hysteresis_at_zero, triangle
from susp_sim_ros.model.terms import dahl_exact
from susp_sim_ros.model.vehicle import hydraulic_curves, velocity_scaling


def test_dahl_virgin_curve_is_exact():
    """From F = 0 over a monotone path x: F = Fc (1 - exp(-sigma x / Fc)), independent of step size."""
    fc, sigma = 40.0, 1e5
    for n in (1, 10, 1000):
        f = 0.0
        for _ in range(n):
            f = dahl_exact(f, fc, sigma, 1e-3 / n)
        np.testing.assert_allclose(f, fc * (1 - math.exp(-sigma * 1e-3 / fc)), rtol=1e-12)


@given(f0=st.floats(-100, 100), level=st.floats(0.1, 100), dx=st.floats(-0.01, 0.01),
       sigma=st.floats(1e3, 1e7))
@settings(max_examples=500, deadline=None)
def test_dahl_never_exceeds_level_and_moves_toward_sliding_direction(f0, level, dx, sigma):
    f = dahl_exact(f0, level, sigma, dx)
    assert -level <= f <= level
    start = min(max(f0, -level), level)
    if dx > 0:
        assert f >= start
    elif dx < 0:
        assert f <= start


def test_dahl_hysteresis_loop_half_width_is_level():
    d = triangle(0.005, 1e-5, 2)
    f = np.zeros_like(d)
    for k in range(1, d.size):
        f[k] = dahl_exact(f[k - 1], 30.0, 1e5, d[k] - d[k - 1])
    np.testing.assert_allclose(half_hysteresis_at_zero(d, f), 30.0, rtol=1e-6)


# (rig, axle, kwargs, paper value [N]); paper numbers and the assumed Fig. 4 scalings (model-spec 5)
RIG_CASES = [
    ("axle", "front", {}, 60.0), ("axle", "rear", {}, 43.0),
    ("damper", "front", {"oil_level": 1.0}, 22.0), ("damper", "front", {"oil_level": 0.0}, 29.0),
    ("damper", "rear", {"oil_level": 1.0}, 10.0), ("damper", "rear", {"oil_level": 0.0}, 20.0),
    ("axle", "front", {"fy": 1000.0}, 75.0), ("axle", "rear", {"fy": 1000.0}, 55.9),
    ("axle", "front", {"fx": 1000.0}, 69.0), ("axle", "rear", {"fx": 1000.0}, 43.0),
]


@pytest.mark.parametrize("rig,axle,kw,paper", RIG_CASES)
def test_rigs_reproduce_paper_values(model_full, rig, axle, kw, paper):
    fn = axle_rig if rig == "axle" else damper_rig
    got = fn(model_full, axle, **kw).half_hysteresis_N
    np.testing.assert_allclose(got, paper, rtol=0.02)


def test_damper_rig_force_velocity_reproduces_measured_curve(model_full):
    """Hydraulic curve + modelled damper friction = the measured curve it was derived from."""
    vp = model_full.vehicle
    for axle, k in (("front", 0), ("rear", 1)):
        for oil, measured in ((1.0, vp.damper_measured_intact), (0.0, vp.damper_measured_empty)):
            fv = np.array(damper_rig(model_full, axle, oil).force_velocity)
            expect = np.interp(fv[:, 0], vp.damper_velocity, measured[k])
            # the sine rig reads the force at the peak velocity after a +-25 mm stroke; Dahl is saturated
            np.testing.assert_allclose(fv[:, 1], expect, rtol=0.02, atol=0.5, err_msg=f"{axle} oil {oil}")
    assert len(fv) == 34, "17 peak velocities in both directions"


def test_hydraulic_curve_is_measured_minus_friction_and_zero_at_creep(model_full):
    vp = model_full.vehicle
    from susp_sim_ros.model.layout import DAMPER_GRID
    h_int, h_emp = hydraulic_curves(vp)
    assert np.all(h_int[:, np.abs(DAMPER_GRID) <= 0.001] == 0.0)
    assert np.all(np.sign(h_int) * np.sign(DAMPER_GRID) >= 0) and np.all(np.sign(h_emp) * np.sign(DAMPER_GRID) >= 0)
    i = int(np.argmin(np.abs(DAMPER_GRID - 0.052)))
    fric = vp.damper_friction_intact[0] * velocity_scaling(vp, np.array([0.052]))[0]
    np.testing.assert_allclose(h_int[0, i], 250.0 - fric, rtol=1e-9)


def test_velocity_scaling_is_one_at_reference_and_monotone(model_full):
    vp = model_full.vehicle
    v = np.linspace(0, 1, 2001)
    s = velocity_scaling(vp, v)
    assert s[v <= vp.sv_reference].max() == 1.0
    assert np.all(np.diff(s) >= 0)
    assert s[-1] == pytest.approx(vp.sv_plateau, rel=1e-6)
    assert velocity_scaling(vp, np.array([0.052]))[0] > 1.5, "paper: much higher at 0.052 m/s"


def test_every_variant_switches_its_scaling(models):
    full, no_h, no_v, dahl = (models[k] for k in ("full", "no_horizontal", "no_velocity", "dahl_only"))
    # horizontal force scaling
    assert axle_rig(full, "front", fy=1000).half_hysteresis_N == pytest.approx(75.0, rel=0.01)
    assert axle_rig(no_h, "front", fy=1000).half_hysteresis_N == pytest.approx(60.0, rel=0.01)
    assert axle_rig(dahl, "front", fy=1000).half_hysteresis_N == pytest.approx(60.0, rel=0.01)
    # oil scaling: dahl_only keeps the nominal (intact) level
    assert damper_rig(dahl, "rear", 0.0).half_hysteresis_N == pytest.approx(10.0, rel=0.01)
    assert damper_rig(no_v, "rear", 0.0).half_hysteresis_N == pytest.approx(20.0, rel=0.01)
    # velocity scaling: the force at 0.052 m/s holds the scaled friction only with it
    f = lambda m: dict(map(tuple, damper_rig(m, "rear", 0.0).force_velocity))[0.052]
    assert f(full) - f(no_v) == pytest.approx(20.0 * (velocity_scaling(full.vehicle, np.array([0.052]))[0] - 1),
                                              rel=0.02)
    assert f(no_h) == pytest.approx(f(full), rel=1e-9)
