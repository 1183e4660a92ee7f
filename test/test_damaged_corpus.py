"""Damaged-input corpus (issue 28): every kind of damage, alone and two at a time, through every command.

Copies of two bundled drives (the rear-empty bump crossing and the intact sine steer), shortened to their
first :data:`CUT_S` seconds to keep the run short, are damaged in each way the integrity check knows
(``susp_sim_ros/io/integrity.py``) and fed to every command that reads a recording: ``sim --drive``,
``validate --measured``, ``diagnose`` (``--dry-run`` for the corpus, one real fit), ``inspect`` and
``replay --dry-run``. Whatever the damage, a command

* exits 0 or 2 (a named error), never 1 or with a traceback;
* when it exits 0, lists in its ``--json`` ``input_findings`` a finding of each kind of damage done (no
  silent run) and says so on stderr; when it exits 2, names the damage, the file and (one damage alone)
  where, on stderr;
* prints no NaN or infinity in its JSON;
* reports an excluded span (an IMU gap, a dead gyro span, dropped non-finite samples) where the drive was
  damaged (log time from the recording's first message).

Each damage works in its own lane (its own part of the drive, of a topic or of the IMU's axes), so that two
of them never hide one another. A damage no command reports yet is listed in :data:`KNOWN_SILENT` (its
case a strict expected failure, left out of the pairs).
"""
from __future__ import annotations

import dataclasses
import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from _cli_helpers import run_cli
from susp_sim_ros.io.drive import (IMU, ROAD_PROFILE, SPEED, STEERING, ImuSeries, Series, TestDrive,
                                   drive_messages, read_drive, write_drive)
from susp_sim_ros.io.integrity import KINDS
from susp_sim_ros.io.recorder import McapRecorder

BAGS = Path(__file__).resolve().parents[1] / "bags"
SOURCES = {"bump": BAGS / "bump_crossing_rear_empty.mcap", "sine": BAGS / "sine_steer_intact.mcap"}
CUT_S = 4.0  # s of each drive kept: the bump crossing's bump and ring-out, the sine steer's first 3 s of steering
NS = 1_000_000_000
JUMP_NS = 1000 * NS  # the clock jump of the corpus
COMMANDS = ("sim", "validate", "diagnose", "inspect", "replay")


