"""Calibration before discovery: re-estimate the base model's uncertain parameters from the drives.

Every parameter the vehicle file marks ``calibrate: true`` (with its plausible ``range``, the prior;
:class:`~susp_sim_ros.model.params.Prior`) and that the base variant uses becomes one calibration
parameter per value (per axle where the file gives front and rear). The prior is a normal distribution
centred on the file's value with the range as its +-2 sigma band; the estimate is the maximum a
posteriori over all drives jointly (scipy ``least_squares`` on the whitened residuals of every signal
plus the prior residuals, each drive's samples weighted as one independent sample per
:data:`~susp_sim_ros.analysis.discrepancy.fit.T_CORR_S`). Hard bounds are the range widened by its own
width on both sides, so a value can leave its range: that is a finding ("sprung mass 1400 -> 1530 kg,
outside its documented range: loaded car or wrong parameter set?").

Identifiability: in prior-scaled coordinates the data's Fisher information ``F = Js^T Js`` (``Js`` the
Jacobian of the weighted residuals times the prior standard deviations) is compared with the prior's
(the identity). A parameter is *informed* when the data shrink its posterior standard deviation to at
most :data:`INFORMED_SHRINK` of the prior's; an eigen-direction of ``F`` with eigenvalue above
:data:`INFORMED_EIGEN` that no single parameter carries is reported as an informed *combination*. The
parameters the drives do not inform are held at their prior value and reported as not informed.

Intervals: the values the vehicle file gives a range but does not calibrate (tyre damping, roll
centres, ...; :func:`consider_params`) and the calibration values the drives do not inform
stay at their file value, but the calibrated values' intervals include what that can cost
(:func:`consider_covariance`), so an estimate that leans on an assumed value carries that value's
uncertainty. The priors' spread itself is checked against the data: where the calibrated values sit
further from their priors than the priors claim, the intervals widen by the empirical-Bayes factor of
:meth:`~.fit.FitResult.prior_scale`. The 95 % interval is the widest of these and the leave-one-drive-out
spread of the refits.

The calibration enters the model through one path: the calibrated values replace the vehicle's
(:meth:`VehicleParams.replace`), and :meth:`~susp_sim_ros.model.vehicle.Model.params` builds the
kernel's parameter vector from them, as for any vehicle file.
"""
from __future__ import annotations

import copy
import dataclasses
import math
from dataclasses import dataclass
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ...errors import ConfigError
from ...model import Model
from ...model.layout import P_INDEX
from ...model.params import AXLES, FrictionVariant, VehicleParams, load_settings
from .candidates import CALIBRATION, CandParam, Candidate, interval_floor, neutral_base

INFORMED_SHRINK = 0.5   # posterior sd / prior sd at most this: informed
INFORMED_EIGEN = 3.0    # data information above 3x the prior's along a direction: informed combination
STEP_OF_SD = 0.1        # finite-difference step, in prior standard deviations

#: Parameters a variant without the scaling does not use (calibrating them would be meaningless).
NEEDS_SWITCH = {"sv_plateau": "velocity_scaling", "sv_speed": "velocity_scaling",
                "damper_friction_empty": "oil_scaling", "damper_measured_empty": "oil_scaling",
                "sh_longitudinal": "horizontal_scaling", "sh_lateral": "horizontal_scaling"}
#: Fields that can never be negative or zero (their hard lower bound stays above zero).
POSITIVE = {"sprung_mass", "unsprung_mass", "cg_height", "roll_inertia", "pitch_inertia", "yaw_inertia",
            "wheel_rate", "tyre_stiffness", "cornering_stiffness", "relaxation_length", "steering_ratio",
            "damper_friction_intact", "sv_speed", "damper_measured_intact", "damper_measured_empty",
            "dahl_stiffness"}


