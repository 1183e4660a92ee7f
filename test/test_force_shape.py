"""Reading physics off the shape of the missing force (issue 26, items 3-4): the learned term's features
and kernel force, and the stability selection's behaviour on known regression problems."""
from __future__ import annotations

import dataclasses
import math
import os
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from susp_sim_ros.analysis.discrepancy import force_shape as fs
from susp_sim_ros.model import Model, load_variant, load_vehicle, simulate
from susp_sim_ros.model.extra_terms import DAMPER_GAS_PRELOAD, EXTRA_VISCOUS_DAMPING
from susp_sim_ros.model.layout import P_INDEX
from susp_sim_ros.model.learned_force import FEATURES, LEARNED_FORCE, feature_series, shape_defaults
from susp_sim_ros.model.maneuvers import build_maneuver
from susp_sim_ros.model.params import TermSetting

DT = 0.001


def _series(n=400, seed=0):
    rng = np.random.default_rng(seed)
    t = DT * np.arange(n)
    D = np.column_stack([0.02 * np.sin(2 * np.pi * (1.0 + 0.3 * i) * t + rng.uniform(0, 6)) for i in range(4)])
    V = np.gradient(D, DT, axis=0)
    F = rng.normal(0, 500, (n, 4))
    return D, V, F, F[::-1].copy()


def test_features_are_what_their_names_say():
    D, V, FX, FY = _series()
    sh = shape_defaults()
    x = D / sh["deflection_ref"]
    u = V / sh["velocity_ref"]
    get = {f: feature_series(f, D, V, FX, FY, DT) for f in FEATURES}
    np.testing.assert_allclose(get["constant"], 1.0)
    np.testing.assert_allclose(get["deflection"], x)
    np.testing.assert_allclose(get["deflection_cubed"], x ** 3)
    np.testing.assert_allclose(get["deflection_squared"], x ** 2)
    np.testing.assert_allclose(get["deflection_velocity"], u)
    np.testing.assert_allclose(get["velocity_squared"], u * np.abs(u))
    knee = sh["knee_velocity"]
    beyond = np.sign(V) * np.maximum(np.abs(V) - knee, 0) / sh["velocity_ref"]
    np.testing.assert_allclose(get["velocity_beyond_knee"], beyond)
    # a valve acts on the damper's oil: the knee's force scales with each damper's oil level
    oil = np.array([1.0, 0.5, 0.0, 0.25])
    np.testing.assert_allclose(feature_series("velocity_beyond_knee", D, V, FX, FY, DT, oil=oil), beyond * oil)
    np.testing.assert_allclose(feature_series("velocity_squared", D, V, FX, FY, DT, oil=oil), u * np.abs(u) * oil)
    # the damper's forces in rebound (v < 0) are the rebound ratio times the compression law's at that speed
    rb = np.where(V < 0.0, 2.5, 1.0)
    assert np.any(V < -knee) and np.any(V > knee)
    for name, want in (("velocity_squared", u * np.abs(u)), ("velocity_beyond_knee", beyond)):
        np.testing.assert_allclose(feature_series(name, D, V, FX, FY, DT, shape={"rebound_ratio": 2.5}), rb * want)
    np.testing.assert_allclose(feature_series("deflection_velocity", D, V, FX, FY, DT, shape={"rebound_ratio": 2.5}), u)
    np.testing.assert_allclose(feature_series("deflection_velocity", D, V, FX, FY, DT, oil=oil), u)
    other = D[:, [1, 0, 3, 2]]
    np.testing.assert_allclose(get["roll_deflection"], (D - other) / sh["deflection_ref"])
    gap = sh["free_play"]
    np.testing.assert_allclose(get["roll_free_play"], np.clip(D - other, -gap, gap) / sh["deflection_ref"])
    # springs met beyond a gap of bump, of rebound (each its own): nothing within it
    g, gr = 0.5 * float(np.abs(D).max()), 0.3 * float(np.abs(D).max())
    gaps = {"contact_gap": g, "rebound_gap": gr}
    contact = {f: feature_series(f, D, V, FX, FY, DT, shape=gaps) for f in ("bump_contact", "rebound_contact")}
    np.testing.assert_allclose(contact["bump_contact"], np.maximum(D - g, 0.0) / sh["deflection_ref"])
    np.testing.assert_allclose(contact["rebound_contact"], np.minimum(D + gr, 0.0) / sh["deflection_ref"])
    assert np.any(D > g) and np.any((D < -gr) & (D > -g)) and np.any(np.abs(D) < gr)
    np.testing.assert_allclose(get["bump_contact"], np.maximum(D - sh["contact_gap"], 0.0) / sh["deflection_ref"])
    # a contact's progressive part: the square of its depth beyond the gap, of the contact's sense
    squares = {f: feature_series(f, D, V, FX, FY, DT, shape=gaps) for f in ("bump_contact_squared",
                                                                             "rebound_contact_squared")}
    np.testing.assert_allclose(squares["bump_contact_squared"], contact["bump_contact"] ** 2)
    np.testing.assert_allclose(squares["rebound_contact_squared"], -contact["rebound_contact"] ** 2)
    assert squares["bump_contact_squared"].max() > 0.0 > squares["rebound_contact_squared"].min()
    z = get["sign_velocity"]
    assert np.all(np.abs(z) <= 1.0 + 1e-12)
    moving = np.abs(V) > 0.02   # past the presliding travel the unit friction element has slid
    assert np.mean(np.sign(z[moving]) == np.sign(V[moving])) > 0.95
    np.testing.assert_allclose(get["lateral_force"], z * np.abs(FY) / sh["force_ref"])
    # friction growing with the compression: the friction element times the signed deflection, so beside
    # sign_velocity a level F0 + F1 d that is higher in bump than in rebound
    np.testing.assert_allclose(get["compression"], z * x)
    assert np.any((D > 0.01) & moving) and np.any((D < -0.01) & moving)
    # Stribeck: the friction element's level falls by 1/e over the Stribeck velocity of sliding
    np.testing.assert_allclose(get["velocity_weakening"], z * np.exp(-np.abs(V) / sh["stribeck_velocity"]))
    # a spring that relaxes: a unit Maxwell element's extension m, dm/dt = v - m / tau, exact per step
    tau = sh["relaxation_time"]
    e = np.exp(-DT / tau)
    m = np.zeros_like(D)
    for t in range(len(D) - 1):
        m[t + 1] = m[t] * e + (D[t + 1] - D[t]) / DT * tau * (1.0 - e)
    np.testing.assert_allclose(get["relaxing_deflection"], m / sh["deflection_ref"], rtol=1e-9, atol=1e-12)
    # a creep: viscous below the creep velocity, its peak 1 at it, fading above; no friction element in it
    vc = sh["creep_velocity"]
    np.testing.assert_allclose(get["creep_damping"], V / vc * np.exp(1.0 - np.abs(V) / vc))
    # a damping met beyond the contact gap of bump, the rebound gap, both (a soft zone between them, off centre
    # where the gaps differ): the deflection velocity times the depth beyond it, none within it, a force of the
    # damper's oil
    for name, depth in (("bump_damping", np.maximum(D - g, 0.0)), ("rebound_damping", np.maximum(-D - gr, 0.0)),
                        ("zone_damping", np.maximum(D - g, 0.0) + np.maximum(-D - gr, 0.0))):
        want = u * depth / sh["deflection_ref"]
        got = feature_series(name, D, V, FX, FY, DT, shape=gaps)
        np.testing.assert_allclose(got, want)
        assert np.any(got != 0.0) and np.all(got[(D <= g) & (D >= -gr)] == 0.0)
        np.testing.assert_allclose(feature_series(name, D, V, FX, FY, DT, shape=gaps, oil=oil), want * oil)
    # one gap for both senses: the zone's feature is the one of a zone centred on static, to the bit
    np.testing.assert_array_equal(feature_series("zone_damping", D, V, FX, FY, DT, shape={"contact_gap": g,
                                                                                           "rebound_gap": g}),
                                  u * np.maximum(np.abs(D) - g, 0.0) / sh["deflection_ref"])


def test_a_relaxing_spring_is_a_dashpot_when_slow_and_a_spring_when_fast():
    """``relaxing_deflection``: at a steady deflection velocity v its extension settles at tau v (a dashpot
    tau k per unit rate k); a deflection much faster than tau passes whole into the spring."""
    tau, n = 0.07, 3000
    ramp = np.tile((0.05 * DT * np.arange(n))[:, None], (1, 4))   # 0.05 m/s for 3 s, 43 relaxation times
    z = np.zeros_like(ramp)
    m = feature_series("relaxing_deflection", ramp, np.gradient(ramp, DT, axis=0), z, z, DT,
                       shape={"relaxation_time": tau, "deflection_ref": 1.0})
    assert m[-1, 0] == pytest.approx(tau * 0.05, rel=1e-9)
    jump = np.zeros((3, 4))
    jump[1:] = 0.01                                                # 1 cm within one 1 ms step
    m = feature_series("relaxing_deflection", jump, np.gradient(jump, DT, axis=0), jump * 0, jump * 0, DT,
                       shape={"relaxation_time": 10.0, "deflection_ref": 1.0})
    assert m[1, 0] == pytest.approx(0.01, rel=1e-4)


def _run(terms, maneuver="bump_crossing", variant="full", vehicle=None):
    base = load_variant(variant)
    model = Model(vehicle or load_vehicle("passat_b8_like"), dataclasses.replace(base, terms=base.terms + tuple(terms)))
    man = build_maneuver(maneuver, model.vehicle.wheelbase)
    res = simulate(model, man.to_inputs(DT), dt=DT, road=man.road, oil=(1.0, 1.0, 0.0, 0.0),
                   outputs=["PITCH_RATE", "ROLL_RATE", "AZ_SF"])
    return {k: res.values[:, j] for j, k in enumerate(("PITCH_RATE", "ROLL_RATE", "AZ_SF"))}


def _bump_run(terms):
    return _run(terms)


def test_the_learned_roll_and_friction_features_are_the_models_own_elements_in_the_kernel():
    """The state-based features against exact identities: ``roll_deflection`` with coefficient
    ``dK d_ref`` is an anti-roll bar dK stiffer (the other wheel's deflection read from the term's state
    is the one the bar sees), and ``sign_velocity`` of level F with presliding travel F / sigma is the axle
    friction element of level F (the paper's Dahl element, no scalings in ``dahl_only``)."""
    sh = shape_defaults()
    vp = load_vehicle("passat_b8_like")
    dk = (4000.0, 2500.0)
    stiffer = dataclasses.replace(vp, arb_rate=(vp.arb_rate[0] + dk[0], vp.arb_rate[1] + dk[1]))
    coef = [dk[0] * sh["deflection_ref"]] * 2 + [dk[1] * sh["deflection_ref"]] * 2
    learned = _run([_learned(c_roll_deflection=coef)], "sine_steer", vehicle=vp)
    listed = _run([], "sine_steer", vehicle=stiffer)
    plain = _run([], "sine_steer", vehicle=vp)
    scale = np.max(np.abs(listed["ROLL_RATE"]))
    np.testing.assert_allclose(learned["ROLL_RATE"], listed["ROLL_RATE"], rtol=0, atol=1e-9 * scale)
    assert np.max(np.abs(listed["ROLL_RATE"] - plain["ROLL_RATE"])) > 1e-2 * scale
    level = 150.0
    no_axle = dataclasses.replace(vp, axle_friction=(0.0, 0.0))
    with_axle = dataclasses.replace(vp, axle_friction=(level, level))
    learned = _run([_learned(c_sign_velocity=level, presliding=level / vp.dahl_stiffness)], variant="dahl_only",
                   vehicle=no_axle)
    listed = _run([], variant="dahl_only", vehicle=with_axle)
    plain = _run([], variant="dahl_only", vehicle=no_axle)
    scale = np.max(np.abs(listed["PITCH_RATE"]))
    np.testing.assert_allclose(learned["PITCH_RATE"], listed["PITCH_RATE"], rtol=0, atol=1e-9 * scale)
    assert np.max(np.abs(listed["PITCH_RATE"] - plain["PITCH_RATE"])) > 1e-2 * scale


def _frictionless_bump(**learned):
    """A bump crossing of the ``dahl_only`` car without friction of note (the terms' force output is the learned
    term's alone) with a learned term of ``learned`` values: the vehicle, the run's (n, 9) outputs (deflections,
    the terms' force per corner, pitch rate), its deflections D and forces F."""
    vp = dataclasses.replace(load_vehicle("passat_b8_like"), axle_friction=(0.0, 0.0),
                             damper_friction_intact=(1e-12, 1e-12), damper_friction_empty=(1e-12, 1e-12))
    model = Model(vp, dataclasses.replace(load_variant("dahl_only"), terms=load_variant("dahl_only").terms + (
        _learned(**learned),)))
    man = build_maneuver("bump_crossing", vp.wheelbase)
    outs = [f"{o}_{w}" for o in ("DEFL", "F_FRICTION") for w in ("FL", "FR", "RL", "RR")] + ["PITCH_RATE"]
    res = simulate(model, man.to_inputs(DT), dt=DT, road=man.road, outputs=outs)
    return vp, res, res.values[:, :4], res.values[:, 4:8]


def test_the_learned_relaxing_spring_in_the_kernel_is_its_feature_on_the_run():
    """The kernel's ``relaxing_deflection`` force along a bump crossing (``dahl_only`` without friction of
    note: the terms' force output is the learned term's alone) is its coefficient times the feature evaluated on
    the run's own deflections (:func:`feature_series`), and it changes the motion."""
    coef, tau = 50.0, 0.05
    vp, res, D, F = _frictionless_bump(c_relaxing_deflection=coef, relaxation_time=tau)
    zero = np.zeros_like(D)
    want = coef * feature_series("relaxing_deflection", D, zero, zero, zero, DT,
                                 shape={"relaxation_time": tau})
    assert np.abs(F).max() > 20.0
    # an output row gives the deflection at the end of its step and the force held over it (from the state
    # at the step's start): the force of row t is the feature of the deflections up to row t - 1
    np.testing.assert_allclose(F[1:], want[:-1], rtol=0, atol=1e-9 * np.abs(F).max())
    plain = _run([], variant="dahl_only", vehicle=vp)
    assert np.max(np.abs(res.values[:, 8] - plain["PITCH_RATE"])) > 1e-2 * np.max(np.abs(plain["PITCH_RATE"]))


