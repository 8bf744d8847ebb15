"""Pseudo-arclength continuation of periodic orbits in a config field, with their bifurcations.

A branch of period-``n`` orbits is the curve ``P(y; lambda) = y`` in the space of the
section state ``y`` and one config field ``lambda`` (the excitation frequency for a
forced-response curve, ``gamma``, ``F0``, the gap ...). It is followed by
pseudo-arclength continuation: a step ``ds`` along the branch, then corrections of the
orbit condition plus the arclength condition, so the branch is followed around folds.
Both the state and the field are scaled (each state by its excursion on the newest
orbit, the field by the continuation range).

* **Jacobian**: the monodromy matrix from the tangent of the period map
  (:class:`~blademodel.orbits.period_map.PeriodMap`: variational equations with
  saltation matrices, replaying the run the last residual made) where the kernel has
  one, else central differences; the field's column is a forward difference of the map,
  or, on a smooth stretch, from the tangent of the last points (:meth:`.corrector._Context.column_rule`).
* **Prediction**: on a smooth stretch, the quadratic through the last three points, for
  the unknowns and the Jacobian alike; else the tangent step and the last Jacobian.
* **Correction**: Broyden's method from that matrix (residuals only), steps halved where
  the residual does not fall (a kink of the map, where an event appears), then Newton
  with fresh Jacobians, then shooting at the predicted value of the field.
* **Parameters**: each value of the field gets the first integrator with its parameters
  changed, interpolated along the field's path where it moves them affinely
  (:mod:`.field_path`).
* The step grows after easy corrections and is halved after hard or failed ones; it is
  kept short where the leading multiplier moves fast (:func:`_multiplier_step`).
* A branch whose new points lie on the part it has passed (a retrace after a wrong turn, or
  a closed branch come round) stops and says from where (:mod:`.self_overlap`).

Each point carries its Floquet multipliers and its orbit's events (their signature: which
transitions, how often). A change in the number of multipliers outside the unit circle
between two points is a bifurcation, located by regula falsi on the multiplier nearest the
unit circle and classified by the multiplier that crossed: through ``+1`` a fold where the
field's tangent component changes sign there too, a branch point where it does not (another
branch crosses: :func:`.corrector._turns`), through ``-1`` a period doubling, a complex pair a
Neimark-Sacker bifurcation. A change in the signature is a grazing, each
one between the two points located by bisection (with the bracket that holds it where the
bisection cannot close).

This module drives a branch (:func:`continuation` and its step control, ``_follow``). A
point's prediction, correction and the location of what lies between two points are in
:mod:`.corrector`, the period maps of the field's values in :mod:`.family`, what a branch
holds in :mod:`~blademodel.orbits.branch`, and the switches to other branches in :mod:`.switching`.
"""

from __future__ import annotations

import time
from dataclasses import replace
from typing import Callable

import numpy as np

from .. import interrupts
from ..numeric.blas_threads import blas_threads_for
from .background import Locator, PendingPoint, resolve
from .branch import Branch, ContinuationInterrupted, SpecialPoint  # noqa: F401  (SpecialPoint: the public name)
from .corrector import (KEPT_JACOBIANS, KEPT_ORBITS, _Context, _at_kink, _field_bracket, _off_circle, _special,
                        _tangent, _unstable_count)
from .family import _Family
from .period_map import FlowError, _copy, _key, kernel_mode
from .self_overlap import NEAR, SelfOverlap, segment_projections, segment_ratios
from .shooting import (ROUNDING_LEVEL, ShootingError, _n_coordinates, _scale_of_excursions, below_rounding,
                       find_periodic_orbit, residual_size)


def continuation(config, name: str, start: float, stop: float, *, periods: int = 1, guess=None, mode=None,
                 transient: int = 20, ds: float = 0.01, ds_min: float = 1e-5, ds_max: float = 0.05,
                 max_points: int = 400, tol: float = 1e-10, max_corrections: int = 8, rel_step: float = 1e-6,
                 locate_tol: float = 1e-7, grazing_tol: float | None = None, steps_per_period: int = 1000,
                 event_tol: float = 1e-10, method: str = "rk4", kernel: str = "auto", jacobian: str = "auto",
                 workers: int | None = None, progress: Callable[[int, float], None] | None = None,
                 checkpoint: Callable[[Branch], None] | None = None, checkpoint_every: float = 30.0,
                 resume: Branch | None = None, cyclic: bool = False) -> Branch:
    """Follow the periodic orbits of ``config`` as its field ``name`` goes from ``start`` toward ``stop``.

    Parameters
    ----------
    config : pydantic config
        E.g. :class:`~blademodel.zheng2022.BladePair`; rebuilt at each value of the field.
    name : str
        The field: ``"omega"`` for a forced-response curve, or ``"gamma"``, ``"F0"`` ...
    start, stop : float
        The range; the branch starts at ``start`` and ends when the field leaves the range
        (it may turn back at folds in between), or earlier where it cannot go on or runs onto
        points it already has (a retrace, a closed branch): its ``message`` says which. Both
        must be values the config takes (``ValueError`` otherwise). The branch's last point lies on
        the end it reaches exactly (an orbit shot at the end's value), unless that shot fails where
        the field takes values past the end: the last point is then the first past it.
    periods : int
        Period of the orbits in excitation periods.
    guess, mode, transient
        The first orbit's guess, as for :func:`~blademodel.orbits.find_periodic_orbit`.
    ds, ds_min, ds_max : float
        Arclength step, in units of the scaled state and of the range ``|stop - start|``.
    max_points : int
        Points at most (a resumed branch's included).
    tol : float
        Scaled residual of each corrected point.
    max_corrections : int
        Newton steps per point before the step is halved.
    rel_step : float
        Difference step relative to each state's scale (and to the range, for the field).
    locate_tol : float
        Bifurcations are located to this fraction of the range.
    grazing_tol : float, optional
        Grazing points are located to this (as ``locate_tol``; None: ``locate_tol``).
        Their bisection takes about ``log2(step / grazing_tol)`` trials of one or two
        integrations each, which on a mistuned ring is most of the cost; a coarser
        ``grazing_tol`` moves only where the grazing points are reported, not the branch
        (its points are the same to the bit), and ``inf`` reports each at the first
        point past it, with no trials (``docs/continuation.md``).
    steps_per_period, event_tol, method, kernel
        The integrator's settings.
    jacobian : {"auto", "tangent", "differences", "forward"}
        How the period map is differentiated (:class:`~blademodel.orbits.period_map.PeriodMap`);
        ``"forward"`` halves the integrations of a ring's Jacobian (multipliers to about ``rel_step``).
    workers : int, optional
        Threads for the difference quotients where the map is differentiated by
        differences (rings): ``None`` or ``-1`` every CPU, ``1`` none; with two or more,
        grazing points are also located in a thread of their own beside the continuation
        (:mod:`.background`). The branch and its special points are the same to the bit
        whatever the number.
    progress : callable, optional
        ``progress(point, value)`` after each point.
    checkpoint : callable, optional
        ``checkpoint(branch)`` with the branch so far (``complete`` False), after a point,
        once ``checkpoint_every`` seconds have passed since the start or the last call: to
        save it, so that a run that is killed keeps its points.
    checkpoint_every : float
        Seconds between two checkpoints.
    resume : Branch, optional
        An unfinished branch of the same field, period and range (a checkpoint, or the
        ``branch`` of :class:`ContinuationInterrupted`, e.g. from
        :func:`~blademodel.orbits.branch_file.load_branch`): the continuation starts
        from its last orbit (shot again, from its state and mode), along the secant
        of its last two points, and the branch returned holds its points, special
        points and cost before the new ones. The steps after it are not those the
        interrupted run would have taken (the step length starts again from ``ds``).
    cyclic : bool
        For a tuned bladed disk under engine-order excitation: follow its travelling-wave
        orbits on the map reduced by their symmetry (:mod:`.cyclic`), over ``T / d`` of
        the period (``d = N / gcd(EO, N)``: 8 on the 24-blade ring at engine order 3),
        with the whole ring's multipliers from its Jacobian. The first orbit (from the
        transient or the guess) must be a fixed point of the reduced map that comes back
        after ``periods`` periods (a travelling wave for 1; the doubled orbits of
        :func:`period_doubled_branch` for 2).

    Returns
    -------
    Branch

    Raises
    ------
    ContinuationInterrupted
        On Ctrl-C (a :class:`KeyboardInterrupt`), with the branch so far.
    ValueError
        If ``resume`` is not a branch of ``name`` with ``periods`` that lies in the range.
    CyclicError
        With ``cyclic``, for a model without the symmetry (naming the field that breaks
        it), or a first orbit that is no travelling wave (a ``ValueError``).
    """
    kwargs = dict(periods=periods, guess=guess, mode=mode, transient=transient, ds=ds, ds_min=ds_min, ds_max=ds_max,
                  max_points=max_points, tol=tol, max_corrections=max_corrections, rel_step=rel_step,
                  locate_tol=locate_tol, grazing_tol=grazing_tol, steps_per_period=steps_per_period,
                  event_tol=event_tol, method=method, kernel=kernel, jacobian=jacobian, workers=workers,
                  progress=progress, checkpoint=checkpoint, checkpoint_every=checkpoint_every)
    if not cyclic:
        return _segment(config, name, start, stop, resume=resume, cyclic=False, **kwargs)
    return _cyclic_branch(config, name, start, stop, resume, kwargs)


