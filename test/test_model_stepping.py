"""One stepping function for everything: chunked real-time stepping, whole-series runs and batch runs
give the same numbers; run-time changes of oil level and variant; the physics-term interface."""
import numpy as np
import pytest

from susp_sim_ros.errors import ConfigError, SuspInputError
from susp_sim_ros.model import Model, RoadProfile, Stepper, load_variant, make_inputs, simulate, simulate_batch
from susp_sim_ros.model.layout import OUTPUT_LABELS, P_INDEX
from susp_sim_ros.model.maneuvers import bump_crossing, sine_steer, vehicle_state
from susp_sim_ros.model.rigs import damper_rig

DT = 1e-3


def test_chunked_stepper_equals_whole_series(model_full):
    man = bump_crossing()
    U = man.to_inputs(DT)
    whole = simulate(model_full, U, dt=DT, road=man.road, oil=vehicle_state("rear_empty"))
    st = Stepper(model_full, dt=DT, road=man.road, oil=vehicle_state("rear_empty"))
    rng = np.random.default_rng(1)
    k, rows = 0, []
    while k < U.shape[0]:
        n = int(min(rng.integers(1, 40), U.shape[0] - k))
        y = st.advance(n, man.speed, 0.0)
        k += n
        rows.append((k, y.copy()))
    for k, y in rows[::25]:
        np.testing.assert_array_equal(y, whole.y[k - 1])  # bit for bit: the same compiled step


def test_batch_equals_single_runs(model_full):
    man = sine_steer(duration=4.0)
    U = man.to_inputs(DT)
    oils = [(1, 1, 1, 1), (0, 0, 1, 1), (1, 1, 0, 0), (0.3, 0.7, 0.2, 0.9)]
    P = np.stack([model_full.params(o) for o in oils])
    res = simulate_batch(model_full, P, U, dt=DT, roads=[man.road], decim=5,
                         outputs=["ROLL_RATE", "YAW_RATE"])
    t, Y, done = res.t, res.values, res.steps_done
    assert np.all(done == U.shape[0])
    for b, oil in enumerate(oils):
        single = simulate(model_full, U, dt=DT, road=man.road, oil=oil, decim=5, outputs=["ROLL_RATE", "YAW_RATE"])
        np.testing.assert_array_equal(Y[b], single.y)
        np.testing.assert_allclose(t, single.t)


def test_batch_blocks_equal_single_runs_and_a_diverging_vehicle_stops_alone(model_full):
    """The batch steps vehicles in blocks of ``kernel.LANES`` (SIMD lanes): 37 vehicles are two full
    blocks and a partial one. Each equals its own single run bit for bit, also when its neighbour in
    the block diverges and stops there."""
    man = bump_crossing()
    U = man.to_inputs(DT)[:3000]
    rng = np.random.default_rng(3)
    n = 2 * model_full.kernel.LANES + 5
    P = np.stack([model_full.params(tuple(rng.uniform(0.0, 1.0, 4))) for _ in range(n)])
    bad = model_full.kernel.LANES + 4
    P[bad, P_INDEX["M_S"]] = 1e-300  # absurd: this body explodes
    S = np.tile(model_full.initial_state(), (n, 1))
    res = simulate_batch(model_full, P, U, dt=DT, roads=[man.road], decim=10,
                         outputs=["PITCH_RATE", "DEFL_RL"], S=S)
    Y, done = res.values, res.steps_done
    assert done[bad] < U.shape[0] and np.all(np.delete(done, bad) == U.shape[0])
    for b in range(n):
        single = simulate(model_full, U, dt=DT, road=man.road, P=P[b].copy(), decim=10,
                          outputs=["PITCH_RATE", "DEFL_RL"])
        assert single.steps_done == done[b]
        np.testing.assert_array_equal(Y[b], single.y)
        np.testing.assert_array_equal(res.state[b], single.state)


