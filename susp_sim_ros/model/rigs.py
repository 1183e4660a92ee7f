"""Virtual test rigs: the paper's measurement procedures run on the model's own force elements.

- Axle friction rig (Suspension Motion Simulator, paper Fig. 2): body held, wheel carrier moved along a
  1 mm/s triangular ramp of +-5 mm with optional quasi-static horizontal forces; the suspension force
  (spring + damper + every friction term) is recorded and half the hysteresis width at zero deflection
  is the friction (paper: 60 N front, 43 N rear).
- Damper hydropulser (paper Fig. 3): the damper alone (hydraulic curve + damper friction terms), a 1 mm/s
  ramp for the friction (paper: 22/29 N front, 10/20 N rear, intact/oil-empty) and sinusoids at 17 peak
  velocities for the force-velocity curve (force at peak velocity).

Both call the same compiled force functions as the vehicle (``rig_run`` in the kernel).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import yaml

from ..errors import ConfigError
from .layout import N_U, U_INDEX
from .params import config_dir
from .vehicle import Model, check_oil, simulate_batch

AXLE_CORNER = {"front": 0, "rear": 2}  # the left wheel of the axle


def _rig_config(kind: str) -> dict:
    path = config_dir() / "rigs.yaml"
    try:
        cfg = yaml.safe_load(path.read_text())[kind]
        return {k: v["value"] for k, v in cfg.items()}
    except (OSError, KeyError, TypeError, yaml.YAMLError) as exc:
        raise ConfigError(f"{path}: cannot read rig procedure '{kind}': {exc}") from None


def _corner(axle: str) -> int:
    if axle not in AXLE_CORNER:
        raise ConfigError(f"--axle: expected front or rear, got {axle!r}")
    return AXLE_CORNER[axle]


def triangle(amplitude: float, step: float, cycles: int) -> np.ndarray:
    """Deflection samples of a triangular ramp 0 -> +A -> -A -> ... -> 0 in increments ``step``."""
    n_q = int(round(amplitude / step))
    up = np.linspace(0.0, amplitude, n_q + 1)
    cycle = np.concatenate([up[:-1], amplitude - 2 * up[:-1], -amplitude + up[:-1]])
    return np.concatenate([np.tile(cycle, cycles), [0.0]])


def half_hysteresis_at_zero(d: np.ndarray, f: np.ndarray) -> float:
    """Half the force gap between the rising and falling branches at d = 0, in the last cycle."""
    rising = np.nonzero((d[:-1] < 0) & (d[1:] >= 0))[0]
    falling = np.nonzero((d[:-1] > 0) & (d[1:] <= 0))[0]
    if len(rising) == 0 or len(falling) == 0:
        raise ValueError("the ramp never crosses zero deflection in both directions")

    def at_zero(k):
        w = -d[k] / (d[k + 1] - d[k])
        return f[k] + w * (f[k + 1] - f[k])

    return 0.5 * (at_zero(rising[-1]) - at_zero(falling[-1]))


@dataclass
class RigResult:
    half_hysteresis_N: float
    deflection: np.ndarray
    force: np.ndarray
    force_velocity: list | None = None


def _run(model: Model, corner: int, d: np.ndarray, dd: np.ndarray, oil, fx, fy, mask, with_spring):
    P = model.params(check_oil(oil, "--oil"))
    S = model.initial_state()
    out = np.zeros(d.size)
    fz = float(model.vehicle.static_wheel_loads()[corner])
    model.kernel.rig_run(P, S, corner, d, dd, float(fx), float(fy), fz, mask, with_spring, out)
    return out


def axle_rig(model: Model, axle: str, fx: float = 0.0, fy: float = 0.0,
             oil=(1.0, 1.0, 1.0, 1.0)) -> RigResult:
    """Axle friction rig on the left wheel of ``axle`` with quasi-static wheel forces fx, fy [N]."""
    c = _rig_config("axle")
    d = triangle(c["amplitude"], c["sample_step"], int(c["cycles"]))
    dd = np.sign(np.gradient(d)) * c["ramp_speed"]
    f = _run(model, _corner(axle), d, dd, oil, fx, fy, model.kernel.MASK_ALL, True)
    return RigResult(half_hysteresis_at_zero(d, f), d, f)


def damper_rig(model: Model, axle: str, oil_level: float = 1.0) -> RigResult:
    """Damper hydropulser for one damper of ``axle`` at oil level ``oil_level`` (1 intact, 0 empty):
    the 1 mm/s friction ramp and the force-velocity curve from sinusoids at the configured peak
    velocities (force at the peak velocity, both directions), sorted by velocity."""
    c = _rig_config("damper")
    corner = _corner(axle)
    oil = [1.0] * 4
    oil[corner] = oil_level
    mask = model.kernel.MASK_DAMPER
    d = triangle(c["amplitude"], c["sample_step"], int(c["cycles"]))
    dd = np.sign(np.gradient(d)) * c["ramp_speed"]
    f = _run(model, corner, d, dd, oil, 0.0, 0.0, mask, False)
    table = []
    amp, n_per, periods = c["sine_amplitude"], int(c["sine_samples_per_period"]), int(c["sine_periods"])
    phase = 2 * np.pi * np.arange(periods * n_per + 1) / n_per
    for vp in c["sine_peak_velocities"]:
        fs = _run(model, corner, amp * np.sin(phase), vp * np.cos(phase), oil, 0.0, 0.0, mask, False)
        last = (periods - 1) * n_per
        table.append([float(vp), float(fs[last])])                 # d = 0 rising: peak +v
        table.append([-float(vp), float(fs[last + n_per // 2])])   # d = 0 falling: peak -v
    table.sort()
    return RigResult(half_hysteresis_at_zero(d, f), d, f, table)


def plot_loops(results: dict[str, RigResult], path, title: str) -> None:
    """Force over deflection of each rig run (hysteresis loops) as a PNG."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for label, r in results.items():
        n = r.deflection.size // 2  # last cycle
        ax.plot(1e3 * r.deflection[n:], r.force[n:], label=f"{label}: {r.half_hysteresis_N:.1f} N")
    ax.set_xlabel("deflection [mm] (bump +)")
    ax.set_ylabel("force [N]")
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# ---- EUSAMA / phase-shift wheel-plate bench -----------------------------------------------------------
WHEELS = ("FL", "FR", "RL", "RR")


