"""The sim-time reorder queue (pure, no rclpy): /clock and inputs released in publish order, whatever
order they arrive in, with the wall-time window and the wait limit of inputs."""
from __future__ import annotations

import subprocess
import sys

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from susp_sim_ros.ros.sim_time import CLOCK, INPUT, INPUT_WAIT_MAX_NS, SimTimeOrderer

WINDOW = 20_000_000  # 20 ms, the node's default sim_reorder_window_s
NOW = 10**18         # wall time [ns] far after every source timestamp below


def run(orderer: SimTimeOrderer, now: int, pull=lambda: None) -> list:
    out: list = []
    orderer.drain(now, lambda t: out.append(("clock", t)), lambda p: out.append(("input", p)), pull)
    return out


@pytest.mark.parametrize("module", ["sim_time", "timing", "recording", "status", "parameters"])
def test_the_shells_pure_parts_import_no_rclpy(module):
    """The reorder queue, timing, recording queue, statuses and parameter table run without rclpy."""
    code = f"import sys, susp_sim_ros.ros.{module}; sys.exit(2 if 'rclpy' in sys.modules else 0)"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, f"susp_sim_ros.ros.{module} pulled in rclpy (rc {r.returncode}): {r.stderr[-500:]}"


@st.composite
def replay(draw):
    """A replay: /clock at increasing times, each followed by 0..3 inputs; the publish (source)
    timestamps increase in publish order; the arrival order is any permutation of it."""
    n_clock = draw(st.integers(1, 12))
    published = []
    src = 1_000
    for k in range(n_clock):
        src += draw(st.integers(1, 5_000_000))
        published.append((src, CLOCK, 1_000_000_000 + 10_000_000 * k))
        for j in range(draw(st.integers(0, 3))):
            src += draw(st.integers(1, 5_000_000))
            published.append((src, INPUT, f"in{k}.{j}"))
    arrival = draw(st.permutations(published))
    return published, arrival


@settings(max_examples=300, deadline=None, derandomize=True, database=None)
@given(replay())
def test_any_arrival_order_is_released_in_publish_order(case):
    """Every event released once, in publish order: an input published between /clock t1 and t2 comes
    after t1 and before t2, as in the lockstep run; the last inputs wait for their wait limit."""
    published, arrival = case
    q = SimTimeOrderer(WINDOW)
    for src, kind, payload in arrival:
        q.push(src, kind, payload)
    assert len(q) == len(published)
    last_clock_src = max(src for src, kind, _ in published if kind == CLOCK)
    out = run(q, last_clock_src + WINDOW)  # every /clock is old enough, no input has waited long
    want = [("clock" if k == CLOCK else "input", p) for s, k, p in published if s <= last_clock_src]
    assert out == want
    tail = [("input", p) for s, k, p in published if s > last_clock_src]
    assert len(q) == len(tail)
    if tail:  # inputs after the last clock wait for the wait limit (wall time since published)
        first = min(s for s, k, _ in published if s > last_clock_src)
        assert run(q, first + INPUT_WAIT_MAX_NS - 1) == []
    assert run(q, published[-1][0] + INPUT_WAIT_MAX_NS) == tail
    assert len(q) == 0


@settings(max_examples=200, deadline=None, derandomize=True, database=None)
@given(st.lists(st.integers(0, 10 * WINDOW), min_size=1, max_size=20), st.integers(0, 10 * WINDOW))
def test_a_clock_waits_for_the_reorder_window(srcs, now):
    """A /clock is released only once it is the window old (wall time), in source order."""
    q = SimTimeOrderer(WINDOW)
    for s in srcs:
        q.push(s, CLOCK, s)
    out = run(q, now)
    due = sorted(s for s in srcs if s <= now - WINDOW)
    assert [t for _, t in out] == due
    assert len(q) == len(srcs) - len(due)


def test_pull_before_a_due_clock_sorts_in_inputs_still_waiting_in_dds():
    """The pull before each due /clock may queue inputs published before it: they go first; it is called
    once per /clock released (and once more for the clock still too young, which ends the drain)."""
    q = SimTimeOrderer(WINDOW)
    q.push(100, CLOCK, 1)
    q.push(300, CLOCK, 2)
    backlog = [(50, INPUT, "before 1"), (200, INPUT, "between"), (400, INPUT, "after 2")]
    calls = []

    def pull():
        calls.append(len(q))
        while backlog:
            q.push(*backlog.pop(0))

    out = run(q, 300 + WINDOW, pull)
    assert out == [("input", "before 1"), ("clock", 1), ("input", "between"), ("clock", 2)]
    assert len(calls) == 2 and len(q) == 1  # "after 2" waits for a later /clock
    q.push(500 + 0, CLOCK, 3)
    assert run(q, 500 + WINDOW) == [("input", "after 2"), ("clock", 3)]


def test_same_source_time_keeps_arrival_order_and_bad_kinds_are_refused():
    q = SimTimeOrderer(WINDOW)
    q.push(10, INPUT, "a")
    q.push(10, INPUT, "b")
    q.push(10, CLOCK, 7)
    q.push(11, CLOCK, 8)
    assert run(q, NOW) == [("input", "a"), ("input", "b"), ("clock", 7), ("clock", 8)]
    with pytest.raises(ValueError, match="kind"):
        q.push(1, 2, None)


@settings(max_examples=300, deadline=None, derandomize=True, database=None)
@given(replay(), st.data())
def test_streamed_with_delivery_delays_under_the_window_gives_publish_order(case, data):
    """As in a running node: each event arrives (wall time) up to the window after it was published,
    /clock messages in publish order (one topic), inputs in any order that implies, and the queue is
    drained at every arrival; what comes out is the publish
    order, and once the last /clock is the window old only the inputs after it are left."""
    published, _ = case
    delays = data.draw(st.lists(st.integers(0, WINDOW - 1), min_size=len(published), max_size=len(published)))
    arrive, last_clock = [], 0
    for (src, kind, _), d in zip(published, delays):
        t = src + d
        if kind == CLOCK:  # one topic: DDS delivers /clock in publish order
            t = last_clock = max(t, last_clock)
        arrive.append(t)
    arrivals = sorted((t, k, event) for k, (t, event) in enumerate(zip(arrive, published)))
    q = SimTimeOrderer(WINDOW)
    out: list = []
    for t_arrive, _, (src, kind, payload) in arrivals:
        q.push(src, kind, payload)
        out += run(q, t_arrive)
    last_clock_src = max(src for src, kind, _ in published if kind == CLOCK)
    out += run(q, max(last_clock_src + WINDOW, arrivals[-1][0]))
    want = [("clock" if k == CLOCK else "input", p) for s, k, p in published if s <= last_clock_src]
    assert out == want
