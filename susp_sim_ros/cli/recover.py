"""``susp recover``: make a recording from a killed process readable again.

Reads every complete record of the damaged file (up to its last complete chunk) and writes them into a
new, properly finalised and indexed MCAP (schemas, channel QoS metadata, ``test_drive`` metadata, log and
publish times and sequence numbers kept).
"""
from __future__ import annotations

from pathlib import Path

from ..errors import RecordingError
from ..io.reader import read_recording
from ..io.recorder import McapRecorder


def add_arguments(p) -> None:
    p.add_argument("recording", help="the MCAP file left by a killed recorder")
    p.add_argument("--out", help="where to write the finalised file (default: <name>.recovered.mcap)")
    p.add_argument("--overwrite", action="store_true", help="overwrite --out if it exists")


def recover(src: str | Path, dst: str | Path, *, overwrite: bool = False) -> dict:
    src, dst = Path(src), Path(dst)
    if src.resolve() == dst.resolve():
        raise RecordingError(f"{dst}: --out must differ from the input file")
    rec = read_recording(src)
    if not rec.channels and not rec.messages:
        raise RecordingError(f"{src}: nothing readable to recover ({rec.error or 'empty'})")
    meta = rec.metadata.get("test_drive")
    with McapRecorder(dst, metadata=meta, overwrite=overwrite) as out:
        for name, data in rec.metadata.items():
            if name != "test_drive":
                out._writer.add_metadata(name, data)
        for m in rec.messages:
            ch = rec.channels[m.channel_id]
            out.write_raw(m.topic, m.msgtype, rec.schema_text(m.channel_id), m.log_time_ns,
                          m.publish_time_ns, m.sequence, m.data, ch.metadata)
    t = [m.log_time_ns for m in rec.messages]
    return {"input": str(src), "out": str(dst), "messages": len(rec.messages),
            "topics": sorted({m.topic for m in rec.messages}), "was_truncated": rec.truncated,
            "damage": rec.error, "duration_s": (max(t) - min(t)) * 1e-9 if t else 0.0,
            "summary": f"{src}: recovered {len(rec.messages)} messages into {dst}"
                       + (f" (input was damaged: {rec.error})" if rec.truncated else " (input was intact)")}


def run(args) -> dict:
    src = Path(args.recording)
    dst = Path(args.out) if args.out else src.with_name(src.stem + ".recovered.mcap")
    return recover(src, dst, overwrite=args.overwrite)
