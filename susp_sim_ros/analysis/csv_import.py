"""Import real measurements from CSV into a recorded test drive (MCAP, interface.md).

CSV layout
==========

Two plain-text files, comma-separated, UTF-8, one header row naming the columns (any order, names are
case-insensitive, surrounding spaces ignored). Numbers are decimal (``12``, ``-0.5``, ``1.5e-3``); no
thousands separators, no ``nan``/``inf``. Lines starting with ``#`` are comments (allowed anywhere, e.g.
for the measurement's provenance). Every other line must be a complete, valid row: a blank line, a row
with a missing or extra field, a cell that is not a finite number, or a time that does not increase
raises :class:`~susp_sim_ros.errors.CsvImportError` naming the file, the line and the column. Nothing is
skipped silently, and an unknown column is an error too (a misspelt column would otherwise vanish). A
leading UTF-8 byte-order mark is ignored. Values the simulation node would reject (speed outside
[0, 70] m/s, |steering-wheel angle| > 4 pi rad, |wheel height| or |road elevation| > 1 m: the one set of
limits, ``limits`` in ``config/integrity.yaml``) are errors too, naming file, line and column.

**Drive file** (one row per sample; all channels share the row's time):

=================================  ========================================  ======================
column (one unit suffix per line)  meaning                                   required
=================================  ========================================  ======================
``time_s``                         time since the start of the drive [s],    yes
                                   >= 0, strictly increasing
``steering_wheel_angle_rad|_deg``  steering-wheel angle, positive = left     yes
``speed_m_s|speed_km_h``           longitudinal speed over ground            yes
``roll_rate_rad_s|_deg_s``         measured roll rate (about x, REP-103)     yes
``pitch_rate_rad_s|_deg_s``        measured pitch rate (about y)             yes
``yaw_rate_rad_s|_deg_s``          measured yaw rate (about z)               yes
``accel_x_m_s2`` (y, z)            specific force incl. gravity (REP-145)    all three or none
``wheel_height_fl_m`` (fr, rl, rr) road height under each wheel (four-poster all four or none
                                   style, overrides the road file)
=================================  ========================================  ======================

**Road file** (optional; flat road without it): columns ``s_m`` (path coordinate of the front axle's
travel, strictly increasing), ``z_left_m``, ``z_right_m`` (elevation of the left/right wheel tracks). The
front axle is at ``s = 0`` when the drive starts (interface.md, ``/road/profile``).

Example::

    # VW Passat, test track, 2024-05-02, rear dampers drained
    time_s,steering_wheel_angle_deg,speed_km_h,roll_rate_deg_s,pitch_rate_deg_s,yaw_rate_deg_s
    0.000,0.0,8.0,0.01,-0.02,0.00
    0.005,0.0,8.0,0.00,-0.01,0.01

Everything is converted to SI and written with :func:`susp_sim_ros.io.drive.write_drive`; the
``test_drive`` metadata gets ``vehicle``, ``maneuver``, ``damper_oil_level``, ``source`` (``measured`` by
default) and ``notes`` (the CSV's ``#`` comment lines plus the file names).
"""
from __future__ import annotations

import csv
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from collections.abc import Mapping, Sequence

import numpy as np

from ..errors import CsvImportError
from ..io.drive import MAX_SPEED, MAX_STEERING, MAX_WHEEL_HEIGHT, ImuSeries, Series, TestDrive, parse_oil, write_drive
from ..io.units import FACTORS
from ..model.params import DEFAULT_VEHICLE
from ..model.road import RoadProfile

_NUMBER = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")

#: Column unit suffix -> unit name of :data:`~susp_sim_ros.io.units.FACTORS` (the factor to SI).
COLUMN_UNITS = {"s": "s", "rad": "rad", "deg": "deg", "m_s": "m/s", "km_h": "km/h", "rad_s": "rad/s",
                "deg_s": "deg/s", "m_s2": "m/s^2", "m": "m"}


def _columns(stem: str, *suffixes: str) -> dict[str, float]:
    """``{stem_suffix: factor to SI}`` for each unit suffix, in the given order."""
    return {f"{stem}_{sfx}": FACTORS[COLUMN_UNITS[sfx]] for sfx in suffixes}