@dataclass(frozen=True)
class CalParam:
    """One calibrated value: a :class:`VehicleParams` field, at one axle (``axle`` 0/1) or for the whole
    car (``axle`` None); ``scale``: a factor on a damper table instead of a value."""

    field: str
    key: str
    where: str
    axle: int | None
    unit: str
    prior: float
    lo: float
    hi: float
    reason: str
    scale: bool = False

    @property
    def name(self) -> str:
        return self.field if self.axle is None else f"{self.field}_{AXLES[self.axle]}"

    @property
    def sd(self) -> float:
        return max((self.hi - self.lo) / 4.0, 1e-9 * max(abs(self.prior), 1.0))

    def interval_floor(self, value: float) -> float:
        """The lowest value a reported interval may show: 0 for a quantity that cannot be negative (its
        documented range starts at or above 0; never above the estimate ``value``), else unbounded."""
        return interval_floor(self.lo >= 0.0 or self.field in POSITIVE, value)

    @property
    def bounds(self) -> tuple[float, float]:
        w = self.hi - self.lo
        lo, hi = self.lo - w, self.hi + w
        if self.field in POSITIVE:
            lo = max(lo, 0.25 * self.lo if self.lo > 0 else 1e-6)
        elif lo < 0 <= self.lo:
            lo = 0.0
        return lo, hi


def sprung_mass_from_wheel_loads(cal: Sequence, wheel_loads_n: Sequence[float], gravity: float,
                                 scale_accuracy: float) -> tuple[list, dict]:
    """The calibration (or inspection nuisance) parameters ``cal`` with the sprung mass's prior taken from the
    car's measured static wheel loads (FL, FR, RL, RR [N]; a wheel-load scale, or the static reading of an
    EUSAMA tester):
    ``sum(F) / g`` minus the unsprung masses (their priors), sd from the scale's relative accuracy per
    wheel and the unsprung masses' sds. Why: a bump crossing seen by a body IMU tells the car's ratios
    (spring rate and damping to mass) but hardly its overall scale, so a heavy car read against the
    vehicle file's mass reads its dampers weak by about the mass ratio (issue 27, benchmarks/RESULTS.md), and
    a calibration that scales every mass and rate by one factor makes the friction levels (held in newtons)
    act stronger or weaker (issue 24); the scale pins it. Returns the parameters and the JSON entry."""
    loads = np.asarray(wheel_loads_n, float)
    if loads.shape != (4,) or not np.all(np.isfinite(loads)) or np.any(loads <= 0):
        raise ConfigError(f"wheel loads: expected four positive static loads FL,FR,RL,RR in N, got "
                          f"{list(wheel_loads_n)}")
    by = {(p.field, p.axle): p for p in cal}
    if ("sprung_mass", None) not in by:
        raise ConfigError("wheel loads given but the sprung mass is not calibrated (inspection: "
                          "config/inspection.yaml estimator.nuisance; diagnosis: `calibrate: true` on sprung_mass "
                          "in the vehicle file)")
    unsprung = [by.get(("unsprung_mass", a)) for a in (0, 1)]
    mu = sum(2.0 * p.prior for p in unsprung if p is not None)
    var_u = sum(4.0 * p.sd ** 2 for p in unsprung if p is not None)
    total = float(loads.sum()) / gravity
    sd = math.sqrt((scale_accuracy * float(np.sqrt(np.sum(loads ** 2))) / gravity) ** 2 + var_u)
    m_s = total - mu
    if not m_s > 2 * sd:
        raise ConfigError(f"wheel loads {list(wheel_loads_n)} N give a total mass of {total:.0f} kg, no more than "
                          f"the unsprung masses ({mu:.0f} kg): not this car's static loads in N")
    old = by[("sprung_mass", None)]
    new = dataclasses.replace(old, prior=m_s, lo=m_s - 2 * sd, hi=m_s + 2 * sd,
                              reason=f"from the measured static wheel loads ({total:.0f} kg in all, the unsprung "
                                     "masses' priors taken off)")
    entry = {"measured_N": [float(v) for v in loads], "total_mass_kg": total, "sprung_mass_prior_kg": m_s,
             "sprung_mass_prior_sd_kg": sd, "vehicle_file_sprung_mass_kg": old.prior,
             "front_share": float(loads[:2].sum() / loads.sum())}
    return [new if p is old else p for p in cal], entry


