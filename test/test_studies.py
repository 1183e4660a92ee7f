"""Parameter studies on Dask (``susp study``, issue 6): study YAML validation, metrics, the same results on a
local Dask cluster as in a plain single-process run, resume after an interrupt or a kill, batch
validation of a folder of drives, and the CLI."""
import csv
import importlib.util
import json
import math
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml

from _cli_helpers import Interrupt, stop_after
from susp_sim_ros.analysis.sweep import (InProcessExecutor, drives_study, load_study,
                                         run_study, study_from_dict)
from susp_sim_ros.analysis.sweep import tasks
from susp_sim_ros.cli.main import main
from susp_sim_ros.errors import ConfigError

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "config" / "studies" / "bump_oil_inspection.yaml"
BAGS = ROOT / "bags"

# a small study: 3 x 2 x 2 = 12 runs of the 8 km/h bump, chunks of 5 -> 3 chunks (the last one short)
TINY = {
    "name": "tiny", "maneuver": "bump_crossing", "chunk_size": 5,
    "parameters": {"oil_front": [1.0, 0.5, 0.0], "oil_rear": {"from": 0.0, "to": 1.0, "num": 2},
                   "bump_height": [0.04, 0.06]},
    "reference": {"oil_front": 1.0, "oil_rear": 1.0},
    "outputs": ["peak_rate", "decay_ratio", "damping_ratio", "ring_out", "rms_after", "rmse_ref",
                {"peak": "F_FRICTION_RL"}],
    "plot": {"y": ["decay_ratio"], "lines": "bump_height",
             "panels": [{"x": "oil_rear", "fixed": {"oil_front": 1.0}}]},
}


def write_study(tmp_path, data, name="study.yaml") -> Path:
    p = tmp_path / name
    p.write_text(yaml.safe_dump(data, sort_keys=False))
    return p


def read_table(path) -> list[dict]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


@pytest.fixture(scope="module")
def dask_executor():
    """A local cluster of two single-threaded worker processes (results cross a process boundary)."""
    from susp_sim_ros.analysis.sweep import make_executor
    ex = make_executor("local", 2)          # what `susp study --workers 2` uses
    try:
        yield ex
    finally:
        ex.close()


@pytest.fixture(scope="module")
def tiny_reference(tmp_path_factory):
    """The tiny study run plainly in this process: the reference every other run must equal."""
    d = tmp_path_factory.mktemp("tiny_ref")
    spec = study_from_dict(json.loads(json.dumps(TINY)), "tiny.yaml")
    res = run_study(spec, d / "out", InProcessExecutor(), progress=False)
    return res, (d / "out" / "results.csv").read_text()


# ---- the study description ------------------------------------------------------------------------
def test_example_study_expands_into_chunks_of_batched_runs():
    spec = load_study(EXAMPLE)
    assert spec.n_runs == 11 * 11 * 3
    assert [r["oil_front"] for r in spec.runs[:1]] == [0.0] and spec.runs[-1]["oil_rear"] == 1.0
    assert spec.runs[1] == {"variant": "full", "oil_front": 0.0, "oil_rear": 0.0, "bump_height": 0.06}
    assert {r["oil_rear"] for r in spec.runs} == {round(0.1 * k,
                                                        12) for k in range(11)}   # 0.3, not 0.30000000000000004
    assert sorted(i for c in spec.chunks for i in c.runs) == list(range(spec.n_runs))
    assert all(len(c.runs) <= spec.data["chunk_size"] for c in spec.chunks)
    assert load_study(EXAMPLE).hash == spec.hash                  # deterministic: resumable


