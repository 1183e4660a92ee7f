"""Parameter studies and batch validation on Dask (``susp study``).

- :mod:`.kinds`: reading a study description of any kind (``config/studies/*.yaml``);
- :mod:`.spec`: sweep and drives studies: validation, expansion into runs/chunks;
- :mod:`.runs`: a run's vehicle, model, parameter vector and maneuver (cached per process);
- :mod:`.ride`: ride studies of semi-active damper controllers;
- :mod:`.tasks`: what one task does (a chunk as one batched simulation, then metrics; one drive);
- :mod:`.store`: the resumable result store (one file per finished chunk);
- :mod:`.runner`: executors (in-process, local Dask cluster, existing scheduler) and the study loop;
- :mod:`.plot`: the figures.
"""
from .runner import DaskExecutor, InProcessExecutor, make_executor, run_study
from .kinds import drives_study, load_study, study_from_dict
from .spec import StudySpec

__all__ = ["DaskExecutor", "InProcessExecutor", "make_executor", "run_study", "StudySpec", "drives_study",
           "load_study", "study_from_dict"]
