"""Detection study of damper oil loss (issue 14): every inspection method on the same virtual cars.

A study of ``kind: roc`` (``config/studies/inspection_roc.yaml``, run by ``susp study``) draws ``cars``
cars, car ``i`` from a random stream seeded by ``(seed, i)`` alone (so chunks are reproducible wherever
they run and a resumed study gets the same cars):

- an oil state (``states``: shares of intact cars, one damper oil-empty, one damper at half oil, several
  dampers losing oil), the wheel(s) at random;
- the vehicle, varied uniformly within the vehicle file's documented ranges (``variation``: sprung mass
  and load, tyre stiffness (pressure), unsprung masses, friction levels, ...), the speed at the bump,
  the bump height and the gyro noise within the study's ranges.

Each car is the reference model (``truth_variant``) with its parameters; it crosses the bump and is
measured by a 200 Hz IMU with white noise, and it stands on the virtual EUSAMA bench
(:func:`~susp_sim_ros.model.rigs.eusama_bench`). The statistics, larger = more suspicious:

- ``eusama``: 100 - the lowest EUSAMA % of the four wheels;
- ``phase_shift``: minus the lowest minimum phase angle of the four wheels [deg];
- ``decay_ratio``: pitch-rate decay ratio after the rear axle has left the bump
  (:func:`~susp_sim_ros.analysis.sweep.tasks.decay_ratio`, on the measured, noisy rate);
- ``model_based``: 1 - the lowest oil level of :func:`~.estimate.one_step_estimate` on the bump
  crossing (the estimator is told nothing of the car but its class); ``model_based_<variant>`` for the
  other ``estimator_variants`` (``dahl_only``: the estimator built on the Dahl-only friction model,
  issue 14 item 4).

``truth_generator`` (default ``"model"``) may instead name a plug-in ``"package.module:function"``
(:func:`truth_generator`) that gives the bump crossing from another simulator, with its own
``truth_generator_options`` (:func:`generator_options`); a plug-in drive's ``metadata["truth_form"]`` is
recorded per car (``truth_form`` column of ``cars.csv``).

Output (:func:`finish_roc`): ROC curves (PNG), AUC with a stratified bootstrap 95 % interval and the
sensitivity at 95 % specificity per method, for one damper oil-empty (the ``roc`` key of
``summary.json``, interface.md), one damper at half oil, and any oil loss; ``cars.csv`` with every car.
"""
from __future__ import annotations

import csv
import importlib
import math
import sys
from pathlib import Path
from collections.abc import Mapping, Sequence

import numpy as np

from ...errors import ConfigError
from ...io.drive import ImuSeries, Series, TestDrive
from ...model import Model, simulate
from ...model.maneuvers import bump_crossing
from ...model.paper import IMU_OUTPUTS
from ...model.params import DEFAULT_VEHICLE, load_variant, load_vehicle
from ...model.rigs import eusama_bench, eusama_plate_motion
from ..discrepancy.data import prepare_case
from .estimate import evaluator_for, load_config, nuisance_params, one_step_estimate

# The detection study's oil groups of a car (``roc.states``: the share of cars in each). Not the vehicle
# states of the registry (``model/paper.py`` ``STATES``: the paper's three oil configurations of one car).
OIL_GROUPS = (INTACT_CAR, ONE_EMPTY, ONE_HALF, SEVERAL) = ("intact", "one_empty", "one_half", "several")
METHODS = ("eusama", "phase_shift", "decay_ratio", "model_based")
SEVERITIES = {ONE_EMPTY: "one damper oil-empty", ONE_HALF: "one damper at half oil",
              "any": "any oil loss (one or more dampers)"}
ROC_KEYS = {"seed", "cars", "states", "variation", "speed_kmh", "bump_height", "gyro_noise_deg_s",
            "accel_noise_m_s2", "imu_rate_hz", "truth_variant", "estimator_variants", "bootstrap",
            "specificity", "several_oil", "local_workers", "vehicle", "truth_generator", "truth_generator_options"}


