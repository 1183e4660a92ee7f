"""Input integrity (issue 28): one check of a recorded test drive that every command runs on what it reads.

:func:`check_drive_integrity` looks at each input series of a :class:`~susp_sim_ros.io.drive.TestDrive`
(speed, steering, wheel heights, damper command, measured IMU) with the one policy table
``config/integrity.yaml`` and returns the drive with the defects it can work around worked around, plus
one :class:`InputFinding` per defect (interface.md, "JSON outputs", ``input_findings``). A defect that
leaves nothing sound to work on raises :class:`IntegrityError` (a named error, exit 2) naming the file,
topic, time and what was expected. Pure: numpy only, no rclpy.

Kinds and what is done (``action``):

* ``non_finite`` -- NaN/inf samples are dropped (``excluded``); an input left empty is an error.
* ``clock_jump`` -- a stamp step forward longer than ``stamps.clock_jump_s`` or backward longer than
  ``stamps.backward_jump_s``: the samples after it are shifted to close it to one sample period
  (``repaired``).
* ``rate_change`` -- the message rate changes part way (a logger that decimates): the running median of
  ``stamps.rate_window`` stamp intervals departs from the topic's median interval by more than
  ``stamps.rate_factor`` for at least that many intervals; the samples are sound (``kept``), the finding
  says where and from/to which rate. A single hole never moves the running median (that is a ``gap``).
* ``stamp_order`` -- messages stored out of log-time order (short backward steps; the check sees each
  input series in the order the file stores it, :func:`~susp_sim_ros.io.drive.drive_from_recording`): the
  samples are sorted (``repaired``).
* ``duplicate_stamp`` -- two samples with one stamp: the later ones are dropped (``excluded``).
* ``gap`` -- a hole longer than ``stamps.gap_periods`` median periods (and ``stamps.gap_min_s``): the span
  is recorded in ``drive.extra["excluded_spans"]`` for the measured IMU (comparisons leave it out,
  ``excluded``); an input holds its last value over it as the node does (``kept``).
* ``spike`` -- a sample far from the running median (``spikes.mad_factor`` robust sd, at least the
  ``spikes.floor_*`` of its signal): dropped (``excluded``). On the road profile (along the path, per
  track, ``spikes.floor_road_profile``) the sample is dropped and the profile joined linearly over it
  (:meth:`_Checker.road_spikes`).
* ``implausible_unit`` -- speed beyond ``limits.speed_max`` m/s but plausible as km/h, steering beyond
  ``limits.steering_max`` rad but plausible as degrees: an error (a topic map with a factor says the unit).
* ``out_of_range`` -- input samples outside what the node accepts (the one set of limits, ``limits.*`` of
  the policy, which :data:`~susp_sim_ros.io.drive_data.MAX_SPEED` and friends read): a speed below 0 or
  above ``limits.speed_max`` m/s, a steering angle beyond +-``limits.steering_max`` rad, a wheel height
  beyond +-``limits.wheel_height_max`` m (values that are no unit mistake), a damper command outside
  [0, 1]: dropped (``excluded``; the value before them holds, as the node keeps its last value when it
  rejects a message; never replaced by interpolated values); an input left without a sample, or a road
  profile beyond +-``limits.wheel_height_max`` m (one message: nothing left), is an error.
* ``dead_sensor`` -- an IMU axis without noise (sample-to-sample spread below ``noise.*_dead_*``), or
  repeating one value for ``noise.dead_run_s``: the axis is listed in ``drive.extra["unusable_signals"]``
  (``excluded``); consumers that cannot do without it raise :class:`IntegrityError`.
* ``saturated_sensor`` -- an IMU axis stuck at its extreme: ``kept`` and reported; the axis is listed in
  ``drive.extra["saturated_signals"]`` (its peaks are lower than the motion: the discrepancy finder and the
  inspection leave it out of their comparisons, or refuse when it is a signal they cannot do without).
* ``bad_metadata`` -- ``test_drive`` metadata the commands rely on, present but unusable (topic
  ``test_drive``, the whole recording): a ``maneuver`` that mentions a maneuver of the registry
  (:data:`~susp_sim_ros.model.paper.MANEUVER_KINDS`) but does not start with one of its names, so that
  :func:`~susp_sim_ros.model.paper.classify_maneuver` reads it as free text (compared over the whole
  drive; ``kept``), a ``vehicle_state`` that names no vehicle state (ignored, the state comes from
  ``damper_oil_level``; ``kept``); a ``vehicle`` without a parameter set here, reported by the commands that
  take the vehicle from the drive (:func:`drive_vehicle`: the reference car is used; ``kept``); a
  ``damper_oil_level`` that is not four fractions in [0, 1] (nor
  ``unknown``) is an error (every simulation needs the oil levels; :func:`check_oil_metadata`).
* ``missing_topic`` -- a maneuver driven by the road (``maneuvers.needs_road``) without ``/road/profile`` or
  ``/road/wheel_heights``: an error (the model would drive a flat road).
"""
from __future__ import annotations

