"""Import measurement files into a recorded test drive (MCAP, interface.md): ASAM MDF4 drives (through
``asammdf``), CSV drives (:mod:`~susp_sim_ros.analysis.csv_import`), OpenCRG roads (through ``pyopencrg``)
and CSV roads.

MDF4 channels
=============
Without a channel map, the MDF4 file's channels are found by the CSV column names (``speed_km_h``,
``steering_wheel_angle_deg``, ``roll_rate_deg_s``, ... see :mod:`~susp_sim_ros.analysis.csv_import`; the
suffix gives the unit), in REP-103 / ISO 8855 axes. A channel map (``--channel-map MAP.yaml``) names them
as a measurement system does::

    speed:                {channel: VehSpd, unit: km/h}
    steering_wheel_angle: {channel: SteerWhlAng, unit: deg}        # scale: -1 if positive to the right
    imu:
      frame: sae_j670            # flu | iso8855 | frd | sae_j670 | {rpy_deg: [r, p, y]} (see topic_map)
      gyro_x: {channel: RollRate, unit: deg/s}
      gyro_y: {channel: PitchRate, unit: deg/s}
      gyro_z: {channel: YawRate, unit: deg/s}
      accel_x: {channel: AccX, unit: g}                            # the three accelerations: optional
      accel_y: {channel: AccY, unit: g}
      accel_z: {channel: AccZ, unit: g}
    wheel_heights: {fl: {channel: ZFL, unit: mm}, fr: ..., rl: ..., rr: ...}   # optional (rig drives)

An entry is ``{channel: NAME, unit: U, scale: S}`` or just the channel name. Without ``unit`` the unit
stored with the MDF4 channel is used when it is one this package knows (``km/h``, ``deg``, ``°/s``, ``g``
...), SI when it is empty, else an error naming the channel. Each input keeps its own time base; the six IMU
channels are interpolated linearly onto the roll-rate (``gyro_x``) channel's times where their time bases
differ. Times are MDF4 times since the measurement start (as the CSV's ``time_s``).

Roads
=====
``--road ROAD.crg`` reads an OpenCRG file with ``pyopencrg`` (chosen over ``crgutils``: it reads and writes
all four CRG formats, checks files, is Apache-2.0 with a public repository and issue tracker; ``crgutils``
reads only and has neither). The road grid's elevation (``uv_to_z(..., grid_only=True)``: without the
reference line's slope and banking, i.e. relative to flat road) is sampled along ``u`` at the file's
``u`` spacing on the two wheel tracks ``v = +-track/2`` (OpenCRG's ``v`` is positive to the left; the track
is the vehicle's front track), and ``s = u - u0`` with ``u0`` the road's ``u`` under the front axle when the
drive starts (``--road-start-u``; default the file's first ``u``). ``--road ROAD.csv`` reads the CSV road layout.

The ``test_drive`` metadata records what was converted: ``import_source``, ``unit_conversion``,
``frame_conversion`` and ``road_source`` (plus ``vehicle``, ``maneuver``, ``damper_oil_level``, ``source``,
``notes`` as for the CSV import).
"""
from __future__ import annotations

import importlib
import os
import math
from pathlib import Path
from types import ModuleType
from typing import Any
from collections.abc import Mapping

import numpy as np

from ..errors import MeasurementImportError, TopicMapError
from ..io.drive import ImuSeries, Series, TestDrive, parse_oil, write_drive
from ..io.topic_map import FRAMES, parse_frame, unit_factor
from ..io.units import UNIT_ALIASES, UNITS
from ..model import load_vehicle
from ..model.paper import IMU_SIGNALS
from ..model.road import RoadProfile
from .csv_import import DRIVE_QUANTITIES, csv_to_drive, import_csv, read_road_csv
from ..model.params import DEFAULT_VEHICLE

_KIND = {"speed": "speed", "steering_wheel_angle": "angle", "gyro": "rate", "accel": "accel", "wheel": "length"}
_IMU_AXES = ("gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z")
_WHEELS = ("fl", "fr", "rl", "rr")


