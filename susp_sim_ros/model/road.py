"""Road elevation along the path: left and right wheel tracks (interface: ``/road/profile``)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import SuspInputError


@dataclass(frozen=True)
class RoadProfile:
    """Elevation ``zl``/``zr`` [m] of the left/right tracks at path coordinates ``s`` [m].

    ``s`` strictly increasing; flat road (z = 0) outside. The front axle is at s = 0 when a drive starts
    and the rear axle trails by the wheelbase (interface.md).
    """

    s: np.ndarray
    zl: np.ndarray
    zr: np.ndarray

    def __post_init__(self):
        s, zl, zr = (np.ascontiguousarray(x, dtype=float) for x in (self.s, self.zl, self.zr))
        if s.ndim != 1 or zl.shape != s.shape or zr.shape != s.shape:
            raise SuspInputError(f"road profile: s, zl, zr must be 1-D of equal length, got "
                                 f"{s.shape}, {zl.shape}, {zr.shape}")
        if not (np.all(np.isfinite(s)) and np.all(np.isfinite(zl)) and np.all(np.isfinite(zr))):
            raise SuspInputError("road profile: values must be finite")
        if s.size > 1 and np.any(np.diff(s) <= 0):
            raise SuspInputError("road profile: path coordinate s must be strictly increasing")
        object.__setattr__(self, "s", s)
        object.__setattr__(self, "zl", zl)
        object.__setattr__(self, "zr", zr)

    @classmethod
    def flat(cls) -> "RoadProfile":
        return cls(np.zeros(0), np.zeros(0), np.zeros(0))

    @classmethod
    def from_flat_array(cls, data, n: int) -> "RoadProfile":
        """From the interface's row-major ``[s.., zl.., zr..]`` layout with ``n`` samples."""
        data = np.asarray(data, dtype=float)
        if data.size != 3 * n:
            raise SuspInputError(f"/road/profile: expected 3*{n} = {3 * n} values, got {data.size}")
        return cls(data[:n], data[n:2 * n], data[2 * n:])

    def to_flat_array(self) -> np.ndarray:
        return np.concatenate([self.s, self.zl, self.zr])

    def mirrored(self) -> "RoadProfile":
        """Left and right tracks swapped (for symmetry checks)."""
        return RoadProfile(self.s, self.zr, self.zl)

    def kernel_arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
        """Arrays for the kernel: (s, zl, zr, n), at least 2 long (n = 0 means flat)."""
        n = self.s.size
        if n < 2:
            z = np.zeros(2)
            return np.array([0.0, 1.0]), z, z.copy(), 0
        return self.s, self.zl, self.zr, n

    def __len__(self) -> int:
        return int(self.s.size)


def cosine_bump(height: float, length: float, start: float, both_tracks: bool = True,
                spacing: float = 0.01) -> RoadProfile:
    """A single cosine bump ``height`` [m] high and ``length`` [m] long starting at path ``start`` [m]."""
    n = max(int(round(length / spacing)), 2) + 1
    x = np.linspace(0.0, length, n)
    z = 0.5 * height * (1.0 - np.cos(2.0 * np.pi * x / length))
    s = start + x
    return RoadProfile(s, z, z.copy() if both_tracks else np.zeros_like(z))
