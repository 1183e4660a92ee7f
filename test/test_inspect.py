"""``susp inspect`` (issue 14): oil levels of the bundled bump crossings, a truth drive of the independent
simulator with one damper empty, what a drive that excites nothing gives, bad input, the state rule."""
import dataclasses
import json
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import given, strategies as st

from truth_generators import independent_sim as ind
from susp_sim_ros.analysis.inspection import inspect_drives, load_config, state_of

BAGS = Path(__file__).resolve().parents[1] / "bags"
CFG = load_config()


@pytest.mark.parametrize("name,front,rear", [("intact", 1.0, 1.0), ("front_empty", 0.0, 1.0),
                                             ("rear_empty", 1.0, 0.0)])
def test_bundled_bump_crossings_read_as_their_states(name, front, rear):
    res = inspect_drives([BAGS / f"bump_crossing_{name}.mcap"])
    for axle, truth in (("front", front), ("rear", rear)):
        a = res.axles_[axle]
        assert a["oil_level"] == pytest.approx(truth, abs=0.15), axle
        lo, hi = a["ci95"]
        assert lo - 1e-9 <= truth <= hi + 1e-9
        assert a["state"] == ("ok" if truth == 1.0 else "empty")
    assert res.elapsed_s_ < 30.0  # 2 s alone on this machine; the 10 s target is checked in the benchmark


def test_the_oil_fit_takes_its_jacobian_updates_from_the_inspection_settings(monkeypatch):
    """The oil fit's Broyden updates are the inspection's own setting (its figures were measured with every
    Jacobian simulated), never the diagnosis's fit.broyden_updates (config/discrepancy.yaml), whichever that is."""
    from susp_sim_ros.analysis.inspection import estimate
    seen = []
    real = estimate.fit_structure

    def spy(*args, **kwargs):
        seen.append(kwargs.get("broyden_updates"))
        return real(*args, **kwargs)

    monkeypatch.setattr(estimate, "fit_structure", spy)
    inspect_drives([BAGS / "bump_crossing_rear_empty.mcap"])
    assert seen and set(seen) == {CFG["estimator"]["broyden_updates"]} == {0}


@pytest.fixture(scope="module")
def truth_paths(tmp_path_factory):
    """Independent-simulator drives: a perturbed car (within the class ranges) crossing a bump at 9 km/h
    with FL oil-empty; and a car standing still (nothing excited)."""
    d = tmp_path_factory.mktemp("truth")
    car = ind.TruthCar().perturbed(7, 0.0, 0.08)
    sensor = ind.TruthSensor(gyro_noise_deg_s=(0.1, 0.1, 0.1))
    bump = ind.make_drive(car, ind.TruthFriction().perturbed(8), None,
                          ind.TruthManeuver.bump(speed_kmh=9.0, height_m=0.06, wheelbase_m=car.wheelbase),
                          sensor, (0.0, 1.0, 1.0, 1.0), seed=3)
    rest = ind.make_drive(car, None, None, ind.TruthManeuver.rest(4.0), sensor, (1.0, 1.0, 1.0, 1.0), seed=4)
    no_imu = dataclasses.replace(bump, imu=None)
    paths = {}
    for name, drive in (("bump", bump), ("rest", rest), ("no_imu", no_imu)):
        paths[name] = d / f"{name}.mcap"
        ind.write_drive(paths[name], drive, overwrite=True)
    return paths


def test_one_empty_damper_found_on_a_car_that_is_not_our_model(truth_paths):
    res = inspect_drives([truth_paths["bump"]])
    truth = {"FL": 0.0, "FR": 1.0, "RL": 1.0, "RR": 1.0}
    for w, t in truth.items():
        e = res.wheels_[w]
        assert e["identifiable"] == "wheel"  # the roll rate tells left from right
        assert e["oil_level"] == pytest.approx(t, abs=0.15), w
        assert e["ci95"][0] - 1e-9 <= t <= e["ci95"][1] + 1e-9, w
    assert res.wheels_["FL"]["state"] in ("empty", "degraded")
    assert all(res.wheels_[w]["state"] in ("ok", "unknown") for w in ("FR", "RL", "RR"))
    assert res.axles_["front"]["oil_level"] == pytest.approx(0.5, abs=0.15)


