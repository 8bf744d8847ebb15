"""Switching branches: the period-doubled branch at a period doubling, the crossing branch at a branch point, and
where a switched branch ends.

The switch is one pseudo-arclength step from the bifurcation along the critical
eigenvector (:func:`_switched`); the branch is then followed as by
:func:`~.arclength.continuation`. On a tuned ring the switch may run on a reduced map
(:mod:`.cyclic`). A switched branch ends where it comes back to the branch it left
(:func:`_back_to`, :func:`_back_to_the_waves`) or lands on it (:func:`_landed_on`).
"""


from __future__ import annotations

import math
from dataclasses import replace
from typing import Callable

import numpy as np

from .arclength import WAVE_TOL, _check_grazing_tol, _run
from .branch import Branch, SpecialPoint
from .corrector import _Context, _tangent
from .cyclic import CyclicError, CyclicSymmetry
from .family import _Family
from .period_map import FlowError, PeriodMap, _copy
from .shooting import ShootingError, _n_coordinates, _orbit_samples, _shoot, _state_scale


def period_doubled_branch(config, name: str, point: SpecialPoint, start: float, stop: float, *,
                          periods: int = 1, ds: float = 0.01, ds_min: float = 1e-5, ds_max: float = 0.05,
                          max_points: int = 400, tol: float = 1e-10, max_corrections: int = 8,
                          rel_step: float = 1e-6, locate_tol: float = 1e-7, grazing_tol: float | None = None,
                          steps_per_period: int = 1000, event_tol: float = 1e-10, method: str = "rk4",
                          kernel: str = "auto",
                          jacobian: str = "auto", workers: int | None = None,
                          progress: Callable[[int, float], None] | None = None,
                          checkpoint: Callable[[Branch], None] | None = None,
                          checkpoint_every: float = 30.0, cyclic: bool = False,
                          parent: Branch | None = None) -> Branch:
    """The branch of period-``2 periods`` orbits born at a period doubling of a period-``periods`` branch.

    At a period doubling the map over ``periods`` excitation periods has the multiplier
    ``-1`` with eigenvector ``v``; the map over twice as many has ``+1`` there, and two
    branches of its fixed points cross: the old orbits (traversed twice) and the new
    ones, which leave along ``v`` at right angles to the field (a pitchfork of the
    doubled map). The switch is one pseudo-arclength step of the doubled map from the
    bifurcation point along ``(v, 0)``; from the point it converges to, the branch is
    followed as by :func:`~.arclength.continuation`, in whichever direction of the field it goes,
    until the field leaves ``[start, stop]``. The branch's first point is the bifurcation
    itself (on the old orbit); a supercritical doubling sends the new branch to the
    side where the old orbits are unstable, a subcritical one to the other.

    On a tuned ring (the point from any branch of travelling waves) with ``cyclic``, the
    doubling is looked at on the map reduced by the ring's symmetry (:mod:`.cyclic`):
    where that map's Jacobian ``J`` has the eigenvalue ``+1`` there (``M = S^(-s d) J^d``
    shows it as ``-1`` on a perturbation that the turn by ``s d`` blades reverses), the
    reduced map has a branch point, and the doubled orbits, which come back after one
    period turned by ``s d`` blades, are its fixed points: the switch is a step along
    that eigenvector on the reduced map, and the branch is followed there, with ``d``
    times fewer steps a period than on the whole ring's map and half as many periods.
    Otherwise the whole ring's map is used, as without ``cyclic``, and the branch's
    message says so.

    Parameters
    ----------
    config, name
        As for :func:`~.arclength.continuation`.
    point : SpecialPoint
        A ``"period-doubling"`` point of a branch of ``periods``-periodic orbits.
    start, stop : float
        The range of the field the new branch is followed in (it must contain the point).
    periods : int
        Period of the *old* branch; the new one has twice it.
    ds, ds_min, ds_max, max_points, tol, max_corrections, rel_step, locate_tol, grazing_tol : float
        As for :func:`~.arclength.continuation`; ``ds`` is also the switch's step along ``v``.
    steps_per_period, event_tol, method, kernel, jacobian, workers, progress, checkpoint, checkpoint_every
        As for :func:`~.arclength.continuation`.
    cyclic : bool
        Follow the new branch on the reduced map where it can be (above); ``periods`` must
        then be 1.
    parent : Branch, optional
        The branch ``point`` lies on. The new branch ends where it comes back to one of that
        branch's other period doublings (its point closest to it, within ``ds_max``): a
        **period-doubling bubble**, past which it would go round the same orbits again, each
        taken a period later.

    Returns
    -------
    Branch
        With ``periods`` twice the old branch's; resumed, if unfinished, by
        :func:`~.arclength.continuation` with ``periods`` twice the old branch's and ``start, stop``
        (and ``cyclic`` where it was followed on the reduced map: its message does not say
        the whole map took it).

    Raises
    ------
    ValueError
        If ``point`` is not a period doubling, or lies outside ``[start, stop]``.
    FlowError
        If the switch converges back onto the old orbits for both signs of ``v``.
    ContinuationInterrupted
        On Ctrl-C, with the branch so far.
    """
    settings = dict(steps_per_period=steps_per_period, event_tol=event_tol, method=method, kernel=kernel)
    fam, ig, y, mode, scale, (lo, hi) = _at_point(config, name, point, "period-doubling", "period doubling", start,
                                                  stop, 2 * periods, settings, jacobian, workers, grazing_tol)
    span = hi - lo
    old = PeriodMap(ig, periods, jacobian, workers)   # the period-``periods`` map
    v, whole = None, ""
    if cyclic:
        v, whole = _reduced_branch_point(fam, ig, point, y, mode, scale, rel_step, periods)
    if v is None:
        _, v = _critical_direction(old.jacobian(y, _copy(mode), scale, rel_step), -1.0, scale)
    ctx = _Context(fam, scale, span, tol, rel_step, max_corrections, grazing_tol)

    def new_orbit(X1, m1):   # not the old orbit again
        y1 = X1[:-1] * scale
        return np.max(np.abs(old(y1, _copy(m1))[0] - y1) / scale) > 1e3 * tol

    others = [] if parent is None else [q for q in parent.points("period-doubling") if q.param != point.param]
    def splitting(q):   # how far the doubled orbit is from period ``periods``: its Poincare samples a period apart
        S = q["sections"]
        return float(np.max(np.abs(S[periods:] - S[:periods]) / ctx.scale))

    ends = [_landed_on(splitting, tol, name, periods)]
    if others:
        ends.append(_back_to(ctx, others, ds_max, f"came back to the period-{periods} orbits at their period "
                             f"doubling", "a period-doubling bubble: past it the branch goes round the same orbits, "
                             "each taken a period later", splitting))
    b = _switched(ctx, point, y, mode, v, new_orbit, f"the period-{periods} orbits", (lo, hi), ds=ds,
                  ds_min=ds_min, ds_max=ds_max, max_points=max_points, locate_tol=locate_tol, progress=progress,
                  checkpoint=checkpoint, checkpoint_every=checkpoint_every, stop=_first_end(ends))
    return replace(b, message=f"{b.message} ({whole})") if whole else b


