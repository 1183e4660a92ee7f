"""The resumable result store of a study: one file per finished chunk, written as the chunk finishes.

Layout of ``OUT``::

    manifest.json          the study (normalised), its hash, and one entry per session (start, resumed chunks)
    chunks/c000017.csv     the rows of finished chunk 17 (sweep); chunks/d000003.json: drive 3 (drives)
    chunks/log.jsonl       one line per chunk computed: chunk id, session, runs, wall time of its task
                           (``recovered``: its file was written, its line lost to a kill)
    results.csv            (or .parquet) all rows by run id, once every chunk is in; drives: drives.csv

A chunk file is written to a temporary name and renamed into place (atomic on POSIX), so a killed study
leaves only whole chunk files; the next run with the same ``--out`` skips them and computes the rest.
Floats are written with ``repr`` (shortest round-trip form), so the table holds exactly the computed
values. A store of a different study (other hash) is refused unless ``fresh=True``.
"""
from __future__ import annotations

import csv
import io
import json
import os
import shutil
import time
from pathlib import Path
from collections.abc import Iterable, Sequence

import numpy as np

from ...errors import SuspInputError
from .spec import StudySpec


def _fmt(v) -> str:
    if type(v) is float:
        return repr(v)
    if isinstance(v, (bool, np.bool_)):
        return "1" if v else "0"
    if isinstance(v, (float, np.floating)):
        return repr(float(v))
    return str(v)


_PLAIN = (float, int, str)      # types the csv writer formats as _fmt does (bool and numpy types are not)