@pytest.mark.parametrize("change, words", [
    ({"colour": 1}, ["colour", "unknown key"]),
    ({"parameters": {"oil_rear": [0.5, 1.2]}}, ["parameters.oil_rear", "[0, 1]"]),
    ({"parameters": {"oil_rear": {"from": 0, "to": 1}}}, ["parameters.oil_rear", "from, to, num"]),
    ({"parameters": {"steer_amplitude": [0.1]}}, ["parameters.steer_amplitude", "sine_steer"]),
    ({"parameters": {"oil_rear": [0.5], "oil_RL": [1.0]}}, ["oil_rear", "oil_RL"]),
    ({"parameters": {"variant": ["full", "no_such_variant"]}}, ["parameters.variant", "no_such_variant"]),
    ({"outputs": ["peak_rate", "wobble"]}, ["outputs[1]", "wobble"]),
    ({"reference": None, "outputs": ["rmse_ref"]}, ["outputs[0]", "reference"]),
    ({"reference": {"speed": 3.0}}, ["reference.speed"]),
    ({"plot": {"y": "decay_ratio", "panels": [{"x": "speed"}]}}, ["plot.panels[0].x", "speed"]),
    ({"chunk_size": 0}, ["chunk_size"]),
    ({"output_rate_hz": 300}, ["output_rate_hz"]),
    ({"vehicle_classes": {"heavy": {"sprung_mass": 1800, "wheel_rate": 30000}}}, ["vehicle_classes.heavy.wheel_rate"]),
    ({"results": "xlsx"}, ["results", "csv or parquet"]),
])
def test_bad_study_yaml_names_file_and_key(tmp_path, change, words):
    data = {**json.loads(json.dumps(TINY)), **change}
    path = write_study(tmp_path, data, "bad_study.yaml")
    with pytest.raises(ConfigError) as exc:
        load_study(path)
    msg = str(exc.value)
    assert "bad_study.yaml" in msg
    for w in words:
        assert w in msg


@pytest.mark.skipif(importlib.util.find_spec("pyarrow") is not None, reason="pyarrow installed: parquet works")
def test_parquet_without_pyarrow_is_a_config_error(tmp_path):
    with pytest.raises(ConfigError, match="results: parquet needs pyarrow"):
        load_study(write_study(tmp_path, {**TINY, "results": "parquet"}))


def test_vehicle_classes_change_the_vehicle():
    spec = study_from_dict({**json.loads(json.dumps(TINY)), "chunk_size": 50, "plot": None,
                            "parameters": {"vehicle_class": ["stock", "heavy"], "oil_rear": [1.0]},
                            "vehicle_classes": {"stock": {}, "heavy": {"sprung_mass": 1900.0,
                                                                       "wheel_rate": [33000.0, 30000.0]}}},
                           "classes.yaml")
    stock, heavy = (tasks.vehicle_params(spec.data, r) for r in spec.runs)
    assert heavy.sprung_mass == 1900.0 and heavy.wheel_rate == (33000.0, 30000.0)
    assert stock.sprung_mass != 1900.0
    res = tasks.chunk_task(spec.data, spec.runs, [None, None])
    assert all(res["ok"]) and res["metrics"][0] != res["metrics"][1]


# ---- metrics and the tasks --------------------------------------------------------------------------
def test_cached_parameter_vector_equals_model_params(model_full):
    data = load_study(EXAMPLE).data
    for oil in ((1.0, 1.0, 1.0, 1.0), (0.0, 0.0, 1.0, 1.0), (0.3, 0.3, 0.7, 0.7)):
        run = {"variant": "full", "oil_front": oil[0], "oil_rear": oil[2]}
        np.testing.assert_array_equal(tasks.params_of(data, run), model_full.params(oil))  # exact: same numbers
    assert tasks.oil_of({"oil_rear": 0.2, "oil_RL": 0.9}) == (1.0, 1.0, 0.9, 0.2)


@pytest.mark.parametrize("zeta", [0.05, 0.2, 0.5])
def test_decay_ratio_of_a_damped_oscillator(zeta):
    t = np.arange(0, 6, 0.001)
    wd = 2 * np.pi * 1.5 * math.sqrt(1 - zeta ** 2)
    q = np.exp(-zeta * 2 * np.pi * 1.5 * t) * np.sin(wd * t)
    r = tasks.decay_ratio(q, 0)
    # successive half-wave peaks of a damped sine: ratio exp(-pi zeta / sqrt(1 - zeta^2)) (1 ms sampling)
    assert r == pytest.approx(math.exp(-math.pi * zeta / math.sqrt(1 - zeta ** 2)), rel=2e-3)
    assert tasks.damping_ratio(r) == pytest.approx(zeta, rel=5e-3)
    assert tasks.decay_ratio(np.exp(-t), 0) == 0.0 and tasks.damping_ratio(0.0) == 1.0