def with_scale_rival(entries: list[dict], calibration: Sequence[dict], shift_sd: float, weighed: bool,
                     is_physics: Callable[[str], bool]) -> list[dict]:
    """The competing entries (``not_identifiable``) of physics terms (``is_physics``) with the car's overall
    force scale added as a rival where the calibration moved it: the sprung mass calibrated more than
    ``shift_sd`` prior sd (range = +-2 sd) from its prior, the car not ``weighed``. Drives that record motion only
    do not tell the scale: every mass, inertia and rate scaled by one factor moves the car the same, while a
    term's force has its size in newtons, so a scale moved down makes a term (and the friction levels held)
    act stronger (benchmarks/RESULTS.md, 2026-12-06 probe). Weighing the car separates them. Other entries
    (the measurement chain's) are returned as they are."""
    m = next((e for e in calibration if e["param"] == "sprung_mass" and e.get("informed")), None)
    if weighed or m is None:
        return entries
    lo, hi = m["prior_range"]
    scale = CalParam("sprung_mass", "mass.sprung", "all", None, "kg", m["prior"], lo, hi, "")
    z = (m["value"] - scale.prior) / scale.sd
    if abs(z) <= shift_sd:
        return entries
    rival, reveal = "sprung_mass:all", reveal_for(scale, "recorded")
    why = (f" The car's overall force scale moved with it: sprung mass calibrated at {m['value']:.0f} kg, "
           f"{z:+.1f} prior sd from the vehicle file's {scale.prior:.0f} kg (every mass and rate moves with it, "
           "while the term's force is in newtons).")
    return [{**e, "competes_with": [*e.get("competes_with", []), rival], "reveal_with": f"{reveal}; {e['reveal_with']}",
             "why": e.get("why", "") + why}
            if is_physics(e["name"]) and rival not in e.get("competes_with", []) else e for e in entries]


def reveal_for(p: CalParam, state: str) -> str:
    """The measurement that pins calibration value ``p`` without the drives (what separates it from a
    physics term that explains the same residual): a damper table on the damper rig in the oil state of
    the vehicle state ``state`` that informs it (its friction ramp and force-velocity sinusoids,
    ``config/rigs.yaml``), any other value measured directly."""
    if p.scale:
        rig = load_settings("rigs.yaml")
        oil = "oil-empty" if "empty" in p.field else "intact"
        v = rig["damper.sine_peak_velocities"]
        return (f"the {oil} {p.where} damper (as in the {state} drives) on the damper rig: the friction ramp "
                f"at {1000 * rig['damper.ramp_speed']:.0f} mm/s and sinusoids from {1000 * min(v):.0f} mm/s "
                "(`susp rig damper`) show whether the damper itself is stronger than its measured curve")
    if p.field == "sprung_mass":
        return ("weighing the car: its static wheel loads on a wheel-load scale (`susp diagnose --wheel-loads "
                "FL,FR,RL,RR`) pin the car's overall force scale, which drives recording motion only do not")
    return f"a measurement of {p.key}" + ("" if p.where == "all" else f" ({p.where})")


def calibration_params(vp: VehicleParams, variant: FrictionVariant,
                       only: Sequence[str] | None = None) -> list[CalParam]:
    """The calibration parameters of vehicle ``vp`` under ``variant`` (optionally only the ``names``)."""
    out = []
    for fld, pr in vp.priors.items():
        if not pr.calibrate:
            continue
        sw = NEEDS_SWITCH.get(fld)
        if sw and not getattr(variant, sw):
            continue
        if pr.shape == "table":
            for a in range(2):
                out.append(CalParam(fld, pr.key, AXLES[a], a, pr.unit, 1.0, pr.lo[0], pr.hi[0], pr.reason, True))
        elif pr.shape == "axle":
            val = getattr(vp, fld)
            for a in range(2):
                out.append(CalParam(fld, pr.key, AXLES[a], a, pr.unit, float(val[a]), pr.lo[a], pr.hi[a],
                                    pr.reason))
        else:
            out.append(CalParam(fld, pr.key, "all", None, pr.unit, float(getattr(vp, fld)), pr.lo[0], pr.hi[0],
                                pr.reason))
    if only is not None:
        out = [p for p in out if p.name in set(only)]
    return out


#: vehicle-file values the model's dynamics never read (they serve the analysis: the rolling radius turns
#: the path into the wheel's rotation angle for the finder's input features); their range is no
#: uncertainty of a simulated signal, so they are neither calibrated nor considered
NOT_IN_THE_DYNAMICS = frozenset({"rolling_radius"})


