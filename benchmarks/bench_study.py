"""Benchmark of ``susp study``: runs per second of the example study (config/studies/) with 1 and 2 local
Dask workers, and the per-run overhead the study engine adds over the bare batch simulation.

    python benchmarks/bench_study.py [--study config/studies/bump_oil_inspection.yaml] [--repeat 9] [--json]

What is timed (wall time unless said otherwise; plots off, they are not per-run cost):

- ``bare``: the batch simulations the study needs and nothing else: the ``simulate_batch`` calls of the
  study's tasks as planned for one worker thread (for the example one call of all 363 runs; the
  reference runs ``rmse_ref`` needs ride in the tasks' batches as the engine puts them, here they are runs
  of the study). Parameter vectors, inputs and roads are prepared before the timer starts. All cores to
  the compiled kernel.
- ``inprocess``: ``run_study`` without Dask, start to end: result store, reference runs, parameters,
  batched simulation, metrics, chunk files, the final ``results.csv`` and ``summary.json``. All cores.
- ``1`` / ``2``: the same on a local cluster of 1 / 2 single-threaded worker processes (the kernel gets
  cores/workers threads each: the same cores as ``bare``). Cluster start-up and each worker's first chunk
  (loading the compiled kernel) are warmed up outside the timer and reported apart.

Overhead (target under 10 %), relative to ``bare`` of the same runs, as the median over rounds of
paired figures (this VM's speed swings by up to 35 % between seconds; a ratio taken within a round
cancels what lasts longer than the round):
- a round runs, per study, ``bare``, ``inprocess``, ``1``, ``2``, ``bare`` again, then the CPU pair; a mode's
  overhead in that round is its time over the mean of the round's two ``bare`` times, minus 1;
- ``dask_1_worker`` / ``inprocess``: that in wall time, all cores; ``engine_cpu``: in CPU time of this
  process with one kernel thread (engine right after bare);
- ``per_run``: the cost of one more run, from the example and an 8x larger copy of it in the same round:
  (engine_large - engine_small) / (bare_large - bare_small) - 1, and the fixed cost per study it leaves
  [ms]: (engine - bare) of the example minus its bare time at the per-run overhead.
Runs per second are the best round of each mode (the least disturbed). ``breakdown_ms`` is where the
engine's time goes in one in-process study (one kernel thread, median).
JSON: ``{"runs": int, "runs_per_s": {"bare": f, "inprocess": f, "1": f, "2": f},
"overhead_pct": {"dask_1_worker": f, "inprocess": f, "engine_cpu": f}, "per_run": {"overhead_pct": {...},
"fixed_ms": {...}}, "scaled": {...}, ...}``.
"""
from __future__ import annotations

import argparse
import collections
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numba
import susp_sim_ros  # noqa: F401  before numpy: idle worker threads sleep (susp_sim_ros/idle_threads.py)
import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from susp_sim_ros.analysis.sweep import InProcessExecutor, load_study, make_executor, run_study, study_from_dict  # noqa: E402
from susp_sim_ros.analysis.sweep import runner, tasks  # noqa: E402
from susp_sim_ros.analysis.sweep import store as store_mod  # noqa: E402
from susp_sim_ros.analysis.sweep.runner import plan_tasks  # noqa: E402
import susp_sim_ros.model as model_mod  # noqa: E402
from susp_sim_ros.model import simulate_batch  # noqa: E402


def bare_batches(spec, threads_total: int = 1):
    """The kernel calls the study's tasks make (``simulate_batch`` inputs per task, the reference runs in
    the task's batch as the engine puts them), prepared in advance. ``threads_total``: worker threads the
    tasks are planned for (1: in-process and one Dask worker)."""
    planned = plan_tasks(spec.chunks, threads_total)
    runs = [[spec.runs[r] for c in t for r in c.runs] for t in planned]
    return [b for rs in runs for b in tasks.batch_inputs(spec.data, tasks.task_batch(spec.data, rs)[0])]


def time_bare(spec, batches, cpu: bool = False) -> float:
    clock = time.process_time if cpu else time.perf_counter
    t0 = clock()
    for b in batches:
        simulate_batch(*b["args"], **b["kw"])
    return clock() - t0