@pytest.mark.parametrize("feature", ["bump_contact", "rebound_contact", "bump_contact_squared",
                                     "rebound_contact_squared"])
def test_the_learned_contact_spring_in_the_kernel_is_its_feature_on_the_run(feature):
    """The kernel's ``bump_contact`` / ``rebound_contact`` force along a bump crossing is its coefficient times
    the feature on the run's own deflections at the contact gap (none within it), and it changes the motion."""
    coef, gap = 200.0, 0.01
    vp, res, D, F = _frictionless_bump(**{f"c_{feature}": coef}, contact_gap=gap)
    zero = np.zeros_like(D)
    want = coef * feature_series(feature, D, zero, zero, zero, DT, shape={"contact_gap": gap})
    assert np.abs(F).max() > 100.0 and np.all(np.abs(F[1:][np.abs(D[:-1]) <= gap]) < 1e-9)
    np.testing.assert_allclose(F[1:], want[:-1], rtol=0, atol=1e-9 * np.abs(F).max())
    plain = _run([], variant="dahl_only", vehicle=vp)
    assert np.max(np.abs(res.values[:, 8] - plain["PITCH_RATE"])) > 1e-2 * np.max(np.abs(plain["PITCH_RATE"]))


def test_the_learned_even_spring_in_the_kernel_is_its_feature_on_the_run():
    """The kernel's ``deflection_squared`` force along a bump crossing is its coefficient times the square of the
    run's own deflections over d_ref, of one sense in bump and rebound, and it changes the motion."""
    coef = 30.0   # [N] at d = +-d_ref (10 mm)
    vp, res, D, F = _frictionless_bump(c_deflection_squared=coef)
    zero = np.zeros_like(D)
    want = coef * feature_series("deflection_squared", D, zero, zero, zero, DT)
    np.testing.assert_allclose(want, coef * (D / 0.01) ** 2, rtol=1e-12)
    assert D.min() < -0.02 and D.max() > 0.02 and F.min() >= 0.0 and np.abs(F).max() > 100.0
    np.testing.assert_allclose(F[1:], want[:-1], rtol=0, atol=1e-9 * np.abs(F).max())
    plain = _run([], variant="dahl_only", vehicle=vp)
    assert np.max(np.abs(res.values[:, 8] - plain["PITCH_RATE"])) > 1e-2 * np.max(np.abs(plain["PITCH_RATE"]))


def test_the_learned_friction_growing_with_the_compression_in_the_kernel_is_its_feature_on_the_run():
    """The kernel's ``compression`` force along a bump crossing is its coefficient times the feature on the
    run's own deflections (the unit friction element advanced over the same increments; beside a plain
    friction level it raises the level in bump and lowers it in rebound), and it changes the motion."""
    coef = 60.0   # [N] of friction level at d_ref of bump
    vp, res, D, F = _frictionless_bump(c_compression=coef)
    zero = np.zeros_like(D)
    want = coef * feature_series("compression", D, zero, zero, zero, DT)
    np.testing.assert_allclose(F[1:], want[:-1], rtol=0, atol=1e-9 * np.abs(F).max())
    ref = shape_defaults()["deflection_ref"]
    assert np.abs(F[1:][D[:-1] > 2 * ref]).max() > 2.0 * coef   # beyond 2 d_ref of bump: more than twice
    plain = _run([], variant="dahl_only", vehicle=vp)
    assert np.max(np.abs(res.values[:, 8] - plain["PITCH_RATE"])) > 1e-2 * np.max(np.abs(plain["PITCH_RATE"]))


def test_the_learned_valve_and_orifice_act_only_as_far_as_the_damper_holds_oil():
    """``velocity_beyond_knee`` (a valve) and ``velocity_squared`` (an orifice) are forces of the damper's oil:
    on the rear-empty car (oil 1, 1, 0, 0) either learned on the rear axle changes nothing (to the bit), the
    same on the front does."""
    plain = _bump_run([])
    for name in ("c_velocity_beyond_knee", "c_velocity_squared"):
        knee = {"knee_velocity": 0.05}
        rear = _bump_run([_learned(**{name: (0.0, 0.0, 1000.0, 1000.0)}, **knee)])
        front = _bump_run([_learned(**{name: (1000.0, 1000.0, 0.0, 0.0)}, **knee)])
        for key in ("PITCH_RATE", "AZ_SF"):
            np.testing.assert_array_equal(rear[key], plain[key])
            assert np.max(np.abs(front[key] - plain[key])) > 1e-2 * np.max(np.abs(plain[key])), (name, key)


def test_the_learned_valves_rebound_ratio_in_the_kernel_is_its_feature_on_the_run():
    """A learned valve with a rebound ratio of 2.5: along a bump crossing the kernel's force is the coefficient
    times the feature on the run's own deflection velocities, 2.5 times the compression law in rebound, and
    the ratio changes the motion."""
    vp = dataclasses.replace(load_vehicle("passat_b8_like"), axle_friction=(0.0, 0.0),
                             damper_friction_intact=(1e-12, 1e-12), damper_friction_empty=(1e-12, 1e-12))
    coef, knee, ratio = 400.0, 0.05, 2.5   # more damping beyond the knee
    man = build_maneuver("bump_crossing", vp.wheelbase)
    outs = [f"{o}_{w}" for o in ("DEFL_VEL", "F_FRICTION") for w in ("FL", "FR", "RL", "RR")] + ["PITCH_RATE"]

    def run(r):
        model = Model(vp, dataclasses.replace(load_variant("dahl_only"), terms=load_variant("dahl_only").terms + (
            _learned(c_velocity_beyond_knee=coef, knee_velocity=knee, rebound_ratio=r),)))
        return simulate(model, man.to_inputs(DT), dt=DT, road=man.road, outputs=outs).values
    res, sym = run(ratio), run(1.0)
    V, F = res[:, :4], res[:, 4:8]
    want = coef * np.where(V < 0.0, ratio, 1.0) * np.sign(V) * np.maximum(np.abs(V) - knee, 0.0) \
        / shape_defaults()["velocity_ref"]
    assert np.any(V < -knee) and np.any(V > knee) and np.abs(F).max() > 10.0
    np.testing.assert_allclose(F[1:], want[:-1], rtol=0, atol=1e-9 * np.abs(F).max())
    assert np.max(np.abs(res[:, 8] - sym[:, 8])) > 1e-3 * np.max(np.abs(sym[:, 8]))


def _learned(**coefs):
    vals = {p.name: (p.default,) * 4 for p in LEARNED_FORCE.params}
    for k, v in coefs.items():
        vals[k] = tuple(v) if isinstance(v, (tuple, list)) else (v,) * 4
    return TermSetting(LEARNED_FORCE, vals)


def test_the_learned_viscous_and_spring_features_are_the_listed_terms_in_the_kernel():
    """A learned force of deflection velocity and deflection is, in the compiled model, exactly the
    listed extra viscous damping and gas-spring terms of the same size: the learned term runs wherever
    a listed one does (node, lockstep runner, finder) with the same numbers."""
    sh = shape_defaults()
    c, k = (300.0, 300.0, 800.0, 800.0), (2000.0, 2000.0, -1500.0, -1500.0)
    listed = _bump_run([TermSetting(EXTRA_VISCOUS_DAMPING, {"c": c}),
                        TermSetting(DAMPER_GAS_PRELOAD, {"f0": (0.0,) * 4, "k": k})])
    learned = _bump_run([_learned(c_deflection_velocity=[x * sh["velocity_ref"] for x in c],
                                  c_deflection=[x * sh["deflection_ref"] for x in k])])
    plain = _bump_run([])
    for key in ("PITCH_RATE", "AZ_SF"):   # a symmetric bump: no roll
        np.testing.assert_allclose(learned[key], listed[key], rtol=0, atol=1e-9 * np.max(np.abs(listed[key])))
        assert np.max(np.abs(listed[key] - plain[key])) > 1e-3 * np.max(np.abs(plain[key]))


#: library features added after the synthetic problems below were drawn: left out of them, so that every seed
#: draws the same problem as before (a column more shifts every later draw). Over 40 seeds of
#: _one_drive_dominant the truth was the stable set in 25 with the earlier library and in 27 with the
#: relaxing spring's six columns drawn in (2026-11-28): the step rule is not weakened by them.
#: The contact springs (bump_contact, rebound_contact), the friction growing with the compression and the damping
#: beyond a contact gap (bump_damping, rebound_damping, in the library since library.position_damping is on) left
#: out the same way (with the latter's eight columns drawn in, the truth was the stable set in 25 of the 40 seeds
#: of _one_drive_dominant as without them, 2026-11-30).
DRAWN_BEFORE = ("relaxing_deflection", "bump_contact", "rebound_contact", "compression", "bump_damping",
                "rebound_damping", "deflection_squared", "zone_damping")


def _design(n_drives=6, n=600, seed=1, truth=None, noise=1.0):
    """A regression problem of the force_shape layout: per drive smooth random columns of every library
    entry, the target their combination ``truth`` {(feature, axle): coef} plus white noise."""
    rng = np.random.default_rng(seed)
    entries = [e for e in fs.library(fs.settings()) if e[0] not in DRAWN_BEFORE]
    cols = fs.columns_of(entries)
    t = np.arange(n) * 0.005
    X, y, g = [], [], []
    for r in range(n_drives):
        Xr = np.column_stack([np.sin(2 * np.pi * rng.uniform(0.5, 4) * t + rng.uniform(0, 6)) *
                              rng.uniform(0.5, 2) for _ in cols])
        yr = rng.normal(0, noise, n)
        for key, coef in (truth or {}).items():
            yr = yr + coef * Xr[:, [c.key for c in cols].index(key)]
        X.append(Xr)
        y.append(yr)
        g.append(np.full(n, r))
    return fs.Design(np.vstack(X), np.concatenate(y), np.concatenate(g), cols)


def test_a_stable_dependence_is_found_with_its_axle_and_sign():
    truth = {("velocity_beyond_knee", "rear"): -3.0, ("sign_velocity", "rear"): 1.5}
    sel = fs.select(_design(truth=truth))
    assert sel is not None
    assert {c.key for c in sel.stable} == set(truth)
    assert sel.dependences[0] == "velocity_beyond_knee" and sel.axles == ["rear"]
    assert "rear axle only" in sel.description() and "valve" in sel.description()
    assert sel.listed_rivals() == []   # no listed term stands for a knee in the damper curve


def test_noise_alone_gives_no_stable_dependence():
    """The false-discovery side: a target of white noise has nothing stable in most seeds."""
    found = [bool(fs.select(_design(seed=s)).stable) for s in range(6)]
    assert sum(found) <= 1, found


def _split_spring(seed, spread=1.2, coef=3.0):
    """A rear spring law no offered feature has (a column not in the design), read by two spring features
    each of which matches it on three of the six drives and carries unrelated motion on the other three
    (``spread`` its amplitude): the resamples split their votes between the two forms."""
    d = _design(seed=seed)
    keys = [c.key for c in d.columns]
    a, b = keys.index(("deflection_cubed", "rear")), keys.index(("deflection", "rear"))
    X = d.X.copy()
    truth, other = X[:, a].copy(), X[:, b].copy()
    first = d.groups < 3
    X[:, a] = np.where(first, truth, truth + spread * other)
    X[:, b] = np.where(first, truth + spread * np.random.default_rng(100 + seed).permutation(other), truth)
    return fs.Design(X, d.y + coef * truth, d.groups, d.columns)


def test_a_spring_law_whose_votes_split_between_its_forms_is_stable_as_a_family():
    """Cluster stability selection (Faletto and Bien 2022): where the resamples split their votes between two
    spring features, neither reaching 0.6 on its own, the spring family does, and its member chosen most
    often stands for it; counted per feature the law would have been missed in those seeds."""
    by_law = 0
    for seed in range(6):
        sel = fs.select(_split_spring(seed))
        assert sel is not None and sel.law_frequency[("spring", "rear")] >= 0.6, seed
        assert {c.key for c in sel.stable} & {("deflection", "rear"), ("deflection_cubed", "rear")}, seed
        assert {fs.law_key(c.key) for c in sel.stable} == {("spring", "rear")}, seed
        if sel.by_law:
            by_law += 1
            assert max(sel.frequency.values()) < 0.6 and len(sel.by_law) == 1
            assert sel.by_law[0] == max(sel.frequency, key=lambda k: sel.frequency[k])
    assert by_law >= 2   # seeds no single member would have found


def test_law_families_pool_only_features_of_one_kind_and_axle():
    assert fs.law_key(("deflection", "rear")) == fs.law_key(("rebound_contact", "rear")) == ("spring", "rear")
    assert fs.law_key(("velocity_beyond_knee", "front")) == ("damping", "front")
    assert fs.law_key(("deflection", "front")) != fs.law_key(("deflection", "rear"))
    assert fs.law_key(("relaxing_deflection", "rear")) == ("relaxing_deflection", "rear")
    assert fs.law_key(("rotation_sin1", "rear")) == ("rotation_1", "rear")
    assert fs.law_key(("road_height", "front")) == ("road_height", "front")   # inputs never pool with states


def _acting_on(design, key, drives):
    """``design`` with column ``key`` (every shape value of it) zero outside ``drives``: a force that acts on
    some drives only (a rear valve where the rear dampers are oil-empty, a knee a drive never reaches)."""
    X = design.X.copy()
    for j, c in enumerate(design.columns):
        if c.key == key:
            X[~np.isin(design.groups, drives), j] = 0.0
    return fs.Design(X, design.y, design.groups, design.columns)


