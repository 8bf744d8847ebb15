"""Periodic orbits by shooting: Newton's method on the period map, Floquet multipliers at the solution."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .period_map import FlowError, PeriodMap, _copy, kernel_mode


class ShootingError(RuntimeError):
    """Newton's method on the period map did not converge; ``history`` holds the scaled residuals.

    ``least_tol`` is set (to a tolerance Newton's method can reach) where the residual stopped
    falling at the level of the integration's rounding errors, below :data:`ROUNDING_LEVEL`:
    the tolerance asked for is then below what the arithmetic gives, not the start far from
    an orbit.
    """

    def __init__(self, message: str, history: list, state: np.ndarray):
        super().__init__(message)
        self.history = history
        self.state = state
        self.least_tol = None


#: A scaled residual that stops falling below this has met the rounding errors of the integration (the bilinear pair's
#: orbits stall between ``9e-14`` and ``8e-13``), not a start far from the orbit nor a gap of the discrete flow (shots
#: into the Coulomb pair's gap at 305.78 rad/s stall at ``5.5e-7`` to ``3.7e-6``, into the bilinear 24-blade ring's at
#: ``4e-4`` to ``9e-3``). Below the default ``tol``, which therefore never meets it.
ROUNDING_LEVEL = 1e-11


def tolerance_above(residual: float) -> float:
    """A tolerance that Newton's method reaches where residuals stop falling at ``residual`` (rounding's level): ten
    times it, rounded up to a power of ten."""
    return float(10.0 ** np.ceil(np.log10(10.0 * residual)))


def below_rounding(residual: float, tol: float) -> str:
    """What to say where residuals stopped falling at ``residual``, rounding's level, above ``tol``."""
    return (f"the residual stops falling at {residual:.2g}, where the integration's rounding errors leave it: "
            f"tol = {tol:g} asks for less than the arithmetic gives; take tol (--tol) {tolerance_above(residual):g} "
            f"or more")


def _not_converged(message: str, history: list, state: np.ndarray, tol: float) -> ShootingError:
    """A :class:`ShootingError` with ``message``, saying so where the residual stalled at rounding's level."""
    best = min(history)
    if not best <= ROUNDING_LEVEL:
        return ShootingError(message, history, state)
    err = ShootingError(f"{message}; {below_rounding(best, tol)}", history, state)
    err.least_tol = tolerance_above(best)
    return err


@dataclass
class PeriodicOrbit:
    """A periodic orbit of the hybrid flow and its stability.

    Attributes
    ----------
    state : ndarray
        The physical state at ``t = 0`` (mod ``periods * period``), SI units.
    mode : int or ndarray
        Its hybrid mode (an array of contact modes on the per-contact kernel).
    periods : int
        The orbit's period in excitation periods.
    period : float
        The excitation period ``T`` in s.
    monodromy : ndarray
        ``dP/dy`` at ``state``: the Jacobian of the map over ``periods * period``.
    multipliers : ndarray of complex
        Its eigenvalues, largest modulus first.
    residual : float
        ``max |P(y) - y| / scale`` at ``state``.
    history : list of float
        The scaled residual before each Newton step, then at the solution.
    state_names : list of str
    scale : ndarray
        The scale of each state used for the residual and the difference steps.
    t, y : ndarray
        The orbit sampled at every step over ``periods * period`` (``y`` physical states).
    """

    state: np.ndarray
    mode: object
    periods: int
    period: float
    monodromy: np.ndarray
    multipliers: np.ndarray
    residual: float
    history: list
    state_names: list
    scale: np.ndarray
    t: np.ndarray = field(repr=False)
    y: np.ndarray = field(repr=False)

    def __repr__(self) -> str:
        # a summary: the state, the monodromy and the sampled orbit are attributes to ask for
        mu = self.largest_multiplier
        return (f"PeriodicOrbit(period-{self.periods}, {'stable' if self.stable else 'unstable'}, largest multiplier "
                f"{mu.real:.6g}{mu.imag:+.6g}j (|mu| = {abs(mu):.6g}), residual {self.residual:.2g}, "
                f"{len(self.state)} states, T = {self.period:.6g} s)")

    @property
    def stable(self) -> bool:
        """All multipliers inside the unit circle."""
        return bool(np.max(np.abs(self.multipliers)) < 1.0)

    @property
    def largest_multiplier(self) -> complex:
        return complex(self.multipliers[0])

    def least_period(self, tol: float | None = None) -> int:
        """The fewest excitation periods after which the orbit comes back: a divisor of ``periods``
        (:func:`~.least_period.least_period`; 1 for the period-1 orbit found with ``periods = 2``)."""
        from .least_period import LEAST_PERIOD_TOL, least_period
        steps = (self.y.shape[0] - 1) // self.periods
        return least_period(self.y[:-1:steps], self.scale, LEAST_PERIOD_TOL if tol is None else tol)

    def amplitudes(self) -> dict:
        """Half the peak-to-peak excursion of each state over the orbit, by name."""
        a = 0.5 * (self.y.max(axis=0) - self.y.min(axis=0))
        return dict(zip(self.state_names, map(float, a)))

    def harmonic(self, name: str, k: int = 1) -> complex:
        """Complex amplitude of the ``k``-th harmonic of the excitation in state ``name`` over the orbit.

        ``x(t) = sum_k Re(X_k exp(i k omega t))``; ``k`` may be a fraction ``j / periods``
        (subharmonics of a period-``n`` orbit).
        """
        i = self.state_names.index(name)
        x = self.y[:-1, i]
        m = x.size
        j = k * self.periods
        if abs(j - round(j)) > 1e-12:
            raise ValueError(f"harmonic {k} is not a multiple of 1/{self.periods}")
        c = np.fft.rfft(x)[int(round(j))] / m
        return complex(2.0 * c) if round(j) else complex(c)


