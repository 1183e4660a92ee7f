"""The missing force of every drive of a fitted finder (against its calibrated model, before any
physics term is added: what the calibration could not explain), seen: time series (CSV), loops (PNG), summary
(``missing_force`` in the JSON) and a report section (issue 26, items 1-2; estimation in
:mod:`.missing_force`).

Three parts make the force the *base* model (the vehicle file's values) lacks, per axle and roll moment:

1. the calibration's corner part: what the calibration supplied as corner force (the calibrated model's
   suspension force -- spring, damper, friction, anti-roll bar -- minus the base model's at the same
   deflections, velocities and wheel forces, along the calibrated model's run;
   :func:`~.missing_force.calibration_force`);
2. the calibration's body part: the inertial force of the calibrated sprung-mass and inertia change,
   ``-(m_cal - m_file) z''``, ``-(Ixx_cal - Ixx_file) phi''``, ``-(Iyy_cal - Iyy_file) theta''`` along the
   calibrated run, split onto the axles and the roll moment by statics as the estimate's channels act on
   the body (:func:`~.missing_force.body_force`): the base model's body, with the file's mass, lacks it to
   move as the calibrated body does. Accelerations from the calibrated run's kernel outputs: heave
   ``AZ_SF - g``, roll and pitch the step-wise difference of ``ROLL_RATE``/``PITCH_RATE``
   (:func:`~.missing_force.body_accelerations`);
3. the estimate against the calibrated model.

The calibration takes up what lies in the span of its values (extra viscous damping in a damper-curve
scale, a gas spring's rate in the wheel rate, and some of either in the sprung mass: the body IMU sees a
mass and a rate mostly through their ratio); the first two parts give it back. Tyre values and the
centre-of-gravity height stay out: they only shape the trajectory the parts are read along.

Per drive the calibrated model (base structure, calibration and measurement chain as fitted) is
simulated to the drive's end; the residual measured - simulated of roll rate, pitch rate and vertical
specific force at the measured sample times (sensor offset removed over the quiet lead-in, else over the
drive) is turned into the force per axle and the roll moment the model lacks, drawn against the model's
own deflection and deflection velocity of that axle (mean of its two corners), with the model's own
suspension force beside it: the hysteresis loops and force-velocity curves an engineer reads physics off.
"""
from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..render import FigureRenderer
from ...model.params import AXLE_CORNERS, CORNER_NAMES
from . import missing_force as mf
from .data import SIGNAL_OF_OUTPUT, SIGNALS, has_road_input
from .candidates import CALIBRATION
from .engine import MIN_QUIET_BIAS

#: kernel outputs simulated per drive: deflection [m], its velocity [m/s], the suspension's forces [N]
_CORNER_OUTPUTS = ("DEFL", "DEFL_VEL", "F_SPRING", "F_DAMPER", "F_FRICTION", "F_ARB", "F_X", "F_Y", "F_Z")
_OUTPUTS = tuple(mf.MEASURED) + tuple(f"{o}_{w}" for o in _CORNER_OUTPUTS for w in CORNER_NAMES)
#: CSV columns (interface.md "missing_force": the first seven are the interface's)
CSV_COLUMNS = ("t", "front_N", "front_sd_N", "rear_N", "rear_sd_N", "roll_Nm", "roll_sd_Nm",
               "front_deflection_m", "rear_deflection_m", "front_deflection_velocity_m_s",
               "rear_deflection_velocity_m_s", "front_model_force_N", "rear_model_force_N",
               "front_calibration_N", "rear_calibration_N", "roll_calibration_Nm",
               "front_base_N", "rear_base_N", "roll_base_Nm",
               "front_body_N", "rear_body_N", "roll_body_Nm")


@dataclass
class DriveForce:
    """One drive's missing force (:class:`~.missing_force.MissingForce`, the force the calibrated model
    lacks) with the model's own axle deflection [m], deflection velocity [m/s] and suspension force [N]
    (n, 2: front, rear) on its grid; ``calibration`` (n, 3 in :data:`~.missing_force.CHANNELS`): what the
    calibration supplied as corner force (module docstring; None when not computed, zero without a
    calibration), ``calibration_check_N`` how closely the re-evaluation reproduced the kernel's force;
    ``body`` (n, 3, same channels): the body-level part, the inertial force of the calibration's
    sprung-mass and inertia change (:func:`~.missing_force.body_force`; None when not computed)."""

    drive: str
    est: mf.MissingForce
    deflection: np.ndarray
    velocity: np.ndarray
    model_force: np.ndarray
    unmeasured_input: bool
    calibration: np.ndarray | None = None
    calibration_check_N: float | None = None
    body: np.ndarray | None = None

    @property
    def base_total(self) -> np.ndarray | None:
        """(n, 3) the force the base model lacks: the calibration's corner part, its body part (when
        computed) and the estimate against the calibrated model."""
        if self.calibration is None:
            return None
        return self.est.force + self.calibration + (0.0 if self.body is None else self.body)