def test_a_force_acting_on_two_drives_of_six_is_stable_and_noise_there_is_not():
    """Counted over the resamples that can test it (two of its drives in them): a dependence that acts on
    only two of the six drives is found although most drive resamples lack one of them (unconditionally it
    would be selected in about 0.4 of them, below the 0.6 of a stable one); on a pure-noise target the same
    restricted column stays unselected."""
    key = ("velocity_beyond_knee", "rear")
    d = _design()
    rng = np.random.default_rng(3)
    only = _acting_on(d, key, [0, 2])
    cols = [j for j, c in enumerate(only.columns) if c.key == key]
    y = only.y + 3.0 * only.X[:, cols[0]]
    sel = fs.select(fs.Design(only.X, y, only.groups, only.columns))
    assert sel is not None and [c.key for c in sel.stable] == [key]
    assert sel.frequency[key] >= 0.9
    found = []
    for seed in range(6):
        noise = _acting_on(_design(seed=seed), key, [0, 2])
        noise = fs.Design(noise.X, rng.normal(0.0, 1.0, len(noise.y)), noise.groups, noise.columns)
        found.append(bool(fs.select(noise).stable))
    assert sum(found) <= 1, found


def _one_drive_dominant(seed):
    """A friction level acting alike on every drive (``sign_velocity`` rear, the truth) beside a column that
    is one dominant drive's target itself, its misfit and noise included, and on a second drive the truth's
    opposite (``peak_deflection`` rear): on all drives at once the second column is the more correlated with
    the target, on a left-out drive it predicts nothing."""
    d = _design(seed=seed)
    keys = [c.key for c in d.columns]
    ja, jp = keys.index(("sign_velocity", "rear")), keys.index(("peak_deflection", "rear"))
    X, y = d.X.copy(), d.y + 3.0 * d.X[:, ja]
    big = d.groups == 0
    y[big] *= 4.0
    X[:, jp] = 0.0
    X[big, jp] = y[big]
    X[d.groups == 1, jp] = -X[d.groups == 1, ja]
    return fs.Design(X, y, d.groups, d.columns)


def test_the_dependence_that_predicts_left_out_drives_is_chosen_over_the_one_that_fits_them_all():
    """Each selection step adds the column that predicts the left-out drives (:func:`fs._forward_cv`), not
    the one most correlated with the target over all drives at once: the latter (a matching pursuit's step)
    split the resamples' votes between the two here and left the truth unstable in two of these four seeds."""
    for seed in range(4):
        sel = fs.select(_one_drive_dominant(seed))
        assert sel is not None and [c.key for c in sel.stable] == [("sign_velocity", "rear")], seed
        assert sel.frequency.get(("peak_deflection", "rear"), 0.0) < 0.6


def test_dependences_a_listed_term_stands_for_name_it_as_the_rival():
    sel = fs.select(_design(truth={("deflection_velocity", "front"): 4.0}))
    assert sel is not None and [c.key for c in sel.stable] == [("deflection_velocity", "front")]
    assert sel.listed_rivals() == ["extra_viscous_damping"]


def test_the_learned_candidate_writes_its_coefficients_and_shape_into_the_term():
    sel = fs.select(_design(truth={("roll_free_play", "front"): 5.0}))
    cand = fs.learned_candidate(sel)
    assert [p.name for p in cand.params][0] == "roll_free_play_front" and cand.params[-1].name == "free_play"
    full = load_variant("full")
    model = Model("passat_b8_like", dataclasses.replace(full, terms=full.terms + (_learned(),)))
    P = np.stack([model.params((1, 1, 1, 1))])
    x = np.array([120.0, 0.003])
    cand.apply(P, P.copy(), x, model)
    np.testing.assert_array_equal(P[0, model.term_param_slice(fs.TERM, "c_roll_free_play")], [120, 120, 0, 0])
    np.testing.assert_array_equal(P[0, model.term_param_slice(fs.TERM, "free_play")], [0.003] * 4)
    written = cand.term_params(x, None)
    assert written["c_roll_free_play"] == {"front": 120.0, "rear": 0.0}


def test_a_contact_at_static_starts_the_fit_at_gap_zero_with_a_step_of_its_range():
    """A spring met at static (``bump_contact`` at gap 0: stiffer in bump than in rebound) is fitted from gap 0
    within the config's range; its step is a share of that range (a step of 0 would stall the fit), and the words
    give the gap."""
    cfg = fs.settings()
    col = fs.Column("bump_contact", "rear", 0.0)
    sel = fs.Selection({col.key: 0.9}, [col], np.array([150.0]), np.array([1.0]), 24)
    gap = fs.learned_candidate(sel, cfg).params[-1]
    assert gap.name == "contact_gap" and gap.shape and gap.neutral == 0.0
    assert (gap.lower, gap.upper) == tuple(float(v) for v in cfg["fit.contact_gap_range_m"])
    assert 0.0 < gap.step < gap.upper - gap.lower
    assert "met beyond 0 mm of bump" in sel.description() and "rear stiffer" in sel.description()
    assert "beyond 15 mm of rebound" in fs.Selection({("rebound_contact", "front"): 0.9},
                                                     [fs.Column("rebound_contact", "front", 0.02)], np.array([90.0]),
                                                     np.array([1.0]), 24).description(shapes={"contact_gap": 0.015})


def test_the_gaps_of_bump_and_rebound_are_fitted_apart_only_where_the_settings_say():
    """``fit.rebound_gap`` (on as shipped since 2026-12-06): off, a learned term's dependences met in bump and in
    rebound share one fitted gap, written to both gaps' parameters (the term as it was before it had two); on, each
    sense is fitted at its own gap from the value the regression picked (a stop or a soft zone laid out for another
    ride height), and a zone's one gap starts both ends."""
    cfg = fs.settings()
    assert cfg["fit.rebound_gap"] is True   # on since the whole truth-generator family ran with it
    cols = [fs.Column("bump_damping", "rear", 0.02), fs.Column("rebound_damping", "rear", 0.0)]
    sel = fs.Selection({c.key: 0.9 for c in cols}, cols, np.array([60.0, 40.0]), np.array([0.6, 0.4]), 24)
    where = {"contact_gap": slice(0, 1), "rebound_gap": slice(1, 2)}
    model = SimpleNamespace(term_param_slice=lambda term, name: where.get(name, slice(2, 4)))
    for apart, names in ((False, ["contact_gap"]), (True, ["contact_gap", "rebound_gap"])):
        cand = fs.learned_candidate(sel, cfg | {"fit.rebound_gap": apart})
        shapes = [p for p in cand.params if p.shape]
        assert [p.name for p in shapes] == names
        assert [p.neutral for p in shapes] == [0.02, 0.0][:len(names)]   # each from the regression's pick
        x = np.array([60.0, 40.0, 0.016, 0.006][:2 + len(names)])
        P = np.zeros((1, 4))
        cand.apply(P, P.copy(), x, model)
        assert (P[0, 0], P[0, 1]) == ((0.016, 0.016) if not apart else (0.016, 0.006))
        written = cand.term_params(x, None)
        assert written["rebound_gap"]["rear"] == P[0, 1] and written["contact_gap"]["rear"] == 0.016
        assert cand.axle_of[-len(names):] == ("rear",) * len(names)
    zone = fs.Selection({("zone_damping", "rear"): 0.9}, [fs.Column("zone_damping", "rear", 0.02)],
                        np.array([80.0]), np.array([1.0]), 24)
    shapes = [p for p in fs.learned_candidate(zone, cfg | {"fit.rebound_gap": True}).params if p.shape]
    assert [(p.name, p.neutral) for p in shapes] == [("contact_gap", 0.02), ("rebound_gap", 0.02)]


def test_a_learned_knee_ranges_over_its_physics_and_sizes_no_effect():
    """The knee the regression picked from the library is the fit's start, free over the config's plausible
    range of valve knees (not a band around the library value: x/4..4x around 0.1 m/s held a rear valve's knee
    at 0.4 m/s, its edge); it is a shape value: the term's effect is sized by its coefficients alone (a
    coefficient interval holding zero is no effect, a knee's interval says nothing about it), and the words
    give the knee as fitted."""
    from susp_sim_ros.analysis.discrepancy.report import _where
    cfg = fs.settings()
    truth = {("velocity_beyond_knee", "rear"): -3.0, ("velocity_beyond_knee", "front"): -2.0}
    sel = fs.select(_design(truth=truth))
    assert sel is not None and {c.key for c in sel.stable} == set(truth)
    cand = fs.learned_candidate(sel)
    knee, ratio = cand.params[-2:]
    assert knee.name == "knee_velocity" and knee.shape
    # a valve brings its rebound ratio: from 1 (symmetric) within the config's range, a shape like the knee
    assert ratio.name == "rebound_ratio" and ratio.shape and ratio.neutral == 1.0 and ratio.step > 0.0
    assert (ratio.lower, ratio.upper) == tuple(float(v) for v in cfg["fit.rebound_ratio_range"])
    assert "in rebound 2.0x what it gives in compression" in sel.description(shapes={"rebound_ratio": 2.0})
    assert (knee.lower, knee.upper) == tuple(float(v) for v in cfg["fit.knee_velocity_range_m_s"])
    assert knee.upper > 4 * min(float(v) for v in cfg["library.knee_velocities_m_s"])
    assert cand.gain_indices == (0, 1)
    # the knee's and the ratio's intervals clear of their starts
    lo, hi = np.array([-200.0, -150.0, 0.3, 1.5]), np.array([50.0, 40.0, 0.5, 2.5])
    assert cand.effect_in_interval(lo, hi)
    assert not cand.effect_in_interval(np.array([-200.0, -150.0, 0.3, 1.5]), np.array([-10.0, 40.0, 0.5, 2.5]))
    assert "0.45 m/s" in sel.description(shapes={"knee_velocity": 0.45})
    # where: no coefficient resolved on its own, the axles it was selected on (both), not the larger one
    x = np.array([-80.0, -60.0, 0.4, 2.0])
    assert _where(cand, x, lo, hi, sel.axles) == "all"
    assert _where(cand, x, np.array([-200.0, -150.0, 0.3, 1.5]), np.array([-10.0, 40.0, 0.5, 2.5]), sel.axles) == \
        cand.axle_of[0]


@settings(max_examples=20, deadline=None)
@given(st.lists(st.floats(-0.05, 0.05), min_size=8, max_size=8), st.floats(-2.0, 2.0))
def test_feature_series_is_finite_and_the_free_play_bounded(ds, v):
    """Any corner deflections (two steps, the wheels of an axle apart): every feature finite, the free-play
    feature within +-free play / d_ref, the roll features antisymmetric between the wheels of an axle."""
    D = np.array(ds).reshape(2, 4)
    V = np.full((2, 4), v)
    F = np.ones((2, 4))
    sh = shape_defaults()
    for f in FEATURES:
        assert np.all(np.isfinite(feature_series(f, D, V, F, F, DT)))
    fp = feature_series("roll_free_play", D, V, F, F, DT)
    assert np.all(np.abs(fp) <= sh["free_play"] / sh["deflection_ref"] + 1e-12)
    for name in ("roll_free_play", "roll_deflection"):
        y = feature_series(name, D, V, F, F, DT)
        np.testing.assert_allclose(y[:, [0, 2]], -y[:, [1, 3]])


@pytest.mark.parametrize("bad", ["no_such_feature"])
def test_an_unknown_feature_is_named(bad):
    with pytest.raises(ValueError, match=bad):
        feature_series(bad, *(np.zeros((3, 4)),) * 4, DT)


def test_the_shape_is_read_against_the_calibration_with_its_far_shifts_undone():
    """The regression's target is the model as calibrated, except that a value moved more than one prior
    sd from its prior (a hypothesis that may have taken up the physics: a blown-off valve read as dampers
    25 % weaker) is set back to its prior; values within one sd (the car) and other terms are kept."""
    from types import SimpleNamespace

    from susp_sim_ros.analysis.discrepancy.calibration import CalParam
    from susp_sim_ros.analysis.discrepancy.finder import CALIBRATION, DiscrepancyFinder

    def par(name, prior, lo, hi):   # prior sd = (hi - lo) / 4
        return CalParam(name, name, "all", None, "1", prior, lo, hi, "test")

    informed = [par("damper", 1.0, 0.9, 1.1), par("mass", 1400.0, 1260.0, 1540.0), par("arb", 15e3, 12e3, 18e3)]
    structure = SimpleNamespace(names=[CALIBRATION, "a_term"], offsets=[0, 3, 4],
                                span=lambda name: range(0, 3))
    fit = SimpleNamespace(structure=structure, x=np.array([0.75, 1430.0, 17000.0, 42.0]))
    finder = DiscrepancyFinder.__new__(DiscrepancyFinder)   # only the calibration's informed values set
    finder.informed_ = informed
    x = finder._without_far_shifts(fit)
    # damper 5 sd off -> prior; mass 0.9 sd off -> kept; arb 1.3 sd off -> prior; the term's value kept
    np.testing.assert_array_equal(x, [1.0, 1430.0, 15e3, 42.0])
    np.testing.assert_array_equal(fit.x, [0.75, 1430.0, 17000.0, 42.0])   # the fit itself untouched
    finder.informed_ = []
    nothing = finder._without_far_shifts(fit)
    np.testing.assert_array_equal(nothing, fit.x)


