"""An independent simulator of ``model-spec.md`` sections 1-4, for truth drives that are NOT our model.

Written from the spec alone (it neither reads nor imports ``susp_sim_ros.model``'s kernel, vehicle,
parameters, terms or linear model, nor ``analysis/synthetic.py``); it differs from our model in its
integrator, damper-curve shape, friction scalings, every assumed value, and optional hidden physics. Every
difference is listed in ``docs/independent_sim.md``.

Public API::

    TruthCar, TruthFriction, TruthHidden, TruthSensor, TruthManeuver   (dataclasses)
    simulate(car, friction, hidden, maneuver, oil, step_s, y0) -> TruthResult   (noise-free truth, with the
        hidden physics' force per corner, ``TruthResult.hidden``)
    make_drive(car, friction, hidden, maneuver, sensor, oil, seed, record_road, step_s) -> TestDrive
    body_modes(car) -> {"bounce": Hz, "pitch": Hz, "roll": Hz}
    write_drive(path, drive, overwrite=True)    (re-exported from susp_sim_ros.io.drive)
"""
from __future__ import annotations

import json
import math
import warnings
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np
import yaml
from numba import njit
from scipy.interpolate import Akima1DInterpolator, PchipInterpolator, PPoly

from susp_sim_ros.io.drive import ImuSeries, Series, TestDrive, write_drive
from susp_sim_ros.model.road import RoadProfile
from .independent_roads import TruthManeuver, iso8608_road, iso8608_psd  # noqa: F401 (re-export)

VERSION = "1.0"
SOURCE = f"synthetic:truth_generators.independent_sim@{VERSION}"
_CONFIG = Path(__file__).resolve().parents[1] / "config" / "vehicles" / "passat_b8_like.yaml"


# ==== parameters ======================================================================================
@dataclass
class TruthCar:
    """Every vehicle parameter of the truth car (SI). Pairs are (front, rear). Defaults: model-spec 3."""

    sprung_mass: float = 1400.0
    unsprung_mass: tuple = (45.0, 40.0)           # per wheel
    a: float = 1.10                               # CG to front axle
    b: float = 1.69                               # CG to rear axle
    track: tuple = (1.58, 1.57)
    cg_height: float = 0.55
    roll_inertia: float = 500.0
    pitch_inertia: float = 2200.0
    yaw_inertia: float = 2500.0
    roll_centre: tuple = (0.05, 0.10)             # the roll equation uses their mean (model-spec 3)
    pitch_centre: float = 0.20
    wheel_rate: tuple = (28000.0, 24000.0)
    arb_rate: tuple = (15000.0, 5000.0)           # wheel to wheel: F_left = k (d_left - d_right)
    bump_travel: tuple = (0.075, 0.085)           # to bump-stop contact
    rebound_travel: tuple = (0.095, 0.105)        # to rebound-stop contact
    stop_rate: float = 120000.0                   # stop force k (e + e^3 / e_c^2), e = stop compression
    stop_cubic_m: float = 0.012
    tyre_stiffness: float = 250000.0
    tyre_damping: float = 100.0
    cornering_stiffness: tuple = (75000.0, 80000.0)   # per wheel, N/rad
    mu: float = 1.0
    relaxation_length: float = 0.5
    slip_fade_speed: float = 1.2                  # slip faded by a smoothstep below this speed
    steering_ratio: float = 15.5
    drive_front_share: float = 1.0
    brake_front_share: float = 0.63
    gravity: float = 9.81
    roll_centre_handling: str = "mean"            # "mean": m_s (h - mean h_rc) a_y; "per_axle": sum F_y,k (h - h_rc,k)
    factors: dict = field(default_factory=dict)   # perturbation factor per parameter (perturbed())

    @property
    def wheelbase(self) -> float:
        return self.a + self.b

    @property
    def total_mass(self) -> float:
        return self.sprung_mass + 2 * self.unsprung_mass[0] + 2 * self.unsprung_mass[1]

    def static_wheel_loads(self) -> np.ndarray:
        """Static tyre loads FL, FR, RL, RR [N]: the sprung weight split by the lever rule, plus each
        wheel's unsprung weight (what a wheel-load scale reads on level ground)."""
        g, L = self.gravity, self.wheelbase
        front = 0.5 * self.sprung_mass * g * self.b / L + self.unsprung_mass[0] * g
        rear = 0.5 * self.sprung_mass * g * self.a / L + self.unsprung_mass[1] * g
        return np.array([front, front, rear, rear])

    def weighed_wheel_loads(self, accuracy: float, seed: int) -> list[float]:
        """:meth:`static_wheel_loads` [N] as a wheel-load scale of relative accuracy ``accuracy`` (sd, per
        wheel) reads them, its errors drawn from ``seed``."""
        rng = np.random.default_rng(seed + 77)
        return (self.static_wheel_loads() * (1.0 + accuracy * rng.standard_normal(4))).tolist()

    def perturbed(self, rng, lo: float = 0.05, hi: float = 0.15, extended: bool = False) -> "TruthCar":
        """A car whose sprung mass, inertias, cornering stiffnesses, wheel rates and tyre stiffness differ
        by a random factor 1 +- U(lo, hi) each (random sign); ``factors`` records them. ``extended`` also
        moves the unsprung masses, CG height, anti-roll-bar rates, roll centres and the tyre relaxation
        length (drawn after the others, so the first draws are those of ``extended=False``)."""
        rng = np.random.default_rng(rng)

        def f():
            return float(1.0 + rng.choice([-1.0, 1.0]) * rng.uniform(lo, hi))
        fac = {}
        kw = {}
        for name in ("sprung_mass", "roll_inertia", "pitch_inertia", "yaw_inertia", "tyre_stiffness"):
            fac[name] = f()
            kw[name] = getattr(self, name) * fac[name]
        for name in ("cornering_stiffness", "wheel_rate"):
            ff, fr = f(), f()
            fac[name] = [ff, fr]
            v = getattr(self, name)
            kw[name] = (v[0] * ff, v[1] * fr)
        if extended:
            for name in ("cg_height", "relaxation_length"):
                fac[name] = f()
                kw[name] = getattr(self, name) * fac[name]
            for name in ("unsprung_mass", "arb_rate", "roll_centre"):
                ff, fr = f(), f()
                fac[name] = [ff, fr]
                v = getattr(self, name)
                kw[name] = (v[0] * ff, v[1] * fr)
        return replace(self, factors=fac, **kw)


@dataclass
class TruthFriction:
    """Friction of the truth car (model-spec 1, own scalings). Levels in N at 1 mm/s; pairs (front, rear)."""

    enabled: bool = True
    axle_level: tuple = (39.5, 33.5)              # axle rig then reads 60.5 / 44.5 N (paper 60 / 43)
    damper_intact: tuple = (21.0, 11.0)           # paper 22 / 10
    damper_empty: tuple = (30.0, 19.0)            # paper 29 / 20
    sigma: float = 1.2e5                          # Dahl stiffness N/m
    sv_plateau: float = 2.0                       # s_v = 1 + (s_inf - 1) tanh((|v| - 1 mm/s)/v_s), >= 1
    sv_speed: float = 0.03
    sv_ref: float = 0.001
    sh_fx_per_kN: tuple = (0.12, 0.0)             # s_h = 1 + kx |Fx| + ky |Fy|
    sh_fy_per_kN: tuple = (0.28, 0.27)
    velocity_scaling: bool = True
    oil_scaling: bool = True
    horizontal_scaling: bool = True
    empty_viscous: tuple = (330.0, 260.0)         # oil-empty hydraulic slope N s/m
    sv_shape: str = "tanh"                        # velocity-scaling form, see s_velocity
    oil_law: str = "linear"                       # weight of the intact curve: oil ("linear") or oil^2 ("quadratic")
    damper_curve: str = "pchip"                   # hydraulic curve between measured points: pchip, akima, linear

    def perturbed(self, rng, dev_N: float = 2.0) -> "TruthFriction":
        """Levels moved by U(-dev_N, dev_N) each (within the paper's rig tolerance)."""
        rng = np.random.default_rng(rng)

        def p(pair):
            return tuple(float(x + rng.uniform(-dev_N, dev_N)) for x in pair)
        return replace(self, axle_level=p(self.axle_level), damper_intact=p(self.damper_intact),
                       damper_empty=p(self.damper_empty))


