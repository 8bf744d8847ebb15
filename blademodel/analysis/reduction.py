"""Vibration reduction ``P_d`` by the shroud contact (MODEL.md §7, Eq. 12-13)."""

from __future__ import annotations

import numpy as np


def mean_square(result, names=("x1", "y1")) -> float:
    """Time mean of the sum of squares of states ``names`` over the recorded periods.

    The records must cover whole periods at every step; the closing sample (equal in
    phase to the first) is left out, which makes the mean exact for periodic motion
    up to the integration error.
    """
    y = np.asarray(sum(result[n] ** 2 for n in names))
    if result.settings.get("record_every", 1) != 1:
        raise ValueError("mean_square needs a result recorded at every step (record_every=1)")
    return float(np.mean(y[1:]))


def vibration_reduction(P: float, P0: float) -> float:
    """``P_d = (P0 - P) / P0 * 100`` in percent: positive when the contact reduces vibration."""
    if not P0 > 0:
        raise ValueError(f"P0 = {P0!r}: the reference system does not move")
    return (P0 - P) / P0 * 100.0
