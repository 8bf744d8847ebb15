"""Largest Lyapunov exponent by the two-trajectory (Benettin) method."""

from __future__ import annotations

import numpy as np

from ..numeric.integrator import HybridIntegrator


def largest_lyapunov(integrator: HybridIntegrator, y, mode: int, *, start_period: int, periods: int,
                     scale, d0: float = 1e-8) -> float:
    """Largest Lyapunov exponent, in 1/period, of the motion through ``(y, mode)``.

    A companion trajectory starts at scaled distance ``d0``; after each excitation
    period the scaled distance ``d`` is measured, ``log(d / d0)`` accumulated and the
    companion pulled back along the separation to distance ``d0``, in the reference's
    mode: at that distance the reference's mode is consistent with the companion's
    state up to ``O(d0)`` (re-deriving the mode would re-apply entry resets such as
    the Jenkins ``z = 0``). For a non-smooth system this finite-difference form is
    the usual practical estimate (no saltation matrices needed).

    A friction law's state that a period leaves unchanged to the bit in both
    trajectories (a Jenkins or Iwan stretch while its contact stays open: nothing
    moves it and it moves nothing, and the next entry into contact resets it) is
    **held**: its separation is left out of that period's distances and pulled back
    to the reference's value. Counted, it is a neutral direction (multiplier 1) of
    the extended state that no motion of the blades reaches, and the estimate of a
    contact-free bilinear orbit tended to 0 instead of ``ln |mu_1|`` of its orbit.
    A period in which no law state is held is measured as before, to the bit.

    Parameters
    ----------
    integrator : HybridIntegrator
    y : ndarray
        State on the attractor (after the transient); not modified.
    mode : int
    start_period : int
        Period index of ``y`` (the time is ``start_period * T``).
    periods : int
        Periods averaged over.
    scale : array_like
        Scale of each physical state for the distance (e.g. ``gap`` for
        displacements, ``gap * omega`` for velocities).
    d0 : float
        Scaled separation kept between the trajectories.

    Returns
    -------
    float
        ``lambda`` per excitation period; divide by ``T`` for 1/s. Negative for a
        stable periodic motion, about zero for quasi-periodic, positive for chaos.
    """
    n = integrator.n_physical
    scale = np.asarray(scale, dtype=float)[:n]
    a = np.array(y, dtype=float)
    direction = np.ones(n) / np.sqrt(n)
    b = a.copy()
    b[:n] += d0 * scale * direction
    law = integrator.law_states
    # the reference runs on a copy of its own: a call that goes on from where the last one ended keeps the kernel's
    # hybrid state of the run (guards read from their boundaries), which a call for the companion would clear
    reference = integrator.worker()
    mode_a = mode_b = mode
    total = 0.0
    for k in range(start_period, start_period + periods):
        start = (b[:n] - a[:n]) / scale
        law_a, law_b = a[law], b[law]
        sa, mode_a, _ = reference.advance(a, mode_a, k, k + 1)
        sb, mode_b, _ = integrator.advance(b, mode_b, k, k + 1)
        if sa or sb:
            raise RuntimeError(f"integration failed at period {k} while estimating the Lyapunov exponent")
        sep = (b[:n] - a[:n]) / scale
        held = law[(a[law] == law_a) & (b[law] == law_b) & (start[law] != 0.0)]
        d_start = d0
        if held.size:
            sep[held] = start[held] = 0.0
            d_start = float(np.linalg.norm(start))
        d = float(np.linalg.norm(sep))
        if d == 0.0:
            return -np.inf  # both trajectories collapsed onto the same state
        total += np.log(d / d_start)
        b[:n] = a[:n] + (sep * (d0 / d)) * scale
        b[n:] = a[n:]
        mode_b = mode_a
    return total / periods