def test_a_learned_friction_brings_its_laws_shape_into_the_fit():
    """A friction-like dependence brings its law's shape into the fit (force_shape.friction_law): the unit
    Dahl element's presliding travel, and on the axle with a plain friction level a velocity weakening (a
    level at rest above the sliding one, coefficient neutral 0) with its Stribeck velocity and the level's
    growth with the compression (coefficient neutral 0); shapes marked
    as such (one value for both axles, the term's declared default to start, bounded by
    config/force_shape.yaml), all written into the term like the coefficients. A learned force without
    friction has none, and the regression is never offered the weakening (it is a law's shape). It
    matters: at one friction level (60 N, rear), a contact that slides after 20 um instead of 100 um
    changes the bump's pitch rate by more than 1 % of its peak and more than three times the benchmark
    drives' gyro noise (0.05 deg/s). The creep the law brings as well is the next test's."""
    cfg = dict(fs.settings()) | {"fit.creep_in_friction_law": False}
    sel = fs.select(_design(truth={("sign_velocity", "rear"): 3.0, ("lateral_force", "rear"): 2.0}))
    cand = fs.learned_candidate(sel, cfg)
    names = [p.name for p in cand.params]
    assert names[len(sel.stable):] == ["velocity_weakening_rear", "compression_rear", "presliding",
                                       "stribeck_velocity"]
    xp, vs = cand.params[-2], cand.params[-1]
    assert xp.shape and vs.shape and cand.axle_of[-2:] == ("rear", "rear")
    for law in cand.params[len(sel.stable):len(sel.stable) + 2]:   # coefficients, neutral none
        assert law.neutral == 0.0 and not law.shape
    assert cand.params[len(sel.stable) + 1].step == cfg["fit.level_growth_step_N"]
    assert (xp.neutral, vs.neutral) == (shape_defaults()["presliding"], shape_defaults()["stribeck_velocity"])
    assert (xp.lower, xp.upper) == tuple(cfg["fit.presliding_range_m"])
    assert (vs.lower, vs.upper) == tuple(cfg["fit.stribeck_velocity_range_m_s"])
    assert cand.gain_indices == tuple(range(len(cand.params) - 2))   # "no effect" is read from the levels
    full = load_variant("full")
    model = Model("passat_b8_like", dataclasses.replace(full, terms=full.terms + (_learned(),)))
    P = np.stack([model.params((1, 1, 1, 1))])
    x = np.array([60.0] * len(sel.stable) + [45.0, 12.0, 2e-5, 0.015])
    cand.apply(P, P.copy(), x, model)
    np.testing.assert_array_equal(P[0, model.term_param_slice(fs.TERM, "presliding")], [2e-5] * 4)
    np.testing.assert_array_equal(P[0, model.term_param_slice(fs.TERM, "stribeck_velocity")], [0.015] * 4)
    np.testing.assert_array_equal(P[0, model.term_param_slice(fs.TERM, "c_velocity_weakening")], [0, 0, 45, 45])
    np.testing.assert_array_equal(P[0, model.term_param_slice(fs.TERM, "c_compression")], [0, 0, 12, 12])
    written = cand.term_params(x, None)
    assert written["presliding"] == {"front": 2e-5, "rear": 2e-5}
    assert written["c_velocity_weakening"] == {"front": 0.0, "rear": 45.0}
    assert written["c_compression"] == {"front": 0.0, "rear": 12.0}
    # a growth with the compression that is stable itself is a dependence, not brought twice
    grown = dataclasses.replace(sel, stable=list(sel.stable) + [fs.Column("compression", "rear")],
                                coef=np.append(sel.coef, 5.0), share=np.append(sel.share, 0.1))
    assert [c.coefficient for c in fs.friction_law(grown, cfg)[0]] == ["velocity_weakening_rear"]
    no_friction = fs.learned_candidate(fs.select(_design(truth={("roll_free_play", "front"): 5.0})), cfg)
    assert not {"presliding", "stribeck_velocity", "velocity_weakening_front"} & {p.name for p in no_friction.params}
    assert "rebound_ratio" not in {p.name for p in no_friction.params} | {p.name for p in cand.params}
    assert "velocity_weakening" not in {f for f, _ in fs.library(cfg)}

    short, long_ = (_run([_learned(c_sign_velocity=(0.0, 0.0, 60.0, 60.0), presliding=xp_)], variant="dahl_only")
                    for xp_ in (2e-5, 1e-4))
    scale = np.max(np.abs(long_["PITCH_RATE"]))
    change = np.max(np.abs(short["PITCH_RATE"] - long_["PITCH_RATE"]))
    assert change > 0.01 * scale and change > 3 * np.radians(0.05)


def test_a_weakening_friction_holds_more_at_rest_than_it_slides_with():
    """The kernel's learned friction with a velocity weakening against its law: the unit Dahl element z
    times 40 + 80 exp(-|v| / v_s) [N] at the rear corners (v_s 10 mm/s): 120 N at rest, 40 N sliding fast,
    the 1/e point at v_s; the front corners, without coefficients, none."""
    from susp_sim_ros.model.layout import C_INDEX, N_CTX
    from susp_sim_ros.model.learned_force import learned_force_force
    names = [p.name for p in LEARNED_FORCE.params]
    vals = {p.name: [p.default] * 4 for p in LEARNED_FORCE.params}
    vals["c_sign_velocity"] = [0.0, 0.0, 40.0, 40.0]
    vals["c_velocity_weakening"] = [0.0, 0.0, 80.0, 80.0]
    vals["stribeck_velocity"] = [0.01] * 4
    p = np.array([v for n in names for v in vals[n]])
    s = np.zeros(3 * 4)
    s[0:4] = 1.0   # the unit Dahl element slid fully in the positive sense at every corner
    for v, want in ((0.0, 120.0), (0.01, 40.0 + 80.0 / np.e), (1.0, 40.0 + 80.0 * np.exp(-100.0))):
        c = np.zeros((4, N_CTX))
        c[:, C_INDEX["DD"]] = v
        got = [learned_force_force(p, 0, s, 0, i, c) for i in range(4)]
        np.testing.assert_allclose(got, [0.0, 0.0, want, want], rtol=1e-12, atol=1e-12)


def test_the_report_gives_a_form_that_stands_for_its_law_family_the_familys_frequency():
    from susp_sim_ros.analysis.discrepancy.report import _md_force_shape
    step = {"step": 1, "stable": ["rebound_contact:rear", "roll_deflection:front"],
            "selection_frequency": {"rebound_contact:rear": 0.58, "roll_deflection:front": 0.95},
            "law_frequency": {"spring:rear": 0.92, "roll:front": 0.95}, "stable_by_law": ["rebound_contact:rear"],
            "description": "A force the model lacks: ..."}
    row = _md_force_shape(None, {"force_shape": [step]}, {}, "x")[-1]
    assert "0.58 (spring law 0.92), 0.95 |" in row
    old = {k: v for k, v in step.items() if k not in ("law_frequency", "stable_by_law")}   # records before
    assert "| 0.58, 0.95 |" in _md_force_shape(None, {"force_shape": [old]}, {}, "x")[-1]
    step["law_members"] = {"first": {"bic": 2436.17, "rms_x_noise": 1.79},
                           "tried": [{"replaced": "rebound_contact:rear", "member": "bump_contact:rear", "bic": 1859.84,
                                      "rms_x_noise": 1.54, "heldout_sq": 5210.4, "heldout_sq_best_so_far": 6020.0}],
                           "kept": ["bump_contact:rear", "roll_deflection:front"]}
    said = _md_force_shape(None, {"force_shape": [step]}, {}, "x")[-1]
    assert "as read 2436.2; `rebound_contact:rear` -> `bump_contact:rear` 1859.8 (held out 5210 against 6020)" in said
    assert said.endswith("Kept: `bump_contact:rear`, `roll_deflection:front`.")


def test_the_stable_set_is_in_the_same_order_whatever_the_interpreters_string_hashing():
    """The resampling has a fixed seed so a diagnosis is reproducible; the stable set's order (the learned
    term's parameter order) must not follow the order of Python sets, which changes with PYTHONHASHSEED."""
    code = ("import sys; sys.path.insert(0, 'test'); from test_force_shape import _design; "
            "from susp_sim_ros.analysis.discrepancy import force_shape as fs; "
            "t = {('velocity_beyond_knee', 'rear'): -3.0, ('sign_velocity', 'rear'): 1.5, "
            "('roll_deflection', 'front'): 2.0, ('deflection_velocity', 'front'): 2.5}; "
            "s = fs.select(_design(truth=t)); print([c.key for c in s.stable], list(s.frequency))")
    root = Path(__file__).resolve().parents[1]
    out = {subprocess.run([sys.executable, "-c", code], cwd=root, capture_output=True, text=True, check=True,
                          env={**os.environ, "PYTHONHASHSEED": str(h)}).stdout for h in (1, 2, 3)}
    assert len(out) == 1, out


def _road_excited_law(seed, road_silent_on=(3, 4, 5)):
    """A front spring law that no feature has (the truth, a column outside the design), matched in part by a
    state feature (``deflection_cubed`` front, the law plus unrelated motion) and excited by the road: where
    the drives carry a road (0-2, bump crossings) the road height under the front wheels follows the law
    exactly, where they do not (``road_silent_on``: sine steers on a flat road) its column is zero while the
    law acts on (the roll moves the deflections)."""
    d = _design(seed=seed)
    keys = [c.key for c in d.columns]
    rng = np.random.default_rng(200 + seed)
    t = np.arange(int(np.sum(d.groups == 0))) * 0.005
    law = np.concatenate([np.sin(2 * np.pi * rng.uniform(0.5, 4) * t + rng.uniform(0, 6))
                          for _ in np.unique(d.groups)])
    X = d.X.copy()
    X[:, keys.index(("road_height", "front"))] = np.where(np.isin(d.groups, road_silent_on), 0.0, law)
    X[:, keys.index(("deflection_cubed", "front"))] = law + 0.4 * X[:, keys.index(("deflection", "rear"))]
    return fs.Design(X, d.y + 3.0 * law, d.groups, d.columns)


def _finder_reading(design, roadless=()):
    """The finder's state reading (``DiscrepancyFinder._state_reading``) of ``design`` led by the front road
    height, on a finder holding only what the reading uses; the drives ``roadless`` lack their road."""
    from types import SimpleNamespace
    from susp_sim_ros.analysis.discrepancy.finder import DiscrepancyFinder
    road = fs.Column("road_height", "front")
    led = fs.Selection({road.key: 0.9}, [road], np.array([3.0]), np.array([1.0]), 24)
    assert led.input_led
    stub = SimpleNamespace(shape_design_=design, force_shape_=[{}],
                           cases_=[SimpleNamespace(name=f"drive{g}", road=None if g in roadless else _flat_road(),
                                                   U=np.zeros((2, 40))) for g in range(6)])
    return DiscrepancyFinder._state_reading(stub, led), stub.force_shape_[-1]


def test_a_road_led_force_is_read_by_the_states_on_the_drives_the_road_does_not_reach():
    """Issue 26, item 5, "follows the road and no state": the force that the road height leads where the drives
    carry a road is read again by the states alone (:func:`fs.without_inputs`), and the drives the road does not
    reach (its column zero on the axle it leads) are named: there a law of the states must show, an input cannot.
    Where the input acts on every drive (the wheel's rotation; a road under every drive) nothing tells a state
    from it: no reading."""
    for seed in range(3):
        d = _road_excited_law(seed)
        states = fs.without_inputs(d)
        assert not any(c.feature in fs.INPUT_FEATURES for c in states.columns)
        assert states.X.shape == (len(d.y), len(states.columns)) and np.array_equal(states.y, d.y)
        (state, silent), record = _finder_reading(d)
        assert silent == [3, 4, 5], seed
        assert state is not None and ("deflection_cubed", "front") in {c.key for c in state.stable}, seed
        assert record["state_reading"]["input_silent_drives"] == ["drive3", "drive4", "drive5"]
        assert record["state_reading"]["input_feature"] == "road_height"
        (state, silent), record = _finder_reading(_road_excited_law(seed, road_silent_on=()))
        assert state is None and silent == [] and "state_reading" not in record, seed
    # a drive that lacks its road is not one the road does not reach: its road is unknown, not flat
    (state, silent), _ = _finder_reading(_road_excited_law(0), roadless=(5,))
    assert silent == [3, 4] and state is not None


def _flat_road():
    """A recorded flat road (what a sine steer's recording carries)."""
    from susp_sim_ros.model.road import RoadProfile
    return RoadProfile(np.array([0.0, 100.0]), np.zeros(2), np.zeros(2))


def _selection(*cols):
    """A selection of ``cols``, each stable, at 50 N with equal shares."""
    n = len(cols)
    return fs.Selection({c.key: 1.0 for c in cols}, list(cols), np.full(n, 50.0), np.full(n, 1.0 / n), 24)


def _written(cand, k: int, value: float, coefficient: str) -> tuple[np.ndarray, np.ndarray]:
    """The learned candidate ``cand`` applied to the ``full`` car with a learned term, its parameter ``k`` at
    ``value`` and every other at neutral: the values it wrote to the term's ``coefficient`` (per corner) and x."""
    full = load_variant("full")
    model = Model("passat_b8_like", dataclasses.replace(full, terms=full.terms + (_learned(),)))
    P = np.stack([model.params((1, 1, 1, 1))])
    x = np.array([p.neutral for p in cand.params])
    x[k] = value
    cand.apply(P, P.copy(), x, model)
    return P[0, model.term_param_slice(fs.TERM, coefficient)], x


