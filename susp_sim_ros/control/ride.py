"""Ride runs: the car driven straight at constant speed over a seeded ISO 8608 random road with a damper
controller in the loop (in-process, the node's :class:`~susp_sim_ros.model.vehicle.Stepper`), and its
ride and road-holding metrics (:mod:`susp_sim_ros.control.ride_metrics`).

The controller samples the outputs every ``controllers.sample_time`` and its command acts from the next
sample on (one sample of computation delay), then through the valve lag. ``passive`` sends no command:
the run is the passive model's, bit for bit. Metrics start once the rear axle has passed the road's
fade-in plus ``ride_maneuver.settle_time`` (config/semiactive.yaml).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from collections.abc import Sequence

import numpy as np

from ..errors import SuspInputError
from ..model.iso8608 import CLASSES, faded_road
from ..model.layout import OUTPUT_LABELS
from ..model.semiactive import number, semiactive_config
from ..model.vehicle import INTACT, Model, Stepper
from ..control.ride_metrics import RideMetrics, ride_metrics
from .controllers import load_controller_params, make_controller, measurement_from_outputs

_INDEX = {k: i for i, k in enumerate(OUTPUT_LABELS)}


@dataclass(frozen=True)
class RideSpec:
    road_class: str
    speed: float      # m/s
    duration: float   # s
    seed: int = 0


@dataclass(frozen=True)
class RideRun:
    """A ride run's result: its :class:`~.ride_metrics.RideMetrics` over the metrics window and how the
    run went; :meth:`to_dict` gives the JSON keys (the metrics', then these), in this order."""

    metrics: RideMetrics
    t_start_s: float                         #: start of the metrics window [s]
    samples: int                             #: samples in the metrics window [-]
    mean_command: dict[str, float] | None    #: mean valve command per wheel [-]; None when passive

    def to_dict(self) -> dict:
        """The JSON object."""
        return {**self.metrics.to_dict(), "t_start_s": self.t_start_s, "samples": self.samples,
                "mean_command": None if self.mean_command is None else dict(self.mean_command)}


def parse_road(text: str) -> str:
    """``iso8608:C`` -> ``"C"`` (classes A-H)."""
    kind, _, cls = str(text).partition(":")
    if kind != "iso8608" or cls.upper() not in CLASSES or len(cls) != 1:
        raise SuspInputError(f"--road: expected iso8608:CLASS with CLASS one of {', '.join(CLASSES)}, got {text!r}")
    return cls.upper()


def run_ride(model: Model, spec: RideSpec, *, controller: str = "passive", oil: Sequence[float] | np.ndarray = INTACT,
             step_s: float = 0.001, config: str | Path | None = None) -> RideRun:
    """Drive ``spec`` with ``controller`` (``step_s`` [s]); returns the ride metrics with the metrics
    window start, its samples and the mean command per wheel (None when passive)."""
    if not (np.isfinite(spec.speed) and 1.0 <= spec.speed <= 70.0):
        raise SuspInputError(f"--speed: expected 3.6-252 km/h, got {spec.speed * 3.6:g} km/h")
    path, cfg = semiactive_config(config)
    fade = number(path, cfg, "ride_maneuver", "fade_in", positive=True)
    settle = number(path, cfg, "ride_maneuver", "settle_time")
    spacing = number(path, cfg, "ride_maneuver", "road_spacing", positive=True)
    vp = model.vehicle
    t_start = (fade + vp.wheelbase) / spec.speed + settle
    if not (np.isfinite(spec.duration) and spec.duration > t_start + 1.0 and spec.duration <= 3600.0):
        raise SuspInputError(f"--duration: expected more than {t_start + 1.0:.1f} s (start transient at this "
                             f"speed) and at most 3600 s, got {spec.duration:g} s")
    road = faded_road(spec.road_class, spec.speed * spec.duration + fade, seed=int(spec.seed), fade_in=fade,
                      spacing=spacing)
    params = load_controller_params(config)
    ctrl = make_controller(controller, vp, model.dampers, params)
    n_ctrl = max(int(round(params.sample_time / step_s)), 1)
    n_total = int(round(spec.duration / step_s))
    st = Stepper(model, dt=step_s, road=road, oil=oil)
    blocks, cmds = [], []
    cmd = None
    done = 0
    while done < n_total and st.healthy:
        n = min(n_ctrl, n_total - done)
        if cmd is not None and not st.semi_active:
            st.set_semi_active(True, cmd)
        y = st.advance(n, spec.speed, 0.0, 0.0, None, cmd)
        blocks.append(st.block.copy())
        done += n
        cmd = ctrl(measurement_from_outputs(y, _INDEX))
        if cmd is not None:
            cmds.append(cmd)
    if not st.healthy:
        raise SuspInputError(f"ride run diverged at {done * step_s:.3f} s (controller {controller})")
    Y = np.vstack(blocks)
    k0 = int(round(t_start / step_s))
    ys = {k: Y[k0:, _INDEX[k]] for k in ("AZ_SF", "ROLL_RATE", "PITCH_RATE")}
    for w in ("FL", "FR", "RL", "RR"):
        ys[f"F_Z_{w}"] = Y[k0:, _INDEX[f"F_Z_{w}"]]
        ys[f"DEFL_{w}"] = Y[k0:, _INDEX[f"DEFL_{w}"]]
    corner = lambda pair: [pair[a] for a in (0, 0, 1, 1)]  # noqa: E731
    metrics = ride_metrics(ys, 1.0 / step_s, gravity=vp.gravity, static_loads=vp.static_wheel_loads(),
                           bump_travel=corner(vp.bump_stop_travel), rebound_travel=corner(vp.rebound_stop_travel))
    mean_command = dict(zip(("FL", "FR", "RL", "RR"), np.mean(cmds, axis=0).tolist())) if cmds else None
    return RideRun(metrics, t_start, int(Y.shape[0] - k0), mean_command)
