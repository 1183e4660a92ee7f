"""Reliability under bad input: property tests (hypothesis) of the node's input handlers.

At least 10,000 generated messages per input topic (``/vehicle/speed``, ``/vehicle/steering_wheel_angle``,
``/road/profile``, ``/road/wheel_heights``, and ``/clock`` under sim time) go straight into the
subscription callbacks of a real :class:`SuspSimNode` (private context, no DDS: fast), in bursts:
NaN, +-inf, huge and negative values, values at and just past every limit, empty and mis-shaped
``Float64MultiArray`` layouts (wrong sizes, strides, data offsets, swapped dims), non-increasing road
profiles, and under sim time ``/clock`` values that are invalid, stale, out of order (shuffled source
timestamps), jumping back (a restart) or far ahead. Asserted: no exception escapes, no internal handler
error, nothing non-finite is ever published (every outgoing message is checked) or recorded (the node
records to an MCAP that is read back), every rejection is counted per topic and cause exactly as an
independent oracle expects (for the scalar topics and ``/clock``) and reported on ``/diagnostics``, and
each cause is logged once (rate-limited), not once per message. A smaller sample goes through DDS into
the same node. Figures (message counts, rejections, log lines, divergences) are printed (``-s``).
"""
from __future__ import annotations

import math
import time
from collections import Counter

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from _reliability_helpers import (EDGE_FLOATS, CheckingPublisher, any_float, expected_scalar_cause,
                                  heights_msgs, profile_msgs, recorded_sim_numbers)
from _ros_helpers import ros_env

PER_TOPIC = 10_000
EXAMPLES = 340          # bursts per topic; 30..32 messages each (at least 10,200 messages)
BURST = dict(min_size=30, max_size=32)
FUZZ = settings(max_examples=EXAMPLES, deadline=None, derandomize=True, database=None,
                suppress_health_check=list(HealthCheck))
SPEED, STEER, PROFILE, HEIGHTS, CLOCK = ("/vehicle/speed", "/vehicle/steering_wheel_angle", "/road/profile",
                                         "/road/wheel_heights", "/clock")
FIGURES: dict = {"messages": Counter(), "rejected": Counter(), "log_lines": Counter(), "divergences": Counter(),
                 "published_samples": Counter()}


class FuzzNode:
    """A SuspSimNode in a private context, recording, with checking publishers and a log tap."""

    def __init__(self, path, sim_time: bool):
        ros_env()
        import rclpy
        from rclpy.parameter import Parameter
        from susp_sim_ros.ros.node import SuspSimNode
        self.rclpy, self.ctx, self.path = rclpy, rclpy.Context(), path
        rclpy.init(context=self.ctx)
        over = [Parameter("use_sim_time", value=sim_time), Parameter("record_path", value=str(path)),
                Parameter("on_divergence", value="hold"), Parameter("realtime_priority", value=0)]
        self.node = n = SuspSimNode(context=self.ctx, parameter_overrides=over, start_thread=False)
        self.pubs = {k: CheckingPublisher(k) for k in ("imu", "odom", "susp", "diag")}
        n.pub_imu, n.pub_odom, n.pub_susp, n.pub_diag = (self.pubs[k] for k in ("imu", "odom", "susp", "diag"))
        self.t_created = time.monotonic()
        self.divergences = 0

    def after_burst(self) -> None:
        """After a burst: nothing non-finite went out; a diverged core (violent but in-range inputs, e.g.
        1 m wheel-height steps) published nothing after the divergence; restart it from rest."""
        for p in self.pubs.values():
            assert not p.bad, p.bad[:1]
        core = self.node.core
        if core.diverged:
            self.divergences += 1
            n0 = self.node.published
            self.node.tick()
            assert self.node.published == n0  # the guard stopped publishing
            with self.node.lock:
                core.reset()

    def check_logging(self, topic: str) -> None:
        """Every (topic, cause) counted was logged, at most once per interval (not once per message)."""
        log = self.node.rejection_log
        allowed = 1 + int((time.monotonic() - self.t_created) / log.interval_s)
        for (tp, cause), n in self.node.core.rejections_by_topic.items():
            if tp != topic:
                continue
            assert log.counts[(tp, cause)] == n, (tp, cause)
            assert 1 <= log.emitted[(tp, cause)] <= allowed, (tp, cause, log.emitted[(tp, cause)])
            FIGURES["rejected"][f"{tp} {cause}"] = n
            FIGURES["log_lines"][f"{tp} {cause}"] = log.emitted[(tp, cause)]
        diag = self.node.diagnostics()[0]["values"]
        assert diag["rejected_total"] == sum(self.node.core.rejections.values())
        for (tp, cause), n in self.node.core.rejections_by_topic.items():
            assert f"{tp}:{cause}={n}" in diag["rejected_by_topic"]
        self.node.publish_diagnostics()  # goes through the checking publisher
        assert self.node.inputs.handler_errors == 0

    def close(self) -> tuple[int, int]:
        try:
            self.node.destroy_node()
        finally:
            self.rclpy.try_shutdown(context=self.ctx)
        return recorded_sim_numbers(self.path)