@dataclass
class TruthHidden:
    """Physics the paper's model lacks (all off by default). Pairs (front, rear); quadruples FL, FR, RL, RR."""

    amplitude_extra_N: tuple = (0.0, 0.0)         # extra axle-friction level extra * A^2 / (A^2 + A0^2)
    amplitude_A0_m: float = 0.008
    amplitude_tau_s: float = 0.8                  # envelope A = max(|d|, A decaying with this time constant)
    gas_preload_N: tuple = (0.0, 0.0, 0.0, 0.0)   # damper gas force f0 + k d on the body (pushes up)
    gas_rate_N_m: tuple = (0.0, 0.0, 0.0, 0.0)
    extra_viscous: tuple = (0.0, 0.0)             # N s/m, c * deflection velocity (viscous_law)
    # forms (AMP_ENVELOPES, AMP_LAWS, AMP_ELEMENTS, VISCOUS_LAWS): the defaults are the forms of version 1.0
    amplitude_envelope: str = "decaying_peak"     # |d| peak decaying with tau; "stroke": half the decaying
    #                                               max-min span; "windowed_rms": sqrt(2) x exponentially windowed RMS
    amplitude_law: str = "saturating"             # A^2/(A^2 + A0^2); "linear": A/A0; "power": (A/A0)^p
    amplitude_exponent: float = 0.5               # p of the power law
    amplitude_element: str = "axle"               # inside the axle friction element (scaled by s_h), or
    #                                               "separate": an own Dahl element, unscaled
    amplitude_stiffness_factor: float = 0.5       # separate element: Dahl stiffness = factor x friction sigma
    viscous_law: str = "linear"                   # c v; "power": c v_r sgn(v) |v/v_r|^n;
    #                                               "saturating": c v_r tanh(v/v_r); "bilinear": slope c
    #                                               up to the knee |v| = v_r, slope ratio x c beyond
    viscous_exponent: float = 0.6
    viscous_ref_m_s: float = 0.1
    viscous_slope_ratio: float = 0.35             # bilinear: slope beyond the knee over slope below
    gas_cubic_N_m3: tuple = (0.0, 0.0, 0.0, 0.0)  # progressive gas spring: + k3 d^3
    # physics no candidate of the product lists (issue 26; off by default, bit-identical then)
    blow_off_velocity_m_s: tuple = (0.0, 0.0)     # damper blow-off valve opens beyond +-v_bo (0 = no valve):
    blow_off_slope_factor: float = 0.3            # the intact hydraulic curve grows with this share of its
    #                                               slope there: F(+-v_bo) + factor (F(v) - F(+-v_bo))
    arb_free_play_m: tuple = (0.0, 0.0)           # anti-roll bar gap g: F_left = k (delta - clip(delta, -g, g))
    stribeck_static_N: tuple = (0.0, 0.0)         # velocity-weakening friction at each corner (front, rear):
    stribeck_coulomb_N: tuple = (0.0, 0.0)        # (F_c + (F_s - F_c) exp(-(v/v_s)^2)) tanh(v/v_eps)
    stribeck_speed_m_s: float = 0.02              # v_s
    stribeck_eps_m_s: float = 0.001               # v_eps (regularisation of sign(v))
    load_friction_coefficient: tuple = (0.0, 0.0)  # strut friction growing with the wheel's vertical load
    #                                               (front, rear): mu max(Fz0 + Ft, 0) tanh(v/v_eps), Fz0 + Ft
    #                                               the corner's tyre load, v_eps = stribeck_eps_m_s
    position_friction_N: tuple = (0.0, 0.0)       # strut friction growing with the compression (front, rear):
    position_friction_rate_N_m: tuple = (0.0, 0.0)  # max(F0 + k d, 0) tanh(v/v_eps), d the deflection from
    #                                               static (positive in bump), v_eps = stribeck_eps_m_s: a rod
    #                                               guide whose side load grows as the spring compresses
    bushing_rate_N_m: tuple = (0.0, 0.0)          # a viscoelastic bushing at each corner (front, rear), parallel
    bushing_damping_N_s_m: tuple = (0.0, 0.0)     # to the spring: a Maxwell element, rate k_b in series with a
    #                                               dashpot c_b, dF/dt = k_b (v - F / c_b): no static force, a
    #                                               stiffness rising from 0 to k_b about its corner frequency
    #                                               k_b / (2 pi c_b) (rubber that stiffens with frequency)
    bushing2_rate_N_m: tuple = (0.0, 0.0)         # a second Maxwell branch beside it (a generalized Maxwell
    bushing2_damping_N_s_m: tuple = (0.0, 0.0)    # element: rubber's spread of relaxation times)
    progressive_rate_N_m2: tuple = (0.0, 0.0)     # a progressive (variable-pitch) coil spring (front, rear): in
    #                                               bump beyond static the rate grows, + k2 max(d, 0)^2 [N] (the
    #                                               rate k + 2 k2 d: closely wound coils coming to block)
    air_spring_rate_N_m: tuple = (0.0, 0.0)       # an air-assist spring beside the coil (front, rear): a gas law
    air_spring_height_m: float = 0.12             # k_a h / n ((1 - d / h)^-n - 1) less its static rate k_a d
    air_spring_exponent: float = 1.4              # (the file's wheel rate holds that): h the air column's
    #                                               effective height, n the polytropic exponent (1.4 adiabatic)
    rebound_spring_rate_N_m: tuple = (0.0, 0.0)   # a rebound (top-out) spring inside the strut (front, rear):
    rebound_spring_gap_m: float = 0.015           # beyond gap g of extension from static it pulls the wheel
    #                                               back, - k_r max(-d - g, 0) [N] (d positive in bump)
    jounce_bumper_rate_N_m: tuple = (0.0, 0.0)    # an elastomer jounce bumper (front, rear) met beyond gap g of
    jounce_bumper_cubic_N_m3: tuple = (0.0, 0.0)  # bump from static: + k_j e + k_j3 e^3, e = max(d - g, 0) [N]
    jounce_bumper_gap_m: float = 0.025            # (a polyurethane bumper stiffening as it is squeezed)
    seal_friction_N: tuple = (0.0, 0.0)           # damper rod-seal friction pressed by the gas charge (front,
    seal_gas_height_m: float = 0.10               # rear): F0 (1 - d / h)^-n tanh(v/v_eps), the gas pressure of
    seal_gas_exponent: float = 1.4                # a monotube damper's charge over its static value (h its gas
    #                                               column per metre of deflection, n polytropic) presses the
    #                                               seal: friction growing, not linearly, with the compression
    bump_stop_force_N: tuple = (0.0, 0.0)         # a bump stop of another law (front, rear), met beyond gap g of
    bump_stop_length_m: float = 0.01              # bump from static: F0 (exp(e / s) - 1), e = max(d - g, 0) [N]
    bump_stop_gap_m: float = 0.02                 # (a cellular elastomer stop whose rate grows exponentially)
    hydraulic_stop_damping_N_s_m: tuple = (0.0, 0.0)  # a hydraulic compression stop in the damper (front, rear):
    hydraulic_stop_gap_m: float = 0.02            # beyond gap g of bump a sleeve throttles the flow, damping
    hydraulic_stop_length_m: float = 0.02         # c_h min(e / s, 1) v with e = max(d - g, 0), both directions,
    #                                               times the damper's oil weight (an empty damper has none)
    hydraulic_stop_in_rebound: bool = False       # the stop beyond gap g of rebound instead, e = max(-d - g, 0)
    hydraulic_stop_exponent: float = 1.0          # the sleeve's law: c_h min((e / s)^n, 1) v (n 1: linear taper)
    hydraulic_stop_both_ways: bool = False        # beyond gap g of bump and of rebound, e = max(|d| - g, 0): a
    #                                               position-sensitive damper (bypass grooves open a soft zone
    #                                               of +-g around static; firmer beyond it)
    hydraulic_stop_rebound_gap_m: float | None = None  # both ways: the soft zone's end in rebound, e = max(-d - g_r,
    #                                               0) for d < 0, when it lies elsewhere than -g (the grooves off
    #                                               centre of the static position: a car that sits lower or higher
    #                                               than the height the damper was laid out for); None: -g
    creep_friction_N: tuple = (0.0, 0.0)          # a strut friction that builds with the sliding velocity by an
    creep_friction_velocity_m_s: float = 0.004    # algebraic law (front, rear): F_c v / sqrt(v^2 + v_c^2) [N], a
    #                                               seal that creeps at low velocity rather than sticking
    rising_rate_N_m2: tuple = (0.0, 0.0)          # a rising-rate linkage (front, rear): the motion ratio changes
    #                                               with travel, so the wheel rate grows linearly through the
    #                                               whole stroke, k + 2 k2 d: + k2 d^2 [N] at every deflection
    #                                               (stiffer in bump, softer in rebound, smoothly through static)


AMP_ENVELOPES = ("decaying_peak", "stroke", "windowed_rms")
AMP_LAWS = ("saturating", "linear", "power")
AMP_ELEMENTS = ("axle", "separate")
VISCOUS_LAWS = ("linear", "power", "saturating", "bilinear")
ROLL_CENTRE_HANDLINGS = ("mean", "per_axle")
#: integrators of the mechanical states (Dahl states always by their exact step solution)
INTEGRATORS = ("rk4", "heun", "semi_implicit_euler")


def _code(value: str, names: tuple, what: str) -> float:
    if value not in names:
        raise ValueError(f"{what} must be one of {names}, got {value!r}")
    return float(names.index(value))


