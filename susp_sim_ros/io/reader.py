"""Robust low-level reading of MCAP recordings: every complete record, even from a truncated file.

:func:`read_recording` streams the file record by record (it needs no summary section), so a file from
a killed recorder yields everything up to its last complete chunk. Two kinds of damage are told apart:

- **truncated** (the file ends inside a record: a copy cut short, a recorder killed during a write): the
  complete records before the cut are used, ``truncated`` is set and a warning is logged;
- **corrupt** (a chunk whose CRC does not match its content, undecodable compressed data, impossible
  record contents): a :class:`RecordingError` naming the file, the byte offset and the cause, unless
  ``allow_corrupt`` (``susp recover`` salvages the records before the damage).

Records are never parsed from partial bytes, chunk CRCs are checked. Any failure of the underlying
libraries becomes a :class:`RecordingError` naming the file, never an unhandled exception.
``finalised`` says whether the file has its summary section (a recording closed properly); a file left by
a killed recorder has not (``susp recover`` adds it).
"""
from __future__ import annotations

import logging
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, cast
from collections.abc import Iterator

from mcap.exceptions import EndOfFile
from mcap.records import Channel, Chunk, Footer, Message, Metadata, Schema
from mcap.stream_reader import StreamReader, breakup_chunk

from ..errors import NotRos2RecordingError, RecordingError
from .messages import MSG_DEFS, decode, full_definition
from .recorder import qos_yaml

log = logging.getLogger(__name__)

MCAP_MAGIC = b"\x89MCAP0\r\n"


@dataclass
class RawMessage:
    """One message as stored: topic, type, times [ns], sequence, CDR bytes."""

    topic: str
    msgtype: str
    log_time_ns: int
    publish_time_ns: int
    sequence: int
    data: bytes
    channel_id: int

    def decoded(self, schema_text: str | None = None) -> Any:
        return decode(self.msgtype, self.data, schema_text)


@dataclass
class Recording:
    """The readable content of an MCAP file, in file order."""

    path: Path
    messages: list[RawMessage] = field(default_factory=list)
    channels: dict[int, Channel] = field(default_factory=dict)
    schemas: dict[int, Schema] = field(default_factory=dict)
    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    profile: str = ""
    truncated: bool = False
    corrupt: bool = False
    error: str = ""
    finalised: bool = False

    def schema_text(self, channel_id: int) -> str | None:
        ch = self.channels.get(channel_id)
        sc = self.schemas.get(ch.schema_id) if ch is not None else None
        return sc.data.decode(errors="replace") if sc is not None and sc.data else None

    def decoding_schema(self, channel_id: int) -> str | None:
        """The ``ros2msg`` text to decode a channel's messages with: its own schema when that is ``ros2msg``;
        for ``ros2idl`` (or no text) None when this package embeds the type, else the ROS 2 Jazzy definition
        from ``rosbags``' type store (None if unknown there too)."""
        ch = self.channels.get(channel_id)
        sc = self.schemas.get(ch.schema_id) if ch is not None else None
        if sc is None:
            return None
        if sc.encoding == "ros2msg" and sc.data:
            return sc.data.decode(errors="replace")
        if sc.name in MSG_DEFS:
            return None
        return _jazzy_definition(sc.name) or None

    def topics(self) -> dict[str, str]:
        return {m.topic: m.msgtype for m in self.messages} | {
            c.topic: (self.schemas[c.schema_id].name if c.schema_id in self.schemas else "")
            for c in self.channels.values()}

    def latched(self, topic: str) -> bool:
        for c in self.channels.values():
            if c.topic == topic:
                return "transient_local" in c.metadata.get("offered_qos_profiles", "")
        return False

    def by_topic(self, topic: str) -> list[RawMessage]:
        return [m for m in self.messages if m.topic == topic]

    def decode_topic(self, topic: str, *, order: str = "log") -> list[tuple[int, Any]]:
        """``(log_time_ns, decoded message)`` of a topic; RecordingError on bad CDR.

        ``order``: ``"log"`` sorts by log time (stable: messages with one log time stay in file order);
        ``"file"`` keeps the order the messages are stored in, for the input integrity check
        (:mod:`~susp_sim_ros.io.integrity`: out-of-order stamps and backward clock jumps are findings it
        repairs, not something to hide). The two are the same for a file whose messages are stored in
        log-time order."""
        if order not in ("log", "file"):
            raise ValueError(f"decode_topic: order must be 'log' or 'file', got {order!r}")
        msgs = self.by_topic(topic)
        out = []
        for m in (msgs if order == "file" else sorted(msgs, key=lambda m: m.log_time_ns)):
            try:
                out.append((m.log_time_ns, m.decoded(self.decoding_schema(m.channel_id))))
            except Exception as exc:  # mcap_ros2 raises assorted errors on malformed CDR/schema
                raise RecordingError(f"{self.path}: topic {topic}: cannot decode a {m.msgtype} message "
                                     f"at log time {m.log_time_ns} ns: {type(exc).__name__}: {exc}") from None
        return out


