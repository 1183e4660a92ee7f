"""Run a study on an executor: in this process, on a local Dask cluster, or on an existing scheduler.

A task is one or more consecutive chunks of a sweep, simulated as one batch (:func:`plan_tasks`): as
many tasks as worker threads where the study is small, tasks of at most ``MAX_CHUNKS_PER_TASK`` chunks
where it is large. The client owns the store: workers return each chunk's metrics and the client writes
the chunk files as soon as their task finishes, so workers need no shared disk for sweeps (drive studies
read the recordings on the workers: the folder must be visible to them, as it is on a local cluster). At
most two tasks per worker thread are in flight, so a study of a million runs does not put a million
tasks on the scheduler.
"""
from __future__ import annotations

import csv
import json
import logging
import math
import os
import time
from collections.abc import Callable, Iterator, Sequence

import numpy as np

from ...errors import SuspInputError
from ...progress import progress as make_progress
from ..inspection.roc import finish_roc, roc_task
from . import tasks
from .plot import plot_drives, plot_sweep
from .ride import finish_ride, ride_summary, ride_task
from .spec import StudySpec
from .store import ResultStore, _parse


# ---- executors -------------------------------------------------------------------------------------------
class InProcessExecutor:
    """Plain single-process execution, in submission order (the reference for the Dask results)."""

    name = "inprocess"
    workers = 1
    threads_total = 1           # tasks run one after another (each on all the kernel's threads)

    def __init__(self, threads: int | None = None):
        self.threads = threads

    def map(self, fn: Callable, tasks: Sequence[tuple]) -> Iterator[tuple]:
        for key, args in tasks:
            t0 = time.perf_counter()
            yield key, fn(*args, **_threads_kw(fn, self.threads)), time.perf_counter() - t0

    def close(self) -> None:
        pass


def _threads_kw(fn, threads: int | None) -> dict:
    """The kernel's thread count for a task that runs the batch kernel (sweeps), nothing for others."""
    return {"threads": threads} if fn is tasks.sweep_task else {}


def _timed(fn, *args, **kw):
    t0 = time.perf_counter()
    return fn(*args, **kw), time.perf_counter() - t0


class DaskExecutor:
    """Tasks on a Dask cluster, yielded as they complete (at most ``in_flight`` per worker thread queued)."""

    def __init__(self, client, cluster=None, threads: int | None = None, in_flight: int = 2,
                 name: str = "dask"):
        self.client, self.cluster, self.threads, self.name = client, cluster, threads, name
        info = client.scheduler_info()
        self.workers = len(info.get("workers", {})) or 1
        self.threads_total = max(1, sum(w.get("nthreads", 1) for w in info.get("workers", {}).values()))
        self.slots = self.threads_total * in_flight

    def map(self, fn: Callable, tasks: Sequence[tuple]) -> Iterator[tuple]:
        """Submits the first tasks now (the caller's own set-up then overlaps their way to the workers)
        and returns an iterator over ``(key, result, seconds)`` as tasks complete."""
        from distributed import as_completed
        kw = _threads_kw(fn, self.threads)
        todo = list(tasks)[::-1]
        pending: dict = {}

        def submit():
            key, args = todo.pop()
            f = self.client.submit(_timed, fn, *args, pure=False, **kw)
            pending[f] = key
            return f

        # with_results: each result is fetched as its task finishes (no extra round trip per chunk); on
        # this client's loop (the default client's would hang when this process holds several clients)
        ac = as_completed([submit() for _ in range(min(self.slots, len(todo)))], loop=self.client.loop,
                          with_results=True)

        def results():
            try:
                for f, (result, elapsed) in ac:
                    key = pending.pop(f)
                    if todo:
                        ac.add(submit())
                    yield key, result, elapsed
            finally:
                for f in list(pending):
                    f.cancel()
        return results()

    def close(self) -> None:
        try:
            self.client.close()
        finally:
            if self.cluster is not None:
                self.cluster.close()


# glibc malloc of local worker processes. Dask's default (MALLOC_TRIM_THRESHOLD_=65536) hands freed memory
# back to the OS at once, so every task page-faults its megabytes of arrays in again (~4 ms, 3-4 % of the
# example's task); these keep up to 256 MiB of freed heap and serve arrays below 64 MiB from it. A value
# set in the environment wins (Dask reads these variables from it first).
WORKER_MALLOC = {"MALLOC_TRIM_THRESHOLD_": 1 << 28, "MALLOC_MMAP_THRESHOLD_": 1 << 26}


