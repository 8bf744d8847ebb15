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
  or, on a smooth stretch, from the tangent of the last points (:meth:`_Context.column_rule`).
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
branch crosses: :func:`_turns`), through ``-1`` a period doubling, a complex pair a
Neimark-Sacker bifurcation. A change in the signature is a grazing, each
one between the two points located by bisection (with the bracket that holds it where the
bisection cannot close).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np

from .. import interrupts
from ..analysis.spectrum import dft_bin
from ..numeric.blas_threads import blas_threads_for
from .background import Locator, PendingPoint, resolve
from .field_path import AffineFieldPath
from .period_map import FlowError, PeriodMap, _copy, _key, kernel_mode, worker_count
from .self_overlap import SelfOverlap
from .shooting import (ShootingError, _n_coordinates, _orbit_samples, _same, _scale_of_excursions, _state_scale,
                       find_periodic_orbit)


@dataclass
class SpecialPoint:
    """A bifurcation found on a branch.

    Attributes
    ----------
    kind : str
        ``"fold"`` (a multiplier through ``+1`` where the branch turns back in the field),
        ``"branch-point"`` (one through ``+1`` where it goes on: another branch crosses it,
        :func:`branch_point_branch`), ``"period-doubling"``, ``"neimark-sacker"`` or ``"grazing"`` (the orbit's
        events change, which transitions or how many: a guard of the orbit touches zero), or
        ``"gap"``: no orbit was found between the branch point before and this one (``bracket``),
        where the step fell below ``ds_min``; the branch goes on from the first orbit that
        shooting at fixed values past the stall found from the last one (the integrator's
        discrete flow can lack orbits over a short stretch, which moves with the step: more
        steps a period may close it; the orbits either side may lie on different branches;
        ``multiplier`` is the largest of the orbit past it);
        ``"nonsmooth-fold"``: the branch turns back at a kink of the map (a grazing), its
        stability changing with no multiplier on the unit circle (one jumps across it);
        located only to within the last step across the kink; or ``"border-collision"``:
        the stability changes at a kink of the map where the branch goes on, a multiplier
        jumping across the unit circle (its modulus differs across a bracket a thousandth
        of the step about as much as across the step; ``multiplier`` is that one, past the
        kink); located to within that bracket (a tenth of the step where a trial beside the
        kink failed), or at the grazing found in it (to ``locate_tol``), then its kink.
    param : float
        The field's value there (located to ``locate_tol`` of the range).
    state : ndarray
        The orbit's section state there.
    multiplier : complex
        The multiplier that crossed the unit circle, at the located point; at a grazing
        point, the largest multiplier of the branch point before it (the map is not
        differentiable at the grazing).
    index : int
        The branch point after which it lies.
    mode : int or ndarray, optional
        The orbit's hybrid mode at the section (not kept in branch files).
    bracket : tuple of float, optional
        The field's values ``(lo, hi)`` between which the point lies, where its location
        ended wider than ``locate_tol``: a border collision's bracket, or a grazing whose
        bisection stopped because no orbit could be solved inside (the discrete flow sees
        a phase that appears only once it spans a step, and just past a grazing
        shooting then stalls: the Coulomb pair between 305.7811 and 305.7831 rad/s).
        ``param`` is then the best estimate inside it: the first orbit found past the
        change, or where that could not be solved to ``tol`` (in such a gap) the trial,
        solved only to tell its side, that lay past it. None where located to
        ``locate_tol``.
    """

    kind: str
    param: float
    state: np.ndarray
    multiplier: complex
    index: int
    mode: object = None
    bracket: tuple | None = None


@dataclass
class Branch:
    """A continued branch of periodic orbits.

    Attributes
    ----------
    field : str
        The continued config field.
    periods : int
    params : ndarray, shape (points,)
    states : ndarray, shape (points, states)
        Section states at ``t = 0``.
    multipliers : ndarray, shape (points, states), complex
        Floquet multipliers per point, largest modulus first.
    stable : ndarray of bool
    amplitudes : ndarray, shape (points, states)
        Half the peak-to-peak excursion of each state over the orbit.
    harmonics : ndarray, shape (points, states), complex
        First harmonic (of the excitation) of each state.
    events : ndarray of int
        Events per orbit (over ``periods`` excitation periods).
    residuals : ndarray, shape (points,)
        Each orbit's scaled residual ``max |P(y) - y| / scale`` in the mode it is recorded
        in (at most ``tol``; the scale is each state's excursion on the branch).
    sections : ndarray, shape (points, periods, states)
        The states at ``t = k T``, ``k = 0 .. periods - 1``: the orbit's Poincare samples
        (a period-2 orbit has two; a bifurcation diagram draws them all).
    special : list of SpecialPoint
    state_names : list of str
    message : str
        Why the continuation ended.
    integrations : int
        What the branch cost, after its first orbit: the integrations of the period map
        (each over ``periods`` excitation periods; residuals, difference quotients,
        trials that locate special points), counted whatever the machine's speed.
    replays : int
        The tangent replays of a kept run (variational equations and saltation matrices
        along the run's logged events, no integration of the flow).
    modes : ndarray of int, shape (points, width)
        Each orbit's hybrid mode at the section: one entry on the product-mode kernel,
        one per contact on the per-contact kernel (what a resumed continuation starts
        its first orbit in); ``-1`` where unknown (points from a file written before
        modes were kept).
    complete : bool
        False for a branch saved or returned before its continuation ended (a
        checkpoint, or after Ctrl-C): :func:`continuation` resumes it (``resume``).
    """

    field: str
    periods: int
    params: np.ndarray
    states: np.ndarray
    multipliers: np.ndarray
    stable: np.ndarray
    amplitudes: np.ndarray
    harmonics: np.ndarray
    events: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    residuals: np.ndarray = field(default_factory=lambda: np.zeros(0))
    sections: np.ndarray = field(default_factory=lambda: np.zeros((0, 1, 0)))
    special: list = field(default_factory=list)
    state_names: list = field(default_factory=list)
    message: str = ""
    integrations: int = 0
    replays: int = 0
    modes: np.ndarray = field(default_factory=lambda: np.zeros((0, 1), dtype=np.int64))
    complete: bool = True

    def points(self, kind: str) -> list:
        """The special points of one kind."""
        return [p for p in self.special if p.kind == kind]


class ContinuationInterrupted(KeyboardInterrupt):
    """Ctrl-C (or a signal raised as one) during a continuation; ``branch`` holds the points found.

    A :class:`KeyboardInterrupt`, so it stops a program as Ctrl-C does; the branch
    (``complete`` False) can be saved, drawn, or passed back as ``resume``.
    """

    def __init__(self, message: str, branch: Branch):
        super().__init__(message)
        self.branch = branch


