"""Motion type from the Poincare samples and the largest Lyapunov exponent."""

from __future__ import annotations

import math

from .periodicity import poincare_period

#: A largest Lyapunov exponent (per excitation period) above this is called chaos,
#: within +-this of zero quasi-periodic. Periodic attractors of the blade pair sit
#: well below zero (-0.444 per period for Table 1: the in-phase motion the contact
#: never feels decays at cx / 2m).
CHAOS_THRESHOLD = 0.02


def motion_class(period: int, lyapunov: float | None = None) -> str:
    """The motion class from a detected period and the largest Lyapunov exponent.

    ``"P<n>"`` when a period ``n >= 1`` was found; otherwise ``"chaos"`` for an
    exponent above :data:`CHAOS_THRESHOLD`, ``"quasi-periodic"`` within it of zero,
    and ``"nonperiodic"`` for a clearly negative exponent (an attracting motion with
    a period above the largest looked for, or an unfinished transient) or without one.
    """
    if period:
        return f"P{int(period)}"
    if lyapunov is None or math.isnan(lyapunov):
        return "nonperiodic"
    if lyapunov > CHAOS_THRESHOLD:
        return "chaos"
    return "quasi-periodic" if lyapunov >= -CHAOS_THRESHOLD else "nonperiodic"


def classify_motion(poincare, lyapunov: float | None = None, *, max_period: int = 16,
                    rtol: float = 1e-5) -> str:
    """``"P<n>"``, ``"chaos"``, ``"quasi-periodic"`` or ``"nonperiodic"`` (:func:`motion_class`).

    Parameters
    ----------
    poincare : array_like
        Poincare samples after the transient.
    lyapunov : float, optional
        Largest Lyapunov exponent per period; without it a motion with no period
        up to ``max_period`` is only called ``"nonperiodic"``.
    """
    return motion_class(poincare_period(poincare, max_period=max_period, rtol=rtol), lyapunov)
