"""Batch evaluation of candidate models over many drives at once (:func:`simulate_batch`).

A *model structure* is a list of candidates; its parameter vector ``x`` concatenates their parameters.
:class:`Evaluator` turns ``x`` into kernel parameter rows (one per drive), runs many parameter sets x
drives in one parallel batch, and turns the simulated gyro rates into residuals (simulated - measured,
deg/s) on each drive's comparison grid, with the measurement-chain terms (time offset, per-drive bias)
applied on the way.
"""
from __future__ import annotations

import itertools
import math
import weakref

from collections import OrderedDict
from collections.abc import Iterator, Sequence

import numpy as np
from numba import get_num_threads

from ...model import Model, simulate_batch
from ...model.vehicle import batch_cost
from ...model.layout import U_INDEX
from .candidates import BY_NAME, Candidate, neutral_base
from .data import SIGNAL_OF_OUTPUT, SIGNAL_OUTPUT, SIGNALS, DriveCase

RATES = ("ROLL_RATE", "PITCH_RATE", "YAW_RATE")
MIN_QUIET_BIAS = 20  # quiet lead-in samples for a standstill-style bias estimate
RUN_QUANTUM_S = 0.5  # a run's length is rounded up to this, so drives of similar length share a batch
#: bytes of simulated signals kept, in all of a process's evaluators together, for runs asked for again in a later
#: call (a calibration returning to a point it tried, a Jacobian about the point just evaluated); about 1600
#: six-drive runs of the bundled drives
RUN_CACHE_BYTES = 512 * 2**20
_TO_REPORT_UNITS = np.array([SIGNAL_OF_OUTPUT[s][1] for s in SIGNALS])


def kernel_calls(n_run: np.ndarray, lanes: int, threads: int) -> list[tuple[np.ndarray, int]]:
    """Which runs share one kernel call, and for how many steps: the runs of one length together, or
    all of them at the longest length when one thread's share of that is smaller
    (:func:`~susp_sim_ros.model.vehicle.batch_cost`): six drives of two lengths run as two calls of three
    vehicles keep each thread busy for both lengths one after the other, as one call of six for the
    longer length only. A run simulated beyond its length keeps the bits of its first steps (the
    kernel is causal and gives a vehicle the same bits in any lane of any block); only they are kept."""
    groups = [(np.nonzero(n_run == n)[0], int(n)) for n in np.unique(n_run)]
    if len(groups) > 1 and batch_cost(len(n_run), int(n_run.max()), lanes, threads) < \
            sum(batch_cost(len(g), n, lanes, threads) for g, n in groups):
        return [(np.arange(len(n_run)), int(n_run.max()))]
    return groups


