"""Soak benchmark: susp_sim_node in real time for a long run, inputs at 100 Hz, recording on.

Starts ``susp_sim_node`` in a subprocess (wall time, defaults: 1 ms step, 100 Hz publishing, its threads
at SCHED_FIFO when permitted) recording to an MCAP file, publishes a road profile (latched) and speed and
steering at ``--rate`` from this process for ``--duration`` seconds, samples the node's resident memory
(RSS) every second, then stops the node with SIGINT (a clean shutdown finalises the recording) and
checks the recording. Reported (``--json``: one JSON object on stdout, logs on stderr):

- ``rss_growth_after_warmup_mb``: highest RSS after the warm-up minus the RSS at the end of the warm-up
  (``--warmup``, default 30 s; 5 s for runs of 60 s or less); also ``rss_*_mb`` at start/warm-up/end/max;
- ``deadline_misses`` (ticks published more than one period late), ``ticks``, ``rtf``, ``jitter_p99_ms``
  and ``jitter_max_ms``, from the node's last ``/diagnostics``;
- ``host_stall_max_ms`` and ``misses_unexplained`` as in ``bench_node.py``: the longest stall a plain
  sleeping-thread probe (:mod:`host_probe`) saw during the run, and the misses no host stall
  explains (:mod:`susp_sim_ros.analysis.host_stalls`); ``misses_by_host`` lists the explained ones,
  ``misses_not_by_host`` the others with the nearest stall and the host time (any CPU) inside each,
  ``timeline_near_unexplained`` every miss and stall within 100 ms of them;
- the recording: ``published_inputs`` (what this process sent) and ``recorded_inputs`` per topic,
  ``recorded_sim`` per ``/sim`` topic, ``sim_gaps`` (missing 10 ms ticks in the recorded
  ``/sim/imu/data`` stamps), ``sequence_gaps`` (per topic), ``node_published_samples``, and
  ``recording_complete``: every input sent is recorded, the three ``/sim`` topics hold the same number of
  samples, no tick is missing and no sequence number skipped, the file is finalised;
- ``node_exit_code`` (0 after SIGINT), ``rejected_inputs`` (0 expected);
- for attributing misses: ``misses_at`` (seconds into the run with new misses), the CPU share of the
  other processes, this one included (``machine_busy_other_mean``/``_max``, per second, fraction of all
  CPUs, from per-process accounting),
  ``steal_mean``/``_max`` (hypervisor steal), ``node_cpu_fraction`` and ``other_realtime_busy`` (other
  processes' SCHED_FIFO/RR threads busy during the run: with the kernel's RT throttling they can stall the
  node's real-time threads for up to 50 ms; two real-time benchmarks at once on 2 cores do).

``run_soak`` is also used by the 20-second version in ``test/test_reliability_soak.py``.
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
from susp_sim_ros.analysis.host_stalls import Miss, attribute, host_time, parse_miss_log  # noqa: E402

MB = 1024 * 1024


def ros_env() -> dict[str, str]:
    """This process's environment for ROS 2 (isolated domain, localhost, writable log dir)."""
    env = dict(os.environ)
    env.setdefault("ROS_DOMAIN_ID", str(random.randint(1, 101)))
    env.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    env.setdefault("ROS_LOG_DIR", tempfile.mkdtemp(prefix="susp_soak_log_"))
    os.environ.update({k: env[k] for k in ("ROS_DOMAIN_ID", "ROS_AUTOMATIC_DISCOVERY_RANGE", "ROS_LOG_DIR")})
    return env


def start_node(record_path: str | Path, params: dict | None = None, env: dict | None = None,
               log=None, remap: dict[str, str] | None = None) -> subprocess.Popen:
    """``susp_sim_node`` in a subprocess recording to ``record_path`` (``params``: more -p overrides;
    ``remap``: topic remappings ``{from: to}``, -r)."""
    args = [sys.executable, "-c", "import sys; from susp_sim_ros.ros.node import main; sys.exit(main())",
            "--ros-args", "-p", f"record_path:={record_path}"]
    for k, v in (params or {}).items():
        args += ["-p", f"{k}:={v}"]
    for a, b in (remap or {}).items():
        args += ["-r", f"{a}:={b}"]
    return subprocess.Popen(args, env=env or ros_env(), stdout=log or sys.stderr, stderr=subprocess.STDOUT)


