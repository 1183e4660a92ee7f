"""Figures rendered beside the computation: a report's PNGs drawn in a forked child process while the
parent goes on (matplotlib draws on one core; a diagnosis's dozen figures took 8-12 s of its run).

Only pure drawing goes to a child: everything a figure shows is computed before it is submitted (a
child forked from a process whose compiled kernels have started threads must not run them). Where
``fork`` is not available (Windows, macOS' default), or with one core, figures are drawn in place.
"""
from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable

Task = tuple[str, Callable[..., object], tuple]


def _spare_cores() -> int:
    try:
        n = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        n = os.cpu_count() or 1
    return max(0, n - 1)


def _draw_all(tasks: list[Task]) -> None:
    for _, draw, args in tasks:
        draw(*args)


class FigureRenderer:
    """Collect drawing calls with :meth:`submit`; :meth:`flush` hands what is collected to a child
    process (when a spare core is free) and returns at once; :meth:`wait` (or leaving the ``with``
    block) shares what is left between the caller and the children as they come free (the caller draws
    one figure at a time, a free child takes half of what is left), returns once every figure is written
    and raises when one failed, naming it."""

    def __init__(self, parallel: bool = True):
        self._ctx = (multiprocessing.get_context("fork")
                     if parallel and "fork" in multiprocessing.get_all_start_methods() else None)
        self._spare = _spare_cores()
        self._pending: list[Task] = []
        self._running: list[tuple[multiprocessing.process.BaseProcess, list[str]]] = []
        self._failed: list[str] = []

    def submit(self, what: str, draw: Callable[..., object], *args) -> None:
        """Draw ``draw(*args)`` later (``what``: the figure, for the error message)."""
        self._pending.append((what, draw, args))

    def _free(self) -> bool:
        for entry in [r for r in self._running if not r[0].is_alive()]:
            self._running.remove(entry)
            self._check(*entry)
        return self._ctx is not None and len(self._running) < self._spare

    def _start(self, tasks: list[Task]) -> None:
        assert self._ctx is not None
        p = self._ctx.Process(target=_draw_all, args=(tasks,), daemon=True)
        p.start()
        self._running.append((p, [t[0] for t in tasks]))

    def _check(self, p, what: list[str]) -> None:
        p.join()
        if p.exitcode != 0:
            self._failed.append(f"{', '.join(what)} (exit code {p.exitcode})")

    def flush(self) -> None:
        """Start drawing what is collected in a child, if a spare core is free (else it waits)."""
        if self._pending and self._free():
            self._start(self._pending)
            self._pending = []

    def wait(self) -> None:
        pending, self._pending = self._pending, []
        while pending:  # the caller draws one figure at a time; a child that is free takes half the rest
            if len(pending) > 1 and self._free():
                half = len(pending) // 2
                self._start(pending[half:])
                pending = pending[:half]
                continue
            _draw_all(pending[:1])
            pending = pending[1:]
        while self._running:
            self._check(*self._running.pop(0))
        if self._failed:
            failed, self._failed = self._failed, []
            raise RuntimeError("figures not written: " + "; ".join(failed) + " (the drawing process's error is "
                               "on stderr above)")

    def __enter__(self) -> "FigureRenderer":
        return self

    def __exit__(self, *exc) -> None:
        if exc[0] is None:
            self.wait()
        else:  # an error in the parent: let the children finish, report the parent's error
            for p, _ in self._running:
                p.join()
            self._running.clear()