def test_vectorised_decay_ratio_equals_the_scalar_definition():
    rng = np.random.default_rng(7)
    t = np.arange(600) * 0.01
    Q = np.array([np.exp(-z * 9 * t) * np.sin(9 * t + ph) for z, ph in zip(rng.uniform(0, 0.6, 60), rng.uniform(0, 6,
                                                                                                                60))])
    Q[3] = 0.0                      # no motion: NaN
    Q[4] = np.exp(-t)               # no overshoot: 0
    k0 = rng.integers(0, 599, 60)
    expected = np.array([tasks.decay_ratio(Q[i], int(k0[i])) for i in range(60)])
    np.testing.assert_array_equal(tasks.decay_ratios(Q, k0), expected)   # same values, not just close


def test_compiled_rms_metrics_equal_the_numpy_forms():
    """rms_after, rmse_ref and {rms: LABEL} (one compiled pass per row, rows in parallel) equal numpy's
    forms to rounding (sequential vs numpy's pairwise sums), and a run against itself is exactly 0."""
    rng = np.random.default_rng(3)
    B, n = 40, 300
    Y = rng.normal(size=(B, n, 2)) * 0.05
    t_after = rng.uniform(0.0, 3.5, B)               # some windows run past the end, some are empty
    data = {**load_study(EXAMPLE).data, "outputs": ["rms_after", "rmse_ref", {"rms": "ROLL_RATE"}]}
    data["after_window_s"], dt_out = 1.0, 0.01
    R = np.degrees(Y[:3, :250, 0])                   # shorter references: the common length counts
    ref_row = rng.integers(0, 3, B)
    ref_row[:3] = [0, 1, 2]                         # the first three are their own references
    got = tasks.batch_metrics(data, Y, t_after, dt_out, R, ref_row)
    k0 = np.clip(np.ceil(t_after / dt_out - 1e-9).astype(np.int64) - 1, 0, n)
    w = 100
    for b in range(B):
        win = np.degrees(Y[b, k0[b]:k0[b] + w, 0])
        expect = np.sqrt(np.mean(win ** 2)) if win.size else math.nan
        np.testing.assert_allclose(got[b, 0], expect, rtol=1e-14, equal_nan=True)
        d = np.degrees(Y[b, :250, 0]) - R[ref_row[b]]
        np.testing.assert_allclose(got[b, 1], np.sqrt(np.mean(d * d)), rtol=1e-14)
        np.testing.assert_allclose(got[b, 2], np.sqrt(np.mean(Y[b, :, 1] ** 2)), rtol=1e-14)
    assert got[:3, 1].tolist() == [0.0, 0.0, 0.0]
    assert np.isnan(got[k0 >= n, 0]).all() and (k0 >= n).any()
    assert np.isnan(tasks.batch_metrics(data, Y, t_after, dt_out)[:, 1]).all()     # no reference


