"""Runs one parsed ``susp`` subcommand (imported by :mod:`~susp_sim_ros.cli.main` only when a subcommand
runs): input-integrity findings, exit codes and printing of the result (interface.md, "Command line")."""
from __future__ import annotations

import argparse
import json
import os
import sys
from types import ModuleType

from ..errors import SuspInputError
from ..io import integrity
from ..io.json_values import jsonable


def run_command(name: str, module: ModuleType | None, args: argparse.Namespace, *, integrity_findings: bool) -> int:
    """Run subcommand ``name`` (its ``module.run(args)``) and print its result; the exit code: 0 success,
    2 bad input (:class:`~susp_sim_ros.errors.SuspInputError`, message only), 1 otherwise. With
    ``integrity_findings`` the result gets the input-integrity findings of every recording read
    (``input_findings``, io/integrity.py)."""
    if module is None:
        raise ValueError(f"susp {name}: its module was not imported")
    integrity.start_collection()
    try:
        result = module.run(args)
        if integrity_findings and isinstance(result, dict):
            result["input_findings"] = integrity.collected()  # interface.md: input integrity
    except SuspInputError as exc:
        print(f"susp {name}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"susp {name}: interrupted", file=sys.stderr)
        return 1
    except Exception as exc:  # an unexpected failure: say what, keep the traceback for --debug users
        if "--debug" in sys.argv or os.environ.get("SUSP_DEBUG"):
            raise
        print(f"susp {name}: failed: {type(exc).__name__}: {exc} (set SUSP_DEBUG=1 for a traceback)",
              file=sys.stderr)
        return 1
    if args.json:
        json.dump(result, sys.stdout, default=jsonable)
        sys.stdout.write("\n")
    else:
        _print_human(result)
    return 0


def _print_human(result: dict) -> None:
    if "summary" in result:
        print(result["summary"])
        return
    for k, v in result.items():
        print(f"{k}: {v}")



__all__ = ["run_command"]
