"""A learned suspension force: physics no listed term describes, written from the dependences the
discrepancy finder read off the missing force (issue 26, items 3-4).

The force at corner ``i`` (positive up on the body, like every term) is a sum of coefficients [N] times
dimensionless features of the corner's state::

    F_i = sum_k  coef_k * phi_k(i)

with the feature vocabulary :data:`FEATURES` (interface.md, ``unlisted_force.dependences``):

==========================  =======================================================================
``constant``                1: a force offset
``deflection``              d / d_ref: a spring
``deflection_cubed``        (d / d_ref)^3: a progressive spring (elastomer, gas volume)
``deflection_velocity``     v / v_ref: viscous damping
``velocity_squared``        oil (v / v_ref) |v / v_ref|: orifice-like damping, a force of the oil's flow
                            through an orifice, so it scales with the damper's oil level ``oil`` as the
                            knee below
``velocity_beyond_knee``    oil sign(v) max(|v| - v_knee, 0) / v_ref: a damper whose slope changes above
                            a knee velocity (a blow-off valve opening, a valve at its stop); a valve acts
                            on the damper's oil, so the force scales with the damper's oil level ``oil``
                            (0 empty, 1 intact: an oil-empty damper builds no pressure to open a valve)
                            (in rebound, v < 0, both damper forces above are ``r`` times what the same
                            speed gives in compression, ``r`` the rebound ratio: a damper's rebound and
                            compression stages are valved apart, its rebound force commonly 2-3x its
                            compression force at the same speed: Dixon, The Shock Absorber Handbook,
                            2007, ch. 5; ``r`` 1 is a symmetric law)
``sign_velocity``           z: friction-like (``z`` a unit Dahl element, -1..1, presliding travel x_p)
``peak_deflection``         z A / d_ref: friction growing with the deflection amplitude (``A`` the peak
                            |d|, forgotten with time constant ``memory``)
``lateral_force``           z |Fy| / F_ref: friction growing with the lateral wheel force
``longitudinal_force``      z |Fx| / F_ref: friction growing with the longitudinal wheel force
``roll_deflection``         (d - d_o) / d_ref: a force on the left-right deflection difference (an
                            anti-roll bar; ``d_o`` the other wheel of the axle)
``roll_free_play``          clip(d - d_o, -g, g) / d_ref: a force only within a free play ``g`` of the
                            left-right deflection difference (an anti-roll bar with play)
``velocity_weakening``      z exp(-|v| / v_s): friction whose level falls with the sliding velocity, the
                            Stribeck effect (``v_s`` the Stribeck velocity); beside ``sign_velocity`` the
                            pair is a static level falling to a sliding one (Armstrong-Helouvry, Dupont and
                            Canudas de Wit, Automatica 30(7), 1994, the exponential form)
``relaxing_deflection``     m / d_ref: a spring that relaxes, stiffer the faster the deflection changes
                            (``m`` the extension of a unit Maxwell element's spring, dm/dt = v - m / tau,
                            ``tau`` its relaxation time: slow motion meets a dashpot of tau per unit
                            rate, fast motion the spring). Linear viscoelasticity's Maxwell element
                            (Ferry, Viscoelastic Properties of Polymers, 3rd ed., 1980, ch. 3): rubber
                            bushings and mounts that stiffen with frequency
``bump_contact``            max(d - g, 0) / d_ref: a spring met beyond a gap ``g`` of bump (a jounce
                            bumper, coils coming to block; with ``g`` 0 a spring stiffer in bump than in
                            rebound)
``rebound_contact``         min(d + g_r, 0) / d_ref: a spring met beyond a gap ``g_r`` of rebound (a
                            rebound or top-out spring; ``g_r`` the rebound gap, the contact gap ``g``
                            unless the fit holds the two apart)
``compression``             z d / d_ref: friction whose level grows with the compression and falls in
                            rebound (beside ``sign_velocity`` a level F0 + F1 d: Coulomb friction in a
                            strut's rod guide and seal is proportional to their normal force, and that
                            follows the deflection where the spring's side load or a damper's gas
                            pressure presses them: Reimpell, Stoll and Betzler, The Automotive Chassis,
                            2nd ed., 2001, on the McPherson strut's friction from the spring's side load)
``creep_damping``           (v / v_c) exp(1 - |v| / v_c): a friction that creeps at low sliding velocity, viscous
                            below the creep velocity ``v_c`` (its peak, the coefficient, at v_c) and fading above;
                            beside ``sign_velocity`` and a velocity weakening of its level the law of a contact
                            that does not stick but creeps, its force building with the sliding velocity (a
                            lubricated or elastomer seal's rate-dependent friction at low speed; the viscous
                            regime below the Stribeck curve's boundary friction: Armstrong-Helouvry, Dupont and
                            Canudas de Wit, Automatica 30(7), 1994; a law's shape like the weakening, fitted only
                            beside a stable friction and only where ``config/force_shape.yaml``
                            ``fit.creep_in_friction_law`` says so)
``bump_damping``            oil (v / v_ref) max(d - g, 0) / d_ref: a damping met beyond the contact gap ``g`` of
                            bump, growing with the depth in the stroke (a hydraulic compression stop, whose
                            sleeve throttles the damper's flow near the end of its travel; a position-sensitive
                            damper's bypass closing: Dixon, The Shock Absorber Handbook, 2007, ch. 5 and 9); a
                            force of the damper's oil, so scaled with its oil level like the valve; offered to
                            the regression only where ``config/force_shape.yaml`` ``library.position_damping``
                            says so
``rebound_damping``         oil (v / v_ref) max(-d - g_r, 0) / d_ref: the same beyond the rebound gap (a
                            hydraulic rebound stop)
``deflection_squared``      (d / d_ref)^2: a spring whose rate grows linearly through the whole stroke (rate
                            k + 2 c d / d_ref^2), its force of one sense in bump and rebound: the second term of
                            any smooth spring law beyond its static rate (a gas charge's or an air spring's
                            n (n + 1) / 2 F0 (d / h)^2, a linkage whose motion ratio changes with travel);
                            offered to the regression only where ``config/force_shape.yaml``
                            ``library.deflection_squared`` says so
``zone_damping``            oil (v / v_ref) (max(d - g, 0) + max(-d - g_r, 0)) / d_ref: a damping met beyond the
                            gap of bump and the rebound gap, one coefficient for both ends of a soft zone (a
                            position-sensitive damper, whose bypass grooves open a soft zone around its layout
                            height and close beyond it in bump and in rebound: Dixon, The Shock Absorber
                            Handbook, 2007, ch. 9; the zone off centre of static where the car sits lower or
                            higher than the height it was laid out for);
                            the sum of ``bump_damping`` and ``rebound_damping`` at one coefficient, offered to
                            the regression only where ``config/force_shape.yaml`` ``library.zone_damping`` says so
``bump_contact_squared``    (max(d - g, 0) / d_ref)^2: a contact spring's progressive part in the depth of its
                            contact, rate 0 at the gap and growing with the squeeze (an elastomer bumper, closely
                            wound coils coming to block one by one, a variable-pitch coil's rate rising from where
                            its first coils close: Reimpell, Stoll and Betzler, The Automotive Chassis, 2nd ed.,
                            2001, ch. 5): a law's shape beside a stable ``bump_contact``, not offered to the
                            regression, fitted where ``config/force_shape.yaml``
                            ``fit.contact_square_competes`` says so
``rebound_contact_squared`` -(min(d + g_r, 0) / d_ref)^2: the same beside a stable ``rebound_contact``, of its
                            sense (a rebound spring's progressive part)
==========================  =======================================================================

Deflection ``d`` [m] from static equilibrium (positive in bump), deflection velocity ``v`` [m/s]. The
reference scales make every coefficient a force [N] at a typical excursion; they and the shape values
(knee, rebound ratio, free play, presliding travel, memory) are parameters with declared defaults like any term's.

States per corner: 0 the unit Dahl element ``z``, 1 the deflection at the start of the step (the context's
deflection plus the step's increment, stored after each step: the other wheel's deflection is read from
it, since the other wheel's corner context may not be filled yet in the step), 2 the amplitude ``A`` [m],
3 the unit Maxwell element's extension ``m`` [m] (advanced by its exact solution over the step at the
step's mean deflection velocity).

:func:`feature_series` evaluates the same features along simulated corner series (tests hold the kernel's
force to it).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .inline_math import TINY, expm1_nonpos
from .layout import C_INDEX
from .terms import PhysicsTerm, TermParam, dahl_exact, register_term

FEATURES = ("constant", "deflection", "deflection_cubed", "deflection_velocity", "velocity_squared",
            "velocity_beyond_knee", "sign_velocity", "peak_deflection", "lateral_force", "longitudinal_force",
            "roll_deflection", "roll_free_play", "velocity_weakening", "relaxing_deflection", "bump_contact",
            "rebound_contact", "compression", "creep_damping", "bump_damping", "rebound_damping",
            "deflection_squared", "zone_damping", "bump_contact_squared", "rebound_contact_squared")
N_FEATURES = len(FEATURES)
#: the features that are the unit Dahl element ``z`` times a level: friction-like, sliding over ``presliding``
FRICTION_LIKE = ("sign_velocity", "peak_deflection", "lateral_force", "longitudinal_force", "compression")
#: a friction law's velocity weakening: a shape of a learned friction, not a dependence of its own
WEAKENING = "velocity_weakening"
#: a friction law's creep: a shape of a learned friction (viscous below a creep velocity), not a dependence
CREEP = "creep_damping"
#: a contact spring's progressive part in the depth of its contact, per contact: a shape of a learned spring law
CONTACT_SQUARES = {"bump_contact": "bump_contact_squared", "rebound_contact": "rebound_contact_squared"}
#: features that shape a law rather than stand for a dependence (not offered to the regression)
LAW_SHAPE_FEATURES = (WEAKENING, CREEP, *CONTACT_SQUARES.values())
#: a friction level's growth with the compression: offered to the regression and, beside a stable plain
#: friction level, fitted as a shape of its law too (analysis/discrepancy/force_shape.friction_law)
LEVEL_GROWTH = "compression"
#: the shape parameters after the coefficients, in this order
SHAPES = ("deflection_ref", "velocity_ref", "force_ref", "knee_velocity", "free_play", "presliding", "memory",
          "stribeck_velocity", "relaxation_time", "contact_gap", "rebound_ratio", "creep_velocity", "rebound_gap")
_O_SHAPE = 4 * N_FEATURES
_DREF, _VREF, _FREF, _KNEE, _GAP, _XP, _MEM, _VS, _TAU, _CGAP, _RR, _VC, _RGAP = (
    _O_SHAPE + 4 * k for k in range(len(SHAPES)))
PRESLIDING, STRIBECK_VELOCITY, REBOUND_RATIO, CREEP_VELOCITY = SHAPES[5], SHAPES[7], SHAPES[10], SHAPES[11]
#: the damper's own forces of the oil, whose law in rebound the rebound ratio scales
DAMPER_OIL = ("velocity_squared", "velocity_beyond_knee")
_Z, _DEF, _AMP, _REL = 0, 4, 8, 12
_C_D, _C_DD, _C_FX, _C_FY, _C_DT = C_INDEX["D"], C_INDEX["DD"], C_INDEX["FX"], C_INDEX["FY"], C_INDEX["DT"]
_C_OIL = C_INDEX["OIL"]


@njit(cache=True, inline="always")
def corner_feature(k, d, d_other, v, fx, fy, oil, z, amp, rel, dref, vref, fref, knee, gap, vs, cgap, rr, vc, rgap):
    """Feature ``k`` of :data:`FEATURES` at one corner (module docstring)."""
    x = d / dref
    u = v / vref
    sgn = 1.0 if v > 0.0 else (-1.0 if v < 0.0 else 0.0)
    rb = rr if v < 0.0 else 1.0
    roll = d - d_other
    if k == 0:
        return 1.0
    if k == 1:
        return x
    if k == 2:
        return x * x * x
    if k == 3:
        return u
    if k == 4:
        return rb * oil * u * abs(u)
    if k == 5:
        return rb * oil * sgn * max(abs(v) - knee, 0.0) / vref
    if k == 6:
        return z
    if k == 7:
        return z * amp / dref
    if k == 8:
        return z * abs(fy) / fref
    if k == 9:
        return z * abs(fx) / fref
    if k == 10:
        return roll / dref
    if k == 11:
        return min(max(roll, -gap), gap) / dref
    if k == 12 or k == 17:
        return _law_shape_feature(k, v, z, vs, vc)
    if k == 16:
        return z * x
    return _gap_or_relaxing_feature(k, d, u, oil, rel, dref, cgap, rgap)


@njit(cache=True, inline="always")
def _law_shape_feature(k, v, z, vs, vc):
    """Features 12 and 17 of :data:`FEATURES` (a friction law's velocity weakening and creep)."""
    if k == 12:
        return z * math.exp(-abs(v) / vs)
    return v / vc * math.exp(1.0 - abs(v) / vc)


@njit(cache=True, inline="always")
def _gap_or_relaxing_feature(k, d, u, oil, rel, dref, cgap, rgap):
    """Features 13-15 and 18-23 of :data:`FEATURES` (a relaxing spring, springs and dampings met beyond a
    contact gap, the spring of one sense in bump and rebound, a contact's progressive part)."""
    if k == 22:
        return (max(d - cgap, 0.0) / dref) ** 2
    if k == 23:
        return -((min(d + rgap, 0.0) / dref) ** 2)
    if k == 20:
        return (d / dref) * (d / dref)
    if k == 21:
        return oil * u * (max(d - cgap, 0.0) + max(-d - rgap, 0.0)) / dref
    if k == 13:
        return rel / dref
    if k == 14:
        return max(d - cgap, 0.0) / dref
    if k == 15:
        return min(d + rgap, 0.0) / dref
    if k == 18:
        return oil * u * max(d - cgap, 0.0) / dref
    return oil * u * max(-d - rgap, 0.0) / dref


@njit(cache=True, inline="always")
def learned_force_force(p, po, s, so, i, c):
    """The sum of coefficients times features, written out without branches (selects only), so the
    kernel's loop over the vehicles of a block stays vectorised while every coefficient is zero."""
    o = i + 1 if i % 2 == 0 else i - 1
    dref, vref, fref = p[po + _DREF + i], p[po + _VREF + i], p[po + _FREF + i]
    d, v = c[i, _C_D], c[i, _C_DD]
    x, u = d / dref, v / vref
    z = s[so + _Z + i]
    sgn = (1.0 if v > 0.0 else 0.0) - (1.0 if v < 0.0 else 0.0)
    roll = d - s[so + _DEF + o]
    gap, cgap, rgap = p[po + _GAP + i], p[po + _CGAP + i], p[po + _RGAP + i]
    q = po + i
    # the damper's oil level, times the rebound ratio in rebound: the scale of its orifice and valve forces
    damper = c[i, _C_OIL] * (1.0 + (p[po + _RR + i] - 1.0) * (1.0 if v < 0.0 else 0.0))
    return (p[q] + p[q + 4] * x + p[q + 8] * x * x * x + p[q + 12] * u + p[q + 16] * damper * u * abs(u)
            + p[q + 20] * damper * sgn * max(abs(v) - p[po + _KNEE + i], 0.0) / vref
            + z * (p[q + 24] + p[q + 28] * s[so + _AMP + i] / dref + p[q + 32] * abs(c[i, _C_FY]) / fref
                   + p[q + 36] * abs(c[i, _C_FX]) / fref + p[q + 48] * math.exp(-abs(v) / p[po + _VS + i])
                   + p[q + 64] * x)
            + p[q + 68] * (v / p[po + _VC + i]) * math.exp(1.0 - abs(v) / p[po + _VC + i])
            + p[q + 40] * roll / dref + p[q + 44] * min(max(roll, -gap), gap) / dref
            + p[q + 52] * s[so + _REL + i] / dref
            + (p[q + 56] * max(d - cgap, 0.0) + p[q + 60] * min(d + rgap, 0.0)) / dref
            + c[i, _C_OIL] * u * (p[q + 72] * max(d - cgap, 0.0) + p[q + 76] * max(-d - rgap, 0.0)
                                  + p[q + 84] * (max(d - cgap, 0.0) + max(-d - rgap, 0.0))) / dref
            + p[q + 80] * x * x
            + (p[q + 88] * max(d - cgap, 0.0) ** 2 - p[q + 92] * min(d + rgap, 0.0) ** 2) / (dref * dref))


@njit(cache=True, inline="always")
def advance_states(z, deflection, amp, rel, dx, presliding, memory, tau, dt):
    """The unit Dahl element, the deflection, the amplitude and the unit Maxwell element's extension one
    step on over the increment ``dx`` [m] (the last exactly for a constant velocity dx / dt over the step)."""
    z_new = dahl_exact(z, 1.0, 1.0 / max(presliding, TINY), dx)
    d_new = deflection + dx   # the kernel passes the context's deflection: no drift, right after a model switch
    decay = 1.0 + expm1_nonpos(-dt / max(memory, TINY))
    amp_new = max(amp * decay, abs(d_new))
    tau_ = max(tau, TINY)
    em = expm1_nonpos(-dt / tau_)
    rel_new = rel * (1.0 + em) - dx / max(dt, TINY) * tau_ * em
    return z_new, d_new, amp_new, rel_new


@njit(cache=True, inline="always")
def learned_force_update(p, po, s, so, i, c, dx):
    z, d, a, m = advance_states(s[so + _Z + i], c[i, _C_D], s[so + _AMP + i], s[so + _REL + i], dx,
                                p[po + _XP + i], p[po + _MEM + i], p[po + _TAU + i], c[i, _C_DT])
    s[so + _Z + i] = z
    s[so + _DEF + i] = d
    s[so + _AMP + i] = a
    s[so + _REL + i] = m


@njit(cache=True)
def _series(D, V, FX, FY, OIL, dt, k, dref, vref, fref, knee, gap, presliding, memory, vs, tau, cgap, rr, vc,
            rgap, out):
    n = D.shape[0]
    z = np.zeros(4)
    amp = np.zeros(4)
    rel = np.zeros(4)
    for t in range(n):
        for i in range(4):
            o = i + 1 if i % 2 == 0 else i - 1
            out[t, i] = corner_feature(k, D[t, i], D[t, o], V[t, i], FX[t, i], FY[t, i], OIL[i], z[i], amp[i],
                                       rel[i], dref, vref, fref, knee, gap, vs, cgap, rr, vc, rgap)
        if t + 1 < n:
            for i in range(4):
                z[i], _, amp[i], rel[i] = advance_states(z[i], D[t, i], amp[i], rel[i], D[t + 1, i] - D[t, i],
                                                         presliding, memory, tau, dt)


def feature_series(name: str, deflection: np.ndarray, velocity: np.ndarray, fx: np.ndarray, fy: np.ndarray,
                   dt: float, shape: dict | None = None, oil: np.ndarray | None = None) -> np.ndarray:
    """Feature ``name`` (n, 4) along simulated corner series (n, 4) of deflection [m], its velocity
    [m/s] and the wheel forces [N] at step ``dt`` [s]; ``shape``: values of :data:`SHAPES` (defaults
    where missing); ``oil``: the dampers' oil levels (4,) [0..1], intact (1) when not given. The states
    start at rest, as the kernel's do."""
    if name not in FEATURES:
        raise ValueError(f"unknown learned-force feature {name!r}; known: {', '.join(FEATURES)}")
    sh = shape_defaults() | dict(shape or {})
    out = np.empty(deflection.shape)
    D, V, FX, FY = (np.ascontiguousarray(a, float) for a in (deflection, velocity, fx, fy))
    OIL = np.ones(4) if oil is None else np.ascontiguousarray(oil, float).reshape(4)
    _series(D, V, FX, FY, OIL, float(dt), FEATURES.index(name), float(sh["deflection_ref"]), float(sh["velocity_ref"]),
            float(sh["force_ref"]), float(sh["knee_velocity"]), float(sh["free_play"]), float(sh["presliding"]),
            float(sh["memory"]), float(sh["stribeck_velocity"]), float(sh["relaxation_time"]), float(sh["contact_gap"]),
            float(sh["rebound_ratio"]), float(sh["creep_velocity"]), float(sh["rebound_gap"]), out)
    return out


_COEF_MEANING = {
    "constant": "force offset", "deflection": "spring force at d = d_ref",
    "deflection_cubed": "progressive spring force at d = d_ref", "deflection_velocity": "viscous force at v = v_ref",
    "velocity_squared": "orifice force at v = v_ref of an intact damper",
    "velocity_beyond_knee": "force change v_ref beyond the knee of an intact damper",
    "sign_velocity": "friction level", "peak_deflection": "friction level at amplitude d_ref",
    "lateral_force": "friction level at |Fy| = F_ref", "longitudinal_force": "friction level at |Fx| = F_ref",
    "velocity_weakening": "friction level at rest above the sliding level (falls with exp(-|v| / v_s))",
    "roll_deflection": "force at a left-right difference d_ref",
    "roll_free_play": "force at a left-right difference d_ref within the play",
    "relaxing_deflection": "spring force at a change of d_ref faster than the relaxation time",
    "bump_contact": "spring force d_ref of bump beyond the contact gap",
    "rebound_contact": "spring force d_ref of rebound beyond the contact gap",
    "compression": "friction level at d = d_ref of bump over its level at static (less in rebound)",
    "creep_damping": "creep force at the creep velocity (viscous below it, fading above)",
    "bump_damping": "damping force at v = v_ref, d_ref of bump beyond the contact gap, of an intact damper",
    "rebound_damping": "damping force at v = v_ref, d_ref of rebound beyond the contact gap, of an intact damper",
    "deflection_squared": "force at d = +-d_ref of a spring whose rate grows through the stroke (one sense in bump "
                          "and rebound)",
    "zone_damping": "damping force at v = v_ref, d_ref beyond the contact gap on either side of static, of an "
                    "intact damper",
    "bump_contact_squared": "progressive spring force d_ref of bump beyond the contact gap (grows with the square "
                            "of the depth)",
    "rebound_contact_squared": "progressive spring force d_ref of rebound beyond the contact gap (grows with the "
                               "square of the depth)"}

LEARNED_FORCE = register_term(PhysicsTerm(
    name="unlisted_force", component="axle",
    meaning="a force learned from the shape of the missing force: coefficients times features of the corner's "
            "state (model/learned_force.py)",
    params=tuple(TermParam(f"c_{f}", "N", _COEF_MEANING[f], 0.0, -1e5, 1e5) for f in FEATURES) + (
        TermParam("deflection_ref", "m", "deflection scale of the features", 0.01, 1e-4, 1.0),
        TermParam("velocity_ref", "m/s", "deflection-velocity scale of the features", 0.1, 1e-3, 10.0),
        TermParam("force_ref", "N", "wheel-force scale of the features", 1000.0, 1.0, 1e5),
        TermParam("knee_velocity", "m/s", "deflection velocity where velocity_beyond_knee sets in", 0.2, 0.0, 5.0),
        TermParam("free_play", "m", "half width of the left-right free play of roll_free_play", 0.004, 0.0, 0.1),
        TermParam("presliding", "m", "presliding travel of the friction-like features' unit Dahl element",
                  1e-4, 1e-7, 0.01),
        TermParam("memory", "s", "time constant with which peak_deflection forgets the peak deflection",
                  1.0, 1e-3, 100.0),
        TermParam("stribeck_velocity", "m/s", "sliding velocity over which velocity_weakening's friction falls "
                  "by 1/e (Stribeck velocity)", 0.01, 1e-4, 1.0),
        TermParam("relaxation_time", "s", "relaxation time of relaxing_deflection's spring (its Maxwell element's "
                  "damping over its rate)", 0.07, 1e-3, 10.0),
        TermParam("contact_gap", "m", "deflection of bump from static beyond which bump_contact, bump_damping and "
                  "zone_damping's bump side act", 0.02, 0.0, 0.2),
        TermParam("rebound_ratio", "1", "force of velocity_squared and velocity_beyond_knee in rebound over the force "
                  "at the same speed in compression (1: a symmetric law)", 1.0, 0.0, 10.0),
        TermParam("creep_velocity", "m/s", "sliding velocity of creep_damping's peak (viscous below it, fading above)",
                  0.001, 1e-5, 1.0),
        TermParam("rebound_gap", "m", "deflection of rebound from static beyond which rebound_contact, rebound_damping "
                  "and zone_damping's rebound side act (the contact gap's value where the finder does not fit it "
                  "apart: config/force_shape.yaml fit.rebound_gap)", 0.02, 0.0, 0.2)),
    n_states=4, force=learned_force_force, update=learned_force_update,
    gains=tuple(f"c_{f}" for f in FEATURES)))


def shape_defaults() -> dict:
    """The declared default of every shape parameter (:data:`SHAPES`)."""
    return {p.name: p.default for p in LEARNED_FORCE.params if p.name in SHAPES}