def test_example_metrics_equal_the_paper_study_path(model_full):
    """The study's peak pitch rate and ring-out equal those of a single `simulate` run (the path of
    `susp paper`) bit for bit, for the paper's three vehicle states."""
    from susp_sim_ros.model import simulate
    from susp_sim_ros.model.maneuvers import bump_crossing
    spec = load_study(EXAMPLE)
    man = bump_crossing(wheelbase=model_full.vehicle.wheelbase)
    t_leave = (float(man.road.s[-1]) + model_full.vehicle.wheelbase) / man.speed
    runs = [{"variant": "full", "oil_front": f, "oil_rear": r, "bump_height": 0.06} for f, r in ((1, 1), (0, 1), (1,
                                                                                                                  0))]
    res = tasks.chunk_task(spec.data, runs, [np.zeros(1000)] * 3)
    cols = spec.metric_columns()
    for run, m in zip(runs, res["metrics"]):
        oil = (run["oil_front"],) * 2 + (run["oil_rear"],) * 2
        sim = simulate(model_full, man.to_inputs(0.001), dt=0.001, road=man.road, oil=oil, outputs=["PITCH_RATE"],
                       decim=10)
        q = np.degrees(sim.y[:, 0])
        above = np.nonzero(np.abs(q) > 0.3)[0]
        assert m[cols.index("peak_pitch_rate_deg_s")] == float(np.abs(q).max())
        assert m[cols.index("ring_out_s")] == float(max(sim.t[above[-1]] - t_leave, 0.0))
    peak = {k: m[cols.index("peak_pitch_rate_deg_s")] for k, m in zip(("intact", "front", "rear"), res["metrics"])}
    decay = {k: m[cols.index("pitch_rate_decay_ratio")] for k, m in zip(("intact", "front", "rear"), res["metrics"])}
    assert peak["intact"] == pytest.approx(8.7, abs=0.05) and peak["rear"] == pytest.approx(9.0,
                                                                                            abs=0.05)  # model-spec 5
    assert decay["rear"] > 3 * decay["intact"]          # the inspection signal sees the oil-empty rear dampers


# ---- the same results everywhere, and resume ---------------------------------------------------------
def test_dask_cluster_gives_the_same_table_as_a_plain_run(tmp_path, dask_executor, tiny_reference):
    ref_res, ref_csv = tiny_reference
    spec = study_from_dict(json.loads(json.dumps(TINY)), "tiny.yaml")
    res = run_study(spec, tmp_path / "dask", dask_executor, progress=False)
    assert res["scheduler"] == "local:2" and res["workers"] == 2
    assert (tmp_path / "dask" / "results.csv").read_text() == ref_csv        # byte for byte
    assert res["n_runs"] == 12 and res["n_chunks"] == 3 and res["runs_failed"] == 0
    rows = read_table(tmp_path / "dask" / "results.csv")
    assert [int(r["run_id"]) for r in rows] == list(range(12))
    assert all(math.isfinite(float(r["pitch_rate_decay_ratio"])) for r in rows)
    ref_row = next(r for r in rows if r["oil_front"] == "1.0" and r["oil_rear"] == "1.0")
    assert float(ref_row["rmse_pitch_rate_vs_ref_deg_s"]) == 0.0             # the reference itself
    assert Path(res["plots"][0]).stat().st_size > 10_000


def test_dask_tasks_spread_over_the_workers(tmp_path, dask_executor):
    """Three chunks on two workers: two tasks (2 + 1 chunks), one on each worker. Each task simulates its
    own reference runs: had the tasks depended on a shared reference future, Dask would have placed
    them all next to it, on one worker."""
    from distributed import get_task_stream
    spec = study_from_dict(json.loads(json.dumps(TINY)), "tiny.yaml")
    with get_task_stream(client=dask_executor.client) as ts:
        run_study(spec, tmp_path / "spread", dask_executor, progress=False, plot=False)
    task_workers = [t["worker"] for t in ts.data if t["key"].startswith("_timed")]
    assert len(task_workers) == 2
    assert len(set(task_workers)) == 2, task_workers
    log = [json.loads(x) for x in (tmp_path / "spread" / "chunks" / "log.jsonl").read_text().splitlines()]
    assert sorted(e["task_chunks"] for e in log) == [1, 2, 2]