@pytest.fixture(scope="module")
def wall(tmp_path_factory):
    f = FuzzNode(tmp_path_factory.mktemp("fuzz") / "wall.mcap", sim_time=False)
    yield f
    f.close()


@pytest.fixture(scope="module")
def simnode(tmp_path_factory):
    f = FuzzNode(tmp_path_factory.mktemp("fuzz") / "sim.mcap", sim_time=True)
    yield f
    f.close()


def _scalar_fuzz(f: FuzzNode, topic: str, handler) -> None:
    from std_msgs.msg import Float64
    node, core = f.node, f.node.core
    n_msgs = 0

    @FUZZ
    @given(st.lists(any_float, **BURST))
    def burst(values):
        nonlocal n_msgs
        before = Counter({c: n for (tp, c), n in core.rejections_by_topic.items() if tp == topic})
        for v in values:
            handler(Float64(data=v), None)
        node.tick()  # wall time: the burst takes effect at its arrival instants
        after = Counter({c: n for (tp, c), n in core.rejections_by_topic.items() if tp == topic})
        want = Counter(c for c in (expected_scalar_cause(topic, v) for v in values) if c)
        assert after - before == want
        accepted = [v for v in values if expected_scalar_cause(topic, v) is None]
        held = core.speed if topic == SPEED else core.steering
        if accepted:
            assert held == accepted[-1]  # the last valid value is held, no rejected one integrated
        assert math.isfinite(held)
        n_msgs += len(values)
        f.after_burst()

    burst()
    f.check_logging(topic)
    FIGURES["messages"][topic] += n_msgs
    FIGURES["divergences"][topic] = f.divergences
    print(f"\n{topic}: {n_msgs} fuzzed messages, rejections {dict(core.rejections_by_topic)}")
    assert n_msgs >= PER_TOPIC


def test_speed_messages(wall):
    _scalar_fuzz(wall, SPEED, wall.node.inputs.on_speed)


def test_steering_messages(wall):
    _scalar_fuzz(wall, STEER, wall.node.inputs.on_steering)


#: message kinds of the strategies that must always be accepted / always be rejected (the others depend
#: on the drawn values)
ALWAYS_OK = {PROFILE: {"valid"}, HEIGHTS: {"valid", "extreme"}}
ALWAYS_BAD = {PROFILE: {"nonincreasing", "empty", "wrong_count", "swapped", "one_dim", "huge_z"},
              HEIGHTS: {"count", "empty"}}


