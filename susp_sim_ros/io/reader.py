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
from typing import Any, Iterator

from mcap.exceptions import EndOfFile
from mcap.records import Channel, Chunk, Footer, Message, Metadata, Schema
from mcap.stream_reader import StreamReader, breakup_chunk

from ..errors import RecordingError
from .messages import decode

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

    def decode_topic(self, topic: str) -> list[tuple[int, Any]]:
        """``(log_time_ns, decoded message)`` of a topic, in log-time order; RecordingError on bad CDR."""
        out = []
        for m in sorted(self.by_topic(topic), key=lambda m: m.log_time_ns):
            try:
                out.append((m.log_time_ns, m.decoded(self.schema_text(m.channel_id))))
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
    for r in StreamReader(src, skip_magic=False, emit_chunks=True, validate_crcs=True).records:
        if isinstance(r, Chunk):
            if r.uncompressed_size > max(1 << 20, _MAX_EXPANSION * len(r.data)):
                raise ValueError(f"chunk claims {r.uncompressed_size} bytes uncompressed from "
                                 f"{len(r.data)} compressed")
            yield from breakup_chunk(r, validate_crc=True)
        else:
            yield r


def read_recording(path: str | os.PathLike, *, allow_truncated: bool = True,
                   allow_corrupt: bool = False) -> Recording:
    """Every complete record of ``path`` (module docstring): a truncated tail is reported via
    ``truncated``/``error`` (RecordingError if not ``allow_truncated``), corruption raises
    :class:`RecordingError` (with ``allow_corrupt``: reported via ``corrupt``/``error``)."""
    path = Path(path)
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


__all__ = ["RawMessage", "Recording", "read_recording", "MCAP_MAGIC"]
