"""``susp import`` (issue 16, item 4): ASAM MDF4 drives through asammdf and OpenCRG roads through pyopencrg,
on files these tests write with the same libraries. An MDF4 drive imported and validated gives the same
numbers as the same drive imported from CSV; units, sensor frames (SAE J670 / FRD) and the CRG wheel tracks
convert to SI / REP-103 as documented and the conversion is kept in the metadata; bad files are exit 2 with
a named error."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

asammdf = pytest.importorskip("asammdf")
pyopencrg = pytest.importorskip("pyopencrg")

from _cli_helpers import cli_json, run_cli  # noqa: E402
from susp_sim_ros.io.drive import ImuSeries, Series, TestDrive, read_drive  # noqa: E402

BUMP = Path(__file__).resolve().parents[1] / "bags" / "bump_crossing_intact.mcap"
G = 9.80665  # m/s^2 per g (the unit the test's "measurement system" records accelerations in)


@pytest.fixture(scope="module")
def common():
    """The bundled bump crossing on one time base (the IMU's), as a CSV row-per-sample measurement has it."""
    d = read_drive(BUMP)
    t = d.imu.t_ns
    interp = lambda s: np.interp(t, s.t_ns, s.values)  # noqa: E731
    return TestDrive({}, Series(t, interp(d.speed)), Series(t, interp(d.steering)), d.road, None,
                     ImuSeries(t, d.imu.gyro, d.imu.accel))


def _write_csv(path, d: TestDrive) -> Path:
    cols = ["time_s", "steering_wheel_angle_rad", "speed_m_s", "roll_rate_rad_s", "pitch_rate_rad_s",
            "yaw_rate_rad_s", "accel_x_m_s2", "accel_y_m_s2", "accel_z_m_s2"]
    rows = np.column_stack([d.imu.t_ns * 1e-9, d.steering.values, d.speed.values, d.imu.gyro, d.imu.accel])
    Path(path).write_text(",".join(cols) + "\n" + "\n".join(",".join(repr(float(x)) for x in r) for r in rows) + "\n")
    return Path(path)


def _write_road_csv(path, road) -> Path:
    Path(path).write_text("s_m,z_left_m,z_right_m\n" + "\n".join(
        f"{s!r},{zl!r},{zr!r}" for s, zl, zr in zip(road.s.tolist(), road.zl.tolist(), road.zr.tolist())) + "\n")
    return Path(path)


def _write_mdf_csv_names(path, d: TestDrive) -> Path:
    """MDF4 whose channels carry the CSV column names (SI units), one channel group."""
    from asammdf import MDF, Signal
    t = d.imu.t_ns * 1e-9
    sig = [Signal(d.steering.values, t, name="steering_wheel_angle_rad", unit="rad"),
           Signal(d.speed.values, t, name="speed_m_s", unit="m/s")]
    sig += [Signal(d.imu.gyro[:, k], t, name=f"{n}_rate_rad_s", unit="rad/s") for k, n in enumerate(("roll", "pitch",
                                                                                                     "yaw"))]
    sig += [Signal(d.imu.accel[:, k], t, name=f"accel_{a}_m_s2", unit="m/s^2") for k, a in enumerate("xyz")]
    mdf = MDF(version="4.10")
    mdf.append(sig, comment="test drive")
    mdf.save(path, overwrite=True)
    return Path(path)


def _write_mdf_vehicle_bus(path, d: TestDrive) -> Path:
    """MDF4 as a car's logger writes it: bus names and units (km/h, deg, deg/s, g), an SAE J670 (FRD) IMU
    in its own channel group, the inputs in another."""
    from asammdf import MDF, Signal
    t = d.imu.t_ns * 1e-9
    frd = np.array([1.0, -1.0, -1.0])
    g, a = d.imu.gyro * frd, d.imu.accel * frd
    mdf = MDF(version="4.10")
    mdf.append([Signal(d.speed.values * 3.6, t, name="VehSpd", unit="km/h"),
                Signal(np.degrees(d.steering.values), t, name="SteerWhlAng", unit="\u00b0")], comment="bus")
    mdf.append([Signal(np.degrees(g[:, k]), t, name=n, unit="\u00b0/s") for k, n in enumerate(("GyroX", "GyroY",
                                                                                               "GyroZ"))]
               + [Signal(a[:, k] / G, t, name=n, unit="g") for k, n in enumerate(("AccX", "AccY", "AccZ"))],
               comment="imu")
    mdf.save(path, overwrite=True)
    return Path(path)


VEHICLE_MAP = """
speed: VehSpd
steering_wheel_angle: SteerWhlAng
imu:
  frame: sae_j670
  gyro_x: GyroX
  gyro_y: GyroY
  gyro_z: GyroZ
  accel_x: AccX
  accel_y: AccY
  accel_z: AccZ
"""


def _metrics(res):
    return {w: win["signals"] for w, win in res["windows"].items()}


def test_mdf4_import_validates_exactly_as_the_csv_import(common, tmp_path):
    csv = _write_csv(tmp_path / "drive.csv", common)
    road = _write_road_csv(tmp_path / "road.csv", common.road)
    mf4 = _write_mdf_csv_names(tmp_path / "drive.mf4", common)
    a = cli_json(["import", csv, "--road", road, "--out", tmp_path / "csv.mcap"])
    b = cli_json(["import", mf4, "--road", road, "--out", tmp_path / "mf4.mcap"])
    assert a["samples"] == b["samples"] == len(common.imu)
    x, y = read_drive(tmp_path / "csv.mcap"), read_drive(tmp_path / "mf4.mcap")
    for s in ("speed", "steering"):
        np.testing.assert_array_equal(getattr(x, s).values, getattr(y, s).values)
        np.testing.assert_array_equal(getattr(x, s).t_ns, getattr(y, s).t_ns)
    np.testing.assert_array_equal(x.imu.gyro, y.imu.gyro)
    np.testing.assert_array_equal(x.road.zl, y.road.zl)
    cli_json(["sim", "--drive", tmp_path / "csv.mcap", "--out", tmp_path / "sim.mcap"])
    va = cli_json(["validate", "--measured", tmp_path / "csv.mcap", "--simulated", tmp_path / "sim.mcap"])
    vb = cli_json(["validate", "--measured", tmp_path / "mf4.mcap", "--simulated", tmp_path / "sim.mcap"])
    assert _metrics(va) == _metrics(vb) and va["rmse_deg_s"]["bump"]["pitch_rate"] > 0
    # a logger's file: other names and units, the FRD IMU and the inputs in separate channel groups
    bus = _write_mdf_vehicle_bus(tmp_path / "bus.mf4", common)
    (tmp_path / "map.yaml").write_text(VEHICLE_MAP)
    c = cli_json(["import", bus, "--channel-map", tmp_path / "map.yaml", "--road", road,
                  "--out", tmp_path / "bus.mcap"])
    z = read_drive(tmp_path / "bus.mcap")
    # deg/s -> rad/s, g -> m/s^2, FRD -> FLU: equal up to the unit conversions' rounding
    np.testing.assert_allclose(z.imu.gyro, x.imu.gyro, rtol=1e-12, atol=1e-18)
    np.testing.assert_allclose(z.imu.accel, x.imu.accel, rtol=1e-12)
    np.testing.assert_allclose(z.speed.values, x.speed.values, rtol=1e-12)
    assert "sae_j670" in c["metadata"]["frame_conversion"] and "km/h" in c["metadata"]["unit_conversion"]
    vc = cli_json(["validate", "--measured", tmp_path / "bus.mcap", "--simulated", tmp_path / "sim.mcap"])
    for w, sigs in _metrics(va).items():
        for s, m in sigs.items():
            assert vc["windows"][w]["signals"][s]["rmse_deg_s"] == pytest.approx(m["rmse_deg_s"], rel=1e-9)


@pytest.mark.parametrize("fmt", ["KDBI", "KRBI", "LDFI"])
def test_opencrg_road_round_trip(common, tmp_path, fmt):
    """A CRG grid whose left and right halves carry different profiles: the imported wheel tracks are the
    left (v > 0) and right (v < 0) halves, s counts from --road-start-u."""
    r = common.road
    z = np.column_stack([0.5 * r.zr, 0.5 * r.zr, r.zl, r.zl])
    road = pyopencrg.CrgRoad(z, u_inc=0.01, v=np.array([-1.5, -0.5, 0.5, 1.5]), u_start=float(r.s[0]))
    crg = tmp_path / f"road_{fmt}.crg"
    road.save(str(crg), fmt=fmt)
    csv = _write_csv(tmp_path / "drive.csv", common)
    res = cli_json(["import", csv, "--road", crg, "--road-start-u", "0", "--out", tmp_path / "d.mcap"])
    got = read_drive(tmp_path / "d.mcap").road
    tol = {"KDBI": 1e-15, "KRBI": 1e-8, "LDFI": 1e-7}[fmt]  # double, float32, text digits (m)
    np.testing.assert_allclose(got.s, r.s, rtol=0, atol=1e-9)
    np.testing.assert_allclose(got.zl, r.zl, rtol=0, atol=tol)
    np.testing.assert_allclose(got.zr, 0.5 * r.zr, rtol=0, atol=tol)
    assert "OpenCRG" in res["metadata"]["road_source"] and "v = +-0.79 m" in res["metadata"]["road_source"]
    default = read_drive(Path(cli_json(["import", csv, "--road", crg, "--out", tmp_path / "e.mcap"])["out"])).road
    np.testing.assert_allclose(default.s, r.s - r.s[0], atol=1e-9)  # default: the road starts under the axle


def test_import_csv_alias_is_the_same_import(common, tmp_path):
    csv = _write_csv(tmp_path / "drive.csv", common)
    a = cli_json(["import-csv", csv, "--out", tmp_path / "a.mcap"])
    b = cli_json(["import", csv, "--out", tmp_path / "b.mcap"])
    assert {k: v for k, v in a.items() if k not in ("out", "summary")} == \
        {k: v for k, v in b.items() if k not in ("out", "summary")}
    assert (tmp_path / "a.mcap").read_bytes() == (tmp_path / "b.mcap").read_bytes()


def test_bad_measurement_files_are_named_errors(common, tmp_path):
    mf4 = _write_mdf_csv_names(tmp_path / "ok.mf4", common)
    data = mf4.read_bytes()
    (tmp_path / "cut.mf4").write_bytes(data[:len(data) // 3])
    (tmp_path / "junk.mf4").write_bytes(b"\x00" * 4096)
    (tmp_path / "drive.txt").write_text("x")
    (tmp_path / "bad_map.yaml").write_text("speed: {channel: VehSpd, unit: furlong}\n")
    (tmp_path / "missing_map.yaml").write_text(VEHICLE_MAP)
    (tmp_path / "road.crg").write_text("this is not a CRG file\n")
    cases = [
        (["import", tmp_path / "cut.mf4"], "cut.mf4"),
        (["import", tmp_path / "junk.mf4"], "not an ASAM MDF file"),
        (["import", tmp_path / "drive.txt"], "unknown measurement format"),
        (["import", mf4, "--channel-map", tmp_path / "bad_map.yaml"], "'furlong' is not a unit of speed"),
        (["import", mf4, "--channel-map", tmp_path / "missing_map.yaml"], "no channel 'VehSpd'"),
        (["import", mf4, "--road", tmp_path / "road.crg"], "road.crg"),
        (["import", _write_csv(tmp_path / "d.csv", common), "--channel-map", tmp_path / "bad_map.yaml"],
         "--channel-map applies to MDF4"),
    ]
    for argv, needle in cases:
        rc, out, err = run_cli(argv + ["--out", tmp_path / "out.mcap"])
        assert rc == 2 and needle in err and "Traceback" not in err, (argv, rc, err)
        assert not (tmp_path / "out.mcap").exists()
