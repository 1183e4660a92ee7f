"""Fitting: nonlinear least squares over batch simulations, linearised screening, forward selection.

- :func:`fit_structure`: scipy ``least_squares`` (trust-region reflective, bounds) on the stacked
  residuals of all drives; the Jacobian by forward differences, all columns in ONE parallel batch.
- :func:`screen`: at the current model, one batch Jacobian over every remaining candidate's parameters;
  each single candidate and each pair is scored by its linearised (Gauss-Newton) fit: predicted residual
  sum of squares, information criterion and a linearised leave-one-drive-out error. The best few are
  refitted nonlinearly.
- Information criterion: BIC on an effective sample count ``n / BLOCK`` (model errors are smooth, so
  neighbouring samples at 200 Hz are not independent; one independent sample per 50 ms), ``k ln n_eff``
  penalising parameters.
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
from scipy.optimize import least_squares

from .engine import Evaluator, Structure

BLOCK = 10


def debias(ev: Evaluator, vec: np.ndarray, idx: Sequence[int]) -> np.ndarray:
    """Subtract, per drive and signal, the mean over the quiet lead-in (the sensor-bias estimate) from
    stacked residual vectors or Jacobian columns ``vec`` (n_res,) or (n_res, m)."""
    out = np.array(vec, float, copy=True)
    o = 0
    for r in idx:
        c = ev.cases[r]
        n, s = c.y_meas.shape
        blk = out[o:o + n * s].reshape((n, s) + out.shape[1:])
        if c.quiet is not None and c.quiet.sum() >= 5:
            blk -= blk[c.quiet].mean(axis=0, keepdims=True)
        o += n * s
    return out


def raw_residuals(ev: Evaluator, st: Structure, X: np.ndarray, idx: Sequence[int]) -> np.ndarray:
    rates = ev.simulate(st, X, idx)
    out = []
    for m, x in enumerate(np.atleast_2d(X)):
        lag = st.lag(x)
        out.append(np.concatenate([ev.case_residual(r, rates[m, j], lag, False).ravel()
                                   for j, r in enumerate(idx)]))
    return np.array(out)


def n_params_bic(ev: Evaluator, st: Structure, idx: Sequence[int]) -> int:
    """Parameters counted by the criterion: the structure's plus one bias per drive and signal."""
    k = st.n_params
    if st.bias:
        k += sum(len(ev.cases[r].signals) for r in idx)
    return k


def bic(rss: float, n: int, k: int) -> float:
    ne = max(n / BLOCK, k + 2.0)
    return ne * math.log(max(rss, 1e-300) / n) + k * math.log(ne)


def fd_jacobian(ev: Evaluator, st: Structure, x: np.ndarray, idx: Sequence[int]):
    """Raw residual at ``x`` and its forward-difference Jacobian (one batch); steps flip direction at an
    upper bound."""
    lo, hi = st.bounds()
    h = st.steps()
    h = np.where(x + h > hi, -h, h)
    X = np.vstack([x] + [x + h[j] * np.eye(len(x))[j] for j in range(len(x))]) if len(x) else x[None]
    R = raw_residuals(ev, st, X, idx)
    J = ((R[1:] - R[0]) / h[:, None]).T if len(x) else np.zeros((R.shape[1], 0))
    return R[0], J


@dataclass
class FitResult:
    structure: Structure
    x: np.ndarray
    rss: float
    n: int
    k_bic: int
    bic: float
    success: bool
    message: str
    nfev: int
    residual: np.ndarray = field(repr=False)
    jac: np.ndarray | None = field(default=None, repr=False)
    idx: tuple[int, ...] = ()

    def ci95(self) -> tuple[np.ndarray, np.ndarray]:
        """95 % intervals from the Gauss-Newton covariance, inflated for residual autocorrelation
        (AR(1) factor (1 + rho)/(1 - rho) from the lag-1 autocorrelation of the residual)."""
        J = self.jac
        k = len(self.x)
        if J is None or k == 0:
            return np.zeros(0), np.zeros(0)
        e = self.residual
        rho = float(np.clip(np.dot(e[1:], e[:-1]) / max(np.dot(e, e), 1e-300), 0.0, 0.98))
        infl = (1 + rho) / (1 - rho)
        s2 = self.rss / max(self.n - k, 1)
        JTJ = J.T @ J
        try:
            cov = np.linalg.pinv(JTJ) * s2 * infl
        except np.linalg.LinAlgError:
            cov = np.full((k, k), np.inf)
        se = np.sqrt(np.clip(np.diag(cov), 0, None))
        se = np.where(np.diag(JTJ) > 1e-12, se, np.inf)
        return self.x - 1.96 * se, self.x + 1.96 * se


