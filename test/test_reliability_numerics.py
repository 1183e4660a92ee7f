"""Numerics beyond test_numerics.py (the paper maneuvers): the virtual test rigs and the bundled drives
(through the lockstep runner, i.e. the node's core) stay finite and bounded and agree for integration
steps from 0.25 ms to 2 ms; and the divergence guard: an absurd vehicle or an injected state stops the
core, the offline runner, ``susp sim`` (exit 1) and the node (ERROR on /diagnostics, nothing non-finite
published or recorded, exit code 1 after finalising its recording) cleanly.

Rigs: their procedures are position-driven (1 mm/s ramps, sinusoids); a time step dt corresponds to a
deflection increment ``ramp_speed * dt`` and ``period / dt`` samples per sine period. The procedures of
``model/rigs.py`` are re-run here with those increments through the same compiled ``rig_run``.
"""
from __future__ import annotations

import subprocess
import time
from pathlib import Path

import numpy as np
import pytest
import yaml

from susp_sim_ros.io.drive import read_drive
from susp_sim_ros.runtime.lockstep import run_lockstep
from susp_sim_ros.model.rigs import _rig_config, axle_rig, damper_rig, half_hysteresis_at_zero, triangle
from susp_sim_ros.model.vehicle import check_oil
from susp_sim_ros.runtime.sim_core import OUTPUT_ENVELOPE, SimCore

ROOT = Path(__file__).resolve().parents[1]
STEPS = (0.00025, 0.0005, 0.001, 0.002)
AXLE_CORNER = {"front": 0, "rear": 2}


def _rig_run(model, corner, d, dd, oil, fx, fy, mask, with_spring):
    P = model.params(check_oil(oil))
    S = model.initial_state()
    out = np.zeros(d.size)
    fz = float(model.vehicle.static_wheel_loads()[corner])
    model.kernel.rig_run(P, S, corner, d, dd, float(fx), float(fy), fz, mask, with_spring, out)
    return out


