"""Pseudo-arclength continuation of periodic orbits in a config field, with their bifurcations.

A branch of period-``n`` orbits is the curve ``P(y; lambda) = y`` in the space of the
section state ``y`` and one config field ``lambda`` (the excitation frequency for a
forced-response curve, ``gamma``, ``F0``, the gap ...). It is followed by
pseudo-arclength continuation: a step ``ds`` along the tangent, then Newton's method on
the orbit condition plus the arclength condition, so the branch is followed around
folds. Both the state and the field are scaled (each state by its excursion on the
first orbit, the field by the continuation range), the Jacobians are central
the tangent of the period map (:class:`~blademodel.orbits.period_map.PeriodMap`:
variational equations with saltation matrices, the field's column along the raw
parameters' direction ``d p / d lambda``) where the kernel has one, else its central
differences (the field's column from maps built at ``lambda +- delta``), and the step
grows after easy corrections and is halved after hard or failed ones.

Each point carries its Floquet multipliers. A change in the number of multipliers
outside the unit circle between two points is a bifurcation, located by bisection on
the arclength and classified by the multiplier that crossed: through ``+1`` a fold
(the field's tangent component changes sign there too), through ``-1`` a period
doubling, a complex pair a Neimark-Sacker bifurcation.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..numeric.contract import C_EVENTS, N_COUNTERS
from .period_map import FlowError, PeriodMap, _copy
from .shooting import _n_coordinates, _orbit_samples, _same, _state_scale, find_periodic_orbit


@dataclass
class SpecialPoint:
    """A bifurcation found on a branch.

    Attributes
    ----------
    kind : str
        ``"fold"``, ``"period-doubling"``, ``"neimark-sacker"`` or ``"grazing"`` (the number
        of events per orbit changes: a guard of the orbit touches zero).
    param : float
        The field's value there (located to ``locate_tol`` of the range).
    state : ndarray
        The orbit's section state there.
    multiplier : complex
        The multiplier that crossed the unit circle, at the located point (at a
        grazing point, the largest one).
    index : int
        The branch point after which it lies.
    mode : int or ndarray, optional
        The orbit's hybrid mode at the section (not kept in branch files).
    """

    kind: str
    param: float
    state: np.ndarray
    multiplier: complex
    index: int
    mode: object = None


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
    sections : ndarray, shape (points, periods, states)
        The states at ``t = k T``, ``k = 0 .. periods - 1``: the orbit's Poincare samples
        (a period-2 orbit has two; a bifurcation diagram draws them all).
    special : list of SpecialPoint
    state_names : list of str
    message : str
        Why the continuation ended.
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
    sections: np.ndarray = field(default_factory=lambda: np.zeros((0, 1, 0)))
    special: list = field(default_factory=list)
    state_names: list = field(default_factory=list)
    message: str = ""

    def points(self, kind: str) -> list:
        """The special points of one kind."""
        return [p for p in self.special if p.kind == kind]


class _Family:
    """Period maps of the config at any value of the field (integrators made on demand, a few kept).

    The field is set as ``--set`` does (:func:`~blademodel.config.apply_overrides`): a
    top-level field, a dotted path (``contacts.0.gap``), or in the components format
    a declared parameter by its bare name (``omega``).
    """

    def __init__(self, config, name: str, periods: int, settings: dict, start: float, jacobian: str = "auto"):
        self.config, self.name, self.periods, self.settings = config, name, periods, settings
        self.jacobian = jacobian
        try:
            self.config_at(start)
        except ValueError as e:
            raise ValueError(f"{type(config).__name__} has no field {name!r} to continue in, or {start!r} is not "
                             f"a value it takes: {e}") from None
        self._cache: dict = {}
        self._first = None

    def config_at(self, value: float):
        from ..config import apply_overrides
        return apply_overrides(self.config, {self.name: float(value)}, source="continuation")

    def parameter_direction(self, value: float, delta: float, names: list) -> tuple[np.ndarray, float]:
        """``d p / d lambda`` over the raw parameters ``names`` and ``d T / d lambda`` at ``value``.

        Central differences of the built models' parameter values and excitation
        periods (no integration): a field enters the parameters through the config's
        own formulas, which are smooth (most are linear).
        """
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
            from ..numeric.kernels import make_integrator
            if len(self._cache) > 8:
                self._cache.pop(next(iter(self._cache)))
            from ..numeric.integrator import StructureMismatch
            model = self.config_at(key).build()
            ig = None
            if self._first is not None and hasattr(self._first, "with_parameters"):
                try:
                    ig = self._first.with_parameters(model)
                except StructureMismatch:
                    pass
            if ig is None:
                ig = make_integrator(model, **self.settings)
                self._first = ig
            self._cache[key] = PeriodMap(ig, self.periods, self.jacobian)
        return self._cache[key]


def continuation(config, name: str, start: float, stop: float, *, periods: int = 1, guess=None, mode=None,
                 transient: int = 20, ds: float = 0.01, ds_min: float = 1e-5, ds_max: float = 0.05,
                 max_points: int = 400, tol: float = 1e-10, max_corrections: int = 8, rel_step: float = 1e-6,
                 locate_tol: float = 1e-7, steps_per_period: int = 1000, event_tol: float = 1e-10,
                 method: str = "rk4", kernel: str = "auto", jacobian: str = "auto",
                 progress: Callable[[int, float], None] | None = None) -> Branch:
    """Follow the periodic orbits of ``config`` as its field ``name`` goes from ``start`` toward ``stop``.

    Parameters
    ----------
    config : pydantic config
        E.g. :class:`~blademodel.zheng2022.BladePair`; rebuilt at each value of the field.
    name : str
        The field: ``"omega"`` for a forced-response curve, or ``"gamma"``, ``"F0"`` ...
    start, stop : float
        The range; the branch starts at ``start`` and ends when the field leaves the range
        (it may turn back at folds in between).
    periods : int
        Period of the orbits in excitation periods.
    guess, mode, transient
        The first orbit's guess, as for :func:`~blademodel.orbits.find_periodic_orbit`.
    ds, ds_min, ds_max : float
        Arclength step, in units of the scaled state and of the range ``|stop - start|``.
    max_points : int
        Points at most.
    tol : float
        Scaled residual of each corrected point.
    max_corrections : int
        Newton steps per point before the step is halved.
    rel_step : float
        Difference step relative to each state's scale (and to the range, for the field).
    locate_tol : float
        Bifurcations are located to this fraction of the range.
    steps_per_period, event_tol, method, kernel
        The integrator's settings.
    jacobian : {"auto", "tangent", "differences"}
        How the period map is differentiated (:class:`~blademodel.orbits.period_map.PeriodMap`).
    progress : callable, optional
        ``progress(point, value)`` after each point.

    Returns
    -------
    Branch
    """
    settings = dict(steps_per_period=steps_per_period, event_tol=event_tol, method=method, kernel=kernel)
    fam = _Family(config, name, periods, settings, start, jacobian)
    span = abs(stop - start)
    if not span > 0:
        raise ValueError(f"start and stop must differ, got {start!r} and {stop!r}")
    direction = 1.0 if stop > start else -1.0
    P0 = fam.map_at(start)
    first = find_periodic_orbit(None, periods=periods, guess=guess, mode=mode, transient=transient, tol=tol,
                                rel_step=rel_step, integrator=P0.integrator, jacobian=jacobian)
    scale = first.scale
    n = scale.size
    ctx = _Context(fam, scale, span, tol, rel_step, max_corrections)

    # scaled unknowns X = (y / scale, lambda / span)
    X = np.append(first.state / scale, start / span)
    m = first.mode
    A = ctx.jacobian(X, m)
    T = _tangent(A, np.append(np.zeros(n), direction))
    return _follow(ctx, [ctx.point(X, m, A)], X, T, m, A, (start, stop), ds=ds, ds_min=ds_min, ds_max=ds_max,
                   max_points=max_points, locate_tol=locate_tol, progress=progress)


def period_doubled_branch(config, name: str, point: SpecialPoint, start: float, stop: float, *,
                          periods: int = 1, ds: float = 0.01, ds_min: float = 1e-5, ds_max: float = 0.05,
                          max_points: int = 400, tol: float = 1e-10, max_corrections: int = 8,
                          rel_step: float = 1e-6, locate_tol: float = 1e-7, steps_per_period: int = 1000,
                          event_tol: float = 1e-10, method: str = "rk4", kernel: str = "auto",
                          jacobian: str = "auto", progress: Callable[[int, float], None] | None = None) -> Branch:
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
    ds, ds_min, ds_max, max_points, tol, max_corrections, rel_step, locate_tol : float
        As for :func:`continuation`; ``ds`` is also the switch's step along ``v``.
    steps_per_period, event_tol, method, kernel, jacobian, progress
        As for :func:`continuation`.

    Returns
    -------
    Branch
        With ``periods`` twice the old branch's.

    Raises
    ------
    ValueError
        If ``point`` is not a period doubling, or lies outside ``[start, stop]``.
    FlowError
        If the switch converges back onto the old orbits for both signs of ``v``.
    """
    if point.kind != "period-doubling":
        raise ValueError(f"point must be a period-doubling point, got a {point.kind!r} point")
    lo, hi = min(start, stop), max(start, stop)
    if not lo <= point.param <= hi:
        raise ValueError(f"the period doubling at {name} = {point.param:g} lies outside [{lo:g}, {hi:g}]")
    settings = dict(steps_per_period=steps_per_period, event_tol=event_tol, method=method, kernel=kernel)
    fam = _Family(config, name, 2 * periods, settings, point.param, jacobian)
    span = hi - lo
    P2 = fam.map_at(point.param)
    ig = P2.integrator
    y = np.asarray(point.state, dtype=float)
    mode = point.mode
    if mode is None:
        full = np.zeros(ig.n_state)
        full[:y.size] = y
        mode = ig.mode_of(full)
    scale = _state_scale(_orbit_samples(ig, y, mode, 2 * periods)[1], _n_coordinates(ig))
    old = PeriodMap(ig, periods, jacobian)   # the period-``periods`` map
    J1 = old.jacobian(y, _copy(mode), scale, rel_step)
    mu, V = np.linalg.eig(J1)
    k = int(np.argmin(np.abs(mu + 1.0)))
    v = np.real(V[:, k]) / scale
    v /= np.linalg.norm(v)
    ctx = _Context(fam, scale, span, tol, rel_step, max_corrections)
    X0 = np.append(y / scale, point.param / span)
    A0 = ctx.jacobian(X0, mode)
    for sign, h in ((1.0, ds), (-1.0, ds), (1.0, 2 * ds), (-1.0, 2 * ds)):
        T0 = np.append(sign * v, 0.0)
        X1, m1, A1 = ctx.correct(X0 + h * T0, T0, _copy(mode))
        if X1 is None:
            continue
        y1 = X1[:-1] * scale
        r_old = np.max(np.abs(old(y1, _copy(m1))[0] - y1) / scale)
        if r_old > 1e3 * tol:   # not the old orbit again
            break
    else:
        raise FlowError(f"the switch at {name} = {point.param:g} came back to the period-{periods} orbits "
                        f"for both signs of the critical eigenvector")
    T1 = _tangent(A1, X1 - X0)
    pts = [ctx.point(X0, mode, A0), ctx.point(X1, m1, A1)]
    X, T, A = ctx.rescale(_state_scale(pts[-1]["Y"], _n_coordinates(ig)), X1, T1, A1)
    pts[-1]["X"], pts[-1]["A"] = X, A
    return _follow(ctx, pts, X, T, m1, A, (lo, hi), ds=ds, ds_min=ds_min, ds_max=ds_max, max_points=max_points,
                   locate_tol=locate_tol, progress=progress)


