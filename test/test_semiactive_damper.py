"""Semi-active damper in the kernel (issue 15): passive outputs unchanged bit for bit, valve lag, curve
family, oil scaling, and the command input through SimCore (validation, stale fallback) and lockstep."""
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from susp_sim_ros.runtime.lockstep import maneuver_drive, run_lockstep
from susp_sim_ros.io.drive import Series
from susp_sim_ros.model import Model
from susp_sim_ros.model.layout import S_INDEX
from susp_sim_ros.model.maneuvers import paper_maneuver, vehicle_state
from susp_sim_ros.model.semiactive import load_damper_family
from susp_sim_ros.model.vehicle import Stepper, simulate
from susp_sim_ros.runtime.sim_core import SimCore

REF = Path(__file__).parent / "data" / "passive_reference.npz"
DT = 0.001


@pytest.fixture(scope="module")
def ref():
    return np.load(REF)


def test_passive_outputs_are_unchanged_bit_for_bit(model_full, ref):
    """Reference made by test/data/make_passive_reference.py with the code before the semi-active damper."""
    cols = [str(c) for c in ref["columns"]]
    d = maneuver_drive(paper_maneuver("bump_crossing"), vehicle_state("rear_empty"), rate_hz=1000.0)
    r = run_lockstep(d, model=model_full, oil=vehicle_state("rear_empty"))
    np.testing.assert_array_equal(np.stack([r[c] for c in cols], 1), ref["lockstep_bump_rear_empty"])
    man = paper_maneuver("sine_steer")
    res = simulate(model_full, man.to_inputs(DT), dt=DT, road=None, oil=vehicle_state("front_empty"),
                   decim=50, outputs=cols)
    np.testing.assert_array_equal(res.y, ref["simulate_sine_front_empty"])


def _bump_run(model, oil, cmd, semi=True):
    man = paper_maneuver("bump_crossing")
    U = man.to_inputs(DT)
    U[:, -4:] = cmd
    P = model.params(oil, semi_active=semi)
    return simulate(model, U, dt=DT, road=man.road, oil=oil, P=P)


def test_family_equal_to_the_passive_curve_reproduces_the_passive_damper(model_full):
    """A valve whose soft and hard curves are both the passive curve is the passive damper at any command
    (to rounding: the blend soft + u (hard - soft) is exact when they are equal)."""
    vp = model_full.vehicle
    fam = replace(load_damper_family(), velocity=vp.damper_velocity, soft=vp.damper_measured_intact,
                  hard=vp.damper_measured_intact)
    m = Model(vp, model_full.variant, dampers=fam)
    oil = (1.0, 0.5, 1.0, 0.0)
    passive = _bump_run(m, oil, 0.0, semi=False)
    for u in (0.0, 0.3, 1.0):
        np.testing.assert_allclose(_bump_run(m, oil, u).y, passive.y, rtol=0, atol=1e-12)


def test_hard_valve_damps_more_than_soft(model_full):
    soft, hard = (_bump_run(model_full, (1, 1, 1, 1), u) for u in (0.0, 1.0))
    for w in ("FL", "RL"):
        # several times the damper force per unit deflection velocity (the curves' ratio), and a
        # slower suspension stroke
        def ratio(r, w=w):
            return np.sum(np.abs(r[f"F_DAMPER_{w}"])) / np.sum(np.abs(r[f"DEFL_VEL_{w}"]))
        assert ratio(hard) > 3.0 * ratio(soft)
        assert np.max(np.abs(hard[f"DEFL_VEL_{w}"])) < np.max(np.abs(soft[f"DEFL_VEL_{w}"]))


def test_oil_empty_damper_ignores_the_command(model_full):
    """Oil loss scales the valve family as it scales the passive curve: with no oil the command does
    nothing (bit for bit)."""
    a, b = (_bump_run(model_full, (0, 0, 0, 0), u) for u in (0.0, 1.0))
    np.testing.assert_array_equal(a.y, b.y)
    c = _bump_run(model_full, (0, 0, 0, 0), 0.0, semi=False)
    np.testing.assert_array_equal(a.y, c.y)


def test_valve_follows_the_command_with_a_first_order_lag(model_full):
    tau = model_full.dampers.valve_time_constant
    assert 0.008 <= tau <= 0.025
    st_ = Stepper(model_full, dt=DT)
    st_.set_semi_active(True, (0.0, 0.0, 0.0, 0.0))
    k = S_INDEX["VALVE"]
    for n in range(1, 61):
        st_.advance(1, 10.0, 0.0, 0.0, None, (1.0, 0.5, 0.0, 1.0))
        np.testing.assert_allclose(st_.S[k:k + 4], np.array([1.0, 0.5, 0.0, 1.0]) * -np.expm1(-n * DT / tau),
                                   rtol=1e-12, atol=1e-15)


