"""Vibration reduction ``P_d`` by the shroud contact (MODEL.md §7, Eq. 12-13)."""

from __future__ import annotations

import numpy as np


def mean_square(states, state_names, names=("x1", "y1")) -> float:
    """Time mean of the sum of squares of states ``names`` over whole periods.

    Parameters
    ----------
    states : ndarray, shape (K * S + 1, n)
        States recorded at every step over ``K`` whole periods, both ends included
        (``result.y`` of a run with ``record_every=1``). The closing sample, equal
        in phase to the first, is left out: the mean is then exact for a periodic
        motion up to the integration error.
    state_names : list of str
    names : tuple of str
        States summed (MODEL.md §7: ``x1`` and ``y1``).
    """
    cols = [list(state_names).index(n) for n in names]
    return float(np.mean(np.sum(np.asarray(states)[1:, cols] ** 2, axis=1)))


def vibration_reduction(P: float, P0: float) -> float:
    """``P_d = (P0 - P) / P0 * 100`` in percent: positive when the contact reduces vibration."""
    if not P0 > 0:
        raise ValueError(f"P0 = {P0!r}: the reference system does not move")
    return (P0 - P) / P0 * 100.0
