"""Ride and road-holding metrics of a recording (issue 15): what ``susp validate`` and the validation
study report next to the rate errors. Pure numpy, no ROS runtime; the formulas are
:mod:`susp_sim_ros.control.ride_metrics`'s (:func:`~.ride.ride_metrics`, :func:`~.ride.comfort_wk_rms`).

- Every series is first put on a uniform grid at the recording's own (median) sample rate inside the
  given time span (:func:`on_uniform_grid`: linear interpolation, never extrapolating; a uniformly
  sampled recording such as the node's or the lockstep runner's is taken sample for sample). The Wk
  filter then runs at that rate; ``wk_accurate_to_hz`` says up to where it stays within
  :data:`~.ride.WK_ACCURACY_DB` of the standard's weighting (about 19 Hz at the node's 100 Hz).
- A recording with ``/sim/suspension`` (deflection, tyre vertical force per wheel) gets the full metrics
  (:func:`ride_of_series`); a measured drive has no suspension travel or tyre loads, only its IMU's
  vertical specific force: it gets ``comfort_wk_rms_m_s2`` alone (:func:`comfort_of_series`).
- Static tyre loads: the vehicle's own (:meth:`~susp_sim_ros.model.params.VehicleParams.static_wheel_loads`,
  the car standing level), not the mean tyre force over the drive. The dynamic tyre load is by
  definition the change against the load of the car at rest (a wheel lifting off is -1); the mean over a
  drive would absorb any sustained load transfer (a long curve, braking) and change with what the drive
  contains, and the same static reference is what ``susp sim --road``, the studies and the node use, so
  the numbers compare. On a straight level drive the mean equals the static load (``mean_tyre_load_N``
  shows it). Only when the recording's vehicle cannot be loaded does the mean stand in, and
  ``static_load_source`` says so.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..errors import RecordingError
from ..io.messages import SUSPENSION_QUANTITIES
from ..model.layout import WHEELS
from . import validation as va
from ..control.ride_metrics import comfort_wk_rms, ride_metrics, wk_accurate_to_hz

_DEFL = SUSPENSION_QUANTITIES.index("deflection")
_FZ = SUSPENSION_QUANTITIES.index("tyre_vertical_force")
NO_SUSPENSION_NOTE = ("no /sim/suspension: suspension travel and tyre loads are not measured, only the "
                      "IMU's vertical acceleration (comfort)")


def on_uniform_grid(t_ns, values, span: tuple[int, int], what: str) -> tuple[np.ndarray, np.ndarray, float]:
    """``(grid_ns, values on it, rate_hz)``: ``values`` (first axis = samples) resampled onto the uniform
    grid at the median sample rate of its samples inside ``span`` [ns]."""
    v = np.asarray(values, float)
    t, flat = va.check_series(t_ns, v.reshape(len(v), -1), what)
    inside = (t >= span[0]) & (t <= span[1])
    if np.count_nonzero(inside) < 2:
        raise va.NoOverlapError(f"{what}: fewer than 2 samples in [{span[0] / va.NS:.3f}, {span[1] / va.NS:.3f}] s")
    rate = va.median_rate(t[inside])
    grid = va.common_grid(span, rate)
    return grid, va.resample(t, flat, grid).reshape((grid.size,) + v.shape[1:]), rate


def _meta(grid: np.ndarray, rate: float) -> dict:
    return {"rate_hz": rate, "samples": int(grid.size), "wk_accurate_to_hz": wk_accurate_to_hz(rate),
            "start_s": float(grid[0] / va.NS), "end_s": float(grid[-1] / va.NS)}


def comfort_of_series(imu_t_ns, accel, span: tuple[int, int], *, gravity: float, what: str) -> dict:
    """``comfort_wk_rms_m_s2`` of the IMU's vertical specific force (``accel`` (n, 3), body z) in ``span``,
    plus the grid it was computed on and a note that travel and tyre loads are unavailable."""
    grid, a, rate = on_uniform_grid(imu_t_ns, np.asarray(accel, float)[:, 2], span, what)
    return {"comfort_wk_rms_m_s2": comfort_wk_rms(a, rate, gravity), **_meta(grid, rate),
            "note": NO_SUSPENSION_NOTE}


def ride_of_series(imu_t_ns, gyro, accel, susp_t_ns, susp, span: tuple[int, int], *, gravity: float,
                   static_loads: Sequence[float] | None, bump_travel, rebound_travel,
                   what: str = "recording") -> dict:
    """:func:`~.ride.ride_metrics` of an IMU series (``gyro``, ``accel`` (n, 3), body axes) and a
    ``/sim/suspension`` series (``susp`` (m, 4, Q)) inside ``span`` [ns], on the IMU's uniform grid.
    ``static_loads`` [N] per wheel FL, FR, RL, RR; ``None``: the mean tyre force in the span (reported
    in ``static_load_source``). Adds ``static_tyre_load_N``, ``mean_tyre_load_N`` and the grid."""
    imu = np.column_stack([np.asarray(gyro, float), np.asarray(accel, float)])
    grid, y, rate = on_uniform_grid(imu_t_ns, imu, span, f"{what} IMU")
    st, sv = va.check_series(susp_t_ns, np.asarray(susp, float).reshape(len(susp), -1), f"{what} /sim/suspension")
    try:
        s = va.resample(st, sv, grid).reshape(grid.size, len(WHEELS), len(SUSPENSION_QUANTITIES))
    except va.ExtrapolationError as exc:
        raise RecordingError(f"{what} /sim/suspension does not cover its IMU's span: {exc}") from None
    series = {"ROLL_RATE": y[:, 0], "PITCH_RATE": y[:, 1], "AZ_SF": y[:, 5]}
    for i, w in enumerate(WHEELS):
        series[f"F_Z_{w}"] = s[:, i, _FZ]
        series[f"DEFL_{w}"] = s[:, i, _DEFL]
    mean_fz = s[:, :, _FZ].mean(axis=0)
    source = "vehicle static wheel loads (car at rest, level)"
    if static_loads is None:
        static_loads, source = mean_fz, "mean tyre force of the recording (its vehicle could not be loaded)"
    out = ride_metrics(series, rate, gravity=gravity, static_loads=static_loads, bump_travel=bump_travel,
                       rebound_travel=rebound_travel).to_dict()
    out["static_tyre_load_N"] = dict(zip(WHEELS, np.asarray(static_loads, float).tolist()))
    out["mean_tyre_load_N"] = dict(zip(WHEELS, mean_fz.tolist()))
    out["static_load_source"] = source
    out.update(_meta(grid, rate))
    return out


def vehicle_ride_args(vp) -> dict:
    """``gravity``, ``static_loads``, ``bump_travel``, ``rebound_travel`` of a VehicleParams, per wheel."""
    axle = (0, 0, 1, 1)  # axle (front 0, rear 1) of FL, FR, RL, RR
    return {"gravity": vp.gravity, "static_loads": vp.static_wheel_loads(),
            "bump_travel": [vp.bump_stop_travel[a] for a in axle],
            "rebound_travel": [vp.rebound_stop_travel[a] for a in axle]}


def summary_line(ride: dict) -> str:
    """One human line: Wk comfort measured vs simulated and the simulated per-wheel dynamic tyre load."""
    if "error" in ride:
        return f"ride: not computed ({ride['error']})"
    m, s = ride.get("measured", {}), ride.get("simulated", {})
    parts = [(f"ride: Wk RMS measured {m.get('comfort_wk_rms_m_s2', float('nan')):.3f} / simulated "
              f"{s.get('comfort_wk_rms_m_s2', float('nan')):.3f} m/s^2")]
    if "dynamic_tyre_load_rms_rel" in s:
        dtl = s["dynamic_tyre_load_rms_rel"]
        travel = s["suspension_travel_rms_m"]
        parts.append("simulated dyn. tyre load RMS " + " ".join(f"{w} {dtl[w]:.3f}" for w in WHEELS)
                     + f", travel RMS max {1e3 * max(travel.values()):.1f} mm, stop contacts "
                     f"{sum(s['stop_contacts'].values())}")
    else:
        parts.append("no /sim/suspension in the simulated recording: comfort only")
    rate = min(x["rate_hz"] for x in (m, s) if "rate_hz" in x) if ("rate_hz" in m or "rate_hz" in s) else None
    if rate is not None:
        parts.append(f"Wk accurate to {wk_accurate_to_hz(rate):.0f} Hz at {rate:.0f} Hz")
    return "; ".join(parts)


__all__ = ["NO_SUSPENSION_NOTE", "comfort_of_series", "on_uniform_grid", "ride_of_series", "summary_line",
           "vehicle_ride_args"]
