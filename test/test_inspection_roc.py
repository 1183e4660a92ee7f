"""The damper-inspection detection study (issue 14): car draws, the ROC figures, the cheap model-based
statistic against the full ``susp inspect`` estimate, and a small study end to end."""
import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from susp_sim_ros.analysis.inspection import inspect_drives, load_config
from susp_sim_ros.analysis.inspection import roc
from susp_sim_ros.analysis.inspection.estimate import nuisance_params, one_step_estimate, prepare
from susp_sim_ros.model.params import load_vehicle

BAGS = Path(__file__).resolve().parents[1] / "bags"
ROOT = Path(__file__).resolve().parents[1]


def test_shipped_study_loads_and_draws_cars_within_the_documented_ranges():
    from susp_sim_ros.analysis.sweep import load_study
    spec = load_study(ROOT / "config/studies/inspection_roc.yaml")
    r = spec.data["roc"]
    vp = load_vehicle(spec.data["vehicle"])
    draws = [roc.car_draw(r, vp, i) for i in range(300)]
    assert roc.car_draw(r, vp, 17) == draws[17]          # a pure function of (seed, car)
    for d in draws:
        for f, v in d["values"].items():
            pr = vp.priors[f]
            vals = v if isinstance(v, tuple) else (v,)
            for a, x in enumerate(vals):
                assert pr.lo[a] <= x <= pr.hi[a], f
        assert r["speed_kmh"][0] <= d["speed_kmh"] <= r["speed_kmh"][1]
        n_bad = sum(o < 1.0 for o in d["oil"])
        assert n_bad == {"intact": 0, "one_empty": 1, "one_half": 1}.get(d["state"], n_bad)
        assert d["state"] != "several" or n_bad >= 2
    share = np.mean([d["state"] == "intact" for d in draws])
    assert share == pytest.approx(r["states"]["intact"], abs=0.08)


@given(st.lists(st.floats(-5, 5), min_size=2, max_size=30), st.lists(st.floats(-5, 5), min_size=2, max_size=30))
@settings(max_examples=50, deadline=None)
def test_auc_is_mann_whitney_and_antisymmetric(neg, pos):
    neg, pos = np.array(neg), np.array(pos)
    a = roc.auc(neg, pos)
    brute = np.mean([(p > n) + 0.5 * (p == n) for p in pos for n in neg])
    assert a == pytest.approx(brute, abs=1e-12)
    assert roc.auc(pos, neg) == pytest.approx(1.0 - a, abs=1e-12)


def test_sensitivity_at_specificity():
    neg = np.arange(100.0)
    assert roc.sensitivity_at(neg, np.array([200.0, 96.0, 10.0, 95.0]), 0.95) == pytest.approx(0.5)


@pytest.fixture(scope="module")
def one_step_vs_full():
    cfg = load_config()
    out = {}
    for s in ("intact", "front_empty", "rear_empty"):
        p = BAGS / f"bump_crossing_{s}.mcap"
        model, ev, _ = prepare([p], cfg=cfg)
        x, _ = one_step_estimate(ev, nuisance_params(model, cfg["estimator"]["nuisance"]), cfg)
        full = inspect_drives([p], cfg=cfg)
        out[s] = (x, np.array([full.wheels_[w]["oil_level"] for w in ("FL", "FR", "RL", "RR")]))
    return cfg, out


def test_one_step_statistic_relates_to_the_full_inspect_estimate(one_step_vs_full):
    """The ROC study's model-based statistic is one Gauss-Newton step of the objective `susp inspect`
    minimises, from the intact car. Near intact it is the converged fit (to second order: 0.05); with an
    empty damper it overshoots the empty wheels to the bound and pulls the intact ones down, but it flags
    the same wheels as the full fit and ranks the cars as the full fit does."""
    cfg, out = one_step_vs_full
    x, full = out["intact"]
    np.testing.assert_allclose(x, full, atol=0.05)
    empty_below = cfg["states"]["empty_below"]
    for s, bad in (("front_empty", (0, 1)), ("rear_empty", (2, 3))):
        x, full = out[s]
        assert set(np.nonzero(x < empty_below)[0]) == set(bad) == set(np.nonzero(full < empty_below)[0])
        assert (1 - x.min()) > (1 - out["intact"][0].min()) + 0.5   # the statistic ranks it above intact


def test_small_study_end_to_end(tmp_path):
    from susp_sim_ros.analysis.sweep import make_executor, run_study
    from susp_sim_ros.analysis.sweep import study_from_dict
    spec = study_from_dict({"name": "roc_tiny", "kind": "roc", "chunk_size": 4, "roc": {
        "seed": 5, "cars": 8, "states": {"intact": 0.5, "one_empty": 0.5}, "variation": ["sprung_mass"],
        "speed_kmh": [6.0, 10.0], "bump_height": [0.05, 0.07], "gyro_noise_deg_s": [0.1, 0.1],
        "estimator_variants": ["full"], "bootstrap": 50}}, "<tiny>")
    class Stop(Exception):
        pass

    def stop(_cid):
        raise Stop

    with pytest.raises(Stop):   # killed after its first chunk ...
        run_study(spec, tmp_path / "out", make_executor("inprocess"), progress=False, on_chunk=stop)
    res = run_study(spec, tmp_path / "out", make_executor("inprocess"), progress=False)
    assert res["chunks_resumed"] == 1 and res["chunks_computed"] == 1   # ... resumes without redoing it
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert set(summary["roc"]) >= set(roc.METHODS)
    for m in roc.METHODS:
        lo, hi = summary["roc"][m]["auc_ci95"]
        assert 0.0 <= lo <= summary["roc"][m]["auc"] <= hi <= 1.0
    assert summary["roc"]["model_based"]["auc"] == 1.0   # an empty damper is never missed here
    assert res["cars_failed"] == 0 and (tmp_path / "out" / "cars.csv").is_file()


