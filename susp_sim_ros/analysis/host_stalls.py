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
- the stalls of one CPU within the miss interval add up to that long. A hypervisor that shares a busy
  host often takes a virtual CPU away in several short slices rather than one long one (steal time): a
  thread on that CPU loses their sum, while the probe records each slice apart. A stall of lateness L
  that ended at E kept the probe off at least over [E - L, E]; only that part inside the miss interval
  counts. Stalls of different CPUs are never added (the same pause of the whole machine would count
  twice), nor stalls whose CPU is not known (``cpu`` None).

The probe sees a stall only to within its own period (a stall of D shows as a lateness between
D - period and D), and a stall that hits while the node is stepping a tick delays that tick by the stall
plus the tick's ordinary work. So the tolerance is the probe's period plus the node's ordinary lateness
(its p99 in the same run). Every other miss is *unexplained*: the node's own.

Times are integer nanoseconds on one clock (``time.time_ns``, the clock the node stamps its ticks with).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from collections.abc import Iterable, Sequence

__all__ = ["Stall", "Miss", "Attribution", "attribute", "summed_on_one_cpu", "parse_miss_log", "format_miss_log"]


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
    """``explained``: (miss, the stall that explains it: the longest single one, else the stalls of one
    CPU inside the miss interval as one ``Stall`` spanning them with their summed lateness);
    ``unexplained``: the rest."""
    explained: list[tuple[Miss, Stall]] = field(default_factory=list)
    unexplained: list[Miss] = field(default_factory=list)


def attribute(misses: Iterable[Miss], stalls: Sequence[Stall], tolerance_ns: int = 0) -> Attribution:
    """Split ``misses`` into those a host stall explains and those it does not (module docstring).

    ``tolerance_ns`` >= 0: how much longer than the stall a miss may be late and still be the host's."""
    if tolerance_ns < 0:
        raise ValueError(f"tolerance_ns must be >= 0, got {tolerance_ns}")
    out = Attribution()
    for m in sorted(misses, key=lambda m: m.tick_ns):
        over = [s for s in stalls if s.start_ns <= m.end_ns and s.end_ns >= m.tick_ns
                and s.lateness_ns + tolerance_ns >= m.lateness_ns]
        summed = summed_on_one_cpu(m, stalls) if not over else None
        if over:
            out.explained.append((m, max(over, key=lambda s: s.lateness_ns)))
        elif summed is not None and summed.lateness_ns + tolerance_ns >= m.lateness_ns:
            out.explained.append((m, summed))
        else:
            out.unexplained.append(m)
    return out


def summed_on_one_cpu(m: Miss, stalls: Sequence[Stall]) -> Stall | None:
    """The stalls of the CPU that lost most time inside ``m``'s interval, as one ``Stall`` spanning them
    whose lateness is that time (only the part [end - lateness, end] of each inside the interval counts);
    None when no stall of a known CPU reaches into it."""
    best: Stall | None = None
    for cpu in sorted({s.cpu for s in stalls if s.cpu is not None}):
        inside = [s for s in stalls if s.cpu == cpu and s.end_ns > m.tick_ns and s.end_ns - s.lateness_ns < m.end_ns]
        lost = sum(min(s.end_ns, m.end_ns) - max(s.end_ns - s.lateness_ns, m.tick_ns) for s in inside)
        if inside and (best is None or lost > best.lateness_ns):
            start, end = min(s.start_ns for s in inside), max(s.end_ns for s in inside)
            best = Stall(start, end, min(lost, end - start), cpu)
    return best


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