import math
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TextIO

import numpy as np

from ..errors import ConfigError, RecordingError
from ..model.paper import MANEUVER_KINDS, STATES, classify_maneuver
from ..model.params import DEFAULT_VEHICLE, load_settings, load_vehicle
from ..model.road import RoadProfile
from . import drive_data as _drive

from .drive_data import Series, TestDrive

KINDS = ("non_finite", "gap", "rate_change", "stamp_order", "duplicate_stamp", "clock_jump", "spike",
         "implausible_unit", "out_of_range", "dead_sensor", "saturated_sensor", "missing_topic", "bad_metadata")
ACTIONS = ("excluded", "repaired", "kept")
GYRO_SIGNALS = ("roll_rate", "pitch_rate", "yaw_rate")
ACCEL_SIGNALS = ("accel_x", "accel_y", "accel_z")
NS = 1_000_000_000
#: the MCAP metadata record that describes a drive (interface.md); the ``topic`` of a bad_metadata finding
METADATA_RECORD = "test_drive"
#: what separates the words of a free-text ``maneuver`` (``bump_crossing_8kmh``, ``slow bump``)
_WORD_SEP = re.compile(r"[^a-z0-9]+")


class IntegrityError(RecordingError):
    """A recording whose defects leave nothing sound to work on (names file, topic, time, what was expected)."""


@dataclass(frozen=True)
class InputFinding:
    """One defect of a recording and what was done about it (interface.md ``input_findings`` entry)."""

    file: str
    topic: str
    kind: str
    from_s: float
    to_s: float
    action: str
    detail: str

    def to_json(self) -> dict[str, Any]:
        return {"file": self.file, "topic": self.topic, "kind": self.kind, "from_s": float(self.from_s),
                "to_s": float(self.to_s), "action": self.action, "detail": self.detail}

    def line(self) -> str:
        """The one stderr/report line: ``input: FILE TOPIC KIND FROM-TO s ACTION: DETAIL``."""
        return (f"input: {self.file} {self.topic} {self.kind} {self.from_s:.3f}-{self.to_s:.3f} s "
                f"{self.action}: {self.detail}")


@dataclass
class IntegrityResult:
    """The drive with its defects worked around, the findings, the IMU signals not to be used
    (``dead_sensor``) and those clipped by the sensor range (``saturated_sensor``)."""

    drive: TestDrive
    findings: list[InputFinding] = field(default_factory=list)
    unusable: set[str] = field(default_factory=set)
    saturated: set[str] = field(default_factory=set)


# ---- policy --------------------------------------------------------------------------------------
def load_policy(path: str | Path | None = None) -> dict[str, Any]:
    """The policy table (``config/integrity.yaml`` or ``path``) as ``{"section.key": value}``;
    ConfigError naming the file and entry when malformed."""
    return load_settings("integrity.yaml", path)


# ---- helpers -------------------------------------------------------------------------------------
def _running_median(x: np.ndarray, w: int) -> np.ndarray:
    """Centred running median of ``x`` (1-D) over ``w`` samples (edges: the nearest full window)."""
    n = x.size
    if n < w:
        return np.full(n, float(np.median(x))) if n else x.copy()
    win = np.lib.stride_tricks.sliding_window_view(x, w)
    med = np.median(win, axis=1)
    h = w // 2
    return np.concatenate([np.full(h, med[0]), med, np.full(n - med.size - h, med[-1])])


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """``[(i0, i1), ...]`` inclusive index ranges where ``mask`` is True."""
    m = np.concatenate([[False], mask.astype(bool), [False]])
    d = np.diff(m.astype(np.int8))
    starts, ends = np.nonzero(d == 1)[0], np.nonzero(d == -1)[0] - 1
    return list(zip(starts.tolist(), ends.tolist()))


def _rate_detail(usual_hz: float, here_hz: float, t_a: float, t_b: float, at_start: bool, at_end: bool,
                 w: int) -> str:
    """The detail of a ``rate_change`` finding: where the rate changes, from and to which rate."""
    if at_start and at_end:
        where = f"{here_hz:.4g} Hz throughout"
    elif at_start:
        where = f"the rate changes from {here_hz:.4g} Hz to {usual_hz:.4g} Hz at {t_b:.3f} s"
    elif at_end:
        where = f"the rate changes from {usual_hz:.4g} Hz to {here_hz:.4g} Hz at {t_a:.3f} s"
    else:
        where = (f"the rate changes from {usual_hz:.4g} Hz to {here_hz:.4g} Hz at {t_a:.3f} s and back to "
                 f"{usual_hz:.4g} Hz at {t_b:.3f} s")
    return (f"{where} (median stamp interval over {w} messages); the samples are used as recorded, at the "
            f"rate they have")


