"""``susp recover``: make a recording from a killed process a finalised, indexed file again.

Reads every complete record of the input (up to its last complete chunk; a truncated tail or a corrupt
chunk ends the readable part) and writes them into a new, properly finalised and indexed MCAP (schemas,
channel QoS metadata, ``test_drive`` and other metadata, log and publish times and sequence numbers
kept). A recording left by a killed ``susp_sim_node`` is already readable as it is (the recorder keeps
the file complete after every chunk); it lacks the summary section (statistics, chunk and message
indexes) that makes large files fast to seek, which this adds.
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
    rec = read_recording(src, allow_corrupt=True)
    if not rec.profile and not rec.metadata and not rec.channels:
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
    state = (f"input was damaged: {rec.error}" if rec.truncated or rec.corrupt
             else "input was complete but not finalised (no summary)" if not rec.finalised
             else "input was intact")
    return {"input": str(src), "out": str(dst), "messages": len(rec.messages),
            "topics": sorted({m.topic for m in rec.messages}),
            "was_truncated": rec.truncated or rec.corrupt or not rec.finalised,
            "was_finalised": rec.finalised, "was_corrupt": rec.corrupt,
            "damage": rec.error, "duration_s": (max(t) - min(t)) * 1e-9 if t else 0.0,
            "summary": f"{src}: recovered {len(rec.messages)} messages into {dst} ({state})"}


def run(args) -> dict:
    src = Path(args.recording)
    dst = Path(args.out) if args.out else src.with_name(src.stem + ".recovered.mcap")
    return recover(src, dst, overwrite=args.overwrite)
