"""MCAP recorder in the ROS 2 profile, as rosbag2 writes it (interface.md, "Simulated recordings").

Profile ``ros2``, schema encoding ``ros2msg`` (full concatenated definitions), message encoding ``cdr``,
zstd-compressed chunks with message indexes and a summary. Channels carry ``offered_qos_profiles``
metadata (YAML, as rosbag2 writes it) so a latched topic such as ``/road/profile`` latches again on
replay.

Kill safety: the file on disk is a complete, readable MCAP at every moment, not only after
:meth:`McapRecorder.close`. It appears (atomically, by rename) with its header and the ``test_drive``
metadata; every finished chunk is then written together with a provisional end (DataEnd, a Footer
without summary, the magic) that the next chunk overwrites (:class:`_CommittingFile`). Chunks are small
and also closed after ``flush_interval_s`` of wall time. So a process killed with SIGKILL leaves a file
that rosbags, ``ros2 bag`` and our reader open as it is, holding everything up to its last complete chunk
(at most ``flush_interval_s`` lost); ``susp recover`` rewrites it with the usual summary and indexes.
"""
from __future__ import annotations

import os
import struct
import time
from pathlib import Path
from typing import Any
from collections.abc import Mapping

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


#: What a file holds after every commit, behind the last complete chunk: a DataEnd record (data-section
#: CRC 0: not given), a Footer without a summary section (summary start 0: readers scan the data
#: section, as rosbags' ``meta_scan`` does) and the closing magic. Overwritten by the next commit.
_DATA_END = struct.pack("<BQI", 0x0F, 4, 0)
_FOOTER = struct.pack("<BQQQI", 0x02, 20, 0, 0, 0)
COMMIT_TAIL = _DATA_END + _FOOTER + b"\x89MCAP0\r\n"


class _CommittingFile:
    """The output stream of mcap's writer: records are held in memory and reach the file only by
    :meth:`commit`, which writes them at the end of the committed data *followed by* a provisional
    :data:`COMMIT_TAIL`, in one positioned write. So between commits the file on disk is always a
    complete MCAP (header, metadata, whole chunks, DataEnd, Footer, magic) that rosbags, the ``mcap``
    tools and our reader open as it is; a process killed at any moment leaves the file as of its last
    commit (only a kill inside the one ``pwrite`` of a commit, microseconds, can leave a torn tail,
    which :func:`~susp_sim_ros.io.reader.read_recording` and ``susp recover`` still handle).

    (A ``RawIOBase`` would be wrapped in a ``BufferedWriter`` by mcap, so this is a plain object.)
    """

    def __init__(self, fd: int):
        self._fd = fd
        self._end = 0  # bytes committed (the provisional tail starts here)
        self._pending = bytearray()
        self.commits = 0

    def write(self, data) -> int:
        self._pending += data
        return len(data)

    def tell(self) -> int:
        return self._end + len(self._pending)

    @property
    def pending(self) -> int:
        return len(self._pending)

    def _pwrite_all(self, buf: bytes, pos: int) -> None:
        view = memoryview(buf)
        while view.nbytes:
            n = os.pwrite(self._fd, view, pos)
            view, pos = view[n:], pos + n

    def commit(self, *, final: bool = False) -> None:
        """Write what the writer produced since the last commit plus the provisional tail (``final``:
        the writer's own summary, footer and magic end the file; nothing is appended)."""
        buf = bytes(self._pending) if final else bytes(self._pending) + COMMIT_TAIL
        self._pwrite_all(buf, self._end)
        self._end += len(self._pending)
        self._pending.clear()
        if final:
            os.ftruncate(self._fd, self._end)
        self.commits += 1

    def flush(self) -> None:
        pass

    def close(self) -> None:
        if self._fd >= 0:
            os.close(self._fd)
            self._fd = -1


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
        if compression not in ("zstd", "lz4", "none"):
            raise RecordingError(f"{path}: unknown compression {compression!r} (zstd, lz4, none)")
        comp = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4,
                "none": CompressionType.NONE}[compression]
        tmp = self.path.with_name(f".{self.path.name}.{os.getpid()}.partial")
        try:
            fd = os.open(tmp, os.O_RDWR | os.O_CREAT | os.O_TRUNC, 0o644)
        except OSError as exc:
            raise RecordingError(f"{path}: cannot open for writing: {exc.strerror or exc}") from None
        self._file = _CommittingFile(fd)
        # mcap's writer only calls write() and tell(); its annotation asks for a file object
        self._writer = Writer(self._file, chunk_size=chunk_size, compression=comp)  # type: ignore[arg-type]
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
        try:
            self._file.commit()  # a complete (empty) recording before it appears under its name
            if overwrite:
                os.replace(tmp, self.path)
            else:
                try:
                    os.link(tmp, self.path)  # fails if the name was taken meanwhile: never overwrites
                except FileExistsError:
                    raise RecordingExistsError(f"{path} exists already, not overwriting.") from None
                except OSError:  # a file system without hard links
                    if self.path.exists():
                        raise RecordingExistsError(f"{path} exists already, not overwriting.") from None
                    os.rename(tmp, self.path)
        except BaseException:
            self._file.close()
            tmp.unlink(missing_ok=True)
            raise
        tmp.unlink(missing_ok=True)

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
        if self._file.pending:  # the writer closed a full chunk: put it on disk
            self._commit()
        if time.monotonic() - self._last_flush >= self._flush_interval:
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
        if self._file.pending:
            self._commit()

    def _commit(self) -> None:
        try:
            self._file.commit()
        except OSError as exc:
            raise RecordingError(f"{self.path}: cannot write: {exc.strerror or exc}") from None
        self._pending = 0  # messages of closed chunks are on disk now

    def flush(self) -> None:
        """Close the chunk in progress and put it on disk (it survives a SIGKILL from now on)."""
        if self._pending:
            self._writer.flush()
        if self._file.pending:
            self._commit()
        self._pending = 0
        self._last_flush = time.monotonic()

    def flush_if_due(self) -> None:
        """:meth:`flush` if ``flush_interval_s`` has passed since the last one (for idle periods)."""
        if not self.closed and time.monotonic() - self._last_flush >= self._flush_interval:
            self.flush()

    def close(self) -> None:
        """Write the summary and indexes and close the file (idempotent)."""
        if self.closed:
            return
        self.closed = True
        try:
            self._writer.finish()
            self._file.commit(final=True)
        finally:
            self._file.close()


__all__ = ["McapRecorder", "METADATA_NAME", "qos_yaml"]
