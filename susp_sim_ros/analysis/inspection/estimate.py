"""Damper oil level per wheel (or axle) from recorded drives: the model fitted with the oil levels free.

The vehicle at an inspection lane is never known exactly, so the oil levels are fitted together with
the nuisance parameters that vary between cars of a class (``config/inspection.yaml`` ``nuisance``:
masses and load, inertias, spring and tyre rates, friction levels, the damper curve's production spread),
each with the vehicle file's plausible ``range`` as a normal prior (+-2 sd), exactly as the discrepancy
finder's calibration does (:mod:`..discrepancy.calibration`; same :class:`~..discrepancy.engine.Evaluator`,
batch simulation and :func:`~..discrepancy.fit.fit_structure`: maximum a posteriori by scipy
``least_squares`` over whitened residuals, each drive counted at its effective sample size). The oil
levels are bounded to [0, 1] with a weak prior that only keeps the information matrix invertible.

What the drives can tell, per axle (:func:`oil_identifiability`): from the posterior covariance of a
per-wheel fit's linearisation at half oil. Left and right are told apart when their *difference* is
pinned to ``per_wheel_max_sd``; a bump across the full width excites both alike (the roll rate stays
flat), so only their mean is, and the axle is fitted as one value. An axle whose mean is not pinned to
``identifiable_max_sd`` is ``unknown``: the drive does not excite it.

What the estimate stands on (issue 27, measured on the truth family's development forms): a crossing
informs the oil level through the body ringing out at damper velocities inside the measured curve
points; a faster or higher one also drives the dampers beyond the last measured point, into the stops,
wheel hop and tyre lift-off, which the drive cannot check against a car that is not our model. So each
signal's residual sd carries a model-form part that grows with how hard the drive moved it
(:func:`add_signal_model_form`: the vertical specific force, which carries those forces directly, far
more than the body rates), and the intact curve's slope beyond its last measured point is fitted per
axle (:func:`curve_beyond_candidate`) instead of assumed. The intervals add a model-form sd per axle
that grows with its peak damper velocity (:func:`model_form_sd`), learned on the development forms.

What is fitted is each damper's remaining force fraction (the kernel's ``OIL`` weight); it is read as an
oil level through the damper type's oil law (:mod:`.oil_law`, a rig measurement, default the model's
identity), which no drive can show: the levels, their intervals and the left-right difference are mapped
through it (:class:`GroupLevel`).

States (``config/inspection.yaml`` ``states``): ``ok`` from ``ok_from``, ``empty`` below
``empty_below``, ``degraded`` between; a 95 % interval that reaches into two of them is ``unknown``.

Left against right (issue 27 item 1, :func:`left_right`): per axle whose sides the drives tell apart,
the left-minus-right oil level with its 95 % interval from the fit's joint covariance of the two dampers
(the per-axle model-form sd, common to both sides of a full-width crossing, cancels in it), flagged
``asymmetric`` when the interval excludes zero and the difference exceeds ``left_right``
``asymmetric_min_difference`` -- the workshop's comparison of an axle's two dampers.
"""
from __future__ import annotations

import copy
import dataclasses
import math
import time
from dataclasses import dataclass, field
from typing import NamedTuple
from pathlib import Path
from collections.abc import Sequence

import numpy as np

from ...errors import ConfigError, SuspInputError
from ...io.drive_data import TestDrive
from ...io.integrity import require_live_imu
from ...model import Model
from ...model.layout import DAMPER_GRID, N_GRID, P_H_INTACT, P_INDEX, U_INDEX
from ...model.params import AXLE_CORNERS, CORNER_NAMES, load_settings, load_vehicle
from ...model.road import RoadProfile
from ..discrepancy.calibration import calibration_candidate, calibration_params, sprung_mass_from_wheel_loads
from ..discrepancy.candidates import CALIBRATION, CandParam, Candidate
from ..discrepancy.data import SIGNALS, DriveCase, load_cases, mark_quiet, select_signals
from ..discrepancy.engine import Evaluator, Structure
from ..discrepancy.fit import FitResult, debias, fd_jacobian, fit_structure, n_effective
from ..discrepancy.locate import noise_sigma
from . import protocol
from .oil_law import OilLaw
from ...model.params import DEFAULT_VEHICLE

STATES = ("ok", "degraded", "empty")


def load_config(path: str | Path | None = None) -> dict:
    """``config/inspection.yaml`` (or ``path``) as {section: {key: value}}, read by the one settings
    loader (:func:`~susp_sim_ros.model.params.load_settings`); a fresh copy each call (callers edit it)."""
    out: dict[str, dict] = {}
    for key, value in load_settings("inspection.yaml", path or None).items():
        sec, k = key.split(".", 1)
        out.setdefault(sec, {})[k] = copy.deepcopy(value)
    return out


def state_of(lo: float, hi: float, states_cfg: dict) -> str:
    """``ok``/``degraded``/``empty`` when the interval [lo, hi] lies in one band, else ``unknown``."""
    def band(x):
        return "ok" if x >= states_cfg["ok_from"] else ("empty" if x < states_cfg["empty_below"] else "degraded")
    return band(lo) if band(lo) == band(hi) else "unknown"


