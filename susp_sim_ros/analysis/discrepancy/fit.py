"""Fitting: nonlinear least squares over batch simulations, linearised screening, forward selection.

- :func:`fit_structure`: scipy ``least_squares`` (trust-region reflective, bounds) on the stacked
  residuals of all drives; the Jacobian by forward differences, all columns in ONE parallel batch.
- :func:`screen`: at the current model, one batch Jacobian over every remaining candidate's parameters;
  each single candidate and each pair is scored by its linearised (Gauss-Newton) fit: predicted residual
  sum of squares, information criterion and a linearised leave-one-drive-out error. The best few are
  refitted nonlinearly.
- Residuals are whitened: every signal of every drive divided by its own white-noise sigma, so roll,
  pitch and yaw rate [deg/s] and specific forces [m/s^2] add up in one sum of squares (1 per sample for
  pure noise).
- Information criterion: BIC on an effective sample count ``n_eff``, ``k ln n_eff`` penalising
  parameters. After calibration the residual is not white: it carries the structural misfit, smooth over
  the body modes, so neighbouring samples are not independent. :func:`learn_residual_correlation` measures,
  per drive and signal, the correlation samples ``tau = 1 + 2 sum rho(k)^2`` of the first calibrated
  residual (Bartlett; an automatic window); each signal then counts ``n / tau`` independent samples, never
  more than one per :data:`T_CORR_S` (the sensor's own bandwidth). A colored misfit thus buys no evidence
  that white noise of the same size would: criteria, intervals and the prior weights all use this ``n_eff``.
- Parameters with a prior (the calibration's) add prior residuals ``sqrt(n / n_eff) (x - mu) / sd``: the
  maximum a posteriori with the data counted at their effective sample size.
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from functools import cached_property
from collections.abc import Sequence

import numpy as np
from scipy.optimize import least_squares

from ...model.params import load_settings
from .data import segment_starts
from .engine import Evaluator, Structure

T_CORR_S = 0.05  # at most one independent sample of model error per 50 ms (the IMU's bandwidth)
#: automatic-window constant: the (squared) autocorrelation sum stops at the first lag M >= C tau(M)
#: (A. Sokal, "Monte Carlo methods in statistical mechanics", 1997, sec. 3; emcee's ``integrated_time``)
SOKAL_WINDOW_C = 5.0
#: fewest compared samples a signal needs for its autocorrelation time to be measured (else the T_CORR_S bound)
MIN_CORR_SAMPLES = 50
PRIOR_SCALE_MAX = 5.0   # the priors' documented spread is widened at most this much (prior_scale)
PRIOR_SCALE_MIN_INFO = 1.0  # directions whose data information is at least the prior's tell the spread


def grid_step_s(c) -> float:
    """The comparison grid's step [s] of the drive case ``c`` (median; :data:`T_CORR_S` with one sample)."""
    t = c.t_grid_s
    return float(np.median(np.diff(t))) if t.size > 1 else T_CORR_S


def n_effective(ev: Evaluator, idx: Sequence[int]) -> float:
    """Effective independent sample count of drives ``idx`` (all their signals): per signal, its samples
    over the residual's autocorrelation time (:attr:`Evaluator.corr_samples`, once learnt), at most one per
    :data:`T_CORR_S`."""
    n = 0.0
    for r in idx:
        c = ev.cases[r]
        floor = max(1.0, T_CORR_S / grid_step_s(c))
        tau = ev.corr_samples.get(r)
        if tau is None:
            n += c.y_meas.size / floor
        else:
            n += float(np.sum(c.y_meas.shape[0] / np.maximum(tau, floor)))
    return max(n, 1.0)


