"""The node's recording, off the real-time path: a deque and a writer thread in front of
:class:`~susp_sim_ros.io.recorder.McapRecorder` (no rclpy)."""
from __future__ import annotations

import heapq
import threading
from collections import deque
from collections.abc import Callable

from ..io.recorder import McapRecorder

#: Log-time window [ns] within which the recording thread puts messages back into log-time order. They
#: come from two threads (tick thread, executor); /diagnostics is logged no earlier than the samples
#: recorded before it, and this window catches any other race (a preempted thread). A finalised file is
#: indexed, but a killed one is read in file order, and rosbags refuses one whose log times go backwards
#: (seen once in 80 killed recordings before both measures).
RECORD_REORDER_NS = 50_000_000


#: Longest wait [s] of the recording thread for a :meth:`RecordingQueue.kick` before it writes what is queued
#: anyway (sim time paused, no ticks): the recording reaches the disk in idle periods too.
RECORD_IDLE_WAKE_S = 0.1


class RecordingQueue:
    """The node's recording, off the real-time path: the tick thread and the callbacks only append
    ``(topic, type, time, CDR bytes or a function making them)`` to a deque (no lock, no wake-up); a writer
    thread encodes input messages, writes (mcap, chunk compression, the kill-safe commits of
    :class:`McapRecorder`) and flushes. It works when kicked (:meth:`kick`, after each publish tick: then
    the tick thread sleeps until its next deadline, so the two do not take turns at the interpreter lock
    within a tick), or after :data:`RECORD_IDLE_WAKE_S` without a kick. A wake-up per message (a
    ``queue.Queue``) cost 18 us a message in the tick thread and a lock hand-over to the writer inside
    every tick. It holds each message until one at least :data:`RECORD_REORDER_NS` later (log time) is
    queued and writes in log-time order, so the file is sorted even where the producing threads raced (a
    kill loses at most that window more than the recorder's flush interval). A full queue (``max_items``,
    a disk that cannot keep up) drops messages, counted in ``dropped``; a write error (disk full) stops
    the recording with one error log (``error``) instead of the node."""

    def __init__(self, recorder: McapRecorder, log_error, max_items: int = 200_000):
        self.recorder, self._log_error = recorder, log_error
        self._items: deque = deque()  # append and popleft are atomic: no lock needed
        self._wake = threading.Event()
        self.max_items = max_items
        self.dropped = 0
        self.error = ""
        self.closed = False
        self._thread = threading.Thread(target=self._run, name="susp_sim_record", daemon=True)
        self._thread.start()

    def write(self, topic: str, msgtype: str, t_ns: int, data, latched: bool = False) -> None:
        if self.closed or self.error:
            return
        if len(self._items) >= self.max_items:
            self.dropped += 1
            return
        self._items.append((topic, msgtype, t_ns, data, latched))

    def kick(self) -> None:
        """Let the writer work now (the node calls this after a publish tick)."""
        self._wake.set()

    def flush_if_due(self) -> None:
        if not self.closed:
            self._items.append(None)
            self._wake.set()

    def _run(self) -> None:
        held: list = []  # (log time, arrival number, item) heap
        arrived, newest = 0, None
        while True:
            self._wake.wait(RECORD_IDLE_WAKE_S)
            self._wake.clear()
            while self._items:
                item = self._items.popleft()
                if item is StopIteration:
                    if not self.error:
                        self._write_held(held, None)
                    return
                if self.error:
                    continue
                if item is None:  # what is due first, then the flush
                    if newest is not None:
                        self._write_held(held, newest - RECORD_REORDER_NS)
                    self._write_held([], None, flush=True)
                    continue
                arrived += 1
                heapq.heappush(held, (item[2], arrived, item))
                newest = item[2] if newest is None else max(newest, item[2])
            if newest is not None and not self.error:
                self._write_held(held, newest - RECORD_REORDER_NS)

    def _write_held(self, held: list, upto: int | None, flush: bool = False) -> None:
        """Write the held messages with log time <= ``upto`` (all: ``None``), oldest first; then flush
        if due (``flush``). A write error stops the recording (disk full, file removed), not the node."""
        try:
            while held and (upto is None or held[0][0] <= upto):
                topic, msgtype, t_ns, data, latched = heapq.heappop(held)[2]
                self.recorder.write(topic, msgtype, t_ns, data() if callable(data) else data, latched=latched)
            if flush:
                self.recorder.flush_if_due()
        except Exception as exc:
            self.error = f"{type(exc).__name__}: {exc}"
            self._log_error(f"recording stopped: {self.error}")

    def close(self) -> None:
        """Write everything queued, then finalise the file (idempotent)."""
        if self.closed:
            return
        self.closed = True
        self._items.append(StopIteration)
        self._wake.set()
        if self._thread is not threading.current_thread():
            self._thread.join()
        try:
            self.recorder.close()
        except Exception as exc:
            self.error = self.error or f"{type(exc).__name__}: {exc}"
            self._log_error(f"recording not finalised: {exc}")


def open_recording(path: str, metadata: dict, overwrite: bool, flush_interval_s: float,
                   log_error: Callable[[str], None]) -> RecordingQueue:
    """The node's recording to the MCAP file ``path`` (:class:`McapRecorder`: ``metadata``, ``overwrite``,
    ``flush_interval_s`` [s]) behind a :class:`RecordingQueue`; ``log_error`` reports a write error."""
    return RecordingQueue(McapRecorder(path, metadata=metadata, overwrite=overwrite,
                                       flush_interval_s=flush_interval_s), log_error)
