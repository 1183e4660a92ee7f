"""The missing force estimated from a recording (issue 26; analysis/discrepancy/missing_force.py).

Truth: :mod:`truth_generators.hidden_force`, the model's own kernel with an axle friction element the
estimating model lacks, so the hidden force is known exactly (model-made truth: it tests the estimator's
mechanics; the generator family of issue 24 measures it on structure the model does not share).
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from susp_sim_ros.analysis.discrepancy import missing_force as mf
from susp_sim_ros.model import load_variant, load_vehicle
from susp_sim_ros.model.layout import P_INDEX
from susp_sim_ros.model.linear import linearise
from susp_sim_ros.model.vehicle import Model, make_inputs, simulate
from truth_generators.hidden_force import hidden_axle_friction

AXLE_LEVEL_N = 150.0       # hidden axle friction per corner [N]


def _case(maneuver="bump_crossing", level=AXLE_LEVEL_N, oil=(1.0, 1.0, 0.0, 0.0), seed=0):
    """Estimate and truth of one drive on the estimate's grid: (estimate, hidden force (n, 3: front,
    rear, roll moment), truth axle deflection velocity (n, 2))."""
    d = hidden_axle_friction(maneuver, level, oil, seed)
    c = d.model_corner
    est = mf.estimate_on_model(d.model_vehicle, d.P, c["DEFL"], c["DEFL_VEL"], c["F_DAMPER"] + c["F_FRICTION"],
                               d.t_imu, d.measured - d.simulated, d.sigma)
    at = lambda x: np.column_stack([np.interp(est.t, d.t, x[:, i]) for i in range(4)])  
    h, v = at(d.hidden), at(d.truth_velocity)
    y = mf.Corners.of(d.P).y
    truth = np.column_stack([h[:, 0] + h[:, 1], h[:, 2] + h[:, 3], h @ y])
    return est, truth, np.column_stack([v[:, :2].mean(axis=1), v[:, 2:].mean(axis=1)])


@pytest.fixture(scope="module")
def rear_empty_bump():
    return _case()


def test_hidden_rear_axle_friction_is_recovered_in_the_body_mode_band(rear_empty_bump):
    est, truth, _ = rear_empty_bump
    dt = float(est.t[1] - est.t[0])
    a, b = mf.band_passed(est.force[:, 1], dt), mf.band_passed(truth[:, 1], dt)
    assert np.corrcoef(a, b)[0, 1] >= 0.9
    assert np.std(a) == pytest.approx(np.std(b), rel=0.2)


def test_loop_half_height_reads_the_known_friction_level(rear_empty_bump):
    est, truth, vel = rear_empty_bump
    level = 2 * AXLE_LEVEL_N  # both rear corners slide (saturating Dahl element)
    assert mf.loop_half_height(truth[:, 1], vel[:, 1]) == pytest.approx(level, rel=0.05)  # the truth is it
    assert mf.loop_half_height(est.force[:, 1], vel[:, 1]) == pytest.approx(level, rel=0.2)


def test_nothing_hidden_gives_a_force_within_its_uncertainty():
    est, truth, vel = _case(level=0.0, seed=1)
    assert np.max(np.abs(truth[:, :2] - truth[:, :2].mean(axis=0))) < 5.0  # only the 1 N damper element
    inside = np.abs(est.force[:, :2]) <= 2.5 * est.sd[:, :2]
    assert inside.mean() > 0.95
    assert abs(mf.loop_half_height(est.force[:, 1], vel[:, 1])) < 0.2 * 2 * AXLE_LEVEL_N


def test_a_unit_force_acts_on_the_body_and_the_wheels_as_the_kernel_applies_suspension_forces():
    P = Model(load_vehicle(), load_variant("dahl_only")).params(np.ones(4))
    c = mf.Corners.of(P)
    B = mf.input_matrix(c)
    # front axle force: heave, nose-up pitch (-x f), the two front wheels pushed down, no roll
    np.testing.assert_allclose(B[:, 0], [1.0, 0.0, -c.x[0], -0.5, -0.5, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(B[:, 1], [1.0, 0.0, -c.x[2], 0.0, 0.0, -0.5, -0.5], atol=1e-12)
    # roll moment: 1 N*m on the body, nothing on heave and pitch, opposite forces on each axle's wheels
    assert B[1, 2] == pytest.approx(1.0) and B[0, 2] == pytest.approx(0.0, abs=1e-12)
    assert B[2, 2] == pytest.approx(0.0, abs=1e-12)
    assert B[3, 2] == pytest.approx(-B[4, 2]) and B[5, 2] == pytest.approx(-B[6, 2])


def test_a_gap_is_predicted_through_never_interpolated():
    t = np.concatenate([np.arange(0.0, 1.0, 0.005), np.arange(2.0, 3.0, 0.005)])
    y = np.ones((t.size, 3))
    grid, dt = mf.uniform_grid(t)
    on, valid = mf.on_grid(t, y, grid, dt)
    assert dt == pytest.approx(0.005)
    gap = (grid > 1.0) & (grid < 2.0 - dt)
    assert gap.sum() > 150 and not valid[gap].any() and valid[~((grid > 0.999) & (grid < 2.0))].all()


def test_equivalent_linearisation_takes_a_viscous_and_a_friction_slope():
    P = Model(load_vehicle(), load_variant("dahl_only")).params(np.ones(4))
    c = mf.Corners.of(P)
    lin = linearise(load_vehicle(), P)
    t = np.linspace(0, 10, 5001)
    d = 0.02 * np.sin(2 * np.pi * t)[:, None] * np.ones(4)
    v = 0.02 * 2 * np.pi * np.cos(2 * np.pi * t)[:, None] * np.ones(4)
    eq = mf.equivalent_linear(lin, c, d, v, 3000.0 * v + 5000.0 * d)
    J = mf.deflection_jacobian(c)
    np.testing.assert_allclose(eq.C - lin.C, J.T @ np.diag(3000.0 + lin.C[0, 3:]) @ J, rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(eq.K - lin.K, J.T @ np.diag([5000.0] * 4) @ J, rtol=1e-9, atol=1e-6)


def _run_with_corner_outputs(P, model, n=4000, dt=0.001):
    """A drive over a four-poster input (wheel heights, steering, acceleration) with the corner outputs."""
    t = dt * np.arange(n)
    wh = np.column_stack([0.02 * np.sin(2 * np.pi * 1.3 * t), 0.01 * np.sin(2 * np.pi * 1.7 * t + 0.5),
                          0.015 * np.sin(2 * np.pi * 0.9 * t + 1.0), 0.01 * np.sin(2 * np.pi * 2.1 * t)])
    U = make_inputs(n, 10.0, 0.05 * np.sin(0.5 * t), 0.3 * np.sin(0.7 * t), wh)
    names = ("DEFL", "DEFL_VEL", "F_X", "F_Y", "F_Z", "F_SPRING", "F_DAMPER", "F_FRICTION", "F_ARB")
    r = simulate(model, U, dt=dt, P=P, outputs=[f"{o}_{w}" for o in names for w in ("FL", "FR", "RL", "RR")])
    return {o: r.values[:, 4 * k:4 * k + 4] for k, o in enumerate(names)}


def test_suspension_force_along_a_run_reproduces_the_kernels_own_force():
    """Spring, damper, friction (with its Dahl history and the horizontal-force scaling) and anti-roll bar
    re-evaluated along a run give the kernel's outputs; so the calibration's part is exactly the force
    difference of the two parameter rows along the run."""
    model = Model(load_vehicle(), load_variant("full"))
    P = model.params((1.0, 1.0, 0.0, 0.0))
    Y = _run_with_corner_outputs(P, model)
    own = Y["F_SPRING"] + Y["F_DAMPER"] + Y["F_FRICTION"] + Y["F_ARB"]
    traj = {k: Y[k] for k in mf.TRAJECTORY}
    again = mf.suspension_force_along(model.kernel, P, *traj.values())
    np.testing.assert_allclose(again, own, atol=1e-6)
    # a stiffer wheel rate and a stronger damper table: the difference is k d + the table's extra force
    vp = load_vehicle()
    stiffer = dataclasses.replace(vp, wheel_rate=tuple(k + 2500.0 for k in vp.wheel_rate),
                                  damper_measured_empty=tuple(tuple(1.5 * f for f in row)
                                                              for row in vp.damper_measured_empty))
    P2 = Model(stiffer, load_variant("full")).params((1.0, 1.0, 0.0, 0.0))
    cf = mf.calibration_force(model.kernel, P2, P, traj, None)
    d_prev = np.vstack([np.zeros((1, 4)), Y["DEFL"][:-1]])
    extra = cf.corner - 2500.0 * d_prev
    assert np.max(np.abs(extra[:, :2])) < 1e-6                       # intact front: only the rate changed
    rear = extra[:, 2:]
    v_prev = np.vstack([np.zeros((1, 4)), Y["DEFL_VEL"][:-1]])[:, 2:]
    assert np.all(rear * v_prev >= -1e-6) and np.max(np.abs(rear)) > 10.0   # oil-empty rear: more damping
    ch = mf.axle_channels(cf.corner, mf.Corners.of(P))
    np.testing.assert_allclose(ch[:, 0], cf.corner[:, 0] + cf.corner[:, 1])
    np.testing.assert_allclose(ch[:, 2], cf.corner @ mf.Corners.of(P).y)
    assert mf.calibration_force(model.kernel, P, P, traj, own).check_N < 1e-6


def test_body_accelerations_are_the_kernels_and_the_body_part_is_their_inertial_force_by_statics():
    """The calibration's body part (:func:`~.missing_force.body_force`): heave ``AZ_SF - g`` and the step-wise
    difference of the rates are the kernel's own body accelerations (its heave, roll and pitch equations
    hold with them along a run, to rounding); the (front, rear, roll) triple of a mass and inertia change
    acts on heave, roll and pitch as ``-dm z''``, ``-dIxx phi''``, ``-dIyy theta''``; a mass change alone
    splits onto the axles as the static load (rear share ``a / (a + b)``)."""
    model = Model(load_vehicle(), load_variant("full"))
    P = model.params((1.0, 1.0, 0.0, 0.0))
    n, dt = 4000, 0.001
    t = dt * np.arange(n)
    wh = np.column_stack([0.02 * np.sin(2 * np.pi * 1.3 * t), 0.01 * np.sin(2 * np.pi * 1.7 * t + 0.5),
                          0.015 * np.sin(2 * np.pi * 0.9 * t + 1.0), 0.01 * np.sin(2 * np.pi * 2.1 * t)])
    U = make_inputs(n, 10.0, 0.05 * np.sin(0.5 * t), 0.3 * np.sin(0.7 * t), wh)
    body = ("AZ_SF", "ROLL_RATE", "PITCH_RATE", "AX_SF", "AY_SF", "VEL_Y", "YAW_RATE", "ROLL", "PITCH")
    forces = ("F_SPRING", "F_DAMPER", "F_FRICTION", "F_ARB")
    r = simulate(model, U, dt=dt, P=P, outputs=list(body) + [f"{o}_{w}" for o in forces
                                                             for w in ("FL", "FR", "RL", "RR")])
    Y = {o: r.values[:, k] for k, o in enumerate(body)}
    fs = sum(r.values[:, len(body) + 4 * k:len(body) + 4 * k + 4] for k in range(len(forces)))
    acc = mf.body_accelerations(P, Y["AZ_SF"], Y["ROLL_RATE"], Y["PITCH_RATE"], dt)
    v = {k: float(P[P_INDEX[k]]) for k in ("G", "M_S", "IXX", "IYY", "H_CG", "H_RC", "H_PC")}
    c = mf.Corners.of(P)
    before = lambda x: np.concatenate([[0.0], x[:-1]])   # the kernel's angles at the step's start
    ax = Y["AX_SF"] + Y["VEL_Y"] * Y["YAW_RATE"] + v["G"] * Y["PITCH"]
    ay = Y["AY_SF"] - v["G"] * Y["ROLL"]
    np.testing.assert_allclose(v["M_S"] * acc[:, 0], fs.sum(axis=1), atol=1e-6 * np.abs(fs.sum(axis=1)).max())
    roll = fs @ c.y + v["M_S"] * (v["H_CG"] - v["H_RC"]) * (ay + v["G"] * before(Y["ROLL"]))
    pitch = -(fs @ c.x) + v["M_S"] * (v["H_CG"] - v["H_PC"]) * (v["G"] * before(Y["PITCH"]) - ax)
    np.testing.assert_allclose(v["IXX"] * acc[:, 1], roll, atol=1e-6 * np.abs(roll).max())
    np.testing.assert_allclose(v["IYY"] * acc[:, 2], pitch, atol=1e-6 * np.abs(pitch).max())
    # a calibrated row: sprung mass +100 kg, roll inertia +50, pitch inertia -200 kg*m^2
    P2 = P.copy()
    for k, dv in (("M_S", 100.0), ("IXX", 50.0), ("IYY", -200.0)):
        P2[P_INDEX[k]] += dv
    d = mf.body_force(P2, P, acc, c)
    gen = mf.input_matrix(c)[:3] @ d.T
    np.testing.assert_allclose(gen.T, acc * [-100.0, -50.0, 200.0], atol=1e-9 * np.abs(acc * 200.0).max())
    P3 = P.copy()
    P3[P_INDEX["M_S"]] += 100.0
    d = mf.body_force(P3, P, acc, c)
    to_front, to_rear = c.x[0], -c.x[2]   # the centre of gravity to the front and the rear axle [m]
    np.testing.assert_allclose(d[:, 1], -100.0 * acc[:, 0] * to_front / (to_front + to_rear),
                               atol=1e-6 * np.abs(100.0 * acc[:, 0]).max())
    np.testing.assert_allclose(d[:, 2], 0.0, atol=1e-9 * np.abs(100.0 * acc[:, 0]).max())
    assert not np.any(mf.body_force(P, P, acc, c))


def test_report_table_says_a_negative_loop_and_never_minus_zero():
    """A loop half height of -0.3 N is 0 in the table (not "-0"); -9 N stays -9 and the text says what a
    negative one means (the model has more friction-like force than the car)."""
    from susp_sim_ros.analysis.discrepancy.missing_force_report import markdown
    ax = lambda loop: {"rms": 20.0, "loop_half_height_N": loop, "sd_mean": 40.0}  # noqa: E731
    mf = {"per_drive": {"d1": {"unmeasured_input": False, "front_N": ax(-0.3), "rear_N": ax(-9.2),
                               "roll_Nm": {"rms": 3.0}}}, "files": []}
    text = "\n".join(markdown(mf))
    row = next(line for line in text.splitlines() if line.startswith("| d1"))
    cells = [c.strip() for c in row.split("|")]
    assert cells[5] == "0" and cells[6] == "-9"
    assert "negative where the model has more friction-like force than the car" in text


def test_report_says_an_unmeasured_road_drive_tells_nothing_about_physics():
    from susp_sim_ros.analysis.discrepancy.missing_force_report import markdown
    ax = {"rms": 11053.0, "loop_half_height_N": -1300.0, "sd_mean": 1836.0}
    mf = {"per_drive": {"highway": {"unmeasured_input": True, "front_N": ax, "rear_N": ax, "roll_Nm": {"rms": 443.0}}},
          "files": []}
    text = "\n".join(markdown(mf))
    assert "highway (input not measured)" in text and "say nothing about missing physics" in text
    mf["per_drive"]["highway"]["unmeasured_input"] = False
    assert "say nothing about missing physics" not in "\n".join(markdown(mf))


def test_loop_panels_scale_the_missing_force_to_itself(tmp_path, monkeypatch):
    """The bundled drives' calibration parts reach +-1500 N beside a missing force of +-100 N: on one axis
    the loop was a flat line. The missing force has the left axis to itself, the model's forces the right."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from susp_sim_ros.analysis.discrepancy import missing_force as mfm
    from susp_sim_ros.analysis.discrepancy.missing_force_report import DriveForce, plot
    n = 2000
    t = np.linspace(0.0, 4.0, n)
    d = 0.03 * np.sin(2 * np.pi * t)
    vel = np.gradient(d, t)
    force = np.zeros((n, 3))
    force[:, 0] = 50.0 * np.tanh(vel / 0.005)    # a 50 N friction-like missing force, front
    big = np.zeros((n, 3))
    big[:, :2] = 1500.0 * np.sin(2 * np.pi * t + 0.5)[:, None]
    est = mfm.MissingForce(t, force, np.full((n, 3), 5.0), 1.0, np.ones(n, bool))
    df = DriveForce("drive", est, np.column_stack([d, d]), np.column_stack([vel, vel]),
                    np.column_stack([30000 * d, 30000 * d]), False, calibration=big, body=-big)
    figs = []
    monkeypatch.setattr(plt, "close", lambda fig=None: figs.append(fig))
    plot(df, tmp_path / "loops.png", "title")
    assert (tmp_path / "loops.png").exists()
    left = [a for a in figs[0].axes if a.get_ylabel() == "front axle missing force [N]"]
    assert len(left) == 2
    for a in left:
        lo, hi = a.get_ylim()
        assert 100.0 <= hi - lo <= 200.0   # +-50 N with matplotlib's margin, not +-1500 N
