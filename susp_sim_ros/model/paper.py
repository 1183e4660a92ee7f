"""Constants of the paper, in one place: its two maneuvers, the three vehicle states of its test drives,
its four friction-model variants with the paper's model numbers, the IMU signals compared and the
signal each maneuver is compared on (interface.md: ``susp validate --study`` tables and SIGNAL names;
model-spec section 5).

The paper validates on slow bump crossings (8 km/h) judged on the pitch rate and sine steering
(50 km/h) judged on the roll rate, with intact dampers and with oil-empty front or rear dampers, and
compares the full friction model against variants without the horizontal-force scaling, without the
velocity scaling, and with plain Dahl friction.
"""
from __future__ import annotations

MANEUVERS = ("bump_crossing", "sine_steer")
STATES = ("intact", "front_empty", "rear_empty")
VARIANTS = ("full", "no_horizontal", "no_velocity", "dahl_only")
#: the paper's name of each variant (Table 5: models 1 to 4)
VARIANT_LABEL = {"full": "Model 1 full", "no_horizontal": "Model 2 no horizontal",
                 "no_velocity": "Model 3 no velocity", "dahl_only": "Model 4 Dahl only"}
#: the IMU signals compared (interface.md SIGNAL): gyro about x, y, z [rad/s], then specific force along
#: x, y, z [m/s^2], REP-103 body axes
IMU_SIGNALS = ("roll_rate", "pitch_rate", "yaw_rate", "accel_x", "accel_y", "accel_z")
#: the kernel output label of each IMU signal (``model/layout.py`` ``OUTPUT_LABELS``), in the same order
IMU_OUTPUTS = ("ROLL_RATE", "PITCH_RATE", "YAW_RATE", "AX_SF", "AY_SF", "AZ_SF")
#: the kernel output label each maneuver is compared on (lower case: the signal name of the JSON outputs)
PRIMARY_OUTPUT = {"bump_crossing": "PITCH_RATE", "sine_steer": "ROLL_RATE"}
PRIMARY_SIGNAL = {m: label.lower() for m, label in PRIMARY_OUTPUT.items()}
