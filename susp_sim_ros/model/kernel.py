"""Generation and loading of the compiled kernel for one list of physics terms.

Numba compiles calls to known functions only, so the list of terms is baked into the kernel: the
template ``_kernel_template.py`` gets its TERMS block replaced by direct calls to each term's ``force``
and ``update`` functions at the term's parameter/state offsets. The generated module is written to a
cache directory under a content hash and imported from there, so numba's on-disk cache
(``cache=True``) keeps the machine code across processes: only the first run of a new term list pays
the compile time (about 20 s).

Cache directory: ``$SUSP_SIM_CACHE`` if set, else ``$XDG_CACHE_HOME/susp_sim_ros`` or
``~/.cache/susp_sim_ros``; a temporary directory if none of these is writable.
"""
from __future__ import annotations

import hashlib
import importlib.util
import inspect
import os
import sys
import tempfile
import threading
from pathlib import Path
from types import ModuleType

from .layout import KernelLayout
from .terms import PhysicsTerm

_TEMPLATE = Path(__file__).with_name("_kernel_template.py")
_BEGIN, _END = "# @@BEGIN TERMS@@", "# @@END TERMS@@"
_MASK = {"axle": 1, "damper": 2}
_loaded: dict[str, ModuleType] = {}
_lock = threading.Lock()


def _cache_dir() -> Path:
    candidates = []
    if os.environ.get("SUSP_SIM_CACHE"):
        candidates.append(Path(os.environ["SUSP_SIM_CACHE"]))
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    candidates.append(Path(base) / "susp_sim_ros")
    candidates.append(Path(tempfile.gettempdir()) / f"susp_sim_ros-{os.getuid()}")
    for d in candidates:
        try:
            d.mkdir(parents=True, exist_ok=True)
            probe = d / ".probe"
            probe.write_text("ok")
            probe.unlink()
            return d
        except OSError:
            continue
    raise OSError(f"no writable kernel cache directory among {', '.join(map(str, candidates))}")


def _terms_block(terms: tuple[PhysicsTerm, ...], layout: KernelLayout) -> str:
    lines = []
    for k, t in enumerate(terms):
        for kind, fn in (("f", t.force), ("u", t.update)):
            py = fn.py_func
            lines.append(f"from {py.__module__} import {py.__name__} as _{kind}{k}")
    lines += ["", f"N_P = {layout.n_p}", f"N_S = {layout.n_s}"]
    # one vehicle, terms selected by component (the rig)
    lines += ["", "", "@njit(cache=True, inline=\"always\")", "def terms_force(p, s, i, c, mask):", "    f = 0.0"]
    for k, t in enumerate(terms):
        po, so = layout.param_offsets[k], layout.state_offsets[k]
        lines.append(f"    if mask & {_MASK[t.component]}:  # {t.name}")
        lines.append(f"        f += _f{k}(p, {po}, s, {so}, i, c)")
    lines += ["    return f", "", "", "@njit(cache=True, inline=\"always\")", "def terms_update(p, s, i, c, dx, mask):"]
    for k, t in enumerate(terms):
        po, so = layout.param_offsets[k], layout.state_offsets[k]
        lines.append(f"    if mask & {_MASK[t.component]}:  # {t.name}")
        lines.append(f"        _u{k}(p, {po}, s, {so}, i, c, dx)")
    if not terms:
        lines.append("    pass")
    lines += _lane_lines(terms, layout)
    return "\n".join(lines)


