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
from .params import config_dir
from .vehicle import Model, check_oil

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
