"""The library of candidate physics terms the discrepancy finder tests (names: interface.md, TERM).

Every candidate is a physically named change of the model with parameters, bounds and a one-line
meaning, applied to the kernel's flat parameter vector ``P`` (one row per drive). Each carries its whole
meaning: how it edits the parameters (``apply``), whether a variant already has it (``in_variant``), and
how its fitted values are written into config (``term_params`` for a variant's ``terms:``, ``to_vehicle``
for the vehicle file). How each maps onto the model (design choice, see also the package docstring):

- the paper's friction scalings (``damper_friction_velocity``, ``damper_friction_oil``,
  ``friction_longitudinal_force``, ``friction_lateral_force``) use the kernel's own scaling switches and
  their continuous parameters (``SV_INF``/``SV_VS``, ``SOIL_EMPTY``, ``SH_X``/``SH_Y``). A model that has
  a scaling switched off is first rewritten with the switch on at its neutral value (plateau 1, ratio 1,
  slope 0), which is exactly the same model; the candidate then frees the continuous parameters;
- ``friction_amplitude``, ``extra_viscous_damping`` and ``damper_gas_preload`` are registered physics
  terms (:mod:`susp_sim_ros.model.amplitude_friction`, :mod:`susp_sim_ros.model.extra_terms`) added to the
  model at zero effect;
- ``mass_error``, ``inertia_error``, ``spring_rate_error``, ``tyre_relaxation_error`` scale vehicle
  parameters;
- ``steering_offset`` (measurement chain): the recorded steering-wheel angle carries a constant offset;
  the model is driven with the recorded angle minus it;
- ``sensor_bias`` and ``time_offset`` model the measurement chain, not the car: a constant gyro offset
  per drive and axis (estimated, like a standstill zeroing, from the drive's quiet lead-in before the
  first excitation, or, for a drive without one, profiled out as the drive's mean residual; before the
  first excitation, so it needs no maneuver data) and one time shift of the IMU against the inputs.
"""
from __future__ import annotations

import math

from dataclasses import dataclass, field
from collections.abc import Callable

import numpy as np

from ...model.amplitude_friction import FRICTION_AMPLITUDE
from ...model.inline_math import TINY
from ...model.layout import P_INDEX

PHYSICS, PARAMETER, MEASUREMENT = "physics", "parameter", "measurement"
CALIBRATION = "calibration"  # the base model's own parameters (see .calibration), never missing physics


def interval_floor(nonnegative: bool, value: float) -> float:
    """The lowest end a reported 95 % interval of a value ``value`` may show: 0 for a quantity that cannot be
    negative (never above the estimate), else unbounded (-inf)."""
    return min(0.0, value) if nonnegative else -math.inf


@dataclass(frozen=True)
class CandParam:
    """One free parameter: neutral value (no effect), bounds, finite-difference/scale step, unit."""

    name: str
    unit: str
    neutral: float
    lower: float
    upper: float
    step: float
    meaning: str = ""
    prior_sd: float | None = None  # a normal prior around ``neutral`` (calibration values, a law's shape)
    #: the lowest value the physics the term stands for can take (None: ``lower``). The fit may go below
    #: it (a term then stands in for a weaker model element), but a term there is no rival physical
    #: explanation of a calibration value (finder: calibration against physics)
    physical_lower: float | None = None
    #: a parameter that shapes the term's law and has no effect of its own (an exponent: with the term's
    #: gains at neutral there is no force whatever it is); "no effect" and "physical" are read from the
    #: other parameters
    shape: bool = False

    def interval_floor(self, value: float) -> float:
        """The lowest value a reported interval of this parameter may show: 0 for a quantity that cannot be
        negative (a level, a time constant, a stiffness: its lowest physical or fitted value >= 0; never above
        the estimate ``value``), unbounded (-inf) for a signed one. A Gauss-Newton or jackknife interval
        x +- 1.96 se knows no bound; cut at 0 it still holds every value the physics allows, and an interval
        that held zero still does (what "holds no effect" reads is unchanged)."""
        low = self.lower if self.physical_lower is None else self.physical_lower
        return interval_floor(low >= 0.0, value)