# quantity -> {column name: factor to SI}
DRIVE_QUANTITIES: dict[str, dict[str, float]] = {
    "time": _columns("time", "s"),
    "steering": _columns("steering_wheel_angle", "rad", "deg"),
    "speed": _columns("speed", "m_s", "km_h"),
    "roll_rate": _columns("roll_rate", "rad_s", "deg_s"),
    "pitch_rate": _columns("pitch_rate", "rad_s", "deg_s"),
    "yaw_rate": _columns("yaw_rate", "rad_s", "deg_s"),
    "accel_x": _columns("accel_x", "m_s2"),
    "accel_y": _columns("accel_y", "m_s2"),
    "accel_z": _columns("accel_z", "m_s2"),
    "wheel_height_fl": _columns("wheel_height_fl", "m"),
    "wheel_height_fr": _columns("wheel_height_fr", "m"),
    "wheel_height_rl": _columns("wheel_height_rl", "m"),
    "wheel_height_rr": _columns("wheel_height_rr", "m"),
}
DRIVE_REQUIRED = ("time", "steering", "speed", "roll_rate", "pitch_rate", "yaw_rate")
DRIVE_GROUPS = (("accel_x", "accel_y", "accel_z"),
                ("wheel_height_fl", "wheel_height_fr", "wheel_height_rl", "wheel_height_rr"))
ROAD_QUANTITIES: dict[str, dict[str, float]] = {"s": _columns("s", "m"), "z_left": _columns("z_left", "m"),
                                                "z_right": _columns("z_right", "m")}
ROAD_REQUIRED = ("s", "z_left", "z_right")


@dataclass
class CsvTable:
    """Parsed columns in SI units keyed by quantity, the source lines of the rows, and the comments."""

    path: str
    columns: dict[str, np.ndarray]
    lines: np.ndarray
    comments: list[str]
    names: dict[str, tuple[str, int]] = field(default_factory=dict)  # quantity -> (column name, index)


def _column_map(path: str, header: Sequence[str], quantities: Mapping[str, Mapping[str, float]],
                required: Sequence[str], groups: Sequence[Sequence[str]],
                line: int) -> dict[str, tuple[int, float, str]]:
    """Header -> {quantity: (field index, factor, column name)} with errors naming the column."""
    lookup = {name: (q, f) for q, names in quantities.items() for name, f in names.items()}
    found: dict[str, tuple[int, float, str]] = {}
    for k, raw in enumerate(header):
        name = raw.strip().lower()
        if name == "":
            raise CsvImportError(f"{path}:{line}: column {k + 1} has an empty name")
        if name not in lookup:
            raise CsvImportError(f"{path}:{line}: unknown column {raw.strip()!r} (column {k + 1}); known: "
                                 f"{', '.join(sorted(lookup))}")
        q, f = lookup[name]
        if q in found:
            raise CsvImportError(f"{path}:{line}: column {raw.strip()!r} (column {k + 1}) gives "
                                 f"{q.replace('_', ' ')} again (already column {found[q][0] + 1}, "
                                 f"{found[q][2]!r})")
        found[q] = (k, f, raw.strip())
    for q in required:
        if q not in found:
            raise CsvImportError(f"{path}:{line}: missing column {' or '.join(quantities[q])} "
                                 f"(header has: {', '.join(h.strip() for h in header)})")
    for g in groups:
        have = [q for q in g if q in found]
        if have and len(have) != len(g):
            missing = [next(iter(quantities[q])) for q in g if q not in found]
            raise CsvImportError(f"{path}:{line}: missing column {', '.join(missing)}: "
                                 f"{', '.join(next(iter(quantities[q])) for q in g)} come all together or not at all")
    return found


def _check_field_count(path: str, lineno: int, header: list[str], fields: list[str]) -> None:
    """A data row has exactly the header's number of fields."""
    if len(fields) == len(header):
        return
    names = [h.strip() for h in header]
    if len(fields) < len(header):
        k = len(fields)
        what = f"column {k + 1} {names[k]!r} is missing"
    else:
        k = len(header)
        what = f"column {k + 1} ({fields[k].strip()!r}) is beyond the header's last column {names[-1]!r}"
    raise CsvImportError(f"{path}:{lineno}: column {k + 1}: expected {len(header)} fields "
                         f"({', '.join(names)}), got {len(fields)}: {what}")


