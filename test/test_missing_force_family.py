"""The force the base model lacks against the generator family's hidden force (issue 26, "see the missing
force"; ``analysis/discrepancy/missing_force_report.py``).

The truth is the independent simulator (``truth_generators/independent_sim.py``), not the product's model:
``TruthResult.hidden`` is the force of the physics the truth holds and the model lacks, per corner, with
the sign of the suspension force (positive pushes the body up and the wheels down, as the estimate's
``front_N``/``rear_N``). The product's figures are taken as ``susp diagnose`` takes them: a
``DiscrepancyFinder`` fitted on the recording (vehicle ``passat_b8_like``, the finder's default, as
``benchmarks/bench_discrepancy.py`` runs the family's cases; base variant of the form; no forward
selection, no held-out runs), then ``missing_force_report.estimate_drives(..., calibration=True)`` against
its ``calibrated_fit_``. Compared, per axle: the force the *base* model (the vehicle file's values) lacks,
i.e. three parts: what the calibration supplied as corner force (calibrated minus base model's spring,
damper, friction and anti-roll bar force along the calibrated run), the calibration's body part (the
inertial force of the calibrated sprung-mass and inertia change, ``-(m_cal - m_file) z''`` and
``-(Iyy_cal - Iyy_file) theta''`` along the calibrated run, split onto the axles by statics) and the
estimate against the calibrated model. Both it and the hidden force are band-passed the same way
(``missing_force.band_passed``, 0.5-4 Hz) on the estimate's grid.

The issue's target, per axle: correlation >= 0.9 and RMS within 20 %. Measured (seed 1; the rear-empty
and the front-empty bump crossing, the drives where each effect shows most; finder fitted on that drive),
correlation / RMS ratio in the band, front axle; rear axle: the calibrated estimate alone; corner part plus
estimate (without the body part, as before it was added) -> the three-part total:

- viscous/linear, rear-empty: -0.06/0.34; 0.29/0.24 | 0.96/1.66; 0.91/1.00 -> 0.95/1.04; 0.98/0.80
  (both met; the rear's ratio 0.803 is 0.003 inside the target: it was 1.00 without the body part)
- viscous/linear, front-empty: 0.33/0.20; 0.17/0.22 | 0.89/0.79; 0.98/1.18 -> 0.96/0.64; 0.98/0.95 (rear met)
- gas/linear_rate, rear-empty: -0.15/0.05; 0.10/0.02 | 0.94/0.80; 0.94/0.87 -> 0.98/0.90; 0.96/0.99 (both met)
- gas/linear_rate, front-empty: 0.22/0.03; -0.03/0.07 | 0.44/0.54; 0.55/0.82 -> 0.94/0.95; 0.98/0.96 (both met)
- amplitude/peak_saturating_axle, rear-empty: 0.41/0.62; 0.11/0.29 | -0.42/6.71; -0.22/3.46 -> 0.57/0.99;
  0.23/0.52
- amplitude/peak_saturating_axle, front-empty: 0.08/0.48; 0.48/0.52 | -0.38/5.53; -0.24/2.29 -> -0.54/1.25;
  0.79/0.88

The calibrated estimate alone meets the target nowhere: the calibration takes up the hidden force where it
lies in the span of its values (extra viscous damping in a measured-damper scale, a gas spring's rate in the
wheel rates, and some of either in the sprung mass and pitch inertia, which the body IMU sees mostly through
their ratio to the rates). The corner and body parts give that back, so the total meets the target on seven
of the twelve case/axle pairs (three with the corner part alone; none lost). The others are
``xfail(strict=True)`` with their figures and reasons (the target is not loosened).

What limits them (measured 2026-12-07, ``benchmarks/bench_missing_force.py --family``): the force the base
model lacks is not the hidden force alone. The forms' **structure twin** (``family.structure_twin``:
``structure/nominal``, the same car, friction, integrator, gyro biases and noise, the physics off) has an
oil-empty damper weaker than the vehicle file's (its calibration reads the oil-empty scale 0.88 at the rear,
0.83 at the front), so on each drive's oil-empty axle the base model lacks a force against the motion:
0.94 x the amplitude friction's band RMS at the rear of the rear-empty crossing, 2.1 x at the front of the
front-empty one, correlated -0.90 / -0.84 with it. On the amplitude form the two cancel (the truth's oil-empty
axle, weaker damper plus extra friction, is about the file's), so what the base model lacks there is not the
hidden friction, and an exact estimate of it could not meet the target either; on the viscous front-empty front
axle it takes a third of the size (RMS ratio 0.65). Paired with the twin (the case's force minus the twin's,
:func:`test_paired_with_its_structure_twin_the_estimate_reads_the_hidden_force`) the estimate reads the hidden
force on nine of the twelve pairs, every viscous and gas pair among them.
"""
from __future__ import annotations