def _array_fuzz(f: FuzzNode, topic: str, handler, strategy) -> None:
    node, core = f.node, f.node.core
    n_msgs, kinds = 0, Counter()

    @FUZZ
    @given(st.lists(strategy(), **BURST))
    def burst(items):
        nonlocal n_msgs
        r0 = sum(n for (tp, _), n in core.rejections_by_topic.items() if tp == topic)
        for msg, kind in items:
            handler(msg, None)
            kinds[kind] += 1
        node.tick()
        n_bad = sum(n for (tp, _), n in core.rejections_by_topic.items() if tp == topic) - r0
        must_bad = sum(1 for _, k in items if k in ALWAYS_BAD[topic])
        must_ok = sum(1 for _, k in items if k in ALWAYS_OK[topic])
        assert must_bad <= n_bad <= len(items) - must_ok  # accepted or rejected (counted), never lost
        if items[-1][1] in ALWAYS_OK[topic]:
            assert core.last_input_ns.get(topic) is not None
        if topic == PROFILE and core.road is not None:
            assert np.all(np.diff(core.road.s) > 0) and np.all(np.isfinite(core.road.zl))
            assert np.all(np.abs(core.road.zl) <= 1.0) and np.all(np.abs(core.road.zr) <= 1.0)
        if topic == HEIGHTS and core.wheel_heights is not None:
            assert core.wheel_heights.shape == (4,) and np.all(np.abs(core.wheel_heights) <= 1.0)
        n_msgs += len(items)
        f.after_burst()

    burst()
    f.check_logging(topic)
    FIGURES["messages"][topic] += n_msgs
    FIGURES["divergences"][topic] = f.divergences
    print(f"\n{topic}: {n_msgs} fuzzed messages by kind {dict(kinds)}, rejections "
          f"{ {c: n for (tp, c), n in core.rejections_by_topic.items() if tp == topic} }")
    assert n_msgs >= PER_TOPIC


def test_road_profile_messages(wall):
    _array_fuzz(wall, PROFILE, wall.node.inputs.on_profile, profile_msgs)


def test_wheel_heights_messages(wall):
    _array_fuzz(wall, HEIGHTS, wall.node.inputs.on_wheel_heights, heights_msgs)


# ---- sim time: /clock (and inputs) with invalid, stale, shuffled, backward and far-ahead times ---------
@st.composite
def clock_event(draw):
    kind = draw(st.sampled_from(["fwd", "fwd", "fwd", "fwd", "same", "stale", "back", "jump", "invalid",
                                 "random", "speed", "steer"]))
    # source timestamp relative to now: shuffled arrival order, all older than the reorder window
    src = draw(st.integers(-80_000_000, -60_000_000))  # (the node's window: sim_reorder_window_s, 20 ms)
    if kind == "fwd":
        return kind, draw(st.integers(1, 20_000_000)), src
    if kind == "same":
        return kind, 0, src
    if kind == "stale":
        return kind, -draw(st.integers(1, 10_000_000)), src
    if kind == "back":
        return kind, -draw(st.integers(10_000_001, 5_000_000_000)), src
    if kind == "jump":
        return kind, draw(st.integers(10_000_000_001, 10 ** 15)), src
    if kind == "invalid":
        sec = draw(st.one_of(st.integers(-2 ** 31, -1), st.just(0), st.integers(0, 2 ** 31 - 1)))
        nsec = draw(st.one_of(st.integers(10 ** 9, 2 ** 32 - 1), st.just(0)))
        if sec > 0 and nsec == 0:
            nsec = 10 ** 9
        return kind, (sec, nsec), src
    if kind == "random":
        return kind, (draw(st.integers(-2 ** 31, 2 ** 31 - 1)), draw(st.integers(0, 2 ** 32 - 1))), src
    return kind, draw(st.one_of(st.floats(0.0, 40.0), st.sampled_from(EDGE_FLOATS))), src


