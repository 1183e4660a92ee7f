"""susp_sim_ros: five-mass full-vehicle model with phenomenological suspension friction for ROS 2.

Layers (imports go one way only): ``model`` (physics, numpy/numba) <- ``io``, ``control`` and
``analysis`` (MCAP, validation, discrepancy, inspection, studies; no rclpy) <- ``node`` and ``cli``
(shells). ``docs/architecture.md`` has the data flow.

The public API is re-exported here (imported on first use, so ``import susp_sim_ros`` stays cheap and
never pulls in rclpy). Every simulation returns one :class:`Response` (signals labelled with the
interface's snake_case names, SI units, ``to_pandas()``/``to_csv()``); nothing changes its inputs::

    import tempfile
    import susp_sim_ros as ss

    model = ss.Model("passat_b8_like", "full")
    bump = ss.paper_maneuver("bump_crossing")          # the paper's 8 km/h bump crossing
    resp = ss.simulate(model, bump.to_inputs(0.001), dt=0.001, road=bump.road,
                       oil=ss.vehicle_state("rear_empty"))
    peak = abs(resp["pitch_rate"]).max()               # rad/s; resp.units["pitch_rate"] == "rad/s"
    table = resp.to_pandas()                           # index time_s, one column per signal

    drive = ss.read_drive("bags/bump_crossing_rear_empty.mcap")
    sim = ss.run_lockstep(drive, model=model)          # the drive through the node's core: a LockstepRun
    check = ss.validate(drive.imu.t_ns, drive.imu.gyro, sim.t_ns, sim.imu.gyro)
    rmse = check.rmse_deg_s("whole", "pitch_rate")     # deg/s, as the paper reports

    finder = ss.DiscrepancyFinder(candidates=["damper_friction_oil", "friction_amplitude"],
                                  calibrate=False, heldout=False)  # a quick look; defaults: everything
    report = finder.fit([drive]).report()              # paths, TestDrive objects, or both
    score = finder.score(["bags/bump_crossing_rear_empty.mcap"])  # share of the residual explained
    pred = finder.predict(drive)                       # the fitted model's IMU signals: a Response

    study = ss.load_study("config/studies/bump_oil_inspection.yaml")
    summary = ss.run_study(study, tempfile.mkdtemp(), ss.make_executor("inprocess"),
                           progress=False, plot=False)
"""
from __future__ import annotations

import importlib
from typing import Any

from . import idle_threads

# before numpy and numba load their thread pools: idle worker threads sleep instead of spinning (the same
# numbers, a third less run time of a diagnosis on two cores; idle_threads.py says why)
idle_threads.apply()

__version__ = "0.1.0"

#: public name -> module that defines it
_API = {
    "Model": "susp_sim_ros.model",
    "Response": "susp_sim_ros.model",
    "paper_maneuver": "susp_sim_ros.model.maneuvers",
    "vehicle_state": "susp_sim_ros.model.maneuvers",
    "load_vehicle": "susp_sim_ros.model",
    "load_variant": "susp_sim_ros.model",
    "make_inputs": "susp_sim_ros.model",
    "simulate": "susp_sim_ros.model",
    "simulate_batch": "susp_sim_ros.model",
    "TestDrive": "susp_sim_ros.io.drive",
    "read_drive": "susp_sim_ros.io.drive",
    "write_drive": "susp_sim_ros.io.drive",
    "run_lockstep": "susp_sim_ros.runtime.lockstep",
    "LockstepRun": "susp_sim_ros.runtime.lockstep",
    "maneuver_drive": "susp_sim_ros.runtime.lockstep",
    "validate": "susp_sim_ros.analysis.validation",
    "DiscrepancyFinder": "susp_sim_ros.analysis.discrepancy",
    "inspect_drives": "susp_sim_ros.analysis.inspection",
    "load_study": "susp_sim_ros.analysis.sweep",
    "run_study": "susp_sim_ros.analysis.sweep",
    "make_executor": "susp_sim_ros.analysis.sweep",
}

__all__ = sorted(_API)


def __getattr__(name: str) -> Any:
    module = _API.get(name)
    if module is None:
        raise AttributeError(f"module 'susp_sim_ros' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
