"""Physics of the independent truth simulator (``truth_generators.independent_sim``).

Reference values: model-spec section 5 (an independent implementation of the same spec).
"""
import json

import numpy as np
import pytest
from scipy.signal import welch

from truth_generators.independent_roads import coherence, iso8608_psd, iso8608_road
from truth_generators.independent_sim import (NY, SOURCE, TruthCar, TruthFriction, TruthHidden,
                                                   TruthManeuver, TruthSensor, body_modes, hydraulic_curves,
                                                   make_drive, simulate, write_drive)
from susp_sim_ros.io.drive import read_drive

V50 = 50 / 3.6


@pytest.fixture(scope="module")
def bump_runs():
    return {st: simulate(maneuver=TruthManeuver.bump(), oil=oil)
            for st, oil in (("intact", (1, 1, 1, 1)), ("rear_empty", (1, 1, 0, 0)))}


def test_body_modes_eigen():
    m = body_modes()
    for k, ref in (("bounce", 1.251), ("pitch", 1.492), ("roll", 2.125)):
        assert m[k] == pytest.approx(ref, rel=0.05), (k, m)


def test_roll_free_decay_of_the_integrator():
    """Free roll vibration (dampers, friction off) of the RK4 stepping itself, from an initial roll rate."""
    y0 = np.zeros(NY)
    y0[3] = 0.05
    r = simulate(friction=TruthFriction(enabled=False), maneuver=TruthManeuver.rest(4.0), y0=y0,
                 dampers=False)
    p = r.gyro[:, 0]
    up = np.nonzero((p[:-1] < 0) & (p[1:] >= 0))[0]
    f = (len(up) - 1) / (r.t[up[-1]] - r.t[up[0]])
    assert f == pytest.approx(2.125, rel=0.05)
    assert np.abs(p).max() == pytest.approx(0.05, rel=0.05)     # undamped: no decay
    assert np.abs(p[-2000:]).max() > 0.045


def test_steady_state_yaw_gain_50kmh():
    # slow ramp of a small steering angle: quasi-steady state at the peak
    man = TruthManeuver("sine", V50, 1.0 + 5.0, 1.0, steer="sine", steer_amplitude_rad=np.radians(10.0),
                        steer_freq_hz=0.05, steer_periods=0.25)
    r = simulate(friction=TruthFriction(enabled=False), maneuver=man)
    delta = np.radians(10.0) / TruthCar().steering_ratio
    assert r.gyro[-1, 2] / delta == pytest.approx(4.25, rel=0.05)


def test_60deg_steer_yaw_rate_and_lateral_acceleration():
    man = TruthManeuver("sine", V50, 1.0 + 5.0, 1.0, steer="sine", steer_amplitude_rad=np.radians(60.0),
                        steer_freq_hz=0.05, steer_periods=0.25)
    r = simulate(maneuver=man)
    assert np.degrees(r.gyro[-1, 2]) == pytest.approx(16.2, rel=0.05)
    assert V50 * r.gyro[-1, 2] == pytest.approx(3.90, rel=0.05)
    assert r.accel[-1, 1] > V50 * r.gyro[-1, 2]       # REP-145: + g*sin(roll), roll positive (left up)


def test_bump_8kmh_pitch_rate(bump_runs):
    for st, r in bump_runs.items():
        q = np.degrees(r.gyro[:, 1])
        first = q[np.nonzero(np.abs(q) > 0.3)[0][0]]
        assert first < 0, st                          # front rises first: nose up
        assert 7.0 <= np.abs(q).max() <= 10.0, (st, np.abs(q).max())
        lead = r.t[np.nonzero(np.abs(q) > 1e-6)[0][0]]
        assert lead >= 1.0                            # quiet lead-in before the front axle reaches it
    # oil-empty rear dampers ring out longer
    t_off = 1.5 + (0.5 + 2.79) / (8 / 3.6)
    ring = {st: r.t[np.abs(np.degrees(r.gyro[:, 1])) > 0.3].max() - t_off for st, r in bump_runs.items()}
    assert ring["rear_empty"] > ring["intact"] + 0.5
    assert 0.3 < ring["intact"] < 1.2


def test_at_rest_accelerometer_reads_g():
    r = simulate(maneuver=TruthManeuver.rest(1.0))
    assert np.allclose(r.accel[:, 2], 9.81, atol=1e-9)
    assert np.allclose(r.gyro, 0.0, atol=1e-12) and np.allclose(r.accel[:, :2], 0.0, atol=1e-12)