def nuisance_params(model: Model, names: Sequence[str], range_scale: dict | None = None):
    """Calibration parameters (:class:`~..discrepancy.calibration.CalParam`) for the vehicle fields
    ``names`` that have a plausible range in the vehicle file, whether or not the file marks them for the
    discrepancy finder's calibration; ``range_scale`` {field: factor} narrows a range about its centre
    (the car-to-car spread where the file's range also holds our own uncertainty of the value)."""
    vp = model.vehicle
    missing = [n for n in names if n not in vp.priors]
    if missing:
        raise ConfigError(f"inspection nuisance parameters without a range in {vp.source_file}: {missing}")
    marked = {k: dataclasses.replace(p, calibrate=k in names) for k, p in vp.priors.items()}
    out = calibration_params(dataclasses.replace(vp, priors=marked), model.variant)
    scale = range_scale or {}
    return [dataclasses.replace(p, lo=p.prior - scale[p.field] * (p.prior - p.lo),
                                hi=p.prior + scale[p.field] * (p.hi - p.prior)) if p.field in scale else p
            for p in out]


def oil_candidate(groups: Sequence[tuple[str, tuple[int, ...]]], prior_sd: float) -> Candidate:
    """The oil levels as one candidate of the fitting machinery: one parameter per group of wheels
    (``("front", (0, 1))`` for an axle, ``("FL", (0,))`` for a wheel), written into the kernel's ``OIL``
    entries (which blend the hydraulic curves and scale the damper friction, model-spec 1)."""
    k = P_INDEX["OIL"]

    def apply(P, _P0, x, _model):
        for (_, wheels), v in zip(groups, x):
            for w in wheels:
                P[:, k + w] = v

    params = tuple(CandParam(f"oil_{name}", "1", 0.5, 0.0, 1.0, 0.05, f"oil level {name} (1 intact, 0 empty)",
                             prior_sd=prior_sd) for name, _ in groups)
    return Candidate("oil_level", CALIBRATION, "damper oil levels", params, apply,
                     tuple(None for _ in groups), "a bump crossing", "bump")


def curve_beyond_candidate(model: Model, prior_sd: float) -> Candidate:
    """Per axle, a factor on the intact damper curve's slope beyond its last measured point: the curve's
    hydraulic force at the kernel's grid velocities beyond ``v_end`` (the vehicle file's outermost
    measured velocity, both directions) becomes ``F(v_end) + s (F(v) - F(v_end))``, ``s`` = 1 the vehicle
    file's linear extrapolation. Prior 1 +- ``prior_sd``, bounds [0, 3] (the force never falls with the
    velocity).

    Why (issue 27): a faster or higher crossing drives the dampers to 1.3-3 m/s, beyond the curve's last
    measured point (1 m/s): the force there is an assumption -- the last segment's slope continued,
    where a real valve may blow off (flatter) or choke (steeper), and another simulator's curve shape
    (PCHIP, Akima) extrapolates otherwise. Held at 1 the fit pays for a wrong extrapolation with the oil
    level, which also scales the force there: intact cars read 0.91-0.92 at 14 km/h over 7.5 cm on the
    development forms with it fixed, 0.99-1.00 with it free. Free, the high-velocity part of the crossing
    pins the factor and the low-velocity part (the body ringing out, inside the measured range) the oil
    level; a slow crossing never reaches beyond the curve and leaves the factor at its prior, without
    effect on the oil. An oil-empty damper's curve is not changed (its oil weight is 0 there anyway)."""
    vel = np.asarray(model.vehicle.damper_velocity, float)
    v_hi, v_lo = float(vel.max()), float(vel.min())
    beyond = np.nonzero((DAMPER_GRID > v_hi + 1e-9) | (DAMPER_GRID < v_lo - 1e-9))[0]
    ref = {int(g): int(np.argmin(np.abs(DAMPER_GRID - (v_hi if DAMPER_GRID[g] > 0 else v_lo)))) for g in beyond}

    def apply(P, _P0, x, _model):
        for (_axle, corners), f in zip(AXLE_CORNERS.items(), x):
            for w in corners:
                base = P_H_INTACT + w * N_GRID
                for g, g_ref in ref.items():
                    P[:, base + g] = P[:, base + g_ref] + f * (P[:, base + g] - P[:, base + g_ref])

    params = tuple(CandParam(f"curve_beyond_{a}", "1", 1.0, 0.0, 3.0, 0.05,
                             f"{a} intact damper curve's slope beyond its last measured point (1: extrapolated "
                             "linearly)", prior_sd=prior_sd) for a in AXLE_CORNERS)
    return Candidate("curve_beyond", CALIBRATION, "intact damper curve beyond its measured points", params, apply,
                     tuple(None for _ in AXLE_CORNERS), "a crossing that drives the dampers beyond 1 m/s", "bump")


def oil_structure(model: Model, cal, groups: Sequence[tuple[str, tuple[int, ...]]], est: dict) -> Structure:
    """The structure the inspection fits: [calibration of the nuisances ``cal``, oil ``groups``, the
    per-axle curve-beyond factors when ``curve_beyond_prior_sd`` > 0, sensor bias]; the oil levels at
    ``offsets[1]``."""
    items: list = [calibration_candidate(model, cal), oil_candidate(groups, est["oil_prior_sd"])]
    sd = float(est.get("curve_beyond_prior_sd", 0.0))
    if sd > 0.0:
        items.append(curve_beyond_candidate(model, sd))
    return Structure(items + ["sensor_bias"])