def test_a_drive_that_excites_nothing_gives_unknown_with_the_reason(truth_paths):
    res = inspect_drives([truth_paths["rest"]])
    for _w, e in res.wheels_.items():
        assert e["oil_level"] is None and e["state"] == "unknown" and e["identifiable"] == "no"
        assert "do not excite" in e["why"]


def _susp(*args):
    r = subprocess.run([sys.executable, "-m", "susp_sim_ros.cli.main", *args], capture_output=True, text=True)
    return r.returncode, r.stdout, r.stderr


def test_cli_bad_input_exit_2(truth_paths, tmp_path):
    rc, _, err = _susp("inspect", str(truth_paths["no_imu"]), "--json")
    assert rc == 2 and "/imu/data" in err and "Traceback" not in err
    rc, _, err = _susp("inspect", str(tmp_path / "missing.mcap"))
    assert rc == 2 and "missing.mcap" in err


def test_cli_json_and_report(tmp_path):
    rc, out, err = _susp("inspect", str(BAGS / "bump_crossing_rear_empty.mcap"), "--json", "--out", str(tmp_path))
    assert rc == 0, err
    d = json.loads(out)
    assert set(d["wheels"]) == {"FL", "FR", "RL", "RR"} and set(d["axles"]) == {"front", "rear"}
    for e in d["wheels"].values():
        assert set(e) >= {"oil_level", "ci95", "state", "identifiable", "why"}
    assert isinstance(d["elapsed_s"], float)
    assert (tmp_path / "inspection.md").is_file() and (tmp_path / "oil_levels.png").is_file()


bands = st.floats(0.0, 1.0, allow_nan=False)


@given(bands, bands)
def test_state_is_unknown_exactly_when_the_interval_spans_two_bands(a, b):
    lo, hi = min(a, b), max(a, b)
    s = state_of(lo, hi, CFG["states"])
    one = state_of(lo, lo, CFG["states"]) == state_of(hi, hi, CFG["states"])
    assert (s == "unknown") == (not one)
    if hi < CFG["states"]["empty_below"]:
        assert s == "empty"
    if lo >= CFG["states"]["ok_from"]:
        assert s == "ok"


def test_inspection_drive_with_unknown_oil_is_read_and_simulated_as_intact(tmp_path, caplog):
    """interface.md: an inspection drive's damper_oil_level is `unknown`; every command reads it, those
    that need oil assume intact and say so."""
    from susp_sim_ros.io.drive import read_drive, write_drive
    from susp_sim_ros.runtime.lockstep import run_lockstep
    d = read_drive(BAGS / "bump_crossing_rear_empty.mcap")
    p = tmp_path / "inspection.mcap"
    write_drive(p, dataclasses.replace(d, metadata={**d.metadata, "damper_oil_level": "unknown"}), overwrite=True)
    drive = read_drive(p)
    assert not drive.oil_known and drive.oil_levels() == (1.0, 1.0, 1.0, 1.0)
    with caplog.at_level("WARNING"):
        sim = run_lockstep(drive)
    assert sim.healthy and "unknown" in caplog.text and "intact" in caplog.text
    res = inspect_drives([p])
    assert res.axles_["rear"]["oil_level"] == pytest.approx(0.0, abs=0.15)   # found, not assumed


@given(st.sampled_from(["unknown", "UNKNOWN", " Unknown "]))
def test_unknown_oil_text(text):
    from susp_sim_ros.errors import RecordingError
    from susp_sim_ros.io.drive import oil_unknown, parse_oil
    assert oil_unknown(text) and not oil_unknown("1,1,1,1") and not oil_unknown(None)
    with pytest.raises(RecordingError, match="expected four comma-separated fractions"):
        parse_oil(text)


