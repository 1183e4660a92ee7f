"""Reading a study description of any kind (``susp study``): a parameter sweep or a batch validation of
recorded drives (:mod:`.spec`), a ride study of damper controllers (:mod:`.ride`) or a damper-inspection
ROC study (:mod:`..inspection.roc`). Each kind parses its own keys; this module only dispatches, so the
kinds do not import each other.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from ...errors import ConfigError
from ...model.paper import VARIANTS
from ..inspection.roc import roc_spec
from .ride import ride_study
from .spec import TOP_KEYS, StudySpec, _drives, _sweep


def load_study(path: str | Path) -> StudySpec:
    """Read and validate a study YAML; expand it into runs and chunks."""
    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text())
    except FileNotFoundError:
        raise ConfigError(f"{path}: study file not found") from None
    except (OSError, yaml.YAMLError) as exc:
        raise ConfigError(f"{path}: cannot read study YAML: {exc}") from None
    return study_from_dict(data, str(path))


def drives_study(folder: str | Path, variants=VARIANTS,
                 name: str = "drives", source: str = "--drives", diagnose: bool = False) -> StudySpec:
    """A batch-validation (and, with ``diagnose``, diagnosis) study over every ``*.mcap`` in ``folder``."""
    return study_from_dict({"name": name, "kind": "drives", "folder": str(folder),
                            "variants": list(variants), "diagnose": diagnose}, source)


def study_from_dict(data: Any, source: str = "<study>") -> StudySpec:
    if not isinstance(data, dict):
        raise ConfigError(f"{source}: a study must be a mapping of keys, got {type(data).__name__}")
    unknown = set(data) - TOP_KEYS
    if unknown and data.get("kind") != "ride":  # a ride study checks its own keys
        raise ConfigError(f"{source}: unknown key(s) {', '.join(sorted(unknown))}; "
                          f"known: {', '.join(sorted(TOP_KEYS))}")
    kind = data.get("kind", "sweep")
    name = data.get("name", Path(source).stem)
    if not isinstance(name, str) or not name or any(c in name for c in "/\\ "):
        raise ConfigError(f"{source}: name: expected a short name without spaces or slashes, got {name!r}")
    if kind == "drives":
        return _drives(data, source, name)
    if kind == "ride":
        return ride_study(data, source, name)
    if kind == "roc":  # damper-inspection detection study (issue 14)
        return roc_spec(data, source, name)
    if kind != "sweep":
        raise ConfigError(f"{source}: kind: expected 'sweep', 'drives', 'ride' or 'roc', got {kind!r}")
    return _sweep(data, source, name)
