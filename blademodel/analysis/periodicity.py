"""Period of a motion from its Poincare samples."""

from __future__ import annotations

import numpy as np


def poincare_period(samples, *, max_period: int = 16, rtol: float = 1e-5) -> int:
    """Smallest ``n <= max_period`` with ``samples[k + n] == samples[k]`` for all ``k``.

    Parameters
    ----------
    samples : array_like, shape (K,) or (K, d)
        Poincare samples after the transient (one per excitation period).
    max_period : int
        Largest period looked for; at least ``2 * max_period`` samples are needed
        to tell a period-``max_period`` motion.
    rtol : float
        Tolerance, relative to each column's largest magnitude over the samples.

    Returns
    -------
    int
        The period ``n``, or 0 if the samples repeat with no period up to
        ``max_period`` (quasi-periodic or chaotic motion, or an unfinished transient).
    """
    x = np.asarray(samples, dtype=float)
    if x.ndim == 1:
        x = x[:, None]
    if len(x) < 2:
        raise ValueError(f"need at least 2 Poincare samples, got {len(x)}")
    scale = np.max(np.abs(x), axis=0)
    scale[scale == 0] = 1.0
    xs = x / scale
    for n in range(1, min(max_period, len(x) - 1) + 1):
        if np.max(np.abs(xs[n:] - xs[:-n])) <= rtol:
            return n
    return 0


def periodicity_label(samples, *, max_period: int = 16, rtol: float = 1e-5) -> str:
    """``"P1"``, ``"P2"``, ... or ``"nonperiodic"`` (see :func:`poincare_period`)."""
    n = poincare_period(samples, max_period=max_period, rtol=rtol)
    return f"P{n}" if n else "nonperiodic"
