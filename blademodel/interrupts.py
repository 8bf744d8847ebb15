"""Ctrl-C and SIGTERM as :class:`KeyboardInterrupt`, and never lost.

Python raises the exception of a signal wherever the main thread happens to be. Raised
inside compiled code that calls back into Python, it can be swallowed: measured on this
project, a Ctrl-C that landed in netCDF4's writing of a result file, or in a callback of
llvmlite while a kernel was compiled, was lost, and the sweep or continuation went on to
its end (1 in about 15 signals sent at random times). So, while :func:`handled` is in
force (the command line, for every command):

* each SIGINT or SIGTERM is counted, then raised as :class:`KeyboardInterrupt`;
* long runs call :func:`check` between units of work (after each sweep point or branch
  point): a signal counted but not yet :func:`acknowledge`-d is raised again there;
* files are written inside :func:`deferred`: a signal that arrives meanwhile is raised
  once the file is complete;
* whoever handles the interrupt (saves what was computed, says how to resume) calls
  :func:`acknowledge` first.

Without :func:`handled` (a notebook, a program of its own) :func:`check`, :func:`deferred`
and :func:`acknowledge` change nothing: Python's own handler stays in place.
"""

from __future__ import annotations

import signal
from contextlib import contextmanager

_count = 0        # signals received while handled
_seen = 0         # of which acknowledged (or raised again by check)
_deferring = 0    # depth of deferred blocks


def _handler(signum, frame):
    global _count
    _count += 1
    if not _deferring:
        raise KeyboardInterrupt


@contextmanager
def handled():
    """Within: SIGINT and SIGTERM counted and raised as :class:`KeyboardInterrupt` (see the module).

    A signal that is ignored when the block starts stays ignored (a shell starts background
    jobs with SIGINT ignored), and so does every signal off the main thread, where Python
    cannot set handlers.
    """
    global _count, _seen
    replaced = {}
    try:
        for sig in (signal.SIGINT, signal.SIGTERM):
            if signal.getsignal(sig) in (signal.default_int_handler, signal.SIG_DFL):
                replaced[sig] = signal.signal(sig, _handler)
    except ValueError:   # not the main thread
        pass
    try:
        yield
    finally:
        for sig, before in replaced.items():
            signal.signal(sig, before)
        _count = _seen = 0


def acknowledge() -> None:
    """The signals so far are being handled: :func:`check` and :func:`deferred` do not raise them again."""
    global _seen
    _seen = _count


def check() -> None:
    """Raise :class:`KeyboardInterrupt` if a signal came that was not acknowledged (its exception was lost)."""
    if _count > _seen:
        acknowledge()
        raise KeyboardInterrupt


@contextmanager
def deferred():
    """Within: a signal is counted but not raised; it is raised when the (outermost) block ends."""
    global _deferring
    _deferring += 1
    try:
        yield
    finally:
        _deferring -= 1
    if not _deferring:
        check()
