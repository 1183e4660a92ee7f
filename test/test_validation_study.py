"""The paper-style study over the bundled drives, and `susp validate` on good and bad recordings."""
import json
import math
from pathlib import Path

import numpy as np
import pytest

from susp_sim_ros.analysis import validation as va, validation_study
from susp_sim_ros.cli.main import main

BAGS = Path(__file__).resolve().parents[1] / "bags"
VARIANTS = ["full", "no_horizontal", "no_velocity", "dahl_only"]


@pytest.fixture(scope="module")
def study_result(tmp_path_factory):
    out = tmp_path_factory.mktemp("study")
    return validation_study.run_validation_study(BAGS, out, progress=False), out


def test_study_tables_have_the_interface_shape(study_result):
    res, _ = study_result
    T = res["tables"]
    for m in ("bump_crossing", "sine_steer"):
        for s in ("intact", "front_empty", "rear_empty"):
            for v in VARIANTS:
                assert isinstance(T[m][s][v], float) and math.isfinite(T[m][s][v]) and T[m][s][v] > 0
    assert res["signals"] == {"bump_crossing": "pitch_rate", "sine_steer": "roll_rate"}


def test_study_reproduces_the_papers_qualitative_findings(study_result):
    res, _ = study_result
    bump = res["tables"]["bump_crossing"]
    intact = [bump["intact"][v] for v in VARIANTS]
    assert max(intact) / min(intact) < 1.5          # variants nearly equal on the intact car
    ratio = bump["rear_empty"]["dahl_only"] / bump["rear_empty"]["full"]
    assert ratio >= 2.0                             # Dahl-only far worse with rear dampers oil-empty
    assert res["findings"]["bump_crossing"]["rear_empty"]["dahl_only_over_full"] == pytest.approx(ratio)
    # with either axle oil-empty, the full model is the best or within 10 % of the best variant
    for s in ("front_empty", "rear_empty"):
        assert bump[s]["full"] <= 1.1 * min(bump[s].values())


def test_study_writes_report_plots_and_json_fast(study_result):
    res, out = study_result
    assert res["elapsed_s"] < 60
    assert len(res["plots"]) == 6 and all(Path(p).stat().st_size > 10_000 for p in res["plots"])
    report = (out / "report.md").read_text()
    r = res["findings"]["bump_crossing"]["rear_empty"]["dahl_only_over_full"]
    assert f"{r:.1f} times" in report and "65" in report and "synthetic" in report
    assert json.loads((out / "study.json").read_text())["tables"] == res["tables"]


def test_study_is_exactly_reproducible(study_result, tmp_path):
    res, _ = study_result
    again = validation_study.run_validation_study(BAGS, tmp_path, progress=False, plots=False)
    assert again["tables"] == res["tables"]  # bit for bit


def test_validate_study_cli_json(tmp_path, capsys):
    rc = main(["validate", "--study", str(BAGS), "--out", str(tmp_path / "r"), "--json", "--no-plots",
               "--no-progress"])
    assert rc == 0
    d = json.loads(capsys.readouterr().out)
    assert set(d["tables"]) == {"bump_crossing", "sine_steer"} and d["elapsed_s"] < 60