# ---- the study description ------------------------------------------------------------------------------
def _roc_mapping(data: dict, source: str) -> dict:
    """The study's ``roc:`` mapping, checked for unknown keys."""
    roc = data.get("roc")
    if not isinstance(roc, dict):
        raise ConfigError(f"{source}: roc: a roc study needs a 'roc:' mapping (see config/studies/inspection_roc.yaml)")
    unknown = set(roc) - ROC_KEYS
    if unknown:
        raise ConfigError(f"{source}: roc: unknown key(s) {', '.join(sorted(unknown))}; "
                          f"known: {', '.join(sorted(ROC_KEYS))}")
    return roc


def _positive(roc: Mapping, source: str, key: str):
    """``roc[key]``, a finite positive number (ConfigError naming the key otherwise)."""
    v = roc.get(key)
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
        raise ConfigError(f"{source}: roc.{key}: expected a positive number, got {v!r}")
    return v


def _range_pair(roc: Mapping, source: str, key: str) -> list[float]:
    """``roc[key]`` as ``[lo, hi]`` with 0 < lo <= hi (a range the cars are drawn from uniformly)."""
    v = roc.get(key)
    if (not isinstance(v, list) or len(v) != 2 or not all(isinstance(x, (int, float)) for x in v)
            or not 0 < v[0] <= v[1]):
        raise ConfigError(f"{source}: roc.{key}: expected [lo, hi] with 0 < lo <= hi, got {v!r}")
    return [float(v[0]), float(v[1])]


def _group_shares(roc: Mapping, source: str) -> dict[str, float]:
    """``roc.states``: the share [-] of cars in each oil group of :data:`OIL_GROUPS` (intact and
    one damper oil-empty required), adding up to 1."""
    states = roc.get("states")
    if (not isinstance(states, dict) or set(states) - set(OIL_GROUPS) or INTACT_CAR not in states
            or ONE_EMPTY not in states):
        raise ConfigError(f"{source}: roc.states: expected shares of {', '.join(OIL_GROUPS)} (intact and one_empty "
                          f"required), got {states!r}")
    shares = {k: float(v) for k, v in states.items()}
    if any(v < 0 for v in shares.values()) or not math.isclose(sum(shares.values()), 1.0, abs_tol=1e-6):
        raise ConfigError(f"{source}: roc.states: shares must be >= 0 and add up to 1, got {shares}")
    return shares


def _models(roc: Mapping, source: str, vehicle: str, load) -> tuple[list, str, list]:
    """The car model's choices, each loaded once to check it: (varied vehicle parameters, each with a
    documented range; the truth's variant; the estimators' variants). ``load`` is the sweep's loader
    that turns a load error into a ConfigError naming the key."""
    vp = load(source, "roc.vehicle", load_vehicle, vehicle)
    variation = roc.get("variation") or []
    if not isinstance(variation, list) or any(v not in vp.priors for v in variation):
        raise ConfigError(f"{source}: roc.variation: expected vehicle parameters with a documented range in "
                          f"{vp.source_file}, got {variation!r}")
    truth = roc.get("truth_variant", "full")
    ests = roc.get("estimator_variants", ["full"])
    if not isinstance(ests, list) or not ests:
        raise ConfigError(f"{source}: roc.estimator_variants: expected a non-empty list of variants")
    for i, v in enumerate([truth, *ests]):
        load(source, f"roc.variants[{i}]", load_variant, v)
    return variation, truth, ests


def _chunk_size(data: Mapping, source: str) -> int:
    """``chunk_size``: cars per chunk (one task), a positive integer (default 20)."""
    chunk = data.get("chunk_size", 20)
    if isinstance(chunk, bool) or not isinstance(chunk, int) or chunk < 1:
        raise ConfigError(f"{source}: chunk_size: expected a positive integer, got {chunk!r}")
    return chunk


