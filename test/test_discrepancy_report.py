"""What the diagnosis report says (issue 24: honest reports): 95 % intervals stay within a quantity's domain
(a length, mass, level or time constant is never shown below zero, a signed quantity is not bounded), an
informed value with an interval wider than its range says what that means, and a parameter given per drive
and signal is summarised, not left blank."""
from __future__ import annotations

import math

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from susp_sim_ros.analysis.discrepancy.calibration import CalParam, calibration_entries
from susp_sim_ros.analysis.discrepancy.candidates import CandParam


def _cal(field: str, lo: float, hi: float, prior: float) -> CalParam:
    return CalParam(field, field, "all", None, "1", prior, lo, hi, "test range")


def test_a_positive_calibration_value_has_no_negative_interval():
    """The bundled dahl_only diagnosis once reported the relaxation length 0.503 m within [-0.018, 1.024] m."""
    p = _cal("relaxation_length", 0.3, 0.8, 0.5)
    (e,) = calibration_entries([p], np.array([0.503]), np.array([-0.01776]), np.array([1.024]), [True])
    assert e["ci95"] == [0.0, 1.024] and e["value"] == 0.503


def test_a_signed_calibration_value_keeps_its_interval():
    p = _cal("steering_offset", -0.02, 0.02, 0.0)
    (e,) = calibration_entries([p], np.array([0.001]), np.array([-0.03]), np.array([0.03]), [True])
    assert e["ci95"] == [-0.03, 0.03]


def test_a_term_level_interval_starts_at_zero_and_holds_the_estimate():
    level = CandParam("extra_front", "N", 0.0, 0.0, 200.0, 1.0)
    assert level.interval_floor(9.19) == 0.0
    memory = CandParam("memory", "s", 1.0, 0.05, 30.0, 0.1)
    assert memory.interval_floor(0.98) == 0.0   # cut at 0, not at its lowest fitted value: an interval
    # that held zero still does, so nothing that reads "holds no effect" changes
    physical = CandParam("gain", "1", 0.0, -1.0, 1.0, 0.1, physical_lower=0.0)
    assert physical.interval_floor(0.3) == 0.0
    lag = CandParam("lag", "s", 0.0, -0.05, 0.05, 0.001)
    assert lag.interval_floor(0.002) == -math.inf


@given(st.floats(0.0, 1e3), st.floats(-1e3, 1e3), st.floats(0.0, 1e3))
def test_clipped_interval_still_holds_the_estimate(value, half_low, half_high):
    """Whatever the interval's width, clipping never moves its lower end above the estimate."""
    p = _cal("axle_friction", 30.0, 40.0, 35.0)
    lo, hi = value - abs(half_low), value + half_high
    (e,) = calibration_entries([p], np.array([value]), np.array([lo]), np.array([hi]), [True])
    assert e["ci95"][0] <= value <= e["ci95"][1] and e["ci95"][0] >= 0.0


def test_report_says_when_an_informed_value_has_an_interval_wider_than_its_range():
    """'informed: yes' beside an interval wider than the prior range reads as a contradiction: the report
    says what it means (the drives' compromise)."""
    from types import SimpleNamespace
    from susp_sim_ros.analysis.discrepancy.report import _md_calibration
    wide = calibration_entries([_cal("relaxation_length", 0.3, 0.8, 0.5)], np.array([0.503]),
                               np.array([-0.018]), np.array([1.024]), [True])
    narrow = calibration_entries([_cal("cg_height", 0.48, 0.62, 0.55)], np.array([0.549]),
                                 np.array([0.501]), np.array([0.597]), [True])
    text = "\n".join(_md_calibration(SimpleNamespace(), {"calibration": wide + narrow}, {}, "x"))
    rows = {line.split("|")[1].strip(): line for line in text.splitlines() if line.startswith("| ")}
    assert "interval wider than its range" in rows["relaxation_length"]
    assert "interval wider" not in rows["cg_height"]
    assert "relaxation_length: the drives' information narrows it" in text and "compromise" in text


def test_a_per_drive_sensor_bias_is_summarised_not_left_blank():
    """The bundled diagnosis listed sensor_bias with an empty "parameters:" line (its values are per drive and
    signal); now the largest with its interval, and where the rest is."""
    from types import SimpleNamespace
    from susp_sim_ros.analysis.discrepancy.report import _md_findings
    bias = {"term": {"name": "sensor_bias", "where": "all", "evidence": {"statement": "offsets",
                                                                         "units": {"bias": "deg/s"}},
                     "params": {"bias": {"a:pitch_rate": 0.002, "b:roll_rate": -0.011, "b:pitch_rate": None}},
                     "ci95": {"a:pitch_rate": [0.0, 0.004], "b:roll_rate": [-0.015, -0.007]}}}
    amp = {"name": "friction_amplitude", "where": "rear", "evidence": {"statement": "grows"},
           "params": {"extra_rear": 24.4}, "ci95": {"extra_rear": [2.5, 46.3]}}
    f = SimpleNamespace(skipped_=[], competing_=[], in_base_=[])
    text = "\n".join(_md_findings(f, {"terms": [bias["term"], amp]}, {}, "x"))
    assert "parameters: \n" not in text + "\n" and "  - parameters: extra_rear = 24.4 [2.5, 46.3]" in text
    assert "bias per drive and signal (deg/s): 3 values, the largest in size -0.011 [-0.015, -0.007] at b:roll_rate" \
        in text


