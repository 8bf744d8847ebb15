"""Time-mean square of displacements over a run, streamed in chunks of periods."""

from __future__ import annotations

import dataclasses

import numpy as np

from ..model import Model
from .contract import C_RECORDS, N_COUNTERS
from .kernels import make_integrator
from .limits import reference_chunk_periods


def without_contacts(model: Model) -> Model:
    """The same model with every contact removed (the reference system of ``P_d``)."""
    return dataclasses.replace(model, contacts=(), name=f"{model.name}_free")


def mean_square_run(model: Model, *, transient: int, periods: int, steps_per_period: int,
                    event_tol: float = 1e-10, names=None, chunk_periods: int = 50) -> float:
    """Mean of the sum of squares of ``names`` over ``periods`` periods after ``transient``.

    The run starts from rest. States are recorded at every step but only
    ``chunk_periods`` periods at a time, so memory does not grow with the run.

    Parameters
    ----------
    model : Model
    transient, periods, steps_per_period : int
    event_tol : float
    names : sequence of str, optional
        States summed; default: the first mass's coordinates (``x1``, ``y1``).
    chunk_periods : int
        Periods per recording chunk (fewer if a chunk's records would exceed
        :func:`~blademodel.numeric.limits.max_record_bytes`).

    Returns
    -------
    float
        The same value :func:`blademodel.analysis.reduction.mean_square` gives on
        records of the whole window.
    """
    integ = make_integrator(model, steps_per_period=steps_per_period, event_tol=event_tol)
    chunk_periods = reference_chunk_periods(integ.steps_per_period, integ.n_state, chunk_periods)
    names = list(names) if names is not None else list(model.masses[0].coordinates)
    cols = [integ.state_names.index(n) for n in names]
    S = integ.steps_per_period
    y = integ.initial_state()
    mode = integ.mode_of(y)
    status, mode, _ = integ.advance(y, mode, 0, transient)
    n = chunk_periods * S + 1
    rec = integ.record_buffer(n)
    total, count, start = 0.0, 0, transient
    while start < transient + periods and not status:
        end = min(transient + periods, start + chunk_periods)
        counters = np.zeros(N_COUNTERS, dtype=np.int64)
        status, mode, _ = integ.advance(y, mode, start, end, n_transient=transient, record=rec,
                                        counters=counters)
        k = int(counters[C_RECORDS])
        first = 1 if start == transient else 0  # the window's opening sample is left out
        total += float(np.sum(rec[1][first:k][:, cols] ** 2))
        count += k - first
        start = end
    if status:
        raise RuntimeError(f"the run of {model.name} failed (status {status})")
    return total / count
