"""Robust low-level reading of MCAP recordings: every complete record, even from a truncated file.

:func:`read_recording` streams the file record by record (it needs no summary section), so a file from
a killed recorder yields everything up to its last complete chunk; ``truncated`` says that the end was
missing or damaged. Any failure of the underlying libraries becomes a :class:`RecordingError` naming
the file, never an unhandled exception.
"""
from __future__ import annotations

import logging
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator

from mcap.records import Channel, Message, Metadata, Schema
from mcap.stream_reader import StreamReader

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
    error: str = ""

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


def _records(f) -> Iterator[Any]:
    yield from StreamReader(f, skip_magic=False, emit_chunks=False).records


def read_recording(path: str | os.PathLike, *, allow_truncated: bool = True) -> Recording:
    """Every complete record of ``path``; a damaged tail is reported via ``truncated``/``error``."""
    path = Path(path)
    try:
        f = open(path, "rb")
    except OSError as exc:
        raise RecordingError(f"{path}: cannot open recording: {exc.strerror or exc}") from None
    rec = Recording(path)
    with f:
        head = f.read(len(MCAP_MAGIC))
        if head != MCAP_MAGIC:
            raise RecordingError(f"{path}: not an MCAP file (bad magic bytes)")
        f.seek(0)
        try:
            for r in _records(f):
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
                elif type(r).__name__ == "Header":
                    rec.profile = r.profile
        except Exception as exc:  # truncated or corrupt: mcap raises EndOfFile, struct.error, CRC errors...
            rec.truncated = True
            rec.error = f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__
            if not allow_truncated:
                raise RecordingError(f"{path}: damaged or truncated MCAP ({rec.error})") from None
            log.warning("%s: truncated or damaged MCAP (%s); using the %d messages before the damage",
                        path, rec.error, len(rec.messages))
    return rec


__all__ = ["RawMessage", "Recording", "read_recording", "MCAP_MAGIC"]
