"""Read the node's ``/sim/suspension`` back from a recording (layout in :mod:`.messages`).

:func:`suspension_from_recording` gives the per-wheel suspension state as a :class:`~.drive.Series` of
values ``(n, 4, Q)``: wheels FL, FR, RL, RR, quantities :data:`~.messages.SUSPENSION_QUANTITIES` (SI),
at the messages' log times. A message whose layout is not [wheel 4, quantity Q] or whose data does not
fit it, or a non-finite value, is a :class:`~susp_sim_ros.errors.RecordingError` naming file, topic and
log time.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import RecordingError
from . import messages as M
from .drive import Series, _fields
from .reader import Recording

SIM_SUSPENSION = "/sim/suspension"
N_WHEELS = 4
N_QUANTITIES = len(M.SUSPENSION_QUANTITIES)


def suspension_array(msg: Any) -> np.ndarray:
    """``(4, Q)`` array of a decoded ``/sim/suspension`` message; ValueError naming what is wrong."""
    sizes = [int(d.size) for d in msg.layout.dim]
    if sizes != [N_WHEELS, N_QUANTITIES]:
        raise ValueError(f"layout dims {sizes}, expected [wheel {N_WHEELS}, quantity {N_QUANTITIES}]")
    off = int(msg.layout.data_offset)
    data = np.asarray(list(msg.data), dtype=float)[off:]
    if data.size != N_WHEELS * N_QUANTITIES:
        raise ValueError(f"{data.size} values after data_offset {off}, expected {N_WHEELS * N_QUANTITIES}")
    if not np.all(np.isfinite(data)):
        raise ValueError("non-finite value")
    return data.reshape(N_WHEELS, N_QUANTITIES)


def has_suspension(rec: Recording, topic: str = SIM_SUSPENSION) -> bool:
    return bool(rec.by_topic(topic))


def suspension_from_recording(rec: Recording, topic: str = SIM_SUSPENSION) -> Series:
    """The ``/sim/suspension`` samples of ``rec`` as a Series of ``(n, 4, Q)`` values (RecordingError if
    there are none or a message is malformed)."""
    if not rec.by_topic(topic):
        raise RecordingError(f"{rec.path}: no messages on topic {topic}")
    items = _fields(rec, topic, suspension_array, M.FLOAT64_ARRAY)
    t = np.array([t for t, _ in items], dtype=np.int64)
    v = np.array([x for _, x in items], dtype=float).reshape(-1, N_WHEELS, N_QUANTITIES)
    return Series(t, v)


__all__ = ["SIM_SUSPENSION", "has_suspension", "suspension_array", "suspension_from_recording"]