def test_tasks_group_consecutive_chunks_of_one_batch_group():
    from susp_sim_ros.analysis.sweep.runner import plan_tasks
    from susp_sim_ros.analysis.sweep.spec import Chunk
    chunks = [Chunk(i, (i,), ("full", 5000)) for i in range(5)] + [Chunk(5 + i, (5 + i,), ("dahl_only",
                                                                                           5000)) for i in range(3)]
    ids = lambda tasks: [[c.id for c in t] for t in tasks]
    assert ids(plan_tasks(chunks, threads=1)) == [[0, 1, 2, 3, 4], [5, 6, 7]]      # never across groups
    assert ids(plan_tasks(chunks, threads=2)) == [[0, 1, 2, 3], [4], [5, 6, 7]]
    assert ids(plan_tasks(chunks, threads=8)) == [[c.id] for c in chunks]        # one chunk per task
    assert ids(plan_tasks(chunks, threads=1, max_chunks=2)) == [[0, 1], [2, 3], [4], [5, 6], [7]]
    assert plan_tasks([], threads=2) == []
    example = load_study(EXAMPLE)                  # the example: one task on one worker, two on two
    assert [len(t) for t in plan_tasks(example.chunks, 1)] == [2]
    assert [len(t) for t in plan_tasks(example.chunks, 2)] == [1, 1]


def test_reference_runs_ride_in_the_task_batch_and_give_the_given_trace_results():
    """A task adds the reference runs its runs need to its own batch (once each; none that is already
    one of its runs) and its metrics equal those computed against separately simulated references."""
    spec = study_from_dict(json.loads(json.dumps(TINY)), "tiny.yaml")
    runs = spec.runs[:4]                      # oil_front 1.0, oil_rear 0/1, both bumps: holds the 2 references
    batch, ref_at = tasks.task_batch(spec.data, runs)
    assert batch == runs and [batch[i] for i in ref_at] == [
        {**r, "oil_front": 1.0, "oil_rear": 1.0} for r in runs]
    runs = spec.runs[4:8]                     # oil_front 0.5: both references added, once each
    batch, ref_at = tasks.task_batch(spec.data, runs)
    assert batch[:4] == runs and len(batch) == 6 and ref_at[4:] == [4, 5]
    assert all(batch[ref_at[i]] == {**runs[i], "oil_front": 1.0, "oil_rear": 1.0} for i in range(4))
    chunks = [spec.runs[4:7], spec.runs[7:10]]
    got = tasks.sweep_task(spec.data, spec.hash, [range(4, 7), range(7, 10)])
    refs = {json.dumps(r, sort_keys=True): np.degrees(tasks.simulate_groups(spec.data, [r])[0][1][0, :, 0])
            for r in (spec.runs[2], spec.runs[3])}                       # the two references, alone
    for c, res in zip(chunks, got):
        given = tasks.chunk_task(spec.data, c, [refs[json.dumps({**r, "oil_front": 1.0, "oil_rear": 1.0},
                                                                  sort_keys=True)] for r in c])
        np.testing.assert_array_equal(res["metrics"], np.array(given["metrics"]))    # bit for bit
        assert res["ok"].tolist() == given["ok"]


def _check_log_after_resume(out: Path, n_chunks: int, first: set):
    log = [json.loads(x) for x in (out / "chunks" / "log.jsonl").read_text().splitlines()]
    ids = [e["chunk"] for e in log]
    assert sorted(ids) == list(range(n_chunks))              # every chunk computed exactly once
    second = {e["chunk"] for e in log if e["session"] == 1}
    assert first.isdisjoint(second) and first | second == set(range(n_chunks))


def test_interrupted_dask_study_resumes_without_repeating_or_losing_chunks(tmp_path, dask_executor, tiny_reference):
    _, ref_csv = tiny_reference
    data = {**json.loads(json.dumps(TINY)), "chunk_size": 2}            # 6 chunks
    spec = study_from_dict(data, "tiny.yaml")
    out = tmp_path / "out"
    with pytest.raises(Interrupt):
        run_study(spec, out, dask_executor, progress=False, on_chunk=stop_after(2))
    first = {int(p.stem[1:]) for p in (out / "chunks").glob("c*.csv")}
    assert len(first) == 2 and not (out / "results.csv").exists()
    res = run_study(spec, out, dask_executor, progress=False)
    assert res["chunks_resumed"] == 2 and res["chunks_computed"] == 4
    _check_log_after_resume(out, 6, first)
    # chunking differs from the reference (2 vs 5 runs per chunk): rows are per run, so the table is the same
    assert (out / "results.csv").read_text() == ref_csv
    # nothing left to do: a third run computes nothing
    again = run_study(spec, out, InProcessExecutor(), progress=False)
    assert again["chunks_computed"] == 0 and (out / "results.csv").read_text() == ref_csv


