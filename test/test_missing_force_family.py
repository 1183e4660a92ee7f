"""The estimated missing force against the generator family's hidden force (issue 26, "see the missing
force"; ``analysis/discrepancy/missing_force_report.py``).

The truth is the independent simulator (``truth_generators/independent_sim.py``), not the product's model:
``TruthResult.hidden`` is the force of the physics the truth holds and the model lacks, per corner, with
the sign of the suspension force (positive pushes the body up and the wheels down, as the estimate's
``front_N``/``rear_N``). The product's estimate is taken as ``susp diagnose`` takes it: a
``DiscrepancyFinder`` fitted on the recording (vehicle ``passat_b8_like``, the finder's default, as
``benchmarks/bench_discrepancy.py`` runs the family's cases; base variant of the form; no forward
selection, no held-out runs), then ``missing_force_report.estimate_drives`` against its
``calibrated_fit_``. Both are band-passed the same way (``missing_force.band_passed``, 0.5-4 Hz) on the
estimate's grid.

The issue's target, per axle: correlation >= 0.9 and RMS within 20 %. Measured (seed 1, the rear-empty
bump crossing, the drive where each effect shows most; finder fitted on that drive) it is met on no case:
the failing cases are ``xfail(strict=True)`` with their figures, the target itself is not loosened. What
limits it (see the reasons): the calibration takes up every hidden force that lies in the span of a
calibration value (extra viscous damping in the measured-damper scales, a gas spring's rate in the wheel
rates, its preload a constant the IMU cannot see), and the amplitude friction's extra level is below the
estimate's floor on one drive. The check without calibration shows the comparison itself (grid, sign,
band, axle sums) is right: there the estimate follows the viscous force.
"""
from __future__ import annotations

import numpy as np
import pytest

from susp_sim_ros.analysis.discrepancy import DiscrepancyFinder
from susp_sim_ros.analysis.discrepancy import missing_force as mf
from susp_sim_ros.analysis.discrepancy import missing_force_report as mfr
from truth_generators import family

SEED = 1
DRIVE = "bump_rear_empty"
#: development forms with amplitude friction, extra viscous damping and a gas spring (preload and rate)
FORMS = ("amplitude/peak_saturating_axle", "viscous/linear", "gas/linear_rate")
AXLES = ("front_N", "rear_N")
MIN_CORRELATION = 0.9      # issue 26
RMS_TOLERANCE = 0.2        # issue 26: estimate RMS within 20 % of the truth's
#: measured (correlation, RMS estimate / truth) per form and axle, in the band, with the calibration;
#: a reason per case the target is not met
SHORT = {
    ("amplitude/peak_saturating_axle", "front_N"): ((0.41, 0.62), "front extra 12 N: band RMS 7 N, below the "
                                                   "estimate's floor (16 N band RMS with nothing hidden, sd 52 N); "
                                                   "the calibration moves masses, rates and damper scales ~10 %"),
    ("amplitude/peak_saturating_axle", "rear_N"): ((0.11, 0.29), "rear extra 22 N: band RMS 18 N, at the "
                                                  "estimate's floor (24 N band RMS with nothing hidden, sd 44 N); "
                                                  "the calibration moves masses, rates and damper scales ~10 %"),
    ("viscous/linear", "front_N"): ((-0.06, 0.34), "the calibration takes the extra damping into the front "
                                    "measured-damper scale (1.17)"),
    ("viscous/linear", "rear_N"): ((0.29, 0.24), "the calibration takes the extra damping into the rear oil-empty "
                                   "measured-damper scale (1.61)"),
    ("gas/linear_rate", "front_N"): ((-0.15, 0.05), "the calibration takes the gas rate (2500 N/m) into the "
                                     "wheel rate (+1770 N/m); the preload is a constant the IMU cannot see"),
    ("gas/linear_rate", "rear_N"): ((0.10, 0.02), "the calibration takes the gas rate (2500 N/m) into the "
                                    "wheel rate (+2030 N/m); the preload is a constant the IMU cannot see"),
}


def _figures(form_name: str, calibrate: bool = True) -> dict[str, tuple[float, float]]:
    """(correlation, RMS ratio estimate / truth) per axle of the band-passed estimate and hidden force."""
    form = family.FORMS[form_name]
    drive = dict(family.make_case(form, SEED))[DRIVE]
    f = DiscrepancyFinder(variant=form.base, heldout=False, max_steps=0, calibrate=calibrate).fit([drive])
    (c,) = f.cases_
    est = mfr.estimate_drives(f, f.calibrated_fit_)[c.name].est
    truth = family.case_truth(form, SEED, DRIVE)
    t = est.t + c.t0_ns * 1e-9                          # the estimate's grid on the truth's clock
    h = np.column_stack([np.interp(t, truth.t, truth.hidden[:, i]) for i in range(4)])
    axle = np.column_stack([h[:, 0] + h[:, 1], h[:, 2] + h[:, 3]])   # FL+FR, RL+RR
    dt = float(est.t[1] - est.t[0])
    a, b = mf.band_passed(est.force[:, :2], dt), mf.band_passed(axle, dt)
    v = est.valid
    return {ch: (float(np.corrcoef(a[v, j], b[v, j])[0, 1]), float(np.std(a[v, j]) / np.std(b[v, j])))
            for j, ch in enumerate(AXLES)}


@pytest.fixture(scope="module")
def figures():
    """One finder fit per case (form, calibration on or off), reused by every axle's test."""
    cache: dict[tuple[str, bool], dict[str, tuple[float, float]]] = {}

    def get(form_name: str, calibrate: bool = True):
        key = (form_name, calibrate)
        if key not in cache:
            cache[key] = _figures(form_name, calibrate)
        return cache[key]
    return get


def _cases():
    for form in FORMS:
        for ch in AXLES:
            short = SHORT.get((form, ch))
            marks: list = []
            if short is not None:
                (corr, ratio), why = short
                marks = [pytest.mark.xfail(strict=True, raises=AssertionError,
                                          reason=f"measured correlation {corr:.2f}, RMS ratio {ratio:.2f}: {why}")]
            yield pytest.param(form, ch, marks=marks, id=f"{form}-{ch}")


@pytest.mark.parametrize(("form", "channel"), list(_cases()))
def test_missing_force_matches_the_hidden_force_in_the_body_mode_band(figures, form, channel):
    corr, ratio = figures(form)[channel]
    assert corr >= MIN_CORRELATION and abs(ratio - 1.0) <= RMS_TOLERANCE, (corr, ratio)


def test_without_calibration_the_estimate_follows_the_hidden_viscous_force(figures):
    """Not the issue's target: the comparison's own check. With nothing calibrated (the model at the
    vehicle file's values) the rear extra damping of the rear-empty bump crossing is seen with the right
    sign, size and timing (measured: correlation 0.90, RMS ratio 0.99), so the shortfalls above come from
    the calibration and the estimate's floor, not from the grid, the sign convention or the axle sums."""
    corr, ratio = figures("viscous/linear", calibrate=False)["rear_N"]
    assert corr >= 0.85 and abs(ratio - 1.0) <= RMS_TOLERANCE, (corr, ratio)
