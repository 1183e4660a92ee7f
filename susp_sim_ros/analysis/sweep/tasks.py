"""What one task does: the runs of one or more chunks as one batched simulation, then the metrics of each run.

Everything here is a pure function of the normalised study description (``spec.data``) and the run
parameters, so a chunk gives bit-identical results wherever it runs (a Dask worker process or thread, or
the client itself): the compiled batch kernel integrates every vehicle independently of its neighbours in
the batch and of the number of threads.

Per worker process, models and parameter vectors are cached: ``Model.params`` costs about as much as 5 %
of a run, so the parameter vector of a (vehicle, variant) is built once and only the oil levels (the
``OIL`` block of ``P``) are set per run.
"""
from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numba import njit, prange

from ...errors import SuspInputError
from ...io.drive import read_drive
from ...model import simulate_batch
from ...model.layout import P_INDEX
from ...model.maneuvers import excitation_end
from ...model.paper import PRIMARY_OUTPUT
from ..discrepancy import DiscrepancyFinder
from ..validation_study import simulate_and_validate
from .runs import (MANEUVER_KEYS, _cache, _lock, inputs_of, maneuver_of, model_of, oil_of,  # noqa: F401
                   params_of, vehicle_params)
from .spec import expand_runs, reference_run

def after_time(man, wheelbase: float) -> float:
    """When the excitation is over [s]: the rear axle has left the bump / the last steer has ended."""
    return excitation_end(man, wheelbase)


def selection(data: Mapping) -> list[str]:
    """Output labels a chunk records: the maneuver's signal first, then those generic metrics name."""
    labels = [PRIMARY_OUTPUT[data["maneuver"]]]
    for m in data["outputs"]:
        if isinstance(m, dict):
            lab = next(iter(m.values()))
            if lab not in labels:
                labels.append(lab)
    return labels


# ---- the batched simulation ---------------------------------------------------------------------------
def _prepare(data: Mapping, runs: Sequence[Mapping]):
    """``(setups, which, oils)``: the distinct setups of ``runs`` — ``(model, base parameter vector,
    maneuver, wheelbase)`` — ``which[i]`` the one of run ``i`` and ``oils[i]`` its oil levels FL, FR, RL,
    RR. The caches are consulted once per distinct setup, not once per run."""
    models: dict = {}
    setup_of: dict = {}
    setups: list[tuple] = []              # (model, base parameter vector, maneuver, wheelbase [m])
    which: list[int] = []
    oils: list[tuple[float, float, float, float]] = []
    for run in runs:
        key = (run.get("vehicle_class"), run.get("vehicle"), run.get("variant", "full"), *map(run.get, MANEUVER_KEYS))
        k = setup_of.get(key)
        if k is None:
            mb = models.get(key[:3])
            if mb is None:
                mb = models[key[:3]] = model_of(data, run)
            wb = mb[0].vehicle.wheelbase
            k = setup_of[key] = len(setups)
            setups.append((mb[0], mb[1], maneuver_of(data, run, wb), wb))
        which.append(k)
        oils.append(oil_of(run))
    return setups, np.array(which, dtype=np.int64), np.array(oils, dtype=float).reshape(len(runs), 4)