#: The scale of a friction law's discrete states (labels such as an Iwan element's ``0``, ``+-1``): so large that
#: a label's scaled value, and a change of label between two points of a branch, is far below any step or
#: tolerance of the scaled unknowns (a power of two, so that labels are scaled and back exactly). Whether the
#: labels come back is asked apart (:func:`residual_size`); Newton's step sets them, as the Jacobian's rows
#: for them are ``-1`` on the diagonal and zero elsewhere (:func:`~.period_map.hold_discrete`).
LABEL_SCALE = 2.0 ** 40


def _state_scale(y_hist: np.ndarray, n_q: int, discrete=()) -> np.ndarray:
    """Per-state scale for residuals and difference steps: each state's excursion, floored by its group's;
    ``discrete`` (the laws' discrete states) :data:`LABEL_SCALE`."""
    return _scale_of_excursions(np.max(np.abs(y_hist), axis=0), n_q, discrete)


def _scale_of_excursions(amp: np.ndarray, n_q: int, discrete=()) -> np.ndarray:
    """:func:`_state_scale` from each state's largest magnitude ``amp``."""
    amp = np.asarray(amp, dtype=float).copy()
    n = amp.size
    labels = np.zeros(n, dtype=bool)
    labels[np.asarray(discrete, dtype=np.int64)] = True
    amp[labels] = 0.0   # a label's size is no measure of the law states beside it
    scale = amp.copy()
    for sl in (slice(0, n_q), slice(n_q, 2 * n_q), slice(2 * n_q, n)):
        if sl.start < sl.stop:
            g = np.max(amp[sl])
            if sl.start == 2 * n_q and n_q and g == 0.0:
                # the law states (a Jenkins element's stretch, a length like the coordinates) are all relaxed on an
                # orbit whose contacts stay open: floored by the coordinates' scale, not 1e-300, which turned their
                # next nonzero values into overflows
                g = np.max(amp[:n_q])
            scale[sl] = np.maximum(scale[sl], 1e-3 * g)
    scale = np.maximum(scale, 1e-300) if np.any(scale > 0) else np.ones(n)
    scale[labels] = LABEL_SCALE
    return scale


def scaled_residual(Py: np.ndarray, y: np.ndarray, scale: np.ndarray, discrete) -> np.ndarray:
    """``(P(y) - y) / scale``, the discrete states' labels read as the map reads them (whole numbers)."""
    r = (Py - y) / scale
    r[discrete] = (Py[discrete] - np.rint(y[discrete])) / scale[discrete]
    return r


