"""Run a model: the Python entry point of the hybrid solver."""

from __future__ import annotations


import warnings

import numpy as np

from ..model import Model
from .contract import (C_LOGGED, C_RECORDS, COUNTER_NAMES, N_COUNTERS, N_STATS, S_MAX_CONE_RATIO, STAT_NAMES,
                       STATUS_EVENT_STORM, STATUS_FRICTION_UNRESOLVED, STATUS_NONFINITE, STATUS_OK)
from .integrator import HybridIntegrator, excitation_period  # noqa: F401  (re-exported)
from .kernels import make_integrator
from .limits import check_run_length
from .result import Counters, SimulationError, SimulationResult


def simulate(model: Model, *, periods: int = 1, transient: int = 0, steps_per_period: int = 1000,
             event_tol: float = 1e-10, record_every: int = 1, max_events_per_step: int = 100,
             max_log: int = 200_000, energy: bool = False, y0=None, period: float | None = None,
             check_stability: bool = True, raise_on_error: bool = True,
             length_scale: float | None = None, progress=None, chunk_periods: int = 50,
             mode0=None, kernel: str = "auto", record_forces: bool = True,
             detect_grazing: bool = True, event_location: str | None = None,
             method: str = "rk4", local_events: bool = True) -> SimulationResult:
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
    mode0 : int or array of int, optional
        Initial mode (per-contact kernel: one mode per contact); by default it
        follows from ``y0`` (every contact with ``delta >= 0`` closed, the friction
        law choosing how).
    kernel : {"auto", "product", "contact"}
        See :func:`blademodel.numeric.kernels.choose_kernel`.
    record_forces : bool
        Per-contact kernel: record each contact's normal and friction force with
        every record (``result.contacts["N"]``, ``["f"]``).
    detect_grazing : bool
        Per-contact kernel: locate a contact entered (or left) and left again within
        one step, which neither end of the step shows (``docs/solver.md``; counter
        ``grazing_events``). The product-mode kernel (the pair's default) does not
        look for them: pass ``kernel="contact"``.
    method : {"rk4", "rk8"}
        Stepping method: classical RK4 or an eighth-order Runge-Kutta method
        (:mod:`~blademodel.numeric.methods`), both through the same event location.
    local_events : bool
        Per-contact kernel: step each cluster of coupled contacts through its events
        on its own (the default); ``False`` splits every coordinate's step at every
        event, for comparison (``docs/solver.md``).
    event_location : {"bisection", "predicted"}, optional
        How events are bracketed; by default bisection on the product-mode kernel
        (the pair's published results, bit for bit) and predicted roots on the
        per-contact kernel (``docs/solver.md``).

    Returns
    -------
    SimulationResult

    Raises
    ------
    ValueError
        For a bad setting, before anything is compiled; a run longer than
        :data:`~blademodel.numeric.limits.MAX_STEPS` steps or keeping more than
        :func:`~blademodel.numeric.limits.max_record_bytes` is a
        :class:`~blademodel.numeric.limits.RunTooLargeError`.
    SimulationError
        If the run fails and ``raise_on_error`` is set.
    """
    check_run_length(model, periods=periods, transient=transient, steps_per_period=steps_per_period,
                     record_every=record_every, energy=energy)
    periods, transient, record_every = int(periods), int(transient), int(record_every)
    integ = make_integrator(model, kernel=kernel, steps_per_period=steps_per_period, event_tol=event_tol,
                            max_events_per_step=max_events_per_step, energy=energy, period=period,
                            check_stability=check_stability, method=method, detect_grazing=detect_grazing,
                            event_location=event_location, local_events=local_events)
    per_contact = integ.kernel == "contact"
    T, n, meta = integ.period, integ.n_state, integ.meta
    y = integ.initial_state(y0)
    if mode0 is None:
        mode = integ.mode_of(y)
    else:
        mode = np.asarray(mode0, dtype=np.int64) if per_contact else int(mode0)

    n_rec = (periods * steps_per_period) // record_every + 1
    rec_t = np.empty(n_rec)
    rec_y = np.empty((n_rec, n))
    nc = len(model.contacts)
    rec_mode = np.empty((n_rec, nc), dtype=np.int8) if per_contact else np.empty(n_rec, dtype=np.int64)
    forces = (np.empty((n_rec, nc)), np.empty((n_rec, nc))) if per_contact and record_forces else None
    poincare = np.empty((periods, n))
    log = integ.log_buffer(max_log)
    counters = np.zeros(N_COUNTERS, dtype=np.int64)
    stats = np.zeros(N_STATS)
    extra = {"forces": forces, "stats": stats} if per_contact else {}
    total = transient + periods
    step = total if progress is None else max(1, int(chunk_periods))
    start, status, t_stop = 0, 0, 0.0
    while start < total and status == 0:
        end = min(total, start + step)
        status, mode, t_stop = integ.advance(y, mode, start, end, n_transient=transient,
                                             record=(rec_t, rec_y, rec_mode), poincare=poincare,
                                             log=log, counters=counters, record_every=record_every, **extra)
        start = end
        if progress is not None:
            progress(start, total)
    nr = int(counters[C_RECORDS])
    nl = min(int(counters[C_LOGGED]), max_log)
    events = integ.named_events(log, nl)
    labels, mode_idx, final_idx = integ.mode_table(rec_mode[:nr], mode)
    mode_label = labels[final_idx]
    contact = None
    if per_contact:
        contact = {"names": list(meta["contacts"]), "modes": rec_mode[:nr],
                   "mode_names": [list(m) for m in meta["contact_modes"]]}
        if forces is not None:
            contact.update(N=forces[0][:nr], f=forces[1][:nr])
    n_poinc = periods if status == 0 else max(0, int(t_stop / T) - transient)
    where = f"at t = {t_stop:.6g} s in mode '{mode_label}'"
    message = {STATUS_OK: "done",
               STATUS_NONFINITE: f"the state became non-finite {where}",
               STATUS_EVENT_STORM: f"event storm: more than {max_events_per_step} events in one step {where}",
               STATUS_FRICTION_UNRESOLVED: f"the friction problem of an event was not resolved {where}"
               }[int(status)]
    counter_dict = Counters(zip(COUNTER_NAMES, map(int, counters)))
    if per_contact:
        counter_dict.update(dict(zip(STAT_NAMES, map(float, stats))))
        if stats[S_MAX_CONE_RATIO] > 1 + 1e-9:
            warnings.warn(f"a sticking contact carried {stats[S_MAX_CONE_RATIO]:.12g} times its slip force "
                          f"(max_cone_ratio > 1 + 1e-9): Coulomb's law was exceeded", RuntimeWarning, stacklevel=2)
    result = SimulationResult(
        t=rec_t[:nr], y=rec_y[:nr], mode=mode_idx,
        poincare_t=T * (transient + 1 + np.arange(n_poinc)), poincare=poincare[:n_poinc],
        events=events, counters=counter_dict,
        state_names=list(meta["state"]), mode_names=labels, params=dict(model.parameters),
        period=T, steps_per_period=int(steps_per_period), final_state=y.copy(), final_mode=final_idx,
        status=int(status), message=message, length_scale=length_scale,
        settings={"periods": periods, "transient": transient, "steps_per_period": steps_per_period,
                  "event_tol": event_tol, "record_every": record_every,
                  "kernel": integ.kernel, "detect_grazing": getattr(integ, "detect_grazing", False),
                  "local_events": getattr(integ, "local_events", False),
                  "event_location": integ.event_location, "method": method},
        contacts=contact, final_contact_modes=np.asarray(mode).copy() if per_contact else None)
    if status != 0 and raise_on_error:
        raise SimulationError(message, result)
    return result