class _ExactReader:
    """File wrapper for mcap's stream reader: a read that cannot return all bytes asked for raises
    ``EndOfFile`` (mcap would otherwise parse a record from the partial bytes) and marks ``short``."""

    def __init__(self, f, size: int):
        self._f, self.size, self.short = f, size, False

    def read(self, n: int = -1) -> bytes:
        data = self._f.read(n)
        if n is not None and n > 0 and len(data) < n:
            self.short = True
            raise EndOfFile()
        return data

    def tell(self) -> int:
        return self._f.tell()


#: Largest plausible decompressed chunk relative to its compressed size (a corrupt size field would
#: otherwise make the decompressor allocate whatever it says).
_MAX_EXPANSION = 1000


def _records(src: _ExactReader) -> Iterator[Any]:
    # mcap's stream reader only calls read() and tell(); its annotation asks for a file object
    for r in StreamReader(src, skip_magic=False, emit_chunks=True,  # type: ignore[arg-type]
                          validate_crcs=True).records:
        if isinstance(r, Chunk):
            if r.uncompressed_size > max(1 << 20, _MAX_EXPANSION * len(r.data)):
                raise ValueError(f"chunk claims {r.uncompressed_size} bytes uncompressed from "
                                 f"{len(r.data)} compressed")
            yield from breakup_chunk(r, validate_crc=True)
        else:
            yield r


ROS1_MAGIC = b"#ROSBAG V"
SQLITE_MAGIC = b"SQLite format 3\x00"
#: MCAP profiles of ROS 2 recordings ("" is what some writers leave; then the channels must be CDR).
ROS2_PROFILES = ("ros2", "")


def read_recording(path: str | os.PathLike, *, allow_truncated: bool = True,
                   allow_corrupt: bool = False) -> Recording:
    """Every complete record of the recording at ``path``, which may be

    - an MCAP file (module docstring: streamed, no summary or index needed, zstd/lz4/uncompressed chunks);
    - a rosbag2 directory: ``metadata.yaml`` and its split files, MCAP (each read as above, in the order
      ``metadata.yaml`` lists them) or sqlite3 ``.db3`` (through ``rosbags``); a directory without
      ``metadata.yaml`` (a recorder killed before writing it) has its ``*.mcap``/``*.db3`` read in name order;
      the bag's ``custom_data`` (``ros2 bag record --custom-data damper_oil_level=1,1,0,0``) is the
      ``test_drive`` metadata when its files carry none;
    - a sqlite3 ``.db3`` file of rosbag2 (through ``rosbags``).

    A truncated tail is reported via ``truncated``/``error`` (RecordingError if not ``allow_truncated``),
    corruption raises :class:`RecordingError` (with ``allow_corrupt``: reported via ``corrupt``/``error``).
    A recording that is not ROS 2 (another MCAP profile, no CDR channel, a ROS 1 bag) raises
    :class:`~susp_sim_ros.errors.NotRos2RecordingError`."""
    path = Path(path)
    if path.is_dir():
        return _read_directory(path, allow_truncated, allow_corrupt)
    try:
        with open(path, "rb") as f:
            head = f.read(16)
    except OSError as exc:
        raise RecordingError(f"{path}: cannot open recording: {exc.strerror or exc}") from None
    if head.startswith(SQLITE_MAGIC):
        return _read_rosbags(path, path)
    if head.startswith(ROS1_MAGIC):
        raise NotRos2RecordingError(f"{path}: a ROS 1 bag, not a ROS 2 recording (convert it first, e.g. with "
                                    f"rosbags-convert)")
    rec = _read_mcap(path, allow_truncated, allow_corrupt)
    _require_ros2(rec)
    return rec


def _require_ros2(rec: Recording) -> None:
    """NotRos2RecordingError unless ``rec`` is a ROS 2 recording: MCAP profile ``ros2`` (or none, with at
    least one CDR channel)."""
    if rec.profile not in ROS2_PROFILES:
        raise NotRos2RecordingError(f"{rec.path}: MCAP profile {rec.profile!r} is not a ROS 2 recording (expected "
                                    f"profile 'ros2' with ros2msg schemas and cdr messages)")
    if rec.profile == "" and rec.channels and not any(c.message_encoding == "cdr" for c in rec.channels.values()):
        encs = sorted({c.message_encoding for c in rec.channels.values()})
        raise NotRos2RecordingError(f"{rec.path}: not a ROS 2 recording: no profile and no cdr channel (message "
                                    f"encodings: {', '.join(map(repr, encs))})")


