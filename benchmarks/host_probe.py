"""A plain sleeping-thread probe of the machine's own stalls, run beside a real-time measurement.

One probe process per CPU this process may run on, each pinned to its CPU and (when permitted) at
SCHED_FIFO above the node's threads (:data:`PROBE_PRIORITY`), sleeps to absolute deadlines
:data:`PROBE_PERIOD_S` apart and records every wake later than :data:`RECORD_MIN_LATENESS_S` as a
:class:`~susp_sim_ros.analysis.host_stalls.Stall` (previous wake, late wake, lateness). Nothing of ours
runs above it, so what delays it is the machine: the hypervisor, the kernel, real-time throttling.
A separate process per CPU (not a thread of the measuring process) keeps the measuring process's GIL and
its other threads out of the figures, and sees a stall of either virtual CPU.

``HostProbe`` starts and stops the processes; ``python benchmarks/host_probe.py`` is one probe (it
prints one JSON object when stopped with SIGINT/SIGTERM or after ``--max-duration``). No ROS.
"""
from __future__ import annotations

import argparse
import json
import os
import select
import signal
import subprocess
import sys
import time
from pathlib import Path

from susp_sim_ros.analysis.host_stalls import Stall

__all__ = ["HostProbe", "PROBE_PERIOD_S", "PROBE_PRIORITY", "run_probe"]

PROBE_PERIOD_S = 0.001          # sleep period [s]: the stall resolution (misses of interest are > 10 ms)
#: wakes later than this [s] are kept as stalls (the rest only in the max): above the probe's ordinary wake
#: latency (p99 0.18 ms at SCHED_FIFO on this 2-vCPU VM, idle, 2026-11-29), below the slices a hypervisor
#: takes a busy host's virtual CPU away in (idle there: 45 wakes of 0.25-1 ms in 8 s, 20 ms together, against
#: one of 1.3 ms above 1 ms), so that the host time inside a deadline miss counts them
RECORD_MIN_LATENESS_S = 0.00025
PROBE_PRIORITY = 20             # SCHED_FIFO priority: above the node's threads (realtime_priority 10, tick 11)
MAX_STALLS_KEPT = 100_000       # a bound on memory if the machine stalls all the time
READY = "probing"               # the probe's first line on stderr once its loop runs
READY_TIMEOUT_S = 20.0          # start-up allowance of a probe process (Python start on a busy machine)


class _Stop(Exception):
    pass


def run_probe(period_s: float = PROBE_PERIOD_S, record_min_s: float = RECORD_MIN_LATENESS_S,
              max_duration_s: float = 3600.0, ready_line: bool = False) -> dict:
    """Sleep to absolute deadlines ``period_s`` apart until SIGINT/SIGTERM or ``max_duration_s``;
    returns ``{"period_ns", "wakes", "lateness_max_ns", "stalls": [[start_ns, end_ns, lateness_ns], ...],
    "start_ns", "end_ns"}`` on the ``time.time_ns`` clock. ``ready_line``: say :data:`READY` on stderr
    when the loop starts."""
    def stop(signum, frame):
        raise _Stop
    old = {s: signal.signal(s, stop) for s in (signal.SIGINT, signal.SIGTERM)}
    period = int(period_s * 1e9)
    record_min = int(record_min_s * 1e9)
    stalls: list[list[int]] = []
    wakes = 0
    late_max = 0
    t_start = prev = time.time_ns()
    t_end_max = t_start + int(max_duration_s * 1e9)
    deadline = t_start + period
    if ready_line:
        print(READY, file=sys.stderr, flush=True)
    try:
        while prev < t_end_max:
            wait = deadline - time.time_ns()
            if wait > 0:
                time.sleep(wait * 1e-9)
            now = time.time_ns()
            late = now - deadline
            wakes += 1
            if late > late_max:
                late_max = late
            if late >= record_min and len(stalls) < MAX_STALLS_KEPT:
                stalls.append([prev, now, late])
            prev = now
            # after a stall, start a fresh schedule instead of a burst of catch-up wakes
            deadline = deadline + period if late < period else now + period
    except _Stop:
        pass
    finally:
        for s, h in old.items():
            signal.signal(s, h)
    return {"period_ns": period, "wakes": wakes, "lateness_max_ns": late_max, "stalls": stalls,
            "start_ns": t_start, "end_ns": time.time_ns()}


def _read_line(fd: int, deadline: float) -> str | None:
    """One line from a pipe, byte by byte (no read-ahead), or None at end of file or at ``deadline``
    (``time.monotonic``)."""
    buf = b""
    while True:
        ready, _, _ = select.select([fd], [], [], max(0.0, deadline - time.monotonic()))
        if not ready:
            return None
        c = os.read(fd, 1)
        if not c:
            return None
        if c == b"\n":
            return buf.decode(errors="replace").strip()
        buf += c


