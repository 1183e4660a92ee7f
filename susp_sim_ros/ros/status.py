"""The node's ``/diagnostics`` statuses (inputs, timing, model, and one per live input-integrity finding
kind and topic) as plain dicts for :func:`~susp_sim_ros.io.messages.diagnostics_msg` (no rclpy)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..io.live_integrity import LiveFinding
from ..runtime.sim_core import SimCore

NODE_NAME = "susp_sim_node"


@dataclass(frozen=True)
class CoreSnapshot:
    """What ``/diagnostics`` reports of the core, taken at once under the node's lock."""

    stale: list[str]
    rejections: dict[str, int]
    by_topic: str
    last_rejection: str
    healthy: bool
    diverged: str
    accel_clamped: int
    time_jumps: int
    sim_s: float
    restarts: int
    oil: list[float]
    started: bool

    @classmethod
    def of(cls, core: SimCore, t_ns: int) -> "CoreSnapshot":
        return cls(stale=core.stale_inputs(t_ns) if core.started else [], rejections=dict(core.rejections),
                   by_topic=",".join(f"{tp}:{c}={n}" for (tp, c), n in sorted(core.rejections_by_topic.items())),
                   last_rejection=core.last_rejection, healthy=core.healthy, diverged=core.diverged,
                   accel_clamped=core.accel_clamped, time_jumps=core.time_jumps, sim_s=core.total_sim_time_s,
                   restarts=core.restarts, oil=core.oil.tolist(), started=core.started)


def node_status(node: Any, snap: CoreSnapshot, wall_s: float) -> list[dict]:
    """Statuses of a :class:`~.node.SuspSimNode` (its public counters) and a core snapshot; ``wall_s``:
    wall time since the core started [s] (for the real-time factor)."""
    stale, rej = snap.stale, snap.rejections
    rtf = snap.sim_s / wall_s if wall_s > 0 and snap.started else 0.0
    tm = node.timing.summary()
    rec = node.recorder
    shared = node.shared_inputs
    message = ("stale: " + ", ".join(stale)) if stale else ("waiting for inputs" if not snap.started else "fresh")
    if shared:
        message += "; more than one publisher: " + ", ".join(shared) + (
            " (refused)" if node.inputs.refuse_shared else "")
    inputs = {"level": 1 if stale or shared else 0, "name": f"{NODE_NAME}: inputs", "message": message,
              "values": {"stale": ",".join(stale), "shared_inputs": ",".join(shared),
                         "publishers": ",".join(f"{t}={n}" for t, n in sorted(node.inputs.publishers.items())),
                         "rejected_total": sum(rej.values()),
                         "queued_sim_events": len(node.inputs.orderer),
                         **{f"rejected_{k}": v for k, v in rej.items()}, "rejected_by_topic": snap.by_topic,
                         "last_rejection": snap.last_rejection, "accel_clamped": snap.accel_clamped,
                         "time_jumps": snap.time_jumps, "handler_errors": node.inputs.handler_errors,
                         "integrity_findings": node.findings.total}}
    timing = {"level": 1 if tm["deadline_misses"] else 0, "name": f"{NODE_NAME}: timing",
              "message": f"real-time factor {rtf:.3f}, {tm['deadline_misses']} deadline misses",
              "values": {"real_time_factor": f"{rtf:.6f}", "sim_time_s": f"{snap.sim_s:.6f}",
                         "restarts": snap.restarts, "mode": "sim_time" if node.sim_time else "wall_time",
                         **{k: (f"{v:.6f}" if isinstance(v, float) else v) for k, v in tm.items()}}}
    values: dict[str, Any] = {
        "healthy": snap.healthy, "diverged": snap.diverged, "on_divergence": node.on_divergence,
        "divergences": node.divergences, "last_divergence": node.failure,
        "vehicle": node.vehicle, "friction_variant": node.variant,
        "damper_oil_level": ",".join(f"{x:g}" for x in snap.oil), "published_samples": node.published,
        "recording_dropped": rec.dropped if rec else 0, "recording_error": rec.error if rec else "",
        "tick_errors": node.tick_errors}
    model = {"level": 0 if snap.healthy else 2, "name": f"{NODE_NAME}: model",
             "message": "numerically healthy" if snap.healthy else
                        (snap.diverged or "numerically unhealthy: stepping stopped"), "values": values}
    if snap.healthy and rec is not None and (rec.error or rec.dropped):
        model["level"] = 1
        model["message"] = "numerically healthy; recording " + (
            f"stopped: {rec.error}" if rec.error else f"dropped {rec.dropped} messages")
    with node.lock:  # semi-active damper and ride metrics: added values of the model status
        values.update(node.semiactive.values(node.core))
    return [inputs, timing, model]


INTEGRITY_PREFIX = f"{NODE_NAME}: input integrity: "


def integrity_statuses(entries: list[tuple[LiveFinding, int, int]], open_gaps: list[str]) -> list[dict]:
    """One status per (input topic, kind) found so far (:meth:`~susp_sim_ros.io.live_integrity.FindingBoard.
    entries`: latest finding, count, new since the last report), named ``"<node>: input integrity: TOPIC
    KIND"``: at the finding's level (WARN, or ERROR for the policy's named errors) when there are new ones
    since the last report or the gap is still open, else OK; its key/values name the topic, the kind, the
    time, the value, what was expected and what the node did, with the counts."""
    out = []
    for f, count, new in entries:
        active = new > 0 or (f.kind == "gap" and f.topic in open_gaps)
        when = f"{f.t_ns * 1e-9:.3f} s"
        message = (f"{f.kind}: {f.value} at {when}, expected {f.expected}" if active else
                   f"no new {f.kind} since the last report (last {f.value} at {when}; {count} in all)")
        out.append({"level": f.level if active else 0, "name": f"{INTEGRITY_PREFIX}{f.topic} {f.kind}",
                    "message": message, "values": {**f.values(), "count": count, "new": new}})
    return out


def log_stale_changes(logger: Any, before: set[str], stale: list[str], timeout_ns: int) -> set[str]:
    """Log the inputs that went stale (warning) or fresh again (info) since ``before``; returns the
    stale set now. ``timeout_ns``: the input timeout [ns]."""
    for topic in set(stale) - before:
        logger.warning(f"input {topic} is stale (no message for more than {timeout_ns * 1e-9:g} s); "
                       "holding its last value")
    for topic in before - set(stale):
        logger.info(f"input {topic} is fresh again")
    return set(stale)


def log_shared_inputs(logger: Any, before: list[str], shared: list[str], counts: dict[str, int],
                      refused: bool) -> list[str]:
    """Warn about the input topics that more than one publisher now feeds (info when one is alone again)
    since ``before``; returns the shared topics now."""
    for topic in sorted(set(shared) - set(before)):
        logger.warning(f"input {topic} has {counts.get(topic, 0)} publishers: the node follows all of them "
                       + ("and refuses their messages (refuse_shared_inputs)" if refused else
                          "(set refuse_shared_inputs:=true to refuse them; keep discovery local with "
                          "ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST or use your own ROS_DOMAIN_ID)"))
    for topic in sorted(set(before) - set(shared)):
        logger.info(f"input {topic} has one publisher again")
    return shared