@dataclass(frozen=True)
class Candidate:
    """A named candidate term. ``apply(P, x, model)`` edits the (R, n_p) parameter rows in place for the
    parameter values ``x`` (one per :attr:`params`); ``axle_of`` maps parameter index -> 'front'/'rear'
    (or None) for the ``where`` field; ``reveal_with`` names the maneuver that excites it."""

    name: str
    kind: str
    meaning: str
    params: tuple[CandParam, ...]
    apply: Callable | None = field(default=None, repr=False)
    axle_of: tuple[str | None, ...] = ()
    reveal_with: str = ""
    needs: str = ""  # what the drives must contain to identify it: oil_empty, lateral, bump, any
    term_module: str = ""  # physics terms: the module whose import registers the kernel term (written
    #                        into a variant's ``terms:`` so the node can import it)
    switch: str = ""  # the paper's scalings: the variant flag (FrictionVariant field) the candidate stands for
    #: how the fitted values are written: ``(x, vp) -> {(section, key): value}`` for the vehicle file
    to_vehicle: Callable | None = field(default=None, repr=False)
    #: registered terms: ``(x, vp) -> {param: {front, rear}}``, the term's entry in a variant's ``terms:``
    term_params: Callable | None = field(default=None, repr=False)

    @property
    def n_params(self) -> int:
        return len(self.params)

    def in_variant(self, variant) -> bool:
        """Whether ``variant`` (a :class:`~susp_sim_ros.model.params.FrictionVariant`) already has this
        physics: its scaling switched on, or its term among the variant's terms."""
        if self.switch:
            return bool(getattr(variant, self.switch))
        return bool(self.term_module) and any(s.term.name == self.name for s in variant.terms)

    def variant_term(self, x: np.ndarray, vp) -> dict | None:
        """The term's entry in a written variant's ``terms:`` at the fitted values ``x`` with the vehicle
        ``vp`` (calibrated) it was fitted on (None: not a term)."""
        if self.term_params is None:
            return None
        return {"name": self.name, "module": self.term_module, "params": self.term_params(x, vp)}

    def neutral(self) -> np.ndarray:
        return np.array([p.neutral for p in self.params], float)

    @property
    def gain_indices(self) -> tuple[int, ...]:
        """Indices of the parameters that size the term's effect (all but the :attr:`CandParam.shape` ones)."""
        return tuple(j for j, p in enumerate(self.params) if not p.shape)

    def physical(self, x: np.ndarray) -> bool:
        """Whether the term's effect at the parameter values ``x`` is one the physics it stands for can
        have: its dominant parameter (furthest from neutral, in steps) respects its
        :attr:`CandParam.physical_lower` (a small value of the other axle's may sit on either side)."""
        gains = self.gain_indices
        if not gains:
            return True
        k = gains[int(np.argmax([abs(x[j] - self.params[j].neutral) / self.params[j].step for j in gains]))]
        p = self.params[k]
        return bool(x[k] >= (p.lower if p.physical_lower is None else p.physical_lower))

    def effect_in_interval(self, lo: np.ndarray, hi: np.ndarray) -> bool:
        """Whether the 95 % intervals ``[lo, hi]`` of the parameters all hold "no effect" (every
        parameter's neutral value inside its interval; :attr:`CandParam.shape` parameters aside). A term
        without parameters (its effect estimated elsewhere, e.g. a sensor bias) gives False."""
        return bool(self.params) and all(lo[k] <= self.params[k].neutral <= hi[k] for k in self.gain_indices)


def _set_axles(P, key, front, rear):
    k = P_INDEX[key]
    P[:, k:k + 2] = front
    P[:, k + 2:k + 4] = rear


def _scale_axles(P, P0, key, front, rear):
    k = P_INDEX[key]
    P[:, k:k + 2] = P0[:, k:k + 2] * front
    P[:, k + 2:k + 4] = P0[:, k + 2:k + 4] * rear


