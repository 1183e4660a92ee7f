"""Launch-free tests of susp_sim_node: in-process with a private context and executor (sim time, the
driver publishes /clock and the inputs), asserting on the values the node publishes."""
from __future__ import annotations

import time

import numpy as np
import pytest

from _ros_helpers import SimDriver
from susp_sim_ros.io import messages as M
from susp_sim_ros.io.drive import Series, TestDrive
from susp_sim_ros.runtime.lockstep import maneuver_drive, run_lockstep
from susp_sim_ros.model import make_inputs, simulate
from susp_sim_ros.model.maneuvers import bump_crossing, sine_steer

T0 = 1_000_000_000
PERIOD = 10_000_000


@pytest.fixture
def driver(request):
    params = getattr(request, "param", None)
    d = SimDriver(params)
    yield d
    d.close()


def steady_drive(duration=5.0, speed=50 / 3.6, steer=0.5, rate=50.0) -> TestDrive:
    n = int(duration * rate) + 1
    t = T0 + np.round(np.arange(n) * 1e9 / rate).astype(np.int64)
    return TestDrive({"maneuver": "steady_steer"}, Series(t, np.full(n, speed)), Series(t, np.full(n, steer)))


def test_steady_steer_gives_the_models_steady_state_yaw_rate(driver, model_full):
    drive = steady_drive()
    driver.play(drive)
    t, g = driver.imu_arrays()
    n_ticks = int((drive.t_end_ns - T0) // PERIOD)
    assert len(t) == n_ticks
    np.testing.assert_array_equal(t, T0 + PERIOD * np.arange(1, n_ticks + 1))
    # the offline run with the same held inputs; tick k is after step 10k
    res = simulate(model_full, make_inputs(n_ticks * 10, 50 / 3.6, 0.5), dt=0.001)
    ref = res["YAW_RATE"][9::10]
    np.testing.assert_allclose(g[:, 2], ref, rtol=0, atol=1e-12)  # same compiled steps, same order
    # and it is a steady state: the last second varies by less than 0.1 %
    late = g[-100:, 2]
    assert late.mean() > 0.05  # left steer turns left (REP-103: positive yaw rate)
    assert np.ptp(late) < 1e-3 * abs(late.mean())


def test_bump_gives_the_offline_pitch_rate_response(driver, model_full):
    man = bump_crossing()
    drive = maneuver_drive(man, rate_hz=50.0)
    driver.play(drive)
    t, g = driver.imu_arrays()
    res = simulate(model_full, man.to_inputs(0.001), dt=0.001, road=man.road)
    ref = res["PITCH_RATE"][9::10]
    n = min(len(ref), len(t))
    assert n >= len(ref) - 1 and n >= len(t) - 1
    assert np.abs(ref).max() > 0.01  # the bump excites pitch
    np.testing.assert_allclose(g[:n, 1], ref[:n], rtol=0, atol=1e-12)  # constant inputs: identical run


def test_node_with_sim_time_equals_lockstep(driver, tmp_path):
    drive = maneuver_drive(sine_steer(duration=3.0), rate_hz=100.0)
    driver.play(drive)
    t, g = driver.imu_arrays()
    ls = run_lockstep(drive)
    np.testing.assert_array_equal(t, ls.t_ns)
    np.testing.assert_allclose(g, ls.imu.gyro, rtol=0, atol=1e-12)


@pytest.mark.slow
def test_fine_and_coarse_clock_give_the_same_outputs():
    """Clock in 1 ms steps (a slow replay) vs clock only at message times (a fast replay)."""
    drive = maneuver_drive(sine_steer(duration=1.5, lead_time=0.2), rate_hz=50.0)
    out = []
    for step in (1_000_000, None):
        d = SimDriver()
        try:
            d.play(drive, clock_step_ns=step)
            out.append(d.imu_arrays())
        finally:
            d.close()
    np.testing.assert_array_equal(out[0][0], out[1][0])
    np.testing.assert_array_equal(out[0][1], out[1][1])


def test_oil_level_change_at_run_time_takes_effect(driver):
    from rclpy.parameter import Parameter
    man = bump_crossing()
    drive = maneuver_drive(man, rate_hz=50.0)
    half = drive.t0_ns + int(0.6 * (drive.t_end_ns - drive.t0_ns)) // PERIOD * PERIOD
    # play the first part, change the oil, play the rest
    sp, st_ = drive.speed.t_ns <= half, drive.steering.t_ns <= half
    first = TestDrive(drive.metadata, Series(drive.speed.t_ns[sp], drive.speed.values[sp]),
                      Series(drive.steering.t_ns[st_], drive.steering.values[st_]), drive.road)
    driver.play(first)
    bad = driver.node.set_parameters([Parameter("damper_oil_level", value=[2.0, 1.0, 1.0, 1.0])])
    assert not bad[0].successful and "damper_oil_level" in bad[0].reason
    ok = driver.node.set_parameters([Parameter("damper_oil_level", value=[1.0, 1.0, 0.0, 0.0])])
    assert ok[0].successful
    np.testing.assert_array_equal(driver.node.core.oil, [1.0, 1.0, 0.0, 0.0])
    from susp_sim_ros.runtime.lockstep import _events
    for t, kind, i in _events(drive):
        if t <= half:
            continue
        driver.clock(t)
        driver.send_value("/vehicle/speed" if kind == 1 else "/vehicle/steering_wheel_angle",
                          (drive.speed if kind == 1 else drive.steering).values[i])
    driver.clock(drive.t_end_ns)
    t, g = driver.imu_arrays()
    intact = run_lockstep(drive, oil=(1, 1, 1, 1))
    empty_rear = run_lockstep(drive, oil=(1, 1, 0, 0))
    before = t <= half
    np.testing.assert_allclose(g[before, 1], intact.imu.gyro[before, 1], atol=1e-12)
    after = ~before
    assert np.abs(g[after, 1] - intact.imu.gyro[after, 1]).max() > 1e-4  # the change took effect
    assert np.abs(empty_rear.imu.gyro[:, 1] - intact.imu.gyro[:, 1]).max() > 1e-3


def test_friction_variant_change_at_run_time(driver):
    from rclpy.parameter import Parameter
    res = driver.node.set_parameters([Parameter("friction_variant", value="dahl_only")])
    assert res[0].successful
    assert driver.node.core.model.variant.name == "dahl_only"
    res = driver.node.set_parameters([Parameter("friction_variant", value="no_such_variant")])
    assert not res[0].successful
    res = driver.node.set_parameters([Parameter("step_s", value=0.002)])
    assert not res[0].successful and "read-only" in res[0].reason
    assert driver.node.core.step_ns == 1_000_000


def test_parameters_are_described_read_only_and_ranged(driver):
    """The descriptors say what may change at run time (ros2 param describe), rclpy enforces read-only
    and scalar ranges before the node's callbacks; a refused change leaves the node as it was."""
    from rclpy.parameter import Parameter
    from susp_sim_ros.ros.parameters import DEFAULTS, RUNTIME
    node = driver.node
    desc = dict(zip(DEFAULTS, node.describe_parameters(list(DEFAULTS))))
    assert {n for n, d in desc.items() if not d.read_only} == set(RUNTIME)
    assert all(d.description == DEFAULTS[n][1] for n, d in desc.items())
    rate = desc["publish_rate_hz"].floating_point_range[0]
    assert (rate.from_value, rate.to_value) == (0.0, 1000.0)
    assert desc["on_divergence"].additional_constraints == "exit or hold"
    prio = desc["realtime_priority"].integer_range[0]
    assert (prio.from_value, prio.to_value) == (0, 98)  # SCHED_FIFO 1..99, the tick thread one above
    assert all(desc[n].floating_point_range[0].from_value == 0.0
               for n in ("step_s", "input_timeout_s", "max_time_jump_s", "diagnostics_rate_hz",
                         "record_flush_interval_s", "sim_reorder_window_s"))
    for name, value in (("publish_rate_hz", 50.0), ("record_path", "x.mcap"), ("realtime_priority", 0),
                        ("use_sim_time", False)):
        res = node.set_parameters([Parameter(name, value=value)])
        assert not res[0].successful, name
    assert node.core.period_ns == 10_000_000 and node.sim_time
    # a run-time change refused by validation is not applied, nor half-applied with another one
    bad = node.set_parameters_atomically([Parameter("damper_oil_level", value=[0.5, 0.5, 0.5, 0.5]),
                                          Parameter("vehicle", value="no_such_vehicle")])
    assert not bad.successful
    np.testing.assert_array_equal(node.core.oil, [1.0, 1.0, 1.0, 1.0])
    assert node.get_parameter("damper_oil_level").value == [1.0, 1.0, 1.0, 1.0]
    ok = node.set_parameters_atomically([Parameter("damper_oil_level", value=[0.5, 0.5, 0.5, 0.5])])
    assert ok.successful
    np.testing.assert_array_equal(node.core.oil, [0.5, 0.5, 0.5, 0.5])
    assert node.diagnostics()[2]["values"]["damper_oil_level"] == "0.5,0.5,0.5,0.5"


def test_bad_inputs_are_rejected_not_integrated(driver):
    driver.clock(T0)
    driver.send_value("/vehicle/speed", 10.0)
    driver.send_value("/vehicle/steering_wheel_angle", 0.1)
    for v in (float("nan"), -1.0, float("inf")):
        driver.send_value("/vehicle/speed", v)
    driver.send_value("/vehicle/steering_wheel_angle", 20.0)
    driver.send_profile([0.0, 2.0, 1.0], [0.0] * 3, [0.0] * 3)  # non-increasing s
    driver.clock(T0 + 1_000_000)  # inputs take effect at the clock they followed
    core = driver.node.core
    assert core.speed == 10.0 and core.steering == 0.1 and core.road is None
    assert core.rejections == {"non_finite": 2, "speed_negative": 1, "steering_range": 1, "road_profile": 1}
    inputs = driver.node.diagnostics()[0]
    assert inputs["values"]["rejected_total"] == 5
    assert "strictly increasing" in inputs["values"]["last_rejection"]


def test_stale_inputs_are_reported(driver):
    driver.clock(T0)
    driver.send_value("/vehicle/speed", 5.0)
    driver.send_value("/vehicle/steering_wheel_angle", 0.0)
    driver.clock(T0 + 200_000_000)
    assert driver.node.diagnostics()[0]["level"] == 0
    driver.send_value("/vehicle/speed", 5.0)
    driver.clock(T0 + 800_000_000)  # steering 0.8 s old, speed 0.6 s old; timeout 0.5 s
    st = driver.node.diagnostics()[0]
    assert st["level"] == 1 and "/vehicle/steering_wheel_angle" in st["values"]["stale"]
    assert "/vehicle/speed" in st["values"]["stale"]


@pytest.mark.parametrize("driver", [{"record_path": ""}], indirect=True)
def test_diagnostics_published(driver):
    from diagnostic_msgs.msg import DiagnosticArray
    got = []
    driver.drv.create_subscription(DiagnosticArray, "/diagnostics", got.append, 10)
    driver.clock(T0)
    driver.send_value("/vehicle/speed", 5.0)
    driver.clock(T0 + 1_100_000_000)
    driver.spin_until(lambda: len(got) > 0)
    names = {s.name for s in got[-1].status}
    assert names == {"susp_sim_node: inputs", "susp_sim_node: timing", "susp_sim_node: model"}
    timing = {kv.key: kv.value for s in got[-1].status if s.name.endswith("timing") for kv in s.values}
    assert {"real_time_factor", "deadline_misses", "jitter_p99_ms"} <= set(timing)


def test_node_recording_equals_lockstep_recording(tmp_path):
    from susp_sim_ros.io.reader import read_recording
    drive = maneuver_drive(bump_crossing(), rate_hz=50.0)
    drive.speed.t_ns, drive.speed.values = drive.speed.t_ns[:120], drive.speed.values[:120]
    drive.steering.t_ns, drive.steering.values = drive.steering.t_ns[:120], drive.steering.values[:120]
    node_path, ls_path = tmp_path / "node.mcap", tmp_path / "ls.mcap"
    d = SimDriver({"record_path": str(node_path)})
    try:
        d.play(drive)
    finally:
        d.close()
    run_lockstep(drive, out_path=ls_path)
    a, b = read_recording(node_path), read_recording(ls_path)
    assert not a.truncated and a.metadata["test_drive"]["source"] == "simulated:full"
    assert b.metadata["test_drive"]["source"] == "simulated:full"
    for topic in ("/sim/imu/data", "/sim/odom", "/sim/suspension", "/vehicle/speed",
                  "/vehicle/steering_wheel_angle", "/road/profile"):
        ma, mb = a.decode_topic(topic), b.decode_topic(topic)
        assert [t for t, _ in ma] == [t for t, _ in mb], topic
        for (_, x), (_, y) in zip(ma, mb):
            assert _close(M.to_dict(x), M.to_dict(y)), topic
    assert a.latched("/road/profile") and b.latched("/road/profile")
    assert "/diagnostics" in a.topics()


def _close(x, y, tol=1e-12) -> bool:
    if isinstance(x, dict):
        return x.keys() == y.keys() and all(_close(x[k], y[k], tol) for k in x)
    if isinstance(x, list):
        return len(x) == len(y) and all(_close(a, b, tol) for a, b in zip(x, y))
    if isinstance(x, float) or isinstance(y, float):
        return abs(x - y) <= tol
    return x == y


def test_params_file_loads(tmp_path):
    """config/susp_sim_node.yaml has the shape ros2 expects and every key is a declared parameter."""
    import rclpy
    from pathlib import Path
    from susp_sim_ros.ros.node import SuspSimNode
    from susp_sim_ros.ros.parameters import DEFAULTS
    cfg = Path(__file__).resolve().parents[1] / "config" / "susp_sim_node.yaml"
    import yaml
    keys = set(yaml.safe_load(cfg.read_text())["susp_sim_node"]["ros__parameters"])
    assert keys == set(DEFAULTS)
    ctx = rclpy.Context()
    rclpy.init(context=ctx, args=["--ros-args", "--params-file", str(cfg),
                                  "-p", "damper_oil_level:=[1.0, 1.0, 0.5, 0.0]", "-p", "use_sim_time:=true"])
    try:
        node = SuspSimNode(context=ctx, start_thread=False)
        assert node.get_parameter("publish_rate_hz").value == 100.0
        np.testing.assert_array_equal(node.core.oil, [1.0, 1.0, 0.5, 0.0])
        assert node.core.period_ns == 10_000_000 and node.core.step_ns == 1_000_000
        node.destroy_node()
    finally:
        rclpy.try_shutdown(context=ctx)


class _ListRecorder:
    """Stands in for McapRecorder: keeps what the recording thread writes."""

    def __init__(self):
        self.written, self.closed = [], False

    def write(self, topic, msgtype, t_ns, data, latched=False):
        self.written.append((t_ns, topic, data))

    def flush_if_due(self):
        pass

    def close(self):
        self.closed = True


from hypothesis import given, settings, strategies as st  # noqa: E402


@settings(max_examples=150, deadline=None)
@given(st.lists(st.integers(-22_000_000, 22_000_000), min_size=1, max_size=60))
def test_recording_thread_writes_in_log_time_order(jitter):
    """Messages queued by two racing threads, up to 44 ms out of log-time order (within the 50 ms
    reorder window), are written sorted and none is lost; a message is held until one a window
    later has been queued (then it is on disk), and close writes the rest."""
    from susp_sim_ros.ros.recording import RECORD_REORDER_NS, RecordingQueue
    rec = _ListRecorder()
    q = RecordingQueue(rec, log_error=lambda text: None)
    times = [1_000_000_000 + k * 10_000_000 + j for k, j in enumerate(jitter)]  # 100 Hz ticks, jittered
    for k, t in enumerate(times):
        q.write("/sim/imu/data" if k % 2 else "/diagnostics", "x", t, bytes([k % 256]))
    q.flush_if_due()
    deadline = time.monotonic() + 5
    newest = max(times)
    due = sorted(t for t in times if t <= newest - RECORD_REORDER_NS)
    while len(rec.written) < len(due) and time.monotonic() < deadline:
        time.sleep(0.001)
    assert [w[0] for w in rec.written] == due          # written as soon as a window-later one came
    q.close()
    assert rec.closed and [w[0] for w in rec.written] == sorted(times)
    assert len(rec.written) == len(times)


@pytest.mark.parametrize("module,ros_args,expected", [
    ("susp_sim_ros.ros.node", ["-p", "realtime_priority:=99"], "realtime_priority"),    # descriptor range
    ("susp_sim_ros.ros.node", ["-p", "step_s:=-0.001"], "step_s"),                      # descriptor range
    ("susp_sim_ros.ros.node", ["-p", "diagnostics_rate_hz:=0.0"], "diagnostics_rate_hz"),
    ("susp_sim_ros.ros.node", ["-p", "on_divergence:=explode"], "on_divergence"),
    ("susp_sim_ros.ros.controller_node", ["-p", "sample_time_s:=0.5"], "sample_time_s"),  # descriptor range
    ("susp_sim_ros.ros.controller_node", ["-p", "sample_time_s:=0.0"], "sample_time_s"),
    ("susp_sim_ros.ros.controller_node", ["-p", "controller:=no_such_law"], "no_such_law"),
])
def test_entry_points_refuse_a_bad_parameter_with_exit_code_2(module, ros_args, expected, capsys):
    """Both nodes' ``main`` (the shared run_node): a bad parameter is one line on stderr naming it, exit
    code 2, no traceback, and rclpy is shut down again."""
    import importlib
    import rclpy
    from _ros_helpers import ros_env
    ros_env()
    main = importlib.import_module(module).main
    assert main(["prog", "--ros-args", *ros_args]) == 2
    err = capsys.readouterr().err
    assert expected in err and "Traceback" not in err and err.count("error:") == 1
    assert not rclpy.ok()


def test_a_shutdown_between_two_waits_is_a_normal_stop(capsys):
    """SIGINT shuts rclpy's context down from its signal handler at any moment; when that falls between
    run_node's ``rclpy.ok()`` and the executor's next wait, the wait fails (RCLError, invalid context).
    Reproduced deterministically: ``stop_when`` shuts the context down and says "go on"."""
    import rclpy
    from rclpy.node import Node
    from _ros_helpers import ros_env
    from susp_sim_ros.ros.run import run_node
    ros_env()

    def shut_down_now(node):
        rclpy.shutdown()
        return False

    assert run_node(lambda: Node("shutdown_race_probe"), "probe", ["prog"], stop_when=shut_down_now) == 0
    assert "Traceback" not in capsys.readouterr().err
    assert not rclpy.ok()


def test_a_real_time_node_spins_with_its_start_up_heap_collected_and_frozen(monkeypatch):
    """run_node(realtime=True) collects and freezes the start-up heap after the node is made and before the
    executor first spins (a full collection in real time held the GIL for 90-200 ms)."""
    import sys
    from rclpy.node import Node
    from _ros_helpers import ros_env
    from susp_sim_ros.ros import run
    ros_env()
    order: list[str] = []
    monkeypatch.setattr(run, "freeze_start_up_heap", lambda: order.append("freeze"))

    def make():
        order.append("make")
        return Node("freeze_order_probe")

    def stop(node):
        order.append("spin")
        return True

    interval = sys.getswitchinterval()
    try:
        assert run.run_node(make, "probe", ["prog"], realtime=True, stop_when=stop) == 0
    finally:
        sys.setswitchinterval(interval)
    assert order == ["make", "freeze", "spin"]


def test_wall_time_begins_when_the_executor_first_spins():
    """No tick thread (and so no /sim sample, which would provoke a controller's commands) before the
    executor spins: inputs that arrive then would wait in DDS while the process still starts up (measured:
    the first commands 150-190 ms late). The first spin starts it, once; a node
    closed before it spins never starts it."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from _ros_helpers import ros_env
    from susp_sim_ros.ros.node import SuspSimNode
    ros_env()
    ctx = rclpy.Context()
    rclpy.init(context=ctx)
    try:
        from rclpy.parameter import Parameter
        # no SCHED_FIFO for this (the test) process's threads: later tests would inherit it
        node = SuspSimNode(context=ctx, parameter_overrides=[Parameter("realtime_priority", value=0)])
        try:
            assert node._ticker is None and not node.core.started
            ex = SingleThreadedExecutor(context=ctx)
            ex.add_node(node)
            end = time.monotonic() + 10.0
            while not node.core.started and time.monotonic() < end:
                ex.spin_once(timeout_sec=0.05)
            ticker = node._ticker
            assert ticker is not None and node.core.started
            ex.spin_once(timeout_sec=0.05)
            assert node._ticker is ticker and node._start_timer is None
            assert len(list(node.timers)) == 1  # the one-shot timer is gone; only the diagnostics timer is left
            ex.shutdown()
        finally:
            node.destroy_node()
        closed = SuspSimNode(context=ctx, parameter_overrides=[Parameter("realtime_priority", value=0)])
        try:
            closed.close()
            ex = SingleThreadedExecutor(context=ctx)
            ex.add_node(closed)
            ex.spin_once(timeout_sec=0.05)
            ex.spin_once(timeout_sec=0.05)
            assert closed._ticker is None and not closed.core.started
            ex.shutdown()
        finally:
            closed.destroy_node()
    finally:
        rclpy.try_shutdown(context=ctx)


def test_controller_parameters_are_read_only_and_ranged():
    """The controller reads its parameters at start only: rclpy refuses a change instead of accepting one
    that would have no effect; the sample period's range is in its descriptor."""
    import rclpy
    from rclpy.parameter import Parameter
    from _ros_helpers import ros_env
    from susp_sim_ros.ros.controller_node import MAX_SAMPLE_TIME_S, DamperControllerNode
    ros_env()
    ctx = rclpy.Context()
    rclpy.init(context=ctx)
    try:
        node = DamperControllerNode(context=ctx)
        desc = dict(zip(("controller", "sample_time_s", "vehicle"),
                        node.describe_parameters(["controller", "sample_time_s", "vehicle"])))
        assert all(d.read_only for d in desc.values())
        period = desc["sample_time_s"].floating_point_range[0]
        assert (period.from_value, period.to_value) == (0.0, MAX_SAMPLE_TIME_S)
        assert "groundhook" in desc["controller"].additional_constraints
        res = node.set_parameters([Parameter("controller", value="groundhook")])
        assert not res[0].successful and node.get_parameter("controller").value == "skyhook"
        node.destroy_node()
    finally:
        rclpy.try_shutdown(context=ctx)


@settings(max_examples=200, deadline=None)
@given(st.integers(-2**31, 2**31 - 1), st.integers(0, 2**32 - 1))
def test_clock_time_is_read_or_refused(sec, nanosec):
    """One reading of /clock for rclpy's time source guard and the node's own /clock callback: a valid
    time in ns, None for a negative second or nanoseconds outside [0, 1e9)."""
    from rosgraph_msgs.msg import Clock
    from susp_sim_ros.ros.conversion import clock_time_ns
    m = Clock()
    m.clock.sec, m.clock.nanosec = sec, nanosec
    valid = sec >= 0 and nanosec < 1_000_000_000
    assert clock_time_ns(m) == (sec * 1_000_000_000 + nanosec if valid else None)
