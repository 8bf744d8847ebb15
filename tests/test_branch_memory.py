"""A branch keeps its points' orbit records only as long as it needs them.

Each branch point's run records the orbit at every step (1001 rows of the pair's states, 0.77 MB on the
24-blade ring). Kept in every point, and in the grazing locations' copies of the points around each grazing,
those records made a branch's memory grow with its points by that much (184 MB for the 2307 points of the
bilinear pair's FRF in ``benchmarks/frf.py``).
"""

from __future__ import annotations

import tracemalloc

import numpy as np

import blademodel.orbits.arclength as arclength
from blademodel.orbits import continuation
from blademodel.orbits.corrector import KEPT_JACOBIANS, KEPT_ORBITS, _Context
from blademodel.zheng2022 import BladePair

CFG = BladePair(friction="bilinear")


def _peak(max_points: int) -> tuple[float, int]:
    """The traced memory's peak over a continuation of the bilinear pair from 250 rad/s, and its points."""
    tracemalloc.start()
    try:
        b = continuation(CFG, "omega", 250.0, 350.0, max_points=max_points, workers=1)
        return tracemalloc.get_traced_memory()[1], len(b.params)
    finally:
        tracemalloc.stop()


def test_a_branch_s_memory_grows_by_far_less_than_an_orbit_record_a_point():
    """The peak of the traced memory over a branch of 120 points exceeds that over 30 points by less than a
    quarter of one orbit's record a point: the records are not kept (with them the growth is more than one record
    a point, and the grazing points in between add two records each)."""
    continuation(CFG, "omega", 250.0, 251.0, max_points=3, workers=1)   # compiled, caches warm
    short, n_short = _peak(30)
    long, n_long = _peak(120)
    assert (n_short, n_long) == (30, 120)
    record = 1001 * 8 * 8   # one period's orbit at 1000 steps, 8 physical states
    assert (long - short) / (n_long - n_short) < 0.25 * record


def _kept_points(monkeypatch):
    """A 12-point branch of the pair from 280 rad/s, as its points are when it ends, with the context that made
    them and, by the id of each point, its orbit record and monodromy matrix as it was made: ``(pts, ctx, made)``."""
    made, seen = {}, {}
    point, assemble = _Context.point, arclength._assemble

    def recording(self, X, mode, A):
        q = point(self, X, mode, A)
        made[id(q)] = q["Y"].copy(), q["J"].copy()
        return q

    def keeping(ctx, pts, *args, **kwargs):
        seen["ctx"], seen["pts"] = ctx, list(pts)
        return assemble(ctx, pts, *args, **kwargs)

    monkeypatch.setattr(_Context, "point", recording)
    monkeypatch.setattr(arclength, "_assemble", keeping)
    b = continuation(CFG, "omega", 280.0, 300.0, max_points=12, workers=1)
    assert len(seen["pts"]) == len(b.params) == 12
    return seen["pts"], seen["ctx"], made


def test_older_points_drop_their_orbit_records_and_get_the_same_orbit_again(monkeypatch):
    """Only the last :data:`KEPT_ORBITS` points of a branch hold their orbit's record when it ends; any other's
    orbit, asked for (:meth:`_Context.orbit`), is its run made again: the record the point had (to the bit but for
    the first point's, made by the integrator built from the model, whose derived parameters round otherwise than
    the copies' the family makes at a value: measured 3e-15 of the orbit's size)."""
    pts, ctx, made = _kept_points(monkeypatch)
    assert [("Y" in q) for q in pts] == [False] * (len(pts) - KEPT_ORBITS) + [True] * KEPT_ORBITS
    for q in pts:
        Y = made[id(q)][0]
        np.testing.assert_allclose(ctx.orbit(q), Y, rtol=0, atol=1e-13 * np.abs(Y).max())
    assert all(np.array_equal(ctx.orbit(q), made[id(q)][0]) for q in pts[1:])


def test_older_points_drop_their_monodromy_matrix_and_get_it_again_from_their_scaled_jacobian(monkeypatch):
    """Only the last :data:`KEPT_JACOBIANS` points of a branch (and its first, which keeps no scale for its scaled
    Jacobian) hold their monodromy matrix when it ends; any other's (:meth:`_Context.monodromy`) is its scaled
    Jacobian brought back to physical units in the scale it was stored in: the matrix the point had, to rounding."""
    pts, ctx, made = _kept_points(monkeypatch)
    assert [("J" in q) for q in pts] == [True] + [False] * (len(pts) - 1 - KEPT_JACOBIANS) + [True] * KEPT_JACOBIANS
    for q in pts:
        J = made[id(q)][1]
        np.testing.assert_allclose(ctx.monodromy(q), J, rtol=0, atol=1e-12 * np.abs(J).max())
