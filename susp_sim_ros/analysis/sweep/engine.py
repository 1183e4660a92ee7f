"""What one task does: a chunk of runs as one batched simulation, then the metrics of each run.

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
import threading
from typing import Mapping, Sequence

import numpy as np

from ...model.layout import OUTPUT_LABELS, P_INDEX
from .spec import MANEUVER_KEYS, SIGNAL, vehicle_key

_cache: dict = {}
_lock = threading.RLock()


# ---- run parameters -> model, parameter vector, maneuver ------------------------------------------------
def vehicle_params(data: Mapping, run: Mapping):
    from ...model.params import load_vehicle
    key = ("vp", vehicle_key(data, run))
    with _lock:
        if key not in _cache:
            if "vehicle_class" in run:
                cls = dict(data["vehicle_classes"][run["vehicle_class"]])
                base = load_vehicle(cls.pop("base"))
                over = {k: tuple(v) if isinstance(v, list) else v for k, v in cls.items()}
                _cache[key] = base.replace(name=f"{base.name}:{run['vehicle_class']}", **over)
            else:
                _cache[key] = load_vehicle(run.get("vehicle", "passat_b8_like"))
        return _cache[key]


def model_of(data: Mapping, run: Mapping):
    """``(Model, base parameter vector)`` of a run's vehicle and friction variant (cached)."""
    from ...model import Model
    key = ("model", vehicle_key(data, run), run.get("variant", "full"))
    vp = vehicle_params(data, run)
    with _lock:
        if key not in _cache:
            m = Model(vp, run.get("variant", "full"))
            _cache[key] = (m, m.params((1.0, 1.0, 1.0, 1.0)))
        return _cache[key]


def oil_of(run: Mapping) -> tuple[float, float, float, float]:
    oil = {w: 1.0 for w in ("FL", "FR", "RL", "RR")}
    if "oil_front" in run:
        oil["FL"] = oil["FR"] = run["oil_front"]
    if "oil_rear" in run:
        oil["RL"] = oil["RR"] = run["oil_rear"]
    for w in oil:
        oil[w] = run.get(f"oil_{w}", oil[w])
    return tuple(float(oil[w]) for w in ("FL", "FR", "RL", "RR"))


def params_of(data: Mapping, run: Mapping, base: np.ndarray | None = None) -> np.ndarray:
    """The run's parameter vector: the (vehicle, variant) base with the run's oil levels."""
    p = (model_of(data, run)[1] if base is None else base).copy()
    k = P_INDEX["OIL"]
    p[k:k + 4] = oil_of(run)
    return p


def maneuver_of(data: Mapping, run: Mapping, wheelbase: float):
    """The run's maneuver (cached: building one reads config/maneuvers.yaml)."""
    from ...model.maneuvers import bump_crossing, sine_steer
    geo = tuple(run.get(k) for k in MANEUVER_KEYS)
    key = ("maneuver", data["maneuver"], geo, wheelbase)
    with _lock:
        if key not in _cache:
            if data["maneuver"] == "bump_crossing":
                man = bump_crossing(speed=run.get("speed"), height=run.get("bump_height"),
                                    length=run.get("bump_length"), wheelbase=wheelbase)
            else:
                man = sine_steer(speed=run.get("speed"), amplitude=run.get("steer_amplitude"),
                                 frequency=run.get("steer_frequency"))
            _cache[key] = man
        return _cache[key]


def inputs_of(man, dt: float) -> np.ndarray:
    """Per-step inputs of a maneuver (cached per process; never written to)."""
    key = ("inputs", man.name, man.speed, man.steer_amplitude, man.steer_frequency, man.steer_start,
           man.steer_periods, man.duration, dt)
    with _lock:
        if key not in _cache:
            _cache[key] = man.to_inputs(dt)
        return _cache[key]


def after_time(man, wheelbase: float) -> float:
    """When the excitation is over [s]: the rear axle has left the bump / the last steer has ended."""
    if man.name == "bump_crossing":
        return (float(man.road.s[-1]) + wheelbase) / man.speed
    return man.steer_start + man.steer_periods / man.steer_frequency


def selection(data: Mapping) -> list[str]:
    """Output labels a chunk records: the maneuver's signal first, then those generic metrics name."""
    labels = [SIGNAL[data["maneuver"]]]
    for m in data["outputs"]:
        if isinstance(m, dict):
            lab = next(iter(m.values()))
            if lab not in labels:
                labels.append(lab)
    return labels