class Structure:
    """A list of candidates with the layout of their joint parameter vector."""

    def __init__(self, items: Sequence[str | Candidate], data_weight: float = 1.0):
        self.cands: tuple[Candidate, ...] = tuple(BY_NAME[n] if isinstance(n, str) else n for n in items)
        self.names = tuple(c.name for c in self.cands)
        self.offsets = np.cumsum([0] + [c.n_params for c in self.cands])
        #: how much the data count against the priors (1: as their noise says; below 1 when left-out
        #: drives showed that the calibration follows the data too closely; see the finder's calibration)
        self.data_weight = float(data_weight)

    @property
    def prior_gain(self) -> float:
        """Factor on the prior residuals that gives the data their :attr:`data_weight`."""
        return 1.0 / math.sqrt(self.data_weight)

    @property
    def n_params(self) -> int:
        return int(self.offsets[-1])

    def span(self, name: str) -> range:
        """The indices of term ``name``'s parameters in the joint vector."""
        k = self.names.index(name)
        return range(int(self.offsets[k]), int(self.offsets[k + 1]))

    def slices(self) -> Iterator[tuple[Candidate, slice]]:
        """Each term with the slice of its parameters in the joint vector, in order."""
        for k, c in enumerate(self.cands):
            yield c, slice(int(self.offsets[k]), int(self.offsets[k + 1]))

    def part(self, x: np.ndarray, name: str) -> np.ndarray:
        s = self.span(name)
        return x[s.start:s.stop]

    def neutral(self) -> np.ndarray:
        return np.concatenate([c.neutral() for c in self.cands]) if self.cands else np.zeros(0)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        lo = [p.lower for c in self.cands for p in c.params]
        hi = [p.upper for c in self.cands for p in c.params]
        return np.array(lo, float), np.array(hi, float)

    def steps(self) -> np.ndarray:
        return np.array([p.step for c in self.cands for p in c.params], float)

    def labels(self) -> list[tuple[str, str]]:
        return [(c.name, p.name) for c in self.cands for p in c.params]

    def lag(self, x: np.ndarray) -> float:
        return float(self.part(x, "time_offset")[0]) if "time_offset" in self.names else 0.0

    def steer_offset(self, x: np.ndarray) -> float:
        """Recorded minus true steering-wheel angle [rad] (0 without the ``steering_offset`` term)."""
        return float(self.part(x, "steering_offset")[0]) if "steering_offset" in self.names else 0.0

    @property
    def bias(self) -> bool:
        return "sensor_bias" in self.names

    def with_(self, *items: str | Candidate) -> "Structure":
        new = [BY_NAME[n] if isinstance(n, str) else n for n in items]
        return Structure(self.cands + tuple(c for c in new if c.name not in self.names), self.data_weight)

    def without(self, name: str) -> "Structure":
        return Structure(tuple(c for c in self.cands if c.name != name), self.data_weight)

    def prior(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(indices, means, standard deviations) of the parameters with a normal prior."""
        ps = [p for c in self.cands for p in c.params]
        idx = np.array([j for j, p in enumerate(ps) if p.prior_sd is not None], np.int64)
        return (idx, np.array([ps[j].neutral for j in idx], float),
                np.array([ps[j].prior_sd for j in idx], float))

    def at_neutral(self, x: np.ndarray, name: str) -> np.ndarray:
        """A copy of ``x`` with the part of ``name`` at its neutral values (the calibration: the vehicle
        file's); ``x`` itself when the structure has no ``name``."""
        if name not in self.names:
            return x
        s = self.span(name)
        out = np.array(x, float, copy=True)
        out[s.start:s.stop] = self.cands[self.names.index(name)].neutral()
        return out

    def embed(self, other: "Structure", x_other: np.ndarray) -> np.ndarray:
        """This structure's vector with each parameter ``(term, parameter)`` that ``other`` has at its value in
        ``x_other``, the rest at neutral. By label, not by position in a term: a term whose parameters changed
        (a learned term rewritten with more columns or a freed part) keeps the values it shares."""
        fitted = dict(zip(other.labels(), x_other))
        return np.array([fitted.get(label, v) for label, v in zip(self.labels(), self.neutral())], float)


class RunCache:
    """The simulated signals of recent runs, least recently used dropped first beyond ``max_bytes``.

    Keyed by everything a run depends on within one :class:`Evaluator` (drive, steering offset, kernel
    parameter bytes, steps): the kernel gives a vehicle the same bits in any lane of any batch, so a hit is
    the run itself. An item is the cache's own read-only copy, so that :attr:`bytes` is the memory it
    holds (a view would keep its whole batch alive)."""

    def __init__(self, max_bytes: int):
        self.max_bytes, self.bytes = int(max_bytes), 0
        self._items: OrderedDict[tuple, np.ndarray] = OrderedDict()
        self.hits = 0

    def get(self, key: tuple) -> np.ndarray | None:
        y = self._items.get(key)
        if y is None:
            return None
        self.hits += 1
        self._items.move_to_end(key)
        return y

    def put(self, key: tuple, y: np.ndarray) -> None:
        y = np.array(y, copy=True)
        y.flags.writeable = False
        old = self._items.pop(key, None)
        self.bytes += y.nbytes - (old.nbytes if old is not None else 0)
        self._items[key] = y
        while self.bytes > self.max_bytes and self._items:
            self.bytes -= self._items.popitem(last=False)[1].nbytes

    def drop_owner(self, owner: int) -> None:
        """Forget the runs of one owner (keys starting with ``owner``: an :class:`Evaluator` that is gone)."""
        for key in [k for k in self._items if k[0] == owner]:
            self.bytes -= self._items.pop(key).nbytes


#: the one run cache of the process: every :class:`Evaluator` keeps its runs here under one byte budget (a test
#: session or a study holds many evaluators; a budget each would multiply the memory)
SHARED_RUNS = RunCache(RUN_CACHE_BYTES)


class OwnedRuns:
    """One :class:`Evaluator`'s runs in a shared :class:`RunCache` (its keys prefixed by its owner number),
    forgotten when the evaluator is gone."""

    _owners = itertools.count()

    def __init__(self, cache: RunCache, evaluator: object):
        self.cache, self.owner, self.hits = cache, next(self._owners), 0
        weakref.finalize(evaluator, cache.drop_owner, self.owner)

    def get(self, key: tuple) -> np.ndarray | None:
        y = self.cache.get((self.owner, *key))
        self.hits += y is not None
        return y

    def put(self, key: tuple, y: np.ndarray) -> None:
        self.cache.put((self.owner, *key), y)


class Evaluator:
    """Simulate parameter sets over the drives and compute residuals.

    ``model`` must contain every registered term a candidate uses (at zero effect); ``cases`` the
    prepared drives. Counts simulated vehicle-seconds in :attr:`vehicle_seconds`.
    """

    def __init__(self, model: Model, cases: Sequence[DriveCase], progress=None):
        self.model, self.cases = model, list(cases)
        self.P0 = np.stack([model.params(c.oil) for c in self.cases])
        self.Pn = neutral_base(self.P0)
        self.n_max = max(c.n_steps for c in self.cases)
        #: steps each drive is simulated for when only its compared samples are needed: up to its last
        #: compared sample plus the largest time offset the fit may try (a run is causal, so the compared
        #: samples are the same as those of a run to the end)
        late = -BY_NAME["time_offset"].params[0].lower
        quantum = math.ceil(RUN_QUANTUM_S / self.cases[0].dt)  # drives of similar length run in one batch
        self.n_compared = np.array([min(self.n_max, quantum * math.ceil(
            (math.ceil((float(c.t_grid_s.max()) + late) / c.dt) + 2) / quantum)) for c in self.cases], np.int64)
        U = np.zeros((len(self.cases), self.n_max, self.cases[0].U.shape[1]))
        for r, c in enumerate(self.cases):
            U[r, :c.n_steps] = c.U
            U[r, c.n_steps:] = c.U[-1]
        self.U = U
        self.roads = [c.road for c in self.cases]
        self.dt = self.cases[0].dt
        self.vehicle_seconds = 0.0
        self.progress = progress
        #: runs already simulated (:meth:`simulate`), in the process's one budget
        self.run_cache: RunCache | OwnedRuns = OwnedRuns(SHARED_RUNS, self)
        # residual weights (n_grid, n_sig): 1 / noise sigma of each drive's signal once known
        self.weights = [np.ones_like(c.y_meas) for c in self.cases]
        #: per drive, the correlation samples (samples per independent one) of each signal's residual after the
        #: first calibration (:func:`~.fit.learn_residual_correlation`); empty until then
        self.corr_samples: dict[int, np.ndarray] = {}

    def set_noise(self, sigma: Sequence[np.ndarray]) -> None:
        """Per drive, the white-noise sigma of each of its signals (native units): residuals are then
        whitened (divided by it) wherever they are stacked for fitting."""
        self.weights = [np.broadcast_to(1.0 / np.maximum(np.asarray(s, float), 1e-12), c.y_meas.shape).copy()
                        for s, c in zip(sigma, self.cases)]

    @property
    def n_res(self) -> list[int]:
        """Compared values per drive (samples x signals; drives may be narrowed to fewer signals)."""
        return [c.y_meas.size for c in self.cases]

    # -- parameters ---------------------------------------------------------------------------------
    def rows(self, st: Structure, x: np.ndarray, idx: Sequence[int] | None = None) -> np.ndarray:
        """Kernel parameter rows (len(idx), n_p) for structure ``st`` at ``x``."""
        idx = range(len(self.cases)) if idx is None else idx
        P = self.Pn[list(idx)].copy()
        P0 = P.copy()
        for c, part in st.slices():
            assert c.apply is not None  # every library and calibration candidate has one
            c.apply(P, P0, x[part], self.model)
        return P

    # -- simulation ---------------------------------------------------------------------------------
    def simulate(self, st: Structure, X: np.ndarray, idx: Sequence[int] | None = None, *,
                 to_end: bool = False) -> np.ndarray:
        """IMU signals for parameter vectors ``X`` (M, n): an object array (M, len(idx)) whose items are
        (n_steps, 6) arrays in :data:`~.data.SIGNALS` order (rates [deg/s], specific forces [m/s^2]) at
        the step times ``dt * (1 .. n_steps)``.

        Runs that are the same (one drive, the same kernel parameters and inputs: a finite-difference
        column of a parameter that drive does not use, or of the time offset, which only shifts the
        comparison) are simulated once; the kernel gives a vehicle the same bits in any lane of any
        batch. Runs of one drive under one steering offset share one row of inputs. Each drive is
        simulated up to its last compared sample (:attr:`n_compared` steps, the length of its items), or
        to the longest drive's end with ``to_end`` (the raw samples outside the comparison window: noise
        floors). Drives of one length run in one batch; items are read-only views of
        the batch outputs (no copies), one item shared by the same runs. A run simulated in an earlier
        call comes from :attr:`run_cache` (the process's one budget, which keeps its own copy) and is not
        counted again (progress, :attr:`vehicle_seconds`)."""
        idx = list(range(len(self.cases))) if idx is None else list(idx)
        X = np.atleast_2d(X)
        M, R = X.shape[0], len(idx)
        P = np.concatenate([self.rows(st, x, idx) for x in X])
        drive = np.tile(np.array(idx, np.int64), M)
        steer = (np.repeat([st.steer_offset(x) for x in X], R) if "steering_offset" in st.names
                 else np.zeros(M * R))
        first: dict[tuple, int] = {}
        run_of = np.array([first.setdefault((int(drive[b]), float(steer[b]), P[b].tobytes()), len(first))
                           for b in range(M * R)], np.int64)
        runs = np.unique(run_of, return_index=True)[1]  # one lane of each distinct run, in run order
        n_all = np.full(len(runs), self.n_max) if to_end else self.n_compared[drive[runs]]
        keys = [(int(drive[b]), float(steer[b]), P[b].tobytes(), int(n)) for b, n in zip(runs, n_all)]
        signals = np.empty(len(runs), object)
        todo = []
        for q, key in enumerate(keys):
            y = self.run_cache.get(key)
            if y is None:
                todo.append(q)
            else:
                signals[q] = y
        runs, n_run = runs[todo], n_all[todo]
        P, drive, steer = P[runs], drive[runs], steer[runs]
        U, u_row = self.U, drive
        if np.any(steer != 0.0):  # the inputs differ per (drive, steering offset): one input row for each
            rows: dict[tuple[int, float], int] = {}
            u_row = np.array([rows.setdefault((int(d), float(s)), len(rows)) for d, s in zip(drive, steer)],
                             np.int64)
            U = self.U[[d for d, _ in rows]]  # fancy indexing: a copy
            U[:, :, U_INDEX["SWA"]] -= np.array([s for _, s in rows])[:, None]
        for lanes, n in kernel_calls(n_run, self.model.kernel.LANES, get_num_threads()):
            res = simulate_batch(self.model, P[lanes], U[:, :n], dt=self.dt, roads=self.roads,
                                 u_row=u_row[lanes], road_row=drive[lanes], outputs=SIGNAL_OUTPUT)
            Y = res.values
            Y[res.steps_done < n_run[lanes]] = 1e3  # a diverged run: a huge residual, never a crash
            Y *= _TO_REPORT_UNITS  # in place: this call's own array, tens of MB for a Jacobian batch
            Y.flags.writeable = False  # its items may be shared by the same runs
            for q, lane in enumerate(lanes):
                signals[todo[lane]] = Y[q, :n_run[lane]]
                self.run_cache.put(keys[todo[lane]], signals[todo[lane]])
            self.vehicle_seconds += len(lanes) * n * self.dt
        if self.progress is not None:
            self.progress.update(len(runs))
        out = np.empty((M, R), object)
        out.ravel()[:] = signals[run_of]
        return out

    def simulate_outputs(self, st: Structure, x: np.ndarray, r: int, outputs: Sequence[str]) -> np.ndarray:
        """Any kernel outputs (SI, ``model/layout.py`` labels) of drive ``r`` under structure ``st`` at
        ``x``, to the drive's end: (n_steps, len(outputs)) at the step times (:attr:`DriveCase.t_sim_s`).
        The steering offset of the structure applies as in :meth:`simulate`."""
        U = self.U[r:r + 1, :self.cases[r].n_steps].copy()
        if "steering_offset" in st.names:
            U[:, :, U_INDEX["SWA"]] -= st.steer_offset(x)
        res = simulate_batch(self.model, self.rows(st, x, [r]), U, dt=self.dt, roads=[self.roads[r]],
                             outputs=list(outputs))
        self.vehicle_seconds += self.cases[r].n_steps * self.dt
        return res.values[0]

    # -- residuals ----------------------------------------------------------------------------------
    def case_residual(self, r: int, rates: np.ndarray, lag: float, bias: bool) -> np.ndarray:
        """Residual (n_grid, n_sig) simulated - measured (native units) of drive ``r`` from its simulated
        signals (n_steps, 6) (an item of :meth:`simulate`); ``lag`` [s]: the measured signal is the
        model output delayed by ``lag``."""
        c = self.cases[r]
        t = c.dt * np.arange(1, len(rates) + 1)
        tq = c.t_grid_s - lag
        sim = np.column_stack([np.interp(tq, t, rates[:, a]) for a in c.axes])
        e = sim - c.y_meas
        if bias:
            e = e - e[self.bias_rows(r)].mean(axis=0)
        return e

    def bias_rows(self, r: int) -> np.ndarray:
        """Comparison samples the sensor-bias estimate of drive ``r`` uses: its quiet lead-in (a
        standstill-style zeroing) when it has one of :data:`MIN_QUIET_BIAS` samples; else every compared
        sample that counts in the fit (the bias profiled out as a constant offset of the whole drive)."""
        c = self.cases[r]
        if c.quiet is not None and c.quiet.sum() >= MIN_QUIET_BIAS:
            return c.quiet
        return self.weights[r][:, 0] > 0

    def bias_values(self, r: int, rates: np.ndarray, lag: float) -> tuple[np.ndarray, np.ndarray]:
        """Estimated gyro bias [deg/s] of drive ``r`` per compared signal (measured - simulated over the
        quiet lead-in), and its standard error."""
        e = -self.case_residual(r, rates, lag, False)
        q = e[self.bias_rows(r)]
        return q.mean(axis=0), q.std(axis=0, ddof=1) / np.sqrt(len(q))

    def residuals(self, st: Structure, X: np.ndarray, idx: Sequence[int] | None = None) -> np.ndarray:
        """Stacked residual vectors (M, n_res(idx)) for parameter vectors ``X``."""
        idx = list(range(len(self.cases))) if idx is None else list(idx)
        X = np.atleast_2d(X)
        rates = self.simulate(st, X, idx)
        out = []
        for m, x in enumerate(X):
            lag = st.lag(x)
            out.append(np.concatenate([(self.case_residual(r, rates[m, j], lag, st.bias) * self.weights[r]).ravel()
                                       for j, r in enumerate(idx)]))
        return np.array(out)

    def case_residuals(self, st: Structure, x: np.ndarray, idx: Sequence[int] | None = None) -> dict:
        """Native-unit residuals {drive index: (n_grid, n_sig)} of structure ``st`` at ``x``."""
        idx = list(range(len(self.cases))) if idx is None else list(idx)
        rates = self.simulate(st, x[None], idx)[0]
        lag = st.lag(x)
        return {r: self.case_residual(r, rates[j], lag, st.bias) for j, r in enumerate(idx)}