def _velocity(P, P0, x, model):
    P[:, P_INDEX["USE_V"]] = 1.0
    P[:, P_INDEX["SV_INF"]] = x[0]
    P[:, P_INDEX["SV_VS"]] = x[1]


def _oil(P, P0, x, model):
    P[:, P_INDEX["USE_OIL"]] = 1.0
    _set_axles(P, "SOIL_EMPTY", x[0], x[1])


def _longitudinal(P, P0, x, model):
    P[:, P_INDEX["USE_H"]] = 1.0
    _set_axles(P, "SH_X", x[0] * 1e-3, x[1] * 1e-3)


def _lateral(P, P0, x, model):
    P[:, P_INDEX["USE_H"]] = 1.0
    _set_axles(P, "SH_Y", x[0] * 1e-3, x[1] * 1e-3)


def _term_axles(name, param):
    def apply(P, P0, x, model):
        sl = model.term_param_slice(name, param)
        P[:, sl.start:sl.start + 2] = x[0]
        P[:, sl.start + 2:sl.stop] = x[1]
    return apply


def _amplitude(P, P0, x, model):
    """Extra level per axle, one onset, one memory and one stroke weight: the level grows with the
    deflection amplitude, taken as ``w`` x the stroke amplitude (half the travel between reversals) plus
    ``1 - w`` x the peak deflection from the static position, forgotten with the memory time constant
    (which of the two a car's joints follow is the data's to say), and follows the axle friction's
    horizontal-force scaling. The extra friction sits in the same joints as the axle friction, so it
    slips over the same presliding travel: its Dahl stiffness is the axle friction's times the extra
    level over the axle level (:func:`amplitude_sigma`), not a free value."""
    _term_axles("friction_amplitude", "extra_level")(P, P0, x, model)
    P[:, model.term_param_slice("friction_amplitude", "onset")] = x[2]
    P[:, model.term_param_slice("friction_amplitude", "memory")] = x[3]
    P[:, model.term_param_slice("friction_amplitude", "stroke_weight")] = x[4]
    P[:, model.term_param_slice("friction_amplitude", "horizontal")] = 1.0
    P[:, model.term_param_slice("friction_amplitude", "sigma")] = amplitude_sigma(
        P[:, model.term_param_slice("friction_amplitude", "extra_level")],
        P[:, model.term_param_slice("axle_friction", "level")], P[:, model.term_param_slice("axle_friction", "sigma")])


def amplitude_sigma(extra, axle_level, axle_sigma):
    """Dahl stiffness [N/m] of the extra amplitude friction with the axle friction's presliding travel
    (``axle_level / axle_sigma`` [m]): ``extra * axle_sigma / axle_level`` (per corner or axle; arrays or
    floats), at least the term's lower bound (a zero extra level has no force whatever its stiffness)."""
    lower = FRICTION_AMPLITUDE.params[FRICTION_AMPLITUDE.param_index("sigma")].lower
    return np.maximum(np.asarray(extra, float) * np.asarray(axle_sigma, float) /
                      np.maximum(np.asarray(axle_level, float), TINY), lower)


def _gas(P, P0, x, model):
    P[:, model.term_param_slice("damper_gas_preload", "f0")] = x[0]
    P[:, model.term_param_slice("damper_gas_preload", "k")] = x[1]


def _mass(P, P0, x, model):
    s = x[0]
    ms0 = P0[:, P_INDEX["M_S"]]
    P[:, P_INDEX["M_S"]] = ms0 * s
    P[:, P_INDEX["M_TOT"]] = P0[:, P_INDEX["M_TOT"]] + ms0 * (s - 1.0)
    g = P0[:, P_INDEX["G"]][:, None]
    k, ku = P_INDEX["FZ0"], P_INDEX["M_U"]
    sprung = P0[:, k:k + 4] - P0[:, ku:ku + 4] * g
    P[:, k:k + 4] = P0[:, ku:ku + 4] * g + sprung * s


def _inertia(P, P0, x, model):
    P[:, P_INDEX["IXX"]] = P0[:, P_INDEX["IXX"]] * x[0]
    P[:, P_INDEX["IYY"]] = P0[:, P_INDEX["IYY"]] * x[1]


