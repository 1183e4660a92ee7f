"""MCAP recorder in the ROS 2 profile, as rosbag2 writes it (interface.md, "Simulated recordings").

Profile ``ros2``, schema encoding ``ros2msg`` (full concatenated definitions), message encoding ``cdr``,
zstd-compressed chunks with message indexes and a summary. Channels carry ``offered_qos_profiles``
metadata (YAML, as rosbag2 writes it) so a latched topic such as ``/road/profile`` latches again on
replay. Chunks are small and also closed after ``flush_interval_s`` of wall time, and the file is
written unbuffered, so a process killed with SIGKILL leaves a file readable up to its last complete
chunk (``susp recover`` turns it into an indexed file again). The ``test_drive`` metadata record is
written first, so even a killed recording keeps it.
"""
from __future__ import annotations

import os
import time
from pathlib import Path
from typing import Any, Mapping

from mcap.well_known import MessageEncoding, SchemaEncoding
from mcap.writer import CompressionType, Writer

from ..errors import RecordingError, RecordingExistsError
from .messages import encode, full_definition

METADATA_NAME = "test_drive"


def qos_yaml(latched: bool = False, depth: int = 10) -> str:
    """``offered_qos_profiles`` channel metadata (one reliable profile) in rosbag2's YAML form."""
    durability = "transient_local" if latched else "volatile"
    return (
        f"- history: keep_last\n  depth: {1 if latched else depth}\n  reliability: reliable\n"
        f"  durability: {durability}\n"
        "  deadline:\n    sec: 9223372036\n    nsec: 854775807\n"
        "  lifespan:\n    sec: 9223372036\n    nsec: 854775807\n"
        "  liveliness: automatic\n"
        "  liveliness_lease_duration:\n    sec: 9223372036\n    nsec: 854775807\n"
        "  avoid_ros_namespace_conventions: false\n")


class _Unbuffered:
    """A write-through file for mcap's writer: every record reaches the OS at once (survives SIGKILL).

    (A ``RawIOBase`` would be wrapped in a ``BufferedWriter`` by mcap, so this is a plain object.)
    """

    def __init__(self, path: Path):
        self._raw = open(path, "wb", buffering=0)
        self._pos = 0

    def write(self, data) -> int:
        view = memoryview(data)
        while view.nbytes:
            n = self._raw.write(view)
            view = view[n:]
            self._pos += n
        return len(data)

    def tell(self) -> int:
        return self._pos

    def write_raw(self, topic: str, msgtype: str, schema_text: str | None, log_time_ns: int,
                  publish_time_ns: int, sequence: int, data: bytes,
                  channel_metadata: Mapping[str, str] | None = None) -> None:
        """Copy a stored message as it is (schema text, channel metadata, times and sequence kept),
        e.g. when recovering a file; ``schema_text=None`` uses the embedded definition."""
        if self.closed:
            raise RecordingError(f"{self.path}: recorder is closed")
        if topic not in self._channels:
            if msgtype not in self._schemas:
                text = schema_text if schema_text is not None else full_definition(msgtype)
                self._schemas[msgtype] = self._writer.register_schema(msgtype, SchemaEncoding.ROS2, text.encode())
            meta = dict(channel_metadata) if channel_metadata else {"offered_qos_profiles": qos_yaml(False)}
            cid = self._writer.register_channel(topic, MessageEncoding.CDR, self._schemas[msgtype], meta)
            self._channels[topic] = (cid, msgtype)
            self._sequence[topic] = 0
        cid = self._channels[topic][0]
        self._writer.add_message(cid, log_time=int(log_time_ns), data=bytes(data),
                                 publish_time=int(publish_time_ns), sequence=int(sequence))
        self._sequence[topic] = int(sequence)
        self.message_count += 1
        self._pending += 1

    def flush(self) -> None:
        pass

    def close(self) -> None:
        self._raw.close()


