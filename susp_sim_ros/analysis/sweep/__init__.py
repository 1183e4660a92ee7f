"""Parameter studies and batch validation on Dask (``susp study``).

- :mod:`.spec`: study descriptions (``config/studies/*.yaml``), validation, expansion into runs/chunks;
- :mod:`.engine`: what one task does (a chunk as one batched simulation, then metrics; one drive);
- :mod:`.store`: the resumable result store (one file per finished chunk);
- :mod:`.runner`: executors (in-process, local Dask cluster, existing scheduler) and the study loop;
- :mod:`.plot`: the figures.
"""
from .runner import DaskExecutor, InProcessExecutor, make_executor, run_study
from .spec import StudySpec, drives_study, load_study, study_from_dict

__all__ = ["DaskExecutor", "InProcessExecutor", "make_executor", "run_study", "StudySpec", "drives_study",
           "load_study", "study_from_dict"]
