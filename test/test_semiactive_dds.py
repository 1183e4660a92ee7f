"""Issue 15 over real DDS: susp_sim_node and susp_damper_controller (skyhook) each in their own process,
this process drives the car over a class C road; the node reports the command-to-force latency and the
ride metrics on /diagnostics, and falls back to the passive damper when the controller stops."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from _ros_helpers import ros_env

pytestmark = pytest.mark.slow


def _start(tmp_path, name, module, *args):
    ros_env()
    log = open(tmp_path / f"{name}.log", "w")
    return subprocess.Popen([sys.executable, "-c", f"import sys; from {module} import main; sys.exit(main())",
                             "--ros-args", *args], stdout=log, stderr=subprocess.STDOUT, env=dict(os.environ))


def _stop(proc) -> int:
    proc.send_signal(signal.SIGINT)
    try:
        return proc.wait(timeout=20)
    except subprocess.TimeoutExpired:
        proc.kill()
        return -9


def test_controller_in_its_own_process_drives_the_dampers(tmp_path):
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from std_msgs.msg import Float64, Float64MultiArray, MultiArrayDimension

    from susp_sim_ros.model.iso8608 import faded_road

    sim = _start(tmp_path, "node", "susp_sim_ros.ros.node", "-p", "diagnostics_rate_hz:=2.0")
    ctl = _start(tmp_path, "controller", "susp_sim_ros.controller_node", "-p", "controller:=skyhook")
    ctx = rclpy.Context()
    rclpy.init(context=ctx)
    node = rclpy.create_node("semiactive_probe", context=ctx)
    diags: list = []
    commands: list = []
    node.create_subscription(DiagnosticArray, "/diagnostics", diags.append, 50)
    node.create_subscription(Float64MultiArray, "/vehicle/damper_command", commands.append, 100)
    steer = node.create_publisher(Float64, "/vehicle/steering_wheel_angle", 10)
    speed = node.create_publisher(Float64, "/vehicle/speed", 10)
    prof = node.create_publisher(Float64MultiArray, "/road/profile", QoSProfile(
        depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE))
    ex = SingleThreadedExecutor(context=ctx)
    ex.add_node(node)

    def status():
        for d in reversed(diags):
            for s in d.status:
                if s.name.endswith(": model"):
                    return {kv.key: kv.value for kv in s.values}
        return None

    def drive(seconds):
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            steer.publish(Float64(data=0.0))
            speed.publish(Float64(data=80 / 3.6))
            ex.spin_once(timeout_sec=0.01)

    try:
        end = time.monotonic() + 40
        while speed.get_subscription_count() == 0 or node.count_publishers("/vehicle/damper_command") == 0:
            assert sim.poll() is None, (tmp_path / "node.log").read_text()
            assert ctl.poll() is None, (tmp_path / "controller.log").read_text()
            assert time.monotonic() < end, "nodes not discovered"
            ex.spin_once(timeout_sec=0.05)
        road = faded_road("C", 400.0, seed=7, spacing=0.05)
        m = Float64MultiArray()
        n = len(road)
        m.layout.dim = [MultiArrayDimension(label="channel", size=3, stride=3 * n),
                        MultiArrayDimension(label="sample", size=n, stride=n)]
        m.data = road.to_flat_array().tolist()
        prof.publish(m)
        end = time.monotonic() + 30      # until the controller's commands arrive (start-up on a busy host)
        while (status() or {}).get("damper_mode") != "semi_active":
            assert time.monotonic() < end, ((tmp_path / "node.log").read_text()
                                            + (tmp_path / "controller.log").read_text())
            drive(0.2)
        drive(6.0)
        on = status()
        ctl_rc = _stop(ctl)           # the controller goes away: the node must fall back to passive
        drive(2.0)
        off = status()
    finally:
        rc = _stop(sim)
        if ctl.poll() is None:
            _stop(ctl)
        ex.shutdown()
        node.destroy_node()
        rclpy.try_shutdown(context=ctx)
    assert rc == 0 and ctl_rc == 0, (tmp_path / "node.log").read_text() + (tmp_path / "controller.log").read_text()
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
