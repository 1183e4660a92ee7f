"""CSV import: the documented layout parses exactly; every malformed line or missing column is an
error naming file, line and column; nothing is skipped silently (hypothesis property tests)."""
import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from susp_sim_ros.analysis import csv_import as ci
from susp_sim_ros.errors import CsvImportError, SuspInputError

HEADER = ["time_s", "steering_wheel_angle_rad", "speed_m_s", "roll_rate_rad_s", "pitch_rate_rad_s",
          "yaw_rate_rad_s"]
finite = st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False)


def table_text(rows, header=HEADER, comments=()):
    lines = [f"# {c}" for c in comments] + [",".join(header)]
    lines += [",".join(repr(float(x)) for x in r) for r in rows]
    return "\n".join(lines) + "\n"


@st.composite
def tables(draw, min_rows=2, max_rows=30):
    n = draw(st.integers(min_rows, max_rows))
    steps = draw(st.lists(st.floats(1e-3, 10.0), min_size=n, max_size=n))
    t = np.cumsum(steps) - steps[0]
    cols = [draw(st.lists(finite, min_size=n, max_size=n)) for _ in HEADER[1:]]
    return [[float(t[i])] + [c[i] for c in cols] for i in range(n)]


@settings(max_examples=150, deadline=None)
@given(tables(), st.lists(st.text("abc xyz", max_size=10), max_size=3))
def test_valid_tables_parse_exactly(rows, comments):
    tab = ci.read_drive_csv("drive.csv", table_text(rows, comments=comments))
    arr = np.array(rows)
    for j, q in enumerate(ci.DRIVE_REQUIRED):
        np.testing.assert_array_equal(tab.columns[q], arr[:, j])  # repr round trip: exact
    assert len(tab.lines) == len(rows)  # every row kept
    assert tab.comments == [c.strip() for c in comments]


@settings(max_examples=150, deadline=None)
@given(tables(min_rows=3), st.data(),
       st.sampled_from(["abc", "", "1,5", "nan", "inf", "1e999", "0x10", "1_000", "--1", "1.2.3", " . "]))
def test_a_bad_cell_names_file_line_and_column(rows, data, junk):
    i = data.draw(st.integers(0, len(rows) - 1))
    j = data.draw(st.integers(0, len(HEADER) - 1))
    lines = table_text(rows).splitlines()
    fields = lines[1 + i].split(",")
    fields[j] = junk
    lines[1 + i] = ",".join(fields)
    with pytest.raises(CsvImportError) as err:
        ci.read_drive_csv("m/drive.csv", "\n".join(lines) + "\n")
    msg = str(err.value)
    assert msg.startswith(f"m/drive.csv:{i + 2}:")  # header is line 1
    if junk != "1,5":  # a comma adds a field: the whole line is named instead
        assert f"'{HEADER[j]}'" in msg and f"column {j + 1}" in msg


@settings(max_examples=60, deadline=None)
@given(tables(), st.integers(0, len(ci.DRIVE_REQUIRED) - 1))
def test_a_missing_column_is_named(rows, j):
    header = HEADER[:j] + HEADER[j + 1:]
    rows = [r[:j] + r[j + 1:] for r in rows]
    with pytest.raises(CsvImportError, match=rf"drive.csv:1: missing column {HEADER[j]}"):
        ci.read_drive_csv("drive.csv", table_text(rows, header))


@settings(max_examples=60, deadline=None)
@given(tables(min_rows=3), st.data())
def test_short_or_long_rows_blank_lines_and_time_going_back_are_errors(rows, data):
    i = data.draw(st.integers(0, len(rows) - 1))
    kind = data.draw(st.sampled_from(["short", "long", "blank", "back"]))
    lines = table_text(rows).splitlines()
    if kind == "short":
        lines[1 + i] = ",".join(lines[1 + i].split(",")[:-1])
    elif kind == "long":
        lines[1 + i] += ",0"
    elif kind == "blank":
        lines.insert(1 + i, "")
    else:
        assume(i > 0)
        f = lines[1 + i].split(",")
        f[0] = repr(rows[i - 1][0])
        lines[1 + i] = ",".join(f)
    with pytest.raises(CsvImportError, match=rf"^drive.csv:{i + 2}: "):
        ci.read_drive_csv("drive.csv", "\n".join(lines) + "\n")