def time_engine(spec, executor, out: Path, cpu: bool = False) -> float:
    """The whole study, start to end (wall time, or CPU time of this process)."""
    clock = time.process_time if cpu else time.perf_counter
    t0 = clock()
    run_study(spec, out, executor, progress=False, fresh=True, plot=False)
    return clock() - t0


def breakdown(spec, tmp: Path, n: int = 7) -> dict:
    """Where an in-process study's time goes (one kernel thread; ms, median of ``n``)."""
    parts = {"kernel (simulate_batch)": (model_mod, "simulate_batch"),
             "store: open": (store_mod.ResultStore, "__init__"),
             "batch preparation": (tasks, "_prepare"),
             "metrics": (tasks, "batch_metrics"),
             "tasks (incl. kernel, metrics)": (tasks, "sweep_task"),
             "chunk files": (store_mod.ResultStore, "write_chunk"),
             "final table and summary": (runner, "_finish_sweep")}
    acc: dict = collections.defaultdict(float)
    saved = []
    for label, (owner, name) in parts.items():
        orig = getattr(owner, name, None)
        if orig is None:            # (an older engine without this part)
            continue
        saved.append((owner, name, orig))

        def wrapped(*a, _orig=orig, _label=label, **kw):
            t0 = time.perf_counter()
            try:
                return _orig(*a, **kw)
            finally:
                acc[_label] += time.perf_counter() - t0
        setattr(owner, name, wrapped)
    rounds = []
    try:
        ex = InProcessExecutor(threads=1)
        for _ in range(n):
            acc.clear()
            t0 = time.perf_counter()
            run_study(spec, tmp / "parts", ex, progress=False, fresh=True, plot=False)
            acc["study (total)"] = time.perf_counter() - t0
            rounds.append(dict(acc))
    finally:
        for owner, name, orig in saved:
            setattr(owner, name, orig)
    return {k: round(1e3 * float(np.median([r.get(k, 0.0) for r in rounds])), 3) for k in rounds[0]}


def _variant(path: str, oil_levels: int | None, chunk_size: int | None):
    """The study at ``path``, with ``oil_levels`` per axle and ``chunk_size`` overridden; plots off."""
    spec = load_study(path)
    if oil_levels or chunk_size:
        raw = yaml.safe_load(Path(path).read_text())
        if oil_levels:
            for k in ("oil_front", "oil_rear"):
                raw["parameters"][k] = {"from": 0.0, "to": 1.0, "num": oil_levels}
        if chunk_size:
            raw["chunk_size"] = chunk_size
        raw.pop("plot", None)
        spec = study_from_dict(raw, path)
    spec.data["plot"] = None
    return spec


def measure(specs: dict, repeat: int, tmp: Path) -> dict:
    """Interleaved rounds over the studies in ``specs``: per study and mode, the list of times [s]."""
    all_threads = numba.config.NUMBA_NUM_THREADS
    inproc, one = InProcessExecutor(), InProcessExecutor(threads=1)
    batches = {name: bare_batches(spec) for name, spec in specs.items()}
    for name, spec in specs.items():   # warm-up outside the timers: kernel, metrics, model/maneuver caches
        time_bare(spec, batches[name])
        time_engine(spec, inproc, tmp / "warm")
    execs, start_s = {}, {}
    rounds = {name: collections.defaultdict(list) for name in specs}
    try:
        for w in (1, 2):
            t0 = time.perf_counter()
            execs[str(w)] = make_executor("local", w)         # what `susp study --workers W` uses
            for spec in specs.values():                       # workers import and load the kernel
                time_engine(spec, execs[str(w)], tmp / f"warm{w}")
                time_engine(spec, execs[str(w)], tmp / f"warm{w}")
            start_s[str(w)] = time.perf_counter() - t0
        for _ in range(repeat):
            for name, spec in specs.items():
                r = rounds[name]
                numba.set_num_threads(all_threads)
                r["bare"].append(time_bare(spec, batches[name]))
                r["inprocess"].append(time_engine(spec, inproc, tmp / "inproc"))
                for w, ex in execs.items():
                    r[w].append(time_engine(spec, ex, tmp / f"dask{w}"))
                r["bare_after"].append(time_bare(spec, batches[name]))
                numba.set_num_threads(1)        # CPU time with one kernel thread
                r["bare_cpu"].append(time_bare(spec, batches[name], cpu=True))
                r["engine_cpu"].append(time_engine(spec, one, tmp / "cpu", cpu=True))
                numba.set_num_threads(all_threads)
    finally:
        numba.set_num_threads(all_threads)
        for ex in execs.values():
            ex.close()
    return {"rounds": rounds, "cluster_startup_and_warmup_s": start_s,
            "reference_runs_added": {name: sum(len(b["idx"]) for b in batches[name]) - specs[name].n_runs
                                     for name in specs}}


