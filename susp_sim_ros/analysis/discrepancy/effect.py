"""A named term's effect as a whole, with its 95 % interval (issue 24, item 3).

A term's parameters can each hold their neutral value inside their marginal 95 % interval while the term's
effect on the drives is far from nothing: the front and rear coefficients of a viscous term trade against
each other and against the calibrated damper factors, so each alone is loose, but the force they add
together along the drives is pinned. What decides whether a term is a finding is that force, not one
coefficient. So the effect is measured where it acts, on the whitened residuals:

- ``e = r(x with the term at neutral) - r(x)``: what the fitted term changes in the drives (one
  simulation; whitened, debiased like the fit's residual);
- its size along its own shape: ``s(theta) = u . (r(theta_T = neutral) - r(theta))`` with
  ``u = e / |e|``, so ``s(x) = |e|``; linearised in the term's parameters, ``ds = -u . J_T d theta_T``
  (``J_T``: the fit's Jacobian columns of the term);
- its variance from the posterior covariance of the term's parameters (data at their effective size
  plus the calibration's priors, so the trade with the calibrated values is in it) or from the
  leave-one-drive-out refits (jackknife), whichever is larger, with the values the calibration holds at
  their file value entering in one of three ways: not at all (:data:`DATA`), free within their priors
  with the data narrowing them (:data:`HELD_FREE`, marginalised: :func:`covariance_held_free`), or kept at
  the file value while the car's may lie anywhere in the prior (:data:`HELD_AT_FILE`, the consider
  covariance of the parameters' intervals, :meth:`~.finder.DiscrepancyFinder.ci95_`).

The interval is stated as a fraction of the fitted effect, ``1 +- 1.96 sd / |e|``: 1 is the term as
fitted, 0 is no effect. The finder (``_judge_physics_terms``) drops a term whose interval from the data
alone holds 0, and drops and lists as competing with the held values one whose interval holds 0 once they
are free within their priors: whether the drives still need the term when those values may be anywhere
the vehicle file allows, the data narrowing them, is the naming question (the consider interval answers
another: how far the estimate is off when a held value is wrong and nobody re-estimates it). Linearising
the effect in the term's parameters is exact for a term whose parameters are gains (viscous coefficient,
extra friction level, gas force and rate) and a first-order statement for its shape parameters.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

Z95 = 1.96  # two-sided 95 % normal quantile


#: how the values the calibration holds at their file value enter an effect's interval
DATA = "data"                  # not at all: the posterior (data and calibration priors) and the jackknife
HELD_FREE = "held_free"        # free within their priors, the data narrowing them (marginalised): naming
HELD_AT_FILE = "held_at_file"  # at their file value while the car's may be anywhere in their priors (consider)


@dataclass(frozen=True)
class TermEffect:
    """A term's effect along its fitted shape. ``size``: ``|e|`` [whitened residual units: sqrt of the
    sum of squares, 1 per sample for noise]; the effect's standard deviation (same units; NaN where not
    available) from the posterior (``sd_data``), with the held values free within their priors
    (``sd_held_free``, includes the posterior's), from the held values kept at their file value
    (``sd_consider``, adds to the posterior's) and from the leave-one-drive-out refits (``sd_jackknife``)."""

    size: float
    sd_data: float
    sd_consider: float
    sd_jackknife: float
    sd_held_free: float = math.nan
    #: per held value, the effect's variance it brings when held at its file value (whitened units^2):
    #: which held values could stand in for the term
    held_share: tuple[float, ...] = ()

    def sd(self, held: str = HELD_FREE) -> float:
        """The effect's standard deviation with the held values entering as ``held`` (:data:`DATA`,
        :data:`HELD_FREE`, :data:`HELD_AT_FILE`), or the jackknife's where that is larger."""
        if held == HELD_FREE and math.isfinite(self.sd_held_free):
            s = self.sd_held_free
        elif held == HELD_AT_FILE and math.isfinite(self.sd_consider):
            s = math.hypot(self.sd_data, self.sd_consider)
        else:
            s = self.sd_data
        return max(s, self.sd_jackknife if math.isfinite(self.sd_jackknife) else 0.0)

    def ci95_fraction(self, held: str = HELD_FREE) -> tuple[float, float]:
        """95 % interval of the effect as a fraction of the fitted one (1: as fitted, 0: no effect)."""
        if self.size <= 0.0:
            return (0.0, 0.0)
        half = Z95 * self.sd(held) / self.size
        return (1.0 - half, 1.0 + half)

    def holds_zero(self, held: str = HELD_FREE) -> bool:
        """Whether the 95 % interval holds "no effect" (also when it is not a number: a failed simulation
        is no evidence of an effect)."""
        return not self.ci95_fraction(held)[0] > 0.0

    def as_json(self) -> dict:
        return {"size_whitened": self.size,
                "ci95_fraction": list(self.ci95_fraction(HELD_FREE)),
                "ci95_fraction_data": list(self.ci95_fraction(DATA)),
                "ci95_fraction_held_at_file_value": list(self.ci95_fraction(HELD_AT_FILE)),
                "sd_whitened": {"posterior": self.sd_data, "held_values_free": _finite_or_none(self.sd_held_free),
                                "held_values_at_file_value": _finite_or_none(self.sd_consider),
                                "leave_one_drive_out": _finite_or_none(self.sd_jackknife)}}


def _finite_or_none(v: float) -> float | None:
    return float(v) if math.isfinite(v) else None


def term_effect(e: np.ndarray, J_term: np.ndarray, cov_term: np.ndarray, consider_term: np.ndarray | None,
                jackknife_term: np.ndarray | None, x_term: np.ndarray,
                cov_held_free: np.ndarray | None = None) -> TermEffect:
    """The effect of one term (module docstring). ``e``: the whitened residual with the term at neutral
    minus the fitted one (n_res,); ``J_term``: the fit's Jacobian columns of the term's parameters
    (n_res, k); ``cov_term``: their posterior covariance (k, k); ``consider_term``: their sensitivity to
    the held values times those values' sds (k, m) or None; ``jackknife_term``: the term's parameters in
    the leave-one-drive-out refits (R, k) or None (fewer than three refits: no jackknife); ``x_term``:
    the fitted values (k,)."""
    size = float(np.linalg.norm(e))
    if size <= 0.0 or J_term.shape[1] == 0:
        return TermEffect(size, math.inf if size > 0 else 0.0, math.nan, math.nan)
    g = -(e / size) @ J_term  # d s / d theta_T
    cov = np.where(np.isfinite(cov_term), cov_term, 0.0)
    if not np.all(np.isfinite(cov_term[np.ix_(g != 0, g != 0)])):
        return TermEffect(size, math.inf, math.nan, math.nan)  # a parameter the data do not inform at all
    sd_data = math.sqrt(max(float(g @ cov @ g), 0.0))
    sd_cons = math.nan
    share: tuple[float, ...] = ()
    if consider_term is not None and consider_term.size:
        per = (g @ consider_term) ** 2
        sd_cons, share = math.sqrt(float(per.sum())), tuple(float(v) for v in per)
    sd_jk = math.nan
    if jackknife_term is not None and len(jackknife_term) >= 3:
        s = (np.asarray(jackknife_term) - x_term) @ g
        R = len(s)
        sd_jk = math.sqrt((R - 1) / R * float(np.sum((s - s.mean()) ** 2)))
    sd_free = math.nan
    if cov_held_free is not None:
        sd_free = math.sqrt(max(float(g @ cov_held_free @ g), 0.0))
    return TermEffect(size, sd_data, sd_cons, sd_jk, sd_free, share)


def covariance_held_free(H: np.ndarray, J: np.ndarray, J_held: np.ndarray, sd_held: np.ndarray,
                         weight: float) -> np.ndarray:
    """Posterior covariance of the estimated parameters with the held values free within their priors
    (marginalised, so the data may narrow them, unlike the consider covariance): the inverse of the
    estimated parameters' information with the held values profiled out, the Schur complement
    ``H - H_eh H_hh^-1 H_he`` with ``H_eh = w J' J_h`` and ``H_hh = w J_h' J_h + diag(sd_held^-2)``.
    ``H``: the estimated parameters' posterior information (data and priors); ``J``, ``J_held``: the
    whitened residual's Jacobians; ``weight``: the data's information per sample. ``H_hh`` is inverted in
    the held values' prior units (``I + w sd J_h' J_h sd``, never singular)."""
    k = H.shape[0]
    if J_held.size == 0 or k == 0:
        return np.linalg.pinv(H)
    sd = np.asarray(sd_held, float)
    Heh = weight * (J.T @ J_held) * sd[None, :]          # in the held values' prior units
    Hs = weight * (J_held * sd[None, :]).T @ (J_held * sd[None, :]) + np.eye(len(sd))
    return np.linalg.pinv(H - Heh @ np.linalg.solve(Hs, Heh.T))