def batch_inputs(data: Mapping, runs: Sequence[Mapping]) -> list[dict]:
    """The batched simulations of ``runs``: one per (kernel, step count), each a dict of ``idx`` (positions
    in ``runs``), ``n_steps``, ``t_after[B]`` (end of the excitation [s]) and ``args``/``kw`` of
    :func:`~susp_sim_ros.model.simulate_batch`."""
    dt, decim = data["step_s"], data["decim"]
    labels = selection(data)
    setups, which, oils = _prepare(data, runs)
    by_group: dict = {}                         # (kernel, n_p, step count) -> setup ids
    for k, (model, _, man, _) in enumerate(setups):
        by_group.setdefault((id(model.kernel), model.layout.n_p, man.n_steps(dt)), []).append(k)
    k_oil = P_INDEX["OIL"]
    out = []
    for (_, _, n_req), ks in by_group.items():
        model = setups[ks[0]][0]
        u_keys: dict[tuple, int] = {}
        U: list[np.ndarray] = []
        r_keys: dict[tuple, int] = {}
        roads: list = []                    # RoadProfile of each distinct road of the group
        local = np.full(len(setups), -1)        # setup id -> row of this group's per-setup tables
        u_of, road_of, t_of = [], [], []
        for j, k in enumerate(ks):
            _, _, man, wb = setups[k]
            local[k] = j
            uk = (man.speed, man.steer_amplitude, man.steer_frequency, man.steer_start, man.steer_periods)
            if uk not in u_keys:
                u_keys[uk] = len(U)
                U.append(inputs_of(man, dt))
            rk = (man.road.s.tobytes(), man.road.zl.tobytes(), man.road.zr.tobytes())
            if rk not in r_keys:
                r_keys[rk] = len(roads)
                roads.append(man.road)
            u_of.append(u_keys[uk])
            road_of.append(r_keys[rk])
            t_of.append(after_time(man, wb))
        idx = np.nonzero(local[which] >= 0)[0]
        row = local[which[idx]]
        P = np.stack([setups[k][1] for k in ks])[row]
        P[:, k_oil:k_oil + 4] = oils[idx]
        out.append({"idx": idx.tolist(), "n_steps": n_req, "t_after": np.array(t_of)[row],
                    "args": (model, P, np.stack(U)),
                    "kw": {"dt": dt, "roads": roads, "u_row": np.array(u_of)[row],
                           "road_row": np.array(road_of)[row], "decim": decim, "outputs": labels}})
    return out


def simulate_groups(data: Mapping, runs: Sequence[Mapping], threads: int | None = None) -> list:
    """Simulate ``runs`` batched per (kernel, step count) (:func:`batch_inputs`). Returns one entry per
    batch: ``(idx, Y, ok, t_after, dt_out)`` with ``idx`` the positions in ``runs``, ``Y[B, n, n_sel]`` the
    recorded outputs (the signal first), ``ok[B]`` (ran to the end and finite) and ``t_after[B]``."""
    if threads is not None:
        import numba
        # numba sets its config attributes from the environment at import: mypy cannot see them
        max_threads: int = numba.config.NUMBA_NUM_THREADS  # type: ignore[attr-defined]
        numba.set_num_threads(max(1, min(int(threads), max_threads)))
    out = []
    for b in batch_inputs(data, runs):
        res = simulate_batch(*b["args"], **b["kw"])
        Y, done = res.values, res.steps_done
        ok = (done == b["n_steps"]) & np.isfinite(Y).all(axis=(1, 2))
        out.append((b["idx"], Y, ok, b["t_after"], data["step_s"] * data["decim"]))
    return out


# ---- metrics --------------------------------------------------------------------------------------------
def decay_ratio(q: np.ndarray, k0: int) -> float:
    """Amplitude ratio of the swing after the largest one, from sample ``k0`` on (the inspection signal).

    After the excitation the signal is cut into half-waves at its sign changes; the ratio is the peak of
    the half-wave following the largest one over that largest peak (0 when the motion dies without
    overshoot). A damped linear oscillator with damping ratio zeta gives exp(-pi zeta / sqrt(1-zeta^2)).
    """
    x = q[k0:]
    if x.size == 0:
        return math.nan
    a = np.abs(x)
    k = int(np.argmax(a))
    if a[k] == 0.0:
        return math.nan
    s = np.sign(x)
    change = np.nonzero(s[k + 1:] * s[k] < 0)[0]
    if change.size == 0:
        return 0.0
    j0 = k + 1 + int(change[0])
    back = np.nonzero(s[j0 + 1:] * s[j0] < 0)[0]
    j1 = j0 + 1 + int(back[0]) if back.size else x.size
    return float(a[j0:j1].max() / a[k])


