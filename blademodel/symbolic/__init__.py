"""Symbolic derivation of the equations of motion, per contact mode."""

from .assembly import derive
from .scaling import ScaledSystem, scaled_equations
from .system import GuardSpec, HybridSystem, Mode, Transition

__all__ = ["derive", "HybridSystem", "Mode", "GuardSpec", "Transition",
           "ScaledSystem", "scaled_equations"]
