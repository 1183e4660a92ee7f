"""The estimator: :class:`DiscrepancyFinder` with ``fit``/``predict``/``score``/``report``.

``fit(drives)`` runs the whole diagnosis:

1. simulate every drive with the base model; residual = simulated - measured rate on the validator's
   grid in the drive's analysis window; noise floor and significant windows (:mod:`.locate`);
2. forward selection over the candidate library (:mod:`.candidates`): at each step every remaining
   candidate and every pair is screened by a linearised fit (:func:`.fit.screen`), the best few are
   refitted by nonlinear least squares over batch simulations of all drives jointly, and the best one is
   accepted only if it lowers the information criterion clearly (``MIN_DELTA_BIC``) AND explains at least
   ``MIN_EXPLAINED`` of the residual variance still above the noise floor; it stops at the noise floor;
3. leave-one-drive-out: the final structure is refitted without each drive in turn and predicts it;
   held-out RMSE before (base model) and after;
4. verdict: ``missing_physics`` when physics/parameter terms were accepted and the held-out fit
   improves; ``no_significant_discrepancy`` when nothing beyond the noise floor (or only the measurement
   chain) was found; ``unexplained_residual`` when a real residual remains that the accepted terms do not
   explain (then the windows describe it).
"""
from __future__ import annotations

import dataclasses
import math
import time
from pathlib import Path
from typing import Sequence

import numpy as np

from ...errors import SuspInputError
from ...model import Model, load_variant, load_vehicle
from ...model.params import TermSetting
from ...model.terms import get_term
from .candidates import BY_NAME, LIBRARY, MEASUREMENT, PHYSICS, SWITCH_OF
from .data import DriveCase, load_cases, mark_quiet
from .engine import Evaluator, Structure
from .fit import FitResult, fit_structure, screen
from .locate import base_outputs, locate, noise_floor

MIN_DELTA_BIC = 10.0
MIN_EXPLAINED = 0.05
FLOOR_STOP = 1.05          # stop when the in-sample RMS is within 5 % of the noise floor
UNEXPLAINED_RATIO = 1.5    # held-out after above this x noise floor and little explained -> unexplained
TERM_MODULES = {"friction_amplitude": "susp_sim_ros.analysis.synthetic",
                "extra_viscous_damping": "susp_sim_ros.model.extra_terms",
                "damper_gas_preload": "susp_sim_ros.model.extra_terms"}


def _ensure_terms_registered():
    from .. import synthetic  # noqa: F401  (registers friction_amplitude)
    from ...model import extra_terms  # noqa: F401


def extended_model(vehicle, variant) -> Model:
    """The base model plus every registered candidate term at zero effect (one compiled kernel)."""
    _ensure_terms_registered()
    vp = vehicle if not isinstance(vehicle, (str, Path)) else load_vehicle(vehicle)
    var = variant if not isinstance(variant, (str, Path)) else load_variant(variant)
    have = {s.term.name for s in var.terms}
    extra = []
    for name in TERM_MODULES:
        if name not in have:
            t = get_term(name)
            vals = {p.name: (p.default,) * 4 for p in t.params}
            if name == "friction_amplitude":
                vals["extra_level"] = (0.0,) * 4
            extra.append(TermSetting(t, vals))
    return Model(vp, dataclasses.replace(var, terms=var.terms + tuple(extra)))