def _spring(P, P0, x, model):
    _scale_axles(P, P0, "K_S", x[0], x[1])


def _relax(P, P0, x, model):
    P[:, P_INDEX["RELAX_LEN"]] = P0[:, P_INDEX["RELAX_LEN"]] * x[0]


def _nothing(P, P0, x, model):
    pass


def axle_map(front, rear) -> dict:
    """A per-axle value as the config files spell it."""
    return {"front": float(front), "rear": float(rear)}


def _velocity_values(x, vp):
    return {("friction", "velocity_scaling_plateau"): float(x[0]),
            ("friction", "velocity_scaling_speed"): float(x[1])}


def _oil_values(x, vp):
    fi, ri = vp.damper_friction_intact
    return {("friction", "damper_level_empty"): axle_map(x[0] * fi, x[1] * ri)}


def _longitudinal_values(x, vp):
    return {("friction", "horizontal_scaling_longitudinal"): axle_map(x[0] * 1e-3, x[1] * 1e-3)}


def _lateral_values(x, vp):
    return {("friction", "horizontal_scaling_lateral"): axle_map(x[0] * 1e-3, x[1] * 1e-3)}


def _mass_values(x, vp):
    return {("body", "sprung_mass"): float(vp.sprung_mass * x[0])}


def _inertia_values(x, vp):
    return {("body", "roll_inertia"): float(vp.roll_inertia * x[0]),
            ("body", "pitch_inertia"): float(vp.pitch_inertia * x[1])}


def _spring_values(x, vp):
    return {("suspension", "wheel_rate"): axle_map(vp.wheel_rate[0] * x[0], vp.wheel_rate[1] * x[1])}


def _relax_values(x, vp):
    return {("tyre", "relaxation_length"): float(vp.relaxation_length * x[0])}


def _amplitude_params(x, vp):
    sig = amplitude_sigma(x[:2], vp.axle_friction, vp.dahl_stiffness)
    return {"extra_level": axle_map(x[0], x[1]), "onset": axle_map(x[2], x[2]), "memory": axle_map(x[3], x[3]),
            "stroke_weight": axle_map(x[4], x[4]), "sigma": axle_map(*sig), "horizontal": axle_map(1.0, 1.0)}


def _viscous(P, P0, x, model):
    _term_axles("extra_viscous_damping", "c")(P, P0, x, model)
    P[:, model.term_param_slice("extra_viscous_damping", "n")] = x[2]


def _viscous_params(x, vp):
    return {"c": axle_map(x[0], x[1]), "n": axle_map(x[2], x[2])}


def _gas_params(x, vp):
    return {"f0": float(x[0]), "k": float(x[1])}


SINE = "a sine-steer (or slalom) drive: lateral wheel forces of several kN"
EMPTY = "a drive with oil-empty dampers on that axle (hydraulic damping masks damper friction otherwise)"