def _corner(Y: np.ndarray, name: str) -> np.ndarray:
    j = _OUTPUTS.index(f"{name}_FL")
    return Y[:, j:j + 4]


def _residual(f, fit, r: int, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Measured times [s], residual measured - simulated (n, 3, SI) and noise sd (3,, SI) of drive ``r``
    against the model of ``fit`` (a :class:`~.fit.FitResult`) simulated as ``Y``."""
    c = f.cases_[r]
    st, x = fit.structure, fit.x
    t_sim = c.t_sim_s
    tq = c.t_raw_s - st.lag(x)
    sig = [SIGNALS[[SIGNAL_OF_OUTPUT[s][0] for s in SIGNALS].index(o)] for o in mf.MEASURED]
    to_si = np.array([1.0 / SIGNAL_OF_OUTPUT[s][1] for s in sig])
    meas = np.column_stack([c.y_raw[:, SIGNALS.index(s)] for s in sig]) * to_si
    sim = np.column_stack([np.interp(tq, t_sim, Y[:, j]) for j in range(len(mf.MEASURED))])
    resid = meas - sim
    quiet = c.quiet_raw if c.quiet_raw is not None and c.quiet_raw.sum() >= MIN_QUIET_BIAS else np.ones(len(tq), bool)
    resid -= resid[quiet].mean(axis=0)
    per, pooled = f.noise_["per_drive"][c.name], f.noise_["noise_floors"]
    sd = np.array([per[s] if math.isfinite(per.get(s, math.nan)) and per[s] > 0 else pooled[s] for s in sig]) * to_si
    return c.t_raw_s, resid, sd


def _calibration_part(f, fit, r: int, Y: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
    """Along drive ``r``'s calibrated run ``Y``: the per-corner force (n_steps, 4) [N] the calibration
    supplied, the re-evaluation's check [N] (:func:`~.missing_force.calibration_force`) and the body-level
    part (n_steps, 3 channels; :func:`~.missing_force.body_force` of the calibrated row's mass and inertias
    against the file's, with the run's body accelerations)."""
    ev, st, x = f.evaluator_, fit.structure, fit.x
    if CALIBRATION not in st.names:
        return np.zeros((len(Y), 4)), 0.0, np.zeros((len(Y), len(mf.CHANNELS)))
    P_cal, P_base = ev.rows(st, x, [r])[0], ev.rows(st, st.at_neutral(x, CALIBRATION), [r])[0]
    traj = {k: _corner(Y, k) for k in mf.TRAJECTORY}
    own = np.sum([_corner(Y, n) for n in ("F_SPRING", "F_DAMPER", "F_FRICTION", "F_ARB")], axis=0)
    cf = mf.calibration_force(ev.model.kernel, P_cal, P_base, traj, own)
    az, roll_rate, pitch_rate = (Y[:, _OUTPUTS.index(o)] for o in mf.BODY_OUTPUTS)
    acc = mf.body_accelerations(P_cal, az, roll_rate, pitch_rate, float(ev.dt))
    return cf.corner, cf.check_N, mf.body_force(P_cal, P_base, acc, mf.Corners.of(P_cal))


def _per_axle(t: np.ndarray, t_sim: np.ndarray, corners: np.ndarray, combine) -> np.ndarray:
    """(n, 2) front and rear of the per-corner series ``corners`` (n_steps, 4) at the times ``t``, its
    two corners combined by ``combine`` (mean of a deflection, sum of a force)."""
    return np.column_stack([combine(np.column_stack([np.interp(t, t_sim, corners[:, i]) for i in ij]), axis=1)
                            for ij in AXLE_CORNERS.values()])


def estimate_drives(f, fit, cfg: dict | None = None, *, calibration: bool = False) -> dict[str, DriveForce]:
    """The missing force of every drive of the fitted finder ``f`` against the model of ``fit`` (module
    docstring). With ``calibration`` also the calibration's part (:attr:`DriveForce.calibration`: the
    calibrated model of ``fit`` against the same structure with its calibration at the file's values)."""
    cfg = mf.settings() if cfg is None else cfg
    ev, st, x = f.evaluator_, fit.structure, fit.x
    out = {}
    for r, c in enumerate(f.cases_):
        Y = ev.simulate_outputs(st, x, r, _OUTPUTS)
        defl, vel = _corner(Y, "DEFL"), _corner(Y, "DEFL_VEL")
        t, resid, sd = _residual(f, fit, r, Y)
        P = ev.rows(st, x, [r])[0]
        est = mf.estimate_on_model(f.model_.vehicle, P, defl, vel,
                                   _corner(Y, "F_DAMPER") + _corner(Y, "F_FRICTION"), t, resid, sd, cfg)
        force = np.sum([_corner(Y, n) for n in ("F_SPRING", "F_DAMPER", "F_FRICTION", "F_ARB")], axis=0)
        d = DriveForce(c.name, est, _per_axle(est.t, c.t_sim_s, defl, np.mean),
                       _per_axle(est.t, c.t_sim_s, vel, np.mean),
                       _per_axle(est.t, c.t_sim_s, force, np.sum), not has_road_input(c))
        if calibration:
            corner, d.calibration_check_N, body = _calibration_part(f, fit, r, Y)
            ch = mf.axle_channels(corner, mf.Corners.of(P))
            # on the estimate's grid as the residual takes the simulation: the measurement at t is the run at t - lag
            tq = est.t - st.lag(x)
            d.calibration = np.column_stack([np.interp(tq, c.t_sim_s, ch[:, j]) for j in range(ch.shape[1])])
            d.body = np.column_stack([np.interp(tq, c.t_sim_s, body[:, j]) for j in range(body.shape[1])])
        out[c.name] = d
    return out


def summary(forces: dict[str, DriveForce], cfg: dict | None = None) -> dict:
    """``missing_force.per_drive`` of the interface: per drive and channel the RMS over the measured
    samples, the RMS in the body-mode band, the mean sd; per axle the loop's half height (friction-like
    level, :func:`~.missing_force.loop_half_height`)."""
    cfg = mf.settings() if cfg is None else cfg
    per = {}
    for name, d in forces.items():
        e = d.est
        v = e.valid
        band = mf.band_passed(e.force, float(e.t[1] - e.t[0]), cfg) if len(e.t) > 1 else e.force
        entry: dict = {}
        for j, ch in enumerate(mf.CHANNELS):
            entry[ch] = {"rms": float(np.sqrt(np.mean(e.force[v, j] ** 2))),
                         "band_rms": float(np.sqrt(np.mean(band[v, j] ** 2))),
                         "sd_mean": float(np.mean(e.sd[v, j]))}
            if j < 2:
                entry[ch]["loop_half_height_N"] = _finite(mf.loop_half_height(e.force[v, j], d.velocity[v, j], cfg))
        entry["intensity_N2_s"] = e.intensity
        entry["unmeasured_input"] = d.unmeasured_input
        if d.calibration is not None and d.base_total is not None:
            entry["calibration"] = _channel_figures(d.calibration, v, e.t, cfg)
            entry["calibration"]["check_N"] = _finite(d.calibration_check_N if d.calibration_check_N is not None
                                                      else math.nan)
            if d.body is not None:
                entry["calibration_body"] = _channel_figures(d.body, v, e.t, cfg)
            entry["base_model"] = _channel_figures(d.base_total, v, e.t, cfg, d.velocity)
        per[name] = entry
    return per


def _channel_figures(x: np.ndarray, v: np.ndarray, t: np.ndarray, cfg: dict,
                     velocity: np.ndarray | None = None) -> dict:
    """Per channel of the (n, 3) series ``x``: RMS and band RMS over the measured samples ``v`` (and with the
    axle ``velocity`` (n, 2), the loop's half height per axle)."""
    band = mf.band_passed(x, float(t[1] - t[0]), cfg) if len(t) > 1 else x
    out: dict = {}
    for j, ch in enumerate(mf.CHANNELS):
        out[ch] = {"rms": float(np.sqrt(np.mean(x[v, j] ** 2))), "band_rms": float(np.sqrt(np.mean(band[v, j] ** 2)))}
        if velocity is not None and j < 2:
            out[ch]["loop_half_height_N"] = _finite(mf.loop_half_height(x[v, j], velocity[v, j], cfg))
    return out


def _finite(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def write_csv(d: DriveForce, path: Path) -> None:
    """The time series of one drive (:data:`CSV_COLUMNS`; SI units as the column names say)."""
    e = d.est
    nan = np.full_like(e.force, np.nan)
    cal = d.calibration if d.calibration is not None else nan
    body = d.body if d.body is not None else nan
    total = d.base_total if d.base_total is not None else nan
    cols = [e.t, e.force[:, 0], e.sd[:, 0], e.force[:, 1], e.sd[:, 1], e.force[:, 2], e.sd[:, 2],
            d.deflection[:, 0], d.deflection[:, 1], d.velocity[:, 0], d.velocity[:, 1],
            d.model_force[:, 0], d.model_force[:, 1], *cal.T, *total.T, *body.T]
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(CSV_COLUMNS)
        for k in np.nonzero(e.valid)[0]:
            w.writerow([f"{c[k]:.6g}" for c in cols])


def plot(d: DriveForce, path: Path, title: str) -> None:
    """Loops of one drive: per axle the missing force against deflection and against deflection
    velocity on the left axis, scaled to it alone (its shape is what is read); on the right axis the
    model's own forces: its suspension force (less its mean), the calibration's corner part (the corner
    force the calibration supplied, when computed) and its body part (the inertial force of the calibrated
    mass and inertia change, which the base model's body with its file mass lacks), often ten times the
    missing force. Below, the three channels over time with their 95 % band (left axis), the calibration's
    corner parts dashed and its body parts dotted (right axis)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    e, v = d.est, d.est.valid
    fig, ax = plt.subplots(3, 2, figsize=(11, 10))
    for row, axle in enumerate(AXLE_CORNERS):
        for col, (x, label) in enumerate(((d.deflection[:, row] * 1e3, "deflection [mm] (+ bump)"),
                                         (d.velocity[:, row] * 1e3, "deflection velocity [mm/s]"))):
            a = ax[row, col]
            a.plot(x[v], e.force[v, row], color="C3", lw=1.2, label="missing force (calibrated model)")
            a.set_xlabel(label)
            a.set_ylabel(f"{axle} axle missing force [N]", color="C3")
            b = a.twinx()
            m = d.model_force[:, row]
            b.plot(x[v], m[v] - m[v].mean(), color="0.6", lw=0.7, label="model's suspension force - mean")
            if d.calibration is not None:
                b.plot(x[v], d.calibration[v, row], color="C0", lw=0.7,
                       label="calibration's corner part (calibrated - base model)")
            if d.body is not None:
                b.plot(x[v], d.body[v, row], color="C2", lw=0.7,
                       label="calibration's body part (-(mass, inertia change) x acceleration)")
            b.set_ylabel("model's forces [N] (grey, blue, green)", color="0.4")
            _over_twin(a, b, loc="upper left", fontsize=7)
            a.set_title(f"{axle} axle" + (" (input not measured: includes the road)" if d.unmeasured_input else ""))
            a.grid(alpha=0.3)
    gs = ax[2, 0].get_gridspec()
    ax[2, 0].remove()
    ax[2, 1].remove()
    a = fig.add_subplot(gs[2, :])
    b = a.twinx() if d.calibration is not None or d.body is not None else None
    for j, ch in enumerate(mf.CHANNELS):
        unit = "N*m" if ch.endswith("Nm") else "N"
        a.plot(e.t, np.where(v, e.force[:, j], np.nan), lw=1.0, color=f"C{j}", label=f"{ch[:-2].rstrip('_')} [{unit}]")
        a.fill_between(e.t, e.force[:, j] - 2 * e.sd[:, j], e.force[:, j] + 2 * e.sd[:, j], color=f"C{j}", alpha=0.2)
        if b is not None and d.calibration is not None:
            b.plot(e.t, np.where(v, d.calibration[:, j], np.nan), lw=0.7, ls="--", color=f"C{j}",
                   label=f"{ch[:-2].rstrip('_')}: calibration's corner part")
        if b is not None and d.body is not None:
            b.plot(e.t, np.where(v, d.body[:, j], np.nan), lw=0.7, ls=":", color=f"C{j}",
                   label=f"{ch[:-2].rstrip('_')}: calibration's body part (mass, inertia)")
    a.set_xlabel("time [s]")
    a.set_ylabel("missing force, +-2 sd (solid)")
    if b is not None:
        b.set_ylabel("calibration's parts (dashed, dotted)", color="0.4")
    _over_twin(a, b, loc="upper right", fontsize=7, ncol=2)
    a.grid(alpha=0.3)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def _over_twin(a, b, **legend) -> None:
    """Axis ``a`` (the missing force) drawn over its twin ``b`` (the model's forces; None: no twin), with one
    legend of both."""
    handles, labels = a.get_legend_handles_labels()
    if b is not None:
        a.set_zorder(b.get_zorder() + 1)
        a.patch.set_visible(False)
        h2, l2 = b.get_legend_handles_labels()
        handles, labels = handles + h2, labels + l2
    a.legend(handles, labels, **legend)


def write(f, out: Path, name: str, *, plots: bool = True, renderer: FigureRenderer | None = None) -> dict:
    """Estimate, write ``missing_force_<drive>.csv`` (and ``<name>_missing_force_<drive>.png``, drawn by
    ``renderer`` when given) into ``out``; returns the interface's ``missing_force`` object."""
    cfg = mf.settings()
    forces = estimate_drives(f, f.calibrated_fit_, cfg, calibration=True)
    files = []
    for drive, d in forces.items():
        p = out / f"missing_force_{drive}.csv"
        write_csv(d, p)
        files.append(str(p))
        if plots:
            p = out / f"{name}_missing_force_{drive}.png"
            title = (f"{drive}: the force the calibrated model lacks (estimated from the recording)\n"
                     "and the calibration's corner and body parts (their sum is what the base model lacks)")
            if renderer is None:
                plot(d, p, title)
            else:
                renderer.submit(str(p), plot, d, p, title)
            files.append(str(p))
    return {"per_drive": summary(forces, cfg), "files": files}


def markdown(mf_json: dict) -> list[str]:
    """The report section."""
    lines = ["## Missing force", "",
             "The force the calibrated model (before any physics term) lacks, estimated from each recording "
             "(Kalman filter and RTS smoother on the model's equivalent-linear error dynamics; body IMU roll "
             "rate, pitch rate and vertical "
             "specific force). Read its shape in the loop plots: friction is a rectangle in the force-"
             "velocity plot (a jump at zero velocity) and a loop of constant height against deflection; "
             "viscous damping a line through the origin against velocity; a spring a line against deflection. "
             "The loop half height is the friction-like level of the axle (both wheels) the model lacks; "
             "negative where the model has more friction-like force than the car. The force the base "
             "model (the vehicle file's values) lacks has three parts: the calibration's corner part (the "
             "corner force the calibration supplied: calibrated minus base model's spring, damper, friction "
             "and anti-roll bar force along the calibrated run), the calibration's body part (the inertial "
             "force of the calibrated sprung-mass and inertia change along the calibrated run, split onto the "
             "axles by statics: the base model's body, with its file mass, lacks it) and the missing force "
             "against the calibrated model.", "",
             "| drive | front RMS [N] | rear RMS [N] | roll RMS [N*m] | front loop half height [N] | "
             "rear loop half height [N] | mean sd front / rear [N] | calibration's corner part band RMS front / "
             "rear [N] | calibration's body part band RMS front / rear [N] "
             "| base model's lack band RMS front / rear [N] |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    def num(x):
        return "-" if x is None else f"{round(x):d}"  # never "-0"

    for drive, e in mf_json["per_drive"].items():
        lines.append(f"| {drive}{' (input not measured)' if e['unmeasured_input'] else ''} | "
                     f"{e['front_N']['rms']:.0f} | {e['rear_N']['rms']:.0f} | {e['roll_Nm']['rms']:.0f} | "
                     f"{num(e['front_N']['loop_half_height_N'])} | {num(e['rear_N']['loop_half_height_N'])} | "
                     f"{e['front_N']['sd_mean']:.0f} / {e['rear_N']['sd_mean']:.0f} | "
                     f"{_pair(e.get('calibration'))} | {_pair(e.get('calibration_body'))} | "
                     f"{_pair(e.get('base_model'))} |")
    if any(e["unmeasured_input"] for e in mf_json["per_drive"].values()):
        lines += ["", "Drives marked (input not measured) have no road in the recording: their estimate carries the "
                  "force of the unmeasured road on the car as well, so its size and loops there say nothing about "
                  "missing physics."]
    lines += ["", "Files: " + ", ".join(Path(p).name for p in mf_json["files"]), ""]
    return lines


def _pair(part: dict | None) -> str:
    """``front / rear`` band RMS [N] of a part's figures, ``-`` when absent."""
    if not part:
        return "-"
    return f"{part['front_N']['band_rms']:.0f} / {part['rear_N']['band_rms']:.0f}"