N_KILL = 1600  # runs (= chunks) of the killed study: large enough that a loaded machine can't finish it first


def test_killed_study_process_resumes(tmp_path, tiny_reference):
    """SIGKILL a real `susp study` process mid-run; the same command finishes the rest."""
    data = {**json.loads(json.dumps(TINY)), "chunk_size": 1,
            "parameters": {"oil_front": {"from": 0.0, "to": 1.0, "num": 40},
                           "oil_rear": {"from": 0.0, "to": 1.0, "num": 40}, "bump_height": [0.06]}}
    path = write_study(tmp_path, data, "killme.yaml")
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "susp_sim_ros.cli.main", "study", str(path), "--out", str(out),
           "--scheduler", "inprocess", "--no-progress", "--no-plot"]
    # one kernel thread: the study must not starve this polling process of both cores (CI saw all
    # chunks done before the poll got to run)
    env = {**os.environ, "PYTHONUNBUFFERED": "1", "NUMBA_NUM_THREADS": "1"}
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and proc.poll() is None:
            if (out / "chunks").exists() and len(list((out / "chunks").glob("c*.csv"))) >= 5:
                break
            time.sleep(0.005)
        proc.send_signal(signal.SIGKILL)
    finally:
        proc.wait(timeout=30)
    assert proc.returncode == -signal.SIGKILL, "study finished before it could be killed"
    first = {int(p.stem[1:]) for p in (out / "chunks").glob("c*.csv")}
    assert 5 <= len(first) < N_KILL
    r = subprocess.run(cmd + ["--json"], env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout)
    assert res["chunks_resumed"] == len(first) and res["chunks_computed"] == N_KILL - len(first)
    _check_log_after_resume(out, N_KILL, first)
    rows = read_table(out / "results.csv")
    assert [int(x["run_id"]) for x in rows] == list(range(N_KILL)) and all(x["ok"] == "1" for x in rows)
    # the killed-and-resumed table equals the plain run of the same runs
    spec = study_from_dict(json.loads(json.dumps(data)), str(path))
    plain = tasks.chunk_task(spec.data, spec.runs[:3], [None] * 3)
    ref = run_study(spec, tmp_path / "plain", InProcessExecutor(), progress=False, plot=False)
    assert (out / "results.csv").read_text() == (tmp_path / "plain" / "results.csv").read_text()
    assert ref["runs_failed"] == 0 and all(plain["ok"])


def test_damaged_chunk_file_is_recomputed(tmp_path, tiny_reference):
    spec = study_from_dict(json.loads(json.dumps(TINY)), "tiny.yaml")
    out = tmp_path / "out"
    run_study(spec, out, InProcessExecutor(), progress=False, plot=False)
    c1 = out / "chunks" / "c000001.csv"
    c1.write_text("\n".join(c1.read_text().splitlines()[:3]))     # cut short, as after a power loss
    res = run_study(spec, out, InProcessExecutor(), progress=False, plot=False)
    assert res["chunks_resumed"] == 2 and res["chunks_computed"] == 1
    assert (out / "results.csv").read_text() == tiny_reference[1]


def test_store_refuses_another_study_unless_fresh(tmp_path, tiny_reference):
    out = tmp_path / "out"
    run_study(study_from_dict(json.loads(json.dumps(TINY)), "tiny.yaml"), out, InProcessExecutor(), progress=False,
              plot=False)
    other = study_from_dict({**json.loads(json.dumps(TINY)), "chunk_size": 4}, "tiny.yaml")
    from susp_sim_ros.errors import SuspInputError
    with pytest.raises(SuspInputError, match="another study"):
        run_study(other, out, InProcessExecutor(), progress=False)
    res = run_study(other, out, InProcessExecutor(), progress=False, fresh=True, plot=False)
    assert res["chunks_resumed"] == 0 and res["chunks_computed"] == 3
    assert (out / "results.csv").read_text() == tiny_reference[1]