import csv

import numpy as np
import pytest

from benchmarks import bench_missing_force as BMF
from susp_sim_ros.analysis.discrepancy import missing_force as mf
from susp_sim_ros.analysis.discrepancy import missing_force_report as mfr
from truth_generators import family

SEED = 1
DRIVES = BMF.FAMILY_DRIVES
FORMS = BMF.FAMILY_FORMS
AXLES = BMF.AXLES
AMPLITUDE = "amplitude/peak_saturating_axle"
#: the structure twin of every form of FORMS (``family.structure_twin``)
TWIN = "structure/nominal"
#: the oil-empty axle of each drive
EMPTY_AXLE = {"bump_rear_empty": "rear_N", "bump_front_empty": "front_N"}
_TWIN_WHY = ("the structure twin's oil-empty damper is weaker than the file's: on this axle the base model lacks "
             "{x} x the hidden force's band RMS against the motion, correlation {c} with it")
#: measured (correlation, RMS ratio base-model total / truth) per form, drive and axle where the target is
#: not met, in the band, with a reason (2026-12-07, bench_missing_force.py --family)
SHORT = {
    (AMPLITUDE, "bump_rear_empty", "front_N"): (
        (0.65, 1.01), "hidden extra friction 7 N band RMS, the size of the estimate's floor; the twin leaves as much "
        "uncorrelated with it (1.03 x, correlation -0.07)"),
    (AMPLITUDE, "bump_rear_empty", "rear_N"): (
        (0.28, 0.48), "hidden extra friction 18 N band RMS; " + _TWIN_WHY.format(x="0.94", c="-0.90")
        + ": the two cancel"),
    (AMPLITUDE, "bump_front_empty", "front_N"): (
        (-0.52, 1.04), "hidden extra friction 10 N band RMS; " + _TWIN_WHY.format(x="2.10", c="-0.84")
        + ": what the base model lacks is against the friction"),
    (AMPLITUDE, "bump_front_empty", "rear_N"): (
        (0.80, 1.04), "hidden extra friction 11 N band RMS: size right, correlation short; the twin leaves 0.38 x "
        "(correlation -0.12)"),
    ("viscous/linear", "bump_front_empty", "front_N"): (
        (0.96, 0.65), "shape right, size short: " + _TWIN_WHY.format(x="0.37", c="-0.86")
        + " (paired with the twin 0.95 / 1.00)"),
}
#: measured (correlation, RMS ratio of the case's force minus its twin's / truth) where the paired reading
#: falls short, with a reason
PAIRED_SHORT = {
    (AMPLITUDE, "bump_rear_empty", "front_N"): (
        (0.62, 1.18), "7 N band RMS of hidden friction against an estimate's sd of 18-20 N"),
    (AMPLITUDE, "bump_front_empty", "front_N"): (
        (0.92, 1.34), "the case's calibration trades more than the twin's (sprung mass -9 % against -4 %, the "
        "wheel rates -10 % against -5 %): the pair is not the hidden force alone"),
    (AMPLITUDE, "bump_front_empty", "rear_N"): (
        (0.86, 1.02), "the same calibration trade, on the axle with the intact dampers"),
}


@pytest.fixture(scope="module")
def fitted():
    """One finder fit per case (form, drive, calibration on or off), reused by every test: the finder, the
    drive's force, the hidden force per axle, the band figures and the
    :class:`~benchmarks.bench_missing_force.FamilyFit`."""
    cache: dict[tuple[str, str, bool], tuple] = {}

    def get(form_name: str, drive: str = DRIVES[0], calibrate: bool = True):
        key = (form_name, drive, calibrate)
        if key not in cache:
            fit = BMF.family_fit(family.FORMS[form_name], drive, SEED, calibrate)
            figures = BMF.band_figures(fit) if np.any(fit.hidden) else None   # a structure twin hides nothing
            cache[key] = (fit.finder, fit.force, fit.hidden, figures, fit)
        return cache[key]
    return get