def test_units_groups_and_unknown_columns():
    text = ("time_s,steering_wheel_angle_deg,speed_km_h,roll_rate_deg_s,pitch_rate_deg_s,yaw_rate_deg_s\n"
            "0,90,36,180,0,0\n0.01,0,36,0,0,0\n")
    tab = ci.read_drive_csv("d.csv", text)
    np.testing.assert_allclose(tab.columns["steering"][0], math.pi / 2)
    np.testing.assert_allclose(tab.columns["speed"], 10.0)
    np.testing.assert_allclose(tab.columns["roll_rate"][0], math.pi)
    with pytest.raises(CsvImportError, match="unknown column 'pitch_rte_rad_s'"):
        ci.read_drive_csv("d.csv", text.replace("pitch_rate_deg_s", "pitch_rte_rad_s"))
    with pytest.raises(CsvImportError, match="missing column accel_y_m_s2, accel_z_m_s2"):
        ci.read_drive_csv("d.csv", text.replace("yaw_rate_deg_s\n", "yaw_rate_deg_s,accel_x_m_s2\n")
                          .replace(",0\n", ",0,1\n"))
    with pytest.raises(CsvImportError, match="again"):
        ci.read_drive_csv("d.csv", text.replace("speed_km_h", "steering_wheel_angle_rad"))
    with pytest.raises(CsvImportError, match="must be >= 0"):
        ci.read_drive_csv("d.csv", text.replace("\n0,90", "\n-1,90"))
    with pytest.raises(CsvImportError, match="empty file"):
        ci.read_drive_csv("d.csv", "# only a comment\n")
    with pytest.raises(CsvImportError, match="at least 2 data rows"):
        ci.read_drive_csv("d.csv", text.splitlines()[0] + "\n0,0,0,0,0,0\n")
    assert issubclass(CsvImportError, SuspInputError)


def test_road_csv_and_files_on_disk(tmp_path):
    road = ci.read_road_csv("r.csv", "s_m,z_left_m,z_right_m\n1.0,0,0\n1.25,0.06,0.05\n1.5,0,0\n")
    np.testing.assert_allclose(road.zl, [0, 0.06, 0])
    with pytest.raises(CsvImportError, match=r"r.csv:3: column 's_m'.*does not increase"):
        ci.read_road_csv("r.csv", "s_m,z_left_m,z_right_m\n1.0,0,0\n1.0,0,0\n")
    with pytest.raises(CsvImportError, match="no such file"):
        ci.read_drive_csv(tmp_path / "missing.csv")
    bad = tmp_path / "latin1.csv"
    bad.write_bytes(b"time_s\n\xe9\n")
    with pytest.raises(CsvImportError, match=r"latin1.csv:2: not UTF-8"):
        ci.read_drive_csv(bad)


def test_csv_to_mcap_round_trip_and_cli(tmp_path, capsys):
    """CSV -> MCAP -> read_drive gives back every sample in SI units; the CLI maps errors to exit 2."""
    from susp_sim_ros.cli.main import main
    from susp_sim_ros.io.drive import read_drive
    t = np.arange(0, 2.0, 0.005)
    drive = tmp_path / "drive.csv"
    rows = ["# test track, rear dampers drained",
            "time_s,speed_km_h,steering_wheel_angle_deg,roll_rate_rad_s,pitch_rate_rad_s,yaw_rate_rad_s,"
            "accel_x_m_s2,accel_y_m_s2,accel_z_m_s2"]
    rows += [f"{x:.3f},8.0,{10 * math.sin(x):.6f},{0.01 * x:.6f},{-0.02 * x:.6f},0,0,0,9.81" for x in t]
    drive.write_text("\n".join(rows) + "\n")
    road = tmp_path / "road.csv"
    road.write_text("s_m,z_left_m,z_right_m\n1.0,0,0\n1.25,0.06,0.06\n1.5,0,0\n")
    out = tmp_path / "drive.mcap"
    assert main(["import-csv", str(drive), "--road", str(road), "--out", str(out), "--oil", "1,1,0,0",
                 "--maneuver", "bump_crossing_8kmh", "--json"]) == 0
    capsys.readouterr()
    d = read_drive(out)
    assert d.metadata["source"] == "measured" and d.metadata["damper_oil_level"] == "1,1,0,0"
    assert "rear dampers drained" in d.metadata["notes"]
    np.testing.assert_array_equal(d.imu.t_ns, np.round(np.round(t, 3) * 1e9).astype(np.int64))
    np.testing.assert_allclose(d.speed.values, 8.0 / 3.6)
    np.testing.assert_allclose(d.steering.values, np.radians(np.round(10 * np.sin(t), 6)), atol=1e-12)
    np.testing.assert_allclose(d.imu.accel[:, 2], 9.81)
    np.testing.assert_allclose(d.road.zl, [0, 0.06, 0])
    # refuses to overwrite; a bad cell and a bad oil string are exit 2 with the location
    assert main(["import-csv", str(drive), "--out", str(out)]) == 2
    assert "exists" in capsys.readouterr().err
    rows[5] = rows[5].replace(",0,0,0,9.81", ",0,x,0,9.81")
    drive.write_text("\n".join(rows) + "\n")
    assert main(["import-csv", str(drive), "--out", str(tmp_path / "b.mcap")]) == 2
    err = capsys.readouterr().err
    assert f"{drive}:6: column 'accel_x_m_s2' (column 7)" in err and "Traceback" not in err
    assert not (tmp_path / "b.mcap").exists()
    assert main(["import-csv", str(drive), "--out", str(tmp_path / "c.mcap"), "--oil", "1,1,2"]) == 2