def roc_spec(data: dict, source: str, name: str):
    """A validated ``kind: roc`` study (:class:`~susp_sim_ros.analysis.sweep.spec.StudySpec`): the
    ``roc:`` settings checked and normalised (speeds in km/h, bump heights in m, gyro noise in deg/s,
    accelerometer noise in m/s^2, IMU rate in Hz), one run per car, ``chunk_size`` cars per chunk."""
    # function-level: breaks the cycle inspection.roc <-> sweep (sweep/kinds.py imports roc_spec)
    from ..sweep.spec import Chunk, StudySpec, _load
    roc = _roc_mapping(data, source)
    cars = int(_positive(roc, source, "cars"))
    shares = _group_shares(roc, source)
    vehicle = roc.get("vehicle", DEFAULT_VEHICLE)
    variation, truth, ests = _models(roc, source, vehicle, _load)
    chunk = _chunk_size(data, source)
    several = roc.get("several_oil", [0.0, 0.5])
    generator = str(roc.get("truth_generator", "model"))
    truth_generator(generator, f"{source}: roc.truth_generator")
    norm = {"name": name, "kind": "roc", "description": str(data.get("description", "")), "vehicle": vehicle,
            "chunk_size": chunk, "results": "csv",
            "roc": {"seed": int(_positive(roc, source, "seed")), "cars": cars, "states": shares,
                    "variation": list(variation),
                    "speed_kmh": _range_pair(roc, source, "speed_kmh"),
                    "bump_height": _range_pair(roc, source, "bump_height"),
                    "gyro_noise_deg_s": _range_pair(roc, source, "gyro_noise_deg_s"),
                    "accel_noise_m_s2": float(roc.get("accel_noise_m_s2", 0.02)),
                    "imu_rate_hz": float(roc.get("imu_rate_hz", 200.0)), "truth_variant": truth,
                    "estimator_variants": list(ests), "bootstrap": int(roc.get("bootstrap", 1000)),
                    "specificity": float(roc.get("specificity", 0.95)), "several_oil": [float(x) for x in several],
                    "local_workers": int(roc.get("local_workers", 2)), "truth_generator": generator}}
    options = generator_options(generator, roc.get("truth_generator_options"), norm["roc"],
                                f"{source}: roc.truth_generator_options")
    if options:   # only then: the hash of a study without options stays as it was
        norm["roc"]["truth_generator_options"] = options
    spec = StudySpec(source, norm)
    spec.runs = [{"car": i} for i in range(cars)]
    spec.chunks = [Chunk(k, tuple(range(j, min(j + chunk, cars)))) for k, j in enumerate(range(0, cars, chunk))]
    return spec


# ---- one car ---------------------------------------------------------------------------------------------
def car_draw(roc: Mapping, vp, i: int) -> dict:
    """Car ``i``: its oil state, oil levels, vehicle parameter values and maneuver (pure function of
    ``(seed, i)``)."""
    rng = np.random.default_rng([int(roc["seed"]), int(i)])
    names = list(roc["states"])
    state = names[int(rng.choice(len(names), p=[roc["states"][n] for n in names]))]
    oil = [1.0] * 4
    if state == ONE_EMPTY:
        oil[int(rng.integers(4))] = 0.0
    elif state == ONE_HALF:
        oil[int(rng.integers(4))] = 0.5
    elif state == SEVERAL:
        lo, hi = roc["several_oil"]
        for w in rng.choice(4, size=int(rng.integers(2, 5)), replace=False):
            oil[int(w)] = float(rng.uniform(lo, hi))
    values: dict[str, float | tuple[float, ...]] = {}   # per parameter: a scalar or per axle
    for f in roc["variation"]:
        pr = vp.priors[f]
        if pr.shape == "axle":
            values[f] = tuple(float(rng.uniform(pr.lo[a], pr.hi[a])) for a in range(2))
        elif pr.shape == "table":
            values[f] = float(rng.uniform(pr.lo[0], pr.hi[0]))
        else:
            values[f] = float(rng.uniform(pr.lo[0], pr.hi[0]))
    return {"car": int(i), "state": state, "oil": oil, "values": values,
            "speed_kmh": float(rng.uniform(*roc["speed_kmh"])), "bump_height": float(rng.uniform(*roc["bump_height"])),
            "gyro_noise_deg_s": float(rng.uniform(*roc["gyro_noise_deg_s"])), "noise_seed": int(rng.integers(2**31))}


def car_vehicle(vp, values: Mapping):
    """The nominal vehicle with the car's values (damper tables: a factor on the whole curve)."""
    changes = {}
    for f, v in values.items():
        if vp.priors[f].shape == "table":
            changes[f] = tuple(tuple(float(x) * v for x in row) for row in getattr(vp, f))
        else:
            changes[f] = v
    return vp.replace(**changes)