PAIRS = {"dask_1_worker": ("1", "bare"), "inprocess": ("inprocess", "bare"), "engine_cpu": ("engine_cpu", "bare_cpu")}


def _paired(rounds: dict) -> dict:
    """Per round: the time of each mode and the bare time it is compared with (wall: the mean of the
    round's two bare runs; CPU: the bare CPU run just before)."""
    bare = (np.array(rounds["bare"]) + np.array(rounds["bare_after"])) / 2
    return {k: (np.array(rounds[m]), bare if b == "bare" else np.array(rounds[b])) for k, (m, b) in PAIRS.items()}


def figures(spec, rounds: dict, n_ref: int) -> dict:
    """Runs/s (best round of each mode) and overheads (median of the rounds' paired ratios) of one study."""
    n = spec.n_runs
    best = {k: min(v) for k, v in rounds.items()}
    best["bare"] = min(best["bare"], best["bare_after"])
    over = {k: float(100 * np.median(e / b - 1)) for k, (e, b) in _paired(rounds).items()}
    return {"study": spec.name, "runs": n, "reference_runs_added": n_ref, "chunks": len(spec.chunks),
            "chunk_size": spec.data["chunk_size"],
            "tasks": {"1": len(plan_tasks(spec.chunks, 1)), "2": len(plan_tasks(spec.chunks, 2))},
            "runs_per_s": {"bare": n / best["bare"], "inprocess": n / best["inprocess"],
                           "1": n / best["1"], "2": n / best["2"]},
            "seconds": {k: best[k] for k in ("bare", "inprocess", "1", "2", "bare_cpu", "engine_cpu")},
            "seconds_median": {k: float(np.median(v)) for k, v in rounds.items()},
            "overhead_pct": over,
            "overhead_pct_range": {k: [float(100 * np.min(e / b - 1)), float(100 * np.max(e / b - 1))]
                                   for k, (e, b) in _paired(rounds).items()},
            # the best round of each mode against the best bare round: least disturbed, but not paired
            "overhead_pct_best": {k: 100 * (best[PAIRS[k][0]] / best[PAIRS[k][1]] - 1) for k in PAIRS},
            "overhead_us_per_run": {k: float(1e6 * np.median(e - b) / n) for k, (e, b) in _paired(rounds).items()}}


