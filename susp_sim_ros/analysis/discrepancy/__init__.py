"""The discrepancy finder: locate where simulation and recorded drives differ beyond sensor noise, name
the missing physics from a library of candidate terms, fit it jointly across drives, prove the fit on
held-out drives, and write the extended model as a variant the node can run.

Modules: :mod:`.data` (drives -> inputs and comparison grid), :mod:`.candidates` (the named candidate
library), :mod:`.engine` (batch simulation and residuals), :mod:`.locate` (noise floor, windows),
:mod:`.fit` (least squares, screening, criterion), :mod:`.finder` (the estimator:
``DiscrepancyFinder().fit(drives).report()``), :mod:`.report` (JSON, variant YAML, plots, Markdown).
"""
from .candidates import LIBRARY
from .finder import DiscrepancyFinder

__all__ = ["DiscrepancyFinder", "LIBRARY"]