#: Points the whole period's map takes past a stall of the cyclic reduction before the reduced map goes on.
CYCLIC_FALLBACK_POINTS = 10


def _cyclic_branch(config, name, start, stop, resume, kwargs) -> Branch:
    """:func:`continuation` with ``cyclic``: on the reduced map, and where that stalls, on the whole period's for
    :data:`CYCLIC_FALLBACK_POINTS` points, then on the reduced map again (each part resuming the last).

    The reduced map's section sees every contact's switching times modulo ``T / d``, not
    ``T``: ``d`` times as many pass it as the whole map's, and where one does the map has a
    kink. Since start states are settled (:func:`~.period_map.settle`) the branch steps over
    the one that stalled it on the tuned 24-blade ring (292.725 rad/s); the fallback stays
    for stalls the settling does not remove. Where the whole map stalls too, or the orbit
    past the stall is no travelling wave, the whole map finishes the branch.
    """
    from .cyclic import CyclicError
    max_points = kwargs["max_points"]
    b = resume
    cyclic = True
    stalls: list = []   # where the reduced map stalled and the whole map took over
    while True:
        if b is not None:   # a part after the first goes on from the last orbit, not from a transient
            kwargs = {**kwargs, "transient": 0}
        if cyclic:
            try:
                b = _segment(config, name, start, stop, resume=b, cyclic=True, **kwargs)
            except CyclicError:
                if b is None:
                    raise
                stalls.append((float(b.params[-1]), "its orbit there is no travelling wave"))
                cyclic = False   # the orbit past the stall broke the symmetry: the whole map from here on
                continue
            if not b.message.startswith(STALLED) or b.params.size >= max_points:
                return _noting(b, name, stalls)
            stalls.append((float(b.params[-1]), None))
            cyclic = False
            limit = min(b.params.size + CYCLIC_FALLBACK_POINTS, max_points)
        else:
            limit = max_points
        before = b.params.size
        b = _segment(config, name, start, stop, resume=b, cyclic=False, **{**kwargs, "max_points": limit})
        if limit == max_points or b.message.startswith(STALLED) or b.params.size <= before:
            return _noting(b, name, stalls)
        cyclic = True


def _noting(b: Branch, name: str, stalls: list) -> Branch:
    """``b`` with its message saying where the whole period's map took over from the cyclic reduction."""
    if not stalls:
        return b
    where = ", ".join(f"{name} = {v:.6g}" + (f" ({why})" if why else "") for v, why in stalls)
    return replace(b, message=f"{b.message} (the cyclic reduction stalled at {where}; the whole period's map took "
                              f"the branch on from there)")


def _segment(config, name: str, start: float, stop: float, *, periods, guess, mode, transient, ds, ds_min, ds_max,
             max_points, tol, max_corrections, rel_step, locate_tol, grazing_tol, steps_per_period, event_tol,
             method, kernel, jacobian, workers, progress, checkpoint, checkpoint_every, resume,
             cyclic) -> Branch:
    """:func:`continuation`, on the reduced map throughout where ``cyclic``."""
    settings = dict(steps_per_period=steps_per_period, event_tol=event_tol, method=method, kernel=kernel)
    _check_grazing_tol(grazing_tol)
    span = abs(stop - start)
    if not span > 0:
        raise ValueError(f"start and stop must differ, got {start!r} and {stop!r}")
    direction = 1.0 if stop > start else -1.0
    at = start
    if resume is not None:
        _check_resumable(resume, name, periods, start, stop)
        at, guess = float(resume.params[-1]), resume.states[-1]
    fam = _Family(config, name, periods, settings, at, jacobian, bounds=(start, stop), workers=workers)
    P0 = fam.map_at(at)
    if cyclic:
        from .cyclic import CyclicSymmetry
        fam.reduce_by(CyclicSymmetry(fam.config_at(at), P0.integrator, periods=periods))
    if resume is not None:
        mode = _last_mode(resume, P0.integrator)
    try:
        first = find_periodic_orbit(None, periods=periods, guess=guess, mode=mode, transient=transient, tol=tol,
                                    rel_step=rel_step, integrator=P0.integrator, jacobian=jacobian, workers=workers)
    except ShootingError as e:
        raise _no_first_orbit(e, name, at, periods, transient, guess is not None) from None
    scale = first.scale
    n = scale.size
    ctx = _Context(fam, scale, span, tol, rel_step, max_corrections, grazing_tol)

    # scaled unknowns X = (y / scale, lambda / span)
    X = np.append(first.state / scale, at / span)
    m = first.mode
    if cyclic:
        X, m = _travelling_wave(ctx, X, m, name, at)
    A = ctx.jacobian(X, m)
    if resume is not None and resume.params.size > 1:   # onward along the secant of its last two points
        T = _tangent(A, X - np.append(resume.states[-2] / scale, resume.params[-2] / span))
    else:
        T = _tangent(A, np.append(np.zeros(n), direction))
    with blas_threads_for(n):   # multipliers, corrections and predictions of the orbit's size
        return _run(ctx, [ctx.point(X, m, A)], X, T, m, A, (start, stop), ds=ds, ds_min=ds_min, ds_max=ds_max,
                    max_points=max_points, locate_tol=locate_tol, progress=progress, checkpoint=checkpoint,
                    checkpoint_every=checkpoint_every, before=resume)


#: How close (scaled residual) an orbit of the whole map must come back under the reduced map, and after its
#: periods under the turn, to be taken as the reduced map's fixed point (:func:`_travelling_wave`,
#: :func:`_reduced_branch_point`).
WAVE_TOL = 1e-6


def _travelling_wave(ctx, X, mode, name, at):
    """The first orbit ``(X, mode)``, found on the whole period's map, solved again on the reduced one (it must be
    a travelling wave: its residual there within :data:`WAVE_TOL`).

    Raises
    ------
    CyclicError
        Where it is not one.
    """
    from .cyclic import CyclicError
    r, _ = ctx.residual(X, mode)
    off = residual_size(r, ctx.discrete)
    Xc, mc, _ = ctx.correct_at_value(X, mode, jacobian=False) if off <= WAVE_TOL else (None, mode, None)
    if Xc is None:
        raise CyclicError(f"the first orbit at {name} = {at:g} is no travelling wave: turned by the symmetry it is "
                          f"{off:.3g} (scaled) from itself; start where the ring's orbit is one (another start, "
                          f"guess or transient), or continue without the cyclic reduction")
    sym = ctx.fam.symmetry
    back = sym.comes_back(Xc[:-1] * ctx.scale, ctx.scale)
    if back > WAVE_TOL:
        raise CyclicError(f"the first orbit at {name} = {at:g} comes back after {sym.periods} period(s) turned by "
                          f"{sym.turn * sym.fraction * sym.periods % sym.blades} blades ({back:.3g} scaled from "
                          f"itself): it is no orbit of that period")
    return Xc, mc