class _Family:
    """Period maps of the config at any value of the field (integrators made on demand, a few kept).

    The field is set as ``--set`` does (:func:`~blademodel.config.apply_overrides`): a
    top-level field, a dotted path (``contacts.0.gap``), or in the components format
    a declared parameter by its bare name (``omega``).
    """

    def __init__(self, config, name: str, periods: int, settings: dict, start: float, jacobian: str = "auto",
                 bounds: tuple | None = None, workers: int | None = None):
        self.config, self.name, self.periods, self.settings = config, name, periods, settings
        self.jacobian = jacobian
        self.workers = worker_count(workers)
        try:
            self.config_at(start)
        except ValueError as e:
            raise ValueError(f"{type(config).__name__} has no field {name!r} to continue in, or {start!r} is not "
                             f"a value it takes: {e}") from None
        self._cache: dict = {}
        self._dropped = (0, 0)   # integrations and replays of the maps no longer kept
        self._first = None
        self.first_value = None   # the field's value the first integrator was built at
        self._bounds = (min(bounds), max(bounds)) if bounds is not None else None
        self._path: AffineFieldPath | None = None
        self._probed = False
        self.symmetry = None   # a tuned ring's CyclicSymmetry: the maps are then the reduced ones (.cyclic)

    def reduce_by(self, symmetry) -> None:
        """Make the maps from here on the ones reduced by a tuned ring's ``symmetry`` (:mod:`.cyclic`)."""
        self.symmetry = symmetry
        self._cache.clear()

    def config_at(self, value: float):
        from ..config import apply_overrides
        return apply_overrides(self.config, {self.name: float(value)}, source="continuation")

    def _values_at(self, value: float) -> tuple[np.ndarray, float | None]:
        """The raw parameters and excitation period of the model built at ``value`` (same structure as the first)."""
        from ..numeric.integrator import excitation_period
        model = self.config_at(value).build()
        if model.structure_key() != self._first.model.structure_key():
            raise ValueError(f"{self.name} = {value:g} changes the model's structure")
        try:
            period = excitation_period(model)
        except ValueError:
            period = None
        return np.array([model.parameters[k] for k in self._first.meta["params"]], dtype=float), period

    def path(self) -> AffineFieldPath | None:
        """The field's affine path over the range widened by a quarter each side (or the range itself), if any.

        Only for integrators that take parameter values directly
        (``with_parameter_values``), once the first one exists.
        """
        if not self._probed and self._first is not None and self._bounds is not None \
                and hasattr(self._first, "with_parameter_values"):
            self._probed = True
            lo, hi = self._bounds
            if hi > lo:
                wide = 0.25 * (hi - lo)
                self._path = (AffineFieldPath.probe(self._values_at, lo - wide, hi + wide)
                              or AffineFieldPath.probe(self._values_at, lo, hi))
        return self._path

    def parameter_direction(self, value: float, delta: float, names: list) -> tuple[np.ndarray, float]:
        """``d p / d lambda`` over the raw parameters ``names`` and ``d T / d lambda`` at ``value``.

        From the field's affine path where it has one (:mod:`.field_path`), else
        central differences of the built models' parameter values and excitation
        periods (no integration): a field enters the parameters through the config's
        own formulas, which are smooth (most are linear).
        """
        path = self.path()
        if path is not None and path.covers(value) and list(names) == list(self._first.meta["params"]):
            return path.derivative(value)
        from ..numeric.integrator import excitation_period
        out = []
        for v in (value + delta, value - delta):
            model = self.config_at(v).build()
            out.append((np.array([model.parameters[k] for k in names], dtype=float), excitation_period(model)))
        return (out[0][0] - out[1][0]) / (2 * delta), (out[0][1] - out[1][1]) / (2 * delta)

    def map_at(self, value: float) -> PeriodMap:
        """The period map at ``value`` (the first integrator's parameters changed, where the kernel allows)."""
        key = float(value)
        if key not in self._cache:
            if len(self._cache) > 8:
                old = self._cache.pop(next(iter(self._cache)))
                self._dropped = (self._dropped[0] + old.evaluations, self._dropped[1] + old.replays)
            # reduced, the map covers T / d; the orbits' period (self.periods) is the symmetry's
            self._cache[key] = PeriodMap(self._integrator_at(key), 1 if self.symmetry else self.periods,
                                         self.jacobian, self.workers, symmetry=self.symmetry)
        return self._cache[key]

    def state_names(self) -> list:
        """The names of the integrator's states (once a period map exists)."""
        return list(self._first.meta["state"])

    def twin(self) -> "_Family":
        """A family of its own period maps (and integrators, and work arrays) that gives the same maps to the bit:
        its first integrator is built at this one's first value, so that both move from it alike."""
        twin = _Family(self.config, self.name, self.periods, self.settings, self.first_value, self.jacobian,
                       bounds=self._bounds, workers=1)
        twin.reduce_by(self.symmetry)
        twin.map_at(self.first_value)
        return twin

    def work(self) -> tuple[int, int]:
        """The integrations and tangent replays of every period map made so far."""
        maps = self._cache.values()
        return (self._dropped[0] + sum(P.evaluations for P in maps),
                self._dropped[1] + sum(P.replays for P in maps))

    def _integrator_at(self, value: float):
        """An integrator at ``value``: the first one with the path's parameter values, its parameters taken from
        the model built at ``value``, or (another structure) a new one."""
        from ..numeric.integrator import StructureMismatch
        from ..numeric.kernels import make_integrator
        if self.symmetry is not None and self._first is not None:
            # moved from the reduced first integrator, the copies are reduced ones: the whole period's tables
            # (the forcing's phase table among them) are not packed for every value
            self._first = self.symmetry.reduced(self._first)
        path = self.path()
        if path is not None and path.covers(value):
            return self._first.with_parameter_values(*path.at(value))
        model = self.config_at(value).build()
        if self._first is not None:
            try:
                return self._first.with_parameters(model)
            except StructureMismatch:
                pass
        self._first = make_integrator(model, **self.settings)
        self.first_value = float(value)
        self._probed = False
        return self._first


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
        points it already has (a retrace, a closed branch): its ``message`` says which.
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
        point past it, with no trials (``docs/orbits.md``, *Continuation*).
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
    off = float(np.max(np.abs(r)))
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
    followed as by :func:`continuation`, in whichever direction of the field it goes,
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
        As for :func:`continuation`.
    point : SpecialPoint
        A ``"period-doubling"`` point of a branch of ``periods``-periodic orbits.
    start, stop : float
        The range of the field the new branch is followed in (it must contain the point).
    periods : int
        Period of the *old* branch; the new one has twice it.
    ds, ds_min, ds_max, max_points, tol, max_corrections, rel_step, locate_tol, grazing_tol : float
        As for :func:`continuation`; ``ds`` is also the switch's step along ``v``.
    steps_per_period, event_tol, method, kernel, jacobian, workers, progress, checkpoint, checkpoint_every
        As for :func:`continuation`.
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
        :func:`continuation` with ``periods`` twice the old branch's and ``start, stop``
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
    scale = _state_scale(_orbit_samples(ig, y, mode, periods)[1], _n_coordinates(ig))
    return fam, ig, y, mode, scale, (lo, hi)


def _first_end(ends: list):
    """``stop(pts)`` for :func:`_follow` that asks each of ``ends`` in turn (the first reason given ends the
    branch), or None where there are none."""
    if not ends:
        return None

    def stop(pts):
        return next((why for why in (end(pts) for end in ends) if why is not None), None)
    return stop


def _switched(ctx, point: SpecialPoint, y, mode, v, is_new, old: str, bounds, *, ds, **follow) -> Branch:
    """The branch that leaves the bifurcation ``point`` (orbit ``y`` in ``mode``) along the scaled state direction
    ``v``, followed by :func:`_run`; its first point is the bifurcation.

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
    X, T, A = ctx.rescale(_state_scale(pts[-1]["Y"], _n_coordinates(fam.map_at(point.param).integrator)),
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
    the branch is followed as by :func:`continuation`, in whichever direction of the field
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
        As for :func:`continuation`.
    point : SpecialPoint
        A ``"branch-point"`` point of a branch of ``periods``-periodic orbits.
    start, stop : float
        The range of the field the new branch is followed in (it must contain the point).
    periods : int
        Period of the branch (the new one has the same).
    ds, ds_min, ds_max, max_points, tol, max_corrections, rel_step, locate_tol, grazing_tol : float
        As for :func:`continuation`; ``ds`` is also the switch's step along ``v``.
    steps_per_period, event_tol, method, kernel, jacobian, workers, progress, checkpoint, checkpoint_every
        As for :func:`continuation`.
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
        Resumed, if unfinished, by :func:`continuation` with the same ``periods``, ``start``
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
        from .shooting import ShootingError, _shoot
        try:
            y_old, _ = _shoot(fam.map_at(X1[-1] * ctx.span), y.copy(), _copy(mode), scale, tol, max_corrections,
                              rel_step, [])
        except (ShootingError, FlowError, np.linalg.LinAlgError, ValueError):
            return True   # no orbit of the old branch there to come back to
        return float(np.max(np.abs(X1[:-1] * scale - y_old) / scale)) > 1e3 * tol

    ends = []
    if fam.symmetry is not None:   # followed on G^2: it ends where it comes back to the travelling waves
        from .cyclic import CyclicSymmetry
        ends.append(_back_to_the_waves(CyclicSymmetry(fam.config_at(point.param), ig), name))
    if crossed is not None:
        others = [q for q in crossed.points("branch-point") if q.param != point.param]
        if others:
            ends.append(_back_to(ctx, others, ds_max, "met the branch it crossed again at its branch point",
                                 "past it the crossing branch goes on beyond the branch it crossed"))
    b = _switched(ctx, point, y, mode, v, off_the_old_branch, "the branch it crosses", (lo, hi), ds=ds,
                  ds_min=ds_min, ds_max=ds_max, max_points=max_points, locate_tol=locate_tol, progress=progress,
                  checkpoint=checkpoint, checkpoint_every=checkpoint_every, stop=_first_end(ends))
    return replace(b, message=f"{b.message} ({whole})") if whole else b


def _landed_on(splitting, tol: float, name: str, periods: int):
    """``stop(pts)`` for :func:`_follow`, which ends a period-doubled branch whose newest orbit is one of period
    ``periods`` again (its ``splitting`` at most ``1e3 tol``): past a gap or a kink the corrections found the
    branch it left, traversed twice, and would follow it as if it were doubled (measured: the 96-blade ring's
    branch doubled at 273.89 rad/s, from 273.834 rad/s on, across a gap)."""
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
    """``stop(pts)`` for :func:`_follow`, which ends a switched branch at its point closest to one of the special
    points ``others`` of the branch it left (its other branch points or period doublings), where that point lies
    within ``reach`` of it (scaled unknowns: the state by ``ctx.scale``, the field by its span). The branch passes
    through such a point where it comes back there, so its closest point is at most about half a step away. The
    message says it ``met`` the point there, and what lies ``past`` it.

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