def test_without_roll_rate_only_the_axles_are_identifiable():
    """Left and right crossing the bump alike differ only through the roll they cause: without the roll
    rate the fit has one oil level per axle, and both wheels carry its figures."""
    cfg = load_config()
    cfg["estimator"]["signals"] = ["pitch_rate", "accel_z"]
    res = inspect_drives([BAGS / "bump_crossing_rear_empty.mcap"], cfg=cfg)
    for axle, wheels, truth in (("front", ("FL", "FR"), 1.0), ("rear", ("RL", "RR"), 0.0)):
        a = res.axles_[axle]
        assert a["identifiable"] == "axle" and a["oil_level"] == pytest.approx(truth, abs=0.15)
        for w in wheels:
            e = res.wheels_[w]
            assert e["identifiable"] == "axle" and e["oil_level"] == a["oil_level"] and e["ci95"] == a["ci95"]
            assert "roll rate" in e["why"]


def _crossing(tmp_path, speed_kmh, height_m, name):
    sensor = ind.TruthSensor(gyro_noise_deg_s=(0.05, 0.05, 0.05))
    d = ind.make_drive(ind.TruthCar(), None, None, ind.TruthManeuver.bump(speed_kmh=speed_kmh, height_m=height_m),
                       sensor, (1.0, 1.0, 1.0, 1.0), seed=5)
    p = tmp_path / f"{name}.mcap"
    ind.write_drive(p, d, overwrite=True)
    return p


def test_a_crossing_outside_the_protocol_is_warned_about_with_wider_intervals(tmp_path):
    """Issue 27: the report states the crossing it saw against the protocol it is validated for; a drive
    too fast over too high a bump gets a warning with the reason and wider intervals."""
    inside = inspect_drives([_crossing(tmp_path, 9.0, 0.06, "inside")])
    outside = inspect_drives([_crossing(tmp_path, 22.0, 0.10, "outside")])
    seen = inside.protocol_["seen"][0]
    assert seen["speed_m_s"] == pytest.approx(9.0 / 3.6, rel=0.01)
    assert seen["bump_height_m"] == pytest.approx(0.06, rel=0.01)
    assert 0.2 < seen["peak_damper_velocity_m_s"]["front"] < outside.protocol_["seen"][0][
        "peak_damper_velocity_m_s"]["front"]
    assert inside.protocol_["warnings"] == []
    quantities = {w["quantity"] for w in outside.protocol_["warnings"]}
    assert quantities == {"speed_m_s", "bump_height_m"}
    assert all("validated for" in w["reason"] for w in outside.protocol_["warnings"])
    assert any("outside the test protocol" in n for n in outside.notes_)
    width = {r: [e["ci95"][1] - e["ci95"][0] for e in res.axles_.values()] for r, res in
             (("in", inside), ("out", outside))}
    # the model-form sd grows with the crossing's peak damper velocity, doubled outside the protocol
    from susp_sim_ros.analysis.inspection.estimate import model_form_sd
    factor = CFG["protocol"]["outside_model_form_factor"]
    assert inside.protocol_["model_form_sd_per_axle"] == model_form_sd(inside.protocol_["seen"], CFG["estimator"])
    assert outside.protocol_["model_form_sd_per_axle"] == model_form_sd(outside.protocol_["seen"], CFG["estimator"],
                                                                        factor)
    assert outside.protocol_["model_form_sd"] >= factor * inside.protocol_["model_form_sd"]
    for w_in, w_out in zip(width["in"], width["out"]):
        assert w_out > w_in


def test_protocol_names_a_drive_set_that_excites_one_axle_only():
    from susp_sim_ros.analysis.inspection import protocol
    cfg = load_config()["protocol"]
    seen = [{"drive": "d", "speed_m_s": 2.5, "bump_height_m": 0.05,
             "peak_damper_velocity_m_s": {"front": 0.4, "rear": 0.0}}]
    found = protocol.warnings(seen, {"front": {"identifiable": "axle"}, "rear": {"identifiable": "no"}}, cfg)
    assert [w["quantity"] for w in found] == ["axles_excited"] and "rear" in found[0]["reason"]
    assert protocol.model_form_factor(found, cfg) == 1.0      # a set-level warning, no drive outside
    slow = [dict(seen[0], speed_m_s=1.0)]
    assert protocol.model_form_factor(protocol.warnings(slow, {}, cfg), cfg) == cfg["outside_model_form_factor"]