def _at_point(config, name, point: SpecialPoint, kind: str, what: str, start, stop, periods: int, settings,
              jacobian, workers, grazing_tol) -> tuple:
    """What a switch at the bifurcation ``point`` (of ``kind``, named ``what`` in errors) starts from:
    ``(family, integrator, state, mode, scale, (lo, hi))``, the family's maps over ``periods`` and the state scaled
    by the excursions of its orbit over them.

    Raises
    ------
    ValueError
        If ``point`` is of another kind or lies outside ``[start, stop]``.
    """
    if point.kind != kind:
        raise ValueError(f"point must be a {what}, got a {point.kind!r} point")
    lo, hi = min(start, stop), max(start, stop)
    if not lo <= point.param <= hi:
        raise ValueError(f"the {what} at {name} = {point.param:g} lies outside [{lo:g}, {hi:g}]")
    _check_grazing_tol(grazing_tol)
    fam = _Family(config, name, periods, settings, point.param, jacobian, bounds=(start, stop), workers=workers)
    ig = fam.map_at(point.param).integrator
    y = np.asarray(point.state, dtype=float)
    mode = point.mode
    if mode is None:
        full = np.zeros(ig.n_state)
        full[:y.size] = y
        mode = ig.mode_of(full)
    scale = _state_scale(_orbit_samples(ig, y, mode, periods)[1], _n_coordinates(ig), ig.discrete_states)
    return fam, ig, y, mode, scale, (lo, hi)


