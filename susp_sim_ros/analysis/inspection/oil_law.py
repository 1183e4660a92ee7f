"""The damper type's oil law: how much of its force a damper keeps as it loses oil (issue 27).

The model blends a damper's intact and oil-empty hydraulic curves, and scales its friction, by one
weight (model-spec 1, "oil level blends between the intact and oil-empty curves"), and takes that weight
to be the oil level itself. Whether a real damper keeps half its force at half its oil is a property of
its design (valve and reservoir layout, where the gas enters), not something a drive can show: a damper
that keeps ``w(o)`` of its force at oil level ``o`` moves the car in every force exactly as a damper of
the model filled to ``w(o)`` (benchmarks/RESULTS.md, 2026-11-27: the truth family's quadratic-law form
reads every partly filled damper as about the square of its level, and no crossing can change that).
So the inspection fits the model's weight -- the damper's remaining force fraction -- and reads it as an
oil level through the damper type's law, measured on a damper rig: the damper drained in steps, its
force at one rig velocity at each step, as the fraction ``(F(o) - F(0)) / (F(1) - F(0))`` of the way
from the oil-empty to the intact force. Without such a measurement the law is the model's own (the
identity) and the report says so.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np
from scipy.interpolate import PchipInterpolator

from ...errors import ConfigError

MODEL_LAW_SOURCE = "the model's own (model-spec 1: the force fraction equals the oil level); no rig measurement given"


@dataclass(frozen=True)
class OilLaw:
    """A damper type's oil law: at each oil level ``oil`` [-] (0 empty, 1 intact), the ``force_fraction``
    [-] of the way from the oil-empty to the intact force it keeps on the rig. Both strictly increasing
    from 0 to 1; between the points monotone cubic (PCHIP, so the law's inverse is monotone too)."""

    oil: tuple[float, ...] = (0.0, 1.0)
    force_fraction: tuple[float, ...] = (0.0, 1.0)
    source: str = MODEL_LAW_SOURCE

    def __post_init__(self) -> None:
        o, f = np.asarray(self.oil, float), np.asarray(self.force_fraction, float)
        where = f"damper oil law ({self.source})"
        if o.ndim != 1 or o.shape != f.shape or o.size < 2:
            raise ConfigError(f"{where}: expected as many oil levels as force fractions, at least two, got "
                              f"{list(self.oil)} and {list(self.force_fraction)}")
        if not (np.all(np.isfinite(o)) and np.all(np.isfinite(f))):
            raise ConfigError(f"{where}: oil levels and force fractions must be finite numbers")
        for name, v in (("oil levels", o), ("force fractions", f)):
            if abs(v[0]) > 1e-9 or abs(v[-1] - 1.0) > 1e-9 or np.any(np.diff(v) <= 0):
                raise ConfigError(f"{where}: the {name} must rise strictly from 0 (oil-empty) to 1 (intact), "
                                  f"got {v.tolist()}")

    @property
    def is_model_law(self) -> bool:
        """Whether this is the identity (the model's own assumption)."""
        return np.allclose(self.oil, self.force_fraction)

    @cached_property
    def _inverse(self) -> PchipInterpolator:
        """Oil level as a function of the force fraction (built once per law)."""
        return PchipInterpolator(np.asarray(self.force_fraction, float), np.asarray(self.oil, float))

    def level(self, force_fraction: float) -> float:
        """The oil level [-] of a damper keeping ``force_fraction`` [-] of its force (clipped to [0, 1])."""
        return float(np.clip(self._inverse(float(np.clip(force_fraction, 0.0, 1.0))), 0.0, 1.0))

    def slope(self, force_fraction: float) -> float:
        """d(oil level) / d(force fraction) [-] at ``force_fraction``: what carries an sd of the fitted force
        fraction into one of the oil level (the linearisation the intervals' combinations use)."""
        return float(self._inverse.derivative()(float(np.clip(force_fraction, 0.0, 1.0))))

    def to_json(self) -> dict:
        return {"oil": list(self.oil), "force_fraction": list(self.force_fraction), "source": self.source,
                "model_law": self.is_model_law}

    @classmethod
    def parse(cls, text: str, source: str = "--oil-law") -> "OilLaw":
        """``OIL:FRACTION,...`` (e.g. ``0:0,0.5:0.25,1:1``), the rig test's points."""
        try:
            pairs = [tuple(float(x) for x in item.split(":")) for item in text.split(",") if item.strip()]
        except ValueError:
            pairs = []
        if not pairs or any(len(p) != 2 for p in pairs):
            raise ConfigError(f"{source}: expected the rig test's points as OIL:FORCE_FRACTION,... "
                              f"(e.g. 0:0,0.5:0.25,1:1), got {text!r}")
        return cls(tuple(p[0] for p in pairs), tuple(p[1] for p in pairs), source)

    @classmethod
    def from_settings(cls, cfg: dict) -> "OilLaw":
        """The law of the inspection settings (``damper_type.oil_law``), the model's own when the settings
        have none (a settings file of before issue 27)."""
        entry = cfg.get("damper_type", {}).get("oil_law")
        if entry is None:
            return cls()
        try:
            oil, frac = entry["oil"], entry["force_fraction"]
        except (KeyError, TypeError):
            raise ConfigError(f"inspection settings damper_type.oil_law: expected {{oil: [...], force_fraction: "
                              f"[...]}}, got {entry!r}") from None
        law = cls(tuple(float(v) for v in oil), tuple(float(v) for v in frac),
                  str(entry.get("source", "inspection settings damper_type.oil_law")))
        return replace(law, source=MODEL_LAW_SOURCE) if law.is_model_law else law
