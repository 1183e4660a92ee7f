"""README's physics-term example compiles and works as it is printed (the blocks are taken from README)."""
from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np

from susp_sim_ros.model import Model, simulate
from susp_sim_ros.model.maneuvers import bump_crossing, vehicle_state

README = Path(__file__).resolve().parents[1] / "README.md"
DT = 0.001


def _blocks(section: str) -> dict[str, str]:
    """The fenced code blocks of README's section whose heading starts with ``section``, by language."""
    text = README.read_text()
    start = text.index(f"## {section}")
    end = text.index("\n## ", start + 3)
    return {lang: body for lang, body in re.findall(r"```(\w+)\n(.*?)```", text[start:end], re.S)}


def test_readme_physics_term_example_compiles_and_damps(tmp_path, monkeypatch):
    blocks = _blocks("Physics terms")
    (tmp_path / "my_damping.py").write_text(blocks["python"])
    (tmp_path / "my_variant.yaml").write_text(blocks["yaml"])
    monkeypatch.syspath_prepend(str(tmp_path))
    try:
        model = Model(variant=str(tmp_path / "my_variant.yaml"))
        base = Model(variant="full")
        assert [t.name for t in model.terms][-1] == "my_damping"
        man = bump_crossing()
        oil = vehicle_state("front_empty")

        def pitch(m):
            return simulate(m, man.to_inputs(DT), dt=DT, road=man.road, oil=oil, outputs=["pitch_rate"])["pitch_rate"]

        k0 = int((man.road.s[-1] + model.vehicle.wheelbase) / man.speed / DT)  # rear axle leaves the bump
        ring = slice(k0, k0 + 1500)
        # 150 / 80 N s/m beside an oil-empty front damper: the ring-out loses energy faster
        assert np.sum(pitch(model)[ring] ** 2) < 0.95 * np.sum(pitch(base)[ring] ** 2)
    finally:
        sys.modules.pop("my_damping", None)


def test_public_api_is_importable_and_lazy():
    """Every name of ``susp_sim_ros.__all__`` resolves; importing the package loads none of the layers
    (and never rclpy) until a name is used."""
    import subprocess
    code = ("import sys, susp_sim_ros as s; assert 'susp_sim_ros.model' not in sys.modules; "
            "[getattr(s, n) for n in s.__all__]; assert 'rclpy' not in sys.modules; print(len(s.__all__))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-800:]
    assert int(r.stdout) >= 5


def _docstring_example() -> str:
    import susp_sim_ros
    return "\n".join(line[4:] for line in susp_sim_ros.__doc__.split("::", 1)[1].strip("\n").split("\n")
                     if line.startswith("    ") or not line.strip())


def test_readme_api_example_is_the_package_docstring_example():
    """README's Python API example is the package docstring's (which the next test runs)."""
    assert _blocks("Python API")["python"].strip() == _docstring_example().strip()


def test_package_docstring_example_runs():
    """The example in ``susp_sim_ros.__doc__`` (and README's Python API section) runs as printed on the
    bundled drive and gives what its comments say."""
    import os

    from susp_sim_ros.model import Response
    from susp_sim_ros.runtime.lockstep import LockstepRun
    ns: dict = {}
    root = Path(__file__).resolve().parents[1]
    cwd = os.getcwd()
    os.chdir(root)
    try:
        exec(compile(_docstring_example(), "susp_sim_ros.__doc__", "exec"), ns)
    finally:
        os.chdir(cwd)
    resp, sim, pred = ns["resp"], ns["sim"], ns["pred"]
    assert isinstance(resp, Response) and isinstance(pred, Response)
    assert isinstance(sim, LockstepRun) and isinstance(sim.response, Response)
    assert resp.units["pitch_rate"] == "rad/s" and 0.01 < ns["peak"] < 1.0
    assert list(ns["table"].columns) == list(resp.labels) and ns["table"].index.name == "time_s"
    assert len(sim.t_ns) > 100 and 0.0 < ns["rmse"] < 1.0  # deg/s: the model follows the drive
    rep = ns["report"]
    assert rep["verdict"] in ("missing_physics", "no_significant_discrepancy", "unexplained_residual")
    assert rep["heldout_rmse_after_deg_s"] <= rep["heldout_rmse_before_deg_s"]
    assert 0.0 < ns["score"] <= 1.0 and "pitch_rate" in pred
    assert ns["summary"]["runs_ok"] == ns["summary"]["n_runs"] == len(ns["study"].runs)