def test_simcore_validates_damper_commands_and_falls_back_when_stale(model_full):
    core = SimCore(model_full, input_timeout_s=0.1)
    core.advance_to(0)
    assert core.set_damper_command(0, [0.2, 0.2, 0.2, 1.5]) is not None
    assert core.set_damper_command(0, [0.2, float("nan"), 0.2, 0.2]) is not None
    assert core.set_damper_command(0, [0.2, 0.2, 0.2]) is not None
    assert core.set_damper_command(0, [0.1] * 4, dims=[("wheel", 5)]) is not None
    assert core.rejections["damper_command"] == 3 and core.rejections["non_finite"] == 1
    assert not core.stepper.semi_active
    assert core.set_damper_command(0, [0.0, 0.5, 1.0, 0.25]) is None
    assert core.stepper.semi_active
    core.advance_to(50_000_000)
    assert core.stepper.semi_active and "/vehicle/damper_command" not in core.stale_inputs(50_000_000)
    core.advance_to(300_000_000)
    assert not core.stepper.semi_active and core.rejections["damper_command_stale"] == 1
    core.advance_to(400_000_000)
    assert core.rejections["damper_command_stale"] == 1  # once per stale spell
    assert core.set_damper_command(400_000_000, [1.0] * 4) is None and core.stepper.semi_active


@settings(max_examples=60, deadline=None)
@given(st.lists(st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-3, 3)),
                min_size=0, max_size=6))
def test_damper_command_handler_never_accepts_bad_values(model_full, data):
    core = SimCore(model_full)
    reason = core.set_damper_command(0, data)
    arr = np.asarray(data, float)
    good = arr.shape == (4,) and np.all(np.isfinite(arr)) and np.all((arr >= 0) & (arr <= 1))
    assert (reason is None) == bool(good)
    assert core.stepper.semi_active == bool(good)


def test_recorded_command_drives_lockstep_and_round_trips(model_full, tmp_path):
    from susp_sim_ros.io.drive import read_drive, write_drive
    d = maneuver_drive(paper_maneuver("bump_crossing"), vehicle_state("intact"), rate_hz=100.0)
    hard = replace(d, damper_command=Series(d.speed.t_ns, np.ones((len(d.speed), 4))))
    write_drive(tmp_path / "cmd.mcap", hard)
    back = read_drive(tmp_path / "cmd.mcap")
    np.testing.assert_array_equal(back.damper_command.values, hard.damper_command.values)
    r_pass, r_hard = run_lockstep(d, model=model_full), run_lockstep(back, model=model_full)
    assert r_hard.rejections == {}
    for w in ("FL", "RL"):  # the hard valve (about twice the passive curve) pushes harder on the bump
        assert np.max(np.abs(r_hard[f"F_DAMPER_{w}"])) > 1.5 * np.max(np.abs(r_pass[f"F_DAMPER_{w}"]))


def test_controller_in_the_lockstep_loop_is_recorded_and_replays(model_full, tmp_path):
    """A library controller in the lockstep loop: its commands are applied and recorded; the recorded
    drive run again (its own commands, no controller) gives the same outputs."""
    from susp_sim_ros.io.drive import read_drive
    d = maneuver_drive(paper_maneuver("bump_crossing"), vehicle_state("intact"), rate_hz=100.0)
    r = run_lockstep(d, model=model_full, controller="skyhook", out_path=tmp_path / "sky.mcap")
    assert r.rejections == {}
    rec = read_drive(tmp_path / "sky.mcap")
    assert rec.damper_command is not None and len(rec.damper_command) > 500
    assert np.all((rec.damper_command.values >= 0) & (rec.damper_command.values <= 1))
    again = run_lockstep(rec, model=model_full)
    np.testing.assert_array_equal(again.values, r.values)
    passive = run_lockstep(d, model=model_full)
    assert not np.array_equal(passive["F_DAMPER_FL"], r["F_DAMPER_FL"])


def test_passive_kernel_gives_the_semi_capable_kernels_numbers_bit_for_bit():
    """Passive batches run a kernel compiled without the semi-active code (it halved batch throughput);
    on passive vehicles it must give exactly the numbers of the full kernel: a bump crossing in three oil
    states on both kernels, every output, bit for bit."""
    import numpy as np

    from susp_sim_ros.model import Model, simulate_batch
    from susp_sim_ros.model.maneuvers import bump_crossing
    model = Model("passat_b8_like", "full")
    man = bump_crossing()
    U = man.to_inputs(0.001)
    P = np.array([model.params(o) for o in ((1, 1, 1, 1), (1, 1, 0, 0), (0, 0, 1, 1))])
    res = simulate_batch(model, P, U, dt=0.001, roads=[man.road])
    y_passive, done_p = res.values, res.steps_done
    assert model._kernel_passive is not None  # the passive batch took the passive kernel
    model._kernel_passive = model.kernel       # now force the semi-capable kernel
    res = simulate_batch(model, P, U, dt=0.001, roads=[man.road])
    y_full, done_f = res.values, res.steps_done
    assert np.array_equal(done_p, done_f)
    assert np.array_equal(y_passive, y_full) and np.any(y_full != 0)
