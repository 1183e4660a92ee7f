"""Live input integrity (issue 28, item 4): the node judges its inputs by the offline policy
(``config/integrity.yaml``) and reports each finding on ``/diagnostics``.

The pure judgement (:mod:`susp_sim_ros.io.live_integrity`) is compared with the offline check
(:func:`~susp_sim_ros.io.integrity.check_drive_integrity`) and with what the simulation core rejects
(hypothesis); the node is spun in-process as in ``test_node.py``."""
from __future__ import annotations

import math
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from susp_sim_ros.io.drive import Series, TestDrive
from susp_sim_ros.io.drive_data import DAMPER_COMMAND, ROAD_PROFILE, SPEED, STEERING, WHEEL_HEIGHTS
from susp_sim_ros.io.integrity import KINDS, IntegrityError, check_drive_integrity, load_policy
from susp_sim_ros.io.live_integrity import (ERROR, WARN, FindingBoard, LiveIntegrity, LivePolicy,
                                            judge_value)
from susp_sim_ros.ros.status import INTEGRITY_PREFIX, integrity_statuses

NS = 1_000_000_000
T0 = 1_000_000_000
POLICY = load_policy()
LIVE = LivePolicy.from_table(POLICY)
SPEED_MAX, STEER_MAX = float(POLICY["limits.speed_max"]), float(POLICY["limits.steering_max"])
WH_MAX = float(POLICY["limits.wheel_height_max"])
GAP_MIN_NS = int(float(POLICY["stamps.gap_min_s"]) * NS)
BACK_NS = int(float(POLICY["stamps.backward_jump_s"]) * NS)
FWD_NS = int(float(POLICY["stamps.clock_jump_s"]) * NS)
ERROR_RE = re.compile(r"topic (\S+): (\w+):")

# values around every limit, both units, and the non-finite ones
scalar = st.one_of(st.floats(allow_nan=True, allow_infinity=True, width=64),
                   st.sampled_from([0.0, -0.0, SPEED_MAX, SPEED_MAX * 3.6, STEER_MAX, STEER_MAX * 180 / math.pi,
                                    -STEER_MAX, math.nextafter(SPEED_MAX, math.inf), -1e-300]),
                   st.floats(-1000.0, 1000.0))


def _constant(n: int, value, period_ns: int = 10_000_000) -> Series:
    t = T0 + np.arange(n, dtype=np.int64) * period_ns
    return Series(t, np.array([value] * n, dtype=float))


def _offline_kinds(drive: TestDrive) -> tuple[set[str], str | None]:
    """Kinds the offline check reports and the kind of its named error (None without one)."""
    try:
        res = check_drive_integrity(drive, "x.mcap", POLICY)
    except IntegrityError as exc:
        m = ERROR_RE.search(str(exc))
        assert m, str(exc)
        return set(), m.group(2)
    return {f.kind for f in res.findings}, None


# ---- the value judgement: the offline policy, the core's rejections -----------------------------------
@settings(max_examples=300, deadline=None)
@given(scalar, st.sampled_from([SPEED, STEERING]))
def test_a_scalar_is_judged_as_the_offline_check_judges_a_drive_of_it(v, topic):
    """A drive whose speed (or steering) is ``v`` throughout: the offline check's kind (an error: every
    sample has it) is the live judgement's kind of one message of ``v``; a sound value gives neither."""
    steady = _constant(40, 10.0 if topic == STEERING else 0.0)
    series = _constant(40, v)
    drive = TestDrive({}, series if topic == SPEED else steady, series if topic == STEERING else steady)
    found, error = _offline_kinds(drive)
    live = judge_value(topic, [v], LIVE)
    if live is None:
        assert error is None and not found, (v, found, error)
    else:
        assert error == live[0], (v, error, live)
        assert live[1] == (ERROR if live[0] == "implausible_unit" else WARN)