# ---- batch validation over a folder of drives ----------------------------------------------------------
def test_batch_validation_over_a_folder(tmp_path, dask_executor):
    folder = tmp_path / "drives"
    folder.mkdir()
    for name in ("bump_crossing_intact.mcap", "bump_crossing_rear_empty.mcap"):
        shutil.copy(BAGS / name, folder / name)
    (folder / "junk.mcap").write_bytes(b"not an mcap file")
    spec = drives_study(folder, ["full", "dahl_only"])
    res = run_study(spec, tmp_path / "out", dask_executor, progress=False)
    rows = {Path(r["file"]).name: r for r in read_table(tmp_path / "out" / "drives.csv")}
    assert set(rows) == {"bump_crossing_intact.mcap", "bump_crossing_rear_empty.mcap", "junk.mcap"}
    assert rows["junk.mcap"]["error"] and res["drives_failed"][0]["file"].endswith("junk.mcap")
    rear = rows["bump_crossing_rear_empty.mcap"]
    assert rear["maneuver"] == "bump_crossing" and rear["state"] == "rear_empty"
    assert float(rear["rmse_dahl_only_deg_s"]) > float(rear["rmse_full_deg_s"]) > 0      # the paper's finding
    assert res["tables"]["bump_crossing"]["rear_empty"]["full"] == pytest.approx(float(rear["rmse_full_deg_s"]))
    # the same numbers as `susp validate --study` computes per drive
    from susp_sim_ros.analysis.validation_study import simulate_and_validate
    from susp_sim_ros.io.drive import read_drive
    one = simulate_and_validate(folder / "bump_crossing_rear_empty.mcap",
                                read_drive(folder / "bump_crossing_rear_empty.mcap"), ["full"], {})
    assert float(rear["rmse_full_deg_s"]) == one.rmse("full")
    assert res["plots"] and Path(res["plots"][0]).exists()


# ---- the command line -------------------------------------------------------------------------------------
def test_cli_study_json_table_and_plot(tmp_path, capsys):
    path = write_study(tmp_path, TINY)
    rc = main(["study", str(path), "--out", str(tmp_path / "o"), "--scheduler", "inprocess", "--json", "--no-progress"])
    assert rc == 0
    res = json.loads(capsys.readouterr().out)
    assert res["n_runs"] == 12 and res["table"].endswith("results.csv") and res["plots"][0].endswith(".png")
    assert "peak_abs_F_FRICTION_RL" in res["columns"]
    assert res["metric_ranges"]["pitch_rate_decay_ratio"][0] > 0


def test_cli_bad_input_exits_2(tmp_path, capsys):
    bad = write_study(tmp_path, {**TINY, "parameters": {"oil_rear": [2.0]}}, "broken.yaml")
    assert main(["study", str(bad), "--out", str(tmp_path / "o"), "--scheduler", "inprocess"]) == 2
    err = capsys.readouterr().err
    assert "broken.yaml" in err and "parameters.oil_rear" in err
    assert main(["study", str(tmp_path / "missing.yaml"), "--out", str(tmp_path / "o")]) == 2
    assert main(["study", "--out", str(tmp_path / "o")]) == 2                     # neither study nor --drives
    assert main(["study", "--drives", str(tmp_path / "nowhere"), "--out", str(tmp_path / "o"),
                 "--scheduler", "inprocess"]) == 2
    assert main(["study", str(EXAMPLE), "--out", str(tmp_path / "o"), "--scheduler", "tcp://127.0.0.1:9",
                 "--connect-timeout", "1"]) == 2