# ---- channel maps ----------------------------------------------------------------------------------------
def _channel(raw: Any, where: str, kind: str) -> dict:
    if isinstance(raw, str):
        raw = {"channel": raw}
    if not isinstance(raw, Mapping) or "channel" not in raw or not isinstance(raw["channel"], str) \
            or not raw["channel"]:
        raise TopicMapError(f"{where}: expected {{channel: NAME, unit: ..., scale: ...}} or a channel name, "
                            f"got {raw!r}")
    unknown = sorted(str(k) for k in raw if k not in ("channel", "unit", "scale"))
    if unknown:
        raise TopicMapError(f"{where}: unknown key(s) {', '.join(unknown)} (known: channel, unit, scale)")
    if raw.get("unit") is not None:
        unit_factor(kind, raw["unit"], None, where)  # checked now, applied when the file is read
    scale = unit_factor(kind, None, raw.get("scale"), where)[0]
    return {"channel": raw["channel"], "unit": raw.get("unit"), "scale": scale, "kind": kind, "where": where}


def parse_channel_map(data: Any, source: str = "channel map") -> dict:
    """A parsed channel map (module docstring): ``{"speed": entry, "steering_wheel_angle": entry, "imu":
    {"frame": (R, name), axis: entry}, "wheel_heights": {wheel: entry} | None}``. TopicMapError naming
    the file and key for anything malformed."""
    if not isinstance(data, Mapping):
        raise TopicMapError(f"{source}: expected a mapping of inputs (speed, steering_wheel_angle, imu, "
                            f"wheel_heights), got {type(data).__name__}")
    known = {"speed", "steering_wheel_angle", "imu", "wheel_heights", "version", "description"}
    unknown = sorted(str(k) for k in data if k not in known)
    if unknown:
        raise TopicMapError(f"{source}: unknown input(s) {', '.join(unknown)} (known: {', '.join(sorted(known))})")
    out: dict[str, Any] = {}
    for name in ("speed", "steering_wheel_angle"):
        if name not in data:
            raise TopicMapError(f"{source}: missing {name} (every drive needs it)")
        out[name] = _channel(data[name], f"{source}: {name}", _KIND[name])
    imu = data.get("imu")
    if not isinstance(imu, Mapping):
        raise TopicMapError(f"{source}: imu: expected a mapping with frame and gyro_x, gyro_y, gyro_z "
                            f"[, accel_x, accel_y, accel_z], got {imu!r}")
    unknown = sorted(str(k) for k in imu if k not in set(_IMU_AXES) | {"frame"})
    if unknown:
        raise TopicMapError(f"{source}: imu: unknown key(s) {', '.join(unknown)} (known: frame, "
                            f"{', '.join(_IMU_AXES)})")
    out["imu"] = {"frame": parse_frame(imu.get("frame"), f"{source}: imu")}
    for ax in _IMU_AXES[:3]:
        if ax not in imu:
            raise TopicMapError(f"{source}: imu: missing {ax}")
    acc = [ax for ax in _IMU_AXES[3:] if ax in imu]
    if acc and len(acc) != 3:
        raise TopicMapError(f"{source}: imu: accel_x, accel_y, accel_z come all together or not at all")
    for ax in _IMU_AXES:
        if ax in imu:
            out["imu"][ax] = _channel(imu[ax], f"{source}: imu.{ax}",
                                      _KIND[ax[:-2] if ax.startswith("accel") else "gyro"])
    wh = data.get("wheel_heights")
    if wh is not None:
        if not isinstance(wh, Mapping) or set(wh) != set(_WHEELS):
            raise TopicMapError(f"{source}: wheel_heights: expected {{fl: ..., fr: ..., rl: ..., rr: ...}}, got {wh!r}")
        out["wheel_heights"] = {w: _channel(wh[w], f"{source}: wheel_heights.{w}", "length") for w in _WHEELS}
    else:
        out["wheel_heights"] = None
    return out


