"""susp_sim_ros: five-mass full-vehicle model with phenomenological suspension friction for ROS 2.

Layers (imports go one way only): ``model`` (physics, numpy/numba) <- ``io``, ``control`` and
``analysis`` (MCAP, validation, discrepancy, inspection, studies; no rclpy) <- ``node`` and ``cli``
(shells). ``docs/architecture.md`` has the data flow.

The public API is re-exported here (imported on first use, so ``import susp_sim_ros`` stays cheap and
never pulls in rclpy)::

    import susp_sim_ros as ss
    model = ss.Model("passat_b8_like", "full")
    drive = ss.read_drive("bags/bump_crossing_rear_empty.mcap")
    sim = ss.run_lockstep(drive, model=model)
    report = ss.DiscrepancyFinder(variant="full").fit(["bags/bump_crossing_rear_empty.mcap"]).report()
"""
from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.1.0"

#: public name -> module that defines it
_API = {
    "Model": "susp_sim_ros.model",
    "Response": "susp_sim_ros.model",
    "load_vehicle": "susp_sim_ros.model",
    "load_variant": "susp_sim_ros.model",
    "make_inputs": "susp_sim_ros.model",
    "simulate": "susp_sim_ros.model",
    "simulate_batch": "susp_sim_ros.model",
    "TestDrive": "susp_sim_ros.io.drive",
    "read_drive": "susp_sim_ros.io.drive",
    "write_drive": "susp_sim_ros.io.drive",
    "run_lockstep": "susp_sim_ros.lockstep",
    "validate": "susp_sim_ros.analysis.validation",
    "DiscrepancyFinder": "susp_sim_ros.analysis.discrepancy",
    "inspect_drives": "susp_sim_ros.analysis.inspection",
    "load_study": "susp_sim_ros.analysis.sweep",
    "run_study": "susp_sim_ros.analysis.sweep",
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