class HostProbe:
    """Probe processes, one per CPU, for the lifetime of a ``with`` block (or :meth:`start`/:meth:`stop`).

    After :meth:`stop`: ``stalls`` (all CPUs, time-ordered), ``lateness_max_ns``, ``wakes``,
    ``period_ns``, ``notes`` (e.g. real-time scheduling not permitted)."""

    def __init__(self, period_s: float = PROBE_PERIOD_S, priority: int = PROBE_PRIORITY,
                 max_duration_s: float = 3600.0, cpus: list[int] | None = None):
        self.period_s, self.priority, self.max_duration_s = period_s, priority, max_duration_s
        self.cpus = sorted(os.sched_getaffinity(0)) if cpus is None else list(cpus)
        self._procs: list[subprocess.Popen] = []
        self.stalls: list[Stall] = []
        self.lateness_max_ns = 0
        self.wakes = 0
        self.period_ns = int(period_s * 1e9)
        self.notes: list[str] = []

    def start(self) -> "HostProbe":
        for cpu in self.cpus:
            args = [sys.executable, str(Path(__file__).resolve()), "--period-ms", str(self.period_s * 1e3),
                    "--cpu", str(cpu), "--priority", str(self.priority), "--max-duration", str(self.max_duration_s)]
            # unbuffered, so that select() sees every line still unread
            self._procs.append(subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, bufsize=0))
        end = time.monotonic() + READY_TIMEOUT_S
        for cpu, p in zip(self.cpus, self._procs):  # each says READY on stderr once it probes
            while True:
                line = _read_line(p.stderr.fileno(), end)
                if line == READY:
                    break
                if line is None:  # timed out or the probe ended: stop() reports why
                    self.notes.append(f"cpu {cpu}: probe not ready after {READY_TIMEOUT_S:g} s")
                    break
                self.notes.append(f"cpu {cpu}: {line}")
        return self

    @property
    def pids(self) -> list[int]:
        """Process ids of the running probes (e.g. to leave them out of a list of other busy processes)."""
        return [p.pid for p in self._procs]

    def stop(self) -> "HostProbe":
        for p in self._procs:
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
        for cpu, p in zip(self.cpus, self._procs):
            try:
                out, err = p.communicate(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()
                out, err = p.communicate()
            out, err = out.decode(errors="replace"), err.decode(errors="replace")
            self.notes += [f"cpu {cpu}: {line}" for line in err.splitlines() if line.strip()]
            if p.returncode == -signal.SIGTERM and not out.strip():
                self.notes.append(f"cpu {cpu}: stopped before it started probing")
                continue
            if p.returncode != 0 or not out.strip():
                raise RuntimeError(f"host probe on cpu {cpu} failed (exit {p.returncode}): {err.strip()[-300:]}")
            d = json.loads(out)
            self.stalls += [Stall(*s, cpu=cpu) for s in d["stalls"]]
            self.lateness_max_ns = max(self.lateness_max_ns, int(d["lateness_max_ns"]))
            self.wakes += int(d["wakes"])
        self._procs = []
        self.stalls.sort(key=lambda s: s.start_ns)
        return self

    def __enter__(self) -> "HostProbe":
        return self.start()

    def __exit__(self, *exc) -> None:
        if self._procs:
            if exc[0] is None:
                self.stop()
            else:  # the measurement failed: end the probes, keep the original error
                for p in self._procs:
                    p.kill()
                    p.wait()
                self._procs = []


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description="one sleeping-thread probe of host stalls; JSON on stdout when stopped")
    ap.add_argument("--period-ms", type=float, default=PROBE_PERIOD_S * 1e3, help="sleep period [ms]")
    ap.add_argument("--record-min-ms", type=float, default=RECORD_MIN_LATENESS_S * 1e3,
                    help="keep wakes later than this as stalls [ms]")
    ap.add_argument("--cpu", type=int, default=None, help="pin to this CPU")
    ap.add_argument("--priority", type=int, default=PROBE_PRIORITY, help="SCHED_FIFO priority (0: normal)")
    ap.add_argument("--max-duration", type=float, default=3600.0, help="stop after this long [s]")
    a = ap.parse_args(argv)
    if a.period_ms <= 0 or a.record_min_ms < 0 or a.max_duration <= 0:
        print("host_probe: --period-ms and --max-duration must be > 0, --record-min-ms >= 0", file=sys.stderr)
        return 2
    if a.cpu is not None:
        os.sched_setaffinity(0, {a.cpu})
    if a.priority > 0:
        try:
            os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(a.priority))
        except (OSError, AttributeError) as exc:
            print(f"no real-time scheduling ({exc}); probing at normal priority", file=sys.stderr)
    print(json.dumps(run_probe(a.period_ms * 1e-3, a.record_min_ms * 1e-3, a.max_duration, ready_line=True)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