def _cell(path: str, lineno: int, fields: list[str], q: str, col: tuple[int, float, str], nonneg: bool,
          increasing: bool, prev: tuple[float, int] | None) -> float:
    """Quantity ``q`` of a data row in SI (column ``col`` = (index, factor to SI, name)); ``prev``: the
    previous row's value [SI] and line, checked against when ``increasing``."""
    k, factor, name = col
    cell = fields[k].strip()
    if not _NUMBER.match(cell):
        what = "empty cell" if cell == "" else f"{cell!r} is not a decimal number"
        raise CsvImportError(f"{path}:{lineno}: column {name!r} (column {k + 1}): {what}")
    x = float(cell) * factor
    if not math.isfinite(x):
        raise CsvImportError(f"{path}:{lineno}: column {name!r} (column {k + 1}): {cell!r} "
                             f"overflows to a non-finite value")
    if nonneg and x < 0:
        raise CsvImportError(f"{path}:{lineno}: column {name!r} (column {k + 1}): must be >= 0, "
                             f"got {cell}")
    if increasing and prev is not None and x <= prev[0]:
        raise CsvImportError(f"{path}:{lineno}: column {name!r} (column {k + 1}): {cell} does not "
                             f"increase (previous row, line {prev[1]}, has {prev[0] / factor:g})")
    return x


def parse_csv(text: str, path: str, quantities: Mapping[str, Mapping[str, float]], required: Sequence[str],
              groups: Sequence[Sequence[str]] = (), increasing: str | None = None,
              nonneg: Sequence[str] = ()) -> CsvTable:
    """Parse CSV ``text`` (``path`` names it in errors) into SI columns; see the module docstring."""
    comments: list[str] = []
    header: list[str] | None = None
    cmap: dict[str, tuple[int, float, str]] = {}
    rows: list[list[float]] = []
    lines: list[int] = []
    order: list[str] = []
    if text.startswith("\ufeff"):  # a UTF-8 byte-order mark (spreadsheet export) is not part of the header
        text = text[1:]
    physical = text.splitlines()
    for lineno, raw in enumerate(physical, start=1):
        stripped = raw.strip()
        if stripped.startswith("#"):
            comments.append(stripped[1:].strip())
            continue
        if stripped == "":
            if lineno == len(physical):
                break
            raise CsvImportError(f"{path}:{lineno}: column 1: blank line (every non-comment line must be a "
                                 f"{'header' if header is None else 'data row'})")
        if "\x00" in raw:
            raise CsvImportError(f"{path}:{lineno}: column {raw[:raw.index(chr(0))].count(',') + 1}: NUL "
                                 f"character (binary data in a text file?)")
        try:
            fields = next(csv.reader([raw], strict=True))
        except csv.Error as exc:
            raise CsvImportError(f"{path}:{lineno}: malformed CSV ({exc}); check the quoting") from None
        if header is None:
            header = fields
            cmap = _column_map(path, header, quantities, required, groups, lineno)
            order = list(cmap)
            continue
        _check_field_count(path, lineno, header, fields)
        prev = (rows[-1], lines[-1]) if rows else None
        rows.append([_cell(path, lineno, fields, q, cmap[q], q in nonneg, q == increasing,
                           None if prev is None else (prev[0][order.index(q)], prev[1])) for q in order])
        lines.append(lineno)
    if header is None:
        raise CsvImportError(f"{path}: empty file: no header row")
    if len(rows) < 2:
        raise CsvImportError(f"{path}: needs at least 2 data rows, got {len(rows)}")
    arr = np.array(rows, dtype=float)
    return CsvTable(path, {q: arr[:, j] for j, q in enumerate(order)}, np.array(lines), comments,
                    {q: (cmap[q][2], cmap[q][0]) for q in order})