@dataclass
class Inspection:
    """Result of :func:`inspect_drives` (fitted attributes end in ``_``)."""

    wheels_: dict
    axles_: dict
    nuisance_: list
    fit_: FitResult = field(repr=False)
    evaluator_: Evaluator = field(repr=False)
    identifiability_: dict = field(default_factory=dict)
    elapsed_s_: float = 0.0
    noise_: dict = field(default_factory=dict)
    vehicle_: str = ""
    notes_: list = field(default_factory=list)
    protocol_: dict = field(default_factory=dict)   # the crossings seen against the test protocol
    left_right_: list = field(default_factory=list)  # per axle: left minus right oil level (left_right)
    wheel_loads_: dict | None = None  # the measured static wheel loads and the sprung mass they give
    oil_law_: OilLaw = field(default_factory=OilLaw)  # how the fitted force fractions were read as oil levels

    def to_json(self) -> dict:
        """The interface object (interface.md, ``susp inspect``) plus details."""
        return {"wheels": self.wheels_, "axles": self.axles_, "elapsed_s": self.elapsed_s_,
                "vehicle": self.vehicle_, "nuisance": self.nuisance_,
                "identifiability": self.identifiability_, "noise": self.noise_, "notes": self.notes_,
                "protocol": self.protocol_, "left_right": self.left_right_, "wheel_loads": self.wheel_loads_,
                "oil_law": self.oil_law_.to_json(),
                "fit": {"success": self.fit_.success, "message": self.fit_.message, "nfev": self.fit_.nfev,
                        "rms_x_noise": math.sqrt(self.fit_.rss / max(self.fit_.n, 1))}}




def _vehicle_name(cases: Sequence[DriveCase], config: str | None, notes: list) -> str:
    """``--config``, else the drives' ``vehicle`` metadata when it names a known parameter set, else the
    reference car (said in ``notes``)."""
    if config:
        return config
    names = {c.metadata.get("vehicle", "") for c in cases} - {""}
    if len(names) == 1:
        name = names.pop()
        try:
            load_vehicle(name)
            return name
        except ConfigError:
            notes.append(f"the drives name vehicle {name!r}, not a known parameter set: fitted as "
                         f"{DEFAULT_VEHICLE} with its class ranges (give --config to choose)")
    elif len(names) > 1:
        notes.append(f"the drives name several vehicles {sorted(names)}: fitted as {DEFAULT_VEHICLE}")
    return DEFAULT_VEHICLE


def prepare(paths: Sequence[str | Path], config: str | None = None, variant: str = "full",
            cfg: dict | None = None, topic_map=None, notes: list | None = None) -> tuple[Model, Evaluator, dict]:
    """Read the drives and set up the evaluator: signals narrowed to the configured ones, the recorded
    oil levels withheld from the estimator (every drive starts intact), noise per drive and signal from
    the measurement itself (robust std of its 3rd differences), quiet lead-ins for the sensor bias.

    ``topic_map``: how recordings in another layout are read (``--topic-map``, interface.md "Topic
    maps"; :mod:`susp_sim_ros.io.topic_map`), ``None`` for the interface's own topics.
    """
    cfg = load_config() if cfg is None else cfg
    notes = [] if notes is None else notes
    vp = load_vehicle(config or DEFAULT_VEHICLE)
    cases = load_cases(paths, wheelbase=vp.wheelbase, topic_map=topic_map)
    name = _vehicle_name(cases, config, notes)
    model = Model(name, variant)
    ev, noise = evaluator_for(model, cases, cfg)
    return model, ev, noise


def evaluator_for(model: Model, cases: Sequence[DriveCase], cfg: dict) -> tuple[Evaluator, dict]:
    """The :class:`Evaluator` of prepared drives ``cases`` for ``model``: signals narrowed to the
    configured ones, the recorded oil levels withheld (every drive starts intact), noise per drive and
    signal from the measurement itself (robust std of its 3rd differences), quiet lead-ins marked for
    the sensor bias. IntegrityError (exit 2) when the integrity check found one of the configured signals
    dead (``dead_sensor``) in a drive read from a recording."""
    want = list(cfg["estimator"]["signals"])
    noise = {}
    for c in cases:
        if isinstance(c.drive, TestDrive):  # a signal the integrity check found dead is no measurement
            require_live_imu(c.drive, c.path, "the inspection", signals=tuple(want),
                             need=f"every one of {', '.join(want)} live")
        c.oil = np.ones(4)          # the estimator is not told the recorded state
        select_signals(c, want)
        if not c.signals:
            raise SuspInputError(f"{c.path}: none of the signals {want} recorded on /imu/data")
        y_raw = c.y_raw
        assert y_raw is not None, "load_cases keeps every measured signal of a drive"
        noise[c.name] = {s: noise_sigma(y_raw[:, SIGNALS.index(s)]) for s in c.signals}
        bad = [s for s, v in noise[c.name].items() if not (math.isfinite(v) and v > 0)]
        if bad:
            raise SuspInputError(f"{c.path}: /imu/data {bad}: no measurable noise (constant or too few samples)")
    ev = Evaluator(model, cases)
    base = ev.simulate(Structure([]), np.zeros((1, 0)))[0]
    for r, c in enumerate(cases):
        mark_quiet(c, base[r][:, :3])
    ev.set_noise([np.array([noise[c.name][s] for s in c.signals]) for c in cases])
    add_signal_model_form(ev, cfg["estimator"].get("signal_model_form") or {})
    return ev, noise


def signal_excursion(y: np.ndarray) -> float:
    """RMS excursion of one measured signal about its median over the compared samples (native units):
    how hard the drive moved it."""
    y = np.asarray(y, float)
    return float(np.sqrt(np.mean((y - np.median(y)) ** 2))) if y.size else 0.0