def _mentions(text: str) -> list[str]:
    """The maneuvers of the registry a free-text ``maneuver`` names anywhere (a full name, or an alias as
    a word)."""
    t = text.strip().lower()
    words = set(_WORD_SEP.split(t))
    return [k.name for k in MANEUVER_KINDS.values() if k.name in t or words & set(k.aliases)]


def check_oil_metadata(metadata: dict[str, Any], file: str | Path) -> None:
    """IntegrityError (``bad_metadata``) when the ``damper_oil_level`` metadata is present, not ``unknown``,
    and not four comma-separated fractions in [0, 1]: every simulation of the drive needs the oil levels,
    and guessing them would compare against the wrong vehicle state."""
    text = metadata.get("damper_oil_level")
    if text is None or _drive.oil_unknown(text):
        return
    try:
        _drive.parse_oil(text)
    except RecordingError:
        raise IntegrityError(f"{file}: {METADATA_RECORD} metadata damper_oil_level: bad_metadata: expected four "
                             f"comma-separated fractions FL,FR,RL,RR in [0, 1] (or 'unknown'), got {text!r}"
                             ) from None


def unknown_vehicle(metadata: dict[str, Any]) -> str | None:
    """Why the ``vehicle`` metadata of a drive names no vehicle parameter set that loads (a name in
    ``config/vehicles/`` or a YAML path), or None when it does or names none (``bad_metadata``)."""
    name = str(metadata.get("vehicle") or "").strip()
    if not name:
        return None
    try:
        load_vehicle(name)
    except ConfigError as exc:  # an unknown name, a missing or malformed file
        return str(exc)
    return None


def drive_vehicle(drive: TestDrive, file: str | Path) -> str:
    """The vehicle parameter set a command that takes the vehicle from the drive uses (validate, the
    validation study): its ``vehicle`` metadata when that loads, else the reference car
    (:data:`~susp_sim_ros.model.params.DEFAULT_VEHICLE`), said so as a ``bad_metadata`` finding (kept) on
    stderr, in the command's findings and in ``drive.extra["input_findings"]``. Only such a command reports
    it: where the vehicle comes from the command line (``diagnose --vehicle``, ``sim --config``) the
    drive's name for its car changes nothing, and a drive of another car is no damaged drive."""
    meta = drive.metadata
    why = unknown_vehicle(meta)
    if why is None:
        name = str(meta.get("vehicle") or "").strip()
        return name or DEFAULT_VEHICLE
    f = InputFinding(str(file), METADATA_RECORD, "bad_metadata", 0.0, drive.duration_s, "kept",
                     f"vehicle {str(meta.get('vehicle')).strip()!r} has no parameter set here ({why}); the "
                     f"reference car {DEFAULT_VEHICLE} is used where the vehicle is taken from the drive")
    found = drive.extra.setdefault("input_findings", [])
    if f.to_json() not in found:
        found.append(f.to_json())
    report([f])
    return DEFAULT_VEHICLE