def make_executor(scheduler: str | None = None, workers: int | None = None,
                  processes: bool = True, connect_timeout_s: float = 10.0) -> InProcessExecutor | DaskExecutor:
    """``scheduler``: ``None``/``"local"`` a local cluster of ``workers`` (default 1) single-threaded
    workers; ``"inprocess"`` no Dask; else the address of an existing scheduler (``tcp://host:8786``).

    On a local cluster each worker's compiled batch kernel gets cores / workers threads."""
    cores = os.cpu_count() or 1
    logging.getLogger("distributed").setLevel(logging.ERROR)   # its INFO lines would drown the progress bar
    if scheduler == "inprocess":
        return InProcessExecutor(threads=None)
    from distributed import Client, LocalCluster
    if scheduler in (None, "", "local"):
        n = workers or 1
        if n < 1:
            raise SuspInputError(f"--workers: expected at least 1, got {n}")
        threads = max(1, cores // n)
        # Dask sets OMP_NUM_THREADS=1 in worker processes; the kernel's OpenMP layer gets its share back
        # no dashboard; the scheduler's small HTTP server (health, metrics) on a free port, not 8787
        import dask
        with dask.config.set({f"distributed.nanny.pre-spawn-environ.{k}": v for k, v in WORKER_MALLOC.items()}):
            cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=processes,
                                   dashboard_address=None, silence_logs=logging.ERROR,
                                   scheduler_kwargs={"dashboard": False, "dashboard_address": "127.0.0.1:0"},
                                   **({"env": {"OMP_NUM_THREADS": str(threads)}} if processes else {}))
        # results straight from the worker, not relayed by the scheduler (one hop less per task)
        return DaskExecutor(Client(cluster, direct_to_workers=True), cluster, threads=threads, name=f"local:{n}")
    try:
        client = Client(scheduler, timeout=f"{connect_timeout_s}s")
    except (OSError, TimeoutError, ValueError) as exc:
        raise SuspInputError(f"--scheduler {scheduler}: cannot connect to a Dask scheduler: {exc}") from None
    return DaskExecutor(client, None, threads=None, name=scheduler)


# ---- running -------------------------------------------------------------------------------------------
def _study_tasks(spec: StudySpec, todo: list,
                 executor) -> tuple[Callable[..., list[dict]], list[tuple[tuple[int, ...], tuple]]]:
    """The task function of the study's kind and its tasks still to run: (chunk ids, arguments of the
    function) per task; a sweep groups consecutive chunks into tasks (:func:`plan_tasks`), every other
    kind runs one chunk per task."""
    if spec.kind == "sweep":
        return tasks.sweep_task, [(tuple(c.id for c in t), (spec.data, spec.hash, [c.runs for c in t]))
                                  for t in plan_tasks(todo, getattr(executor, "threads_total", 1))]
    if spec.kind == "ride":
        return _ride_task, [((c.id,), (spec.data, c.id, spec.runs[c.id])) for c in todo]
    if spec.kind == "roc":  # damper-inspection detection study (issue 14): one task per chunk of cars
        return roc_task, [((c.id,), (spec.data, list(c.runs))) for c in todo]
    return _drive_task, [((c.id,), (spec.runs[c.id]["file"], spec.data["variants"], spec.data["diagnose"]))
                         for c in todo]


def _store_results(spec: StudySpec, store: ResultStore, done_tasks, done_runs: int, t_start: float, *,
                   progress: bool, on_chunk: Callable[[int], None] | None) -> list[int]:
    """Write each chunk to ``store`` as its task returns, with a progress bar; the ids of the chunks
    computed in this session. The session is closed in the store even when interrupted."""
    unit = {"drives": "drive", "roc": "car"}.get(spec.kind, "run")
    bar = make_progress(total=spec.n_runs, initial=done_runs, desc=spec.name, unit=unit, enabled=progress,
                        smoothing=0.1)
    computed: list[int] = []
    try:
        for cids, results, elapsed in done_tasks:
            for cid, result in zip(cids, results):
                store.write_chunk(cid, result, elapsed, task_chunks=len(cids))
                computed.append(cid)
                bar.update(len(spec.chunks[cid].runs))
                if on_chunk is not None:
                    on_chunk(cid)
    finally:
        bar.close()
        store.finish_session(chunks_computed=len(computed),
                             elapsed_s=round(time.perf_counter() - t_start, 3))
    return computed


