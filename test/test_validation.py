"""The validator's pure parts: alignment, resampling without extrapolation, metrics, windows."""
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from susp_sim_ros.analysis import validation as va
from susp_sim_ros.errors import RecordingError, SuspInputError

NS = va.NS


def grid_ns(duration_s, rate_hz, t0_s=0.0):
    step = int(round(NS / rate_hz))
    return int(t0_s * NS) + step * np.arange(int(round(duration_s * rate_hz)) + 1, dtype=np.int64)


def test_identical_recordings_have_zero_error():
    t = grid_ns(5.0, 200.0)
    y = np.sin(2 * np.pi * 1.3 * t / NS) + 0.1 * np.cos(2 * np.pi * 7 * t / NS)
    m = va.compare(t, y, t, y.copy())
    assert m.rmse == 0.0  # exactly: same grid, same data
    assert m.max_error == 0.0 and m.mean_error == 0.0
    assert m.correlation == pytest.approx(1.0, abs=1e-12)
    assert m.phase_lag_s == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("offset", [-0.7, 0.01, 3.0])
def test_constant_offset_gives_its_magnitude(offset):
    t = grid_ns(4.0, 100.0)
    y = np.sin(2 * np.pi * 0.5 * t / NS)
    m = va.compare(t, y, t, y + offset)
    np.testing.assert_allclose(m.rmse, abs(offset), rtol=1e-12)  # analytic: RMSE of a constant
    np.testing.assert_allclose(m.mean_error, offset, rtol=1e-12)
    np.testing.assert_allclose(m.max_error, abs(offset), rtol=1e-12)


def test_sine_against_zero_gives_amplitude_over_root_two():
    amp, f = 2.5, 2.0
    t = grid_ns(5.0, 1000.0)  # whole number of periods
    y = amp * np.sin(2 * np.pi * f * t / NS)
    m = va.compare(t, np.zeros_like(y), t, y)
    # analytic A / sqrt(2) over whole periods; the closed grid counts one endpoint twice (rel. 1/n)
    np.testing.assert_allclose(m.rmse, amp / math.sqrt(2), rtol=1e-3)


def test_phase_shifted_sine_gives_analytic_rmse_and_lag():
    amp, f, lag = 1.0, 1.0, 0.05
    t = grid_ns(10.0, 1000.0)
    x = t / NS
    meas = amp * np.sin(2 * np.pi * f * x)
    sim = amp * np.sin(2 * np.pi * f * (x - lag))  # the simulation lags by 50 ms
    m = va.compare(t, meas, t, sim)
    phi = 2 * np.pi * f * lag
    np.testing.assert_allclose(m.rmse, math.sqrt(2) * amp * abs(math.sin(phi / 2)), rtol=1e-3)
    np.testing.assert_allclose(m.phase_lag_s, lag, atol=1e-3)
    np.testing.assert_allclose(m.correlation, math.cos(phi), atol=1e-3)


def test_different_rates_use_the_lower_rate_and_are_exactly_reproducible():
    rng = np.random.default_rng(1)
    tm = grid_ns(3.0, 200.0) + rng.integers(-100_000, 100_000, 601)  # 200 Hz with jitter
    tm.sort()
    ts = grid_ns(3.0, 100.0)
    ym, ys = np.sin(tm / NS), np.sin(ts / NS) + 0.01
    a = va.compare(tm, ym, ts, ys)
    b = va.compare(tm.copy(), ym.copy(), ts.copy(), ys.copy())
    assert a == b  # bit for bit
    assert a.n <= 301
    np.testing.assert_allclose(a.rmse, 0.01, atol=2e-4)  # interpolation error of a slow sine is tiny


def test_no_overlap_is_a_named_error():
    t1 = grid_ns(1.0, 100.0)
    t2 = grid_ns(1.0, 100.0, t0_s=5.0)
    with pytest.raises(va.NoOverlapError, match="no time overlap"):
        va.compare(t1, np.zeros(t1.size), t2, np.zeros(t2.size))
    assert issubclass(va.NoOverlapError, RecordingError)


def test_window_outside_the_data_is_no_overlap_and_window_cuts():
    t = grid_ns(4.0, 100.0)
    y = (t >= 2 * NS).astype(float)  # differ only in the second half
    m = va.compare(t, np.zeros(t.size), t, y, window=(0, NS))
    assert m.rmse == 0.0 and m.end_s <= 1.0
    with pytest.raises(va.NoOverlapError):
        va.compare(t, y, t, y, window=(10 * NS, 11 * NS))


def test_bad_series_are_named_errors():
    t = np.array([0, 10, 10, 20], np.int64)
    with pytest.raises(RecordingError, match="strictly increasing"):
        va.compare(t, np.zeros(4), grid_ns(1, 100), np.zeros(101), names=("m.mcap", "s.mcap"))
    with pytest.raises(RecordingError, match="non-finite"):
        va.compare(grid_ns(1, 10), np.array([0.0] * 5 + [np.nan] + [0.0] * 5), grid_ns(1, 10), np.zeros(11))
    with pytest.raises(RecordingError, match="at least 2"):
        va.compare(np.array([0]), np.zeros(1), grid_ns(1, 10), np.zeros(11))