def correlation_samples(e: np.ndarray) -> float:
    """Samples of the series ``e`` per independent one, for a regression on a feature that looks like it:
    ``1 + 2 sum_k rho(k)^2`` over the lags up to an automatic window (the first ``M >= C tau(M)``,
    :data:`SOKAL_WINDOW_C`), between 1 and the length. Bartlett's variance of the correlation of two
    independent series, ``(1/n) sum_k rho_x(k) rho_y(k)``, with the feature as smooth as the residual
    (the worst case: a term that can mimic the misfit); Pyper and Peterman (1998, Can. J. Fish. Aquat. Sci.
    55, 2127) give ``n_eff`` this way. Squared, so an oscillating misfit (a body mode ringing out, whose
    plain autocorrelation sum cancels) counts as correlated as it is. White noise gives 1, an AR(1) process
    ``(1 + phi^2) / (1 - phi^2)``."""
    x = np.asarray(e, float) - float(np.mean(e))
    n = x.size
    var = float(x @ x)
    if n < 2 or var <= 0.0:
        return 1.0
    f = np.fft.rfft(x, 2 * n)
    acf = np.fft.irfft(f * np.conj(f))[:n] / var
    taus = 2.0 * np.cumsum(acf * acf) - 1.0
    ok = np.arange(n) >= SOKAL_WINDOW_C * taus
    m = int(np.argmax(ok)) if ok.any() else n // 2
    return float(min(max(taus[min(m, n // 2)], 1.0), n))


def learn_residual_correlation(ev: Evaluator, fit: FitResult) -> dict[int, np.ndarray]:
    """Set :attr:`Evaluator.corr_samples` from ``fit``'s residual (the first calibrated fit: what the
    model leaves when its known physics is tuned): per drive of the fit, the correlation samples
    (:func:`correlation_samples`) of every signal's compared (weighted) samples, each stretch between
    excluded spans of the measurement (``holes_s``: gaps) on its own and weighted by its samples; a signal
    without a stretch of :data:`MIN_CORR_SAMPLES` compared samples keeps the :data:`T_CORR_S` bound.
    Returns what it set."""
    out: dict[int, np.ndarray] = {}
    o = 0
    for r in fit.idx:
        c = ev.cases[r]
        n, s = c.y_meas.shape
        blk = fit.residual[o:o + n * s].reshape(n, s)
        tau = np.ones(s)
        cuts = segment_starts(c.t_grid_s, getattr(c, "holes_s", ()))  # no lag reaches across a gap
        for j in range(s):
            used = ev.weights[r][:, j] > 0
            pieces = [(e[u], int(u.sum())) for e, u in zip(np.split(blk[:, j], cuts), np.split(used, cuts))]
            pieces = [(e, m) for e, m in pieces if m >= MIN_CORR_SAMPLES]
            if pieces:  # each stretch between excluded spans on its own, weighted by its samples
                tau[j] = sum(correlation_samples(e) * m for e, m in pieces) / sum(m for _, m in pieces)
        out[r] = tau
        o += n * s
    ev.corr_samples = dict(out)
    return out


def debias(ev: Evaluator, vec: np.ndarray, idx: Sequence[int]) -> np.ndarray:
    """Subtract, per drive and signal, the mean over the bias rows (:meth:`Evaluator.bias_rows`: the quiet
    lead-in, else the whole drive; the sensor-bias estimate) from
    stacked residual vectors or Jacobian columns ``vec`` (n_res,) or (n_res, m)."""
    out = np.array(vec, float, copy=True)
    o = 0
    for r in idx:
        c = ev.cases[r]
        n, s = c.y_meas.shape
        blk = out[o:o + n * s].reshape((n, s) + out.shape[1:])
        q = ev.bias_rows(r)
        blk -= blk[q].mean(axis=0, keepdims=True)
        blk[~q & ~(ev.weights[r][:, 0] > 0)] = 0.0  # rows held out of the fit stay out
        o += n * s
    return out


def raw_residuals(ev: Evaluator, st: Structure, X: np.ndarray, idx: Sequence[int]) -> np.ndarray:
    rates = ev.simulate(st, X, idx)
    out = []
    for m, x in enumerate(np.atleast_2d(X)):
        lag = st.lag(x)
        out.append(np.concatenate([(ev.case_residual(r, rates[m, j], lag, False) * ev.weights[r]).ravel()
                                   for j, r in enumerate(idx)]))
    return np.array(out)


def n_params_bic(ev: Evaluator, st: Structure, idx: Sequence[int]) -> int:
    """Parameters counted by the criterion: the structure's plus one bias per drive and signal."""
    k = st.n_params
    if st.bias:
        k += sum(len(ev.cases[r].signals) for r in idx)
    return k


def bic(rss: float, n: int, k: int, n_eff: float) -> float:
    """BIC of a whitened residual sum of squares ``rss`` over ``n`` samples worth ``n_eff``."""
    ne = max(n_eff, k + 2.0)
    return ne * math.log(max(rss, 1e-300) / n) + k * math.log(ne)


def fd_jacobian(ev: Evaluator, st: Structure, x: np.ndarray, idx: Sequence[int],
                r0: np.ndarray | None = None, cols: Sequence[int] | np.ndarray | None = None):
    """Raw residual at ``x`` and its forward-difference Jacobian (one batch); steps flip direction at an
    upper bound. ``r0``: the raw residual at ``x`` when it is known already (not simulated again);
    ``cols``: only these parameters' columns (default all)."""
    lo, hi = st.bounds()
    h = st.steps()
    h = np.where(x + h > hi, -h, h)
    c = np.arange(len(x)) if cols is None else np.asarray(cols, np.int64)
    h = h[c]
    X = np.repeat(x[None], len(c), axis=0)
    X[np.arange(len(c)), c] += h
    if r0 is None:
        X = np.vstack([x[None], X])
    R = raw_residuals(ev, st, X, idx) if len(X) else np.zeros((0, 0))
    if r0 is None:
        r0, R = R[0], R[1:]
    J = ((R - r0) / h[:, None]).T if len(c) else np.zeros((r0.size, 0))
    return r0, J


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
    n_eff: float = 0.0

    def data_information_scale(self) -> float:
        """How much one sample's squared Jacobian informs: the effective independent share of a sample
        (``n_eff / n``, as in the objective) over the residual variance (whitened units; above 1 when the
        model misfits)."""
        k = len(self.x)
        s2 = max(self.rss / max(self.n - k, 1), 1.0)
        ratio = self.n_eff / self.n if self.n_eff > 0 else 1.0
        return ratio / s2 * self.structure.data_weight

    @cached_property
    def gram(self) -> np.ndarray:
        """``J.T @ J`` of the whitened residual's Jacobian (every row, unscaled), formed once per fit: the
        information, the prior scale and each leave-one-drive-out fold's information read it."""
        J = self.jac
        k = len(self.x)
        return np.zeros((k, k)) if J is None else J.T @ J

    def information(self, prior_scale: float = 1.0) -> np.ndarray:
        """Posterior information: Gauss-Newton information of the data (scaled by
        :meth:`data_information_scale`, the same weighting as the objective) plus the priors' (the
        calibration's parameters; ``prior_scale``: a factor on their standard deviations, :meth:`prior_scale`)."""
        J = self.jac
        k = len(self.x)
        if J is None or k == 0:
            return np.zeros((k, k))
        H = self.gram * self.data_information_scale()
        pidx, _, psd = self.structure.prior()
        H[pidx, pidx] += 1.0 / (prior_scale * psd) ** 2
        return H

    def prior_scale(self) -> float:
        """Empirical-Bayes factor ``tau >= 1`` on the priors' standard deviations: how far the calibrated
        values sit from their priors compared with the spread the priors claim.

        Type-II maximum likelihood (the evidence approximation; MacKay, Information Theory, Inference and
        Learning Algorithms, 2003, ch. 28; for a linear-Gaussian model Bishop, Pattern Recognition and
        Machine Learning, 2006, sec. 3.5): in the priors' scaled coordinates ``z = (x - mu) / sd`` the data
        information ``F`` (the parameters without a prior profiled out) has eigen-directions ``u_k`` with
        information ``l_k``. Along each direction the data alone estimate ``d_k = c_k (l_k + 1) / l_k``
        from the posterior coordinate ``c_k = u_k . z``, with variance ``1 / l_k``; under a prior
        ``N(0, tau^2)`` it is distributed ``N(0, tau^2 + 1 / l_k)``. ``tau`` maximises that likelihood over
        the directions the data inform at least as much as the prior (:data:`PRIOR_SCALE_MIN_INFO`).

        Why: the drives inform ratios (stiffness to mass, damping to mass, friction to mass) but not the
        car's overall scale, which rests on the priors only. When the car sits further from the priors
        than they claim (another car, a loaded one), the directions the data inform show it, and the
        intervals of the directions they do not inform must widen by the same factor
        (:meth:`covariance`). 1 when the priors are consistent with the data (never narrower than
        documented)."""
        J = self.jac
        pidx, mu, psd = self.structure.prior()
        if J is None or len(pidx) < 2:
            return 1.0
        Hd = self.gram * self.data_information_scale()
        other = np.setdiff1d(np.arange(len(self.x)), pidx)
        F = Hd[np.ix_(pidx, pidx)]
        if other.size:
            F = F - Hd[np.ix_(pidx, other)] @ np.linalg.pinv(Hd[np.ix_(other, other)]) @ Hd[np.ix_(other, pidx)]
        Fs = F * psd[:, None] * psd[None, :]
        lam, U = np.linalg.eigh(0.5 * (Fs + Fs.T))
        use = lam >= PRIOR_SCALE_MIN_INFO
        if not use.any():
            return 1.0
        c = U[:, use].T @ ((self.x[pidx] - mu) / psd)
        d2 = (c * (lam[use] + 1.0) / lam[use]) ** 2
        v = 1.0 / lam[use]

        t2 = np.linspace(1.0, PRIOR_SCALE_MAX ** 2, 400)[:, None]  # candidate tau^2, a grid search
        nll = np.sum(np.log(t2 + v) + d2 / (t2 + v), axis=1)
        return float(math.sqrt(t2[int(np.argmin(nll)), 0]))

    def covariance(self, prior_scale: float = 1.0) -> np.ndarray:
        """Posterior covariance, the inverse of :meth:`information`; ``prior_scale``: a factor on the
        priors' standard deviations (:meth:`prior_scale`)."""
        k = len(self.x)
        if self.jac is None or k == 0:
            return np.zeros((k, k))
        H = self.information(prior_scale)
        try:
            cov = np.linalg.pinv(H)
        except np.linalg.LinAlgError:
            cov = np.full((k, k), np.inf)
        uninformed = np.diag(H) <= 1e-12
        cov[uninformed, :] = np.inf
        cov[:, uninformed] = np.inf
        return cov

    def ci95(self, prior_scale: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
        """95 % intervals from :meth:`covariance`."""
        if self.jac is None or len(self.x) == 0:
            return np.zeros(0), np.zeros(0)
        se = np.sqrt(np.clip(np.diag(self.covariance(prior_scale)), 0, None))
        return self.x - 1.96 * se, self.x + 1.96 * se


def broyden_update(J: np.ndarray, s: np.ndarray, y: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """Broyden's rank-one secant update of the Jacobian ``J`` for the step ``s`` that changed the residual by
    ``y``: the least change of ``J`` in the norm scaled by ``scale`` (each parameter's typical step) with
    ``J_new s = y`` (Broyden, Math. Comp. 19, 1965; Dennis and Schnabel, *Numerical Methods for Unconstrained
    Optimization and Nonlinear Equations*, 1996, sec. 8.1). Columns of parameters the step leaves alone stay."""
    w = s / scale ** 2
    sw = float(s @ w)
    if not sw > 0.0:
        return J
    return J + np.outer(y - J @ s, w / sw)


def fit_structure(ev: Evaluator, st: Structure, x0: np.ndarray | None = None,
                  idx: Sequence[int] | None = None, max_nfev: int = 30,
                  fixed: Sequence[int] = (),
                  prior: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
                  broyden_updates: int | None = None) -> FitResult:
    """Least-squares fit of ``st``'s parameters over drives ``idx`` (all by default); the parameters
    ``fixed`` (indices) stay at their ``x0`` values (their Jacobian columns are not simulated and are
    zero in the result). ``prior``: (indices, means, sds) in place of the structure's own normal priors
    (:meth:`Structure.prior`), weighted as those are. ``broyden_updates``: how many of the solver's
    Jacobians after a simulated one are Broyden updates of it (:func:`broyden_update`, from the residuals
    the solver has at its accepted points) instead of simulated; 0: every one simulated; default:
    ``fit.broyden_updates`` of ``config/discrepancy.yaml``. The fit's own Jacobian (``FitResult.jac``, which
    intervals and the held-out checks read) is always simulated, and the fit ends only on a stop the solver
    judged on a simulated Jacobian or on ``max_nfev`` (evaluations counted over its restarts)."""
    if broyden_updates is None:
        broyden_updates = int(load_settings("discrepancy.yaml")["fit.broyden_updates"])
    idx = tuple(range(len(ev.cases))) if idx is None else tuple(idx)
    x0 = st.neutral() if x0 is None else np.asarray(x0, float)
    lo, hi = st.bounds()
    free = np.setdiff1d(np.arange(st.n_params), np.asarray(fixed, np.int64))
    # the last point asked for: its key, raw and debiased residual, Jacobian once asked for. The
    # Jacobian is simulated only where the solver asks for it (accepted steps), not at rejected trials.
    last: dict = {}
    # the point of the last Jacobian handed out: x, residual, Jacobian and the updates since a simulated one
    prev: dict = {}

    def resid(x, with_jac: bool = True, simulated: bool = False):
        key = x.tobytes()
        if last.get("key") != key:
            last.clear()
            last.update(key=key, raw=raw_residuals(ev, st, x[None], idx)[0], J=None, simulated=False)
            last["r"] = debias(ev, last["raw"], idx) if st.bias else last["raw"]
        if with_jac and (last["J"] is None or (simulated and not last["simulated"])):
            if not simulated and prev and prev["updates"] < broyden_updates:
                last["J"] = broyden_update(prev["J"], x - prev["x"], last["r"] - prev["r"], x_scale)
                updates = prev["updates"] + 1
            else:
                J = np.zeros((last["raw"].size, st.n_params))
                _, J[:, free] = fd_jacobian(ev, st, x, idx, r0=last["raw"], cols=free)
                last["J"], last["simulated"], updates = (debias(ev, J, idx) if st.bias else J), True, 0
            prev.update(x=x.copy(), r=last["r"], J=last["J"], updates=updates)
        return last["r"], last["J"]

    n = sum(ev.n_res[r] for r in idx)
    ne = n_effective(ev, idx)
    k = n_params_bic(ev, st, idx)
    if st.n_params == 0:
        return _without_parameters(ev, st, idx, n, k, ne)
    pidx, pmu, psd, pw, prior_jac = _prior_system(st, n, ne, prior)

    x0 = np.clip(x0, lo, hi)

    def full_x(z):
        x = x0.copy()
        x[free] = z
        return x

    def fun(z):
        x = full_x(z)
        r, _ = resid(x, with_jac=False)
        return np.concatenate([r, pw * (x[pidx] - pmu) / psd]) if len(pidx) else r

    def jac(z):
        _, J = resid(full_x(z))
        return (np.vstack([J, prior_jac]) if len(pidx) else J)[:, free]

    x_scale = st.steps().copy()
    x_scale[pidx] *= 10.0  # a prior parameter's step is a tenth of its prior sd
    if not len(free):  # everything held: the structure at x0
        r, J = resid(x0)
        rss = float(r @ r)
        return FitResult(st, x0, rss, n, k, bic(rss, n, k, ne), True, "every parameter fixed", 1, r, J, idx, ne)
    z, nfev = x0[free], 0
    while True:
        sol = least_squares(fun, z, jac=lambda z, *_: jac(z), bounds=(lo[free], hi[free]),
                            x_scale=x_scale[free], method="trf",
                            max_nfev=max_nfev - nfev, xtol=1e-4, ftol=1e-6)
        nfev += int(sol.nfev)
        x = full_x(sol.x)
        stopped_on_update = bool(prev) and prev["updates"] > 0 and np.array_equal(prev["x"], x)
        r, J = resid(x, simulated=True)
        # a stop judged on an updated Jacobian may be the update's error, not the optimum: go on from the
        # point with its simulated Jacobian until a stop is judged on a simulated one (or the budget is spent)
        if not (stopped_on_update and sol.status in (1, 2, 3, 4) and nfev < max_nfev):
            break
        z = sol.x
    rss = float(r @ r)
    return FitResult(st, x, rss, n, k, bic(rss, n, k, ne), bool(sol.success), str(sol.message),
                     nfev, r, J, idx, ne)


def _without_parameters(ev: Evaluator, st: Structure, idx: tuple[int, ...], n: int, k: int, ne: float
                        ) -> FitResult:
    """The fit of a structure without parameters: its residual (debiased when it has a bias)."""
    r = raw_residuals(ev, st, np.zeros((1, 0)), idx)[0]
    if st.bias:
        r = debias(ev, r, idx)
    rss = float(r @ r)
    return FitResult(st, np.zeros(0), rss, n, k, bic(rss, n, k, ne), True, "no free parameters", 1, r, None, idx,
                     ne)


def _prior_system(st: Structure, n: int, ne: float,
                  prior: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None):
    """The prior's parameter indices, means and sds (``prior``, or the structure's), the weight of its
    residual rows (the data counted at their effective size, :func:`n_effective`) and their Jacobian."""
    pidx, pmu, psd = st.prior() if prior is None else prior
    pw = math.sqrt(n / ne) * st.prior_gain
    prior_jac = np.zeros((len(pidx), st.n_params))
    prior_jac[np.arange(len(pidx)), pidx] = pw / psd
    return pidx, pmu, psd, pw, prior_jac


def prior_rows(free: Sequence[int], at: np.ndarray, pidx, pmu, psd, pw: float):
    """Rows ``(A, b)`` that add the normal priors of the parameters among the columns ``free`` to a
    linearised least-squares step taken at ``at`` (the step ``d`` then minimises ``|A d - b|`` with them);
    ``None`` when none of ``free`` has a prior."""
    free = list(free)
    rows = [(free.index(j), m, sd) for j, m, sd in zip(pidx, pmu, psd) if j in free]
    if not rows:
        return None
    A = np.zeros((len(rows), len(free)))
    b = np.zeros(len(rows))
    for q, (c, m, sd) in enumerate(rows):
        A[q, c] = pw / sd
        b[q] = -pw * (at[free[c]] - m) / sd
    return A, b


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
    ne = n_effective(ev, idx)
    pidx, pmu, psd = st.prior()
    pw = math.sqrt(n / ne) * st.prior_gain
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
            # prior rows of the calibration's parameters keep the linearised step within reason
            A, b = Js, -r
            pr = prior_rows(cols, x, pidx, pmu, psd, pw)
            if pr is not None:
                A, b = np.vstack([Js, pr[0]]), np.concatenate([-r, pr[1]])
            d, *_ = np.linalg.lstsq(A, b, rcond=None)
            d = np.clip(x[cols] + d, lo[cols], hi[cols]) - x[cols]
            e = r + Js @ d
        else:
            d, e = np.zeros(0), r
        rss = float(e @ e)
        k = n_params_bic(ev, sub, idx)
        opt = Option(add, rss, bic(rss, n, k, ne), d)
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
