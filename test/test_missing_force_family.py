"""The force the base model lacks against the generator family's hidden force (issue 26, "see the missing
force"; ``analysis/discrepancy/missing_force_report.py``).

The truth is the independent simulator (``truth_generators/independent_sim.py``), not the product's model:
``TruthResult.hidden`` is the force of the physics the truth holds and the model lacks, per corner, with
the sign of the suspension force (positive pushes the body up and the wheels down, as the estimate's
``front_N``/``rear_N``). The product's figures are taken as ``susp diagnose`` takes them: a
``DiscrepancyFinder`` fitted on the recording (vehicle ``passat_b8_like``, the finder's default, as
``benchmarks/bench_discrepancy.py`` runs the family's cases; base variant of the form; no forward
selection, no held-out runs), then ``missing_force_report.estimate_drives(..., calibration=True)`` against
its ``calibrated_fit_``. Compared, per axle: the force the *base* model (the vehicle file's values) lacks
at the corners, i.e. what the calibration supplied as corner force (calibrated minus base model's spring,
damper, friction and anti-roll bar force along the calibrated run) plus the estimate against the calibrated
model. Both it and the hidden force are band-passed the same way (``missing_force.band_passed``, 0.5-4 Hz)
on the estimate's grid.

The issue's target, per axle: correlation >= 0.9 and RMS within 20 %. Measured (seed 1; the rear-empty
and the front-empty bump crossing, the drives where each effect shows most; finder fitted on that drive),
correlation / RMS ratio in the band, front axle; rear axle:

- viscous/linear, rear-empty: calibrated estimate -0.06/0.34; 0.29/0.24 -> base-model total 0.96/1.66;
  0.91/1.00 (rear met)
- viscous/linear, front-empty: 0.33/0.20; 0.17/0.22 -> 0.89/0.79; 0.98/1.18 (rear met)
- gas/linear_rate, rear-empty: -0.15/0.05; 0.10/0.02 -> 0.94/0.80; 0.94/0.87 (rear met)
- gas/linear_rate, front-empty: 0.22/0.03; -0.03/0.07 -> 0.44/0.54; 0.55/0.82
- amplitude/peak_saturating_axle, rear-empty: 0.41/0.62; 0.11/0.29 -> -0.42/6.71; -0.22/3.46
- amplitude/peak_saturating_axle, front-empty: 0.08/0.48; 0.48/0.52 -> -0.38/5.53; -0.24/2.29

The calibrated estimate alone meets the target nowhere: the calibration takes up the hidden force where it
lies in the span of a corner value (extra viscous damping in a measured-damper scale, a gas spring's rate in
the wheel rates). The calibration's part gives that back, so the base-model total meets it on three
case/axle pairs; the others are ``xfail(strict=True)`` with their figures and reasons (the target is not
loosened). What limits them: the calibration also moves body-level values (sprung mass, pitch inertia,
by -9 to +6 %) that are no corner force and stay out of the total, and trades them against the wheel rates
and damper scales (the body IMU sees a mass-rate pair mostly as their ratio); the corner side of such a
trade is in the calibration's part, its body side is not. Where the hidden force is small (the amplitude
friction, 7-18 N band RMS) that trade swamps it. For the record (a diagnostic, not in the product): adding
the body side, the inertial force ``-(m_cal - m_file) z'' `` and ``-(Iyy_cal - Iyy_file) theta''`` split
onto the axles, gives 0.95/1.03 (viscous rear-empty front), 0.96/0.64 (viscous front-empty front),
0.98/0.90 (gas rear-empty front), 0.94/0.96 and 0.99/0.96 (gas front-empty), 0.59/0.98 and 0.27/0.49
(amplitude rear-empty).
"""
from __future__ import annotations

import csv

import numpy as np
import pytest

from susp_sim_ros.analysis.discrepancy import DiscrepancyFinder
from susp_sim_ros.analysis.discrepancy import missing_force as mf
from susp_sim_ros.analysis.discrepancy import missing_force_report as mfr
from truth_generators import family

SEED = 1
#: the drives where each effect shows most: the oil-empty dampers unmask the hidden force of their axle
DRIVES = ("bump_rear_empty", "bump_front_empty")
#: development forms with amplitude friction, extra viscous damping and a gas spring (preload and rate)
FORMS = ("amplitude/peak_saturating_axle", "viscous/linear", "gas/linear_rate")
AXLES = ("front_N", "rear_N")
MIN_CORRELATION = 0.9      # issue 26
RMS_TOLERANCE = 0.2        # issue 26: estimate RMS within 20 % of the truth's
_TRADE = ("the calibration moved the sprung mass {m} (not a corner force) with the wheel rates {k} "
          "(a corner force, in the total)")
