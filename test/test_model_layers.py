"""The pure core imports no rclpy; the layers of docs/architecture.md import one way, without cycles."""
import ast
import subprocess
import sys
from pathlib import Path

import pytest


@pytest.mark.parametrize("module", ["susp_sim_ros.model", "susp_sim_ros.model.rigs",
                                    "susp_sim_ros.model.maneuvers", "susp_sim_ros.analysis.paper_comparison",
                                    "susp_sim_ros.cli.main", "susp_sim_ros.io.topic_map", "susp_sim_ros.io.reader",
                                    "susp_sim_ros.analysis.measurement_import"])
def test_core_does_not_import_rclpy(module):
    code = f"import sys, {module}; sys.exit(2 if 'rclpy' in sys.modules else 0)"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, f"{module} pulled in rclpy (rc {r.returncode}): {r.stderr[-500:]}"


#: the layers of docs/architecture.md, lowest first; top-level modules (errors, progress,
#: idle_threads) are shared by all
LAYERS = {"model": 0, "io": 1, "control": 2, "runtime": 3, "analysis": 4, "cli": 5, "ros": 5}


def _import_graph() -> tuple[dict[str, Path], dict[str, set[str]]]:
    """Every module of the package and the package modules it imports (top-level or function-local;
    package ``__init__`` re-exports not counted)."""
    root = Path(__file__).resolve().parents[1] / "susp_sim_ros"
    mods = {}
    for f in root.rglob("*.py"):
        parts = f.relative_to(root.parent).with_suffix("").parts
        mods[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = f

    def resolve(cur, node):
        base = cur.split(".") if mods[cur].name == "__init__.py" else cur.split(".")[:-1]
        if node.level:
            base = base[: len(base) - node.level + 1]
        return ".".join(base + ([node.module] if node.module else []))

    edges: dict[str, set[str]] = {m: set() for m in mods}
    for m, f in mods.items():
        for n in ast.walk(ast.parse(f.read_text())):
            targets = []
            if isinstance(n, ast.Import):
                targets = [a.name for a in n.names]
            elif isinstance(n, ast.ImportFrom):
                t = resolve(m, n) if n.level else (n.module or "")
                targets = [t] + [f"{t}.{a.name}" for a in n.names]
            edges[m] |= {t for t in targets if t in mods and t != m and not m.startswith(t + ".")
                         and mods[t].name != "__init__.py"}
    return mods, edges


def test_no_import_cycle_between_modules():
    """No module imports (directly or through others) a module that imports it back; package
    ``__init__`` re-exports are not counted. Function-local imports count like top-level ones."""
    mods, edges = _import_graph()
    cycles, state = [], {}

    def visit(u, path):
        state[u] = 1
        for v in sorted(edges[u]):
            if state.get(v) == 1:
                cycles.append(path[path.index(v):] + [v])
            elif v not in state:
                visit(v, path + [v])
        state[u] = 2

    for m in sorted(mods):
        if m not in state and mods[m].name != "__init__.py":
            visit(m, [m])
    assert not cycles, "import cycles: " + "; ".join(" -> ".join(c) for c in cycles[:5])


def _layer(module: str) -> int:
    """The layer of a module; the package itself (its ``__init__``, which imports only top-level modules
    eagerly and re-exports the layers lazily) and the top-level modules are 0, shared by all."""
    parts = module.split(".")
    return LAYERS.get(parts[1], 0) if len(parts) > 1 else 0


def test_no_upward_import_between_layers():
    """docs/architecture.md's layers: a module imports only from its own layer or those below it
    (model <- io <- control <- runtime <- analysis <- cli, ros)."""
    mods, edges = _import_graph()
    upward = sorted(f"{m} -> {t}" for m in mods for t in edges[m] if _layer(t) > _layer(m))
    assert not upward, "upward imports: " + "; ".join(upward)


def test_layer_table_names_every_package():
    root = Path(__file__).resolve().parents[1] / "susp_sim_ros"
    packages = {p.name for p in root.iterdir() if (p / "__init__.py").is_file()}
    assert packages == set(LAYERS)
