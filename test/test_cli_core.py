"""The susp CLI: JSON keys of interface.md, exit codes, the paper study's qualitative findings."""
import json
import subprocess
import sys

import numpy as np
import pytest

from susp_sim_ros.analysis.paper_comparison import run_paper_comparison


def susp(*args):
    r = subprocess.run([sys.executable, "-m", "susp_sim_ros.cli.main", *args], capture_output=True, text=True)
    return r.returncode, r.stdout, r.stderr


def test_rig_json_keys():
    rc, out, err = susp("rig", "damper", "--axle", "front", "--oil", "0", "--json")
    assert rc == 0, err
    d = json.loads(out)
    assert d["half_hysteresis_N"] == pytest.approx(29.0, rel=0.02)
    fv = np.array(d["force_velocity"])
    assert fv.shape == (34, 2) and np.all(np.diff(fv[:, 0]) > 0)
    rc, out, _ = susp("rig", "axle", "--axle", "rear", "--fy", "1000", "--json")
    assert json.loads(out)["half_hysteresis_N"] == pytest.approx(55.9, rel=0.02)


@pytest.mark.parametrize("args,needle", [
    (("rig", "damper", "--axle", "front", "--oil", "1.5"), "--oil"),
    (("rig", "axle", "--axle", "front", "--config", "no_such_car"), "unknown vehicle 'no_such_car'"),
    (("rig", "axle", "--axle", "front", "--variant", "/nonexistent/v.yaml"), "v.yaml"),
])
def test_bad_input_exit_2_with_named_error(args, needle):
    rc, out, err = susp(*args, "--json")
    assert rc == 2
    assert needle in err and "Traceback" not in err


def test_paper_study_qualitative_findings():
    """Paper: variants hardly differ on the intact car; with oil-empty rear dampers the body rings out
    far longer and the variants separate (no velocity scaling underestimates friction)."""
    st = run_paper_comparison()
    bump = st.rmse_vs_full["bump_crossing"]
    ring = st.ring_out_s["bump_crossing"]
    peak_intact = np.max(np.abs(st.traces["bump_crossing"]["intact"]["full"][1]))
    assert max(bump["intact"].values()) < 0.01 * peak_intact
    assert bump["rear_empty"]["dahl_only"] > 5 * bump["intact"]["dahl_only"]
    assert bump["rear_empty"]["no_velocity"] > 5 * bump["rear_empty"]["no_horizontal"]
    assert ring["rear_empty"]["full"] > 2 * ring["intact"]["full"]
    assert ring["rear_empty"]["dahl_only"] > 1.25 * ring["rear_empty"]["full"]
    assert max(ring["intact"].values()) - min(ring["intact"].values()) < 0.1


def test_paper_job_writes_report_and_plots(tmp_path):
    rc, out, err = susp("paper", "--out", str(tmp_path), "--json")
    assert rc == 0, err
    d = json.loads(out)
    assert set(d["rmse_vs_full_deg_s"]) == {"bump_crossing", "sine_steer"}
    assert d["rmse_vs_full_deg_s"]["bump_crossing"]["rear_empty"]["full"] == 0.0
    for p in d["plots"] + d["rig_plots"]:
        assert (tmp_path / p.split("/")[-1]).stat().st_size > 10_000  # a real figure, not an empty file
    assert "| rear_empty |" in (tmp_path / "paper_study.md").read_text()


def test_rig_plot_png(tmp_path):
    rc, _, err = susp("rig", "axle", "--axle", "front", "--plot", str(tmp_path / "loop.png"))
    assert rc == 0, err
    assert (tmp_path / "loop.png").read_bytes()[:4] == b"\x89PNG"