def residual_size(r: np.ndarray, discrete) -> float:
    """``max |r|`` of a scaled residual, or at least 1 where a discrete state (scaled by :data:`LABEL_SCALE`)
    does not come back to its label: such an orbit is not periodic whatever the rest."""
    res = float(np.max(np.abs(r)))
    return max(res, 1.0) if len(discrete) and np.any(r[discrete] != 0.0) else res


def find_periodic_orbit(model, *, periods: int = 1, guess=None, mode=None, transient: int = 20,
                        tol: float = 1e-10, max_iter: int = 30, rel_step: float = 1e-6,
                        steps_per_period: int = 1000, event_tol: float = 1e-10, method: str = "rk4",
                        kernel: str = "auto", integrator=None, jacobian: str = "auto",
                        workers: int | None = None) -> PeriodicOrbit:
    """A periodic orbit of ``periods`` excitation periods by shooting on the exact hybrid flow.

    Newton's method on ``r(y) = P(y) - y``, ``P`` the map over ``periods * T``
    (:class:`~blademodel.orbits.period_map.PeriodMap`), with the Jacobian
    ``dP/dy`` from the tangent of the flow or by central differences (``jacobian``),
    each state scaled by its excursion; a step
    that does not reduce the residual is halved (up to eight times). The Floquet
    multipliers are the eigenvalues of ``dP/dy`` at the solution. Unstable orbits
    are found as readily as stable ones: nothing here integrates toward an attractor
    but the optional transient that makes the guess.

    Parameters
    ----------
    model : Model
        A built model (``config.build()``).
    periods : int
        Period of the orbit in excitation periods (2 for period-2 ...).
    guess : array_like or dict, optional
        State at ``t = 0``; by default the state after ``transient`` periods from rest.
    mode : int or array, optional
        The guess's hybrid mode (a row of :attr:`~blademodel.orbits.branch.Branch.modes`
        will do); by default the one its state belongs to.
    transient : int
        Periods integrated from rest (or from ``guess``) before the first step.
    tol : float
        Converged when ``max |P(y) - y| / scale <= tol`` and the friction laws' discrete
        states (:attr:`~blademodel.components.friction.base.FrictionLaw.discrete_states`, an
        Iwan element's label) come back exactly: they are held as part of the mode, not solved
        for (:func:`~.period_map.hold_discrete`).
    max_iter : int
        Newton steps allowed.
    rel_step : float
        Difference step relative to each state's scale.
    steps_per_period, event_tol, method, kernel
        The integrator's settings (:func:`blademodel.numeric.simulate`).
    integrator : Integrator, optional
        Use this integrator (its settings) instead of making one.
    jacobian : {"auto", "tangent", "differences", "forward"}
        How ``dP/dy`` is formed (:class:`~blademodel.orbits.period_map.PeriodMap`): the
        tangent of the flow (variational equations, saltation matrices) on the
        product-mode kernel, central differences elsewhere.
    workers : int, optional
        Threads for the difference quotients (:class:`~blademodel.orbits.period_map.PeriodMap`):
        ``None`` or ``-1`` every CPU, ``1`` none; the orbit is the same to the bit.

    Returns
    -------
    PeriodicOrbit

    Raises
    ------
    ShootingError
        If Newton's method does not reach ``tol`` in ``max_iter`` steps or the
        residual stops decreasing; the error carries the residual history.
    FlowError
        If an integration fails.
    """
    from ..numeric.kernels import make_integrator
    if integrator is None:
        integrator = make_integrator(model, kernel=kernel, steps_per_period=steps_per_period,
                                     event_tol=event_tol, method=method)
    ig = integrator
    P = PeriodMap(ig, periods, jacobian, workers)
    n = P.n
    y_full = ig.initial_state(guess)
    mode = kernel_mode(ig, mode)
    if mode is None:
        mode = ig.mode_of(y_full)
    mode = _copy(mode)
    if transient > 0:
        status, mode, t = ig.advance(y_full, mode, 0, int(transient))
        if status != 0:
            raise FlowError(f"the transient stopped at t = {t:.6g} s with status {status}")
    y = y_full[:n].copy()
    n_q = _n_coordinates(ig)
    scale = _state_scale(_orbit_samples(ig, y, mode, periods)[1], n_q, P.discrete)

    history = []
    y, mode = _shoot(P, y, mode, scale, tol, max_iter, rel_step, history)
    J = P.jacobian(y, mode, scale, rel_step)
    mu = np.linalg.eigvals(J)
    mu = mu[np.argsort(-np.abs(mu), kind="stable")]
    t_orbit, y_orbit = _orbit_samples(ig, y, mode, periods)
    return PeriodicOrbit(state=y, mode=_copy(mode), periods=int(periods), period=ig.period, monodromy=J,
                         multipliers=mu, residual=history[-1], history=history,
                         state_names=list(ig.meta["state"][:n]), scale=scale, t=t_orbit, y=y_orbit)


