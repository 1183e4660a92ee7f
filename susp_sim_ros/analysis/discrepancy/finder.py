"""The estimator: :class:`DiscrepancyFinder` with ``fit``/``predict``/``score``/``report``.

``fit(drives)`` runs the whole diagnosis: first make the known physics fit, then name only what no
calibration explains.

1. simulate every drive with the base model; residual = simulated - measured at the measured IMU
   sample times in the drive's analysis window, for every IMU signal the drive excites (roll, pitch, yaw
   rate, specific forces); each signal's own noise floor (:mod:`.locate`); residuals whitened by it;
2. unmeasured inputs: a drive without road input whose vertical signals show broadband residual power
   around the body and wheel modes is driven by a road the recording lacks: those signals leave the fit
   (verdict ``unmeasured_input``, with the ISO 8608 class estimated from the residual); its handling
   signals (yaw rate, lateral acceleration) stay;
3. calibration (:mod:`.calibration`): the base model's uncertain parameters, jointly over all drives,
   maximum a posteriori within their documented priors, with the measurement chain (sensor bias, time
   offset); identifiability decides which are informed, the rest stay at their prior;
4. discovery on the calibrated model: forward selection over the physics candidates
   (:mod:`.candidates`), each refitted jointly with the informed calibration parameters (so a residual a
   recalibration within the priors explains is never named); a term is accepted only if it lowers the
   information criterion clearly, explains a real share of the residual above noise, improves the drives
   held out from its fit (leave-one-drive-out) and is selected in most of those refits; backward
   elimination, then the measurement chain decided again on the model with its physics terms. At each
   step the shape regression (:mod:`.force_shape`) also offers input features (the road under the wheel,
   the wheel's rotation); a residual led by one is an input the recording lacks: discovery stops there
   and no physics is named for it (``unmeasured_input`` of that kind);
5. leave-one-drive-out of the whole result (calibration included) against the base model; each physics
   term judged on its effect on the drives as a whole (:mod:`.effect`), the measurement chain on its
   parameters: a term whose 95 % interval holds no effect is not named (dropped, the rest refitted; listed
   in ``not_identifiable`` when a held vehicle value could stand in for it);
6. verdict: ``missing_physics``, ``unmeasured_input``, ``no_significant_discrepancy`` or
   ``unexplained_residual`` (:func:`.report.verdict`).
"""
from __future__ import annotations

import dataclasses
import importlib
import math
import time
from pathlib import Path
from collections.abc import Sequence

import numpy as np

from ...errors import SuspInputError
from ...model import Model, load_variant, load_vehicle
from ...model.layout import U_INDEX
from ...model.paper import MANEUVER_KINDS
from ...model.response import Response
from ...model.params import TermSetting, load_settings
from ...model.terms import get_term
from ...progress import progress
from .calibration import (STEP_OF_SD, CalParam, calibration_candidate, calibration_entries, calibration_params,
                          consider_params, consider_sensitivity, identifiability, reveal_for,
                          sprung_mass_from_wheel_loads, vehicle_at, with_scale_rival)
from .candidates import BY_NAME, CALIBRATION, LIBRARY, MEASUREMENT, PHYSICS, Candidate
from .data import GYRO, SIGNALS, DriveCase, has_road_input, load_cases, mark_quiet, primary_signals, select_signals
from .data import SIGNAL_UNIT, as_cases
from .decoys import decoy_margin
from .effect import DATA, HELD_FREE, TermEffect, covariance_held_free, term_effect
from . import force_shape
from .engine import Evaluator, Structure
from .fit import (FitResult, Option, bic, debias, fit_structure, learn_residual_correlation, n_effective,
                  prior_rows, raw_residuals, screen)
from .locate import base_outputs, locate, noise_floor
from .report import interface_json, is_physics
from .road_estimate import GYRO_VERTICAL, estimate_road, road_usability
from .unmeasured import detect_unmeasured_road

MIN_DELTA_BIC = 10.0
MIN_EXPLAINED = 0.05
FLOOR_STOP = 1.05          # stop when the in-sample RMS is within 5 % of the noise floor
STEERING_RAD = math.radians(10)  # steering-wheel angle that makes lateral wheel forces of note
EXCITED_RATIO = 4.0        # a signal is compared when its measured spread exceeds this x its noise floor
MIN_HELDOUT_GAIN = 0.02    # a term must lower the held-out residual above noise by at least 2 %
TRIALS = 3                 # best-screened candidates (and pairs) refitted nonlinearly at each step
TRIAL_NFEV = 10            # iterations of such a trial fit (warm start; the accepted model is polished)
FINAL_POLISH_NFEV = 30      # iterations of the final structure's joint fit, calibration included
HELDOUT_NFEV = 6           # least-squares iterations of each final leave-one-drive-out refit (warm start)
HELD_SHARE = 0.5           # other drives carrying less than this share of a value's information: the held drive's own
DATA_WEIGHTS = (1.0, 0.5, 0.25, 0.1, 0.05, 0.02, 0.01)  # candidate weights of the data against the priors
WEIGHT_TOLERANCE = 0.005   # ... the largest within 0.5 % of the best held-out residual is taken
MIN_STABLE = 0.5           # ... and be selected (train-set BIC test) in at least half the refits
RECALIBRATION_NFEV = 8      # iterations of the recalibration of every ranged value a term must beat
COMPETES_SHARE = 0.8        # the held values named as competing bring this share of a term's consider variance
RIVAL_CORRELATION = 0.7     # a refused term whose parameters correlate this much with a one-state value competes
SHIFT_SD = 1.0              # a calibration value further than this (prior sd) from its prior, informed by
                            # the drives of one vehicle state only, is a hypothesis: physics competes with it
TERM_CANDIDATES = tuple(c for c in LIBRARY if c.term_module)  # candidates that are kernel terms
LEARNED_MODULE = "susp_sim_ros.model.learned_force"  # the learned term (unlisted_force) of force_shape
INPUT_MODULE = "susp_sim_ros.model.input_force"  # the input features' term of force_shape (never a candidate)


def _ensure_terms_registered():
    for c in TERM_CANDIDATES:
        importlib.import_module(c.term_module)
    importlib.import_module(LEARNED_MODULE)
    importlib.import_module(INPUT_MODULE)


def extended_model(vehicle, variant) -> Model:
    """The base model plus every registered candidate term at zero effect (one compiled kernel), and the
    input features' term (:mod:`~susp_sim_ros.model.input_force`) at zero effect with the vehicle's rolling
    radius [m]."""
    _ensure_terms_registered()
    vp = vehicle if not isinstance(vehicle, (str, Path)) else load_vehicle(vehicle)
    var = variant if not isinstance(variant, (str, Path)) else load_variant(variant)
    have = {s.term.name for s in var.terms}
    extra = []
    for name in [c.name for c in TERM_CANDIDATES] + [force_shape.TERM, force_shape.INPUT_TERM]:
        if name not in have:
            t = get_term(name)
            vals = {p.name: (p.default,) * 4 for p in t.params}  # every term's default is zero effect
            if name == force_shape.INPUT_TERM:
                vals["rolling_radius"] = (vp.rolling_radius,) * 4
            extra.append(TermSetting(t, vals))
    return Model(vp, dataclasses.replace(var, terms=var.terms + tuple(extra)))