class Probe:
    """This process's side: publishes the inputs (profile latched, speed and steering at ``rate_hz`` from
    a thread), listens to ``/diagnostics``, counts what it sent."""

    def __init__(self, rate_hz: float = 100.0, realtime: bool = True):
        import rclpy
        from diagnostic_msgs.msg import DiagnosticArray
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from std_msgs.msg import Float64, Float64MultiArray, MultiArrayDimension
        self.rclpy, self.Float64 = rclpy, Float64
        self.rate_hz = rate_hz
        self.ctx = rclpy.Context()
        rclpy.init(context=self.ctx)
        self.node = rclpy.create_node("susp_soak_probe", context=self.ctx)
        self.diag: dict[str, dict[str, str]] = {}
        self.timeline: list[tuple[float, int, float]] = []  # (monotonic, deadline misses, jitter max) per /diagnostics
        self.miss_log: dict[int, int] = {}  # tick_ns -> lateness_ns, the union of the node's deadline_miss_log
        self.node.create_subscription(DiagnosticArray, "/diagnostics", self._on_diag, 10)
        self.speed = self.node.create_publisher(Float64, "/vehicle/speed", 100)
        self.steer = self.node.create_publisher(Float64, "/vehicle/steering_wheel_angle", 100)
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL,
                             reliability=ReliabilityPolicy.RELIABLE)
        self.profile = self.node.create_publisher(Float64MultiArray, "/road/profile", latched)
        s = np.arange(0.0, 2000.0, 0.05)  # a gently rough road with a bump every 40 m
        z = 0.005 * np.sin(2 * np.pi * s / 3.1) + 0.04 * np.maximum(0.0, np.cos(2 * np.pi * s / 40.0)) ** 40
        m = Float64MultiArray()
        m.layout.dim = [MultiArrayDimension(label="channel", size=3, stride=3 * s.size),
                        MultiArrayDimension(label="sample", size=s.size, stride=s.size)]
        m.data = np.concatenate([s, z, 0.8 * z]).tolist()
        self.profile.publish(m)
        self.sent = {"/vehicle/speed": 0, "/vehicle/steering_wheel_angle": 0, "/road/profile": 1}
        self.ex = SingleThreadedExecutor(context=self.ctx)
        self.ex.add_node(self.node)
        self._spin = threading.Thread(target=self.ex.spin, daemon=True)
        self._spin.start()
        self._stop = threading.Event()
        self._pub: threading.Thread | None = None
        if realtime:
            from susp_sim_ros.ros.timing import raise_priority
            note = raise_priority(5)
            if note:
                print(f"soak probe: {note}", file=sys.stderr)

    def _on_diag(self, msg) -> None:
        for st in msg.status:
            self.diag[st.name.split(": ")[-1]] = {kv.key: kv.value for kv in st.values}
        t = self.diag.get("timing", {})
        self.miss_log.update((m.tick_ns, m.lateness_ns) for m in parse_miss_log(t.get("deadline_miss_log", "")))
        self.timeline.append((time.monotonic(), int(t.get("deadline_misses", 0)), float(t.get("jitter_max_ms", 0))))

    def wait_for(self, proc: subprocess.Popen, timeout: float = 60.0) -> None:
        """Until both sides of discovery are through: the node's subscriptions match our publishers and
        its /diagnostics reach us (its publisher matched our subscription), then a settling second."""
        end = time.monotonic() + timeout
        while self.speed.get_subscription_count() == 0 or self.steer.get_subscription_count() == 0 \
                or self.profile.get_subscription_count() == 0 or not self.timeline:
            if time.monotonic() > end or proc.poll() is not None:
                raise RuntimeError("susp_sim_node did not come up (no subscriber on the input topics)")
            time.sleep(0.02)
        time.sleep(1.0)

    def start_publishing(self) -> None:
        def loop():
            t0 = time.monotonic()
            k = 0
            while not self._stop.is_set():
                t = k / self.rate_hz
                self.speed.publish(self.Float64(data=50.0 / 3.6 + 2.0 * math.sin(2 * math.pi * 0.05 * t)))
                self.steer.publish(self.Float64(data=0.5 * math.sin(2 * math.pi * 0.2 * t)))
                self.sent["/vehicle/speed"] += 1
                self.sent["/vehicle/steering_wheel_angle"] += 1
                k += 1
                self._stop.wait(max(0.0, t0 + k / self.rate_hz - time.monotonic()))
        self._pub = threading.Thread(target=loop, name="soak_inputs", daemon=True)
        self._pub.start()

    def stop_publishing(self) -> None:
        self._stop.set()
        if self._pub is not None:
            self._pub.join()

    def close(self) -> None:
        self.stop_publishing()
        self.ex.shutdown()
        self.node.destroy_node()
        self.rclpy.try_shutdown(context=self.ctx)