@dataclass
class TruthSensor:
    """Measurement chain of the truth drive's IMU and inputs."""

    imu_rate_hz: float = 200.0
    jitter_s: float = 0.0                         # Gaussian timestamp jitter (stamps only), clipped +-0.4/rate
    bandwidth_hz: float | None = None             # first-order low-pass on the true motion
    gyro_noise_deg_s: tuple = (0.05, 0.05, 0.05)  # white, RMS per sample, per axis (roll, pitch, yaw)
    accel_noise_m_s2: tuple = (0.02, 0.02, 0.02)
    gyro_bias_deg_s: tuple = (0.0, 0.0, 0.0)
    accel_bias_m_s2: tuple = (0.0, 0.0, 0.0)
    time_offset_s: float = 0.0                    # IMU samples show the motion at t - tau
    steering_offset_rad: float = 0.0              # recorded = true + offset, then quantised
    steering_resolution_rad: float = 0.0          # 0 = no quantisation
    input_rate_hz: float = 100.0                  # /vehicle/speed and /vehicle/steering_wheel_angle
    exact_rms: bool = True                        # scale each noise channel to exactly its RMS


# ==== damper curves ===================================================================================
#: The hydropulser points as in config/vehicles/passat_b8_like.yaml when this was written; used only
#: when that file is missing or its ``dampers`` section cannot be read (a warning says so).
_FALLBACK_DAMPERS = {
    "velocity": [-1.0, -0.5, -0.3, -0.2, -0.1, -0.052, -0.026, -0.01, -0.001, 0.0, 0.001, 0.01, 0.026, 0.052,
                 0.1, 0.2, 0.3, 0.5, 1.0],
    "front": [-2300.0, -1500.0, -1050.0, -850.0, -580.0, -400.0, -240.0, -110.0, -22.0, 0.0, 22.0, 80.0, 160.0,
              250.0, 360.0, 520.0, 620.0, 800.0, 1150.0],
    "rear": [-1610.0, -1050.0, -735.0, -595.0, -406.0, -280.0, -168.0, -77.0, -10.0, 0.0, 10.0, 56.0, 112.0,
             175.0, 252.0, 364.0, 434.0, 560.0, 805.0]}


def load_measured_dampers(path: str | Path = _CONFIG) -> dict:
    """Measured damper points (incl. friction) from the vehicle YAML (``dampers``: ``velocity``,
    ``measured_intact`` front/rear), read with plain yaml; the embedded copy if that cannot be read."""
    try:
        with open(path) as fh:
            d = yaml.safe_load(fh)["dampers"]

        def val(x):
            return x["value"] if isinstance(x, dict) and "value" in x else x
        out = {"velocity": np.asarray(val(d["velocity"]), float),
               "front": np.asarray(val(d["measured_intact"])["front"], float),
               "rear": np.asarray(val(d["measured_intact"])["rear"], float)}
        v = out["velocity"]
        if v.ndim != 1 or v.size < 4 or np.any(np.diff(v) <= 0) or out["front"].shape != v.shape \
                or out["rear"].shape != v.shape:
            raise ValueError("malformed damper table")
        return out
    except (OSError, KeyError, TypeError, ValueError, yaml.YAMLError) as exc:
        warnings.warn(f"independent_sim: cannot read damper points from {path} ({exc}); "
                      "using the embedded copy", stacklevel=2)
        return {k: np.asarray(v, float) for k, v in _FALLBACK_DAMPERS.items()}


#: velocity-scaling shapes g(x), x = (|v| - v_ref)/v_s, s_v = max(1, 1 + (s_inf - 1) g(x)): the spec
#: gives plateau and speed, not the form (kernel code = index)
SV_SHAPES = ("tanh", "ramp", "sqrt")
#: oil laws: weight w(oil) of the intact hydraulic curve and of the intact friction level
OIL_LAWS = ("linear", "quadratic")
#: damper-curve shapes between the measured points
DAMPER_CURVES = ("pchip", "akima", "linear")


def _sv_shape(x, shape: str):
    if shape == "tanh":
        return np.tanh(x)
    if shape == "ramp":                  # linear to the plateau at x = 2
        return np.clip(0.5 * x, -1.0, 1.0)
    if shape == "sqrt":                  # steep start, plateau at x = 3
        return np.sign(x) * np.minimum(1.0, np.sqrt(np.abs(x) / 3.0))
    raise ValueError(f"velocity-scaling shape must be one of {SV_SHAPES}, got {shape!r}")


def s_velocity(v, fr: TruthFriction):
    """Own velocity scaling of damper friction: 1 + (s_inf - 1) g((|v| - v_ref)/v_s), clipped >= 1, with
    g = tanh by default (``fr.sv_shape``, :data:`SV_SHAPES`)."""
    x = (np.abs(v) - fr.sv_ref) / fr.sv_speed
    return np.maximum(1.0, 1.0 + (fr.sv_plateau - 1.0) * _sv_shape(x, fr.sv_shape))


def _curve(v, F, shape: str) -> PPoly:
    """A piecewise cubic through (v, F) in the form ``shape`` (:data:`DAMPER_CURVES`)."""
    if shape == "pchip":
        return PchipInterpolator(v, F, extrapolate=False)
    if shape == "akima":
        return Akima1DInterpolator(v, F)
    if shape == "linear":
        slope = np.diff(F) / np.diff(v)
        c = np.vstack([np.zeros_like(slope), np.zeros_like(slope), slope, F[:-1]])
        return PPoly(c, v, extrapolate=False)
    raise ValueError(f"damper curve must be one of {DAMPER_CURVES}, got {shape!r}")


def hydraulic_curves(fr: TruthFriction, measured: dict | None = None):
    """Per axle: PCHIP through (measured - own damper friction), zero for |v| <= 1 mm/s.

    Returns (X (2, n), C (2, 4, n-1), E (2, 4): [F_lo, slope_lo, F_hi, slope_hi]) and the interpolators.
    """
    m = measured or load_measured_dampers()
    v = m["velocity"]
    X, C, E, P = [], [], [], []
    for k, axle in enumerate(("front", "rear")):
        fsa = fr.damper_intact[k] * (s_velocity(v, fr) if fr.velocity_scaling else 1.0)
        F = m[axle] - np.sign(v) * fsa
        F = np.where(v > 0, np.maximum(F, 0.0), np.minimum(F, 0.0))
        F[np.abs(v) <= fr.sv_ref + 1e-12] = 0.0
        F = np.maximum.accumulate(F)          # monotone
        p = _curve(v, F, fr.damper_curve)
        dp = p.derivative()
        X.append(v)
        C.append(p.c)
        E.append([F[0], float(dp(v[0])), F[-1], float(dp(v[-1]))])
        P.append(p)
    return np.array(X), np.ascontiguousarray(np.array(C)), np.array(E), P


# ==== parameter arrays for the kernel =================================================================
(G, MS, MT, IXX, IYY, IZZ, H, HRC, HPC, A_, B_, MU, RELAX, VFADE, RATIO, KT, CT, KSTOP, ESTOP, DSCALE,
 SIGMA, SVINF, SVS, SVREF, FRIC, AMPA0, AMPTAU, DRIVEF, BRAKEF, SVON, AMPENV, AMPLAW, AMPEXP, AMPSEP, SEPSIG,
 VISLAW, VISN, VISREF, SVSHAPE, OILLAW, RCMODE, INTEG, BOFAC, STRVS, STREPS, VISRATIO, NP) = range(47)
(WX, WY, WK, WMU, WFZ0, WCA, WKARB, WBUMP, WREB, WFCA, WFCS, WSOIL, WKX, WKY, WCEMPTY, WAXLE, WOIL,
 WAMPX, WGF0, WGK, WCV, WTRACK, WHRC, WGK3, WBOV, WGAP, WSTRS, WSTRC, WLFMU, WPF0, WPFK, WBUK, WBUC, WBUK2, WBUC2,
 WPRG, WAIRK, WAIRH, WAIRN, WRSK, WRSG, WJBK, WJBK3, WJBG, WSEAL, WSEALH, WSEALN, WBSF, WBSL, WBSG,
 WHSC, WHSG, WHSL, WCRF, WCRV, WHSR, WHSN, WRR, WHSGR, NW) = range(60)
NY = 20          # z zd phi phid th thd vy r zw[4] zwd[4] Fy[4]
NOUT = 22        # p q r  fx fy fz  d[4]  F_friction[4]  Fz[4]  F_hidden[4]
NAUX = 5         # per corner from _deriv: d, dd, Fz, Fs, the hidden physics' force in Fs