class DiscrepancyFinder:
    """Find, name, fit and prove missing physics in recorded test drives (see the module docstring).

    Parameters (all keyword): ``vehicle``, ``variant`` (the base model), ``candidates`` (names from the
    library; default all), ``max_steps`` of the forward selection, ``heldout`` (leave-one-drive-out),
    ``progress`` (a bar on stderr: :func:`susp_sim_ros.progress.progress`). Fitted attributes end in ``_``.
    """

    calibrated_fields_: list[str]  # set by fit (annotations only: no class attribute)
    calibration_: list[dict]

    def __init__(self, *, vehicle: str = "passat_b8_like", variant: str = "full",
                 candidates: Sequence[str] | None = None, max_steps: int = 8, heldout: bool = True,
                 progress: bool = False, calibrate: bool = True,
                 wheel_loads_n: Sequence[float] | None = None, scale_accuracy: float | None = None):
        """``wheel_loads_n``: the car's static wheel loads FL, FR, RL, RR [N] as weighed, with the scale's
        relative accuracy per wheel ``scale_accuracy`` (sd, 1): the calibration's sprung-mass prior comes
        from them (:func:`~.calibration.sprung_mass_from_wheel_loads`)."""
        self.vehicle, self.variant, self.calibrate = vehicle, variant, calibrate
        if wheel_loads_n is not None and scale_accuracy is None:
            raise SuspInputError("wheel loads given without the scale's accuracy (scale_accuracy)")
        if wheel_loads_n is not None and not calibrate:
            raise SuspInputError("wheel loads given to a finder that does not calibrate (calibrate=False)")
        self.wheel_loads_n, self.scale_accuracy = wheel_loads_n, scale_accuracy
        self.candidates = tuple(candidates) if candidates is not None else \
            tuple(c.name for c in LIBRARY) + (force_shape.TERM,)
        unknown = [c for c in self.candidates if c not in BY_NAME and c != force_shape.TERM]
        if unknown:
            raise SuspInputError(f"unknown candidate terms {unknown}; known: {sorted(BY_NAME) + [force_shape.TERM]}")
        self.max_steps, self.heldout, self.progress = max_steps, heldout, progress

    # -- helpers -------------------------------------------------------------------------------------
    def _check_fitted(self):
        if not hasattr(self, "result_"):
            raise RuntimeError("DiscrepancyFinder: call fit() first")

    def _testable(self, cases: Sequence[DriveCase], base_variant) -> tuple[list[str], list[dict], list[str]]:
        """Candidates to test; the not-identifiable ones with the maneuver that would reveal them; the
        ones already in the base model."""
        lateral = any(c.maneuver in MANEUVER_KINDS and MANEUVER_KINDS[c.maneuver].steers for c in cases) \
            or _steers(cases)
        bump = any(c.road is not None and len(c.road) >= 2 for c in cases) or \
            any(np.any(c.U[:, 3:7] != 0) for c in cases)
        in_base, out, skip = [], [], []
        for name in self.candidates:
            if name == force_shape.TERM:  # learned from the data at each step (_learned_trial), not listed
                continue
            cand = BY_NAME[name]
            if cand.kind != PHYSICS:  # parameters are calibrated, the measurement chain with them
                continue
            if cand.in_variant(base_variant):
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
    def fit(self, drives) -> "DiscrepancyFinder":
        """Diagnose ``drives``: recordings (paths), read :class:`~susp_sim_ros.io.drive.TestDrive` objects
        or prepared :class:`~.data.DriveCase` objects (:func:`~.data.as_cases`; never modified). Returns
        the finder, fitted."""
        t_start = time.perf_counter()
        vp = self.vehicle if not isinstance(self.vehicle, (str, Path)) else load_vehicle(self.vehicle)
        drives = as_cases(drives, wheelbase=vp.wheelbase)
        bar = None
        if self.progress:
            bar = progress(desc="diagnose: vehicle runs", unit="run", leave=False)
        try:
            self._fit(drives, bar)
        finally:
            if bar is not None:
                bar.close()
        self.elapsed_s_ = time.perf_counter() - t_start
        return self

    def _fit(self, drives, bar):
        ev = self._prepare(drives, bar)
        allidx = tuple(range(len(ev.cases)))
        # 3. calibration of the known physics (with the measurement chain)
        cur = self._calibrate(ev, self.model_)
        self.calibrated_fit_ = cur  # what the missing force is estimated against (missing_force_report)
        path = [{"step": 0, "structure": list(cur.structure.names), "rss": cur.rss, "bic": cur.bic,
                 "rms_x_noise": math.sqrt(cur.rss / cur.n)}]
        accepted: list[dict] = []
        # 4. discovery on the calibrated model: forward, backward, against the calibration shifts
        cur = self._forward(ev, cur, path, accepted)
        cur = self._backward(ev, cur, path, accepted)
        shift_competing: list[dict] = []
        if not self.input_led_:  # a residual that follows an input names no physics, not even as a rival
            cur, shift_competing = self._shift_competition(ev, cur, self.testable_, path, accepted)
            shift_competing += self._refused_competition(cur, shift_competing)
            shift_competing += self._one_drive_competition(ev, cur, shift_competing)
        if accepted:
            cur = self._measurement_chain(ev, cur, path)
        final_held: dict | None = None
        if any(c.kind == PHYSICS for c in cur.structure.cands):  # final polish, calibration jointly
            cur = fit_structure(ev, cur.structure, cur.x, allidx, max_nfev=FINAL_POLISH_NFEV)
            cur, final_held = self._final_progressive_part(ev, cur)
            self._set_calibration(cur)
        self.path_, self.accepted_ = path, accepted
        self._finish(ev, cur, final_held)
        # 6. the physics terms judged on their effect's interval, then the measurement chain on its
        # parameters' intervals: an entry the data do not support is dropped; one a held vehicle value could
        # stand in for is not named but listed as competing with it
        # (each drop refits the rest, which is judged again)
        effect_competing: list[dict] = []
        self.effect_dropped_: list[dict] = []  # {name, why}: physics terms not named on their effect's interval
        for _ in range(len(cur.structure.names) + 1):
            drop, held, why = self._judge_physics_terms()
            if drop:
                effect_competing += held
                self.effect_dropped_ += [{"name": n, "why": why[n]} for n in drop]
                self._finish(ev, self._drop_terms(ev, self.result_, drop, path, accepted, why))
                continue
            drop, competing = self._judge_measurement_terms()
            if not drop:
                break
            self._finish(ev, self._drop_terms(ev, self.result_, drop, path, accepted))
        else:  # every round dropped something (cannot outlast the structure's terms): the last judgement
            _, competing = self._judge_measurement_terms()
            self.effects_ = self.term_effects_()
        self.competing_: list[dict] = with_scale_rival(competing + shift_competing + effect_competing,
                                                       getattr(self, "calibration_", []), SHIFT_SD,
                                                       getattr(self, "wheel_loads_", None) is not None, is_physics)
        return self

    def _prepare(self, drives, bar) -> Evaluator:
        """Stages 1-2: the extended model, the prepared drives and their evaluator, the base run (noise
        floors, windows, excited signals), the testable candidates and the base model's fit."""
        model = extended_model(self.vehicle, self.variant)
        self.model_ = model
        self.base_variant_ = load_variant(self.variant) if isinstance(self.variant, (str, Path)) else self.variant
        if drives and isinstance(drives[0], DriveCase):
            cases = list(drives)
        else:
            cases = load_cases(list(drives), wheelbase=model.vehicle.wheelbase)
        ev = Evaluator(model, cases, progress=bar)
        self.cases_, self.evaluator_ = cases, ev
        self._base_run(ev, model, cases)
        testable, skipped, in_base = self._testable(cases, self.base_variant_)
        self.refused_: list[tuple] = []  # (fit before, option, its fit, checks) of terms refused after the criterion
        self.force_shape_: list[dict] = []  # what the shape regression saw at each forward step (force_shape)
        self.learned_selection_: force_shape.Selection | None = None  # of the last learned trial offered
        self.progressive_part_: dict | None = None  # the final check of a learned spring's cube, when it ran
        self.extension_selection_: force_shape.Selection | None = None  # of the last extension of it offered
        if force_shape.TERM in self.candidates and force_shape.learned_in(self.base_variant_):
            in_base.append(force_shape.TERM)   # a variant the finder wrote: its learned force is the base model's
        self.learnable_ = force_shape.TERM in self.candidates and force_shape.TERM not in in_base
        self.input_led_ = False  # set when the shape regression finds the residual led by an input feature
        self.road_one_axle_: list[dict] = []  # road-led readings on one axle only: no input finding (_input_finding)
        self.input_weighed_: list[dict] = []  # state readings of input-led steps that stood as physics
        self.testable_, self.skipped_, self.in_base_ = testable, skipped, in_base
        self.base_fit_ = fit_structure(ev, Structure([]))
        return ev

    def _forward(self, ev: Evaluator, cur: FitResult, path: list, accepted: list) -> FitResult:
        """Forward selection on the calibrated model ``cur``: at each step the screened candidates (and
        pairs) are fitted and the first that passes every test (:meth:`_first_passing`) is added; stops at
        the noise floor, when nothing is left or nothing passes. Records each step in ``path`` and each
        added term in ``accepted``; sets the single-candidate ranking of the first step (``ranking_``)."""
        n = cur.n
        base_fit, testable, skipped = self.base_fit_, self.testable_, self.skipped_
        ranking = None
        recalibrations: dict[int, FitResult] = {}  # per step: every ranged value refitted within its prior
        for step in range(1, self.max_steps + 1):
            if math.sqrt(cur.rss / n) <= FLOOR_STOP:
                break
            remaining = [c for c in testable if c not in cur.structure.names]
            learnable = self.learnable_ and force_shape.TERM not in cur.structure.names
            extendable = self._extendable(cur)
            if not remaining and not learnable and not extendable:
                break
            opts = screen(ev, cur, remaining, pairs=True, heldout=ranking is None) if remaining else []
            if ranking is None and remaining:
                ranking = [o for o in opts if len(o.add) == 1]
                _skip_masked(ranking, testable, skipped)
                remaining = [c for c in testable if c not in cur.structure.names]
                opts = [o for o in opts if all(a in remaining for a in o.add)]
            excess = max(cur.rss - n, 1e-12)
            sel = self._shape_selection(ev, cur, step) if learnable else None
            input_sel: force_shape.Selection | None = None
            silent: list[int] = []
            if sel is not None and sel.input_led:
                # the missing force follows an input: no state reading, or none where the input is silent,
                # and it is an input the recording lacks, no physics named for it (issue 26, 5)
                input_sel, (sel, silent) = sel, self._state_reading(sel)
                if sel is None:
                    if self._input_finding(ev, input_sel, step):
                        break
                    input_sel = None   # no input: the step goes on with the listed candidates
            learned = self._learned_trial(ev, cur, sel) if sel is not None else None
            if extendable:
                learned = self._extension_trial(ev, cur, step)
            if not opts and learned is None:
                if input_sel is not None:
                    self._input_finding(ev, input_sel, step)
                break
            best, best_fit, ok, checks = self._first_passing(ev, cur, opts, recalibrations, step, learned)
            if input_sel is not None:
                ok = self._states_explain_silent(ev, cur, best_fit, silent, ok, checks)
            gain = cur.rss - best_fit.rss
            per_before = self._per_drive_rmse(ev, cur)
            per_after = self._per_drive_rmse(ev, best_fit)
            path.append({"step": step, "added": list(best.add), "structure": list(best_fit.structure.names),
                         "rss": best_fit.rss, "bic": best_fit.bic, "delta_bic": cur.bic - best_fit.bic,
                         "explained_fraction_of_excess": gain / excess,
                         "rms_x_noise": math.sqrt(best_fit.rss / n), "accepted": bool(ok), **checks})
            if not ok:
                if input_sel is not None:
                    self._input_finding(ev, input_sel, step)
                break
            if extendable and force_shape.TERM in best.add:   # the learned term extended: its entry amended
                self._amend_learned(accepted, step, gain / excess, checks)
            else:
                accepted += [{"name": name, "step": step, **self._learned_words(name),
                              "delta_bic": cur.bic - best_fit.bic,
                              "explained_fraction_of_excess": gain / excess,
                              "explained_fraction_of_base_excess": gain / max(base_fit.rss - n, 1e-12),
                              "per_drive_rmse_before": per_before,
                              "per_drive_rmse_after": per_after, "with": list(best.add), **checks}
                             for name in best.add]
            cur = best_fit
        self.ranking_ = ranking or []
        return cur

    # -- calibration against physics (issue 24, item 4) -----------------------------------------------
    def _one_state_shifts(self, cur: FitResult) -> list[tuple[int, CalParam, str, float]]:
        """The calibrated values of ``cur`` that sit more than :data:`SHIFT_SD` prior standard deviations
        from their prior and that the drives of one vehicle state alone inform (without that state's rows
        the data tell less about the value than its prior does, or that state carries most of what all
        drives tell: :func:`_informed_only_by`), as
        ``(index in cur.x, parameter, state, shift in prior sd)``. Such a value (the oil-empty rear damper
        of the one rear-empty car 39 % stronger than measured) is a hypothesis, not a fact."""
        if cur.jac is None:
            return []
        far = {j: (p, z) for j, p, z in self._far_shifts(cur)}
        if not far:
            return []
        out = []
        for j, state in self._one_state_values(cur).items():
            if j in far:
                p, z = far[j]
                out.append((j, p, state, z))
        return out

    def _far_shifts(self, fit: FitResult) -> list[tuple[int, CalParam, float]]:
        """The calibrated values of ``fit`` more than :data:`SHIFT_SD` prior sd from their prior, as
        ``(index in fit.x, parameter, shift in prior sd)``."""
        st = fit.structure
        if CALIBRATION not in st.names or not self.informed_:
            return []
        a = st.span(CALIBRATION).start
        out = []
        for i, p in enumerate(self.informed_):
            z = float((fit.x[a + i] - p.prior) / p.sd)
            if abs(z) > SHIFT_SD:
                out.append((a + i, p, z))
        return out

    def _one_state_values(self, fit: FitResult) -> dict[int, str]:
        """The calibration values of ``fit`` (index in ``fit.x``) that the drives of one vehicle state
        alone inform, with that state: without that state's rows the data tell less about the value than
        its prior does, or less than half of what all rows tell (:func:`_informed_only_by`); every one when
        all drives share one state."""
        st = fit.structure
        if CALIBRATION not in st.names or fit.jac is None:
            return {}
        a = st.span(CALIBRATION).start
        cal = range(a, a + len(self.informed_))
        edges = np.cumsum([0] + [self.evaluator_.n_res[q] for q in fit.idx])
        rows_of: dict[str, np.ndarray] = {}
        for k, q in enumerate(fit.idx):
            rows = rows_of.setdefault(self.cases_[q].state, np.zeros(len(fit.residual), bool))
            rows[edges[k]:edges[k + 1]] = True
        if len(rows_of) == 1:
            return {j: next(iter(rows_of)) for j in cal}
        return {j: s for s, rows in rows_of.items() for j in _informed_only_by(fit, rows) if j in cal}

    @staticmethod
    def _competing_entry(cand: Candidate, rivals: list[str], reveals: Sequence[str], why: str) -> dict:
        """A ``not_identifiable`` entry of physics term ``cand`` (listed, or the learned term with its
        dependences in words) competing with the calibration values ``rivals`` (``PARAM:where``): the
        measurements that pin them (``reveals``, once each), then the term's own maneuver."""
        reveal = "; ".join(dict.fromkeys(reveals))
        return {"name": cand.name, "competes_with": rivals,
                "reveal_with": f"{reveal}; then {cand.reveal_with}" if cand.reveal_with else reveal,
                "why": f"{cand.meaning} {why}"}

    def _refused_competition(self, final: FitResult, listed: list[dict]) -> list[dict]:
        """Terms the drives want clearly (criterion and share of the excess passed) but a later test
        refused (held-out drives, stability, recalibration), whose parameters move together with a
        calibration value (posterior correlation at least :data:`RIVAL_CORRELATION` in the term's joint fit)
        and whose effect on the drives that value alone would reproduce only by moving more than
        :data:`SHIFT_SD` prior sd (least squares on its Jacobian column; a smaller effect is the
        calibration's own uncertainty, not a rival hypothesis): the calibration may have taken what the term
        would explain, or the term would take what is a wrong value; the drives cannot say which.
        A listed term competes with the values the drives of one vehicle state alone inform (a stronger
        oil-empty damper and extra damping of the one rear-empty car); the learned term (physics no candidate
        lists, read off the missing force's shape) only when it also beat its decoys, and with any calibrated
        value: its dependences are the data's own, so a spring-like missing force and a stiffer wheel rate
        informed by every drive are rival readings of the same residual (issue 24, item 4, for the learned
        term; it was dropped in silence before).
        Listed in ``not_identifiable`` with ``competes_with`` and ``reveal_with``, never dropped in silence.
        Terms in ``final`` or already ``listed``, and terms fitted where their physics cannot be
        (:meth:`Candidate.physical`: negative extra damping is a weaker damper, the calibration's business),
        are skipped."""
        out: list[dict] = []
        seen = set(final.structure.names) | {c["name"] for c in listed}
        for before, o, f, checks in sorted(self.refused_, key=lambda t: t[2].bic):
            name = o.add[0]
            st = f.structure
            if name in seen or CALIBRATION not in st.names or f.jac is None \
                    or (name == force_shape.TERM and not checks.get("decoys_beaten")):
                continue
            cand = st.cands[st.names.index(name)]
            if not cand.physical(st.part(f.x, name)):
                continue
            seen.add(name)
            a = st.span(CALIBRATION).start
            term = st.span(name)
            t0, t1 = term.start, term.stop
            # the term's size against the value, its law's shape as fitted (an exponent free beside them
            # would share the covariance and hide the trade of size against value)
            gains = cand.gain_indices
            cov = _conditioned_on(f.information(), [t0 + j for j in range(t1 - t0) if j not in gains])
            sd = np.sqrt(np.clip(np.diag(cov), 1e-300, None))
            rho = np.abs(cov / np.outer(sd, sd))
            one_state = self._one_state_values(f)
            values = one_state if name != force_shape.TERM else \
                {j: one_state.get(j, "") for j in range(a, a + len(self.informed_))}
            # the term's effect on the drives, and the shift of each value that alone would reproduce it
            effect = f.jac[:, t0:t1] @ (f.x[t0:t1] - st.neutral()[t0:t1])
            cols = f.jac[:, list(values)]
            shift = dict(zip(values, (cols.T @ effect) / np.maximum(np.sum(cols * cols, axis=0), 1e-300)))
            rivals = sorted(((float(rho[t0:t1, j].max()), j) for j in values
                             if rho[t0:t1, j].max() >= RIVAL_CORRELATION
                             and abs(shift[j]) >= SHIFT_SD * self.informed_[j - a].sd), reverse=True)
            if not rivals:
                continue
            params = [self.informed_[j - a] for _, j in rivals]
            refused = ("held-out drives" if not checks.get("passed", True) else
                       "a recalibration of the ranged vehicle values explaining as much")
            decoys = ", beats its decoys" if checks.get("decoys_beaten") else ""
            informed = [f"{p.field}:{p.where} ("
                        + (f"informed by the {values[j]} drives only, " if values[j] else "")
                        + f"posterior correlation {r:.2f}; the term's effect is {shift[j] / p.sd:+.1f} prior sd of it)"
                        for p, (r, j) in zip(params, rivals)]
            out.append(self._competing_entry(
                cand, [f"{p.field}:{p.where}" for p in params],
                [reveal_for(p, values[j] or "recorded") for p, (_, j) in zip(params, rivals)],
                f"lowers the criterion by {before.bic - f.bic:.0f} and explains "
                f"{100 * (before.rss - f.rss) / max(before.rss - before.n, 1e-12):.0f} % of the residual above "
                f"noise{decoys}, but {refused} refused it; "
                + ", ".join(informed)
                + " moves with it: the drives cannot tell the term from that calibration value"))
        return out

    def _one_drive_competition(self, ev: Evaluator, final: FitResult, listed: list[dict]) -> list[dict]:
        """Terms the drives want clearly (criterion, share of the excess, decoys beaten) that only the held-out
        test refused, where the drives that lose are the ones that alone tell the term's size: each owns a
        level of the term (without it the other drives carry less than :data:`HELD_SHARE` of what all drives
        tell of that level, the rule :func:`_informed_only_by` applies to calibration values) while the
        term predicts the other drives held out (their gain at least :data:`MIN_HELDOUT_GAIN` of their excess).
        Leaving out the one drive that tells a value tests whether the others tell it, not whether the term
        holds: the rear axle's amplitude friction shows mainly with the rear dampers oil-empty, so the one
        rear-empty bump crossing carries most of what the drives say of its rear level, and held out the
        others predict it from the sine steers. Listed in ``not_identifiable``, never named, never dropped in
        silence: competing with the calibration values that drive alone tells in the term's fit (its oil-empty
        damper), revealed by another drive of that vehicle state. Terms in ``final`` or ``listed`` and terms
        fitted where their physics cannot be are skipped."""
        out: list[dict] = []
        seen = set(final.structure.names) | {c["name"] for c in listed}
        R = len(ev.cases)
        for before, o, f, checks in sorted(self.refused_, key=lambda t: t[2].bic):
            name = o.add[0]
            st = f.structure
            if name in seen or f.jac is None or R < 3 or not checks.get("decoys_beaten") \
                    or checks.get("heldout_gain_fraction_of_excess", 1.0) >= MIN_HELDOUT_GAIN \
                    or checks.get("selected_in_fraction_of_refits", 0.0) < MIN_STABLE:
                continue
            cand = st.cands[st.names.index(name)]
            if not cand.physical(st.part(f.x, name)):
                continue
            span = st.span(name)
            levels = [span[j] for j in cand.gain_indices]
            owners: dict[int, list[int]] = {}
            sq_old = sq_new = n_held = 0.0
            for h in range(R):
                owned = _owned_by(f, _drive_rows(ev, f, h), levels)
                if owned:
                    owners[h] = owned
                    continue
                old_h, _, new_h, _, n_h = self._fold_pair(ev, before, f, h)
                sq_old, sq_new, n_held = sq_old + old_h, sq_new + new_h, n_held + n_h
            others_gain = (sq_old - sq_new) / max(sq_old - n_held, 1e-12)
            if not owners or len(owners) == R or others_gain < MIN_HELDOUT_GAIN:
                continue
            seen.add(name)
            labels = st.labels()
            a = st.span(CALIBRATION).start if CALIBRATION in st.names else -1
            own_values: list[str] = []
            for h in owners:
                own_values += [f"{self.informed_[j - a].field}:{self.informed_[j - a].where}"
                               for j in _informed_only_by(f, _drive_rows(ev, f, h))
                               if a >= 0 and labels[j][0] == CALIBRATION]
            told = "; ".join(f"{ev.cases[f.idx[h]].name} alone tells its {', '.join(labels[j][1] for j in js)}"
                             for h, js in owners.items())
            out.append(self._competing_entry(
                cand, list(dict.fromkeys(own_values)),
                [f"another {c.maneuver.replace('_', ' ')} in the vehicle state {c.state} (another height or speed "
                 f"than {c.name}), to hold out" for c in (ev.cases[f.idx[h]] for h in owners)],
                f"lowers the criterion by {before.bic - f.bic:.0f}, explains "
                f"{100 * (before.rss - f.rss) / max(before.rss - before.n, 1e-12):.0f} % of the residual above "
                f"noise, beats its decoys and predicts the other drives held out ({100 * others_gain:.0f} % of "
                f"their excess), but {told}: held out, that drive tests whether the others tell the value, "
                f"not whether the term holds (held-out gain over all drives "
                f"{100 * checks['heldout_gain_fraction_of_excess']:.0f} %)"))
        return out

    def _shift_competition(self, ev: Evaluator, cur: FitResult, testable: list[str], path: list,
                           accepted: list) -> tuple[FitResult, list[dict]]:
        """Physics against the calibration shifts of :meth:`_one_state_shifts`, on equal terms: every
        physics candidate not in ``cur`` is fitted with those values held at their priors and scored by
        the criterion plus the prior cost of the shifts it avoids (the shifted calibration pays
        ``sum z^2``, a term ``log n_eff`` per parameter). A candidate that does the shifts' work (it beats
        the calibration without them by :data:`MIN_DELTA_BIC`), scores clearly better than the shifted
        calibration (by :data:`MIN_DELTA_BIC`) and passes the held-out test of every named term
        (:meth:`_heldout_check`) is named: the evidence decides for the physics; one that scores clearly
        worse leaves the shifts standing; any other competes with them: it is listed in
        ``not_identifiable`` with ``competes_with`` (the shifted values, ``PARAM:where``) and
        ``reveal_with`` (the rig test of each value, then the term's own maneuver), never absorbed
        silently. Returns the (possibly extended) fit and the competing entries; the decision is
        recorded in ``path``."""
        shifts = self._one_state_shifts(cur)
        self.shifts_ = [{"param": f"{p.field}:{p.where}", "state": s, "value": float(cur.x[j]),
                         "prior": p.prior, "shift_in_prior_sd": z} for j, p, s, z in shifts]
        cands = [c for c in testable if c not in cur.structure.names and BY_NAME[c].kind == PHYSICS]
        if not shifts or not cands:
            return cur, []
        allidx = tuple(range(len(ev.cases)))
        idx = sorted({j for j, *_ in shifts})
        pen = float(sum(z ** 2 for *_, z in shifts))
        lne = math.log(max(cur.n_eff, 2.0))
        x0 = cur.x.copy()
        for j, p, *_ in shifts:
            x0[j] = p.prior
        held = fit_structure(ev, cur.structure, x0, allidx, max_nfev=TRIAL_NFEV, fixed=idx)
        crit_shift, crit_held = cur.bic + pen, held.bic - len(idx) * lne
        rivals = sorted({f"{p.field}:{p.where}" for _, p, *_ in shifts})
        reveals = [reveal_for(p, s) for _, p, s, _ in shifts]
        moved = ", ".join(f"{d['param']} {d['value']:.3g} (prior {d['prior']:.3g})" for d in self.shifts_)
        competing: list[dict] = []
        for crit, name, f in _held_trials(ev, cur, held, cands, idx, lne):
            if not BY_NAME[name].physical(f.structure.part(f.x, name)):
                continue  # no physical rival: the term stands in for a weaker model element
            if crit_held - crit < MIN_DELTA_BIC or crit > crit_shift + MIN_DELTA_BIC:
                continue  # the term does not do what the shifts do, or the shifts explain clearly more
            entry = {"step": len(path), "shift_test": name, "held_at_prior": rivals,
                     "criterion_with_shifts": crit_shift, "criterion_without_shifts": crit_held,
                     "criterion_term_without_shifts": crit}
            # better on equal terms but failing on held-out drives, or within the margin: undecided
            checks = self._decoy_check(ev, held, f) if crit <= crit_shift - MIN_DELTA_BIC else {}
            if checks.get("decoys_beaten"):
                checks.update(self._heldout_check(ev, cur, f))
            entry.update(checks)
            if checks.get("decoys_beaten") and checks.get("passed") and not competing:
                path.append({**entry, "added": [name], "structure": list(f.structure.names), "rss": f.rss,
                             "bic": f.bic, "accepted": True,
                             "why": f"with {', '.join(rivals)} at their measured values the term explains the "
                                    "drives better than those shifts do (criterion and prior cost on equal "
                                    "terms): the evidence decides for the physics"})
                accepted.append({"name": name, "step": len(path) - 1, "delta_bic": crit_shift - crit,
                                 "instead_of_shifts": self.shifts_, **checks})
                return f, []  # the final joint polish frees the held values again
            path.append({**entry, "accepted": False,
                         "why": "explains the drives as well as the calibration shifts: not identifiable"})
            competing.append(self._competing_entry(
                BY_NAME[name], rivals, reveals, f"explains the drives as well as the calibration moving {moved} beyond "
                "one prior sd on the drives of one vehicle state only: the drives cannot tell them apart"))
        return cur, competing

    def _finish(self, ev: Evaluator, cur: FitResult, heldout: dict | None = None) -> None:
        """Stage 5 on the final structure: the intervals' ingredients, the leave-one-drive-out of the
        whole result against the base model (``heldout`` when it was computed already), the calibration
        table."""
        self.result_ = cur
        self.consider_se_ = self._consider_se(ev, cur)
        self.prior_scale_ = cur.prior_scale() if self.calibrate else 1.0
        if self.identifiability_ is not None:
            self.identifiability_["prior_scale"] = self.prior_scale_
        self.heldout_ = (heldout if heldout is not None else self._heldout(ev, cur)) if self.heldout else None
        self.jackknife_se_ = _jackknife_se(self.heldout_, len(cur.x))
        self._set_calibration(cur)

    def _judge_measurement_terms(self) -> tuple[list[str], list[dict]]:
        """The final structure's measurement-chain terms (time offset, steering offset) whose 95 %
        intervals hold no effect: those whose interval from the data alone (posterior and drive-to-drive
        spread) holds it, to drop; and those whose interval holds it only with the values the calibration
        held at their file value (:meth:`_consider_se`), as entries ``{name, competes_with, reveal_with,
        why, value, ci95}``: the held values that bring most of the interval's width (at least
        :data:`COMPETES_SHARE` of it between them, strongest first) could stand in for the term."""
        st, x = self.result_.structure, self.result_.x
        lo, hi = self.ci95_()
        lo_d, hi_d = self._ci95(self.result_, consider=False)
        drop, competing = [], []
        for term, part in st.slices():
            name, cand = term.name, BY_NAME.get(term.name)
            if cand is None or cand.kind != MEASUREMENT:
                continue
            if cand.effect_in_interval(lo_d[part], hi_d[part]):
                drop.append(name)
            elif cand.effect_in_interval(lo[part], hi[part]):
                rivals = self._competitors(part)
                keys = [self.consider_keys_[self.consider_names_.index(r)] for r in rivals]
                competing.append({
                    "name": name, "competes_with": rivals,
                    "reveal_with": f"a measurement of {', '.join(keys) or 'the held vehicle values'} (held at the "
                                   f"vehicle file's value; the drives do not pin it), then {cand.reveal_with}",
                    "value": {p.name: float(v) for p, v in zip(cand.params, x[part])},
                    "ci95": {p.name: [float(l), float(h)] for p, l, h in zip(cand.params, lo[part], hi[part])},
                    "why": f"its 95 % interval holds no effect once {', '.join(rivals) or 'the held values'} "
                           "may lie anywhere in their priors: the drives cannot tell the two apart"})
        return drop, competing

    def _judge_physics_terms(self) -> tuple[list[str], list[dict], dict[str, str]]:
        """The final structure's physics terms judged on their effect as a whole (:mod:`.effect`; issue 24,
        item 3: a term whose 95 % interval holds no effect is never named). At most one term per call, the
        weakest, so two terms that stand in for each other are not both dropped (the caller refits and
        judges again): first among those whose interval from the data alone (posterior and drive-to-drive
        spread) holds it, the one whose interval reaches furthest below zero; else among those whose
        interval holds it once the values the calibration holds at their file value are free within their
        priors, the same, also returned as an entry ``{name, competes_with, reveal_with, why, value,
        effect}`` of physics competing with those values (the held values that bring most of the effect's
        variance); the learned term, too, with its dependences in words.
        Returns (names to drop, competing entries, name -> reason)."""
        effects = self.effects_ = self.term_effects_()  # the report's, once nothing more drops
        for held in (DATA, HELD_FREE):
            weak = [(_finite_or_lowest(eff.ci95_fraction(held)[0]), name) for name, eff in effects.items()
                    if eff.holds_zero(held)]
            if weak:
                break
        if not weak:
            return [], [], {}
        _, name = min(weak)
        eff = effects[name]
        lo, hi = eff.ci95_fraction(held)
        if held == DATA:
            why = (f"the 95 % interval of its effect on the drives, {lo:.2f} to {hi:.2f} of the fitted one, holds no "
                   "effect")
            return [name], [], {name: why + ": not named"}
        rivals = self._strongest_held(np.array(eff.held_share))
        why = (f"the 95 % interval of its effect, {lo:.2f} to {hi:.2f} of the fitted one once "
               f"{', '.join(rivals) or 'the held vehicle values'} may lie anywhere in their priors, holds no "
               "effect: the drives cannot tell the term from those values")
        st, x = self.result_.structure, self.result_.x
        cand = st.cands[st.names.index(name)]
        keys = [self.consider_keys_[self.consider_names_.index(r)] for r in rivals]
        entry = self._competing_entry(cand, rivals, [f"a measurement of {', '.join(keys)} (held at the vehicle "
                                                     "file's value)"] if keys else [], why)
        entry.update({"value": {p.name: float(v) for p, v in zip(cand.params, st.part(x, name))},
                      "effect": eff.as_json()})
        return [name], [entry], {name: why + ": not named"}

    def term_effects_(self) -> dict[str, TermEffect]:
        """Each physics term of the final structure: its effect on the drives as a whole, with the
        interval's ingredients (:mod:`.effect`)."""
        fit, ev = self.result_, self.evaluator_
        st = fit.structure
        if fit.jac is None:
            return {}
        cov = fit.covariance(getattr(self, "prior_scale_", 1.0))
        cons = getattr(self, "consider_sd_", None)
        Jh = getattr(self, "consider_jac_", np.zeros((0, 0)))
        # the held values' priors as documented: the empirical-Bayes factor is measured on the calibrated
        # values, which the drives inform; nothing here tells the held values' spread
        cov_free = covariance_held_free(fit.information(getattr(self, "prior_scale_", 1.0)), fit.jac, Jh,
                                        self.consider_prior_sd_, fit.data_information_scale()) \
            if Jh.size and Jh.shape[0] == fit.jac.shape[0] else None
        folds = [f["params"] for f in (self.heldout_ or {}).get("folds", []) if len(f.get("params", [])) == len(fit.x)]
        out = {}
        for cand, part in st.slices():
            if cand.kind != PHYSICS or not cand.params:
                continue
            x0 = fit.x.copy()
            x0[part] = cand.neutral()
            r0 = raw_residuals(ev, st, x0[None], fit.idx)[0]
            if st.bias:
                r0 = debias(ev, r0, fit.idx)
            jk = np.array(folds)[:, part] if len(folds) >= 3 else None
            out[cand.name] = term_effect(r0 - fit.residual, fit.jac[:, part], cov[part, part],
                                         cons[part] if cons is not None and cons.shape[0] == len(fit.x) else None,
                                         jk, fit.x[part], None if cov_free is None else cov_free[part, part])
        return out

    def _competitors(self, part: slice) -> list[str]:
        """The held values (``PARAM:where``) that bring most of the consider variance of the parameters in
        ``part`` (a term's slice of the joint vector)."""
        contrib = getattr(self, "consider_contrib_", None)
        if contrib is None or not contrib.size:
            return []
        return self._strongest_held(contrib[part].sum(axis=0))

    def _strongest_held(self, share: np.ndarray) -> list[str]:
        """The held values (``PARAM:where``) whose ``share`` (one per held value) make up at least
        :data:`COMPETES_SHARE` of the total, strongest first."""
        share = np.asarray(share, float)
        if not share.size:
            return []
        order = np.argsort(share)[::-1]
        total, out, acc = float(share.sum()), [], 0.0
        for j in order:
            if total <= 0 or acc >= COMPETES_SHARE * total:
                break
            out.append(self.consider_names_[j])
            acc += float(share[j])
        return out

    def _drop_terms(self, ev: Evaluator, cur: FitResult, names: list[str], path: list,
                    accepted: list, why: dict[str, str] | None = None) -> FitResult:
        """``cur`` without the terms ``names`` (refitted, calibration jointly), each drop in the path with
        its reason (``why``: name -> reason; default: the measurement chain's)."""
        f = _refit_without(ev, cur, names)
        for name in names:
            _record_drop(path, accepted, cur, f, name, (why or {}).get(
                name, "its 95 % interval from the drives holds no effect: not named"))
        return f

    def _base_run(self, ev: Evaluator, model, cases: list[DriveCase]) -> None:
        """Stages 1-2: the base model's run, quiet lead-ins and noise floors per signal; which signals
        each drive excites (and unmeasured road input); the base residuals and the windows above noise."""
        allidx = tuple(range(len(cases)))
        sims = ev.simulate(Structure([]), np.zeros((1, 0)), to_end=True)[0]
        for r, c in enumerate(cases):
            mark_quiet(c, sims[r][:, :3])
        self.noise_ = noise_floor(cases, list(sims))
        self.estimated_roads_: dict = {}
        self.unmeasured_ = self._choose_signals(ev, sims)
        sigmas = [self._case_sigma(c) for c in cases]
        ev.set_noise(sigmas)
        self.noise_floor_ = self.noise_["noise_floor_deg_s"]
        base_res = [ev.case_residual(r, sims[r], 0.0, False) for r in allidx]
        self.base_residuals_ = base_res
        outs = [base_outputs(model, c, ev.Pn[r]) for r, c in enumerate(cases)]
        self.base_outputs_ = outs
        self.windows_ = locate(cases, base_res, sigmas, outs)

    def _recalibration(self, ev: Evaluator, cur: FitResult, cache: dict[int, FitResult], step: int) -> FitResult:
        """Every ranged value refitted within its prior at this step (once per step)."""
        if step not in cache:
            cache[step] = self._recalibrate(ev, cur)
        return cache[step]

    def _first_passing(self, ev: Evaluator, cur: FitResult, opts: list, recalibrations: dict[int, FitResult],
                       step: int, learned: tuple[Option, FitResult] | None = None):
        """Fit the best-screened candidates (singles first; a pair only when no single term alone
        passes) and return ``(option, fit, passed, checks)`` of the first that passes every test: BIC,
        share of the excess, held-out, and better than recalibrating the known physics alone
        (:meth:`_recalibration` of this ``step``); else the best-BIC trial with ``passed`` False."""
        allidx = tuple(range(len(ev.cases)))
        best, best_fit = None, None
        best_checks: dict = {}
        singles: dict[str, FitResult] = {}   # the single trials' fits, by term: a pair's members alone
        for size in (1, 2):
            trials = []
            for o in [o for o in opts if len(o.add) == size][:TRIALS]:
                st = cur.structure.with_(*o.add)
                trials.append((o, fit_structure(ev, st, _warm(st, cur, o), allidx, max_nfev=TRIAL_NFEV)))
            if size == 1 and learned is not None:  # the learned term competes with the single listed ones
                trials.append(learned)
            # every trial in BIC order until one passes: the best-BIC term failing its held-out test
            # must not hide a runner-up that passes; on a tie the listed term goes first
            if size == 1:
                singles.update((o.add[0], f) for o, f in trials)
            for o, f in sorted(trials, key=lambda t: (t[1].bic, force_shape.TERM in t[0].add)):
                ok, in_sample, checks = self._passes(ev, cur, f, recalibrations, step, singles)
                if force_shape.TERM in o.add and self.force_shape_:   # the learned trial's outcome, kept
                    self.force_shape_[-1]["trial"] = {"delta_bic": cur.bic - f.bic, "passed": ok, **checks}
                if best_fit is None or f.bic < best_fit.bic:
                    best, best_fit, best_checks = o, f, checks
                if ok:
                    return o, f, True, checks
                if in_sample and size == 1:  # clear in the drives, refused by a later test
                    self.refused_.append((cur, o, f, dict(checks)))
        assert best is not None and best_fit is not None  # opts or the learned trial: a trial was fitted
        return best, best_fit, False, best_checks

    def _passes(self, ev: Evaluator, cur: FitResult, f: FitResult, recalibrations: dict[int, FitResult],
                step: int, singles: dict[str, FitResult] | None = None) -> tuple[bool, bool, dict]:
        """Every test a new term (or pair) that took ``cur`` to ``f`` must pass, in order: BIC, share of
        the excess, values the named physics can take (:meth:`Candidate.physical`), decoys, held-out drives,
        for a pair each member's own share of the held-out gain (:meth:`_pair_members_check`; ``singles``:
        the single trials' fits at this step, by term), better than recalibrating the known physics alone.
        Returns ``(passed, passed_in_sample, checks)``."""
        excess = max(cur.rss - cur.n, 1e-12)
        ok = (cur.bic - f.bic) >= MIN_DELTA_BIC and cur.rss - f.rss >= MIN_EXPLAINED * excess
        in_sample = ok
        checks: dict = {}
        if ok:
            # a physics name only for values its physics can take (negative extra damping is a damper
            # weaker than its curve: the calibration's business, not a term in parallel)
            new = [c for c in f.structure.cands if c.name not in cur.structure.names and c.kind == PHYSICS]
            unphysical = [c.name for c in new if not c.physical(f.structure.part(f.x, c.name))]
            if unphysical:
                checks, ok = {"unphysical": unphysical}, False
        if ok:
            checks = self._decoy_check(ev, cur, f)
            ok = checks["decoys_beaten"]
        if ok:
            checks.update(self._heldout_check(ev, cur, f))
            ok = checks["passed"]
        pair = [c.name for c in f.structure.cands if c.name not in cur.structure.names]
        if ok and len(pair) == 2 and "heldout_gain_fraction_of_excess" in checks:  # drives to hold out
            checks.update(self._pair_members_check(ev, cur, pair, checks["heldout_gain_fraction_of_excess"],
                                                   singles or {}))
            ok = checks["members_earn_their_place"]
        if ok:
            recal = self._recalibration(ev, cur, recalibrations, step)
            checks["recalibration_rss"] = recal.rss
            ok = f.rss < recal.rss
        return bool(ok), bool(in_sample), checks

    def _pair_members_check(self, ev: Evaluator, cur: FitResult, pair: list[str], pair_gain: float,
                            singles: dict[str, FitResult]) -> dict:
        """A pair is tried only when no single term passes: for two terms that act only together (two
        effects that cancel in one drive and not in another). Each member must then earn its place out of
        sample: the pair's held-out gain (:meth:`_heldout_check`, a fraction of the held-out excess of
        ``cur``) must exceed the other member's alone by :data:`MIN_HELDOUT_GAIN`, the share a single term
        must lower the held-out residual by. A pair whose second member adds nothing on the left-out drives
        (or predicts them worse) is one term that failed a later test with a passenger, not two effects.
        ``member_heldout_gain``: per member, the pair's gain less the other member's alone."""
        alone = {}
        for name in pair:
            f1 = singles.get(name)
            if f1 is None:  # not among the best-screened singles: fitted here
                st = cur.structure.with_(name)
                f1 = fit_structure(ev, st, st.embed(cur.structure, cur.x), tuple(range(len(ev.cases))),
                                   max_nfev=TRIAL_NFEV)
            alone[name] = self._heldout_check(ev, cur, f1)["heldout_gain_fraction_of_excess"]
        own = {a: float(pair_gain - alone[b]) for a, b in (pair, pair[::-1])}
        return {"member_heldout_gain": own,
                "members_earn_their_place": bool(min(own.values()) >= MIN_HELDOUT_GAIN)}

    # -- physics no candidate lists (issue 26, items 3-4) ---------------------------------------------
    def _shape_selection(self, ev: Evaluator, cur: FitResult, step: int,
                         shapes: dict | None = None) -> force_shape.Selection | None:
        """What the missing force left by ``cur`` depends on (:mod:`.force_shape`: the model's corner states
        and, beside them, the input features). Records what the regression saw in ``force_shape_``; None
        when fewer than two drives have rows. ``shapes``: shape values the library's features are offered at
        only (:func:`.force_shape.design_for`)."""
        # proposed against the file's values, and when nothing is stable there against the calibration as
        # fitted with its far shifts undone (item 4); the joint fit then weighs calibration and learned force
        st = cur.structure
        against = "file_values"
        design = force_shape.design_for(self, st, st.at_neutral(cur.x, CALIBRATION), cur.idx, shapes=shapes)
        sel = force_shape.select(design)
        if sel is not None and not sel.stable and CALIBRATION in st.names:
            against = "calibration_within_priors"
            design = force_shape.design_for(self, st, self._without_far_shifts(cur), cur.idx, shapes=shapes)
            sel = force_shape.select(design)
        self.shape_design_ = design   # the regression the selection read: the input check's state reading
        if sel is None:
            return None
        phys = sel.physics()
        self.force_shape_.append({
            "step": step, "read_against": against, "resamples": sel.resamples,
            "selection_frequency": {f"{k[0]}:{k[1]}": q for k, q in sorted(sel.frequency.items())},
            "law_frequency": {f"{k[0]}:{k[1]}": q for k, q in sorted(sel.law_frequency.items())},
            "stable": [f"{c.feature}:{c.axle}" for c in sel.stable],
            "stable_by_law": [f"{k[0]}:{k[1]}" for k in sel.by_law], "dependences": sel.dependences,
            "description": sel.description() if sel.stable else "", "listed_rivals": phys.listed_rivals(),
            "input_led": sel.input_led})
        return sel

    def _without_far_shifts(self, fit: FitResult) -> np.ndarray:
        """``fit.x`` with every calibrated value further than :data:`SHIFT_SD` prior sd from its prior set
        back to the prior: the shape regression's second look when nothing is stable against the file's
        values. Within its prior a calibrated value is the car (at the file's values the regression sees
        every difference of this car from the file too: springs, bars, masses, which can hide a force such
        as a velocity-weakening friction); far beyond it, a hypothesis that may have taken up what physics
        explains (a blown-off damper valve taken as intact dampers 25 % weaker, 5 prior sd), which the
        regression must see."""
        x = np.array(fit.x, float, copy=True)
        for j, p, _ in self._far_shifts(fit):
            x[j] = p.prior
        return x

    def _state_reading(self, sel: force_shape.Selection) -> tuple[force_shape.Selection | None, list[int]]:
        """The states' reading of a missing force led by an input feature (``sel``), and the drives on which
        that input is silent (its column zero on the axles it leads: a sine steer on a flat road for the road
        height; a drive that lacks its road is not one of them), as indices of the finder's drives. The
        reading is the stability selection of the same regression without the input features
        (:func:`.force_shape.without_inputs`): a law of the states that the road excites (a spring of a law no
        feature has) lets the road height lead on the drives that carry a road, while the same law acts
        wherever the states move. ``(None, silent)`` when no drive is silent to the input (the wheel's
        rotation acts on every drive: nothing tells a state from it) or nothing of the states is stable."""
        design = self.shape_design_
        lead = force_shape.group_of(sel.leading or "")
        axles = _lead_axles(sel)
        cols = [j for j, c in enumerate(design.columns) if force_shape.group_of(c.feature) == lead and c.axle in axles]
        # a drive that lacks its road is not one the road does not reach: its road is unknown, not flat
        known = (lambda g: has_road_input(self.cases_[g])) if sel.input_kind == "road" else (lambda g: True)
        reached = _drives_reached(design, cols)
        silent = [int(g) for g in np.unique(design.groups) if known(int(g)) and int(g) not in reached]
        if not silent:
            return None, []
        state = force_shape.select(force_shape.without_inputs(design))
        offered = None
        if state is None or not state.stable:
            state = offered = self._spring_where_road_leads_one_axle(sel, 0 if state is None else state.resamples)
            if state is None:
                return None, silent
        self.force_shape_[-1]["state_reading"] = {   # this step's record (_shape_selection)
            "input_feature": sel.leading, "dependences": state.dependences,
            "stable": [f"{c.feature}:{c.axle}" for c in state.stable],
            "description": state.description(), "input_silent_drives": [self.cases_[g].name for g in silent],
            **({"spring_offered_on_axle": offered.stable[0].axle} if offered is not None else {})}
        return state, silent

    def _spring_where_road_leads_one_axle(self, sel: force_shape.Selection,
                                          resamples: int) -> force_shape.Selection | None:
        """Where the recorded road leads ``sel`` on one axle only (:meth:`_road_on_one_axle`: no road recorded
        off, which would show at both) and no reading of the states is stable, a spring of that axle for the
        fit to test (:func:`.force_shape.spring_on_axle`; ``fit.spring_where_road_leads_one_axle`` in
        ``config/force_shape.yaml``): a law of the states the road excites there and no feature has (a gas
        charge's even part over a bump, ``gas/polytropic_charge_rear``: the road height under the rear wheels
        led, nothing of the states was stable, and nothing was named). It is tested as the states' reading is
        (:meth:`_states_explain_silent`). None when off, or the road leads on both axles or on drives without
        their road."""
        if not force_shape.settings()["fit.spring_where_road_leads_one_axle"]:
            return None
        one = self._road_on_one_axle(sel, _lead_axles(sel))
        return None if one is None else force_shape.spring_on_axle(self.shape_design_, one["axle"], resamples)

    def _states_explain_silent(self, ev: Evaluator, cur: FitResult, new: FitResult, silent: list[int], ok: bool,
                               checks: dict) -> bool:
        """Whether the trial ``cur`` -> ``new`` of an input-led step stands as physics: it passed every test
        (``ok``) and it predicts the drives the input does not reach (``silent``) held out, each refitted
        without it as in :meth:`_heldout_check`, by :data:`MIN_HELDOUT_GAIN` of their excess over noise: a
        law of the states acts wherever they move, a road only where it is. On a road recorded wrong
        (the family's ``road/bump_recorded_low``) the held-out test of every trial refused the states'
        reading, while the drives the road does not reach did not tell (the calibration, compromised by
        the road error, leaves a residual there that a refit takes up): this is a condition beside the
        tests, not instead of them. The figures join ``checks`` and the step's ``state_reading``, with the
        terms the trial ``added`` and, where the learned term is one, its ``fitted_dependences`` (the form the
        competition of :meth:`_law_members_compete` kept, which may differ from the reading's)."""
        folds = [self._fold_pair(ev, cur, new, list(new.idx).index(g)) for g in silent if g in new.idx]
        sq_old = sum(f[0] for f in folds)
        n_held = sum(f[4] for f in folds)
        gain = (sq_old - sum(f[2] for f in folds)) / max(sq_old - n_held, 1e-12)
        explains = bool(ok and folds and gain >= MIN_HELDOUT_GAIN)
        weighed = {"input_silent_heldout_gain": float(gain), "states_explain_input_silent_drives": explains}
        checks.update(weighed)
        record = self.force_shape_[-1]["state_reading"]   # this step's (_state_reading)
        added = [n for n in new.structure.names if n not in cur.structure.names]
        record.update(weighed, added=added)
        if force_shape.TERM in added and self.learned_selection_ is not None:
            # the law as fitted: the competition of a law family's members may have kept another form
            record["fitted_dependences"] = self.learned_selection_.dependences
        if explains:
            self.input_weighed_.append(record)
        return explains

    def _input_finding(self, ev: Evaluator, sel: force_shape.Selection, step: int) -> bool:
        """An ``unmeasured_input`` finding per drive from a selection led by an input feature: the missing
        force follows the road under the wheel or the wheel's rotation, which the recording lacks. A drive
        that carries its road and whose force follows that road says what else it can be: the road as
        recorded may be off, or a law of the states that the road excites and no feature describes is
        missing (a spring of another law over a bump); the same road at another speed tells them apart
        (``road_recorded``, said once in the verdict's reason: :data:`.report.ROAD_RECORDED`).

        Except where the recorded road leads on one axle only (:meth:`_road_on_one_axle`): both axles roll
        over the same recorded track, so a road recorded off would show at both; what follows it on one
        axle is a law of the states there that the road excites (recorded in ``road_one_axle_`` and the
        step's ``road_one_axle``; the verdict's reason says so). Returns whether a finding was made."""
        lead = sel.leading
        assert lead is not None
        ks = [k for k, c in enumerate(sel.stable) if force_shape.group_of(c.feature) == force_shape.group_of(lead)]
        axles = _lead_axles(sel)
        one = self._road_on_one_axle(sel, axles)
        if one is not None:
            self.force_shape_[-1]["road_one_axle"] = one   # this step's record (_shape_selection)
            self.road_one_axle_.append(one)
            return False
        freq = max(sel.frequency[force_shape.group_key(sel.stable[k].key)] for k in ks)
        words = force_shape.WORDS[lead]
        self.input_led_ = True
        for c in ev.cases:
            self.unmeasured_.append({
                "kind": sel.input_kind, "drive": c.name, "signals": list(c.signals), "feature": lead,
                "axles": axles, "step": step, "selection_frequency": freq,
                "statement": (f"{c.name}: the force the model lacks {words} ({', '.join(axles)} "
                              f"{'axle' if len(axles) == 1 else 'axles'}, selected in {100 * freq:.0f} % of drive "
                              f"resamples): an input the recording lacks, not physics of the model's states; "
                              f"no physics term is named for it"),
                "road_recorded": sel.input_kind == "road" and has_road_input(c)})
        return True

    def _road_on_one_axle(self, sel: force_shape.Selection, axles: list[str]) -> dict | None:
        """Whether a road-led selection (``sel``, its lead stable on ``axles``) follows the recorded road on one
        axle only, every drive its road column acts on carrying its road: then ``{input_feature, axle,
        drives}``, else None. Front and rear wheels of a side roll over the same recorded track (the rear
        a wheelbase later), so a road recorded off (a profilometer's gain, another wheel track) changes the
        input of both axles alike, and a recording that lacks its road lacks it under both."""
        if sel.input_kind != "road" or len(axles) != 1:
            return None
        design = self.shape_design_
        lead = force_shape.group_of(sel.leading or "")
        acting = _drives_reached(design, [j for j, c in enumerate(design.columns)
                                          if force_shape.group_of(c.feature) == lead])
        if not acting or not all(has_road_input(self.cases_[g]) for g in acting):
            return None
        return {"input_feature": sel.leading, "axle": axles[0], "drives": [self.cases_[g].name for g in acting]}

    def _learned_trial(self, ev: Evaluator, cur: FitResult,
                       sel: force_shape.Selection) -> tuple[Option, FitResult] | None:
        """The missing force left by ``cur``, read off its shape (``sel``, :meth:`_shape_selection`; input
        features left out), as a learned term fitted on every drive: an extra trial of the forward step,
        tested like every listed candidate (:meth:`_passes`) and competing with them on the criterion.
        None when no state dependence is stable or listed terms stand for every one."""
        sel = sel.physics()
        if not sel.stable or sel.listed_rivals():
            return None   # nothing stable, or listed terms stand for every dependence: they compete already
        fit = self._learned_fit(ev, cur, sel)
        cfg = force_shape.settings()
        if cfg["fit.law_members_compete"]:
            fit, sel = self._law_members_compete(ev, cur, fit, sel)
        if cfg["fit.other_axle_competes"]:
            fit, sel = self._other_axle_competes(ev, cur, fit, sel)
        self.learned_selection_ = sel
        return Option((force_shape.TERM,), math.nan, math.nan, np.zeros(0)), fit

    def _learned_fit(self, ev: Evaluator, cur: FitResult, sel: force_shape.Selection) -> FitResult:
        """``cur`` with the learned term of ``sel`` fitted on every drive, its coefficients started at the
        regression's (its friction law in two stages, a contact spring's progressive part after the plain
        contact)."""
        cand = force_shape.learned_candidate(sel, progressive=False)
        st = cur.structure.with_(cand)
        x0 = st.embed(cur.structure, cur.x)
        a = st.span(cand.name).start
        lo, hi = st.bounds()
        k = len(sel.coef)
        x0[a:a + k] = np.clip(sel.coef, lo[a:a + k], hi[a:a + k])
        fit = self._fit_with_friction_law(ev, st, x0, a, sel)
        if force_shape.spring_law(sel):
            fit = self._with_progressive_part(ev, fit, sel)
        return fit

    def _law_members_compete(self, ev: Evaluator, cur: FitResult, fit: FitResult,
                             sel: force_shape.Selection) -> tuple[FitResult, force_shape.Selection]:
        """The learned trial's fit ``fit`` of ``sel`` against the same term with a dependence of a law family
        replaced by each other member a resample chose (:func:`.force_shape.law_members`: the regression may
        be sure of a force's kind and wrong in its form), each fitted as the first; dependence by dependence in
        the selection's order, each from the best so far, the one the criterion prefers is the trial
        (``fit.law_members_compete`` in ``config/force_shape.yaml``), provided it also predicts the drives
        held out one at a time better (:meth:`_held_out_sums`): a form chosen in sample alone can fit the
        drives at hand by what the model's structure misses on them (an air spring's progressive front read
        as a spring met in rebound: a lower criterion, 1.23 -> 1.64 x the noise held out). What competed is
        recorded in ``force_shape_`` (``law_members``) where anything did."""
        tried = []
        best, best_sel = fit, sel
        for key in force_shape.law_keys(sel):
            start = {c.key for c in best_sel.stable}
            for alt in force_shape.law_members(best_sel, key, self.shape_design_):
                f = self._learned_fit(ev, cur, alt)
                member = next(c for c in alt.stable if c.key not in start)
                entry = {"replaced": f"{key[0]}:{key[1]}", "member": f"{member.feature}:{member.axle}",
                         "bic": f.bic, "rms_x_noise": math.sqrt(f.rss / f.n)}
                better, held = self._preferred(ev, best, f)
                if held is not None:
                    entry.update(heldout_sq_best_so_far=held[0], heldout_sq=held[1])
                if better:
                    best, best_sel = f, alt
                tried.append(entry)
        if tried:
            self.force_shape_[-1]["law_members"] = {
                "first": {"bic": fit.bic, "rms_x_noise": math.sqrt(fit.rss / fit.n)}, "tried": tried,
                "kept": [f"{c.feature}:{c.axle}" for c in best_sel.stable]}
        return best, best_sel

    def _other_axle_competes(self, ev: Evaluator, cur: FitResult, fit: FitResult,
                             sel: force_shape.Selection) -> tuple[FitResult, force_shape.Selection]:
        """The learned trial's fit ``fit`` of ``sel`` against the same term with its law-family dependences
        also on the other axle (:func:`.force_shape.other_axle`), fitted as the first; that one is the trial
        when the criterion prefers it and it also predicts the drives held out one at a time better
        (:meth:`_held_out_sums`), as in :meth:`_law_members_compete` (``fit.other_axle_competes`` in
        ``config/force_shape.yaml``). Recorded in ``force_shape_`` (``other_axle``) where it was offered."""
        alt = force_shape.other_axle(sel, self.shape_design_)
        if alt is None:
            return fit, sel
        f = self._learned_fit(ev, cur, alt)
        have = {c.key for c in sel.stable}
        entry = {"added": [f"{c.feature}:{c.axle}" for c in alt.stable if c.key not in have],
                 "first": {"bic": fit.bic, "rms_x_noise": math.sqrt(fit.rss / fit.n)},
                 "bic": f.bic, "rms_x_noise": math.sqrt(f.rss / f.n), "kept": False}
        better, held = self._preferred(ev, fit, f)
        if held is not None:
            entry.update(heldout_sq_first=held[0], heldout_sq=held[1])
        if better:
            fit, sel = f, alt
            entry["kept"] = True
        self.force_shape_[-1]["other_axle"] = entry
        return fit, sel

    def _preferred(self, ev: Evaluator, best: FitResult, f: FitResult) -> tuple[bool, tuple[float, float] | None]:
        """Whether the learned trial's fit ``f`` replaces ``best``: a lower criterion and, where drives can be
        held out, a smaller sum over the drives held out one at a time (:meth:`_held_out_sums`, returned for
        the record; None when not computed)."""
        if f.bic >= best.bic:
            return False, None
        held = self._held_out_sums(ev, best, f)
        return held is None or held[1] < held[0], held

    def _learned_words(self, name: str) -> dict:
        """A learned term's dependences and description for its ``accepted`` entry (none for another term)."""
        sel = self.learned_selection_ if name == force_shape.TERM else None
        return {"dependences": sel.dependences, "description": sel.description()} if sel else {}

    def _extendable(self, cur: FitResult) -> bool:
        """Whether the learned term this finder wrote into ``cur`` may be extended at this step
        (:meth:`_extension_trial`): ``fit.extend_learned`` set in ``config/force_shape.yaml``."""
        return bool(self.learnable_ and force_shape.TERM in cur.structure.names
                    and self.learned_selection_ is not None and force_shape.settings()["fit.extend_learned"])

    def _extension_trial(self, ev: Evaluator, cur: FitResult, step: int) -> tuple[Option, FitResult] | None:
        """The learned term of ``cur`` extended by what the missing force it leaves depends on: the same
        regression (:meth:`_shape_selection`) against ``cur`` with the learned term in, its shapes (a contact gap,
        a knee) held at their fitted values since the term has one of each, and the stable dependences it lacks
        added (:func:`.force_shape.extended`: a force of several dependences of which the first regression
        found the strongest). An extra trial of the forward step, tested as every candidate is
        (:meth:`_passes`). None when nothing stable is added, or the residual follows an input (that is the
        first regression's to tell, before any learned term)."""
        old = self.learned_selection_
        assert old is not None
        term = force_shape.TERM
        cand0 = cur.structure.cands[cur.structure.names.index(term)]
        x_term = cur.structure.part(cur.x, term)
        held = {p.name: float(v) for p, v in zip(cand0.params, x_term) if p.shape and p.name in force_shape.HELD_SHAPES}
        sel = self._shape_selection(ev, cur, step, shapes=held)
        if sel is not None and sel.input_led:
            return None
        fitted = x_term[:len(old.stable)]
        merged = force_shape.extended(old, fitted, sel.physics(), self.shape_design_) \
            if sel is not None and sel.stable else None
        how = "stable_dependences"
        if merged is None and force_shape.settings()["fit.other_axle_extends"]:
            merged, how = force_shape.other_axle_extended(old, fitted, self.shape_design_), "other_axle"
        if merged is None:
            return None
        record: dict[str, object] = {
            "dependences": merged.dependences, "how": how, "description": merged.description(),
            "added": [f"{c.feature}:{c.axle}" for c in merged.stable[len(old.stable):]]}
        if sel is not None:
            self.force_shape_[-1]["extends"] = record
        else:
            self.force_shape_.append({"step": step, "extends": record})
        cand = force_shape.learned_candidate(merged, progressive=False)
        st = cur.structure.without(term).with_(cand)
        x0 = st.embed(cur.structure, cur.x)   # every value as fitted, the added ones at the regression's
        labels, had = st.labels(), set(cur.structure.labels())
        lo, hi = st.bounds()
        for c, v in zip(merged.stable, merged.coef):
            j = labels.index((term, c.coefficient))
            if (term, c.coefficient) not in had:
                x0[j] = float(np.clip(v, lo[j], hi[j]))
        fit = fit_structure(ev, st, x0, tuple(range(len(ev.cases))), max_nfev=TRIAL_NFEV)
        if how == "other_axle":   # sized by the fit: the added axle must carry its share of the fitted force
            coef = st.part(fit.x, term)[:len(merged.stable)]
            sized = force_shape.fitted_shares(merged, coef, self.shape_design_, len(old.stable))
            record["fitted_coefficients"] = {f"{c.feature}:{c.axle}": float(v) for c, v in zip(merged.stable, coef)}
            if sized is None:
                record["offered"] = False
                return None
            merged = sized
            record["fitted_shares"] = {f"{c.feature}:{c.axle}": float(q) for c, q in zip(merged.stable, merged.share)}
            record["description"] = merged.description()
        if force_shape.spring_law(merged):
            fit = self._with_progressive_part(ev, fit, merged)
        self.extension_selection_ = merged
        return Option((term,), math.nan, math.nan, np.zeros(0)), fit

    def _amend_learned(self, accepted: list[dict], step: int, share: float, checks: dict) -> None:
        """The learned term's ``accepted`` entry after its extension passed at ``step``: its dependences and
        words the extended term's, the extension's figures under ``extended``."""
        sel = self.extension_selection_
        assert sel is not None   # set by the extension trial that passed
        self.learned_selection_ = sel
        entry = next(a for a in accepted if a["name"] == force_shape.TERM)
        entry.update(dependences=sel.dependences, description=sel.description())
        entry.setdefault("extended", []).append({"step": step, "explained_fraction_of_excess": share, **checks})

    def _with_progressive_part(self, ev: Evaluator, plain: FitResult, sel: force_shape.Selection) -> FitResult:
        """The learned trial's fit ``plain`` (a contact spring without its progressive part) and, from it, the
        fit with the smooth progressive part freed (:func:`force_shape.spring_law`, starting at 0); the one
        the criterion prefers is kept. In two stages, the corner first and its bending second, as the
        friction's weakening: started together, the gap traded against the cube and the fit found another
        basin (a rebound spring beyond 15 mm: 1.12-1.15 -> 1.17-1.22x the noise held out, 2026-11-30).
        Whether the drives held out want the cube is judged once, on the final structure
        (:meth:`_final_progressive_part`), not here: at the step that offers it one drive sizes the cube,
        true or not (a rising-rate linkage's, 2026-12-02).

        With ``fit.contact_square_competes``, the progressive part in the square of each stable contact's depth
        (:data:`.force_shape.CONTACT_SQUARE`) is freed from ``plain`` as well, and from the square from static
        that meets each corner at twice its gap (:func:`.force_shape.square_from_static`), and all compete on the
        criterion: a contact's own stiffening starts at its gap without a jump in rate, which the corner and a
        cube from static read as a jump and a bend (a variable-pitch coil, an elastomer bumper)."""
        forms = [force_shape.CUBE]
        if force_shape.settings()["fit.contact_square_competes"] and force_shape.spring_law(
                sel, force_shape.CONTACT_SQUARE):
            forms.append(force_shape.CONTACT_SQUARE)
        best = plain
        for form in forms:
            cand = force_shape.learned_candidate(sel, progressive=form)
            st = plain.structure.without(cand.name).with_(cand)
            x1 = st.embed(plain.structure, plain.x)   # every value as fitted, the progressive part at neutral
            starts = [x1]
            if form == force_shape.CONTACT_SQUARE:   # and from static (force_shape.square_from_static)
                labels = st.labels()
                own = {name: j for j, (t, name) in enumerate(labels) if t == cand.name}
                moved = force_shape.square_from_static(sel, {name: float(x1[j]) for name, j in own.items()})
                if moved:
                    x2 = x1.copy()
                    for name, v in moved.items():
                        x2[own[name]] = v
                    starts.append(x2)
            for x0 in starts:
                freed = fit_structure(ev, st, x0, tuple(range(len(ev.cases))), max_nfev=TRIAL_NFEV)
                if freed.bic < best.bic:
                    best = freed
        return best

    def _final_progressive_part(self, ev: Evaluator, final: FitResult) -> tuple[FitResult, dict | None]:
        """With ``fit.progressive_part_held_out``: the final structure ``final`` (polished) against the same
        structure with its learned spring's smooth progressive part (:func:`force_shape.spring_law`) left out
        and refitted as the final polish is; the one whose drives held out one at a time, each refitted in
        full without the drive (:meth:`_heldout`), are predicted better is kept, with that held-out figure
        (to be ``heldout_`` without computing it again). Why on the final structure: the cube is informed
        most by the drive with the largest strokes and refitted without it may extrapolate
        (gas/unequal_axle_charges#1: its front-empty bump crossing 0.064 -> 0.089 deg/s held out), but judged
        at the step that offers it, before the rest of the structure and the calibration have moved, it
        refused a true one (unlisted/rising_rate_linkage#1: 1.14 -> 2.20 x the noise held out, 2026-12-02).
        The figures go to ``progressive_part_``. The held-out figure of the kept fit is chosen on, so a
        reader comparing it with a run without the switch should know that it is the lower of two."""
        term, sel = force_shape.TERM, self.learned_selection_
        if (not force_shape.settings()["fit.progressive_part_held_out"] or not self.heldout or sel is None
                or term not in final.structure.names or len(ev.cases) < 2):
            return final, None
        labels = final.structure.labels()
        if not any((term, c.coefficient) in labels for form in (force_shape.CUBE, force_shape.CONTACT_SQUARE)
                   for c in force_shape.spring_law(sel, form)):
            return final, None
        st = final.structure.without(term).with_(force_shape.learned_candidate(sel, progressive=False))
        plain = fit_structure(ev, st, st.embed(final.structure, final.x), tuple(range(len(ev.cases))),
                              max_nfev=FINAL_POLISH_NFEV)
        held_with, held_without = self._heldout(ev, final), self._heldout(ev, plain)
        kept = bool(held_with["after_deg_s"] <= held_without["after_deg_s"])
        self.progressive_part_ = {"dependences": sel.dependences, "heldout_with_deg_s": held_with["after_deg_s"],
                                  "heldout_without_deg_s": held_without["after_deg_s"], "kept": kept}
        return (final, held_with) if kept else (plain, held_without)

    def _fit_with_friction_law(self, ev: Evaluator, st: Structure, x0: np.ndarray, a: int,
                               sel: force_shape.Selection) -> FitResult:
        """The learned trial's fit (term at offset ``a`` of ``st``). With a friction law's velocity weakening
        (:func:`force_shape.friction_law`) in two stages, since a sticking friction's residual is rough in
        its levels: the plain levels (and their growth with the compression) first with the weakening (and a
        creep, where the settings bring one) held at none, then from the fitted level
        split between sliding and rest (``fit.weakening_start_share`` of it at rest); the better fit is kept
        (refitted with every value free when it is the first)."""
        allidx = tuple(range(len(ev.cases)))
        cfg = force_shape.settings()
        cols = force_shape.friction_law(sel, cfg)[0]
        law = [c for c in cols if c.feature == force_shape.WEAKENING]
        labels = st.labels()
        term = force_shape.TERM
        # a creep (where the settings bring one) is held at none with its velocity in the first stage, as the
        # weakening: the plain levels first
        creep = [labels.index((term, c.coefficient)) for c in cols if c.feature == force_shape.CREEP]
        if creep:
            creep.append(labels.index((term, force_shape.CREEP_VELOCITY)))
        if not law and not creep:
            return fit_structure(ev, st, x0, allidx, max_nfev=TRIAL_NFEV)
        weak = [labels.index((term, c.coefficient)) for c in law]
        held = weak + ([labels.index((term, force_shape.STRIBECK_VELOCITY))] if law else []) + creep
        plain = fit_structure(ev, st, x0, allidx, max_nfev=TRIAL_NFEV, fixed=held)
        share = float(cfg["fit.weakening_start_share"])
        x1 = plain.x.copy()
        for c, j in zip(law, weak):
            level = labels.index((term, force_shape.Column("sign_velocity", c.axle).coefficient))
            x1[j] = share * plain.x[level]
            x1[level] = (1.0 - share) * plain.x[level]
        split = fit_structure(ev, st, x1, allidx, max_nfev=TRIAL_NFEV)
        if split.rss <= plain.rss:
            return split
        # without a weakening the second stage started where the first ended: its fit is that refit
        return fit_structure(ev, st, plain.x, allidx, max_nfev=TRIAL_NFEV) if law else plain

    def _backward(self, ev: Evaluator, cur: FitResult, path: list, accepted: list) -> FitResult:
        """Backward elimination after the forward steps: an accepted physics term that a later one made
        redundant (removing it costs less than :data:`MIN_DELTA_BIC`) is dropped, latest-accepted last,
        and the drop is recorded in the selection path. A term accepted in a pair with the dropped one must
        then earn its place alone (:meth:`_partner_alone`)."""
        phys = [c.name for c in cur.structure.cands if c.kind == PHYSICS]
        if len(phys) < 2:
            return cur
        for name in phys:
            if name not in cur.structure.names:
                continue   # dropped as a partner already
            f_wo = _refit_without(ev, cur, [name])
            if f_wo.bic - cur.bic < MIN_DELTA_BIC:
                partners = [a["name"] for a in accepted if a["name"] != name and name in a.get("with", ())]
                _record_drop(path, accepted, cur, f_wo, name, "redundant once the later terms are in (removing it "
                                                              f"costs less than {MIN_DELTA_BIC:.0f} BIC)")
                cur = f_wo
                for partner in partners:
                    cur = self._partner_alone(ev, cur, partner, name, path, accepted)
        return cur

    def _partner_alone(self, ev: Evaluator, cur: FitResult, name: str, dropped: str, path: list,
                       accepted: list) -> FitResult:
        """``cur`` without the physics term ``name`` when, accepted in a pair with ``dropped`` (just removed
        as redundant), it does not earn its place alone: removing it must cost at least :data:`MIN_DELTA_BIC`
        and it must pass the held-out test (:meth:`_heldout_check`) against ``cur`` without it. Its pair's
        tests judged the two together (each member's held-out share beside the other); once one is gone, that
        judgement no longer holds for the other (on the blind ``gas/isothermal_charge_front`` #2 the pair of the
        amplitude friction and an extra damping was accepted, the friction dropped as redundant later, and the
        damping stayed, named for a gas spring). The drop is recorded in the selection path with its figures;
        ``cur`` when it earns its place."""
        f_wo = _refit_without(ev, cur, [name])
        checks = self._heldout_check(ev, f_wo, cur)
        if f_wo.bic - cur.bic >= MIN_DELTA_BIC and checks["passed"]:
            return cur
        _record_drop(path, accepted, cur, f_wo, name, f"accepted in a pair with {dropped} only: alone it does not "
                     f"earn its place (the criterion by {MIN_DELTA_BIC:.0f} BIC and the held-out test)", **checks)
        return f_wo

    def _measurement_terms(self, ev: Evaluator) -> list[str]:
        """The measurement-chain candidates the drives can show: sensor bias and time offset, and the
        steering offset where a drive steers."""
        meas: list[str] = [n for n in ("sensor_bias", "time_offset") if n in self.candidates]
        if _steers(ev.cases) and "steering_offset" in self.candidates:
            meas.append("steering_offset")
        return meas

    def _measurement_chain(self, ev: Evaluator, cur: FitResult, path: list) -> FitResult:
        """The measurement-chain terms (sensor bias, time offset, steering offset) decided again on the
        model with its physics terms: at the calibration the criterion weighs a term's gain against a
        residual the missing physics still dominates (BIC on ``log(rss)``), so a sensor bias of one
        drive, worth its parameters on the final model, could not pay for itself there. A term is added
        when it lowers the criterion by :data:`MIN_DELTA_BIC`; the step is recorded in the path."""
        allidx = tuple(range(len(ev.cases)))
        n = cur.n
        for name in self._measurement_terms(ev):
            if name in cur.structure.names:
                continue
            st = cur.structure.with_(name)
            f = fit_structure(ev, st, st.embed(cur.structure, cur.x), allidx, max_nfev=TRIAL_NFEV)
            if cur.bic - f.bic >= MIN_DELTA_BIC:
                path.append({"step": len(path), "added": [name], "structure": list(st.names), "rss": f.rss,
                             "bic": f.bic, "delta_bic": cur.bic - f.bic,
                             "explained_fraction_of_excess": (cur.rss - f.rss) / max(cur.rss - n, 1e-12),
                             "rms_x_noise": math.sqrt(f.rss / n), "accepted": True,
                             "why": "measurement chain decided again on the model with its physics terms"})
                cur = f
        return cur

    def ci95_(self) -> tuple[np.ndarray, np.ndarray]:
        """95 % intervals of the final parameters: the Gauss-Newton posterior's, widened to the
        leave-one-drive-out (jackknife) spread of the refits where that is larger. The jackknife sees what
        per-sample statistics cannot: drives that pull a parameter apart because the model's structure
        differs from the car's."""
        return self._ci95(self.result_)

    def _ci95(self, fit: FitResult, consider: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """As :meth:`ci95_`; ``consider`` False leaves out what the held values add (the data alone)."""
        if fit is not getattr(self, "result_", None):
            return fit.ci95()
        lo, hi = fit.ci95(getattr(self, "prior_scale_", 1.0))
        se = (hi - lo) / (2 * 1.96)
        cons = getattr(self, "consider_se_", None) if consider else None
        if cons is not None and len(cons) == len(fit.x):
            se = np.sqrt(se ** 2 + cons ** 2)
        jk = getattr(self, "jackknife_se_", None)
        if jk is not None and len(jk) == len(fit.x):
            se = np.maximum(se, jk)
        return fit.x - 1.96 * se, fit.x + 1.96 * se

    def _consider_se(self, ev: Evaluator, fit: FitResult) -> np.ndarray | None:
        """Standard errors the final parameters inherit from the values held at their file value: the
        vehicle file's uncalibrated ranges (:func:`~.calibration.consider_params`) and the calibration
        values the drives do not inform (:func:`~.calibration.consider_covariance`): one batch of
        simulations with each of them stepped by a tenth of its standard deviation. This is what lets a
        calibrated value's interval include the truth when the data pin it only through an assumed value
        (the unsprung masses, the tyre damping, a friction level the drives do not inform, ...)."""
        self.consider_contrib_ = np.zeros((len(fit.x), 0))
        self.consider_sd_ = np.zeros((len(fit.x), 0))  # S x sd: each parameter's shift per held value's sd
        self.consider_jac_ = np.zeros((0, 0))  # the whitened residual's Jacobian in the held values
        self.consider_prior_sd_ = np.zeros(0)
        self.consider_names_: list[str] = []   # PARAM:where, as in the calibration table
        self.consider_keys_: list[str] = []    # the vehicle file's key of each
        if not self.calibrate or fit.jac is None or not len(fit.x):
            return None
        cons = self._held_values()
        if not cons:
            return None
        st = fit.structure
        st2, x2, at = self._with_held_values(st, fit.x, cons)
        sd = np.array([p.sd for p in cons])
        h = STEP_OF_SD * sd
        X = np.repeat(x2[None], len(cons) + 1, axis=0)
        X[1 + np.arange(len(cons)), at + np.arange(len(cons))] += h
        R = raw_residuals(ev, st2, X, fit.idx)
        Jc = ((R[1:] - R[0]) / h[:, None]).T
        if st.bias:
            Jc = debias(ev, Jc, fit.idx)
        S = consider_sensitivity(fit.jac, fit.information(), Jc, fit.data_information_scale())
        self.consider_sd_ = S * sd[None, :]
        self.consider_jac_, self.consider_prior_sd_ = Jc, sd
        self.consider_contrib_ = self.consider_sd_ ** 2
        self.consider_names_ = [f"{p.field}:{p.where}" for p in cons]
        self.consider_keys_ = [p.key if p.where == "all" else f"{p.key} ({p.where})" for p in cons]
        return np.sqrt(np.clip(self.consider_contrib_.sum(axis=1), 0, None))

    # -- signals ------------------------------------------------------------------------------------
    def _case_sigma(self, c: DriveCase) -> np.ndarray:
        """Noise sigma of each of the drive's signals (plus, on a drive with an unmeasured road, the road's
        share of its handling signals; :mod:`.unmeasured`)."""
        per = self.noise_["per_drive"][c.name]
        pooled = self.noise_["noise_floors"]
        extra: dict[str, float]  # signal -> variance the unmeasured road adds [native units^2]
        extra = next((u.get("extra_noise_variance", {}) for u in getattr(self, "unmeasured_", [])
                      if u["drive"] == c.name), {})
        return np.array([math.sqrt((per[s] if math.isfinite(per[s]) and per[s] > 0 else pooled[s]) ** 2
                                   + extra.get(s, 0.0)) for s in c.signals])

    def _choose_signals(self, ev: Evaluator, sims: np.ndarray) -> list[dict]:
        """Narrow every drive to the signals it excites (measured spread above :data:`EXCITED_RATIO` x
        noise; the maneuver's primary gyro signal always); drop the signals an unmeasured road drives."""
        found = []
        for r, c in enumerate(ev.cases):
            per = self.noise_["per_drive"][c.name]
            keep = []
            for j, sig in enumerate(c.signals):
                spread = float(np.std(c.y_meas[:, j]))
                if sig in primary_signals(c.maneuver) or spread > EXCITED_RATIO * per.get(sig, math.inf):
                    keep.append(sig)
            if not has_road_input(c):
                resid = ev.case_residual(r, sims[r], 0.0, False)
                hit = detect_unmeasured_road(c, resid, per, self.model_)
                if hit is not None:
                    self._estimate_road(c, resid, per, hit)
                    found.append(hit)
                    keep = [s for s in keep if s not in hit["signals"]]
            if not keep:
                keep = [s for s in GYRO if s in c.signals][:1]
            select_signals(c, keep)
        return found

    def _estimate_road(self, c: DriveCase, resid: np.ndarray, per: dict, hit: dict) -> None:
        """The road of an ``unmeasured_input`` drive estimated from its body motion
        (:mod:`.road_estimate`) into ``estimated_roads_``, its usability figures into ``hit``."""
        gd = hit.get("gd_n0_m3")
        if not gd:
            return
        est = estimate_road(c, resid, per, self.model_, gd)
        cross = (estimate_road(c, resid, per, self.model_, gd, signals=GYRO_VERTICAL)
                 if set(est.signals) - set(GYRO_VERTICAL) and set(GYRO_VERTICAL) <= set(est.signals) else None)
        self.estimated_roads_[c.name] = est.road
        hit["road_estimate"] = {"estimated_from": list(est.signals), "band_hz": list(est.band_hz),
                                "path_m": [float(est.road.s[0]), float(est.road.s[-1])],
                                "rms_m": {"left": float(np.std(est.road.zl)), "right": float(np.std(est.road.zr))},
                                **road_usability(c, self.model_, est, resid, cross)}

    # -- calibration --------------------------------------------------------------------------------
    def _calibrate(self, ev: Evaluator, model: Model) -> FitResult:
        """MAP calibration of the base model with the measurement chain; identifiability; the
        measurement-chain terms kept only where the criterion wants them. Sets ``calibration_``."""
        allidx = tuple(range(len(ev.cases)))
        meas = self._measurement_terms(ev)
        params = calibration_params(model.vehicle, model.variant) if self.calibrate else []
        self.wheel_loads_ = None
        if self.wheel_loads_n is not None and self.scale_accuracy is not None:  # both or neither (__init__)
            params, self.wheel_loads_ = sprung_mass_from_wheel_loads(params, self.wheel_loads_n, model.vehicle.gravity,
                                                                     self.scale_accuracy)
        self.calibration_params_ = params
        self.calibrated_vehicle_, self.calibrated_fields_, self.informed_ = model.vehicle, [], []
        if not params and not meas:
            self.calibration_, self.identifiability_ = [], None
            learn_residual_correlation(ev, fit_structure(ev, Structure([])))
            return fit_structure(ev, Structure([]))
        cand = calibration_candidate(model, params) if params else None
        st = Structure([cand, *meas] if cand else meas)
        fit1 = fit_structure(ev, st, st.neutral(), allidx, max_nfev=12)
        # every criterion from here on counts the samples the calibrated misfit leaves independent
        learn_residual_correlation(ev, fit1)
        ne = n_effective(ev, allidx)
        fit1 = dataclasses.replace(fit1, n_eff=ne, bic=bic(fit1.rss, fit1.n, fit1.k_bic, ne))
        ident, informed = None, []
        if params:
            k = len(params)
            assert fit1.jac is not None  # free parameters: fit_structure returns the Jacobian
            ident = identifiability(fit1.jac[:, :k], params, fit1.data_information_scale())
            informed = [p for p, ok in zip(params, ident["informed"]) if ok]
        self.identifiability_ = ident
        cand2 = calibration_candidate(model, informed) if informed else None
        st2 = Structure([cand2, *meas] if cand2 else meas)
        x0 = st2.neutral()
        if cand2:
            first = {p.name: v for p, v in zip(params, fit1.x[:len(params)])}
            x0[:len(informed)] = [first[p.name] for p in informed]
        for name in meas:
            if st.part(fit1.x, name).size:
                st2.part(x0, name)[:] = st.part(fit1.x, name)
        cur = fit_structure(ev, st2, x0, allidx, max_nfev=20)
        if cand2 and len(ev.cases) >= 2:
            w, scores = self._data_weight(cur)
            if ident is not None:
                ident["data_weight"] = w
                ident["data_weight_heldout_rss"] = scores
            if w < 1.0:
                st2 = Structure(st2.cands, w)
                cur = fit_structure(ev, st2, cur.x, allidx, max_nfev=20)
        # measurement-chain terms only where they pay for themselves
        for name in meas:
            if name not in cur.structure.names:
                continue
            f_wo = _refit_without(ev, cur, [name], max_nfev=10)
            if cur.bic - f_wo.bic > -MIN_DELTA_BIC:
                cur = f_wo
        self.informed_ = informed
        self._set_calibration(cur)
        return cur

    def _recalibrate(self, ev: Evaluator, cur: FitResult) -> FitResult:
        """The current structure with every value the vehicle file gives a range refitted within its prior
        (the calibration's informed values and the held ones, :meth:`_held_values`: tyre damping, roll
        centres, ...): the most a recalibration of the known physics
        can explain. A candidate term is named only when it explains more than this (its fit's residual
        is below this one's): "no recalibration within the priors explains the same residual"."""
        if not self.calibrate:
            return cur
        extra = self._held_values()
        if not extra:
            return cur
        st2, x2, _ = self._with_held_values(cur.structure, cur.x, extra)
        return fit_structure(ev, st2, x2, tuple(range(len(ev.cases))), max_nfev=RECALIBRATION_NFEV)

    def _held_values(self) -> list[CalParam]:
        """The ranged values the calibration holds at their file value: the calibration values the drives
        do not inform and the vehicle file's uncalibrated ranges (:func:`~.calibration.consider_params`:
        unsprung masses, tyre damping, roll centres, ...)."""
        informed = {p.name for p in self.informed_}
        return ([p for p in self.calibration_params_ if p.name not in informed]
                + consider_params(self.model_.vehicle, self.model_.variant))

    def _with_held_values(self, st: Structure, x: np.ndarray,
                          held: Sequence[CalParam]) -> tuple[Structure, np.ndarray, int]:
        """Structure ``st`` (parameters ``x``) with its calibration widened by the ``held`` values after the
        informed ones, at their file values: the widened structure, its parameters and the index of the
        first held value."""
        cal = calibration_candidate(self.model_, list(self.informed_) + list(held))
        has_cal = CALIBRATION in st.names
        st2 = Structure([cal if c.name == CALIBRATION else c for c in st.cands] if has_cal else [cal, *st.cands],
                        st.data_weight)
        x2 = np.concatenate([np.concatenate([st.part(x, CALIBRATION) if has_cal else np.zeros(0),
                                             [p.prior for p in held]]) if n == CALIBRATION else st.part(x, n)
                             for n in st2.names])
        return st2, x2, st2.span(CALIBRATION).start + len(self.informed_)

    def _data_weight(self, fit: FitResult) -> tuple[float, dict]:
        """How much the drives may pull the calibration away from its priors, chosen by leave-one-drive-
        out (empirical Bayes by cross-validation): for each weight of the data against the priors in
        :data:`DATA_WEIGHTS` the calibration is refitted without each drive (Gauss-Newton step at
        ``fit``, no further simulation) and predicts it. The largest weight within
        :data:`WEIGHT_TOLERANCE` of the best held-out residual wins. Weight 1 trusts the data as their
        noise says; a smaller weight means the calibration followed structure the model lacks (a missing
        friction term absorbed by mass, stiffness or damper factors), which then stays in the residual
        for the discovery stage. Intervals widen with it (the data count less). Calibration values only
        the held-out drive informs keep their joint value in its fold (:func:`_informed_only_by`)."""
        J, r = fit.jac, fit.residual
        assert J is not None  # a calibration with free parameters: fit_structure returns the Jacobian
        scores = {}
        for w in DATA_WEIGHTS:
            sq = 0.0
            for h in range(len(fit.idx)):
                held = _drive_rows(self.evaluator_, fit, h)
                ne_t = max(fit.n_eff * (~held).sum() / len(r), 1.0)
                d = _fold_step(fit, held, math.sqrt((~held).sum() / ne_t / w))
                e = r[held] + J[held] @ d
                sq += float(e @ e)
            scores[w] = sq
        best = min(scores.values())
        w = next(w for w in DATA_WEIGHTS if scores[w] <= best * (1.0 + WEIGHT_TOLERANCE))
        return w, {str(k): v for k, v in scores.items()}

    def _set_calibration(self, fit: FitResult) -> None:
        """The calibration table and calibrated vehicle from ``fit`` (the calibration stage, and again
        the final joint fit with the found terms, whose values are the ones reported)."""
        params, informed = self.calibration_params_, self.informed_
        vals = {}
        if informed and CALIBRATION in fit.structure.names:
            a = fit.structure.span(CALIBRATION).start
            lo, hi = self._ci95(fit)
            vals = {p.name: (fit.x[a + j], lo[a + j], hi[a + j]) for j, p in enumerate(informed)}
        x_all = np.array([vals.get(p.name, (p.prior,))[0] for p in params])
        lo_all = np.array([vals.get(p.name, (0, -math.inf))[1] for p in params])
        hi_all = np.array([vals.get(p.name, (0, 0, math.inf))[2] for p in params])
        self.calibration_ = calibration_entries(params, x_all, lo_all, hi_all, [p.name in vals for p in params])
        self.calibrated_vehicle_ = vehicle_at(self.model_.vehicle, informed, [vals[p.name][0] for p in informed])
        self.calibrated_fields_ = sorted({p.field for p in informed})

    # -- proof --------------------------------------------------------------------------------------
    @staticmethod
    def _decoy_check(ev: Evaluator, before: FitResult, after: FitResult) -> dict:
        """The term that took ``before`` to ``after`` against its decoys (:mod:`.decoys`: its own effect
        time-reversed and circularly shifted, scaled to the residual): ``decoys_beaten`` when its criterion
        beats the best decoy's by :data:`MIN_DELTA_BIC`."""
        blocks, o = [], 0
        for r in before.idx:
            n, s = ev.cases[r].y_meas.shape
            blocks.append((o, n, s))
            o += n * s
        d = decoy_margin(before.residual, after.residual, after.n_eff, blocks)
        return {**d, "decoys_beaten": bool(d["decoy_margin"] >= MIN_DELTA_BIC)}

    def _heldout_check(self, ev: Evaluator, cur: FitResult, new: FitResult) -> dict:
        """Leave-one-drive-out of the new term(s), linearised (no further simulation): for each drive,
        the current structure and the structure with the new term are each refitted on the other drives
        (a Gauss-Newton step from its own joint fit, ``cur`` and ``new``, with the calibration's priors,
        within bounds) and predict the held-out drive. Each structure is linearised at its own optimum:
        removing a term by a linear step from ``new`` would misjudge terms whose shape parameters act only
        through their level (the onset of amplitude friction). The held-out drives' whitened residual must
        drop by :data:`MIN_HELDOUT_GAIN` of its excess over noise, and the term must pass the criterion on
        the training drives in at least :data:`MIN_STABLE` of the folds. With a single drive there is
        nothing to hold out: the in-sample criterion decides.

        Both structures hold the same calibration values at their joint fits' values in a fold: those the
        held-out drive informs (:func:`_informed_only_by`) in either of them (:func:`_held_in_both`).
        Which values the other drives can tell depends on the structure (a term that explains what the
        oil-empty front damper's factor and the front wheel rate took up in the bump crossing frees them
        to be told by the other drives), so each structure's own set would hold different values at what
        the held-out drive itself says: the structure that holds more of them is judged partly in sample
        (a viscoelastic bushing's learned force lost to the calibration alone held out, -0.5 % gain, while
        it halved the front-empty bump crossing's residual in the joint fit; with one set 31 %)."""
        R = len(ev.cases)
        if R < 2 or new.jac is None:
            return {"passed": True, "heldout": "single drive: in-sample criterion only"}
        k_new = len(new.x) - len(cur.x)
        folds = self._folds(ev, cur, new)
        sq_old, sq_new, n_held = (sum(f[i] for f in folds) for i in (0, 2, 4))
        n_sel = 0
        for _, old_t, _, new_t, n_h in folds:
            ne_t = max(new.n_eff * (len(new.residual) - n_h) / len(new.residual), 1.0)
            d_bic = ne_t * math.log(max(old_t, 1e-300) / max(new_t, 1e-300)) - k_new * math.log(ne_t)
            n_sel += int(d_bic >= MIN_DELTA_BIC)
        excess = max(sq_old - n_held, 1e-12)
        gain = (sq_old - sq_new) / excess
        stable = n_sel / R
        return {"passed": bool(gain >= MIN_HELDOUT_GAIN and stable >= MIN_STABLE),
                "heldout_gain_fraction_of_excess": float(gain), "selected_in_fraction_of_refits": float(stable)}

    def _held_out_sums(self, ev: Evaluator, a: FitResult, b: FitResult) -> tuple[float, float] | None:
        """The squared whitened residuals of the drives held out one at a time, ``a``'s and ``b``'s, each
        refitted on the others as :meth:`_heldout_check` does (:meth:`_fold_pair`, linearised at its own
        fit, the same values held in both); None with one drive, or a fit without free values: nothing to
        hold out, the in-sample criterion decides."""
        if len(ev.cases) < 2 or a.jac is None or b.jac is None:
            return None
        folds = self._folds(ev, a, b)
        return sum(f[0] for f in folds), sum(f[2] for f in folds)

    def _folds(self, ev: Evaluator, cur: FitResult, new: FitResult) -> list[tuple[float, float, float, float, int]]:
        """:meth:`_fold_pair` for every drive held out in turn."""
        return [self._fold_pair(ev, cur, new, h) for h in range(len(ev.cases))]

    @staticmethod
    def _fold_pair(ev: Evaluator, cur: FitResult, new: FitResult, h: int) -> tuple[float, float, float, float, int]:
        """Drive ``h`` (position in ``new.idx``) held out of both structures, each refitted on the others with
        the same values held (:func:`_held_in_both`): ``(old held, old training, new held, new training,
        held rows)``, squared whitened residuals."""
        held = _drive_rows(ev, new, h)
        fix_old, fix_new = _held_in_both(cur, new, held)
        old_h, old_t = _fold_refit(cur, held, fix_old)
        new_h, new_t = _fold_refit(new, held, fix_new)
        return old_h, old_t, new_h, new_t, int(held.sum())

    def _per_drive_rmse(self, ev: Evaluator, f: FitResult) -> dict:
        """Per drive, the RMSE of its primary gyro signal(s) [deg/s] at ``f``."""
        res = ev.case_residuals(f.structure, f.x, f.idx)
        return {ev.cases[r].name: _primary_rmse(ev.cases[r], e) for r, e in res.items()}

    def _heldout(self, ev: Evaluator, final: FitResult) -> dict:
        """Leave-one-drive-out: the final structure (calibration included) refitted without each drive
        predicts it; against the base model. Per signal and for the primary gyro signals [deg/s].

        Calibration values that only the held-out drive informs, or that it carries most of
        (:func:`_informed_only_by`: the oil-empty damper of the only drive with that axle empty) no other
        drive can predict. They keep the joint fit's value while the others are refitted without the
        drive, and are then calibrated
        on the held-out drive with every other value at the fold's (the drive's own calibration, as its
        sensor bias is; :func:`_recalibrate_on_drive`): the fold is judged as a user would run it on a
        new drive, not with a joint value fitted next to other values than the fold's. Each fold keeps
        the training values (``params``), the values calibrated on the drive (``calibrated_on_drive``)
        and its RMSE with the joint values instead (``rmse_after_joint_values_deg_s``; pooled:
        ``after_joint_values_deg_s``).

        With ``heldout.fold_prior_from_other_drives`` (``config/discrepancy.yaml``) no value is held: every
        fold refits all values on the other drives, then calibrates every calibration value on the held-out
        drive with what the other drives tell of it as its prior (:func:`_fold_prior`), the Bayesian update
        of the fold's posterior by the new drive. A value the other drives pin stays at the fold's value, one
        they do not tell is the drive's own calibration within its prior, and the values between are
        weighed as they are informed: no share at which the rule jumps (:data:`HELD_SHARE`). A fold's
        ``rmse_after_joint_values_deg_s`` is then its RMSE at the fold's values before that calibration."""
        R = len(ev.cases)
        if R == 1:
            return self._heldout_halves(ev, final)
        update = bool(load_settings("discrepancy.yaml")["heldout.fold_prior_from_other_drives"])
        folds = []
        labels = final.structure.labels()
        before_sig: dict[str, list] = {}
        after_sig: dict[str, list] = {}
        prim_b = prim_a = prim_j = prim_n = 0.0
        for h in range(R):
            train = tuple(r for r in range(R) if r != h)
            prior = None
            if final.structure.n_params and train:
                held = _drive_rows(ev, final, h)
                if update:
                    x = fit_structure(ev, final.structure, final.x, train, max_nfev=HELDOUT_NFEV).x
                    own, prior = _fold_prior(final, held, x)
                else:
                    own = _informed_only_by(final, held)
                    x = fit_structure(ev, final.structure, final.x, train, max_nfev=HELDOUT_NFEV, fixed=own).x
            else:
                x, own = final.x, []
            x_pred = _recalibrate_on_drive(ev, final.structure, x, h, own, prior)
            e_after = ev.case_residuals(final.structure, x_pred, [h])[h]
            e_joint = ev.case_residuals(final.structure, x, [h])[h] if own else e_after
            e_before = self.base_residuals_[h]
            c = ev.cases[h]
            for j, sig in enumerate(c.signals):
                before_sig.setdefault(sig, []).append((float(np.sum(e_before[:, j] ** 2)), e_before.shape[0]))
                after_sig.setdefault(sig, []).append((float(np.sum(e_after[:, j] ** 2)), e_after.shape[0]))
            pj = [j for j, s in enumerate(c.signals) if s in primary_signals(c.maneuver)]
            if pj:
                prim_b += float(np.sum(e_before[:, pj] ** 2))
                prim_a += float(np.sum(e_after[:, pj] ** 2))
                prim_j += float(np.sum(e_joint[:, pj] ** 2))
                prim_n += e_before.shape[0] * len(pj)
            folds.append({"drive": c.name, "rmse_before_deg_s": _primary_rmse(c, e_before),
                          "rmse_after_deg_s": _primary_rmse(c, e_after), "params": x.tolist(),
                          "calibrated_on_drive": {f"{labels[j][0]}.{labels[j][1]}": float(x_pred[j]) for j in own},
                          "rmse_after_joint_values_deg_s": _primary_rmse(c, e_joint),
                          "by_signal": {s: {"before": float(np.sqrt(np.mean(e_before[:, j] ** 2))),
                                            "after": float(np.sqrt(np.mean(e_after[:, j] ** 2)))}
                                        for j, s in enumerate(c.signals)}})

        def pool(v):
            return float(math.sqrt(sum(a for a, _ in v) / max(sum(b for _, b in v), 1)))

        by_signal = {s: {"before": pool(before_sig[s]), "after": pool(after_sig[s])} for s in SIGNALS
                     if s in before_sig}
        return {"before_deg_s": math.sqrt(prim_b / prim_n) if prim_n else math.nan,
                "after_deg_s": math.sqrt(prim_a / prim_n) if prim_n else math.nan,
                "after_joint_values_deg_s": math.sqrt(prim_j / prim_n) if prim_n else math.nan,
                "by_signal": by_signal, "folds": folds}

    def _heldout_halves(self, ev: Evaluator, final: FitResult) -> dict:
        """A single drive: fitted on one half of its comparison samples (in time), it predicts the other,
        and the other way round; figures pooled over both halves."""
        c = ev.cases[0]
        n = c.y_meas.shape[0]
        w0 = ev.weights[0].copy()
        e_before = self.base_residuals_[0]
        e_after = np.zeros_like(e_before)
        folds = []
        for k, held in enumerate((np.arange(n) < n // 2, np.arange(n) >= n // 2)):
            ev.weights[0] = w0 * (~held)[:, None]
            try:
                x = fit_structure(ev, final.structure, final.x, (0,), max_nfev=HELDOUT_NFEV).x \
                    if final.structure.n_params else final.x
                e = ev.case_residuals(final.structure, x, [0])[0]
            finally:
                ev.weights[0] = w0
            e_after[held] = e[held]
            folds.append({"drive": f"{c.name}:{'first' if k == 0 else 'second'}_half", "params": x.tolist(),
                          "rmse_before_deg_s": _primary_rmse(c, e_before[held]),
                          "rmse_after_deg_s": _primary_rmse(c, e[held])})
        by_signal = {s: {"before": float(np.sqrt(np.mean(e_before[:, j] ** 2))),
                         "after": float(np.sqrt(np.mean(e_after[:, j] ** 2)))} for j, s in enumerate(c.signals)}
        fold = {"drive": c.name, "rmse_before_deg_s": _primary_rmse(c, e_before),
                "rmse_after_deg_s": _primary_rmse(c, e_after), "by_signal": by_signal, "halves": folds}
        return {"before_deg_s": fold["rmse_before_deg_s"], "after_deg_s": fold["rmse_after_deg_s"],
                "by_signal": by_signal, "folds": [fold], "method": "held-out halves of the one drive"}

    # -- estimator API ------------------------------------------------------------------------------
    def _new_data(self, drives) -> tuple[Evaluator, np.ndarray]:
        """An evaluator of the fitted model over new drives (any form :func:`~.data.as_cases` takes)
        and their base-model signals (R,) of (n_steps, 6) arrays (:meth:`~.engine.Evaluator.simulate`),
        quiet lead-ins marked as in :meth:`fit`."""
        ev = Evaluator(self.model_, as_cases(drives, wheelbase=self.model_.vehicle.wheelbase))
        sims = ev.simulate(Structure([]), np.zeros((1, 0)), to_end=True)[0]
        for r, c in enumerate(ev.cases):
            mark_quiet(c, sims[r][:, :3])
        return ev, sims

    def predict(self, drive=0) -> Response:
        """The fitted model's IMU signals of one drive at its measured sample times in its analysis
        window (time offset and sensor bias included), as a :class:`~susp_sim_ros.model.Response` (SI:
        rates [rad/s], specific forces [m/s^2]; ``t`` [s] since the drive's first input).

        ``drive``: new data -- a recording's path, a :class:`~susp_sim_ros.io.drive.TestDrive` or a
        :class:`~.data.DriveCase`, simulated with the fitted model as fitted -- or the index or name of
        a drive given to :meth:`fit`."""
        self._check_fitted()
        names = [c.name for c in self.cases_]
        if isinstance(drive, (int, np.integer)) or (isinstance(drive, str) and drive in names):
            ev, r = self.evaluator_, int(drive) if not isinstance(drive, str) else names.index(drive)
        else:
            ev, r = self._new_data(drive)[0], 0
        st, x = self.result_.structure, self.result_.x
        rates = ev.simulate(st, x[None], [r])[0, 0]
        e = ev.case_residual(r, rates, st.lag(x), st.bias)
        return _signals_response(ev.cases[r], ev.cases[r].y_meas + e)

    def score(self, drives=None) -> float:
        """Fraction of the base model's residual mean square the fitted model explains on the primary
        gyro signal(s) (1 = perfect, 0 = no better than the base model, below 0 = worse).

        With ``drives`` (new data: paths, TestDrive or DriveCase objects): on those drives, simulated with
        the fitted model as fitted (no refit). Without: held-out (leave-one-drive-out) on the fitted
        drives; in-sample when held-out was switched off."""
        self._check_fitted()
        if drives is not None:
            ev, sims = self._new_data(drives)
            st, x = self.result_.structure, self.result_.x
            rates = ev.simulate(st, x[None])[0]
            before = after = 0.0
            for r, c in enumerate(ev.cases):
                pj = [j for j, s in enumerate(c.signals) if s in primary_signals(c.maneuver)]
                before += float(np.sum(ev.case_residual(r, sims[r], 0.0, False)[:, pj] ** 2))
                after += float(np.sum(ev.case_residual(r, rates[r], st.lag(x), st.bias)[:, pj] ** 2))
            return 1.0 - after / max(before, 1e-12)
        if self.heldout_:
            return 1.0 - (self.heldout_["after_deg_s"] / max(self.heldout_["before_deg_s"], 1e-12)) ** 2
        return 1.0 - self.result_.rss / max(self.base_fit_.rss, 1e-12)

    def report(self) -> dict:
        """The interface JSON (``susp diagnose --json``)."""
        self._check_fitted()
        return interface_json(self)


def _held_trials(ev: Evaluator, cur: FitResult, held: FitResult, cands: Sequence[str], idx: Sequence[int],
                 lne: float) -> list[tuple[float, str, FitResult]]:
    """Every candidate of ``cands`` added to ``cur``'s structure and fitted with the values ``idx`` held
    where ``held`` has them (at their priors), best first, as ``(criterion, name, fit)``: the criterion is
    the fit's BIC less ``log n_eff`` per held value (those values are not fitted, so they cost nothing)."""
    trials = []
    for name in cands:
        st = cur.structure.with_(name)
        fix = [st.labels().index(cur.structure.labels()[j]) for j in idx]
        f = fit_structure(ev, st, st.embed(held.structure, held.x), tuple(range(len(ev.cases))),
                          max_nfev=TRIAL_NFEV, fixed=fix)
        trials.append((f.bic - len(idx) * lne, name, f))
    return sorted(trials, key=lambda t: t[0])


def _conditioned_on(info: np.ndarray, fixed: Sequence[int]) -> np.ndarray:
    """The covariance from the information ``info`` with the parameters ``fixed`` held at their values:
    their rows and columns left out of the (pseudo-)inversion and zero in the result."""
    keep = np.setdiff1d(np.arange(info.shape[0]), np.asarray(fixed, np.int64))
    cov = np.zeros_like(info)
    cov[np.ix_(keep, keep)] = np.linalg.pinv(info[np.ix_(keep, keep)], hermitian=True)
    return cov


def _warm(st: Structure, cur: FitResult, o) -> np.ndarray:
    """Start of the nonlinear refit: current values plus the linearised step of the option."""
    x = st.embed(cur.structure, cur.x)
    labels = st.labels()
    cols = [j for j, (t, _) in enumerate(labels) if t in cur.structure.names or t in o.add]
    if len(o.delta) == len(cols):
        x[cols] = x[cols] + o.delta
    lo, hi = st.bounds()
    return np.clip(x, lo, hi)


def _informed_only_by(fit: FitResult, held: np.ndarray, pw: float | None = None) -> list[int]:
    """Calibration parameters (with a prior) that the rows outside ``held`` inform less than their prior
    does (the oil-empty damper of the only drive with an empty damper). A leave-one-drive-out refit keeps
    them at the joint fit's value: no other drive can predict them, and reverting them to the prior would
    judge the prior, not the model. ``pw``: the prior rows' weight (default: the structure's).

    What the other rows tell about a value is its information with every other parameter free (the
    Schur complement of the training rows' Gauss-Newton information, the other values' priors included),
    not its own column's: a drive that moves the value only together with others (the rear-empty sine
    steer, where the oil-empty rear damper trades against the friction terms) does not inform it. Nor do
    rows that carry less than :data:`HELD_SHARE` of what all rows tell about it: the front-empty sine steer
    informs the oil-empty front damper, but refitted on it alone, without the bump crossing that carries
    most of its information, the value follows what the model lacks in the sine steer."""
    if fit.jac is None or not len(fit.x):
        return []
    pidx = fit.structure.prior()[0]
    if not len(pidx):
        return []
    info, info_all, prior_info = _data_information(fit, held, pw)
    return [int(j) for j in pidx if info[j] < prior_info[j] or info[j] < HELD_SHARE * info_all[j]]


def _data_information(fit: FitResult, held: np.ndarray, pw: float | None = None
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """What the rows outside ``held`` and what all rows tell of each parameter, every other parameter free
    with the priors in (the Schur complement of the Gauss-Newton information, less the parameter's own
    prior), and that prior information; ``pw``: the prior rows' weight (default: the structure's)."""
    assert fit.jac is not None
    pidx, _, psd = fit.structure.prior()
    if pw is None:
        pw = _training_prior_weight(fit, held)
    prior_info = np.zeros(len(fit.x))
    prior_info[pidx] = (pw / psd) ** 2

    def data_info(gram: np.ndarray) -> np.ndarray:
        A = gram + np.diag(prior_info)
        return 1.0 / np.maximum(np.diag(np.linalg.pinv(A, hermitian=True)), 1e-300) - prior_info

    Jh = fit.jac[held]   # the training rows' product is all rows' less the held rows' (they are few)
    return data_info(fit.gram - Jh.T @ Jh), data_info(fit.gram), prior_info


def _training_prior_weight(fit: FitResult, held: np.ndarray) -> float:
    """The weight of the prior rows against the rows outside ``held`` (their count over their effective
    count, :func:`n_effective`, taken in proportion to the fit's; as :func:`fit.fit_structure` weighs)."""
    tr = int((~held).sum())
    return math.sqrt(tr / max(fit.n_eff * tr / len(held), 1.0)) * fit.structure.prior_gain


def _owned_by(fit: FitResult, held: np.ndarray, cols: Sequence[int]) -> list[int]:
    """The parameters ``cols`` (indices, a physics term's levels: no prior) that the ``held`` rows own: the
    other rows carry less than :data:`HELD_SHARE` of what all rows tell of each, every other parameter free
    and the calibration's priors in (the Schur complement of the Gauss-Newton information, as
    :func:`_informed_only_by` measures calibration values)."""
    if fit.jac is None or not len(cols):
        return []
    info, info_all, _ = _data_information(fit, held)
    return [int(j) for j in cols if info[j] < HELD_SHARE * info_all[j]]


def _recalibrate_on_drive(ev: Evaluator, st: Structure, x: np.ndarray, r: int, own: Sequence[int],
                          prior: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """``x`` with the values ``own`` (indices: those only drive ``r`` informs) fitted on drive ``r`` alone,
    with their priors (``prior``: (indices, means, sds) in their place), every other value fixed at ``x``;
    ``x`` itself without such values."""
    if not len(own):
        return x
    others = np.setdiff1d(np.arange(st.n_params), np.asarray(own, np.int64))
    return fit_structure(ev, st, x, (r,), max_nfev=HELDOUT_NFEV, fixed=others.tolist(), prior=prior).x


def _fold_prior(fit: FitResult, held: np.ndarray, x_fold: np.ndarray
                ) -> tuple[list[int], tuple[np.ndarray, np.ndarray, np.ndarray] | None]:
    """The calibration values of ``fit`` (indices) and the prior a leave-one-drive-out fold calibrates them
    with on its held-out drive (the rows ``held``): centred at the fold's values ``x_fold``, each as
    precise as the other drives and its own prior make it (the Schur complement of :func:`_data_information`
    plus the prior information, a Laplace approximation of the fold's posterior, one value at a time; Gelman
    et al., *Bayesian Data Analysis*, 3rd ed., 2013, sec. 4.1). In the prior rows' currency of the training
    rows: sd = pw_t / sqrt(info + prior info), which is the value's own prior sd where the other drives tell
    nothing of it. The physics terms' values and shapes stay at the fold's (they are what is predicted)."""
    st = fit.structure
    if CALIBRATION not in st.names or fit.jac is None or not len(fit.x):
        return [], None
    span = st.span(CALIBRATION)
    idx = np.intersect1d(np.arange(span.start, span.stop), st.prior()[0])
    if not len(idx):
        return [], None
    pw_t = _training_prior_weight(fit, held)
    info, _, prior_info = _data_information(fit, held, pw_t)
    sd = pw_t / np.sqrt(np.maximum(info[idx] + prior_info[idx], 1e-300))
    return idx.tolist(), (idx, np.asarray(x_fold, float)[idx], sd)


def _held_in_both(a: FitResult, b: FitResult, held: np.ndarray) -> tuple[list[int], list[int]]:
    """The values that the ``held`` rows inform (:func:`_informed_only_by`) in ``a`` or in ``b``, as indices
    of ``a``'s and of ``b``'s parameters: what a fold of either structure holds at its joint fit's value,
    so two structures compared on the held rows are refitted under the same rule
    (:meth:`DiscrepancyFinder._heldout_check`)."""
    la, lb = a.structure.labels(), b.structure.labels()
    both = {la[j] for j in _informed_only_by(a, held)} | {lb[j] for j in _informed_only_by(b, held)}
    return [j for j, k in enumerate(la) if k in both], [j for j, k in enumerate(lb) if k in both]


def _fold_step(fit: FitResult, held: np.ndarray, pw: float | None = None,
               fixed: Sequence[int] | None = None) -> np.ndarray:
    """The parameter step that refits ``fit`` on the rows outside ``held``: one Gauss-Newton step from the
    joint fit with the priors (their rows weighted ``pw``, default the structure's), clipped to the
    bounds; values only the ``held`` rows inform stay (:func:`_informed_only_by`), or the values ``fixed``
    (indices) when given."""
    r, J, x = fit.residual, fit.jac, fit.x
    assert J is not None  # callers pass fits with free parameters
    tr = ~held
    st = fit.structure
    pidx, pmu, psd = st.prior()
    lo, hi = st.bounds()
    if pw is None:
        pw = _training_prior_weight(fit, held)
    hold = set(_informed_only_by(fit, held, pw) if fixed is None else fixed)
    free = [j for j in range(len(x)) if j not in hold]
    A, b = J[tr][:, free], -r[tr]
    pr = prior_rows(free, x, pidx, pmu, psd, pw)
    if pr is not None:
        A, b = np.vstack([A, pr[0]]), np.concatenate([b, pr[1]])
    d = np.zeros(len(x))
    d[free], *_ = np.linalg.lstsq(A, b, rcond=None)
    # within the parameters' bounds, as the nonlinear refit: a parameter the training drives hardly
    # inform must not predict the held-out drive from an impossible value
    return np.clip(x + d, lo, hi) - x


def _fold_refit(fit: FitResult, held: np.ndarray, fixed: Sequence[int] | None = None) -> tuple[float, float]:
    """Squared whitened residual on the ``held`` rows and on the others after refitting ``fit`` on the
    others only (:func:`_fold_step`, with the values ``fixed`` held when given)."""
    r = fit.residual
    tr = ~held
    if fit.jac is None or not len(fit.x):
        return float(r[held] @ r[held]), float(r[tr] @ r[tr])
    e = r + fit.jac @ _fold_step(fit, held, fixed=fixed)
    return float(e[held] @ e[held]), float(e[tr] @ e[tr])


def _lead_axles(sel: force_shape.Selection) -> list[str]:
    """The axles on which ``sel``'s leading dependence (a rotation harmonic's sine and cosine as one) is
    stable, front first."""
    lead = force_shape.group_of(sel.leading or "")
    return sorted({c.axle for c in sel.stable if force_shape.group_of(c.feature) == lead}, key=force_shape.AXLES.index)


def _refit_without(ev: Evaluator, cur: FitResult, names: Sequence[str], max_nfev: int = TRIAL_NFEV) -> FitResult:
    """``cur`` without the terms ``names``, refitted on every drive from its values (calibration jointly)."""
    st = cur.structure
    for name in names:
        st = st.without(name)
    return fit_structure(ev, st, st.embed(cur.structure, cur.x), tuple(range(len(ev.cases))), max_nfev=max_nfev)


def _record_drop(path: list, accepted: list, cur: FitResult, f: FitResult, name: str, why: str,
                 **figures) -> None:
    """Term ``name`` dropped from ``cur`` (``f`` the fit without it): its entry in the selection path with the
    fit's figures, ``figures`` (a test's) and the reason ``why``; its ``accepted`` entry gone."""
    path.append({"step": len(path), "removed": name, "structure": list(f.structure.names), "rss": f.rss,
                 "bic": f.bic, "delta_bic": cur.bic - f.bic, **figures, "why": why})
    accepted[:] = [a for a in accepted if a["name"] != name]


def _drives_reached(design: force_shape.Design, cols: Sequence[int]) -> list[int]:
    """The drives (groups of ``design``) on which any of the columns ``cols`` is not zero, in order."""
    return [int(g) for g in np.unique(design.groups) if np.any(design.X[design.groups == g][:, cols])]


def _drive_rows(ev: Evaluator, fit: FitResult, h: int) -> np.ndarray:
    """The rows of ``fit.residual`` that belong to its drive at position ``h`` of ``fit.idx`` (a mask)."""
    edges = np.cumsum([0] + [ev.n_res[q] for q in fit.idx])
    rows = np.zeros(len(fit.residual), bool)
    rows[edges[h]:edges[h + 1]] = True
    return rows


def _finite_or_lowest(v: float) -> float:
    """``v``, or minus infinity where it is not a number (the weakest of all)."""
    return v if math.isfinite(v) else -math.inf


def _steers(cases: Sequence[DriveCase]) -> bool:
    """Whether any drive steers by more than :data:`STEERING_RAD` (steering-wheel angle)."""
    return any(float(np.max(np.abs(c.U[:, U_INDEX["SWA"]]))) > STEERING_RAD for c in cases)


def _jackknife_se(heldout: dict | None, k: int) -> np.ndarray | None:
    """Jackknife standard errors of the final parameters from the leave-one-drive-out refits (at least
    three drives), or None."""
    if not heldout or k == 0:
        return None
    rows = [f["params"] for f in heldout["folds"] if len(f.get("params", [])) == k]
    if len(rows) < 3:
        return None
    X = np.array(rows)
    R = len(X)
    return np.sqrt((R - 1) / R * np.sum((X - X.mean(axis=0)) ** 2, axis=0))


def _primary_rmse(c: DriveCase, e: np.ndarray) -> float:
    """RMSE [deg/s] of drive ``c``'s primary gyro signal(s) in its residual ``e`` (n_grid, n_sig)."""
    pj = [j for j, s in enumerate(c.signals) if s in primary_signals(c.maneuver)]
    return float(np.sqrt(np.mean(e[:, pj] ** 2))) if pj else math.nan


def _whitened(ev: Evaluator, st: Structure, x: np.ndarray, r: int) -> float:
    """Whitened residual sum of squares of drive ``r`` at ``x``."""
    e = ev.case_residuals(st, x, [r])[r] * ev.weights[r]
    return float(np.sum(e * e))


def _skip_masked(ranking: list, testable: list[str], skipped: list[dict]) -> None:
    """Candidates a typical parameter change moves by less than a tenth of the noise are masked in
    these drives: moved from ``testable`` to ``skipped`` with the reason."""
    for o in ranking:
        if o.excitation_rms < 0.1:
            c = BY_NAME[o.add[0]]
            skipped.append({"name": c.name, "reveal_with": c.reveal_with,
                            "why": f"masked in these drives: a typical change moves the signals by "
                                   f"{o.excitation_rms:.3f} x their noise RMS, under a tenth"})
            testable.remove(c.name)


def _signals_response(c: DriveCase, y: np.ndarray) -> Response:
    """IMU signals ``y`` (n_grid, n_sig; rates [deg/s], specific forces [m/s^2]) of drive ``c`` at its
    comparison times as a :class:`Response` in SI units."""
    to_si = np.array([math.radians(1.0) if SIGNAL_UNIT[a] == "deg/s" else 1.0 for a in c.axes])
    return Response(c.t_grid_s, y * to_si, c.signals, t_ns=c.grid_ns)