def cpu_times() -> tuple[float, float, float]:
    """Machine-wide (busy, idle, steal) CPU seconds since boot (/proc/stat; steal: time the hypervisor
    gave our virtual CPUs to someone else)."""
    with open("/proc/stat") as f:
        v = [int(x) for x in f.readline().split()[1:]]
    tick = os.sysconf("SC_CLK_TCK")
    idle = v[3] + v[4]
    steal = v[7] if len(v) > 7 else 0
    return (sum(v[:8]) - idle - steal) / tick, idle / tick, steal / tick


class OtherProcessesCpu:
    """CPU seconds used by all other processes since the last call (per-process accounting from
    /proc/PID/stat; the machine-wide busy time of /proc/stat is sampled at the scheduler tick and misses
    most of a process that wakes 1000 times a second for a few microseconds, like the node)."""

    def __init__(self, exclude: set[int]):
        self.exclude = exclude
        self.seen = self._sample()

    def _sample(self) -> dict[int, float]:
        out = {}
        for pid in os.listdir("/proc"):
            if pid.isdigit() and int(pid) not in self.exclude:
                try:
                    out[int(pid)] = proc_cpu_s(int(pid))
                except (OSError, IndexError, ValueError):
                    continue
        return out

    def delta(self) -> float:
        now = self._sample()
        d = sum(c - self.seen.get(pid, 0.0) for pid, c in now.items())  # a new process: all of its CPU
        self.seen = now
        return max(d, 0.0)


def proc_cpu_s(pid: int) -> float:
    with open(f"/proc/{pid}/stat") as f:
        parts = f.read().rsplit(")", 1)[1].split()
    return (int(parts[11]) + int(parts[12])) / os.sysconf("SC_CLK_TCK")


def rt_threads(exclude: set[int]) -> dict[tuple[int, int], tuple[str, float]]:
    """Real-time (SCHED_FIFO/RR) user threads of other processes: {(pid, tid): (name, CPU seconds)}.
    Under the kernel's RT throttling (95 % of each second), other busy real-time threads can stall the
    node's real-time threads for up to 50 ms: the usual cause of deadline misses on a shared machine."""
    out = {}
    tick = os.sysconf("SC_CLK_TCK")
    for pid in os.listdir("/proc"):
        if not pid.isdigit() or int(pid) in exclude:
            continue
        try:
            for tid in os.listdir(f"/proc/{pid}/task"):
                with open(f"/proc/{pid}/task/{tid}/stat") as f:
                    name, rest = f.read().rsplit(")", 1)
                parts = rest.split()
                # fields after the name: parts[0] = state (field 3); policy is field 41, flags field 9
                if int(parts[38]) in (1, 2) and not int(parts[6]) & 0x00200000:  # not a kernel thread
                    out[(int(pid), int(tid))] = (name.split("(", 1)[1], (int(parts[11]) + int(parts[12])) / tick)
        except (OSError, IndexError, ValueError):
            continue
    return out


