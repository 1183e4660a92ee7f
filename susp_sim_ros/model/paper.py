"""Constants of the paper, in one place: its two maneuvers, the three vehicle states of its test drives,
its four friction-model variants and the signal each maneuver is compared on (interface.md: ``susp
validate --study`` tables; model-spec section 5).

The paper validates on slow bump crossings (8 km/h) judged on the pitch rate and sine steering
(50 km/h) judged on the roll rate, with intact dampers and with oil-empty front or rear dampers, and
compares the full friction model against variants without the horizontal-force scaling, without the
velocity scaling, and with plain Dahl friction.
"""
from __future__ import annotations

MANEUVERS = ("bump_crossing", "sine_steer")
STATES = ("intact", "front_empty", "rear_empty")
VARIANTS = ("full", "no_horizontal", "no_velocity", "dahl_only")
#: the kernel output label each maneuver is compared on (lower case: the signal name of the JSON outputs)
PRIMARY_OUTPUT = {"bump_crossing": "PITCH_RATE", "sine_steer": "ROLL_RATE"}
PRIMARY_SIGNAL = {m: label.lower() for m, label in PRIMARY_OUTPUT.items()}
