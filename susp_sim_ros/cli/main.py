"""``susp``: the command-line shell over the pure core (interface.md, "Command line").

Each subcommand lives in its own module ``susp_sim_ros.cli.<name>`` exposing ``add_arguments(parser)``
and ``run(args) -> dict``. The returned dict is printed as one JSON object with ``--json`` (logs go to
stderr), else as a human summary (its ``"summary"`` entry if present). Exit codes: 0 success, 2 bad
input (:class:`~susp_sim_ros.errors.SuspInputError`, message only, no traceback), 1 otherwise.

This module stays light (``susp --help`` answers without numba, scipy or the model): it names the
subcommands, and imports a subcommand's module (with its implementation) and
:mod:`~susp_sim_ros.cli.dispatch` (running it, integrity findings, printing) only when that subcommand
is asked for, by module path.
"""
from __future__ import annotations

import argparse
import importlib
import importlib.util
import sys
from collections.abc import Mapping, Sequence
from types import ModuleType

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
#: the module that runs a parsed subcommand (imported only then)
DISPATCH_MODULE = "susp_sim_ros.cli.dispatch"


def module_path(name: str) -> str:
    """The module of subcommand ``name`` (``import-csv`` -> ``susp_sim_ros.cli.import_csv``)."""
    return f"susp_sim_ros.cli.{MODULE_NAMES.get(name, name.replace('-', '_'))}"


def _module(name: str) -> ModuleType:
    return importlib.import_module(module_path(name))


def build_parser(available: Mapping[str, ModuleType | None]) -> argparse.ArgumentParser:
    """The ``susp`` parser over ``available`` subcommands; a subcommand given as None is listed (name and
    help) without its arguments, so the top-level help needs none of the subcommand modules."""
    parser = argparse.ArgumentParser(prog="susp", description=(__doc__ or "").split("\n")[0])
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name, mod in available.items():
        # argparse %-formats help strings (not descriptions): a literal "95 %" must be written "95 %%"
        p = sub.add_parser(name, help=SUBCOMMANDS[name].replace("%", "%%"), description=SUBCOMMANDS[name])
        p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
        if mod is not None:
            mod.add_arguments(p)
    return parser


def _installed() -> list[str]:
    """The subcommands whose module is there (found, not imported)."""
    return [name for name in SUBCOMMANDS if importlib.util.find_spec(module_path(name)) is not None]


def _available() -> dict[str, ModuleType]:
    """Every installed subcommand's module, imported."""
    return {name: _module(name) for name in _installed()}


def _command(argv: Sequence[str]) -> str | None:
    """The subcommand ``argv`` names: its first argument that is not an option (``susp`` itself has only
    ``-h``), or None."""
    return next((a for a in argv if not a.startswith("-")), None)


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    name = _command(argv)
    available: dict[str, ModuleType | None] = dict.fromkeys(_installed())
    if name in available:
        available[name] = _module(name)
    args = build_parser(available).parse_args(argv)
    dispatch = importlib.import_module(DISPATCH_MODULE)
    return dispatch.run_command(args.command, available[args.command], args,
                                integrity_findings=args.command in INTEGRITY_COMMANDS)


if __name__ == "__main__":
    sys.exit(main())