#: measured (correlation, RMS ratio base-model total / truth) per form, drive and axle where the target is
#: not met, in the band, with a reason
SHORT = {
    ("amplitude/peak_saturating_axle", "bump_rear_empty", "front_N"): (
        (-0.42, 6.71), "hidden extra friction 7 N band RMS; " + _TRADE.format(m="-9.5 %", k="-10 / -11 %")
        + ": the rate and damper-scale side of that trade is 47 N band RMS; the estimate's floor is 16 N"),
    ("amplitude/peak_saturating_axle", "bump_rear_empty", "rear_N"): (
        (-0.22, 3.46), "hidden extra friction 18 N band RMS; " + _TRADE.format(m="-9.5 %", k="-10 / -11 %")
        + ": the rate side of that trade is 61 N band RMS; the estimate's floor is 24 N"),
    ("amplitude/peak_saturating_axle", "bump_front_empty", "front_N"): (
        (-0.38, 5.53), "hidden extra friction 10 N band RMS; " + _TRADE.format(m="-7 %", k="-8 %")
        + ": the rate side of that trade is 52 N band RMS"),
    ("amplitude/peak_saturating_axle", "bump_front_empty", "rear_N"): (
        (-0.24, 2.29), "hidden extra friction 11 N band RMS; " + _TRADE.format(m="-7 %", k="-8 %")
        + ": the rate side of that trade is 22 N band RMS"),
    ("viscous/linear", "bump_rear_empty", "front_N"): (
        (0.96, 1.66), "shape right, size not: the front intact damper scale 1.17 comes with the sprung mass "
        "+6 % (not a corner force); the damper part alone is 1.7x the hidden damping"),
    ("viscous/linear", "bump_front_empty", "front_N"): (
        (0.89, 0.79), "the front oil-empty damper scale 1.27 takes two thirds of the hidden damping; the "
        "estimate adds 11 N band RMS of the rest, at its floor"),
    ("gas/linear_rate", "bump_rear_empty", "front_N"): (
        (0.94, 0.80), "the front wheel rate takes +1770 N/m of the 2500 N/m gas rate, the sprung mass "
        "(-1.6 %, not a corner force) some of the rest: RMS ratio 0.796, just outside 20 %"),
    ("gas/linear_rate", "bump_front_empty", "front_N"): (
        (0.44, 0.54), "the calibration puts the gas rate into the sprung mass (-5.5 %, not a corner force) "
        "rather than the front wheel rate (+560 N/m) and lowers the front oil-empty damper scale (0.81)"),
    ("gas/linear_rate", "bump_front_empty", "rear_N"): (
        (0.55, 0.82), "as the front: the sprung mass (-5.5 %) stands in for most of the gas rate, the rear "
        "wheel rate takes +940 N/m of 2500 and the rear intact damper scale moves to 0.94"),
}


def _fit(form_name: str, drive: str, calibrate: bool = True):
    """The finder fitted on ``drive`` of the form's case, its drive's :class:`~.missing_force_report.DriveForce`
    (with the calibration's part) and the hidden force per axle (n, 2) on the estimate's grid."""
    form = family.FORMS[form_name]
    recording = dict(family.make_case(form, SEED))[drive]
    f = DiscrepancyFinder(variant=form.base, heldout=False, max_steps=0, calibrate=calibrate).fit([recording])
    (c,) = f.cases_
    d = mfr.estimate_drives(f, f.calibrated_fit_, calibration=True)[c.name]
    truth = family.case_truth(form, SEED, drive)
    t = d.est.t + c.t0_ns * 1e-9                        # the estimate's grid on the truth's clock
    h = np.column_stack([np.interp(t, truth.t, truth.hidden[:, i]) for i in range(4)])
    return f, d, np.column_stack([h[:, 0] + h[:, 1], h[:, 2] + h[:, 3]])   # FL+FR, RL+RR


def _figures(d, hidden: np.ndarray) -> dict[str, dict[str, tuple[float, float]]]:
    """(correlation, RMS ratio part / truth) per part (``estimate``: against the calibrated model,
    ``calibration``: the calibration's part, ``base_total``: their sum) and axle, band-passed."""
    dt = float(d.est.t[1] - d.est.t[0])
    b, v = mf.band_passed(hidden, dt), d.est.valid
    out = {}
    for part, x in (("estimate", d.est.force), ("calibration", d.calibration), ("base_total", d.base_total)):
        a = mf.band_passed(x[:, :2], dt)
        out[part] = {ch: (float(np.corrcoef(a[v, j], b[v, j])[0, 1]) if np.std(a[v, j]) > 0 else 0.0,
                          float(np.std(a[v, j]) / np.std(b[v, j]))) for j, ch in enumerate(AXLES)}
    return out


@pytest.fixture(scope="module")
def fitted():
    """One finder fit per case (form, drive, calibration on or off), reused by every test."""
    cache: dict[tuple[str, str, bool], tuple] = {}

    def get(form_name: str, drive: str = DRIVES[0], calibrate: bool = True):
        key = (form_name, drive, calibrate)
        if key not in cache:
            f, d, hidden = _fit(form_name, drive, calibrate)
            cache[key] = (f, d, hidden, _figures(d, hidden))
        return cache[key]
    return get