def test_a_learned_contact_spring_brings_its_smooth_progressive_part_into_the_fit():
    """A stable spring met beyond a gap (bump or rebound contact) or of one sense in bump and rebound brings the
    cube of the deflection on its axle into the learned trial (force_shape.spring_law): a coefficient neutral 0
    after the stable ones, stepped by config/force_shape.yaml, written into the term like the others, and named
    in the words with its force at 40 mm (d_ref 10 mm: 64 times its coefficient) once fitted, once per axle with
    its strongest spring. Not where the cube is stable itself, nor beside a friction or an axle without a contact
    or an even spring."""
    cfg = fs.settings()

    contact = _selection(fs.Column("rebound_contact", "rear", 0.02), fs.Column("sign_velocity", "front"))
    assert fs.spring_law(contact) == [fs.Column("deflection_cubed", "rear")]
    assert fs.spring_law(_selection(fs.Column("bump_contact", "rear", 0.0),
                                    fs.Column("deflection_cubed", "rear"))) == []
    assert fs.spring_law(_selection(fs.Column("sign_velocity", "rear"), fs.Column("deflection", "front"))) == []
    both = _selection(fs.Column("bump_contact", "front", 0.0), fs.Column("rebound_contact", "rear", 0.02))
    assert fs.spring_law(both) == [fs.Column("deflection_cubed", "front"), fs.Column("deflection_cubed", "rear")]
    # the even spring is a smooth law's first term beyond the static rate, the cube its next (a gas column)
    even = _selection(fs.Column("deflection_squared", "front"), fs.Column("sign_velocity", "rear"))
    assert fs.spring_law(even) == [fs.Column("deflection_cubed", "front")]
    squared_and_cubed = _selection(fs.Column("deflection_squared", "rear"), fs.Column("deflection_cubed", "rear"))
    assert fs.spring_law(squared_and_cubed) == []

    cand = fs.learned_candidate(contact, cfg)
    names = [p.name for p in cand.params]
    k = names.index("deflection_cubed_rear")
    assert names[:2] == ["rebound_contact_rear", "sign_velocity_front"]
    assert k > names.index("velocity_weakening_front")
    assert names[-1] in ("presliding", "stribeck_velocity", "creep_velocity")   # the friction law's shapes last
    cubic = cand.params[k]
    assert cubic.neutral == 0.0 and not cubic.shape and cubic.step == cfg["fit.progressive_step_N"]
    assert cand.axle_of[k] == "rear" and k in cand.gain_indices
    written, x = _written(cand, k, 3.0, "c_deflection_cubed")
    np.testing.assert_array_equal(written, [0, 0, 3, 3])
    assert cand.term_params(x, None)["c_deflection_cubed"] == {"front": 0.0, "rear": 3.0}
    plain = fs.learned_candidate(contact, cfg, progressive=False)   # the finder's first stage: the contact alone
    assert [p.name for p in plain.params] == [n for n in names if n != "deflection_cubed_rear"]

    words = contact.description(np.array([80.0, 30.0]), {"deflection_cubed_rear": 3.0, "contact_gap": 0.026})
    assert "beyond 26 mm of rebound" in words
    assert "progressive part (the cube of the deflection: rear +192 N at 40 mm)" in words
    assert "progressive" not in contact.description(np.array([80.0, 30.0]), {"deflection_cubed_rear": 0.0})
    # the even spring's cube is named too, and a part shared by two springs of one axle once, with the stronger
    even_words = even.description(np.array([40.0, 30.0]), {"deflection_cubed_front": -2.0})
    assert "progressive part (the cube of the deflection: front -128 N at 40 mm)" in even_words
    two = fs.Selection({("bump_contact", "front"): 1.0, ("deflection_squared", "front"): 1.0},
                       [fs.Column("bump_contact", "front", 0.01), fs.Column("deflection_squared", "front")],
                       np.array([60.0, 40.0]), np.array([0.6, 0.4]), 24)
    two_words = two.description(None, {"deflection_cubed_front": 1.0})
    assert two_words.count("progressive part") == 1
    assert two_words.index("progressive part") < two_words.index(fs.WORDS["deflection_squared"].split(",")[0])


def test_a_contact_may_be_progressive_in_the_square_of_its_depth():
    """``spring_law(sel, CONTACT_SQUARE)``: each stable contact's progressive part in the square of its depth
    beyond its gap (``bump_contact_squared`` beside ``bump_contact``, ``rebound_contact_squared`` beside
    ``rebound_contact``, once per axle and contact), nothing for an axle with only the even spring or none; the
    candidate of that form carries those coefficients (neutral 0, the progressive step) in place of the cube, and
    the words give each one's force at 40 mm of its sense beyond its gap (d_ref 10 mm: a coefficient of 2 N at a
    gap of 20 mm gives 2 x (20 / 10)^2 = 8 N)."""
    cfg = fs.settings()

    both = _selection(fs.Column("bump_contact", "rear", 0.02), fs.Column("rebound_contact", "front", 0.01),
                     fs.Column("deflection_squared", "front"), fs.Column("sign_velocity", "rear"))
    assert fs.spring_law(both, fs.CONTACT_SQUARE) == [fs.Column("bump_contact_squared", "rear"),
                                                        fs.Column("rebound_contact_squared", "front")]
    assert fs.spring_law(both) == [fs.Column("deflection_cubed", "front"), fs.Column("deflection_cubed", "rear")]
    assert fs.spring_law(_selection(fs.Column("deflection_squared", "rear")), fs.CONTACT_SQUARE) == []
    with pytest.raises(ValueError, match="progressive form 'quartic'"):
        fs.spring_law(both, "quartic")
    cand = fs.learned_candidate(both, cfg, progressive=fs.CONTACT_SQUARE)
    names = [p.name for p in cand.params]
    assert "deflection_cubed_rear" not in names and "deflection_cubed_front" not in names
    k = names.index("bump_contact_squared_rear")
    assert cand.params[k].neutral == 0.0 and cand.params[k].step == cfg["fit.progressive_step_N"]
    assert cand.axle_of[k] == "rear" and names.index("rebound_contact_squared_front") > names.index(
        "sign_velocity_rear")
    np.testing.assert_array_equal(_written(cand, k, 2.0, "c_bump_contact_squared")[0], [0, 0, 2, 2])
    assert [p.name for p in fs.learned_candidate(both, cfg, progressive=True).params] == [
        p.name for p in fs.learned_candidate(both, cfg).params]
    rear = _selection(fs.Column("bump_contact", "rear", 0.02))
    words = rear.description(np.array([80.0]), {"bump_contact_squared_rear": 2.0, "contact_gap": 0.02})
    assert "progressive in the depth of its contact (its square: rear +8 N at 40 mm of bump)" in words
    assert "cube" not in words
    assert "progressive" not in rear.description(np.array([80.0]), {"contact_gap": 0.02})
    # the sense of a contact whose square carries it: its whole force at 40 mm, not its corner's sign
    carried = rear.description(np.array([-7.0]), {"bump_contact_squared_rear": 67.0, "contact_gap": 0.022})
    assert "(rear stiffer 100 %)" in carried
    assert "(rear softer 100 %)" in rear.description(np.array([-7.0]), {"contact_gap": 0.022})


def test_a_contact_s_square_has_a_start_from_static():
    """``square_from_static``: each contact's corner (coefficient c beyond gap g) replaced by the square from static
    that meets its force at twice the gap, c d_ref / (4 g), its gap at 0 (a rebound contact's own gap where the term
    holds one), the corner's coefficient at 0; a variable-pitch coil k2 max(d, 0)^2 read as a corner beyond 18 mm
    starts near its truth. Nothing for a contact at static or without a fitted value."""
    k2, g, dref = 150000.0, 0.018, 0.01   # the truth's square, the plain fit's corner, the term's d_ref
    corner = k2 * (2 * g) ** 2 / g * dref   # the corner through the square's force at 2 g: its force at d_ref beyond g
    sel = fs.Selection({("bump_contact", "rear"): 1.0, ("rebound_contact", "front"): 1.0},
                       [fs.Column("bump_contact", "rear", g), fs.Column("rebound_contact", "front", 0.01)],
                       np.array([corner, 20.0]), np.array([0.7, 0.3]), 24)
    moved = fs.square_from_static(sel, {"bump_contact_rear": corner, "rebound_contact_front": 20.0, "contact_gap": g,
                                        "rebound_gap": 0.01})
    assert moved["bump_contact_squared_rear"] == pytest.approx(k2 * dref ** 2)   # 15 N at d_ref: the truth
    assert moved["rebound_contact_squared_front"] == pytest.approx(
        20.0 * dref / 0.04)
    assert moved["bump_contact_rear"] == moved["rebound_contact_front"] == moved["contact_gap"] == moved[
        "rebound_gap"] == 0.0
    one_gap = fs.square_from_static(sel, {"bump_contact_rear": corner, "rebound_contact_front": 20.0,
                                          "contact_gap": g})
    assert "rebound_gap" not in one_gap and one_gap["rebound_contact_squared_front"] == pytest.approx(
        20.0 * dref / (4 * g))
    assert fs.square_from_static(sel, {"bump_contact_rear": corner, "contact_gap": 0.0}) == {}


@pytest.mark.parametrize("switch", [False, True])
def test_a_progressive_part_is_kept_where_the_final_structure_predicts_the_drives_held_out_better(monkeypatch,
                                                                                                 switch):
    """``fit.progressive_part_held_out``: the final structure's learned cube is kept only where the drives held
    out one at a time are predicted better with it than by the same structure refitted without it
    (``DiscrepancyFinder._final_progressive_part``), with the kept fit's held-out figure and a record; off, or
    where the final structure has no cube, the final fit stands and nothing is held out. The step that offers
    the cube decides on the criterion alone."""
    from types import SimpleNamespace
    from susp_sim_ros.analysis.discrepancy import finder as fm
    cube = (fs.TERM, fs.Column(fs.PROGRESSIVE, "front").coefficient)

    class _Structure:
        def __init__(self, labels):
            self.names, self._labels = [fs.TERM], labels

        def labels(self):
            return self._labels

        def without(self, name):
            return _Structure([lab for lab in self._labels if lab != cube])

        def with_(self, cand):
            return self

        def embed(self, other, x):
            return x[:1]

    sel = fs.Selection({("deflection_squared", "front"): 1.0}, [fs.Column("deflection_squared", "front")],
                       np.array([40.0]), np.array([1.0]), 24)
    final = SimpleNamespace(structure=_Structure([(fs.TERM, "deflection_squared_front"), cube]), x=np.ones(2))
    plain = SimpleNamespace(structure=_Structure([(fs.TERM, "deflection_squared_front")]), x=np.ones(1))
    held = {id(final): 0.066, id(plain): 0.060}   # the cube extrapolates held out (unequal_axle_charges#1)
    stub = SimpleNamespace(heldout=True, learned_selection_=sel, progressive_part_=None,
                           _heldout=lambda ev, f: {"after_deg_s": held[id(f)]})
    cfg = {**fs.settings(), "fit.progressive_part_held_out": switch}
    monkeypatch.setattr(fm.force_shape, "settings", lambda: cfg)
    monkeypatch.setattr(fm, "fit_structure", lambda *a, **k: plain)
    ev = SimpleNamespace(cases=[0, 1, 2])
    kept, kept_held = fm.DiscrepancyFinder._final_progressive_part(stub, ev, final)
    if not switch:
        assert (kept, kept_held, stub.progressive_part_) == (final, None, None)
        return
    assert kept is plain and kept_held == {"after_deg_s": 0.060}
    assert stub.progressive_part_ == {"dependences": ["deflection_squared"], "heldout_with_deg_s": 0.066,
                                      "heldout_without_deg_s": 0.060, "kept": False}
    held[id(final)] = 0.055   # predicts them better (a rising-rate linkage's cube): kept
    assert fm.DiscrepancyFinder._final_progressive_part(stub, ev, final) == (final, {"after_deg_s": 0.055})
    assert stub.progressive_part_["kept"] is True
    stub._heldout = None   # no cube in the final structure: nothing held out
    assert fm.DiscrepancyFinder._final_progressive_part(stub, ev, plain) == (plain, None)
    ev1 = SimpleNamespace(cases=[0])   # one drive: nothing to hold out
    assert fm.DiscrepancyFinder._final_progressive_part(stub, ev1, final) == (final, None)


def test_a_recorded_road_that_leads_on_one_axle_only_is_no_input_finding():
    """Front and rear wheels roll over the same recorded track, so a road recorded off changes both axles'
    input alike: a missing force the recorded road leads on one axle only is a law of the states there that
    the road excites, not an input (``DiscrepancyFinder._road_on_one_axle``); where it leads on both, where the
    drives it acts on lack their road, or where it is the wheel's rotation, the input finding stands. The
    reason's words say which axle."""
    from types import SimpleNamespace
    from susp_sim_ros.analysis.discrepancy.finder import DiscrepancyFinder
    from susp_sim_ros.analysis.discrepancy.report import road_one_axle_words
    design = _road_excited_law(0)
    keys = [c.key for c in design.columns]
    X = design.X.copy()
    X[:, keys.index(("road_height", "rear"))] = X[:, keys.index(("road_height", "front"))]   # the same track
    design = fs.Design(X, design.y, design.groups, design.columns)

    def stub(roadless=()):
        return SimpleNamespace(shape_design_=design, cases_=[
            SimpleNamespace(name=f"drive{g}", road=None if g in roadless else _flat_road(), U=np.zeros((2, 40)))
            for g in range(6)])

    def led(*cols):
        return fs.Selection({c.key: 0.9 for c in cols}, list(cols), np.full(len(cols), 3.0),
                            np.full(len(cols), 1.0 / len(cols)), 24)

    rear = led(fs.Column("road_height", "rear"))
    one = DiscrepancyFinder._road_on_one_axle(stub(), rear, ["rear"])
    assert one == {"input_feature": "road_height", "axle": "rear", "drives": ["drive0", "drive1", "drive2"]}
    assert DiscrepancyFinder._road_on_one_axle(stub(), led(fs.Column("road_height", "front"),
                                                           fs.Column("road_height", "rear")), ["front", "rear"]) is None
    assert DiscrepancyFinder._road_on_one_axle(stub(roadless=(1,)), rear, ["rear"]) is None   # its road unknown
    rotation = led(fs.Column("rotation_sin1", "rear"), fs.Column("rotation_cos1", "rear"))
    assert rotation.input_kind == "wheel_rotation"
    assert DiscrepancyFinder._road_on_one_axle(stub(), rotation, ["rear"]) is None
    words = road_one_axle_words(SimpleNamespace(road_one_axle_=[one, one]))
    assert words.count("rear axle only") == 1 and "same recorded track" in words
    assert road_one_axle_words(SimpleNamespace()) == ""


