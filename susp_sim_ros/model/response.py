"""What every simulation returns: a :class:`Response`, the labelled time series of one vehicle or a batch.

One result type for :func:`~susp_sim_ros.model.simulate` (one vehicle over an input series),
:func:`~susp_sim_ros.model.simulate_batch` (many vehicles, a leading vehicle axis) and
:func:`~susp_sim_ros.runtime.lockstep.run_lockstep` (a recorded drive through the node's core), with one label
spelling: the snake_case signal names of the interface (``roll_rate``, ``pitch_rate``, ``yaw_rate``,
``accel_x`` .. ``accel_z`` as on ``/imu/data``; the ``/sim/suspension`` quantities per wheel, e.g.
``damper_force_rl``). Units are SI (REP-103 axes), one per signal, taken from the kernel's output layout
(:data:`~susp_sim_ros.model.layout.OUTPUT_UNITS`).

The kernel's own layout names (``PITCH_RATE``, ``F_DAMPER_RL``) stay the names of the compiled arrays;
:func:`signal_name` / :func:`output_label` translate, and ``outputs=`` and ``response[...]`` accept
either (the kernel name as an alias of the signal it records). Pure numpy; pandas only inside
:meth:`Response.to_pandas`.
"""
from __future__ import annotations

import csv
import io
import os
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .layout import OUTPUT_LABELS, OUTPUT_UNITS, WHEELS

#: kernel output name (layout) -> signal name of the interface; a per-wheel output adds ``_fl`` .. ``_rr``
_SIGNAL_STEM = {
    "ROLL_RATE": "roll_rate", "PITCH_RATE": "pitch_rate", "YAW_RATE": "yaw_rate",
    "AX_SF": "accel_x", "AY_SF": "accel_y", "AZ_SF": "accel_z",
    "ROLL": "roll", "PITCH": "pitch", "YAW": "yaw",
    "POS_X": "position_x", "POS_Y": "position_y", "VEL_X": "velocity_x", "VEL_Y": "velocity_y",
    "HEAVE": "heave", "PATH_S": "path_s",
    "DEFL": "deflection", "DEFL_VEL": "deflection_velocity", "F_SPRING": "spring_force",
    "F_DAMPER": "damper_force", "F_FRICTION": "friction_force", "F_ARB": "arb_force",
    "F_Z": "tyre_vertical_force", "F_X": "wheel_force_x", "F_Y": "wheel_force_y",
    "Z_ROAD": "wheel_height",
}


def _stem_and_wheel(label: str) -> tuple[str, str]:
    """``('F_DAMPER', 'RL')`` of ``'F_DAMPER_RL'``, ``('PITCH_RATE', '')`` of a scalar output."""
    for w in WHEELS:
        if label.endswith("_" + w) and label[:-3] in OUTPUT_UNITS:
            return label[:-3], w
    return label, ""


def _signal_of(label: str) -> str:
    """Signal name of a kernel output (an output without an entry above: its name in lower case)."""
    stem, wheel = _stem_and_wheel(label)
    return _SIGNAL_STEM.get(stem, stem.lower()) + (f"_{wheel.lower()}" if wheel else "")


#: every kernel output in layout order, as signal names (the labels of a full response)
SIGNAL_NAMES: tuple[str, ...] = tuple(_signal_of(x) for x in OUTPUT_LABELS)
_TO_SIGNAL = dict(zip(OUTPUT_LABELS, SIGNAL_NAMES))
_TO_OUTPUT = dict(zip(SIGNAL_NAMES, OUTPUT_LABELS))
#: SI unit of every signal (from the layout's unit of its kernel output)
SIGNAL_UNITS: dict[str, str] = {s: OUTPUT_UNITS[_stem_and_wheel(k)[0]] for k, s in _TO_SIGNAL.items()}


def signal_name(label: str) -> str:
    """The signal name of an output given by either spelling (``'PITCH_RATE'`` -> ``'pitch_rate'``)."""
    if label in _TO_OUTPUT:
        return label
    try:
        return _TO_SIGNAL[label]
    except KeyError:
        raise KeyError(f"unknown output {label!r}; known: {', '.join(SIGNAL_NAMES)}") from None


def output_label(name: str) -> str:
    """The kernel layout name of an output given by either spelling (``'pitch_rate'`` -> ``'PITCH_RATE'``)."""
    return _TO_OUTPUT[signal_name(name)]


def _csv_unit(unit: str) -> str:
    """A unit as a column-name suffix, as :mod:`susp_sim_ros.analysis.csv_import` reads them
    (``rad/s`` -> ``rad_s``, ``m/s^2`` -> ``m_s2``)."""
    return unit.replace("/", "_").replace("^", "")