def _finish(spec: StudySpec, store: ResultStore, plot: bool) -> dict:
    """The kind's own results from the complete store (tables, figures, summary figures)."""
    if spec.kind == "sweep":
        return _finish_sweep(spec, store, plot)
    if spec.kind == "ride":
        return finish_ride(spec, store, plot)
    if spec.kind == "roc":
        return finish_roc(spec, store, plot)
    return _finish_drives(spec, store, plot)


def run_study(spec: StudySpec, out, executor, *, progress: bool = True, fresh: bool = False,
              plot: bool = True, on_chunk: Callable[[int], None] | None = None) -> dict:
    """Run (or resume) ``spec`` into ``out``; returns the JSON-ready result (times in s).

    ``on_chunk(cid)`` is called after each chunk is stored (tests interrupt a study from it)."""
    t_start = time.perf_counter()
    store = ResultStore(spec, out, fresh=fresh)
    resumed = sorted(store.done)
    fn, todo_tasks = _study_tasks(spec, [c for c in spec.chunks if c.id not in store.done], executor)
    t_compute, cpu_compute = time.perf_counter(), time.process_time()
    done_tasks = executor.map(fn, todo_tasks)        # on a cluster: submitted, on their way while we go on
    store.begin_session()
    done_runs = sum(len(spec.chunks[c].runs) for c in resumed)
    computed = _store_results(spec, store, done_tasks, done_runs, t_start, progress=progress, on_chunk=on_chunk)
    compute_s, cpu_s = time.perf_counter() - t_compute, time.process_time() - cpu_compute
    missing = set(range(len(spec.chunks))) - store.done
    if missing:
        raise RuntimeError(f"{len(missing)} chunk(s) missing after the run: {sorted(missing)[:10]}")
    new_runs = sum(len(spec.chunks[c].runs) for c in computed)
    result = {"study": spec.name, "kind": spec.kind, "source": spec.path, "out": str(store.out),
              "hash": spec.hash, "scheduler": executor.name, "workers": executor.workers,
              "n_runs": spec.n_runs, "n_chunks": len(spec.chunks), "chunks_resumed": len(resumed),
              "chunks_computed": len(computed), "runs_computed": new_runs,
              "compute_s": compute_s, "cpu_s": cpu_s, "runs_per_s": new_runs / compute_s if compute_s > 0 else math.nan}
    result.update(_finish(spec, store, plot))
    result["elapsed_s"] = time.perf_counter() - t_start
    (store.out / "summary.json").write_text(json.dumps(result, indent=1, default=str))
    result["summary"] = summary_text(result)
    return result


MAX_CHUNKS_PER_TASK = 8    # a task's chunks are stored when the task ends: this bounds what a kill loses


