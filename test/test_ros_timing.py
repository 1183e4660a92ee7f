"""The node's publish-timing statistics: whole-run percentiles from a log-linear histogram."""
from __future__ import annotations

import time

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from susp_sim_ros.ros.timing import DurationHistogram, TimingStats

PERIOD = 1_000_000  # 1 kHz [ns]


def nearest_rank(values: np.ndarray, p: float) -> float:
    return float(np.sort(values)[max(1, int(np.ceil(p / 100 * values.size))) - 1])


@settings(max_examples=200, deadline=None)
@given(st.lists(st.integers(0, 10**11), min_size=1, max_size=300), st.sampled_from([0.0, 1.0, 50.0, 90.0, 99.0, 100.0]))
def test_histogram_percentile_within_its_resolution(values, p):
    """Any durations (0 to 100 s): the percentile is the exact nearest-rank value within 1 us below
    1 ms and 0.2 % above; the maximum is exact."""
    h = DurationHistogram()
    for v in values:
        h.add(v)
    exact = nearest_rank(np.array(values, dtype=np.int64), p)
    assert abs(h.percentile_ns(p) - exact) <= max(1000.0, 2e-3 * exact)
    assert h.max_ns == max(values)


def test_bins_are_contiguous_and_ordered():
    """Bin index grows with the duration and each bin's centre lies inside the durations it counts."""
    h = DurationHistogram()
    us = np.unique(np.geomspace(1, 1e9, 4000).astype(np.int64))
    idx = [h.index(u * 1000) for u in us]
    assert all(b >= a for a, b in zip(idx, idx[1:]))
    for u, i in zip(us, idx):
        assert abs(h.bin_centre_ns(i) - u * 1000) <= max(1000.0, 2e-3 * u * 1000)


def test_whole_run_summary_costs_the_same_after_an_hour():
    """An hour of 1 kHz ticks: the summary's figures match the exact ones and it still takes well under
    a millisecond (a long percentile over a buffer held the GIL against the tick thread)."""
    rng = np.random.default_rng(3)
    late = rng.gamma(2.0, 60_000.0, 3_600_000).astype(np.int64)
    late[::50_000] = 3 * PERIOD  # rare misses
    tm = TimingStats(PERIOD)
    for v in late[:20_000].tolist():
        tm.record(0, v)
    small = min(_time(tm.summary) for _ in range(5))
    for v in late[20_000:].tolist():
        tm._late.add(v)  # the rest straight into the histogram (the record path is tested above)
    tm.ticks = late.size
    s = tm.summary()
    assert abs(s["lateness_p99_ms"] - nearest_rank(late, 99) * 1e-6) <= 2e-3 * s["lateness_p99_ms"] + 1e-3
    assert abs(s["lateness_p50_ms"] - nearest_rank(late, 50) * 1e-6) <= 1e-3
    big = min(_time(tm.summary) for _ in range(5))
    assert big < 1e-3 and big < 5 * small + 2e-4


def _time(f) -> float:
    t = time.perf_counter()
    f()
    return time.perf_counter() - t


def test_misses_and_jitter_counted():
    tm = TimingStats(PERIOD)
    pubs = [0, PERIOD + 10_000, 2 * PERIOD + 5_000, 3 * PERIOD + 2 * PERIOD]  # the last 2 ms late
    for k, p in enumerate(pubs):
        tm.record(k * PERIOD, p)
    s = tm.summary()
    assert s["deadline_misses"] == 1 and s["ticks"] == 4
    assert abs(s["jitter_max_ms"] - 1.995) < 1e-9
    assert abs(s["lateness_p50_ms"] - 0.0055) <= 1e-3


def test_start_up_heap_is_collected_then_frozen():
    """Garbage left by start-up is collected (a reference cycle is freed, not frozen forever) and every
    survivor goes to the permanent generation, so no later full collection walks it in real time."""
    import gc
    import weakref

    from susp_sim_ros.ros.timing import freeze_start_up_heap

    class Cycle:
        pass

    a = Cycle()
    a.self = a
    dead = weakref.ref(a)
    del a
    alive = Cycle()
    try:
        freeze_start_up_heap()
        assert dead() is None
        assert gc.get_freeze_count() > 0
        assert not any(o is alive for o in gc.get_objects())  # frozen objects are out of every generation
    finally:
        gc.unfreeze()


def test_warm_up_loads_the_semi_active_family_before_real_time():
    """The first damper command must not load the damper family (~20 ms of YAML) inside a tick."""
    from susp_sim_ros.model.params import DEFAULT_VEHICLE
    from susp_sim_ros.model.vehicle import Model
    from susp_sim_ros.ros.parameters import warm_up

    model = Model(DEFAULT_VEHICLE, "full")
    assert model._dampers is None
    warm_up(model)
    assert model._dampers is not None