def add_signal_model_form(ev: Evaluator, fractions: dict) -> None:
    """Widen each compared signal's residual sd from its white noise ``sigma_n`` to
    ``hypot(sigma_n, f * A)``: ``f`` the signal's model-form fraction (``fractions``, config
    ``estimator.signal_model_form``), ``A`` its RMS excursion in the drive (:func:`signal_excursion`).

    Why (issue 27): the misfit a car that is not our model leaves is not white noise; it grows with the
    excitation. The vertical specific force carries the suspension forces directly -- the damper force
    at velocities beyond the measured curve points (extrapolated), bump-stop contact, wheel hop and tyre
    lift-off after a fast or high bump, the integrator's handling of the impact -- all of which the drive
    cannot check and which the fit would otherwise absorb into the oil level (intact cars read 0.7-0.8 on
    the development forms at 14 km/h). The body rates see those forces only integrated over the body's
    inertia, dominated by the body modes whose damping, at damper velocities inside the measured range,
    is what tells the oil level. So a signal counts less the harder the drive moves it, the accelerometer
    three times as fast as the gyros (its fraction 0.3 against 0.1, learned on the development forms);
    a signal the drive barely moves (the roll rate of a full-width bump) keeps its noise weight, so a
    one-sided damping loss still shows in it."""
    for r, c in enumerate(ev.cases):
        for j, s in enumerate(c.signals):
            f = float(fractions.get(s, 0.0))
            if f > 0.0:
                w = ev.weights[r][:, j]
                sigma = 1.0 / np.maximum(w, 1e-300)
                ev.weights[r][:, j] = np.where(w > 0, 1.0 / np.hypot(sigma, f * signal_excursion(c.y_meas[:, j])), 0.0)


def _information(ev: Evaluator, st: Structure, x: np.ndarray) -> np.ndarray:
    """Posterior covariance of ``st``'s parameters from the linearisation at ``x`` (data at their
    effective sample size, as :meth:`FitResult.covariance`, plus the priors)."""
    idx = tuple(range(len(ev.cases)))
    r, J = fd_jacobian(ev, st, x, idx)
    if st.bias:
        J = debias(ev, J, idx)
    ratio = n_effective(ev, idx) / J.shape[0]
    H = ratio * (J.T @ J)
    pidx, _, psd = st.prior()
    H[pidx, pidx] += 1.0 / psd ** 2
    return np.linalg.pinv(H)


def _tracks_differ(cases: Sequence[DriveCase], tol_m: float = 1e-3) -> bool:
    """Whether any drive's road differs between the left and right tracks by more than ``tol_m``."""
    for c in cases:
        road = c.road
        if isinstance(road, RoadProfile) and len(road) >= 2 and np.max(
                np.abs(np.asarray(road.zl) - np.asarray(road.zr))) > tol_m:
            return True
        zr = c.U[:, U_INDEX["ZR_IN"]:U_INDEX["ZR_IN"] + 4]
        if np.max(np.abs(zr[:, 0] - zr[:, 1])) > tol_m or np.max(np.abs(zr[:, 2] - zr[:, 3])) > tol_m:
            return True
    return False


def _road_excites(cases: Sequence[DriveCase], tol_m: float = 1e-3) -> bool:
    """Whether any drive's road (profile or wheel heights) leaves the flat by more than ``tol_m``."""
    for c in cases:
        road = c.road
        if isinstance(road, RoadProfile) and len(road) >= 2 and np.max(
                np.abs(np.concatenate([road.zl, road.zr]))) > tol_m:
            return True
        if np.max(np.abs(c.U[:, U_INDEX["ZR_IN"]:U_INDEX["ZR_IN"] + 4])) > tol_m:
            return True
    return False


def oil_identifiability(ev: Evaluator, cal, cfg: dict) -> dict:
    """Per axle: ``wheel`` (left and right told apart), ``axle`` (only their mean) or ``no``, with the
    posterior sds it was decided on (linearised at half oil, nuisances at their prior centre)."""
    est = cfg["estimator"]
    groups = [(w, (i,)) for i, w in enumerate(CORNER_NAMES)]
    st = oil_structure(ev.model, cal, groups, est)
    x = st.neutral()
    cov = _information(ev, st, x)
    o = st.offsets[1]
    C = cov[o:o + 4, o:o + 4]
    out = {}
    for axle, (l, r) in AXLE_CORNERS.items():
        d = np.zeros(4)
        d[l], d[r] = 1.0, -1.0
        m = np.zeros(4)
        m[l] = m[r] = 0.5
        sd_diff = float(math.sqrt(max(d @ C @ d, 0.0)))
        sd_mean = float(math.sqrt(max(m @ C @ m, 0.0)))
        if sd_mean > est["identifiable_max_sd"]:
            kind = "no"
            why = (f"the drives do not excite the {axle} dampers: their mean oil level is pinned only to a "
                   f"posterior sd of {sd_mean:.2f} (needs <= {est['identifiable_max_sd']:g})")
        elif sd_diff <= est["per_wheel_max_sd"]:
            kind = "wheel"
            if _tracks_differ(ev.cases):
                how = "the left and right tracks were excited differently"
            elif _road_excites(ev.cases):
                how = ("both tracks were excited alike, but a left-right damping difference rolls the body "
                       "and the roll rate shows it")
            else:
                how = ("the road is flat: the maneuver itself (steering, braking) moved the suspension and "
                       "rolled the body")
            why = (f"left and right {axle} dampers told apart: {how}; their oil difference is pinned to a "
                   f"posterior sd of {sd_diff:.3f} (<= {est['per_wheel_max_sd']:g})")
        else:
            kind = "axle"
            if not any("roll_rate" in c.signals for c in ev.cases):
                cause = "no roll rate is compared, which would show a left-right damping difference"
            elif _tracks_differ(ev.cases):
                cause = "the roll the tracks' difference caused does not separate them"
            else:
                cause = "left and right were excited alike and the roll stayed too small to separate them"
            why = (f"only the {axle} axle's mean oil level is identifiable (sd {sd_mean:.2f}): {cause}; the "
                   f"left-right difference stays at sd {sd_diff:.2f} (> {est['per_wheel_max_sd']:g})")
        out[axle] = {"identifiable": kind, "why": why, "sd_mean": sd_mean, "sd_difference": sd_diff}
    return out