@settings(max_examples=200, deadline=None)
@given(st.lists(scalar, min_size=4, max_size=4), st.sampled_from([WHEEL_HEIGHTS, DAMPER_COMMAND]))
def test_a_wheel_array_is_judged_as_the_offline_check_judges_a_drive_of_it(values, topic):
    n = 40
    t = T0 + np.arange(n, dtype=np.int64) * 10_000_000
    arr = Series(t, np.tile(np.array(values, dtype=float), (n, 1)))
    drive = TestDrive({}, _constant(n, 10.0), _constant(n, 0.0),
                      wheel_heights=arr if topic == WHEEL_HEIGHTS else None,
                      damper_command=arr if topic == DAMPER_COMMAND else None)
    found, error = _offline_kinds(drive)
    live = judge_value(topic, values, LIVE)
    if live is None:
        assert error is None and not found, (values, found, error)
    else:
        assert error == live[0] and live[1] == WARN, (values, error, live)


@settings(max_examples=300, deadline=None)
@given(scalar, scalar, st.lists(scalar, min_size=4, max_size=4), st.lists(scalar, min_size=4, max_size=4))
def test_the_live_judgement_finds_a_value_defect_exactly_when_the_core_rejects_it(speed, steer, heights, command):
    """One set of limits: what the core refuses is what the policy calls a defect (and vice versa)."""
    from susp_sim_ros.runtime.sim_core import SimCore
    core = SimCore(_model())
    for topic, setter, values in ((SPEED, core.set_speed, speed), (STEERING, core.set_steering, steer),
                                  (WHEEL_HEIGHTS, core.set_wheel_heights, heights),
                                  (DAMPER_COMMAND, core.set_damper_command, command)):
        rejected = setter(T0, values) is not None
        found = judge_value(topic, values if isinstance(values, list) else [values], LIVE)
        assert rejected == (found is not None), (topic, values, found)
        assert found is None or found[0] in KINDS


_MODEL = None


def _model():
    global _MODEL
    if _MODEL is None:
        from susp_sim_ros.model.vehicle import Model
        _MODEL = Model("passat_b8_like", "full")
    return _MODEL


def test_road_profile_findings_are_errors():
    n = 5
    s = np.linspace(0.0, 4.0, n)
    ok = np.concatenate([s, np.zeros(n), np.zeros(n)])
    assert judge_value(ROAD_PROFILE, ok, LIVE) is None
    high = ok.copy()
    high[n + 2] = 2 * WH_MAX
    kind, level, value, expected = judge_value(ROAD_PROFILE, high, LIVE)
    assert (kind, level) == ("out_of_range", ERROR) and "limits.wheel_height_max" in expected
    nan = ok.copy()
    nan[1] = math.nan
    assert judge_value(ROAD_PROFILE, nan, LIVE)[:2] == ("non_finite", ERROR)


# ---- stamps: the same kinds as the offline check of the same stamps -----------------------------------
@settings(max_examples=250, deadline=None)
@given(period_ms=st.integers(5, 50), n1=st.integers(3, 20), n2=st.integers(3, 20),
       step=st.one_of(st.integers(-3 * NS, 40 * NS), st.sampled_from([-BACK_NS, -BACK_NS - 1, FWD_NS, FWD_NS + 1,
                                                                       GAP_MIN_NS, GAP_MIN_NS + 1])))