def test_gas_preload_starts_in_equilibrium():
    hid = TruthHidden(gas_preload_N=(150.0, 150.0, 100.0, 100.0), gas_rate_N_m=(2000.0,) * 4)
    r = simulate(hidden=hid, maneuver=TruthManeuver.rest(1.0))
    assert np.abs(r.gyro).max() < 1e-9 and np.abs(r.accel[:, 2] - 9.81).max() < 1e-6
    assert np.all(r.deflection[0] < -1e-3)           # preload extends the struts


def test_sine_steer_mirror_symmetry():
    base = dict(speed_kmh=50.0, freq_hz=0.5, periods=2.0)
    a = simulate(maneuver=TruthManeuver.sine(amplitude_deg=60.0, **base))
    b = simulate(maneuver=TruthManeuver.sine(amplitude_deg=-60.0, **base))
    scale = np.abs(a.gyro).max()
    assert scale > 0.1
    np.testing.assert_allclose(a.gyro[:, [0, 2]], -b.gyro[:, [0, 2]], atol=1e-9 * scale)
    np.testing.assert_allclose(a.gyro[:, 1], b.gyro[:, 1], atol=1e-9 * scale)
    np.testing.assert_allclose(a.accel[:, 1], -b.accel[:, 1], atol=1e-9)
    np.testing.assert_allclose(a.deflection, b.deflection[:, [1, 0, 3, 2]], atol=1e-12)


def test_iso8608_psd_and_coherence():
    ds = 0.02
    f = P = None
    acc, cross = [], []
    for seed in range(4):
        s, zl, zr = iso8608_road(2000.0, "C", seed, ds=ds)
        for z in (zl, zr):
            f, P = welch(z, fs=1 / ds, nperseg=int(100 / ds))
            acc.append(P)
        from scipy.signal import csd
        f, Pc = csd(zl, zr, fs=1 / ds, nperseg=int(100 / ds))
        cross.append(Pc)
    P = np.mean(acc, axis=0)
    edges = np.geomspace(0.05, 10.0, 9)
    for lo, hi in zip(edges[:-1], edges[1:]):
        m = (f >= lo) & (f < hi)
        ratio = np.mean(P[m] / iso8608_psd(f[m], "C"))
        assert ratio == pytest.approx(1.0, abs=0.10), (lo, hi, ratio)
    # cross-spectrum / PSD = coherence gamma(n) at long wavelengths
    m = (f >= 0.05) & (f < 0.15)
    g = np.mean(np.real(np.mean(cross, axis=0))[m] / iso8608_psd(f[m], "C"))
    assert g == pytest.approx(np.mean(coherence(f[m], 0.2)), abs=0.1)
    # class steps: x4 in PSD per class
    _, zb, _ = iso8608_road(500.0, "B", 1, ds=ds)
    _, zd, _ = iso8608_road(500.0, "D", 1, ds=ds)
    assert np.var(zd) / np.var(zb) == pytest.approx(16.0, rel=1e-9)


def test_written_drive_gyro_noise_and_readback(tmp_path):
    sensor = TruthSensor(imu_rate_hz=500.0, gyro_noise_deg_s=(0.1, 0.07, 0.05), accel_noise_m_s2=(0.03,) * 3)
    d = make_drive(maneuver=TruthManeuver.rest(6.0), sensor=sensor, seed=11)
    p = tmp_path / "rest.mcap"
    write_drive(p, d, overwrite=True)
    e = read_drive(p)
    assert e.metadata["source"] == SOURCE and e.metadata["vehicle"] == "independent"
    assert e.metadata["damper_oil_level"] == "1,1,1,1"
    np.testing.assert_array_equal(e.imu.t_ns, d.imu.t_ns)
    np.testing.assert_allclose(e.imu.gyro, d.imu.gyro, rtol=0, atol=0)
    np.testing.assert_allclose(e.speed.values, d.speed.values)
    assert e.road is not None
    g = np.degrees(e.imu.gyro)
    for k, want in enumerate(sensor.gyro_noise_deg_s):
        assert np.sqrt(np.mean(g[:, k] ** 2)) == pytest.approx(want, rel=0.03)
        x = g[:, k] - g[:, k].mean()
        assert abs(np.dot(x[1:], x[:-1]) / np.dot(x, x)) < 0.1      # white
    assert np.sqrt(np.mean((e.imu.accel[:, 2] - 9.81) ** 2)) == pytest.approx(0.03, rel=0.03)
    truth = json.loads(e.metadata["truth"])
    assert truth["sensor"]["gyro_noise_deg_s"] == [0.1, 0.07, 0.05]
    assert truth["car"]["sprung_mass"] == 1400.0 and "friction" in truth and "hidden" in truth