def _arrays(car: TruthCar, fr: TruthFriction, hid: TruthHidden, oil, dampers_on: bool = True,
            integrator: str = "rk4"):
    P = np.zeros(NP)
    P[G], P[MS], P[MT] = car.gravity, car.sprung_mass, car.total_mass
    P[IXX], P[IYY], P[IZZ] = car.roll_inertia, car.pitch_inertia, car.yaw_inertia
    P[H], P[HRC], P[HPC] = car.cg_height, 0.5 * (car.roll_centre[0] + car.roll_centre[1]), car.pitch_centre
    P[A_], P[B_], P[MU], P[RELAX], P[VFADE] = car.a, car.b, car.mu, car.relaxation_length, car.slip_fade_speed
    P[RATIO], P[KT], P[CT] = car.steering_ratio, car.tyre_stiffness, car.tyre_damping
    P[KSTOP], P[ESTOP], P[DSCALE] = car.stop_rate, car.stop_cubic_m, 1.0 if dampers_on else 0.0
    P[SIGMA], P[SVINF], P[SVS], P[SVREF] = fr.sigma, fr.sv_plateau, fr.sv_speed, fr.sv_ref
    P[SVON] = 1.0 if fr.velocity_scaling else 0.0
    P[FRIC] = 1.0 if fr.enabled else 0.0
    P[AMPA0], P[AMPTAU] = hid.amplitude_A0_m, hid.amplitude_tau_s
    P[DRIVEF], P[BRAKEF] = car.drive_front_share, car.brake_front_share
    P[AMPENV] = _code(hid.amplitude_envelope, AMP_ENVELOPES, "amplitude_envelope")
    P[AMPLAW] = _code(hid.amplitude_law, AMP_LAWS, "amplitude_law")
    P[AMPEXP] = hid.amplitude_exponent
    P[AMPSEP] = _code(hid.amplitude_element, AMP_ELEMENTS, "amplitude_element")
    P[SEPSIG] = hid.amplitude_stiffness_factor * fr.sigma
    P[VISLAW] = _code(hid.viscous_law, VISCOUS_LAWS, "viscous_law")
    P[VISN], P[VISREF], P[VISRATIO] = hid.viscous_exponent, hid.viscous_ref_m_s, hid.viscous_slope_ratio
    P[SVSHAPE] = _code(fr.sv_shape, SV_SHAPES, "sv_shape")
    P[OILLAW] = _code(fr.oil_law, OIL_LAWS, "oil_law")
    P[RCMODE] = _code(car.roll_centre_handling, ROLL_CENTRE_HANDLINGS, "roll_centre_handling")
    P[INTEG] = _code(integrator, INTEGRATORS, "integrator")
    P[BOFAC] = hid.blow_off_slope_factor
    P[STRVS], P[STREPS] = hid.stribeck_speed_m_s, hid.stribeck_eps_m_s
    W = np.zeros((4, NW))
    L = car.wheelbase
    for i in range(4):
        k = 0 if i < 2 else 1
        W[i, WX] = car.a if k == 0 else -car.b
        W[i, WTRACK] = car.track[k]
        W[i, WY] = 0.5 * car.track[k] * (1.0 if i % 2 == 0 else -1.0)
        W[i, WK], W[i, WMU], W[i, WCA] = car.wheel_rate[k], car.unsprung_mass[k], car.cornering_stiffness[k]
        share = car.b / L if k == 0 else car.a / L
        W[i, WFZ0] = (0.5 * car.sprung_mass * share + car.unsprung_mass[k]) * car.gravity
        W[i, WKARB], W[i, WBUMP], W[i, WREB] = car.arb_rate[k], car.bump_travel[k], car.rebound_travel[k]
        W[i, WFCA], W[i, WFCS] = fr.axle_level[k], fr.damper_intact[k]
        W[i, WSOIL] = (fr.damper_empty[k] / fr.damper_intact[k]) if fr.oil_scaling else 1.0
        hs = 1.0 if fr.horizontal_scaling else 0.0
        W[i, WKX], W[i, WKY] = hs * fr.sh_fx_per_kN[k] * 1e-3, hs * fr.sh_fy_per_kN[k] * 1e-3
        W[i, WCEMPTY], W[i, WAXLE], W[i, WOIL] = fr.empty_viscous[k], k, float(oil[i])
        W[i, WAMPX], W[i, WGF0], W[i, WGK] = hid.amplitude_extra_N[k], hid.gas_preload_N[i], hid.gas_rate_N_m[i]
        W[i, WCV], W[i, WHRC] = hid.extra_viscous[k], car.roll_centre[k]
        W[i, WGK3] = hid.gas_cubic_N_m3[i]
        W[i, WBOV], W[i, WGAP] = hid.blow_off_velocity_m_s[k], hid.arb_free_play_m[k]
        W[i, WSTRS], W[i, WSTRC] = hid.stribeck_static_N[k], hid.stribeck_coulomb_N[k]
        W[i, WLFMU] = hid.load_friction_coefficient[k]
        W[i, WPF0], W[i, WPFK] = hid.position_friction_N[k], hid.position_friction_rate_N_m[k]
        W[i, WBUK], W[i, WBUC] = hid.bushing_rate_N_m[k], hid.bushing_damping_N_s_m[k]
        W[i, WBUK2], W[i, WBUC2] = hid.bushing2_rate_N_m[k], hid.bushing2_damping_N_s_m[k]
        W[i, WPRG] = hid.progressive_rate_N_m2[k]
        W[i, WAIRK], W[i, WAIRH], W[i, WAIRN] = hid.air_spring_rate_N_m[k], hid.air_spring_height_m, \
            hid.air_spring_exponent
        W[i, WRSK], W[i, WRSG] = hid.rebound_spring_rate_N_m[k], hid.rebound_spring_gap_m
        W[i, WJBK], W[i, WJBK3], W[i, WJBG] = hid.jounce_bumper_rate_N_m[k], hid.jounce_bumper_cubic_N_m3[k], \
            hid.jounce_bumper_gap_m
        W[i, WSEAL], W[i, WSEALH], W[i, WSEALN] = hid.seal_friction_N[k], hid.seal_gas_height_m, \
            hid.seal_gas_exponent
        W[i, WBSF], W[i, WBSL], W[i, WBSG] = hid.bump_stop_force_N[k], hid.bump_stop_length_m, hid.bump_stop_gap_m
        W[i, WHSC], W[i, WHSG], W[i, WHSL] = hid.hydraulic_stop_damping_N_s_m[k], hid.hydraulic_stop_gap_m, \
            hid.hydraulic_stop_length_m
        W[i, WCRF], W[i, WCRV] = hid.creep_friction_N[k], hid.creep_friction_velocity_m_s
        W[i, WHSR] = 0.0 if hid.hydraulic_stop_both_ways else -1.0 if hid.hydraulic_stop_in_rebound else 1.0
        W[i, WHSN] = hid.hydraulic_stop_exponent
        W[i, WHSGR] = hid.hydraulic_stop_gap_m if hid.hydraulic_stop_rebound_gap_m is None \
            else hid.hydraulic_stop_rebound_gap_m
        W[i, WRR] = hid.rising_rate_N_m2[k]
    X, C, E, _ = hydraulic_curves(fr)
    return P, W, X, C, E


# ==== kernel ==========================================================================================
@njit(cache=True)
def _damper(v, ax, X, C, E):
    n = X.shape[1]
    if v <= X[ax, 0]:
        return E[ax, 0] + E[ax, 1] * (v - X[ax, 0])
    if v >= X[ax, n - 1]:
        return E[ax, 2] + E[ax, 3] * (v - X[ax, n - 1])
    lo, hi = 0, n - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if X[ax, mid] <= v:
            lo = mid
        else:
            hi = mid
    dx = v - X[ax, lo]
    return ((C[ax, 0, lo] * dx + C[ax, 1, lo]) * dx + C[ax, 2, lo]) * dx + C[ax, 3, lo]


@njit(cache=True)
def _oil_weight(oil, law):
    """The weight of the intact hydraulic curve and friction level of a damper holding ``oil`` [-] under the
    oil law of kernel code ``law`` (:data:`OIL_LAWS`: 0 linear, 1 quadratic)."""
    return oil if law == 0.0 else oil * oil


@njit(cache=True)
def _hydraulic(f_intact, v, w_oil, c_empty):
    """Hydraulic damper force [N]: the intact curve's force ``f_intact`` at the damper velocity ``v`` [m/s]
    blended by the oil weight ``w_oil`` with the oil-empty damper's viscous force ``c_empty * v``."""
    return w_oil * f_intact + (1.0 - w_oil) * c_empty * v


def damper_rig_force(fr: TruthFriction, oil: float, velocity_m_s: float, axle: int = 0) -> float:
    """The hydraulic force [N] of this generator's damper (``axle`` 0 front, 1 rear) drained to ``oil`` [-]
    at the damper velocity ``velocity_m_s``: what a damper rig measures of the damper type (friction aside),
    through the kernel's own functions."""
    X, C, E, _ = hydraulic_curves(fr)
    w = _oil_weight(float(oil), _code(fr.oil_law, OIL_LAWS, "oil_law"))
    return float(_hydraulic(_damper(float(velocity_m_s), axle, X, C, E), float(velocity_m_s), w,
                            float(fr.empty_viscous[axle])))