def _cases(short_of: dict):
    """Every (form, drive, axle), those in ``short_of`` xfail (strict) with their measured figures and reason."""
    for form in FORMS:
        for drive in DRIVES:
            for ch in AXLES:
                short = short_of.get((form, drive, ch))
                marks: list = []
                if short is not None:
                    (corr, ratio), why = short
                    marks = [pytest.mark.xfail(strict=True, raises=AssertionError,
                                              reason=f"measured correlation {corr:.2f}, RMS ratio {ratio:.2f}: {why}")]
                yield pytest.param(form, drive, ch, marks=marks, id=f"{form}-{drive}-{ch}")


@pytest.mark.parametrize(("form", "drive", "channel"), list(_cases(SHORT)))
def test_force_the_base_model_lacks_matches_the_hidden_force_in_the_body_mode_band(fitted, form, drive, channel):
    corr, ratio = fitted(form, drive)[3]["base_total"][channel]
    assert BMF.met(corr, ratio), (corr, ratio)


@pytest.mark.parametrize(("form", "drive", "channel"), list(_cases(PAIRED_SHORT)))
def test_paired_with_its_structure_twin_the_estimate_reads_the_hidden_force(fitted, form, drive, channel):
    """Not the issue's target (above, unchanged): what the hidden physics adds to the force the base model lacks,
    the case's minus its structure twin's (the same car, biases and noise, the physics off), meets the issue's
    figures, so the shortfalls above are the twin's force, not the estimate's reading of the physics."""
    assert family.structure_twin(family.FORMS[form]).name == TWIN
    p = BMF.paired_figures(fitted(form, drive)[4], fitted(TWIN, drive)[4])[channel]
    assert BMF.met(p["corr"], p["rms_ratio"]), p


def test_the_structure_twin_lacks_a_force_against_the_motion_on_the_oil_empty_axle(fitted):
    """Why the amplitude pairs miss the target: with the physics off, the generator's oil-empty damper is weaker
    than the vehicle file's (the twin's calibration reads its scale below 0.9: measured 0.88 rear, 0.83 front),
    so on the oil-empty axle the base model lacks a force against the motion, anti-correlated with the amplitude
    form's hidden friction (measured -0.90 / -0.84) and at least 0.8 x its band RMS (0.94 / 2.10)."""
    for drive, ch in EMPTY_AXLE.items():
        twin = fitted(TWIN, drive)[4]
        p = BMF.paired_figures(fitted(AMPLITUDE, drive)[4], twin)[ch]
        assert p["twin_corr_with_hidden"] <= -0.8 and p["twin_rms_over_hidden"] >= 0.8, (drive, p)
        (scale,) = [e["value"] for e in twin.finder.report()["calibration"]
                    if e["param"] == "damper_measured_empty" and e["where"] == ch.split("_")[0]]
        assert scale < 0.9, (drive, scale)


#: (form, axle) whose calibration corner part falls short of the mechanism test below, measured, with why
CORNER_PART_SHORT = {
    ("viscous/linear", "rear_N"): "measured correlation 0.835, RMS ratio 1.08 on 2026-11-28 and 2026-11-29 (0.888 / "
    "0.945 with the unsprung masses held at the file's values): the rear unsprung mass (+3 %) and wheel rate "
    "(+1.3 %) share the hidden damping with the damper scale, and the wheel's inertia is neither a corner nor a "
    "body part of the decomposition; the base-model total is unchanged (0.976 / 0.806, was 0.979 / 0.803)"}


@pytest.mark.parametrize(("form", "channel"), [
    pytest.param(form, ch, id=f"{form}-{ch}", marks=[pytest.mark.xfail(strict=True, raises=AssertionError,
                                                                       reason=CORNER_PART_SHORT[(form, ch)])]
                 if (form, ch) in CORNER_PART_SHORT else [])
    for form in ("viscous/linear", "gas/linear_rate") for ch in AXLES])
def test_the_calibration_takes_up_the_hidden_force_and_its_part_gives_it_back(fitted, form, channel):
    """Why the estimate against the calibrated model alone falls short (measured on the rear-empty bump
    crossing: band RMS 2-35 % of the hidden force, correlation -0.14 to 0.27): the calibration has taken the
    viscous damping into the damper scales and the gas rate into the wheel rates. Its part follows the
    hidden force (measured correlation 0.95-0.98, one short: :data:`CORNER_PART_SHORT`) and is most of it."""
    fig = fitted(form)[3]
    corr_e, ratio_e = fig["estimate"][channel]
    corr_c, ratio_c = fig["calibration"][channel]
    assert ratio_e <= 0.4, ratio_e
    assert corr_c >= 0.85 and ratio_c >= 0.75, (corr_c, ratio_c)