@dataclass(eq=False)
class Response:
    """Labelled outputs of a simulation, SI units.

    ``t`` (n,) sample times [s] (since the start of the run, or of the recorded drive for a lockstep
    run); ``values`` (n, k) for one vehicle or (B, n, k) for a batch of B vehicles, column ``j`` is
    ``labels[j]``; ``response["pitch_rate"]`` is its column, (n,) or (B, n). ``steps_done`` of
    ``steps_requested`` integration steps ran (an int, or (B,) for a batch: fewer when the health check
    stopped a run; the rest of its rows are zero); ``state`` the state vector(s) after the last step.

    ``t_ns``: the ROS times of the samples [ns] when the run follows a recorded drive's clock (a lockstep
    run, a finder's prediction of a drive), else None. What only a run through the node's core has (the
    recording's metadata, the divergence guard, refused inputs, the output file, the IMU samples) is in
    :class:`~susp_sim_ros.runtime.lockstep.LockstepRun`, which holds a Response.
    """

    t: np.ndarray
    values: np.ndarray
    labels: tuple[str, ...]
    steps_done: Any = None          # int, or np.ndarray (B,) for a batch
    steps_requested: int = 0
    state: np.ndarray | None = field(default=None, repr=False)
    t_ns: np.ndarray | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        self.labels = tuple(signal_name(x) for x in self.labels)
        self._column = {x: j for j, x in enumerate(self.labels)}

    # -- shape ---------------------------------------------------------------------------------------
    @property
    def is_batch(self) -> bool:
        """Whether ``values`` has a leading vehicle axis."""
        return self.values.ndim == 3

    @property
    def n_vehicles(self) -> int:
        return self.values.shape[0] if self.is_batch else 1

    def __len__(self) -> int:
        """Number of samples."""
        return len(self.t)

    @property
    def ok(self) -> bool:
        """Every vehicle ran all requested steps (True when the run does not count steps)."""
        if self.steps_done is None:
            return True
        return bool(np.all(np.asarray(self.steps_done) == self.steps_requested))

    # -- signals -------------------------------------------------------------------------------------
    def __getitem__(self, label: str) -> np.ndarray:
        """The samples of one signal: (n,) or (B, n) for a batch (a view, no copy)."""
        if not isinstance(label, str):
            raise TypeError(f"a Response is indexed by signal name, not {label!r}; recorded: "
                            f"{', '.join(self.labels)}")
        try:
            j = self._column[signal_name(label)]
        except KeyError:
            raise KeyError(f"output {label!r} not recorded; recorded: {', '.join(self.labels)}") from None
        return self.values[..., j]

    def __contains__(self, label: object) -> bool:
        try:
            return isinstance(label, str) and signal_name(label) in self._column
        except KeyError:
            return False

    def __iter__(self) -> Iterator[str]:
        """Not iterable: ``simulate_batch`` returned a ``(t, Y, done)`` tuple before it returned a
        Response, and unpacking one must fail loudly rather than bind labels."""
        raise TypeError("a Response is not a tuple: use .t, .values, .steps_done (or .labels, .signals)")

    @property
    def signals(self) -> dict[str, np.ndarray]:
        """``{label: samples}`` of every recorded signal (views into ``values``)."""
        return {x: self.values[..., j] for j, x in enumerate(self.labels)}

    @property
    def units(self) -> dict[str, str]:
        """``{label: SI unit}``."""
        return {x: SIGNAL_UNITS[x] for x in self.labels}

    def vehicle(self, b: int) -> "Response":
        """Vehicle ``b`` of a batch as a one-vehicle response (views, no copy)."""
        if not self.is_batch:
            raise IndexError("vehicle(): not a batch response")
        done = np.asarray(self.steps_done)
        return Response(self.t, self.values[b], self.labels, int(done[b]), self.steps_requested,
                        None if self.state is None else self.state[b])

    # -- names of the kernel era, kept for existing callers ------------------------------------------
    @property
    def y(self) -> np.ndarray:
        """``values`` (the name the old single-run result used)."""
        return self.values

    @property
    def outputs(self) -> np.ndarray:
        """``values`` (the name the lockstep result used)."""
        return self.values

    # -- export --------------------------------------------------------------------------------------
    def to_dict(self) -> dict[str, np.ndarray]:
        """Columns as a dict: ``time_s`` (and ``vehicle`` for a batch, long format), then every label."""
        if not self.is_batch:
            return {"time_s": self.t, **self.signals}
        B, n = self.values.shape[:2]
        out = {"vehicle": np.repeat(np.arange(B), n), "time_s": np.tile(self.t, B)}
        out.update({x: self.values[..., j].reshape(-1) for j, x in enumerate(self.labels)})
        return out

    def to_pandas(self):
        """A ``pandas.DataFrame``: index ``time_s`` (a ``(vehicle, time_s)`` MultiIndex for a batch),
        one column per label; the units in ``df.attrs["units"]``. Needs pandas (imported here only)."""
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("Response.to_pandas() needs pandas (pip install pandas); "
                              "to_dict() and to_csv() work without it") from None
        df = pd.DataFrame(self.to_dict())
        df = df.set_index(["vehicle", "time_s"] if self.is_batch else "time_s")
        df.attrs["units"] = self.units
        return df

    def to_csv(self, path: str | os.PathLike | None = None) -> str | None:
        """Write the columns as CSV with the unit in each column name (``pitch_rate_rad_s``, as
        :mod:`susp_sim_ros.analysis.csv_import` names them); to ``path``, or return the text."""
        cols = self.to_dict()
        head = [k if k in ("vehicle", "time_s") else f"{k}_{_csv_unit(SIGNAL_UNITS[k])}" for k in cols]
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(head)
        w.writerows(zip(*(c.tolist() for c in cols.values())))
        if path is None:
            return buf.getvalue()
        with open(path, "w", newline="") as f:
            f.write(buf.getvalue())
        return None


def selected_labels(outputs: Sequence[str] | None) -> tuple[tuple[str, ...], np.ndarray]:
    """Signal names and kernel output columns of an ``outputs=`` selection (either spelling; ``None``:
    every output)."""
    names = SIGNAL_NAMES if outputs is None else tuple(signal_name(x) for x in outputs)
    return names, np.array([OUTPUT_LABELS.index(_TO_OUTPUT[x]) for x in names], dtype=np.int64)


__all__ = ["Response", "SIGNAL_NAMES", "SIGNAL_UNITS", "output_label", "selected_labels", "signal_name"]