def damper_rig_oil_law(fr: TruthFriction, oils, velocity_m_s: float, accuracy: float = 0.0,
                       rng: np.random.Generator | None = None, axle: int = 0) -> tuple[tuple, tuple]:
    """A rig test of this generator's damper type drained in steps: at each of ``oils`` (rising from 0 to 1)
    the force at ``velocity_m_s`` (:func:`damper_rig_force`), each reading off by a relative error of sd
    ``accuracy`` (drawn from ``rng``), as the fraction of the way from the oil-empty to the intact force.
    Returns (oil levels, force fractions), the table ``susp inspect --oil-law`` takes."""
    force = np.array([damper_rig_force(fr, o, velocity_m_s, axle) for o in oils])
    if accuracy > 0.0:
        force = force * (1.0 + accuracy * (rng or np.random.default_rng()).standard_normal(force.size))
    frac = (force - force[0]) / (force[-1] - force[0])
    return tuple(float(o) for o in oils), tuple(float(f) for f in frac)


@njit(cache=True)
def _tyre_force(Ft, Fz0):
    """The dynamic tyre force ``Ft`` [N] limited to ``-Fz0`` (lift-off: the total load Fz0 + Ft >= 0)."""
    return -Fz0 if Fz0 + Ft < 0.0 else Ft


@njit(cache=True)
def _air_spring(d, k, h, n):
    """The force [N, in Fs's sense] of an air spring of static rate ``k`` [N/m], effective column height
    ``h`` [m] and polytropic exponent ``n`` at deflection ``d`` [m] (positive in bump) beyond its static rate's
    share: k h / n ((1 - d / h)^-n - 1) - k d (the static load and rate belong to the vehicle file). The
    column is held at 5 % of its height (beyond the bump stops' travel)."""
    return k * h / n * (_gas_column(d, h) ** -n - 1.0) - k * d


@njit(cache=True)
def _gas_column(d, h):
    """The gas column's length over its static length ``h`` [m] at deflection ``d`` [m] (positive in bump),
    1 - d / h, held at 5 % (beyond the bump stops' travel)."""
    q = 1.0 - d / h
    return q if q > 0.05 else 0.05


@njit(cache=True)
def _hidden_springs(d, w):
    """The force [N, in Fs's sense] of the hidden spring laws of one corner (its row ``w`` of W) at
    deflection ``d`` [m] (positive in bump): a progressive coil's + k2 max(d, 0)^2, an air-assist spring
    (:func:`_air_spring`), a rebound spring's - k_r max(-d - g, 0), a jounce bumper's k_j e + k_j3 e^3 with
    e = max(d - g, 0), an exponential bump stop's F0 (exp(e / s) - 1) with e = max(d - g, 0), a rising-rate
    linkage's + k2 d^2."""
    F = 0.0
    if w[WPRG] > 0.0 and d > 0.0:          # progressive coil: the rate grows in bump
        F += w[WPRG] * d * d
    if w[WAIRK] > 0.0:                      # air-assist spring: the gas law less its static rate
        F += _air_spring(d, w[WAIRK], w[WAIRH], w[WAIRN])
    if w[WRSK] > 0.0 and -d > w[WRSG]:      # rebound spring: engages beyond its gap of extension
        F -= w[WRSK] * (-d - w[WRSG])
    if w[WJBK] + w[WJBK3] > 0.0 and d > w[WJBG]:   # jounce bumper: met beyond its gap of bump
        e = d - w[WJBG]
        F += w[WJBK] * e + w[WJBK3] * e * e * e
    if w[WBSF] > 0.0 and d > w[WBSG]:       # exponential bump stop: met beyond its gap of bump
        F += w[WBSF] * math.expm1((d - w[WBSG]) / w[WBSL])
    if w[WRR] != 0.0:                       # rising-rate linkage: the rate grows through the whole stroke
        F += w[WRR] * d * d
    return F


@njit(cache=True)
def _strut_friction(w, P, d, dd, Ft):
    """The hidden strut friction laws of one corner (``w`` its row of W) [N, in Fs's sense]: a Stribeck
    (velocity-weakening) friction, one growing with the vertical tyre load ``Fz0 + Ft``, one growing with
    the compression ``d``, a rod seal's pressed by the damper's gas charge and one that creeps (its own algebraic
    law of sliding); 0 when none is set."""
    F = 0.0
    slide = math.tanh(dd / P[STREPS])   # each law's sign of sliding, smoothed over v_eps
    if w[WSTRS] != 0.0 or w[WSTRC] != 0.0:
        ra = dd / P[STRVS]
        F += (w[WSTRC] + (w[WSTRS] - w[WSTRC]) * math.exp(-ra * ra)) * slide
    if w[WLFMU] != 0.0:
        Fload = w[WFZ0] + Ft
        F += w[WLFMU] * (Fload if Fload > 0.0 else 0.0) * slide
    if w[WPF0] != 0.0 or w[WPFK] != 0.0:
        Fpn = w[WPF0] + w[WPFK] * d
        F += (Fpn if Fpn > 0.0 else 0.0) * slide
    if w[WSEAL] != 0.0:
        F += w[WSEAL] * _gas_column(d, w[WSEALH]) ** -w[WSEALN] * slide
    if w[WCRF] != 0.0:   # its own algebraic law of sliding, not the tanh above
        F += w[WCRF] * dd / math.sqrt(dd * dd + w[WCRV] * w[WCRV])
    return F