def _oil_groups(ident: dict) -> list[tuple[str, tuple[int, ...]]]:
    """The oil-level parameters to fit, as (name, corners): one per wheel where the drives tell left
    from right (``wheel``), one per axle where they pin only the mean (``axle``), none where not even
    that (``no``)."""
    groups: list = []
    for axle, (l, r) in AXLE_CORNERS.items():
        kind = ident[axle]["identifiable"]
        if kind == "wheel":
            groups += [(CORNER_NAMES[l], (l,)), (CORNER_NAMES[r], (r,))]
        elif kind == "axle":
            groups.append((axle, (l, r)))
    return groups


def _broyden_updates(est: dict) -> int:
    """The oil fit's Broyden updates per simulated Jacobian (``estimator.broyden_updates``; a settings file
    of before that key: 0, every Jacobian simulated, as the fit always ran then)."""
    return int(est.get("broyden_updates", 0))


def _fit_oil(model: Model, ev: Evaluator, cal, groups: list, est: dict) -> tuple[Structure, FitResult, np.ndarray]:
    """The maximum a posteriori fit of nuisances, oil ``groups`` [-, 0..1] and sensor bias, and its
    covariance (with the ``consider`` parameters' share when configured); without any oil group the
    nuisances alone, one evaluation (nothing to estimate, the fit only supplies the structure)."""
    updates = _broyden_updates(est)
    if groups:
        st = oil_structure(model, cal, groups, est)
        fit = fit_structure(ev, st, max_nfev=int(est["max_nfev"]), broyden_updates=updates)
    else:
        st = Structure([calibration_candidate(model, cal), "sensor_bias"])
        fit = fit_structure(ev, st, max_nfev=1, broyden_updates=updates)
    cov = fit.covariance()
    if groups and est.get("consider"):
        cov = cov + oil_consider_covariance(ev, fit, cal, nuisance_params(model, est["consider"]))
    return st, fit, cov


def model_form_sd(seen: Sequence[dict], est: dict, factor: float = 1.0) -> dict[str, float]:
    """Per axle, the model-form sd [oil fraction] of its oil level: ``model_form_sd`` plus
    ``model_form_sd_per_m_s`` times the axle's peak damper velocity over the drives (the fitted model's,
    :func:`protocol.crossings`), times ``factor`` (outside the protocol).

    Why it grows with the damper velocity (issue 27, learned on the truth family's development forms):
    the faster the dampers run, the more of the crossing lies beyond the damper curve's measured points
    (its shape there is assumed), in bump-stop contact, wheel hop and tyre lift-off, and the more the
    integrator and the friction's velocity scaling differ in how they carry the impact: the car that is
    not our model then differs from it in ways the drive cannot check, and the oil level absorbs part of
    it. A slow crossing keeps the dampers where the curve is measured and the base term holds."""
    base, slope = float(est["model_form_sd"]), float(est.get("model_form_sd_per_m_s", 0.0))
    peak = {a: max((float(s["peak_damper_velocity_m_s"][a]) for s in seen), default=0.0) for a in AXLE_CORNERS}
    return {a: factor * (base + slope * v) for a, v in peak.items()}


def _check_protocol(ev: Evaluator, fit: FitResult, ident: dict, cfg: dict, model: Model,
                    notes: list) -> tuple[list, list, dict]:
    """The crossings the drives made against the test protocol: (seen, warnings, model-form sd [-] of
    the oil levels per axle, grown with the axle's peak damper velocity and widened outside the
    protocol); the warnings and damper-curve notes go to ``notes``."""
    seen = protocol.crossings(ev, fit.structure, fit.x)
    found = protocol.warnings(seen, ident, cfg["protocol"])
    # outside the protocol the model-form error is larger than where the inspection was validated
    sd_m = model_form_sd(seen, cfg["estimator"], protocol.model_form_factor(found, cfg["protocol"]))
    notes += [f"outside the test protocol: {w['drive'] + ': ' if w['drive'] else ''}{w['reason']}" for w in found]
    notes += protocol.curve_notes(seen, model.vehicle.damper_velocity)
    return seen, found, sd_m


def _axle_of(name: str) -> str:
    """The axle of an oil group: its own name for an axle group, the wheel's axle for a wheel group."""
    if name in AXLE_CORNERS:
        return name
    k = CORNER_NAMES.index(name)
    return next(a for a, corners in AXLE_CORNERS.items() if k in corners)


class GroupLevel(NamedTuple):
    """One fitted oil group as reported: the oil level [-] and its 95 % interval, the fit's parameter index
    of the group's force fraction, and d(oil level)/d(force fraction) there (the oil law's slope)."""

    level: float
    lo: float
    hi: float
    param: int
    slope: float = 1.0


def _group_intervals(groups: list, oil_off: int, x: np.ndarray, se: np.ndarray, sd_m: dict,
                     law: OilLaw) -> dict[str, GroupLevel]:
    """{group: GroupLevel}: the fitted force fraction [-] with the posterior sd ``se`` and its axle's
    model-form sd ``sd_m`` combined into a 95 % interval, clipped to [0, 1], and the three read as oil
    levels through the damper type's oil ``law`` (monotone, so the interval maps onto the level's)."""
    by_group = {}
    for g, (name, _wheels) in enumerate(groups):
        j = oil_off + g
        w = float(x[j])
        s = math.hypot(se[j], sd_m[_axle_of(name)])
        by_group[name] = GroupLevel(law.level(w), law.level(max(0.0, w - 1.96 * s)),
                                    law.level(min(1.0, w + 1.96 * s)), j, law.slope(w))
    return by_group


