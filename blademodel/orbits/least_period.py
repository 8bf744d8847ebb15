"""The least period of an orbit sought over several excitation periods.

Shooting over ``n`` periods finds every fixed point of the map over ``n T``, and the orbits
of fewer periods that divide ``n`` are among them: on a stretch where the period-1 orbit is
the only one, an orbit sought (or a branch followed) with ``periods = 2`` is that orbit run
twice. Its Poincare samples tell: they repeat after the least period.
"""

from __future__ import annotations

import numpy as np

from .shooting import LABEL_SCALE

#: How close (scaled) the samples ``k`` periods apart must come for the orbit to have period ``k``: far above a
#: converged orbit's residual (``1e-10``), far below the distance between the samples of a period-``n`` orbit
#: away from the bifurcation it was born at (that distance grows as the square root of the field's distance
#: from a period doubling: on the bilinear pair's doubled branch in ``gamma`` about ``0.5 sqrt(distance /
#: range)``, so ``1e-6`` within about ``4e-12`` of the range from the doubling).
LEAST_PERIOD_TOL = 1e-6


def least_period(sections: np.ndarray, scale: np.ndarray, tol: float = LEAST_PERIOD_TOL) -> int:
    """The fewest excitation periods after which an orbit comes back to itself.

    Parameters
    ----------
    sections : ndarray, shape (n, states)
        The orbit's states at ``t = k T``, ``k = 0 .. n - 1`` (``n`` its periods).
    scale : ndarray, shape (states,)
        Each state's scale; the friction laws' discrete labels are those scaled by
        :data:`~.shooting.LABEL_SCALE`, which must come back exactly (as whole numbers).
    tol : float
        Largest scaled distance between samples ``k`` periods apart for period ``k``.

    Returns
    -------
    int
        The least ``k`` dividing ``n`` with every sample ``k`` periods from the next
        within ``tol``; ``n`` if there is none.
    """
    sections = np.asarray(sections, dtype=float)
    n = sections.shape[0]
    labels = scale >= LABEL_SCALE
    for k in range(1, n):
        if n % k:
            continue
        moved = np.roll(sections, -k, axis=0) - sections
        if np.max(np.abs(moved[:, ~labels]) / scale[~labels], initial=0.0) <= tol and \
                np.all(np.rint(moved[:, labels]) == 0):
            return k
    return n


def branch_least_periods(branch, tol: float = LEAST_PERIOD_TOL) -> np.ndarray:
    """:func:`least_period` of each point of a :class:`~.branch.Branch`, from its Poincare samples.

    Each state is scaled by its half peak-to-peak excursion at that point, floored by
    ``1e-9`` of the largest (a state the orbit does not move). A branch without samples
    of every period (a file written before they were kept) gives its ``periods`` at each point.
    """
    points, n = len(branch.params), branch.periods
    if branch.sections.shape[:2] != (points, n):
        return np.full(points, n, dtype=np.int64)
    out = np.empty(points, dtype=np.int64)
    for i in range(points):
        amp = branch.amplitudes[i]
        scale = np.maximum(amp, 1e-9 * np.max(amp, initial=0.0))
        out[i] = least_period(branch.sections[i], np.maximum(scale, 1e-300), tol)
    return out
