"""The units of imported data and their factors to SI: the one table that topic maps
(:mod:`~susp_sim_ros.io.topic_map`), channel maps and MDF4 channel units
(:mod:`~susp_sim_ros.analysis.measurement_import`) and CSV column suffixes
(:mod:`~susp_sim_ros.analysis.csv_import`) read. ``value_SI = raw * FACTORS[unit]``.

Each unit's factor is declared once, in :data:`FACTORS`. Sources:

- ``deg`` (and ``deg/s``): pi/180 rad, exact by definition (SI Brochure, 9th ed. 2019, Table 8);
- ``km/h``: 1000 m / 3600 s = 1/3.6 m/s, exact (SI Brochure Table 8: h = 3600 s);
- ``mph``: 1 international mile (1609.344 m, exact since the 1959 international yard and pound
  agreement) per hour = 0.44704 m/s, exact (NIST SP 811, 2008, appendix B.8);
- ``g``: standard acceleration of gravity 9.80665 m/s^2, exact by definition (3rd CGPM, 1901);
- ``cm``, ``mm``: SI prefixes centi (1e-2) and milli (1e-3) (SI Brochure Table 7); ``%``: per cent, 0.01;
- ``rad``, ``m/s``, ``m``, ``rad/s``, ``m/s^2``, ``s``, ``1``: SI, factor 1.

:data:`UNITS` groups the accepted spellings by kind of quantity (angle, speed, length, rate, accel,
fraction), as topic maps and channel maps name them; :data:`UNIT_ALIASES` maps the spellings measurement
systems write into MDF4 files (``°/s``, ``kph``, ``m/s²`` ...) onto these names. A file layer module:
it imports nothing of this package.
"""
from __future__ import annotations

import math

G_STANDARD = 9.80665  # m/s^2 per g, standard gravity (CGPM 1901)

#: SI factor of each unit name, declared once (module docstring for the sources).
FACTORS: dict[str, float] = {
    "rad": 1.0, "deg": math.pi / 180.0,                          # angle
    "m/s": 1.0, "km/h": 1.0 / 3.6, "mph": 0.44704,               # speed
    "m": 1.0, "cm": 0.01, "mm": 0.001,                           # length
    "rad/s": 1.0, "deg/s": math.pi / 180.0,                      # angular rate
    "m/s^2": 1.0, "g": G_STANDARD,                               # acceleration
    "1": 1.0, "%": 0.01,                                         # fraction
    "s": 1.0,                                                    # time (CSV ``time_s``)
}

#: Unit strings as measurement systems write them -> this package's unit names (keys of :data:`FACTORS`;
#: ``""``: no unit stored, read as SI).
UNIT_ALIASES = {"°": "deg", "grad": "deg", "degree": "deg", "deg": "deg", "rad": "rad",
                "°/s": "deg/s", "deg/s": "deg/s", "grad/s": "deg/s", "rad/s": "rad/s", "1/s": "rad/s",
                "km/h": "km/h", "kph": "km/h", "kmh": "km/h", "m/s": "m/s", "mph": "mph",
                "m/s^2": "m/s^2", "m/s2": "m/s^2", "m/s²": "m/s^2", "m/(s^2)": "m/s^2", "g": "g",
                "m": "m", "mm": "mm", "cm": "cm", "": ""}

# the spellings a topic map or channel map accepts for each kind of quantity, in the order error messages
# list them
_SPELLINGS: dict[str, tuple[str, ...]] = {
    "angle": ("rad", "deg"),
    "speed": ("m/s", "km/h", "mph"),
    "length": ("m", "cm", "mm"),
    "rate": ("rad/s", "deg/s"),
    "accel": ("m/s^2", "m/s2", "g"),
    "fraction": ("1", "%"),
}
#: kind of quantity -> {accepted spelling: SI factor} (value_SI = raw * scale * factor)
UNITS: dict[str, dict[str, float]] = {kind: {s: FACTORS[UNIT_ALIASES.get(s, s)] for s in spellings}
                                      for kind, spellings in _SPELLINGS.items()}

__all__ = ["FACTORS", "G_STANDARD", "UNITS", "UNIT_ALIASES"]