def _axle_model_form_sd(sd_m: dict, axle: str, a: GroupLevel, b: GroupLevel) -> float:
    """The axle's model-form sd (a force fraction) as an oil level, through the mean slope of its two sides."""
    return sd_m[axle] * 0.5 * (a.slope + b.slope)


def _wheel_and_axle_levels(ident: dict, by_group: dict[str, GroupLevel], cov: np.ndarray, sd_m: dict,
                           states_cfg: dict) -> tuple[dict, dict]:
    """The report's entries per wheel and per axle: oil level [-], 95 % interval, state, the fit's own sd
    (``sd_fit``: Gauss-Newton and consider parts, without the model-form term, as an oil level) and what
    the drives can tell. A wheel of an ``axle`` group carries the axle's figures; an axle of two ``wheel``
    groups the mean of its wheels' levels (their covariance carried through the oil law's slopes)."""
    wheels, axles = {}, {}

    def entry(v, lo, hi, sd_fit, kind, why):
        return {"oil_level": v, "ci95": [lo, hi], "state": state_of(lo, hi, states_cfg),
                "sd_fit": float(sd_fit), "identifiable": kind, "why": why}

    for axle, (l, r) in AXLE_CORNERS.items():
        info = ident[axle]
        kind = info["identifiable"]
        if kind == "no":
            none = {"oil_level": None, "ci95": None, "state": "unknown"}
            for w in (l, r):
                wheels[CORNER_NAMES[w]] = dict(none, identifiable="no", why=info["why"])
            axles[axle] = dict(none, identifiable="no", why=info["why"])
            continue
        if kind == "axle":
            gl = by_group[axle]
            v, lo, hi = gl.level, gl.lo, gl.hi
            sd_fit = gl.slope * math.sqrt(max(cov[gl.param, gl.param], 0.0))
            for w in (l, r):
                wheels[CORNER_NAMES[w]] = entry(v, lo, hi, sd_fit, "axle", info["why"])
        else:
            for w in (l, r):
                gw = by_group[CORNER_NAMES[w]]
                wheels[CORNER_NAMES[w]] = entry(gw.level, gw.lo, gw.hi,
                                                gw.slope * math.sqrt(max(cov[gw.param, gw.param], 0.0)),
                                                "wheel", info["why"])
            a, b = by_group[CORNER_NAMES[l]], by_group[CORNER_NAMES[r]]
            v = 0.5 * (a.level + b.level)
            var = (a.slope ** 2 * cov[a.param, a.param] + b.slope ** 2 * cov[b.param, b.param]
                   + 2 * a.slope * b.slope * cov[a.param, b.param])
            sd_fit = 0.5 * math.sqrt(max(var, 0.0))
            s = math.hypot(sd_fit, _axle_model_form_sd(sd_m, axle, a, b))
            lo, hi = max(0.0, v - 1.96 * s), min(1.0, v + 1.96 * s)
        axles[axle] = entry(v, lo, hi, sd_fit, kind, info["why"])
    return wheels, axles