def _merge(into: Recording, part: Recording) -> None:
    """Append the records of one split file to ``into``, giving its schemas and channels ids unique in the
    merged recording (split files number them independently)."""
    smap: dict[int, int] = {}
    for sid, sc in part.schemas.items():
        key = (sc.name, sc.encoding, bytes(sc.data))
        found = next((i for i, o in into.schemas.items() if (o.name, o.encoding, bytes(o.data)) == key), None)
        if found is None:
            found = len(into.schemas) + 1
            into.schemas[found] = Schema(id=found, name=sc.name, encoding=sc.encoding, data=sc.data)
        smap[sid] = found
    cmap: dict[int, int] = {}
    for cid, ch in part.channels.items():
        sid = smap.get(ch.schema_id, 0)
        found = next((i for i, o in into.channels.items() if (o.topic, o.schema_id, o.message_encoding) ==
                      (ch.topic, sid, ch.message_encoding)), None)
        if found is None:
            found = len(into.channels) + 1
            into.channels[found] = Channel(id=found, schema_id=sid, topic=ch.topic,
                                            message_encoding=ch.message_encoding, metadata=dict(ch.metadata))
        cmap[cid] = found
    for m in part.messages:
        m.channel_id = cmap.get(m.channel_id, m.channel_id)
        into.messages.append(m)
    for k, v in part.metadata.items():
        into.metadata.setdefault(k, v)
    into.profile = into.profile or part.profile
    if part.truncated or part.corrupt:
        into.truncated |= part.truncated
        into.corrupt |= part.corrupt
        into.error = f"{part.path.name}: {part.error}"


def _read_directory(path: Path, allow_truncated: bool, allow_corrupt: bool) -> Recording:
    meta_file = path / "metadata.yaml"
    custom: dict[str, str] = {}
    if meta_file.is_file():
        import yaml
        try:
            info = yaml.safe_load(meta_file.read_text(encoding="utf-8"))["rosbag2_bagfile_information"]
            storage = str(info.get("storage_identifier", ""))
            files = [path / Path(str(f)).name for f in info["relative_file_paths"]]
            compression = str(info.get("compression_mode", "") or "").lower()
        except (OSError, UnicodeDecodeError, yaml.YAMLError, KeyError, TypeError, AttributeError) as exc:
            raise RecordingError(f"{meta_file}: not a rosbag2 metadata file ({type(exc).__name__}: {exc})") from None
        missing = [f.name for f in files if not f.is_file()]
        if missing:
            raise RecordingError(f"{path}: rosbag2 directory lacks the split file(s) {', '.join(missing)} listed "
                                 f"in metadata.yaml")
        if storage not in ("mcap", "sqlite3"):
            raise RecordingError(f"{path}: rosbag2 storage {storage!r} is not supported (mcap or sqlite3)")
        custom = info.get("custom_data")  # `ros2 bag record --custom-data damper_oil_level=1,1,0,0 ...`
        custom = {str(k): str(v) for k, v in custom.items()} if isinstance(custom, dict) else {}
        if storage == "sqlite3" or compression not in ("", "none"):
            rec = _read_rosbags(path, path)
            if custom:
                rec.metadata.setdefault("test_drive", custom)
            return rec
    else:
        files = sorted(list(path.glob("*.mcap")) + list(path.glob("*.db3")))
        if not files:
            raise RecordingError(f"{path}: a directory without metadata.yaml and without *.mcap or *.db3 files "
                                 f"(expected a rosbag2 directory)")
        log.warning("%s: no metadata.yaml (recorder killed?); reading %s in name order", path,
                    ", ".join(f.name for f in files))
    rec = Recording(path)
    rec.finalised = True
    for f in files:
        part = (_read_rosbags(f, f) if f.suffix == ".db3"
                else _read_mcap(f, allow_truncated, allow_corrupt))
        if f.suffix != ".db3":
            _require_ros2(part)
        rec.finalised &= part.finalised
        _merge(rec, part)
    if custom:
        rec.metadata.setdefault("test_drive", custom)
    return rec


def _jazzy_definition(msgtype: str) -> str:
    """Concatenated ``ros2msg`` definition of a ROS 2 Jazzy type from ``rosbags``' type store ("" if unknown)."""
    try:
        from rosbags.typesys import Stores, get_typestore
        return get_typestore(Stores.ROS2_JAZZY).generate_msgdef(msgtype, ros_version=2)[0]
    except Exception:  # rosbags missing, or a type it does not know
        return ""


