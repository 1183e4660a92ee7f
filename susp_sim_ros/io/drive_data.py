"""What a recorded test drive is (interface.md, "A recorded test drive"): its topics, the input limits,
the series it holds and :class:`TestDrive`. Reading and writing them: :mod:`.drive`; checking them:
:mod:`.integrity` (both import this module, which imports neither).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import RecordingError, SuspInputError
from ..model.params import load_settings
from ..model.road import RoadProfile

SPEED = "/vehicle/speed"
STEERING = "/vehicle/steering_wheel_angle"
ROAD_PROFILE = "/road/profile"
WHEEL_HEIGHTS = "/road/wheel_heights"
DAMPER_COMMAND = "/vehicle/damper_command"  # semi-active valve command [FL, FR, RL, RR] in [0, 1] (optional)
IMU = "/imu/data"
SIM_IMU = "/sim/imu/data"

#: The input limits, declared once with unit and source in ``config/integrity.yaml`` (section ``limits``):
#: values beyond them are absurd; the node rejects such a message (SimCore), the integrity check of the
#: offline tools drops such samples (``out_of_range``, :mod:`.integrity`), the CSV import refuses them.
LIMITS = load_settings("integrity.yaml")
MAX_SPEED = float(LIMITS["limits.speed_max"])                # m/s (speeds in [0, MAX_SPEED])
MAX_STEERING = float(LIMITS["limits.steering_max"])          # rad, |steering-wheel angle|
MAX_WHEEL_HEIGHT = float(LIMITS["limits.wheel_height_max"])  # m, |road height under a wheel / profile elevation|
#: the range of a semi-active valve command [1] (interface.md, "Added inputs": 0 softest, 1 hardest)
DAMPER_COMMAND_RANGE = (0.0, 1.0)


@dataclass
class Series:
    """Samples ``values`` (1-D, or (n, k)) at times ``t_ns`` (int64 nanoseconds)."""

    t_ns: np.ndarray
    values: np.ndarray

    def __post_init__(self):
        self.t_ns = np.asarray(self.t_ns, dtype=np.int64)
        self.values = np.asarray(self.values, dtype=float)
        if self.values.shape[:1] != self.t_ns.shape:
            raise SuspInputError(f"Series: {self.t_ns.size} times but values of shape {self.values.shape}")

    def __len__(self) -> int:
        return int(self.t_ns.size)


@dataclass
class ImuSeries:
    """IMU samples: ``gyro`` (n, 3) roll/pitch/yaw rate [rad/s], ``accel`` (n, 3) specific force [m/s^2]."""

    t_ns: np.ndarray
    gyro: np.ndarray
    accel: np.ndarray

    def __post_init__(self):
        self.t_ns = np.asarray(self.t_ns, dtype=np.int64)
        self.gyro = np.asarray(self.gyro, dtype=float).reshape(-1, 3)
        self.accel = np.asarray(self.accel, dtype=float).reshape(-1, 3)
        if not (self.gyro.shape[0] == self.accel.shape[0] == self.t_ns.size):
            raise SuspInputError(f"ImuSeries: {self.t_ns.size} times, gyro {self.gyro.shape}, "
                                 f"accel {self.accel.shape}")

    def __len__(self) -> int:
        return int(self.t_ns.size)

    @property
    def t_s(self) -> np.ndarray:
        return self.t_ns.astype(float) * 1e-9


OIL_UNKNOWN = "unknown"  # interface.md: an inspection drive's damper state is what is to be found


def oil_unknown(text: str | None) -> bool:
    """Whether a ``damper_oil_level`` value says the state is not known (an inspection drive)."""
    return text is not None and str(text).strip().lower() == OIL_UNKNOWN


def parse_oil(text: str | None, what: str = "test_drive metadata damper_oil_level") -> tuple[float, ...]:
    """``"1,1,0,0"`` -> (1.0, 1.0, 0.0, 0.0); missing -> intact. ``"unknown"`` is not a value: check
    :func:`oil_unknown` first (:meth:`TestDrive.oil_levels` assumes intact for it)."""
    if text is None or str(text).strip() == "":
        return (1.0, 1.0, 1.0, 1.0)
    try:
        vals = tuple(float(x) for x in str(text).replace(" ", "").split(","))
    except ValueError:
        vals = ()
    if len(vals) != 4 or not all(np.isfinite(v) and 0.0 <= v <= 1.0 for v in vals):
        raise RecordingError(f"{what}: expected four comma-separated fractions FL,FR,RL,RR in [0, 1], "
                             f"got {text!r}")
    return vals


@dataclass
class TestDrive:
    """A recorded (or synthetic) test drive: the inputs of the model and what was measured."""

    __test__ = False  # not a pytest test class

    metadata: dict[str, str]
    speed: Series
    steering: Series
    road: RoadProfile | None = None
    wheel_heights: Series | None = None
    imu: ImuSeries | None = None
    extra: dict[str, Any] = field(default_factory=dict)
    damper_command: Series | None = None  # (n, 4) valve commands; None: passive dampers

    @property
    def oil_known(self) -> bool:
        """False for an inspection drive (``damper_oil_level: unknown``)."""
        return not oil_unknown(self.metadata.get("damper_oil_level"))

    def oil_levels(self) -> tuple[float, float, float, float]:
        """The recorded oil levels; intact when unknown (:attr:`oil_known` tells, callers say so)."""
        if not self.oil_known:
            return (1.0, 1.0, 1.0, 1.0)
        return parse_oil(self.metadata.get("damper_oil_level"))  # type: ignore[return-value]

    @property
    def t0_ns(self) -> int:
        starts = [s.t_ns[0] for s in (self.speed, self.steering) if len(s)]
        return int(min(starts)) if starts else 0

    @property
    def t_end_ns(self) -> int:
        ends = [s.t_ns[-1] for s in (self.speed, self.steering, self.wheel_heights) if s is not None and len(s)]
        return int(max(ends)) if ends else self.t0_ns

    @property
    def duration_s(self) -> float:
        return (self.t_end_ns - self.t0_ns) * 1e-9


# ---- reading -------------------------------------------------------------------------------------
#: Message type each topic must have when present (a recording with another type there is rejected).
