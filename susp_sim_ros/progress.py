"""Progress for long commands: a tqdm bar on a terminal, plain periodic lines where nobody watches.

Every long command (``susp study``, ``validate --study``, ``diagnose``, ``paper``, ``replay``,
``generate``) makes its progress with :func:`progress`. On a terminal (the stream's ``isatty()``) it is a
tqdm bar; otherwise (a log file, CI, a pipe) one plain line at most every :data:`LINE_INTERVAL_S`
(``study: 120/363 run (33 %), 41 s, about 83 s left``) and, if any line was written, a last one when it
closes: a short run writes nothing, a long one leaves a readable record and no carriage returns.
``SUSP_PROGRESS=bar|lines|off`` overrides the choice (``auto``, the default, decides by ``isatty``).
"""
from __future__ import annotations

import os
import sys
import time
from typing import IO

from .errors import SuspInputError

__all__ = ["progress", "PlainProgress", "LINE_INTERVAL_S", "MODES"]

LINE_INTERVAL_S = 10.0  # at most one plain progress line per this many seconds [s]
MODES = ("auto", "bar", "lines", "off")
ENV = "SUSP_PROGRESS"


class PlainProgress:
    """The tqdm calls our commands use (``update``, ``set_postfix_str``, ``reset``, ``close``, ``n``,
    ``total``, context manager), written as plain lines at most every ``interval_s`` seconds."""

    def __init__(self, total: float | None = None, *, desc: str = "", unit: str = "it", initial: float = 0,
                 stream: IO[str] | None = None, interval_s: float = LINE_INTERVAL_S, enabled: bool = True,
                 clock=time.monotonic):
        self.total, self.desc, self.unit = total, desc, unit
        self.n = self._start_n = initial
        self.stream = stream if stream is not None else sys.stderr
        self.interval_s, self.enabled, self._clock = interval_s, enabled, clock
        self.postfix = ""
        self._t0 = self._last = clock()
        self.lines = 0
        self._closed = False

    def _fmt(self, x: float) -> str:
        return f"{x:g}" if isinstance(x, int) or float(x).is_integer() else f"{x:.1f}"

    def line(self, final: bool = False) -> str:
        elapsed = self._clock() - self._t0
        head = f"{self.desc}: " if self.desc else ""
        if self.total:
            pct = 100.0 * self.n / self.total
            text = f"{head}{self._fmt(self.n)}/{self._fmt(self.total)} {self.unit} ({pct:.0f} %)"
        else:
            text = f"{head}{self._fmt(self.n)} {self.unit}"
        text += f", {elapsed:.0f} s"
        done = self.n - self._start_n
        if not final and self.total and done > 0 and self.n < self.total:
            text += f", about {elapsed / done * (self.total - self.n):.0f} s left"
        if final:
            text += ", done"
        return text + (f" [{self.postfix}]" if self.postfix else "")

    def _emit(self, final: bool = False) -> None:
        print(self.line(final), file=self.stream, flush=True)
        self.lines += 1
        self._last = self._clock()

    def update(self, n: float = 1) -> None:
        self.n += n
        if self.enabled and self._clock() - self._last >= self.interval_s:
            self._emit()

    def set_postfix_str(self, s: str = "", refresh: bool = True) -> None:
        self.postfix = str(s)

    def reset(self, total: float | None = None) -> None:
        self.n = self._start_n = 0
        if total is not None:
            self.total = total

    def close(self) -> None:
        if not self._closed and self.enabled and self.lines:
            self._emit(final=True)
        self._closed = True

    def __enter__(self) -> "PlainProgress":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _mode(stream: IO[str]) -> str:
    mode = os.environ.get(ENV, "auto").strip().lower() or "auto"
    if mode not in MODES:
        raise SuspInputError(f"environment variable {ENV}={mode!r}: expected one of {', '.join(MODES)}")
    if mode == "auto":
        isatty = getattr(stream, "isatty", None)
        mode = "bar" if isatty is not None and isatty() else "lines"
    return mode


def progress(total: float | None = None, *, desc: str = "", unit: str = "it", enabled: bool = True,
             initial: float = 0, stream: IO[str] | None = None, interval_s: float = LINE_INTERVAL_S,
             **tqdm_kwargs):
    """A progress object for a long loop on ``stream`` (default stderr): tqdm on a terminal, else
    :class:`PlainProgress`; silent when ``enabled`` is false. ``tqdm_kwargs`` (``leave``,
    ``bar_format``, ``smoothing``...) only shape the bar."""
    stream = stream if stream is not None else sys.stderr
    mode = _mode(stream) if enabled else "off"
    if mode == "bar":
        from tqdm import tqdm
        tqdm_kwargs.setdefault("dynamic_ncols", True)
        return tqdm(total=total, desc=desc, unit=unit, initial=initial, file=stream, **tqdm_kwargs)
    return PlainProgress(total, desc=desc, unit=unit, initial=initial, stream=stream, interval_s=interval_s,
                         enabled=mode == "lines")
