"""Analyses of simulation results: pure functions of results (the Lyapunov
estimate advances a given integrator, nothing else)."""

from .classify import CHAOS_THRESHOLD, classify_motion, motion_class
from .lyapunov import largest_lyapunov
from .periodicity import periodicity_label, poincare_period
from .reduction import mean_square, vibration_reduction
from .spectrum import amplitude_spectrum, harmonic_amplitudes

__all__ = ["poincare_period", "periodicity_label", "amplitude_spectrum", "harmonic_amplitudes", "largest_lyapunov",
           "mean_square", "vibration_reduction", "classify_motion", "motion_class", "CHAOS_THRESHOLD"]