# ---- the batched simulation ---------------------------------------------------------------------------
def simulate_runs(data: Mapping, runs: Sequence[Mapping], threads: int | None = None):
    """Simulate ``runs``; batched per (variant, step count). Returns per run ``(Y[n, n_sel], done,
    t_after, dt_out)`` in the order given."""
    from ...model import simulate_batch
    if threads is not None:
        import numba
        numba.set_num_threads(max(1, min(int(threads), numba.config.NUMBA_NUM_THREADS)))
    dt, decim = data["step_s"], data["decim"]
    labels = selection(data)
    prepared = []
    for run in runs:
        model, base = model_of(data, run)
        wb = model.vehicle.wheelbase
        man = maneuver_of(data, run, wb)
        prepared.append((model, man, wb, params_of(data, run, base)))
    groups: dict = {}
    for i, (model, man, _, _) in enumerate(prepared):
        groups.setdefault((id(model.kernel), model.layout.n_p, man.n_steps(dt)), []).append(i)
    out: list = [None] * len(runs)
    for idx in groups.values():
        model = prepared[idx[0]][0]
        u_keys, U, r_keys, roads = {}, [], {}, []
        u_row, road_row = [], []
        for i in idx:
            man = prepared[i][1]
            uk = (man.speed, man.steer_amplitude, man.steer_frequency, man.steer_start, man.steer_periods)
            if uk not in u_keys:
                u_keys[uk] = len(U)
                U.append(inputs_of(man, dt))
            rk = (man.road.s.tobytes(), man.road.zl.tobytes(), man.road.zr.tobytes())
            if rk not in r_keys:
                r_keys[rk] = len(roads)
                roads.append(man.road)
            u_row.append(u_keys[uk])
            road_row.append(r_keys[rk])
        P = np.stack([prepared[i][3] for i in idx])
        _, Y, done = simulate_batch(model, P, np.stack(U), dt=dt, roads=roads, u_row=np.array(u_row),
                                    road_row=np.array(road_row), decim=decim, outputs=labels)
        n_req = prepared[idx[0]][1].n_steps(dt)
        for j, i in enumerate(idx):
            _, man, wb, _ = prepared[i]
            out[i] = (Y[j], int(done[j]) == n_req and bool(np.all(np.isfinite(Y[j]))),
                      after_time(man, wb), dt * decim)
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
    """:func:`decay_ratio` of every row of ``q[B, n]`` (from ``k0[B]`` on), vectorised; equal values."""
    B, n = q.shape
    idx = np.arange(n)[None, :]
    x = np.where(idx >= k0[:, None], q, 0.0)
    a = np.abs(x)
    rows = np.arange(B)
    k = np.argmax(a, axis=1)
    peak = a[rows, k]
    s = np.sign(x)
    opp = (s * s[rows, k][:, None] < 0) & (idx > k[:, None])
    has = opp.any(axis=1)
    j0 = np.argmax(opp, axis=1)
    opp2 = (s * s[rows, j0][:, None] < 0) & (idx > j0[:, None])
    j1 = np.where(opp2.any(axis=1), np.argmax(opp2, axis=1), n)
    second = np.where((idx >= j0[:, None]) & (idx < j1[:, None]), a, 0.0).max(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        r = np.where(has, second / np.where(peak > 0, peak, 1.0), 0.0)
    r[(peak == 0) | (k0 >= n)] = math.nan
    return r


def damping_ratio(r: float) -> float:
    """Equivalent damping ratio of a half-cycle amplitude ratio ``r`` (logarithmic decrement)."""
    if not math.isfinite(r):
        return math.nan
    if r <= 0.0:
        return 1.0
    d = -math.log(r)                    # per half cycle
    return float(d / math.sqrt(math.pi ** 2 + d * d))


def batch_metrics(data: Mapping, Y: np.ndarray, t_after: np.ndarray, dt_out: float,
                  ref: np.ndarray | None) -> np.ndarray:
    """The study's ``outputs`` (columns, in order) of runs ``Y[B, n, n_sel]`` (rates in deg/s).

    ``t_after[B]``: end of the excitation [s]; ``ref[B, n]``: reference traces [deg/s] or ``None``.
    Every value is a function of its own run only (row-wise reductions)."""
    labels = selection(data)
    B, n = Y.shape[0], Y.shape[1]
    q = np.degrees(Y[:, :, 0])
    a = np.abs(q)
    # sample k is at (k+1) dt_out: first sample at or after t_after
    k0 = np.clip(np.ceil(t_after / dt_out - 1e-9).astype(np.int64) - 1, 0, n)
    rows = np.arange(B)
    cols = []
    decay = None
    for m in data["outputs"]:
        if isinstance(m, dict):
            kind, lab = next(iter(m.items()))
            x = Y[:, :, labels.index(lab)]
            cols.append(np.abs(x).max(axis=1) if kind == "peak" else np.sqrt(np.mean(x * x, axis=1)))
        elif m == "peak_rate":
            cols.append(a.max(axis=1))
        elif m in ("decay_ratio", "damping_ratio"):
            if decay is None:
                decay = decay_ratios(q, k0)
            cols.append(decay if m == "decay_ratio" else np.array([damping_ratio(x) for x in decay]))
        elif m == "ring_out":
            above = a > data["ring_out_threshold_deg_s"]
            last = n - 1 - np.argmax(above[:, ::-1], axis=1)
            cols.append(np.where(above.any(axis=1), np.maximum((last + 1) * dt_out - t_after, 0.0), 0.0))
        elif m == "rms_after":
            w = max(int(round(data["after_window_s"] / dt_out)), 1)
            idx = k0[:, None] + np.arange(w)[None, :]
            valid = idx < n
            x = np.where(valid, q[rows[:, None], np.minimum(idx, n - 1)], 0.0)
            cnt = valid.sum(axis=1)
            cols.append(np.where(cnt > 0, np.sqrt((x * x).sum(axis=1) / np.maximum(cnt, 1)), math.nan))
        elif m == "rmse_ref" and ref is None:
            cols.append(np.full(B, math.nan))
        elif m == "rmse_ref":
            k = min(n, ref.shape[1])
            d = q[:, :k] - ref[:, :k]
            cols.append(np.sqrt(np.mean(d * d, axis=1)))
    return np.stack(cols, axis=1) if cols else np.zeros((B, 0))


# ---- tasks ---------------------------------------------------------------------------------------------
def reference_task(data: Mapping, refs: Sequence[Mapping], threads: int | None = None) -> list:
    """Signal traces [deg/s] of reference runs."""
    res = simulate_runs(data, refs, threads)
    for (Y, ok, _, _), r in zip(res, refs):
        if not ok:
            raise RuntimeError(f"reference run {json.dumps(dict(r))} became non-finite")
    return [np.degrees(Y[:, 0]) for Y, _, _, _ in res]


def chunk_task(data: Mapping, runs: Sequence[Mapping], refs: Sequence[np.ndarray | None],
               threads: int | None = None) -> dict:
    """One chunk: batched simulation and metrics. Returns ``{"ok": [...], "metrics": [[...], ...]}``
    (metrics NaN for a run that became non-finite)."""
    res = simulate_runs(data, runs, threads)
    n_out = len(data["outputs"])
    metrics = np.full((len(runs), n_out), math.nan)
    ok = [bool(r[1]) for r in res]
    by_len: dict = {}
    for i, (Y, good, _, _) in enumerate(res):
        if good:
            by_len.setdefault(Y.shape, []).append(i)
    for idx in by_len.values():
        Y = np.stack([res[i][0] for i in idx])
        ta = np.array([res[i][2] for i in idx])
        have = data.get("reference") is not None and all(refs[i] is not None for i in idx)
        ref = np.stack([refs[i] for i in idx]) if have else None
        metrics[idx] = batch_metrics(data, Y, ta, res[idx[0]][3], ref)
    return {"ok": ok, "metrics": metrics.tolist()}


def drive_task(path: str, variants: Sequence[str], diagnose: bool = False) -> dict:
    """Batch validation of one recorded drive: lockstep simulation with each variant, RMSE per variant
    in the paper's window and signal; with ``diagnose``, the discrepancy finder on this drive alone
    against the first variant. A drive that fails gives a row with ``error`` instead of raising."""
    from ...errors import SuspInputError
    from ...io.drive import read_drive
    from ..study import simulate_and_validate
    row = {"file": path}
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
    from ..discrepancy import DiscrepancyFinder
    f = DiscrepancyFinder(variant=variant, heldout=False, progress=False).fit([path])
    rep = f.report()
    return {"diag_verdict": rep["verdict"],
            "diag_terms": ";".join(f"{t['name']}:{t['where']}" for t in rep["terms"]),
            "diag_rmse_before_deg_s": rep["heldout_rmse_before_deg_s"],
            "diag_rmse_after_deg_s": rep["heldout_rmse_after_deg_s"],
            "diag_noise_floor_deg_s": rep["noise_floor_deg_s"]}
