"""Helpers the tests share: run the ``susp`` command line in-process, and interrupt a study after n chunks."""
from __future__ import annotations

import contextlib
import io
import json

from susp_sim_ros.cli.main import main


def run_cli(argv) -> tuple[int, str, str]:
    """``susp ARGV`` in this process: (exit code, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main([str(a) for a in argv])
    return rc, out.getvalue(), err.getvalue()


def cli_json(argv) -> dict:
    """``susp ARGV --json``, which must succeed: its JSON."""
    rc, out, err = run_cli(list(argv) + ["--json"])
    assert rc == 0, err
    return json.loads(out)


class Interrupt(Exception):
    """Raised by :func:`stop_after` to kill a study in the middle."""


def stop_after(n: int):
    """An ``on_chunk`` hook for ``run_study`` that raises :class:`Interrupt` after ``n`` stored chunks."""
    seen = []

    def hook(cid):
        seen.append(cid)
        if len(seen) == n:
            raise Interrupt()
    return hook
