"""Foxglove (and Lichtblick) open our recordings: every schema parses with the real ``@foxglove/rosmsg``
and every message decodes with ``@foxglove/rosmsg2-serialization`` (test/foxglove/check.mjs, pinned in
test/foxglove/package-lock.json, installed by scripts/setup.sh).

Checked: the bundled drives, a fresh offline recording (``susp sim``), a node recording and a file with
every message type we write. Message counts per topic must match the Python reader, and the first message
of each topic must decode to the same values as in Python.
"""
from __future__ import annotations

import json
import math
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from susp_sim_ros.io import messages as M
from susp_sim_ros.io.reader import read_recording

ROOT = Path(__file__).resolve().parents[1]
FOX = ROOT / "test" / "foxglove"
CHECK = FOX / "check.mjs"
NODE, NPM = shutil.which("node"), shutil.which("npm")

pytestmark = pytest.mark.skipif(
    NODE is None or NPM is None,
    reason="node/npm not installed: Foxglove's message parser (test/foxglove) cannot run here; "
           "install Node.js >= 18 with npm and run scripts/setup.sh")


def foxglove_check(paths: list[Path]) -> dict:
    """Run check.mjs on ``paths``; its JSON report (asserting it ran)."""
    if not (FOX / "node_modules" / "@foxglove" / "rosmsg").is_dir():
        pytest.fail(f"{FOX}/node_modules is not installed: run `bash scripts/setup.sh` (npm ci there)")
    r = subprocess.run([NODE, str(CHECK), "--json", "--samples", *map(str, paths)], capture_output=True,
                       text=True, timeout=600, cwd=FOX)
    assert r.returncode in (0, 1), f"check.mjs failed to run (exit {r.returncode}): {r.stderr}"
    return json.loads(r.stdout)


def _same(x, y, where: str = "") -> None:
    if isinstance(x, dict):
        assert isinstance(y, dict) and x.keys() == y.keys(), f"{where}: {sorted(x)} != {sorted(y)}"
        for k in x:
            _same(x[k], y[k], f"{where}.{k}")
    elif isinstance(x, list):
        assert isinstance(y, list) and len(x) == len(y), f"{where}: length {len(x)} != {len(y)}"
        for i, (a, b) in enumerate(zip(x, y)):
            _same(a, b, f"{where}[{i}]")
    elif isinstance(x, float) or isinstance(y, float):
        assert (math.isnan(x) and math.isnan(y)) or x == y, f"{where}: {x!r} != {y!r}"
    else:
        assert x == y, f"{where}: {x!r} != {y!r}"


def assert_foxglove_reads(paths: list[Path]) -> dict:
    """Every file parsed and decoded by Foxglove, with the Python reader's per-topic counts and values."""
    report = foxglove_check(paths)
    failed = [f"{f['path']}: {f['error']}" for f in report["files"] if not f["ok"]]
    assert not failed, "Foxglove cannot open:\n" + "\n".join(failed)
    assert report["parsed"] == report["total"] == len(paths)
    total = 0
    for path, got in zip(paths, report["files"]):
        rec = read_recording(path)
        assert not rec.truncated and not rec.corrupt
        want = {}
        for m in rec.messages:
            want[m.topic] = want.get(m.topic, 0) + 1
        assert got["topics"] == want, path
        assert got["messages"] == len(rec.messages) > 0, path
        assert sorted(got["schemas"]) == sorted({s.name for s in rec.schemas.values()}), path
        for topic, sample in got["samples"].items():
            _same(M.to_dict(rec.decode_topic(topic)[0][1]), sample, f"{path.name}:{topic}")
        total += len(rec.messages)
    assert report["messages"] == total
    return report


def test_bundled_drives():
    paths = sorted((ROOT / "bags").glob("*.mcap"))
    assert len(paths) == 6
    report = assert_foxglove_reads(paths)
    assert report["messages"] == 3 * 2375 + 3 * 3202  # bags/README.md: six drives


def test_fresh_offline_recording(tmp_path):
    out = tmp_path / "X.mcap"
    r = subprocess.run([sys.executable, "-m", "susp_sim_ros.cli.main", "sim", "--maneuver", "bump",
                        "--state", "rear_empty", "--out", str(out)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    report = assert_foxglove_reads([out])
    assert {"/sim/imu/data", "/sim/odom", "/sim/suspension", "/road/profile", "/vehicle/speed",
            "/vehicle/steering_wheel_angle"} <= set(report["files"][0]["topics"])


def test_node_recording(tmp_path):
    from _ros_helpers import SimDriver
    from susp_sim_ros.runtime.lockstep import maneuver_drive
    from susp_sim_ros.model.maneuvers import bump_crossing
    drive = maneuver_drive(bump_crossing(), rate_hz=50.0)
    for s in (drive.speed, drive.steering):  # the first 1.2 s (with the latched road profile)
        s.t_ns, s.values = s.t_ns[:60], s.values[:60]
    path = tmp_path / "node.mcap"
    d = SimDriver({"record_path": str(path)})
    try:
        d.play(drive)
    finally:
        d.close()
    report = assert_foxglove_reads([path])
    topics = report["files"][0]["topics"]
    assert {"/sim/imu/data", "/sim/odom", "/sim/suspension", "/diagnostics", "/road/profile"} <= set(topics)


def test_every_message_type_we_write(tmp_path):
    from susp_sim_ros.io.recorder import McapRecorder
    from susp_sim_ros.model.layout import OUTPUT_LABELS
    y = np.linspace(-1.0, 1.0, len(OUTPUT_LABELS))
    t = 1_234_567_891
    msgs = [("/vehicle/speed", M.FLOAT64, M.float64(13.9)),
            ("/road/profile", M.FLOAT64_ARRAY, M.road_profile_msg([0.0, 1.0], [0.0, 0.01], [0.0, -0.01])),
            ("/sim/imu/data", M.IMU, M.imu_msg(t, y)),
            ("/sim/odom", M.ODOMETRY, M.odom_msg(t, y)),
            ("/diagnostics", M.DIAGNOSTIC_ARRAY,
             M.diagnostics_msg(t, [{"level": 1, "name": "n", "message": "m", "values": {"k": "v"}}])),
            ("/clock", M.CLOCK, M.clock_msg(t))]
    written = {m[1] for m in msgs}
    assert written >= {M.FLOAT64, M.FLOAT64_ARRAY, M.IMU, M.ODOMETRY, M.DIAGNOSTIC_ARRAY, M.CLOCK}
    path = tmp_path / "all_types.mcap"
    with McapRecorder(path, metadata={"source": "test"}) as rec:
        for topic, msgtype, msg in msgs:
            rec.write(topic, msgtype, t, msg)
    report = assert_foxglove_reads([path])
    assert sorted(report["files"][0]["schemas"]) == sorted(written)