def test_a_creeping_friction_builds_with_the_sliding_velocity_and_holds_nothing_at_rest():
    """The kernel's learned friction with a creep (``creep_damping``) and a weakening that takes its level at
    rest to none, against the law: z (60 - 60 exp(-|v| / v_s)) + 30 (v / v_c) exp(1 - |v| / v_c) [N] at the
    rear corners (v_s 5 mm/s, v_c 2 mm/s): nothing at rest, viscous at 30 e / v_c N s/m just above it, the
    sliding level when fast; the front corners, without coefficients, none. A creep coefficient of 0 leaves
    the force bit for bit as without the creep (the settings' switch off: every fit as before)."""
    from susp_sim_ros.model.layout import C_INDEX, N_CTX
    from susp_sim_ros.model.learned_force import learned_force_force
    names = [p.name for p in LEARNED_FORCE.params]
    vals = {p.name: [p.default] * 4 for p in LEARNED_FORCE.params}
    vals["c_sign_velocity"] = [0.0, 0.0, 60.0, 60.0]
    vals["c_velocity_weakening"] = [0.0, 0.0, -60.0, -60.0]
    vals["stribeck_velocity"] = [0.005] * 4
    vals["creep_velocity"] = [0.002] * 4

    def force(v, creep):
        vals["c_creep_damping"] = [0.0, 0.0, creep, creep]
        p = np.array([x for n in names for x in vals[n]])
        s = np.zeros(4 * 4)
        s[0:4] = np.sign(v)   # the unit Dahl element slid fully in the sense of motion
        c = np.zeros((4, N_CTX))
        c[:, C_INDEX["DD"]] = v
        return np.array([learned_force_force(p, 0, s, 0, i, c) for i in range(4)])

    np.testing.assert_array_equal(force(0.0, 30.0), 0.0)
    slow = 1e-5
    np.testing.assert_allclose(force(slow, 30.0)[2:], 60.0 * (1.0 - np.exp(-slow / 0.005))
                               + 30.0 * slow / 0.002 * np.exp(1.0 - slow / 0.002), rtol=1e-12)
    assert force(slow, 30.0)[2] == pytest.approx(slow * (60.0 / 0.005 + 30.0 * np.e / 0.002), rel=0.01)
    np.testing.assert_allclose(force(0.002, 30.0)[2:], 60.0 * (1.0 - np.exp(-0.4)) + 30.0, rtol=1e-12)
    np.testing.assert_allclose(force(-0.002, 30.0)[2:], -(60.0 * (1.0 - np.exp(-0.4)) + 30.0), rtol=1e-12)
    assert force(0.5, 30.0)[2] == pytest.approx(60.0, rel=1e-9)
    np.testing.assert_array_equal(force(0.01, 30.0)[:2], 0.0)
    # without the creep, the weakened friction alone: bit for bit z (60 - 60 exp(-|v| / v_s))
    for v in (1e-4, 0.003, -0.2):
        assert force(v, 0.0)[2] == np.sign(v) * 60.0 + np.sign(v) * -60.0 * np.exp(-abs(v) / 0.005)


def test_a_learned_friction_brings_its_creep_only_where_the_settings_say():
    """``fit.creep_in_friction_law``: off, a learned friction's law is as before the creep; on (the shipped
    setting since the whole family was measured with it, benchmarks/RESULTS.md 2026-11-30), every friction axle
    gets a creep coefficient (neutral 0, after the other law coefficients) and the creep velocity as a shape (the
    term's declared 1 mm/s to start, bounded by the settings), written into the term like the others; the
    regression is never offered the creep (a law's shape)."""
    on_cfg = fs.settings()
    assert on_cfg["fit.creep_in_friction_law"] is True
    sel = fs.select(_design(truth={("sign_velocity", "rear"): 3.0, ("lateral_force", "rear"): 2.0}))
    off_cfg = dict(on_cfg) | {"fit.creep_in_friction_law": False}
    off = [p.name for p in fs.learned_candidate(sel, off_cfg).params]
    assert not {"creep_damping_rear", "creep_velocity"} & set(off)
    cand = fs.learned_candidate(sel, on_cfg)
    names = [p.name for p in cand.params]
    assert names[len(sel.stable):] == ["velocity_weakening_rear", "compression_rear", "creep_damping_rear",
                                       "presliding", "stribeck_velocity", "creep_velocity"]
    creep, vc = cand.params[len(sel.stable) + 2], cand.params[-1]
    assert creep.neutral == 0.0 and not creep.shape and creep.step == on_cfg["fit.creep_step_N"]
    assert vc.shape and vc.neutral == shape_defaults()["creep_velocity"] == 0.001
    assert (vc.lower, vc.upper) == tuple(on_cfg["fit.creep_velocity_range_m_s"])
    assert cand.axle_of[len(sel.stable) + 2] == "rear"
    full = load_variant("full")
    model = Model("passat_b8_like", dataclasses.replace(full, terms=full.terms + (_learned(),)))
    P = np.stack([model.params((1, 1, 1, 1))])
    x = np.array([60.0] * len(sel.stable) + [45.0, 12.0, 25.0, 2e-5, 0.015, 0.003])
    cand.apply(P, P.copy(), x, model)
    np.testing.assert_array_equal(P[0, model.term_param_slice(fs.TERM, "c_creep_damping")], [0, 0, 25, 25])
    np.testing.assert_array_equal(P[0, model.term_param_slice(fs.TERM, "creep_velocity")], [0.003] * 4)
    written = cand.term_params(x, None)
    assert written["c_creep_damping"] == {"front": 0.0, "rear": 25.0}
    assert written["creep_velocity"] == {"front": 0.003, "rear": 0.003}
    assert "creep_damping" not in {f for f, _ in fs.library(on_cfg)}
    no_friction = fs.learned_candidate(fs.select(_design(truth={("roll_free_play", "front"): 5.0})), on_cfg)
    assert not {"creep_velocity", "creep_damping_front"} & {p.name for p in no_friction.params}


def test_a_learned_friction_is_described_with_its_fitted_law():
    """The description of a learned friction gives its fitted law in numbers: per axle its sliding level and its
    level at rest (sliding plus weakening), the Stribeck velocity, the creep's force at its creep velocity and the
    presliding travel, so that a contact that creeps (a level at rest near none) reads apart from one that sticks;
    a level at rest below the sliding one on every axle is said to be the law of a damping that saturates too
    (the rig test that tells them apart named); without a fitted law (the regression's description) none of it."""
    sel = fs.select(_design(truth={("sign_velocity", "front"): 3.0, ("sign_velocity", "rear"): 3.0}))
    assert {c.feature for c in sel.stable} == {"sign_velocity"}
    fitted = {"sign_velocity_front": 53.2, "sign_velocity_rear": 40.1, "velocity_weakening_front": -51.3,
              "velocity_weakening_rear": -40.7, "creep_damping_front": 17.8, "creep_damping_rear": 13.1,
              "presliding": 2.57e-5, "stribeck_velocity": 0.01255, "creep_velocity": 0.00684}
    words = sel.description(np.array([fitted[c.coefficient] for c in sel.stable]), fitted)
    assert ("the friction's law as fitted: front 53 N sliding and 2 N at rest, rear 40 N sliding and -1 N at rest "
            "(Stribeck velocity 12.6 mm/s), creeping (viscous) below 6.8 mm/s (front 18 N, rear 13 N at it), "
            "presliding travel 26 um") in words
    sticking = {k: v for k, v in fitted.items() if "creep" not in k} | {"velocity_weakening_front": 20.0}
    words = sel.description(np.array([fitted[c.coefficient] for c in sel.stable]), sticking)
    assert "front 53 N sliding and 73 N at rest" in words and "creeping" not in words
    assert "damping that saturates" not in words   # a level at rest above the sliding one: a contact that sticks
    at_none = sticking | {"velocity_weakening_front": -53.5}   # a level at rest of -0.3 N: "0 N", never "-0 N"
    words = sel.description(np.array([fitted[c.coefficient] for c in sel.stable]), at_none)
    assert "front 53 N sliding and 0 N at rest" in words and "-0 N" not in words
    rising = {k: v for k, v in fitted.items() if "creep" not in k}
    words = sel.description(np.array([fitted[c.coefficient] for c in sel.stable]), rising)
    assert "grows with the sliding velocity over about 13 mm/s as a damping that saturates there does" in words
    assert "a damper rig at 1-50 mm/s tells them apart" in words
    assert "the friction's law" not in sel.description()
    spring = fs.select(_design(truth={("deflection", "rear"): 3.0}))
    assert "the friction's law" not in spring.description(None, fitted)


@pytest.mark.parametrize("feature", ["bump_damping", "rebound_damping", "zone_damping"])
def test_a_learned_damping_beyond_a_gap_in_the_kernel_is_its_feature_on_the_run(feature):
    """The kernel's ``bump_damping`` / ``rebound_damping`` / ``zone_damping`` force along a bump crossing is its
    coefficient times the feature on the run's own deflections and deflection velocities at the contact gap (none
    within it), it scales with the damper's oil (none at the oil-empty rear), and it changes the motion."""
    vp = dataclasses.replace(load_vehicle("passat_b8_like"), axle_friction=(0.0, 0.0),
                             damper_friction_intact=(1e-12, 1e-12), damper_friction_empty=(1e-12, 1e-12))
    coef, gap = 400.0, 0.01
    man = build_maneuver("bump_crossing", vp.wheelbase)
    outs = [f"{o}_{w}" for o in ("DEFL", "DEFL_VEL", "F_FRICTION") for w in ("FL", "FR", "RL", "RR")] + ["PITCH_RATE"]
    model = Model(vp, dataclasses.replace(load_variant("dahl_only"), terms=load_variant("dahl_only").terms + (
        _learned(**{f"c_{feature}": coef}, contact_gap=gap),)))
    oil = (1.0, 1.0, 0.0, 0.0)
    res = simulate(model, man.to_inputs(DT), dt=DT, road=man.road, oil=oil, outputs=outs).values
    D, V, F = res[:, :4], res[:, 4:8], res[:, 8:12]
    want = coef * feature_series(feature, D, V, V, V, DT, shape={"contact_gap": gap}, oil=np.array(oil))
    assert np.abs(F[:, :2]).max() > 50.0 and np.abs(F[:, 2:]).max() < 1e-9   # (the friction output's 1e-12 N)
    assert np.all(np.abs(F[1:][np.abs(D[:-1]) <= gap]) < 1e-9)
    np.testing.assert_allclose(F[1:], want[:-1], rtol=0, atol=1e-9 * np.abs(F).max())
    plain = _run([], variant="dahl_only", vehicle=vp)
    assert np.max(np.abs(res[:, 12] - plain["PITCH_RATE"])) > 1e-3 * np.max(np.abs(plain["PITCH_RATE"]))


def test_an_even_spring_is_offered_to_the_regression_only_where_the_settings_say():
    """``library.deflection_squared``: off, the regression's library has no square of the deflection; on, it
    has one column per axle, in the spring law family, described as one sense in bump and rebound."""
    cfg = fs.settings()
    assert cfg["library.deflection_squared"] is True   # on since the whole family ran with it
    off = fs.library(dict(cfg) | {"library.deflection_squared": False})
    assert "deflection_squared" not in {f for f, _ in off}
    on = fs.library(cfg)
    assert [e for e in on if e not in off] == [("deflection_squared", None)] and len(on) == len(off) + 1
    assert fs.law_key(("deflection_squared", "front")) == ("spring", "front")
    sel = fs.Selection({("deflection_squared", "rear"): 1.0}, [fs.Column("deflection_squared", "rear")],
                       np.array([40.0]), np.array([1.0]), 24)
    words = sel.description()
    assert "one sense in bump and rebound" in words and "rear stiffer in bump, softer in rebound" in words


def test_a_zone_damping_is_offered_to_the_regression_only_where_the_settings_say():
    """``library.zone_damping`` (on as shipped since 2026-12-06): off, the regression's library has no damping beyond
    a gap on either side of static; on, one entry at every offered contact gap, in the damping law family, described
    with its gap on both sides; it is the sum of the bump and rebound dampings at one coefficient."""
    cfg = fs.settings()
    assert cfg["library.zone_damping"] is True   # on since its blind forms and the whole family ran with it
    off = fs.library(dict(cfg) | {"library.zone_damping": False})
    assert "zone_damping" not in {f for f, _ in off}
    on = fs.library(dict(cfg) | {"library.zone_damping": True})
    gaps = [float(v) for v in cfg["library.contact_gaps_m"]]
    assert [e for e in on if e not in off] == [("zone_damping", g) for g in gaps]
    assert fs.law_key(("zone_damping", "rear")) == ("damping", "rear")
    sel = fs.Selection({("zone_damping", "rear"): 1.0}, [fs.Column("zone_damping", "rear", 0.01)],
                       np.array([80.0]), np.array([1.0]), 24)
    words = sel.description(shapes={"contact_gap": 0.012})
    assert "a damping met beyond 12 mm of bump and 12 mm of rebound" in words and "rear more damping" in words
    words = sel.description(shapes={"contact_gap": 0.016, "rebound_gap": 0.006})   # a zone off centre
    assert "a damping met beyond 16 mm of bump and 6 mm of rebound" in words
    D = np.linspace(-0.05, 0.05, 41)[:, None] * np.ones((1, 4))
    V = np.full_like(D, 0.1)
    z = np.zeros_like(D)
    both = [feature_series(f, D, V, z, z, DT, shape={"contact_gap": 0.012}) for f in
            ("bump_damping", "rebound_damping", "zone_damping")]
    np.testing.assert_allclose(both[2], both[0] + both[1])