def test_seeded_reproducibility_and_sensor_chain():
    sensor = TruthSensor(gyro_bias_deg_s=(0.2, -0.1, 0.05), time_offset_s=0.02, steering_offset_rad=0.01,
                         steering_resolution_rad=np.radians(0.1), jitter_s=2e-4)
    man = TruthManeuver.sine()
    a, ta = make_drive(maneuver=man, sensor=sensor, seed=5, return_truth=True)
    b = make_drive(maneuver=man, sensor=sensor, seed=5)
    c = make_drive(maneuver=man, sensor=sensor, seed=6)
    np.testing.assert_array_equal(a.imu.gyro, b.imu.gyro)
    np.testing.assert_array_equal(a.imu.t_ns, b.imu.t_ns)
    assert a.metadata == b.metadata
    assert not np.array_equal(a.imu.gyro, c.imu.gyro)
    assert a.metadata["maneuver"].startswith("sine_steer")
    # steering offset and resolution on the recorded input only
    st = a.steering.values
    assert st[0] == pytest.approx(0.01, abs=np.radians(0.05))
    assert np.allclose(st / np.radians(0.1), np.round(st / np.radians(0.1)))
    # time offset: the IMU's yaw rate lags the truth by 20 ms (cross-correlation peak)
    t = a.imu.t_ns * 1e-9
    yaw = a.imu.gyro[:, 2] - np.radians(0.05)
    lags = np.arange(-0.05, 0.0501, 0.001)
    err = [np.mean((yaw - np.interp(t - L, ta.t, ta.gyro[:, 2])) ** 2) for L in lags]
    assert lags[int(np.argmin(err))] == pytest.approx(0.02, abs=0.003)


def test_rough_road_drive_without_road_and_maneuver_names():
    d = make_drive(maneuver=TruthManeuver.rough("D", 60.0, 5.0, seed=2), record_road=False, seed=1)
    assert d.road is None and d.metadata["maneuver"].startswith("rough_road")
    assert json.loads(d.metadata["truth"])["road_class"] == "D"
    assert np.degrees(d.imu.gyro[:, 1]).std() > 0.5            # the car still drives over it
    assert TruthManeuver.bump().text().startswith("bump_crossing")
    assert TruthManeuver.brake().text().startswith("braking")


def test_braking_pitches_nose_down():
    r = simulate(maneuver=TruthManeuver.brake(speed_kmh=50.0, decel_mps2=4.0))
    q = np.degrees(r.gyro[:, 1])
    assert q[np.nonzero(np.abs(q) > 0.1)[0][0]] > 0        # pitch positive = nose down
    i = int(np.argmin(np.abs(r.t - 2.5)))
    assert r.accel[i, 0] < -3.5                             # decelerating (specific force incl. tilt)


def test_perturbed_car_records_factors():
    car = TruthCar().perturbed(np.random.default_rng(3))
    base = TruthCar()
    for name in ("sprung_mass", "roll_inertia", "pitch_inertia", "yaw_inertia", "tyre_stiffness"):
        f = car.factors[name]
        assert 0.05 <= abs(f - 1) <= 0.15
        assert getattr(car, name) == pytest.approx(getattr(base, name) * f)
    for name in ("cornering_stiffness", "wheel_rate"):
        for k in range(2):
            f = car.factors[name][k]
            assert 0.05 <= abs(f - 1) <= 0.15
            assert getattr(car, name)[k] == pytest.approx(getattr(base, name)[k] * f)
    m = body_modes(car)
    assert m["bounce"] != pytest.approx(body_modes()["bounce"], rel=1e-3)


def test_damper_curve_is_pchip_minus_own_friction():
    X, C, E, P = hydraulic_curves(TruthFriction())
    v = X[0]
    assert P[0](0.0) == 0.0 and P[0](0.001) == 0.0
    # at 0.052 m/s: measured 250 N minus 21 N * (1 + tanh(0.051/0.03))
    assert P[0](0.052) == pytest.approx(250.0 - 21.0 * (1 + np.tanh(0.051 / 0.03)), rel=1e-9)
    vv = np.linspace(v[0], v[-1], 2001)
    assert np.all(np.diff(P[0](vv)) >= -1e-9) and np.all(np.diff(P[1](vv)) >= -1e-9)