def rss_bytes(pid: int) -> int:
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    return 0


def check_recording(path: Path, sent: dict[str, int], period_ns: int = 10_000_000) -> dict:
    """Message counts, missing ticks and sequence gaps of the node's recording."""
    from rclpy.serialization import deserialize_message
    from sensor_msgs.msg import Imu
    from susp_sim_ros.io.reader import read_recording
    rec = read_recording(path)
    counts: dict[str, int] = {}
    seq_gaps: dict[str, int] = {}
    for topic in sorted(rec.topics()):
        msgs = rec.by_topic(topic)
        counts[topic] = len(msgs)
        seq = np.array([m.sequence for m in msgs], dtype=np.int64)
        seq_gaps[topic] = int(np.count_nonzero(np.diff(seq) != 1)) + (int(seq[0] != 1) if seq.size else 0)
    stamps = np.array([(lambda i: i.header.stamp.sec * 1_000_000_000 + i.header.stamp.nanosec)(
        deserialize_message(m.data, Imu)) for m in rec.by_topic("/sim/imu/data")], dtype=np.int64)
    d = np.diff(stamps)
    sim_gaps = int(np.sum(np.maximum(d // period_ns - 1, 0))) + int(np.count_nonzero(d % period_ns))
    inputs = {t: counts.get(t, 0) for t in sent}
    sim = {t: counts.get(t, 0) for t in ("/sim/imu/data", "/sim/odom", "/sim/suspension")}
    why = [w for w, bad in (
        (f"inputs recorded {inputs} != sent {dict(sent)}", inputs != dict(sent)),
        (f"/sim topics differ {sim}", len(set(sim.values())) != 1 or sim["/sim/imu/data"] == 0),
        (f"{sim_gaps} missing ticks", sim_gaps != 0), (f"sequence gaps {seq_gaps}", any(seq_gaps.values())),
        ("not finalised", not rec.finalised or rec.truncated)) if bad]
    complete = not why
    return {"recorded_inputs": inputs, "recorded_sim": sim, "recorded_diagnostics": counts.get("/diagnostics", 0),
            "sim_gaps": sim_gaps, "sequence_gaps": seq_gaps, "finalised": rec.finalised,
            "recording_complete": bool(complete), "incomplete_because": why,
            "recording_bytes": path.stat().st_size}


def _nearest_stall(m, stalls, t_wall0_ns: int) -> dict:
    """A miss the host does not explain, with the probe's longest stall within 50 ms of it and the host
    time inside it, any CPU (for the reader)."""
    near = [st for st in stalls if st.start_ns - 50_000_000 <= m.end_ns and st.end_ns + 50_000_000 >= m.tick_ns]
    st = max(near, key=lambda x: x.lateness_ns) if near else None
    return {"t_s": round((m.tick_ns - t_wall0_ns) * 1e-9, 3), "late_ms": round(m.lateness_ns * 1e-6, 2),
            "nearest_stall_ms": round(st.lateness_ns * 1e-6, 2) if st else None,
            "nearest_stall_at_s": round((st.end_ns - t_wall0_ns) * 1e-9, 3) if st else None,
            "host_ms_inside": round(host_time(stalls, m.tick_ns, m.end_ns) * 1e-6, 2)}


def _timeline_near(unexplained, misses, stalls, t_wall0_ns: int, window_ns: int = 100_000_000) -> dict:
    """Misses and host stalls within ``window_ns`` of an unexplained miss (at most 200 of each), as
    ``{"misses": [[t_s, late_ms]], "stalls": [[cpu, start_s, end_s, late_ms]]}``."""
    def near(a, b):
        return any(a - window_ns <= m.end_ns and b + window_ns >= m.tick_ns for m in unexplained)
    s = lambda ns: round((ns - t_wall0_ns) * 1e-9, 4)
    return {"misses": [[s(m.tick_ns), round(m.lateness_ns * 1e-6, 2)] for m in sorted(misses, key=lambda m: m.tick_ns)
                       if near(m.tick_ns, m.end_ns)][:200],
            "stalls": [[st.cpu, s(st.start_ns), s(st.end_ns), round(st.lateness_ns * 1e-6, 2)] for st in stalls
                       if near(st.start_ns, st.end_ns)][:200]}


def run_soak(duration: float = 300.0, warmup: float | None = None, rate_hz: float = 100.0,
             out_dir: str | Path | None = None, realtime_probe: bool = True) -> dict:
    warmup = (5.0 if duration <= 60 else 30.0) if warmup is None else warmup
    env = ros_env()
    out_dir = Path(out_dir or tempfile.mkdtemp(prefix="susp_soak_"))
    path = out_dir / "soak.mcap"
    if path.exists():
        path.unlink()
    host = HostProbe(max_duration_s=duration + 300.0).start()  # the machine's own stalls, whole run
    try:
        probe = Probe(rate_hz, realtime=realtime_probe)
    except BaseException:
        host.__exit__(*sys.exc_info())
        raise
    proc = start_node(path, env=env)
    rss: list[tuple[float, int]] = []
    # (t, machine busy, idle, steal, node CPU, other processes' CPU in the last interval) [s]
    load: list[tuple[float, float, float, float, float, float]] = []
    rt_seen: dict = {}
    rt_busy: list = []  # (t, other real-time threads that used > 50 ms CPU in the last second)
    try:
        probe.wait_for(proc)
        others = OtherProcessesCpu({proc.pid})
        probe.start_publishing()
        t0 = time.monotonic()
        t_wall0 = time.time_ns()
        while time.monotonic() - t0 < duration:
            if proc.poll() is not None:
                raise RuntimeError(f"susp_sim_node exited during the soak (code {proc.returncode})")
            rss.append((time.monotonic() - t0, rss_bytes(proc.pid)))
            load.append((time.monotonic() - t0, *cpu_times(), proc_cpu_s(proc.pid), others.delta()))
            rt = rt_threads({proc.pid, os.getpid(), *host.pids})  # the host probes are ours, by design
            busy_rt = sorted({f"{n}[{pid}]" for k, (n, c) in rt.items() if c - rt_seen.get(k, c) > 0.05
                              for pid in (k[0],)})
            rt_seen.update({k: c for k, (n, c) in rt.items()})
            if busy_rt:
                rt_busy.append((round(time.monotonic() - t0, 1), busy_rt))
            time.sleep(min(1.0, max(0.0, duration - (time.monotonic() - t0))))
        rss.append((time.monotonic() - t0, rss_bytes(proc.pid)))
        load.append((time.monotonic() - t0, *cpu_times(), proc_cpu_s(proc.pid), others.delta()))
        probe.stop_publishing()
        time.sleep(1.2)  # the last inputs are taken; a final /diagnostics covers the whole run
        diag = {k: dict(v) for k, v in probe.diag.items()}
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)
        try:
            code = proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
            code = proc.wait()
        sent = dict(probe.sent)
        probe.close()
        host.stop()
    t = np.array([x for x, _ in rss])
    r = np.array([y for _, y in rss], dtype=float) / MB
    at_warm = float(np.interp(warmup, t, r))
    after = r[t >= warmup]
    timing, inputs, model = diag.get("timing", {}), diag.get("inputs", {}), diag.get("model", {})
    # machine load per second, and the seconds in which deadline misses happened (for attribution)
    L = np.array(load)
    dt = np.diff(L[:, 0])
    ncpu = os.cpu_count() or 1
    busy_other = L[1:, 5] / dt / ncpu  # busy fraction of the other processes (this one included)
    steal = np.diff(L[:, 3]) / dt / ncpu
    miss_at = []
    for (ta, ma, _), (tb, mb, jb) in zip(probe.timeline, probe.timeline[1:]):
        if mb > ma:  # misses within the second before this /diagnostics; the load around it
            near = (L[1:, 0] >= ta - t0 - 1.5) & (L[1:, 0] <= tb - t0 + 1.5)
            miss_at.append({"t_s": round(tb - t0, 1), "misses": mb - ma, "jitter_max_ms": jb,
                            "busy_other_max": float(busy_other[near].max()) if near.any() else None,
                            "steal_max": float(steal[near].max()) if near.any() else None})
    misses = int(timing.get("deadline_misses", -1))
    tolerance_ns = host.period_ns + int(float(timing.get("lateness_p99_ms", 0.0)) * 1e6)
    logged = [Miss(t_, late) for t_, late in probe.miss_log.items()]
    att = attribute(logged, host.stalls, tolerance_ns)
    res = {
        "duration_s": duration, "warmup_s": warmup, "rate_hz": rate_hz,
        "rss_start_mb": float(r[0]), "rss_after_warmup_mb": at_warm, "rss_end_mb": float(r[-1]),
        "rss_max_mb": float(r.max()),
        "rss_growth_after_warmup_mb": float(after.max() - at_warm) if after.size else 0.0,
        "deadline_misses": misses, "ticks": int(timing.get("ticks", 0)),
        "host_stall_max_ms": round(host.lateness_max_ns * 1e-6, 6),
        "misses_unexplained": len(att.unexplained) + max(0, misses - len(probe.miss_log)),
        "misses_by_host": [{"late_ms": round(m.lateness_ns * 1e-6, 2), "host_stall_ms": round(st.lateness_ns * 1e-6, 2)}
                           for m, st in att.explained][:20],
        "misses_not_by_host": [_nearest_stall(m, host.stalls, t_wall0) for m in att.unexplained][:20],
        # the raw timeline around them, for a reader who wants to weigh them: every miss and every stall
        # (CPU, ms) within 100 ms of an unexplained miss, seconds into the run
        "timeline_near_unexplained": _timeline_near(att.unexplained, logged, host.stalls, t_wall0),
        "rtf": float(timing.get("real_time_factor", "nan")), "jitter_p99_ms": float(timing.get("jitter_p99_ms", "nan")),
        "jitter_max_ms": float(timing.get("jitter_max_ms", "nan")),
        "rejected_inputs": int(inputs.get("rejected_total", -1)),
        "node_published_samples": int(model.get("published_samples", 0)),
        "node_exit_code": code, "published_inputs": sent,
        "misses_at": miss_at,
        "machine_busy_other_mean": float(busy_other.mean()), "machine_busy_other_max": float(busy_other.max()),
        "steal_mean": float(steal.mean()), "steal_max": float(steal.max()),
        "node_cpu_fraction": float((L[-1, 4] - L[0, 4]) / (L[-1, 0] - L[0, 0])),
        "other_realtime_busy": rt_busy[:20],
    }
    res.update(check_recording(path, sent))
    res["recording"] = str(path)
    return res


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    ap.add_argument("--duration", type=float, default=300.0, help="soak length [s] (default 300)")
    ap.add_argument("--warmup", type=float, default=None, help="warm-up before the RSS baseline [s] "
                    "(default 30; 5 for runs of 60 s or less)")
    ap.add_argument("--rate", type=float, default=100.0, help="input rate [Hz] (default 100)")
    ap.add_argument("--out", default=None, help="folder for the recording (default: a temporary one)")
    ap.add_argument("--probe-normal-priority", action="store_true",
                    help="run the input publisher without real-time scheduling")
    a = ap.parse_args(argv)
    res = run_soak(a.duration, a.warmup, a.rate, a.out, realtime_probe=not a.probe_normal_priority)
    if a.json:
        print(json.dumps(res))
    else:
        for k, v in res.items():
            print(f"{k}: {v}")
    ok = (res["rss_growth_after_warmup_mb"] < 5.0 and res["misses_unexplained"] == 0 and res["recording_complete"]
          and res["node_exit_code"] == 0)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