def test_a_force_beyond_a_gap_is_worded_with_the_drives_reach_and_a_zone_with_one_end_beyond_it_as_a_stop():
    """A learned force met beyond a gap says how deep beyond it the drives reach (the range the fitted force is seen
    over: a damping's with oil in the damper, a spring's in every drive). A zone damping whose rebound end lies
    beyond the deepest rebound the drives reach with oil on its axle is, as far as they tell, a stop in bump (its
    rebound side is zero in every drive) and is worded so, with the reach and the drive that would tell; the bump
    end beyond the deepest bump, a stop in rebound. The reach is the deepest of the axle's two corners over every
    drive, with oil over the drives whose damper there holds oil (:func:`drives_reach`)."""
    sel = fs.Selection({("zone_damping", "rear"): 1.0}, [fs.Column("zone_damping", "rear", 0.02)],
                       np.array([150.0]), np.array([1.0]), 24)
    shapes = {"contact_gap": 0.020, "rebound_gap": 0.053}
    zone = "a damping met beyond 20 mm of bump and 53 mm of rebound"
    assert zone in sel.description(shapes=shapes)   # no reach given: the zone as fitted

    def reach(rear_oil, rear=(0.05, 0.06)):   # the front's and the rear's every drive's reach apart from the oil's
        return fs.Reach({"front": (0.03, 0.07), "rear": rear}, {"front": (0.03, 0.060), "rear": rear_oil})

    words = sel.description(shapes=shapes, reach=reach((0.045, 0.038)))
    assert zone not in words and "a damping met beyond 20 mm of bump" in words
    assert "rebound end, 53.0 mm, lies beyond the deepest rebound the drives reach with oil in the damper (38.0 mm)" \
        in words
    assert "a stop in bump" in words and "rear more damping 100 %" in words
    words = sel.description(shapes={"contact_gap": 0.050, "rebound_gap": 0.010}, reach=reach((0.045, 0.038)))
    assert "a damping met beyond 10 mm of rebound" in words and "a stop in rebound" in words
    assert "deepest bump the drives reach with oil in the damper (45.0 mm)" in words
    words = sel.description(shapes=shapes, reach=reach((0.045, 0.060)))   # both ends reached
    assert zone in words
    assert "seen in these drives to 45 mm of bump and 60 mm of rebound with oil in the damper" in words
    # a spring beyond a gap: every drive's reach (a spring acts without oil); beyond the reach, met in none
    bumper = fs.Selection({("bump_contact", "rear"): 1.0}, [fs.Column("bump_contact", "rear", 0.03)],
                          np.array([150.0]), np.array([1.0]), 24)
    words = bumper.description(shapes={"contact_gap": 0.031}, reach=reach((0.02, 0.02)))
    assert "a spring met beyond 31 mm of bump" in words and "seen in these drives to 50 mm of bump (" in words
    words = bumper.description(shapes={"contact_gap": 0.031}, reach=reach((0.02, 0.02), rear=(0.029, 0.02)))
    assert "beyond the deepest bump these drives reach (29.0 mm): met in none of them" in words

    class Evaluator:   # the deflections of two drives, FL FR RL RR: the rear's deepest rebound on RR in drive 2,
        # whose rear dampers hold no oil
        def simulate_outputs(self, st, x, r, names):
            assert names == ["DEFL_FL", "DEFL_FR", "DEFL_RL", "DEFL_RR"]
            return np.array([[[0.010, -0.020, 0.030, -0.005], [0.004, 0.002, 0.001, 0.0]],
                             [[0.001, 0.003, -0.002, -0.041], [0.0, 0.0, 0.002, 0.001]]][r])

        def rows(self, st, x):
            P = np.zeros((2, P_INDEX["OIL"] + 4))
            P[:, P_INDEX["OIL"]:P_INDEX["OIL"] + 4] = [[1.0, 1.0, 0.6, 0.6], [1.0, 1.0, 0.0, 0.0]]
            return P

    class Finder:
        evaluator_, cases_ = Evaluator(), [None, None]

    class Fit:
        structure, x = None, np.zeros(0)

    got = fs.drives_reach(Finder(), Fit())
    assert got.every == {"front": (0.010, 0.020), "rear": (0.030, 0.041)}
    # with oil: the rear's rebound of the oil-empty drive 2 does not count, nor its bump (2 mm, below drive 1's)
    assert got.with_oil == {"front": (0.010, 0.020), "rear": (0.030, 0.005)}
    assert got.of("zone_damping", "rear") == (0.030, 0.005) and got.of("bump_contact", "rear") == (0.030, 0.041)


def test_a_damping_beyond_a_gap_is_offered_to_the_regression_only_where_the_settings_say():
    """``library.position_damping``: off, the regression's library has no damping beyond a contact gap; on (as
    shipped since the whole family ran with it), each of bump and rebound at every offered contact gap, a
    damping in the damping law family, described with its gap and sense."""
    cfg = fs.settings()
    # on as shipped since the whole family ran with it (benchmarks/RESULTS.md, 2026-11-30, 19:04-21:07)
    assert cfg["library.position_damping"] is True
    off = fs.library(dict(cfg) | {"library.position_damping": False})
    assert not {"bump_damping", "rebound_damping"} & {f for f, _ in off}
    on = fs.library(cfg)
    gaps = [float(v) for v in cfg["library.contact_gaps_m"]]
    for name in ("bump_damping", "rebound_damping"):
        assert [s for f, s in on if f == name] == gaps
        assert fs.law_key((name, "rear")) == ("damping", "rear")
    assert len(on) == len(off) + 2 * len(gaps)
    sel = fs.Selection({("rebound_damping", "front"): 1.0}, [fs.Column("rebound_damping", "front", 0.01)],
                       np.array([80.0]), np.array([1.0]), 24)
    words = sel.description(shapes={"contact_gap": 0.012})
    assert "a damping met beyond 12 mm of rebound" in words and "front more damping" in words
    assert "front axle only" in words
    assert [p.name for p in fs.learned_candidate(sel, cfg).params] == ["rebound_damping_front", "rebound_gap"]
    one_gap = dict(cfg) | {"fit.rebound_gap": False}   # one gap for both senses: the contact gap
    assert [p.name for p in fs.learned_candidate(sel, one_gap).params] == ["rebound_damping_front", "contact_gap"]


def test_a_learned_creep_in_the_kernel_is_its_feature_on_the_run():
    """The kernel's ``creep_damping`` force along a bump crossing is its coefficient times the feature on the
    run's own deflection velocities (no friction element in it), and it changes the motion."""
    vp = dataclasses.replace(load_vehicle("passat_b8_like"), axle_friction=(0.0, 0.0),
                             damper_friction_intact=(1e-12, 1e-12), damper_friction_empty=(1e-12, 1e-12))
    coef, vc = 40.0, 0.005
    man = build_maneuver("bump_crossing", vp.wheelbase)
    outs = [f"{o}_{w}" for o in ("DEFL_VEL", "F_FRICTION") for w in ("FL", "FR", "RL", "RR")] + ["PITCH_RATE"]
    model = Model(vp, dataclasses.replace(load_variant("dahl_only"), terms=load_variant("dahl_only").terms + (
        _learned(c_creep_damping=(0.0, 0.0, coef, coef), creep_velocity=vc),)))
    res = simulate(model, man.to_inputs(DT), dt=DT, road=man.road, outputs=outs).values
    V, F = res[:, :4], res[:, 4:8]
    want = coef * V / vc * np.exp(1.0 - np.abs(V) / vc)
    want[:, :2] = 0.0
    assert np.abs(F[:, 2:]).max() > 0.9 * coef and np.any(np.abs(V[:, 2:]) > 10 * vc)
    np.testing.assert_allclose(F[1:], want[:-1], rtol=0, atol=1e-9 * coef)
    plain = _run([], variant="dahl_only", vehicle=vp)
    assert np.max(np.abs(res[:, 8] - plain["PITCH_RATE"])) > 1e-3 * np.max(np.abs(plain["PITCH_RATE"]))


def test_a_learned_term_holds_one_value_of_each_shape_when_it_is_read_again():
    """When a learned term is in the structure, the regression that reads the residual it leaves offers the
    features of a shape the term holds (a contact gap, a knee) at its fitted value only, the term having one of
    each; the others as always. A column's coefficient adds to the term's own, so a feature the term has is
    read as a change of its fitted coefficient."""
    from types import SimpleNamespace
    cfg = dict(fs.settings()) | {"library.position_damping": True}
    held = fs.library(cfg | {"fit.rebound_gap": False}, {"contact_gap": 0.0149})   # one gap for both senses
    for f in ("bump_contact", "rebound_contact", "bump_damping", "rebound_damping"):
        assert [s for g, s in held if g == f] == [0.0149]
    assert [s for g, s in held if g == "velocity_beyond_knee"] == \
        [s for g, s in fs.library(cfg) if g == "velocity_beyond_knee"]   # a shape the term lacks: every value
    assert fs.HELD_SHAPES == {"knee_velocity", "free_play", "relaxation_time", "contact_gap", "rebound_gap"}
    apart = fs.library(cfg | {"fit.rebound_gap": True}, {"contact_gap": 0.0149, "rebound_gap": 0.006})
    for f, gap in (("bump_contact", 0.0149), ("bump_damping", 0.0149), ("rebound_contact", 0.006),
                   ("rebound_damping", 0.006)):
        assert [s for g, s in apart if g == f] == [gap]   # the gaps held apart: each sense at its own
    where = {"c_bump_damping": slice(4, 8), "contact_gap": slice(0, 1), "rebound_gap": slice(1, 2)}
    model = SimpleNamespace(term_param_slice=lambda term, name: where.get(name, slice(2, 3)))
    for rebound_gap_apart, rebound_gap in ((False, 0.0149), (True, 0.0)):
        col = fs._column_candidate(fs.Column("bump_damping", "rear", 0.0149), 20.0, 5000.0,
                                   cfg | {"fit.rebound_gap": rebound_gap_apart})
        P = np.zeros((2, 8))
        P[:, 6:8] = 60.0   # the term's fitted rear coefficient
        col.apply(P, P.copy(), np.array([20.0]), model)
        np.testing.assert_array_equal(P[:, 6:8], 80.0)
        np.testing.assert_array_equal(P[:, 4:6], 0.0)
        assert P[0, 0] == 0.0149 and P[0, 1] == rebound_gap   # one gap for both senses unless held apart


def test_a_law_found_on_one_axle_is_offered_on_the_other_at_its_shape():
    """:func:`force_shape.other_axle`: a selection that holds a law-family dependence on one axle (a valve
    above a knee at the rear) gains the same feature on the other axle at the same shape, both fitted by
    least squares to the target (here both axles carry it); a dependence of no law family is not mirrored,
    one on both axles already, or one that would carry less than ``selection.min_share``, gives nothing to
    offer; off as shipped."""
    d = _design(seed=4, noise=0.5)
    keys = [(c.key, c.shape) for c in d.columns]
    rear = d.columns[keys.index((("velocity_beyond_knee", "rear"), 0.2))]
    front = d.columns[keys.index((("velocity_beyond_knee", "front"), 0.2))]
    y = 2.0 * d.X[:, d.columns.index(rear)] + 1.2 * d.X[:, d.columns.index(front)] + \
        np.random.default_rng(6).normal(0.0, 0.5, len(d.y))
    design = fs.Design(d.X, y, d.groups, d.columns)
    sel = fs.Selection({rear.key: 0.7, front.key: 0.5}, [rear], np.array([2.3]), np.array([1.0]), 24)
    alt = fs.other_axle(sel, design)
    assert alt is not None and alt.stable == [rear, front]
    np.testing.assert_allclose(alt.coef, [2.0, 1.2], atol=0.05)
    assert alt.axles == ["front", "rear"] and alt.frequency == sel.frequency
    assert fs.other_axle(alt, design) is None   # on both axles already
    faint = fs.Design(d.X, y - 1.15 * d.X[:, d.columns.index(front)], d.groups, d.columns)   # 0.05 at the front
    assert fs.other_axle(sel, faint) is None   # below selection.min_share: no front term
    lawless = next(c for c in d.columns if c.feature not in fs.LAW_OF and c.axle == "rear")
    assert fs.other_axle(fs.Selection({lawless.key: 0.9}, [lawless], np.array([1.0]), np.array([1.0]), 24),
                         design) is None
    assert fs.settings()["fit.other_axle_competes"] is True   # on since the whole family ran with it (2026-12-06)


def test_a_learned_term_is_extended_by_the_dependences_the_residual_it_leaves_adds():
    """:func:`force_shape.extended`: the term's dependences as fitted, and the stable ones the regression of
    the residual it leaves adds (a position-sensitive damper read first at the front in bump, then in rebound):
    the old coefficients as fitted plus what the residual asks of them, the added ones fitted with them, shares
    of the sum; nothing added, no extension."""
    d = _design(seed=3, noise=0.5)
    keys = [c.key for c in d.columns]
    first = d.columns[keys.index(("sign_velocity", "rear"))]
    added = d.columns[keys.index(("deflection_velocity", "front"))]
    y = 0.4 * d.X[:, keys.index(first.key)] + 2.0 * d.X[:, keys.index(added.key)] + \
        np.random.default_rng(5).normal(0.0, 0.5, len(d.y))
    one = [c for c in d.columns if c.key not in {first.key, added.key} or c in (first, added)]
    design = fs.Design(d.X[:, [d.columns.index(c) for c in one]], y, d.groups, one)
    old = fs.Selection({first.key: 0.9}, [first], np.array([1.5]), np.array([1.0]), 24)
    new = fs.Selection({first.key: 0.7, added.key: 0.8}, [first, added], np.array([0.4, 2.0]),
                       np.array([0.1, 0.9]), 24)
    ext = fs.extended(old, np.array([1.6]), new, design)
    assert ext is not None
    assert [c.key for c in ext.stable] == [first.key, added.key]
    np.testing.assert_allclose(ext.coef, [1.6 + 0.4, 2.0], atol=0.05)
    contrib = design.X[:, [one.index(first), one.index(added)]] * ext.coef
    share = contrib.var(axis=0) / contrib.sum(axis=1).var()
    np.testing.assert_allclose(ext.share, share / share.sum())
    assert ext.frequency[first.key] == 0.9 and ext.frequency[added.key] == 0.8
    assert set(ext.dependences) == {"deflection_velocity", "sign_velocity"} and ext.axles == ["front", "rear"]
    assert fs.extended(old, np.array([1.6]), fs.Selection({first.key: 0.7}, [first], np.array([0.4]),
                                                          np.array([1.0]), 24), design) is None
    cfg = fs.settings()
    # on as shipped since the family's cases with a learned term ran with it (benchmarks/RESULTS.md, 2026-11-30)
    assert cfg["fit.extend_learned"] is True


def test_a_named_learned_term_is_offered_on_the_other_axle_for_the_fit_to_size():
    """:func:`force_shape.other_axle_extended`: a named learned term whose later regression adds nothing stable is
    offered with each law-family dependence also on the other axle, at the shape the design holds (one column per
    key: its shapes held), the added coefficient at 0 and the old ones as fitted: the fit sizes it, not the
    regression's share at the offer (a small rear gas charge the calibration took up, gas/unequal_axle_charges #2).
    A dependence of no law family is not mirrored; one on both axles already gives nothing to offer."""
    d = _design(seed=4, noise=0.5)
    held = [c for c in d.columns if c.feature != "velocity_beyond_knee" or c.shape == 0.2]   # the knee held
    design = fs.Design(d.X[:, [d.columns.index(c) for c in held]], d.y, d.groups, held)
    keys = [c.key for c in held]
    rear = held[keys.index(("velocity_beyond_knee", "rear"))]
    front = held[keys.index(("velocity_beyond_knee", "front"))]
    lawless = next(c for c in held if c.feature not in fs.LAW_OF and c.axle == "rear")
    old = fs.Selection({rear.key: 0.8, lawless.key: 0.7}, [rear, lawless], np.array([2.0, 0.5]),
                       np.array([0.8, 0.2]), 24)
    alt = fs.other_axle_extended(old, np.array([2.2, 0.4]), design)
    assert alt is not None and alt.stable == [rear, lawless, front]   # the front at the rear's knee, 0.2 m/s
    np.testing.assert_array_equal(alt.coef, [2.2, 0.4, 0.0])
    assert alt.frequency == old.frequency
    assert fs.other_axle_extended(alt, alt.coef, design) is None   # on both axles already
    only_lawless = fs.Selection({lawless.key: 0.9}, [lawless], np.array([1.0]), np.array([1.0]), 24)
    assert fs.other_axle_extended(only_lawless, np.array([1.0]), design) is None
    # on as shipped since the family's cases with a learned term ran with it (benchmarks/RESULTS.md, 2026-12-07)
    assert fs.settings()["fit.other_axle_extends"] is True


