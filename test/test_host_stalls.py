"""Attribution of deadline misses to host stalls (synthetic miss/stall timelines), the miss log the node
lists on /diagnostics, and the sleeping-thread probe itself (a short real run)."""
from __future__ import annotations

import time

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from susp_sim_ros.analysis.host_stalls import Miss, Stall, attribute, format_miss_log, host_time, parse_miss_log
from benchmarks.host_probe import HostProbe

MS = 1_000_000
PERIOD = 10 * MS  # the node's publish period at 100 Hz


def stall(end_ms: float, late_ms: float, probe_period_ms: float = 1.0) -> Stall:
    """A probe stall as the probe records it: previous wake one probe period before the deadline."""
    end = int(end_ms * MS)
    late = int(late_ms * MS)
    return Stall(end - late - int(probe_period_ms * MS), end, late)


def test_miss_inside_a_longer_stall_is_the_hosts():
    # the host stopped everything for 14 ms from t = 1000 ms; the node's tick due at 1005 ms came 12 ms late
    a = attribute([Miss(1005 * MS, 12 * MS)], [stall(1014, 14)])
    assert len(a.explained) == 1 and a.unexplained == []


def test_miss_longer_than_every_stall_is_the_nodes():
    # a 4 ms stall (the VM's common tick-sized one) cannot make a tick 25 ms late
    a = attribute([Miss(1005 * MS, 25 * MS)], [stall(1008, 4)], tolerance_ns=2 * MS)
    assert a.explained == [] and a.unexplained == [Miss(1005 * MS, 25 * MS)]


def test_long_stall_elsewhere_in_time_explains_nothing():
    # a 30 ms stall two seconds earlier does not explain a 12 ms miss now
    a = attribute([Miss(5000 * MS, 12 * MS)], [stall(3030, 30)])
    assert a.unexplained == [Miss(5000 * MS, 12 * MS)]


def test_tolerance_covers_probe_resolution_and_node_work():
    # the stall hit while the node was stepping its tick: late by the stall (13 ms, probe saw 12.4 ms)
    # plus the tick's own 0.5 ms of work; the probe period (1 ms) and the node's p99 lateness cover it
    m = Miss(2000 * MS, int(13.5 * MS))
    s = stall(2013.4, 12.4)
    assert attribute([m], [s], tolerance_ns=0).unexplained == [m]
    assert attribute([m], [s], tolerance_ns=int(1.6 * MS)).explained == [(m, s)]


def test_stall_touching_the_miss_interval_at_either_end_overlaps():
    m = Miss(1000 * MS, 11 * MS)                       # occupies [1000, 1011] ms
    before = Stall(980 * MS, 1000 * MS, 15 * MS)       # ends at the deadline
    after = Stall(1011 * MS, 1030 * MS, 15 * MS)       # starts at the publish
    for s in (before, after):
        assert attribute([m], [s]).explained == [(m, s)]
    assert attribute([m], [Stall(1012 * MS, 1030 * MS, 15 * MS)]).unexplained == [m]


def test_mixed_timeline_counts_each_miss_once_and_names_the_longest_stall():
    stalls = [stall(1014, 14), stall(1013, 4), stall(7050, 16), stall(9000, 4)]
    misses = [Miss(1003 * MS, 11 * MS), Miss(7040 * MS, 15 * MS), Miss(9000 * MS, 20 * MS),
              Miss(12000 * MS, 11 * MS)]
    a = attribute(misses, stalls, tolerance_ns=int(1.5 * MS))
    assert [m for m, _ in a.explained] == misses[:2]
    assert a.explained[0][1].lateness_ns == 14 * MS  # the 14 ms stall, not the 4 ms one beside it
    assert a.unexplained == misses[2:]