def decay_ratios(q: np.ndarray, k0: np.ndarray) -> np.ndarray:
    """:func:`decay_ratio` of every row of ``q[B, n]`` (from ``k0[B]`` on); equal values (one compiled pass
    per row: comparisons, a maximum and one division, so no rounding can differ from the scalar form)."""
    q = np.ascontiguousarray(q, dtype=np.float64)
    B = q.shape[0]
    out, peak, last = np.empty(B), np.empty(B), np.empty(B, np.int64)
    _row_metrics(q[:, :, None], 0, 1.0, np.ascontiguousarray(k0, dtype=np.int64), math.inf, peak, out, last)
    return out


_DEG = 180.0 / math.pi     # np.degrees(x) is x * (180 / pi): the same product, bit for bit


@njit(cache=True, nogil=True)
def _signal_row(Y, b, col, scale, k0, threshold, peak_out, decay_out, last_out):
    """Row ``b`` of :func:`_row_metrics`."""
    n = Y.shape[1]
    top, last = 0.0, -1
    for i in range(n):
        v = abs(Y[b, i, col] * scale)
        if v > top:
            top = v
        if v > threshold:
            last = i
    peak_out[b], last_out[b] = top, last
    decay_out[b] = math.nan
    if k0[b] >= n:
        return
    k, peak = -1, 0.0
    for i in range(max(k0[b], 0), n):          # the first largest |q| (as argmax)
        v = abs(Y[b, i, col] * scale)
        if v > peak:
            k, peak = i, v
    if peak == 0.0:
        return
    pos = Y[b, k, col] * scale > 0.0
    j0 = -1
    for i in range(k + 1, n):                   # the next half-wave starts at the first sign change
        v = Y[b, i, col] * scale
        if (v < 0.0) if pos else (v > 0.0):
            j0 = i
            break
    if j0 < 0:
        decay_out[b] = 0.0
        return
    pos = Y[b, j0, col] * scale > 0.0
    second = abs(Y[b, j0, col] * scale)
    for i in range(j0 + 1, n):                  # ... and ends at the one after
        v = Y[b, i, col] * scale
        if (v < 0.0) if pos else (v > 0.0):
            break
        if abs(v) > second:
            second = abs(v)
    decay_out[b] = second / peak


@njit(cache=True, nogil=True, parallel=True)
def _row_metrics(Y, col, scale, k0, threshold, peak_out, decay_out, last_out):
    """Per row ``b`` of the signal ``q = Y[b, :, col] * scale``: the largest |q| (``peak_out``), the decay
    ratio from sample ``k0[b]`` on (:func:`decay_ratio`) and the last sample with |q| > ``threshold``
    (-1: none). Only comparisons, maxima and one division: the values numpy's forms give, exactly. Rows
    in parallel on the kernel's threads (a row's values do not depend on the others)."""
    for b in prange(Y.shape[0]):
        _signal_row(Y, b, col, scale, k0, threshold, peak_out, decay_out, last_out)


@njit(cache=True, nogil=True, parallel=True)
def _row_rms(Y, col, scale, start, count, R, ref_row, out):
    """Per row ``b``: the RMS of ``Y[b, i, col] * scale - R[ref_row[b], i]`` (no reference where
    ``ref_row[b] < 0``) over ``start[b] <= i < start[b] + count`` within the row; NaN if that is empty.
    One pass per row, rows in parallel."""
    n = Y.shape[1]
    for b in prange(Y.shape[0]):
        lo = max(start[b], 0)
        hi = min(start[b] + count, n)
        r = ref_row[b]
        if r >= 0:
            hi = min(hi, R.shape[1])
        acc = 0.0
        for i in range(lo, hi):
            d = Y[b, i, col] * scale
            if r >= 0:
                d -= R[r, i]
            acc += d * d
        out[b] = math.sqrt(acc / (hi - lo)) if hi > lo else math.nan