def _lane_lines(terms: tuple[PhysicsTerm, ...], layout: KernelLayout) -> list[str]:
    """The block's terms, each in its own loop over the lanes, behind a test of the block's active-term
    mask: ``active_terms(P, nl)`` sets bit ``k`` when term ``k`` declares no gains
    (:attr:`PhysicsTerm.gains`) or one of them is non-zero at some corner of some lane. A term at zero gain
    in every lane of the block is skipped (its force is zero then; its states rest as unloaded). The test
    sits outside the lane loops, so each loop still runs its vehicles on SIMD instructions. The forces are
    summed in the terms' order, as :func:`terms_force` sums them."""
    if len(terms) > 62:
        raise ValueError(f"{len(terms)} physics terms: the kernel's active-term mask holds at most 62")
    lines = ["", "", "@njit(cache=True, inline=\"always\")", "def active_terms(P, nl):", "    act = 0"]
    for k, t in enumerate(terms):
        if not t.gains:
            lines.append(f"    act |= {1 << k}  # {t.name}: always")
            continue
        rows = [layout.param_offsets[k] + 4 * t.param_index(g) + i for g in t.gains for i in range(4)]
        lines += [f"    g = 0.0  # {t.name}: {', '.join(t.gains)}", "    for l in range(nl):"]
        lines += [f"        g += abs(P[{r}, l])" for r in rows]
        lines += ["    if g != 0.0:  # NaN counts as acting", f"        act |= {1 << k}"]
    lines += ["    return act", "", "", "@njit(cache=True, inline=\"always\")",
              "def terms_force_lanes(P, S, C, W, r, i, nl, act):",
              "    for l in range(nl):", "        W[r, l] = 0.0"]
    for k, t in enumerate(terms):
        po, so = layout.param_offsets[k], layout.state_offsets[k]
        lines += [f"    if act & {1 << k}:  # {t.name}", "        for l in range(nl):",
                  f"            W[r, l] += _f{k}(P[:, l], {po}, S[:, l], {so}, i, C[:, :, l])"]
    lines += ["", "", "@njit(cache=True, inline=\"always\")", "def terms_update_lanes(P, S, C, W, r, i, nl, act):"]
    for k, t in enumerate(terms):
        po, so = layout.param_offsets[k], layout.state_offsets[k]
        lines += [f"    if act & {1 << k}:  # {t.name}", "        for l in range(nl):",
                  f"            _u{k}(P[:, l], {po}, S[:, l], {so}, i, C[:, :, l], W[r, l])"]
    if not terms:
        lines.append("    pass")
    return lines


def _dependency_digest(terms: tuple[PhysicsTerm, ...]) -> str:
    """Hash of every source file the kernel compiles in. Numba's cache does not notice a change in a
    function imported from another file, so a change there must change the kernel's own file."""
    files = {Path(__file__).with_name(f) for f in ("layout.py", "terms.py", "inline_math.py", "friction_scaling.py")}
    for t in terms:
        for fn in (t.force, t.update):
            src = inspect.getsourcefile(fn.py_func)
            if src is None:
                raise ValueError(f"term {t.name}: no source file for {fn.py_func.__name__}; the kernel imports "
                                 f"a term's functions from their module file")
            files.add(Path(src))
    h = hashlib.sha256()
    for f in sorted(files):
        h.update(f.read_bytes())
    return h.hexdigest()[:16]


def kernel_source(terms: tuple[PhysicsTerm, ...], semi_active: bool = True) -> str:
    """Source text of the kernel module for ``terms`` (the template with its TERMS block filled);
    ``semi_active=False`` leaves the semi-active damper code out (a passive-only kernel)."""
    text = _TEMPLATE.read_text()
    if not semi_active:
        text = text.replace("\nSEMI_ACTIVE_CODE = True\n", "\nSEMI_ACTIVE_CODE = False\n", 1)
    head, rest = text.split(_BEGIN, 1)
    _, tail = rest.split(_END, 1)
    block = _terms_block(terms, KernelLayout.for_terms(terms))
    return f"{head}{_BEGIN}\n# dependencies: {_dependency_digest(terms)}\n{block}\n{_END}{tail}"


def load_kernel(terms: tuple[PhysicsTerm, ...], semi_active: bool = True) -> ModuleType:
    """The compiled kernel module for ``terms`` (generated, cached on disk, imported once per process);
    ``semi_active=False``: the passive-only kernel (:func:`kernel_source`)."""
    source = kernel_source(terms, semi_active)
    key = hashlib.sha256(source.encode()).hexdigest()[:16]
    with _lock:
        mod = _loaded.get(key)
        if mod is not None:
            return mod
        path = _cache_dir() / f"susp_kernel_{key}.py"
        if not path.exists() or path.read_text() != source:
            tmp = path.with_suffix(f".{os.getpid()}.tmp")
            tmp.write_text(source)
            os.replace(tmp, path)
        name = f"susp_kernel_{key}"
        spec = importlib.util.spec_from_file_location(name, path)
        if spec is None or spec.loader is None:
            raise ImportError(f"{path}: cannot load the generated kernel module")
        mod = importlib.util.module_from_spec(spec)
        sys.modules[name] = mod
        spec.loader.exec_module(mod)
        _loaded[key] = mod
        return mod
