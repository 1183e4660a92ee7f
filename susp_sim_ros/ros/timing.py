"""Real-time timing of the wall-time node: SCHED_FIFO priority, the tick thread with absolute deadlines,
and the publish-timing statistics reported on ``/diagnostics`` (no rclpy)."""
from __future__ import annotations

import gc
import os
import threading
import time
from collections import deque
from collections.abc import Callable

import numpy as np

from ..analysis.host_stalls import format_miss_log

#: Python's thread switch interval while the node runs [s]: the tick thread must get the GIL promptly
#: when its deadline comes, not after the default 5 ms of a busy executor thread.
SWITCH_INTERVAL_S = 0.0001

MISS_LOG_KEEP = 100  # recent deadline misses listed on /diagnostics (a 1 Hz reader loses none below 100/s)


class DurationHistogram:
    """Durations [ns] counted in log-linear bins (the HdrHistogram layout, Tene): 1 us wide below
    :data:`LINEAR_US` us, then 1/:data:`SUB_BINS` of the value wide (0.2 %). Adding is one store and the
    percentiles of a whole run (an hour at 1 kHz or longer) cost the same few microseconds as of a second,
    so no long C call holds the GIL against the tick thread and the figures cover every tick, not a window.
    The maximum is kept exactly."""

    LINEAR_US = 1024
    SUB_BINS = LINEAR_US // 2

    def __init__(self) -> None:
        self.counts = np.zeros(64 * self.SUB_BINS, dtype=np.int64)  # any int64 duration in us
        self.n = 0
        self.max_ns = 0

    def index(self, ns: int) -> int:
        us = max(int(ns), 0) // 1000
        if us < self.LINEAR_US:
            return us
        shift = us.bit_length() - 10
        return shift * self.SUB_BINS + (us >> shift)

    def bin_centre_ns(self, i: int) -> float:
        """Middle of bin ``i`` [ns]."""
        if i < self.LINEAR_US:
            return (i + 0.5) * 1000.0
        shift = i // self.SUB_BINS - 1
        low = (i - shift * self.SUB_BINS) << shift
        return (low + 0.5 * (1 << shift)) * 1000.0

    def add(self, ns: int) -> None:
        self.counts[self.index(ns)] += 1
        self.n += 1
        if ns > self.max_ns:
            self.max_ns = ns

    def percentile_ns(self, p: float) -> float:
        """The ``p``-th percentile [ns] (nearest rank, the middle of its bin, never above the maximum);
        0 when empty."""
        if not self.n:
            return 0.0
        rank = max(1, int(np.ceil(p / 100.0 * self.n)))
        i = int(np.searchsorted(np.cumsum(self.counts), rank))
        return min(self.bin_centre_ns(i), float(self.max_ns))


class TimingStats:
    """Publish timing in wall-time mode: period deviation (jitter), lateness, deadline misses, over the
    whole run (:class:`DurationHistogram`, 1 us or 0.2 % resolution, the maxima exact).

    The last :data:`MISS_LOG_KEEP` misses (deadline and lateness [ns], ``time.time_ns`` clock) are listed
    on ``/diagnostics`` as ``deadline_miss_log`` so a benchmark can set them beside host stalls
    (:mod:`~susp_sim_ros.analysis.host_stalls`)."""

    def __init__(self, period_ns: int):
        self.period_ns = period_ns
        self._jit = DurationHistogram()
        self._late = DurationHistogram()
        self.deadline_misses = 0
        self.miss_log: deque[tuple[int, int]] = deque(maxlen=MISS_LOG_KEEP)  # (tick_ns, lateness_ns)
        self.ticks = 0
        self._last_pub: int | None = None

    def record(self, tick_ns: int, published_ns: int) -> None:
        late = published_ns - tick_ns
        self._late.add(late)
        self.ticks += 1
        if late > self.period_ns:
            self.deadline_misses += 1
            self.miss_log.append((tick_ns, late))
        if self._last_pub is not None:
            self._jit.add(abs(published_ns - self._last_pub - self.period_ns))
        self._last_pub = published_ns

    def summary(self) -> dict[str, float | int | str]:
        ms = 1e-6
        return {"jitter_p50_ms": self._jit.percentile_ns(50) * ms, "jitter_p99_ms": self._jit.percentile_ns(99) * ms,
                "jitter_max_ms": self._jit.max_ns * ms,
                "lateness_p50_ms": self._late.percentile_ns(50) * ms,
                "lateness_p99_ms": self._late.percentile_ns(99) * ms,
                "deadline_misses": self.deadline_misses, "ticks": self.ticks,
                "deadline_miss_log": format_miss_log(self.miss_log)}