def _msgdef_text(conn) -> tuple[str, str]:
    """(schema encoding, definition text) of a rosbags connection: the stored one, else this package's
    embedded definitions, else rosbags' ROS 2 Jazzy type store; ("", "") when the type is unknown."""
    fmt = getattr(getattr(conn.msgdef, "format", None), "name", "NONE")
    if fmt in ("MSG", "IDL") and conn.msgdef.data:
        return ("ros2msg" if fmt == "MSG" else "ros2idl"), conn.msgdef.data
    if conn.msgtype in MSG_DEFS:
        return "ros2msg", full_definition(conn.msgtype)
    text = _jazzy_definition(conn.msgtype)  # "" for an unknown type: skipped, or named when needed
    return ("ros2msg", text) if text else ("", "")


def _read_rosbags(path: Path, name: Path) -> Recording:
    """A rosbag2 directory or ``.db3`` file through ``rosbags`` (sqlite3 storage, compressed bags)."""
    from rosbags.interfaces import ConnectionExtRosbag2
    from rosbags.rosbag2 import Reader
    rec = Recording(name)
    rec.profile = "ros2"
    rec.finalised = True
    try:
        with Reader(path) as r:
            ids: dict[int, int] = {}
            for conn in r.connections:
                enc, text = _msgdef_text(conn)
                sid = len(rec.schemas) + 1
                rec.schemas[sid] = Schema(id=sid, name=conn.msgtype, encoding=enc, data=text.encode())
                ext = cast(ConnectionExtRosbag2, conn.ext)  # a rosbag2 reader's connections carry rosbag2 extensions
                durab = [getattr(getattr(q, "durability", None), "name", "").lower()
                         for q in ext.offered_qos_profiles]
                cid = len(rec.channels) + 1
                latched = any("transient_local" in d for d in durab)
                rec.channels[cid] = Channel(id=cid, schema_id=sid, topic=conn.topic,
                                            message_encoding=ext.serialization_format,
                                            metadata={"offered_qos_profiles": qos_yaml(latched)})
                ids[id(conn)] = cid
            for seq, (conn, t, data) in enumerate(r.messages()):
                rec.messages.append(RawMessage(conn.topic, conn.msgtype, int(t), int(t), seq, bytes(data),
                                               ids[id(conn)]))
    except RecordingError:
        raise
    except Exception as exc:  # rosbags raises ReaderError, apsw errors, KeyError on bad metadata, ...
        raise RecordingError(f"{path}: cannot read rosbag2 recording: {type(exc).__name__}: {exc}") from None
    return rec


def _read_mcap(path: Path, allow_truncated: bool, allow_corrupt: bool) -> Recording:
    try:
        f = open(path, "rb")
        size = os.fstat(f.fileno()).st_size
    except OSError as exc:
        raise RecordingError(f"{path}: cannot open recording: {exc.strerror or exc}") from None
    rec = Recording(path)
    with f:
        head = f.read(len(MCAP_MAGIC))
        if head != MCAP_MAGIC:
            raise RecordingError(f"{path}: not an MCAP file (bad magic bytes)")
        f.seek(0)
        src = _ExactReader(f, size)
        try:
            for r in _records(src):
                if isinstance(r, Message):
                    ch = rec.channels.get(r.channel_id)
                    if ch is None:
                        continue
                    sc = rec.schemas.get(ch.schema_id)
                    rec.messages.append(RawMessage(ch.topic, sc.name if sc else "", r.log_time,
                                                   r.publish_time, r.sequence, bytes(r.data), r.channel_id))
                elif isinstance(r, Channel):
                    rec.channels[r.id] = r
                elif isinstance(r, Schema):
                    rec.schemas[r.id] = r
                elif isinstance(r, Metadata):
                    rec.metadata[r.name] = dict(r.metadata)
                elif isinstance(r, Footer):
                    rec.finalised = r.summary_start != 0
                elif type(r).__name__ == "Header":
                    rec.profile = r.profile
        except Exception as exc:  # mcap raises EndOfFile, struct.error, CRC errors, zstd errors, ...
            what = f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__
            if src.short:
                rec.truncated = True
                rec.error = f"file ends inside a record at byte {size} ({what})"
                if not allow_truncated:
                    raise RecordingError(f"{path}: truncated MCAP: {rec.error}") from None
                log.warning("%s: truncated MCAP (%s); using the %d messages before the cut",
                            path, rec.error, len(rec.messages))
            else:
                rec.corrupt = True
                rec.error = f"damaged data before byte {f.tell()} of {size} ({what})"
                if not allow_corrupt:
                    raise RecordingError(f"{path}: corrupt MCAP: {rec.error}") from None
                log.warning("%s: corrupt MCAP (%s); using the %d messages before the damage",
                            path, rec.error, len(rec.messages))
    return rec


__all__ = ["RawMessage", "Recording", "read_recording", "MCAP_MAGIC", "ROS2_PROFILES"]
