"""Physics no candidate lists, named from its shape and modelled (issue 26, items 3-4), end to end.

Model-made truth: the synthetic measurement vehicle of the bundled drives without its amplitude friction
and with a damper blow-off valve instead (every damper 50 N softer per 0.1 m/s of deflection velocity
beyond 0.27 m/s, written as the learned term itself: as a valve acts on the oil, in the intact dampers
only), six drives (bump crossing and sine steer, intact /
front-empty / rear-empty). No listed candidate has a knee in the damper curve. The finder must name an
``unlisted_force`` whose leading dependence is the knee, fit it near the truth, and write a variant
that runs in the node's core (lockstep runner) and the batch model with the finder's numbers (1e-9).

Slow: one diagnosis of six drives (about 45 s on an idle machine).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from susp_sim_ros.analysis import synthetic as syn
from susp_sim_ros.analysis.discrepancy import DiscrepancyFinder
from susp_sim_ros.analysis.discrepancy.data import SIGNAL_OUTPUT, make_inputs_from_drive
from susp_sim_ros.analysis.discrepancy.engine import _TO_REPORT_UNITS
from susp_sim_ros.analysis.discrepancy.report import write_outputs
from susp_sim_ros.model import Model, simulate_batch
from susp_sim_ros.model.learned_force import LEARNED_FORCE
from susp_sim_ros.model.params import TermSetting
from susp_sim_ros.runtime.lockstep import run_lockstep

pytestmark = pytest.mark.slow

KNEE_M_S, COEF_N = 0.27, -50.0   # the knee off the regression's offered knees (0.1, 0.2, 0.4): the fit moves it
TOL = 1e-9  # deg/s: the same compiled step on the same parameters (test_discrepancy_written_model.py)


def _blow_off() -> TermSetting:
    vals = {p.name: (p.default,) * 4 for p in LEARNED_FORCE.params}
    vals["c_velocity_beyond_knee"] = (COEF_N,) * 4
    vals["knee_velocity"] = (KNEE_M_S,) * 4
    return TermSetting(LEARNED_FORCE, vals)


@pytest.fixture(scope="module")
def diagnosed(tmp_path_factory):
    hidden = syn.HiddenPhysics.reference().replace(amplitude_extra=(0.0, 0.0), extra_terms=(_blow_off(),))
    drives = [syn.generate_drive(m, s, hidden=hidden) for m in ("bump_crossing", "sine_steer")
              for s in ("intact", "front_empty", "rear_empty")]
    f = DiscrepancyFinder(variant="full", heldout=False).fit(drives)
    out = tmp_path_factory.mktemp("unlisted")
    return f, f.report(), write_outputs(f, out, "learned", plots=False)


def test_the_knee_is_named_as_an_unlisted_force_and_fitted_near_the_truth(diagnosed):
    f, rep, _ = diagnosed
    assert rep["verdict"] == "missing_physics"
    phys = [t for t in rep["terms"] if t["evidence"]["kind"] == "physics"]
    assert [t["name"] for t in phys] == ["unlisted_force"], rep["terms"]
    t = phys[0]
    assert t["dependences"][0] == "velocity_beyond_knee" and "valve" in t["description"]
    assert t["where"] == "all"
    for axle in ("front", "rear"):
        coef = t["params"][f"velocity_beyond_knee_{axle}"]
        assert 0.6 * COEF_N > coef > 1.5 * COEF_N, (axle, coef)
    assert t["params"]["knee_velocity"] == pytest.approx(KNEE_M_S, abs=0.05)
    ev = t["evidence"]
    assert ev["decoy_margin"] >= 10 and ev["passed"]
    # the shape regression's record: what it saw at the step that named it
    assert rep["force_shape"][0]["stable"] and rep["force_shape"][0]["listed_rivals"] == []


@pytest.mark.xfail(strict=True, raises=AssertionError, reason=(
    "measured 2026-11-27: coefficient intervals rear [-161, 58] N, front [-147, 46] N (fitted inside 0.6-1.5 x "
    "the truth): since the knee is scaled by the damper's oil level, this 50 N valve acts only in the intact "
    "dampers, whose deflection velocities pass the 0.27 m/s knee far less than the oil-empty ones' did; the "
    "term is named on its effect as a whole (the finder's criterion), its single coefficients are not resolved"))
def test_a_coefficient_of_the_learned_knee_is_resolved_from_zero(diagnosed):
    """The term's effect is not zero coefficient by coefficient: not every coefficient's interval (held values
    included) holds zero."""
    _, rep, _ = diagnosed
    t = next(t for t in rep["terms"] if t["name"] == "unlisted_force")
    assert any(t["ci95"][f"velocity_beyond_knee_{axle}"][1] < 0.0 for axle in ("front", "rear")), t["ci95"]


def test_the_written_variant_carries_the_learned_term(diagnosed):
    f, _, paths = diagnosed
    var = yaml.safe_load(Path(paths["variant"]).read_text())
    learned = [t for t in var["terms"] if t["name"] == "unlisted_force"]
    assert len(learned) == 1 and learned[0]["module"] == "susp_sim_ros.model.learned_force"
    assert learned[0]["params"]["c_velocity_beyond_knee"]["rear"] < 0


def test_the_written_model_is_the_fitted_model_in_batch_and_lockstep(diagnosed):
    """The written vehicle/variant pair simulated by the batch model on the finder's inputs, and by the
    node's core (lockstep runner, every 1 ms) on the bump crossings against the fitted rows on the node's
    held inputs: equal to 1e-9 deg/s."""
    f, _, paths = diagnosed
    ev, st, x = f.evaluator_, f.result_.structure, f.result_.x
    vehicle = paths.get("vehicle", "passat_b8_like")
    m = Model(vehicle, paths["variant"])
    fitted = ev.simulate(st, x[None], to_end=True)[0]
    P = np.stack([m.params(c.oil) for c in ev.cases])
    rows = np.arange(len(ev.cases))
    res = simulate_batch(m, P, ev.U, dt=ev.dt, roads=ev.roads, u_row=rows, road_row=rows, outputs=SIGNAL_OUTPUT)
    for r, c in enumerate(ev.cases):
        np.testing.assert_allclose(res.values[r] * _TO_REPORT_UNITS, fitted[r], rtol=0, atol=TOL, err_msg=c.name)
    t_steps = ev.dt * np.arange(1, ev.n_max + 1)
    for r, c in enumerate(ev.cases):
        if c.maneuver != "bump_crossing":
            continue
        ls = run_lockstep(c.drive, vehicle=vehicle, variant=paths["variant"], publish_rate_hz=1000.0)
        assert ls.healthy
        t_ls = (ls.t_ns - c.t0_ns) * 1e-9
        meas = np.column_stack([np.degrees(ls.imu.gyro), ls.imu.accel])
        rates = np.column_stack([np.interp(t_steps, t_ls, meas[:, a]) for a in range(6)])
        U, _ = make_inputs_from_drive(c.drive, ev.dt, hold=True)
        Uh = np.empty((1, ev.n_max, U.shape[1]))
        Uh[0, :len(U)], Uh[0, len(U):] = U, U[-1]
        held = simulate_batch(ev.model, ev.rows(st, x, [r]), Uh, dt=ev.dt, roads=[c.road], u_row=np.array([0]),
                              road_row=np.array([0]), outputs=SIGNAL_OUTPUT).values[0] * _TO_REPORT_UNITS
        np.testing.assert_allclose(rates[:c.n_steps], held[:c.n_steps], rtol=0, atol=TOL, err_msg=c.name)


def test_the_node_runs_the_written_learned_term(diagnosed):
    pytest.importorskip("rclpy")
    from _ros_helpers import SimDriver

    f, _, paths = diagnosed
    vehicle = paths.get("vehicle", "passat_b8_like")
    d = SimDriver({"vehicle": vehicle, "friction_variant": paths["variant"]})
    try:
        assert "unlisted_force" in [t.name for t in d.node.core.model.terms]
        np.testing.assert_array_equal(d.node.core.model.params(f.cases_[0].oil),
                                      Model(vehicle, paths["variant"]).params(f.cases_[0].oil))
    finally:
        d.close()