@pytest.mark.slow
def test_cli_batch_diagnosis_over_a_folder(tmp_path, capsys):
    """`susp study --drives DIR --diagnose`: the discrepancy finder per drive, one summary table."""
    folder = tmp_path / "drives"
    folder.mkdir()
    shutil.copy(BAGS / "bump_crossing_rear_empty.mcap", folder)
    rc = main(["study", "--drives", str(folder), "--diagnose", "--variants", "full", "--out", str(tmp_path / "o"),
               "--scheduler", "inprocess", "--json", "--no-progress"])
    assert rc == 0
    res = json.loads(capsys.readouterr().out)
    (row,) = read_table(tmp_path / "o" / "drives.csv")
    assert row["error"] == "" and row["diag_verdict"] in ("missing_physics", "no_significant_discrepancy",
                                                          "unexplained_residual")
    assert float(row["diag_rmse_after_deg_s"]) <= float(row["diag_rmse_before_deg_s"])
    assert res["diagnosis"]["verdicts"] == {row["diag_verdict"]: 1}
    # the same verdict and numbers as the finder on that drive
    from susp_sim_ros.analysis.discrepancy import DiscrepancyFinder
    rep = DiscrepancyFinder(variant="full", heldout=False).fit([str(folder / "bump_crossing_rear_empty.mcap")]).report()
    assert row["diag_verdict"] == rep["verdict"]
    assert float(row["diag_rmse_after_deg_s"]) == rep["heldout_rmse_after_deg_s"]


def test_table_with_quoted_fields_equals_a_parsed_and_rewritten_one(tmp_path):
    """The final table is merged from the chunk files as text; a field the CSV writer had to quote (a
    vehicle class named with a comma and a quote) comes out as parsing and writing every row would give."""
    data = {**json.loads(json.dumps(TINY)), "chunk_size": 2, "plot": None,
            "parameters": {"vehicle_class": ['heavy, "B"', "stock"], "oil_rear": [0.0, 1.0]},
            "vehicle_classes": {"stock": {}, 'heavy, "B"': {"sprung_mass": 1900.0}}}
    spec = study_from_dict(data, "quoted.yaml")
    res = run_study(spec, tmp_path / "out", InProcessExecutor(), progress=False, plot=False)
    text = (tmp_path / "out" / "results.csv").read_text()
    rows = list(csv.reader(text.splitlines()))
    assert rows[0][:2] == ["run_id", "vehicle_class"] and [r[1] for r in rows[1:]] == ['heavy, "B"'] * 2 + ["stock"] * 2
    import io
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerows(rows)
    assert buf.getvalue() == text and res["runs_ok"] == 4
    assert [int(r[0]) for r in rows[1:]] == [0, 1, 2, 3]


def test_a_kill_between_chunk_file_and_log_line_is_mended_on_resume(tmp_path):
    """A chunk file renamed into place whose log line a kill prevented, and a log line the kill cut: on
    reopening, the cut line is dropped (it would swallow the next one) and the chunk gets its line,
    marked recovered, in the session that wrote it; the log holds every finished chunk once."""
    from susp_sim_ros.analysis.sweep.store import ResultStore
    spec = load_study(write_study(tmp_path, TINY))
    out = tmp_path / "out"
    store = ResultStore(spec, out)
    store.begin_session()
    n = [len(c.runs) for c in spec.chunks]
    for cid in (0, 1):
        store.write_chunk(cid, {"ok": [True] * n[cid], "metrics": np.zeros((n[cid], len(spec.metric_columns())))},
                          0.1)
    log = out / "chunks" / "log.jsonl"
    lines = log.read_text().splitlines(keepends=True)
    log.write_text(lines[0] + lines[1][:10])      # chunk 1: its file whole, its line cut by the kill
    again = ResultStore(spec, out)
    assert again.done == {0, 1} and log.read_text().endswith("\n")
    entries = again.log()
    assert [e["chunk"] for e in entries] == [0, 1]
    assert entries[1]["recovered"] is True and entries[1]["session"] == 0 and "recovered" not in entries[0]
    again.begin_session()
    m = np.zeros((n[2], len(spec.metric_columns())))
    again.write_chunk(2, {"ok": [True] * n[2], "metrics": m}, 0.1)
    assert [(e["chunk"], e["session"]) for e in again.log()] == [(0, 0), (1, 0), (2, 1)]
