"""Numerics: generated code, the compiled hybrid RK4 kernel, results."""

from .compiled import CompiledSystem, compile_model
from .result import SimulationError, SimulationResult
from .integrator import HybridIntegrator, excitation_period
from .simulate import simulate
from .contact_kernel import ContactIntegrator
from .kernels import make_integrator
from .stability import StepTooLargeError

__all__ = ["simulate", "HybridIntegrator", "ContactIntegrator", "make_integrator", "compile_model", "CompiledSystem", "SimulationResult", "SimulationError",
           "StepTooLargeError", "excitation_period"]
