"""CSV import under damage (complements test_csv_import.py): a valid drive CSV mutated at random (a
character inserted, deleted or replaced, a line duplicated, dropped, cut, swapped or replaced by junk)
either parses with exactly one row per data line (nothing skipped) or raises CsvImportError naming the
file, a line that exists and a column; missing columns, short and long rows, quoting and NUL bytes,
out-of-range values and a byte-order mark are covered one by one."""
from __future__ import annotations

import math
import re

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from susp_sim_ros.analysis import csv_import as ci
from susp_sim_ros.errors import CsvImportError

HEADER = ("time_s,steering_wheel_angle_deg,speed_km_h,roll_rate_rad_s,pitch_rate_rad_s,yaw_rate_rad_s,"
          "wheel_height_fl_m,wheel_height_fr_m,wheel_height_rl_m,wheel_height_rr_m")
N_COLS = HEADER.count(",") + 1


def valid_text(n=12) -> str:
    rows = ["# measured on the test track", HEADER]
    for k in range(n):
        rows.append(f"{k * 0.01:.2f},{5 * math.sin(k):.4f},{30 + k * 0.1:.2f},0.001,-0.002,{0.01 * k:.3f},"
                    f"0.0{k % 3},0.01,-0.01,0")
    return "\n".join(rows) + "\n"


LINE_ERROR = re.compile(r"^m/drive\.csv:(\d+): column (\d+|'[^']*' \(column \d+\))")
FILE_ERROR = re.compile(r"^m/drive\.csv: (empty file|needs at least 2 data rows)")
JUNK = st.sampled_from(list(",;\"'\t #x-.e+0159") + ["\x00", "\r", "nan", "inf", "1e999", ",,", "\"a,b\""])


@st.composite
def mutations(draw):
    lines = valid_text().splitlines()
    kind = draw(st.sampled_from(["insert", "delete", "replace", "dup", "drop", "cut", "swap", "junkline"]))
    i = draw(st.integers(0, len(lines) - 1))
    if kind in ("insert", "delete", "replace"):
        line = lines[i]
        j = draw(st.integers(0, len(line)))
        junk = draw(JUNK)
        if kind == "insert":
            line = line[:j] + junk + line[j:]
        elif kind == "delete":
            line = line[:j] + line[j + 1:]
        else:
            line = line[:j] + junk + line[j + 1:]
        lines[i] = line
    elif kind == "dup":
        lines.insert(i, lines[i])
    elif kind == "drop":
        del lines[i]
    elif kind == "cut":
        lines = lines[:i]
        if lines and draw(st.booleans()):
            lines[-1] = lines[-1][:draw(st.integers(0, len(lines[-1])))]
    elif kind == "swap":
        k = draw(st.integers(0, len(lines) - 1))
        lines[i], lines[k] = lines[k], lines[i]
    else:
        lines[i] = draw(st.text(alphabet=",;0123456789.-eE abc#\"\t", max_size=30))
    return "\n".join(lines) + "\n", kind


@settings(max_examples=600, deadline=None, derandomize=True, database=None,
          suppress_health_check=list(HealthCheck))
@given(mutations())
def test_damaged_csv_is_parsed_completely_or_named(mutated):
    text, kind = mutated
    physical = text.splitlines()
    try:
        drive = ci.csv_to_drive("m/drive.csv", drive_text=text)
    except CsvImportError as exc:
        msg = str(exc)
        m = LINE_ERROR.match(msg)
        if m:
            assert 1 <= int(m.group(1)) <= len(physical), msg  # a line that exists
        else:
            m = re.match(r"^m/drive\.csv:(\d+): (missing column|unknown column|column|malformed CSV)", msg)
            assert FILE_ERROR.match(msg) or (m and 1 <= int(m.group(1)) <= len(physical)), msg
        return
    # parsed: one row per data line, nothing skipped
    data_lines = [ln for ln in physical if ln.strip() and not ln.strip().startswith("#")][1:]
    assert len(drive.imu) == len(data_lines) == len(drive.speed)
    assert np.all(np.isfinite(drive.speed.values)) and np.all(np.diff(drive.speed.t_ns) > 0)


@pytest.mark.parametrize("line, needle", [
    ("0.12,1,30,0,0,0,0,0,0",
     r"m/drive.csv:15: column 10: expected 10 fields .* got 9: column 10 'wheel_height_rr_m' is missing"),
    ("0.12,1,30,0,0,0,0,0,0,0,7", r"m/drive.csv:15: column 11: .* got 11: column 11 \('7'\) is beyond"),
    ("0.12,1,30,0,0,0,0,0,0,\"0", r"m/drive.csv:15: malformed CSV"),
    ("0.12,1,30,\x00,0,0,0,0,0,0", r"m/drive.csv:15: column 4: NUL"),
    ("0.12,1,-3,0,0,0,0,0,0,0", r"m/drive.csv:15: column 'speed_km_h' \(column 3\): -0.83\d* m/s is outside"),
    ("0.12,800,30,0,0,0,0,0,0,0",
     r"m/drive.csv:15: column 'steering_wheel_angle_deg' \(column 2\): 13.9\d* rad is outside"),
    ("0.12,1,30,0,0,0,0,0,1.5,0", r"m/drive.csv:15: column 'wheel_height_rl_m' \(column 9\): 1.5 m is outside"),
    ("", r"m/drive.csv:15: column 1: blank line"),
])
def test_each_bad_line_names_file_line_and_column(line, needle):
    text = valid_text().splitlines()
    text.insert(14, line)
    text.append("0.99,0,30,0,0,0,0,0,0,0")
    with pytest.raises(CsvImportError, match=needle):
        ci.csv_to_drive("m/drive.csv", drive_text="\n".join(text) + "\n")


def test_missing_columns_and_groups_are_named():
    for j, name in enumerate(HEADER.split(",")[:6]):
        cols = HEADER.split(",")
        del cols[j]
        rows = [",".join(cols)] + [",".join(["0.1" if k else f"{r * 0.1:.1f}" for k in range(len(cols))])
                                   for r in range(3)]
        with pytest.raises(CsvImportError, match=rf"m/drive.csv:1: missing column {name.rsplit('_', 2)[0]}"):
            ci.read_drive_csv("m/drive.csv", "\n".join(rows) + "\n")
    cols = HEADER.split(",")[:-1]  # three of four wheel heights
    rows = [",".join(cols)] + [",".join(["0" for _ in cols])]
    with pytest.raises(CsvImportError, match=r"m/drive.csv:1: missing column wheel_height_rr_m"):
        ci.read_drive_csv("m/drive.csv", "\n".join(rows) + "\n")


def test_byte_order_mark_and_road_range(tmp_path):
    p = tmp_path / "bom.csv"
    p.write_bytes(b"\xef\xbb\xbf" + valid_text().encode())
    assert len(ci.csv_to_drive(p).imu) == 12  # a spreadsheet's BOM is not part of the first column name
    with pytest.raises(CsvImportError, match=r"r.csv:3: column 'z_left_m' \(column 2\): 2 m is outside"):
        ci.read_road_csv("r.csv", "s_m,z_left_m,z_right_m\n0,0,0\n1,2,0\n")
