"""The vibration reduction ``P_d`` along a branch of periodic orbits (MODEL.md section 7, Eq. 12-13).

``P`` is each orbit's time-mean of the sum of squares of the observed coordinates (the first
mass's: ``x1`` and ``y1``, as in sweeps), kept with the branch
(:attr:`~.branch.Branch.mean_squares`); ``P0`` the same for the model without its contacts at
that value of the field, exact (:func:`~blademodel.analysis.contact_free.contact_free_mean_squares`);
``P_d = (P0 - P) / P0 * 100``. Along a branch that holds unstable orbits too: how much a
shroud would remove on orbits that a sweep never lands on.
"""

from __future__ import annotations

import numpy as np


def branch_vibration_reduction(branch, config, names=None) -> np.ndarray:
    """``P_d`` in percent at each point of ``branch`` (NaN where the branch has no mean squares).

    Parameters
    ----------
    branch : Branch
        A continued branch of ``config``.
    config
        The config it was continued from (each point's model is built at its value of the field).
    names : sequence of str, optional
        The coordinates summed; default: the first mass's (``x1``, ``y1``), as sweeps observe.

    Raises
    ------
    ValueError
        If a name is not a coordinate of the model, or the contact-free model has no
        closed-form steady state (:func:`~blademodel.analysis.contact_free.contact_free_mean_squares`).
    """
    from ..analysis.contact_free import contact_free_mean_squares
    from ..analysis.reduction import vibration_reduction
    from ..config import apply_overrides
    from ..sweep.point import observed
    out = np.full(branch.params.size, np.nan)
    if branch.mean_squares.shape != branch.states.shape:
        return out
    first = apply_overrides(config, {branch.field: float(branch.params[0])}, source="P_d").build()
    names = list(names) if names else list(observed(first))
    unknown = [n for n in names if n not in branch.state_names]
    if unknown:
        raise ValueError(f"P_d: {', '.join(map(repr, unknown))} is not a state of the branch "
                         f"({', '.join(branch.state_names)})")
    cols = [branch.state_names.index(n) for n in names]
    for i, value in enumerate(branch.params):
        model = first if i == 0 else apply_overrides(config, {branch.field: float(value)}, source="P_d").build()
        ms0 = contact_free_mean_squares(model)   # (about a millisecond on the pair: the model's build)
        out[i] = vibration_reduction(float(np.sum(branch.mean_squares[i, cols])), sum(ms0[n] for n in names))
    return out
