"""Where a branch runs onto the part of itself it has already passed.

A continuation that takes a wrong turn (at a kink of the map, where the tangent is not
defined, the step can come back onto the arm it arrived on) goes on along the points it has
already found, in the other direction: it retraces them and reports every bifurcation
there twice, until it leaves the range where it started, or until ``max_points``. A branch
that is a closed curve (an isola, a bubble of period-2 orbits between two period doublings)
comes round onto its first points and goes round again. Either way, every point from there
on is one the branch already has.

:class:`SelfOverlap` keeps the branch's points in its raw unknowns (state, then field) and,
every :data:`CHECK_EVERY` points, measures how far the newest lies from the polyline of the
points before it (all but the last two segments), in the continuation's current scaling.
A point *lies on* the part passed where that distance is at most :data:`NEAR` of the
longer of the step just taken and the segment it lies on: the sagitta of an arc of the
branch over a segment is a small fraction of the segment, while past a turn a point lies
off the other arm by about its distance from the turn (a smooth fold, whose arms part as
fast as the branch moves) or that distance times the angle between the arms (a kink). Only
:data:`CHECKS` such points in a row, on segments that follow each other the same way, make
the verdict: backwards, a retrace; forwards, a branch gone round. A kink whose arms part at
less than about a hundredth of a radian would pass for a retrace (they lie within ``NEAR``
of each other over three checks): a turn that sharp is not told from one.
"""

from __future__ import annotations

import numpy as np

#: Every how many points the newest is checked.
CHECK_EVERY = 4
#: Checks in a row on the part passed that make the verdict.
CHECKS = 3
#: The distance from the polyline, relative to the longer of the step and the segment, that counts as on it.
NEAR = 0.05


def segment_ratios(a: np.ndarray, b: np.ndarray, step: float) -> np.ndarray:
    """Each segment's distance from a point, over the longer of its length and ``step``: the segments run from the
    rows of ``a`` to those of ``b``, both taken from the point (a point *lies on* a segment where this is at most
    :data:`NEAR`)."""
    return segment_projections(a, b, step)[0]


def segment_projections(a: np.ndarray, b: np.ndarray, step: float) -> tuple[np.ndarray, np.ndarray]:
    """:func:`segment_ratios` and where the point projects onto each segment, ``t`` from 0 at its start (``a``) to
    1 at its end (``b``), clipped to the segment."""
    seg = b - a
    length2 = np.einsum("ij,ij->i", seg, seg)
    t = np.clip(-np.einsum("ij,ij->i", a, seg) / np.where(length2 > 0, length2, 1.0), 0.0, 1.0)
    dist = np.linalg.norm(a + t[:, None] * seg, axis=1)
    return dist / np.maximum(np.sqrt(length2), step), t


class SelfOverlap:
    """The branch's points, to tell when new ones lie on the part it has already passed.

    Parameters
    ----------
    n : int
        The number of states (the unknowns are the states, then the field).
    """

    def __init__(self, n: int):
        self._raw = np.empty((64, n + 1))
        # segment i's field interval, widened by the reach its length gives (measured in the scaling when
        # point i + 1 came, one since moved: twice that)
        self._lo = np.empty(64)
        self._hi = np.empty(64)
        self._size = 0
        self._hits: dict[int, int] = {}   # point index -> the segment its point lies on (checks that found one)

    def sync(self, pts, weights: np.ndarray) -> None:
        """Match the points kept to the branch's ``pts`` (whose states are ``q["state"]``, fields ``q["param"]``):
        the new ones appended, their segments measured in the scaling ``weights`` (see :meth:`segment_under`).
        Where the branch dropped points it must say so at once (:meth:`truncate`), before it appends others."""
        k = len(pts)
        if self._size > k:
            self.truncate(k)
        if self._raw.shape[0] < k:
            size = max(2 * self._raw.shape[0], k)
            raw, lo, hi = np.empty((size, self._raw.shape[1])), np.empty(size), np.empty(size)
            raw[:self._size], lo[:self._size], hi[:self._size] = (self._raw[:self._size], self._lo[:self._size],
                                                                  self._hi[:self._size])
            self._raw, self._lo, self._hi = raw, lo, hi
        for i in range(self._size, k):
            self._raw[i, :-1] = pts[i]["state"]
            self._raw[i, -1] = pts[i]["param"]
            if i > 0:
                a, b = self._raw[i - 1], self._raw[i]
                reach = 2 * NEAR * float(np.linalg.norm((b - a) / weights)) * weights[-1]
                self._lo[i - 1] = min(a[-1], b[-1]) - reach
                self._hi[i - 1] = max(a[-1], b[-1]) + reach
        self._size = k

    def truncate(self, k: int) -> None:
        """Forget the points from ``k`` on (the branch went back to its point ``k - 1``)."""
        self._size = min(self._size, k)
        self._hits = {i: s for i, s in self._hits.items() if i < k}

    def segment_under(self, k: int, weights: np.ndarray, step: float) -> int | None:
        """The segment ``[i, i + 1]`` (``i + 1 <= k - 2``) on which point ``k`` lies, by :data:`NEAR`, or None.

        ``weights`` divide the raw unknowns into the continuation's scaled ones (the state
        scale, then the field's span); ``step`` is the scaled length of the step that found
        point ``k``.
        """
        if k < 3:
            return None
        raw = self._raw[:k - 1]
        x = self._raw[k]
        # a segment can only lie within reach of x if its field interval does
        reach = 2 * NEAR * step * weights[-1]
        cand = np.flatnonzero((self._lo[:k - 2] <= x[-1] + reach) & (x[-1] - reach <= self._hi[:k - 2]))
        if cand.size == 0:
            return None
        ratio = segment_ratios((raw[cand] - x) / weights, (raw[cand + 1] - x) / weights, step)
        best = int(np.argmin(ratio))
        return int(cand[best]) if ratio[best] <= NEAR else None

    def verdict(self, pts, weights: np.ndarray, step: float) -> tuple | None:
        """At every :data:`CHECK_EVERY`-th point of the branch ``pts`` (its newest, ``k``, found by a step of scaled
        length ``step``; the points kept first brought up to ``pts``, :meth:`sync`): ``(way, since, segment)``
        where this check and the :data:`CHECKS` - 1 before it found their points on segments ever earlier on the
        branch (``way`` ``"back"``, a retrace) or ever later (``"round"``, the branch came round onto itself),
        ``since`` the first of those points and ``segment`` the one it lies on; else None."""
        k = len(pts) - 1
        if k % CHECK_EVERY:
            return None
        self.sync(pts, weights)
        hit = self.segment_under(k, weights, step)
        if hit is None:
            self._hits.pop(k, None)
            return None
        self._hits[k] = hit
        since = k - (CHECKS - 1) * CHECK_EVERY
        seq = [self._hits.get(i) for i in range(since, k + 1, CHECK_EVERY)]
        if any(s is None for s in seq):
            return None
        steps = np.diff(seq)
        if np.all(steps < 0):
            return "back", since, seq[0]
        if np.all(steps > 0):
            return "round", since, seq[0]
        return None
