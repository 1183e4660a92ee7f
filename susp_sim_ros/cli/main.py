"""``susp``: the command-line shell over the pure core (interface.md, "Command line").

Each subcommand lives in its own module ``susp_sim_ros.cli.<name>`` exposing ``add_arguments(parser)``
and ``run(args) -> dict``. The returned dict is printed as one JSON object with ``--json`` (logs go to
stderr), else as a human summary (its ``"summary"`` entry if present). Exit codes: 0 success, 2 bad
input (:class:`~susp_sim_ros.errors.SuspInputError`, message only, no traceback), 1 otherwise.
"""
from __future__ import annotations

import argparse
import importlib
import json
import os
import sys
from types import ModuleType

import numpy as np

from ..errors import SuspInputError
from ..io import integrity

SUBCOMMANDS = {
    "sim": "offline run: a paper maneuver or a recorded test drive (lockstep); writes a simulated MCAP",
    "rig": "virtual test rigs: axle friction rig, damper hydropulser, EUSAMA/phase-shift wheel-plate bench",
    "paper": "the paper's maneuvers x vehicle states x friction variants, with table, plots and report",
    "replay": "play a recorded test drive onto its topics with /clock",
    "recover": "make a recording from a killed process readable again (finalise it)",
    "validate": "compare measured and simulated drives, or run the paper-style study over a folder",
    "diagnose": "the discrepancy finder over one or more drives",
    "inspect": "damper oil level per wheel with 95 % intervals from recorded drives (bump crossing)",
    "study": "a parameter study from config/studies/*.yaml on Dask",
    "generate": "write the synthetic reference test drives (bags/)",
    "import-csv": "convert a CSV measurement into a recorded test drive MCAP",
    "import": "convert a measurement (ASAM MDF4 or CSV, road OpenCRG or CSV) into a recorded test drive MCAP",
}
#: subcommands that check every recording they read (io/integrity.py) and report ``input_findings``
INTEGRITY_COMMANDS = ("sim", "validate", "diagnose", "inspect", "replay")
#: subcommands whose module name is not the command name (``import`` is a Python keyword)
MODULE_NAMES = {"import": "import_measurement"}


def _module(name: str):
    return importlib.import_module(f"susp_sim_ros.cli.{MODULE_NAMES.get(name, name.replace('-', '_'))}")


def build_parser(available: dict[str, ModuleType]) -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="susp", description=__doc__.split("\n")[0])
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name, mod in available.items():
        # argparse %-formats help strings (not descriptions): a literal "95 %" must be written "95 %%"
        p = sub.add_parser(name, help=SUBCOMMANDS[name].replace("%", "%%"), description=SUBCOMMANDS[name])
        p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
        mod.add_arguments(p)
    return parser


def _available() -> dict[str, ModuleType]:
    out = {}
    for name in SUBCOMMANDS:
        try:
            out[name] = _module(name)
        except ModuleNotFoundError as exc:
            if exc.name != f"susp_sim_ros.cli.{MODULE_NAMES.get(name, name.replace('-', '_'))}":
                raise
    return out


def _print_human(result: dict) -> None:
    if "summary" in result:
        print(result["summary"])
        return
    for k, v in result.items():
        print(f"{k}: {v}")


def main(argv: list[str] | None = None) -> int:
    available = _available()
    args = build_parser(available).parse_args(argv)
    integrity.start_collection()
    try:
        result = available[args.command].run(args)
        if args.command in INTEGRITY_COMMANDS and isinstance(result, dict):
            result["input_findings"] = integrity.collected()  # interface.md: input integrity
    except SuspInputError as exc:
        print(f"susp {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"susp {args.command}: interrupted", file=sys.stderr)
        return 1
    except Exception as exc:  # an unexpected failure: say what, keep the traceback for --debug users
        if "--debug" in sys.argv or os.environ.get("SUSP_DEBUG"):
            raise
        print(f"susp {args.command}: failed: {type(exc).__name__}: {exc} (set SUSP_DEBUG=1 for a traceback)",
              file=sys.stderr)
        return 1
    if args.json:
        json.dump(result, sys.stdout, default=_jsonable)
        sys.stdout.write("\n")
    else:
        _print_human(result)
    return 0


def _jsonable(x):
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    return str(x)


if __name__ == "__main__":
    sys.exit(main())