def _first_end(ends: list):
    """``stop(pts)`` for :func:`~.arclength._follow` that asks each of ``ends`` in turn (the first reason given ends the
    branch), or None where there are none."""
    if not ends:
        return None

    def stop(pts):
        return next((why for why in (end(pts) for end in ends) if why is not None), None)
    return stop


def _switched(ctx, point: SpecialPoint, y, mode, v, is_new, old: str, bounds, *, ds, **follow) -> Branch:
    """The branch that leaves the bifurcation ``point`` (orbit ``y`` in ``mode``) along the scaled state direction
    ``v``, followed by :func:`~.arclength._run`; its first point is the bifurcation.

    The switch is one pseudo-arclength step from the point along ``(v, 0)``, on the
    hyperplane normal to it, for either sign of ``v`` and then at twice the step, until
    ``is_new(X, mode)`` says the corrected point is not on the old branch (described by
    ``old`` in the error).
    """
    fam, scale, span = ctx.fam, ctx.scale, ctx.span
    X0 = np.append(y / scale, point.param / span)
    A0 = ctx.jacobian(X0, mode)
    for sign, h in ((1.0, ds), (-1.0, ds), (1.0, 2 * ds), (-1.0, 2 * ds)):
        T0 = np.append(sign * v, 0.0)
        X1, m1, A1 = ctx.correct(X0 + h * T0, T0, _copy(mode))
        if X1 is not None and is_new(X1, m1):
            break
    else:
        raise FlowError(f"the switch at {fam.name} = {point.param:g} came back to {old} for both signs of the "
                        f"critical eigenvector")
    T1 = _tangent(A1, X1 - X0)
    pts = [ctx.point(X0, mode, A0), ctx.point(X1, m1, A1)]
    X, T, A = ctx.rescale(_state_scale(ctx.orbit(pts[-1]), _n_coordinates(fam.map_at(point.param).integrator),
                                       ctx.discrete),
                          X1, T1, A1)
    pts[-1]["X"], pts[-1]["A"] = X, A
    return _run(ctx, pts, X, T, m1, A, bounds, ds=ds, **follow)