def left_right(ident: dict, by_group: dict[str, GroupLevel], cov: np.ndarray, sd_m: dict, tracks_differ: bool,
               axles: dict, lr_cfg: dict) -> list[dict]:
    """Per axle, the workshop's left-against-right comparison (the EUSAMA test's practice: an axle's
    left-right difference is judged besides each wheel's value): ``{"axle", "difference", "ci95",
    "sd", "asymmetric", "reason"}``, ``difference`` the left minus the right oil level [oil fraction].

    The interval is ``difference +- 1.96 sd`` (clipped to [-1, 1]) with ``sd`` from the fit's joint
    covariance of the two dampers (``var_l + var_r - 2 cov_lr``; Gauss-Newton posterior plus the
    consider part, so whatever the nuisances, the curve-beyond factors and the oil-empty curve's slope
    do to both sides alike cancels through their correlation), each side's sd carried from its force
    fraction to its oil level by the oil law's slope there (:class:`GroupLevel`).

    How the model-form sd is treated: on a crossing that excites both tracks alike it is left out of
    the difference. In the estimator it is one figure per axle (:func:`model_form_sd`, from the axle's
    peak damper velocity, the same for both wheels), standing for what the drive cannot check on that
    axle -- the damper curve beyond its measured points (fitted as ONE factor per axle,
    :func:`curve_beyond_candidate`, applied to both corners alike), bump-stop contact, wheel hop, tyre
    lift-off, the integrator's handling of the impact. A full-width bump strokes both dampers of an axle
    alike, so these errors enter both sides' forces alike and move both oil levels together: they sit in
    the axle's mean, which the pitch rate and the vertical specific force carry. The difference is read
    from the roll a left-right damping difference causes (``wheel`` identifiability is decided on
    exactly the posterior sd of this difference, :func:`oil_identifiability`), and an error common to
    both sides rolls nothing. What differs between the sides (the sensor noise, the per-wheel oil and
    consider parameters) is in the fit's covariance. When the drives excite the tracks differently
    (a one-sided bump) the two dampers run at different velocities and the common-mode argument fails:
    then the two sides' model-form errors are taken as independent, ``sd_m * sqrt(2)`` added in
    quadrature. Flagged ``asymmetric`` when the interval excludes zero AND ``|difference|`` exceeds
    ``lr_cfg["asymmetric_min_difference"]`` (``config/inspection.yaml`` ``left_right``). An axle whose
    sides the drives do not tell apart (``axle``/``no`` identifiability) has no difference (None),
    never flagged, with the reason."""
    thr = float(lr_cfg["asymmetric_min_difference"])
    out: list[dict] = []
    for axle, (l, r) in AXLE_CORNERS.items():
        kind = ident[axle]["identifiable"]
        nl, nr = CORNER_NAMES[l], CORNER_NAMES[r]
        if kind != "wheel":
            why = ("the drives do not excite this axle" if kind == "no"
                   else "the drives do not tell its left from its right damper (only their mean)")
            out.append({"axle": axle, "difference": None, "ci95": None, "sd": None, "asymmetric": False,
                        "reason": f"{axle}: no left-right comparison: {why}"})
            continue
        a, b = by_group[nl], by_group[nr]
        jl, jr = a.param, b.param
        d = float(a.level - b.level)
        var = max(float(a.slope ** 2 * cov[jl, jl] + b.slope ** 2 * cov[jr, jr]
                        - 2.0 * a.slope * b.slope * cov[jl, jr]), 0.0)
        if tracks_differ:
            var += 2.0 * _axle_model_form_sd(sd_m, axle, a, b) ** 2
        sd = math.sqrt(var)
        lo, hi = max(-1.0, d - 1.96 * sd), min(1.0, d + 1.96 * sd)
        excludes_zero = lo > 0.0 or hi < 0.0
        flag = bool(excludes_zero and abs(d) > thr)
        ci = f"[{lo:.2f}, {hi:.2f}]"
        # in words: the lower side, by how much, the interval of that gap (the difference's, sign turned)
        lower, higher = (f"left ({nl})", f"right ({nr})") if d < 0 else (f"right ({nr})", f"left ({nl})")
        gap = f"{abs(d):.2f} lower than {higher} [{min(abs(lo), abs(hi)):.2f}, {max(abs(lo), abs(hi)):.2f}]"
        if flag:
            reason = (f"{axle}: {lower} {gap}: one damper has lost oil against the other (asymmetric: more "
                      f"than {thr:.2f} apart)")
        elif excludes_zero:
            reason = (f"{axle}: {lower} {gap}: a difference, but not more than {thr:.2f}: within what the "
                      "workshop practice accepts")
        else:
            state = axles.get(axle, {}).get("state")
            both = {"ok": ": both intact", "empty": ": both have lost their oil (the axle as a whole)",
                    "degraded": ": both have lost oil alike (the axle as a whole)"}.get(state or "", "")
            reason = f"{axle}: left and right alike, left minus right {d:+.2f} {ci}{both}"
        out.append({"axle": axle, "difference": d, "ci95": [lo, hi], "sd": sd, "asymmetric": flag,
                    "reason": reason})
    return out


def _nuisance_entries(cal, x: np.ndarray, se: np.ndarray) -> list[dict]:
    """The fitted nuisance parameters (in their own units) with prior, prior range and 95 % interval."""
    return [{"param": p.name, "unit": p.unit, "prior": p.prior, "prior_range": [p.lo, p.hi],
             "value": float(x[k]), "ci95": [float(x[k] - 1.96 * se[k]), float(x[k] + 1.96 * se[k])]}
            for k, p in enumerate(cal)]


def _curve_beyond_entries(st: Structure, x: np.ndarray, se: np.ndarray) -> list[dict]:
    """The fitted curve-beyond factors (:func:`curve_beyond_candidate`) as nuisance entries."""
    c = st.names.index("curve_beyond")
    out = []
    for k, p in enumerate(st.cands[c].params):
        j = st.offsets[c] + k
        sd = float(p.prior_sd or 0.0)
        out.append({"param": p.name, "unit": p.unit, "prior": p.neutral,
                    "prior_range": [p.neutral - 2 * sd, p.neutral + 2 * sd], "value": float(x[j]),
                    "ci95": [float(x[j] - 1.96 * se[j]), float(x[j] + 1.96 * se[j])]})
    return out


def scale_accuracy(cfg: dict | None = None) -> float:
    """The relative sd of one weighed static wheel load (settings ``wheel_loads.scale_accuracy``; the
    inspection's and the diagnosis's ``--wheel-loads``)."""
    cfg = load_config() if cfg is None else cfg
    acc = cfg.get("wheel_loads", {}).get("scale_accuracy")
    if acc is None:
        raise ConfigError("wheel loads given but the inspection settings have no wheel_loads.scale_accuracy")
    return float(acc)


