"""Numerics: generated code, the compiled hybrid RK4 kernel, results."""

from .compiled import CompiledSystem, compile_model
from .result import SimulationError, SimulationResult
from .simulate import excitation_period, simulate
from .stability import StepTooLargeError

__all__ = ["simulate", "compile_model", "CompiledSystem", "SimulationResult", "SimulationError",
           "StepTooLargeError", "excitation_period"]