def test_hidden_physics_changes_the_response(bump_runs):
    base = bump_runs["intact"]
    visc = simulate(maneuver=TruthManeuver.bump(), hidden=TruthHidden(extra_viscous=(800.0, 800.0)))
    assert np.abs(visc.gyro[:, 1]).max() != pytest.approx(np.abs(base.gyro[:, 1]).max(), rel=1e-3)
    amp = simulate(maneuver=TruthManeuver.bump(), hidden=TruthHidden(amplitude_extra_N=(20.0, 25.0)))
    assert np.abs(amp.friction).max() > np.abs(base.friction).max() + 10.0


@pytest.mark.parametrize("law,expect", [
    ("linear", lambda v: 300.0 * v),
    ("power", lambda v: 300.0 * 0.1 * np.sign(v) * np.abs(v / 0.1) ** 0.6),
    ("bilinear", lambda v: 300.0 * np.sign(v) * np.where(np.abs(v) <= 0.06, np.abs(v),
                                                          0.06 + 0.35 * (np.abs(v) - 0.06)))])
def test_the_extra_damping_follows_its_law(law, expect):
    """The generator's hidden extra damping against the deflection velocity (central differences of the
    recorded deflection; away from reversals and samples where the velocity changes fast)."""
    ref = 0.06 if law == "bilinear" else 0.1
    r = simulate(maneuver=TruthManeuver.bump(), hidden=TruthHidden(extra_viscous=(300.0, 300.0), viscous_law=law,
                                                                   viscous_ref_m_s=ref, viscous_exponent=0.6,
                                                                   viscous_slope_ratio=0.35))
    d, h, t = np.asarray(r.deflection)[:, 0], np.asarray(r.hidden)[:, 0], np.asarray(r.t)
    v = np.gradient(d, t)
    smooth = np.abs(np.gradient(v, t)) * (t[1] - t[0]) < 1e-4
    sel = smooth & (np.abs(v) > 0.01)
    assert sel.sum() > 100 and np.abs(v[sel]).max() > 0.1
    np.testing.assert_allclose(h[sel], expect(v[sel]), rtol=0.05, atol=1.0)


def test_the_load_dependent_strut_friction_follows_its_law():
    """Rear-only strut friction mu max(F_z0 + F_t, 0) tanh(v/v_eps) against the recorded tyre load (on a
    straight drive the tyre load holds no lateral load transfer, so it is F_z0 + F_t) and the deflection
    velocity (central differences of the recorded deflection): the size exactly bounded by mu x load, the
    law where the velocity is well resolved; zero at the front."""
    mu, eps = 0.02, 0.001
    r = simulate(maneuver=TruthManeuver.bump(), oil=(1, 1, 0, 0),
                 hidden=TruthHidden(load_friction_coefficient=(0.0, mu), stribeck_eps_m_s=eps))
    h, fz, t = np.asarray(r.hidden), np.asarray(r.tyre_load), np.asarray(r.t)
    assert np.all(h[:, :2] == 0.0)
    h, fz = h[:, 2:], fz[:, 2:]
    v = np.gradient(np.asarray(r.deflection)[:, 2:], t, axis=0)
    assert np.all(np.abs(h) <= mu * fz * (1.0 + 1e-12))
    assert 50.0 < np.abs(h).max() < 150.0                    # about 62 N at the static rear load
    fast = np.abs(v) > 0.005                                 # sliding: tanh saturated, the force mu F_z
    np.testing.assert_allclose(h[fast], mu * fz[fast] * np.tanh(v[fast] / eps), rtol=1e-3, atol=0.01)
    assert fast.sum() > 1000 and fz[fast].max() > 1.4 * fz[fast].min()   # a load-dependent level
    # the regularisation, where the velocity changes slowly over a step
    smooth = np.abs(np.gradient(v, t, axis=0)) * (t[1] - t[0]) < 1e-5
    slow = smooth & (np.abs(v) > 2e-4) & (np.abs(v) < 0.003)
    assert slow.sum() > 100
    np.testing.assert_allclose(h[slow] / (mu * fz[slow]), np.tanh(v[slow] / eps), atol=0.005)


def test_the_load_dependent_strut_friction_off_is_bit_identical():
    man = TruthManeuver.bump()
    a = simulate(maneuver=man, oil=(1, 1, 0, 0))
    b = simulate(maneuver=man, oil=(1, 1, 0, 0), hidden=TruthHidden(load_friction_coefficient=(0.0, 0.0)))
    for name in ("t", "gyro", "accel", "deflection", "friction", "tyre_load", "hidden"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