def branch_point_branch(config, name: str, point: SpecialPoint, start: float, stop: float, *,
                        periods: int = 1, ds: float = 0.01, ds_min: float = 1e-5, ds_max: float = 0.05,
                        max_points: int = 400, tol: float = 1e-10, max_corrections: int = 8,
                        rel_step: float = 1e-6, locate_tol: float = 1e-7, grazing_tol: float | None = None,
                        steps_per_period: int = 1000, event_tol: float = 1e-10, method: str = "rk4",
                        kernel: str = "auto", jacobian: str = "auto", workers: int | None = None,
                        progress: Callable[[int, float], None] | None = None,
                        checkpoint: Callable[[Branch], None] | None = None,
                        checkpoint_every: float = 30.0, cyclic: bool = False,
                        crossed: Branch | None = None) -> Branch:
    """The other branch of period-``periods`` orbits through a branch point of a branch.

    At a branch point a multiplier passes ``+1`` while the branch goes on: two branches
    of fixed points of the same map cross there. On a symmetric structure (identical
    blades, a tuned ring's travelling waves) the branch followed holds the symmetric
    orbits and the other one orbits that break the symmetry (blades vibrating with
    different amplitudes: localisation), leaving along the eigenvector ``v`` of the
    multiplier ``+1``, which the symmetry reverses. The switch is one pseudo-arclength
    step from the point along ``(v, 0)``, which is normal to the old branch's tangent
    where that tangent keeps the symmetry (the step does not meet the old branch), for
    either sign of ``v``; the new point is accepted where shooting at its value of the
    field from the branch point's orbit finds another orbit (the old branch's). From there
    the branch is followed as by :func:`~.arclength.continuation`, in whichever direction of the field
    it goes, until the field leaves ``[start, stop]``. Its first point is the branch point
    itself. The whole period's map is used (a branch point found on a tuned ring's reduced
    map leads to orbits that are no travelling waves), except with ``cyclic``, below.

    On a tuned ring (the point from a branch of travelling waves) with ``cyclic``, the
    branch point is looked at on the reduced map ``G`` (:mod:`.cyclic`): where ``G``'s
    Jacobian ``J`` has the eigenvalue ``-1`` there (``M = S^(-s d) J^d`` shows it as
    ``+1``), ``G`` period-doubles, and the crossing orbits are fixed points of ``G^2``,
    the map over ``2 T / d`` turned by ``2 s`` blades (``CyclicSymmetry(every=2)``): the
    switch steps along that eigenvector, and the branch is followed there, with ``d / 2``
    times fewer steps a period than on the whole ring's map. Otherwise the whole ring's
    map is used, and the branch's message says why.

    Parameters
    ----------
    config, name
        As for :func:`~.arclength.continuation`.
    point : SpecialPoint
        A ``"branch-point"`` point of a branch of ``periods``-periodic orbits.
    start, stop : float
        The range of the field the new branch is followed in (it must contain the point).
    periods : int
        Period of the branch (the new one has the same).
    ds, ds_min, ds_max, max_points, tol, max_corrections, rel_step, locate_tol, grazing_tol : float
        As for :func:`~.arclength.continuation`; ``ds`` is also the switch's step along ``v``.
    steps_per_period, event_tol, method, kernel, jacobian, workers, progress, checkpoint, checkpoint_every
        As for :func:`~.arclength.continuation`.
    cyclic : bool
        Follow the crossing branch on ``G^2`` where it can be (above); ``periods`` must then
        be 1. There it ends where it comes back to the travelling waves.
    crossed : Branch, optional
        The branch ``point`` lies on. The crossing branch ends where it comes back to one of
        that branch's other branch points (its closest point within ``ds_max`` of it, in the
        continuation's scaled unknowns): past it, it would go on beyond the branch it
        crossed (on a symmetric structure, as its own mirror image).

    Returns
    -------
    Branch
        Resumed, if unfinished, by :func:`~.arclength.continuation` with the same ``periods``, ``start``
        and ``stop`` (on the whole map).

    Raises
    ------
    ValueError
        If ``point`` is not a branch point, or lies outside ``[start, stop]``.
    FlowError
        If the switch converges back onto the old branch for both signs of ``v``.
    ContinuationInterrupted
        On Ctrl-C, with the branch so far.
    """
    settings = dict(steps_per_period=steps_per_period, event_tol=event_tol, method=method, kernel=kernel)
    fam, ig, y, mode, scale, (lo, hi) = _at_point(config, name, point, "branch-point", "branch point", start, stop,
                                                  periods, settings, jacobian, workers, grazing_tol)
    P = fam.map_at(point.param)
    v, whole = None, ""
    if cyclic:
        v, whole = _reduced_crossing(fam, ig, point, y, mode, scale, rel_step, periods)
    if v is None:
        _, v = _critical_direction(P.jacobian(y, _copy(mode), scale, rel_step), 1.0, scale)
    ctx = _Context(fam, scale, hi - lo, tol, rel_step, max_corrections, grazing_tol)

    def off_the_old_branch(X1, m1):
        try:
            y_old, _ = _shoot(fam.map_at(X1[-1] * ctx.span), y.copy(), _copy(mode), scale, tol, max_corrections,
                              rel_step, [])
        except (ShootingError, FlowError, np.linalg.LinAlgError, ValueError):
            return True   # no orbit of the old branch there to come back to
        return float(np.max(np.abs(X1[:-1] * scale - y_old) / scale)) > 1e3 * tol

    ends = []
    others = [] if crossed is None else [q for q in crossed.points("branch-point") if q.param != point.param]
    if fam.symmetry is not None:   # followed on G^2: it ends where it comes back to the travelling waves
        ends.append(_back_to_the_waves(CyclicSymmetry(fam.config_at(point.param), ig), name, ctx.orbit, others))
    if others:
        ends.append(_back_to(ctx, others, ds_max, "met the branch it crossed again at its branch point",
                             "past it the crossing branch goes on beyond the branch it crossed"))
    b = _switched(ctx, point, y, mode, v, off_the_old_branch, "the branch it crosses", (lo, hi), ds=ds,
                  ds_min=ds_min, ds_max=ds_max, max_points=max_points, locate_tol=locate_tol, progress=progress,
                  checkpoint=checkpoint, checkpoint_every=checkpoint_every, stop=_first_end(ends))
    return replace(b, message=f"{b.message} ({whole})") if whole else b


