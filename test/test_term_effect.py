"""A named term's effect as a whole with its 95 % interval (issue 24, item 3; analysis/discrepancy/effect.py)."""
import math
from types import SimpleNamespace

import numpy as np
import pytest

from susp_sim_ros.analysis.discrepancy import finder as fm
from susp_sim_ros.analysis.discrepancy.effect import (DATA, HELD_AT_FILE, HELD_FREE, TermEffect, covariance_held_free,
                                                      term_effect)
from susp_sim_ros.analysis.discrepancy.engine import Structure


def _linear_case(rho: float, n: int = 400, seed: int = 0, theta_true=(0.05, 0.05)):
    """A linear model y = J theta + noise whose two columns correlate by ``rho``, fitted by least squares:
    the residual change with the term at neutral, the Jacobian, the posterior covariance, the estimate."""
    rng = np.random.default_rng(seed)
    a = rng.normal(size=n)
    b = rho * a + np.sqrt(1 - rho ** 2) * rng.normal(size=n)
    J = -np.column_stack([a, b])                         # residual = measured - model: dr/dtheta = -column
    theta_true = np.asarray(theta_true, float)
    y = -J @ theta_true + rng.normal(size=n)
    theta = np.linalg.lstsq(-J, y, rcond=None)[0]
    r_fit = y + J @ theta
    r_neutral = y.copy()
    cov = np.linalg.inv(J.T @ J)
    return r_neutral - r_fit, J, cov, theta


def test_marginal_intervals_holding_zero_do_not_hide_an_effect_the_drives_pin():
    """Two coefficients whose effects on the drives are nearly the same (correlation 0.995), so they trade
    against each other: each one's marginal interval holds zero, the force they add together does not
    (the viscous front and rear coefficients beside the calibrated damper factors)."""
    e, J, cov, theta = _linear_case(0.995, theta_true=(0.1, 0.1))
    se = np.sqrt(np.diag(cov))
    assert np.all(np.abs(theta) < 1.96 * se)                          # marginally "nothing"
    eff = term_effect(e, J, cov, None, None, theta)
    lo, hi = eff.ci95_fraction(DATA)
    assert lo > 0.5 and hi < 1.5
    # the size is what the term changes in the residual, and its linearised sd the posterior's along it
    assert eff.size == pytest.approx(np.linalg.norm(J @ theta))
    g = J.T @ (J @ theta) / eff.size
    assert eff.sd_data == pytest.approx(np.sqrt(g @ cov @ g))


def test_an_effect_within_the_noise_holds_zero():
    """A term fitted to noise alone: its effect's interval holds zero (a finding that may be nothing)."""
    rng = np.random.default_rng(3)
    J = -rng.normal(size=(400, 2))
    y = rng.normal(size=400)
    theta = np.linalg.lstsq(-J, y, rcond=None)[0]
    eff = term_effect(J @ theta, J, np.linalg.inv(J.T @ J), None, None, theta)
    assert eff.holds_zero(DATA)


def test_covariance_with_the_held_values_free_is_the_marginal_block_and_never_narrower():
    rng = np.random.default_rng(1)
    J = rng.normal(size=(300, 3)) * np.array([1e-3, 1.0, 1e3])        # parameters of very different units
    Jh = rng.normal(size=(300, 2)) * np.array([10.0, 0.1]) + 500.0 * J[:, [0]]
    H = 0.5 * J.T @ J
    sd = np.array([0.05, 2.0])
    full = np.block([[H, 0.5 * J.T @ Jh], [0.5 * Jh.T @ J, 0.5 * Jh.T @ Jh + np.diag(sd ** -2)]])
    C = covariance_held_free(H, J, Jh, sd, 0.5)
    np.testing.assert_allclose(C, np.linalg.inv(full)[:3, :3], rtol=1e-6)
    assert np.all(np.diag(C) >= np.diag(np.linalg.inv(H)) * (1 - 1e-9))


def test_a_held_value_that_does_what_the_term_does_makes_the_effect_unidentifiable():
    """A held value whose effect on the drives is the term's own (collinear Jacobian) with a wide prior:
    from the data alone the effect is pinned, with the held value free within its prior it is not."""
    e, J, cov, theta = _linear_case(0.0)
    H = J.T @ J
    Jh = J @ np.array([1.0, 1.0])[:, None]                           # the held value moves both at once
    C = covariance_held_free(H, J, Jh, np.array([1.0]), 1.0)
    eff = term_effect(e, J, cov, None, None, theta, cov_held_free=C)
    assert not eff.holds_zero(DATA)
    assert eff.holds_zero(HELD_FREE)
    # a narrow prior on the held value (it is known): the effect is pinned again
    C = covariance_held_free(H, J, Jh, np.array([1e-4]), 1.0)
    assert not term_effect(e, J, cov, None, None, theta, cov_held_free=C).holds_zero(HELD_FREE)


def test_drive_to_drive_spread_widens_the_interval():
    """Leave-one-drive-out refits that scatter the term along its effect widen the interval (the larger
    of the posterior's and the jackknife's), as for the parameters' intervals."""
    e, J, cov, theta = _linear_case(0.0)
    tight = term_effect(e, J, cov, None, theta[None] + np.zeros((6, 2)), theta)
    assert tight.sd(DATA) == pytest.approx(tight.sd_data)
    refits = theta[None] + np.outer([1, -1, 1, -1, 1, -1], theta)   # each refit doubles or removes the term
    wide = term_effect(e, J, cov, None, refits, theta)
    assert wide.sd_jackknife > wide.sd_data and wide.holds_zero(DATA)


