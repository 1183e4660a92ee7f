"""The node's parameters: defaults, ``ParameterDescriptor`` (description, read-only, ranges) and the
validation of run-time changes.

Only :data:`RUNTIME` may change while the node runs; every other parameter is declared read-only, so
rclpy refuses a change before any callback runs. The ranges rclpy can check (scalars) are in the
descriptors; the per-element range of ``damper_oil_level`` is in its descriptor for ``ros2 param
describe`` but checked by :func:`~susp_sim_ros.model.vehicle.check_oil` (rclpy checks ranges of scalar
parameters only). A run-time change is validated (and a new model built and compiled) by
:func:`prepare_change` in the node's on-set callback and applied in its post-set callback. (rclpy's
pre-set callback can only rewrite the list of parameters; refusing there would lose the reason.)
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor

from ..model.vehicle import Model, Stepper, check_oil

#: name -> (default, description)
DEFAULTS: dict[str, tuple[Any, str]] = {
    "vehicle": ("passat_b8_like", "vehicle parameter set name (config/vehicles) or YAML path"),
    "friction_variant": ("full", "friction variant: full, no_horizontal, no_velocity, dahl_only or a YAML path"),
    "damper_oil_level": ([1.0, 1.0, 1.0, 1.0], "damper oil level FL, FR, RL, RR in [0, 1] (1 = intact)"),
    "step_s": (0.001, "fixed internal integration step [s]"),
    "publish_rate_hz": (100.0, "publish rate of /sim topics [Hz]"),
    "record_path": ("", "MCAP file to record to (empty: no recording)"),
    "record_overwrite": (False, "overwrite an existing record_path"),
    "record_flush_interval_s": (1.0, "the recording's open chunk is put on disk at least this often; a killed "
                                     "node loses at most this much [s]"),
    "input_timeout_s": (0.5, "an input not refreshed for this long is reported stale [s]"),
    "diagnostics_rate_hz": (1.0, "publish rate of /diagnostics [Hz]"),
    "sim_reorder_window_s": (0.02, "sim time: /clock and inputs are put in publish order and processed "
                                    "this long after they were published (wall time) [s]"),
    "realtime_priority": (10, "SCHED_FIFO priority of the wall-time tick thread (0: normal scheduling; "
                              "falls back to normal scheduling when not permitted)"),
    "max_time_jump_s": (10.0, "a jump of ROS time forward by more than this is not stepped through; the "
                              "simulation continues from the new time [s]"),
    "on_divergence": ("exit", "when the divergence guard stops the simulation: exit (code 1, after an ERROR "
                              "diagnostic and finalising the recording) or hold (stay up reporting ERROR)"),
}
#: the parameters that may change while the node runs
RUNTIME = ("damper_oil_level", "friction_variant", "vehicle")
#: closed ranges (from, to) in the descriptors; SimCore still refuses a publish rate of 0
RANGES: dict[str, tuple[float, float]] = {
    "publish_rate_hz": (0.0, 1000.0),    # SimCore: (0, 1000] Hz
    "damper_oil_level": (0.0, 1.0),      # per element (checked by check_oil, see the module docstring)
}
CONSTRAINTS = {"on_divergence": "exit or hold",
               "friction_variant": "full, no_horizontal, no_velocity, dahl_only or a variant YAML path"}
ON_DIVERGENCE = ("exit", "hold")


def descriptor(name: str) -> ParameterDescriptor:
    """The ``ParameterDescriptor`` of parameter ``name``: description, read-only unless in
    :data:`RUNTIME`, range and constraints where known."""
    d = ParameterDescriptor(description=DEFAULTS[name][1], read_only=name not in RUNTIME,
                            additional_constraints=CONSTRAINTS.get(name, ""))
    if name in RANGES:
        lo, hi = RANGES[name]
        d.floating_point_range = [FloatingPointRange(from_value=lo, to_value=hi, step=0.0)]
    return d


def declare_parameters(node) -> dict[str, Any]:
    """Declare the parameters on ``node`` (an rclpy ``Node``) with their descriptors (those already
    declared, e.g. from overrides, are kept); returns name -> value."""
    for name, (default, _) in DEFAULTS.items():
        if not node.has_parameter(name):
            node.declare_parameter(name, default, descriptor(name))
    return {name: node.get_parameter(name).value for name in DEFAULTS}


def warm_up(model: Model) -> None:
    """Run the compiled kernel once on a throwaway stepper (JIT compile before real time starts)."""
    Stepper(model, dt=0.001).advance(2, 1.0, 0.0)


@dataclass(frozen=True)
class RuntimeChange:
    """A validated run-time parameter change, ready to apply: the new oil levels (None: unchanged) and
    the new compiled model (None: vehicle and variant unchanged)."""

    oil: np.ndarray | None
    model: Model | None
    vehicle: str
    variant: str


def prepare_change(new: dict[str, Any], vehicle: str, variant: str) -> RuntimeChange:
    """Validate the run-time parameters in ``new`` (name -> value) against the current ``vehicle`` and
    ``variant``; build and compile a new model if they change. Raises ``SuspInputError`` (or
    ``ValueError``/``TypeError`` from a parameter file) naming the parameter."""
    oil = check_oil(new["damper_oil_level"], "parameter damper_oil_level") if "damper_oil_level" in new else None
    model = None
    vehicle_new = str(new.get("vehicle", vehicle))
    variant_new = str(new.get("friction_variant", variant))
    if (vehicle_new, variant_new) != (vehicle, variant):
        model = Model(vehicle_new, variant_new)
        warm_up(model)
    return RuntimeChange(oil, model, vehicle_new, variant_new)
