"""Run a model: the Python entry point of the hybrid solver."""

from __future__ import annotations


import numpy as np

from ..model import Model
from .integrator import HybridIntegrator, excitation_period  # noqa: F401  (re-exported)
from .result import SimulationError, SimulationResult

_COUNTERS = ("steps", "events", "bisections", "rhs_evaluations", "events_logged", "records")


def simulate(model: Model, *, periods: int = 1, transient: int = 0, steps_per_period: int = 1000,
             event_tol: float = 1e-10, record_every: int = 1, max_events_per_step: int = 100,
             max_log: int = 200_000, energy: bool = False, y0=None, period: float | None = None,
             check_stability: bool = True, raise_on_error: bool = True,
             length_scale: float | None = None, progress=None, chunk_periods: int = 50,
             mode0: int | None = None) -> SimulationResult:
    """Integrate ``model`` from rest with fixed-step RK4 and located events.

    Parameters
    ----------
    model : Model
    periods : int
        Excitation periods recorded after the transient.
    transient : int
        Excitation periods integrated first and discarded.
    steps_per_period : int
        RK4 steps per period: ``h = T / steps_per_period``.
    event_tol : float
        Bisection stops when the event is bracketed within ``event_tol * h``.
    record_every : int
        Record the state every this many steps (Poincare samples are always kept).
    max_events_per_step : int
        More events than this within one step stop the run (an event storm).
    max_log : int
        Most events kept in the log (all are counted).
    energy : bool
        Also integrate input work and dissipations (states ``W_in``, ``D_visc``,
        ``D_fric``); see :func:`blademodel.numeric.energy.energy_balance`.
    y0 : array_like or dict, optional
        Initial state (SI); default rest, ``x = u = 0`` (MODEL.md §6).
    period : float, optional
        Override the excitation period (required without harmonic forces).
    check_stability : bool
        Refuse a step beyond RK4's stability limit of the stiffest mode.
    raise_on_error : bool
        Raise :class:`SimulationError` on a non-finite state or an event storm;
        otherwise return the partial result with ``status`` and ``message``.
    length_scale : float, optional
        Scale for non-dimensional outputs (``X1 = x1 / length_scale``).
    progress : callable, optional
        ``progress(done_periods, total_periods)``, called after every chunk of
        ``chunk_periods`` periods (the run is split without changing its result).
    mode0 : int, optional
        Initial mode; by default it follows from ``y0`` (every contact with
        ``delta >= 0`` closed, the friction law choosing how).

    Returns
    -------
    SimulationResult
    """
    for name, value, lo in (("periods", periods, 1), ("transient", transient, 0), ("record_every", record_every, 1)):
        if int(value) != value or value < lo:
            raise ValueError(f"{name} = {value!r} must be an integer >= {lo}")
    integ = HybridIntegrator(model, steps_per_period=steps_per_period, event_tol=event_tol,
                             max_events_per_step=max_events_per_step, energy=energy, period=period,
                             check_stability=check_stability)
    T, n, meta = integ.period, integ.n_state, integ.meta
    y = integ.initial_state(y0)
    mode = integ.mode_of(y) if mode0 is None else int(mode0)

    n_rec = (periods * steps_per_period) // record_every + 1
    rec_t = np.empty(n_rec)
    rec_y = np.empty((n_rec, n))
    rec_mode = np.empty(n_rec, dtype=np.int64)
    poincare = np.empty((periods, n))
    log_t = np.empty(max_log)
    log_guard = np.empty(max_log, dtype=np.int64)
    log_from = np.empty(max_log, dtype=np.int64)
    log_to = np.empty(max_log, dtype=np.int64)
    counters = np.zeros(6, dtype=np.int64)
    total = transient + periods
    step = total if progress is None else max(1, int(chunk_periods))
    start, status, t_stop = 0, 0, 0.0
    while start < total and status == 0:
        end = min(total, start + step)
        status, mode, t_stop = integ.advance(y, mode, start, end, n_transient=transient,
                                             record=(rec_t, rec_y, rec_mode), poincare=poincare,
                                             log=(log_t, log_guard, log_from, log_to), counters=counters,
                                             record_every=record_every)
        start = end
        if progress is not None:
            progress(start, total)
    nr = int(counters[5])
    nl = min(int(counters[4]), max_log)
    modes, guards = meta["modes"], meta["guards"]
    events = {"t": log_t[:nl].copy(),
              "guard": [guards[f][gi] for f, gi in zip(log_from[:nl], log_guard[:nl])],
              "from": [modes[i] for i in log_from[:nl]],
              "to": [modes[i] for i in log_to[:nl]]}
    n_poinc = periods if status == 0 else max(0, int(t_stop / T) - transient)
    message = {0: "done",
               1: f"the state became non-finite at t = {t_stop:.6g} s in mode '{modes[mode]}'",
               2: f"event storm: more than {max_events_per_step} events in one step at t = {t_stop:.6g} s "
                  f"in mode '{modes[mode]}'"}[int(status)]
    result = SimulationResult(
        t=rec_t[:nr], y=rec_y[:nr], mode=rec_mode[:nr],
        poincare_t=T * (transient + 1 + np.arange(n_poinc)), poincare=poincare[:n_poinc],
        events=events, counters=dict(zip(_COUNTERS, map(int, counters))),
        state_names=list(meta["state"]), mode_names=list(modes), params=dict(model.parameters),
        period=T, steps_per_period=int(steps_per_period), final_state=y.copy(), final_mode=int(mode),
        status=int(status), message=message, length_scale=length_scale,
        settings={"periods": periods, "transient": transient, "steps_per_period": steps_per_period,
                  "event_tol": event_tol, "record_every": record_every})
    if status != 0 and raise_on_error:
        raise SimulationError(message, result)
    return result