LIBRARY: tuple[Candidate, ...] = (
    Candidate("damper_friction_velocity", PHYSICS,
              "shock-absorber friction grows with stroke velocity to a plateau (paper: s_v)",
              (CandParam("plateau", "1", 1.0, 1.0, 5.0, 0.5, "s_v at high stroke velocity"),
               CandParam("speed", "m/s", 0.02, 0.003, 0.2, 0.005, "stroke velocity scale of the rise")),
              _velocity, (None, None), "an oil-empty-damper drive with fast strokes (bump crossing)",
              "oil_empty", switch="velocity_scaling", to_vehicle=_velocity_values),
    Candidate("damper_friction_oil", PHYSICS,
              "shock-absorber friction level changes when the damper loses its oil (paper: s_oil)",
              (CandParam("ratio_front", "1", 1.0, 0.2, 5.0, 0.3, "F_empty/F_intact, front"),
               CandParam("ratio_rear", "1", 1.0, 0.2, 5.0, 0.3, "F_empty/F_intact, rear")),
              _oil, ("front", "rear"), "drives with oil-empty dampers on the axle in question", "oil_empty",
              switch="oil_scaling", to_vehicle=_oil_values),
    Candidate("friction_longitudinal_force", PHYSICS,
              "suspension friction grows with the longitudinal wheel force (paper: s_h, Fx)",
              (CandParam("kx_front", "1/kN", 0.0, 0.0, 3.0, 0.3, "relative growth per kN |Fx|, front"),
               CandParam("kx_rear", "1/kN", 0.0, 0.0, 3.0, 0.3, "relative growth per kN |Fx|, rear")),
              _longitudinal, ("front", "rear"),
              "a braking/accelerating drive or a bump crossing with oil-empty dampers", "any",
              switch="horizontal_scaling", to_vehicle=_longitudinal_values),
    Candidate("friction_lateral_force", PHYSICS,
              "suspension friction grows with the lateral wheel force (paper: s_h, Fy)",
              (CandParam("ky_front", "1/kN", 0.0, 0.0, 3.0, 0.3, "relative growth per kN |Fy|, front"),
               CandParam("ky_rear", "1/kN", 0.0, 0.0, 3.0, 0.3, "relative growth per kN |Fy|, rear")),
              _lateral, ("front", "rear"), SINE, "lateral", switch="horizontal_scaling",
              to_vehicle=_lateral_values),
    Candidate("friction_amplitude", PHYSICS,
              "suspension friction grows with deflection amplitude (extra Dahl element above an onset stroke)",
              (CandParam("extra_front", "N", 0.0, 0.0, 200.0, 10.0, "extra level at large amplitude, front"),
               CandParam("extra_rear", "N", 0.0, 0.0, 200.0, 10.0, "extra level at large amplitude, rear"),
               CandParam("onset", "m", 0.005, 0.0, 0.02, 0.002, "stroke amplitude where the extra sets in"),
               CandParam("memory", "s", 1.0, 0.05, 5.0, 0.2, "how long the peak deflection is remembered"),
               CandParam("stroke_weight", "1", 0.0, 0.0, 1.0, 0.2, "weight of the stroke amplitude against the "
                         "remembered peak deflection")),
              _amplitude, ("front", "rear", None, None, None),
              "a bump crossing (strokes of several cm), best with oil-empty dampers", "bump",
              "susp_sim_ros.model.amplitude_friction", term_params=_amplitude_params),
    # one preload and one rate for all four corners: a rate per axle is the calibrated wheel rate of that axle
    # under another name, and made a structure-only run read as missing physics (per axle tried and withdrawn,
    # benchmarks/RESULTS.md, family section 2026-12-01, 10:28)
    Candidate("damper_gas_preload", PHYSICS,
              "gas-spring force of a pressurised damper: preload change plus gas stiffness",
              (CandParam("f0", "N", 0.0, -500.0, 500.0, 20.0, "force change at static deflection"),
               CandParam("k", "N/m", 0.0, -20000.0, 20000.0, 1000.0, "gas stiffness")),
              _gas, (None, None), "a bump crossing (large deflection)", "bump", "susp_sim_ros.model.extra_terms",
              term_params=_gas_params),
    Candidate("extra_viscous_damping", PHYSICS,
              "additional damping in parallel with the damper (bushings, residual oil), linear unless the "
              "drives say otherwise: c v_ref sgn(v) |v/v_ref|^n",
              # a passive element in parallel adds damping, never removes it: c >= 0 as physics (the fit may
              # go below, standing in for a damper weaker than its curve, which the calibration then owns)
              (CandParam("c_front", "N s/m", 0.0, -2000.0, 5000.0, 100.0, "viscous coefficient, front",
                         physical_lower=0.0),
               CandParam("c_rear", "N s/m", 0.0, -2000.0, 5000.0, 100.0, "viscous coefficient, rear",
                         physical_lower=0.0),
               # why an exponent: real dampers and bushings are rarely linear (valve-controlled: digressive,
               # n < 1; orifice flow: progressive, n > 1; Dixon 2007, ch. 5), and a linear term cannot follow
               # a digressive law across the drives' velocities (each drive wants another c). Prior: linear,
               # +-0.5; one exponent for both axles (one damper type)
               CandParam("exponent", "1", 1.0, 0.2, 2.0, 0.1, "exponent of the force-velocity law, both axles",
                         prior_sd=0.5, shape=True)),
              _viscous, ("front", "rear", None), "any drive with body motion",
              "any", "susp_sim_ros.model.extra_terms", term_params=_viscous_params),
    Candidate("mass_error", PARAMETER, "sprung mass differs from the parameter set (loading, tolerance)",
              (CandParam("scale", "1", 1.0, 0.8, 1.2, 0.01, "sprung mass factor"),),
              _mass, (None,), "a bump crossing (heave/pitch frequencies)", "any", to_vehicle=_mass_values),
    Candidate("inertia_error", PARAMETER, "body roll/pitch inertia differs from the parameter set",
              (CandParam("roll_scale", "1", 1.0, 0.7, 1.3, 0.02, "roll inertia factor"),
               CandParam("pitch_scale", "1", 1.0, 0.7, 1.3, 0.02, "pitch inertia factor")),
              _inertia, (None, None), "sine steer (roll) and bump crossing (pitch)", "any",
              to_vehicle=_inertia_values),
    Candidate("spring_rate_error", PARAMETER, "wheel rates differ from the parameter set",
              (CandParam("front_scale", "1", 1.0, 0.8, 1.2, 0.01, "front wheel-rate factor"),
               CandParam("rear_scale", "1", 1.0, 0.8, 1.2, 0.01, "rear wheel-rate factor")),
              _spring, ("front", "rear"), "a bump crossing", "any", to_vehicle=_spring_values),
    Candidate("tyre_relaxation_error", PARAMETER, "tyre relaxation length differs from the parameter set",
              (CandParam("scale", "1", 1.0, 0.2, 5.0, 0.2, "relaxation-length factor"),),
              _relax, (None,), SINE, "lateral", to_vehicle=_relax_values),
    Candidate("time_offset", MEASUREMENT,
              "the IMU signal lags the inputs (sensor bandwidth, timestamping)",
              (CandParam("lag", "s", 0.0, -0.05, 0.05, 0.001, "measured minus model time (positive: IMU late)"),),
              _nothing, (None,), "any drive with fast body motion", "any"),
    Candidate("steering_offset", MEASUREMENT,
              "the steering-angle sensor is not zeroed: recorded steering-wheel angle minus the true one",
              (CandParam("offset", "rad", 0.0, -0.05, 0.05, 0.001,
                         "recorded minus true steering-wheel angle (one value for all drives of the car)"),),
              _nothing, (None,), "a drive with steering (a straight stretch with a yaw-rate offset)", "lateral"),
    Candidate("sensor_bias", MEASUREMENT,
              "constant sensor offset per drive and signal (from each drive's quiet lead-in, else its mean)",
              (), _nothing, (), "a drive with a quiet lead-in before the maneuver", "any"),
)

BY_NAME = {c.name: c for c in LIBRARY}


def neutral_base(P0: np.ndarray) -> np.ndarray:
    """Base rows rewritten so every paper scaling is switched on at its neutral value where it was off
    (the same model: s_v = 1 with plateau 1, s_oil = 1 with ratio 1, s_h = 1 with zero slopes)."""
    P = P0.copy()
    if np.all(P[:, P_INDEX["USE_V"]] < 0.5):
        P[:, P_INDEX["USE_V"]] = 1.0
        P[:, P_INDEX["SV_INF"]] = 1.0
    if np.all(P[:, P_INDEX["USE_OIL"]] < 0.5):
        P[:, P_INDEX["USE_OIL"]] = 1.0
        _set_axles(P, "SOIL_EMPTY", 1.0, 1.0)
    if np.all(P[:, P_INDEX["USE_H"]] < 0.5):
        P[:, P_INDEX["USE_H"]] = 1.0
        _set_axles(P, "SH_X", 0.0, 0.0)
        _set_axles(P, "SH_Y", 0.0, 0.0)
    return P
