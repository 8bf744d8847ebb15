"""Numerics: generated code, the compiled hybrid RK4 kernel, results."""

from .compiled import CompiledSystem, compile_model
from .result import SimulationError, SimulationResult
from .integrator import HybridIntegrator, excitation_period
from .simulate import simulate
from .stability import StepTooLargeError

__all__ = ["simulate", "HybridIntegrator", "compile_model", "CompiledSystem", "SimulationResult", "SimulationError",
           "StepTooLargeError", "excitation_period"]
