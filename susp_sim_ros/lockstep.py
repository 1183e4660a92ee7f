"""Offline "lockstep" runs: a recorded test drive through the node's :class:`SimCore`, without DDS.

The recorded input messages are fed in log-time order into the same core the node uses (step to the
message time, then apply the input), so the outputs equal what the node publishes when the recording is
replayed with ``/clock`` (sim time), at any replay rate. With ``out_path`` the simulated MCAP is written:
the inputs received, every ``/sim`` topic and the ``test_drive`` metadata with ``source:
simulated:<variant>`` (the node's recording holds the same, plus ``/diagnostics``).
"""
from __future__ import annotations

import logging
import os
from collections.abc import Sequence

import numpy as np

from .io import messages as M
from .io.drive import DAMPER_COMMAND, ROAD_PROFILE, SPEED, STEERING, WHEEL_HEIGHTS, ImuSeries, Series, TestDrive
from .io.recorder import McapRecorder
from .model.layout import OUTPUT_LABELS, output_index
from .model.response import Response
from .model.maneuvers import Maneuver
from .model.paper import IMU_OUTPUTS
from .model.vehicle import Model
from .sim_core import SimCore, sample_messages
from .model.params import DEFAULT_VEHICLE

log = logging.getLogger(__name__)

_GYRO = [output_index(k) for k in IMU_OUTPUTS[:3]]
_ACC = [output_index(k) for k in IMU_OUTPUTS[3:]]

_ROAD, _SPEED, _STEER, _WH, _CMD = 0, 1, 2, 3, 4


def simulated_metadata(drive_meta: dict[str, str], vehicle: str, variant: str,
                       oil: Sequence[float]) -> dict[str, str]:
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


def run_lockstep(drive: TestDrive, *, vehicle: str = DEFAULT_VEHICLE, variant: str = "full",
                 oil: Sequence[float] | None = None, step_s: float = 0.001, publish_rate_hz: float = 100.0,
                 out_path: str | os.PathLike | None = None, overwrite: bool = False,
                 input_timeout_s: float = 0.5, model: Model | None = None,
                 controller: str | None = None) -> Response:
    """Run ``drive`` through a :class:`SimCore` as fast as possible (see the module docstring).

    ``controller``: a damper controller (:mod:`susp_sim_ros.control`) in the loop, as the
    ``susp_damper_controller`` node would run it: on every output sample it computes a command that is
    applied at that sample's time (and recorded as ``/vehicle/damper_command``); ``None`` or
    ``"passive"``: the drive's own commands, if any.

    Returns a :class:`~susp_sim_ros.model.response.Response` of every output at the publish ticks:
    ``t`` [s] since the drive's first input, ``t_ns`` the ROS times, ``imu`` the ``/sim/imu/data``
    samples, ``metadata`` the simulated recording's ``test_drive`` record, ``rejections`` the refused
    inputs by topic. ``drive`` is never modified.

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
    ts: list[int] = []
    ys: list[np.ndarray] = []
    road_msg = None
    if drive.road is not None:
        road_msg = M.road_profile_msg(drive.road.s, drive.road.zl, drive.road.zr)
    ctrl = None
    if controller not in (None, "passive"):
        import dataclasses

        from .control.controllers import load_controller_params, make_controller, measurement_from_outputs
        params = dataclasses.replace(load_controller_params(), sample_time=core.period_ns * 1e-9)
        ctrl = make_controller(controller, model.vehicle, model.dampers, params)
        out_index = {k: i for i, k in enumerate(OUTPUT_LABELS)}
    sp, st = drive.speed.values.tolist(), drive.steering.values.tolist()
    wh = drive.wheel_heights.values if drive.wheel_heights is not None else None
    cmd = drive.damper_command.values if drive.damper_command is not None else None
    try:
        def emit(samples):
            for smp in samples:
                ts.append(smp.t_ns)
                ys.append(smp.y)
                if rec is not None:
                    for topic, mt, msg in sample_messages(smp):
                        rec.write(topic, mt, smp.t_ns, msg)
                if ctrl is not None:
                    cmd = ctrl(measurement_from_outputs(smp.y, out_index))
                    if cmd is not None and core.set_damper_command(smp.t_ns, cmd) is None and rec is not None:
                        rec.write(DAMPER_COMMAND, M.FLOAT64_ARRAY, smp.t_ns, M.wheel_heights_msg(cmd))

        for t, kind, i in _events(drive):
            emit(core.advance_to(t))
            if kind == _SPEED:
                core.set_speed(t, sp[i])
                if rec is not None:
                    rec.write(SPEED, M.FLOAT64, t, {"data": sp[i]})
            elif kind == _STEER:
                core.set_steering(t, st[i])
                if rec is not None:
                    rec.write(STEERING, M.FLOAT64, t, {"data": st[i]})
            elif kind == _WH:
                core.set_wheel_heights(t, wh[i])
                if rec is not None:
                    rec.write(WHEEL_HEIGHTS, M.FLOAT64_ARRAY, t, M.wheel_heights_msg(wh[i]))
            elif kind == _CMD:
                core.set_damper_command(t, cmd[i])
                if rec is not None:
                    rec.write(DAMPER_COMMAND, M.FLOAT64_ARRAY, t, M.wheel_heights_msg(cmd[i]))
            else:
                n = len(drive.road)
                core.set_road_profile(t, road_msg["data"], [("channel", 3), ("sample", n)])
                if rec is not None:
                    rec.write(ROAD_PROFILE, M.FLOAT64_ARRAY, t, road_msg, latched=True)
        emit(core.advance_to(drive.t_end_ns))
    finally:
        if rec is not None:
            rec.close()
    t_arr = np.array(ts, dtype=np.int64)
    Y = np.array(ys).reshape(-1, len(OUTPUT_LABELS))
    imu = ImuSeries(t_arr, Y[:, _GYRO], Y[:, _ACC])
    return Response((t_arr - drive.t0_ns) * 1e-9, Y, OUTPUT_LABELS, t_ns=t_arr, metadata=meta,
                    healthy=core.healthy, diverged=core.diverged, rejections=dict(core.rejections),
                    out_path=None if out_path is None else str(out_path), imu=imu)


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
    meta = {"vehicle": vehicle, "maneuver": maneuver.name,
            "damper_oil_level": ",".join(f"{float(x):g}" for x in oil),
            "source": "synthetic:susp_sim_ros.lockstep.maneuver_drive"}
    return TestDrive(meta, Series(t_ns, maneuver.speed_at(t_rel)), Series(t_ns.copy(), maneuver.steering(t_rel)),
                     road, None, None, {})


__all__ = ["run_lockstep", "maneuver_drive", "simulated_metadata"]