def test_validate_pair_identical_is_zero_and_sim_recording_matches_study(study_result, tmp_path, capsys):
    from susp_sim_ros.io.drive import read_drive
    from susp_sim_ros.runtime.lockstep import run_lockstep
    drive_path = BAGS / "bump_crossing_rear_empty.mcap"
    assert main(["validate", "--measured", str(drive_path), "--simulated", str(drive_path), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert all(v == 0.0 for w in d["rmse_deg_s"].values() for v in w.values())
    sim = tmp_path / "sim.mcap"
    run_lockstep(read_drive(drive_path), variant="dahl_only", out_path=sim)
    assert main(["validate", "--measured", str(drive_path), "--simulated", str(sim), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["simulated_topic"] == "/sim/imu/data"
    res, _ = study_result
    # the recorded simulation validates to the study's number (same lockstep, same validator)
    np.testing.assert_allclose(d["rmse_deg_s"]["bump"]["pitch_rate"],
                               res["tables"]["bump_crossing"]["rear_empty"]["dahl_only"], rtol=1e-9)


@pytest.mark.parametrize("frac", [0.0, 0.02, 0.1, 0.25, 0.37, 0.5, 0.6, 0.83, 0.95, 0.99])
def test_truncated_measured_gives_prefix_or_named_error(tmp_path, capsys, frac):
    src = BAGS / "sine_steer_intact.mcap"
    data = src.read_bytes()
    bad = tmp_path / "trunc.mcap"
    bad.write_bytes(data[:int(len(data) * frac)])
    rc = main(["validate", "--measured", str(bad), "--simulated", str(src), "--json"])
    err = capsys.readouterr().err
    assert rc in (0, 2), err
    assert "Traceback" not in err
    if rc == 2:
        assert str(bad) in err
    rc = main(["validate", "--measured", str(src), "--simulated", str(bad), "--json"])
    err = capsys.readouterr().err
    assert rc in (0, 2) and "Traceback" not in err


def test_junk_missing_topic_and_no_overlap_are_exit_2(tmp_path, capsys):
    from susp_sim_ros.io.drive import ImuSeries, TestDrive, read_drive, write_drive
    src = BAGS / "bump_crossing_intact.mcap"
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"not an mcap file")
    assert main(["validate", "--measured", str(junk), "--simulated", str(src)]) == 2
    assert "not an MCAP file" in capsys.readouterr().err
    assert main(["validate", "--measured", str(tmp_path / "none.mcap"), "--simulated", str(src)]) == 2
    assert "none.mcap" in capsys.readouterr().err
    d = read_drive(src)
    no_imu = tmp_path / "no_imu.mcap"
    write_drive(no_imu, TestDrive(d.metadata, d.speed, d.steering, d.road, None, None, {}))
    assert main(["validate", "--measured", str(no_imu), "--simulated", str(src)]) == 2
    assert "/imu/data" in capsys.readouterr().err
    assert main(["validate", "--measured", str(src), "--simulated", str(no_imu)]) == 2
    assert "/sim/imu/data" in capsys.readouterr().err
    late = tmp_path / "late.mcap"
    shift = 100 * va.NS
    d.speed.t_ns += shift
    d.steering.t_ns += shift
    write_drive(late, TestDrive(d.metadata, d.speed, d.steering, d.road, None,
                                ImuSeries(d.imu.t_ns + shift, d.imu.gyro, d.imu.accel), {}))
    assert main(["validate", "--measured", str(src), "--simulated", str(late)]) == 2
    assert "no time overlap" in capsys.readouterr().err
    assert main(["validate", "--study", str(tmp_path / "empty"), "--out", str(tmp_path / "o")]) == 2
    assert main(["validate"]) == 2


def test_study_reports_input_findings_and_names_a_refused_drive(tmp_path, capsys):
    """A copy of bags/ with one drive holed (2 s of IMU missing), one dead on its table signal (roll gyro of a
    sine steer) and one naming a vehicle without parameters: the study runs (exit 0), its report and JSON
    carry every input finding, the dead drive is named as refused (left out of the tables), the holed drive
    is compared without the gap and the unknown vehicle simulated as the reference car."""
    import dataclasses
    import shutil

    from susp_sim_ros.io.drive import ImuSeries, drive_from_recording, write_drive
    from susp_sim_ros.io.reader import read_recording
    from susp_sim_ros.model.params import DEFAULT_VEHICLE
    bags = tmp_path / "bags"
    bags.mkdir()
    for p in BAGS.glob("*.mcap"):
        shutil.copy(p, bags / p.name)

    def damage(name, change):
        d = drive_from_recording(read_recording(BAGS / name))
        write_drive(bags / name, change(d), overwrite=True)

    def hole(d):
        keep = (d.imu.t_ns < d.imu.t_ns[600]) | (d.imu.t_ns > d.imu.t_ns[600] + 2 * va.NS)
        return dataclasses.replace(d, imu=ImuSeries(d.imu.t_ns[keep], d.imu.gyro[keep], d.imu.accel[keep]))

    def dead_roll(d):
        g = d.imu.gyro.copy()
        g[:, 0] = 0.0
        return dataclasses.replace(d, imu=ImuSeries(d.imu.t_ns, g, d.imu.accel))

    damage("sine_steer_intact.mcap", hole)
    damage("sine_steer_rear_empty.mcap", dead_roll)
    damage("bump_crossing_intact.mcap", lambda d: dataclasses.replace(d, metadata={**d.metadata,
                                                                                    "vehicle": "independent"}))
    out = tmp_path / "out"
    rc = main(["validate", "--study", str(bags), "--out", str(out), "--json", "--no-plots", "--no-progress"])
    cap = capsys.readouterr()
    assert rc == 0, cap.err
    res = json.loads(cap.out)
    saved = json.loads((out / "study.json").read_text())
    kinds = {(Path(f["file"]).name, f["kind"]) for f in saved["input_findings"]}
    assert kinds == {("sine_steer_intact.mcap", "gap"), ("sine_steer_rear_empty.mcap", "dead_sensor"),
                     ("bump_crossing_intact.mcap", "bad_metadata")}
    assert {(Path(f["file"]).name, f["kind"]) for f in res["input_findings"]} == kinds
    (refused,) = saved["refused_drives"]
    assert Path(refused["file"]).name == "sine_steer_rear_empty.mcap" and "dead_sensor roll_rate" in refused["error"]
    assert "rear_empty" not in saved["tables"]["sine_steer"] and "intact" in saved["tables"]["sine_steer"]
    by_name = {Path(d["file"]).name: d for d in saved["drives"]}
    assert "sine_steer_rear_empty.mcap" not in by_name
    assert by_name["bump_crossing_intact.mcap"]["vehicle"] == DEFAULT_VEHICLE
    assert [f["kind"] for f in by_name["sine_steer_intact.mcap"]["input_findings"]] == ["gap"]
    report = (out / "report.md").read_text()
    section = report[report.index("## Input findings"):]
    for name, kind in kinds:
        assert f"{name} " in section and f" {kind} " in section, (name, kind)
    assert "refused, left out of the tables" in section and "sine_steer_rear_empty.mcap" in section
    assert "refused" in cap.err
    # the holed drive is compared without its gap: fewer samples than the intact one, none interpolated
    clean = validation_study.run_validation_study(BAGS, tmp_path / "clean", progress=False, plots=False)
    intact = {Path(d["file"]).name: d for d in clean["drives"]}["sine_steer_intact.mcap"]
    holed = by_name["sine_steer_intact.mcap"]
    n = holed["validation"]["full"]["windows"]["steering"]["signals"]["roll_rate"]["n"]
    assert n < intact["validation"]["full"]["windows"]["steering"]["signals"]["roll_rate"]["n"] - 150
    assert "## Input findings" not in (tmp_path / "clean" / "report.md").read_text()
    assert clean["input_findings"] == [] and clean["refused_drives"] == []


def test_study_refusing_every_drive_is_a_named_error(tmp_path, capsys):
    import dataclasses

    from susp_sim_ros.io.drive import drive_from_recording, write_drive
    from susp_sim_ros.io.reader import read_recording
    bags = tmp_path / "bags"
    bags.mkdir()
    d = drive_from_recording(read_recording(BAGS / "bump_crossing_intact.mcap"))
    write_drive(bags / "noroad.mcap", dataclasses.replace(d, road=None))
    rc = main(["validate", "--study", str(bags), "--out", str(tmp_path / "o"), "--no-plots", "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2 and "refused every drive" in err and "missing_topic" in err and "noroad.mcap" in err