@njit(cache=True)
def _deriv(y, v, ax, dsw, ZR, ZRD, j, Ff, P, W, X, C, E, dy, aux):
    """dy/dt of the mechanical states; aux[i] = (d, dd, Fz, Fs, F_hidden): F_hidden the part of Fs from
    the hidden physics computed here (all but the Dahl elements and the bushings). Forces held over the step
    ``Ff`` (friction and bushings: splitting)."""
    z, zd, phi, phid, th, thd, vy, r = y[0], y[1], y[2], y[3], y[4], y[5], y[6], y[7]
    d = np.empty(4)
    dd = np.empty(4)
    for i in range(4):
        d[i] = y[8 + i] - (z - W[i, WX] * th + W[i, WY] * phi)
        dd[i] = y[12 + i] - (zd - W[i, WX] * thd + W[i, WY] * phid)
    sumFy = y[16] + y[17] + y[18] + y[19]
    ay = sumFy / P[MT]
    sF = 0.0
    sYF = 0.0
    sXF = 0.0
    for i in range(4):
        o = i - 1 if i % 2 == 1 else i + 1            # partner wheel on the same axle
        Fhid = 0.0
        if W[i, WGAP] > 0.0:                          # anti-roll bar with free play +-gap
            delta = d[i] - d[o]
            dc = min(max(delta, -W[i, WGAP]), W[i, WGAP])
            Fs = W[i, WK] * d[i] + W[i, WKARB] * (delta - dc)
            Fhid -= W[i, WKARB] * dc
        else:
            Fs = W[i, WK] * d[i] + W[i, WKARB] * (d[i] - d[o])
        Fspr = _hidden_springs(d[i], W[i])
        Fs += Fspr
        Fhid += Fspr
        eb = d[i] - W[i, WBUMP]
        er = -d[i] - W[i, WREB]
        if eb > 0.0:
            Fs += P[KSTOP] * (eb + eb * eb * eb / (P[ESTOP] * P[ESTOP]))
        if er > 0.0:
            Fs -= P[KSTOP] * (er + er * er * er / (P[ESTOP] * P[ESTOP]))
        ia = int(W[i, WAXLE])
        w_oil = _oil_weight(W[i, WOIL], P[OILLAW])
        if W[i, WBOV] > 0.0 and abs(dd[i]) > W[i, WBOV]:   # blow-off valve open: softer intact curve
            vb = W[i, WBOV] if dd[i] > 0.0 else -W[i, WBOV]
            Fc0 = _damper(dd[i], ia, X, C, E)
            Fb = _damper(vb, ia, X, C, E)
            Fbo = Fb + P[BOFAC] * (Fc0 - Fb)
            Fh = _hydraulic(Fbo, dd[i], w_oil, W[i, WCEMPTY])
            Fhid += P[DSCALE] * w_oil * (Fbo - Fc0)
        else:
            Fh = _hydraulic(_damper(dd[i], ia, X, C, E), dd[i], w_oil, W[i, WCEMPTY])
        sg, av = (1.0 if dd[i] >= 0.0 else -1.0), abs(dd[i])
        if P[VISLAW] == 0.0:
            Fv = W[i, WCV] * dd[i]
        elif P[VISLAW] == 1.0:
            Fv = W[i, WCV] * P[VISREF] * sg * (av / P[VISREF]) ** P[VISN]
        elif P[VISLAW] == 2.0:
            Fv = W[i, WCV] * P[VISREF] * math.tanh(dd[i] / P[VISREF])
        else:  # two-stage valve: slope c up to the knee v_r, ratio x c beyond
            Fv = W[i, WCV] * sg * (av if av <= P[VISREF] else P[VISREF] + P[VISRATIO] * (av - P[VISREF]))
        Fgas = W[i, WGF0] + W[i, WGK] * d[i] + W[i, WGK3] * d[i] * d[i] * d[i]
        Fs += P[DSCALE] * Fh + Ff[i] + Fv + W[i, WGF0] + W[i, WGK] * d[i] + W[i, WGK3] * d[i] * d[i] * d[i]
        Fhid += Fv + Fgas
        depth = W[i, WHSR] * d[i] if W[i, WHSR] != 0.0 else abs(d[i])   # WHSR 0: both ways
        gap = W[i, WHSGR] if W[i, WHSR] == 0.0 and d[i] < 0.0 else W[i, WHSG]   # both ways: the rebound side's own
        if W[i, WHSC] > 0.0 and depth > gap:   # hydraulic stop: damping beyond its gap
            engaged = (depth - gap) / W[i, WHSL]
            if W[i, WHSN] != 1.0:
                engaged = engaged ** W[i, WHSN]
            Fhs = w_oil * W[i, WHSC] * min(engaged, 1.0) * dd[i]
            Fs += Fhs
            Fhid += Fhs
        Ft = _tyre_force(P[KT] * (ZR[i, j] - y[8 + i]) + P[CT] * (ZRD[i, j] - y[12 + i]), W[i, WFZ0])
        Fsf = _strut_friction(W[i], P, d[i], dd[i], Ft)
        Fs += Fsf
        Fhid += Fsf
        dy[8 + i] = y[12 + i]
        dy[12 + i] = (Ft - Fs) / W[i, WMU]
        Fyax = y[16 + (i // 2) * 2] + y[17 + (i // 2) * 2]
        dFz = -W[i, WY] / (0.5 * W[i, WTRACK]) * Fyax * W[i, WHRC] / W[i, WTRACK]   # left loses in +Fy
        Fz = W[i, WFZ0] + Ft + dFz
        if Fz < 0.0:
            Fz = 0.0
        aux[i, 0] = d[i]
        aux[i, 1] = dd[i]
        aux[i, 2] = Fz
        aux[i, 3] = Fs
        aux[i, 4] = Fhid
        sF += Fs
        sYF += W[i, WY] * Fs
        sXF += W[i, WX] * Fs
        # lateral tyre force with first-order relaxation
        vv = abs(v)
        x = vv / P[VFADE]
        fade = 1.0 if x >= 1.0 else x * x * (3.0 - 2.0 * x)
        veff = vv if vv > P[VFADE] else P[VFADE]
        if i < 2:
            alpha = dsw / P[RATIO] - (vy + P[A_] * r) / veff
        else:
            alpha = -(vy - P[B_] * r) / veff
        alpha *= fade
        muFz = P[MU] * Fz
        Fss = muFz * math.tanh(W[i, WCA] * alpha / muFz) if muFz > 1e-6 else 0.0
        vr = vv if vv > 0.5 else 0.5
        dy[16 + i] = vr / P[RELAX] * (Fss - y[16 + i])
    dy[0] = zd
    dy[1] = sF / P[MS]
    dy[2] = phid
    if P[RCMODE] == 0.0:
        dy[3] = (sYF + P[MS] * (P[H] - P[HRC]) * (ay + P[G] * phi)) / P[IXX]
    else:                   # each axle's lateral force acts at its own roll centre
        mlat = P[MS] / P[MT] * ((y[16] + y[17]) * (P[H] - W[0, WHRC]) + (y[18] + y[19]) * (P[H] - W[2, WHRC]))
        dy[3] = (sYF + mlat + P[MS] * (P[H] - P[HRC]) * P[G] * phi) / P[IXX]
    dy[4] = thd
    dy[5] = (-sXF + P[MS] * (P[H] - P[HPC]) * (P[G] * th - ax)) / P[IYY]
    dy[6] = ay - v * r
    dy[7] = (P[A_] * (y[16] + y[17]) - P[B_] * (y[18] + y[19])) / P[IZZ]


@njit(cache=True)
def _dahl(F, dx, Fc, sigma):
    if Fc <= 0.0:
        return 0.0
    if F > Fc:
        F = Fc
    elif F < -Fc:
        F = -Fc
    if dx == 0.0:
        return F
    s = 1.0 if dx > 0.0 else -1.0
    return s * Fc + (F - s * Fc) * math.exp(-sigma * abs(dx) / Fc)


@njit(cache=True)
def _maxwell(F, dx, h, k, c):
    """A Maxwell element's force [N] after a step of ``h`` [s] over which its ends moved ``dx`` [m] at
    constant velocity: the exact solution of dF/dt = k (dx/h - F/c), relaxation time c / k."""
    decay = math.exp(-h * k / c)
    return F * decay + c * (dx / h) * (1.0 - decay)


@njit(cache=True)
def _step(y, yt, h, j, V, AX, DSW, ZR, ZRD, Ff, P, W, X, C, E, k1, k2, k3, k4, aux2):
    """yt = the mechanical states one step on from y (k1 = dy/dt at y given) by the integrator P[INTEG]."""
    if P[INTEG] == 0.0:            # classical RK4
        for m in range(NY):
            yt[m] = y[m] + 0.5 * h * k1[m]
        _deriv(yt, V[j + 1], AX[j + 1], DSW[j + 1], ZR, ZRD, j + 1, Ff, P, W, X, C, E, k2, aux2)
        for m in range(NY):
            yt[m] = y[m] + 0.5 * h * k2[m]
        _deriv(yt, V[j + 1], AX[j + 1], DSW[j + 1], ZR, ZRD, j + 1, Ff, P, W, X, C, E, k3, aux2)
        for m in range(NY):
            yt[m] = y[m] + h * k3[m]
        _deriv(yt, V[j + 2], AX[j + 2], DSW[j + 2], ZR, ZRD, j + 2, Ff, P, W, X, C, E, k4, aux2)
        for m in range(NY):
            yt[m] = y[m] + h / 6.0 * (k1[m] + 2.0 * k2[m] + 2.0 * k3[m] + k4[m])
    elif P[INTEG] == 1.0:          # Heun (explicit trapezoid, second order)
        for m in range(NY):
            yt[m] = y[m] + h * k1[m]
        _deriv(yt, V[j + 2], AX[j + 2], DSW[j + 2], ZR, ZRD, j + 2, Ff, P, W, X, C, E, k2, aux2)
        for m in range(NY):
            yt[m] = y[m] + 0.5 * h * (k1[m] + k2[m])
    else:                          # semi-implicit (symplectic) Euler: velocities first, positions with them
        for m in range(NY):
            yt[m] = y[m] + h * k1[m]
        for m in (0, 2, 4, 8, 9, 10, 11):
            yt[m] = y[m] + h * yt[m + 1 if m < 8 else m + 4]


@njit(cache=True)
def _envelope(i, dn, decay, P, Aenv, Ahi, Alo, M2):
    """Update wheel i's amplitude envelope Aenv[i] [m] with the deflection dn by the form P[AMPENV]."""
    if P[AMPENV] == 0.0:       # decaying peak of |d|
        a_prev = Aenv[i] * decay
        Aenv[i] = abs(dn) if abs(dn) > a_prev else a_prev
    elif P[AMPENV] == 1.0:     # half the span between a decaying max and min of d
        hi_prev = dn + (Ahi[i] - dn) * decay
        lo_prev = dn + (Alo[i] - dn) * decay
        Ahi[i] = dn if dn > hi_prev else hi_prev
        Alo[i] = dn if dn < lo_prev else lo_prev
        Aenv[i] = 0.5 * (Ahi[i] - Alo[i])
    else:                      # sqrt(2) x RMS over an exponential window
        M2[i] = decay * M2[i] + (1.0 - decay) * dn * dn
        Aenv[i] = math.sqrt(2.0 * M2[i])


@njit(cache=True)
def _amplitude_level(extra, A, P):
    """Extra friction level [N] at envelope A [m] by the law P[AMPLAW]."""
    if P[AMPLAW] == 0.0:
        A2 = A * A
        return extra * A2 / (A2 + P[AMPA0] * P[AMPA0])
    if P[AMPLAW] == 1.0:
        return extra * (A / P[AMPA0])
    return extra * (A / P[AMPA0]) ** P[AMPEXP]


@njit(cache=True)
def _s_velocity(v, P):
    """Velocity scaling of the damper friction at deflection speed v [m/s] by the shape P[SVSHAPE], >= 1."""
    xs = (v - P[SVREF]) / P[SVS]
    if P[SVSHAPE] == 0.0:
        gs = math.tanh(xs)
    elif P[SVSHAPE] == 1.0:
        gs = min(1.0, max(-1.0, 0.5 * xs))
    else:
        gs = min(1.0, math.sqrt(abs(xs) / 3.0)) * (1.0 if xs >= 0.0 else -1.0)
    sv = 1.0 + (P[SVINF] - 1.0) * gs
    return sv if sv >= 1.0 else 1.0


@njit(cache=True)
def _run(y0, n, h, V, AX, DSW, ZR, ZRD, SL, P, W, X, C, E, out):
    """RK4 on the mechanical states, Dahl states by their exact position-domain solution per step."""
    y = y0.copy()
    Fa = np.zeros(4)
    Fd = np.zeros(4)
    Fe = np.zeros(4)                 # separate amplitude element
    Fash = np.zeros(4)               # shadow of the axle element without the amplitude extra (hidden output)
    Aenv = np.zeros(4)
    Ahi = np.zeros(4)
    Alo = np.zeros(4)
    M2 = np.zeros(4)
    Ff = np.zeros(4)
    Fm = np.zeros(4)                 # viscoelastic bushings (Maxwell elements; the second branch's Fm2)
    Fm2 = np.zeros(4)
    Fheld = np.zeros(4)              # every force held over a step: friction and bushings
    k1 = np.zeros(NY)
    k2 = np.zeros(NY)
    k3 = np.zeros(NY)
    k4 = np.zeros(NY)
    yt = np.zeros(NY)
    aux = np.zeros((4, NAUX))
    aux2 = np.zeros((4, NAUX))
    decay = math.exp(-h / P[AMPTAU])
    for k in range(n + 1):
        j = 2 * k
        for i in range(4):
            Ff[i] = P[FRIC] * (Fa[i] + Fd[i] + Fe[i])
            Fheld[i] = Ff[i] + (Fm[i] + Fm2[i])
        _deriv(y, V[j], AX[j], DSW[j], ZR, ZRD, j, Fheld, P, W, X, C, E, k1, aux)
        ay = (y[16] + y[17] + y[18] + y[19]) / P[MT]
        out[k, 0] = y[3]
        out[k, 1] = y[5]
        out[k, 2] = y[7]
        out[k, 3] = AX[j] - y[6] * y[7] - P[G] * math.sin(y[4])
        out[k, 4] = ay + P[G] * math.sin(y[2]) * math.cos(y[4])
        out[k, 5] = k1[1] + P[G] * math.cos(y[2]) * math.cos(y[4])
        for i in range(4):
            out[k, 6 + i] = aux[i, 0]
            out[k, 10 + i] = Ff[i]
            out[k, 14 + i] = aux[i, 2]
            out[k, 18 + i] = aux[i, 4] + P[FRIC] * (Fa[i] - Fash[i] + Fe[i]) + (Fm[i] + Fm2[i])
        if k == n:
            break
        _step(y, yt, h, j, V, AX, DSW, ZR, ZRD, Fheld, P, W, X, C, E, k1, k2, k3, k4, aux2)
        # friction over the step's deflection increment; scalings from the step's start
        share = P[DRIVEF] if AX[j] >= 0.0 else P[BRAKEF]
        for i in range(4):
            dn = yt[8 + i] - (yt[0] - W[i, WX] * yt[4] + W[i, WY] * yt[2])
            dx = dn - aux[i, 0]
            sh_share = share if i < 2 else 1.0 - share
            Fx = 0.5 * P[MT] * AX[j] * sh_share - aux[i, 2] * SL[i, j]
            sh = 1.0 + W[i, WKX] * abs(Fx) + W[i, WKY] * abs(y[16 + i])
            _envelope(i, dn, decay, P, Aenv, Ahi, Alo, M2)
            Famp = _amplitude_level(W[i, WAMPX], Aenv[i], P)
            # shadow axle element at the level without the amplitude extra (equals Fa when nothing is
            # added inside the axle element, so the hidden output's Fa - Fash is then exactly zero)
            Fash[i] = _dahl(Fash[i], dx, W[i, WFCA] * sh, P[SIGMA])
            if P[AMPSEP] == 0.0:
                Fca = (W[i, WFCA] + Famp) * sh
            else:
                Fca = W[i, WFCA] * sh
                Fe[i] = _dahl(Fe[i], dx, Famp, P[SEPSIG])
            sv = _s_velocity(abs(dx) / h, P) if P[SVON] > 0.0 else 1.0
            w_oil = _oil_weight(W[i, WOIL], P[OILLAW])
            soil = 1.0 + (W[i, WSOIL] - 1.0) * (1.0 - w_oil)
            Fcs = W[i, WFCS] * sv * soil * sh
            Fa[i] = _dahl(Fa[i], dx, Fca, P[SIGMA])
            Fd[i] = _dahl(Fd[i], dx, Fcs, P[SIGMA])
            if W[i, WBUK] > 0.0:
                Fm[i] = _maxwell(Fm[i], dx, h, W[i, WBUK], W[i, WBUC])
            if W[i, WBUK2] > 0.0:
                Fm2[i] = _maxwell(Fm2[i], dx, h, W[i, WBUK2], W[i, WBUC2])
        for m in range(NY):
            y[m] = yt[m]
    return y


# ==== driver ==========================================================================================
@dataclass
class TruthResult:
    """Noise-free truth at every step: t [s], gyro (n,3) rad/s, accel (n,3) specific force m/s^2,
    deflection (n,4) m, friction (n,4) N, tyre load (n,4) N, and ``hidden`` (n,4) N per corner (FL FR RL RR):
    the sum of the forces of the hidden physics (everything :class:`TruthHidden` adds), with the sign of the
    suspension force (positive pushes the body up and the wheel down). Its parts: extra viscous ``Fv``; gas
    ``f0 + k d + k3 d^3``; a separate amplitude element's force; amplitude friction inside the axle element:
    that element's force minus a shadow Dahl element run on the same deflection increments at the level
    without the amplitude extra (the same s_h); blow-off: the damper force with the valve minus without it;
    anti-roll-bar free play: the bar's force with the gap minus without it (``-k clip(delta, -g, g)``);
    Stribeck friction; load-dependent strut friction ``mu max(F_z0 + F_t, 0) tanh(v/v_eps)``; strut friction
    growing with the compression; the viscoelastic bushings' force; the progressive, air-assist and rebound springs'
    and the jounce bumpers', exponential bump stops' and rising-rate linkages' forces; a hydraulic compression
    stop's damping. Friction and bushing forces are those held over the step that starts at ``t`` (as
    ``friction``)."""

    t: np.ndarray
    gyro: np.ndarray
    accel: np.ndarray
    deflection: np.ndarray
    friction: np.ndarray
    tyre_load: np.ndarray
    hidden: np.ndarray


def _road_at(s_query, road):
    """Road height and slope at path coordinates (flat outside the profile, linear inside)."""
    if road is None:
        z = np.zeros_like(s_query)
        return z, z.copy()
    s, zp = road
    z = np.interp(s_query, s, zp, left=0.0, right=0.0)
    seg = np.diff(zp) / np.diff(s)
    idx = np.searchsorted(s, s_query, side="right") - 1
    inside = (idx >= 0) & (idx < s.size - 1)
    slope = np.zeros_like(s_query)
    slope[inside] = seg[idx[inside]]
    return z, slope


def _static_offset(P, W, X, C, E):
    """Static equilibrium (z, phi, theta, zw) when a gas preload shifts it (Newton on the accelerations)."""
    y = np.zeros(NY)
    if not (np.any(W[:, WGF0] != 0.0) or np.any(W[:, WGK] != 0.0)):
        return y
    idx = [0, 2, 4, 8, 9, 10, 11]
    acc = [1, 3, 5, 12, 13, 14, 15]
    ZR = np.zeros((4, 1))
    dy = np.zeros(NY)
    aux = np.zeros((4, NAUX))
    Ff = np.zeros(4)

    def res(yy):
        _deriv(yy, 0.0, 0.0, 0.0, ZR, ZR, 0, Ff, P, W, X, C, E, dy, aux)
        return dy[acc].copy()
    for _ in range(20):
        r0 = res(y)
        J = np.zeros((7, 7))
        for c, k in enumerate(idx):
            yp = y.copy()
            yp[k] += 1e-6
            J[:, c] = (res(yp) - r0) / 1e-6
        step = np.linalg.solve(J, -r0)
        y[idx] += step
        if np.max(np.abs(step)) < 1e-12:
            break
    return y


def simulate(car: TruthCar | None = None, friction: TruthFriction | None = None,
             hidden: TruthHidden | None = None, maneuver: TruthManeuver | None = None,
             oil=(1.0, 1.0, 1.0, 1.0), step_s: float = 2e-4, y0=None, dampers: bool = True,
             integrator: str = "rk4") -> TruthResult:
    """Run the truth model; noise-free outputs at every step (t = 0 .. duration). ``integrator``: one of
    :data:`INTEGRATORS` for the mechanical states."""
    car = car or TruthCar()
    friction = friction or TruthFriction()
    hidden = hidden or TruthHidden()
    maneuver = maneuver or TruthManeuver.rest()
    P, W, X, C, E = _arrays(car, friction, hidden, oil, dampers, integrator)
    n = int(round(maneuver.duration_s / step_s))
    th = np.arange(2 * n + 3) * (0.5 * step_s)
    V = maneuver.speed(th)
    AX = maneuver.accel(th)
    DSW = maneuver.steering(th)
    s_front = np.concatenate([[0.0], np.cumsum(0.5 * (V[1:] + V[:-1]) * np.diff(th))])
    road = maneuver.road(car.wheelbase)
    ZR = np.zeros((4, th.size))
    SL = np.zeros((4, th.size))
    for i in range(4):
        sw = s_front - (0.0 if i < 2 else car.wheelbase)
        prof = None if road is None else (road[0], road[1] if i % 2 == 0 else road[2])
        ZR[i], SL[i] = _road_at(sw, prof)
    ZRD = SL * V[None, :]
    y = _static_offset(P, W, X, C, E) if y0 is None else np.asarray(y0, float).copy()
    out = np.zeros((n + 1, NOUT))
    _run(y, n, step_s, V, AX, DSW, ZR, ZRD, SL, P, W, X, C, E, out)
    return TruthResult(np.arange(n + 1) * step_s, out[:, 0:3], out[:, 3:6], out[:, 6:10], out[:, 10:14],
                       out[:, 14:18], out[:, 18:22])


def body_modes(car: TruthCar | None = None) -> dict:
    """Bounce, pitch and roll natural frequencies [Hz] of this model's own linearisation at rest with
    dampers and friction off (numerical Jacobian of the kernel's derivative, eigen-analysis)."""
    car = car or TruthCar()
    P, W, X, C, E = _arrays(car, TruthFriction(enabled=False), TruthHidden(), (1, 1, 1, 1), dampers_on=False)
    P[CT] = 0.0
    st = [0, 2, 4, 8, 9, 10, 11, 1, 3, 5, 12, 13, 14, 15]
    ZR = np.zeros((4, 1))
    Ff = np.zeros(4)
    aux = np.zeros((4, NAUX))

    def f(x):
        y = np.zeros(NY)
        y[st] = x
        dy = np.zeros(NY)
        _deriv(y, 0.0, 0.0, 0.0, ZR, ZR, 0, Ff, P, W, X, C, E, dy, aux)
        return dy[st]
    J = np.zeros((14, 14))
    for c in range(14):
        e = np.zeros(14)
        e[c] = 1e-6
        J[:, c] = (f(e) - f(-e)) / 2e-6
    lam, vec = np.linalg.eig(J)
    res = {}
    for k in np.nonzero(lam.imag > 0)[0]:
        fhz = abs(lam[k]) / (2 * np.pi)
        if fhz > 5.0:
            continue                      # wheel hop
        w = np.abs(vec[:3, k]) * np.array([1.0, 0.5 * car.track[0], car.a])
        res[("bounce", "roll", "pitch")[int(np.argmax(w))]] = float(fhz)
    return res


def _white(rng, n, rms, exact):
    x = rng.standard_normal(n)
    if exact and rms > 0 and n > 1:
        x = (x - x.mean()) / np.sqrt(np.mean((x - x.mean()) ** 2))
    return x * rms


def truth_car_of(drive) -> TruthCar:
    """The truth car a drive of :func:`make_drive` was made with (its ``truth`` metadata)."""
    return TruthCar(**json.loads(drive.metadata["truth"])["car"])


def make_drive(car: TruthCar | None = None, friction: TruthFriction | None = None,
               hidden: TruthHidden | None = None, maneuver: TruthManeuver | None = None,
               sensor: TruthSensor | None = None, oil=(1.0, 1.0, 1.0, 1.0), seed: int = 0,
               record_road: bool = True, step_s: float = 2e-4, t0_ns: int = 0,
               return_truth: bool = False, integrator: str = "rk4", recorded_road_scale: float = 1.0):
    """A truth test drive (``TestDrive``; with ``return_truth`` also the :class:`TruthResult`). The road is
    recorded as driven, or with its heights times ``recorded_road_scale`` (a road recorded wrong: a
    profilometer's gain error, the profile of another wheel track)."""
    car = car or TruthCar()
    friction = friction or TruthFriction()
    hidden = hidden or TruthHidden()
    maneuver = maneuver or TruthManeuver.rest()
    sensor = sensor or TruthSensor()
    oil = tuple(float(o) for o in oil)
    truth = simulate(car, friction, hidden, maneuver, oil, step_s, integrator=integrator)
    rng = np.random.default_rng(seed)
    T = maneuver.duration_s
    # IMU: sampled at nominal instants, showing the (band-limited) motion at t - tau; stamps jittered
    sig = np.hstack([truth.gyro, truth.accel])
    if sensor.bandwidth_hz:
        from scipy.signal import lfilter
        al = math.exp(-2 * math.pi * sensor.bandwidth_hz * step_s)
        sig = np.column_stack([lfilter([1 - al], [1, -al], c, zi=[al * c[0]])[0] for c in sig.T])
    ti = np.arange(0.0, T + 1e-12, 1.0 / sensor.imu_rate_hz)
    tq = np.clip(ti - sensor.time_offset_s, 0.0, truth.t[-1])
    samp = np.column_stack([np.interp(tq, truth.t, c) for c in sig.T])
    n = ti.size
    noise = np.column_stack([_white(rng, n, math.radians(sensor.gyro_noise_deg_s[k]), sensor.exact_rms)
                             for k in range(3)] +
                            [_white(rng, n, sensor.accel_noise_m_s2[k], sensor.exact_rms) for k in range(3)])
    bias = np.concatenate([np.radians(sensor.gyro_bias_deg_s), np.asarray(sensor.accel_bias_m_s2, float)])
    meas = samp + noise + bias[None, :]
    jit = np.zeros(n)
    if sensor.jitter_s > 0:
        jit = np.clip(rng.normal(0.0, sensor.jitter_s, n), -0.4 / sensor.imu_rate_hz, 0.4 / sensor.imu_rate_hz)
    imu_t = t0_ns + np.round((ti + jit) * 1e9).astype(np.int64)
    imu = ImuSeries(imu_t, meas[:, :3], meas[:, 3:])
    # inputs
    tin = np.arange(0.0, T + 1e-12, 1.0 / sensor.input_rate_hz)
    tin_ns = t0_ns + np.round(tin * 1e9).astype(np.int64)
    steer = maneuver.steering(tin) + sensor.steering_offset_rad
    if sensor.steering_resolution_rad > 0:
        steer = np.round(steer / sensor.steering_resolution_rad) * sensor.steering_resolution_rad
    speed = Series(tin_ns, maneuver.speed(tin))
    road = None
    rd = maneuver.road(car.wheelbase)
    if record_road:
        if rd is None:
            road = RoadProfile(np.array([0.0, maneuver.speed_mps * T + car.wheelbase + 10.0]),
                               np.zeros(2), np.zeros(2))
        else:
            road = RoadProfile(rd[0], recorded_road_scale * np.asarray(rd[1]), recorded_road_scale * np.asarray(rd[2]))
    truth_meta = {
        "generator": SOURCE, "seed": seed, "step_s": step_s, "integrator": integrator, "oil": list(oil),
        "car": asdict(car), "friction": asdict(friction), "hidden": asdict(hidden),
        "sensor": asdict(sensor), "maneuver": maneuver.to_dict(),
        "damper_measured_points": {k: v.tolist() for k, v in load_measured_dampers().items()},
        "road_class": maneuver.road_class, "road_recorded": bool(record_road),
        "recorded_road_scale": recorded_road_scale,
        "noise_rms_realised": {"gyro_rad_s": np.sqrt(np.mean(noise[:, :3] ** 2, axis=0)).tolist(),
                               "accel_m_s2": np.sqrt(np.mean(noise[:, 3:] ** 2, axis=0)).tolist()},
        "gyro_noise_rad_s": [math.radians(x) for x in sensor.gyro_noise_deg_s],
        "gyro_bias_rad_s": [math.radians(x) for x in sensor.gyro_bias_deg_s],
        "time_offset_s": sensor.time_offset_s, "steering_offset_rad": sensor.steering_offset_rad,
    }
    meta = {"vehicle": "independent", "maneuver": maneuver.text(),
            "damper_oil_level": ",".join(f"{o:g}" for o in oil), "source": SOURCE,
            "truth": json.dumps(truth_meta, default=lambda o: o.tolist() if hasattr(o, "tolist") else str(o))}
    drive = TestDrive(meta, speed, Series(tin_ns, steer), road, None, imu)
    return (drive, truth) if return_truth else drive


__all__ = ["TruthCar", "TruthFriction", "TruthHidden", "TruthSensor", "TruthManeuver", "TruthResult",
           "simulate", "make_drive", "body_modes", "hydraulic_curves", "damper_rig_force", "damper_rig_oil_law",
           "s_velocity",
           "load_measured_dampers",
           "SV_SHAPES", "OIL_LAWS", "DAMPER_CURVES", "AMP_ENVELOPES", "AMP_LAWS", "AMP_ELEMENTS", "VISCOUS_LAWS",
           "ROLL_CENTRE_HANDLINGS", "INTEGRATORS",
           "write_drive", "iso8608_road", "iso8608_psd", "SOURCE"]