def test_a_small_batch_is_shared_among_the_threads_with_the_same_numbers(model_full):
    """Fewer vehicles than the threads' blocks (a diagnosis evaluates six drives at a time) are shared
    evenly among the threads (:func:`batch_block`) instead of one block on one thread; each vehicle still
    equals its own single run bit for bit, on one thread or two."""
    import numba

    from susp_sim_ros.model.vehicle import batch_block, batch_cost
    assert [batch_block(n, 16, 2) for n in (1, 6, 7, 31, 32, 100)] == [1, 3, 4, 16, 16, 16]
    assert batch_block(6, 16, 1) == 6 and batch_block(3, 16, 8) == 1
    assert batch_cost(6, 100, 16, 2) == 300  # two blocks of three, one per thread
    assert batch_cost(40, 100, 16, 2) == 3200  # three blocks of 16: two on one thread
    man = bump_crossing()
    U = man.to_inputs(DT)[:2000]
    rng = np.random.default_rng(5)
    P = np.stack([model_full.params(tuple(rng.uniform(0.0, 1.0, 4))) for _ in range(7)])
    singles = [simulate(model_full, U, dt=DT, road=man.road, P=P[b].copy(), decim=10,
                        outputs=["ROLL_RATE", "DEFL_FL"]).y for b in range(len(P))]
    before = numba.get_num_threads()
    try:
        for threads in sorted({1, min(2, numba.config.NUMBA_NUM_THREADS)}):
            numba.set_num_threads(threads)
            res = simulate_batch(model_full, P, U, dt=DT, roads=[man.road], decim=10,
                                 outputs=["ROLL_RATE", "DEFL_FL"])
            for b in range(len(P)):
                np.testing.assert_array_equal(res.values[b], singles[b])
    finally:
        numba.set_num_threads(before)


def test_batch_mixes_drives_and_roads(model_full):
    bump, sine = bump_crossing(), sine_steer(duration=bump_crossing().duration)
    n = min(bump.n_steps(DT), sine.n_steps(DT))
    U = np.stack([bump.to_inputs(DT)[:n], sine.to_inputs(DT)[:n]])
    P = np.tile(model_full.params(), (2, 1))
    res = simulate_batch(model_full, P, U, dt=DT, roads=[bump.road, sine.road], u_row=[0, 1],
                         road_row=[0, 1], outputs=["PITCH_RATE"])
    Y = res.values
    for b, man in enumerate((bump, sine)):
        single = simulate(model_full, U[b], dt=DT, road=man.road, outputs=["PITCH_RATE"])
        np.testing.assert_array_equal(Y[b], single.y)


def test_oil_change_at_run_time_takes_effect_next_step(model_full):
    man = bump_crossing()
    a = Stepper(model_full, dt=DT, road=man.road)
    b = Stepper(model_full, dt=DT, road=man.road)
    for st in (a, b):
        st.advance(2000, man.speed, 0.0)
    b.set_oil(vehicle_state("rear_empty"))
    ya = a.advance(1, man.speed, 0.0).copy()
    yb = b.advance(1, man.speed, 0.0).copy()
    i = OUTPUT_LABELS.index("F_DAMPER_RL")
    assert ya[i] != yb[i]
    with pytest.raises(SuspInputError, match="damper_oil_level"):
        b.set_oil([1, 1, 1.5, 0])


def test_variant_change_keeps_body_state(models):
    man = bump_crossing()
    st = Stepper(models["full"], dt=DT, road=man.road)
    st.advance(2500, man.speed, 0.0)
    s_before = st.S.copy()
    st.set_model(models["dahl_only"])
    np.testing.assert_array_equal(st.S, s_before)  # same terms: everything carries over
    assert st.P[P_INDEX["USE_V"]] == 0.0


def test_non_finite_state_stops_cleanly(model_full):
    P = model_full.params()
    P[P_INDEX["M_S"]] = 1e-300  # absurd: the body explodes
    res = simulate(model_full, make_inputs(1000, 10.0, 0.1), dt=DT, road=RoadProfile.flat(), P=P)
    assert not res.ok and res.steps_done < 1000


def test_physics_term_interface_extra_viscous_damping(tmp_path):
    """A term added by a variant file: on the damper rig it adds exactly c*v to the damper force."""
    f = tmp_path / "visc.yaml"
    f.write_text("name: visc\nvelocity_scaling: true\noil_scaling: true\nhorizontal_scaling: true\n"
                 "terms:\n  - name: extra_viscous_damping\n    params: {c: {front: 500.0, rear: 0.0}}\n")
    base, visc = Model(variant="full"), Model(variant=str(f))
    assert [t.name for t in visc.terms][-1] == "extra_viscous_damping"
    fb = np.array(damper_rig(base, "front", 1.0).force_velocity)
    fv = np.array(damper_rig(visc, "front", 1.0).force_velocity)
    np.testing.assert_allclose(fv[:, 1] - fb[:, 1], 500.0 * fv[:, 0], rtol=1e-6, atol=1e-6)
    rb = np.array(damper_rig(base, "rear", 1.0).force_velocity)
    rv = np.array(damper_rig(visc, "rear", 1.0).force_velocity)
    np.testing.assert_allclose(rv, rb, rtol=1e-12)
    # and in the vehicle it damps the ring-out
    man = bump_crossing()
    q = lambda m: simulate(m, man.to_inputs(DT), dt=DT, road=man.road, oil=vehicle_state("front_empty"),
                           outputs=["PITCH_RATE"]).y[:, 0]
    k0 = int((man.road.s[-1] + visc.vehicle.wheelbase) / man.speed / DT)  # rear axle leaves the bump
    ring = slice(k0, k0 + 1500)
    assert np.sum(q(visc)[ring] ** 2) < 0.8 * np.sum(q(base)[ring] ** 2)