def damping_ratio(r: float) -> float:
    """Equivalent damping ratio of a half-cycle amplitude ratio ``r`` (logarithmic decrement)."""
    if not math.isfinite(r):
        return math.nan
    if r <= 0.0:
        return 1.0
    d = -math.log(r)                    # per half cycle
    return float(d / math.sqrt(math.pi ** 2 + d * d))


def batch_metrics(data: Mapping, Y: np.ndarray, t_after: np.ndarray, dt_out: float,
                  R: np.ndarray | None = None, ref_row: np.ndarray | None = None) -> np.ndarray:
    """The study's ``outputs`` (columns, in order) of runs ``Y[B, n, n_sel]`` (rates in deg/s).

    ``t_after[B]``: end of the excitation [s]; ``R[m, n]``: reference traces [deg/s] and ``ref_row[B]``
    the one of each run (or ``None``: no reference, ``rmse_ref`` is NaN). Every value is a function of its
    own run only (row-wise reductions, compiled, rows in parallel)."""
    labels = selection(data)
    B, n = Y.shape[0], Y.shape[1]
    Y = np.ascontiguousarray(Y, dtype=np.float64)
    # sample k is at (k+1) dt_out: first sample at or after t_after
    k0 = np.clip(np.ceil(t_after / dt_out - 1e-9).astype(np.int64) - 1, 0, n)
    zero, none = np.zeros(B, np.int64), np.full(B, -1, np.int64)
    no_ref = np.zeros((1, 1))
    # one compiled pass over the signal (deg/s) for the peak, the decay ratio and the ring-out
    peak, decay, last = np.empty(B), np.empty(B), np.empty(B, np.int64)
    _row_metrics(Y, 0, _DEG, k0, float(data["ring_out_threshold_deg_s"]), peak, decay, last)
    cols = []
    for m in data["outputs"]:
        if isinstance(m, dict):
            kind, lab = next(iter(m.items()))
            c = labels.index(lab)
            if kind == "peak":
                cols.append(np.abs(Y[:, :, c]).max(axis=1))
            else:
                _row_rms(Y, c, 1.0, zero, n, no_ref, none, out := np.empty(B))
                cols.append(out)
        elif m == "peak_rate":
            cols.append(peak)
        elif m == "decay_ratio":
            cols.append(decay)
        elif m == "damping_ratio":
            cols.append(np.array([damping_ratio(x) for x in decay.tolist()]))
        elif m == "ring_out":
            cols.append(np.where(last >= 0, np.maximum((last + 1) * dt_out - t_after, 0.0), 0.0))
        elif m == "rms_after":
            w = max(int(round(data["after_window_s"] / dt_out)), 1)
            _row_rms(Y, 0, _DEG, k0, w, no_ref, none, out := np.empty(B))
            cols.append(out)
        elif m == "rmse_ref" and R is None:
            cols.append(np.full(B, math.nan))
        elif m == "rmse_ref":
            _row_rms(Y, 0, _DEG, zero, n, np.ascontiguousarray(R, dtype=np.float64),
                     np.ascontiguousarray(ref_row, dtype=np.int64), out := np.empty(B))
            cols.append(out)
    return np.stack(cols, axis=1) if cols else np.zeros((B, 0))


