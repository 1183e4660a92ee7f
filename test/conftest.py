"""Shared test set-up: an isolated ROS 2 environment and session-wide models (kernels compile once)."""
import os
import random
import sys
import tempfile
from pathlib import Path

import pytest

import susp_sim_ros  # noqa: F401  before any test module imports numpy: its idle-thread settings (idle_threads.py)

# the repository root: the truth generators (truth_generators/) and benchmarks/ are not installed
ROOT = str(Path(__file__).resolve().parents[1])
if ROOT not in sys.path:
    sys.path.insert(0, ROOT)

os.environ.setdefault("ROS_DOMAIN_ID", str(random.randint(1, 101)))
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
os.environ.setdefault("ROS_LOG_DIR", tempfile.mkdtemp(prefix="susp-roslog-"))


@pytest.fixture(scope="session")
def model_full():
    from susp_sim_ros.model import Model
    return Model("passat_b8_like", "full")


@pytest.fixture(scope="session")
def models():
    from susp_sim_ros.model import Model
    return {v: Model("passat_b8_like", v) for v in ("full", "no_horizontal", "no_velocity", "dahl_only")}
