"""Attribution of real-time deadline misses to host stalls (pure: no threads, no ROS).

A *host stall* is what a plain sleeping thread sees when the machine itself does not run it: the probe
(:mod:`host_probe`) sleeps to absolute deadlines one period apart and records each wake
that came late. A stall is the interval from the probe's previous wake (the last instant it was seen
running) to the late wake, with the wake's lateness as its length: the machine stopped the probe for at
least that long (for at most the whole interval).

A *deadline miss* of the node is a tick published more than one period after its deadline; it occupies
the interval from the deadline to the publish.

A miss is *explained* by the host when a stall overlaps it and the stall is at least as long as the
miss is late, less ``tolerance_ns``: the probe sees a stall only to within its own period (a stall of D
shows as a lateness between D - period and D), and a stall that hits while the node is stepping a tick
delays that tick by the stall plus the tick's ordinary work. So the tolerance is the probe's period plus
the node's ordinary lateness (its p99 in the same run). Every other miss is *unexplained*: the node's own.

Times are integer nanoseconds on one clock (``time.time_ns``, the clock the node stamps its ticks with).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from collections.abc import Iterable, Sequence

__all__ = ["Stall", "Miss", "Attribution", "attribute", "parse_miss_log", "format_miss_log"]


@dataclass(frozen=True)
class Stall:
    """The probe was not run between ``start_ns`` (its previous wake) and ``end_ns`` (the late wake),
    and woke ``lateness_ns`` after its deadline [ns]."""
    start_ns: int
    end_ns: int
    lateness_ns: int

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
    """``explained``: (miss, the longest overlapping stall that explains it); ``unexplained``: the rest."""
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
        if over:
            out.explained.append((m, max(over, key=lambda s: s.lateness_ns)))
        else:
            out.unexplained.append(m)
    return out


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
