"""The reference generator (synthetic measurement vehicle) and the bundled drives in bags/."""
from pathlib import Path

import numpy as np
import pytest

from susp_sim_ros.analysis import synthetic as syn
from susp_sim_ros.analysis import validation as va
from susp_sim_ros.model import Model, get_term, load_vehicle
from susp_sim_ros.model import amplitude_friction as af
from susp_sim_ros.model.layout import C_INDEX, N_CTX
from susp_sim_ros.model.rigs import half_hysteresis_at_zero, triangle

BAGS = Path(__file__).resolve().parents[1] / "bags"


def rig_half_hysteresis(model, corner, amplitude):
    """Axle rig at 1 mm/s, +-amplitude, 3 cycles (like model/rigs.py, any amplitude)."""
    d = triangle(amplitude, 1e-5, 3)
    dd = np.sign(np.gradient(d)) * 0.001
    P = model.params()
    S = model.initial_state()
    out = np.zeros(d.size)
    fz = float(model.vehicle.static_wheel_loads()[corner])
    model.kernel.rig_run(P, S, corner, d, dd, 0.0, 0.0, fz, model.kernel.MASK_ALL, True, out)
    return half_hysteresis_at_zero(d, out)


@pytest.fixture(scope="module")
def synthetic_model():
    return Model("passat_b8_like", syn.synthetic_variant())


def test_term_is_registered_through_the_term_interface():
    t = get_term("friction_amplitude")
    assert t is syn.FRICTION_AMPLITUDE is af.FRICTION_AMPLITUDE and t.component == "axle"
    assert [p.name for p in t.params] == ["extra_level", "onset", "scale", "band", "sigma", "horizontal", "memory",
                                          "stroke_weight"]
    # the bundled generator uses the stroke-amplitude form without horizontal scaling (bags unchanged)
    setting = next(s for s in syn.synthetic_variant().terms if s.term.name == "friction_amplitude")
    assert not {"memory", "horizontal"} & set(setting.values)
    assert {p.name: p.default for p in t.params if p.name in ("memory", "horizontal")} == {"memory": 0.0,
                                                                                          "horizontal": 0.0}


@pytest.mark.parametrize("corner, amplitude, expected, tol", [
    (2, 0.005, 43.0, 0.5),   # paper: rear 43 N at small amplitude (the +-5 mm rig) - unchanged
    (2, 0.025, 65.0, 1.0),   # paper outlook: rear 65 N at large amplitude
    (0, 0.005, 60.0, 0.5),   # front at small amplitude unchanged
])
def test_rig_reads_the_papers_amplitude_dependence(synthetic_model, corner, amplitude, expected, tol):
    np.testing.assert_allclose(rig_half_hysteresis(synthetic_model, corner, amplitude), expected, atol=tol)


def test_default_model_has_no_amplitude_dependence():
    m = Model("passat_b8_like", "full")
    np.testing.assert_allclose(rig_half_hysteresis(m, 2, 0.025), rig_half_hysteresis(m, 2, 0.005), atol=0.5)


def test_level_function():
    f = af.friction_amplitude_level
    assert f(24.0, 0.005, 0.008, 0.004) == 0.0
    np.testing.assert_allclose(f(24.0, 0.005, 0.008, 1.0), 24.0)
    np.testing.assert_allclose(f(24.0, 0.005, 0.008, 0.013), 24.0 * (1 - np.exp(-1)))


def test_drive_is_reproducible_from_the_seed_and_labelled_synthetic():
    a = syn.generate_drive("bump_crossing", "rear_empty", seed=7)
    b = syn.generate_drive("bump_crossing", "rear_empty", seed=7)
    c = syn.generate_drive("bump_crossing", "rear_empty", seed=8)
    np.testing.assert_array_equal(a.imu.t_ns, b.imu.t_ns)
    np.testing.assert_array_equal(a.imu.gyro, b.imu.gyro)
    assert not np.array_equal(a.imu.gyro, c.imu.gyro)
    m = a.metadata
    assert m["source"] == syn.SOURCE and m["source"].startswith("synthetic:")
    assert "friction_amplitude" in m["hidden_physics"] and "SYNTHETIC" in m["notes"]
    assert m["damper_oil_level"] == "1,1,0,0" and m["maneuver"].startswith("bump_crossing")
    rate = va.median_rate(a.imu.t_ns)
    assert 100.0 <= rate <= 200.0 + 1e-6
    assert np.all(np.diff(a.imu.t_ns) > 0)
    # sensor noise is there, about the specified level: high-pass residual of the pitch rate at rest
    # before the bump (first 0.3 s: the car stands still on a flat road)
    quiet = (a.imu.t_ns - a.imu.t_ns[0]) < 0.3e9
    noise = np.degrees(np.std(np.diff(a.imu.gyro[quiet, 0]))) / np.sqrt(2)
    np.testing.assert_allclose(noise, syn.ImuSpec.reference().gyro_noise_deg_s, rtol=0.35)


def test_bundled_drives_are_what_the_generator_makes():
    """bags/ holds the output of `susp generate` with the seed in its metadata (byte for byte on the same
    software; to floating-point rounding across revisions of the compiled kernel)."""
    from susp_sim_ros.io.drive import read_drive
    files = sorted(BAGS.glob("*.mcap"))
    assert {f.name for f in files} >= {n for n, _, _ in syn.bundle_names()}
    assert sum(f.stat().st_size for f in files) < 5e6
    d = read_drive(BAGS / "bump_crossing_rear_empty.mcap")
    g = syn.generate_drive("bump_crossing", "rear_empty", seed=int(d.metadata["seed"]))
    np.testing.assert_array_equal(d.imu.t_ns, g.imu.t_ns)
    np.testing.assert_allclose(d.imu.gyro, g.imu.gyro, rtol=0, atol=1e-9)  # noise is 7e-4 rad/s
    np.testing.assert_array_equal(d.steering.values, g.steering.values)
    assert d.metadata["hidden_physics"] == g.metadata["hidden_physics"]