#: A step's grazing point whose location leaves a bracket this many times its tolerance wide was not located
#: (its trials found no orbit inside): :func:`_passed_unseen`.
UNSEEN_BRACKET = 1e3


def _passed_unseen(found: list, ctx, locate_tol: float) -> bool:
    """Whether a grazing point of a step (``found``, :meth:`~.corrector._Context.detect`'s) is left with a bracket
    wider than :data:`UNSEEN_BRACKET` times its tolerance: located now (in this thread), where the location would
    otherwise run beside the continuation. False where grazing points are not located (``grazing_tol = inf``)."""
    tol = locate_tol if ctx.grazing_tol is None else float(ctx.grazing_tol)
    pending = [q for q in found if isinstance(q, PendingPoint)]
    if not pending or not np.isfinite(tol):
        return False
    widest = UNSEEN_BRACKET * tol * ctx.span
    for q in pending:
        located = q.located()
        for at in (located if isinstance(located, list) else [located]):
            bracket = at.get("bracket")
            if bracket is not None and bracket[1] - bracket[0] > widest:
                return True
    return False


def _check_grazing_tol(grazing_tol) -> None:
    """Raise ``ValueError`` unless ``grazing_tol`` is None or a number > 0 (``inf`` included)."""
    if grazing_tol is not None and not float(grazing_tol) > 0.0:
        raise ValueError(f"grazing_tol must be > 0 (or inf: no location), got {grazing_tol!r}")


def _check_resumable(branch: Branch, name: str, periods: int, start: float, stop: float) -> None:
    """Raise ``ValueError`` (naming what differs) unless ``branch`` can be resumed by this continuation."""
    if branch.field != name or branch.periods != periods:
        raise ValueError(f"resume: the branch was continued in {branch.field!r} with period {branch.periods}, "
                         f"not in {name!r} with period {periods}")
    if branch.params.size == 0:
        raise ValueError("resume: the branch has no points")
    lo, hi = min(start, stop), max(start, stop)
    last = float(branch.params[-1])
    if not lo <= last <= hi:
        raise ValueError(f"resume: the branch's last point, {name} = {last:g}, lies outside [{lo:g}, {hi:g}]")


def _last_mode(branch: Branch, integrator):
    """The mode of the branch's last orbit as the kernel takes it, or None where the branch does not know it."""
    if branch.modes.shape[0] != branch.params.size or branch.modes.shape[1] == 0 or np.any(branch.modes[-1] < 0):
        return None
    return kernel_mode(integrator, branch.modes[-1].astype(np.int64))


def _mode_row(mode) -> np.ndarray:
    """A mode as a row of :attr:`Branch.modes`."""
    return np.atleast_1d(np.asarray(mode, dtype=np.int64)).copy()


def _run(ctx, pts, X, T, m, A, bounds, *, progress, checkpoint, checkpoint_every, before=None, **follow) -> Branch:
    """:func:`_follow` into a :class:`Branch` (after the points of ``before``), with checkpoints and Ctrl-C."""
    special: list = []
    last = time.monotonic()

    def report(point: int, value: float) -> None:
        nonlocal last
        interrupts.check()   # a Ctrl-C whose exception compiled code swallowed
        if progress is not None:
            progress(point, value)
        if checkpoint is not None and time.monotonic() - last >= checkpoint_every:
            checkpoint(_assemble(ctx, pts, special, f"in progress at {ctx.fam.name} = {value:.6g}", before, False))
            last = time.monotonic()

    earlier = 0 if before is None else before.params.size - 1
    # grazing points located on period maps of their own, beside the continuation where a second CPU is free
    ctx.locator = Locator(ctx.twin, thread=ctx.fam.workers >= 2)
    try:
        try:
            prior = None if before is None or before.params.size < 2 else \
                {"state": before.states[-2], "param": float(before.params[-2])}
            message = _follow(ctx, pts, special, X, T, m, A, bounds, progress=report, earlier=earlier, prior=prior,
                              **follow)
        except KeyboardInterrupt:
            interrupts.acknowledge()
            where = f"{ctx.fam.name} = {pts[-1]['param']:.6g}"
            raise ContinuationInterrupted(f"interrupted at {where} after {earlier + len(pts)} points",
                                          _assemble(ctx, pts, special, f"interrupted at {where}", before,
                                                    False)) from None
        return _assemble(ctx, pts, special, message, before, True)
    finally:
        ctx.locator.shutdown()
        ctx.locator = None


def _assemble(ctx, pts, special, message: str, before: Branch | None, complete: bool) -> Branch:
    """The branch of the points ``pts`` and ``special`` points, after those of ``before`` (whose last point is
    ``pts[0]`` found again), once the special points still being located have their places (in ``special``)."""
    fam = ctx.fam
    resolve(special)
    integrations, replays = fam.work()
    if ctx.locator is not None and ctx.locator.context is not None:
        twin = ctx.locator.context.fam.work()
        integrations, replays = integrations + twin[0], replays + twin[1]
    b = Branch(field=fam.name, periods=fam.periods, params=np.array([p["param"] for p in pts]),
               states=np.array([p["state"] for p in pts]), multipliers=np.array([p["mu"] for p in pts]),
               stable=np.array([p["stable"] for p in pts], dtype=bool),
               amplitudes=np.array([p["amp"] for p in pts]), harmonics=np.array([p["h1"] for p in pts]),
               events=np.array([p["events"] for p in pts], dtype=np.int64) * (
                   fam.symmetry.fraction * fam.symmetry.periods if fam.symmetry else 1),
               residuals=np.array([p["residual"] for p in pts]),
               sections=np.array([p["sections"] for p in pts]), special=_along_branch(special, pts, ctx),
               state_names=fam.state_names()[:ctx.n], message=message, integrations=integrations,
               replays=replays, modes=np.array([_mode_row(p["mode"]) for p in pts]), complete=complete,
               mean_squares=np.array([p["ms"] for p in pts]))
    if before is None:
        return b
    k = before.params.size - 1   # before's last point is this run's first
    if before.modes.shape != (k + 1, b.modes.shape[1]):   # unknown (a file written before modes were kept)
        before = replace(before, modes=np.full((k + 1, b.modes.shape[1]), -1, dtype=np.int64))
    if before.mean_squares.shape != (k + 1, b.mean_squares.shape[1]):   # unknown (a file written before they were)
        before = replace(before, mean_squares=np.full((k + 1, b.mean_squares.shape[1]), np.nan))
    return replace(b, **{f: np.concatenate([np.asarray(getattr(before, f))[:k], getattr(b, f)]) for f in _PER_POINT},
                   special=list(before.special) + [replace(q, index=q.index + k) for q in special],
                   integrations=before.integrations + integrations, replays=before.replays + replays)


def _along_branch(special: list, pts: list, ctx) -> list:
    """The special points in their order along the branch: by the point after which each lies, then by where it
    projects onto the chord to the next point (in the scaled unknowns). Those of one step are found by kind, the
    changes of stability first and the grazing points after them, whatever their places."""
    def place(p: SpecialPoint) -> tuple:
        i = p.index
        if i + 1 >= len(pts):
            return i, 0.0
        a, b, x = (ctx.unknowns(q) for q in (pts[i], pts[i + 1], {"state": p.state, "param": p.param}))
        chord = b - a
        length = float(chord @ chord)
        return i, (float((x - a) @ chord) / length if length > 0.0 else 0.0)

    return sorted(special, key=place)


#: The fields of :class:`Branch` that hold one entry per point.
_PER_POINT = ("params", "states", "multipliers", "stable", "amplitudes", "harmonics", "events", "residuals",
              "sections", "modes", "mean_squares")


def _no_first_orbit(e: ShootingError, name: str, at: float, periods: int, transient: int,
                    guessed: bool) -> ShootingError:
    """The shooting error at a branch's first point, saying where it was and what may find an orbit there."""
    start = "from the guess" if guessed else f"after {transient} periods from rest"
    if getattr(e, "least_tol", None) is not None:   # the tolerance is below rounding, the start is fine
        err = ShootingError(f"no orbit of period {periods} found at the start, {name} = {at:g} ({start}) to the "
                            f"tolerance asked: {e}", e.history, e.state)
        err.least_tol = e.least_tol
    else:
        err = ShootingError(f"no orbit of period {periods} found at the start, {name} = {at:g} ({start}): {e}. "
                            f"Where the residual stays large the start is far from such an orbit (the motion there "
                            f"may be chaotic or of another period): another transient, a guess, another start or "
                            f"another period may find one", e.history, e.state)
    err.at_start = True   # for the command's hint at its options
    return err


