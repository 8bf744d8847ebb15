"""Motion type from the Poincare samples and the largest Lyapunov exponent."""

from __future__ import annotations

import math

from .periodicity import poincare_period

#: A largest Lyapunov exponent (per excitation period) above this is called chaos.
#: Periodic attractors of the blade pair sit well below zero (about -0.3 and less
#: for the damping of Table 1); quasi-periodic motion gives about zero.
CHAOS_THRESHOLD = 0.02


def classify_motion(poincare, lyapunov: float | None = None, *, max_period: int = 16,
                    rtol: float = 1e-5) -> str:
    """``"P<n>"``, ``"chaos"``, ``"quasi-periodic"`` or ``"nonperiodic"``.

    Parameters
    ----------
    poincare : array_like
        Poincare samples after the transient.
    lyapunov : float, optional
        Largest Lyapunov exponent per period; without it a motion with no period
        up to ``max_period`` is only called ``"nonperiodic"``.
    """
    n = poincare_period(poincare, max_period=max_period, rtol=rtol)
    if n:
        return f"P{n}"
    if lyapunov is None or math.isnan(lyapunov):
        return "nonperiodic"
    return "chaos" if lyapunov > CHAOS_THRESHOLD else "quasi-periodic"