def test_amplitude_friction_is_clearly_present_in_the_rear_empty_bump_drive():
    """The discrepancy finder needs it: without the hidden term the full model fits the drive far
    better, and what it misses is well above the sensor noise."""
    from susp_sim_ros.runtime.lockstep import run_lockstep

    def rmse_full(drive):
        r = run_lockstep(drive, variant="full")
        w = va.analysis_windows(drive, load_vehicle(drive.metadata["vehicle"]).wheelbase)["bump"]
        return va.validate(drive.imu.t_ns, drive.imu.gyro, r.imu.t_ns, r.imu.gyro,
                           windows={"bump": w}).rmse_deg_s("bump", "pitch_rate")

    with_term = rmse_full(syn.generate_drive("bump_crossing", "rear_empty"))
    without = rmse_full(syn.generate_drive("bump_crossing", "rear_empty",
                                           hidden=syn.HiddenPhysics.reference().replace(amplitude_extra=(0.0, 0.0))))
    # what the hidden term alone adds (errors add in quadrature) is far above the gyro noise
    assert np.sqrt(with_term ** 2 - without ** 2) > 4 * syn.ImuSpec.reference().gyro_noise_deg_s
    assert without < 0.6 * with_term


def _amplitude_term_run(d, *, memory=0.0, horizontal=0.0, sh=1.0, dt=1e-3, extra=20.0, stroke_weight=0.0):
    """Drive corner 0 of the amplitude-friction term through deflections ``d`` [m]; its Dahl force [N] and
    remembered amplitude [m] per step."""
    p = np.zeros(4 * 8)
    p[0:4], p[4:8], p[8:12], p[12:16], p[16:20] = extra, 0.0, 0.005, 0.001, 1e5
    p[20:24], p[24:28], p[28:32] = horizontal, memory, stroke_weight
    s = np.zeros(4 * 7)
    c = np.zeros((4, N_CTX))
    c[:, C_INDEX["DT"]] = dt
    c[:, C_INDEX["SH"]] = sh
    force, amp = [], []
    prev = 0.0
    for x in d:
        af.friction_amplitude_update(p, 0, s, 0, 0, c, x - prev)
        prev = x
        force.append(s[0])
        amp.append(s[24] if memory > 0.0 else s[20])
    return np.array(force), np.array(amp)


def test_amplitude_memory_forgets_the_peak_deflection_with_its_time_constant():
    tau, dt = 0.5, 1e-3
    d = np.concatenate([np.linspace(0.0, 0.02, 200), np.full(1000, 0.0)])
    _, amp = _amplitude_term_run(d, memory=tau, dt=dt)
    assert amp[199] == pytest.approx(0.02, rel=1e-9)
    # back at the static position the remembered peak decays as exp(-t / tau)
    np.testing.assert_allclose(amp[200 + 499], 0.02 * np.exp(-500 * dt / tau), rtol=1e-6)


def test_amplitude_stroke_weight_blends_the_stroke_and_the_remembered_peak():
    """An offset stroke (from +20 mm to +10 mm and back, rebound never reaching the static position): the
    stroke amplitude is 5 mm, the peak deflection 20 mm. Weight 1 is the stroke form (memory 0), weight
    0 the peak form, weight 0.5 in between: the extra level, seen as the saturated friction force."""
    d = np.concatenate([np.linspace(0.0, 0.02, 400), np.linspace(0.02, 0.01, 400),
                        np.linspace(0.01, 0.02, 400)])
    stroke, _ = _amplitude_term_run(d, memory=0.0, dt=1e-4)
    peak, _ = _amplitude_term_run(d, memory=100.0, stroke_weight=0.0, dt=1e-4)
    as_stroke, _ = _amplitude_term_run(d, memory=100.0, stroke_weight=1.0, dt=1e-4)
    half, _ = _amplitude_term_run(d, memory=100.0, stroke_weight=0.5, dt=1e-4)
    np.testing.assert_allclose(as_stroke, stroke, rtol=1e-12, atol=1e-12)
    assert stroke[-1] == pytest.approx(20.0 * (1.0 - np.exp(-0.005 / 0.005)), rel=1e-3)
    assert peak[-1] == pytest.approx(20.0 * (1.0 - np.exp(-0.02 / 0.005)), rel=1e-3)
    assert half[-1] == pytest.approx(20.0 * (1.0 - np.exp(-0.0125 / 0.005)), rel=1e-3)


def test_amplitude_level_follows_the_axle_horizontal_scaling_when_asked():
    d = np.linspace(0.0, 0.05, 2000)  # one long stroke: the Dahl element saturates at its level
    plain, _ = _amplitude_term_run(d, memory=1.0, horizontal=0.0, sh=1.8)
    scaled, _ = _amplitude_term_run(d, memory=1.0, horizontal=1.0, sh=1.8)
    level = 20.0 * (1.0 - np.exp(-0.05 / 0.005))
    assert plain[-1] == pytest.approx(level, rel=1e-3)
    assert scaled[-1] == pytest.approx(1.8 * level, rel=1e-3)