def _shoot(P, y, mode, scale, tol, max_iter, rel_step, history):
    """Newton's method (:func:`_newton`) until the orbit also comes back to the mode it starts in.

    Converged in a mode the orbit does not come back to (the section state lies on a
    switching boundary of the guess's mode, ``P(y) = y`` but the mode at ``t = T`` is
    another), the state is not an orbit of the hybrid system in the mode it ends in:
    solved again from that mode, at most three times. Returns ``(y, mode)``.
    """
    for _ in range(3):
        y, mode_end = _newton(P, y, mode, scale, tol, max_iter, rel_step, history)
        if _same(mode_end, mode):
            return y, mode
        mode = _copy(mode_end)
    raise ShootingError(f"the orbit does not come back to its mode at the section (mode {mode!r} -> "
                        f"{mode_end!r}): it switches exactly there", history, y)


def _newton(P, y, mode, scale, tol, max_iter, rel_step, history):
    """Newton's method on ``P(y) - y`` from ``(y, mode)``; the solution and the mode ``P`` ends in."""
    n = y.size
    for it in range(max_iter + 1):
        Py, mode_end = P(y, _copy(mode))   # kept: the tangent below replays this run
        r = scaled_residual(Py, y, scale, P.discrete)
        res = residual_size(r, P.discrete)
        history.append(res)
        if res <= tol:
            return y, mode_end
        if it == max_iter:
            raise _not_converged(f"shooting did not converge in {max_iter} Newton steps: scaled residual "
                                 f"{res:.3g} > tol = {tol:g} (history: {_show(history)})", history, y, tol)
        J = P.jacobian(y, mode, scale, rel_step)   # only where not converged: a ring's replay is not cheap
        Js = (J - np.eye(n)) * scale[None, :] / scale[:, None]
        step = np.linalg.lstsq(Js, -r, rcond=None)[0] * scale
        lam = 1.0
        for _ in range(9):
            y_try = y + lam * step
            y_try[P.discrete] = y[P.discrete] + step[P.discrete]   # a label is set whole, not halved
            try:
                r_try = scaled_residual(P(y_try, _copy(mode))[0], y_try, scale, P.discrete)
                if residual_size(r_try, P.discrete) < res:
                    break
            except FlowError:
                pass
            lam *= 0.5
        else:
            raise _not_converged(f"shooting stalled: no step along the Newton direction reduces the scaled "
                                 f"residual {res:.3g} (history: {_show(history)})", history, y, tol)
        y = y_try


def _show(history) -> str:
    return ", ".join(f"{h:.2g}" for h in history)


def _same(a, b) -> bool:
    return bool(np.array_equal(np.asarray(a), np.asarray(b)))


def _n_coordinates(ig) -> int:
    """Number of generalized coordinates (the state starts with them, then their velocities)."""
    names = ig.meta["state"]
    return sum(1 for s in names if ("v" + s) in names)


def _orbit_samples(ig, y, mode, periods, counters=None):
    """The trajectory from ``(y, mode)`` at every step over ``periods`` periods: ``t`` and physical states.

    ``counters`` (``contract.N_COUNTERS`` int64), if given, accumulates the run's counters.
    """
    from .period_map import settle
    n = ig.n_physical
    full = np.zeros(ig.n_state)
    full[:n] = y
    m = periods * ig.steps_per_period + 1
    rec = ig.record_buffer(m)
    mode = settle(ig, full, _copy(mode))
    status, _, t = ig.advance(full, mode, 0, periods, n_transient=0, record=rec, counters=counters)
    if status != 0:
        raise FlowError(f"the integration stopped at t = {t:.6g} s with status {status}")
    return rec[0].copy(), rec[1][:, :n].copy()