def test_extra_viscous_damping_follows_its_power_law_on_the_rig(tmp_path):
    """With an exponent the term's force is c v_ref sgn(v) |v/v_ref|^n: at v_ref it is c v_ref whatever n,
    below v_ref a digressive law (n < 1) gives more than the linear one, above less."""
    f = tmp_path / "visc.yaml"
    f.write_text("name: visc\nvelocity_scaling: true\noil_scaling: true\nhorizontal_scaling: true\n"
                 "terms:\n  - name: extra_viscous_damping\n"
                 "    params: {c: {front: 500.0, rear: 0.0}, n: {front: 0.5, rear: 0.5}}\n")
    base, visc = Model(variant="full"), Model(variant=str(f))
    fb = np.array(damper_rig(base, "front", 1.0).force_velocity)
    fv = np.array(damper_rig(visc, "front", 1.0).force_velocity)
    v = fv[:, 0]
    np.testing.assert_allclose(fv[:, 1] - fb[:, 1], 500.0 * 0.1 * np.sign(v) * np.sqrt(np.abs(v) / 0.1),
                               rtol=1e-6, atol=1e-6)
    slow, fast = (np.abs(v) > 0) & (np.abs(v) < 0.1), np.abs(v) > 0.1
    assert slow.any() and fast.any()
    extra = np.abs(fv[:, 1] - fb[:, 1])
    assert np.all(extra[slow] > 500.0 * np.abs(v[slow])) and np.all(extra[fast] < 500.0 * np.abs(v[fast]))


@pytest.mark.parametrize("text,match", [
    ("name: x\nvelocity_scaling: yes-ish\noil_scaling: true\nhorizontal_scaling: true\n", "velocity_scaling"),
    ("name: x\nvelocity_scaling: true\noil_scaling: true\nhorizontal_scaling: true\nterms: [{name: nope}]\n",
     "unknown physics term 'nope'"),
    ("name: x\nvelocity_scaling: true\noil_scaling: true\nhorizontal_scaling: true\n"
     "terms: [{name: extra_viscous_damping, params: {k: 1}}]\n", "unknown parameters"),
    ("- just a list\n", "mapping"),
])
def test_variant_errors_name_file_and_key(tmp_path, text, match):
    f = tmp_path / "bad.yaml"
    f.write_text(text)
    with pytest.raises(ConfigError, match=match) as e:
        load_variant(str(f))
    assert "bad.yaml" in str(e.value)


def test_vehicle_errors_name_file_and_key(tmp_path):
    from susp_sim_ros.model import config_dir, load_vehicle
    src = (config_dir() / "vehicles" / "passat_b8_like.yaml").read_text()
    f = tmp_path / "car.yaml"
    f.write_text(src.replace("sprung_mass: {value: 1400.0", "sprung_mass: {value: -3"))
    with pytest.raises(ConfigError, match=r"car.yaml: body.sprung_mass must be > 0"):
        load_vehicle(str(f))
    f.write_text(src.replace("  cg_height:", "  cg_heigth:"))
    with pytest.raises(ConfigError, match=r"missing parameter body.cg_height"):
        load_vehicle(str(f))
    with pytest.raises(ConfigError, match="unknown vehicle 'golf'"):
        load_vehicle("golf")


def test_every_vehicle_parameter_has_unit_and_source(model_full):
    srcs = model_full.vehicle.sources
    assert len(srcs) == 40  # every entry of the vehicle file read (incl. tyre.rolling_radius), with unit and source
    for key, (unit, source) in srcs.items():
        assert unit and source, key


def test_bare_variant_name_is_not_shadowed_by_a_folder(tmp_path, monkeypatch):
    (tmp_path / "dahl_only").mkdir()
    monkeypatch.chdir(tmp_path)
    assert load_variant("dahl_only").velocity_scaling is False