def _landed_on(splitting, tol: float, name: str, periods: int):
    """``stop(pts)`` for :func:`~.arclength._follow`, which ends a period-doubled branch whose newest orbit is
    one of period ``periods`` again (its ``splitting`` at most ``1e3 tol``): past a gap or a kink the
    corrections found the branch it left, traversed twice, and would follow it as if it were doubled (measured:
    the 96-blade ring's branch doubled at 273.89 rad/s, from 273.834 rad/s on, across a gap)."""
    def stop(pts):
        if len(pts) < 3:
            return None
        s = splitting(pts[-1])
        if s > 1e3 * tol:
            return None
        return (f"landed on the period-{periods} orbits at {name} = {pts[-1]['param']:.6g} (its orbit a period apart "
                f"differs by {s:.2g} of the scale: the corrections found the branch it left, traversed twice)")
    return stop


#: A doubled branch ends at its parent's other period doubling only where its orbits' splitting (how far they are
#: from their parent's period) has fallen there below this fraction of its largest on the branch (:func:`_back_to`).
COLLAPSED = 0.1


def _back_to(ctx, others: list, reach: float, met: str, past: str, splitting=None):
    """``stop(pts)`` for :func:`~.arclength._follow`, which ends a switched branch at its point closest to one of
    the special points ``others`` of the branch it left (its other branch points or period doublings), where that
    point lies within ``reach`` of it (scaled unknowns: the state by ``ctx.scale``, the field by its span). The
    branch passes through such a point where it comes back there, so its closest point is at most about half a
    step away. The message says it ``met`` the point there, and what lies ``past`` it.

    ``splitting(q)``, where given, measures how far the orbit of point ``q`` lies from the
    branch left (a doubled orbit from period 1): it must have fallen to :data:`COLLAPSED` of
    its largest on the branch at that point too, so that a branch that only runs close to
    the one it left (doubled orbits hardly split) does not end where it passes near one of
    its special points (measured: the 96-blade ring's branch doubled at 273.89 rad/s passed
    within ``reach`` of the doubling at 272.27 without coming back to it).
    """
    def distance(q, b):
        return math.hypot(float(np.linalg.norm((q["state"] - b.state) / ctx.scale)),
                          (q["param"] - b.param) / ctx.span)

    largest = [0.0]

    def stop(pts):
        if splitting is not None:
            largest[0] = max(largest[0], splitting(pts[-1]))
        if len(pts) < 4:
            return None
        for b in others:
            d0, d1, d2 = (distance(q, b) for q in pts[-3:])
            if d1 <= reach and d1 < d0 and d1 <= d2 and \
                    (splitting is None or splitting(pts[-2]) <= COLLAPSED * largest[0]):
                return (f"{met} {ctx.fam.name} = {b.param:.6g} (its point at {pts[-2]['param']:.6g} the closest; "
                        f"{past})")
        return None
    return stop