def test_stamp_steps_are_judged_as_the_offline_check_judges_them(period_ms, n1, n2, step):
    """A regular topic with one step (back, a hole, or a jump forward) between two runs of messages:
    the live kinds among gap / clock_jump / stamp_order are the offline check's (after a step back of
    at most ``stamps.backward_jump_s`` the offline check sorts the messages, which can open a hole between
    the two runs; live no message was missing, so gaps are compared for forward steps only)."""
    p = period_ms * 1_000_000
    if step > 0:
        step = max(step, 1)
    first = T0 + np.arange(n1, dtype=np.int64) * p
    second = first[-1] + step + p // 2 + np.arange(n2, dtype=np.int64) * p  # off the grid: no duplicate
    t = np.concatenate([first, second])
    stamp_kinds = {"gap", "clock_jump", "stamp_order"}
    speed = Series(t, np.full(t.size, 10.0))
    found, error = _offline_kinds(TestDrive({}, speed, Series(t, np.zeros(t.size))))
    assert error is None
    live = LiveIntegrity(POLICY)
    got = [f for tt in t.tolist() for f in live.check(SPEED, tt, [10.0])]
    if step < 0:  # offline sorts a short step back, which may leave a hole: live the messages kept coming
        stamp_kinds.discard("gap")
    assert {f.kind for f in got} == found & stamp_kinds, (step, found, [f.detail for f in got])
    assert all(f.level == WARN and f.action == "kept" and f.from_ns is not None for f in got)


@settings(max_examples=150, deadline=None)
@given(period_ms=st.integers(5, 50), n=st.integers(3, 30), wait_ms=st.integers(0, 5000))
def test_an_open_gap_is_reported_once_while_it_lasts_and_again_when_it_ends(period_ms, n, wait_ms):
    p = period_ms * 1_000_000
    live = LiveIntegrity(POLICY)
    for k in range(n):
        assert live.check(STEERING, T0 + k * p, [0.1]) == []
    last = T0 + (n - 1) * p
    limit = live.gap_limit_ns(STEERING)
    assert limit == max(int(float(POLICY["stamps.gap_periods"]) * p), GAP_MIN_NS)
    now = last + wait_ms * 1_000_000
    open_ = live.check_gaps(now)
    assert [f.kind for f in open_] == (["gap"] if now - last > limit else [])
    later = live.check_gaps(now + 10 * NS)
    assert len(later) == (0 if open_ else 1)  # once per gap
    assert live.open_gaps() == [STEERING]
    ended = live.check(STEERING, now + 10 * NS, [0.1])
    assert [f.kind for f in ended] == ["gap"] and ended[0].from_ns == last
    assert live.open_gaps() == []
    assert not live.check_gaps(now + 10 * NS + p)


def test_non_finite_messages_do_not_count_as_stamps():
    """As offline (non-finite samples are dropped before the stamp checks): a NaN is its own finding."""
    live = LiveIntegrity(POLICY)
    for k in range(5):
        live.check(SPEED, T0 + k * 10_000_000, [5.0])
    f = live.check(SPEED, T0 + 5 * 10_000_000, [math.nan])
    assert [x.kind for x in f] == ["non_finite"] and f[0].action == "excluded"
    assert live.check_gaps(T0 + 4 * 10_000_000 + GAP_MIN_NS + 1)[0].from_ns == T0 + 4 * 10_000_000


def test_finding_board_statuses_go_back_to_ok_after_a_report():
    live, board = LiveIntegrity(POLICY), FindingBoard()
    board.add(live.check(SPEED, T0, [100.0]))  # km/h
    board.add(live.check(SPEED, T0 + 10_000_000, [-1.0]))
    board.add(live.check(SPEED, T0 + 20_000_000, [101.0]))
    st_ = {s["name"]: s for s in integrity_statuses(board.entries(), [])}
    unit = st_[f"{INTEGRITY_PREFIX}{SPEED} implausible_unit"]
    assert unit["level"] == ERROR and unit["values"]["count"] == 2 and unit["values"]["new"] == 2
    assert unit["values"]["value"] == "101 m/s" and unit["values"]["time_s"] == "1.020000000"
    assert "km/h" in unit["values"]["expected"] and unit["values"]["topic"] == SPEED
    assert st_[f"{INTEGRITY_PREFIX}{SPEED} out_of_range"]["level"] == WARN
    board.mark_reported()
    assert all(s["level"] == 0 for s in integrity_statuses(board.entries(), []))


