"""Benchmark of susp_sim_node in real-time (wall-time) mode, across processes over DDS.

Starts ``susp_sim_node`` in a subprocess (default parameters: 1 ms step, 100 Hz publishing), feeds it
speed and steering at 100 Hz from this process for ``--duration`` seconds, and reports:

- ``rtf``: achieved real-time factor (simulated time / wall time), from the node's ``/diagnostics``;
- ``jitter_p50_ms``, ``jitter_p99_ms``, ``jitter_max_ms``: publish-period jitter,
  |t_publish(k) - t_publish(k-1) - period|, measured by the node at each publish;
- ``latency_p50_ms``, ``latency_p99_ms``: input-to-output latency: the age of each ``/sim/imu/data``
  sample when it arrives in this (another) process, wall receive time minus the sample's stamp (the
  instant the sample represents, i.e. up to which the inputs received so far were integrated);
- ``deadline_misses``: ticks published more than one period late (or skipped), from ``/diagnostics``;
- ``host_stall_max_ms``: the longest stall of the machine itself in the same run: the largest lateness
  of a plain sleeping-thread probe (:mod:`host_probe`: one process per CPU, pinned, 1 ms
  period, SCHED_FIFO above the node's threads when permitted), running from before the node starts
  until after it stops;
- ``misses_unexplained``: deadline misses no host stall explains (:mod:`susp_sim_ros.analysis.host_stalls`:
  neither one stall that overlapped the miss nor the time any CPU was stalled inside it were at least as
  long as the miss was late, less the probe's period and the node's ordinary lateness p99 in the same run;
  a tick due while the previous one was still late is weighed from that publish on). The node lists its
  misses with their deadlines on ``/diagnostics`` (``deadline_miss_log``); a miss it could not list counts
  as unexplained.

The node runs with its defaults, i.e. its threads at SCHED_FIFO when permitted (``realtime_priority``).
The probe here (input publisher and output subscriber) gets SCHED_FIFO too when permitted, as a real-time
consumer would, so that the load of other processes on the machine enters the figures through the node
and not through the measuring instrument; ``--probe-normal-priority`` measures with an ordinary probe.

``--json`` prints exactly these keys (interface.md); logs go to stderr, the attribution of each miss
included.
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
from pathlib import Path

import susp_sim_ros  # noqa: F401  before numpy: idle worker threads sleep (susp_sim_ros/idle_threads.py)
import numpy as np

# the host-stall probe lives beside the benchmarks (not installed); this file may be loaded from anywhere
sys.path.insert(0, str(Path(__file__).resolve().parent))
from host_probe import HostProbe  # noqa: E402


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env.setdefault("ROS_DOMAIN_ID", str(random.randint(1, 101)))
    env.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    env.setdefault("ROS_LOG_DIR", tempfile.mkdtemp(prefix="bench_node_log_"))
    return env


def run(duration: float, rate_hz: float = 100.0, probe_rt: bool = True) -> dict:
    # the machine's own stalls over the whole run; the probes end with the run, also when it fails
    with HostProbe(max_duration_s=duration + 300.0) as host:
        return _run(duration, rate_hz, probe_rt, host)


def _run(duration: float, rate_hz: float, probe_rt: bool, host) -> dict:
    env = _env()
    os.environ.update({k: env[k] for k in ("ROS_DOMAIN_ID", "ROS_AUTOMATIC_DISCOVERY_RANGE", "ROS_LOG_DIR")})
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray
    from rclpy.executors import SingleThreadedExecutor
    from sensor_msgs.msg import Imu
    from std_msgs.msg import Float64

    from susp_sim_ros.analysis.host_stalls import Miss, attribute, parse_miss_log
    node_proc = subprocess.Popen(
        [sys.executable, "-c", "import sys; from susp_sim_ros.ros.node import main; sys.exit(main())",
         "--ros-args", "-p", f"publish_rate_hz:={float(rate_hz)}"],
        env=env, stdout=sys.stderr, stderr=sys.stderr)
    ctx = rclpy.Context()
    rclpy.init(context=ctx)
    node = rclpy.create_node("bench_node_probe", context=ctx)
    lat: list[int] = []
    diag: dict[str, str] = {}
    miss_log: dict[int, int] = {}  # tick_ns -> lateness_ns, the union of every /diagnostics' list
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
                miss_log.update((m.tick_ns, m.lateness_ns) for m in parse_miss_log(diag.get("deadline_miss_log", "")))

    node.create_subscription(Imu, "/sim/imu/data", on_imu, 100)
    node.create_subscription(DiagnosticArray, "/diagnostics", on_diag, 10)
    speed = node.create_publisher(Float64, "/vehicle/speed", 10)
    steer = node.create_publisher(Float64, "/vehicle/steering_wheel_angle", 10)
    ex = SingleThreadedExecutor(context=ctx)
    ex.add_node(node)
    spin = threading.Thread(target=ex.spin, daemon=True)
    spin.start()
    if probe_rt:
        from susp_sim_ros.ros.timing import raise_priority
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
        host.stop()
    if not diag:
        raise RuntimeError("no /diagnostics timing status received from susp_sim_node")
    la = np.asarray(lat, dtype=float) * 1e-6
    print("bench_node: node timing status: " + ", ".join(f"{k}={v}" for k, v in diag.items()), file=sys.stderr)
    misses = int(diag["deadline_misses"])
    tolerance_ns = host.period_ns + int(float(diag["lateness_p99_ms"]) * 1e6)
    att = attribute([Miss(t, late) for t, late in miss_log.items()], host.stalls, tolerance_ns)
    unlisted = max(0, misses - len(miss_log))  # more misses than the node could list: counted as the node's
    for m, st in att.explained:
        print(f"bench_node: miss at {m.tick_ns} late {m.lateness_ns * 1e-6:.2f} ms: host stall of "
              f"{st.lateness_ns * 1e-6:.2f} ms at {st.end_ns}", file=sys.stderr)
    for m in att.unexplained:
        print(f"bench_node: miss at {m.tick_ns} late {m.lateness_ns * 1e-6:.2f} ms: no host stall explains it",
              file=sys.stderr)
    big = sum(st.lateness_ns > 1e9 / rate_hz for st in host.stalls)
    print(f"bench_node: host probe: {host.wakes} wakes on {len(host.cpus)} CPUs, {len(host.stalls)} stalls "
          f">= 1 ms, {big} longer than a node period, max {host.lateness_max_ns * 1e-6:.2f} ms; tolerance "
          f"{tolerance_ns * 1e-6:.2f} ms" + "".join(f"; {n}" for n in host.notes), file=sys.stderr)
    return {
        "rtf": float(diag["real_time_factor"]),
        "jitter_p50_ms": float(diag["jitter_p50_ms"]),
        "jitter_p99_ms": float(diag["jitter_p99_ms"]),
        "jitter_max_ms": float(diag["jitter_max_ms"]),
        "latency_p50_ms": float(np.percentile(la, 50)) if la.size else float("nan"),
        "latency_p99_ms": float(np.percentile(la, 99)) if la.size else float("nan"),
        "deadline_misses": misses,
        "host_stall_max_ms": round(host.lateness_max_ns * 1e-6, 6),
        "misses_unexplained": len(att.unexplained) + unlisted,
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