def test_independent_truth_cars_are_scored_by_every_method():
    """truth_generator plug-in truth_generators.roc:bump_crossing: the bump crossing comes from the
    independent simulator (not our model); an intact car and one with FR oil-empty (cars 0 and 1 of this
    seed) are told apart."""
    spec = roc.roc_spec({"roc": {"seed": 20261123, "cars": 2,
                                 "truth_generator": "truth_generators.roc:bump_crossing",
                                 "states": {"intact": 0.4, "one_empty": 0.35, "one_half": 0.2, "several": 0.05},
                                 "variation": ["sprung_mass", "tyre_stiffness", "axle_friction"],
                                 "speed_kmh": [5.0, 15.0], "bump_height": [0.04, 0.08],
                                 "gyro_noise_deg_s": [0.05, 0.2], "estimator_variants": ["full"]}}, "<t>", "t")
    intact, empty = (roc.car_statistics(spec.data, i) for i in (0, 1))
    assert intact["state"] == "intact" and empty["state"] == "one_empty" and empty["oil_FR"] == 0.0
    assert all(intact[f"est_oil_{w}"] > 0.85 for w in ("FL", "FR", "RL", "RR"))
    assert empty["est_oil_FR"] < 0.3 and empty["model_based"] > intact["model_based"] + 0.5
    assert empty["eusama"] > intact["eusama"] and empty["phase_shift"] > intact["phase_shift"]


def _held_out_roc(cars: int, **extra):
    """The held-out twin's roc section (config/studies/inspection_roc_held_out.yaml) with ``cars`` cars."""
    import yaml
    doc = yaml.safe_load((ROOT / "config/studies/inspection_roc_held_out.yaml").read_text())
    doc["roc"].update(cars=cars, **extra)
    return doc


def test_family_plugin_cycles_the_held_out_forms_deterministically():
    """truth_generators.roc:family_bump_crossing: car i from held-out form i mod n (the split as loaded),
    the same drive for the same draw, different forms giving different drives; the drawn car values in
    the form's car except for the beyond-priors form, whose car keeps its own band."""
    from truth_generators import family
    from truth_generators import roc as plugins
    spec = roc.roc_spec(_held_out_roc(4), "<t>", "t")
    r = spec.data["roc"]
    held_out = [f.name for f in family.forms("held_out")]
    assert r["truth_generator_options"]["forms"] == held_out
    vp = load_vehicle(spec.data["vehicle"])
    draws = [roc.car_draw(r, vp, i) for i in range(2)]
    out = [plugins.family_bump_crossing(d, r) for d in draws]
    assert [o[0].metadata["truth_form"] for o in out] == held_out[:2]
    again = plugins.family_bump_crossing(draws[0], r)
    np.testing.assert_array_equal(again[0].imu.gyro, out[0][0].imu.gyro)
    assert again[1] == out[0][1]
    n = min(len(o[2]) for o in out)
    assert not np.allclose(out[0][2][:n], out[1][2][:n])
    assert 0 < out[0][1] < len(out[0][2])
    # the car: drawn values where the form's car allows
    d = draws[0]
    form = family.FORMS["structure/tyre_lag_0.25m"]
    car = plugins.family_car(form, d, 7)
    assert car.sprung_mass == d["values"]["sprung_mass"] and car.relaxation_length == 0.25
    beyond = plugins.family_car(family.FORMS["structure/car_beyond_priors"], d, 7)
    assert abs(beyond.sprung_mass / 1400.0 - 1.0) >= 0.15 and beyond.sprung_mass != d["values"]["sprung_mass"]
    # forms named in the study; an unknown one refused when the study is loaded
    named = roc.roc_spec(_held_out_roc(2, truth_generator_options={"forms": ["viscous/power"]}), "<t>", "t")
    assert plugins.family_bump_crossing(d, named.data["roc"])[0].metadata["truth_form"] == "viscous/power"
    from susp_sim_ros.errors import ConfigError
    with pytest.raises(ConfigError, match="truth_generator_options.*no/such"):
        roc.roc_spec(_held_out_roc(2, truth_generator_options={"forms": ["no/such"]}), "<t>", "t")


def test_held_out_twin_study_end_to_end(tmp_path):
    """A handful of the held-out twin's cars (two forms, 6 cars) through the study: every method
    reported, each car's form in cars.csv."""
    import csv
    from susp_sim_ros.analysis.sweep import make_executor, run_study, study_from_dict
    doc = _held_out_roc(6, truth_generator_options={"forms": ["structure/velocity_scaling_sqrt", "viscous/power"]},
                        states={"intact": 0.5, "one_empty": 0.5}, bootstrap=20, estimator_variants=["full"],
                        seed=5)
    doc["chunk_size"] = 6
    spec = study_from_dict(doc, "<held-out tiny>")
    res = run_study(spec, tmp_path / "out", make_executor("inprocess"), progress=False)
    assert res["cars_failed"] == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert set(summary["roc"]) == set(roc.METHODS)
    for m in roc.METHODS:
        assert 0.0 <= summary["roc"][m]["auc"] <= 1.0
    with open(tmp_path / "out" / "cars.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["truth_form"] for r in rows] == ["structure/velocity_scaling_sqrt", "viscous/power"] * 3
