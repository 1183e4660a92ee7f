"""The kernel's inlined exponentials against the C maths library (they replace it so the step
vectorises; see ``model/inline_math.py``)."""
import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from numba import njit

from susp_sim_ros.model.inline_math import expm1_nonpos, tanh


@njit
def _eval(xs, e, t):
    for k in range(xs.shape[0]):
        e[k] = expm1_nonpos(xs[k])
        t[k] = tanh(xs[k])


def _run(xs):
    xs = np.asarray(xs, float)
    e, t = np.empty_like(xs), np.empty_like(xs)
    _eval(xs, e, t)
    return e, t


def _ulps(got, want):
    return np.abs(got - want) / np.spacing(np.abs(want)).clip(np.finfo(float).tiny)


def test_expm1_and_tanh_match_libm_over_the_whole_range():
    rng = np.random.default_rng(0)
    xs = np.concatenate([-np.exp(rng.uniform(-40.0, 3.7, 200_000)), -rng.uniform(0.0, 40.0, 200_000),
                         [0.0, -0.0, -5e-324, -1e-300, -0.5 * math.log(2), -40.0]])
    e, t = _run(xs)
    assert _ulps(e, np.array([math.expm1(x) for x in xs])).max() <= 1.0
    assert _ulps(t, np.array([math.tanh(x) for x in xs])).max() <= 3.0
    _, tp = _run(-xs)  # tanh is odd
    np.testing.assert_array_equal(tp, -t)


@settings(max_examples=500, deadline=None)
@given(st.floats(min_value=-40.0, max_value=0.0))
def test_expm1_within_one_ulp(x):
    e, _ = _run([x])
    assert _ulps(e, np.array([math.expm1(x)]))[0] <= 1.0


def test_edges_below_range_and_nan():
    e, t = _run([-41.0, -1e300, -math.inf, math.nan])
    assert e[0] == -1.0 and e[1] == -1.0 and e[2] == -1.0 and math.isnan(e[3])
    assert t[0] == -1.0 and t[1] == -1.0 and t[2] == -1.0 and math.isnan(t[3])