class _Checker:
    def __init__(self, drive: TestDrive, file: str, policy: dict[str, Any]):
        self.drive, self.file, self.pol = drive, file, policy
        starts = [int(s.t_ns[0]) for s in self._all_series() if s is not None and len(s)]
        self.t0 = min(starts) if starts else 0
        self.findings: list[InputFinding] = []

    def _all_series(self) -> list:
        d = self.drive
        return [d.speed, d.steering, d.wheel_heights, d.damper_command, d.imu]

    def s(self, t_ns: int) -> float:
        return (int(t_ns) - self.t0) / NS

    def add(self, topic: str, kind: str, t_a: int, t_b: int, action: str, detail: str) -> None:
        self.findings.append(InputFinding(self.file, topic, kind, round(self.s(t_a), 6), round(self.s(t_b), 6),
                                          action, detail))

    def fail(self, topic: str, t_a: int, t_b: int, what: str) -> IntegrityError:
        return IntegrityError(f"{self.file}: topic {topic}: {what} (log time {self.s(t_a):.3f}-"
                              f"{self.s(t_b):.3f} s from the recording's first message)")

    # -- stamps ----------------------------------------------------------------------------------------
    def stamps(self, topic: str, t: np.ndarray, v: np.ndarray, *, is_input: bool
               ) -> tuple[np.ndarray, np.ndarray, list[tuple[int, int]]]:
        """Non-finite samples, clock jumps, order, duplicates and gaps of one series."""
        if t.size:
            bad = ~np.isfinite(v.reshape(t.size, -1)).all(axis=1)
            if bad.any():
                for i0, i1 in _runs(bad):
                    self.add(topic, "non_finite", int(t[i0]), int(t[i1]), "excluded",
                             f"{i1 - i0 + 1} sample(s) with NaN or inf dropped")
                if bad.all():  # the span of the samples (log time 0 would read as before the recording)
                    raise self.fail(topic, int(t.min()), int(t.max()),
                                    f"non_finite: every one of its {t.size} sample(s) is NaN or inf; expected "
                                    f"finite values")
                t, v = t[~bad], v[~bad]
        if t.size < 3:
            return t, v, []
        dt = np.diff(t)
        pos = dt[dt > 0]
        period = int(np.median(pos)) if pos.size else 0
        jump_fwd = int(float(self.pol["stamps.clock_jump_s"]) * NS)
        jump_back = int(float(self.pol["stamps.backward_jump_s"]) * NS)
        jumps = np.nonzero((dt > jump_fwd) | (dt < -jump_back))[0]
        if jumps.size and period > 0:
            t = t.copy()
            for k in jumps.tolist():
                step = int(t[k + 1] - t[k])
                t[k + 1:] -= step - period
                self.add(topic, "clock_jump", int(t[k]), int(t[k + 1]), "repaired",
                         f"log time jumps by {step / NS:+.3f} s after {k + 1} samples; later samples shifted "
                         f"to close it to one sample period ({period / NS * 1e3:.2f} ms)")
            dt = np.diff(t)
        if (dt < 0).any():
            back = np.nonzero(dt < 0)[0]
            order = np.argsort(t, kind="stable")
            self.add(topic, "stamp_order", int(t[back + 1].min()), int(t[back].max()), "repaired",
                     f"{back.size} sample(s) stored out of log-time order; sorted by log time")
            t, v = t[order], v[order]
            dt = np.diff(t)
        if (dt == 0).any():
            dup = np.concatenate([[False], dt == 0])
            self.add(topic, "duplicate_stamp", int(t[np.nonzero(dup)[0][0]]), int(t[np.nonzero(dup)[0][-1]]),
                     "excluded", f"{int(dup.sum())} sample(s) repeat the log time of the one before; dropped")
            t, v = t[~dup], v[~dup]
            dt = np.diff(t)
        spans: list[tuple[int, int]] = []
        if t.size >= 3 and period > 0:
            lim = max(float(self.pol["stamps.gap_periods"]) * period, float(self.pol["stamps.gap_min_s"]) * NS)
            for k in np.nonzero(dt > lim)[0].tolist():
                spans.append((int(t[k]), int(t[k + 1])))
                self.add(topic, "gap", int(t[k]), int(t[k + 1]), "kept" if is_input else "excluded",
                         f"no sample for {dt[k] / NS:.3f} s (median period {period / NS * 1e3:.2f} ms); "
                         + ("the last value is held over it" if is_input
                            else "left out of comparisons, not interpolated across"))
            self.rate_change(topic, t)
        return t, v, spans

    def rate_change(self, topic: str, t: np.ndarray) -> None:
        """``rate_change`` findings of one series (stamps sorted, without duplicates): each run of at least
        ``stamps.rate_window`` intervals whose running median departs from the topic's median interval by
        more than ``stamps.rate_factor``. The running median ignores a single hole (a ``gap``)."""
        w = int(self.pol["stamps.rate_window"])
        dt = np.diff(t).astype(float)
        if dt.size < 2 * w:
            return
        factor = float(self.pol["stamps.rate_factor"])
        level = _running_median(dt, w)
        base = float(np.median(dt))
        off = (level > factor * base) | (level < base / factor)
        usual = float(np.median(dt[~off])) if (~off).any() else base
        for i0, i1 in _runs(off):
            if i1 - i0 + 1 >= w:
                self.add(topic, "rate_change", int(t[i0]), int(t[i1 + 1]), "kept",
                         _rate_detail(NS / usual, NS / float(np.median(dt[i0:i1 + 1])), self.s(t[i0]),
                                      self.s(t[i1 + 1]), i0 == 0, i1 + 1 == dt.size, w))

    # -- spikes and units ----------------------------------------------------------------------------
    def spikes(self, topic: str, t: np.ndarray, v: np.ndarray, floor: float, unit: str
               ) -> tuple[np.ndarray, np.ndarray]:
        w = int(self.pol["spikes.window"])
        if t.size < w:
            return t, v
        vv = v.reshape(t.size, -1)
        bad = np.zeros(t.size, bool)
        for j in range(vv.shape[1]):
            x = vv[:, j]
            r = x - _running_median(x, w)
            sd = 1.4826 * float(np.median(np.abs(r - np.median(r))))
            bad |= np.abs(r) > max(float(self.pol["spikes.mad_factor"]) * sd, floor)
        if bad.any() and bad.mean() < 0.05:  # more than 5 % is not a spike but the signal (unit check)
            for i0, i1 in _runs(bad):
                peak = float(np.max(np.abs(vv[i0:i1 + 1])))
                self.add(topic, "spike", int(t[i0]), int(t[i1]), "excluded",
                         f"{i1 - i0 + 1} sample(s) up to {peak:.4g} {unit} far from the running median "
                         f"(beyond {floor:g} {unit} and {self.pol['spikes.mad_factor']:g} robust sd); dropped")
            t, v = t[~bad], v[~bad]
        return t, v

    def units(self, topic: str, t: np.ndarray, v: np.ndarray, limit: float, factor: float, unit: str,
              other: str, recorded: np.ndarray) -> None:
        """``implausible_unit`` (an error) when the samples ``v`` (at log times ``t``, spikes dropped) exceed
        ``limit`` [``unit``] but ``factor`` times them fit (the ``other`` unit); the error names the whole
        topic, ``recorded`` (its log times as recorded: the spike check may drop edge samples of a signal
        recorded in the wrong unit). Values beyond ``limit`` that are no unit mistake are left to
        :meth:`in_range` (``out_of_range``)."""
        if not t.size:
            return
        peak = float(np.max(np.abs(v)))
        if peak > limit:
            k = int(np.argmax(np.abs(v)))
            if peak * factor <= limit:
                raise self.fail(topic, int(recorded.min()), int(recorded.max()),
                                f"implausible_unit: values up to {peak:.4g} {unit} (at {self.s(t[k]):.3f} s) exceed "
                                f"the plausible {limit:g} {unit} but fit {other}; expected {unit} (give a topic "
                                f"map with the unit factor, --topic-map)")

    def in_range(self, topic: str, s: Series | None, lo: float, hi: float, unit: str, limit: str
                 ) -> Series | None:
        """``out_of_range``: the samples of input ``s`` (sorted, checked) with a value outside [``lo``, ``hi``]
        [``unit``] (what the node accepts; ``limit`` names the policy entry) dropped, one finding per run of
        them; IntegrityError when no sample is left."""
        if s is None or not len(s):
            return s
        t = s.t_ns
        v = s.values.reshape(len(s), -1)
        bad = np.asarray(((v < lo) | (v > hi)).any(axis=1), dtype=bool)
        if not bad.any():
            return s
        if bad.all():
            raise self.fail(topic, int(t.min()), int(t.max()),
                            f"out_of_range: every one of its {t.size} sample(s) is outside [{lo:.4g}, {hi:.4g}] {unit} "
                            f"({limit}); expected values the node accepts, within [{lo:.4g}, {hi:.4g}] {unit}")
        for i0, i1 in _runs(bad):
            seg = v[i0:i1 + 1]
            self.add(topic, "out_of_range", int(t[i0]), int(t[i1]), "excluded",
                     f"{i1 - i0 + 1} sample(s) outside [{lo:.4g}, {hi:.4g}] {unit} ({limit}; values from "
                     f"{float(seg.min()):.4g} to {float(seg.max()):.4g} {unit}); dropped as the node rejects them "
                     f"(the value before them holds), not interpolated")
        return _drive.Series(t[~bad], s.values[~bad])

    # -- IMU noise -----------------------------------------------------------------------------------
    def imu_noise(self, topic: str, t: np.ndarray, gyro: np.ndarray, accel: np.ndarray
                  ) -> tuple[set[str], set[str]]:
        """``dead_sensor`` and ``saturated_sensor`` findings of the IMU (gyro [rad/s], accel [m/s^2] at log
        times ``t`` [ns]); the names of the dead and of the saturated signals."""
        unusable: set[str] = set()
        saturated: set[str] = set()
        if t.size < 10:
            return unusable, saturated
        period = float(np.median(np.diff(t))) / NS
        run_n = max(int(math.ceil(float(self.pol["noise.dead_run_s"]) / max(period, 1e-9))), 10)
        for names, data, floor, unit in ((GYRO_SIGNALS, gyro, float(self.pol["noise.gyro_dead_rad_s"]), "rad/s"),
                                         (ACCEL_SIGNALS, accel, float(self.pol["noise.accel_dead_m_s2"]), "m/s^2")):
            for j, name in enumerate(names):
                x = data[:, j]
                spread = float(np.std(np.diff(x)))
                if spread < floor:
                    unusable.add(name)
                    self.add(topic, "dead_sensor", int(t[0]), int(t[-1]), "excluded",
                             f"{name} shows no noise (sample-to-sample spread {spread:.3g} {unit}, a live sensor "
                             f"shows more than {floor:g} {unit}; value {float(np.median(x)):.4g} {unit}); "
                             f"not used as a measurement")
                    continue
                same = np.concatenate([[False], np.diff(x) == 0])
                for i0, i1 in _runs(same):
                    if i1 - i0 + 2 >= run_n:
                        unusable.add(name)
                        self.add(topic, "dead_sensor", int(t[i0 - 1]), int(t[i1]), "excluded",
                                 f"{name} repeats {float(x[i0]):.4g} {unit} for {i1 - i0 + 2} samples; "
                                 f"not used as a measurement")
                ext = float(np.max(np.abs(x)))
                at = np.abs(np.abs(x) - ext) <= 1e-9 * max(ext, 1.0)
                if ext > 0 and at.mean() >= float(self.pol["noise.saturated_fraction"]) and at.sum() >= run_n:
                    i = np.nonzero(at)[0]
                    saturated.add(name)
                    self.add(topic, "saturated_sensor", int(t[i[0]]), int(t[i[-1]]), "kept",
                             f"{name} sits at {float(x[i[0]]):.4g} {unit} for {int(at.sum())} samples: clipped "
                             f"by the sensor range, peaks there are lower than the motion; left out of the "
                             f"discrepancy finder's and the inspection's comparisons")
        return unusable, saturated

    # -- the drive -----------------------------------------------------------------------------------
    def run(self) -> IntegrityResult:
        DAMPER_COMMAND, IMU, ROAD_PROFILE = _drive.DAMPER_COMMAND, _drive.IMU, _drive.ROAD_PROFILE
        SPEED, STEERING, WHEEL_HEIGHTS = _drive.SPEED, _drive.STEERING, _drive.WHEEL_HEIGHTS
        d, pol = self.drive, self.pol
        names = d.extra.get("input_topics", {})
        excluded: dict[str, list[tuple[int, int]]] = {}

        def scalar(key: str, default: str, s: Series | None, floor_key: str | None, unit: str) -> Series | None:
            if s is None or not len(s):
                return s
            topic = names.get(key, default)
            t, v, _ = self.stamps(topic, s.t_ns, s.values, is_input=True)
            if floor_key is not None:
                t, v = self.spikes(topic, t, v, float(pol[floor_key]), unit)
            return _drive.Series(t, v)

        speed = scalar("speed", SPEED, d.speed, "spikes.floor_speed", "m/s")
        steering = scalar("steering", STEERING, d.steering, "spikes.floor_steering", "rad")
        assert speed is not None and steering is not None
        self.units(names.get("speed", SPEED), speed.t_ns, speed.values, float(pol["limits.speed_max"]),
                   1.0 / 3.6, "m/s", "km/h", d.speed.t_ns)
        self.units(names.get("steering", STEERING), steering.t_ns, steering.values, float(pol["limits.steering_max"]),
                   math.pi / 180.0, "rad", "degrees", d.steering.t_ns)
        speed_max, steer_max = float(pol["limits.speed_max"]), float(pol["limits.steering_max"])
        wh_max = float(pol["limits.wheel_height_max"])
        speed = self.in_range(names.get("speed", SPEED), speed, 0.0, speed_max, "m/s", "limits.speed_max")
        steering = self.in_range(names.get("steering", STEERING), steering, -steer_max, steer_max, "rad",
                                 "limits.steering_max")
        assert speed is not None and steering is not None
        wh = scalar("wheel_heights", WHEEL_HEIGHTS, d.wheel_heights, "spikes.floor_wheel_heights", "m")
        wh = self.in_range(names.get("wheel_heights", WHEEL_HEIGHTS), wh, -wh_max, wh_max, "m",
                           "limits.wheel_height_max")
        cmd = scalar("damper_command", DAMPER_COMMAND, d.damper_command, None, "1")
        lo, hi = _drive.DAMPER_COMMAND_RANGE
        cmd = self.in_range(names.get("damper_command", DAMPER_COMMAND), cmd, lo, hi, "1",
                            "the valve command range of interface.md")
        self.road_range(names.get("road_profile", ROAD_PROFILE), wh_max)
        road = self.road_spikes(names.get("road_profile", ROAD_PROFILE))
        imu = d.imu
        unusable: set[str] = set()
        saturated: set[str] = set()
        if imu is not None and len(imu):
            topic = names.get("imu", IMU)
            t, v, gaps = self.stamps(topic, imu.t_ns, np.hstack([imu.gyro, imu.accel]), is_input=False)
            if gaps:
                excluded[topic] = gaps
            t, v = self._imu_spikes(topic, t, v)
            imu = _drive.ImuSeries(t, v[:, :3], v[:, 3:])
            unusable, saturated = self.imu_noise(topic, imu.t_ns, imu.gyro, imu.accel)
        self.metadata()
        maneuver = str(d.metadata.get("maneuver", ""))
        needs = [w for w in pol["maneuvers.needs_road"] if str(w).lower() in maneuver.lower()]
        if needs and d.road is None and (wh is None or not len(wh)):
            rp = names.get("road_profile", ROAD_PROFILE)
            self.add(rp, "missing_topic", self.t0, d.t_end_ns, "kept", f"maneuver {maneuver!r} needs the road")
            raise self.fail(rp, self.t0, d.t_end_ns,
                            f"missing_topic: maneuver {maneuver!r} is driven by the road but the recording has no "
                            f"{rp} (nor {names.get('wheel_heights', WHEEL_HEIGHTS)}); expected the road profile "
                            f"(without it the model would drive a flat road)")
        extra = dict(d.extra)
        extra["input_findings"] = [f.to_json() for f in self.findings]
        extra["excluded_spans"] = excluded
        extra["unusable_signals"] = sorted(unusable)
        extra["saturated_signals"] = sorted(saturated)
        out = _drive.TestDrive(d.metadata, speed, steering, road, wh, imu, extra, damper_command=cmd)
        return IntegrityResult(out, list(self.findings), unusable, saturated)

    def road_range(self, topic: str, limit_m: float) -> None:
        """``out_of_range`` (an error: the road profile is one message, nothing is left without it): an
        elevation of the road profile beyond +-``limit_m`` [m] (``limits.wheel_height_max``)."""
        road = self.drive.road
        if road is None or not len(road):
            return
        z = np.concatenate([np.abs(road.zl), np.abs(road.zr)])
        if not np.all(np.isfinite(z)) or float(z.max()) <= limit_m:
            return
        raise self.fail(topic, self.t0, self.t0,
                        f"out_of_range: road elevation up to {float(z.max()):.4g} m beyond +-{limit_m:g} m "
                        f"(limits.wheel_height_max); expected a road the node accepts")

    def road_spikes(self, topic: str) -> RoadProfile | None:
        """``spike`` (``excluded``): road-profile samples far from the running median along the path (over
        ``spikes.window`` samples, beyond ``spikes.mad_factor`` robust sd of the residual and at least
        ``spikes.floor_road_profile`` m) in either track. The sample (its ``s`` and both tracks) is dropped:
        the profile is joined linearly over it, as the model joins any two neighbouring samples. A smooth
        bump follows the running median and gives none. More than 5 % of the samples that far off are the
        road, not spikes (kept as recorded)."""
        road = self.drive.road
        w = int(self.pol["spikes.window"])
        if road is None or len(road.s) < w:
            return road
        floor = float(self.pol["spikes.floor_road_profile"])
        factor = float(self.pol["spikes.mad_factor"])
        bad = np.zeros(len(road.s), bool)
        for z in (road.zl, road.zr):
            r = z - _running_median(z, w)
            sd = 1.4826 * float(np.median(np.abs(r - np.median(r))))
            bad |= np.abs(r) > max(factor * sd, floor)
        if not bad.any() or bad.mean() >= 0.05:
            return road
        for i0, i1 in _runs(bad):
            peak = float(np.max(np.abs(np.concatenate([road.zl[i0:i1 + 1], road.zr[i0:i1 + 1]]))))
            self.add(topic, "spike", self.t0, self.t0, "excluded",
                     f"{i1 - i0 + 1} road sample(s) at s = {road.s[i0]:.4g}-{road.s[i1]:.4g} m up to {peak:.4g} m "
                     f"far from the running median along the path (beyond {floor:g} m and {factor:g} robust sd); "
                     f"dropped, the profile joined linearly over it")
        return RoadProfile(road.s[~bad], road.zl[~bad], road.zr[~bad])

    # -- metadata ------------------------------------------------------------------------------------
    def metadata(self) -> None:
        """``bad_metadata`` findings: the ``test_drive`` fields the commands read, present but unusable."""
        meta, t_end = self.drive.metadata, self.drive.t_end_ns
        check_oil_metadata(meta, self.file)
        maneuver = str(meta.get("maneuver", ""))
        named = _mentions(maneuver)
        if named and classify_maneuver(maneuver) is None:
            known = ", ".join(n for k in MANEUVER_KINDS.values() for n in k.names)
            self.add(METADATA_RECORD, "bad_metadata", self.t0, t_end, "kept",
                     f"maneuver {maneuver!r} mentions {' and '.join(named)} but does not start with a maneuver "
                     f"name (expected one of {known} at the start); read as free text: compared over the whole "
                     f"drive, not the maneuver's window")
        state = meta.get("vehicle_state")
        if state is not None and str(state).strip() and str(state).strip() not in STATES:
            self.add(METADATA_RECORD, "bad_metadata", self.t0, t_end, "kept",
                     f"vehicle_state {state!r} is no vehicle state (expected one of {', '.join(STATES)}); "
                     f"ignored: the damper state is taken from damper_oil_level")

    def _imu_spikes(self, topic: str, t: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        w = int(self.pol["spikes.window"])
        if t.size < w:
            return t, v
        floors = [float(self.pol["spikes.floor_gyro"])] * 3 + [float(self.pol["spikes.floor_accel"])] * 3
        bad = np.zeros(t.size, bool)
        for j in range(6):
            x = v[:, j]
            r = x - _running_median(x, w)
            sd = 1.4826 * float(np.median(np.abs(r - np.median(r))))
            bad |= np.abs(r) > max(float(self.pol["spikes.mad_factor"]) * sd, floors[j])
        if bad.any() and bad.mean() < 0.05:
            for i0, i1 in _runs(bad):
                self.add(topic, "spike", int(t[i0]), int(t[i1]), "excluded",
                         f"{i1 - i0 + 1} IMU sample(s) far from the running median (beyond "
                         f"{self.pol['spikes.mad_factor']:g} robust sd and {floors[0]:g} rad/s / {floors[3]:g} "
                         f"m/s^2); dropped")
            t, v = t[~bad], v[~bad]
        return t, v


def check_drive_integrity(drive: TestDrive, file: str | Path, policy: dict[str, Any] | None = None
                          ) -> IntegrityResult:
    """The drive with its defects worked around and one finding per defect; IntegrityError when nothing
    sound is left (see the module docstring for each kind and its action)."""
    return _Checker(drive, str(file), policy if policy is not None else load_policy()).run()


def require_live_imu(drive: TestDrive, file: str | Path, what: str, signals: tuple[str, ...] = GYRO_SIGNALS,
                     need: str = "a live gyro on every axis", *, saturated: bool = False,
                     verb: str = "needs") -> None:
    """IntegrityError when ``what`` (a command that uses the measured IMU, and ``verb`` -- "needs", or
    "need" after a plural ``what`` -- ``need``) would use one of ``signals`` the check found dead
    (``drive.extra["unusable_signals"]``) or, with ``saturated``, clipped by the sensor range
    (``drive.extra["saturated_signals"]``); the message names each kind and says where (its findings, log
    time from the recording's first message)."""
    dead = [s for s in signals if s in drive.extra.get("unusable_signals", ())]
    clipped = [s for s in signals if saturated and s not in dead and s in drive.extra.get("saturated_signals", ())]
    if not dead and not clipped:
        return
    topic = drive.extra.get("input_topics", {}).get("imu", "/imu/data")
    parts, expected = [], []
    if dead:
        parts.append("dead_sensor " + ", ".join(f"{s} {_dead_span(drive, s)}" for s in dead))
        expected.append("noise above the policy floor")
    if clipped:
        parts.append("saturated_sensor " + ", ".join(f"{s} {_dead_span(drive, s, 'saturated_sensor')}"
                                                     for s in clipped))
        expected.append("an axis within its sensor range")
    raise IntegrityError(f"{file}: topic {topic}: {'; '.join(parts)} (log time from the recording's first "
                         f"message): {what} {verb} {need} (expected {' and '.join(expected)}); nothing sound to "
                         f"work on")


def _dead_span(drive: TestDrive, signal: str, kind: str = "dead_sensor") -> str:
    """``FROM-TO s`` of the ``kind`` findings of ``signal`` (the whole IMU record without one)."""
    spans = [(float(f["from_s"]), float(f["to_s"])) for f in drive.extra.get("input_findings", ())
             if f.get("kind") == kind and str(f.get("detail", "")).split(" ", 1)[0] == signal]
    if not spans and drive.imu is not None and len(drive.imu):
        starts = [int(x.t_ns[0]) for x in (drive.speed, drive.steering, drive.wheel_heights,
                                           drive.damper_command, drive.imu) if x is not None and len(x)]
        spans = [((int(drive.imu.t_ns[0]) - min(starts)) / NS, (int(drive.imu.t_ns[-1]) - min(starts)) / NS)]
    if not spans:
        return "(no samples)"
    return ", ".join(f"{a:.3f}-{b:.3f} s" for a, b in spans)


# ---- reporting -----------------------------------------------------------------------------------
_COLLECTED: list[dict[str, Any]] = []
_SEEN: set[tuple] = set()


def start_collection() -> None:
    """Forget the findings reported so far (the CLI calls this before each command)."""
    _COLLECTED.clear()
    _SEEN.clear()


def report(findings: list[InputFinding], stream: TextIO | None = None) -> None:
    """One line per finding on stderr (each once per collection) and keep it for :func:`collected`."""
    out = stream if stream is not None else sys.stderr
    for f in findings:
        key = tuple(f.to_json().values())
        if key in _SEEN:
            continue
        _SEEN.add(key)
        _COLLECTED.append(f.to_json())
        print(f.line(), file=out)


def collected() -> list[dict[str, Any]]:
    """The findings reported since :func:`start_collection` (``input_findings`` of the command's JSON)."""
    return [dict(f) for f in _COLLECTED]


def append_to_report(path: str | Path) -> None:
    """Append the ``## Input findings`` section (the findings collected so far) to a Markdown report."""
    text = markdown(collected())
    if text:
        with open(path, "a", encoding="utf-8") as fh:
            fh.write(text)


def markdown(findings: list[dict[str, Any]]) -> str:
    """The ``## Input findings`` section of a Markdown report (empty text when there are none)."""
    if not findings:
        return ""
    lines = ["", "## Input findings", ""]
    lines += [f"- {InputFinding(**f).line()}" for f in findings]
    return "\n".join(lines) + "\n"
