"""The test protocol of a damper inspection: what crossing each drive made, against the crossings the
inspection is validated for (``config/inspection.yaml`` ``protocol``).

Per drive (:func:`crossings`): the speed over the drive [m/s], the bump height [m] (highest point of the
recorded road profile above its start, either track) and the peak damper velocity per axle [m/s] of the
fitted model (what the oil estimate leans on). :func:`warnings` names every quantity outside the
protocol, with the reason, and a drive set that excites one axle only; :func:`curve_notes` says where
the dampers run beyond the last measured point of their curve (extrapolated there). Outside the
protocol the inspection widens its intervals (:func:`model_form_factor`): the model-form error grows
with the excitation, and the inspection was not validated there.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from ...io.units import FACTORS
from ...model.layout import U_INDEX
from ...model.params import AXLE_CORNERS, CORNER_NAMES
from ..discrepancy.engine import Evaluator, Structure

KMH = 1.0 / FACTORS["km/h"]  # km/h per m/s (human-facing text only)
CM = 1.0 / FACTORS["cm"]     # cm per m (human-facing text only)


def crossings(ev: Evaluator, st: Structure, x: np.ndarray) -> list[dict]:
    """Per drive of ``ev``: ``{"drive", "speed_m_s", "bump_height_m", "peak_damper_velocity_m_s":
    {"front", "rear"}}`` under the fitted structure ``st`` at ``x`` (bump height None without a road
    profile)."""
    outs = [f"DEFL_VEL_{w}" for w in CORNER_NAMES]
    res = []
    for r, c in enumerate(ev.cases):
        v = c.U[:, U_INDEX["V"]]
        moving = v[v > 0.1 * max(float(np.max(v)), 1e-9)]
        dv = np.abs(ev.simulate_outputs(st, x, r, outs))
        height = None
        if c.road is not None and c.road.s.size:
            z = np.maximum(c.road.zl, c.road.zr)
            height = float(np.max(z) - z[0])
        res.append({"drive": c.name,
                    "speed_m_s": float(np.median(moving)) if moving.size else 0.0,
                    "bump_height_m": height,
                    "peak_damper_velocity_m_s": {a: float(dv[:, list(w)].max()) for a, w in AXLE_CORNERS.items()}})
    return res


def warnings(seen: Sequence[Mapping], identifiable: Mapping[str, Mapping], protocol: Mapping) -> list[dict]:
    """Every way the drives leave the protocol: ``{"drive", "quantity", "value", "protocol", "reason"}``
    (``drive`` None for the drive set as a whole). ``identifiable``: the inspection's per-axle
    identifiability (``"no"`` when the drives do not excite that axle)."""
    lo_v, hi_v = protocol["speed_m_s"]
    lo_h, hi_h = protocol["bump_height_m"]
    out: list[dict] = []
    for s in seen:
        v = s["speed_m_s"]
        if not lo_v <= v <= hi_v:
            out.append({"drive": s["drive"], "quantity": "speed_m_s", "value": v, "protocol": [lo_v, hi_v],
                        "reason": f"driven at {v * KMH:.1f} km/h, the inspection is validated for "
                                  f"{lo_v * KMH:.0f}-{hi_v * KMH:.0f} km/h: "
                                  + ("faster strokes reach the damper curve where its shape is assumed"
                                     if v > hi_v else "too slow a crossing barely moves the dampers")})
        h = s["bump_height_m"]
        if h is not None and not lo_h <= h <= hi_h:
            out.append({"drive": s["drive"], "quantity": "bump_height_m", "value": h, "protocol": [lo_h, hi_h],
                        "reason": f"a {h * CM:.1f} cm bump, the inspection is validated for "
                                  f"{lo_h * CM:.0f}-{hi_h * CM:.0f} cm: "
                                  + ("a higher bump drives the dampers faster and may reach the stops"
                                     if h > hi_h else "a lower bump excites the dampers too little")})
    silent = [a for a, e in identifiable.items() if e.get("identifiable") == "no"]
    if silent and len(silent) < len(identifiable):
        out.append({"drive": None, "quantity": "axles_excited", "value": len(identifiable) - len(silent),
                    "protocol": [len(identifiable), len(identifiable)],
                    "reason": f"the drives excite one axle only (not the {', '.join(silent)}): cross the bump "
                              "so that both axles pass it"})
    return out


def curve_notes(seen: Sequence[Mapping], curve_velocity_m_s: Sequence[float]) -> list[str]:
    """A note per drive and axle whose dampers run faster than the damper curve's last measured point
    (``curve_velocity_m_s``: the vehicle file's ``dampers.velocity``): beyond it the curve is extrapolated
    with its end slope, an assumption the drive cannot check."""
    v_end = float(min(-min(curve_velocity_m_s), max(curve_velocity_m_s)))
    return [f"{s['drive']}: the {axle} dampers reach {pv:.2f} m/s, beyond the damper curve's last measured "
            f"point ({v_end:.2f} m/s): the curve is extrapolated there"
            for s in seen for axle, pv in s["peak_damper_velocity_m_s"].items() if pv > v_end]


def model_form_factor(found: Sequence[Mapping], protocol: Mapping) -> float:
    """Factor on the inspection's model-form standard deviation: 1 inside the protocol, the protocol's
    ``outside_model_form_factor`` when any drive leaves it (speed, bump height, damper velocity)."""
    leaves = any(w["drive"] is not None for w in found)
    return float(protocol["outside_model_form_factor"]) if leaves else 1.0
