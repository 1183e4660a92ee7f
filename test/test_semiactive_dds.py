"""Issue 15 over real DDS: susp_sim_node and susp_damper_controller (skyhook) each in their own process,
this process drives the car over a class C road; the node reports the command-to-force latency and the
ride metrics on /diagnostics, and falls back to the passive damper when the controller stops."""
from __future__ import annotations

import json
import time

import pytest

from _ros_helpers import Probe, profile_msg, start_node_process, stop_process

pytestmark = pytest.mark.slow
SPEED = 80 / 3.6  # [m/s]


def test_controller_in_its_own_process_drives_the_dampers(tmp_path):
    from diagnostic_msgs.msg import DiagnosticArray
    from std_msgs.msg import Float64MultiArray

    from susp_sim_ros.model.iso8608 import faded_road

    node_log, ctl_log = tmp_path / "node.log", tmp_path / "controller.log"
    sim = start_node_process(node_log, "susp_sim_ros.ros.node", "-p", "diagnostics_rate_hz:=2.0")
    ctl = start_node_process(ctl_log, "susp_sim_ros.ros.controller_node", "-p", "controller:=skyhook")
    probe = Probe("semiactive_probe")
    node = probe.node
    diags: list = []
    commands: list = []
    node.create_subscription(DiagnosticArray, "/diagnostics", diags.append, 50)
    node.create_subscription(Float64MultiArray, "/vehicle/damper_command", commands.append, 100)

    def status():
        for d in reversed(diags):
            for s in d.status:
                if s.name.endswith(": model"):
                    return {kv.key: kv.value for kv in s.values}
        return None

    def drive(seconds):
        probe.drive(seconds, speed=SPEED, steer=0.0)

    try:
        probe.wait_for(lambda: probe.speed.get_subscription_count() > 0
                       and node.count_publishers("/vehicle/damper_command") > 0,
                       {node_log: sim, ctl_log: ctl}, 40, "nodes not discovered")
        road = faded_road("C", 400.0, seed=7, spacing=0.05)
        probe.profile.publish(profile_msg(road.s, road.zl, road.zr))
        end = time.monotonic() + 30      # until the controller's commands arrive (start-up on a busy host)
        while (status() or {}).get("damper_mode") != "semi_active":
            assert time.monotonic() < end, node_log.read_text() + ctl_log.read_text()
            drive(0.2)
        drive(6.0)
        on = status()
        ctl_rc = stop_process(ctl)    # the controller goes away: the node must fall back to passive
        drive(2.0)
        off = status()
    finally:
        rc = stop_process(sim)
        if ctl.poll() is None:
            stop_process(ctl)
        probe.close()
    assert rc == 0 and ctl_rc == 0, node_log.read_text() + ctl_log.read_text()
    assert on is not None and off is not None
    assert on["damper_mode"] == "semi_active" and int(on["commands_applied"]) > 300
    assert len(commands) > 300 and any(0.0 < c.data[0] < 1.0 for c in commands)  # continuous skyhook
    lat = {k: float(on[f"command_latency_{k}_ms"]) for k in ("p50", "p99", "max")}
    # arrival to the next 10 ms tick plus DDS transport: well under the valve's 15 ms time constant
    # at the median; the tail depends on a shared 2-core machine
    assert 0.0 < lat["p50"] < 15.0 and lat["p99"] < 100.0, lat
    assert 0.2 < float(on["comfort_wk_rms_m_s2"]) < 3.0
    assert off["damper_mode"] == "passive"
    (tmp_path / "latency.json").write_text(json.dumps(lat))
    print(f"command-to-force latency over DDS [ms]: {lat}; Wk RMS {on['comfort_wk_rms_m_s2']} m/s^2")