class DiscrepancyFinder:
    """Find, name, fit and prove missing physics in recorded test drives (see the module docstring).

    Parameters (all keyword): ``vehicle``, ``variant`` (the base model), ``candidates`` (names from the
    library; default all), ``max_steps`` of the forward selection, ``heldout`` (leave-one-drive-out),
    ``progress`` (a tqdm bar on stderr). Fitted attributes end in ``_``.
    """

    def __init__(self, *, vehicle: str = "passat_b8_like", variant: str = "full",
                 candidates: Sequence[str] | None = None, max_steps: int = 8, heldout: bool = True,
                 progress: bool = False):
        self.vehicle, self.variant = vehicle, variant
        self.candidates = tuple(candidates) if candidates is not None else tuple(c.name for c in LIBRARY)
        unknown = [c for c in self.candidates if c not in BY_NAME]
        if unknown:
            raise SuspInputError(f"unknown candidate terms {unknown}; known: {sorted(BY_NAME)}")
        self.max_steps, self.heldout, self.progress = max_steps, heldout, progress

    # -- helpers -------------------------------------------------------------------------------------
    def _check_fitted(self):
        if not hasattr(self, "result_"):
            raise RuntimeError("DiscrepancyFinder: call fit() first")

    def _testable(self, cases: Sequence[DriveCase], base_variant) -> tuple[list[str], list[dict], list[str]]:
        """Candidates to test; the not-identifiable ones with the maneuver that would reveal them; the
        ones already in the base model."""
        empty = {ax: any(c.oil[k] < 0.999 or c.oil[k + 1] < 0.999 for c in cases)
                 for ax, k in (("front", 0), ("rear", 2))}
        lateral = any(c.maneuver == "sine_steer" or float(np.max(np.abs(c.U[:, 2]))) > math.radians(10)
                      for c in cases)
        bump = any(c.road is not None and len(c.road) >= 2 for c in cases) or \
            any(np.any(c.U[:, 3:7] != 0) for c in cases)
        in_base, out, skip = [], [], []
        for name in self.candidates:
            cand = BY_NAME[name]
            sw = SWITCH_OF.get(name)
            if sw and getattr(base_variant, sw):
                in_base.append(name)
                continue
            if name == "friction_amplitude" and any(s.term.name == name for s in base_variant.terms):
                in_base.append(name)
                continue
            # only a structurally absent excitation rules a candidate out before testing (no steering:
            # no lateral force; flat road: no strokes); masking is judged from the data (see _excitation)
            ok = {"oil_empty": True, "lateral": lateral, "bump": bump or lateral,
                  "any": True}[cand.needs or "any"]
            if not ok:
                why = {"oil_empty": "masked by hydraulic damping: no drive has oil-empty dampers",
                       "lateral": "never excited: no drive has steering (no lateral wheel force)",
                       "bump": "never excited: no drive has road unevenness"}[cand.needs]
                skip.append({"name": name, "reveal_with": cand.reveal_with, "why": why})
            else:
                out.append(name)
        return out, skip, in_base

    # -- fit -----------------------------------------------------------------------------------------
    def fit(self, drives: Sequence[str | Path] | Sequence[DriveCase]) -> "DiscrepancyFinder":
        t_start = time.perf_counter()
        bar = None
        if self.progress:
            from tqdm import tqdm
            bar = tqdm(desc="diagnose: vehicle runs", unit="run", leave=False, dynamic_ncols=True)
        try:
            self._fit(drives, bar)
        finally:
            if bar is not None:
                bar.close()
        self.elapsed_s_ = time.perf_counter() - t_start
        return self

    def _fit(self, drives, bar):
        model = extended_model(self.vehicle, self.variant)
        self.model_ = model
        self.base_variant_ = load_variant(self.variant) if isinstance(self.variant, (str, Path)) else self.variant
        if drives and isinstance(drives[0], DriveCase):
            cases = list(drives)
        else:
            cases = load_cases(list(drives), wheelbase=model.vehicle.wheelbase)
        ev = Evaluator(model, cases, progress=bar)
        self.cases_, self.evaluator_ = cases, ev
        allidx = tuple(range(len(cases)))
        # 1. base run, quiet lead-ins, noise floor, windows
        rates = ev.simulate(Structure([]), np.zeros((1, 0)))[0]
        for r, c in enumerate(cases):
            mark_quiet(c, rates[r])
        base_res = [ev.case_residual(r, rates[r], 0.0, False) for r in allidx]
        self.base_residuals_ = base_res
        self.noise_ = noise_floor(cases, list(rates))
        sigma = self.noise_["noise_floor_deg_s"]
        self.noise_floor_ = sigma
        outs = [base_outputs(model, c, ev.Pn[r]) for r, c in enumerate(cases)]
        self.base_outputs_ = outs
        self.windows_ = locate(cases, base_res, sigma, outs)
        testable, skipped, in_base = self._testable(cases, self.base_variant_)
        self.testable_, self.skipped_, self.in_base_ = testable, skipped, in_base
        # 2. forward selection
        cur = fit_structure(ev, Structure([]))
        base_fit = cur
        n = cur.n
        path = [{"step": 0, "structure": [], "rss": cur.rss, "bic": cur.bic,
                 "rmse_deg_s": math.sqrt(cur.rss / n)}]
        accepted: list[dict] = []
        ranking = None
        for step in range(1, self.max_steps + 1):
            if math.sqrt(cur.rss / n) <= FLOOR_STOP * sigma:
                break
            remaining = [c for c in testable if c not in cur.structure.names]
            if not remaining:
                break
            opts = screen(ev, cur, remaining, pairs=True, heldout=ranking is None)
            if ranking is None:
                ranking = [o for o in opts if len(o.add) == 1]
                # masked: a typical parameter change moves the residual by less than a tenth of the noise
                for o in ranking:
                    if o.excitation_rms < 0.1 * sigma and o.add[0] not in ("sensor_bias",):
                        c = BY_NAME[o.add[0]]
                        skipped.append({"name": c.name, "reveal_with": c.reveal_with,
                                        "why": f"masked in these drives: a typical change moves the rates by "
                                               f"{o.excitation_rms:.4f} deg/s RMS, under a tenth of the noise"})
                        testable.remove(c.name)
                remaining = [c for c in testable if c not in cur.structure.names]
                opts = [o for o in opts if all(a in remaining for a in o.add)]
                if not opts:
                    break
            # singles first; a pair only when no single term alone passes (one is not enough)
            excess = max(cur.rss - n * sigma ** 2, 1e-12)
            best, best_fit, ok = None, None, False
            for size in (1, 2):
                cands = [o for o in opts if len(o.add) == size][:3]
                for o in cands:
                    st = cur.structure.with_(*o.add)
                    f = fit_structure(ev, st, _warm(st, cur, o), allidx, max_nfev=20)
                    if best_fit is None or f.bic < best_fit.bic:
                        best, best_fit = o, f
                gain = cur.rss - best_fit.rss
                ok = (cur.bic - best_fit.bic) >= MIN_DELTA_BIC and gain >= MIN_EXPLAINED * excess
                if ok:
                    break
            gain = cur.rss - best_fit.rss
            per_before = _per_case_rms(ev, cur)
            per_after = _per_case_rms(ev, best_fit)
            path.append({"step": step, "added": list(best.add), "structure": list(best_fit.structure.names),
                         "rss": best_fit.rss, "bic": best_fit.bic, "delta_bic": cur.bic - best_fit.bic,
                         "explained_fraction_of_excess": gain / excess,
                         "rmse_deg_s": math.sqrt(best_fit.rss / n), "accepted": bool(ok)})
            if not ok:
                break
            for name in best.add:
                accepted.append({"name": name, "step": step, "delta_bic": cur.bic - best_fit.bic,
                                 "explained_fraction_of_excess": gain / excess,
                                 "explained_fraction_of_base_excess":
                                     gain / max(base_fit.rss - n * sigma ** 2, 1e-12),
                                 "per_drive_rmse_before_deg_s": per_before,
                                 "per_drive_rmse_after_deg_s": per_after, "with": list(best.add)})
            cur = best_fit
        # final polish
        if cur.structure.n_params:
            cur = fit_structure(ev, cur.structure, cur.x, allidx, max_nfev=30)
        self.result_, self.base_fit_, self.path_, self.accepted_ = cur, base_fit, path, accepted
        self.ranking_ = ranking or []
        # 3. leave-one-drive-out
        self.heldout_ = self._heldout(ev, cur) if self.heldout else None
        return self

    def _heldout(self, ev: Evaluator, final: FitResult) -> dict:
        n_all = sum(ev.n_res)
        before = np.array([float(np.mean(e ** 2)) for e in self.base_residuals_])
        sizes = np.array(ev.n_res, float)
        after = []
        folds = []
        for h in range(len(ev.cases)):
            train = tuple(r for r in range(len(ev.cases)) if r != h)
            if final.structure.n_params and train:
                f = fit_structure(ev, final.structure, final.x, train, max_nfev=12)
                x = f.x
            else:
                x = final.x
            rm = ev.per_case_rmse(final.structure, x, [h])[0]
            after.append(rm ** 2)
            folds.append({"drive": ev.cases[h].name, "rmse_before_deg_s": math.sqrt(before[h]),
                          "rmse_after_deg_s": rm, "params": x.tolist()})
        after = np.array(after)
        return {"before_deg_s": float(math.sqrt(np.sum(before * sizes) / n_all)),
                "after_deg_s": float(math.sqrt(np.sum(after * sizes) / n_all)), "folds": folds}

    # -- estimator API ------------------------------------------------------------------------------
    def predict(self, drive: int | str = 0) -> tuple[np.ndarray, np.ndarray]:
        """Grid times [s] and the fitted model's rates [deg/s] (incl. time offset and bias) of a fitted
        drive (index or name)."""
        self._check_fitted()
        r = drive if isinstance(drive, int) else [c.name for c in self.cases_].index(drive)
        ev, st, x = self.evaluator_, self.result_.structure, self.result_.x
        rates = ev.simulate(st, x[None], [r])[0, 0]
        e = ev.case_residual(r, rates, st.lag(x), st.bias)
        c = self.cases_[r]
        return c.t_grid_s, c.y_meas + e

    def score(self) -> float:
        """Held-out (leave-one-drive-out) fraction of the base model's residual mean square explained
        (1 = perfect, 0 = no better than the base model); in-sample when held-out was switched off."""
        self._check_fitted()
        if self.heldout_:
            return 1.0 - (self.heldout_["after_deg_s"] / max(self.heldout_["before_deg_s"], 1e-12)) ** 2
        return 1.0 - self.result_.rss / max(self.base_fit_.rss, 1e-12)

    def report(self) -> dict:
        """The interface JSON (``susp diagnose --json``)."""
        from .report import interface_json
        self._check_fitted()
        return interface_json(self)


def _warm(st: Structure, cur: FitResult, o) -> np.ndarray:
    """Start of the nonlinear refit: current values plus the linearised step of the option."""
    x = st.embed(cur.structure, cur.x)
    labels = st.labels()
    cols = [j for j, (t, _) in enumerate(labels) if t in cur.structure.names or t in o.add]
    if len(o.delta) == len(cols):
        x[cols] = x[cols] + o.delta
    lo, hi = st.bounds()
    return np.clip(x, lo, hi)


def _per_case_rms(ev: Evaluator, f: FitResult) -> dict:
    out, o = {}, 0
    for r in f.idx:
        m = ev.n_res[r]
        e = f.residual[o:o + m]
        out[ev.cases[r].name] = float(np.sqrt(np.mean(e * e)))
        o += m
    return out