def load_channel_map(path: str | os.PathLike) -> dict:
    import yaml
    try:
        data = yaml.safe_load(Path(path).read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise TopicMapError(f"{path}: no such channel map file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise TopicMapError(f"{path}: cannot read channel map: {exc}") from None
    except yaml.YAMLError as exc:
        raise TopicMapError(f"{path}: not valid YAML: {str(exc).splitlines()[0]}") from None
    return parse_channel_map(data, str(path))


def _default_channel_map(names: set[str], path) -> dict:
    """The channel map of an MDF4 file whose channels carry the CSV column names (unit by suffix)."""
    def find(q: str, kind: str, where: str, required: bool = True):
        for name, factor in DRIVE_QUANTITIES[q].items():
            if name in names:
                return {"channel": name, "unit": None, "scale": factor, "kind": kind, "where": where,
                        "suffix_unit": True}
        if required:
            raise MeasurementImportError(f"{path}: no channel {' or '.join(DRIVE_QUANTITIES[q])} (channels: "
                                         f"{', '.join(sorted(names)) or 'none'}); name the channels with "
                                         f"--channel-map")
        return None
    cm: dict[str, Any] = {"speed": find("speed", "speed", "speed"),
                          "steering_wheel_angle": find("steering", "angle", "steering_wheel_angle"),
                          "imu": {"frame": (FRAMES["flu"], "flu")}}
    for ax, q in zip(_IMU_AXES, IMU_SIGNALS):
        e = find(q, "rate" if ax.startswith("gyro") else "accel", ax, required=ax.startswith("gyro"))
        if e is not None:
            cm["imu"][ax] = e
    if sum(ax in cm["imu"] for ax in _IMU_AXES[3:]) not in (0, 3):
        raise MeasurementImportError(f"{path}: accel_x_m_s2, accel_y_m_s2, accel_z_m_s2 come all together or "
                                     f"not at all")
    whs = [find(f"wheel_height_{w}", "length", f"wheel_height_{w}", required=False) for w in _WHEELS]
    cm["wheel_heights"] = dict(zip(_WHEELS, whs)) if all(whs) else None
    return cm


def _reader_for(path, module: str, what: str) -> ModuleType:
    """The optional library ``module`` that reads ``what`` (the ``import`` extra), for the existing file
    ``path``; a named error when either is missing."""
    try:
        lib = importlib.import_module(module)
    except ImportError:
        raise MeasurementImportError(f"{path}: reading {what} needs {module} (pip install "
                                     f"'susp_sim_ros[import]')") from None
    if not Path(path).is_file():
        raise MeasurementImportError(f"{path}: no such file")
    return lib


# ---- MDF4 ------------------------------------------------------------------------------------------------
def _open_mdf(path):
    MDF = _reader_for(path, "asammdf", "MDF4").MDF
    with open(path, "rb") as f:
        head = f.read(8)
    if not head.startswith(b"MDF "):
        raise MeasurementImportError(f"{path}: not an ASAM MDF file (no 'MDF' identification block)")
    # asammdf's half-built reader complains from its __del__ ("Exception ignored ... Traceback") when a
    # damaged file fails to open: silence that while it is collected, and report the cause once, by name
    import gc
    import sys
    why, hook = "", sys.unraisablehook
    sys.unraisablehook = lambda *_: None
    try:
        try:
            return MDF(path)
        except Exception as exc:  # asammdf raises MdfException, struct.error, ValueError... on damaged files
            why = f"{type(exc).__name__}: {exc}"
        gc.collect()
    finally:
        sys.unraisablehook = hook
    raise MeasurementImportError(f"{path}: cannot read MDF file: {why}")


def _signal(mdf, path, e: dict) -> tuple[np.ndarray, np.ndarray, str]:
    """(times [s], values SI, description) of a channel-map entry."""
    name = e["channel"]
    if name not in mdf.channels_db:
        raise MeasurementImportError(f"{path}: no channel {name!r} ({e['where']}; channels: "
                                     f"{', '.join(sorted(n for n in mdf.channels_db if n != 't')[:40])})")
    try:
        sig = mdf.get(name, raw=False)
        t = np.asarray(sig.timestamps, dtype=float)
        v = np.asarray(sig.samples, dtype=float)
    except Exception as exc:  # damaged data blocks, non-numeric samples
        raise MeasurementImportError(f"{path}: channel {name!r}: cannot read numeric samples "
                                     f"({type(exc).__name__}: {exc})") from None
    if v.ndim != 1 or t.shape != v.shape or t.size < 2:
        raise MeasurementImportError(f"{path}: channel {name!r}: expected a scalar signal with at least 2 samples, "
                                     f"got shape {v.shape}")
    if e.get("suffix_unit"):
        factor, how = e["scale"], f"unit from the name {name}"
    else:
        unit = e["unit"]
        if unit is None:
            stored = str(getattr(sig, "unit", "") or "").strip()
            if stored.lower() not in UNIT_ALIASES and stored not in UNIT_ALIASES:
                raise MeasurementImportError(f"{path}: channel {name!r} ({e['where']}): unit {stored!r} is not known "
                                             f"here; give unit: in the channel map (one of "
                                             f"{', '.join(UNITS[e['kind']])})")
            unit = UNIT_ALIASES.get(stored, UNIT_ALIASES.get(stored.lower())) or None
        try:
            f_unit = unit_factor(e["kind"], unit, None, e["where"])[0]
        except TopicMapError as exc:
            raise MeasurementImportError(f"{path}: channel {name!r}: {exc}") from None
        factor = f_unit * e["scale"]
        how = f"{unit or 'SI'}" + (f", scale {e['scale']:g}" if e["scale"] != 1.0 else "")
    if not (np.isfinite(t).all() and np.isfinite(v).all()):
        k = int(np.nonzero(~(np.isfinite(t) & np.isfinite(v)))[0][0])
        raise MeasurementImportError(f"{path}: channel {name!r}: non-finite sample {k} (t = {t[k]} s)")
    back = np.nonzero(np.diff(t) <= 0)[0]
    if back.size:
        k = int(back[0]) + 1
        raise MeasurementImportError(f"{path}: channel {name!r}: times not strictly increasing at sample {k}")
    return t, v * factor, f"{e['where'].split(': ')[-1]} <- {name} ({how}, x{factor:.9g})"


def _ns(t: np.ndarray) -> np.ndarray:
    return np.round(t * 1e9).astype(np.int64)


def _resolve_channel_map(mdf, path, channel_map: str | os.PathLike | dict | None) -> tuple[dict, str]:
    """The channel map to read ``mdf`` with, and how the import notes name it: the CSV column names
    when none is given, else the map (a file or an already loaded mapping)."""
    if channel_map is None:
        return _default_channel_map(set(mdf.channels_db), path), "channel names as the CSV columns"
    cm = channel_map if isinstance(channel_map, dict) else load_channel_map(channel_map)
    return cm, Path(channel_map).name if not isinstance(channel_map, dict) else "channel map"


def _imu_in_body_axes(mdf, path, cm: dict, conv: list) -> tuple[np.ndarray, np.ndarray, np.ndarray, list, bool]:
    """The IMU channels in SI units on the gyro_x times, rotated from the sensor's into the body axes:
    (times [s], gyro [rad/s], specific force [m/s^2], the axes interpolated onto the gyro_x times,
    whether any accelerometer channel is mapped; a missing axis is 0). Unit conversions go to ``conv``."""
    axes = {}
    for ax in _IMU_AXES:
        if ax in cm["imu"]:
            axes[ax] = _signal(mdf, path, cm["imu"][ax])
            conv.append(axes[ax][2])
    t_imu = axes["gyro_x"][0]
    resampled = []
    cols = []
    for ax in _IMU_AXES:
        if ax not in axes:
            cols.append(np.zeros_like(t_imu))
            continue
        t, v, _ = axes[ax]
        if t.shape != t_imu.shape or not np.array_equal(t, t_imu):
            v = np.interp(t_imu, t, v)
            resampled.append(ax)
        cols.append(v)
    sensor = np.column_stack(cols)
    rot = cm["imu"]["frame"][0]
    gyro, accel = sensor[:, :3], sensor[:, 3:]
    if not np.array_equal(rot, np.eye(3)):
        gyro, accel = gyro @ np.asarray(rot).T, accel @ np.asarray(rot).T
    return t_imu, gyro, accel, resampled, "accel_x" in axes


def _wheel_heights(mdf, path, cm: dict, conv: list) -> Series | None:
    """The road height under each wheel [m] (FL, FR, RL, RR) on the first wheel's times, when the map
    names them; unit conversions go to ``conv``."""
    if not cm.get("wheel_heights"):
        return None
    sigs = [_signal(mdf, path, cm["wheel_heights"][w]) for w in _WHEELS]
    tw = sigs[0][0]
    conv += [s[2] for s in sigs]
    return Series(_ns(tw), np.column_stack([s[1] if np.array_equal(s[0], tw) else np.interp(tw, s[0], s[1])
                                            for s in sigs]))


def mdf_to_drive(path: str | os.PathLike, channel_map: str | os.PathLike | dict | None = None, *,
                 vehicle: str = DEFAULT_VEHICLE, maneuver: str = "", damper_oil_level: str = "1,1,1,1",
                 source: str = "measured", notes: str = ""):
    """A :class:`~susp_sim_ros.io.drive.TestDrive` from an ASAM MDF4 file (nothing written); the
    conversions (units, IMU frame) are recorded in its metadata."""
    parse_oil(damper_oil_level, "damper_oil_level")
    mdf = _open_mdf(path)
    try:
        cm, map_name = _resolve_channel_map(mdf, path, channel_map)
        conv: list = []
        ts, vs, d = _signal(mdf, path, cm["speed"])
        conv.append(d)
        tst, vst, d = _signal(mdf, path, cm["steering_wheel_angle"])
        conv.append(d)
        t_imu, gyro, accel, resampled, has_accel = _imu_in_body_axes(mdf, path, cm, conv)
        wh = _wheel_heights(mdf, path, cm, conv)
    finally:
        mdf.close()
    rot, frame = cm["imu"]["frame"]
    note_parts = [f"imported from {Path(path).name} (ASAM MDF4, {map_name})"]
    if not has_accel:
        note_parts.append("no accelerometer channels: linear_acceleration written as 0")
    if resampled:
        note_parts.append(f"IMU channels {', '.join(resampled)} interpolated onto the gyro_x times")
    if notes:
        note_parts.append(notes)
    frame_text = (f"imu: {frame} -> REP-103 body axes (x forward, y left, z up), v_body = R v_sensor, R = "
                  f"{np.round(np.asarray(rot), 12).tolist()}")
    meta = {"vehicle": vehicle, "maneuver": maneuver, "damper_oil_level": damper_oil_level, "source": source,
            "notes": "; ".join(note_parts), "import_source": f"{Path(path).name} (ASAM MDF4)",
            "unit_conversion": "; ".join(conv), "frame_conversion": frame_text}
    return TestDrive(meta, Series(_ns(ts), vs), Series(_ns(tst), vst), None, wh,
                     ImuSeries(_ns(t_imu), gyro, accel))


# ---- OpenCRG ---------------------------------------------------------------------------------------------
def crg_to_road(path: str | os.PathLike, track_m: float, start_u: float | None = None):
    """``(RoadProfile, description)`` of an OpenCRG road: the grid elevation on the wheel tracks at
    ``v = +-track_m/2``, ``s = u - start_u`` (``start_u``: the road's ``u`` under the front axle when the
    drive starts; default the file's first ``u``) (module docstring)."""
    pyopencrg = _reader_for(path, "pyopencrg", "OpenCRG")
    try:
        road = pyopencrg.read(str(path), check=True)
        u = np.asarray(road.u, dtype=float)
        half = 0.5 * float(track_m)
        if not (road.v_min <= -half and half <= road.v_max):
            raise MeasurementImportError(f"{path}: the road is {road.v_min:g} .. {road.v_max:g} m wide (v); the "
                                         f"wheel tracks at v = +-{half:g} m lie outside it")
        zl = np.asarray(road.uv_to_z(u, half, grid_only=True), dtype=float)
        zr = np.asarray(road.uv_to_z(u, -half, grid_only=True), dtype=float)
    except MeasurementImportError:
        raise
    except Exception as exc:  # pyopencrg raises CrgFormatError, ValueError, OSError on bad files
        raise MeasurementImportError(f"{path}: not a readable OpenCRG file: {type(exc).__name__}: {exc}") from None
    bad = ~(np.isfinite(zl) & np.isfinite(zr))
    if bad.any():
        k = int(np.nonzero(bad)[0][0])
        raise MeasurementImportError(f"{path}: no elevation on a wheel track at u = {u[k]:g} m (NaN in the grid)")
    u0 = float(u[0]) if start_u is None else float(start_u)
    if not math.isfinite(u0):
        raise MeasurementImportError(f"--road-start-u: expected a finite u [m], got {start_u}")
    try:
        prof = RoadProfile(u - u0, zl, zr)
    except Exception as exc:
        raise MeasurementImportError(f"{path}: road not usable: {exc}") from None
    desc = (f"{Path(path).name} (OpenCRG via pyopencrg {pyopencrg.__version__}): s = u - {u0:g} m, elevation "
            f"of the grid (without reference-line slope and banking) on the wheel tracks v = +-{half:g} m, "
            f"{u.size} samples every {road.u_inc:g} m")
    return prof, desc


# ---- the import --------------------------------------------------------------------------------------------
def import_measurement(drive_path: str | os.PathLike, out: str | os.PathLike, road: str | os.PathLike | None = None,
                       *, channel_map: str | os.PathLike | None = None, overwrite: bool = False,
                       vehicle: str = DEFAULT_VEHICLE, road_start_u: float | None = None, **metadata) -> dict:
    """``susp import``: an MDF4 (``.mf4``/``.mdf``) or CSV drive plus an optional road (``.crg`` or
    ``.csv``) into a test-drive MCAP at ``out``; returns a summary dict."""
    suffix = Path(drive_path).suffix.lower()
    rsuffix = Path(road).suffix.lower() if road is not None else None
    if rsuffix not in (None, ".csv", ".crg"):
        raise MeasurementImportError(f"--road {road}: expected an OpenCRG .crg or a road .csv file")
    if suffix == ".csv":
        if channel_map is not None:
            raise MeasurementImportError(f"{drive_path}: --channel-map applies to MDF4 files; a CSV drive uses the "
                                         f"column names of the CSV layout (susp_sim_ros/analysis/csv_import.py)")
        if rsuffix != ".crg":  # the CSV import as it was (susp import-csv)
            return import_csv(drive_path, out, road, overwrite=overwrite, vehicle=vehicle, **metadata)
        drive = csv_to_drive(drive_path, None, vehicle=vehicle, **metadata)
        drive.metadata["import_source"] = f"{Path(drive_path).name} (CSV)"
    elif suffix in (".mf4", ".mdf"):
        drive = mdf_to_drive(drive_path, channel_map, vehicle=vehicle, **metadata)
        if rsuffix == ".csv" and road is not None:
            drive.road = read_road_csv(road)
            drive.metadata["road_source"] = f"{Path(road).name} (CSV road layout)"
    else:
        raise MeasurementImportError(f"{drive_path}: unknown measurement format {suffix or '(no suffix)'!r} "
                                     f"(expected .mf4 / .mdf (ASAM MDF4) or .csv)")
    if rsuffix == ".crg" and road is not None:
        drive.road, desc = crg_to_road(road, load_vehicle(vehicle).track[0], road_start_u)
        drive.metadata["road_source"] = desc
    n = write_drive(out, drive, overwrite=overwrite)
    return {"out": str(out), "messages": n, "samples": len(drive.imu),
            "duration_s": float((drive.imu.t_ns[-1] - drive.imu.t_ns[0]) * 1e-9),
            "road_samples": 0 if drive.road is None else len(drive.road), "metadata": drive.metadata}


__all__ = ["mdf_to_drive", "crg_to_road", "import_measurement", "parse_channel_map", "load_channel_map",
           "UNIT_ALIASES"]