def _follow(ctx, pts, X, T, m, A, bounds, *, ds, ds_min, ds_max, max_points, locate_tol, progress) -> Branch:
    """Continue from the last point ``pts[-1]`` (unknowns ``X``, tangent ``T``) until the field leaves ``bounds``."""
    fam, span = ctx.fam, ctx.span
    name, periods = fam.name, fam.periods
    ig = fam.map_at(X[-1] * span).integrator
    n = ctx.n
    n_q = _n_coordinates(ig)
    lo, hi = min(bounds), max(bounds)
    special: list = []
    h = ds
    message = f"left [{lo:g}, {hi:g}] in {name}"
    jumped = False
    while len(pts) < max_points:
        X_new, m_new, A_new = ctx.correct(X + h * T, T, m, A)
        secant = False
        if X_new is None and abs(T[-1]) > 0.1:
            # Newton on the arclength system can cycle across a kink of the map (a switching
            # time passing the section); away from folds, shooting at the predicted value does not
            X_new, m_new, A_new = ctx.correct_at_value(X + h * T, m)
            secant = X_new is not None
        if X_new is None:
            if h / 2 < ds_min:
                if not jumped and len(pts) > 1:
                    # halving brought the prediction ever closer to a kink of the map (a switching
                    # time passing the section), where the difference quotients, and so the tangent,
                    # straddle it: jump across along the secant of the last two points instead
                    prev = np.append(pts[-2]["state"] / ctx.scale, pts[-2]["param"] / span)
                    if np.linalg.norm(X - prev) > 0:
                        T = (X - prev) / np.linalg.norm(X - prev)
                        A = None
                    jumped, h = True, 4 * ds_min * max(1.0, ds / ds_min) ** 0.5
                    continue
                message = f"the step fell below ds_min = {ds_min:g} at {name} = {X[-1] * span:.6g}: {ctx.why}"
                break
            h /= 2
            continue
        jumped = False
        if secant:   # the difference quotients there may straddle the kink: the secant is the tangent
            T_new = (X_new - X) / np.linalg.norm(X_new - X)
        else:
            T_new = _tangent(A_new, T)
        new = ctx.point(X_new, m_new, A_new)
        special += ctx.detect(pts[-1], new, X, T, m, len(pts) - 1, locate_tol)
        pts.append(new)
        # each state scaled by its excursion on the newest orbit: amplitudes that grow a
        # hundredfold through a resonance do not shrink the steps a hundredfold
        X, T, A = ctx.rescale(_state_scale(new["Y"], n_q), X_new, T_new, A_new)
        new["X"], new["A"] = X, A
        m = m_new
        h = min(h * 1.5, ds_max) if ctx.iterations <= 4 else (h if ctx.iterations <= 8 else h / 2)
        if progress is not None:
            progress(len(pts), X[-1] * span)
        lam = X[-1] * span
        if lam > hi + 1e-12 * span or lam < lo - 1e-12 * span:
            if bounds[1] in (lo, hi) and (lam > hi if bounds[1] == hi else lam < lo):
                message = f"reached {name} = {bounds[1]:g}"
            break
    else:
        message = f"stopped after max_points = {max_points} points at {name} = {X[-1] * span:.6g}"
    return Branch(field=name, periods=periods, params=np.array([p["param"] for p in pts]),
                  states=np.array([p["state"] for p in pts]), multipliers=np.array([p["mu"] for p in pts]),
                  stable=np.array([p["stable"] for p in pts], dtype=bool),
                  amplitudes=np.array([p["amp"] for p in pts]), harmonics=np.array([p["h1"] for p in pts]),
                  events=np.array([p["events"] for p in pts], dtype=np.int64),
                  sections=np.array([p["sections"] for p in pts]), special=special, state_names=list(ig.meta["state"][:n]),
                  message=message)


