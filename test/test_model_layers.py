"""The pure core imports no rclpy (three layers, one direction of imports)."""
import subprocess
import sys

import pytest


@pytest.mark.parametrize("module", ["susp_sim_ros.model", "susp_sim_ros.model.rigs",
                                    "susp_sim_ros.model.maneuvers", "susp_sim_ros.analysis.paper_study",
                                    "susp_sim_ros.cli.main", "susp_sim_ros.io.topic_map", "susp_sim_ros.io.reader",
                                    "susp_sim_ros.analysis.measurement_import"])
def test_core_does_not_import_rclpy(module):
    code = f"import sys, {module}; sys.exit(2 if 'rclpy' in sys.modules else 0)"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, f"{module} pulled in rclpy (rc {r.returncode}): {r.stderr[-500:]}"