def test_short_stalls_add_up():
    # steal time in slices: the hypervisor took CPU 1 away four times for 3 ms within a 12 ms-late tick
    m = Miss(1000 * MS, 12 * MS)                                  # occupies [1000, 1012] ms
    slices = [Stall(s.start_ns, s.end_ns, s.lateness_ns, 1) for s in (stall(1003, 3), stall(1006, 3),
                                                                      stall(1009, 3), stall(1012, 3))]
    a = attribute([m], slices, tolerance_ns=int(1.5 * MS))
    assert [x for x, _ in a.explained] == [m]
    assert a.explained[0][1].lateness_ns == 12 * MS
    # one slice fewer leaves 9 ms of host time: not enough for a 12 ms miss with 1.5 ms of tolerance
    assert attribute([m], slices[1:], tolerance_ns=int(1.5 * MS)).unexplained == [m]


def test_host_time_is_the_time_any_cpu_was_stalled_once():
    # both CPUs stalled over [1000, 1006] at once: 6 ms, not 12; one after the other: 12 ms
    at_once = [Stall(999 * MS, 1006 * MS, 6 * MS, 0), Stall(999 * MS, 1006 * MS, 6 * MS, 1)]
    one_after_other = [Stall(999 * MS, 1006 * MS, 6 * MS, 0), Stall(1005 * MS, 1012 * MS, 6 * MS, 1)]
    assert host_time(at_once, 1000 * MS, 1012 * MS) == 6 * MS
    assert host_time(one_after_other, 1000 * MS, 1012 * MS) == 12 * MS
    assert host_time(one_after_other + [Stall(1003 * MS, 1005 * MS, 2 * MS)], 1000 * MS, 1012 * MS) == 12 * MS
    m = Miss(1000 * MS, 12 * MS)
    tol = int(1.5 * MS)
    assert attribute([m], at_once, tol).unexplained == [m]
    assert [x for x, _ in attribute([m], one_after_other, tol).explained] == [m]


def test_only_the_part_of_a_stall_inside_the_miss_counts():
    m = Miss(1000 * MS, 12 * MS)                                  # occupies [1000, 1012] ms
    # 8 ms stall ending 4 ms into the miss: 4 ms inside; 6 ms stall ending at 1010: [1004, 1010] -> 10 ms
    parts = [Stall(990 * MS, 1004 * MS, 8 * MS, 0), Stall(1003 * MS, 1010 * MS, 6 * MS, 1)]
    assert host_time(parts, m.tick_ns, m.end_ns) == 10 * MS
    assert attribute([m], parts, tolerance_ns=1 * MS).unexplained == [m]     # 10 + 1 < 12
    a = attribute([m], parts, tolerance_ns=2 * MS)
    assert a.explained[0][1].lateness_ns == 10 * MS               # 10 + 2 >= 12


def test_a_tick_due_while_the_previous_one_was_late_carries_its_backlog():
    # a 20 ms stall from the deadline at 1000 ms: that tick is published at 1022 (22 ms late), the next,
    # due at 1010, right after it at 1023 (13 ms late, 1 ms of its own): both the host's
    stall_ = stall(1020, 20)
    first, second = Miss(1000 * MS, 22 * MS), Miss(1010 * MS, 13 * MS)
    a = attribute([first, second], [stall_], tolerance_ns=int(2.5 * MS))
    assert a.unexplained == [] and [m for m, _ in a.explained] == [first, second]
    # the next tick taking 15 ms of its own after that publish, with no stall then, is the node's
    late_own = Miss(1010 * MS, 27 * MS)
    a = attribute([first, late_own], [stall_], tolerance_ns=int(2.5 * MS))
    assert a.unexplained == [late_own]
    # a backlog the node caused stays the node's: the first tick 22 ms late with no stall at all
    a = attribute([first, second], [], tolerance_ns=int(2.5 * MS))
    assert a.unexplained == [first, second]


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 10_000), st.integers(PERIOD + 1, 60 * MS)), max_size=20),
       st.lists(st.tuples(st.integers(0, 10_000), st.integers(0, 60 * MS), st.sampled_from([None, 0, 1])),
                max_size=20),
       st.integers(0, 3 * MS))