def _read_text(path: str | os.PathLike) -> str:
    try:
        return Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise CsvImportError(f"{path}: no such file") from None
    except UnicodeDecodeError as exc:
        raw = Path(path).read_bytes()
        line = raw[:exc.start].count(b"\n") + 1
        raise CsvImportError(f"{path}:{line}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    except OSError as exc:
        raise CsvImportError(f"{path}: cannot read: {exc.strerror or exc}") from None


def read_drive_csv(path: str | os.PathLike, text: str | None = None) -> CsvTable:
    """Parse a drive CSV (module docstring); ``text`` instead of reading ``path`` (tests)."""
    text = _read_text(path) if text is None else text
    return parse_csv(text, str(path), DRIVE_QUANTITIES, DRIVE_REQUIRED, DRIVE_GROUPS, increasing="time",
                     nonneg=("time",))


def read_road_csv(path: str | os.PathLike, text: str | None = None):
    """Parse a road CSV into a :class:`~susp_sim_ros.model.road.RoadProfile`."""
    text = _read_text(path) if text is None else text
    t = parse_csv(text, str(path), ROAD_QUANTITIES, ROAD_REQUIRED, increasing="s")
    _check_range(path, t, "z_left", ROAD_QUANTITIES, -MAX_WHEEL_HEIGHT, MAX_WHEEL_HEIGHT, "m")
    _check_range(path, t, "z_right", ROAD_QUANTITIES, -MAX_WHEEL_HEIGHT, MAX_WHEEL_HEIGHT, "m")
    return RoadProfile(t.columns["s"], t.columns["z_left"], t.columns["z_right"])


def _check_range(path, tab: CsvTable, q: str, quantities, lo: float, hi: float, unit: str) -> None:
    """CsvImportError naming file, line and column for the first value of quantity ``q`` outside
    [lo, hi] (SI): values the simulation node would reject, caught at import instead of being dropped."""
    if q not in tab.columns:
        return
    v = tab.columns[q]
    bad = np.nonzero((v < lo) | (v > hi))[0]
    if bad.size:
        i = int(bad[0])
        name, k = tab.names[q]
        raise CsvImportError(f"{path}:{tab.lines[i]}: column {name!r} (column {k + 1}): {v[i]:g} {unit} is outside "
                             f"the range the simulation accepts [{lo:g}, {hi:g}] {unit}")


def csv_to_drive(drive_csv: str | os.PathLike, road_csv: str | os.PathLike | None = None, *,
                 vehicle: str = DEFAULT_VEHICLE, maneuver: str = "", damper_oil_level: str = "1,1,1,1",
                 source: str = "measured", notes: str = "", drive_text: str | None = None,
                 road_text: str | None = None):
    """A :class:`~susp_sim_ros.io.drive.TestDrive` from the CSV files (nothing written)."""
    parse_oil(damper_oil_level, "damper_oil_level")
    tab = read_drive_csv(drive_csv, drive_text)
    _check_range(drive_csv, tab, "speed", DRIVE_QUANTITIES, 0.0, MAX_SPEED, "m/s")
    _check_range(drive_csv, tab, "steering", DRIVE_QUANTITIES, -MAX_STEERING, MAX_STEERING, "rad")
    for w in ("fl", "fr", "rl", "rr"):
        _check_range(drive_csv, tab, f"wheel_height_{w}", DRIVE_QUANTITIES, -MAX_WHEEL_HEIGHT, MAX_WHEEL_HEIGHT, "m")
    c = tab.columns
    t_ns = np.round(c["time"] * 1e9).astype(np.int64)
    dup = np.nonzero(np.diff(t_ns) <= 0)[0]
    if dup.size:
        k = int(dup[0]) + 1
        raise CsvImportError(f"{drive_csv}:{tab.lines[k]}: column 'time_s': equal to the previous row's "
                             f"time at nanosecond resolution")
    gyro = np.column_stack([c["roll_rate"], c["pitch_rate"], c["yaw_rate"]])
    if "accel_x" in c:
        accel = np.column_stack([c["accel_x"], c["accel_y"], c["accel_z"]])
    else:
        accel = np.zeros_like(gyro)
    road = read_road_csv(road_csv, road_text) if road_csv is not None else None
    wh = None
    if "wheel_height_fl" in c:
        wh = Series(t_ns, np.column_stack([c[f"wheel_height_{w}"] for w in ("fl", "fr", "rl", "rr")]))
    note_parts = [f"imported from {Path(drive_csv).name}" + (f" and {Path(road_csv).name}" if road_csv else "")]
    note_parts += tab.comments
    if "accel_x" not in c:
        note_parts.append("no accelerometer columns: linear_acceleration written as 0")
    if notes:
        note_parts.append(notes)
    meta = {"vehicle": vehicle, "maneuver": maneuver, "damper_oil_level": damper_oil_level,
            "source": source, "notes": "; ".join(note_parts)}
    return TestDrive(meta, Series(t_ns, c["speed"]), Series(t_ns, c["steering"]), road, wh,
                     ImuSeries(t_ns, gyro, accel), {"csv_lines": tab.lines})


def import_csv(drive_csv: str | os.PathLike, out: str | os.PathLike, road_csv: str | os.PathLike | None = None,
               *, overwrite: bool = False, **metadata) -> dict:
    """Convert the CSV files to a test-drive MCAP at ``out``; returns a summary dict."""
    drive = csv_to_drive(drive_csv, road_csv, **metadata)
    n = write_drive(out, drive, overwrite=overwrite)
    return {"out": str(out), "messages": n, "samples": len(drive.imu),
            "duration_s": float((drive.imu.t_ns[-1] - drive.imu.t_ns[0]) * 1e-9),
            "road_samples": 0 if drive.road is None else len(drive.road),
            "metadata": drive.metadata}


__all__ = ["CsvTable", "parse_csv", "read_drive_csv", "read_road_csv", "csv_to_drive", "import_csv",
           "DRIVE_QUANTITIES", "ROAD_QUANTITIES"]
