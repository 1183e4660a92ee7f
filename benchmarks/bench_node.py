"""Benchmark of susp_sim_node in real-time (wall-time) mode, across processes over DDS.

Starts ``susp_sim_node`` in a subprocess (default parameters: 1 ms step, 100 Hz publishing), feeds it
speed and steering at 100 Hz from this process for ``--duration`` seconds, and reports:

- ``rtf``: achieved real-time factor (simulated time / wall time), from the node's ``/diagnostics``;
- ``jitter_p50_ms``, ``jitter_p99_ms``, ``jitter_max_ms``: publish-period jitter,
  |t_publish(k) - t_publish(k-1) - period|, measured by the node at each publish;
- ``latency_p50_ms``, ``latency_p99_ms``: input-to-output latency: the age of each ``/sim/imu/data``
  sample when it arrives in this (another) process, wall receive time minus the sample's stamp (the
  instant the sample represents, i.e. up to which the inputs received so far were integrated);
- ``deadline_misses``: ticks published more than one period late (or skipped), from ``/diagnostics``.

The node runs with its defaults, i.e. its threads at SCHED_FIFO when permitted (``realtime_priority``).
The probe here (input publisher and output subscriber) gets SCHED_FIFO too when permitted, as a real-time
consumer would, so that the load of other processes on the machine enters the figures through the node
and not through the measuring instrument; ``--probe-normal-priority`` measures with an ordinary probe.

``--json`` prints exactly these keys (interface.md); logs go to stderr.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import random
import signal
import subprocess
import sys
import tempfile
import threading
import time

import numpy as np


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env.setdefault("ROS_DOMAIN_ID", str(random.randint(1, 101)))
    env.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    env.setdefault("ROS_LOG_DIR", tempfile.mkdtemp(prefix="bench_node_log_"))
    return env


def run(duration: float, rate_hz: float = 100.0, probe_rt: bool = True) -> dict:
    env = _env()
    os.environ.update({k: env[k] for k in ("ROS_DOMAIN_ID", "ROS_AUTOMATIC_DISCOVERY_RANGE", "ROS_LOG_DIR")})
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray
    from rclpy.executors import SingleThreadedExecutor
    from sensor_msgs.msg import Imu
    from std_msgs.msg import Float64

    node_proc = subprocess.Popen(
        [sys.executable, "-c", "import sys; from susp_sim_ros.node import main; sys.exit(main())",
         "--ros-args", "-p", f"publish_rate_hz:={float(rate_hz)}"],
        env=env, stdout=sys.stderr, stderr=sys.stderr)
    ctx = rclpy.Context()
    rclpy.init(context=ctx)
    node = rclpy.create_node("bench_node_probe", context=ctx)
    lat: list[int] = []
    diag: dict[str, str] = {}
    measuring = threading.Event()

    def on_imu(msg: Imu) -> None:
        now = time.time_ns()
        if measuring.is_set():
            lat.append(now - (msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec))

    def on_diag(msg: DiagnosticArray) -> None:
        for st in msg.status:
            if st.name.endswith(": timing"):
                diag.clear()
                diag.update({kv.key: kv.value for kv in st.values})

    node.create_subscription(Imu, "/sim/imu/data", on_imu, 100)
    node.create_subscription(DiagnosticArray, "/diagnostics", on_diag, 10)
    speed = node.create_publisher(Float64, "/vehicle/speed", 10)
    steer = node.create_publisher(Float64, "/vehicle/steering_wheel_angle", 10)
    ex = SingleThreadedExecutor(context=ctx)
    ex.add_node(node)
    spin = threading.Thread(target=ex.spin, daemon=True)
    spin.start()
    if probe_rt:
        from susp_sim_ros.node import raise_priority
        note = raise_priority(5)
        if note:
            print(f"bench_node: probe: {note}", file=sys.stderr)
    try:
        t_wait = time.monotonic() + 60.0
        while speed.get_subscription_count() == 0 or node.count_publishers("/sim/imu/data") == 0:
            if time.monotonic() > t_wait or node_proc.poll() is not None:
                raise RuntimeError("susp_sim_node did not come up (no subscriber on /vehicle/speed)")
            time.sleep(0.05)
        time.sleep(1.0)  # let discovery settle
        measuring.set()
        t0 = time.monotonic()
        k = 0
        while time.monotonic() - t0 < duration:
            t = time.monotonic() - t0
            speed.publish(Float64(data=50.0 / 3.6))
            steer.publish(Float64(data=0.5 * math.sin(2 * math.pi * 0.5 * t)))
            k += 1
            time.sleep(max(0.0, t0 + k / rate_hz - time.monotonic()))
        measuring.clear()
        time.sleep(1.5)  # a final /diagnostics covering the whole run
    finally:
        node_proc.send_signal(signal.SIGINT)
        try:
            node_proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            node_proc.kill()
        ex.shutdown()
        node.destroy_node()
        rclpy.try_shutdown(context=ctx)
    if not diag:
        raise RuntimeError("no /diagnostics timing status received from susp_sim_node")
    la = np.asarray(lat, dtype=float) * 1e-6
    print("bench_node: node timing status: " + ", ".join(f"{k}={v}" for k, v in diag.items()), file=sys.stderr)
    return {
        "rtf": float(diag["real_time_factor"]),
        "jitter_p50_ms": float(diag["jitter_p50_ms"]),
        "jitter_p99_ms": float(diag["jitter_p99_ms"]),
        "jitter_max_ms": float(diag["jitter_max_ms"]),
        "latency_p50_ms": float(np.percentile(la, 50)) if la.size else float("nan"),
        "latency_p99_ms": float(np.percentile(la, 99)) if la.size else float("nan"),
        "deadline_misses": int(diag["deadline_misses"]),
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    ap.add_argument("--duration", type=float, default=300.0, help="measured run length [s] (default 300)")
    ap.add_argument("--rate", type=float, default=100.0, help="publish and input rate [Hz] (default 100)")
    ap.add_argument("--probe-normal-priority", action="store_true",
                    help="run the probe (publisher/subscriber) without real-time scheduling")
    a = ap.parse_args(argv)
    res = run(a.duration, a.rate, probe_rt=not a.probe_normal_priority)
    if a.json:
        print(json.dumps(res))
    else:
        for k, v in res.items():
            print(f"{k}: {v}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
