"""Parameter sweeps: study specs, grids, executors and incremental storage."""

from .runner import open_result, points, run_study
from .spec import Axis, RunSettings, Study, load_study

__all__ = ["Study", "Axis", "RunSettings", "load_study", "run_study", "open_result", "points"]