def test_attribution_partitions_the_misses(miss_spec, stall_spec, tol):
    misses = [Miss(t * MS, late) for t, late in miss_spec]
    stalls = [Stall(t * MS, t * MS + late + MS, late, cpu) for t, late, cpu in stall_spec]
    a = attribute(misses, stalls, tol)
    assert sorted([m for m, _ in a.explained] + a.unexplained, key=lambda m: (m.tick_ns, m.lateness_ns)) == \
        sorted(misses, key=lambda m: (m.tick_ns, m.lateness_ns))
    for m, s in a.explained:  # every explanation satisfies the rule: the host took the miss's own part
        assert s.start_ns <= m.end_ns and s.end_ns >= m.tick_ns
        assert s.lateness_ns + tol >= m.end_ns - max(s.start_ns, m.tick_ns)
    assert attribute(misses, [], tol).unexplained == sorted(misses, key=lambda m: m.tick_ns)


def test_inconsistent_inputs_are_refused():
    with pytest.raises(ValueError, match="inconsistent stall"):
        Stall(10, 5, 1)
    with pytest.raises(ValueError, match="inconsistent stall"):
        Stall(0, 5 * MS, 6 * MS)  # late by more than it was away
    with pytest.raises(ValueError, match="tolerance_ns"):
        attribute([], [], -1)


@given(st.lists(st.tuples(st.integers(0, 2**62), st.integers(0, 2**40)), max_size=100))
def test_miss_log_round_trip(items):
    assert parse_miss_log(format_miss_log(items)) == [Miss(t, late) for t, late in items]


def test_malformed_miss_log_is_a_named_error():
    with pytest.raises(ValueError, match="deadline_miss_log.*'12x'"):
        parse_miss_log("1:2,12x")


def test_node_timing_lists_its_misses():
    from susp_sim_ros.ros.timing import TimingStats
    tm = TimingStats(PERIOD)
    for k, late in enumerate([MS, 2 * MS, 15 * MS, MS, 30 * MS]):
        tm.record(k * PERIOD, k * PERIOD + late)
    s = tm.summary()
    assert s["deadline_misses"] == 2
    assert parse_miss_log(s["deadline_miss_log"]) == [Miss(2 * PERIOD, 15 * MS), Miss(4 * PERIOD, 30 * MS)]


def test_probe_sees_a_stall_it_is_given():
    """Two pinned probe processes for half a second, one of them stopped (SIGSTOP) for 60 ms: that CPU's
    probe records a stall of about 60 ms at that time; the probe's own wakes are counted."""
    import os
    import signal
    probe = HostProbe(max_duration_s=30.0).start()
    try:
        time.sleep(0.05)  # start() returned once both probe
        p = probe._procs[0]
        t0 = time.time_ns()
        os.kill(p.pid, signal.SIGSTOP)
        time.sleep(0.06)
        os.kill(p.pid, signal.SIGCONT)
        t1 = time.time_ns()
        time.sleep(0.1)
    finally:
        probe.stop()
    assert probe.wakes > 200  # about 1 per ms per CPU
    long = [s for s in probe.stalls if s.lateness_ns > 40 * MS]
    assert len(long) == 1, probe.stalls
    s = long[0]
    assert s.start_ns <= t0 + 2 * MS and s.end_ns >= t1 - 2 * MS  # the stall lies where we made it
    assert probe.lateness_max_ns == max(x.lateness_ns for x in probe.stalls)
    assert attribute([Miss(t0 + MS, 50 * MS)], probe.stalls, 2 * MS).unexplained == []


def test_probe_without_real_time_scheduling_still_probes_and_says_so():
    """Where SCHED_FIFO is refused (here: an invalid priority), the probe runs at normal priority and
    says why in its notes instead of failing."""
    probe = HostProbe(priority=1000, max_duration_s=30.0).start()
    time.sleep(0.05)
    probe.stop()
    assert probe.wakes > 20
    assert any("no real-time scheduling" in n for n in probe.notes), probe.notes