def marginal(small: dict, large: dict) -> dict:
    """Per-run overhead as the cost of one more run, per round: (engine_L - engine_S) / (bare_L - bare_S)
    - 1 between two sizes of the same study, and the fixed cost per study it leaves [ms]: (engine - bare)
    of the small one minus its bare time at the per-run overhead; medians over the rounds."""
    ps, pl = _paired(small), _paired(large)
    out = {"overhead_pct": {}, "fixed_ms": {}, "overhead_pct_range": {}}
    for k in PAIRS:
        (es, bs), (el, bl) = ps[k], pl[k]
        rate = (el - es) / (bl - bs) - 1
        out["overhead_pct"][k] = float(100 * np.median(rate))
        out["overhead_pct_range"][k] = [float(100 * rate.min()), float(100 * rate.max())]
        out["fixed_ms"][k] = float(1e3 * np.median((es - bs) - rate * bs))
        # from the best rounds (of each mode and size) instead of per round
        be, bb = (min(es), min(el)), (min(bs), min(bl))
        out.setdefault("overhead_pct_best", {})[k] = 100 * ((be[1] - be[0]) / (bb[1] - bb[0]) - 1)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--study", default=str(ROOT / "config" / "studies" / "bump_oil_inspection.yaml"))
    ap.add_argument("--repeat", type=int, default=9)
    ap.add_argument("--oil-levels", type=int, default=None,
                    help="override the number of oil levels per axle (a bigger study than the example)")
    ap.add_argument("--chunk-size", type=int, default=None, help="override the study's chunk_size")
    ap.add_argument("--scale-oil-levels", type=int, default=31,
                    help="oil levels per axle of the larger copy of the study that gives the per-run "
                         "overhead (default 31: 8x the example's runs; 0: none)")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)

    specs = {"study": _variant(args.study, args.oil_levels, args.chunk_size)}
    if args.scale_oil_levels:
        specs["scaled"] = _variant(args.study, args.scale_oil_levels, args.chunk_size)
    tmp = Path(tempfile.mkdtemp(prefix="bench-study-"))
    load0 = os.getloadavg()[0]
    m = measure(specs, args.repeat, tmp)
    numba.set_num_threads(1)
    parts = breakdown(specs["study"], tmp)
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    out = figures(specs["study"], m["rounds"]["study"], m["reference_runs_added"]["study"])
    over = out["overhead_pct"]
    out.update({"cores": os.cpu_count() or 1, "kernel_threads": numba.config.NUMBA_NUM_THREADS,
                "repeat": args.repeat, "breakdown_ms": parts, "load_average": [load0, os.getloadavg()[0]],
                "cluster_startup_and_warmup_s": m["cluster_startup_and_warmup_s"]})
    if "scaled" in specs:
        out["scaled"] = figures(specs["scaled"], m["rounds"]["scaled"], m["reference_runs_added"]["scaled"])
        out["per_run"] = {"runs": [out["runs"], out["scaled"]["runs"]],
                          **marginal(m["rounds"]["study"], m["rounds"]["scaled"])}
    out["overhead_target_pct"] = 10.0
    out["overhead_ok"] = max(over.values()) < 10.0
    out["per_run_overhead_ok"] = "per_run" in out and max(out["per_run"]["overhead_pct"].values()) < 10.0
    if args.json:
        print(json.dumps(out))
        return 0
    for f in [out] + ([out["scaled"]] if "scaled" in out else []):
        r, u, o = f["runs_per_s"], f["overhead_us_per_run"], f["overhead_pct"]
        print(f"{f['study']}: {f['runs']} runs (+{f['reference_runs_added']} reference runs) in {f['chunks']} "
              f"chunks ({f['tasks']['1']} task(s) on 1 worker, {f['tasks']['2']} on 2), {out['cores']} cores")
        print(f"  bare batch simulation     {r['bare']:8.0f} runs/s")
        print(f"  engine, no Dask           {r['inprocess']:8.0f} runs/s  (overhead {o['inprocess']:+.1f} %, "
              f"{u['inprocess']:.0f} us/run)")
        print(f"  engine, Dask 1 worker     {r['1']:8.0f} runs/s  (overhead {o['dask_1_worker']:+.1f} %, "
              f"{u['dask_1_worker']:.0f} us/run)")
        print(f"  engine, Dask 2 workers    {r['2']:8.0f} runs/s")
        print(f"  engine - bare, CPU        {o['engine_cpu']:+8.1f} %       (one kernel thread, "
              f"{u['engine_cpu']:.0f} us/run)")
    if "per_run" in out:
        pr = out["per_run"]
        print(f"per-run overhead (one more run, between {pr['runs'][0]} and {pr['runs'][1]} runs; target < 10 %) "
              f"and the fixed cost per study it leaves:")
        for k in ("dask_1_worker", "inprocess", "engine_cpu"):
            print(f"  {k:18s} {pr['overhead_pct'][k]:+6.1f} %   fixed {pr['fixed_ms'][k]:6.1f} ms")
    print("where an in-process study's time goes (one kernel thread, ms):")
    for k, v in parts.items():
        print(f"    {k:38s} {v:8.2f}")
    print(f"load average {out['load_average'][0]:.1f} -> {out['load_average'][1]:.1f} on {out['cores']} cores "
          f"(runs/s: best of {args.repeat} rounds; overheads: median of the rounds' paired ratios); "
          f"cluster start + warm-up "
          f"{m['cluster_startup_and_warmup_s']['1']:.1f} s (1 worker), "
          f"{m['cluster_startup_and_warmup_s']['2']:.1f} s (2 workers)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