def test_model_form_sd_grows_with_the_peak_damper_velocity():
    """Issue 27 item 2: the intervals' model-form term is learned on the development forms as a base plus
    a part per m/s of the axle's peak damper velocity (config entries with unit and source), per axle."""
    from susp_sim_ros.analysis.inspection.estimate import model_form_sd
    est = CFG["estimator"]
    assert est["model_form_sd_per_m_s"] > 0
    seen = [{"peak_damper_velocity_m_s": {"front": 0.5, "rear": 2.0}},
            {"peak_damper_velocity_m_s": {"front": 1.0, "rear": 1.5}}]
    sd = model_form_sd(seen, est)
    assert sd["front"] == pytest.approx(est["model_form_sd"] + 1.0 * est["model_form_sd_per_m_s"])
    assert sd["rear"] == pytest.approx(est["model_form_sd"] + 2.0 * est["model_form_sd_per_m_s"])
    assert model_form_sd(seen, est, 2.0)["rear"] == pytest.approx(2 * sd["rear"])


def test_signal_model_form_weights_a_signal_by_how_hard_the_drive_moved_it():
    """Each signal's residual sd is its noise combined with a fraction of its own RMS excursion: a signal
    the drive barely moves keeps its noise weight, one it moves hard counts less; samples held out (weight
    0) stay out."""
    from types import SimpleNamespace
    import numpy as np
    from susp_sim_ros.analysis.inspection.estimate import add_signal_model_form, signal_excursion
    rng = np.random.default_rng(0)
    quiet, moved = rng.normal(0, 0.1, 400), 2.0 * np.sin(np.linspace(0, 20, 400))
    case = SimpleNamespace(signals=("roll_rate", "accel_z"), y_meas=np.column_stack([quiet, moved]))
    w = np.column_stack([np.full(400, 10.0), np.full(400, 50.0)])
    w[:5] = 0.0
    ev = SimpleNamespace(cases=[case], weights=[w.copy()])
    add_signal_model_form(ev, {"roll_rate": 0.1, "accel_z": 0.3})
    got = ev.weights[0]
    assert np.all(got[:5] == 0.0)
    assert got[10, 0] == pytest.approx(1.0 / np.hypot(0.1, 0.1 * signal_excursion(quiet)))
    assert got[10, 0] == pytest.approx(10.0, rel=0.01)                   # noise-dominated: unchanged
    assert got[10, 1] == pytest.approx(1.0 / np.hypot(0.02, 0.3 * signal_excursion(moved)))
    assert got[10, 1] < 50.0 / 10                                         # moved hard: counts much less


def test_curve_beyond_factor_changes_the_intact_curve_only_beyond_its_measured_points():
    """The per-axle factor scales the intact hydraulic curve's rise beyond the last measured velocity and
    leaves the measured range and the oil-empty curve alone; 1 is the vehicle file's extrapolation."""
    import numpy as np
    from susp_sim_ros.analysis.inspection.estimate import curve_beyond_candidate
    from susp_sim_ros.model import Model
    from susp_sim_ros.model.layout import DAMPER_GRID, N_GRID, P_H_EMPTY, P_H_INTACT
    model = Model()
    cand = curve_beyond_candidate(model, 0.5)
    P0 = model.params()[None, :]
    P1 = P0.copy()
    cand.apply(P1, P0, np.array([1.0, 1.0]), model)
    assert np.array_equal(P1, P0)
    P2 = P0.copy()
    cand.apply(P2, P0, np.array([2.0, 0.5]), model)
    v_end = max(model.vehicle.damper_velocity)
    out = np.abs(DAMPER_GRID) > v_end + 1e-9
    g_end = int(np.argmin(np.abs(DAMPER_GRID - v_end)))
    g_far = int(np.argmax(DAMPER_GRID))
    for w, f in ((0, 2.0), (1, 2.0), (2, 0.5), (3, 0.5)):
        base = P_H_INTACT + w * N_GRID
        assert np.array_equal(P2[0, base:base + N_GRID][~out], P0[0, base:base + N_GRID][~out])
        rise0 = P0[0, base + g_far] - P0[0, base + g_end]
        assert P2[0, base + g_far] - P2[0, base + g_end] == pytest.approx(f * rise0)
    assert np.array_equal(P2[0, P_H_EMPTY:P_H_EMPTY + 4 * N_GRID], P0[0, P_H_EMPTY:P_H_EMPTY + 4 * N_GRID])