def plan_tasks(chunks: Sequence, threads: int, max_chunks: int = MAX_CHUNKS_PER_TASK) -> list[list]:
    """Consecutive chunks of one batch group (kernel and step count) into tasks of ``k`` chunks:
    ``k = ceil(len(chunks) / threads)`` (every worker thread gets work, and a small study is one task per
    thread rather than one per chunk: each task costs a round trip through the scheduler and a batch
    with a partly empty last block of lanes), at most ``max_chunks``."""
    k = max(1, min(max_chunks, -(-len(chunks) // max(1, threads))))
    planned: list[list] = []
    for c in chunks:
        if planned and len(planned[-1]) < k and planned[-1][-1].group == c.group:
            planned[-1].append(c)
        else:
            planned.append([c])
    return planned


def _ride_task(data, run_id: int, run) -> list[dict]:
    """:func:`.ride.ride_task` as a task of one chunk."""
    return [ride_task(data, run_id, run)]


def _drive_task(path: str, variants, diagnose: bool) -> list[dict]:
    """:func:`tasks.drive_task` as a task of one chunk."""
    return [tasks.drive_task(path, variants, diagnose)]


def _finish_sweep(spec: StudySpec, store: ResultStore, plot: bool) -> dict:
    header = store.columns()
    lines = store.lines()
    metric_cols = spec.metric_columns()
    rows = None
    if spec.data["results"] == "csv":
        table = store.write_lines(header, lines, "results")
    else:
        rows = list(csv.reader(lines))
        table = store.write_table(header, rows, "results", spec.data["results"])
    plots = []
    if plot and spec.data.get("plot"):
        rows = rows if rows is not None else list(csv.reader(lines))
        cols = {h: [_parse(r[i]) for r in rows] for i, h in enumerate(header)}
        plots.append(str(plot_sweep(spec, cols, store.out / f"{spec.name}.png")))
    ok, metrics = store.outcomes()
    good = metrics[ok]
    ranges = {}
    for j, c in enumerate(metric_cols):
        vals = good[np.isfinite(good[:, j]), j]
        if vals.size:
            ranges[c] = [float(vals.min()), float(vals.max())]
    return {"table": str(table), "columns": header, "plots": plots, "runs_ok": good.shape[0],
            "runs_failed": len(lines) - good.shape[0], "metric_ranges": ranges}


def _finish_drives(spec: StudySpec, store: ResultStore, plot: bool) -> dict:
    rows = store.drive_rows()
    variants = spec.data["variants"]
    header = ["file", "maneuver", "state", "vehicle", "source", "signal", "window",
              *[f"rmse_{v}_deg_s" for v in variants], "best_variant",
              *(DIAG_COLUMNS if spec.data["diagnose"] else ()), "error"]
    table = store.write_table(header, [[r.get(h, "") for h in header] for r in rows], "drives")
    tables: dict = {}
    for r in rows:
        if r.get("error") or not r.get("maneuver"):
            continue
        cell = tables.setdefault(r["maneuver"], {}).setdefault(r["state"], {})
        for v in variants:
            cell.setdefault(v, []).append(r[f"rmse_{v}_deg_s"])
    tables = {m: {s: {v: sum(x) / len(x) for v, x in c.items()} for s, c in by_s.items()}
              for m, by_s in tables.items()}
    plots = []
    if plot and any(not r.get("error") for r in rows):
        plots.append(str(plot_drives(rows, variants, store.out / f"{spec.name}_rmse.png")))
    failed = [{"file": r["file"], "error": r["error"]} for r in rows if r.get("error")]
    return {"table": str(table), "columns": header, "plots": plots, "tables": tables, "unit": "deg/s",
            "drives_ok": len(rows) - len(failed), "drives_failed": failed,
            "diagnosis": _diagnosis_summary(rows) if spec.data["diagnose"] else "off (--diagnose)"}


DIAG_COLUMNS = ("diag_verdict", "diag_terms", "diag_rmse_before_deg_s", "diag_rmse_after_deg_s",
                "diag_noise_floor_deg_s")


def _diagnosis_summary(rows) -> dict:
    """Verdict counts and how often each term was found, over the diagnosed drives."""
    verdicts: dict[str, int] = {}
    terms: dict[str, int] = {}
    for r in rows:
        if r.get("error"):
            continue
        verdicts[r["diag_verdict"]] = verdicts.get(r["diag_verdict"], 0) + 1
        for t in filter(None, r["diag_terms"].split(";")):
            terms[t] = terms.get(t, 0) + 1
    return {"verdicts": verdicts, "terms_found": dict(sorted(terms.items(), key=lambda kv: -kv[1]))}


def summary_text(r: dict) -> str:
    units = {"drives": "drives", "roc": "cars"}.get(r["kind"], "runs")
    lines = [f"study {r['study']} ({r['kind']}): {r['n_runs']} {units} "
             f"in {r['n_chunks']} chunks on {r['scheduler']} ({r['workers']} worker(s)); "
             f"{r['chunks_computed']} chunks computed, {r['chunks_resumed']} resumed"]
    if r["runs_computed"]:
        lines.append(f"  {r['runs_per_s']:.3g} {units}/s over {r['compute_s']:.1f} s")
    for c, (lo, hi) in r.get("metric_ranges", {}).items():
        lines.append(f"  {c}: {lo:.4g} .. {hi:.4g}")
    if r["kind"] == "ride":
        lines += ride_summary(r)
    for sev, by_m in r.get("roc_by_severity", {}).items():
        lines.append(f"  ROC {sev} vs intact: " + ", ".join(
            f"{m} AUC {x['auc']:.3f} [{x['auc_ci95'][0]:.3f}, {x['auc_ci95'][1]:.3f}] sens@95%spec "
            f"{x['sensitivity_at_95_specificity']:.2f}" for m, x in by_m.items()))
    if r["kind"] == "drives":
        for m, by_s in r["tables"].items():
            for s, row in by_s.items():
                lines.append(f"  {m} {s}: " + ", ".join(f"{v} {x:.3f}" for v, x in row.items()) + " deg/s RMSE")
        for f in r["drives_failed"]:
            lines.append(f"  FAILED {f['file']}: {f['error']}")
        lines.append(f"  diagnosis: {r['diagnosis']}")
    lines.append(f"  table: {r['table']}" + (f"; plots: {', '.join(r['plots'])}" if r["plots"] else ""))
    return "\n".join(lines)
