"""Figures of a study: metric vs a swept parameter (one panel per slice, one line per value of another
parameter); for drive studies, RMSE per drive and variant."""
from __future__ import annotations

import math
from pathlib import Path
from collections.abc import Sequence

import numpy as np

from .spec import StudySpec

LABELS = {"oil_front": "front damper oil level (FL, FR) [-]", "oil_rear": "rear damper oil level (RL, RR) [-]",
          "bump_height": "bump height [m]", "bump_length": "bump length [m]", "speed": "speed [m/s]",
          "steer_amplitude": "steering amplitude [rad]", "steer_frequency": "steering frequency [Hz]",
          **{f"oil_{w}": f"oil level {w} [-]" for w in ("FL", "FR", "RL", "RR")}}


def _label(col: str) -> str:
    return (col.replace("_deg_s", " [deg/s]").replace("_s", " [s]") if col.endswith(("_deg_s", "_s"))
            else col).replace("_", " ")


def plot_sweep(spec: StudySpec, cols: dict, path: Path) -> Path:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cfg = spec.data["plot"]
    ys, panels, lines = cfg["y"], cfg["panels"], cfg["lines"]
    ok = np.array([bool(x) for x in cols["ok"]])
    fig, axes = plt.subplots(len(ys), len(panels), figsize=(5.2 * len(panels), 3.6 * len(ys)),
                             squeeze=False, sharex="col")
    line_vals = sorted(set(cols[lines])) if lines else [None]
    for j, p in enumerate(panels):
        sel = ok.copy()
        for k, v in p["fixed"].items():
            sel &= np.array([x == v for x in cols[k]])
        # parameters neither on the axis, the lines nor fixed: average over them (said in the title)
        others = [k for k in spec.swept if k not in (p["x"], lines, *p["fixed"]) and len(set(cols[k])) > 1]
        for i, y in enumerate(ys):
            ax = axes[i, j]
            for lv in line_vals:
                m = sel & (np.array([x == lv for x in cols[lines]]) if lines else True)
                xs = sorted(set(np.array(cols[p["x"]], dtype=object)[m]))
                vals = []
                for xv in xs:
                    mm = m & np.array([x == xv for x in cols[p["x"]]])
                    v = np.array(cols[y], float)[mm]
                    vals.append(float(np.mean(v)) if v.size else math.nan)
                ax.plot(xs, vals, marker="o", ms=3.5, label=f"{lines} = {lv:g}" if lines else None)
            ax.set_ylabel(_label(y))
            ax.grid(True, alpha=0.3)
            if i == 0:
                title = p["title"] or ", ".join(f"{k} = {v}" for k, v in p["fixed"].items())
                if others:
                    title += f" (mean over {', '.join(others)})"
                ax.set_title(title, fontsize=10)
            if i == len(ys) - 1:
                ax.set_xlabel(LABELS.get(p["x"], p["x"]))
    if lines:
        axes[0, 0].legend(fontsize=8)
    fig.suptitle(cfg["title"] or f"{spec.name}: {spec.data['maneuver'].replace('_', ' ')}", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_drives(rows: Sequence[dict], variants: Sequence[str], path: Path) -> Path:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    good = [r for r in rows if not r.get("error")]
    names = [Path(r["file"]).stem for r in good]
    fig, ax = plt.subplots(figsize=(max(6.0, 0.9 * len(good) + 2), 4.2))
    w = 0.8 / len(variants)
    x = np.arange(len(good))
    for k, v in enumerate(variants):
        ax.bar(x + (k - (len(variants) - 1) / 2) * w, [r[f"rmse_{v}_deg_s"] for r in good], w, label=v)
    ax.set_xticks(x, names, rotation=30, ha="right", fontsize=8)
    ax.set_ylabel("RMSE of the drive's signal [deg/s]")
    ax.set_title("measured vs simulated, per drive and friction variant (pitch rate: bump, roll rate: steer)",
                 fontsize=9)
    ax.legend(fontsize=8)
    ax.grid(True, axis="y", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