def inspect_drives(paths: Sequence[str | Path], config: str | None = None, variant: str = "full",
                   cfg: dict | None = None, topic_map=None,
                   wheel_loads_n: Sequence[float] | None = None, oil_law: OilLaw | None = None) -> Inspection:
    """Estimate each damper's oil level with a 95 % interval from the drives ``paths``: what the drives
    can tell (:func:`oil_identifiability`), the fit of oil levels and nuisances, the test protocol, and
    the levels per wheel and axle. ``wheel_loads_n``: the car's measured static wheel loads FL, FR, RL, RR
    [N], when weighed (:func:`sprung_mass_from_wheel_loads`). ``oil_law``: the damper type's oil law
    (:class:`~.oil_law.OilLaw`, from a rig test), else the settings' ``damper_type.oil_law``, else the
    model's own: the fit estimates each damper's remaining force fraction, the law reads it as oil."""
    t_start = time.perf_counter()
    cfg = load_config() if cfg is None else cfg
    est = cfg["estimator"]
    law = OilLaw.from_settings(cfg) if oil_law is None else oil_law
    notes: list = []
    model, ev, noise = prepare(paths, config, variant, cfg, topic_map, notes)
    cal = nuisance_params(model, est["nuisance"], est.get("nuisance_range_scale"))
    loads_entry: dict | None = None
    if wheel_loads_n is not None:
        cal, loads_entry = sprung_mass_from_wheel_loads(cal, wheel_loads_n, model.vehicle.gravity,
                                                        scale_accuracy(cfg))
    ident = oil_identifiability(ev, cal, cfg)
    groups = _oil_groups(ident)
    st, fit, cov = _fit_oil(model, ev, cal, groups, est)
    se = np.sqrt(np.clip(np.diag(cov), 0, None))
    seen, found, sd_m = _check_protocol(ev, fit, ident, cfg, model, notes)
    oil_off: int = st.offsets[1] if groups else 0     # unused without groups
    by_group = _group_intervals(groups, oil_off, fit.x, se, sd_m, law)
    wheels, axles = _wheel_and_axle_levels(ident, by_group, cov, sd_m, cfg["states"])
    lr = (left_right(ident, by_group, cov, sd_m, _tracks_differ(ev.cases), axles, cfg["left_right"])
          if "left_right" in cfg else [])   # a settings file of before the comparison has no section
    nuis = _nuisance_entries(cal, fit.x, se)
    if "curve_beyond" in st.names:
        nuis += _curve_beyond_entries(st, fit.x, se)
    if not fit.success and fit.nfev < int(est["max_nfev"]):
        notes.append(f"fit did not converge: {fit.message}")
    res = Inspection(wheels, axles, nuis, fit, ev, ident, 0.0, noise, model.vehicle.name, notes,
                     {"validated_for": dict(cfg["protocol"]), "seen": seen, "warnings": found,
                      "model_form_sd": max(sd_m.values()), "model_form_sd_per_axle": sd_m}, lr)
    res.wheel_loads_ = loads_entry
    res.oil_law_ = law
    res.elapsed_s_ = time.perf_counter() - t_start
    return res


def oil_consider_covariance(ev: Evaluator, fit: FitResult, cal, consider) -> np.ndarray:
    """Covariance added to the fitted parameters by the uncertainty of the ``consider`` parameters
    (held at their prior centre, prior sd as in the vehicle file): ``S Sigma_c S^T`` with the
    sensitivity ``S = -H^-1 (w J_a^T J_c)`` of the weighted least-squares estimate to them (Schmidt's
    consider covariance), from one forward-difference Jacobian at the fitted values. ``fit``'s structure
    is [calibration of ``cal``, oil levels, sensor bias]."""
    k_cal, n_c = len(cal), len(consider)
    ext = Structure([calibration_candidate(ev.model, list(cal) + list(consider))] + list(fit.structure.cands[1:]))
    x = np.concatenate([fit.x[:k_cal], [p.prior for p in consider], fit.x[k_cal:]])
    idx = tuple(range(len(ev.cases)))
    _, J = fd_jacobian(ev, ext, x, idx)
    if ext.bias:
        J = debias(ev, J, idx)
    cols_c = np.arange(k_cal, k_cal + n_c)
    cols_a = np.setdiff1d(np.arange(J.shape[1]), cols_c)
    Ja, Jc = J[:, cols_a], J[:, cols_c]
    w = n_effective(ev, idx) / J.shape[0]
    H = w * (Ja.T @ Ja)
    pidx, _, psd = fit.structure.prior()
    H[pidx, pidx] += 1.0 / psd ** 2
    S = -np.linalg.pinv(H) @ (w * (Ja.T @ Jc))
    sd_c = np.array([p.sd for p in consider])
    return S @ np.diag(sd_c ** 2) @ S.T


def one_step_estimate(ev: Evaluator, cal, cfg: dict) -> tuple[np.ndarray, np.ndarray]:
    """The cheap model-based statistic of the ROC study: ONE Gauss-Newton step of exactly the objective
    :func:`inspect_drives` minimises (the same whitened residuals of the same signals, the same
    effective-sample weighting and priors), per wheel, taken from the intact car at the prior centre
    (oil 1 on every wheel, every nuisance at its vehicle-file value) and clipped to the bounds.

    It costs one batch of 1 + n_params simulations (the Jacobian), where the full fit takes several
    and an identifiability pass. Returns the four oil levels FL, FR, RL, RR and their linearised sds
    (noise-only, without the model-form term). Near intact it is the full fit's first iterate; far from
    it (an empty damper) the step overshoots or stops short, but in the same direction, so it ranks cars
    as the full estimate does (test_inspection_roc checks both)."""
    est = cfg["estimator"]
    groups = [(w, (i,)) for i, w in enumerate(CORNER_NAMES)]
    st = oil_structure(ev.model, cal, groups, est)
    o = st.offsets[1]
    x0 = st.neutral()
    x0[o:o + 4] = 1.0
    idx = tuple(range(len(ev.cases)))
    r, J = fd_jacobian(ev, st, x0, idx)
    if st.bias:
        r, J = debias(ev, r, idx), debias(ev, J, idx)
    ratio = n_effective(ev, idx) / J.shape[0]
    pidx, pmu, psd = st.prior()
    H = ratio * (J.T @ J)
    g = ratio * (J.T @ r)
    H[pidx, pidx] += 1.0 / psd ** 2
    g[pidx] += (x0[pidx] - pmu) / psd ** 2
    cov = np.linalg.pinv(H)
    lo, hi = st.bounds()
    x1 = np.clip(x0 - cov @ g, lo, hi)
    return x1[o:o + 4], np.sqrt(np.clip(np.diag(cov)[o:o + 4], 0, None))
