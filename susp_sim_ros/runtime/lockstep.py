"""Offline "lockstep" runs: a recorded test drive through the node's :class:`SimCore`, without DDS.

The recorded input messages are fed in log-time order into the same core the node uses (step to the
message time, then apply the input), so the outputs equal what the node publishes when the recording is
replayed with ``/clock`` (sim time), at any replay rate. With ``out_path`` the simulated MCAP is written:
the inputs received, every ``/sim`` topic and the ``test_drive`` metadata with ``source:
simulated:<variant>`` (the node's recording holds the same, plus ``/diagnostics``).
"""
from __future__ import annotations

import dataclasses
import logging
import os
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ..control.controllers import load_controller_params, make_controller, measurement_from_outputs
from ..io import messages as M
from ..io.drive import DAMPER_COMMAND, ROAD_PROFILE, SPEED, STEERING, WHEEL_HEIGHTS, ImuSeries, Series, TestDrive
from ..io.recorder import McapRecorder
from ..model.layout import OUTPUT_LABELS, output_index
from ..model.response import Response
from ..model.maneuvers import Maneuver
from ..model.paper import IMU_OUTPUTS
from ..model.vehicle import Model
from .sim_core import SimCore, sample_messages
from ..model.params import DEFAULT_VEHICLE

log = logging.getLogger(__name__)

_GYRO = [output_index(k) for k in IMU_OUTPUTS[:3]]
_ACC = [output_index(k) for k in IMU_OUTPUTS[3:]]

_ROAD, _SPEED, _STEER, _WH, _CMD = 0, 1, 2, 3, 4


@dataclass(eq=False)
class LockstepRun:
    """A recorded drive run through the node's core: the :class:`Response` of every output at the publish
    ticks (``response``; its ``t`` [s] from the drive's first input, ``t_ns`` the ROS times) and what only
    such a run has: ``imu`` (the ``/sim/imu/data`` samples), ``metadata`` (the simulated recording's
    ``test_drive`` record), ``healthy``/``diverged`` (the divergence guard: False and why when it stopped
    the core), ``rejections`` (inputs the core refused, by topic) and ``out_path`` (the simulated MCAP).
    The response's signals read through: ``run["pitch_rate"]``, ``run.t``, ``run.values``, ``len(run)``."""

    response: Response
    imu: ImuSeries
    metadata: dict[str, str] = field(default_factory=dict)
    healthy: bool = True
    diverged: str = ""
    rejections: dict[str, int] = field(default_factory=dict)
    out_path: str | None = None

    def __getitem__(self, label: str) -> np.ndarray:
        return self.response[label]

    def __contains__(self, label: object) -> bool:
        return label in self.response

    def __len__(self) -> int:
        return len(self.response)

    @property
    def t(self) -> np.ndarray:
        """Sample times [s] since the drive's first input."""
        return self.response.t

    @property
    def t_ns(self) -> np.ndarray:
        """ROS times of the samples [ns]."""
        assert self.response.t_ns is not None
        return self.response.t_ns

    @property
    def values(self) -> np.ndarray:
        return self.response.values

    @property
    def labels(self) -> tuple[str, ...]:
        return self.response.labels

    @property
    def ok(self) -> bool:
        """The run stayed healthy to the drive's end."""
        return self.healthy and self.response.ok


def simulated_metadata(drive_meta: dict[str, str], vehicle: str, variant: str,
                       oil: Sequence[float] | np.ndarray) -> dict[str, str]:
    meta = {str(k): str(v) for k, v in drive_meta.items()}
    if "source" in meta:
        meta["input_source"] = meta["source"]
    meta.update({"vehicle": str(vehicle), "friction_variant": str(variant),
                 "damper_oil_level": ",".join(f"{float(x):g}" for x in oil),
                 "source": f"simulated:{variant}"})
    meta.setdefault("maneuver", "")
    return meta


