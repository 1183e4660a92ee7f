"""The sim-time reorder queue: ``/clock`` and inputs back in publish order (pure, no rclpy).

In sim time ROS 2 gives no order across topics, and a busy executor may take an input before the
``/clock`` message published just before it (or after the next one). So ``/clock`` and the inputs go
through one queue ordered by the publishers' source timestamps [ns] (ties: arrival order):

- an input is released once a ``/clock`` published after it has arrived (per topic DDS keeps order, so
  every earlier ``/clock`` is in the queue by then), or when it is ``input_wait_max_ns`` old (wall time)
  with no later ``/clock``;
- a ``/clock`` is released once it is ``window_ns`` old (wall time), so that inputs published before it
  can still be sorted in. Before it is released the caller's ``pull`` takes every message DDS already
  holds into the queue (a lagging executor takes one message per subscription per round): the window
  then only has to cover DDS delivery, not the executor's backlog.

An input published after ``/clock`` t and before the next ``/clock`` thus takes effect exactly at t, as in
the offline lockstep run, at any replay rate.
"""
from __future__ import annotations

import heapq
from collections.abc import Callable
from typing import Any

CLOCK, INPUT = 0, 1
#: an input with no later /clock is released after this long anyway (wall time) [ns]
INPUT_WAIT_MAX_NS = 500_000_000


class SimTimeOrderer:
    """Events ``(source timestamp [ns], kind, payload)`` in, released in publish order by :meth:`drain`.

    ``window_ns``: how long (wall time) a ``/clock`` waits for inputs published before it [ns].
    """

    def __init__(self, window_ns: int, input_wait_max_ns: int = INPUT_WAIT_MAX_NS):
        self.window_ns = int(window_ns)
        self.input_wait_max_ns = int(input_wait_max_ns)
        self._events: list[tuple[int, int, int, Any]] = []  # (source ns, arrival number, kind, payload)
        self._seq = 0
        self.max_clock_src_ns = 0  # newest source timestamp of a /clock queued so far

    def __len__(self) -> int:
        """Events waiting."""
        return len(self._events)

    def push(self, src_ns: int, kind: int, payload: Any) -> None:
        """Queue a ``/clock`` (``kind`` :data:`CLOCK`) or an input (:data:`INPUT`) published at ``src_ns``."""
        if kind not in (CLOCK, INPUT):
            raise ValueError(f"kind: expected CLOCK (0) or INPUT (1), got {kind!r}")
        self._seq += 1
        heapq.heappush(self._events, (int(src_ns), self._seq, kind, payload))
        if kind == CLOCK:
            self.max_clock_src_ns = max(self.max_clock_src_ns, int(src_ns))

    def drain(self, now_ns: int, on_clock: Callable[[Any], None], on_input: Callable[[Any], None],
              pull: Callable[[], None] = lambda: None) -> int:
        """Release every event due at wall time ``now_ns`` [ns], in publish order, to ``on_clock`` /
        ``on_input`` (their payloads). ``pull`` is called once before each ``/clock`` is released and
        may :meth:`push` more events (those published earlier are then released first). Returns the
        number released."""
        released = 0
        pulled = False
        while self._events:
            src, _, kind, payload = self._events[0]
            if kind == CLOCK:
                if src > now_ns - self.window_ns:
                    break
                if not pulled:  # inputs published before this /clock may still wait in DDS
                    pulled = True
                    pull()
                    continue
            elif not (src < self.max_clock_src_ns or src <= now_ns - self.input_wait_max_ns):
                break
            heapq.heappop(self._events)
            released += 1
            if kind == CLOCK:
                pulled = False
                on_clock(payload)
            else:
                on_input(payload)
        return released