def _follow(ctx, pts, special, X, T, m, A, bounds, *, ds, ds_min, ds_max, max_points, locate_tol, progress,
            earlier: int = 0, prior: dict | None = None, stop: Callable[[list], str | None] | None = None) -> str:
    """Continue from the last point ``pts[-1]`` (unknowns ``X``, tangent ``T``) until the field leaves ``bounds``.

    Appends the points to ``pts`` and the special points to ``special`` as it finds them;
    returns why it stopped. ``prior``: a resumed branch's point before ``pts[0]`` (its
    ``state`` and ``param``), for the secant that the shots past a kink or a gap take while
    ``pts`` holds one point. ``earlier`` points before ``pts`` (a resumed branch's) count
    toward ``max_points``, and progress reports the total. ``stop(pts)``, asked after every
    regular point, may end the branch there, returning why.
    """
    fam, span = ctx.fam, ctx.span
    name = fam.name
    ig = fam.map_at(X[-1] * span).integrator
    n_q = _n_coordinates(ig)
    lo, hi = min(bounds), max(bounds)
    h = ds
    message = ""   # (every way out of the loop below says why)
    jumped = ahead = switched = gap_tried = modes_tried = False
    ahead_reach = AHEAD_FRACTIONS   # the fractions of the range shots just ahead may take (until a regular point)
    shots = True        # fixed-value shots allowed (not on the retry of a step whose shot led onto a side arm)
    landing = None      # where the branch stood before its last fixed-value shot, while a reversal may undo it
    overlap = SelfOverlap(ctx.n)
    retaken = []        # (where, the shorter ds_max) of each wrong turn taken again (:func:`_before_the_turn`)
    while earlier + len(pts) < max_points:
        X_pred, A_pred = ctx.predict(pts, X, T, A, h)
        landed, X_end, beyond = _end_landing(ctx, X, X_pred, bounds)
        X_new = None
        if landed is not None:
            # the prediction passes an end of the range: the branch lands on the end itself, shooting at its
            # value. Where the field takes no values past it (mu below 0) corrections there cannot be built;
            # where it does, a shot that fails or lands off the step (the branch turns before the end) leaves
            # the step to the arclength correction, and the branch ends at its first point past the end
            X_new, m_new, A_new = ctx.correct_at_value(X_end, m)
            if beyond and X_new is not None and np.linalg.norm(X_new - X_end) > h:
                X_new = None
        if X_new is None and (landed is None or beyond):
            X_new, m_new, A_new = ctx.correct(X_pred, T, m, A_pred, column=ctx.column_rule(pts))
        if X_new is not None and np.linalg.norm(X_new - X_pred) > ds_max and _passed(ctx, pts[:-2], X_new, h):
            # Newton's method wandered off and converged on the part of the branch already passed
            # (measured: from 261.45 rad/s, 35 steps away, onto the bilinear pair's branch at 266.15
            # rad/s, which the branch then went round again until max_points; at ds_max = 0.03, with the
            # steps shrunk to 6.3e-3 at 261.432 rad/s, onto it at 266.069, between two of its points)
            ctx.why = "the correction converged back onto the branch already passed"
            X_new = None
        A_last = A if A is not None else pts[-1].get("A")   # (a jump across a kink drops A: the last point's)
        if X_new is not None and A_last is not None and _ran_back_unturned(ctx, pts, X, X_new, T, A_last, A_new, h):
            # behind the last point in the field, with no turn between them: not the branch ahead (the Iwan pair at
            # 2000 steps a period, from 157.376 back to 157.131 rad/s, every orbit there stable and their events
            # changing at every step: it then went over its points again and stopped). As a failed correction
            ctx.why = "the correction landed behind the last point in the field with no turn between them"
            X_new = None
        secant = False
        if X_new is None and abs(T[-1]) > 0.1 and shots:
            # Newton on the arclength system can cycle across a kink of the map (a switching
            # time passing the section); away from folds, shooting at the predicted value does not
            X_new, m_new, A_new = ctx.correct_at_value(X + h * T, m)
            secant = X_new is not None
        trail = pts if len(pts) > 1 or prior is None else [prior, *pts]   # the last two points for a secant
        if X_new is None and h / 2 < ds_min and not ahead and len(trail) > 1 and shots:
            # the arclength corrections fail at every step length just before a kink of the map (a
            # stick phase that appears or vanishes): shooting at values of the field just past it,
            # from the last orbit, converges (the Coulomb pair at 164.915 rad/s, in 2 to 5 steps).
            # The way on is the secant's (the tangent from difference quotients that straddle the
            # kink can point anywhere: there its field component was -0.003 on a rising branch)
            ahead = True
            X_new, m_new, A_new = (None, m, None) if not ahead_reach else \
                _shoot_along_secant(ctx, trail, X, m, ahead_reach)
            secant = X_new is not None
        arm = False
        if X_new is None and h / 2 < ds_min and jumped and not switched and pts[-1]["unstable"]:
            # even the jump failed, on an unstable arm: a turn reached from its unstable side (a
            # nonsmooth fold, where no orbit lies ahead); the stable arm that the turn leads back onto
            switched = True
            X_new, m_new, A_new = _other_arm(ctx, trail, X, m, ds_max)
            arm = X_new is not None
        if X_new is None and h / 2 < ds_min and jumped and shots and not modes_tried and len(trail) > 1:
            # a stick-slip switch of the orbit at the section, met from the side where Newton's method stalls
            # in the last orbit's mode: shots just ahead from the kernel's other modes
            modes_tried = True
            X_new, m_new, A_new = _shoot_from_other_modes(ctx, trail, X, m, ds_max)
            secant = X_new is not None
        gap = False
        if X_new is None and h / 2 < ds_min and jumped and shots and not gap_tried and len(trail) > 1:
            # everything else failed at the shortest step: the discrete flow may have no orbit over a
            # stretch (the bilinear 24-blade ring from 290.85 to 290.90 rad/s at 1000 steps a period, and
            # orbits from 290.95 on); shooting farther on, from the last orbit, may find the branch past it
            gap_tried = True
            X_new, m_new, A_new = _shoot_along_secant(ctx, trail, X, m, GAP_REACH)
            gap = secant = X_new is not None
        if X_new is None:
            if h / 2 < ds_min:
                if not jumped and len(trail) > 1:
                    # halving brought the prediction ever closer to a kink of the map (a switching
                    # time passing the section), where the difference quotients, and so the tangent,
                    # straddle it: jump across along the secant of the last two points instead
                    prev = ctx.unknowns(trail[-2])
                    if np.linalg.norm(X - prev) > 0:
                        T = (X - prev) / np.linalg.norm(X - prev)
                        A = None
                    jumped, h = True, 4 * ds_min * max(1.0, ds / ds_min) ** 0.5
                    continue
                message = _stalled(ds_min, name, X[-1] * span, ctx, fam.settings["steps_per_period"])
                break
            h /= 2
            continue
        iterations = ctx.iterations   # the point's own corrections (locating its bifurcations makes others)
        new = ctx.point(X_new, m_new, A_new)
        if new["residual"] > ctx.tol:
            # a correction that returned a state that is not an orbit in the mode it is recorded in
            # (a guard, not expected to fire: the correctors check the mode the orbit comes back to)
            ctx.why = f"the corrected point's residual {new['residual']:.3g} exceeds tol"
            ctx.rounding = new["residual"] if new["residual"] <= ROUNDING_LEVEL else None   # tol below rounding
            h /= 2
            if h < ds_min:
                message = _stalled(ds_min, name, X[-1] * span, ctx, fam.settings["steps_per_period"])
                break
            continue
        new["regular"] = not (secant or arm)
        if arm:   # the turn is at the unstable arm's last orbit, to within the last step tried past it
            found = [_special("nonsmooth-fold", pts[-1], len(pts) - 1)]
        elif gap:   # nothing is located inside (no orbit was found there): the gap itself is the special point
            found = [_special("gap", new, len(pts) - 1, bracket=_field_bracket(X, X_new, span))]
        else:
            found = ctx.detect(pts[-1], new, X, T, m, len(pts) - 1, locate_tol,
                               before=pts[-2] if len(pts) > 1 else None)
        if secant and not (ahead or gap) and h / 2 >= ds_min and _passed_unseen(found, ctx, locate_tol):
            # the step's grazing could not be bracketed from the last orbit: trials inside found no orbit
            # there, so the branch does not run straight from one point to the next. Measured on the Coulomb
            # pair at ds_max 0.15: a shot at a fixed value (the arclength corrections had failed) from 412.8
            # to 427.2 rad/s landed past its S at 420.35-420.68 rad/s (two folds and the unstable arm
            # between), with a grazing point bracketed in [419.2, 422.6] as the only trace. A shorter step
            ctx.why = "the step's grazing point could not be located (the step passed a turn or a gap)"
            h /= 2
            continue
        off_circle = any(_at_kink(q) for q in found)
        retry = any(_off_circle(q) for q in found)
        T_away = None   # past a kink the new point lies on another arm: onward on it is away from the kink
        if not retry and any(q.kind == "border-collision" for q in found):
            # a border collision is off the circle by nature: where the branch goes on through it (its new
            # tangent, oriented away from the kink, keeps the field's direction) it is kept; where it
            # turns back it is a nonsmooth fold, approached by shorter steps as before
            T_away = _away_from_kink(ctx, X_new, m_new, A_new, new["events"], X_new - X, np.sign(T[-1]),
                                     pts[-1]["unstable"])
            retry = float(T_away[-1]) * float(T[-1]) < 0
        if not jumped and h / 2 >= ds_min and retry:
            # the stability changed, but no multiplier lies on the unit circle where the change is
            # located: the correction landed on another arm of the branch (measured on the bilinear
            # pair's period-2 branch, from an unstable arm to a stable one); a shorter step
            h /= 2   # (a grazing found is not located: its location starts once the step is taken)
            continue
        if off_circle:
            # even the shortest step (or a jump across a kink) changed the stability with no
            # multiplier on the circle: the arm that comes back from a nonsmooth fold (a grazing
            # where the branch turns: the Coulomb pair at 420.684 rad/s), whose tangent opposes
            # the last one, so orienting it by that one (or taking the secant to it, where the
            # point was shot at a value of the field) would lead back into the fold. Onward is
            # away from the kink (:func:`_away_from_kink`)
            T_new = T_away if T_away is not None else \
                _away_from_kink(ctx, X_new, m_new, A_new, new["events"], X_new - X, np.sign(T[-1]),
                                pts[-1]["unstable"])
        elif secant:   # the difference quotients there may straddle the kink: the secant is the tangent
            T_new = (X_new - X) / np.linalg.norm(X_new - X)
        elif jumped:   # across a kink: onward is away from the last point
            T_new = _tangent(A_new, X_new - X)
        else:
            T_new = _tangent(A_new, T)
            if A is not None and T_new[-1] * T[-1] < 0:
                T_new = _oriented(T_new, A_new, A, T)
        if landing is not None and new["regular"] and not jumped and not off_circle and \
                float(X_new[-1] - X[-1]) * float(T[-1]) < 0 and \
                not any(q.kind in ("fold", "nonsmooth-fold") for q in found):
            # a regular step that runs back in the field with no fold, soon after a fixed-value shot: the
            # shot landed on a side arm that ends at a grazing, and this step crossed back onto the branch
            # (which it would retrace). Back to where the shot started, shorter, without shots
            _truncate(pts, special, overlap, landing["points"], landing["special"])
            X, T, A, m, h = landing["X"], landing["T"], landing["A"], landing["m"], landing["h"] / 2
            ctx.scale = landing["scale"]
            landing, shots, jumped, ahead = None, False, False, False
            continue
        if secant:
            landing = {"points": len(pts), "special": len(special), "X": X, "T": T, "A": A, "m": m, "h": h,
                       "scale": ctx.scale.copy(), "steps": 0}
        elif landing is not None:
            landing["steps"] += 1
            if landing["steps"] > LANDING_WATCH:
                landing = None
        if new["regular"]:
            shots = True
        if secant and (ahead or gap):
            h = max(h, 4 * ds_min)   # past the kink (the gap): steps grow again from there
        if new["regular"]:
            ahead_reach = AHEAD_FRACTIONS
        elif secant and ahead:
            # the next shots just ahead, before a regular point, go farther than this one: shots that each took the
            # least fraction crawled (the bilinear 24-blade ring at 500 steps a period, 49 points 1.5e-7 rad/s apart
            # from 290.8391745 rad/s, until max_points, where the discrete flow has no orbit a step further)
            ahead_reach = tuple(f for f in ahead_reach if f > 1.5 * abs(float(X_new[-1] - X[-1])))
        ahead = False
        if off_circle:
            found = _kinds_at_kink(found, bool(T_new[-1] * T[-1] < 0))
        jumped = False
        if new["regular"]:
            # a turn further on may be reached from its unstable side too, and another gap may follow
            switched = gap_tried = modes_tried = False
        for q in found:
            if isinstance(q, PendingPoint):
                q.start()
        special += found
        new["n_special"] = len(special)
        pts.append(new)
        # each state scaled by its excursion on the newest orbit: amplitudes that grow a
        # hundredfold through a resonance do not shrink the steps a hundredfold
        taken = float(np.linalg.norm(X_new - X))
        X, T, A = ctx.rescale(_scale_of_excursions(new["magnitude"], n_q, ctx.discrete), X_new, T_new, A_new)
        new["X"], new["A"], new["T"] = X, A, T   # (T: to come back to, after a wrong turn)
        new["scale"] = ctx.scale                 # (the scale A is in: for its monodromy matrix, once dropped)
        _shed(pts)
        m = m_new
        h = min(h * 1.5, ds_max) if iterations <= 4 else (h if iterations <= 8 else h / 2)
        if len(pts) > 1 and new["regular"]:
            h = _multiplier_step(h, taken, pts[-2]["mu"], new["mu"], ds_min)
        if progress is not None:
            progress(earlier + len(pts), X[-1] * span)
        lam = X[-1] * span
        on_end = landed is not None and float(X_new[-1]) == X_end[-1]   # (the shot keeps the field's value)
        if lam > hi + 1e-12 * span or lam < lo - 1e-12 * span or on_end:
            if bounds[1] in (lo, hi) and (lam > hi if bounds[1] == hi else lam < lo) or on_end and landed == bounds[1]:
                message = f"reached {name} = {bounds[1]:g}"
            else:
                message = _left_at_start(lo, hi, name, bounds[0], special)
            break
        on_itself = overlap.verdict(pts, np.append(ctx.scale, span), taken) if new["regular"] else None
        if on_itself is not None:
            again = _before_the_turn(pts, *on_itself) if len(retaken) < RETRACE_RETRIES else None
            if again is None:
                message = _on_itself(*on_itself, name, pts, earlier)
                break
            # a wrong turn at a kink: back to before it, the longest step halved for the rest of the branch
            k, turn = again
            retaken.append((pts[turn]["param"], ds_max / 2))
            q = pts[k]
            _truncate(pts, special, overlap, k + 1, q["n_special"])
            X, T, A, m = q["X"], q["T"], q["A"], _copy(q["mode"])
            ctx.scale = q["scale"]   # the scaling X, T and A were rescaled to
            ds_max /= 2
            h = min(h, ds_max)
            landing, shots, jumped, ahead, switched, gap_tried = None, True, False, False, False, False
            modes_tried, ahead_reach = False, AHEAD_FRACTIONS
            continue
        why = stop(pts) if stop is not None and new["regular"] else None
        if why is not None:
            message = why
            break
    else:
        message = f"stopped after max_points = {max_points} points at {name} = {X[-1] * span:.6g}"
    for value, shorter in retaken:
        message += (f" (it turned back onto itself after a wrong turn near {name} = {value:.6g} and took the turn "
                    f"again from before it at ds_max = {shorter:g})")
    return message