@dataclass
class PlateMotion:
    """The documented bench input: the wheel-plate height [m] at times ``t`` [s] (its rate is taken by
    the model from successive samples) and the instantaneous plate frequency [Hz] and phase [rad]
    (``z = amplitude(t) * sin(phase)``). One plate moves at a time; the other three wheels stand on
    still plates."""

    t: np.ndarray
    z: np.ndarray
    frequency_hz: np.ndarray
    phase: np.ndarray
    sweep_start: int  # first sample of the sweep (after the settling dwell at the start frequency)


def eusama_plate_motion(cfg: dict | None = None) -> PlateMotion:
    """The EUSAMA plate motion of ``config/rigs.yaml`` ``eusama``: ``settle_duration`` at
    ``start_frequency`` (amplitude ramped in over its first half), then a linear sweep down to
    ``end_frequency`` over ``sweep_duration``, at ``plate_amplitude``."""
    c = _rig_config("eusama") if cfg is None else cfg
    dt, f0, f1 = c["step"], c["start_frequency"], c["end_frequency"]
    n_settle = int(round(c["settle_duration"] / dt))
    n_sweep = int(round(c["sweep_duration"] / dt))
    t = dt * np.arange(n_settle + n_sweep)
    f = np.full(t.size, f0)
    ts = t[n_settle:] - t[n_settle]
    f[n_settle:] = f0 + (f1 - f0) * ts / c["sweep_duration"]
    phase = 2 * np.pi * np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * dt)])
    amp = np.full(t.size, c["plate_amplitude"])
    ramp = max(n_settle // 2, 1)
    amp[:ramp] *= 0.5 * (1 - np.cos(np.pi * np.arange(ramp) / ramp))
    return PlateMotion(t, amp * np.sin(phase), f, phase, n_settle)


@dataclass
class PlateResult:
    """One wheel on the plate: EUSAMA %, minimum phase angle [deg], resonance [Hz] and per-cycle curves
    (cycle frequency [Hz], dynamic contact-force amplitude [N], phase angle [deg])."""

    eusama_percent: float
    phase_min_deg: float
    resonance_hz: float
    static_load_N: float
    freq_hz: np.ndarray
    force_amp_N: np.ndarray
    phase_deg: np.ndarray


def _per_cycle(pm: PlateMotion, fdyn: np.ndarray):
    """Amplitude [N] and phase angle [deg] of the dynamic contact force against the plate motion, one
    value per whole plate cycle of the sweep (``fdyn ~ a sin(phase) + b cos(phase)`` by projection)."""
    k = np.floor(pm.phase / (2 * np.pi)).astype(np.int64)
    sel = np.arange(pm.t.size) >= pm.sweep_start
    k, ph, f, fd = k[sel], pm.phase[sel], pm.frequency_hz[sel], fdyn[sel]
    k = k - k[0]
    n = np.bincount(k).astype(float)
    a = 2 * np.bincount(k, fd * np.sin(ph)) / n
    b = 2 * np.bincount(k, fd * np.cos(ph)) / n
    freq = np.bincount(k, f) / n
    whole = slice(1, len(n) - 1)  # whole cycles only
    a, b, freq = a[whole], b[whole], freq[whole]
    # force leads the plate displacement by atan2(b, a); the phase-shift method's angle is 180 deg minus
    # that lead (180 deg when the plate drives the tyre above resonance, falling to its minimum just below
    # the wheel resonance, lower the weaker the damping); unsigned: the angle between the two phasors (a
    # wheel that lifts off can push it past 180 deg)
    lead = np.degrees(np.arctan2(b, a))
    return freq, np.hypot(a, b), np.abs((180.0 - lead + 180.0) % 360.0 - 180.0)


def eusama_bench(model: Model, oil=(1.0, 1.0, 1.0, 1.0), wheels=WHEELS,
                 plate: PlateMotion | None = None, P: np.ndarray | None = None) -> dict[str, PlateResult]:
    """The EUSAMA and phase-shift tests on the full five-mass model standing still on four plates
    (per-wheel road heights, the four-poster input): each wheel's plate in turn moves by ``plate``
    (default :func:`eusama_plate_motion`), the others stay still, as on a real tester (one axle at a
    time, one wheel after the other). EUSAMA % = minimum total contact force over the sweep / static
    wheel load x 100; phase angle as in :func:`_per_cycle`; resonance = the cycle of largest dynamic
    contact-force amplitude. ``P``: a parameter vector to use instead of ``model.params(oil)``."""
    oil = check_oil(oil, "--oil")
    pm = eusama_plate_motion() if plate is None else plate
    dt = float(pm.t[1] - pm.t[0])
    U = np.zeros((len(wheels), pm.t.size, N_U))
    for r, w in enumerate(wheels):
        U[r, :, U_INDEX["ZR_IN"] + WHEELS.index(w)] = pm.z
    P = np.repeat((model.params(oil) if P is None else P)[None], len(wheels), axis=0)
    labels = [f"F_Z_{w}" for w in wheels]
    res = simulate_batch(model, P, U, dt=dt, roads=(None,), u_row=np.arange(len(wheels)),
                         outputs=labels)
    Y, done = res.values, res.steps_done
    if np.any(done < pm.t.size):
        raise RuntimeError("EUSAMA bench: the simulation diverged")
    fz0 = model.vehicle.static_wheel_loads()
    out = {}
    for r, w in enumerate(wheels):
        i = WHEELS.index(w)
        fz = Y[r, :, r]
        # outputs are recorded after each step: sample k belongs to the plate height of input row k
        sweep = fz[pm.sweep_start:]
        f, amp, ph = _per_cycle(pm, fz - fz0[i])
        out[w] = PlateResult(float(100.0 * sweep.min() / fz0[i]), float(ph.min()), float(f[np.argmax(amp)]),
                             float(fz0[i]), f, amp, ph)
    return out


def plot_eusama(results: dict[str, PlateResult], path, title: str) -> None:
    """Dynamic contact-force amplitude and phase angle over the plate frequency per wheel (PNG)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(6.4, 6.0), sharex=True)
    for w, r in results.items():
        a1.plot(r.freq_hz, 100 * r.force_amp_N / r.static_load_N,
                label=f"{w}: EUSAMA {r.eusama_percent:.0f} %, res. {r.resonance_hz:.1f} Hz")
        a2.plot(r.freq_hz, r.phase_deg, label=f"{w}: min {r.phase_min_deg:.0f} deg")
    a1.set_ylabel("dyn. contact force amplitude [% static]")
    a2.set_ylabel("phase angle [deg]")
    a2.set_xlabel("plate frequency [Hz]")
    for a in (a1, a2):
        a.grid(True, alpha=0.3)
        a.legend(fontsize=8)
    a1.set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