def bump_drive(model, draw: Mapping, roc: Mapping, dt: float = 0.001):
    """The car's bump crossing as a recorded drive (in memory): inputs at 100 Hz, road profile, and a
    ``imu_rate_hz`` IMU with white gyro and accelerometer noise; plus the index of the first IMU sample
    after the rear axle has left the bump."""
    vp = model.vehicle
    man = bump_crossing(speed=draw["speed_kmh"] / 3.6, height=draw["bump_height"], wheelbase=vp.wheelbase)
    res = simulate(model, man.to_inputs(dt), dt=dt, road=man.road, oil=draw["oil"],
                   outputs=list(IMU_OUTPUTS))
    if not res.ok:
        raise RuntimeError(f"car {draw['car']}: the truth simulation diverged")
    rng = np.random.default_rng(draw["noise_seed"])
    step = max(1, int(round(1.0 / (roc["imu_rate_hz"] * dt))))
    y = res.y[step - 1::step]
    t = res.t[step - 1::step]
    t0 = 1_000_000_000
    gyro = y[:, :3] + np.radians(draw["gyro_noise_deg_s"]) * rng.standard_normal((len(t), 3))
    accel = y[:, 3:] + roc["accel_noise_m_s2"] * rng.standard_normal((len(t), 3))
    t_in = np.arange(0.0, man.duration + 1e-9, 0.01)
    t_in_ns = t0 + np.round(t_in * 1e9).astype(np.int64)
    meta = {"vehicle": vp.name, "maneuver": f"{man.name}_{draw['speed_kmh']:.0f}kmh",
            "damper_oil_level": "unknown", "source": "simulated:inspection_roc"}
    drive = TestDrive(meta, Series(t_in_ns, np.full(t_in.size, man.speed)), Series(t_in_ns.copy(), np.zeros(t_in.size)),
                      man.road, None, ImuSeries(t0 + np.round(t * 1e9).astype(np.int64), gyro, accel), {})
    t_after = (float(man.road.s[-1]) + vp.wheelbase) / man.speed
    return drive, int(np.searchsorted(t, t_after)), np.degrees(gyro[:, 1])


def truth_generator(spec: str, source: str = "roc.truth_generator"):
    """The bump-crossing generator a study names: ``"model"`` (None: the reference model,
    :func:`bump_drive`) or a plug-in ``"package.module:function"`` taking ``(draw, roc)`` and returning
    what :func:`bump_drive` returns. The product ships no truth generator; the repository's
    ``truth_generators`` package (``truth_generators.roc:bump_crossing``) is found from the current
    directory when it is not installed, so run such a study from the repository root."""
    if spec == "model":
        return None
    module, sep, func = spec.partition(":")
    if not sep or not module or not func.isidentifier():
        raise ConfigError(f"{source}: expected 'model' or a plug-in 'package.module:function', got {spec!r}")
    try:
        mod = importlib.import_module(module)
    except ModuleNotFoundError as exc:
        if str(Path.cwd()) in sys.path or (exc.name or "").split(".")[0] != module.split(".")[0]:
            raise ConfigError(f"{source}: cannot import {module!r} ({exc})") from exc
        sys.path.append(str(Path.cwd()))
        try:
            mod = importlib.import_module(module)
        except ModuleNotFoundError as exc2:
            raise ConfigError(f"{source}: cannot import {module!r} ({exc2}; run from the repository root)") from exc2
    fn = getattr(mod, func, None)
    if not callable(fn):
        raise ConfigError(f"{source}: {module!r} has no function {func!r}")
    return fn


def generator_options(spec: str, options, roc: Mapping, source: str = "roc.truth_generator_options") -> dict:
    """The plug-in's ``roc.truth_generator_options`` (a mapping, default none), checked and normalised by
    the plug-in's module function ``<function>_options(options, roc)`` when it has one (a ValueError
    there is a ConfigError naming the key); the plug-in reads them from ``roc["truth_generator_options"]``.
    The reference model (``"model"``) takes none."""
    if options is not None and not isinstance(options, dict):
        raise ConfigError(f"{source}: expected a mapping, got {options!r}")
    fn = truth_generator(spec, source)
    module, _, func = spec.partition(":")
    check = None if fn is None else getattr(sys.modules[module], f"{func}_options", None)
    if check is None:
        if options and fn is None:
            raise ConfigError(f"{source}: the reference model ('model') takes no options")
        return dict(options or {})
    try:
        return dict(check(options, roc))
    except ValueError as exc:
        raise ConfigError(f"{source}: {exc}") from exc