def _events(drive: TestDrive) -> list[tuple[int, int, int]]:
    """(t_ns, kind, index) of every input message, in log-time order (road profile first at t0)."""
    ev: list[tuple[int, int, int]] = []
    if drive.road is not None:
        ev.append((drive.t0_ns, _ROAD, 0))
    for kind, s in ((_SPEED, drive.speed), (_STEER, drive.steering), (_WH, drive.wheel_heights),
                    (_CMD, drive.damper_command)):
        if s is not None:
            ev.extend(zip(s.t_ns.tolist(), [kind] * len(s), range(len(s))))
    ev.sort(key=lambda e: (e[0], e[1]))
    return ev


def _controller_in_loop(controller: str | None, model: Model, core: SimCore):
    """The library damper controller run on every output sample (None for ``None`` or ``"passive"``)."""
    if controller in (None, "passive"):
        return None
    params = dataclasses.replace(load_controller_params(), sample_time=core.period_ns * 1e-9)
    return make_controller(controller, model.vehicle, model.dampers, params)


class _Feed:
    """Feeds a drive's input messages into the core (and the recording), collects the output samples and
    runs the controller in the loop, if any, on each of them."""

    def __init__(self, core: SimCore, drive: TestDrive, rec: McapRecorder | None, ctrl) -> None:
        self.core, self.rec, self.ctrl = core, rec, ctrl
        self.ts: list[int] = []
        self.ys: list[np.ndarray] = []
        self.out_index = {k: i for i, k in enumerate(OUTPUT_LABELS)}
        sp, st = drive.speed.values.tolist(), drive.steering.values.tolist()
        # (_events yields wheel-height and damper-command events only for the series the drive has)
        wh = drive.wheel_heights.values if drive.wheel_heights is not None else np.empty((0, 4))
        cmd = drive.damper_command.values if drive.damper_command is not None else np.empty((0, 4))
        road_msg: dict = {}  # the road profile message and its number of samples (if the drive has a road)
        n_road = 0
        if drive.road is not None:
            road_msg = M.road_profile_msg(drive.road.s, drive.road.zl, drive.road.zr)
            n_road = len(drive.road)
        # kind -> (apply to the core at t, topic, message type, the message of sample i, latched)
        self.inputs = {
            _SPEED: (lambda t, i: core.set_speed(t, sp[i]), SPEED, M.FLOAT64, lambda i: {"data": sp[i]}, False),
            _STEER: (lambda t, i: core.set_steering(t, st[i]), STEERING, M.FLOAT64, lambda i: {"data": st[i]}, False),
            _WH: (lambda t, i: core.set_wheel_heights(t, wh[i]), WHEEL_HEIGHTS, M.FLOAT64_ARRAY,
                  lambda i: M.wheel_heights_msg(wh[i]), False),
            _CMD: (lambda t, i: core.set_damper_command(t, cmd[i]), DAMPER_COMMAND, M.FLOAT64_ARRAY,
                   lambda i: M.wheel_heights_msg(cmd[i]), False),
            _ROAD: (lambda t, i: core.set_road_profile(t, road_msg["data"], [("channel", 3), ("sample", n_road)]),
                    ROAD_PROFILE, M.FLOAT64_ARRAY, lambda i: road_msg, True),
        }

    def apply(self, t: int, kind: int, i: int) -> None:
        """Input message ``i`` of ``kind`` at ROS time ``t`` [ns] into the core, and into the recording."""
        set_input, topic, msgtype, message, latched = self.inputs[kind]
        set_input(t, i)
        if self.rec is not None:
            self.rec.write(topic, msgtype, t, message(i), latched=latched)

    def emit(self, samples) -> None:
        for smp in samples:
            self.ts.append(smp.t_ns)
            self.ys.append(smp.y)
            if self.rec is not None:
                for topic, mt, msg in sample_messages(smp):
                    self.rec.write(topic, mt, smp.t_ns, msg)
            if self.ctrl is not None:
                cmd = self.ctrl(measurement_from_outputs(smp.y, self.out_index))
                if cmd is not None and self.core.set_damper_command(smp.t_ns, cmd) is None and self.rec is not None:
                    self.rec.write(DAMPER_COMMAND, M.FLOAT64_ARRAY, smp.t_ns, M.wheel_heights_msg(cmd))