def test_held_values_at_their_file_value_add_their_consider_variance():
    e, J, cov, theta = _linear_case(0.0)
    cons = np.array([[0.03, 0.0], [0.03, 0.001]])                   # per held value: parameter shift per sd
    eff = term_effect(e, J, cov, cons, None, theta)
    g = J.T @ e / eff.size * -1.0
    assert eff.sd_consider == pytest.approx(np.linalg.norm(g @ cons))
    assert eff.held_share[0] > eff.held_share[1]
    assert eff.sd(HELD_AT_FILE) == pytest.approx(np.hypot(eff.sd_data, eff.sd_consider))


def _finder_with(effects: dict) -> fm.DiscrepancyFinder:
    st = Structure(["extra_viscous_damping", "friction_amplitude", "time_offset"])
    f = fm.DiscrepancyFinder()
    f.result_ = SimpleNamespace(structure=st, x=np.r_[120.0, 80.0, 1.0, 30.0, 30.0, 0.005, 1.0, 0.0, 0.001])
    f.consider_names_ = ["a:all", "b:all", "tyre_damping:front"]
    f.consider_keys_ = ["geometry.a", "geometry.b", "tyre_damping (front)"]
    f.term_effects_ = lambda: effects  # type: ignore[method-assign]
    return f


def test_physics_terms_are_judged_on_their_effect():
    """Issue 24 item 3: a physics term whose effect's interval from the data alone holds zero is dropped;
    one whose interval holds zero once the held values are free in their priors is dropped too and listed
    as competing with the held values that bring most of its variance, with the measurement that separates
    them; one whose interval excludes zero stays."""
    pinned = TermEffect(300.0, 20.0, 30.0, 25.0, 40.0, (1.0, 0.5, 0.0))
    loose = TermEffect(100.0, 60.0, 30.0, 10.0, 70.0, ())
    rival = TermEffect(300.0, 20.0, 500.0, 25.0, 200.0, (9.0, 1.0, 0.01))
    f = _finder_with({"extra_viscous_damping": pinned, "friction_amplitude": loose})
    drop, competing, why = f._judge_physics_terms()
    assert drop == ["friction_amplitude"] and competing == []
    # two terms that stand in for each other: only the weaker goes (the other is judged again after the refit)
    weaker = TermEffect(100.0, 80.0, 30.0, 10.0, 90.0, ())
    drop, _, _ = _finder_with({"extra_viscous_damping": loose, "friction_amplitude": weaker})._judge_physics_terms()
    assert drop == ["friction_amplitude"]
    # a failed simulation (not a number) is no evidence of an effect
    nan = TermEffect(math.nan, math.nan, math.nan, math.nan, math.nan, ())
    assert nan.holds_zero(DATA)
    assert _finder_with({"extra_viscous_damping": nan, "friction_amplitude": pinned})._judge_physics_terms()[0] \
        == ["extra_viscous_damping"]
    assert "holds no effect" in why["friction_amplitude"]
    f = _finder_with({"extra_viscous_damping": rival, "friction_amplitude": pinned})
    drop, competing, why = f._judge_physics_terms()
    assert drop == ["extra_viscous_damping"] and [c["name"] for c in competing] == ["extra_viscous_damping"]
    c = competing[0]
    assert c["competes_with"] == ["a:all"] and "geometry.a" in c["reveal_with"]
    assert c["value"] == {"c_front": 120.0, "c_rear": 80.0, "exponent": 1.0}
    assert c["effect"]["ci95_fraction"][0] <= 0.0 < c["effect"]["ci95_fraction_data"][0]


def test_a_term_not_named_on_its_effect_is_said_in_the_verdict():
    """A term dropped because its effect may be nothing is not named, and an unexplained remainder's reason
    says it was tried and why (a user sees what the finder saw), and so does a "nothing missing" within the
    structure level."""
    from susp_sim_ros.analysis.discrepancy.report import structure_level, verdict
    n = 1000
    rms = structure_level() * 1.1
    f = SimpleNamespace(result_=SimpleNamespace(structure=SimpleNamespace(names=("calibration",)), rss=rms ** 2 * n,
                                                n=n),
                        base_fit_=SimpleNamespace(rss=6.0 ** 2 * n, n=n), windows_=[{}], heldout_=None,
                        unmeasured_=[], competing_=[],
                        effect_dropped_=[{"name": "extra_viscous_damping",
                                          "why": "the 95 % interval of its effect ... holds no effect: not named"}])
    v, why = verdict(f)
    assert v == "unexplained_residual"
    assert "tried and not named: extra_viscous_damping (the 95 % interval" in why
    # within the structure level too: "nothing is missing" says what was tried beside it
    f.result_.rss = (structure_level() * 0.9) ** 2 * n
    v, why = verdict(f)
    assert v == "no_significant_discrepancy" and "nothing is missing" in why
    assert "tried and not named: extra_viscous_damping (the 95 % interval" in why
    f.effect_dropped_ = []
    assert "tried" not in verdict(f)[1]
    f.result_.rss = rms ** 2 * n
    assert "tried" not in verdict(f)[1]
