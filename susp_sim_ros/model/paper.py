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

from dataclasses import dataclass

from ..errors import ConfigError


@dataclass(frozen=True)
class ManeuverKind:
    """One of the paper's maneuvers: everything the code needs to know about it, in one entry.

    ``factory`` names the function of :mod:`susp_sim_ros.model.maneuvers` that builds it (with the values
    of ``config/maneuvers.yaml``, section ``name``); ``config_keys`` maps each of that function's keywords
    to the key of its default value in that section; ``sweep_arguments`` maps each study parameter of this
    maneuver to that function's keyword; ``uses_wheelbase``: the factory takes the vehicle's wheelbase
    (the drive lasts until the rear axle has passed the excitation). A drive's free-text ``maneuver``
    metadata is recognised as this kind when it starts with one of its :attr:`names`
    (:func:`classify_maneuver`)."""

    name: str
    aliases: tuple[str, ...]
    factory: str
    #: the kernel output label the maneuver is compared on (``model/layout.py`` ``OUTPUT_LABELS``)
    primary_output: str
    #: which body motion it excites ("pitch" or "roll")
    excites: str
    #: what excites it: the road profile (a bump) or the steering wheel
    needs_road_profile: bool
    uses_wheelbase: bool
    #: the analysis window of the validation (``analysis/validation.py``): "bump" or "steering"
    window: str
    #: the ``maneuver`` metadata of the synthetic drives (``bags/*.mcap``)
    label: str
    #: the paper measures the ring-out after the excitation (model-spec 5)
    ring_out: bool
    sweep_arguments: tuple[tuple[str, str], ...]
    #: (factory keyword, key in ``config/maneuvers.yaml``) of each default value the factory reads
    config_keys: tuple[tuple[str, str], ...]
    #: the paper's headline finding is on this maneuver (``dahl_only`` 65 times the RMSE of ``full`` with
    #: oil-empty rear dampers; the findings of ``susp validate --study``)
    headline: bool = False

    @property
    def primary_signal(self) -> str:
        """The signal name of the JSON outputs (``primary_output`` in lower case)."""
        return self.primary_output.lower()

    @property
    def config_section(self) -> str:
        """Its section in ``config/maneuvers.yaml`` (its name): the default values of ``config_keys``."""
        return self.name

    @property
    def steers(self) -> bool:
        """The drive turns the steering wheel (a lateral wheel force)."""
        return not self.needs_road_profile

    @property
    def names(self) -> tuple[str, ...]:
        return (self.name, *self.aliases)


#: the paper's maneuvers, in the paper's order (Table 5): the one registry (docs/architecture.md "Registries")
MANEUVER_KINDS: dict[str, ManeuverKind] = {k.name: k for k in (
    ManeuverKind("bump_crossing", ("bump",), "bump_crossing", "PITCH_RATE", "pitch", needs_road_profile=True,
                 uses_wheelbase=True, window="bump", label="bump_crossing_8kmh", ring_out=True,
                 sweep_arguments=(("speed", "speed"), ("bump_height", "height"), ("bump_length", "length")),
                 config_keys=(("speed", "speed"), ("height", "bump_height"), ("length", "bump_length"),
                              ("start", "bump_start"), ("settle_time", "settle_time")), headline=True),
    ManeuverKind("sine_steer", ("sine",), "sine_steer", "ROLL_RATE", "roll", needs_road_profile=False,
                 uses_wheelbase=False, window="steering", label="sine_steer_50kmh", ring_out=False,
                 sweep_arguments=(("speed", "speed"), ("steer_amplitude", "amplitude"),
                                  ("steer_frequency", "frequency")),
                 config_keys=(("speed", "speed"), ("amplitude", "amplitude"), ("frequency", "frequency"),
                              ("periods", "periods"), ("lead_time", "lead_time"),
                              ("settle_time", "settle_time"))),
)}
#: the entries by what they are, for code that needs one particular maneuver (its factory, its findings)
BUMP_CROSSING = MANEUVER_KINDS["bump_crossing"]
SINE_STEER = MANEUVER_KINDS["sine_steer"]
#: the maneuver of the paper's headline finding (the entry with ``headline``)
HEADLINE_MANEUVER = next(k for k in MANEUVER_KINDS.values() if k.headline)
#: the maneuvers whose ring-out the paper measures, in registry order
RING_OUT_MANEUVERS = tuple(m for m, k in MANEUVER_KINDS.items() if k.ring_out)
MANEUVERS = tuple(MANEUVER_KINDS)
DEFAULT_MANEUVER = MANEUVERS[0]
#: every name a maneuver is known by: the aliases first, then the full names
MANEUVER_CHOICES = tuple(a for k in MANEUVER_KINDS.values() for a in k.aliases) + MANEUVERS
#: the study parameters that set a maneuver's geometry, in registry order
MANEUVER_PARAMETERS = tuple(dict.fromkeys(p for k in MANEUVER_KINDS.values() for p, _ in k.sweep_arguments))


def maneuver_kind(name: str) -> ManeuverKind:
    """The registry entry of a maneuver name or alias; :class:`ConfigError` naming the known ones."""
    for kind in MANEUVER_KINDS.values():
        if name in kind.names:
            return kind
    known = " or ".join(f"{k.name} ({', '.join(k.aliases)})" for k in MANEUVER_KINDS.values())
    raise ConfigError(f"unknown maneuver {name!r}: expected {known}")


def classify_maneuver(text: str | None) -> str | None:
    """The maneuver a free-text name starts with (any of its names, case-insensitive), or ``None``."""
    t = (text or "").strip().lower()
    for kind in MANEUVER_KINDS.values():
        if any(t.startswith(n) for n in kind.names):
            return kind.name
    return None


#: the paper's vehicle states (``config/maneuvers.yaml`` ``states``: the oil levels of each,
#: :func:`~susp_sim_ros.model.maneuvers.vehicle_state`); code that means one of them names its constant
STATES = (INTACT, FRONT_EMPTY, REAR_EMPTY) = ("intact", "front_empty", "rear_empty")
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
PRIMARY_OUTPUT = {m: k.primary_output for m, k in MANEUVER_KINDS.items()}
PRIMARY_SIGNAL = {m: k.primary_signal for m, k in MANEUVER_KINDS.items()}