def consider_params(vp: VehicleParams, variant: FrictionVariant) -> list[CalParam]:
    """The "consider" parameters: values the vehicle file gives a plausible range but does not let the
    calibration move (``calibrate: false``, e.g. tyre damping, steering ratio). They stay
    at their file value, but their range is an uncertainty the calibrated values inherit
    (:func:`consider_covariance`). Degenerate ranges (a definition, such as the 1 mm/s friction reference
    speed) and damper tables are not uncertain in this sense."""
    out = []
    for fld, pr in vp.priors.items():
        if pr.calibrate or pr.shape == "table" or fld in NOT_IN_THE_DYNAMICS:
            continue
        sw = NEEDS_SWITCH.get(fld)
        if sw and not getattr(variant, sw):
            continue
        val = getattr(vp, fld)
        axles = range(2) if pr.shape == "axle" else (None,)
        for a in axles:
            lo, hi = (pr.lo[a], pr.hi[a]) if a is not None else (pr.lo[0], pr.hi[0])
            v = float(val[a]) if a is not None else float(val)
            if hi - lo <= 1e-12 * max(abs(v), 1.0):
                continue
            out.append(CalParam(fld, pr.key, AXLES[a] if a is not None else "all", a, pr.unit, v, lo, hi,
                                pr.reason))
    return out


def consider_covariance(J_est: np.ndarray, H: np.ndarray, J_con: np.ndarray, sd_con: np.ndarray,
                        weight: float) -> np.ndarray:
    """Covariance the estimated parameters gain because the consider parameters are held at their file
    values while the car's may lie anywhere in their priors: the estimate follows a consider value's error
    with the sensitivity ``S = -H^-1 H_ec``, so its error covariance grows by ``S P_cc S^T`` (the consider
    covariance of orbit determination: Tapley, Schutz & Born, Statistical Orbit Determination, 2004,
    sec. 6.3). Unlike the posterior with the consider values marginalised out, it does not let the data
    narrow the consider values: the point estimate did not move them, so their error stays as large as
    their prior says. The point estimate keeps the consider parameters at their file values; only the
    intervals widen.

    ``J_est``/``J_con``: Jacobians of the whitened residual w.r.t. the estimated and the consider
    parameters; ``H``: the posterior information of the estimated parameters (data and priors);
    ``sd_con``: the consider parameters' prior standard deviations; ``weight``: the data's information
    weight per sample (as in :meth:`~.fit.FitResult.information`)."""
    k = J_est.shape[1]
    if J_con.shape[1] == 0 or k == 0:
        return np.zeros((k, k))
    S = consider_sensitivity(J_est, H, J_con, weight)
    return (S * sd_con[None, :] ** 2) @ S.T


def consider_sensitivity(J_est: np.ndarray, H: np.ndarray, J_con: np.ndarray, weight: float) -> np.ndarray:
    """``S = H^-1 H_ec`` (k x n_con): how far each estimated parameter moves per unit error of each consider
    parameter (:func:`consider_covariance`; arguments as there). ``(S[i, j] sd_j)^2`` is the share of
    parameter i's consider variance that consider value j brings: what the estimate competes with."""
    Hec = weight * (J_est.T @ J_con)
    return np.linalg.pinv(H) @ Hec


def vehicle_at(vp: VehicleParams, params: Sequence[CalParam], theta: Sequence[float]) -> VehicleParams:
    """``vp`` with the calibration ``params`` at values ``theta``."""
    changes: dict[str, Any] = {}  # field -> new value (float, or an axle pair / table tuple)
    for p, v in zip(params, theta):
        cur = changes.get(p.field, getattr(vp, p.field))
        v = float(v)
        if p.scale:
            assert p.axle is not None  # a damper-table factor is per axle (calibration_params)
            base = getattr(vp, p.field)
            rows = list(cur)
            rows[p.axle] = tuple(float(x) * v for x in base[p.axle])
            changes[p.field] = tuple(rows)
        elif p.axle is None:
            changes[p.field] = v
        else:
            pair = list(cur)
            pair[p.axle] = v
            changes[p.field] = tuple(pair)
    return dataclasses.replace(vp, **changes) if changes else vp