def test_resample_refuses_to_extrapolate():
    t = grid_ns(1.0, 10.0)
    y = np.arange(t.size, dtype=float)
    with pytest.raises(va.ExtrapolationError):
        va.resample(t, y, np.array([t[-1] + 1]))
    with pytest.raises(va.ExtrapolationError):
        va.resample(t, y, np.array([t[0] - 1, t[0]]))
    assert issubclass(va.ExtrapolationError, SuspInputError)
    np.testing.assert_allclose(va.resample(t, y, t), y)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.integers(1, 10**8), min_size=2, max_size=40),
       st.lists(st.floats(-1e3, 1e3), min_size=40, max_size=40),
       st.integers(-10**9, 10**9), st.floats(0.5, 2000.0))
def test_resampled_points_stay_inside_data_span_and_range(steps, values, t0, rate):
    """Property: the common grid never leaves either recording, and interpolated values stay inside the
    range of the data (linear interpolation invents nothing beyond the samples)."""
    t = t0 + np.cumsum(np.asarray(steps, np.int64))
    y = np.asarray(values[:t.size])
    grid = va.common_grid((int(t[0]), int(t[-1])), rate)
    assert grid.size == 0 or (grid[0] >= t[0] and grid[-1] <= t[-1])
    out = va.resample(t, y, grid)
    if out.size:
        assert out.min() >= y.min() - 1e-9 and out.max() <= y.max() + 1e-9
    # anything beyond the ends raises
    for bad in (t[0] - 1, t[-1] + 1):
        with pytest.raises(va.ExtrapolationError):
            va.resample(t, y, np.array([bad]))


@settings(max_examples=100, deadline=None)
@given(st.integers(0, 10**10), st.integers(0, 10**10), st.integers(0, 10**10), st.integers(0, 10**10),
       st.floats(1.0, 1000.0))
def test_compare_grid_lies_in_the_overlap(a0, a1, b0, b1, rate):
    ta = np.array(sorted({a0, a0 + a1 + 1}), np.int64)
    tb = np.array(sorted({b0, b0 + b1 + 1}), np.int64)
    try:
        m = va.compare(ta, np.zeros(2), tb, np.ones(2), rate_hz=rate)
    except va.NoOverlapError:
        lo, hi = max(ta[0], tb[0]), min(ta[-1], tb[-1])
        assert hi < lo or va.common_grid((int(lo), int(hi)), rate).size < 2
        return
    lo, hi = max(ta[0], tb[0]), min(ta[-1], tb[-1])
    assert lo / NS - 1e-9 <= m.start_s <= m.end_s <= hi / NS + 1e-9
    assert m.rmse == 1.0


def test_bump_window_covers_bump_and_ringout():
    t = grid_ns(8.0, 100.0)
    v = np.full(t.size, 2.0)
    s = np.linspace(1.0, 1.5, 51)
    z = 0.03 * (1 - np.cos(2 * np.pi * (s - 1.0) / 0.5))
    w = va.bump_window(t, v, s, z, z, 2.79, end_ns=int(t[-1]))
    # front axle reaches s = 0.99 m at 0.495 s; rear axle leaves 1.51 + 2.79 m at 2.15 s
    assert w.start_ns == pytest.approx(0.0, abs=1e7)
    np.testing.assert_allclose(w.end_ns / NS, (1.51 + 2.79) / 2.0 + va.WINDOW_RINGOUT_S, atol=0.011)
    assert va.bump_window(t, v, s, 0 * s, 0 * s, 2.79, end_ns=int(t[-1])) is None


def test_steering_window():
    t = grid_ns(10.0, 100.0)
    x = t / NS
    swa = np.where((x > 2) & (x < 6), np.sin(2 * np.pi * 0.5 * (x - 2)), 0.0)
    w = va.steering_window(t, swa, end_ns=int(t[-1]))
    assert 1.4 < w.start_ns / NS < 1.6
    np.testing.assert_allclose(w.end_ns / NS, 6.0 + va.WINDOW_RINGOUT_S, atol=0.02)
    assert va.steering_window(t, swa, end_ns=int(7 * NS)).end_ns == 7 * NS  # cut at the end of data
    assert va.steering_window(t, 0 * swa, end_ns=int(t[-1])) is None


def test_validate_reports_deg_s_per_window_and_skips_foreign_windows():
    t = grid_ns(4.0, 100.0)
    g = np.zeros((t.size, 3))
    g2 = g.copy()
    g2[:, 1] = math.radians(0.5)
    res = va.validate(t, g, t, g2, windows={"late": va.Window("late", 100 * NS, 101 * NS)})
    np.testing.assert_allclose(res.rmse_deg_s("whole", "pitch_rate"), 0.5, rtol=1e-12)
    assert res.rmse_deg_s("whole", "roll_rate") == 0.0
    assert "late" in res.skipped
    d = res.as_dict()
    assert d["windows"]["whole"]["signals"]["pitch_rate"]["rmse_deg_s"] == pytest.approx(0.5)
    assert d["windows"]["whole"]["signals"]["pitch_rate"]["correlation"] is None  # constant: undefined
