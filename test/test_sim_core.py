"""SimCore: input validation, exact time stepping independent of call granularity."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from susp_sim_ros.errors import SuspInputError
from susp_sim_ros.model import make_inputs, simulate
from susp_sim_ros.runtime.sim_core import SimCore, sample_messages

T0 = 5_000_000_000


@pytest.fixture
def core(model_full):
    return SimCore(model_full, step_s=0.001, publish_rate_hz=100.0)


def test_rejections_are_counted_and_not_integrated(core):
    assert core.set_speed(T0, 10.0) is None
    assert "non-finite" in core.set_speed(T0, float("nan"))
    assert "negative" in core.set_speed(T0, -0.1)
    assert "4 pi" in core.set_steering(T0, 13.0)
    assert core.set_steering(T0, -12.0) is None
    assert "strictly increasing" in core.set_road_profile(T0, [0, 2, 1, 0, 0, 0, 0, 0, 0], [("c", 3), ("s", 3)])
    assert "3*3" in core.set_road_profile(T0, [0, 1, 2], [("c", 3), ("s", 3)])
    assert "4 values" in core.set_wheel_heights(T0, [0.0, 0.0])
    assert core.speed == 10.0 and core.steering == -12.0 and core.road is None
    assert core.rejections == {"non_finite": 1, "speed_negative": 1, "steering_range": 1,
                               "road_profile": 2, "wheel_heights": 1}


def test_acceleration_from_successive_speeds(core):
    core.set_speed(T0, 10.0)
    core.set_speed(T0 + 100_000_000, 11.0)
    assert core.accel == pytest.approx(10.0)
    core.set_speed(T0 + 200_000_000, 11.0)
    assert core.accel == 0.0


def test_bad_configuration(model_full):
    with pytest.raises(SuspInputError, match="publish_rate_hz"):
        SimCore(model_full, publish_rate_hz=0.0)
    with pytest.raises(SuspInputError, match="step_s"):
        SimCore(model_full, step_s=0.02, publish_rate_hz=100.0)
    with pytest.raises(SuspInputError, match="damper_oil_level"):
        SimCore(model_full, oil=(1, 1, 1))


def test_granularity_independence_and_equality_with_simulate(model_full):
    """Stepping to t in one call, in 1 ms calls or in random pieces gives identical samples."""
    rng = np.random.default_rng(0)
    end = T0 + 2_000_000_000
    runs = []
    for pieces in ("one", "ms", "random"):
        c = SimCore(model_full)
        c.set_speed(T0, 15.0)
        c.set_steering(T0, 0.3)
        c.advance_to(T0)
        if pieces == "one":
            times = [end]
        elif pieces == "ms":
            times = list(range(T0 + 1_000_000, end + 1, 1_000_000))
        else:
            times = sorted(set(rng.integers(T0, end, 300).tolist())) + [end]
        out = [s for t in times for s in c.advance_to(t)]
        runs.append(out)
    for other in runs[1:]:
        assert [s.t_ns for s in other] == [s.t_ns for s in runs[0]]
        np.testing.assert_array_equal(np.array([s.y for s in other]), np.array([s.y for s in runs[0]]))
    ref = simulate(model_full, make_inputs(2000, 15.0, 0.3), dt=0.001)
    np.testing.assert_allclose(np.array([s.y for s in runs[0]]), ref.y[9::10], rtol=0, atol=1e-12)


def test_time_going_backwards_restarts(core):
    core.set_speed(T0, 10.0)
    core.advance_to(T0)
    assert len(core.advance_to(T0 + 50_000_000)) == 5
    assert core.advance_to(T0 - 1_000_000_000) == []
    assert core.steps_done == 0 and core.started
    assert [s.t_ns for s in core.advance_to(T0 - 980_000_000)] == [T0 - 990_000_000, T0 - 980_000_000]


def test_stale_inputs(core):
    core.advance_to(T0)
    assert core.stale_inputs(T0 + 100_000_000) == []
    assert set(core.stale_inputs(T0 + 600_000_000)) == {"/vehicle/speed", "/vehicle/steering_wheel_angle"}
    core.set_speed(T0 + 600_000_000, 3.0)
    assert core.stale_inputs(T0 + 700_000_000) == ["/vehicle/steering_wheel_angle"]


def test_wheel_heights_override_profile(core):
    core.set_road_profile(T0, [0.0, 1.0, 0.1, 0.1, 0.1, 0.1], [("channel", 3), ("sample", 2)])
    assert core.stepper.road is not None
    assert core.set_wheel_heights(T0, [0.01, 0.0, 0.0, 0.0]) is None
    assert core.stepper.road is None  # per-wheel mode


def test_sample_messages(core):
    core.set_speed(T0, 10.0)
    core.advance_to(T0)
    s = core.advance_to(T0 + 10_000_000)[0]
    msgs = sample_messages(s)
    assert [m[0] for m in msgs] == ["/sim/imu/data", "/sim/odom", "/sim/suspension"]
    assert msgs[1][2]["header"]["frame_id"] == "odom" and msgs[1][2]["child_frame_id"] == "base_link"


def test_wall_time_never_restarts_on_a_late_reading(core):
    core.set_speed(T0, 10.0)
    core.advance_to(T0)
    core.advance_to(T0 + 30_000_000)
    steps = core.steps_done
    assert core.advance_to(T0 + 29_999_000, allow_restart=False) == []
    assert core.steps_done == steps and core.restarts == 0
    assert core.total_sim_time_s == pytest.approx(0.03)
    core.advance_to(T0, allow_restart=True)
    assert core.restarts == 1 and core.total_sim_time_s == pytest.approx(0.03)


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.lists(st.tuples(st.integers(0, 3), st.floats(0.0, 60.0)), min_size=1, max_size=40))
def test_offline_accelerations_follow_the_node_rule(model_full, msgs):
    """The finder's inputs (discrepancy.data.speed_accelerations) derive the acceleration from speed
    messages as the node does, repeated timestamps and absurd jumps included (never inf or NaN)."""
    from susp_sim_ros.analysis.discrepancy.data import speed_accelerations
    core = SimCore(model_full, step_s=0.001, publish_rate_hz=100.0)
    t = np.cumsum([dt * 5_000_000 for dt, _ in msgs]) + T0  # steps of 0..15 ms, 0 = same time
    v = [x for _, x in msgs]
    expected = []
    for tk, vk in zip(t, v):
        assert core.set_speed(int(tk), vk) is None
        expected.append(core.accel)
    got = speed_accelerations(t, v)
    assert np.all(np.isfinite(got))
    np.testing.assert_array_equal(got, expected)