def calibration_candidate(model: Model, params: Sequence[CalParam]) -> Candidate:
    """The calibration as one candidate of the fitting machinery: its ``apply`` rebuilds each drive's
    parameter row from the vehicle at the calibrated values (the model's own path from a vehicle to the
    kernel's parameter vector), keeping the row's oil levels and the extended model's terms."""
    vp0 = model.vehicle
    cache: dict[bytes, np.ndarray] = {}
    k = P_INDEX["OIL"]

    def apply(P, P0, x, _model):
        key = np.asarray(x, float).tobytes()
        row = cache.get(key)
        if row is None:
            if len(cache) > 64:
                cache.clear()
            m = copy.copy(model)  # the same terms and kernel; only the vehicle differs
            m.vehicle = vehicle_at(vp0, params, x)
            row = cache[key] = m.params()
        P[:] = row  # the oil levels enter the parameter vector in their own slots only (Model.params)
        P[:, k:k + 4] = P0[:, k:k + 4]
        P[:] = neutral_base(P)

    cps = tuple(CandParam(p.name, p.unit, p.prior, *p.bounds, STEP_OF_SD * p.sd, p.reason, prior_sd=p.sd)
                for p in params)
    return Candidate(CALIBRATION, "calibration", "base-model parameters re-estimated within their priors",
                     cps, apply, tuple(p.where if p.where != "all" else None for p in params),
                     "drives that excite the parameter", "any")


def identifiability(J: np.ndarray, params: Sequence[CalParam], weight: float) -> dict:
    """Which calibration parameters (and combinations) the drives inform.

    ``J``: Jacobian of the whitened data residuals w.r.t. the parameters (columns as ``params``);
    ``weight``: the data's information weight (effective independent samples per sample). Returns the
    posterior/prior sd ratio per parameter, the informed flags and the informed directions (eigenvectors
    of the prior-scaled Fisher information with eigenvalue > :data:`INFORMED_EIGEN`)."""
    sd = np.array([p.sd for p in params])
    Js = J * sd[None, :]
    F = weight * (Js.T @ Js)
    post = np.linalg.inv(F + np.eye(len(params)))
    shrink = np.sqrt(np.clip(np.diag(post), 0, None))
    informed = shrink <= INFORMED_SHRINK
    lam, vec = np.linalg.eigh(F)
    combos = []
    for i in np.argsort(lam)[::-1]:
        if lam[i] < INFORMED_EIGEN:
            break
        v = vec[:, i] / np.max(np.abs(vec[:, i]))
        big = [j for j in np.argsort(-np.abs(v)) if abs(v[j]) >= 0.3]
        if len(big) >= 2 and not all(informed[j] for j in big):
            combos.append({"weights": {params[j].name: float(v[j]) for j in big},
                           "information_vs_prior": float(lam[i])})
    return {"posterior_over_prior_sd": {p.name: float(s) for p, s in zip(params, shrink)},
            "informed": [bool(x) for x in informed], "combinations": combos[:5],
            "eigenvalues": [float(x) for x in np.sort(lam)[::-1]]}


def calibration_entries(params: Sequence[CalParam], x: np.ndarray, ci_lo: np.ndarray, ci_hi: np.ndarray,
                        informed: Sequence[bool]) -> list[dict]:
    """The interface's ``calibration`` list (interface.md, JSON outputs)."""
    out = []
    for p, v, lo, hi, inf in zip(params, x, ci_lo, ci_hi, informed):
        if not inf:
            v, lo, hi = p.prior, p.prior - 1.96 * p.sd, p.prior + 1.96 * p.sd
        lo = max(lo, p.interval_floor(v))  # a mass, a rate, a length: no interval below zero
        out.append({"param": p.field, "where": p.where, "unit": p.unit, "prior": float(p.prior),
                    "prior_range": [float(p.lo), float(p.hi)], "value": float(v),
                    "ci95": [_finite(lo), _finite(hi)], "informed": bool(inf),
                    "outside_prior": bool(inf and not (p.lo <= v <= p.hi)), "key": p.key,
                    "range_source": p.reason})
    return out


def outside_statement(e: dict) -> str:
    """Plain words for a calibrated value outside its documented range."""
    where = "" if e["where"] == "all" else f" ({e['where']})"
    return (f"{e['param']}{where} {e['prior']:.4g} -> {e['value']:.4g} {e['unit']}, outside its documented "
            f"range {e['prior_range'][0]:.4g}-{e['prior_range'][1]:.4g} ({e['range_source'] or 'no reason given'}): "
            f"a different load or car, or a wrong parameter set?")


def _finite(x: float) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None