def _shed(pts) -> None:
    """Drop from the older branch points what only the last ones need: the orbit's record (the last
    :data:`~.corrector.KEPT_ORBITS` keep it) and the monodromy matrix (the last
    :data:`~.corrector.KEPT_JACOBIANS`; a point that keeps no scale for its ``A`` keeps it), so that a branch's
    memory does not grow with its points by an orbit and a matrix a point."""
    if len(pts) > KEPT_ORBITS:
        pts[-KEPT_ORBITS - 1].pop("Y", None)
    if len(pts) > KEPT_JACOBIANS and "scale" in pts[-KEPT_JACOBIANS - 1]:
        pts[-KEPT_JACOBIANS - 1].pop("J", None)


def _kinds_at_kink(found: list, turned: bool) -> list:
    """The special points ``found`` by a step whose stability changed at a kink of the map (one of them located where
    no multiplier lies on the unit circle, :func:`.corrector._off_circle`): where the branch ``turned`` there, those
    at the kink (border collisions too) are a nonsmooth fold; else those off the circle are border collisions,
    whatever the multiplier nearest the circle. The Iwan pair down in omega at 2000 steps a period (its elements'
    slips missed by the kernel, since mended) reported three Neimark-Sacker bifurcations near 165.56 rad/s with a
    multiplier of modulus 0.458: the stability changes of an unstable window at kinks, the multiplier nearest the
    circle a complex one inside it."""
    return [replace(q, kind="nonsmooth-fold") if turned and _at_kink(q) else
            replace(q, kind="border-collision") if _off_circle(q) else q for q in found]


