"""Attribution of real-time deadline misses to host stalls (pure: no threads, no ROS).

A *host stall* is what a plain sleeping thread sees when the machine itself does not run it: the probe
(:mod:`host_probe`) sleeps to absolute deadlines one period apart and records each wake
that came late. A stall is the interval from the probe's previous wake (the last instant it was seen
running) to the late wake, with the wake's lateness as its length: the machine stopped the probe for at
least that long (for at most the whole interval).

A *deadline miss* of the node is a tick published more than one period after its deadline; it occupies
the interval from the deadline to the publish.

A miss is *explained* by the host when the host took at least as long as the miss is late, less
``tolerance_ns``, in one of two ways:

- one stall overlaps it and is that long; or
- the host time inside the miss interval adds up to that long: the time during which any CPU was
  stalled (the union of the stalls, so a pause of the whole machine counts once). A hypervisor that
  shares a busy host often takes a virtual CPU away in many short slices rather than one long one
  (steal time), which the probe records one by one; and a stall of either CPU can hold the tick thread,
  which needs the interpreter's lock that a thread of the node on the stalled CPU may hold. This is the
  most the host can have taken: a miss beyond it is the node's for sure. A stall of lateness L that
  ended at E kept the probe off at least over [E - L, E]; only that part inside the interval counts.

A tick due while the previous one was still being published carries its backlog: it could not start
before that publish, so the part of its lateness up to it is the previous miss's, and only the rest,
from the previous publish to its own, is weighed against the host time in between; it is the host's when
that previous miss was too (a backlog the node caused stays the node's).

The probe sees a stall only to within its own period (a stall of D shows as a lateness between
D - period and D), and a stall that hits while the node is stepping a tick delays that tick by the stall
plus the tick's ordinary work. So the tolerance is the probe's period plus the node's ordinary lateness
(its p99 in the same run). Every other miss is *unexplained*: the node's own.

Times are integer nanoseconds on one clock (``time.time_ns``, the clock the node stamps its ticks with).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from collections.abc import Iterable, Sequence

__all__ = ["Stall", "Miss", "Attribution", "attribute", "host_time", "parse_miss_log", "format_miss_log"]


@dataclass(frozen=True)
class Stall:
    """The probe was not run between ``start_ns`` (its previous wake) and ``end_ns`` (the late wake),
    and woke ``lateness_ns`` after its deadline [ns]; ``cpu``: the CPU the probe was pinned to (None:
    not known)."""
    start_ns: int
    end_ns: int
    lateness_ns: int
    cpu: int | None = None

    def __post_init__(self):
        if self.end_ns < self.start_ns or self.lateness_ns < 0 or self.lateness_ns > self.end_ns - self.start_ns:
            raise ValueError(f"inconsistent stall {self}: need start <= end and 0 <= lateness <= end - start")


@dataclass(frozen=True)
class Miss:
    """A tick due at ``tick_ns`` published ``lateness_ns`` after it [ns]."""
    tick_ns: int
    lateness_ns: int

    @property
    def end_ns(self) -> int:
        return self.tick_ns + self.lateness_ns


@dataclass
class Attribution:
    """``explained``: (miss, the stall that explains it: the longest single one, else the host time inside
    the miss's own interval, from the previous publish when it carries a backlog, as one ``Stall`` spanning
    that interval, ``cpu`` None); ``unexplained``: the rest."""
    explained: list[tuple[Miss, Stall]] = field(default_factory=list)
    unexplained: list[Miss] = field(default_factory=list)


def attribute(misses: Iterable[Miss], stalls: Sequence[Stall], tolerance_ns: int = 0) -> Attribution:
    """Split ``misses`` into those a host stall explains and those it does not (module docstring).

    ``tolerance_ns`` >= 0: how much longer than the stall a miss may be late and still be the host's."""
    if tolerance_ns < 0:
        raise ValueError(f"tolerance_ns must be >= 0, got {tolerance_ns}")
    out = Attribution()
    prev_end: int | None = None   # the latest publish of a miss so far
    prev_host = True              # whether that miss was the host's
    for m in sorted(misses, key=lambda m: m.tick_ns):
        backlog = prev_end is not None and prev_end > m.tick_ns
        start = min(prev_end, m.end_ns) if prev_end is not None and backlog else m.tick_ns
        over = [s for s in stalls if s.start_ns <= m.end_ns and s.end_ns >= m.tick_ns
                and s.lateness_ns + tolerance_ns >= m.lateness_ns]
        host = bool(over)
        if over:
            out.explained.append((m, max(over, key=lambda s: s.lateness_ns)))
        elif prev_host or not backlog:
            lost = host_time(stalls, start, m.end_ns)
            host = lost + tolerance_ns >= m.end_ns - start
            if host:
                out.explained.append((m, Stall(start, m.end_ns, lost)))
        if not host:
            out.unexplained.append(m)
        if prev_end is None or m.end_ns >= prev_end:
            prev_end, prev_host = m.end_ns, host
    return out


def host_time(stalls: Sequence[Stall], start_ns: int, end_ns: int) -> int:
    """How long [ns] any CPU was stalled between ``start_ns`` and ``end_ns``: the union of the stalls'
    parts [end - lateness, end] inside that interval (a pause of several CPUs at once counts once)."""
    parts = sorted((max(s.end_ns - s.lateness_ns, start_ns), min(s.end_ns, end_ns)) for s in stalls
                   if s.end_ns > start_ns and s.end_ns - s.lateness_ns < end_ns)
    total, reach = 0, start_ns
    for a, b in parts:
        a = max(a, reach)
        if b > a:
            total += b - a
            reach = b
    return total


def format_miss_log(misses: Iterable[tuple[int, int]]) -> str:
    """``"tick_ns:lateness_ns,..."``: how the node lists its recent misses on ``/diagnostics``."""
    return ",".join(f"{t}:{late}" for t, late in misses)


def parse_miss_log(text: str) -> list[Miss]:
    """The inverse of :func:`format_miss_log`; a malformed entry raises ``ValueError`` naming it."""
    out = []
    for item in filter(None, (x.strip() for x in text.split(","))):
        try:
            t, late = item.split(":")
            out.append(Miss(int(t), int(late)))
        except ValueError:
            raise ValueError(f"deadline_miss_log: malformed entry {item!r} (expected tick_ns:lateness_ns)") from None
    return out
