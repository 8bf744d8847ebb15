"""Pool workers that never outlive the sweep that started them.

:func:`init_worker` runs first in every pool worker: it leaves Ctrl-C to the
parent (which stops the pool and says how to resume) and ties the worker's life
to its parent's. On Linux the kernel kills the worker when the parent dies
(``prctl(PR_SET_PDEATHSIG, SIGKILL)``), even in the middle of a compiled
kernel; everywhere a daemon thread also watches the parent id and exits the
worker when it changes (the portable fallback, and the guard against the
parent dying before ``prctl`` took effect).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import signal
import sys
import threading
import time

#: ``PR_SET_PDEATHSIG`` of ``<linux/prctl.h>``.
PR_SET_PDEATHSIG = 1
#: Seconds between two looks of the watchdog at the parent id.
WATCH_INTERVAL = 0.5


def _set_parent_death_signal(sig: int) -> bool:
    """Ask Linux to send ``sig`` to this process when its parent dies; False where unavailable."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        return libc.prctl(PR_SET_PDEATHSIG, int(sig), 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def _watch_parent(parent: int) -> None:
    while True:
        if os.getppid() != parent:
            os._exit(1)
        time.sleep(WATCH_INTERVAL)


def init_worker(parent: int) -> None:
    """Initializer of pool workers: ignore SIGINT and exit when process ``parent`` dies.

    Parameters
    ----------
    parent : int
        Process id of the sweep (the pool's owner).
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _set_parent_death_signal(signal.SIGKILL)
    if os.getppid() != parent:   # the parent died before the death signal was set
        os._exit(1)
    threading.Thread(target=_watch_parent, args=(parent,), daemon=True, name="parent-watchdog").start()