def _left_at_start(lo: float, hi: float, name: str, start: float, special: list) -> str:
    """Why a branch that left its range at the end it started from stopped: the range, that end, and the last
    turn (a fold of either kind) that brought it back, if the branch has one."""
    message = f"left [{lo:g}, {hi:g}] in {name} at {name} = {start:g}, the end it started from"
    turns = [q for q in special if q.kind in ("fold", "nonsmooth-fold")]
    if turns:
        message += f", after it turned back at the {turns[-1].kind} at {name} = {turns[-1].param:.6g}"
    return message


def _end_landing(ctx, X, X_pred, bounds) -> tuple:
    """``(end, X_end, beyond)`` where the prediction ``X_pred`` from ``X`` passes an end of the range ``bounds``:
    that end, the unknowns where the prediction's line meets it (to shoot from), and whether the field takes
    values past it; else ``(None, None, None)``."""
    lam = X_pred[-1] * ctx.span
    for end, outward in ((max(bounds), 1.0), (min(bounds), -1.0)):
        if (lam - end) * outward > 0 and (X[-1] * ctx.span - end) * outward < 0:
            x_end = end / ctx.span
            X_end = X + (x_end - X[-1]) / (X_pred[-1] - X[-1]) * (X_pred - X)
            X_end[-1] = x_end
            return end, X_end, bool(ctx.fam.admits(lam))
    return None, None, None


#: How many times a branch that turned back onto itself (a wrong turn at a kink) goes back before the turn with its
#: longest step halved, before it stops there (:func:`_before_the_turn`).
RETRACE_RETRIES = 2