def freeze_start_up_heap() -> None:
    """Collect once and move every object alive after start-up (the imports of numpy, scipy, numba, rclpy,
    the compiled model) to the collector's permanent generation (:func:`gc.freeze`), before real time begins.

    Why: a full (generation 2) collection walks every tracked object and holds the GIL throughout. With the
    ~110 000 start-up objects it took 90-280 ms on a 2-core host (measured 2026-12-01); in real time it would
    stop the tick thread and the executor alike, and every input would wait in DDS that long. Frozen objects
    are never scanned again, so later collections cover only what
    the run allocates (a full one after the freeze: microseconds). Call it once, after the last start-up
    allocation and before the tick thread starts."""
    gc.collect()
    gc.freeze()


def raise_priority(priority: int) -> str:
    """SCHED_FIFO ``priority`` for every thread of this process so far (executor, DDS receive threads),
    so other processes cannot preempt a thread that holds the GIL the tick thread needs. Returns a
    note if not permitted (then normal scheduling is kept)."""
    if priority <= 0:
        return "real-time scheduling off (realtime_priority 0)"
    try:
        tids = [int(t) for t in os.listdir("/proc/self/task")]
        for tid in tids:
            os.sched_setscheduler(tid, os.SCHED_FIFO, os.sched_param(priority))
    except (OSError, AttributeError, ValueError) as exc:
        return f"no real-time scheduling ({exc}); using normal priority"
    return ""



class TickThread:
    """Wall-time stepping: a thread that wakes at each publish tick (absolute deadlines from
    ``next_tick_ns()``, ``time.time_ns`` clock [ns], so no drift) and calls ``tick(now_ns)``.

    ``priority`` > 0: the thread runs SCHED_FIFO one above the process's other threads
    (:func:`raise_priority`), else with normal scheduling (also when not permitted: ``log`` says so).
    ``begin()`` runs once in the thread before the first tick; ``ok()`` false ends the loop. An exception
    from ``tick`` goes to ``on_error`` (the thread never dies silently) unless the node is shutting down.
    """

    def __init__(self, *, priority: int, begin: Callable[[], None], next_tick_ns: Callable[[], int],
                 tick: Callable[[int], object], ok: Callable[[], bool],
                 on_error: Callable[[Exception], None], log: Callable[[str], None]):
        self.priority = int(priority)
        self._begin, self._next, self._tick, self._ok = begin, next_tick_ns, tick, ok
        self._on_error, self._log = on_error, log
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="susp_sim_tick", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def stop(self, timeout_s: float = 2.0) -> None:
        """Ask the thread to end and wait for it up to ``timeout_s`` [s] (idempotent)."""
        self._stop.set()
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join(timeout=timeout_s)

    def _run(self) -> None:
        if self.priority > 0:
            try:  # one above the process's other threads
                os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(self.priority + 1))
            except (OSError, AttributeError) as exc:
                self._log(f"tick thread: no real-time scheduling ({exc}); using normal priority")
        self._begin()
        while not self._stop.is_set() and self._ok():
            wait = (self._next() - time.time_ns()) * 1e-9
            if wait > 0:
                if self._stop.wait(wait):
                    break
            try:
                self._tick(time.time_ns())
            except Exception as exc:
                if self._stop.is_set() or not self._ok():
                    break  # shutting down (SIGINT): the context went away under a publish
                self._on_error(exc)