#: A crossing branch's orbit is a travelling wave where its symmetry breaking ``y - G(y)`` is at most this fraction
#: of that of its first point past the switch (:func:`_back_to_the_waves`).
ON_THE_WAVES = 1e-6


def _back_to_the_waves(sym, name: str, orbit, others=()):
    """For a crossing branch followed on ``G^2``: ``stop(pts)`` for :func:`~.arclength._follow`, which ends it
    where it passes the travelling waves again.

    How an orbit breaks the travelling-wave symmetry is ``y - G(y)``, ``G(y) = S^s Phi(0
    -> tau)(y)`` read off its rebuilt period (no integration). Projected on its value at
    the branch's first point past the switch, it falls to zero where the crossing branch
    meets the travelling waves at another branch point, and changes sign past it, where
    the branch goes on as its own image under ``G`` (the blades' roles moved): there it
    ends, and where its newest point is a travelling wave itself (the step landed on the
    crossed branch; the projection's sign is rounding's there). The message says where:
    at the crossed branch's branch point in ``others`` within a step of the last two
    points' values of the field, where there is one; else at the vertex the projections
    give (:func:`_vertex`), unless the step landed on the waves (nothing locates the
    meeting inside it then). ``orbit(q)``: a branch point's orbit at every step
    (:meth:`.corrector._Context.orbit`; older points keep none).
    """
    def broken(q):
        Y = orbit(q)
        return q["state"][:sym.n] - sym.turned(Y[(Y.shape[0] - 1) // (sym.fraction * sym.periods)])

    first = []
    past = "past it the crossing branch goes on as its own image under the ring's turn"

    def stop(pts):
        if len(pts) < 3:
            return None
        if not first:
            first.append(broken(pts[1]))
        e0, e1 = (float(np.dot(broken(q), first[0])) for q in pts[-2:])
        landed = np.linalg.norm(broken(pts[-1])) <= ON_THE_WAVES * np.linalg.norm(first[0])
        if not (landed or e0 > 0.0 >= e1):
            return None
        a, b = pts[-2]["param"], pts[-1]["param"]
        between = f"between its points at {a:.6g} and {b:.6g}"
        reach = abs(b - a)   # the meeting lies within about a step of the two points, in the field
        near = [q for q in others if min(a, b) - reach <= q.param <= max(a, b) + reach]
        if near:
            q = min(near, key=lambda q: min(abs(q.param - a), abs(q.param - b)))
            return f"came back to the travelling waves at their branch point {name} = {q.param:.6g} ({between}; {past})"
        if landed:
            return (f"came back to the travelling waves {between}, where they have another branch point (its last "
                    f"point is a travelling wave: the step landed on them; {past})")
        return (f"came back to the travelling waves near {name} = {_vertex(a, b, e0, e1):.6g}, where they have "
                f"another branch point ({between}; {past})")
    return stop


def _vertex(a: float, b: float, e0: float, e1: float) -> float:
    """Where a crossing branch meets the travelling waves, from its points at the field's values ``a`` and ``b``
    whose symmetry breaking projects to ``e0 > 0 >= e1``.

    ``G`` maps the crossing branch onto itself with the breaking reversed, so the field is
    even in it there: the meeting is the vertex of the parabola ``lambda = v - c e^2``
    through both points (a pitchfork's), which lies past the points where the last step
    turned across it. Where the two breakings are of about one size (the parabola's
    vertex ill-determined), the value interpolated linearly.
    """
    if abs(e0 * e0 - e1 * e1) > 1e-3 * max(e0 * e0, e1 * e1):
        return (b * e0 * e0 - a * e1 * e1) / (e0 * e0 - e1 * e1)
    return a + e0 / (e0 - e1) * (b - a)


def _reduced_crossing(fam, ig, point, y, mode, scale, rel_step, periods) -> tuple:
    """For :func:`branch_point_branch` with ``cyclic``: the direction (scaled, unit) along which the crossing
    branch leaves the branch point on ``G^2``, ``fam`` reduced by that symmetry from then on; or ``(None, why)``
    where the whole map must take it (``fam`` left as it is)."""
    sym = CyclicSymmetry(fam.config_at(point.param), ig) if periods == 1 else None
    lam, v, why = _reduced_direction(fam, ig, sym, y, mode, scale, rel_step, periods, -1.0, "branch point")
    if why:
        return None, why
    if abs(lam + 1.0) > BRANCH_POINT_TOL or sym.fraction % 2:
        return None, (f"on the whole ring's map: the reduced map does not period-double there (its eigenvalue "
                      f"nearest -1 is {complex(lam):.4g}, over T / {sym.fraction}), so the crossing orbits keep no "
                      f"turn of the ring")
    fam.reduce_by(CyclicSymmetry(fam.config_at(point.param), ig, every=2))
    return v, ""


#: How close to ``+1`` the reduced map's Jacobian must have an eigenvalue at a period doubling for the doubled
#: branch to be followed on the reduced map (:func:`period_doubled_branch`): the doubling is located to
#: ``locate_tol``, so the eigenvalue lies far closer.
BRANCH_POINT_TOL = 1e-3


def _reduced_branch_point(fam, ig, point, y, mode, scale, rel_step, periods) -> tuple:
    """For :func:`period_doubled_branch` with ``cyclic``: the direction (scaled, unit) along which the doubled
    branch leaves the reduced map's branch point, ``fam`` reduced from then on; or ``(None, why)`` where the whole
    map must take it (``fam`` left as it is)."""
    sym = CyclicSymmetry(fam.config_at(point.param), ig, periods=2) if periods == 1 else None
    lam, v, why = _reduced_direction(fam, ig, sym, y, mode, scale, rel_step, periods, 1.0, "doubling")
    if why:
        return None, why
    if abs(lam - 1.0) > BRANCH_POINT_TOL:
        return None, (f"on the whole ring's map: the reduced map has no branch point there (its eigenvalue nearest "
                      f"+1 is {complex(lam):.4g}), so the doubled orbits break the reduction's symmetry")
    fam.reduce_by(sym)
    return v, ""


def _reduced_direction(fam, ig, sym, y, mode, scale, rel_step, periods: int, target: float, what: str) -> tuple:
    """``(eigenvalue, direction, "")`` of the reduced map (``symmetry=sym``) at the ring's orbit ``y`` at a
    bifurcation: its Jacobian's eigenvalue nearest ``target`` and that eigenvector (:func:`_critical_direction`);
    or ``(None, None, why)`` where the orbit is no travelling wave (the whole map must take it). The reduction
    follows the bifurcations (``what``) of period-1 orbits only."""
    if periods != 1:
        raise CyclicError(f"the cyclic reduction follows the {what}s of period-1 orbits, not of periods = {periods}")
    G = PeriodMap(ig, 1, fam.jacobian, fam.workers, symmetry=sym)
    off = float(np.max(np.abs(G(y, _copy(mode))[0] - y) / scale))
    if off > WAVE_TOL:
        return None, None, (f"on the whole ring's map: the orbit at the {what} is no travelling wave ({off:.3g} "
                            f"scaled from itself under the reduced map)")
    lam, v = _critical_direction(G.jacobian(y, _copy(mode), scale, rel_step), target, scale)
    return lam, v, ""


def _critical_direction(J, target: float, scale) -> tuple:
    """The eigenvalue of ``J`` nearest ``target`` and its eigenvector's real part in the scaled states, of unit
    length: the direction a branch born there leaves along."""
    lam, W = np.linalg.eig(J)
    k = int(np.argmin(np.abs(lam - target)))
    v = np.real(W[:, k]) / scale
    return lam[k], v / np.linalg.norm(v)
