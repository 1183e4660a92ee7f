"""Semi-active damper and ride values for the node's ``/diagnostics`` (issue 15; pure, no rclpy).

Kept out of ``node.py`` so the node stays a thin adapter: it calls :meth:`SemiActiveDiagnostics.command_applied`
when a damper command is applied, :meth:`~SemiActiveDiagnostics.published` with the samples it publishes and
:meth:`~SemiActiveDiagnostics.values` when it builds its diagnostics.
"""
from __future__ import annotations

import time

import numpy as np

from ..control.ride_metrics import RideMonitor
from ..model.vehicle import Model
from ..runtime.sim_core import SimCore


class SemiActiveDiagnostics:
    """Semi-active damper and ride values of the model status on ``/diagnostics`` (issue 15): the damper
    mode and command, command-to-force latency (from a command's DDS source timestamp to the publication of the first
    ``/sim`` sample computed with it, wall clock; the valve lag comes on top) and the running ride
    metrics (:class:`~susp_sim_ros.control.ride_metrics.RideMonitor`) over the published samples. Samples are
    only queued on the publishing path; the metrics are computed when the diagnostics are built."""

    def __init__(self, model: Model, period_ns: int):
        vp = model.vehicle
        corner = lambda pair: [pair[a] for a in (0, 0, 1, 1)]  # noqa: E731
        self.monitor = RideMonitor(1e9 / period_ns, gravity=vp.gravity, static_loads=vp.static_wheel_loads(),
                                   bump_travel=corner(vp.bump_stop_travel),
                                   rebound_travel=corner(vp.rebound_stop_travel))
        self._rows: list = []
        self._pending: list[tuple[int, int]] = []   # (sim time applied, source timestamp) of commands
        self.latency_ms: list[float] = []
        self._restarts = 0

    def command_applied(self, t_ns: int, src_ns: int) -> None:
        if src_ns > 0:
            self._pending.append((int(t_ns), src_ns))

    def published(self, samples) -> None:
        now = time.time_ns()
        for smp in samples:
            self._rows.append(smp.y)
            while self._pending and self._pending[0][0] <= smp.t_ns:
                self.latency_ms.append((now - self._pending.pop(0)[1]) * 1e-6)
        del self.latency_ms[:-10000]

    def values(self, core: SimCore) -> dict:
        if core.restarts != self._restarts:
            self._restarts = core.restarts
            self.monitor.reset()
        if self._rows:
            self.monitor.update(np.asarray(self._rows))
            self._rows.clear()
        v = self.monitor.values()
        lat = np.asarray(self.latency_ms)
        cmd = core.damper_command
        semi = core.stepper.semi_active
        values = {"damper_mode": "semi_active" if semi else "passive",
                  "damper_command": ",".join(f"{x:g}" for x in cmd) if cmd is not None else "",
                  "valve_time_constant_ms": f"{core.model.dampers.valve_time_constant * 1e3:g}" if semi else "",
                  "command_latency_p50_ms": f"{np.percentile(lat, 50):.3f}" if lat.size else "",
                  "command_latency_p99_ms": f"{np.percentile(lat, 99):.3f}" if lat.size else "",
                  "command_latency_max_ms": f"{lat.max():.3f}" if lat.size else "",
                  "commands_applied": int(lat.size),
                  "comfort_wk_rms_m_s2": f"{v.comfort_wk_rms_m_s2:.6f}",
                  **{f"dynamic_tyre_load_rms_rel_{w}": f"{x:.6f}" for w, x in v.dynamic_tyre_load_rms_rel.items()},
                  **{f"suspension_travel_rms_m_{w}": f"{x:.6f}" for w, x in v.suspension_travel_rms_m.items()},
                  **{f"stop_contacts_{w}": x for w, x in v.stop_contacts.items()},
                  "ride_samples": v.samples}
        return values