# ---- tasks ---------------------------------------------------------------------------------------------
def task_batch(data: Mapping, runs: Sequence[Mapping]) -> tuple[list, list]:
    """What a task simulates: ``runs``, then the distinct reference runs they need that are not among
    them, as one list (one batched simulation per kernel group). Returns ``(batch, ref_at)``:
    ``ref_at[i]`` is the position in ``batch`` of the reference of ``batch[i]`` (``None``: no reference).

    Riding in the same batch, a reference run usually costs nothing: the kernel advances vehicles in
    blocks of 16 lanes and the last block of a batch is rarely full (the example's references are runs of
    the study itself)."""
    batch = list(runs)
    ref = data.get("reference")
    if ref is None:
        return batch, [None] * len(batch)
    # runs of a sweep share their keys in one order, so their items are a key (a reference run with its
    # items in another order would just be simulated once more)
    pos: dict = {}
    for i, r in enumerate(batch):                   # first position of each distinct run
        pos.setdefault(tuple(r.items()), i)
    # a run's reference depends on its values of the keys the reference does not set
    drop = set(ref) | ({"vehicle"} if "vehicle_class" in ref else set()) | (
        {"vehicle_class"} if "vehicle" in ref else set())
    ref_of: dict = {}
    ref_at = []
    for r in runs:
        nk = tuple([kv for kv in r.items() if kv[0] not in drop])
        p = ref_of.get(nk)
        if p is None:
            rr = reference_run(ref, r)
            key = tuple(rr.items())
            p = pos.get(key)
            if p is None:
                p = pos[key] = len(batch)
                batch.append(rr)
            ref_of[nk] = p
        ref_at.append(p)
    ref_at += list(range(len(runs), len(batch)))        # a reference run is its own reference
    return batch, ref_at


_runs_cache: dict = {}     # study hash -> its runs (this process)


def study_runs(data: Mapping, study: str) -> list[dict]:
    """The runs of the sweep ``data`` (:func:`~.spec.expand_runs`), expanded once per process; ``study``
    is its hash (the cache key; the last two studies are kept)."""
    with _lock:
        runs = _runs_cache.get(study)
        if runs is None:
            while len(_runs_cache) >= 2:
                _runs_cache.pop(next(iter(_runs_cache)))
            runs = _runs_cache[study] = expand_runs(data)
        return runs


def sweep_task(data: Mapping, study: str, chunks: Sequence[Sequence[int]], threads: int | None = None) -> list[dict]:
    """One task: the runs of one or more chunks (their run ids in the sweep ``data`` whose hash is
    ``study``: a task ships ids, not run descriptions) and the reference runs they need, simulated
    together (:func:`task_batch`), then the metrics of each run. Returns per chunk ``{"ok": bool[n],
    "metrics": float[n, n_outputs]}`` (metrics NaN for a run that became non-finite). A reference run that
    became non-finite raises ``RuntimeError`` (no run could be compared with it)."""
    every = study_runs(data, study)
    runs = [every[i] for c in chunks for i in c]
    batch, ref_at = task_batch(data, runs)
    groups = simulate_groups(data, batch, threads)
    R, ref_row = None, None
    if data.get("reference") is not None:
        where = {i: (g, j) for g, (idx, *_) in enumerate(groups) for j, i in enumerate(idx)}
        distinct = sorted(set(ref_at))
        for p in distinct:
            g, j = where[p]
            if not groups[g][2][j]:
                raise RuntimeError(f"reference run {json.dumps(dict(batch[p]))} became non-finite")
        R = np.degrees(np.stack([groups[where[p][0]][1][where[p][1], :, 0] for p in distinct]))
        row = {p: k for k, p in enumerate(distinct)}
        ref_row = np.array([row[p] for p in ref_at])
    ok, metrics = _metrics(data, groups, len(batch), R, ref_row)
    out, k = [], 0
    for c in chunks:
        out.append({"ok": ok[k:k + len(c)], "metrics": metrics[k:k + len(c)]})
        k += len(c)
    return out


def chunk_task(data: Mapping, runs: Sequence[Mapping], refs: Sequence[np.ndarray | None] | None = None,
               threads: int | None = None) -> dict:
    """Batched simulation and metrics of ``runs`` against given reference traces ``refs[i]`` [deg/s] (or
    ``None``). Returns ``{"ok": [...], "metrics": [[...], ...]}`` (lists)."""
    groups = simulate_groups(data, runs, threads)
    R, ref_row = None, None
    if refs is not None and any(r is not None for r in refs):
        given = [i for i, r in enumerate(refs) if r is not None]
        R = np.stack([r for r in refs if r is not None])       # in the order of ``given``
        ref_row = np.full(len(runs), -1)
        ref_row[given] = np.arange(len(given))
    ok, metrics = _metrics(data, groups, len(runs), R, ref_row)
    return {"ok": ok.tolist(), "metrics": metrics.tolist()}