def test_the_body_part_gives_back_what_the_calibration_put_in_the_sprung_mass(fitted):
    """The gas spring of the front-empty bump crossing: the calibration takes its rate mostly into the sprung
    mass and pitch inertia (-5.5 / -5.2 %) rather than the wheel rates, so the corner part alone follows the
    hidden force poorly (measured correlation 0.43 / 0.56, RMS ratio 0.54 / 0.83, front / rear); the body
    part, the inertial force of that mass and inertia change, follows it (measured 0.97 / 0.64 correlation,
    RMS ratio 0.67 / 0.77) and with it the total meets the target on both axles (the parametrised test)."""
    fig = fitted("gas/linear_rate", "bump_front_empty")[3]
    assert fig["calibration"]["front_N"][0] < 0.6, fig["calibration"]
    corr, ratio = fig["body"]["front_N"]
    assert corr >= 0.9 and ratio >= 0.5, (corr, ratio)
    assert fig["body"]["rear_N"][0] >= 0.5, fig["body"]


def test_without_calibration_the_estimate_follows_the_hidden_viscous_force(fitted):
    """Not the issue's target: the comparison's own check. With nothing calibrated (the model at the
    vehicle file's values) the rear extra damping of the rear-empty bump crossing is seen with the right
    sign, size and timing (measured: correlation 0.90, RMS ratio 0.99), so the shortfalls above come from
    the calibration and the estimate's floor, not from the grid, the sign convention or the axle sums;
    and with nothing calibrated the calibration's corner and body parts are zero: the base-model total is
    the estimate."""
    _, d, _, fig, _ = fitted("viscous/linear", calibrate=False)
    corr, ratio = fig["estimate"]["rear_N"]
    assert corr >= 0.85 and abs(ratio - 1.0) <= BMF.TARGETS["band_rms_ratio_within"], (corr, ratio)
    assert d.calibration is not None and not np.any(d.calibration)
    assert d.body is not None and not np.any(d.body)
    np.testing.assert_array_equal(d.base_total, d.est.force)


def test_the_calibrations_part_is_written_beside_the_missing_force(fitted, tmp_path):
    """CSV (the interface's seven columns first, then the parts), JSON ``per_drive`` keys and the loop
    plot; the re-evaluated calibrated force reproduces the kernel's own along the run; the base-model total
    is the corner part, the body part and the estimate."""
    f, d, _, _, _ = fitted("viscous/linear")
    out = mfr.write(f, tmp_path, "case", plots=True)
    (name,) = out["per_drive"]
    entry = out["per_drive"][name]
    assert entry["calibration"]["check_N"] < 1e-6
    for part in ("calibration", "calibration_body", "base_model"):
        assert set(mf.CHANNELS) <= set(entry[part])
    assert entry["base_model"]["rear_N"]["loop_half_height_N"] is not None
    for key in ("front_N", "rear_N", "roll_Nm", "intensity_N2_s", "unmeasured_input"):  # the existing keys
        assert key in entry
    (path,) = [p for p in out["files"] if p.endswith(".csv")]
    rows = list(csv.reader(open(path)))
    head = rows[0]
    assert head[:7] == ["t", "front_N", "front_sd_N", "rear_N", "rear_sd_N", "roll_Nm", "roll_sd_Nm"]
    assert head[-9:] == ["front_calibration_N", "rear_calibration_N", "roll_calibration_Nm",
                         "front_base_N", "rear_base_N", "roll_base_Nm", "front_body_N", "rear_body_N", "roll_body_Nm"]
    x = np.array(rows[1:], float)
    col = {h: x[:, k] for k, h in enumerate(head)}
    for ch, unit in (("front", "N"), ("rear", "N"), ("roll", "Nm")):
        parts = col[f"{ch}_{unit}"] + col[f"{ch}_calibration_{unit}"] + col[f"{ch}_body_{unit}"]
        np.testing.assert_allclose(col[f"{ch}_base_{unit}"], parts,
                                   rtol=1e-4, atol=1e-3 * max(1.0, float(np.abs(col[f"{ch}_base_{unit}"]).max())))
    assert any(p.endswith(".png") for p in out["files"])
