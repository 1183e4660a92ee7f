"""The likelihood that knows the model is imperfect (issue 24, item 2): the discrepancy finder counts the
samples of a colored residual at their effective number (Bartlett's correlation samples of the
calibrated residual, ``analysis/discrepancy/fit.py``), so a smooth misfit buys no evidence that white
noise of the same size would."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from _series import ar1
from susp_sim_ros.analysis.discrepancy.finder import MIN_DELTA_BIC
from susp_sim_ros.analysis.discrepancy.fit import (T_CORR_S, bic, correlation_samples,
                                                   learn_residual_correlation, n_effective)

N = 2000
DT = T_CORR_S  # one grid step per T_CORR_S: the bound leaves every white sample independent


def _evaluator(n: int = N, dt: float = DT) -> SimpleNamespace:
    """The slice of an Evaluator the sample count reads: one drive, one signal, every sample compared."""
    case = SimpleNamespace(t_grid_s=np.arange(n) * dt, y_meas=np.zeros((n, 1)))
    return SimpleNamespace(cases=[case], weights=[np.ones((n, 1))], corr_samples={})


def _delta_bic(y: np.ndarray, f: np.ndarray, learn: bool) -> tuple[float, float]:
    """Criterion gain of the one-parameter term ``b f`` on the residual ``y`` (the calibrated model's), with
    the sample count learnt from ``y`` or fixed; and the fitted effect ``b``."""
    ev = _evaluator(y.size)
    if learn:
        learn_residual_correlation(ev, SimpleNamespace(idx=(0,), residual=y))
    ne = n_effective(ev, [0])
    b = float(f @ y / (f @ f))
    r1 = y - b * f
    return bic(float(y @ y), y.size, 0, ne) - bic(float(r1 @ r1), y.size, 1, ne), b


def test_correlation_samples_of_white_noise_an_ar1_process_and_a_ring_out():
    rng = np.random.default_rng(1)
    assert abs(correlation_samples(rng.standard_normal(20000)) - 1.0) < 0.15
    phi = 0.9
    tau = correlation_samples(ar1(rng, 20000, phi))
    assert abs(tau / ((1 + phi * phi) / (1 - phi * phi)) - 1.0) < 0.15, tau
    # a lightly damped 1.3 Hz mode at 100 Hz (AR(2)): its plain autocorrelation sum nearly cancels,
    # the squared one counts the ring-out's length
    r, w = 0.99, 2 * np.pi * 1.3 / 100
    e = rng.standard_normal(20000)
    x = np.zeros_like(e)
    for i in range(2, x.size):
        x[i] = 2 * r * np.cos(w) * x[i - 1] - r * r * x[i - 2] + e[i]
    assert correlation_samples(x) > 30


def test_a_colored_residual_does_not_name_a_term_that_white_noise_would():
    """Per seed: a smooth feature fitted to a smooth residual (AR(1), phi 0.98) with no term in it; then the
    same fitted effect under white noise of the same variance. Wherever white noise names the effect (as it
    should: it is real there), the colored residual, counted at its effective size, does not; counted at
    every sample, it would (the test can fail)."""
    named_white, named_colored, named_naive = 0, 0, 0
    for seed in range(60):
        rng = np.random.default_rng(seed)
        f, colored = ar1(rng, N, 0.98), ar1(rng, N, 0.98)
        d_colored, b = _delta_bic(colored, f, learn=True)
        d_naive, _ = _delta_bic(colored, f, learn=False)
        d_white, _ = _delta_bic(b * f + rng.standard_normal(N), f, learn=True)
        if d_white >= MIN_DELTA_BIC:
            named_white += 1
            named_colored += d_colored >= MIN_DELTA_BIC
            named_naive += d_naive >= MIN_DELTA_BIC
    assert named_white >= 25, named_white
    assert named_colored == 0
    assert named_naive >= 0.8 * named_white  # without the effective count the smooth residual names it


def test_white_residual_keeps_one_sample_per_bound_and_colored_counts_fewer():
    rng = np.random.default_rng(3)
    ev = _evaluator()
    learn_residual_correlation(ev, SimpleNamespace(idx=(0,), residual=rng.standard_normal(N)))
    assert n_effective(ev, [0]) > 0.85 * N
    learn_residual_correlation(ev, SimpleNamespace(idx=(0,), residual=ar1(rng, N, 0.95)))
    assert n_effective(ev, [0]) < N / 15
    fine = _evaluator(N, DT / 5)  # five grid steps per T_CORR_S: white noise counts one in five
    learn_residual_correlation(fine, SimpleNamespace(idx=(0,), residual=rng.standard_normal(N)))
    assert abs(n_effective(fine, [0]) - N / 5) < 1e-6


def test_no_lag_reaches_across_an_excluded_span():
    """Two stretches of white noise on either side of a gap, at different levels (a sensor bias that moved
    while the logger was down): each counts as white; joined across the gap they would look correlated."""
    rng = np.random.default_rng(4)
    half = N // 2
    y = np.concatenate([rng.standard_normal(half), 5.0 + rng.standard_normal(half)])
    ev = _evaluator()
    t = ev.cases[0].t_grid_s
    learn_residual_correlation(ev, SimpleNamespace(idx=(0,), residual=y))
    joined = float(ev.corr_samples[0][0])
    ev.cases[0].holes_s = ((float(t[half - 1]) + 0.1 * DT, float(t[half]) - 0.1 * DT),)
    learn_residual_correlation(ev, SimpleNamespace(idx=(0,), residual=y))
    assert joined > 50 and float(ev.corr_samples[0][0]) < 1.3


@settings(max_examples=60, deadline=None)
@given(arrays(np.float64, st.integers(2, 400), elements=st.floats(-1e6, 1e6)))
def test_correlation_samples_are_finite_and_between_one_and_the_length(x):
    tau = correlation_samples(x)
    assert np.isfinite(tau) and 1.0 <= tau <= x.size