def _metrics(data: Mapping, groups: list, n: int, R: np.ndarray | None,
             ref_row: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """``(ok[n], metrics[n, n_outputs])`` of the runs simulated in ``groups`` (:func:`simulate_groups`);
    ``R[m, n_samples]``: reference traces [deg/s], ``ref_row[i]`` the one of run ``i`` (-1: none)."""
    metrics = np.full((n, len(data["outputs"])), math.nan)
    ok = np.zeros(n, bool)
    for idx, _, good, _, _ in groups:
        ok[idx] = good
    want_ref = data.get("reference") is not None and R is not None

    def refs_of(idx):
        """``(R, rows)`` for the runs ``idx``, or ``(None, None)`` if one of them has no reference."""
        if not want_ref or ref_row is None:
            return None, None
        rows = ref_row[idx]
        return (R, rows) if (rows >= 0).all() else (None, None)

    if len(groups) == 1 and ok.all():           # the usual task: one batch, every run finished
        idx, Y, _, ta, dt_out = groups[0]
        metrics[idx] = batch_metrics(data, Y, ta, dt_out, *refs_of(np.asarray(idx)))
        return ok, metrics
    # runs of equal output length together (as one batch: the metrics are row-wise)
    rows: dict = {}
    for g, (idx, Y, good, _, _) in enumerate(groups):
        for j, i in enumerate(idx):
            if good[j]:
                rows.setdefault(Y.shape[1:], []).append((i, g, j))
    for sel in rows.values():
        idx = [i for i, _, _ in sel]
        Y = np.stack([groups[g][1][j] for _, g, j in sel])
        ta = np.array([groups[g][3][j] for _, g, j in sel])
        metrics[idx] = batch_metrics(data, Y, ta, groups[sel[0][1]][4], *refs_of(np.array(idx)))
    return ok, metrics


def drive_task(path: str, variants: Sequence[str], diagnose: bool = False) -> dict:
    """Batch validation of one recorded drive: lockstep simulation with each variant, RMSE per variant
    in the paper's window and signal; with ``diagnose``, the discrepancy finder on this drive alone
    against the first variant. A drive that fails gives a row with ``error`` instead of raising."""
    row: dict[str, Any] = {"file": path}
    try:
        drive = read_drive(path)
        models = _cache.setdefault(("drive_models",), {})
        with _lock:
            res = simulate_and_validate(path, drive, list(variants), models)
        row.update({"maneuver": res.maneuver or "", "state": res.state, "vehicle": res.vehicle,
                    "source": res.source, "signal": res.signal, "window": res.window,
                    **{f"rmse_{v}_deg_s": res.rmse(v) for v in variants}, "error": ""})
        best = min(variants, key=lambda v: res.rmse(v))
        row["best_variant"] = best
        if diagnose:
            row.update(diagnose_drive(path, variants[0]))
    except (SuspInputError, RuntimeError, ValueError, OSError) as exc:
        row["error"] = f"{type(exc).__name__}: {exc}"
    return row


def diagnose_drive(path: str, variant: str) -> dict:
    """The discrepancy finder (``susp diagnose``) on one drive: verdict, terms, RMSE before/after the
    fit on this drive (no held-out drive in a one-drive fit), noise floor."""
    f = DiscrepancyFinder(variant=variant, heldout=False, progress=False).fit([path])
    rep = f.report()
    return {"diag_verdict": rep["verdict"],
            "diag_terms": ";".join(f"{t['name']}:{t['where']}" for t in rep["terms"]),
            "diag_rmse_before_deg_s": rep["heldout_rmse_before_deg_s"],
            "diag_rmse_after_deg_s": rep["heldout_rmse_after_deg_s"],
            "diag_noise_floor_deg_s": rep["noise_floor_deg_s"]}