def fit_structure(ev: Evaluator, st: Structure, x0: np.ndarray | None = None,
                  idx: Sequence[int] | None = None, max_nfev: int = 30) -> FitResult:
    """Least-squares fit of ``st``'s parameters over drives ``idx`` (all by default)."""
    idx = tuple(range(len(ev.cases))) if idx is None else tuple(idx)
    x0 = st.neutral() if x0 is None else np.asarray(x0, float)
    lo, hi = st.bounds()
    cache: dict = {}

    def resid(x):
        key = x.tobytes()
        if key not in cache:
            r, J = fd_jacobian(ev, st, x, idx)
            if st.bias:
                r, J = debias(ev, r, idx), debias(ev, J, idx)
            cache.clear()
            cache[key] = (r, J)
        return cache[key]

    n = sum(ev.n_res[r] for r in idx)
    k = n_params_bic(ev, st, idx)
    if st.n_params == 0:
        r = raw_residuals(ev, st, np.zeros((1, 0)), idx)[0]
        if st.bias:
            r = debias(ev, r, idx)
        rss = float(r @ r)
        return FitResult(st, np.zeros(0), rss, n, k, bic(rss, n, k), True, "no free parameters", 1, r,
                         None, idx)
    x0 = np.clip(x0, lo, hi)
    sol = least_squares(lambda x: resid(x)[0], x0, jac=lambda x: resid(x)[1], bounds=(lo, hi),
                        x_scale=st.steps(), method="trf", max_nfev=max_nfev, xtol=1e-4, ftol=1e-6)
    r, J = resid(sol.x)
    rss = float(r @ r)
    return FitResult(st, sol.x, rss, n, k, bic(rss, n, k), bool(sol.success), str(sol.message),
                     int(sol.nfev), r, J, idx)


@dataclass
class Option:
    add: tuple[str, ...]
    rss_lin: float
    bic_lin: float
    delta: np.ndarray = field(repr=False)
    heldout_lin: float = math.nan
    excitation_rms: float = math.inf


def screen(ev: Evaluator, current: FitResult, remaining: Sequence[str], *, pairs: bool = True,
           heldout: bool = False) -> list[Option]:
    """Linearised scores of adding each remaining candidate (and each pair) to ``current``."""
    idx = current.idx
    st = current.structure.with_(*remaining)
    x = st.embed(current.structure, current.x)
    r0, J = fd_jacobian(ev, st, x, idx)
    lo, hi = st.bounds()
    labels = st.labels()
    n = len(r0)
    options = list(itertools.combinations(remaining, 1))
    if pairs:
        options += list(itertools.combinations(remaining, 2))
    sizes = [ev.n_res[r] for r in idx]
    bounds_idx = np.cumsum([0] + sizes)
    out = []
    for add in options:
        sub = current.structure.with_(*add)
        cols = [j for j, (t, _) in enumerate(labels) if t in sub.names]
        Js = J[:, cols]
        r = r0
        if sub.bias:
            r, Js = debias(ev, r0, idx), debias(ev, Js, idx)
        if Js.shape[1]:
            d, *_ = np.linalg.lstsq(Js, -r, rcond=None)
            d = np.clip(x[cols] + d, lo[cols], hi[cols]) - x[cols]
            e = r + Js @ d
        else:
            d, e = np.zeros(0), r
        rss = float(e @ e)
        k = n_params_bic(ev, sub, idx)
        opt = Option(add, rss, bic(rss, n, k), d)
        new = [j for j, (t, _) in enumerate(labels) if t in add]
        if new:  # RMS change of the rates for one typical step of each new parameter (root-sum-square)
            steps = st.steps()[new]
            opt.excitation_rms = float(math.sqrt(sum(np.mean((J[:, j] * h) ** 2) for j, h in zip(new, steps))))
        if heldout and Js.shape[1] and len(idx) > 1:
            sq = 0.0
            for h in range(len(idx)):
                m = np.ones(n, bool)
                m[bounds_idx[h]:bounds_idx[h + 1]] = False
                dh, *_ = np.linalg.lstsq(Js[m], -r[m], rcond=None)
                dh = np.clip(x[cols] + dh, lo[cols], hi[cols]) - x[cols]
                eh = r[~m] + Js[~m] @ dh
                sq += float(eh @ eh)
            opt.heldout_lin = math.sqrt(sq / n)
        out.append(opt)
    out.sort(key=lambda o: o.bic_lin)
    return out