def run_lockstep(drive: TestDrive, *, vehicle: str = DEFAULT_VEHICLE, variant: str = "full",
                 oil: Sequence[float] | np.ndarray | None = None, step_s: float = 0.001, publish_rate_hz: float = 100.0,
                 out_path: str | os.PathLike | None = None, overwrite: bool = False,
                 input_timeout_s: float = 0.5, model: Model | None = None,
                 controller: str | None = None) -> LockstepRun:
    """Run ``drive`` through a :class:`SimCore` as fast as possible (see the module docstring).

    ``controller``: a damper controller (:mod:`susp_sim_ros.control`) in the loop, as the
    ``susp_damper_controller`` node would run it: on every output sample it computes a command that is
    applied at that sample's time (and recorded as ``/vehicle/damper_command``); ``None`` or
    ``"passive"``: the drive's own commands, if any.

    Returns a :class:`LockstepRun`: the :class:`~susp_sim_ros.model.response.Response` of every output
    at the publish ticks and the run's IMU samples, metadata, guard state and refused inputs. ``drive``
    is never modified.

    If the divergence guard stops the core, the result ends at the last good sample, ``healthy`` is
    False and ``diverged`` says why (the output file, if any, holds the samples up to there)."""
    if oil is None and not drive.oil_known:
        log.warning("damper_oil_level is unknown (an inspection drive): simulating intact dampers; give "
                    "the oil levels (--oil) to simulate another state")
    oil = tuple(drive.oil_levels() if oil is None else oil)
    model = model or Model(vehicle, variant)
    core = SimCore(model, step_s=step_s, publish_rate_hz=publish_rate_hz, oil=oil,
                   input_timeout_s=input_timeout_s)
    meta = simulated_metadata(drive.metadata, model.vehicle.name, model.variant.name, oil)
    rec = McapRecorder(out_path, metadata=meta, overwrite=overwrite) if out_path is not None else None
    feed = _Feed(core, drive, rec, _controller_in_loop(controller, model, core))
    try:
        for t, kind, i in _events(drive):
            feed.emit(core.advance_to(t))
            feed.apply(t, kind, i)
        feed.emit(core.advance_to(drive.t_end_ns))
    finally:
        if rec is not None:
            rec.close()
    ts, ys = feed.ts, feed.ys
    t_arr = np.array(ts, dtype=np.int64)
    Y = np.array(ys).reshape(-1, len(OUTPUT_LABELS))
    imu = ImuSeries(t_arr, Y[:, _GYRO], Y[:, _ACC])
    return LockstepRun(Response((t_arr - drive.t0_ns) * 1e-9, Y, OUTPUT_LABELS, t_ns=t_arr), imu, meta,
                       healthy=core.healthy, diverged=core.diverged, rejections=dict(core.rejections),
                       out_path=None if out_path is None else str(out_path))


def maneuver_drive(maneuver: Maneuver, oil: Sequence[float] = (1.0, 1.0, 1.0, 1.0), *,
                   rate_hz: float = 100.0, t0_ns: int = 1_000_000_000,
                   vehicle: str = DEFAULT_VEHICLE) -> TestDrive:
    """A paper maneuver as a test drive: speed and steering messages at ``rate_hz`` from ``t0_ns``
    (ROS time 0 means "no clock yet" to a sim-time node, so the default starts at 1 s), its road."""
    n = int(round(maneuver.duration * rate_hz)) + 1
    k = np.arange(n)
    t_rel = k / rate_hz
    t_ns = t0_ns + np.round(k * (1e9 / rate_hz)).astype(np.int64)
    road = maneuver.road if len(maneuver.road) >= 2 else None
    # the source label recorded drives carry, kept from before the module moved to runtime/
    meta = {"vehicle": vehicle, "maneuver": maneuver.name,
            "damper_oil_level": ",".join(f"{float(x):g}" for x in oil),
            "source": "synthetic:susp_sim_ros.lockstep.maneuver_drive"}
    return TestDrive(meta, Series(t_ns, maneuver.speed_at(t_rel)), Series(t_ns.copy(), maneuver.steering(t_rel)),
                     road, None, None, {})


__all__ = ["LockstepRun", "run_lockstep", "maneuver_drive", "simulated_metadata"]
