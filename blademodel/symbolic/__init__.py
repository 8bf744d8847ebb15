"""Symbolic derivation of the equations of motion, per contact mode."""

from .assembly import derive
from .scaling import ScaledSystem, eq11_discrepancy, paper_eq11, scaled_equations
from .system import GuardSpec, HybridSystem, Mode, Transition

__all__ = ["derive", "HybridSystem", "Mode", "GuardSpec", "Transition",
           "ScaledSystem", "scaled_equations", "paper_eq11", "eq11_discrepancy"]