_cache: dict = {}


def _estimator(vehicle: str, variant: str, cfg: dict):
    key = ("est", vehicle, variant)
    if key not in _cache:
        m = Model(vehicle, variant)
        _cache[key] = (m, nuisance_params(m, cfg["estimator"]["nuisance"],
                                          cfg["estimator"].get("nuisance_range_scale")))
    return _cache[key]


def car_statistics(data: Mapping, i: int) -> dict:
    """Every method's statistic for car ``i`` (one row of ``cars.csv``)."""
    # function-level: breaks the cycle inspection.roc <-> sweep (sweep/kinds.py imports roc_spec)
    from ..sweep.tasks import decay_ratio
    roc = data["roc"]
    key = ("setup", data["vehicle"], roc["truth_variant"])
    if key not in _cache:
        _cache[key] = (load_vehicle(data["vehicle"]), eusama_plate_motion(), load_config(),
                       load_variant(roc["truth_variant"]))
    vp0, plate, cfg, truth_variant = _cache[key]
    draw = car_draw(roc, vp0, i)
    car = Model(car_vehicle(vp0, draw["values"]), truth_variant)
    row = {"car": i, "state": draw["state"], **{f"oil_{w}": o for w, o in zip(("FL", "FR", "RL", "RR"), draw["oil"])},
           "speed_kmh": draw["speed_kmh"], "bump_height_m": draw["bump_height"],
           "gyro_noise_deg_s": draw["gyro_noise_deg_s"]}
    for f, v in draw["values"].items():
        if isinstance(v, tuple):
            row[f"{f}_front"], row[f"{f}_rear"] = v
        else:
            row[f] = v
    bench = eusama_bench(car, draw["oil"], plate=plate)
    row["eusama_min_percent"] = min(r.eusama_percent for r in bench.values())
    row["phase_min_deg"] = min(r.phase_min_deg for r in bench.values())
    plugin = truth_generator(roc.get("truth_generator", "model"))
    if plugin is not None:
        drive, k_after, pitch_meas = plugin(draw, roc)
        if drive.metadata.get("truth_form"):   # the plug-in's form of the truth (a generator family)
            row["truth_form"] = str(drive.metadata["truth_form"])
    else:
        drive, k_after, pitch_meas = bump_drive(car, draw, roc)
    row["decay_ratio"] = decay_ratio(pitch_meas, k_after)
    for variant in roc["estimator_variants"]:
        model, cal = _estimator(data["vehicle"], variant, cfg)
        case = prepare_case(f"car_{i}.mcap", drive, wheelbase=model.vehicle.wheelbase)
        ev, _ = evaluator_for(model, [case], cfg)
        x, _ = one_step_estimate(ev, cal, cfg)
        sfx = "" if variant == roc["estimator_variants"][0] else f"_{variant}"
        for w, o in zip(("FL", "FR", "RL", "RR"), x):
            row[f"est{sfx}_oil_{w}"] = float(o)
        row[f"model_based{sfx}"] = float(1.0 - np.min(x))
    row["eusama"] = 100.0 - row["eusama_min_percent"]
    row["phase_shift"] = -row["phase_min_deg"]
    return row


def roc_task(data: Mapping, cars: Sequence[int]) -> list[dict]:
    """One chunk: the rows of its cars (a failed car is a row with its error, never a lost chunk)."""
    rows = []
    for i in cars:
        try:
            rows.append(car_statistics(data, i))
        except Exception as exc:  # noqa: BLE001 - reported per car in cars.csv and the summary
            rows.append({"car": int(i), "error": f"{type(exc).__name__}: {exc}"})
    return [{"rows": rows}]


# ---- ROC analysis ------------------------------------------------------------------------------------------
def auc(neg: np.ndarray, pos: np.ndarray) -> float:
    """Area under the ROC curve: P(pos > neg) + P(tie) / 2 (Mann-Whitney)."""
    from scipy.stats import rankdata
    x = np.concatenate([neg, pos])
    r = rankdata(x)
    n0, n1 = len(neg), len(pos)
    return float((r[n0:].sum() - n1 * (n1 + 1) / 2) / (n0 * n1))


