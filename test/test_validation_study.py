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