# ---- the damage -------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Span:
    """Where a finding must be: ``kind`` on ``topic`` from ``t_a`` to ``t_b`` (log time, ns)."""

    kind: str
    topic: str
    t_a: int
    t_b: int
    tol_s: float = 2e-6  # findings are rounded to 1 us

    def after_jump(self, at: int) -> Span:
        """The span as the check reports it once it has closed an IMU clock jump after log time ``at`` (ns):
        times recorded 1000 s late are back in place, within the stamp jitter (50 us)."""
        if self.topic != IMU or self.t_b <= at:
            return self
        back = [t - JUMP_NS if t > at + JUMP_NS // 2 else t for t in (self.t_a, self.t_b)]
        return dataclasses.replace(self, t_a=back[0], t_b=back[1], tol_s=2e-4)


@dataclass(frozen=True)
class Damage:
    """One way to damage a drive: the kind the check must report, whether it leaves nothing sound
    (``error``: exit 2 everywhere) and the commands that refuse it though the check works around it."""

    kind: str
    apply: Callable[[TestDrive, float], tuple[TestDrive, list[Span]]]
    drives: tuple[str, ...] = ("bump", "sine")
    error: bool = False
    refused_by: tuple[str, ...] = ()
    as_listed: bool = False  # written in the order the series list its samples, not sorted by log time


def _at(s: Series | ImuSeries, lo: float, hi: float, where: float) -> int:
    """The sample index at fraction ``lo + where * (hi - lo)`` of a series (``where`` in [0, 1])."""
    return int((lo + where * (hi - lo)) * (len(s) - 1))


def _imu(d: TestDrive, t_ns, gyro, accel) -> TestDrive:
    return dataclasses.replace(d, imu=ImuSeries(t_ns, gyro, accel))


def non_finite(d: TestDrive, where: float) -> tuple[TestDrive, list[Span]]:
    """Three NaN/inf samples of the lateral acceleration in 5-15 % of the IMU record: dropped."""
    imu = d.imu
    k = _at(imu, 0.05, 0.15, where)
    a = imu.accel.copy()
    a[k:k + 3, 1] = [np.nan, np.inf, -np.inf]
    return _imu(d, imu.t_ns, imu.gyro, a), [Span("non_finite", IMU, int(imu.t_ns[k]), int(imu.t_ns[k + 2]))]


def non_finite_all(d: TestDrive, where: float) -> tuple[TestDrive, list[Span]]:
    """Every lateral acceleration sample NaN: nothing sound left of the IMU."""
    a = d.imu.accel.copy()
    a[:, 1] = np.nan
    return _imu(d, d.imu.t_ns, d.imu.gyro, a), [Span("non_finite", IMU, int(d.imu.t_ns[0]), int(d.imu.t_ns[-1]))]


def gap(d: TestDrive, where: float) -> tuple[TestDrive, list[Span]]:
    """No IMU message for 0.4 s from 15-25 % of the record: left out, never interpolated across."""
    imu = d.imu
    k = _at(imu, 0.15, 0.25, where)
    keep = (imu.t_ns <= imu.t_ns[k]) | (imu.t_ns > imu.t_ns[k] + int(0.4 * NS))
    after = int(imu.t_ns[keep][np.searchsorted(imu.t_ns[keep], imu.t_ns[k], side="right")])
    return (_imu(d, imu.t_ns[keep], imu.gyro[keep], imu.accel[keep]),
            [Span("gap", IMU, int(imu.t_ns[k]), after)])


def clock_jump(d: TestDrive, where: float) -> tuple[TestDrive, list[Span]]:
    """The IMU clock steps 1000 s forward at 40-45 % of the record: repaired (closed to one period)."""
    imu = d.imu
    k = _at(imu, 0.40, 0.45, where)
    t = imu.t_ns.copy()
    t[k + 1:] += JUMP_NS
    period = int(np.median(np.diff(imu.t_ns)))
    return _imu(d, t, imu.gyro, imu.accel), [Span("clock_jump", IMU, int(t[k]), int(t[k]) + period, 2e-4)]


def stamp_order(d: TestDrive, where: float) -> tuple[TestDrive, list[Span]]:
    """Two speed messages out of log-time order at 30-40 % of the drive (the file holds them in the order
    listed, see :func:`_write_as_listed`): sorted."""
    t, v = d.speed.t_ns.copy(), d.speed.values.copy()
    k = _at(d.speed, 0.30, 0.40, where)
    t[k], t[k + 1] = t[k + 1], t[k]
    v[k], v[k + 1] = v[k + 1], v[k]
    return dataclasses.replace(d, speed=Series(t, v)), []


def duplicate_stamp(d: TestDrive, where: float) -> tuple[TestDrive, list[Span]]:
    """A steering message with the log time of the one before at 30-40 % of the drive: dropped."""
    t = d.steering.t_ns.copy()
    k = _at(d.steering, 0.30, 0.40, where)
    t[k] = t[k - 1]
    return dataclasses.replace(d, steering=Series(t, d.steering.values)), []


def rate_change(d: TestDrive, where: float) -> tuple[TestDrive, list[Span]]:
    """The steering logger decimates to a fifth for 1.6 s from 45-50 % of the drive: kept."""
    s = d.steering
    i_a = _at(s, 0.45, 0.50, where)
    i_b = i_a + 160
    keep = np.r_[np.arange(i_a), np.arange(i_a, i_b, 5), np.arange(i_b, len(s))]
    return dataclasses.replace(d, steering=Series(s.t_ns[keep], s.values[keep])), []


def spike(d: TestDrive, where: float) -> tuple[TestDrive, list[Span]]:
    """One speed sample 50 m/s too high at 60-70 % of the drive: dropped."""
    v = d.speed.values.copy()
    k = _at(d.speed, 0.60, 0.70, where)
    v[k] += 50.0
    return dataclasses.replace(d, speed=Series(d.speed.t_ns, v)), [
        Span("spike", "/vehicle/speed", int(d.speed.t_ns[k]), int(d.speed.t_ns[k]))]


def road_spike(d: TestDrive, where: float) -> tuple[TestDrive, list[Span]]:
    """One road-profile sample 0.5 m up at 20-80 % of the profile (the bump crossing's): dropped, the
    profile joined over it (the road is one message: the finding is at the recording's first message)."""
    from susp_sim_ros.model.road import RoadProfile
    r = d.road
    k = int((0.2 + 0.6 * where) * (len(r.s) - 1))
    zl = r.zl.copy()
    zl[k] += 0.5
    return dataclasses.replace(d, road=RoadProfile(r.s, zl, r.zr)), [Span("spike", ROAD_PROFILE, _t0(d), _t0(d))]


def out_of_range(d: TestDrive, where: float) -> tuple[TestDrive, list[Span]]:
    """Twenty speed messages (0.2 s) at -0.5 m/s, a speed the node rejects, at 75-85 % of the drive: dropped."""
    v = d.speed.values.copy()
    k = _at(d.speed, 0.75, 0.85, where)
    v[k:k + 20] = -0.5
    return dataclasses.replace(d, speed=Series(d.speed.t_ns, v)), [
        Span("out_of_range", SPEED, int(d.speed.t_ns[k]), int(d.speed.t_ns[k + 19]))]


def dead_sensor(d: TestDrive, where: float) -> tuple[TestDrive, list[Span]]:
    """The roll gyro freezes at 55-65 % of the IMU record until its end (over 1 s): axis unusable."""
    imu = d.imu
    k = _at(imu, 0.55, 0.65, where)
    g = imu.gyro.copy()
    g[k:, 0] = g[k, 0]
    return _imu(d, imu.t_ns, g, imu.accel), [Span("dead_sensor", IMU, int(imu.t_ns[k]), int(imu.t_ns[-1]))]


def dead_accel(d: TestDrive, where: float) -> tuple[TestDrive, list[Span]]:
    """The vertical accelerometer (a signal of the inspection) freezes at 55-65 % of the IMU record."""
    imu = d.imu
    k = _at(imu, 0.55, 0.65, where)
    a = imu.accel.copy()
    a[k:, 2] = a[k, 2]
    return _imu(d, imu.t_ns, imu.gyro, a), [Span("dead_sensor", IMU, int(imu.t_ns[k]), int(imu.t_ns[-1]))]


def saturated_sensor(d: TestDrive, where: float) -> tuple[TestDrive, list[Span]]:
    """The yaw gyro clipped by its range: 35-45 % of its samples at the extreme."""
    g = d.imu.gyro.copy()
    c = float(np.quantile(np.abs(g[:, 2]), 0.55 + 0.1 * where))
    g[:, 2] = np.clip(g[:, 2], -c, c)
    return _imu(d, d.imu.t_ns, g, d.imu.accel), []


def implausible_unit(d: TestDrive, where: float) -> tuple[TestDrive, list[Span]]:
    """The steering-wheel angle recorded in degrees (only the sine steer turns the wheel far enough to tell)."""
    s = d.steering
    return dataclasses.replace(d, steering=Series(s.t_ns, np.degrees(s.values))), [
        Span("implausible_unit", STEERING, int(s.t_ns[0]), int(s.t_ns[-1]))]


def missing_topic(d: TestDrive, where: float) -> tuple[TestDrive, list[Span]]:
    """A bump crossing without its road profile."""
    return dataclasses.replace(d, road=None), [Span("missing_topic", ROAD_PROFILE, _t0(d), d.t_end_ns)]


def bad_metadata(d: TestDrive, where: float) -> tuple[TestDrive, list[Span]]:
    """A maneuver that names one of the registry's but does not start with it, a vehicle_state that is none."""
    man = d.metadata.get("maneuver", "")
    return dataclasses.replace(d, metadata={**d.metadata, "maneuver": f"slow_{man}", "vehicle_state": "rear-empty"}), []


def bad_oil(d: TestDrive, where: float) -> tuple[TestDrive, list[Span]]:
    """``damper_oil_level`` that is no set of four fractions: every simulation needs it."""
    return dataclasses.replace(d, metadata={**d.metadata, "damper_oil_level": "1,1,2,0"}), []


DAMAGES = {
    "non_finite": Damage("non_finite", non_finite),
    "non_finite_all": Damage("non_finite", non_finite_all, error=True),
    "gap": Damage("gap", gap),
    "clock_jump": Damage("clock_jump", clock_jump),
    "stamp_order": Damage("stamp_order", stamp_order, as_listed=True),
    "duplicate_stamp": Damage("duplicate_stamp", duplicate_stamp),
    "rate_change": Damage("rate_change", rate_change),
    "spike": Damage("spike", spike),
    "road_spike": Damage("spike", road_spike, drives=("bump",)),
    "dead_sensor": Damage("dead_sensor", dead_sensor, refused_by=("inspect",)),
    "dead_accel": Damage("dead_sensor", dead_accel, refused_by=("inspect",)),
    "saturated_sensor": Damage("saturated_sensor", saturated_sensor),
    "implausible_unit": Damage("implausible_unit", implausible_unit, drives=("sine",), error=True),
    "out_of_range": Damage("out_of_range", out_of_range),
    "missing_topic": Damage("missing_topic", missing_topic, drives=("bump",), error=True),
    "bad_metadata": Damage("bad_metadata", bad_metadata),
    "bad_oil": Damage("bad_metadata", bad_oil, error=True),
}
#: damage that no command reports yet, and why (a product bug outside the integrity check; listed here so the
#: corpus says so, and strict: the case fails once the bug is fixed, to be taken off this list)
KNOWN_SILENT: dict[str, str] = {}
SINGLE = [pytest.param(name, drive, id=f"{name}-{drive}",
                       marks=[pytest.mark.xfail(strict=True, reason=KNOWN_SILENT[name])] if name in KNOWN_SILENT
                       else [])
          for name, dmg in DAMAGES.items() for drive in dmg.drives]


def test_the_corpus_covers_every_kind():
    assert {d.kind for d in DAMAGES.values()} == set(KINDS)


# ---- the drives ---------------------------------------------------------------------------------------
def _cut(d: TestDrive, seconds: float) -> TestDrive:
    """The first ``seconds`` of a drive (road profile whole)."""
    end = d.t0_ns + int(seconds * NS)

    def head(s):
        return None if s is None else Series(s.t_ns[s.t_ns <= end], s.values[s.t_ns <= end])
    k = d.imu.t_ns <= end
    return dataclasses.replace(d, speed=head(d.speed), steering=head(d.steering),
                               wheel_heights=head(d.wheel_heights), damper_command=head(d.damper_command),
                               imu=ImuSeries(d.imu.t_ns[k], d.imu.gyro[k], d.imu.accel[k]))


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    """The shortened clean drives, their simulated recordings (for ``validate``) and a folder for damage."""
    tmp = tmp_path_factory.mktemp("damaged_corpus")
    out = {"dir": tmp}
    for name, src in SOURCES.items():
        d = _cut(read_drive(src), CUT_S)
        clean = tmp / f"{name}_clean.mcap"
        write_drive(clean, d)
        sim = tmp / f"{name}_sim.mcap"
        rc, _, err = run_cli(["sim", "--drive", clean, "--out", sim])
        assert rc == 0, err
        out[name] = (d, sim)
    return out


def _damaged(corpus, drive: str, names: tuple[str, ...], where: tuple[float, ...]) -> tuple[Path, TestDrive,
                                                                                           list[Span]]:
    d, _ = corpus[drive]
    spans: list[Span] = []
    for n, w in zip(names, where):
        d, s = DAMAGES[n].apply(d, w)
        spans += s
    for jump in [sp for sp in spans if sp.kind == "clock_jump"]:
        spans = [sp if sp is jump else sp.after_jump(jump.t_a) for sp in spans]
    path = corpus["dir"] / f"{drive}_{'+'.join(names)}_{'_'.join(f'{w:.3f}' for w in where)}.mcap"
    if any(DAMAGES[n].as_listed for n in names):
        _write_as_listed(path, d)
    else:
        write_drive(path, d, overwrite=True)
    return path, d, spans


def _write_as_listed(path: Path, d: TestDrive) -> None:
    """:func:`write_drive`, but the speed and steering messages in the file in the order their series list
    them (a recorder that wrote them out of log-time order), each in the place of the log time of its rank."""
    msgs = drive_messages(d)
    for topic, s in ((SPEED, d.speed), (STEERING, d.steering)):
        slots = [i for i, m in enumerate(msgs) if m[1] == topic]
        for i, t, v in zip(slots, s.t_ns.tolist(), s.values.tolist()):
            msgs[i] = (t, topic, msgs[i][2], {"data": v}, False)
    with McapRecorder(path, metadata={str(k): str(v) for k, v in d.metadata.items()}, overwrite=True) as rec:
        for t, topic, mt, msg, latched in msgs:
            rec.write(topic, mt, t, msg, latched=latched)


def _t0(d: TestDrive) -> int:
    """The recording's first message (what ``from_s``/``to_s`` count from)."""
    return min(int(s.t_ns[0]) for s in (d.speed, d.steering, d.wheel_heights, d.damper_command, d.imu)
               if s is not None and len(s))


# ---- running the commands ---------------------------------------------------------------------------------
def _no_nan(text: str) -> None:
    raise AssertionError(f"{text} in the JSON output")


def _argv(command: str, path: Path, sim: Path, out: Path) -> list:
    return {"sim": ["sim", "--drive", path],
            "validate": ["validate", "--measured", path, "--simulated", sim],
            "diagnose": ["diagnose", path, "--dry-run", "--out", out],
            "inspect": ["inspect", path],
            "replay": ["replay", path, "--dry-run"]}[command]


def _run(argv) -> tuple[int, dict | None, str]:
    """``susp ARGV --json``: exit 0 or 2 only, no traceback, no NaN/inf in the JSON."""
    rc, out, err = run_cli(list(argv) + ["--json"])
    assert rc in (0, 2), (argv, rc, err)
    assert "Traceback" not in err, (argv, err)
    if rc == 2:
        assert " error: " in err, (argv, err)
        return rc, None, err
    return rc, json.loads(out, parse_constant=_no_nan), err


def _check_spans(res: dict, d: TestDrive, spans: list[Span], argv) -> None:
    """Each expected span is a finding of its kind and topic exactly where the drive was damaged."""
    t0 = _t0(d)
    for sp in spans:
        got = [(f["from_s"], f["to_s"]) for f in res["input_findings"]
               if f["kind"] == sp.kind and f["topic"] == sp.topic]
        want = ((sp.t_a - t0) / NS, (sp.t_b - t0) / NS)
        assert any(abs(a - want[0]) <= sp.tol_s and abs(b - want[1]) <= sp.tol_s for a, b in got), (argv, sp, want, got)


def _run_all(corpus, drive: str, names: tuple[str, ...], where: tuple[float, ...], *, single: bool) -> dict:
    path, d, spans = _damaged(corpus, drive, names, where)
    kinds = {DAMAGES[n].kind for n in names}
    error = any(DAMAGES[n].error for n in names)
    rcs = {}
    for command in COMMANDS:
        argv = _argv(command, path, corpus[drive][1], corpus["dir"] / "diagnose")
        rc, res, err = _run(argv)
        rcs[command] = rc
        if rc == 2:  # refused: for the damage done, said by name (and alone: where, from the first message)
            assert any(k in err for k in kinds), (argv, err)
            assert str(path) in err, (argv, err)
            t0 = _t0(d)
            for sp in spans if single else ():
                assert f"{(sp.t_a - t0) / NS:.3f}-{(sp.t_b - t0) / NS:.3f} s" in err, (argv, sp, err)
            continue
        assert not error, (argv, "a damage that leaves nothing sound was not refused")
        found = {f["kind"] for f in res["input_findings"]}
        assert kinds <= found, (argv, kinds, res["input_findings"])  # no silent run
        assert found <= set(KINDS) and all(f["file"] == str(path) for f in res["input_findings"])
        assert f"input: {path} " in err  # and the stderr line
        _check_spans(res, d, spans, argv)
    if single:
        dmg = DAMAGES[names[0]]
        want = {c: 2 if dmg.error or c in dmg.refused_by else 0 for c in COMMANDS}
        assert rcs == want, (names, drive)
    return rcs


# ---- each kind alone ----------------------------------------------------------------------------------
@pytest.mark.parametrize("name,drive", SINGLE)
def test_each_damage_alone_through_every_command(corpus, name, drive):
    _run_all(corpus, drive, (name,), (0.5,), single=True)


def test_clean_copies_give_no_finding(corpus):
    for drive in SOURCES:
        path, d, _ = _damaged(corpus, drive, (), ())
        for command in ("sim", "validate", "replay"):
            rc, res, err = _run(_argv(command, path, corpus[drive][1], corpus["dir"] / "diagnose"))
            assert rc == 0 and res["input_findings"] == [] and "input: " not in err


# ---- two kinds at a time ----------------------------------------------------------------------------------
@st.composite
def _pairs(draw):
    drive = draw(st.sampled_from(sorted(SOURCES)))
    names = sorted(n for n, dmg in DAMAGES.items() if drive in dmg.drives and n not in KNOWN_SILENT)
    pair = draw(st.lists(st.sampled_from(names), min_size=2, max_size=2, unique=True))
    where = tuple(draw(st.floats(0.0, 1.0)) for _ in pair)
    return drive, tuple(pair), where


@settings(max_examples=6, deadline=None)
@given(case=_pairs())
def test_two_damages_at_once_through_every_command(corpus, case):
    drive, names, where = case
    _run_all(corpus, drive, names, where, single=False)


# ---- the real fit ------------------------------------------------------------------------------------------
def test_diagnose_fits_a_damaged_drive_and_reports_every_finding(corpus):
    """One real ``diagnose`` fit (one candidate, no held-out pass: the cost of the corpus is the read) of a
    bump crossing damaged five ways at once: exit 0, every kind in ``input_findings`` and the report."""
    names = ("non_finite", "gap", "clock_jump", "spike", "saturated_sensor")
    path, d, spans = _damaged(corpus, "bump", names, (0.5,) * len(names))
    out = corpus["dir"] / "fit"
    argv = ["diagnose", path, "--candidates", "time_offset", "--no-heldout", "--no-plots", "--no-progress",
            "--out", out]
    rc, res, err = _run(argv)
    assert rc == 0, err
    assert {f["kind"] for f in res["input_findings"]} >= set(names)
    _check_spans(res, d, spans, argv)
    report = next(out.glob("*.md")).read_text()
    assert "## Input findings" in report and all(f" {k} " in report for k in names)
    # a dead gyro leaves the fit nothing sound: a named error before any fitting
    path, _, _ = _damaged(corpus, "bump", ("dead_sensor",), (0.5,))
    rc, _, err = _run(argv[:1] + [path] + argv[2:])
    assert rc == 2 and "dead_sensor" in err


# ---- what validate leaves out -----------------------------------------------------------------------------
def test_validate_leaves_out_the_damaged_span_and_axis(corpus):
    """An IMU gap is left out of the comparison exactly over the hole (as many grid points fewer as the hole
    holds at the comparison rate); a gyro axis that dies gives no metric, the live axes keep theirs."""
    _, sim = corpus["sine"]
    clean, _, _ = _damaged(corpus, "sine", (), ())
    holed, _, (sp,) = _damaged(corpus, "sine", ("gap",), (0.5,))
    base = _run(["validate", "--measured", clean, "--simulated", sim])[1]
    res = _run(["validate", "--measured", holed, "--simulated", sim])[1]
    rate = 100.0  # Hz: the lower rate of the two recordings (the simulated IMU at the default --rate)
    for w in ("whole", "steering"):
        for sig, m in res["windows"][w]["signals"].items():
            fewer = base["windows"][w]["signals"][sig]["n"] - m["n"]
            assert abs(fewer - (sp.t_b - sp.t_a) / NS * rate) <= 1.0, (w, sig, fewer)
            assert m["phase_lag_s"] is None  # not computed across a hole
    dead, _, _ = _damaged(corpus, "sine", ("dead_sensor",), (0.5,))
    res = _run(["validate", "--measured", dead, "--simulated", sim])[1]
    for w, ms in res["rmse_deg_s"].items():
        assert set(ms) == {"pitch_rate", "yaw_rate"}, w


# ---- a span excluded gives the same metrics as the drive cut there ----------------------------------------
def _imu_only(d: TestDrive, keep: np.ndarray) -> TestDrive:
    return _imu(d, d.imu.t_ns[keep], d.imu.gyro[keep], d.imu.accel[keep])


def test_an_imu_gap_to_the_end_gives_the_metrics_of_the_drive_cut_there(corpus):
    """The IMU falls silent 2.5 s into the sine steer and sends one last message at the end of the drive: the
    gap [a, end] is excluded, and ``validate`` gives per window and signal the RMSE (to the printed digit) and
    the sample count of the measured drive truncated at a (every series cut there)."""
    d, sim = corpus["sine"]
    imu = d.imu
    k = int(np.searchsorted(imu.t_ns, imu.t_ns[0] + int(2.5 * NS)))
    a = int(imu.t_ns[k])
    keep = (imu.t_ns <= a) | (np.arange(len(imu)) == len(imu) - 1)
    holed = corpus["dir"] / "sine_gap_to_end.mcap"
    write_drive(holed, _imu_only(d, keep), overwrite=True)
    cut = corpus["dir"] / "sine_cut_at_gap.mcap"
    write_drive(cut, _cut(d, (a - d.t0_ns) / NS), overwrite=True)
    res = _run(["validate", "--measured", holed, "--simulated", sim])[1]
    base = _run(["validate", "--measured", cut, "--simulated", sim])[1]
    (gap,) = [f for f in res["input_findings"] if f["kind"] == "gap"]
    t0 = _t0(d)
    assert gap["from_s"] == pytest.approx((a - t0) / NS, abs=2e-6)
    assert gap["to_s"] == pytest.approx((int(imu.t_ns[-1]) - t0) / NS, abs=2e-6)
    assert base["input_findings"] == []
    assert set(res["rmse_deg_s"]) == set(base["rmse_deg_s"]) == {"whole", "steering"}
    for w, ms in base["rmse_deg_s"].items():
        assert set(res["rmse_deg_s"][w]) == set(ms)
        for sig, rmse in ms.items():
            assert f"{res['rmse_deg_s'][w][sig]:.3f}" == f"{rmse:.3f}", (w, sig)
            assert res["windows"][w]["signals"][sig]["n"] == base["windows"][w]["signals"][sig]["n"], (w, sig)


@settings(max_examples=4, deadline=None)
@given(start=st.floats(0.2, 0.6), length_s=st.floats(0.2, 1.0))
def test_an_imu_gap_in_the_middle_sums_the_squared_errors_of_the_two_pieces(corpus, start, length_s):
    """A gap in the middle of the IMU record: per window and signal, the squared errors ``validate`` sums
    over the holed drive are those of the piece before the gap plus those of the piece after it (the IMU
    record cut at each side; inputs whole so that the windows are the same): nothing is compared across
    the hole, nothing is lost beside it."""
    d, sim = corpus["sine"]
    imu = d.imu
    k = int(start * (len(imu) - 1))
    a = int(imu.t_ns[k])
    b = int(imu.t_ns[np.searchsorted(imu.t_ns, a + int(length_s * NS), side="right")])
    runs = {}
    for name, keep in (("holed", (imu.t_ns <= a) | (imu.t_ns >= b)), ("before", imu.t_ns <= a),
                       ("after", imu.t_ns >= b)):
        path = corpus["dir"] / f"sine_middle_{name}.mcap"
        write_drive(path, _imu_only(d, keep), overwrite=True)
        runs[name] = _run(["validate", "--measured", path, "--simulated", sim])[1]
    assert [f["kind"] for f in runs["holed"]["input_findings"]] == ["gap"]
    for w, ms in runs["holed"]["windows"].items():
        for sig, m in ms["signals"].items():
            pieces = [runs[p]["windows"][w]["signals"][sig] for p in ("before", "after")
                      if w in runs[p]["windows"] and sig in runs[p]["windows"][w]["signals"]]
            assert m["n"] == sum(p["n"] for p in pieces), (w, sig)
            sse = m["n"] * m["rmse_deg_s"] ** 2
            assert sse == pytest.approx(sum(p["n"] * p["rmse_deg_s"] ** 2 for p in pieces), rel=1e-9), (w, sig)
