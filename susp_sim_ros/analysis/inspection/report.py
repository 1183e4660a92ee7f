"""Markdown + PNG report of a damper inspection (:func:`.estimate.inspect_drives`)."""
from __future__ import annotations

import json
from pathlib import Path


from ...model.params import CORNER_NAMES
from ...io.json_values import jsonable
from ..discrepancy.data import SIGNAL_UNIT, SIGNALS
from .protocol import CM, KMH


def plot_fit(res, path: Path) -> list[str]:
    """Measured against fitted signals, one PNG per drive; returns the file names."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    ev, fit = res.evaluator_, res.fit_
    rates = ev.simulate(fit.structure, fit.x[None])[0]
    names = []
    for r, c in enumerate(ev.cases):
        e = ev.case_residual(r, rates[r], 0.0, fit.structure.bias)
        fig, axes = plt.subplots(len(c.signals), 1, figsize=(7.0, 2.2 * len(c.signals)), sharex=True, squeeze=False)
        for j, s in enumerate(c.signals):
            ax = axes[j, 0]
            ax.plot(c.t_grid_s, c.y_meas[:, j], ".", ms=2, color="0.4", label="measured")
            ax.plot(c.t_grid_s, c.y_meas[:, j] + e[:, j], "-", lw=1.2, color="C0", label="fitted model")
            ax.set_ylabel(f"{s} [{SIGNAL_UNIT[SIGNALS.index(s)]}]")
            ax.grid(True, alpha=0.3)
        axes[0, 0].legend(fontsize=8)
        axes[0, 0].set_title(f"{c.name}: measured vs fitted", fontsize=10)
        axes[-1, 0].set_xlabel("time [s]")
        fig.tight_layout()
        name = f"fit_{c.name}.png"
        fig.savefig(path / name, dpi=100)
        plt.close(fig)
        names.append(name)
    return names


def plot_intervals(res, path: Path, states_cfg: dict) -> str:
    """Oil level and 95 % interval per wheel over the state bands (PNG)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.0, 3.2))
    ax.axvspan(0, states_cfg["empty_below"], color="C3", alpha=0.12, label="empty")
    ax.axvspan(states_cfg["empty_below"], states_cfg["ok_from"], color="C1", alpha=0.12, label="degraded")
    ax.axvspan(states_cfg["ok_from"], 1.0, color="C2", alpha=0.12, label="ok")
    for k, w in enumerate(CORNER_NAMES):
        e = res.wheels_[w]
        if e["oil_level"] is None:
            ax.text(0.5, k, "unknown (not excited)", ha="center", va="center", fontsize=8)
            continue
        lo, hi = e["ci95"]
        ax.errorbar(e["oil_level"], k, xerr=[[e["oil_level"] - lo], [hi - e["oil_level"]]], fmt="o", color="k",
                    capsize=4)
        ax.text(1.02, k, f"{e['state']} ({e['identifiable']})", va="center", fontsize=8)
    ax.set_yticks(range(4), CORNER_NAMES)
    ax.set_xlim(0, 1.25)
    ax.invert_yaxis()
    ax.set_xlabel("oil level (1 intact, 0 empty), 95 % interval")
    ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    name = "oil_levels.png"
    fig.savefig(path / name, dpi=110)
    plt.close(fig)
    return name


