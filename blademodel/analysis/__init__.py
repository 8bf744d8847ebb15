"""Analyses of simulation results: pure functions, no integration."""

from .periodicity import periodicity_label, poincare_period

__all__ = ["poincare_period", "periodicity_label"]