def _cases():
    for form in FORMS:
        for drive in DRIVES:
            for ch in AXLES:
                short = SHORT.get((form, drive, ch))
                marks: list = []
                if short is not None:
                    (corr, ratio), why = short
                    marks = [pytest.mark.xfail(strict=True, raises=AssertionError,
                                              reason=f"measured correlation {corr:.2f}, RMS ratio {ratio:.2f}: {why}")]
                yield pytest.param(form, drive, ch, marks=marks, id=f"{form}-{drive}-{ch}")


@pytest.mark.parametrize(("form", "drive", "channel"), list(_cases()))
def test_force_the_base_model_lacks_matches_the_hidden_force_in_the_body_mode_band(fitted, form, drive, channel):
    corr, ratio = fitted(form, drive)[3]["base_total"][channel]
    assert corr >= MIN_CORRELATION and abs(ratio - 1.0) <= RMS_TOLERANCE, (corr, ratio)


@pytest.mark.parametrize("form", ["viscous/linear", "gas/linear_rate"])
def test_the_calibration_takes_up_the_hidden_force_and_its_part_gives_it_back(fitted, form):
    """Why the estimate against the calibrated model alone falls short (measured on the rear-empty bump
    crossing: band RMS 2-34 % of the hidden force, correlation -0.15 to 0.29): the calibration has taken the
    viscous damping into the damper scales and the gas rate into the wheel rates. Its part follows the
    hidden force (measured correlation 0.89-0.96) and is most of it."""
    fig = fitted(form)[3]
    for ch in AXLES:
        corr_e, ratio_e = fig["estimate"][ch]
        corr_c, ratio_c = fig["calibration"][ch]
        assert ratio_e <= 0.4, (ch, ratio_e)
        assert corr_c >= 0.85 and ratio_c >= 0.75, (ch, corr_c, ratio_c)


def test_without_calibration_the_estimate_follows_the_hidden_viscous_force(fitted):
    """Not the issue's target: the comparison's own check. With nothing calibrated (the model at the
    vehicle file's values) the rear extra damping of the rear-empty bump crossing is seen with the right
    sign, size and timing (measured: correlation 0.90, RMS ratio 0.99), so the shortfalls above come from
    the calibration and the estimate's floor, not from the grid, the sign convention or the axle sums;
    and with nothing calibrated the calibration's part is zero: the base-model total is the estimate."""
    _, d, _, fig = fitted("viscous/linear", calibrate=False)
    corr, ratio = fig["estimate"]["rear_N"]
    assert corr >= 0.85 and abs(ratio - 1.0) <= RMS_TOLERANCE, (corr, ratio)
    assert d.calibration is not None and not np.any(d.calibration)
    np.testing.assert_array_equal(d.base_total, d.est.force)


def test_the_calibrations_part_is_written_beside_the_missing_force(fitted, tmp_path):
    """CSV (the interface's seven columns first, then the parts), JSON ``per_drive`` keys and the loop
    plot; the re-evaluated calibrated force reproduces the kernel's own along the run."""
    f, d, _, _ = fitted("viscous/linear")
    out = mfr.write(f, tmp_path, "case", plots=True)
    (name,) = out["per_drive"]
    entry = out["per_drive"][name]
    assert entry["calibration"]["check_N"] < 1e-6
    for part in ("calibration", "base_model"):
        assert set(mf.CHANNELS) <= set(entry[part])
    assert entry["base_model"]["rear_N"]["loop_half_height_N"] is not None
    for key in ("front_N", "rear_N", "roll_Nm", "intensity_N2_s", "unmeasured_input"):  # the existing keys
        assert key in entry
    (path,) = [p for p in out["files"] if p.endswith(".csv")]
    rows = list(csv.reader(open(path)))
    head = rows[0]
    assert head[:7] == ["t", "front_N", "front_sd_N", "rear_N", "rear_sd_N", "roll_Nm", "roll_sd_Nm"]
    assert head[-6:] == ["front_calibration_N", "rear_calibration_N", "roll_calibration_Nm",
                         "front_base_N", "rear_base_N", "roll_base_Nm"]
    x = np.array(rows[1:], float)
    col = {h: x[:, k] for k, h in enumerate(head)}
    for ch, unit in (("front", "N"), ("rear", "N"), ("roll", "Nm")):
        np.testing.assert_allclose(col[f"{ch}_base_{unit}"], col[f"{ch}_{unit}"] + col[f"{ch}_calibration_{unit}"],
                                   rtol=1e-4, atol=1e-3 * max(1.0, float(np.abs(col[f"{ch}_base_{unit}"]).max())))
    assert any(p.endswith(".png") for p in out["files"])
