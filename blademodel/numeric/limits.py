"""Limits of a run's length and memory, checked before anything is compiled or allocated.

Two limits, both with a reason:

* **Steps.** A run takes at most :data:`MAX_STEPS` ``= 2**53`` RK4 steps in all,
  ``(transient + periods) * steps_per_period``: step counts and times stay exact
  in float64 and fit the kernels' int64 counters (a larger count used to reach the
  compiler as an integer it cannot type).
* **Memory.** What a run keeps — the recorded states (every ``record_every``-th
  step of the recorded periods), the Poincare samples and, with ``P_d``, one
  chunk of the reference run — must fit in :func:`max_record_bytes` (2 GiB by
  default; ``$BLADEMODEL_MAX_RECORD_BYTES`` changes it). A larger request used to
  fail on allocation, with a ``MemoryError`` traceback, after the kernel was built.

Both checks name the settings and say which way to change them.
"""

from __future__ import annotations

import math
import numbers
import os

#: Most RK4 steps of one run, ``(transient + periods) * steps_per_period``.
MAX_STEPS = 2 ** 53

#: Default of :func:`max_record_bytes`: 2 GiB.
DEFAULT_MAX_RECORD_BYTES = 2 * 1024 ** 3

#: Environment variable overriding :data:`DEFAULT_MAX_RECORD_BYTES` (a number of bytes).
RECORD_BYTES_ENV = "BLADEMODEL_MAX_RECORD_BYTES"


class RunTooLargeError(ValueError):
    """A run that exceeds :data:`MAX_STEPS` or the record memory of :func:`max_record_bytes`."""


def max_record_bytes() -> int:
    """The memory a run may keep, in bytes: ``$BLADEMODEL_MAX_RECORD_BYTES`` or 2 GiB.

    Raises
    ------
    ValueError
        If the environment variable is set but is not a positive number.
    """
    text = os.environ.get(RECORD_BYTES_ENV)
    if text is None or not text.strip():
        return DEFAULT_MAX_RECORD_BYTES
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{RECORD_BYTES_ENV} = {text!r} must be a positive number of bytes")
    return int(value)


def check_integer(name: str, value, lo: int) -> int:
    """``value`` as an int if it is a whole number ``>= lo`` (not a bool), else ``ValueError``."""
    ok = isinstance(value, numbers.Integral) and not isinstance(value, bool)
    if not ok and isinstance(value, float) and math.isfinite(value) and value.is_integer():
        ok = True
    if not ok or value < lo:
        raise ValueError(f"{name} = {value!r} must be an integer >= {lo}")
    return int(value)


def _size(n_bytes: float) -> str:
    for unit, size in (("TiB", 1024 ** 4), ("GiB", 1024 ** 3), ("MiB", 1024 ** 2), ("KiB", 1024)):
        if n_bytes >= size:
            return f"{n_bytes / size:.3g} {unit}"
    return f"{int(n_bytes)} B"


def run_state_size(model) -> int:
    """Length of the state vector of ``model``: positions, velocities and friction-law states."""
    return 2 * len(model.coordinates) + sum(len(c.friction.states) for c in model.contacts)


def record_bytes(periods: int, steps_per_period: int, record_every: int, n_state: int, n_contacts: int) -> int:
    """Bytes kept by a run: the records (time, state, modes, contact forces) and the Poincare samples."""
    n_records = periods * steps_per_period // record_every + 1
    per_record = 8 * (1 + n_state) + 8 + 16 * n_contacts
    return n_records * per_record + periods * 8 * n_state


def check_run_length(model, *, periods: int, transient: int, steps_per_period: int, record_every: int = 1,
                     reference: bool = False, energy: bool = False) -> None:
    """Refuse, before anything is compiled or allocated, a run too long to count or too large to keep.

    Parameters
    ----------
    model : Model
    periods, transient, steps_per_period, record_every : int
        As in :func:`~blademodel.numeric.simulate.simulate`.
    reference : bool
        Also check the reference run of ``P_d`` (the model without contacts,
        recorded at every step, at least one period at a time).
    energy : bool
        The run integrates the three energy accumulators too.

    Raises
    ------
    ValueError
        For a setting that is not a whole number in range.
    RunTooLargeError
        Beyond :data:`MAX_STEPS`, or beyond :func:`max_record_bytes`; the message
        names the settings and the limit.
    """
    periods = check_integer("periods", periods, 1)
    transient = check_integer("transient", transient, 0)
    steps_per_period = check_integer("steps_per_period", steps_per_period, 1)
    record_every = check_integer("record_every", record_every, 1)
    settings = (f"transient = {transient}, periods = {periods}, steps_per_period = {steps_per_period}")
    steps = (transient + periods) * steps_per_period
    if steps > MAX_STEPS:
        raise RunTooLargeError(
            f"{settings}: {steps:.3g} RK4 steps in all, more than a run takes (2**53 = {MAX_STEPS:.3g}, "
            f"so that step counts and times stay exact); use fewer periods or steps per period")
    limit = max_record_bytes()
    n_state = run_state_size(model) + (3 if energy else 0)
    need = record_bytes(periods, steps_per_period, record_every, n_state, len(model.contacts))
    if need > limit:
        per = need / max(periods * steps_per_period // record_every, 1)
        every = math.ceil(periods * steps_per_period * per / limit)
        raise RunTooLargeError(
            f"{settings}, record_every = {record_every}: the run would keep "
            f"{periods * steps_per_period // record_every + 1} records of {n_state} states "
            f"({_size(need)}), more than the limit of {_size(limit)} (${RECORD_BYTES_ENV}); "
            f"record every {every} steps or more, or record fewer periods")
    if reference:
        n_free = 2 * len(model.coordinates)
        one = record_bytes(1, steps_per_period, 1, n_free, 0)
        if one > limit:
            raise RunTooLargeError(
                f"steps_per_period = {steps_per_period}: one period of the P_d reference run, recorded at every "
                f"step, needs {_size(one)}, more than the limit of {_size(limit)} (${RECORD_BYTES_ENV}); "
                f"use fewer steps per period")


def reference_chunk_periods(steps_per_period: int, n_state: int, chunk_periods: int) -> int:
    """Periods per chunk of a reference run: ``chunk_periods``, fewer if that would exceed the memory limit."""
    fit = max_record_bytes() // max(record_bytes(1, steps_per_period, 1, n_state, 0), 1)
    return max(1, min(int(chunk_periods), int(fit)))