def test_a_fast_high_crossing_of_a_development_form_reads_intact(tmp_path):
    """Issue 27 item 1: an intact car of another simulator's development form (PCHIP curve, own
    extrapolation), driven at 14 km/h over a 7.5 cm bump (dampers at 2-3 m/s, beyond the curve's last
    measured point), reads intact once the estimate stands on what the drive informs (the curve beyond
    its measured points fitted per axle, each signal weighted by its model-form spread); with both held
    as before it read 0.7-0.8."""
    from truth_generators import family
    d = family.bump_crossing(family.FORMS["structure/nominal"], 1, (1.0, 1.0, 1.0, 1.0), 14.0, 0.075)
    p = tmp_path / "fast.mcap"
    ind.write_drive(p, d, overwrite=True)
    res = inspect_drives([p])
    for w, e in res.wheels_.items():
        assert e["oil_level"] == pytest.approx(1.0, abs=0.06), w
        assert e["ci95"][0] <= 1.0 <= e["ci95"][1] + 1e-9 and e["state"] in ("ok", "unknown"), w
    assert {n["param"] for n in res.nuisance_} >= {"curve_beyond_front", "curve_beyond_rear"}
    old = load_config()
    old["estimator"].update(signal_model_form={}, curve_beyond_prior_sd=0.0)
    before = inspect_drives([p], cfg=old)
    assert max(e["oil_level"] for e in before.wheels_.values()) < 0.85


@pytest.fixture(scope="module")
def left_right_paths(tmp_path_factory):
    """Independent-simulator crossings (not our model) of one perturbed car at 9 km/h over a 6 cm bump:
    intact, and with the rear-left damper half filled (the others intact)."""
    d = tmp_path_factory.mktemp("left_right")
    car = ind.TruthCar().perturbed(11, 0.0, 0.08)
    sensor = ind.TruthSensor(gyro_noise_deg_s=(0.1, 0.1, 0.1))
    paths = {}
    for name, oil in (("intact", (1.0, 1.0, 1.0, 1.0)), ("rl_half", (1.0, 1.0, 0.5, 1.0))):
        drive = ind.make_drive(car, ind.TruthFriction().perturbed(12), None,
                               ind.TruthManeuver.bump(speed_kmh=9.0, height_m=0.06, wheelbase_m=car.wheelbase),
                               sensor, oil, seed=13)
        paths[name] = d / f"{name}.mcap"
        ind.write_drive(paths[name], drive, overwrite=True)
    return paths


def _lr(res) -> dict:
    d = res.to_json()["left_right"]
    assert [e["axle"] for e in d] == ["front", "rear"]
    for e in d:
        assert set(e) >= {"axle", "difference", "ci95", "asymmetric", "reason"}
    return {e["axle"]: e for e in d}


def test_one_half_filled_rear_damper_flags_the_rear_axle_asymmetric(left_right_paths, tmp_path):
    """Issue 27 item 1: left against right per axle. Rear-left at half oil, the others intact: the rear's
    left-minus-right difference is about -0.5 with an interval that excludes zero, flagged asymmetric and
    said so in words; the front is not flagged. The report has the section, one line per axle."""
    from susp_sim_ros.analysis.inspection.report import write_inspection_report
    res = inspect_drives([left_right_paths["rl_half"]])
    lr = _lr(res)
    rear, front = lr["rear"], lr["front"]
    assert rear["difference"] == pytest.approx(-0.5, abs=0.15)
    assert rear["ci95"][1] < 0.0 and rear["asymmetric"]
    assert abs(rear["difference"]) > CFG["left_right"]["asymmetric_min_difference"]
    assert rear["reason"].startswith("rear: left (RL) ") and "lower than right (RR)" in rear["reason"]
    assert "lost oil" in rear["reason"]
    assert not front["asymmetric"] and front["ci95"][0] <= 0.0 <= front["ci95"][1]
    # the difference is the wheels' own figures, its sd the joint one (tighter than either wheel's interval
    # would suggest when their errors are correlated, never looser than the fit's own sds combined)
    w = res.wheels_
    assert rear["difference"] == pytest.approx(w["RL"]["oil_level"] - w["RR"]["oil_level"])
    assert rear["sd"] <= w["RL"]["sd_fit"] + w["RR"]["sd_fit"] + 1e-12
    md = write_inspection_report(res, tmp_path / "out", CFG, [left_right_paths["rl_half"]])
    text = Path(md["report"]).read_text()
    section = text.split("## Left against right", 1)[1].split("\n## ", 1)[0]
    lines = [s for s in section.splitlines() if s.startswith("- ")]
    assert len(lines) == 2 and "**asymmetric**" in lines[1] and "rear:" in lines[1] and "front:" in lines[0]
    assert json.loads(Path(md["json"]).read_text())["left_right"][1]["asymmetric"] is True