def _atomic_write(path: Path, data: bytes) -> None:
    """Write to a temporary name, then rename: readers see the old file or the whole new one.

    No fsync (it cost ~10 % of a small study's time): a killed study, the case resume is for, loses
    nothing that was renamed into place; after an OS crash or a power loss a damaged chunk file fails the
    check on resume and is recomputed, a lost manifest starts the study over. Results are never wrong,
    at worst computed again."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    with open(tmp, "wb") as f:
        f.write(data)
    os.replace(tmp, path)


class ResultStore:
    def __init__(self, spec: StudySpec, out: str | Path, *, fresh: bool = False):
        self.spec, self.out = spec, Path(out)
        self.chunk_dir = self.out / "chunks"
        self.log_path = self.chunk_dir / "log.jsonl"
        self.manifest_path = self.out / "manifest.json"
        try:
            self.out.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise SuspInputError(f"--out {self.out}: cannot create the directory: {exc.strerror or exc}") from None
        manifest = None
        if self.manifest_path.exists():
            try:
                manifest = json.loads(self.manifest_path.read_text())
            except (OSError, ValueError):
                manifest = None
            if manifest is not None and manifest.get("hash") != spec.hash and not fresh:
                raise SuspInputError(
                    f"--out {self.out}: holds results of another study ({manifest.get('name')!r}, hash "
                    f"{manifest.get('hash')}) or of this study edited since (hash now {spec.hash}); use "
                    f"another --out, or --fresh to discard them")
            if fresh or manifest is None or manifest.get("hash") != spec.hash:
                manifest = None
        if manifest is None and self.chunk_dir.exists():
            shutil.rmtree(self.chunk_dir)
        self.chunk_dir.mkdir(exist_ok=True)
        for tmp in self.chunk_dir.glob(".*.tmp"):       # leftovers of a killed writer
            tmp.unlink()
        self.manifest = manifest or {"name": spec.name, "kind": spec.kind, "hash": spec.hash,
                                     "source": spec.path, "spec": spec.data, "n_runs": spec.n_runs,
                                     "n_chunks": len(spec.chunks), "sessions": []}
        self.session = len(self.manifest["sessions"])
        self._bodies: dict[int, str] = {}           # chunk id -> rows written in this session
        self._values: dict[int, tuple] = {}         # chunk id -> (ok, metrics) of this session
        self._texts: dict[str, dict] = {}            # swept key -> value -> its csv text
        self.done = self._finished()
        self._reconcile_log()

    def _reconcile_log(self) -> None:
        """Mend the log after a kill: a line the kill cut is dropped (the next line would be appended to
        it and lost too), and a chunk whose file was written but whose line was not (killed between the
        two) gets its line, marked ``recovered``, in the session that wrote it (the last one; its wall
        time unknown). The log then holds every finished chunk exactly once."""
        if self.log_path.exists():
            text = self.log_path.read_text()
            if text and not text.endswith("\n"):
                _atomic_write(self.log_path, text[:text.rfind("\n") + 1].encode())
        missing = sorted(self.done - {e.get("chunk") for e in self.log()})
        if missing:
            with open(self.log_path, "a") as f:
                for cid in missing:
                    f.write(json.dumps({"chunk": cid, "session": max(self.session - 1, 0),
                                        "runs": len(self.spec.chunks[cid].runs), "elapsed_s": None,
                                        "task_chunks": None, "recovered": True}) + "\n")

    def begin_session(self) -> None:
        """Record this session in the manifest (before its first chunk is written)."""
        self.manifest["sessions"].append({"started": time.strftime("%Y-%m-%dT%H:%M:%S"),
                                          "chunks_already_done": len(self.done)})
        _atomic_write(self.manifest_path, json.dumps(self.manifest, indent=1, default=str).encode())

    # -- chunks ----------------------------------------------------------------------------------------
    def _chunk_path(self, cid: int) -> Path:
        return self.chunk_dir / (f"c{cid:06d}.csv" if self.spec.kind == "sweep" else f"d{cid:06d}.json")

    def _finished(self) -> set[int]:
        ids = set()
        pattern = "c*.csv" if self.spec.kind == "sweep" else "d*.json"
        for p in self.chunk_dir.glob(pattern):
            try:
                cid = int(p.stem[1:])
            except ValueError:
                continue
            if 0 <= cid < len(self.spec.chunks) and self._intact(p, cid):
                ids.add(cid)
        return ids

    def _intact(self, p: Path, cid: int) -> bool:
        """A whole chunk file: the header and one complete row per run (sweep), valid JSON (drives)."""
        try:
            text = p.read_text()
            if self.spec.kind != "sweep":
                json.loads(text)
                return True
            rows = list(csv.reader(io.StringIO(text)))
        except (OSError, ValueError, UnicodeDecodeError, csv.Error):
            return False
        n = len(self.columns())
        ids = [int(r[0]) for r in rows[1:] if len(r) == n and r[0].isdigit()]
        return (text.endswith("\n") and bool(rows) and rows[0] == self.columns()
                and ids == list(self.spec.chunks[cid].runs))

    def _header(self) -> str:
        buf = io.StringIO()
        csv.writer(buf, lineterminator="\n").writerow(self.columns())
        return buf.getvalue()

    def _field_text(self, key: str, value) -> str:
        """A swept value as the csv writer writes it in a row, with its trailing comma (cached)."""
        cache = self._texts.setdefault(key, {})
        t = cache.get((type(value), value))          # (1 and 1.0 are one dict key, not one text)
        if t is None:
            buf = io.StringIO()
            csv.writer(buf, lineterminator="\n").writerow([value if type(value) in _PLAIN else _fmt(value), ""])
            t = cache[(type(value), value)] = buf.getvalue()[:-1]   # "text," (an empty second field)
        return t

    def columns(self) -> list[str]:
        return ["run_id", *self.spec.swept, "ok", *self.spec.metric_columns()]

    def write_chunk(self, cid: int, result, elapsed_s: float, task_chunks: int = 1) -> None:
        """Store a finished chunk (sweep: ``{"ok", "metrics"}`` from the task; drives: a row).

        ``elapsed_s``: wall time of the task that computed it, a task of ``task_chunks`` chunks."""
        chunk = self.spec.chunks[cid]
        if self.spec.kind == "sweep":
            ok = np.asarray(result["ok"], bool)
            metrics = np.asarray(result["metrics"], dtype=float).reshape(len(chunk.runs), -1)
            runs, swept, text_of = self.spec.runs, self.spec.swept, self._field_text
            # the csv writer's text of each field: repr() of a float (metrics: never quoted), a swept
            # value's text once per distinct value
            body = "".join([f"{rid},{''.join([text_of(k, runs[rid][k]) for k in swept])}{'1' if g else '0'}"
                            f"{''.join([',' + repr(x) for x in m])}\n"
                            for rid, g, m in zip(chunk.runs, ok.tolist(), metrics.tolist())])
            self._bodies[cid] = body                     # for the final table: not read back
            text = self._header() + body
            self._values[cid] = (ok, metrics)
            data = text.encode()
        else:
            data = json.dumps(result, default=_fmt).encode()
        _atomic_write(self._chunk_path(cid), data)
        self.done.add(cid)
        with open(self.log_path, "a") as f:
            f.write(json.dumps({"chunk": cid, "session": self.session, "runs": len(chunk.runs),
                                "elapsed_s": round(elapsed_s, 6), "task_chunks": task_chunks}) + "\n")

    def log(self) -> list[dict]:
        if not self.log_path.exists():
            return []
        out = []
        for line in self.log_path.read_text().splitlines():
            try:
                out.append(json.loads(line))
            except ValueError:          # a line cut by a kill
                pass
        return out

    # -- the final table ---------------------------------------------------------------------------------
    def rows(self) -> list[list[str]]:
        """All sweep rows (strings, as stored) ordered by run id."""
        return list(csv.reader(self.lines()))

    def lines(self) -> list[str]:
        """All sweep rows as stored (CSV lines without the line end), ordered by run id.

        The chunk files are merged as text; a chunk with quoted fields is parsed and written again with
        the same writer, which gives the same text (so the table is what parsing every row would give)."""
        lines: list[str] = []
        for cid in sorted(self.done):
            body = self._bodies.get(cid)
            if body is None:                    # a chunk of an earlier session
                body = self._chunk_path(cid).read_text().split("\n", 1)[1]
            if '"' not in body and "\r" not in body:
                lines.extend(body.split("\n")[:-1])
                continue
            for row in csv.reader(io.StringIO(body, newline="")):      # a field may hold a line end
                buf = io.StringIO()
                csv.writer(buf, lineterminator="\n").writerow(row)
                lines.append(buf.getvalue()[:-1])
        ids = [r for cid in sorted(self.done) for r in self.spec.chunks[cid].runs]
        if any(a >= b for a, b in zip(ids, ids[1:])):     # chunks of several batch groups interleave
            lines.sort(key=lambda ln: int(ln[:ln.index(",")]))
        return lines

    def outcomes(self) -> tuple[np.ndarray, np.ndarray]:
        """``ok[n]`` and ``metrics[n, n_outputs]`` of every stored run (chunk order): the computed values
        of this session's chunks, the parsed ones of earlier sessions' (equal: stored as ``repr``)."""
        n_out = len(self.spec.metric_columns())
        oks, mets = [], []
        for cid in sorted(self.done):
            v = self._values.get(cid)
            if v is None:
                body = self._chunk_path(cid).read_text().split("\n", 1)[1]
                tail = np.array([ln.rsplit(",", n_out + 1)[1:] for ln in body.split("\n")[:-1]], dtype=float)
                v = (tail[:, 0] == 1.0, tail[:, 1:])
            oks.append(v[0])
            mets.append(v[1].reshape(len(v[0]), n_out))
        if not oks:
            return np.zeros(0, bool), np.zeros((0, n_out))
        return np.concatenate(oks), np.concatenate(mets)

    def write_lines(self, header: Sequence[str], lines: Sequence[str], name: str) -> Path:
        """The CSV table from rows already formatted (:meth:`lines`)."""
        buf = io.StringIO()
        csv.writer(buf, lineterminator="\n").writerow(header)
        path = self.out / f"{name}.csv"
        _atomic_write(path, (buf.getvalue() + "".join(ln + "\n" for ln in lines)).encode())
        return path

    def drive_rows(self) -> list[dict]:
        return [json.loads(self._chunk_path(cid).read_text()) for cid in sorted(self.done)]

    def write_table(self, header: Sequence[str], rows: Iterable[Sequence], name: str, fmt: str = "csv") -> Path:
        rows = list(rows)
        if fmt == "parquet":
            import pyarrow as pa
            import pyarrow.parquet as pq
            cols = {h: [_parse(r[i]) for r in rows] for i, h in enumerate(header)}
            path = self.out / f"{name}.parquet"
            pq.write_table(pa.table(cols), path)
            return path
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(header)
        w.writerows([[_fmt(x) for x in r] for r in rows])
        path = self.out / f"{name}.csv"
        _atomic_write(path, buf.getvalue().encode())
        return path

    def finish_session(self, **info) -> None:
        self.manifest["sessions"][-1].update(info)
        _atomic_write(self.manifest_path, json.dumps(self.manifest, indent=1, default=str).encode())


def _parse(s: str):
    try:
        return int(s)
    except ValueError:
        try:
            return float(s)
        except ValueError:
            return s