def test_an_axle_the_fit_added_keeps_its_place_only_with_its_share_of_the_fitted_force():
    """:func:`force_shape.fitted_shares`: the extension's coefficients as fitted and each column's share of the
    fitted force's variance; an added column (after the first ``n_old``) below ``fit.other_axle_min_share`` of it
    withdraws the offer; 0 as shipped, the trial's tests judging the added axle (a true rear a quarter of the
    front's carries a few per cent of the variance)."""
    d = _design(seed=4, noise=0.5)
    keys = [c.key for c in d.columns]
    rear = d.columns[keys.index(("deflection", "rear"))]
    front = d.columns[keys.index(("deflection", "front"))]
    sel = fs.Selection({rear.key: 0.8}, [rear, front], np.array([2.0, 0.0]), np.array([1.0, 0.0]), 24)
    cfg = {**fs.settings(), "fit.other_axle_min_share": 0.05}
    sized = fs.fitted_shares(sel, np.array([2.0, 1.0]), d, 1, cfg)
    assert sized is not None
    np.testing.assert_array_equal(sized.coef, [2.0, 1.0])
    contrib = d.X[:, [keys.index(rear.key), keys.index(front.key)]] * sized.coef
    share = contrib.var(axis=0) / contrib.sum(axis=1).var()
    np.testing.assert_allclose(sized.share, share / share.sum())
    assert 0.05 < sized.share[1] < 0.5
    assert fs.fitted_shares(sel, np.array([2.0, 0.2]), d, 1, cfg) is None   # about 1 % of the force: withdrawn
    assert fs.fitted_shares(sel, np.array([0.2, 2.0]), d, 2, cfg) is not None   # nothing added: no share asked
    assert fs.settings()["fit.other_axle_min_share"] == 0.0
    faint = fs.fitted_shares(sel, np.array([2.0, 0.2]), d, 1)   # as shipped: stands, its share said
    assert faint is not None and 0.0 < faint.share[1] < 0.05


def test_the_forms_of_a_stable_law_family_are_offered_to_the_fit_with_their_shapes_and_coefficients():
    """:func:`force_shape.law_members`: a stable dependence of a law family is offered replaced by each other
    member of the family on its axle that a resample chose (with ``fit.law_members_whole_family`` off; on, by
    every member on the axle), never by one the selection holds already or one of another family; a member
    with a shape takes the value that fits best,
    or the one another stable column holds (one value per shape serves the term); the coefficients are the
    least-squares fit of all the columns; standing for its family, the member does."""
    truth = {("sign_velocity", "front"): 1.0}
    d = _design(seed=4, noise=0.3)
    keys = [c.key for c in d.columns]
    valve = next(c for c in d.columns if c.key == ("velocity_beyond_knee", "rear") and c.shape == 0.2)
    y = d.y + 2.0 * d.X[:, d.columns.index(valve)] + sum(v * d.X[:, keys.index(k)] for k, v in truth.items())
    design = fs.Design(d.X, y, d.groups, d.columns)
    friction, viscous = d.columns[keys.index(("sign_velocity", "front"))], d.columns[keys.index(("deflection_velocity",
                                                                                                 "rear"))]
    freq = {friction.key: 0.9, viscous.key: 0.4, valve.key: 0.3, ("roll_deflection", "rear"): 0.3}
    sel = fs.Selection(freq, [friction, viscous], np.array([1.0, 1.0]), np.array([0.5, 0.5]), 24,
                       {("friction", "front"): 0.9, ("damping", "rear"): 0.7}, (viscous.key,))
    assert fs.law_keys(sel) == [friction.key, viscous.key]
    chosen = {**fs.settings(), "fit.law_members_whole_family": False}   # the members some resample chose
    assert fs.law_members(sel, friction.key, design, chosen) == []   # no other friction form chosen at the front
    (alt,) = fs.law_members(sel, viscous.key, design, chosen)   # velocity_squared: no resample chose it
    assert [c.key for c in alt.stable] == [friction.key, valve.key]
    assert alt.stable[1].shape == 0.2 and alt.by_law == (valve.key,)
    A = design.X[:, [d.columns.index(c) for c in alt.stable]]
    np.testing.assert_allclose(alt.coef, np.linalg.lstsq(A, y, rcond=None)[0])
    np.testing.assert_allclose(alt.coef, [1.0, 2.0], atol=0.05)
    assert alt.frequency == freq and alt.share.sum() == pytest.approx(1.0)
    # a knee another stable column holds is the one the member takes
    front_valve = next(c for c in d.columns if c.key == ("velocity_beyond_knee", "front") and c.shape == 0.4)
    held = fs.Selection({**freq, front_valve.key: 0.8}, [friction, front_valve, viscous], np.ones(3),
                        np.full(3, 1 / 3), 24)
    (alt2,) = fs.law_members(held, viscous.key, design, chosen)
    assert alt2.stable[2].key == valve.key and alt2.stable[2].shape == 0.4 and alt2.by_law == ()
    # a member the selection holds already is not offered
    assert fs.law_members(fs.Selection(freq, [friction, valve, viscous], np.ones(3), np.full(3, 1 / 3), 24),
                          viscous.key, design, chosen) == []
    # a member with which listed terms stand for every dependence is not offered (they compete already):
    # friction growing with the peak deflection alone is the listed amplitude friction; beside a dependence
    # no listed term stands for, it is the learned term's
    amp = next(c for c in d.columns if c.key == ("peak_deflection", "front"))
    roll = next(c for c in d.columns if c.key == ("roll_deflection", "rear"))
    alone = fs.Selection({**freq, amp.key: 0.4}, [friction], np.ones(1), np.ones(1), 24)
    assert fs.LISTED_FOR[amp.feature] == "friction_amplitude"
    assert fs.law_members(alone, friction.key, design, chosen) == []
    (beside,) = fs.law_members(fs.Selection({**freq, amp.key: 0.4}, [friction, roll], np.ones(2), np.full(2, 0.5),
                                            24), friction.key, design, chosen)
    assert [c.key for c in beside.stable] == [amp.key, roll.key] and beside.listed_rivals() == []
    # on as shipped since every case of the truth-generator family ran with it (benchmarks/RESULTS.md, 2026-12-01)
    assert fs.settings()["fit.law_members_compete"] is True
    # with fit.law_members_whole_family every member of the family on the axle is offered, those no resample chose
    # too (velocity_squared, the damping beyond a gap in bump or rebound at the rear); never one of another family
    whole = {**fs.settings(), "fit.law_members_whole_family": True}
    offered = {alt.stable[1].key for alt in fs.law_members(sel, viscous.key, design, whole)}
    damping = {c.key for c in d.columns if c.axle == "rear" and fs.LAW_OF.get(c.feature) == "damping"}
    assert offered == damping - {viscous.key} and valve.key in offered and ("velocity_squared", "rear") in offered
    # the front's other friction form drawn here (the peak deflection) beside the viscous damping: listed terms
    # stand for both, so it is not offered even now
    assert fs.law_members(sel, friction.key, design, whole) == []
    # on as shipped since the family's cases with a stable physics dependence ran with it (RESULTS.md, 2026-12-01)
    assert fs.settings()["fit.law_members_whole_family"] is True


def test_a_rewritten_learned_term_starts_from_its_fitted_values_by_label():
    """``Structure.embed``: a learned term rewritten with one more column (an extension) keeps its fitted
    coefficient and the other terms' values, the added column at neutral (by label: copied as a whole block,
    the term would no longer line up)."""
    from susp_sim_ros.analysis.discrepancy.engine import Structure
    first, added = fs.Column("sign_velocity", "rear"), fs.Column("deflection_velocity", "front")
    one = fs.learned_candidate(fs.Selection({first.key: 0.9}, [first], np.array([1.5]), np.array([1.0]), 24))
    two = fs.learned_candidate(fs.Selection({first.key: 0.9, added.key: 0.8}, [first, added],
                                            np.array([1.5, 2.0]), np.array([0.5, 0.5]), 24))
    old = Structure(["time_offset"]).with_(one)
    new = Structure(["time_offset"]).with_(two)
    x_old = old.neutral() + np.linspace(0.01, 0.02, len(old.neutral()))
    x_new = new.embed(old, x_old)
    fitted = dict(zip(old.labels(), x_old))
    for label, v, v0 in zip(new.labels(), x_new, new.neutral()):
        assert v == (fitted[label] if label in fitted else v0), label
    assert (fs.TERM, added.coefficient) not in fitted
    assert x_new[new.labels().index((fs.TERM, first.coefficient))] == fitted[(fs.TERM, first.coefficient)]


def test_a_spring_is_offered_on_the_axle_the_road_leads_alone():
    """:func:`force_shape.spring_on_axle`: the spring-family column of the axle that alone fits the target best
    (least squares, at its offered shape), standing for its family, every other spring member of the axle at
    frequency 0 so that :func:`force_shape.law_members` offers each to the fit (but the plain spring, for which
    the listed gas preload stands: it competes already); none of another axle or family; None without a spring
    column on the axle."""
    rng = np.random.default_rng(7)
    cols = fs.columns_of(fs.library(fs.settings()))   # every column, the contact springs at their gaps too
    t = np.arange(400) * 0.005
    X = np.vstack([np.column_stack([np.sin(2 * np.pi * rng.uniform(0.5, 4) * t + rng.uniform(0, 6)) for _ in cols])
                   for _ in range(4)])
    groups = np.repeat(np.arange(4), len(t))
    contact = next(c for c in cols if c.key == ("bump_contact", "rear") and c.shape == 0.02)
    y = 3.0 * X[:, cols.index(contact)] + rng.normal(0.0, 0.3, len(groups))
    design = fs.Design(X, y, groups, cols)
    sel = fs.spring_on_axle(design, "rear", 24)
    assert sel is not None and sel.stable == [contact] and sel.by_law == (contact.key,)
    np.testing.assert_allclose(sel.coef, [3.0], atol=0.1)
    springs = {c.key for c in cols if c.axle == "rear" and fs.LAW_OF.get(c.feature) == "spring"}
    assert set(sel.frequency) == springs and set(sel.frequency.values()) == {0.0}
    assert sel.resamples == 24 and sel.dependences == ["bump_contact"] and sel.leading == "bump_contact"
    offered = {alt.stable[0].key for alt in fs.law_members(sel, contact.key, design)}
    assert offered == springs - {contact.key, ("deflection", "rear")}
    assert {("deflection_cubed", "rear"), ("rebound_contact", "rear")} <= offered
    assert fs.LISTED_FOR["deflection"] == "damper_gas_preload"
    assert fs.spring_on_axle(design, "front", 24).stable[0].axle == "front"
    no_springs = [c for c in cols if fs.LAW_OF.get(c.feature) != "spring"]
    keep = [cols.index(c) for c in no_springs]
    assert fs.spring_on_axle(fs.Design(X[:, keep], y, groups, no_springs), "rear", 24) is None
    # on as shipped since the family's cases it can reach ran with it (benchmarks/RESULTS.md, 2026-12-01)
    assert fs.settings()["fit.spring_where_road_leads_one_axle"] is True


def test_the_exact_drive_bootstrap_enumerates_every_resample_with_its_probability():
    """``selection.exact_bootstrap``: every multiset of six draws from six drives once (462), weighted by its
    multinomial probability (weights sum to 1; all six drives once: 6! / 6^6), and the random draws otherwise
    (more resamples than ``exact_bootstrap_max``, or the switch off)."""
    cfg = dict(fs.settings(), **{"selection.exact_bootstrap": True})
    drives = np.arange(6)
    out = fs.drive_resamples(drives, cfg)
    assert len(out) == math.comb(11, 6) == 462
    assert len({tuple(p) for p, _ in out}) == 462 and all(np.all(np.diff(p) >= 0) for p, _ in out)
    assert sum(w for _, w in out) == pytest.approx(1.0)
    assert dict((tuple(p), w) for p, w in out)[tuple(drives)] == pytest.approx(math.factorial(6) / 6 ** 6)
    for over in ({"selection.exact_bootstrap_max": 461}, {"selection.exact_bootstrap": False}):
        drawn = fs.drive_resamples(drives, dict(cfg, **over))
        assert len(drawn) == int(cfg["selection.resamples"]) and all(w == 1.0 for _, w in drawn)


def test_the_exact_drive_bootstrap_gives_the_frequencies_many_random_draws_estimate():
    """The selection frequencies over the enumerated resamples are those random draws converge to: within
    0.05 of 2000 draws' (their Monte Carlo sd at most 0.011) for every dependence, one near the threshold
    among them, which 24 draws (as shipped) may miss by up to about 0.2 (their sd 0.10)."""
    d = _design(seed=3, truth={("sign_velocity", "rear"): 1.5, ("deflection", "front"): 0.2}, noise=1.0)
    base = fs.settings()
    exact = fs.select(d, dict(base, **{"selection.exact_bootstrap": True}))
    many = fs.select(d, dict(base, **{"selection.resamples": 2000}))
    assert exact is not None and many is not None and exact.resamples == 456   # the six one-drive multisets skipped
    keys = set(exact.frequency) | set(many.frequency)
    assert max(abs(exact.frequency.get(k, 0.0) - many.frequency.get(k, 0.0)) for k in keys) <= 0.05
    # the weak front spring near the threshold (measured 0.62 exact, 0.71 from the 24 draws as shipped)
    assert 0.5 < exact.frequency[("deflection", "front")] < 0.75
