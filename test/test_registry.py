"""The maneuver registry (``model/paper.py`` ``MANEUVER_KINDS``) is the one list of the paper's maneuvers."""
import argparse
import ast
from pathlib import Path

import pytest
import yaml

from susp_sim_ros.cli import sim as sim_cli
from susp_sim_ros.errors import ConfigError
from susp_sim_ros.model import maneuvers
from susp_sim_ros.model.paper import (HEADLINE_MANEUVER, MANEUVER_CHOICES, MANEUVER_KINDS, MANEUVERS,
                                      PRIMARY_OUTPUT, RING_OUT_MANEUVERS, classify_maneuver, maneuver_kind)

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "susp_sim_ros"
#: the registry itself, and (for now) the discrepancy finder's data module, which another change owns
REGISTRY_MODULES = {PACKAGE / "model" / "paper.py"}


def _code_strings(tree: ast.AST):
    """Every string constant of a module that is not a docstring (f-string parts included)."""
    docs = {id(n.body[0].value) for n in ast.walk(tree)
            if isinstance(n, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef))
            and n.body and isinstance(n.body[0], ast.Expr) and isinstance(n.body[0].value, ast.Constant)}
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docs:
            yield node


def _sources():
    for f in sorted(PACKAGE.rglob("*.py")):
        yield f, ast.parse(f.read_text(), str(f))


def test_registry_matches_config():
    cfg = yaml.safe_load((ROOT / "config" / "maneuvers.yaml").read_text())
    assert set(cfg) - {"states"} == set(MANEUVER_KINDS) == set(MANEUVERS) == set(PRIMARY_OUTPUT)
    for kind in MANEUVER_KINDS.values():
        assert callable(getattr(maneuvers, kind.factory))
        assert maneuvers.paper_maneuver(kind.name).name == kind.name
        section = cfg[kind.config_section]
        assert [key for _, key in kind.config_keys] == list(section)
        assert maneuvers.maneuver_defaults(kind.name) == {kw: float(section[key]["value"])
                                                          for kw, key in kind.config_keys}
        # the study parameters are factory keywords, and so are the config keys
        keywords = {kw for kw, _ in kind.config_keys}
        assert {arg for _, arg in kind.sweep_arguments} <= keywords
        assert classify_maneuver(kind.label) == kind.name


def test_cli_offers_the_registry():
    """``susp sim --maneuver`` offers exactly the registry's names and aliases."""
    parser = argparse.ArgumentParser()
    sim_cli.add_arguments(parser)
    action = next(a for a in parser._actions if "--maneuver" in a.option_strings)
    assert set(action.choices) == set(MANEUVER_CHOICES) == {n for k in MANEUVER_KINDS.values() for n in k.names}
    assert HEADLINE_MANEUVER.name in MANEUVERS and set(RING_OUT_MANEUVERS) <= set(MANEUVERS)


def test_aliases_resolve_and_unknown_names_the_known():
    for kind in MANEUVER_KINDS.values():
        for name in kind.names:
            assert maneuver_kind(name) is kind
    with pytest.raises(ConfigError) as exc:
        maneuver_kind("slalom")
    for kind in MANEUVER_KINDS.values():
        assert kind.name in str(exc.value) and all(a in str(exc.value) for a in kind.aliases)


def test_no_code_branches_on_a_maneuver_name():
    """Outside the registry module no comparison (==, !=, in, ...) names a maneuver."""
    names = set(MANEUVERS)
    hits = []
    for f, tree in _sources():
        if f in REGISTRY_MODULES:
            continue
        for node in ast.walk(tree):
            if isinstance(node, ast.Compare):
                for sub in ast.walk(node):
                    if isinstance(sub, ast.Constant) and sub.value in names:
                        hits.append(f"{f.relative_to(ROOT)}:{node.lineno}: {sub.value!r}")
    assert not hits, "branch on a maneuver name; use the registry (maneuver_kind):\n" + "\n".join(hits)


def test_no_module_outside_the_registry_spells_a_maneuver_name():
    """No string in code (docstrings aside) outside the registry module holds a maneuver's name: lists,
    keys, labels and messages take it from the registry entry (``kind.name``, ``kind.label``)."""
    names = set(MANEUVERS)
    hits = [f"{f.relative_to(ROOT)}:{node.lineno}: {node.value!r}"
            for f, tree in _sources() if f not in REGISTRY_MODULES
            for node in _code_strings(tree) if any(n in node.value for n in names)]
    assert not hits, "a maneuver name spelt out; read the registry (model/paper.py):\n" + "\n".join(hits)