def _back_to_the_waves(sym, name: str):
    """For a crossing branch followed on ``G^2``: ``stop(pts)`` for :func:`_follow`, which ends it where it passes
    the travelling waves again.

    How an orbit breaks the travelling-wave symmetry is ``y - G(y)``, ``G(y) = S^s Phi(0
    -> tau)(y)`` read off its rebuilt period (no integration). Projected on its value at
    the branch's first point past the switch, it falls to zero where the crossing branch
    meets the travelling waves at another branch point, and changes sign past it, where
    the branch goes on as its own image under ``G`` (the blades' roles moved): there it ends.
    """
    def broken(q):
        Y = q["Y"]
        return q["state"][:sym.n] - sym.turned(Y[(Y.shape[0] - 1) // (sym.fraction * sym.periods)])

    first = []

    def stop(pts):
        if len(pts) < 3:
            return None
        if not first:
            first.append(broken(pts[1]))
        e0, e1 = (float(np.dot(broken(q), first[0])) for q in pts[-2:])
        if not (e0 > 0.0 >= e1):
            return None
        at = pts[-2]["param"] + e0 / (e0 - e1) * (pts[-1]["param"] - pts[-2]["param"])
        return (f"came back to the travelling waves near {name} = {at:.6g}, where they have another branch point "
                f"(past it the crossing branch goes on as its own image under the ring's turn)")
    return stop


def _reduced_crossing(fam, ig, point, y, mode, scale, rel_step, periods) -> tuple:
    """For :func:`branch_point_branch` with ``cyclic``: the direction (scaled, unit) along which the crossing
    branch leaves the branch point on ``G^2``, ``fam`` reduced by that symmetry from then on; or ``(None, why)``
    where the whole map must take it (``fam`` left as it is)."""
    from .cyclic import CyclicSymmetry
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
    from .cyclic import CyclicSymmetry
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
    from .cyclic import CyclicError
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
               sections=np.array([p["sections"] for p in pts]), special=list(special),
               state_names=fam.state_names()[:ctx.n], message=message, integrations=integrations,
               replays=replays, modes=np.array([_mode_row(p["mode"]) for p in pts]), complete=complete)
    if before is None:
        return b
    k = before.params.size - 1   # before's last point is this run's first
    if before.modes.shape != (k + 1, b.modes.shape[1]):   # unknown (a file written before modes were kept)
        before = replace(before, modes=np.full((k + 1, b.modes.shape[1]), -1, dtype=np.int64))
    return replace(b, **{f: np.concatenate([np.asarray(getattr(before, f))[:k], getattr(b, f)]) for f in _PER_POINT},
                   special=list(before.special) + [replace(q, index=q.index + k) for q in special],
                   integrations=before.integrations + integrations, replays=before.replays + replays)


#: The fields of :class:`Branch` that hold one entry per point.
_PER_POINT = ("params", "states", "multipliers", "stable", "amplitudes", "harmonics", "events", "residuals",
              "sections", "modes")


def _no_first_orbit(e: ShootingError, name: str, at: float, periods: int, transient: int,
                    guessed: bool) -> ShootingError:
    """The shooting error at a branch's first point, saying where it was and what may find an orbit there."""
    start = "from the guess" if guessed else f"after {transient} periods from rest"
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
    message = f"left [{lo:g}, {hi:g}] in {name}"
    jumped = ahead = switched = gap_tried = False
    shots = True        # fixed-value shots allowed (not on the retry of a step whose shot led onto a side arm)
    landing = None      # where the branch stood before its last fixed-value shot, while a reversal may undo it
    overlap = SelfOverlap(ctx.n)
    while earlier + len(pts) < max_points:
        X_pred, A_pred = ctx.predict(pts, X, T, A, h)
        X_new, m_new, A_new = ctx.correct(X_pred, T, m, A_pred, column=ctx.column_rule(pts))
        if X_new is not None and np.linalg.norm(X_new - X_pred) > ds_max and _passed(ctx, pts[:-2], X_new, h):
            # Newton's method wandered off and converged on the part of the branch already passed
            # (measured: from 261.45 rad/s, 35 steps away, onto the bilinear pair's branch at 266.15
            # rad/s, which the branch then went round again until max_points)
            ctx.why = "the correction converged back onto the branch already passed"
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
            X_new, m_new, A_new = _shoot_along_secant(ctx, trail, X, m)
            secant = X_new is not None
        arm = False
        if X_new is None and h / 2 < ds_min and jumped and not switched and pts[-1]["unstable"]:
            # even the jump failed, on an unstable arm: a turn reached from its unstable side (a
            # nonsmooth fold, where no orbit lies ahead); the stable arm that the turn leads back onto
            switched = True
            X_new, m_new, A_new = _other_arm(ctx, pts, X, m, ds_max)
            arm = X_new is not None
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
                message = _stalled(ds_min, name, X[-1] * span, ctx.why, fam.settings["steps_per_period"])
                break
            h /= 2
            continue
        iterations = ctx.iterations   # the point's own corrections (locating its bifurcations makes others)
        new = ctx.point(X_new, m_new, A_new)
        if new["residual"] > ctx.tol:
            # a correction that returned a state that is not an orbit in the mode it is recorded in
            # (a guard, not expected to fire: the correctors check the mode the orbit comes back to)
            ctx.why = f"the corrected point's residual {new['residual']:.3g} exceeds tol"
            h /= 2
            if h < ds_min:
                message = _stalled(ds_min, name, X[-1] * span, ctx.why, fam.settings["steps_per_period"])
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
        off_circle = any(_at_kink(q) for q in found)
        retry = any(_off_circle(q) for q in found)
        T_away = None   # past a kink the new point lies on another arm: onward on it is away from the kink
        if not retry and any(q.kind == "border-collision" for q in found):
            # a border collision is off the circle by nature: where the branch goes on through it (its new
            # tangent, oriented away from the kink, keeps the field's direction) it is kept; where it
            # turns back it is a nonsmooth fold, approached by shorter steps as before
            T_away = _away_from_kink(ctx, X_new, m_new, A_new, new["events"], X_new - X)
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
                _away_from_kink(ctx, X_new, m_new, A_new, new["events"], X_new - X)
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
            for q in special[landing["special"]:]:
                if isinstance(q, PendingPoint) and q.future is not None:
                    q.future.cancel()   # a location not yet begun in the locator's thread is not wanted
            del pts[landing["points"]:]
            overlap.truncate(len(pts))
            del special[landing["special"]:]
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
        ahead = False
        if off_circle and T_new[-1] * T[-1] < 0:
            found = [replace(q, kind="nonsmooth-fold") if _at_kink(q) else q for q in found]
        jumped = False
        if new["regular"]:
            # a turn further on may be reached from its unstable side too, and another gap may follow
            switched = gap_tried = False
        for q in found:
            if isinstance(q, PendingPoint):
                q.start()
        special += found
        pts.append(new)
        # each state scaled by its excursion on the newest orbit: amplitudes that grow a
        # hundredfold through a resonance do not shrink the steps a hundredfold
        taken = float(np.linalg.norm(X_new - X))
        X, T, A = ctx.rescale(_scale_of_excursions(new["magnitude"], n_q), X_new, T_new, A_new)
        new["X"], new["A"] = X, A
        m = m_new
        h = min(h * 1.5, ds_max) if iterations <= 4 else (h if iterations <= 8 else h / 2)
        if len(pts) > 1 and new["regular"]:
            h = _multiplier_step(h, taken, pts[-2]["mu"], new["mu"], ds_min)
        if progress is not None:
            progress(earlier + len(pts), X[-1] * span)
        lam = X[-1] * span
        if lam > hi + 1e-12 * span or lam < lo - 1e-12 * span:
            if bounds[1] in (lo, hi) and (lam > hi if bounds[1] == hi else lam < lo):
                message = f"reached {name} = {bounds[1]:g}"
            break
        on_itself = overlap.verdict(pts, np.append(ctx.scale, span), taken) if new["regular"] else None
        if on_itself is not None:
            message = _on_itself(*on_itself, name, pts, earlier)
            break
        why = stop(pts) if stop is not None and new["regular"] else None
        if why is not None:
            message = why
            break
    else:
        message = f"stopped after max_points = {max_points} points at {name} = {X[-1] * span:.6g}"
    return message


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
    unstable stretch between stable ends, which :meth:`_Context._window` misses: the point
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
    travel = X - ctx.unknowns(pts[-2])
    if not abs(travel[-1]) > 1e-3 * np.linalg.norm(travel):
        return None, mode, None
    if fractions is None:
        return _shoot_ahead(ctx, X, np.sign(travel[-1]), mode)
    return _shoot_ahead(ctx, X, np.sign(travel[-1]), mode, fractions=fractions)


def _passed(ctx, pts, X, reach) -> bool:
    """Whether ``X`` lies within ``reach`` of one of the branch points ``pts`` (in the current scaling)."""
    if not pts:
        return False
    P = np.array([ctx.unknowns(q) for q in pts])
    return bool(np.min(np.linalg.norm(P - X, axis=1)) <= reach)


#: How the message of a branch that stopped where its step fell below ``ds_min`` begins.
STALLED = "the step fell below ds_min"


def _stalled(ds_min, name, value, why, steps_per_period) -> str:
    """Why a branch stopped where its step fell below ``ds_min``, with what may get it through.

    The integrator's discrete flow can lack orbits over a short stretch of the field, and
    the stretch moves with the step: the bilinear 24-blade ring from 290.6 rad/s stops at
    290.847 rad/s at 1000 steps a period and at 290.839 at 500, and passes at 2000 (where a
    run from 290.8 to 290.95 stops at 290.936 instead); the Coulomb pair has such a gap at
    305.78 rad/s.
    """
    return (f"{STALLED} = {ds_min:g} at {name} = {value:.6g}: {why} (the integrator's discrete "
            f"flow may lack orbits over a short stretch, which moves with the step: more steps a period, "
            f"steps_per_period (--steps-per-period) {2 * steps_per_period} instead of {steps_per_period}, may get "
            f"through)")


def _away_from_kink(ctx, X_new, mode, A_new, events, step, first=1e-3, growth=4.0):
    """The tangent at ``X_new``, a point on an arm of the branch that starts at a kink of the map (the last
    ``step`` crossed it), oriented away from the kink.

    Orienting it away from the last point instead misleads where the step landed on the new
    arm nearer the kink than the last point was from it: an arm that folds back is then
    walked into the kink, turned at it onto the arm the step came from, and the branch
    retraced (measured on the Coulomb pair at its nonsmooth fold at 420.684 rad/s, reached
    by long steps: back down to where it started). The kink is where the orbit's events
    change: orbits are corrected at ``X_new`` plus and minus ``delta`` along the tangent, on
    the hyperplane normal to it, for ``delta`` from ``first`` of the step, growing by
    ``growth`` up to the step, until on exactly one side the orbit's events or mode differ
    from ``X_new``'s (or its correction fails): the kink is that way. Where both sides change
    at once, or neither within the step, the tangent oriented away from the last point.
    """
    reach = float(np.linalg.norm(step))
    t = _tangent(A_new, step)
    delta = first * reach
    while delta <= reach * (1.0 + 1e-12):
        changed = []
        for side in (1.0, -1.0):
            Xc, mc, _ = ctx.correct(X_new + side * delta * t, t, _copy(mode), A_new, jacobian=False)
            if Xc is None or ctx.events != events or _key(mc) != _key(mode):
                changed.append(side)
        if len(changed) == 1:
            return -changed[0] * t
        if changed:
            break
        delta *= growth
    return t


def _shoot_ahead(ctx, X, direction, mode, fractions=(1e-6, 1e-5, 1e-4, 1e-3), accept=None):
    """Shooting at the field's values a little past ``X`` (``direction`` +1 or -1 in the field), from its state:
    the first orbit that converges and that ``accept(X_new)`` takes (its unknowns, mode and Jacobian; ``ctx.events``
    holds its events when ``accept`` is called), else ``(None, mode, None)``. ``fractions`` are of the range (the
    field's scaled unit)."""
    for frac in fractions:
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
    mu, V = np.linalg.eig(last["J"])
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


def _turns(p, q, T_p=None) -> bool:
    """Whether the branch turns back in the field between its points ``p`` and ``q``: the field components of
    their tangents (``T_p``, where known, else from ``p``'s Jacobian) have opposite signs.

    A multiplier through ``+1`` is a **fold** where the branch turns, and a **branch
    point** where it goes on: another branch crosses it there (a tuned ring's
    travelling waves meet orbits that break their symmetry, the blades' amplitudes
    differing), and the map's Jacobian along the branch, ``[A; t]``, is singular without
    the field's component of ``t`` vanishing.
    """
    if T_p is None:
        T_p = _tangent(p["A"], np.append(np.zeros(p["A"].shape[0]), 1.0))
    T_q = _tangent(q["A"], T_p)
    return float(T_p[-1]) * float(T_q[-1]) < 0.0


def _chord(p, q) -> float:
    """The distance from ``p`` to ``q``."""
    d = q - p
    return math.sqrt(float(np.dot(d, d)))


def _end_tangent(points, chords=None):
    """The unit tangent at the last of ``points`` of the polynomial through them in their chord length (None where two
    coincide): the derivative of its Lagrange form there. ``chords``: the distances between successive points, where
    known (:func:`_chord`)."""
    if chords is None:
        chords = [_chord(p, q) for p, q in zip(points[:-1], points[1:])]
    s = [0.0]
    for c in chords:
        s.append(s[-1] + c)
    s = [v - s[-1] for v in s]
    if any(b <= a for a, b in zip(s[:-1], s[1:])):
        return None
    # the Lagrange basis' derivatives at the last point, s = 0: for the others only the product without (s - 0)
    # survives; the last one's is -sum(1 / s_j)
    weights = [math.prod(-v for k, v in enumerate(s[:-1]) if k != i)
               / math.prod(si - v for k, v in enumerate(s) if k != i) for i, si in enumerate(s[:-1])]
    weights.append(-sum(1.0 / v for v in s[:-1]))
    t = np.dot(weights, points)
    return t / math.sqrt(float(np.dot(t, t)))


def _tangent(A, previous):
    """The unit null vector of ``A`` (``n x (n + 1)``) pointing the way of ``previous``."""
    M = np.vstack([A, previous])
    rhs = np.zeros(A.shape[0] + 1)
    rhs[-1] = 1.0
    t = np.linalg.solve(M, rhs)
    t /= np.linalg.norm(t)
    return t if np.dot(t, previous) >= 0 else -t


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


#: :meth:`_Context.column_rule` takes a Jacobian's field column from the tangent of the branch's last points where
#: that tangent's estimated error, relative to its field component, is at most this (else a difference quotient).
COLUMN_ACCURACY = 1e-2
#: The most the leading Floquet multiplier's modulus may change from one branch point to the next, estimated from
#: the last step (:func:`_multiplier_step`): windows of instability narrower than a step are resolved.
MULTIPLIER_STEP = 0.1
#: How far past the last orbit (fractions of the range) a branch stalled at the shortest step shoots for an orbit
#: beyond a gap of the discrete flow (:func:`_shoot_along_secant`).
GAP_REACH = (3e-3, 1e-2, 3e-2)
#: Regular steps after a fixed-value shot during which a step that runs back in the field with no fold sends the
#: branch back to before the shot.
LANDING_WATCH = 3
#: Halvings of a correction step whose residual did not fall, before the step is taken as it is.
MAX_HALVINGS = 4
#: Corrections in a row that do not halve the best residual, after which a correction gives up.
STALL = 5
#: A trial of the grazing bisection is solved to this fraction of the bracket's width (scaled residual).
TRIAL_ACCURACY = 1e-4
#: A stability change is a border collision (a multiplier jumps across the unit circle at a kink of the map)
#: once its bracket has shrunk to JUMP_NARROWING of its first width (JUMP_NARROWING_FAILED where a trial
#: inside it failed, as trials beside a kink do) while the crossing multiplier's modulus still differs
#: between the ends by at least JUMP_KEPT of what it differed by at first: a modulus that is continuous
#: there would have closed that gap with the bracket.
JUMP_NARROWING = 1e-3
JUMP_NARROWING_FAILED = 1e-1
JUMP_KEPT = 0.5


class _Context:
    """Residuals, Jacobians, corrections and bifurcation tests in the scaled unknowns."""

    def __init__(self, fam: _Family, scale, span, tol, rel_step, max_corrections, grazing_tol=None):
        self.fam, self.scale, self.span = fam, scale, span
        self.tol, self.rel_step, self.max_corrections = tol, rel_step, max_corrections
        self.grazing_tol = grazing_tol   # grazing points' location tolerance (None: the bifurcations' locate_tol)
        self.locator: Locator | None = None   # where grazing points are located (set by _run for its branch)
        self.n = scale.size
        self.iterations = 0
        self._run = None   # the last residual's run (its events and signature: :attr:`events`, :attr:`signature`)
        self.why = ""

    @property
    def events(self) -> int:
        """The events of the orbit of the last residual's run (``-1`` before any)."""
        return -1 if self._run is None else self._run.events

    @property
    def signature(self) -> tuple | None:
        """The event signature (:meth:`~.period_map.MapRun.signature`) of the last residual's run."""
        return None if self._run is None else self._run.signature()

    def correct_at_value(self, X, mode, jacobian=True):
        """Shooting at the field's value of the prediction ``X`` (no arclength condition); ``(None, ..)`` on failure.

        Without ``jacobian`` the point's Jacobian is not taken (None), and ``self.events``
        holds its orbit's events.
        """
        from .shooting import ShootingError, _shoot
        lam = X[-1] * self.span
        try:
            P = self.fam.map_at(lam)
            y, mode = _shoot(P, X[:-1] * self.scale, _copy(mode), self.scale, self.tol, self.max_corrections,
                             self.rel_step, [])
        except (ShootingError, FlowError, np.linalg.LinAlgError, ValueError) as e:
            self.why = f"{self.why}; shooting at {self.fam.name} = {lam:.6g}: {e}"
            return None, mode, None
        Xc = np.append(y / self.scale, X[-1])
        self.iterations = self.max_corrections // 2
        if not jacobian:
            self.residual(Xc, mode)   # the orbit's events
            return Xc, mode, None
        A = self._jacobian_at(Xc, mode)
        return (Xc, mode, A) if A is not None else (None, mode, None)

    def _jacobian_at(self, X, mode, column=None):
        """:meth:`jacobian` at a corrected point, or None (with ``why``) where a perturbed integration fails."""
        try:
            return self.jacobian(X, mode, column)
        except (FlowError, ValueError) as e:
            self.why = f"the Jacobian at the corrected point: {e}"
            return None

    def twin(self) -> "_Context":
        """A context on period maps of its own (:meth:`_Family.twin`): for work in another thread."""
        return _Context(self.fam.twin(), self.scale.copy(), self.span, self.tol, self.rel_step, self.max_corrections,
                        self.grazing_tol)

    def rescale(self, scale, X, T, A):
        """``X``, the tangent ``T`` and the Jacobian ``A`` in the state scale ``scale`` (was ``self.scale``)."""
        n, r = self.n, self.scale / scale
        X, T, A = X.copy(), T.copy(), A.copy()
        X[:n] *= r
        T[:n] *= r
        T /= np.linalg.norm(T)
        A[:, :n] *= r[:, None] / r[None, :]
        A[:, n] *= r
        self.scale = scale.copy()
        return X, T, A

    def residual(self, X, mode):
        """``(P(y) - y) / scale`` and the mode the map ends in."""
        P = self.fam.map_at(X[-1] * self.span)
        y = X[:-1] * self.scale
        Py, mode_end = P(y, _copy(mode))
        self._run = P.last_run
        return (Py - y) / self.scale, mode_end

    def jacobian(self, X, mode, column=None):
        """``d residual / dX`` (``n x (n + 1)``): the tangent of the flow where it exists, else central differences.

        The state columns are the monodromy matrix (the tangent replays the run the
        residual at ``X`` already made); the field's column is a forward difference of
        the map, ``(P(y; lambda + delta) - P(y; lambda)) / delta`` with ``P(y; lambda)``
        from that same run: one integration, where the tangent's own parameter column,
        which follows the parameters and the moving period step by step, costs about
        seven. Its error, about ``delta`` relative, only slows the corrections by as
        much; the orbits are solved to ``tol`` whatever the column, and the multipliers
        come from the exact monodromy. ``column``, where given (:meth:`column_rule`), is
        asked first for the field's column from the state columns and may spare that
        integration.
        """
        n, d = self.n, self.rel_step
        lam = X[-1] * self.span
        P = self.fam.map_at(lam)
        y = X[:-1] * self.scale
        A = np.empty((n, n + 1))
        J = None
        if P.exact:
            s = P.try_derivatives(y, mode)
            if s is not None:
                J = s.monodromy
        if J is None:
            J = P.differences(y, mode, self.scale, d)
        A[:, :n] = (J - np.eye(n)) * self.scale[None, :] / self.scale[:, None]
        c = None if column is None else column(X, mode, A[:, :n])
        A[:, n] = c if c is not None else \
            (self.fam.map_at(lam + d * self.span).plain(y, mode) - P(y, mode)[0]) / self.scale / d
        return A

    def correct(self, X, T, mode, A=None, jacobian=True, tol=None, newton=True, column=None, quick=False):
        """Newton on the orbit and arclength conditions from the prediction ``X``; ``(None, ..)`` on failure.

        With ``A`` (the Jacobian at the last point) the first attempt is Broyden's
        method: that matrix, corrected by a rank-one update after every step, only
        residuals evaluated (the arclength row is exact and stays so); then Newton with
        the Jacobian taken afresh. The orbit must come back to the mode it starts in at the
        section: converged in another one, or failing where the flow from the
        prediction ends in another one (the section state crossed a switching boundary
        between the points), the correction is done again from that mode. Returns the
        point, its mode and its Jacobian (None without ``jacobian``: for a test that needs
        only the orbit's events, ``self.events``, which the last residual's run counted).
        ``tol`` replaces ``self.tol`` for this correction. Without ``newton`` (and with
        ``A``) only Broyden's method is tried, in each mode: a trial that may fail cheaply.
        ``column`` goes to :meth:`jacobian` for the converged point's Jacobian. A ``quick``
        correction (Broyden's method only) gives up at the first residual that does not fall,
        without the halvings that may rescue it: for trials that have others beside them.
        """
        tol = self.tol if tol is None else tol
        Xp = X.copy()
        self.why = ""
        if not newton and A is None:
            raise ValueError("a correction without Newton's method needs A, the matrix Broyden's method starts from")
        retry = not newton   # how a retry from another mode corrects: Broyden's method (True) or Newton's
        tries = ([(mode, True)] if A is not None else []) + ([(mode, False)] if newton else [])
        tried = set()
        while tries:
            mode, chord = tries.pop(0)
            tried.add((_key(mode), chord))
            Xc = Xp.copy()
            first_end = None
            try:
                G = np.vstack([A, T]) if chord else None
                X_old = F_old = None
                res_old = best = np.inf
                halvings = since_best = 0
                for it in range(2 * self.max_corrections if chord else self.max_corrections):
                    r, mode_end = self.residual(Xc, mode)
                    first_end = mode_end if first_end is None else first_end
                    res = float(np.max(np.abs(r)))
                    if res <= tol:
                        break
                    if res < 0.5 * best:
                        best, since_best = res, 0
                    else:
                        since_best += 1
                        if since_best > STALL:
                            raise FlowError(f"the corrections stalled at a residual of {best:.2g}")
                    if quick and res >= res_old:
                        raise FlowError(f"a quick trial's residual rose from {res_old:.2g} to {res:.2g}")
                    F = np.append(r, np.dot(T, Xc - Xp))
                    if chord and X_old is not None:   # Broyden: the secant condition along the step taken
                        step = Xc - X_old
                        G = G + np.outer(F - F_old - G @ step, step) / np.dot(step, step)
                    if res >= res_old and halvings < MAX_HALVINGS:
                        # no decrease (the step crossed a kink of the map, where an event appears or
                        # leaves, and undamped corrections cycle between its sides): back halfway
                        halvings += 1
                        Xc = X_old + 0.5 * (Xc - X_old)
                        continue
                    halvings = 0
                    if not chord:
                        G = np.vstack([self.jacobian(Xc, mode), T])
                    X_old, F_old, res_old = Xc, F, res
                    Xc = Xc + np.linalg.solve(G, -F)
                    if not (np.all(np.isfinite(Xc)) and np.linalg.norm(Xc - Xp) < 1.0):
                        raise FlowError("the correction diverged (moved by more than the orbit's excursion)")
                else:
                    raise FlowError(f"no convergence in {it + 1} corrections (residual {res:.2g})")
            except (FlowError, np.linalg.LinAlgError, ValueError) as e:   # ValueError: a field out of its range
                self.why = str(e)
                if first_end is not None and (_key(first_end), retry) not in tried and \
                        all(_key(first_end) != _key(m) for m, _ in tries):
                    tries.append((_copy(first_end), retry))
                continue
            self.iterations = it
            if _same(mode_end, mode):
                if not jacobian:
                    return Xc, mode, None
                A = self._jacobian_at(Xc, mode, column)
                if A is None:
                    continue
                return Xc, mode, A
            # converged, but to an orbit that comes back in another mode: solving again from the
            # same mode (Newton after Broyden) lands there too; that mode is the one to try
            tries = [(m, c) for m, c in tries if _key(m) != _key(mode)]
            if (_key(mode_end), retry) not in tried:
                tries.append((_copy(mode_end), retry))
            self.why = "the orbit's mode at the section keeps changing (it switches exactly there)"
        return None, mode, None

    def predict(self, pts, X, T, A, h):
        """The prediction a step ``h`` along the branch from ``X`` and the matrix Broyden's method starts from.

        On a smooth stretch (the last three points in one mode with the same number of
        events, the last two reached by regular steps), the quadratic
        through the three points in their arclength, for the unknowns and for the Jacobian
        alike: the corrections start about a hundred times closer than from the tangent
        step, and from a Jacobian close enough that one correction brings the residual from
        about ``1e-6`` to ``1e-11`` (measured on the bilinear pair at ``ds_max = 1/200``;
        extrapolated linearly from the last two, to about ``5e-10``, so that most points
        took a third residual). A cubic through four points predicts closer still, but
        at the default steps it made the Coulomb pair's branch zigzag across its fold at
        420.35 rad/s (207 folds), so it is not used. Elsewhere the tangent step and the
        last Jacobian.
        """
        if A is None or len(pts) < 3:
            return X + h * T, A
        a, b, c = pts[-3], pts[-2], pts[-1]
        if not (b.get("regular") and c.get("regular") and a["events"] == b["events"] == c["events"]
                and _key(a["mode"]) == _key(b["mode"]) == _key(c["mode"])):
            return X + h * T, A
        Xa, Xb = (self.unknowns(q) for q in (a, b))
        d0, d1 = float(np.linalg.norm(Xb - Xa)), float(np.linalg.norm(X - Xb))
        if not (d0 > 0 and d1 > 0):
            return X + h * T, A
        s0, s1 = -(d0 + d1), -d1       # arclength of a and b; X is at 0, the prediction at h
        La = (h - s1) * h / ((s0 - s1) * s0)
        Lb = (h - s0) * h / ((s1 - s0) * s1)
        Lc = (h - s0) * (h - s1) / (s0 * s1)
        Aa, Ab = (self._jacobian_of(q) for q in (a, b))
        return La * Xa + Lb * Xb + Lc * X, La * Aa + Lb * Ab + Lc * A

    def column_rule(self, pts):
        """The field's column of a new point's Jacobian from the branch's own points, or None.

        On a smooth stretch (the last three points in one mode and with one event
        signature, the last two reached by regular steps), where the new point keeps that
        mode and signature, the branch's tangent ``t`` at the new point is that of the cubic
        through the last three points and it, in their arclength, to third order in the
        step. Along the branch the residual stays zero, ``A_y t_y + a t_lambda = 0``, which
        gives the field's column ``a = -A_y t_y / t_lambda`` from the exact state columns
        ``A_y``, without the integration at a shifted value of the field that the difference
        quotient takes. The quadratic through the last two points and the new one (second
        order) estimates the error, as an embedded Runge-Kutta pair's lower order does: where
        ``|t_cubic - t_quadratic| / |t_lambda|`` exceeds :data:`COLUMN_ACCURACY` (a bent
        stretch, or near a fold, where the division magnifies the error) the rule returns
        None and the difference is taken. The column
        only starts Broyden's method at the next point and orients the next tangent: the
        orbits are solved to ``tol`` and the multipliers come from the exact monodromy
        whatever it is. Returns ``column(X, mode, A_y)``, the column at the corrected
        point ``X`` or None, for :meth:`jacobian`.
        """
        if len(pts) < 3:
            return None
        z, a, b = pts[-3], pts[-2], pts[-1]
        if not (a.get("regular") and b.get("regular") and z["signature"] == a["signature"] == b["signature"]
                and _key(z["mode"]) == _key(a["mode"]) == _key(b["mode"])):
            return None
        before = [self.unknowns(q) for q in (z, a, b)]
        chords = [_chord(p, q) for p, q in zip(before[:-1], before[1:])]

        def column(X, mode, A_y):
            if self.signature != b["signature"] or _key(mode) != _key(b["mode"]):
                return None
            last = chords + [_chord(before[-1], X)]
            t = _end_tangent(before[1:] + [X], last[1:])
            t_cubic = _end_tangent(before + [X], last)
            if t is None or t_cubic is None or \
                    np.linalg.norm(t_cubic - t) > COLUMN_ACCURACY * abs(t[-1]):
                return None
            return -(A_y @ t_cubic[:-1]) / t_cubic[-1]

        return column

    def unknowns(self, q):
        """The scaled unknowns ``X`` (state, then field) of the branch point ``q`` in the current state scale."""
        return np.append(q["state"] / self.scale, q["param"] / self.span)

    def _jacobian_of(self, q):
        """The scaled Jacobian of the branch point ``q`` in the current state scale."""
        n = self.n
        A = np.empty((n, n + 1))
        A[:, :n] = (q["J"] - np.eye(n)) * self.scale[None, :] / self.scale[:, None]
        A[:, n] = q["dl"] * self.span / self.scale
        return A

    def multipliers(self, A):
        """Floquet multipliers from the scaled Jacobian ``A``, largest modulus first."""
        return self._multipliers_of(self._physical(A))

    def _multipliers_of(self, J):
        """The orbit's Floquet multipliers from its map's Jacobian ``J`` (physical units), largest modulus first:
        ``J``'s eigenvalues, or with a cyclic reduction those of the whole period's monodromy it gives."""
        sym = self.fam.symmetry
        return _largest_first(np.linalg.eigvals(J if sym is None else sym.monodromy(J)))

    def _physical(self, A):
        """The monodromy matrix in physical units from the scaled Jacobian ``A``."""
        n = self.n
        return A[:, :n] * self.scale[:, None] / self.scale[None, :] + np.eye(n)

    def point(self, X, mode, A):
        """The branch point's record from its scaled unknowns and Jacobian."""
        n = self.n
        J = self._physical(A)   # kept in physical units: the scale changes from point to point
        mu = self._multipliers_of(J)
        lam = X[-1] * self.span
        P = self.fam.map_at(lam)
        y = X[:-1] * self.scale
        r = P.run(y, mode)
        Y = r.period_orbit()
        residual = float(np.max(np.abs(r.end[:self.n] - y) / self.scale))
        top, bottom = Y.max(axis=0), Y.min(axis=0)
        amp = 0.5 * (top - bottom)
        c = dft_bin(Y[:-1], self.fam.periods) * 2.0 / (Y.shape[0] - 1)
        S = (Y.shape[0] - 1) // self.fam.periods
        return {"param": lam, "state": y, "sections": Y[:-1:S].copy(), "mu": mu, "stable": bool(np.max(np.abs(mu)) < 1.0), "amp": amp,
                "h1": c, "unstable": _unstable_count(mu), "X": X.copy(), "mode": _copy(mode), "A": A, "Y": Y,
                "events": r.events, "signature": r.signature(), "regular": True, "residual": residual,
                "magnitude": np.maximum(top, -bottom),   # each state's largest |value| on the orbit
                "J": J, "dl": A[:, n] * self.scale / self.span}

    def detect(self, a, b, Xa, Ta, mode, index, locate_tol, before=None):
        """The bifurcations between consecutive points ``a`` and ``b``, each located on the arclength.

        A change in the number of multipliers outside the unit circle (fold, branch point,
        period doubling, Neimark-Sacker: :meth:`_locate_crossing`), and a change in the orbit's
        events (which transitions it crosses, counted: its signature,
        :meth:`~.period_map.MapRun.signature`): a guard of the orbit touches zero there (a
        contact that grazes, a slip that comes to rest: **grazing**, including the end of
        continuous sliding; every one between the two points, :meth:`_locate_grazings`).
        Not the number of events alone: where one phase appears and another vanishes
        within a step the number stays (the Coulomb pair from 314.02 to 314.21 rad/s at
        ``ds_max = 0.02``: 15 events, a stick phase appearing at 314.137 and a short slip
        before the contact opens vanishing at 314.182).

        Where ``a`` and ``b`` have the same count, a multiplier may still have crossed the
        circle and come back within the step (:meth:`_window`, from ``before``, the point
        before ``a``); both crossings are then located.
        """
        found = []
        bracket = None
        pairs = [(a, b, Xa)]
        if before is not None and a["unstable"] == b["unstable"]:
            m = self._window(before, a, b, Xa, mode)
            if m is not None:
                pairs = [(a, m, Xa), (m, b, m["X"])]
        for p, q, Xp in pairs:
            if p["unstable"] == q["unstable"]:
                continue
            best, jump = self._locate_crossing(p, q, Xp, Ta, mode, locate_tol)
            mu = best["mu"][np.argmin(np.abs(np.abs(best["mu"]) - 1.0))]
            if jump is not None:
                kind = "border-collision"   # with the multiplier that jumped across the circle
                mu = _crossing_multiplier(best["mu"], min(p["unstable"], q["unstable"]))
                bracket = jump
            elif abs(mu.imag) > 1e-6 * abs(mu):
                kind = "neimark-sacker"
            elif mu.real < 0:
                kind = "period-doubling"
            else:
                kind = "fold" if _turns(p, q, Ta if p is a else None) else "branch-point"
            found.append(_special(kind, best, index, mu, jump))
        if a["signature"] != b["signature"]:
            # the largest multiplier of the point before: at the grazing the map is not differentiable, and
            # difference quotients there straddle the kink (measured on 4- to 12-blade rings: 2e4 to 2.4e5 between
            # points at about 0.62)
            tol = locate_tol if self.grazing_tol is None else self.grazing_tol
            multiplier = a["mu"][0]

            def finish(at):
                return _special("grazing", at, index, multiplier)
            # located later, elsewhere (.background): on what the step has now (the points' dicts are
            # rescaled later, their arrays never changed in place); a border collision whose bracket holds
            # the grazing is placed there (background.resolve): that is its kink
            args = (self.scale.copy(), dict(a), dict(b), Xa.copy(), Ta, _copy(mode), tol)
            found.append(PendingPoint(lambda ctx: _locate_grazings_in(ctx, *args), self.locator, finish, index,
                                      bracket, unlocated=_unlocated(b, _field_bracket(Xa, b["X"], self.span))))
        return found

    def _window(self, before, a, b, Xa, mode):
        """A point between ``a`` and ``b`` (which have the same number of multipliers outside the unit circle)
        where that number differs, or None.

        A step can jump a window of stability or instability whose two ends it does not
        resolve (the bilinear pair at ``ds_max = 0.2``: unstable at 416.73 and 417.98 rad/s,
        its period-doubling multiplier 1.0003 and 1.0099 in modulus there, and stable between
        the period doublings at 416.73 and 417.80). The moduli of the multipliers on either
        side of the circle (the last outside and the first inside, largest first) are
        interpolated by the parabola through ``before``, ``a`` and ``b`` in their arclength;
        where it crosses the circle and comes back between ``a`` and ``b``, the point at its
        extremum is corrected (on the hyperplane normal to the chord), and returned where its
        count differs. One correction where the parabola says so, none elsewhere.
        """
        u = a["unstable"]
        Xb = b["X"]
        d0 = d1 = None
        for j in (u - 1, u):
            if j < 0 or j >= a["mu"].size:
                continue
            g0, g1, g2 = (float(abs(q["mu"][j])) - 1.0 for q in (before, a, b))
            if not (min(g0, g1, g2) > 0.0 or max(g0, g1, g2) < 0.0):
                continue
            if d0 is None:   # (in floats: this runs at every step, numpy's polyfit cost a tenth of the branch)
                X0 = self.unknowns(before)
                d0, d1 = float(np.linalg.norm(Xa - X0)), float(np.linalg.norm(Xb - Xa))
            if not (d0 > 0.0 and d1 > 0.0):
                return None
            # the parabola through (-d0, g0), (0, g1), (d1, g2) in Newton's form, and its extremum
            f01, f12 = (g1 - g0) / d0, (g2 - g1) / d1
            c2 = (f12 - f01) / (d0 + d1)
            if c2 == 0.0:
                continue
            at = 0.5 * (-f01 / c2 - d0)
            if not 0.0 < at < d1 or (g0 + f01 * (at + d0) + c2 * (at + d0) * at > 0.0) == (g1 > 0.0):
                continue
            Xm, mm, Am = self._corrected(Xa, Xb, at / d1, mode, a["A"] if at <= 0.5 * d1 else b["A"], True)
            if Xm is not None and _unstable_count(self.multipliers(Am)) != u:
                return self.point(Xm, mm, Am)
        return None

    def _corrected(self, X_lo, X_hi, theta, mode, A, jacobian, tol=None, at_value=False, newton=True, step=None,
                   quick=False):
        """The branch point between two of its points ``X_lo``, ``X_hi``, a fraction ``theta`` of the way.

        Predicted on the chord between them and corrected with ``A`` as Broyden's first
        matrix and ``tol`` for :meth:`correct`: on the hyperplane normal to the chord, or
        with ``at_value`` at the predicted value of the field if the ends have different
        values. A trial near a grazing point sits on a kink of the branch, where the map's
        difference in the field straddles the event that appears: the field's column of
        the Jacobian is then wrong and Newton on the arclength system cycles, while
        shooting at a fixed value never uses it (the branch may be all but vertical there:
        measured, ends ``2.7e-4`` apart in the scaled states and ``2e-7`` in the field).
        Around a fold the field does not move monotonically between the ends, so the
        hyperplane is needed there. A point corrected farther from either end than they
        are from each other has left the bracket and is refused, unless (with ``step``,
        the ends of the continuation step the bracket lies in) it was solved at a fixed
        value and lies within the step's length of one of its ends: where the branch bows
        between the ends of a bracket its points there lie farther from them than they
        from each other (the Coulomb pair between 224.23 and 224.60 rad/s, where the
        friction states rise and fall again), and refusing them stopped the grazing's
        location with a bracket 0.09 to 0.28 rad/s wide. ``(X, mode, A)``, or ``X`` None.
        """
        width = np.linalg.norm(X_hi - X_lo)
        Xp = X_lo + theta * (X_hi - X_lo)
        normal = (X_hi - X_lo) / width
        fixed = at_value and abs(X_hi[-1] - X_lo[-1]) > 1e-12 * max(abs(X_hi[-1]), abs(X_lo[-1]))
        if fixed:
            normal = np.zeros_like(normal)
            normal[-1] = 1.0
        Xm, mm, Am = self.correct(Xp, normal, mode, A, jacobian=jacobian, tol=tol, newton=newton, quick=quick)
        if Xm is None and not fixed and newton:
            Xm, mm, Am = self.correct_at_value(Xp, mode, jacobian=jacobian)
        if Xm is not None and not (_between(Xm, X_lo, X_hi) or (fixed and step is not None and _near(Xm, *step))):
            # corrected away from the bracket (a kink of the map, a fold of the branch across
            # the chord's hyperplane): the location stops at the bracket it has
            self.why = "a correction inside the bracket left it"
            return None, mm, None
        return Xm, mm, Am

    def _locate_crossing(self, a, b, Xa, Ta, mode, locate_tol):
        """The first point past a change of the number of unstable multipliers from ``a`` to ``b``.

        The test function is ``|mu| - 1`` of the multiplier nearest the unit circle, smooth
        along the branch: regula falsi with the Illinois modification between the
        bracket's two corrected points, each trial kept at least half ``locate_tol`` inside
        it, so the bracket closes to ``locate_tol`` of arclength in a few corrected points
        where bisection took about twenty; which side a trial lies on is decided by its
        count of unstable multipliers.

        Returns the point and, for a **border collision**, the field's values at the
        bracket's ends (else None). A border collision is found where the bracket shrank
        to ``JUMP_NARROWING`` of its first width (``JUMP_NARROWING_FAILED`` if a trial
        failed) while the modulus of the crossing multiplier (the one whose count changes)
        still differs between its ends by ``JUMP_KEPT`` of its first difference: a
        multiplier jumps across the circle at a kink of the map (a grazing where the
        orbit's event sequence changes). There the location stops: regula falsi would
        close such a bracket only linearly, with trials ever nearer the kink, where
        corrections struggle (measured on the 24-blade ring at 274.2262 rad/s: 0.875 on one
        side, 1.04 to 1.08 on the other, 31 trials; or 0.991 and 1.16 across a second kink
        1e-5 rad/s above the first, seven location sequences ended by failed trials).
        """
        def test(mu):
            return float(np.abs(mu[np.argmin(np.abs(np.abs(mu) - 1.0))]) - 1.0)

        k = min(a["unstable"], b["unstable"])

        def crossing(mu):
            return float(abs(_crossing_multiplier(mu, k)))

        X_lo, X_hi = Xa, b["X"]
        A_lo, A_hi = a["A"], b["A"]
        f_lo, f_hi = test(a["mu"]), test(b["mu"])
        c_lo, c_hi = crossing(a["mu"]), crossing(b["mu"])
        first, first_gap = float(np.linalg.norm(X_hi - X_lo)), abs(c_hi - c_lo)
        best = b
        last = 0
        jump = False

        def jumped(width, narrowing):
            return width <= narrowing * first and abs(c_hi - c_lo) >= JUMP_KEPT * first_gap > 0.0

        for _ in range(100):
            width = float(np.linalg.norm(X_hi - X_lo))
            if width <= locate_tol:
                break
            if jumped(width, JUMP_NARROWING):
                jump = True
                break
            theta = 0.5
            if f_lo * f_hi < 0.0:
                theta = f_lo / (f_lo - f_hi)
            margin = min(0.5 * locate_tol / width, 0.5)
            theta = min(max(theta, margin), 1.0 - margin)
            Xm, mm, Am = self._corrected(X_lo, X_hi, theta, mode, A_lo if theta <= 0.5 else A_hi, True)
            if Xm is None:
                jump = jumped(width, JUMP_NARROWING_FAILED)
                break
            mu = self.multipliers(Am)
            f = test(mu)
            if _unstable_count(mu) == a["unstable"]:
                X_lo, A_lo, f_lo, c_lo = Xm, Am, f, crossing(mu)
                if last < 0:
                    f_hi *= 0.5
                last = -1
            else:
                X_hi, A_hi, f_hi, c_hi = Xm, Am, f, crossing(mu)
                best = (Xm, mm, Am)
                if last > 0:
                    f_lo *= 0.5
                last = 1
        bracket = (X_lo[-1] * self.span, X_hi[-1] * self.span) if jump else None
        return (self.point(*best) if isinstance(best, tuple) else best), bracket

    def _locate_grazing(self, a, b, Xa, Ta, mode, locate_tol, step=None, near=False):
        """The first point past a change of the orbit's events (its signature) from ``a``'s, toward ``b``, by
        bisection.

        The signature has no smooth test function, so the bracket is halved; each trial needs
        only its orbit's events (no Jacobian, no multipliers), and its prediction, halfway
        between the bracket's corrected ends, comes ever closer to the branch. Trials are
        solved at a fixed value of the field (where the ends' values differ). The bracket
        is closed when it is ``locate_tol`` wide in the scaled unknowns, or in the field
        alone once a halving no longer shrinks it by a quarter: an arm of the branch may
        end at the grazing (a small hysteresis loop whose arms end where their guards
        touch zero: the bilinear pair at 313.1142 rad/s, where orbits with 20 and 22
        events coexist over 1e-4 rad/s), and then the state across the bracket does not
        close at all. A trial only has to tell on which side of the grazing point it
        lies, so it is solved to :data:`TRIAL_ACCURACY` of the bracket's width (never
        looser than the branch's ``tol`` needs less): where the bracket is wide, one or
        two corrections, by Broyden's method alone, from the Jacobian of the end nearer
        the trial (``a``'s up to the bracket's middle, ``b``'s past it); a trial that
        fails is tried beside. The located point is solved to ``tol``; it gets no
        Jacobian (the map has a kink there). Returns the located point's field value,
        state, mode, scaled unknowns ``X``, signature and ``bracket``: None where the
        bisection closed, else the field's values across the last bracket, where no trial
        inside it could be solved (:class:`SpecialPoint`); the first point past the change
        found (``b`` if none was). With ``near`` the change is looked for near ``Xa`` first:
        trials at twice ``locate_tol`` from it, then four times as far each, until one lies
        past the change or halfway across the bracket; then the bisection.
        """
        X_lo, X_hi = Xa, b["X"]
        step = (Xa, b["X"]) if step is None else step
        best = None
        previous = np.inf
        closed = False
        reach = 2.0 * locate_tol if near else np.inf   # the first trials' distance from X_lo, growing fourfold
        X_before = None   # the lower end before X_lo: their secant predicts where the chord to X_hi does not
        while True:
            width = float(np.linalg.norm(X_hi - X_lo))
            if width <= locate_tol or (abs(X_hi[-1] - X_lo[-1]) <= locate_tol and width > 0.75 * previous):
                closed = True   # closed, or closed in the field while the state across it no longer closes
                break
            previous = width
            trial_tol = max(self.tol, TRIAL_ACCURACY * width)
            if reach < 0.5 * width:
                Xm, mm, _ = self._corrected(X_lo, X_hi, reach / width, mode, a["A"], False, trial_tol, at_value=True,
                                            newton=False, step=step)
                if Xm is None:
                    Xm, mm = self._along_secant(X_before, X_lo, X_hi, reach / width, mode, a["A"], trial_tol, step)
                if Xm is not None and self.signature == a["signature"]:
                    X_before, X_lo, reach = X_lo, Xm, 4.0 * reach
                    continue
                reach = np.inf
                if Xm is not None:
                    X_hi, best = Xm, (Xm, mm, self.signature)
                    continue
            for theta in (0.5, 0.25, 0.75):   # a trial right at the grazing point can stall: one beside it
                Xm, mm, _ = self._corrected(X_lo, X_hi, theta, mode, a["A"] if theta <= 0.5 else b["A"], False,
                                            trial_tol, at_value=True, newton=False, step=step, quick=True)
                if Xm is not None:
                    break
            if Xm is None:
                Xm, mm = self._along_secant(X_before, X_lo, X_hi, 0.5, mode, a["A"], trial_tol, step)
            if Xm is None:   # Broyden's method from the ends' Jacobians failed: Newton's, once
                Xm, mm, _ = self._corrected(X_lo, X_hi, 0.5, mode, a["A"], False, trial_tol, at_value=True,
                                            step=step)
            if Xm is None:
                break
            if self.signature == a["signature"]:
                X_before, X_lo = X_lo, Xm
            else:
                X_hi, best = Xm, (Xm, mm, self.signature)
        bracket = None if closed else _field_bracket(X_lo, X_hi, self.span)
        if best is not None:
            Xt, mt, signature = best
            r, _ = self.residual(Xt, mt)
            Xb, mb = Xt, mt
            if float(np.max(np.abs(r))) > self.tol:
                d = X_hi - X_lo
                Xb, mb, _ = self.correct(Xt, d / np.linalg.norm(d), mt, a["A"], jacobian=False)
            if Xb is not None:
                signature = self.signature
                if bracket is not None:   # (solved to tol, the point may have moved just out of it: by 2e-10 rad/s)
                    value = float(Xb[-1] * self.span)
                    bracket = (min(bracket[0], value), max(bracket[1], value))
            else:
                # the trial, solved only to tell its side, is no orbit to tol: it may lie where none is (a gap of
                # the discrete flow, from 305.7811 to 305.7831 rad/s on the Coulomb pair, where trials solved to
                # 1e-6 were found). It stands as the estimate; the first orbit past the change is only known to
                # lie before b
                Xb, mb = Xt, mt
                bracket = _field_bracket(X_lo, b["X"], self.span)
            # no Jacobian: the map is not differentiable here, and the special point takes the multiplier
            # of the point before (detect)
            return {"param": Xb[-1] * self.span, "state": Xb[:-1] * self.scale, "mode": _copy(mb), "X": Xb,
                    "signature": signature, "bracket": bracket}
        return b if bracket is None else _unlocated(b, bracket)

    def _along_secant(self, X_before, X_lo, X_hi, theta, mode, A, tol, step):
        """A trial a fraction ``theta`` of the way from ``X_lo`` to ``X_hi`` in the field, its state predicted on the
        secant through ``X_before`` and ``X_lo`` (not on the chord to ``X_hi``) and solved at that value of the field
        by Broyden's method from ``A``: ``(X, mode)``, or ``(None, mode)``.

        Where the branch bends between a bracket's ends the chord's prediction lies far from
        it and the corrections stall (the Coulomb pair from 201.14 to 202.17 rad/s, a
        second grazing point's bracket: residuals of 0.016 to 0.048 at the chord's trials,
        Newton's method 1.2e-4), while the lower end's last two points lie on the branch.
        """
        if X_before is None or X_lo[-1] == X_before[-1]:
            return None, mode
        lam = X_lo[-1] + theta * (X_hi[-1] - X_lo[-1])
        Xp = X_lo + (lam - X_lo[-1]) / (X_lo[-1] - X_before[-1]) * (X_lo - X_before)
        Xp[-1] = lam
        normal = np.zeros_like(Xp)
        normal[-1] = 1.0
        Xm, mm, _ = self.correct(Xp, normal, mode, A, jacobian=False, tol=tol, newton=False)
        if Xm is None or not _near(Xm, *step):
            return None, mm
        return Xm, mm

    def _locate_grazings(self, a, b, Xa, Ta, mode, locate_tol, most=16):
        """Every grazing point between consecutive points ``a`` and ``b`` (whose signatures differ), in order.

        :meth:`_locate_grazing` finds the first past ``a``; where the orbit just past it
        does not yet have ``b``'s signature, another grazing lies between it and ``b``,
        located the same way from it (its trials start from ``a``'s Jacobian), and so on,
        up to ``most``: a step long enough to cross several (the Coulomb pair from 159.71
        to 160.37 rad/s at ``ds_max = 0.3``: 12 events, then 16) reports each, as shorter
        steps, which cross them one at a time, do. The next change is looked for near the
        last first (``near``): on a tuned ring the contacts that graze together change the
        orbit's events in stages a few ``locate_tol`` apart (the 24-blade ring at
        277.40165527, 277.40166105 and 277.40166913 rad/s), each of which a bisection
        across the rest of the step took about 19 trials to find. Two changes found within
        twice ``locate_tol`` of each other are one grazing point (each is located only to
        ``locate_tol``: the Coulomb pair at 183.745228 rad/s, 15 events, then 16 over
        2e-6 rad/s, then 13). Where a location finds no orbit past the change (or an
        integration in it fails) the list ends with ``b``'s orbit, the first branch point
        past that grazing, with the bracket that holds it.
        """
        found = []
        lo, X_lo = a, Xa
        for _ in range(most):
            try:
                at = self._locate_grazing(lo, b, X_lo, Ta, mode, locate_tol, step=(Xa, b["X"]), near=bool(found))
            except (FlowError, np.linalg.LinAlgError, ValueError):
                # an integration of the location failed: a grazing point's place is not worth the branch
                at = _unlocated(b, _field_bracket(X_lo, b["X"], self.span))
            at_b = at["X"] is b["X"]
            if not at_b and at["signature"] == lo["signature"]:
                break   # solved to tol, the point past the grazing fell back before it: that one is known
            if not (found and not at_b and np.linalg.norm(at["X"] - X_lo) <= 2.0 * locate_tol):
                found.append(at)   # (two changes closer than their locations' tolerance are one grazing point)
            if at_b or at["signature"] == b["signature"] or not _between(at["X"], X_lo, b["X"]):
                break
            lo = {"X": at["X"], "A": a["A"], "signature": at["signature"]}
            X_lo, mode = at["X"], at["mode"]
        return found


def _locate_grazings_in(ctx: _Context, scale, a, b, Xa, Ta, mode, tol):
    """:meth:`_Context._locate_grazings` in ``ctx`` (the locator's), in the scale of the step that found them."""
    ctx.scale = scale
    return ctx._locate_grazings(a, b, Xa, Ta, mode, tol)


def _field_bracket(X_lo, X_hi, span) -> tuple:
    """The field's values at two scaled points, lower first."""
    lo, hi = sorted((float(X_lo[-1] * span), float(X_hi[-1] * span)))
    return lo, hi


def _unlocated(b: dict, bracket) -> dict:
    """A grazing point left at the branch point ``b`` past it, known to lie in the field's ``bracket``."""
    return {"param": b["param"], "state": b["state"], "mode": b["mode"], "X": b["X"], "signature": b["signature"],
            "bracket": bracket}


def _special(kind: str, point: dict, index: int, multiplier=None, bracket=None) -> SpecialPoint:
    """A special point at the branch point ``point`` (``multiplier``: by default its largest; ``bracket``: by
    default the point's own, if it has one)."""
    mu = point["mu"][0] if multiplier is None else multiplier
    bracket = point.get("bracket") if bracket is None else bracket
    return SpecialPoint(kind=kind, param=point["param"], state=point["state"], multiplier=complex(mu), index=index,
                        mode=_copy(point["mode"]), bracket=None if bracket is None else tuple(map(float, bracket)))


def _off_circle(p: SpecialPoint) -> bool:
    """A fold, branch point, period doubling or Neimark-Sacker point whose critical multiplier is not on the unit
    circle."""
    return p.kind not in ("grazing", "border-collision", "gap") and abs(abs(p.multiplier) - 1.0) > 0.05


def _at_kink(p) -> bool:
    """A change of stability with no multiplier on the unit circle: off it (:func:`_off_circle`), or a border
    collision (a multiplier jumping across it)."""
    return _off_circle(p) or p.kind == "border-collision"


def _between(X, X_lo, X_hi) -> bool:
    """Whether ``X`` lies strictly between two points: nearer to each than they are to each other."""
    width = np.linalg.norm(X_hi - X_lo)
    d_lo, d_hi = np.linalg.norm(X - X_lo), np.linalg.norm(X - X_hi)
    return bool(min(d_lo, d_hi) > 1e-6 * width and max(d_lo, d_hi) < width)


def _near(X, X_a, X_b) -> bool:
    """Whether ``X`` lies within a step's length of either end of the step from ``X_a`` to ``X_b``."""
    reach = np.linalg.norm(X_b - X_a)
    return bool(min(np.linalg.norm(X - X_a), np.linalg.norm(X - X_b)) <= reach)


def _crossing_multiplier(mu, k: int) -> complex:
    """The multiplier whose count outside the unit circle changes between ``k`` and ``k + 1``: the ``k + 1``-th
    largest in modulus."""
    return mu[np.argsort(-np.abs(mu), kind="stable")[k]]


def _largest_first(mu):
    """Multipliers sorted by modulus, largest first (ties in their order)."""
    return mu[np.argsort(-np.abs(mu), kind="stable")]


def _unstable_count(mu) -> int:
    return int(np.sum(np.abs(mu) > 1.0))

