"""The node's parameters: defaults, ``ParameterDescriptor`` (description, read-only, ranges) and the
validation of run-time changes.

Only :data:`RUNTIME` may change while the node runs; every other parameter is declared read-only, so
rclpy refuses a change before any callback runs. The ranges rclpy can check (scalars, closed intervals)
are in the descriptors and checked by rclpy at start and on every change; the strict bounds (a step or a
rate of 0) are checked by :class:`~susp_sim_ros.runtime.sim_core.SimCore` and :func:`check_start_values`, the
per-element range of ``damper_oil_level`` (in its descriptor for ``ros2 param describe``) by
:func:`~susp_sim_ros.model.vehicle.check_oil` (rclpy checks ranges of scalar parameters only).

A run-time change is validated (and a new model built and compiled) in the node's on-set callback and
applied in its post-set callback (:class:`RuntimeParameters`). (rclpy's pre-set callback can only
rewrite the list of parameters; refusing there would lose the reason.)
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor, SetParametersResult

from ..errors import SuspInputError

from ..model.vehicle import Model, Stepper, check_oil
from ..model.params import DEFAULT_VEHICLE

#: name -> (default, description)
DEFAULTS: dict[str, tuple[Any, str]] = {
    "vehicle": (DEFAULT_VEHICLE, "vehicle parameter set name (config/vehicles) or YAML path"),
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
    "refuse_shared_inputs": (False, "refuse the messages of an input topic while more than one publisher feeds "
                                    "it (e.g. another process on the same ROS domain); a warning either way"),
    "on_divergence": ("exit", "when the divergence guard stops the simulation: exit (code 1, after an ERROR "
                              "diagnostic and finalising the recording) or hold (stay up reporting ERROR)"),
}
#: the parameters that may change while the node runs
RUNTIME = ("damper_oil_level", "friction_variant", "vehicle")
INF = float("inf")
#: closed ranges (from, to) in the descriptors; the strict lower bounds (> 0) are checked by SimCore
#: (step, publish rate, timeout, time jump) and :func:`check_start_values` (diagnostics rate)
RANGES: dict[str, tuple[float, float]] = {
    "publish_rate_hz": (0.0, 1000.0),    # SimCore: (0, 1000] Hz
    "damper_oil_level": (0.0, 1.0),      # per element (checked by check_oil, see the module docstring)
    "step_s": (0.0, INF),                # SimCore: (0, publish period]
    "input_timeout_s": (0.0, INF),       # SimCore: > 0
    "max_time_jump_s": (0.0, INF),       # SimCore: > 0
    "diagnostics_rate_hz": (0.0, INF),   # check_start_values: > 0
    "record_flush_interval_s": (0.0, INF),
    "sim_reorder_window_s": (0.0, INF),
}
#: integer ranges: SCHED_FIFO priorities are 1..99 and the tick thread runs one above the others
INTEGER_RANGES: dict[str, tuple[int, int]] = {"realtime_priority": (0, 98)}
#: parameters that must be > 0 and that nothing else checks
POSITIVE = ("diagnostics_rate_hz",)
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
    if name in INTEGER_RANGES:
        ilo, ihi = INTEGER_RANGES[name]
        d.integer_range = [IntegerRange(from_value=ilo, to_value=ihi, step=1)]
    return d


def declare_parameters(node) -> dict[str, Any]:
    """Declare the parameters on ``node`` (an rclpy ``Node``) with their descriptors (those already
    declared, e.g. from overrides, are kept); returns name -> value."""
    for name, (default, _) in DEFAULTS.items():
        if not node.has_parameter(name):
            node.declare_parameter(name, default, descriptor(name))
    values = {name: node.get_parameter(name).value for name in DEFAULTS}
    check_start_values(values)
    return values


def check_start_values(values: dict[str, Any]) -> None:
    """What the descriptors cannot say: :data:`POSITIVE` > 0, ``on_divergence`` one of
    :data:`ON_DIVERGENCE`. Raises ``SuspInputError`` naming the parameter."""
    for name in POSITIVE:
        if not float(values[name]) > 0:
            raise SuspInputError(f"parameter {name}: expected a value > 0, got {values[name]}")
    if values["on_divergence"] not in ON_DIVERGENCE:
        raise SuspInputError(f"parameter on_divergence: expected exit or hold, got {values['on_divergence']!r}")


def warm_up(model: Model) -> None:
    """Run the compiled kernel once on a throwaway stepper, passive and semi-active, so neither the JIT
    compile nor the first switch to the semi-active damper family (its hydraulic curves, ~20 ms the first
    time) falls into a real-time tick."""
    stepper = Stepper(model, dt=0.001)
    stepper.advance(2, 1.0, 0.0)
    stepper.set_semi_active(True, np.full(4, 0.5))
    stepper.advance(2, 1.0, 0.0)


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


class RuntimeParameters:
    """The node's parameter callbacks. On-set (:meth:`validate`): ``use_sim_time`` is fixed after start;
    the :data:`RUNTIME` parameters are validated by :func:`prepare_change` (a new model built and compiled
    here, off the apply path); a refusal names the parameter and leaves the node as it was. Post-set
    (:meth:`applied`): the validated change goes to ``apply``. Read-only parameters and ranges are refused
    by rclpy (descriptors) before either runs.

    ``current()`` gives the node's (vehicle, variant); ``log`` is the node's logger."""

    def __init__(self, node, current: Callable[[], tuple[str, str]], apply: Callable[[RuntimeChange], None]):
        self.sim_time = bool(node.get_parameter("use_sim_time").value)
        self.current, self.apply, self.log = current, apply, node.get_logger()
        self.pending: RuntimeChange | None = None  # validated, not yet applied
        node.add_on_set_parameters_callback(self.validate)
        node.add_post_set_parameters_callback(self.applied)

    def validate(self, params) -> SetParametersResult:
        new = {p.name: p.value for p in params}
        if new.get("use_sim_time", self.sim_time) != self.sim_time:
            return SetParametersResult(successful=False, reason="parameter use_sim_time is fixed after start; "
                                                                f"run-time changes: {', '.join(RUNTIME)}")
        try:
            self.pending = prepare_change({k: v for k, v in new.items() if k in RUNTIME}, *self.current())
        except (SuspInputError, ValueError, TypeError) as exc:
            self.log.warning(f"rejected parameter change: {exc}")
            return SetParametersResult(successful=False, reason=str(exc))
        return SetParametersResult(successful=True)

    def applied(self, params) -> None:
        change, self.pending = self.pending, None
        if change is not None:
            self.apply(change)
        self.log.info(f"parameters changed: {', '.join(f'{p.name}={p.value}' for p in params)}")