def test_clock_messages_under_sim_time(simnode):
    from rosgraph_msgs.msg import Clock
    from std_msgs.msg import Float64
    f = simnode
    node, core = f.node, f.node.core
    n_clock, kinds = 0, Counter()
    base = [2_000_000_000]

    def clock(t_or_pair, src):
        m = Clock()
        if isinstance(t_or_pair, tuple):
            m.clock.sec, m.clock.nanosec = t_or_pair
        else:
            m.clock.sec, m.clock.nanosec = divmod(int(t_or_pair), 1_000_000_000)
        node.inputs.on_clock(m, {"source_timestamp": src})

    # start: an input and a clock so that the core runs
    now = time.time_ns()
    node.inputs.on_speed(Float64(data=10.0), {"source_timestamp": now - 2_000_000_000})
    clock(base[0], now - 1_000_000_000)

    @settings(FUZZ, max_examples=420)  # a sixth of the events are inputs (speed, steering)
    @given(st.lists(clock_event(), **BURST))
    def burst(events):
        nonlocal n_clock
        inv0 = core.rejections_by_topic[(CLOCK, "clock_invalid")]
        want_invalid = 0
        now = time.time_ns()
        for kind, val, src in events:
            kinds[kind] += 1
            cur = max(node.now_ns(), 1)
            if kind == "speed":
                node.inputs.on_speed(Float64(data=val), {"source_timestamp": now + src})
                continue
            if kind == "steer":
                node.inputs.on_steering(Float64(data=val), {"source_timestamp": now + src})
                continue
            n_clock += 1
            if kind == "invalid":
                want_invalid += 1
                clock(val, now + src)
            elif kind == "random":
                sec, nsec = val
                if sec < 0 or nsec >= 10 ** 9 or (sec == 0 and nsec == 0):
                    want_invalid += 1
                clock(val, now + src)
            else:
                t = cur + val
                if t <= 0 or t >= 2 ** 31 * 1_000_000_000:
                    t = cur
                clock(t, now + src)
        # a final clock published after everything else releases the inputs still queued
        # older than the window
        clock(max(node.now_ns(), 1), time.time_ns() - node.inputs.orderer.window_ns - 1_000_000)
        assert core.rejections_by_topic[(CLOCK, "clock_invalid")] - inv0 == want_invalid
        assert len(node.inputs.orderer) == 0  # nothing stuck in the reorder queue
        f.after_burst()

    burst()
    f.check_logging(CLOCK)
    FIGURES["messages"][CLOCK] += n_clock
    FIGURES["divergences"][CLOCK] = f.divergences
    FIGURES["restarts_under_sim_time"] = core.restarts
    print(f"\n/clock: {n_clock} fuzzed clock messages by kind {dict(kinds)}; rejections "
          f"{ {c: n for (tp, c), n in core.rejections_by_topic.items() if tp == CLOCK} }, "
          f"{core.restarts} restarts, {core.time_jumps} jumps not stepped through")
    assert n_clock >= PER_TOPIC
    assert core.restarts > 0 and core.time_jumps > 0
    assert core.rejections_by_topic[(CLOCK, "clock_stale")] > 0


def test_fuzzed_recordings_hold_only_finite_states(wall, simnode):
    """Close both fuzzed nodes: their recordings finalise and hold no non-finite /sim value."""
    if not FIGURES["messages"]:
        pytest.skip("checks the recordings of the fuzz tests above; run the whole file")
    figures = {}
    for name, f in (("wall", wall), ("sim", simnode)):
        samples = f.node.published
        n, bad = f.close()
        assert bad == 0 and n == 3 * samples and samples > 0, (name, n, bad, samples)
        figures[name] = {"published_samples": samples, "recorded_sim_messages": n, "non_finite": bad,
                         "divergences_caught": f.divergences}
        f.close = lambda: (0, 0)  # already closed (fixture teardown)
    print(f"\nfuzz figures: messages {dict(FIGURES['messages'])}; recordings {figures}; "
          f"log lines per cause {dict(FIGURES['log_lines'])}")