def test_noise_line_says_when_there_is_no_quiet_lead_in(monkeypatch):
    """The highway drives (no standstill) printed "quiet lead-in cross-check nan deg/s"."""
    from types import SimpleNamespace
    from susp_sim_ros.analysis.discrepancy import report
    monkeypatch.setattr(report, "verdict", lambda f: ("unmeasured_input", "the road is not in the recording"))
    noise = {"noise_floors": {"roll_rate": 0.18}, "units": {"roll_rate": "deg/s"}}
    f = SimpleNamespace(model_=SimpleNamespace(vehicle=SimpleNamespace(name="car")), base_variant_=None,
                        variant="full", cases_=[1, 2], noise_floor_=0.3965,
                        noise_={**noise, "quiet_lead_in_pooled_deg_s": None})
    text = "\n".join(report._md_header(f, {}, {}, "x"))
    assert "nan" not in text and "no quiet lead-in in the drives to cross-check it" in text
    f.noise_ = {**noise, "quiet_lead_in_pooled_deg_s": 0.0392}
    assert "quiet lead-in cross-check 0.0392 deg/s" in "\n".join(report._md_header(f, {}, {}, "x"))


def test_selection_table_says_when_no_step_was_taken(monkeypatch):
    """A diagnosis that took no selection step (the highway drives: an unmeasured road) printed a table
    header with no row."""
    from types import SimpleNamespace
    from susp_sim_ros.analysis.discrepancy import report
    monkeypatch.setattr(report, "ranking_table", lambda f: [])
    f = SimpleNamespace(path_=[{"step": 0}], windows_=[])
    text = "\n".join(report._md_selection(f, {}, {}, "x"))
    assert "| - | nothing | | | | | | no step was taken: the verdict above says why |" in text


def test_a_term_profiled_out_per_drive_is_not_said_to_have_zero_parameters():
    from susp_sim_ros.analysis.discrepancy.candidates import BY_NAME
    from susp_sim_ros.analysis.discrepancy.report import statement
    bias, lag = BY_NAME["sensor_bias"], BY_NAME["time_offset"]
    assert bias.n_params == 0 and "parameter(s)" not in statement(bias, {}, {}, None)
    assert f"; {lag.n_params} parameter(s)" in statement(lag, {}, {}, None)


def test_held_out_table_says_which_values_were_calibrated_on_the_left_out_drive():
    """A fold's "after" includes the values calibrated on the left-out drive (those the other drives cannot
    predict): the per-drive table names them and gives the RMSE with the joint fit's values beside it, so
    a reader sees how much of "held-out" is that calibration."""
    from types import SimpleNamespace
    from susp_sim_ros.analysis.discrepancy import report
    folds = [{"drive": "bump_front_empty", "rmse_before_deg_s": 0.1675, "rmse_after_deg_s": 0.0608,
              "rmse_after_joint_values_deg_s": 0.0633,
              "calibrated_on_drive": {"calibration.damper_measured_empty_front": 0.884}},
             {"drive": "bump_intact", "rmse_before_deg_s": 0.0628, "rmse_after_deg_s": 0.0581,
              "rmse_after_joint_values_deg_s": 0.0581, "calibrated_on_drive": {}}]
    f = SimpleNamespace(heldout_={"folds": folds, "after_joint_values_deg_s": 0.0611},
                        noise_={"units": {"roll_rate": "deg/s"}})
    rep = {"heldout_rmse_by_signal": {"roll_rate": {"before": 0.2, "after": 0.06}},
           "noise_floors": {"roll_rate": 0.05}, "heldout_rmse_before_deg_s": 0.13, "heldout_rmse_after_deg_s": 0.0596}
    text = "\n".join(report._md_heldout(f, rep, {}, "x"))
    assert "| bump_front_empty | 0.1675 | 0.0608 | 0.0633 | damper_measured_empty_front |" in text
    assert "| bump_intact | 0.0628 | 0.0581 | 0.0581 | - |" in text
    assert "| **pooled** | **0.1300** | **0.0596** | 0.0611 | |" in text


def test_the_reason_says_why_a_road_led_force_was_named_as_physics():
    """The verdict's words for an input-led step whose states' reading stood (issue 26, item 5): what the road
    led (without the input's "(an input, not a state)"), the law of the states, the drives the road does not
    reach and the held-out gain there."""
    from susp_sim_ros.analysis.discrepancy.report import input_weighed_words
    words = input_weighed_words({"input_feature": "road_height", "dependences": ["bump_contact"],
                                 "input_silent_drives": ["sine_intact", "sine_rear_empty"],
                                 "input_silent_heldout_gain": 0.624, "added": ["unlisted_force"]})
    assert words.startswith("the force the model lacks follows the road height under the wheel where the drives")
    assert "(bump_contact)" in words and "(sine_intact, sine_rear_empty)" in words and "62 %" in words
    assert "an input, not a state" not in words and words.endswith("physics, not an input")
    # the law as fitted, where the competition of a family's members kept another form than the reading's
    kept = input_weighed_words({"input_feature": "road_height", "dependences": ["bump_contact"],
                                "fitted_dependences": ["deflection_squared"], "input_silent_drives": ["sine_intact"],
                                "input_silent_heldout_gain": 0.3, "added": ["unlisted_force"]})
    assert "(deflection_squared)" in kept and "bump_contact" not in kept
    # no law of the states stable, a spring offered on the axle the road led alone: said so, no first form named
    offered = input_weighed_words({"input_feature": "road_height", "dependences": ["deflection_cubed"],
                                   "spring_offered_on_axle": "rear", "input_silent_drives": ["sine_intact"],
                                   "input_silent_heldout_gain": 0.47, "added": ["unlisted_force"]})
    assert offered.startswith("the force the model lacks follows the road height under the wheel on the rear axle "
                              "only where the drives carry it")
    assert "no law of the states was stable, but a spring of that axle offered to the fit passed every test" in offered
    assert "(deflection_cubed)" not in offered and "47 %" in offered and offered.endswith("physics, not an input")
