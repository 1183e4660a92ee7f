"""Damper inspection (issue 14): oil level per damper from drives, workshop-method statistics, ROC."""
from .estimate import Inspection, inspect_drives, load_config, scale_accuracy, state_of

__all__ = ["Inspection", "inspect_drives", "load_config", "scale_accuracy", "state_of"]