# ---- the node --------------------------------------------------------------------------------------
@pytest.fixture
def driver():
    from _ros_helpers import SimDriver
    d = SimDriver({"diagnostics_rate_hz": 0.01})  # the test publishes /diagnostics itself
    yield d
    d.close()


def _integrity(node) -> dict[str, dict]:
    return {s["name"][len(INTEGRITY_PREFIX):]: s for s in node.diagnostics()
            if s["name"].startswith(INTEGRITY_PREFIX)}


def test_node_reports_live_findings_on_diagnostics(driver):
    from diagnostic_msgs.msg import DiagnosticArray
    got: list = []
    driver.drv.create_subscription(DiagnosticArray, "/diagnostics", got.append, 10)
    node, core = driver.node, driver.node.core
    period = 10_000_000
    t = 10 * NS
    driver.clock(t)
    for _ in range(5):  # a regular speed topic
        driver.send_value(SPEED, 12.0)
        t += period
        driver.clock(t)
    driver.send_value(SPEED, 100.0)                 # km/h on the wire (beyond speed_max as m/s)
    driver.send_value(SPEED, -2.0)                  # out of range
    driver.send_value(STEERING, float("nan"))       # non-finite
    driver.send_value(STEERING, 90.0)               # degrees on the wire
    t += period
    driver.clock(t)
    assert core.speed == 12.0 and core.steering == 0.0  # rejected as before, last values held
    assert core.rejections == {"speed_range": 1, "speed_negative": 1, "non_finite": 1, "steering_range": 1}
    found = _integrity(node)
    assert set(found) == {f"{SPEED} implausible_unit", f"{SPEED} out_of_range", f"{STEERING} non_finite",
                          f"{STEERING} implausible_unit"}
    unit = found[f"{SPEED} implausible_unit"]
    assert unit["level"] == ERROR
    v = unit["values"]
    assert (v["topic"], v["kind"], v["value"], v["action"]) == (SPEED, "implausible_unit", "100 m/s", "excluded")
    assert float(v["time_s"]) == pytest.approx((t - period) / NS) and "km/h" in v["expected"]
    assert found[f"{SPEED} out_of_range"]["level"] == WARN
    assert found[f"{STEERING} implausible_unit"]["values"]["expected"].startswith("rad within")
    assert node.diagnostics()[0]["values"]["integrity_findings"] == 4
    # the speed topic falls silent while the simulation runs: a gap, open until the next message
    t += 2 * GAP_MIN_NS
    driver.clock(t)
    gap = _integrity(node)[f"{SPEED} gap"]
    assert gap["level"] == WARN and gap["values"]["detail"].startswith("gap open")
    # published: one DiagnosticStatus per (topic, kind), with its level
    node.publish_diagnostics()
    driver.spin_until(lambda: any(s.name.startswith(INTEGRITY_PREFIX) for m in got for s in m.status))
    status = {s.name: s for s in got[-1].status}
    pub = status[f"{INTEGRITY_PREFIX}{SPEED} implausible_unit"]
    assert pub.level == bytes([ERROR])
    assert {kv.key: kv.value for kv in pub.values}["kind"] == "implausible_unit"
    assert status[f"{INTEGRITY_PREFIX}{SPEED} gap"].level == bytes([WARN])
    # reported: back to OK, except the gap that is still open
    after = _integrity(node)
    assert after[f"{SPEED} implausible_unit"]["level"] == 0 and after[f"{SPEED} gap"]["level"] == WARN
    # logged once per (topic, kind), not per message
    assert node.integrity_error_log.emitted[(SPEED, "implausible_unit")] == 1
    assert node.integrity_log.emitted[(SPEED, "gap")] == 1
    # a message ends the gap; time going back (a looped replay) is a clock jump on the topic
    driver.send_value(SPEED, 12.0)
    t += period
    driver.clock(t)
    assert _integrity(node)[f"{SPEED} gap"]["values"]["detail"].startswith("gap ended")
    driver.clock(t - 5 * NS // 2)
    driver.send_value(SPEED, 12.0)
    driver.clock(t - 5 * NS // 2 + period)
    jump = _integrity(node)[f"{SPEED} clock_jump"]
    assert jump["level"] == WARN and float(jump["values"]["from_s"]) == pytest.approx((t - period) / NS)
    assert core.restarts == 1 and node.inputs.handler_errors == 0


# ---- a unit mistake needs evidence, as offline -------------------------------------------------------------
def _steering_drive(values: np.ndarray) -> TestDrive:
    n = values.size
    return TestDrive({}, _constant(n, 10.0), Series(T0 + np.arange(n, dtype=np.int64) * 10_000_000, values))


@settings(max_examples=60, deadline=None)
@given(amp=st.floats(0.02, 2.0), freq=st.floats(0.1, 0.6), phase=st.floats(0.0, 6.28), at=st.integers(12, 280),
       outlier=st.floats(STEER_MAX * 1.001, STEER_MAX * 180 / math.pi), sign=st.sampled_from([-1.0, 1.0]),
       noise=st.floats(0.0, 0.01), seed=st.integers(0, 2**16))
def test_one_outlier_in_radians_is_a_spike_not_a_unit_mistake_live_and_offline(amp, freq, phase, at, outlier, sign,
                                                                              noise, seed):
    """A steering angle recorded in radians (a plausible sine steer at 100 Hz) with one message beyond
    ``limits.steering_max`` that would fit as degrees: offline the sample is a ``spike`` (dropped before the
    unit is judged), live it is a ``spike`` too (the node rejects it), never ``implausible_unit``. The same
    steering recorded in degrees is a unit mistake for both once it passes the limit. Steering rates up to
    7.5 rad/s (a quick driver; the spike floor assumes at most about 15 rad/s)."""
    rng = np.random.default_rng(seed)
    t = np.arange(300) / 100.0
    rad = amp * np.sin(2 * np.pi * freq * t + phase) + noise * rng.standard_normal(t.size)
    v = rad.copy()
    v[at] = sign * outlier
    found, error = _offline_kinds(_steering_drive(v))
    assert error is None and "spike" in found and "implausible_unit" not in found, (found, error)
    live = LiveIntegrity(POLICY)
    kinds = [f.kind for k, x in enumerate(v) for f in live.check(STEERING, T0 + k * 10_000_000, [float(x)])]
    assert "implausible_unit" not in kinds and kinds.count("spike") == 1, kinds
    # in degrees: the offline check refuses it, the live check says so as soon as the limit is passed
    deg = np.degrees(rad)
    if np.max(np.abs(deg)) > STEER_MAX * 1.001:
        assert _offline_kinds(_steering_drive(deg))[1] == "implausible_unit"
        live = LiveIntegrity(POLICY)
        kinds = [f.kind for k, x in enumerate(deg) for f in live.check(STEERING, T0 + k * 10_000_000, [float(x)])]
        assert "spike" not in kinds and "implausible_unit" in kinds, kinds


def test_a_speed_outlier_after_a_steady_drive_is_a_spike_and_km_h_stays_a_unit_mistake():
    live = LiveIntegrity(POLICY)
    for k in range(20):
        assert live.check(SPEED, T0 + k * 10_000_000, [12.0 + 0.01 * (k % 3)]) == []
    (f,) = live.check(SPEED, T0 + 20 * 10_000_000, [100.0])
    assert (f.kind, f.level, f.action) == ("spike", WARN, "excluded") and "no unit mistake" in f.expected
    kmh = LiveIntegrity(POLICY)  # the same drive in km/h: in line with its messages, beyond the limit
    found = [f.kind for k in range(40) for f in kmh.check(SPEED, T0 + k * 10_000_000, [3.6 * (12.0 + 0.5 * k)])]
    assert found and set(found) == {"implausible_unit"}