def test_bad_inputs_through_dds_into_a_live_node():
    """A smaller sample through DDS (publisher node -> subscription -> the same handlers): the node takes
    every message, rejects the bad ones, keeps stepping and publishing finite outputs."""
    from _ros_helpers import SimDriver
    from std_msgs.msg import MultiArrayDimension
    rng = np.random.default_rng(7)
    d = SimDriver({"on_divergence": "hold"})
    try:
        node, core = d.node, d.node.core
        T = 1_000_000_000
        d.clock(T)
        d.send_value(SPEED, 12.0)
        d.send_value(STEER, 0.2)
        sent = Counter()
        for _ in range(40):
            T += 10_000_000
            d.clock(T)
            before = node.inputs.inputs_taken
            burst = []
            for _ in range(25):
                v = float(rng.choice(EDGE_FLOATS)) if rng.random() < 0.7 else float(rng.uniform(0, 30))
                burst.append((SPEED if rng.random() < 0.5 else STEER, d.Float64(data=v)))
            for _ in range(8):
                m = d.Float64MultiArray()
                n = int(rng.integers(0, 6))
                m.layout.dim = [MultiArrayDimension(label="x", size=int(rng.integers(0, 2 ** 32)), stride=0)
                                for _ in range(n % 3)]
                m.data = [float(x) for x in rng.choice(EDGE_FLOATS, n)]
                burst.append((HEIGHTS if n % 2 else PROFILE, m))
            for topic, m in burst:
                if topic == PROFILE:  # latched, depth 1: one at a time, or only the last one arrives
                    continue
                d.pub[topic].publish(m)
                sent[topic] += 1
            n_burst = sum(1 for tp, _ in burst if tp != PROFILE)
            d.spin_until(lambda want=before + n_burst: node.inputs.inputs_taken >= want)
            for topic, m in burst:
                if topic == PROFILE:
                    d.send(topic, m)
                    sent[topic] += 1
            for sec, nsec in ((-5, 2 ** 32 - 1), (-2 ** 31, 0), (3, 10 ** 9), (0, 0)):
                bad = d.Clock()
                bad.clock.sec, bad.clock.nanosec = sec, nsec
                d.pub_clock.publish(bad)
                sent[CLOCK] += 1
        inv = core.rejections_by_topic[(CLOCK, "clock_invalid")]
        d.spin_until(lambda: core.rejections_by_topic[(CLOCK, "clock_invalid")] >= 160)
        d.clock(T + 500_000_000)
        d.wait_samples(90)  # 1.01 .. 1.90 s
        t, g = d.imu_arrays()
        assert len(t) >= 90 and np.all(np.isfinite(g)) and core.healthy
        assert node.inputs.handler_errors == 0 and core.rejections_by_topic[(CLOCK, "clock_invalid")] >= inv
        total = sum(core.rejections.values())
        assert total > 500
        lines = sum(node.rejection_log.emitted.values())
        assert lines <= len(core.rejections_by_topic)  # once per cause
        print(f"\nthrough DDS: sent {dict(sent)}, rejected {total} in {len(core.rejections_by_topic)} causes, "
              f"{lines} log lines, {len(t)} finite IMU samples published")
    finally:
        d.close()


@settings(max_examples=300, deadline=None, derandomize=True, database=None)
@given(st.lists(st.tuples(st.text(max_size=8), st.integers(0, 2 ** 32 - 1), st.integers(0, 2 ** 32 - 1)), max_size=3),
       st.integers(0, 2 ** 32 - 1), st.lists(st.floats(allow_nan=False), max_size=20))
def test_fast_array_encoder_decodes_like_rclpy(dims, offset, data):
    """The node records Float64MultiArray inputs with the numpy CDR encoder: rclpy decodes it to the same
    message its own serialiser describes (bytes may differ only in padding)."""
    from rclpy.serialization import deserialize_message, serialize_message
    from std_msgs.msg import Float64MultiArray, MultiArrayDimension
    from susp_sim_ros.io.messages import encode_float64_multiarray
    m = Float64MultiArray()
    m.layout.dim = [MultiArrayDimension(label=a, size=b, stride=c) for a, b, c in dims]
    m.layout.data_offset = offset
    m.data = data
    fast = deserialize_message(encode_float64_multiarray(dims, offset, data), Float64MultiArray)
    ref = deserialize_message(serialize_message(m), Float64MultiArray)
    assert fast == ref
    if not any("\x00" in a for a, _, _ in dims):  # (CDR strings end at a NUL, in both encoders)
        assert fast == m
