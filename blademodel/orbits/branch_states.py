"""The states a branch's report and plot show: one by its name, or several by a pattern.

A pattern (``"x*"``: every blade's tangential coordinate) stands for the largest of the
states it matches at each point, and the smallest: the envelope by which the forced
response of a mistuned bladed disk is read (the largest blade's amplitude, and how far
the blades spread), where a tuned ring's travelling wave gives every blade the same.
"""

from __future__ import annotations

from fnmatch import fnmatchcase

import numpy as np

#: The characters that make ``state`` a pattern (:func:`fnmatch.fnmatchcase`'s).
PATTERN = "*?["
#: States whose values at a point agree to this fraction of the largest are alike there: on a tuned ring's travelling
#: wave every blade's, where which one is largest is rounding's choice.
ALIKE = 1e-9


def state_indices(names, state: str, what: str = "state") -> list[int]:
    """The indices in ``names`` of ``state``: a name, or a pattern such as ``"x*"`` (every match, in order).

    Raises
    ------
    ValueError
        Naming ``what`` and ``state`` where the name is not one of ``names`` or the pattern
        matches none.
    """
    names = list(names)
    if not any(c in state for c in PATTERN):
        if state not in names:
            raise ValueError(f"{what} {state!r}: not a state of the model ({', '.join(names)})")
        return [names.index(state)]
    found = [i for i, name in enumerate(names) if fnmatchcase(name, state)]
    if not found:
        raise ValueError(f"{what} {state!r}: the pattern matches no state of the model ({', '.join(names)})")
    return found


def envelope(values: np.ndarray, indices: list[int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The largest and smallest of ``|values[:, indices]|`` at each point (row), and the index of the largest.

    Parameters
    ----------
    values : ndarray
        A quantity per point and state (complex first harmonics, or amplitudes).
    indices : list of int
        The states taken (:func:`state_indices`).

    Returns
    -------
    largest, smallest : ndarray
        One value per point.
    which : ndarray of int
        The state (an index of ``values``' columns) that is largest at each point.
    """
    a = np.abs(np.asarray(values)[:, indices])
    return a.max(axis=1), a.min(axis=1), np.asarray(indices)[np.argmax(a, axis=1)]


def alike(largest: np.ndarray, smallest: np.ndarray) -> np.ndarray:
    """Where the states of an :func:`envelope` are alike (to :data:`ALIKE` of the largest): at each point."""
    return np.asarray(largest) - np.asarray(smallest) <= ALIKE * np.asarray(largest)
