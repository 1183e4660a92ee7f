"""Real-time timing of the wall-time node: SCHED_FIFO priority, the tick thread with absolute deadlines,
and the publish-timing statistics reported on ``/diagnostics`` (no rclpy)."""
from __future__ import annotations

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


class TimingStats:
    """Publish timing in wall-time mode: period deviation (jitter), lateness, deadline misses.

    The last :data:`MISS_LOG_KEEP` misses (deadline and lateness [ns], ``time.time_ns`` clock) are listed
    on ``/diagnostics`` as ``deadline_miss_log`` so a benchmark can set them beside host stalls
    (:mod:`~susp_sim_ros.analysis.host_stalls`).

    Ring buffers in numpy arrays: recording is one store, the summary never converts Python lists
    (a long C call would hold the GIL against the tick thread)."""

    def __init__(self, period_ns: int, keep: int = 360_000):
        self.period_ns = period_ns
        self._jit = np.zeros(keep, dtype=np.int64)
        self._late = np.zeros(keep, dtype=np.int64)
        self._jit.fill(0)  # touch every page now: memory is flat from the start, not growing for an hour
        self._late.fill(0)
        self._n_jit = 0
        self.deadline_misses = 0
        self.miss_log: deque[tuple[int, int]] = deque(maxlen=MISS_LOG_KEEP)  # (tick_ns, lateness_ns)
        self.ticks = 0
        self._last_pub: int | None = None

    def record(self, tick_ns: int, published_ns: int) -> None:
        keep = self._late.size
        late = published_ns - tick_ns
        self._late[self.ticks % keep] = late
        self.ticks += 1
        if late > self.period_ns:
            self.deadline_misses += 1
            self.miss_log.append((tick_ns, late))
        if self._last_pub is not None:
            self._jit[self._n_jit % keep] = abs(published_ns - self._last_pub - self.period_ns)
            self._n_jit += 1
        self._last_pub = published_ns

    def summary(self) -> dict[str, float | int | str]:
        j = self._jit[:min(self._n_jit, self._jit.size)] * 1e-6
        lt = self._late[:min(self.ticks, self._late.size)] * 1e-6
        q = lambda a, p: float(np.percentile(a, p)) if a.size else 0.0
        return {"jitter_p50_ms": q(j, 50), "jitter_p99_ms": q(j, 99),
                "jitter_max_ms": float(j.max()) if j.size else 0.0,
                "lateness_p50_ms": q(lt, 50), "lateness_p99_ms": q(lt, 99),
                "deadline_misses": self.deadline_misses, "ticks": self.ticks,
                "deadline_miss_log": format_miss_log(self.miss_log)}


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
