"""The maneuver registry (``model/paper.py`` ``MANEUVER_KINDS``) is the one list of the paper's maneuvers."""
import ast
from pathlib import Path

import pytest
import yaml

from susp_sim_ros.errors import ConfigError
from susp_sim_ros.model import maneuvers
from susp_sim_ros.model.paper import MANEUVER_KINDS, MANEUVERS, PRIMARY_OUTPUT, maneuver_kind

ROOT = Path(__file__).resolve().parents[1]


def test_registry_matches_config():
    cfg = yaml.safe_load((ROOT / "config" / "maneuvers.yaml").read_text())
    assert set(cfg) - {"states"} == set(MANEUVER_KINDS) == set(MANEUVERS) == set(PRIMARY_OUTPUT)
    for kind in MANEUVER_KINDS.values():
        assert callable(getattr(maneuvers, kind.factory))
        assert maneuvers.paper_maneuver(kind.name).name == kind.name


def test_aliases_resolve_and_unknown_names_the_known():
    for kind in MANEUVER_KINDS.values():
        for name in kind.names:
            assert maneuver_kind(name) is kind
    with pytest.raises(ConfigError) as exc:
        maneuver_kind("slalom")
    for kind in MANEUVER_KINDS.values():
        assert kind.name in str(exc.value) and all(a in str(exc.value) for a in kind.aliases)


def test_no_code_branches_on_a_maneuver_name():
    """Outside model/paper.py and model/maneuvers.py no comparison (==, !=, in, ...) names a maneuver."""
    names = set(MANEUVERS)
    exempt = {ROOT / "susp_sim_ros" / "model" / "paper.py", ROOT / "susp_sim_ros" / "model" / "maneuvers.py"}
    hits = []
    for f in sorted((ROOT / "susp_sim_ros").rglob("*.py")):
        if f in exempt:
            continue
        for node in ast.walk(ast.parse(f.read_text(), str(f))):
            if isinstance(node, ast.Compare):
                for sub in ast.walk(node):
                    if isinstance(sub, ast.Constant) and sub.value in names:
                        hits.append(f"{f.relative_to(ROOT)}:{node.lineno}: {sub.value!r}")
    assert not hits, "branch on a maneuver name; use the registry (maneuver_kind):\n" + "\n".join(hits)