def sensitivity_at(neg: np.ndarray, pos: np.ndarray, specificity: float) -> float:
    """Share of positives above the threshold that keeps ``specificity`` of the negatives below it."""
    thr = np.quantile(neg, specificity, method="higher")
    return float(np.mean(pos > thr))


def roc_summary(neg: np.ndarray, pos: np.ndarray, n_boot: int, specificity: float, seed: int) -> dict:
    """AUC, stratified bootstrap 95 % interval, sensitivity at ``specificity``."""
    rng = np.random.default_rng(seed)
    a = auc(neg, pos)
    boots = [auc(rng.choice(neg, neg.size), rng.choice(pos, pos.size)) for _ in range(n_boot)]
    lo, hi = np.quantile(boots, [0.025, 0.975])
    return {"auc": a, "auc_ci95": [float(lo), float(hi)],
            "sensitivity_at_95_specificity": sensitivity_at(neg, pos, specificity),
            "n_negative": int(neg.size), "n_positive": int(pos.size)}


def roc_curve(neg: np.ndarray, pos: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    thr = np.unique(np.concatenate([neg, pos]))[::-1]
    fpr = np.array([0.0] + [np.mean(neg >= t) for t in thr])
    tpr = np.array([0.0] + [np.mean(pos >= t) for t in thr])
    return fpr, tpr


def finish_roc(spec, store, plot: bool) -> dict:
    """Collect the cars, write ``cars.csv``, the ROC figure and the ``roc`` summary."""
    roc = spec.data["roc"]
    rows = [r for chunk in store.drive_rows() for r in chunk["rows"]]
    rows.sort(key=lambda r: r["car"])
    failed = [r for r in rows if "error" in r]
    good = [r for r in rows if "error" not in r]
    header = sorted({k for r in good for k in r}, key=lambda k: (k != "car", k != "state", k))
    out = Path(store.out)
    with open(out / "cars.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header + ["error"])
        for r in rows:
            w.writerow([r.get(h, "") for h in header] + [r.get("error", "")])
    methods = list(METHODS) + [f"model_based_{v}" for v in roc["estimator_variants"][1:]]
    stat = {m: np.array([r[m] for r in good], float) for m in methods}
    state = np.array([r["state"] for r in good])
    neg = state == INTACT_CAR
    groups = {ONE_EMPTY: state == ONE_EMPTY, ONE_HALF: state == ONE_HALF, "any": state != INTACT_CAR}
    by_sev: dict = {}
    for sev, pos in groups.items():
        if pos.sum() < 2 or neg.sum() < 2:
            continue
        by_sev[sev] = {m: roc_summary(stat[m][neg], stat[m][pos], roc["bootstrap"], roc["specificity"],
                                      roc["seed"] + k) for k, m in enumerate(methods)}
    result = {"roc": by_sev.get(ONE_EMPTY, {}), "roc_by_severity": by_sev,
              "roc_positive_class": SEVERITIES[ONE_EMPTY], "cars_ok": len(good), "cars_failed": len(failed),
              "failures": failed[:10], "table": str(out / "cars.csv"), "plots": []}
    if plot and by_sev:
        result["plots"].append(str(plot_roc(stat, neg, groups, by_sev, methods, out / f"{spec.name}.png")))
    return result


def plot_roc(stat, neg, groups, by_sev, methods, path: Path) -> Path:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    sevs = [s for s in (ONE_EMPTY, ONE_HALF, "any") if s in by_sev]
    fig, axes = plt.subplots(1, len(sevs), figsize=(4.6 * len(sevs), 4.4), squeeze=False)
    for ax, sev in zip(axes[0], sevs):
        pos = groups[sev]
        for m in methods:
            fpr, tpr = roc_curve(stat[m][neg], stat[m][pos])
            s = by_sev[sev][m]
            ax.plot(fpr, tpr, label=f"{m}: AUC {s['auc']:.3f} [{s['auc_ci95'][0]:.3f}, {s['auc_ci95'][1]:.3f}]")
        ax.plot([0, 1], [0, 1], ":", color="0.6")
        ax.axvline(0.05, color="0.7", lw=0.8)
        ax.set_title(f"{SEVERITIES[sev]} vs intact", fontsize=10)
        ax.set_xlabel("false positive rate (1 - specificity)")
        ax.set_ylabel("sensitivity")
        ax.legend(fontsize=7, loc="lower right")
        ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
