"""First contact: ``--help`` of the CLI, of every subcommand and of every console script works (exit 0,
a usage line, no traceback) and starts nothing (the node scripts print their parameters and exit)."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from susp_sim_ros.cli.main import SUBCOMMANDS
from susp_sim_ros.ros.run import wants_help

BIN = Path(sys.executable).parent
CONSOLE_SCRIPTS = ("susp", "susp_sim_node", "susp_damper_controller")


def _help(*cmd: str) -> subprocess.CompletedProcess:
    return subprocess.run([*cmd, "--help"], capture_output=True, text=True, timeout=60)


def test_top_level_help_lists_every_subcommand():
    r = _help(str(BIN / "susp"))
    assert r.returncode == 0, r.stderr
    assert "Traceback" not in r.stderr and r.stdout.startswith("usage: susp")
    for name in SUBCOMMANDS:
        assert name in r.stdout


def test_top_level_help_imports_no_subcommand_implementation():
    """``susp --help`` is quick: the CLI's main module names the subcommands and imports a subcommand's
    implementation (numba kernels, scipy.signal, the model) only when that subcommand runs."""
    r = _help(str(BIN / "susp"))
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith("usage: susp") and "Traceback" not in r.stderr
    for name in SUBCOMMANDS:
        assert f"\n    {name}" in r.stdout, name
    code = ("import sys, susp_sim_ros.cli.main\n"
            "heavy = [m for m in ('scipy.signal', 'numba', 'susp_sim_ros.model') if m in sys.modules]\n"
            "print(','.join(heavy))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "", f"importing susp_sim_ros.cli.main imported {r.stdout.strip()}"


@pytest.mark.parametrize("name", sorted(SUBCOMMANDS))
def test_every_subcommand_help(name):
    r = _help(str(BIN / "susp"), name)
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith(f"usage: susp {name}") and "Traceback" not in r.stderr


@pytest.mark.parametrize("script", CONSOLE_SCRIPTS[1:])
def test_node_scripts_print_their_parameters_and_exit(script):
    """The node scripts answer ``--help`` without starting a node (no rclpy context, no DDS traffic):
    every declared parameter is listed with its default."""
    r = _help(str(BIN / script))
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith(f"usage: {script}") and "parameters:" in r.stdout
    assert "[INFO]" not in r.stdout + r.stderr          # no node was started
    expected = ("step_s", "publish_rate_hz", "damper_oil_level") if script == "susp_sim_node" else (
        "controller", "sample_time_s", "vehicle")
    for p in expected:
        assert p in r.stdout


def test_help_after_ros_args_is_not_ours():
    """``-h`` inside ``--ros-args`` belongs to ROS (``--ros-args -h``): only arguments outside it ask us."""
    assert wants_help(["susp_sim_node", "--help"])
    assert wants_help(["susp_sim_node", "-h", "--ros-args", "-p", "step_s:=0.001"])
    assert not wants_help(["susp_sim_node", "--ros-args", "-p", "step_s:=0.001"])