def _before_the_turn(pts, way: str, since: int, segment: int) -> tuple[int, int] | None:
    """Where a branch that retraces its points (``way == "back"``: from point ``since`` on it lies on segment
    ``segment`` of the part passed, :meth:`SelfOverlap.verdict`) takes its wrong turn again from, and about where
    the turn was: ``(k, turn)``, point indices; or None (a branch come round, or a point that does not keep what
    a new start needs: one of a resumed branch's).

    The points after the turn retrace those before it about step for step, so the turn lies about halfway
    between ``segment`` and ``since``. The branch goes back to ``segment``, where the part it retraced began, so
    that the whole approach to the turn is taken again at the shorter steps: from two points before the turn the
    mistuned bilinear 8-blade ring approached its nonsmooth fold at 252.8536 rad/s as before and turned wrong
    again, at half and at a quarter of the step; from the retraced part's start, at half the step, it turned
    right.
    """
    if way != "back":
        return None
    k, turn = segment, min((segment + 1 + since) // 2, len(pts) - 1)
    if not 0 <= k < len(pts) - 1 or "T" not in pts[k] or "n_special" not in pts[k]:
        return None
    return k, turn


def _truncate(pts, special, overlap, n_points: int, n_special: int) -> None:
    """Drop the points from ``n_points`` on and the special points from ``n_special`` on (cancelling the grazing
    locations not yet begun), as when a branch goes back to an earlier point."""
    for q in special[n_special:]:
        if isinstance(q, PendingPoint) and q.future is not None:
            q.future.cancel()   # a location not yet begun in the locator's thread is not wanted
    del pts[n_points:]
    overlap.truncate(len(pts))
    del special[n_special:]


def _on_itself(way, since, segment, name, pts, earlier) -> str:
    """Why a branch stopped whose points from about ``pts[since]`` lie on its part already passed, from its
    ``segment`` on, going ``way`` (``"back"`` or ``"round"``, :meth:`SelfOverlap.verdict`)."""
    first = f"its point {earlier + since} ({name} = {pts[since]['param']:.6g})"
    onto = f"its points {earlier + segment} to {earlier + segment + 1} ({name} = {pts[segment]['param']:.6g})"
    if way == "back":
        return (f"the branch turned back onto itself: from {first} on it retraces the points it passed, from "
                f"{onto} backwards (a wrong turn at a kink of the map, where the tangent is not defined; a shorter "
                f"ds_max may take the turn right)")
    return (f"the branch came round onto itself: from {first} on it goes over the points it passed, from {onto} "
            f"onwards (a closed branch: an isola, or period-2 orbits between two period doublings)")


def _multiplier_step(h, taken, mu_before, mu_after, ds_min) -> float:
    """The next step ``h``, shortened so that the leading multiplier's modulus, changing as it did over the last step
    (of length ``taken``), changes by at most :data:`MULTIPLIER_STEP` (but to no less than ``4 ds_min``).

    Where a multiplier leaves the unit circle and comes back within one step, neither end of
    the step sees it: the Coulomb pair down at ``ds_max = 0.3``, on the path the predictor's
    test by event signature takes, stepped from 253.8 to 243.0 rad/s, its leading multiplier
    -0.81 and -0.90 there, across the period doublings at 250.32 and 245.37 rad/s (an
    unstable stretch between stable ends, which :meth:`.corrector._Context._window` misses: the point
    before, at 260.4 rad/s, led with another multiplier, of modulus 0.61).
    """
    change = abs(float(abs(mu_after[0])) - float(abs(mu_before[0])))
    if change <= 0.0:
        return h
    return max(min(h, MULTIPLIER_STEP * taken / change), min(h, 4 * ds_min))


def _shoot_along_secant(ctx, pts, X, mode, fractions=None):
    """:func:`_shoot_ahead` from the last orbit ``X`` the way the field went along the secant of the last two points
    (``fractions`` of the range, its default where None): ``(X, mode, A)``, or ``(None, mode, None)`` also where
    that secant does not move the field.

    Used past a kink of the map where the arclength corrections fail (short shots), and past
    a gap of the discrete flow (:data:`GAP_REACH`): where no orbit lies over a stretch of the
    field, which moves with the step (the Coulomb pair at 305.78 rad/s, where a phase is seen
    only once it spans a step end; the bilinear 24-blade ring at 1000 steps a period from
    290.85 to 290.90 rad/s). The orbits either side of a gap may lie on different branches:
    a fold or a turn inside it is not seen.
    """
    way = _field_way(ctx, pts, X)
    if way == 0.0:
        return None, mode, None
    if fractions is None:
        return _shoot_ahead(ctx, X, way, mode)
    return _shoot_ahead(ctx, X, way, mode, fractions=fractions)


def _shoot_from_other_modes(ctx, pts, X, mode, reach):
    """:func:`_shoot_ahead` along the secant's way from the last orbit ``X`` started in each other mode of the
    product-mode kernel (none on the per-contact kernel: a mode for each contact, too many to try), taking the first
    orbit no farther from ``X`` than ``reach`` (the longest step): ``(X, mode, A)`` or ``(None, mode, None)``.

    Where a stick-slip switch of the orbit passes the section, its state there lies on the switching boundary and
    the map has a kink: from the mode of the side the branch came from, Newton's method stalls on the other side,
    while a start in another mode, whose entry reset puts the state on that side, converges. Measured on the
    bilinear pair in ``F0`` from 60 N down: at 4.50999 N the slip orbits' section state reaches the stick
    boundary, shots from the slip mode stalled (residuals 3e-3 to 4e-2 from 4.5085 to 4.492 N) and the branch
    jumped a gap to 2.74 N, over orbits that shooting from rest finds; from the open mode (its entry resets the
    stretch), the shot at 4.5085 N converges on the stick orbit, 0.004 of the scale away. Tried only where
    everything but the gap's long shots failed at the shortest step, so branches that got on before are
    unchanged.
    """
    ig = ctx.fam.map_at(X[-1] * ctx.span).integrator
    way = _field_way(ctx, pts, X)
    if getattr(ig, "kernel", "") != "product" or way == 0.0:
        return None, mode, None
    now = kernel_mode(ig, mode)
    for other in (m for m in range(len(ig.mode_names)) if m != now):
        found = _shoot_ahead(ctx, X, way, other, accept=lambda Xn: float(np.linalg.norm(Xn - X)) <= reach)
        if found[0] is not None:
            return found
    return None, mode, None


#: Points whose field values must all have gone one way for a secant that hardly moves the field to give its way
#: (:func:`_field_way`).
STEADY_POINTS = 4


def _field_way(ctx, pts, X) -> float:
    """The way the field goes at the last point ``X`` (``pts[-1]``'s unknowns): the sign of the secant of the last two
    points in the field, or 0 where that secant hardly moves it (a field component under ``1e-3`` of its length: at
    a fold the way is not known) unless the last :data:`STEADY_POINTS` points' values all went one way.

    The scaled secant's field component depends on the range: where the steps shrink toward a kink the state moves
    much faster than the field, and over 1480 to 2000 rad/s the tuned 24-blade ring's last secant before the kink at
    1481.1533 rad/s had a field component of ``5e-4`` of its length (``2e-2`` over 1470 to 1483, where it went on);
    its values had risen steadily, and shooting just past them found the orbit beyond the kink.
    """
    travel = X - ctx.unknowns(pts[-2])
    if abs(travel[-1]) > 1e-3 * np.linalg.norm(travel):
        return float(np.sign(travel[-1]))
    values = np.array([q["param"] for q in pts[-STEADY_POINTS:]])
    steps = np.sign(np.diff(values))
    if values.size == STEADY_POINTS and steps[0] != 0.0 and np.all(steps == steps[0]):
        return float(steps[0])
    return 0.0


def _passed(ctx, pts, X, step) -> bool:
    """Whether ``X`` lies within ``step`` (the step's length) of one of the branch points ``pts`` or on the polyline
    through them (in the current scaling): within :data:`~.self_overlap.NEAR` of the longer of the segment and
    ``step``, as :class:`~.self_overlap.SelfOverlap` tells a point on the part passed.

    Not only near one of the points: where the steps shrink toward a kink a correction that lands between two points
    passed long before lies farther than the step from both (the bilinear pair down from 600 rad/s at ``ds_max =
    0.03``: from 261.432 rad/s, at a step of ``6.3e-3``, it landed at 266.069, between points 0.1 rad/s apart, and
    the branch went over that stretch again).
    """
    if not pts:
        return False
    P = np.array([ctx.unknowns(q) for q in pts])
    return bool(np.min(np.linalg.norm(P - X, axis=1)) <= step) or _on_polyline(P, X, step)


def _on_polyline(P, X, step) -> bool:
    """Whether ``X`` lies on the polyline through the rows of ``P`` (scaled unknowns): within
    :data:`~.self_overlap.NEAR` of the longer of a segment and ``step``."""
    return len(P) > 1 and bool(np.min(segment_ratios(P[:-1] - X, P[1:] - X, step)) <= NEAR)


#: How the message of a branch that stopped where its step fell below ``ds_min`` begins.
STALLED = "the step fell below ds_min"


def _stalled(ds_min, name, value, ctx, steps_per_period) -> str:
    """Why a branch stopped where its step fell below ``ds_min``, with what may get it through.

    The integrator's discrete flow can lack orbits over a short stretch of the field, and
    the stretch moves with the step: the bilinear 24-blade ring from 290.6 rad/s stops at
    290.847 rad/s at 1000 steps a period and at 290.839 at 500, and passes at 2000 (where a
    run from 290.8 to 290.95 stops at 290.936 instead); the Coulomb pair has such a gap at
    305.78 rad/s. Where the last attempts' residuals stopped falling at the integration's
    rounding errors (``ctx.rounding``), ``tol`` is what stops the branch: the bilinear pair
    at ``tol = 1e-13`` from 280 rad/s, whose residuals stop between ``9e-14`` and ``8e-13``.
    """
    if ctx.rounding is not None:
        return f"{STALLED} = {ds_min:g} at {name} = {value:.6g}: {below_rounding(ctx.rounding, ctx.tol)} ({ctx.why})"
    return (f"{STALLED} = {ds_min:g} at {name} = {value:.6g}: {ctx.why} (the integrator's discrete "
            f"flow may lack orbits over a short stretch, which moves with the step: more steps a period, "
            f"steps_per_period (--steps-per-period) {2 * steps_per_period} instead of {steps_per_period}, may get "
            f"through)")


def _away_from_kink(ctx, X_new, mode, A_new, events, step, heading, before=None, first=1e-3, growth=4.0):
    """The tangent at ``X_new``, a point on an arm of the branch that starts at a kink of the map (the last
    ``step`` crossed it, going the field's way ``heading``, +1 or -1), oriented away from the kink.

    Orienting it away from the last point instead misleads where the step landed on the new
    arm nearer the kink than the last point was from it: an arm that folds back is then
    walked into the kink, turned at it onto the arm the step came from, and the branch
    retraced (measured on the Coulomb pair at its nonsmooth fold at 420.684 rad/s, reached
    by long steps: back down to where it started). Which way the kink lies is decided by
    the first of these that tells:

    1. the side where the stability changed: orbits are corrected at ``X_new`` plus and
       minus ``delta`` along the tangent, on the hyperplane normal to it, for ``delta``
       from ``first`` of the step, growing by ``growth`` up to the step; the kink is on the
       side where the orbit has the last point's count of unstable multipliers ``before``
       (where that differs from ``X_new``'s; else any other count), or another mode, or
       its correction fails, where exactly one side does: a change to a third count is
       another kink (the 96-blade ring's period-doubled branch near 275.18 rad/s, whose
       kinks lie close together, took a wrong turn where any change counted);
    2. the field: where ``X_new`` lies behind the last point (the step passed a turn and
       the correction landed on the arm that comes back), onward is back in the field;
    3. the side where the same probes' events first differ from ``X_new``'s, where exactly
       one side's do.

    Else the tangent oriented away from the last point. The events alone (the rule until
    rule 1 and 2 came first) mislead where the new arm has grazings of its own nearer than
    the kink: the Iwan pair at its nonsmooth fold at F0 = 3.712318 N going down, whose arms
    lie 1e-5 of the state apart, their events changing every 1e-6 N; the branch was walked
    back into the kink and turned onto itself.
    """
    reach = float(np.linalg.norm(step))
    t = _tangent(A_new, step)
    unstable = _unstable_count(ctx.multipliers(A_new))

    def came_from(count):   # whether an orbit with this count of unstable multipliers is on the arm the step left
        return count == before if before is not None and before != unstable else count != unstable

    by_events = None
    delta = first * reach
    while delta <= reach * (1.0 + 1e-12):
        changed, differ = [], []
        for side in (1.0, -1.0):
            Xc, mc, Ac = ctx.correct(X_new + side * delta * t, t, _copy(mode), A_new)
            if Xc is None or _key(mc) != _key(mode) or came_from(_unstable_count(ctx.multipliers(Ac))):
                changed.append(side)
            if Xc is None or ctx.events != events or _key(mc) != _key(mode):
                differ.append(side)
        if len(changed) == 1:
            return -changed[0] * t
        if by_events is None and differ:
            by_events = -differ[0] * t if len(differ) == 1 else t
        if changed:
            break
        delta *= growth
    if float(step[-1]) * heading < 0:
        return t if float(t[-1]) * heading < 0 else -t
    return t if by_events is None else by_events


def _shoot_ahead(ctx, X, direction, mode, fractions=None, accept=None):
    """Shooting at the field's values a little past ``X`` (``direction`` +1 or -1 in the field), from its state:
    the first orbit that converges and that ``accept(X_new)`` takes (its unknowns, mode and Jacobian; ``ctx.events``
    holds its events when ``accept`` is called), else ``(None, mode, None)``. ``fractions`` are of the range (the
    field's scaled unit; :data:`AHEAD_FRACTIONS` where None)."""
    for frac in AHEAD_FRACTIONS if fractions is None else fractions:
        Xv = X.copy()
        Xv[-1] += direction * frac
        X_new, m_new, _ = ctx.correct_at_value(Xv, mode, jacobian=False)
        if X_new is None or (accept is not None and not accept(X_new)):
            continue
        A_new = ctx._jacobian_at(X_new, m_new)
        if A_new is not None:
            return X_new, m_new, A_new
    return None, mode, None


def _other_arm(ctx, pts, X, mode, reach, fractions=(1e-5, 1e-4, 1e-3), displacement=1e-4):
    """The stable arm of a nonsmooth fold reached from its unstable arm: ``(X, mode, A)`` or ``(None, mode, None)``.

    At such a turn (a grazing where the branch folds back: the Coulomb pair at
    420.684 rad/s going down) the unstable arm ``a`` ends and the other arm ``b`` goes
    back in the field, its orbits with the grazing event sequence (a brief stick
    more, say). Next to the turn the two are too close for Newton's method: from
    the last orbit displaced along its unstable eigenvector, onto the side whose run
    has the other event sequence, it converges back to ``a``. A little further back
    in the field (``fractions`` of the range) the arms have separated, and the same
    start converges to ``b``. Accepted: an orbit whose events differ from the last
    point's (measured on the Coulomb pair: at 1e-5 and 5e-5 of a 20 rad/s range back,
    Newton returned to ``a``; at 5e-4 it found the 12-event stable orbit,
    ``|mu| = 0.735``), no farther from the last point than ``reach`` (the longest step,
    in the scaled unknowns): Newton's method may converge anywhere, and an orbit farther
    away is another branch, not the other arm.
    """
    last = pts[-1]
    mu, V = np.linalg.eig(ctx.monodromy(last))
    k = int(np.argmax(np.abs(mu)))
    if abs(mu[k]) <= 1.0 or abs(mu[k].imag) > 1e-9 * abs(mu[k]):
        return None, mode, None
    n = ctx.n
    e = np.real(V[:, k]) / ctx.scale
    e /= np.max(np.abs(e))
    lam = X[-1] * ctx.span
    P = ctx.fam.map_at(lam)
    side = None
    for sign in (1.0, -1.0):
        try:
            P(X[:n] * ctx.scale + sign * displacement * e * ctx.scale, _copy(mode))
        except FlowError:
            continue
        if P.last_events != last["events"]:
            side = sign
            break
    if side is None:
        return None, mode, None
    back = -np.sign(X[-1] - pts[-2]["param"] / ctx.span)   # the field's way back from the turn
    return _shoot_ahead(ctx, np.append(X[:n] + side * displacement * e, X[-1]), back, mode, fractions,
                        accept=lambda X_new: ctx.events != last["events"] and np.linalg.norm(X_new - X) <= reach)


def _ran_back_unturned(ctx, pts, X, X_new, T, A, A_new, step) -> bool:
    """Whether the correction ``X_new`` of a step (length ``step``) from the last point ``X`` (tangent ``T``,
    Jacobian ``A``) landed on the part of the branch already passed, behind ``X`` in the field, with no turn
    between them.

    Along a branch the field changes its way only at a turn. A turn changes the sign of
    ``det(dP/dy - I)`` (``(-1)`` to the number of real multipliers above 1) where an odd number
    of multipliers passes ``+1``: a fold, smooth or at a kink. At the vertex of a symmetric
    branch (which meets another at a pitchfork, its halves images of each other under the
    symmetry) it does not, but a point past that vertex is the image of one passed, not a
    point on the polyline through the points passed (``pts``, the last one ``X`` among them,
    :func:`_on_polyline`), which this asks too.

    Where the last point lies past a kink, on an arm of another stability than the part passed
    (its Jacobian's sign differs from the new point's with no turn between them), a correction on
    that polyline is refused too where it goes back along the part passed beside a point of its
    own stability: the arm after a turn differs in stability from the part it comes back beside.
    Measured on the pair with eight Iwan elements down in ``omega`` at 1000 steps a period: the
    stable arm turns unstable at a kink at 395.42962 rad/s and the branch turns at 395.42951 onto
    a second unstable arm; from the first unstable arm, next to the turn, a correction (and a jump
    along the secant, which keeps no Jacobian: ``A`` is then the last point's) landed back on the
    stable arm, and the branch retraced it; refused, the shots for the other arm find the second one.
    """
    if float(X_new[-1] - X[-1]) * float(T[-1]) >= 0 or len(pts) < 2:
        return False
    P = np.array([ctx.unknowns(q) for q in pts])
    ratios, at = segment_projections(P[:-1] - X_new, P[1:] - X_new, step)
    near = np.flatnonzero(ratios <= NEAR)
    if near.size == 0:
        return False
    n = A.shape[0]
    if np.linalg.slogdet(A[:, :n])[0] * np.linalg.slogdet(A_new[:, :n])[0] > 0:
        return True
    # The Jacobians tell of a turn between the last point and the new one. But where the last point lies on an arm
    # past a kink, the correction can land back on the arm before it, which no turn leads onto: a turn changes the
    # parity of the real multipliers above 1, so the arm after it differs in stability from the part it comes
    # back beside. Landed on the part passed, going back along it, beside a point of its own stability: retraced
    count = _unstable_count(ctx.multipliers(A_new))
    way = float(X_new[-1] - X[-1])
    for k in near:
        beside = pts[k] if at[k] < 0.5 else pts[k + 1]
        if beside["unstable"] == count and float(P[k + 1, -1] - P[k, -1]) * way < 0:
            return True
    return False


def _oriented(T_new, A_new, A, T):
    """``T_new`` or ``-T_new``: the one with ``det([A_new; T_new])`` of the sign of ``det([A; T])``.

    The sign of that determinant is the branch's orientation (it does not change at a fold,
    where the field turns back, nor under the state scaling). Orienting by ``T_new . T > 0``
    instead fails where the tangent turns sharply: at a kink of the map, whose difference
    quotients straddle it, the new tangent kept the state's way and reversed the field's (the
    bilinear pair at 154.267 rad/s, going down: the branch then went back up over itself).
    """
    s_old = np.linalg.slogdet(np.vstack([A, T]))[0]
    s_new = np.linalg.slogdet(np.vstack([A_new, T_new]))[0]
    return T_new if s_old * s_new >= 0 else -T_new
#: The most the leading Floquet multiplier's modulus may change from one branch point to the next, estimated from
#: the last step (:func:`_multiplier_step`): windows of instability narrower than a step are resolved.
MULTIPLIER_STEP = 0.1
#: How far past the last orbit (fractions of the range) a branch stalled at the shortest step shoots for an orbit
#: beyond a gap of the discrete flow (:func:`_shoot_along_secant`).
GAP_REACH = (3e-3, 1e-2, 3e-2)
#: How far past the last orbit (fractions of the range) a branch stalled at the shortest step before a kink shoots
#: first (:func:`_shoot_ahead`); shots in a row, with no regular point between, each go farther than the last.
AHEAD_FRACTIONS = (1e-6, 1e-5, 1e-4, 1e-3)
#: Regular steps after a fixed-value shot during which a step that runs back in the field with no fold sends the
#: branch back to before the shot.
LANDING_WATCH = 3