def _tangent(A, previous):
    """The unit null vector of ``A`` (``n x (n + 1)``) pointing the way of ``previous``."""
    M = np.vstack([A, previous])
    rhs = np.zeros(A.shape[0] + 1)
    rhs[-1] = 1.0
    t = np.linalg.solve(M, rhs)
    t /= np.linalg.norm(t)
    return t if np.dot(t, previous) >= 0 else -t


class _Context:
    """Residuals, Jacobians, corrections and bifurcation tests in the scaled unknowns."""

    def __init__(self, fam: _Family, scale, span, tol, rel_step, max_corrections):
        self.fam, self.scale, self.span = fam, scale, span
        self.tol, self.rel_step, self.max_corrections = tol, rel_step, max_corrections
        self.n = scale.size
        self.iterations = 0
        self.why = ""

    def correct_at_value(self, X, mode):
        """Shooting at the field's value of the prediction ``X`` (no arclength condition); ``(None, ..)`` on failure."""
        from .shooting import ShootingError, _newton
        lam = X[-1] * self.span
        try:
            P = self.fam.map_at(lam)
            y, mode_end = _newton(P, X[:-1] * self.scale, mode, self.scale, self.tol, self.max_corrections,
                                  self.rel_step, [])
        except (ShootingError, FlowError, np.linalg.LinAlgError, ValueError) as e:
            self.why = f"{self.why}; shooting at {self.fam.name} = {lam:.6g}: {e}"
            return None, mode, None
        if not _same(mode_end, mode):
            mode = _copy(mode_end)
        Xc = np.append(y / self.scale, X[-1])
        self.iterations = self.max_corrections // 2
        A = self._jacobian_at(Xc, mode)
        return (Xc, mode, A) if A is not None else (None, mode, None)

    def _jacobian_at(self, X, mode):
        """:meth:`jacobian` at a corrected point, or None (with ``why``) where a perturbed integration fails."""
        try:
            return self.jacobian(X, mode)
        except (FlowError, ValueError) as e:
            self.why = f"the Jacobian at the corrected point: {e}"
            return None

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
        return (Py - y) / self.scale, mode_end

    def jacobian(self, X, mode):
        """``d residual / dX`` (``n x (n + 1)``): the tangent of the flow where it exists, else central differences."""
        n, d = self.n, self.rel_step
        lam = X[-1] * self.span
        P = self.fam.map_at(lam)
        y = X[:-1] * self.scale
        A = np.empty((n, n + 1))
        if P.exact:
            ig = P.integrator
            dp, dT = self.fam.parameter_direction(lam, d * self.span, ig.meta["params"])
            s = P.try_derivatives(y, mode, dp, dT)
            if s is not None:
                A[:, :n] = (s.monodromy - np.eye(n)) * self.scale[None, :] / self.scale[:, None]
                A[:, n] = s.parameter * self.span / self.scale
                return A
        J = P.differences(y, mode, self.scale, d)
        A[:, :n] = (J - np.eye(n)) * self.scale[None, :] / self.scale[:, None]
        Pp, Pm = self.fam.map_at(lam + d * self.span), self.fam.map_at(lam - d * self.span)
        A[:, n] = (Pp(y, _copy(mode))[0] - Pm(y, _copy(mode))[0]) / self.scale / (2 * d)
        return A

    def correct(self, X, T, mode, A=None):
        """Newton on the orbit and arclength conditions from the prediction ``X``; ``(None, ..)`` on failure.

        With ``A`` (the Jacobian at the last point) the first attempt is a chord method:
        the same matrix every step, only residuals evaluated; then Newton with the
        Jacobian taken afresh. The orbit must come back to the mode it starts in at the
        section: converged in another one, or failing where the flow from the
        prediction ends in another one (the section state crossed a switching boundary
        between the points), the correction is done again from that mode. Returns the
        point, its mode and its Jacobian.
        """
        Xp = X.copy()
        self.why = ""
        tries = ([(mode, True)] if A is not None else []) + [(mode, False)]
        tried = set()
        while tries:
            mode, chord = tries.pop(0)
            tried.add((_key(mode), chord))
            Xc = Xp.copy()
            first_end = None
            try:
                G = np.vstack([A, T]) if chord else None
                for it in range(2 * self.max_corrections if chord else self.max_corrections):
                    r, mode_end = self.residual(Xc, mode)
                    first_end = mode_end if first_end is None else first_end
                    res = float(np.max(np.abs(r)))
                    if res <= self.tol:
                        break
                    if not chord:
                        G = np.vstack([self.jacobian(Xc, mode), T])
                    Xc = Xc + np.linalg.solve(G, -np.append(r, np.dot(T, Xc - Xp)))
                    if not (np.all(np.isfinite(Xc)) and np.linalg.norm(Xc - Xp) < 1.0):
                        raise FlowError("the correction diverged (moved by more than the orbit's excursion)")
                else:
                    raise FlowError(f"no convergence in {it + 1} corrections (residual {res:.2g})")
            except (FlowError, np.linalg.LinAlgError, ValueError) as e:   # ValueError: a field out of its range
                self.why = str(e)
                if first_end is not None and (_key(first_end), False) not in tried and \
                        all(_key(first_end) != _key(m) for m, _ in tries):
                    tries.append((_copy(first_end), False))
                continue
            self.iterations = it
            if _same(mode_end, mode):
                A = self._jacobian_at(Xc, mode)
                if A is None:
                    continue
                return Xc, mode, A
            if (_key(mode_end), False) not in tried:
                tries.append((_copy(mode_end), False))
            self.why = "the orbit's mode at the section keeps changing (it switches exactly there)"
        return None, mode, None

    def point(self, X, mode, A):
        """The branch point's record from its scaled unknowns and Jacobian."""
        n = self.n
        J = A[:, :n] * self.scale[:, None] / self.scale[None, :] + np.eye(n)
        mu = np.linalg.eigvals(J)
        mu = mu[np.argsort(-np.abs(mu), kind="stable")]
        lam = X[-1] * self.span
        P = self.fam.map_at(lam)
        y = X[:-1] * self.scale
        counters = np.zeros(N_COUNTERS, dtype=np.int64)
        t, Y = _orbit_samples(P.integrator, y, mode, self.fam.periods, counters)
        amp = 0.5 * (Y.max(axis=0) - Y.min(axis=0))
        c = np.fft.rfft(Y[:-1], axis=0)[self.fam.periods] * 2.0 / (Y.shape[0] - 1)
        S = P.integrator.steps_per_period
        return {"param": lam, "state": y, "sections": Y[:-1:S].copy(), "mu": mu, "stable": bool(np.max(np.abs(mu)) < 1.0), "amp": amp,
                "h1": c, "unstable": _unstable_count(mu), "X": X.copy(), "mode": _copy(mode), "A": A, "Y": Y,
                "events": int(counters[C_EVENTS])}

    def detect(self, a, b, Xa, Ta, mode, index, locate_tol):
        """The bifurcations between consecutive points ``a`` and ``b``, each located by bisection.

        A change in the number of multipliers outside the unit circle (fold, period
        doubling, Neimark-Sacker), and a change in the number of events per orbit: a
        guard of the orbit touches zero there (a contact that grazes, a slip that comes
        to rest: **grazing**, including the end of continuous sliding).
        """
        found = []
        for what in ("unstable", "events"):
            if a[what] == b[what]:
                continue
            best = self._bisect(a, b, Xa, Ta, mode, what, locate_tol)
            if what == "events":
                found.append(SpecialPoint(kind="grazing", param=best["param"], state=best["state"],
                                          multiplier=complex(best["mu"][0]), index=index, mode=_copy(best["mode"])))
                continue
            mu = best["mu"][np.argmin(np.abs(np.abs(best["mu"]) - 1.0))]
            if abs(mu.imag) > 1e-6 * abs(mu):
                kind = "neimark-sacker"
            else:
                kind = "period-doubling" if mu.real < 0 else "fold"
            found.append(SpecialPoint(kind=kind, param=best["param"], state=best["state"], multiplier=complex(mu),
                                      index=index, mode=_copy(best["mode"])))
        return found

    def _bisect(self, a, b, Xa, Ta, mode, what, locate_tol):
        """The first point past the change of ``what`` from ``a`` to ``b``, to ``locate_tol`` of arclength."""
        lo, hi = 0.0, float(np.dot(Ta, b["X"] - Xa))
        best = b
        while hi - lo > locate_tol:
            mid = 0.5 * (lo + hi)
            Xm, mm, Am = self.correct(Xa + mid * Ta, Ta, mode, a["A"])
            if Xm is None:
                Xm, mm, Am = self.correct_at_value(Xa + mid * Ta, mode)
            if Xm is None:
                break
            pm = self.point(Xm, mm, Am)
            if pm[what] == a[what]:
                lo = mid
            else:
                hi, best = mid, pm
        return best


def _key(mode):
    """A hashable form of a mode (an int, or the per-contact kernel's array)."""
    return tuple(np.atleast_1d(mode).tolist())


def _unstable_count(mu) -> int:
    return int(np.sum(np.abs(mu) > 1.0))

