"""Benchmark of ``susp study``: runs per second of the example study (config/studies/) with 1 and 2 local
Dask workers, and the per-run overhead the study engine adds over the bare batch simulation.

    python benchmarks/bench_study.py [--study config/studies/bump_oil_inspection.yaml] [--repeat 9] [--json]

What is timed (wall time unless said otherwise; plots off, they are not per-run cost):

- ``bare``: the batch simulations the study needs and nothing else: one ``simulate_batch`` call per chunk
  plus one for the study's distinct reference runs (3 for the example: the intact car on each bump;
  ``rmse_ref`` needs them, so they are simulation work, not engine work). Parameter vectors, inputs and
  roads are prepared before the timer starts. All cores to the compiled kernel.
- ``inprocess``: ``run_study`` without Dask, start to end: result store, reference runs, parameters,
  batched simulation, metrics, chunk files, the final ``results.csv`` and ``summary.json``. All cores.
- ``1`` / ``2``: the same on a local cluster of 1 / 2 single-threaded worker processes (the kernel gets
  cores/workers threads each: the same cores as ``bare``). Cluster start-up and each worker's first chunk
  (loading the compiled kernel) are warmed up outside the timer and reported apart.

Overhead (target under 10 %), relative to ``bare`` of the same runs:
- ``dask_1_worker`` / ``inprocess``: (engine - bare) / bare in wall time, all cores;
- ``engine_cpu``: the same in CPU time of this process with one kernel thread (the figure least disturbed
  by other load on the machine).
Rounds are interleaved (bare, in-process, CPU pair, Dask 1, Dask 2, repeated ``--repeat`` times) and each
figure is the best of its rounds: on a shared machine the best round is the one least disturbed.
``breakdown_ms`` is where the engine's time goes in one in-process study (one kernel thread, median).
JSON: ``{"runs": int, "runs_per_s": {"bare": f, "inprocess": f, "1": f, "2": f},
"overhead_pct": {"dask_1_worker": f, "inprocess": f, "engine_cpu": f}, "overhead_us_per_run": {...}, ...}``.
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
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from susp_sim_ros.analysis.sweep import InProcessExecutor, load_study, make_executor, run_study  # noqa: E402
from susp_sim_ros.analysis.sweep import engine, runner  # noqa: E402
from susp_sim_ros.analysis.sweep import store as store_mod  # noqa: E402
from susp_sim_ros.analysis.sweep.spec import reference_run  # noqa: E402
import susp_sim_ros.model as model_mod  # noqa: E402
from susp_sim_ros.model import simulate_batch  # noqa: E402


def _batch(data, runs):
    """Everything one simulate_batch call needs for ``runs`` (one kernel, one step count)."""
    dt = data["step_s"]
    model, _ = engine.model_of(data, runs[0])
    mans = [engine.maneuver_of(data, r, engine.model_of(data, r)[0].vehicle.wheelbase) for r in runs]
    U, u_row, roads, road_row, ids = [], [], [], [], []
    for m in mans:                              # maneuvers are cached: equal ones are one object
        if id(m) not in ids:
            ids.append(id(m))
            U.append(m.to_inputs(dt))
            roads.append(m.road)
        u_row.append(ids.index(id(m)))
        road_row.append(ids.index(id(m)))
    P = np.stack([engine.params_of(data, r) for r in runs])
    return model, P, np.stack(U), roads, np.array(u_row), np.array(road_row)


def bare_batches(spec):
    """Per chunk, and for the distinct reference runs: the inputs of simulate_batch, prepared in advance."""
    data = spec.data
    out = [_batch(data, [spec.runs[r] for r in c.runs]) for c in spec.chunks]
    if data.get("reference") is not None:
        refs = list({json.dumps(reference_run(data, r), sort_keys=True): reference_run(data, r)
                     for r in spec.runs}.values())
        by_kernel: dict = {}
        for r in refs:
            by_kernel.setdefault((r.get("variant", "full"), engine.maneuver_of(
                data, r, engine.model_of(data, r)[0].vehicle.wheelbase).n_steps(data["step_s"])), []).append(r)
        out += [_batch(data, rs) for rs in by_kernel.values()]
    return out


def time_bare(spec, batches, cpu: bool = False) -> float:
    clock = time.process_time if cpu else time.perf_counter
    labels = engine.selection(spec.data)
    t0 = clock()
    for model, P, U, roads, u_row, road_row in batches:
        simulate_batch(model, P, U, dt=spec.data["step_s"], roads=roads, u_row=u_row, road_row=road_row,
                       decim=spec.data["decim"], outputs=labels)
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
             "reference runs (incl. kernel)": (runner, "_references"),
             "chunk preparation": (engine, "_prepare"),
             "metrics": (engine, "batch_metrics"),
             "chunk tasks (incl. kernel, metrics)": (engine, "chunk_task"),
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
        for k in range(n):
            acc.clear()
            t0 = time.perf_counter()
            run_study(spec, tmp / "parts", ex, progress=False, fresh=True, plot=False)
            acc["study (total)"] = time.perf_counter() - t0
            rounds.append(dict(acc))
    finally:
        for owner, name, orig in saved:
            setattr(owner, name, orig)
    return {k: round(1e3 * float(np.median([r.get(k, 0.0) for r in rounds])), 3) for k in rounds[0]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--study", default=str(ROOT / "config" / "studies" / "bump_oil_inspection.yaml"))
    ap.add_argument("--repeat", type=int, default=9)
    ap.add_argument("--oil-levels", type=int, default=None,
                    help="override the number of oil levels per axle (a bigger study than the example)")
    ap.add_argument("--chunk-size", type=int, default=None, help="override the study's chunk_size")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)

    spec = load_study(args.study)
    if args.oil_levels or args.chunk_size:
        import yaml
        from susp_sim_ros.analysis.sweep import study_from_dict
        raw = yaml.safe_load(Path(args.study).read_text())
        if args.oil_levels:
            for k in ("oil_front", "oil_rear"):
                raw["parameters"][k] = {"from": 0.0, "to": 1.0, "num": args.oil_levels}
        if args.chunk_size:
            raw["chunk_size"] = args.chunk_size
        raw.pop("plot", None)
        spec = study_from_dict(raw, args.study)
    spec.data["plot"] = None
    n, cores, all_threads = spec.n_runs, os.cpu_count() or 1, numba.config.NUMBA_NUM_THREADS
    tmp = Path(tempfile.mkdtemp(prefix="bench-study-"))
    load0 = os.getloadavg()[0]
    batches = bare_batches(spec)
    n_ref_runs = sum(len(b[1]) for b in batches) - n
    inproc, one = InProcessExecutor(), InProcessExecutor(threads=1)
    # warm-up outside the timers: kernel and metrics compiled/loaded, caches of models and maneuvers
    time_bare(spec, batches)
    time_engine(spec, inproc, tmp / "warm")
    execs, start_s = {}, {}
    try:
        for w in (1, 2):
            t0 = time.perf_counter()
            execs[str(w)] = make_executor("local", w)         # what `susp study --workers W` uses
            time_engine(spec, execs[str(w)], tmp / f"warm{w}")  # workers import and load the kernel
            time_engine(spec, execs[str(w)], tmp / f"warm{w}")
            start_s[str(w)] = time.perf_counter() - t0
        rounds = collections.defaultdict(list)
        for k in range(args.repeat):
            numba.set_num_threads(all_threads)
            rounds["bare"].append(time_bare(spec, batches))
            rounds["inprocess"].append(time_engine(spec, inproc, tmp / "inproc"))
            numba.set_num_threads(1)        # CPU time with one kernel thread (robust to other load)
            rounds["bare_cpu"].append(time_bare(spec, batches, cpu=True))
            rounds["engine_cpu"].append(time_engine(spec, one, tmp / "cpu", cpu=True))
            numba.set_num_threads(all_threads)
            for w, ex in execs.items():
                rounds[w].append(time_engine(spec, ex, tmp / f"dask{w}"))
        numba.set_num_threads(1)
        parts = breakdown(spec, tmp)
        numba.set_num_threads(all_threads)
    finally:
        for ex in execs.values():
            ex.close()
    best = {k: min(v) for k, v in rounds.items()}
    t_bare = best["bare"]

    def pct(t, base):
        return 100 * (t - base) / base

    def us(t, base):
        return 1e6 * (t - base) / n
    over = {"dask_1_worker": pct(best["1"], t_bare), "inprocess": pct(best["inprocess"], t_bare),
            "engine_cpu": pct(best["engine_cpu"], best["bare_cpu"])}
    out = {
        "study": spec.name, "runs": n, "reference_runs": n_ref_runs, "chunks": len(spec.chunks),
        "chunk_size": spec.data["chunk_size"], "cores": cores, "kernel_threads": all_threads,
        "repeat": args.repeat,
        "runs_per_s": {"bare": n / t_bare, "inprocess": n / best["inprocess"], "1": n / best["1"], "2": n / best["2"]},
        "seconds": {k: best[k] for k in ("bare", "inprocess", "1", "2", "bare_cpu", "engine_cpu")},
        "seconds_median": {k: float(np.median(v)) for k, v in rounds.items()},
        "overhead_pct": over,
        "overhead_us_per_run": {"dask_1_worker": us(best["1"], t_bare), "inprocess": us(best["inprocess"], t_bare),
                                "engine_cpu": us(best["engine_cpu"], best["bare_cpu"])},
        "overhead_target_pct": 10.0, "overhead_ok": max(over.values()) < 10.0,
        "breakdown_ms": parts,
        "load_average": [load0, os.getloadavg()[0]],
        "cluster_startup_and_warmup_s": start_s,
    }
    if args.json:
        print(json.dumps(out))
    else:
        r, u = out["runs_per_s"], out["overhead_us_per_run"]
        print(f"{spec.name}: {n} runs (+{n_ref_runs} reference runs) in {len(spec.chunks)} chunks, {cores} cores")
        print(f"  bare batch simulation     {r['bare']:8.0f} runs/s")
        print(f"  engine, no Dask           {r['inprocess']:8.0f} runs/s  (overhead {over['inprocess']:+.1f} %, "
              f"{u['inprocess']:.0f} us/run)")
        print(f"  engine, Dask 1 worker     {r['1']:8.0f} runs/s  (overhead {over['dask_1_worker']:+.1f} %, "
              f"{u['dask_1_worker']:.0f} us/run; target < 10 %)")
        print(f"  engine, Dask 2 workers    {r['2']:8.0f} runs/s")
        print(f"  engine - bare, CPU        {over['engine_cpu']:+8.1f} %       (one kernel thread, "
              f"{u['engine_cpu']:.0f} us/run)")
        print("  where an in-process study's time goes (one kernel thread, ms):")
        for k, v in parts.items():
            print(f"    {k:38s} {v:8.2f}")
        print(f"  load average              {out['load_average'][0]:.1f} -> {out['load_average'][1]:.1f} "
              f"on {cores} cores (figures are best of {args.repeat} interleaved rounds)")
        print(f"  cluster start + warm-up   1 worker {start_s['1']:.1f} s, 2 workers {start_s['2']:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