def test_rigs_at_every_step(models):
    """Axle rig (with and without horizontal forces) and hydropulser (friction ramp, force-velocity at
    17 peak velocities) at 0.25-2 ms: finite and within 1 % (force-velocity: 2 % or 1 N) of the
    configured procedure."""
    ca, cd = _rig_config("axle"), _rig_config("damper")
    worst = {}
    for var in ("full",):  # the other variants run the same compiled terms with other switches
        model = models[var]
        for axle, corner in AXLE_CORNER.items():
            for fx, fy in ((0.0, 0.0), (1000.0, 0.0), (0.0, 1000.0)):
                ref = axle_rig(model, axle, fx, fy).half_hysteresis_N
                for dt in STEPS:
                    d = triangle(ca["amplitude"], ca["ramp_speed"] * dt, int(ca["cycles"]))
                    dd = np.sign(np.gradient(d)) * ca["ramp_speed"]
                    f = _rig_run(model, corner, d, dd, (1, 1, 1, 1), fx, fy, model.kernel.MASK_ALL, True)
                    assert np.all(np.isfinite(f)) and np.abs(f).max() < 1e4
                    h = half_hysteresis_at_zero(d, f)
                    assert h == pytest.approx(ref, rel=0.01), (var, axle, fx, fy, dt, h, ref)
                    worst["axle"] = max(worst.get("axle", 0.0), abs(h / ref - 1))
            for oil_level in (1.0, 0.0):
                ref = damper_rig(model, axle, oil_level)
                oil = [1.0] * 4
                oil[corner] = oil_level
                mask = model.kernel.MASK_DAMPER
                for dt in STEPS:
                    d = triangle(cd["amplitude"], cd["ramp_speed"] * dt, int(cd["cycles"]))
                    dd = np.sign(np.gradient(d)) * cd["ramp_speed"]
                    f = _rig_run(model, corner, d, dd, oil, 0, 0, mask, False)
                    assert np.all(np.isfinite(f))
                    assert half_hysteresis_at_zero(d, f) == pytest.approx(ref.half_hysteresis_N, rel=0.01)
                    amp, periods = cd["sine_amplitude"], int(cd["sine_periods"])
                    table = dict((v, fv) for v, fv in ref.force_velocity)
                    for vp in cd["sine_peak_velocities"]:
                        n_per = 4 * int(round(2 * np.pi * amp / vp / dt / 4))  # whole period in steps of dt
                        phase = 2 * np.pi * np.arange(periods * n_per + 1) / n_per
                        fs = _rig_run(model, corner, amp * np.sin(phase), vp * np.cos(phase), oil, 0, 0, mask, False)
                        assert np.all(np.isfinite(fs))
                        last = (periods - 1) * n_per
                        for v, got in ((vp, fs[last]), (-vp, fs[last + n_per // 2])):
                            want = table[v]
                            assert abs(got - want) <= max(1.0, 0.02 * abs(want)), (var, axle, oil_level, dt, v, got,
                                                                                   want)
                            worst["damper"] = max(worst.get("damper", 0.0), abs(got - want) / max(abs(want), 1.0))
    print(f"\nrigs at dt {STEPS}: worst relative deviation from the configured procedure {worst}")


@pytest.fixture(scope="module")
def drives():
    return {p.stem: read_drive(p) for p in sorted((ROOT / "bags").glob("*.mcap"))}


def test_bundled_drives_through_lockstep_at_every_step(drives, models):
    """Every bundled drive, every friction variant, steps 0.25/0.5/1/2 ms through the node's core:
    healthy, finite, bounded, and within 3 % (RMSE relative to the peak) of the 1 ms run."""
    worst = 0.0
    n_runs = 0
    for name, drive in drives.items():
        main = 1 if name.startswith("bump") else 0  # pitch rate on the bump, roll rate on the steer
        for var, model in models.items():
            ref = None
            for dt in (0.001,) + tuple(s for s in STEPS if s != 0.001):
                r = run_lockstep(drive, model=model, step_s=dt)
                n_runs += 1
                assert r.healthy and not r.diverged and not r.rejections, (name, var, dt, r.diverged)
                assert np.all(np.isfinite(r.values)) and np.all(np.abs(r.values) <= OUTPUT_ENVELOPE)
                g = r.imu.gyro
                assert np.abs(g).max() < 1.0 and np.abs(r["DEFL_FL"]).max() < 0.15 and r["F_Z_RL"].min() >= 0
                if ref is None:
                    ref = g
                    continue
                n = min(len(ref), len(g))
                err = np.sqrt(np.mean((g[:n, main] - ref[:n, main]) ** 2)) / np.abs(ref[:, main]).max()
                assert err < 0.03, (name, var, dt, err)
                worst = max(worst, err)
    print(f"\nbundled drives: {n_runs} lockstep runs ({len(drives)} drives x {len(models)} variants x "
          f"{len(STEPS)} steps), worst relative RMSE vs 1 ms {worst:.4f}")


# ---- divergence guard ---------------------------------------------------------------------------------
def absurd_vehicle(tmp_path) -> Path:
    """The reference car with 1 g wheels: wheel hop at ~2.5 kHz, far beyond what a 1 ms step resolves."""
    src = ROOT / "config" / "vehicles" / "passat_b8_like.yaml"
    data = yaml.safe_load(src.read_text())
    data["name"] = "absurd_light_wheels"
    data["body"]["unsprung_mass"]["value"] = {"front": 0.001, "rear": 0.001}
    out = tmp_path / "absurd_light_wheels.yaml"
    out.write_text(yaml.safe_dump(data))
    return out


def test_guard_stops_the_core_on_an_injected_state(model_full):
    core = SimCore(model_full)
    core.set_speed(1_000_000_000, 10.0)
    core.advance_to(1_000_000_000)
    good = core.advance_to(1_100_000_000)
    assert len(good) == 10 and core.healthy
    core.stepper.S[:3] = 1e200  # an exploded state
    out = core.advance_to(1_500_000_000)
    assert out == [] and not core.healthy and "diverged" in core.diverged
    assert core.advance_to(2_000_000_000) == []  # stays stopped
    assert all(np.all(np.isfinite(s.y)) for s in good)


def test_guard_stops_lockstep_and_susp_sim_on_an_absurd_vehicle(tmp_path, capsys):
    from susp_sim_ros.cli.main import main
    from susp_sim_ros.runtime.lockstep import maneuver_drive
    from susp_sim_ros.model.maneuvers import bump_crossing
    veh = absurd_vehicle(tmp_path)
    drive = maneuver_drive(bump_crossing(), rate_hz=100.0)
    r = run_lockstep(drive, vehicle=str(veh), variant="full", out_path=tmp_path / "a.mcap")
    assert not r.healthy and "diverged" in r.diverged
    assert np.all(np.isfinite(r.values)) and np.all(np.abs(r.values) <= OUTPUT_ENVELOPE)
    from test_reliability_files import read_recording  # noqa: F401  (same reader)
    from _reliability_helpers import recorded_sim_numbers
    n, bad = recorded_sim_numbers(tmp_path / "a.mcap")
    assert bad == 0 and n == 3 * len(r.t_ns)
    rc = main(["sim", "--maneuver", "bump", "--config", str(veh), "--out", str(tmp_path / "b.mcap")])
    err = capsys.readouterr().err
    assert rc == 1 and "simulation diverged" in err and "Traceback" not in err
    print(f"\nabsurd vehicle: {r.diverged}")


def test_node_in_process_reports_error_and_publishes_nothing_after(tmp_path):
    """In-process node (sim time, on_divergence hold): an injected state trips the guard; nothing more is
    published, /diagnostics says ERROR with the reason; a restart from rest (replay loop) recovers."""
    from _reliability_helpers import CheckingPublisher
    from _ros_helpers import SimDriver
    d = SimDriver({"on_divergence": "hold", "record_path": str(tmp_path / "n.mcap")})
    try:
        node = d.node
        diag = CheckingPublisher("diag")
        node.pub_diag = diag
        sent = []
        diag.publish = lambda m, _p=diag.publish: (sent.append(m), _p(m))
        d.clock(1_000_000_000)
        d.send_value("/vehicle/speed", 10.0)
        d.clock(1_200_000_000)
        n0 = node.published
        assert n0 == 20
        with node.lock:
            node.core.stepper.S[:3] = np.nan
        d.clock(1_500_000_000)
        assert node.published == n0 and not node.core.healthy and node.failure
        model = [s for s in sent[-1].status if s.name.endswith(": model")][0]
        assert model.level == b"\x02" and "diverged" in model.message  # published at once, ERROR
        assert node.divergences == 1
        d.clock(3_000_000_000)
        assert node.published == n0  # still nothing
        d.clock(2_000_000_000)  # time back by 1 s: a restart from rest
        d.clock(2_100_000_000)
        assert node.core.healthy and node.published == n0 + 10
    finally:
        d.close()
    from _reliability_helpers import recorded_sim_numbers
    n, bad = recorded_sim_numbers(tmp_path / "n.mcap")
    assert bad == 0 and n == 3 * (n0 + 10)


@pytest.mark.slow
def test_node_process_with_an_absurd_vehicle_exits_1_after_an_error_diagnostic(tmp_path):
    """The node as a process (wall time, on_divergence exit): ERROR on /diagnostics (received here),
    exit code 1 within seconds, a finalised recording without a single non-finite /sim value."""
    import importlib.util
    spec = importlib.util.spec_from_file_location("bench_soak", ROOT / "benchmarks" / "bench_soak.py")
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    env = bench.ros_env()
    probe = bench.Probe(100.0, realtime=False)
    rec = tmp_path / "absurd.mcap"
    proc = bench.start_node(rec, {"vehicle": str(absurd_vehicle(tmp_path)), "realtime_priority": 0}, env=env,
                            log=subprocess.PIPE)
    try:
        probe.wait_for(proc)
        probe.start_publishing()
        t0 = time.monotonic()
        code = proc.wait(timeout=60)
        took = time.monotonic() - t0
        out = proc.stdout.read().decode(errors="replace")
        end = time.monotonic() + 2
        while time.monotonic() < end and probe.diag.get("model", {}).get("diverged", "") == "":
            time.sleep(0.05)
    finally:
        if proc.poll() is None:
            proc.kill()
        probe.close()
    assert code == 1, out[-2000:]
    assert "stopped: simulation diverged" in out and "Traceback" not in out
    assert "simulation diverged" in probe.diag["model"]["diverged"]
    from _reliability_helpers import recorded_sim_numbers
    from susp_sim_ros.io.reader import read_recording
    r = read_recording(rec)
    assert r.finalised and not r.truncated
    n, bad = recorded_sim_numbers(rec)
    assert bad == 0
    print(f"\nnode with an absurd vehicle: exit {code} {took:.1f} s after the inputs started, {n} finite /sim "
          f"messages recorded, ERROR diagnostic received: {probe.diag['model']['diverged'][:120]}")