def test_an_intact_car_is_not_flagged_asymmetric(left_right_paths):
    res = inspect_drives([left_right_paths["intact"]])
    for axle, e in _lr(res).items():
        assert not e["asymmetric"], axle
        assert e["ci95"][0] <= 0.0 <= e["ci95"][1] and "alike" in e["reason"], axle


def test_both_rear_dampers_empty_are_alike_not_asymmetric():
    """Both rear dampers oil-empty (the bundled drive): each reads empty, and left against right they are
    alike (the axle as a whole has lost its oil), so the rear is not flagged asymmetric."""
    res = inspect_drives([BAGS / "bump_crossing_rear_empty.mcap"])
    for w in ("RL", "RR"):
        assert res.wheels_[w]["state"] == "empty" and res.wheels_[w]["oil_level"] < 0.15, w
    lr = _lr(res)
    assert not lr["rear"]["asymmetric"] and not lr["front"]["asymmetric"]
    assert lr["rear"]["ci95"][0] <= 0.0 <= lr["rear"]["ci95"][1]
    assert "alike" in lr["rear"]["reason"] and "lost" in lr["rear"]["reason"]


def test_left_right_rule_without_a_fit():
    """The comparison's rule on given figures: flagged only when the interval excludes zero AND the
    difference exceeds the configured limit; an axle the drives do not tell apart has no difference; a
    one-sided excitation adds the two sides' model-form sds as independent."""
    import numpy as np
    from susp_sim_ros.analysis.inspection.estimate import GroupLevel, left_right
    thr = CFG["left_right"]["asymmetric_min_difference"]
    ident = {"front": {"identifiable": "wheel"}, "rear": {"identifiable": "wheel"}}
    x = np.array([1.0, 1.0 - 0.5 * thr, 1.0 - 2.0 * thr, 1.0])   # front: apart but small; rear: large
    by_group = {w: GroupLevel(float(x[j]), 0.0, 1.0, j) for j, w in enumerate(("FL", "FR", "RL", "RR"))}
    cov = np.diag([0.01 ** 2] * 4)
    sd_m = {"front": 0.05, "rear": 0.05}
    lr = {e["axle"]: e for e in left_right(ident, by_group, cov, sd_m, False, {}, CFG["left_right"])}
    assert lr["front"]["ci95"][0] > 0.0 and not lr["front"]["asymmetric"]
    assert lr["rear"]["asymmetric"] and lr["rear"]["sd"] == pytest.approx(0.01 * np.sqrt(2))
    one_sided = left_right(ident, by_group, cov, sd_m, True, {}, CFG["left_right"])
    assert one_sided[1]["sd"] == pytest.approx(np.sqrt(2 * 0.01 ** 2 + 2 * 0.05 ** 2))
    none = left_right({"front": {"identifiable": "axle"}, "rear": {"identifiable": "no"}}, {}, cov, sd_m,
                      False, {}, CFG["left_right"])
    assert all(e["difference"] is None and e["ci95"] is None and not e["asymmetric"] for e in none)
    assert "tell its left from its right" in none[0]["reason"] and "do not excite" in none[1]["reason"]
