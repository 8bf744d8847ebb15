"""An independent reference integrator of a model's hybrid system.

This module integrates the same hybrid system as the compiled kernel
(:mod:`.loop`), but shares none of its numerics: the flows, guards, candidate
conditions and resets are lambdified straight from the SymPy
:class:`~blademodel.symbolic.system.HybridSystem` (not from the generated Numba
source), the smooth arcs are integrated by :func:`scipy.integrate.solve_ivp`
with an adaptive high-order method (DOP853 by default) at tight tolerances, and
the guards of the current mode are handed to ``solve_ivp`` as terminal event
functions, so that events are located by SciPy's own root finder on the dense
output. It is slow (pure Python right-hand sides) and meant for validating the
kernel and for benchmarks, not for production runs.

Semantics shared with the kernel (see :func:`blademodel.numeric.loop.integrate`):

* a guard with ``direction = -1`` fires when it falls through zero, ``+1`` when it
  rises through zero, ``0`` either way;
* on an event the candidates of the guard are tried in order: the reset is
  applied to the state at the event, and the first candidate whose condition
  holds on the post-reset state *in the target mode* is taken; the last candidate
  is unconditional;
* the initial mode is found as in :func:`blademodel.numeric.loop.initial_mode`:
  starting from the all-open mode, every contact whose penetration is ``>= 0``
  is closed through its own closing guard's candidates (resets included).

Restart rule (guard against immediate re-triggering)
    ``solve_ivp`` locates a root ``t_e`` to a few ulps, and the state there may
    lie on either side of the guard's zero. Like the kernel, which takes the far
    end of its bisection bracket, the reference takes the state at the first time
    ``t_e + d`` (``d`` = 0, then one ulp of ``t_e``, doubling) at which the fired
    guard is *strictly* on the far side of zero, evaluated on the step's dense
    output (``d`` is at most :data:`NUDGE_MAX` times the excitation period, else
    the root itself is used). Restarting strictly past the root means a guard of
    the new mode with the same zero (e.g. the opening guard after a closing) starts
    on the correct side, while a genuine immediate event of the new mode (a guard
    that starts at ``+0`` and falls, like the Jenkins stick guards right after
    the contact closes with ``z = 0``) is still detected and located by
    ``solve_ivp`` in its first step. No event is ever skipped.

Simultaneous events
    ``solve_ivp`` terminates at the earliest root of all the mode's guards and
    reports only that one; if two roots coincide to the last bit, the one SciPy
    sorts first is taken, whereas the kernel takes the lower guard index. Exact
    ties are not expected outside contrived initial states.

Why the nudge matters
    Without it (restarting at the root itself), the bilinear base case and the
    bilinear case at zero gap leave the kernel's event sequence within five
    periods: after a closing located at ``delta = -0``, the stick guards
    ``mu N -+ kd z`` start at ``-0`` instead of ``+0``, and the immediate stick to
    slip transition is missed. With the nudge every tested case follows the
    kernel's event sequence event by event (``tests/test_reference.py``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

from ..model import Model
from .result import SimulationError

#: Largest nudge past a located root, as a fraction of the excitation period.
NUDGE_MAX = 1e-12

_LAMBDIFIED: dict = {}


def _lambdify(args, expr):
    """Scalar (``math``-module) lambdified function of ``(t, y, p)``."""
    try:
        return sp.lambdify(args, expr, modules="math", cse=True, docstring_limit=0)
    except TypeError:  # SymPy < 1.13 has no docstring_limit
        return sp.lambdify(args, expr, modules="math", cse=True)


@dataclass
class _Candidate:
    target: int
    condition: Callable | None  # None: unconditional (the last candidate)
    reset_index: np.ndarray
    reset: Callable | None


@dataclass
class _Mode:
    name: str
    flow: Callable
    guards: list
    directions: list
    guard_names: list
    candidates: list  # per guard: list of _Candidate


@dataclass
class _Lambdified:
    state_names: list
    param_names: list
    mode_names: list
    modes: list
    open_mode: int
    close_guard: list  # per mode: per contact, index of its closing guard or -1


def _lambdify_system(model: Model) -> _Lambdified:
    """Lambdify every flow, guard, condition and reset of ``derive(model)``.

    Memoised per model structure: parameters stay arguments, so models that only
    differ by parameter values share the functions.
    """
    key = model.structure_key()
    if key in _LAMBDIFIED:
        return _LAMBDIFIED[key]
    from ..symbolic import derive
    system = derive(model)
    state = system.state
    args = (system.t, state, system.params)
    modes = []
    for mode in system.modes:
        flow_exprs = [*system.u, *mode.accelerations, *mode.state_rates]
        guards, directions, names, cands = [], [], [], []
        for g in mode.guards:
            guards.append(_lambdify(args, g.expr))
            directions.append(int(g.direction))
            names.append(g.name)
            per = []
            for ci, c in enumerate(g.candidates):
                last = ci == len(g.candidates) - 1
                cond = None if last or c.condition is sp.true else _lambdify(args, c.condition)
                keys = list(c.reset)
                idx = np.array([state.index(k) for k in keys], dtype=int)
                reset = _lambdify(args, [c.reset[k] for k in keys]) if keys else None
                per.append(_Candidate(c.target, cond, idx, reset))
            cands.append(per)
        modes.append(_Mode(mode.name, _lambdify(args, flow_exprs), guards, directions, names, cands))
    n_contacts = len(model.contacts)
    close_guard = []
    for mode in system.modes:
        row = [-1] * n_contacts
        for gi, g in enumerate(mode.guards):
            if g.direction > 0 and g.name.endswith(": close"):
                row[g.contact] = gi
        close_guard.append(row)
    out = _Lambdified([s.name for s in state], [p.name for p in system.params],
                      [m.name for m in system.modes], modes, system.open_mode, close_guard)
    _LAMBDIFIED[key] = out
    return out


class ReferenceSystem:
    """The lambdified hybrid system of a model with its parameter values bound.

    Parameters
    ----------
    model : Model

    Attributes
    ----------
    state_names, mode_names : list of str
        As in :class:`~blademodel.numeric.result.SimulationResult`.
    params : ndarray
        Parameter values in the order of ``model.parameters``.
    """

    def __init__(self, model: Model):
        self._sys = _lambdify_system(model)
        self.model = model
        self.state_names = list(self._sys.state_names)
        self.mode_names = list(self._sys.mode_names)
        self.params = np.array([model.parameters[n] for n in self._sys.param_names], dtype=float)

    @property
    def n_state(self) -> int:
        return len(self.state_names)

    def guard_names(self, mode: int) -> list[str]:
        """Names of the guards of ``mode`` in index order."""
        return list(self._sys.modes[mode].guard_names)

    def rhs(self, mode: int, t: float, y: np.ndarray) -> np.ndarray:
        """The flow ``dy/dt`` of ``mode``."""
        return np.array(self._sys.modes[mode].flow(t, y, self.params), dtype=float)

    def guard_values(self, mode: int, t: float, y: np.ndarray) -> np.ndarray:
        """Values of every guard of ``mode`` at ``(t, y)``."""
        p = self.params
        return np.array([g(t, y, p) for g in self._sys.modes[mode].guards], dtype=float)

    def event_functions(self, mode: int) -> list[Callable]:
        """The guards of ``mode`` as ``solve_ivp`` events (terminal, with direction)."""
        m, p = self._sys.modes[mode], self.params
        events = []
        for g, d in zip(m.guards, m.directions):
            def event(t, y, g=g):
                return g(t, y, p)
            event.terminal = True
            event.direction = float(d)
            events.append(event)
        return events

    def transition(self, mode: int, guard: int, t: float, y: np.ndarray) -> tuple[int, np.ndarray]:
        """Apply guard ``guard`` of ``mode`` to the state ``y`` at time ``t``.

        Returns
        -------
        target : int
            The mode of the first candidate whose condition holds on the
            post-reset state in that mode (the last candidate is unconditional).
        y_new : ndarray
            The post-reset state (a new array).
        """
        p = self.params
        for c in self._sys.modes[mode].candidates[guard]:
            y_new = np.array(y, dtype=float)
            if c.reset is not None:
                y_new[c.reset_index] = c.reset(t, y, p)
            if c.condition is None or bool(c.condition(t, y_new, p)):
                return c.target, y_new
        raise AssertionError("unreachable: the last candidate is unconditional")

    def initial_mode(self, t: float, y: np.ndarray) -> tuple[int, np.ndarray]:
        """Mode of the state ``y``: every contact with ``delta >= 0`` is closed.

        Contacts are closed one at a time through their closing guard's
        candidates (resets applied), as in the kernel. Returns ``(mode, y)``.
        """
        mode = self._sys.open_mode
        y = np.array(y, dtype=float)
        for j in range(len(self.model.contacts)):
            gi = self._sys.close_guard[mode][j]
            if gi < 0:
                continue
            if self.guard_values(mode, t, y)[gi] >= 0.0:
                mode, y = self.transition(mode, gi, t, y)
        return mode, y

    def direction(self, mode: int, guard: int) -> int:
        return self._sys.modes[mode].directions[guard]


@dataclass
class ReferenceResult:
    """Outcome of :func:`simulate_reference`.

    Iterating yields the five primary outputs, so
    ``t, y, mode, n_events, log = simulate_reference(...)`` works.

    Attributes
    ----------
    t_final : float
        End time in s.
    y_final : ndarray
        State at ``t_final`` (SI), columns named by ``state_names``.
    mode_final : int
        Mode index at ``t_final`` (``mode_names[mode_final]``).
    n_events : int
        Events that occurred (all of them, logged or not).
    event_log : dict
        ``t`` (ndarray), ``guard``, ``from``, ``to`` (lists of names) of every event
        at ``t >= log_from``, the same layout as ``SimulationResult.events``.
    t_eval, y_eval, mode_eval : ndarray
        The dense samples requested with ``t_eval`` (empty otherwise); a sample at
        the time of an event holds the state just before it.
    initial_mode : int
        The mode chosen for the initial state.
    state_names, mode_names : list of str
    segments, nfev : int
        Smooth arcs integrated and right-hand-side evaluations (cost counters).
    nudged, grazing : int
        Events whose restart state had to be moved past the located root, and
        events where no state strictly past the root was found within
        :data:`NUDGE_MAX` (the root itself was then used).
    """

    t_final: float
    y_final: np.ndarray
    mode_final: int
    n_events: int
    event_log: dict
    t_eval: np.ndarray
    y_eval: np.ndarray
    mode_eval: np.ndarray
    initial_mode: int
    state_names: list
    mode_names: list
    segments: int = 0
    nfev: int = 0
    nudged: int = 0
    grazing: int = 0
    settings: dict = field(default_factory=dict)

    def __iter__(self) -> Iterator:
        return iter((self.t_final, self.y_final, self.mode_final, self.n_events, self.event_log))


def _strictly_past(g_value: float, direction: int, g_start: float) -> bool:
    if direction < 0:
        return g_value < 0.0
    if direction > 0:
        return g_value > 0.0
    return g_value < 0.0 if g_start > 0.0 else g_value > 0.0


def _initial_state(ref: ReferenceSystem, y0) -> np.ndarray:
    y = np.zeros(ref.n_state)
    if y0 is None:
        return y
    if isinstance(y0, dict):
        for k, v in y0.items():
            if k not in ref.state_names:
                raise KeyError(f"y0 names unknown state {k!r}; states are {ref.state_names}")
            y[ref.state_names.index(k)] = v
        return y
    y0 = np.asarray(y0, dtype=float).ravel()
    if y0.size > ref.n_state:
        raise ValueError(f"y0 has {y0.size} values for {ref.n_state} states")
    y[: y0.size] = y0
    return y


def simulate_reference(model: Model, t_end: float, *, y0=None, t_eval: Sequence[float] | None = None,
                       rtol: float = 1e-12, atol: float | Sequence[float] = 1e-16, method: str = "DOP853",
                       max_events: int = 100_000, log_from: float = 0.0,
                       max_step: float = math.inf) -> ReferenceResult:
    """Integrate ``model`` from ``t = 0`` to ``t_end`` with ``solve_ivp`` and exact events.

    Parameters
    ----------
    model : Model
    t_end : float
        End time in s (e.g. ``periods * T``).
    y0 : array_like or dict, optional
        Initial state (SI), as in :func:`~blademodel.numeric.simulate.simulate`;
        default rest. The initial mode follows the kernel's rule (every contact
        with penetration ``>= 0`` is closed through its closing guard), which may
        reset part of the state (e.g. a stick projection).
    t_eval : sequence of float, optional
        Sorted times in ``[0, t_end]`` at which to sample the state from the
        dense output (e.g. the Poincare times ``k T``).
    rtol : float
        Relative tolerance of ``solve_ivp``.
    atol : float or sequence of float
        Absolute tolerance of ``solve_ivp`` (SI units per state; the default
        ``1e-16`` suits displacements of order ``1e-4`` m).
    method : str
        ``solve_ivp`` method; an explicit high-order one (``"DOP853"``) by default.
    max_events : int
        Stop with :class:`~blademodel.numeric.result.SimulationError` after this
        many events (an event storm or Zeno behaviour).
    log_from : float
        Only events at ``t >= log_from`` are logged (all are counted), like the
        kernel's logging of the recorded window only.
    max_step : float
        Largest step of ``solve_ivp``.

    Returns
    -------
    ReferenceResult
        Unpacks as ``(t_final, y_final, mode_final, n_events, event_log)``.

    Raises
    ------
    SimulationError
        If ``solve_ivp`` fails, the state becomes non-finite, or more than
        ``max_events`` events occur.

    Notes
    -----
    See the module docstring for the restart rule that prevents re-triggering
    right after an event.
    """
    if not (t_end >= 0 and math.isfinite(t_end)):
        raise ValueError(f"t_end = {t_end!r} must be a finite number >= 0")
    ref = ReferenceSystem(model)
    y = _initial_state(ref, y0)
    t = 0.0
    mode, y = ref.initial_mode(t, y)
    mode0 = mode

    samples = np.asarray([] if t_eval is None else t_eval, dtype=float)
    if samples.size and (np.any(np.diff(samples) < 0) or samples[0] < 0 or samples[-1] > t_end):
        raise ValueError("t_eval must be sorted and lie within [0, t_end]")
    y_eval = np.empty((samples.size, ref.n_state))
    mode_eval = np.empty(samples.size, dtype=np.int64)
    k_sample = 0

    try:
        from .simulate import excitation_period
        scale = excitation_period(model)
    except ValueError:
        scale = max(t_end, 1.0)
    nudge_max = NUDGE_MAX * scale

    log_t, log_guard, log_from_mode, log_to = [], [], [], []
    n_events = segments = nfev = nudged = grazing = 0
    events_cache: dict[int, list] = {}
    while True:
        events = events_cache.setdefault(mode, ref.event_functions(mode))
        g_start = ref.guard_values(mode, t, y)
        if t < t_end:
            sol = solve_ivp(lambda tt, yy, m=mode: ref.rhs(m, tt, yy), (t, t_end), y, method=method,
                            rtol=rtol, atol=atol, events=events or None, dense_output=True,
                            max_step=max_step)
            segments += 1
            nfev += int(sol.nfev)
            if sol.status < 0:
                raise SimulationError(f"solve_ivp failed at t = {t:.6g} s in mode "
                                      f"'{ref.mode_names[mode]}': {sol.message}")
            t_stop = float(sol.t[-1])
            fired = [i for i, te in enumerate(sol.t_events or []) if len(te)] if sol.status == 1 else []
        else:
            sol, t_stop, fired = None, t, []

        # dense samples inside this arc: [t, t_stop) if an event ends it, [t, t_end] otherwise
        while k_sample < samples.size and (samples[k_sample] < t_stop or
                                           (not fired and samples[k_sample] <= t_stop)):
            ts = samples[k_sample]
            if ts == t or sol is None:
                y_eval[k_sample] = y
            elif ts == t_stop:
                y_eval[k_sample] = sol.y[:, -1]
            else:
                y_eval[k_sample] = sol.sol(ts)
            mode_eval[k_sample] = mode
            k_sample += 1

        if not fired:
            y = np.array(sol.y[:, -1]) if sol is not None else y
            t = t_end
            break

        gi = min(fired, key=lambda i: (sol.t_events[i][-1], i))
        te = float(sol.t_events[gi][-1])
        direction = ref.direction(mode, gi)
        # restart strictly past the root (see the module docstring)
        t_new, y_new = te, np.asarray(sol.sol(te), dtype=float)
        d = 0.0
        while not _strictly_past(ref.guard_values(mode, t_new, y_new)[gi], direction, g_start[gi]):
            d = math.ulp(te) if d == 0.0 else 2.0 * d
            if d > nudge_max:
                t_new, y_new = te, np.asarray(sol.sol(te), dtype=float)
                grazing += 1
                break
            t_new = te + d
            y_new = np.asarray(sol.sol(t_new), dtype=float)
        nudged += t_new != te
        if not np.all(np.isfinite(y_new)):
            raise SimulationError(f"the state became non-finite at t = {t_new:.6g} s "
                                  f"in mode '{ref.mode_names[mode]}'")
        new_mode, y = ref.transition(mode, gi, t_new, y_new)
        t = t_new
        n_events += 1
        if t >= log_from:
            log_t.append(t)
            log_guard.append(ref.guard_names(mode)[gi])
            log_from_mode.append(ref.mode_names[mode])
            log_to.append(ref.mode_names[new_mode])
        mode = new_mode
        if n_events > max_events:
            raise SimulationError(f"more than {max_events} events by t = {t:.6g} s "
                                  f"(mode '{ref.mode_names[mode]}')")

    while k_sample < samples.size:  # samples at t_end exactly
        y_eval[k_sample] = y
        mode_eval[k_sample] = mode
        k_sample += 1
    if not np.all(np.isfinite(y)):
        raise SimulationError(f"the state became non-finite by t = {t:.6g} s")
    event_log = {"t": np.array(log_t), "guard": log_guard, "from": log_from_mode, "to": log_to}
    return ReferenceResult(t, y, mode, n_events, event_log, samples, y_eval, mode_eval, mode0,
                           list(ref.state_names), list(ref.mode_names), segments, nfev, nudged, grazing,
                           {"rtol": rtol, "atol": atol, "method": method, "t_end": t_end})