def write_inspection_report(res, out: str | Path, cfg: dict, drives) -> dict:
    """``inspection.md``, ``inspection.json`` and the PNGs into ``out``; returns the paths written."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    d = res.to_json()
    (out / "inspection.json").write_text(json.dumps(d, indent=1, default=jsonable))
    pngs = plot_fit(res, out)
    iv = plot_intervals(res, out, cfg["states"])
    st = cfg["states"]
    lines = ["# Damper inspection", "",
             f"Drives: {', '.join(str(p) for p in drives)}. Vehicle class: `{res.vehicle_}`. "
             f"Run time {res.elapsed_s_:.1f} s.", "",
             "Oil level per damper (1 intact, 0 empty) with its 95 % interval, fitted together with the "
             "vehicle parameters that vary within the class (masses, inertias, spring and tyre rates, friction "
             f"levels). States: `ok` from {st['ok_from']:g}, `empty` below {st['empty_below']:g}, `degraded` "
             "between, `unknown` when the interval reaches into two.", "",
             "| damper | oil level | 95 % interval | state | identifiable |", "|---|---|---|---|---|"]
    for w in CORNER_NAMES:
        e = d["wheels"][w]
        v = "-" if e["oil_level"] is None else f"{e['oil_level']:.2f}"
        ci = "-" if e["ci95"] is None else f"{e['ci95'][0]:.2f} - {e['ci95'][1]:.2f}"
        lines.append(f"| {w} | {v} | {ci} | {e['state']} | {e['identifiable']} |")
    lines += ["", "| axle | oil level | 95 % interval | state |", "|---|---|---|---|"]
    for a, e in d["axles"].items():
        v = "-" if e["oil_level"] is None else f"{e['oil_level']:.2f}"
        ci = "-" if e["ci95"] is None else f"{e['ci95'][0]:.2f} - {e['ci95'][1]:.2f}"
        lines.append(f"| {a} | {v} | {ci} | {e['state']} |")
    law = d.get("oil_law") or {}
    lines += ["", (f"Oil law of the damper type: {law['source']}: a drive shows each damper's remaining force "
                   "fraction, which reads as its oil level only through how the damper type loses force with "
                   "its oil; a rig test of a damper drained in steps gives it (`--oil-law`)."
                   if law.get("model_law", True) else
                   "Oil law of the damper type (force fraction kept at each oil level, rig test): "
                   + ", ".join(f"{o:g} -> {f:g}" for o, f in zip(law["oil"], law["force_fraction"]))
                   + f" ({law['source']}); the fitted force fractions are read as oil levels through it.")]
    lines += ["", "What the drives can tell:", ""]
    for a, e in d["identifiability"].items():
        lines.append(f"- {a}: **{e['identifiable']}**: {e['why']}")
    lines += ["", f"![oil levels]({iv})"]
    lines += _left_right_lines(d.get("left_right") or [], cfg.get("left_right") or {})
    lines += ["", "## Vehicle parameters fitted alongside (nuisances)", "",
              "| parameter | unit | prior | range | fitted | 95 % |", "|---|---|---|---|---|---|"]
    for n in d["nuisance"]:
        lines.append(f"| {n['param']} | {n['unit']} | {n['prior']:.4g} | {n['prior_range'][0]:.4g} - "
                     f"{n['prior_range'][1]:.4g} | {n['value']:.4g} | {n['ci95'][0]:.4g} - {n['ci95'][1]:.4g} |")
    w = d.get("wheel_loads")
    lines += ["", ("Weighed: static wheel loads " + ", ".join(f"{v:.0f}" for v in w["measured_N"])
                   + f" N (FL, FR, RL, RR), {w['total_mass_kg']:.0f} kg in all: sprung mass "
                   f"{w['sprung_mass_prior_kg']:.0f} +- {w['sprung_mass_prior_sd_kg']:.0f} kg as its prior (vehicle "
                   f"file {w['vehicle_file_sprung_mass_kg']:.0f} kg)") if w else
              "Not weighed: the sprung mass rests on the vehicle file's range; a car far from it reads its dampers "
              "off by about the mass ratio (`--wheel-loads`)."]
    lines += ["", f"Fit: {d['fit']['message']} ({d['fit']['nfev']} evaluations), residual RMS "
              f"{d['fit']['rms_x_noise']:.2f} x the sensor noise.", ""]
    for n in d["notes"]:
        lines.append(f"- note: {n}")
    lines += _protocol_lines(d.get("protocol") or {})
    lines += ["", "## Measured vs fitted", ""] + [f"![{p}]({p})" for p in pngs]
    (out / "inspection.md").write_text("\n".join(lines) + "\n")
    return {"report": str(out / "inspection.md"), "json": str(out / "inspection.json"),
            "plots": [str(out / p) for p in pngs + [iv]]}


def _left_right_lines(lr: list, lr_cfg: dict) -> list[str]:
    """The report's left-against-right section: one line per axle saying in words what its left-minus-right
    oil level and 95 % interval mean (:func:`.estimate.left_right`)."""
    if not lr:
        return []
    thr = lr_cfg.get("asymmetric_min_difference")
    out = ["", "## Left against right", "",
           "Per axle, the left minus the right damper's oil level with its 95 % interval (the workshop's "
           "comparison of an axle's two dampers, as the EUSAMA test judges their difference besides each "
           "wheel's value). Flagged **asymmetric** when the interval excludes zero and the two are more than "
           + ("the configured limit" if thr is None else f"{thr:.2f}") + " apart.", ""]
    for e in lr:
        out.append(f"- {'**asymmetric** ' if e['asymmetric'] else ''}{e['reason']}")
    return out


def _protocol_lines(p: dict) -> list[str]:
    """The report's test-protocol section: each drive's crossing against what the inspection is validated
    for, and the warnings (speeds in km/h and heights in cm for reading; SI in the JSON)."""
    if not p:
        return []
    v = p["validated_for"]
    out = ["", "## Test protocol", "",
           f"Validated for crossings at {v['speed_m_s'][0] * KMH:.0f}-{v['speed_m_s'][1] * KMH:.0f} km/h over "
           f"{v['bump_height_m'][0] * CM:.0f}-{v['bump_height_m'][1] * CM:.0f} cm bumps, both axles crossing.",
           "",
           "| drive | speed [km/h] | bump height [cm] | peak damper velocity front / rear [m/s] |", "|---|---|---|---|"]
    for s in p["seen"]:
        h = "-" if s["bump_height_m"] is None else f"{s['bump_height_m'] * CM:.1f}"
        pv = s["peak_damper_velocity_m_s"]
        out.append(f"| {s['drive']} | {s['speed_m_s'] * KMH:.1f} | {h} | {pv['front']:.2f} / {pv['rear']:.2f} |")
    out.append("")
    if p["warnings"]:
        out += [f"- **outside the protocol**: {w['drive'] + ': ' if w['drive'] else ''}{w['reason']}"
                for w in p["warnings"]]
        out.append(f"- the intervals carry a model-form sd of {p['model_form_sd']:.3f} (oil fraction), widened "
                   "because the inspection was not validated there")
    else:
        out.append("- every drive within the protocol")
    return out

