"""Errors of sweeps and result files, each with the exit code the command line returns.

The messages name the file (and the other process, the address, ...) and say
what to do next, so the command line prints them as they are, without a
traceback.
"""

from __future__ import annotations


class SweepError(Exception):
    """A sweep that cannot go on; ``exit_code`` is what ``blademodel`` returns (1)."""

    exit_code = 1


class ResultFileError(SweepError, ValueError):
    """A result file that is empty, unreadable, damaged or holds another study (exit code 2)."""

    exit_code = 2


class ResultLockedError(SweepError):
    """The result file is being written by another process.

    Attributes
    ----------
    path : str
        The result file.
    owner : dict
        What the other process wrote into the lock: ``pid``, ``host``, ``started``, ``command``.
    """

    def __init__(self, message: str, *, path: str, owner: dict):
        super().__init__(message)
        self.path = path
        self.owner = owner


class WorkerLostError(SweepError):
    """A worker process of the pool died (killed, out of memory); finished points are kept."""


class SchedulerError(SweepError):
    """The Dask scheduler cannot be reached."""


class SweepInterrupted(KeyboardInterrupt):
    """Ctrl-C during a sweep; the message says what is saved and how to resume."""