class McapRecorder:
    """Write ROS 2 messages to an MCAP file.

    ``with McapRecorder(path, metadata={...}) as rec: rec.write(topic, msgtype, log_time_ns, msg)``;
    ``msg`` is a plain dict (encoded with the embedded definition) or CDR bytes (e.g. from
    ``rclpy.serialization.serialize_message``). Refuses to overwrite an existing file unless
    ``overwrite=True``.
    """

    def __init__(self, path: str | os.PathLike, *, metadata: Mapping[str, str] | None = None,
                 overwrite: bool = False, chunk_size: int = 256 * 1024, flush_interval_s: float = 1.0,
                 compression: str = "zstd"):
        self.path = Path(path)
        if self.path.exists() and not overwrite:
            raise RecordingExistsError(f"{path} exists already, not overwriting.")
        try:
            self._file = _Unbuffered(self.path)
        except OSError as exc:
            raise RecordingError(f"{path}: cannot open for writing: {exc}") from None
        comp = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4,
                "none": CompressionType.NONE}[compression]
        self._writer = Writer(self._file, chunk_size=chunk_size, compression=comp)
        self._writer.start(profile="ros2", library="susp_sim_ros recorder (mcap python)")
        self._schemas: dict[str, int] = {}
        self._channels: dict[str, tuple[int, str]] = {}
        self._sequence: dict[str, int] = {}
        self._flush_interval = float(flush_interval_s)
        self._last_flush = time.monotonic()
        self._pending = 0
        self.message_count = 0
        self.closed = False
        if metadata is not None:
            self._writer.add_metadata(METADATA_NAME, {str(k): str(v) for k, v in metadata.items()})

    # -- context manager ------------------------------------------------------------------------------
    def __enter__(self) -> "McapRecorder":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # -- writing ----------------------------------------------------------------------------------------
    def _channel(self, topic: str, msgtype: str, latched: bool) -> int:
        known = self._channels.get(topic)
        if known is not None:
            if known[1] != msgtype:
                raise RecordingError(f"{self.path}: topic {topic} already recorded as {known[1]}, "
                                     f"not {msgtype}")
            return known[0]
        sid = self._schemas.get(msgtype)
        if sid is None:
            sid = self._writer.register_schema(msgtype, SchemaEncoding.ROS2,
                                               full_definition(msgtype).encode())
            self._schemas[msgtype] = sid
        cid = self._writer.register_channel(topic, MessageEncoding.CDR, sid,
                                            {"offered_qos_profiles": qos_yaml(latched)})
        self._channels[topic] = (cid, msgtype)
        self._sequence[topic] = 0
        return cid

    def write(self, topic: str, msgtype: str, log_time_ns: int, msg: Mapping[str, Any] | bytes, *,
              latched: bool = False, publish_time_ns: int | None = None) -> None:
        """Append one message; channels (and schemas) are created on first use of a topic."""
        if self.closed:
            raise RecordingError(f"{self.path}: recorder is closed")
        cid = self._channel(topic, msgtype, latched)
        data = bytes(msg) if isinstance(msg, (bytes, bytearray, memoryview)) else encode(msgtype, msg)
        seq = self._sequence[topic] = self._sequence[topic] + 1
        t = int(log_time_ns)
        self._writer.add_message(cid, log_time=t, data=data,
                                 publish_time=t if publish_time_ns is None else int(publish_time_ns),
                                 sequence=seq)
        self.message_count += 1
        self._pending += 1
        now = time.monotonic()
        if now - self._last_flush >= self._flush_interval:
            self.flush()

    def write_raw(self, topic: str, msgtype: str, schema_text: str | None, log_time_ns: int,
                  publish_time_ns: int, sequence: int, data: bytes,
                  channel_metadata: Mapping[str, str] | None = None) -> None:
        """Copy a stored message as it is (schema text, channel metadata, times and sequence kept),
        e.g. when recovering a file; ``schema_text=None`` uses the embedded definition."""
        if self.closed:
            raise RecordingError(f"{self.path}: recorder is closed")
        if topic not in self._channels:
            if msgtype not in self._schemas:
                text = schema_text if schema_text is not None else full_definition(msgtype)
                self._schemas[msgtype] = self._writer.register_schema(msgtype, SchemaEncoding.ROS2, text.encode())
            meta = dict(channel_metadata) if channel_metadata else {"offered_qos_profiles": qos_yaml(False)}
            cid = self._writer.register_channel(topic, MessageEncoding.CDR, self._schemas[msgtype], meta)
            self._channels[topic] = (cid, msgtype)
            self._sequence[topic] = 0
        cid = self._channels[topic][0]
        self._writer.add_message(cid, log_time=int(log_time_ns), data=bytes(data),
                                 publish_time=int(publish_time_ns), sequence=int(sequence))
        self._sequence[topic] = int(sequence)
        self.message_count += 1
        self._pending += 1

    def flush(self) -> None:
        """Close the chunk in progress and push it to the file (it survives a SIGKILL from now on)."""
        if self._pending:
            self._writer.flush()
            self._pending = 0
        self._last_flush = time.monotonic()

    def close(self) -> None:
        """Write the summary and indexes and close the file (idempotent)."""
        if self.closed:
            return
        self.closed = True
        try:
            self._writer.finish()
        finally:
            self._file.close()


__all__ = ["McapRecorder", "METADATA_NAME", "qos_yaml"]
