"""Where sweep points run: in this process, in a process pool, or on a Dask cluster.

Every executor yields ``(index, output)`` as points finish, in any order; the
caller writes them. Points start from rest and are deterministic, so the three
give bit-identical results.
"""

from __future__ import annotations

import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import Callable, Iterator

from .point import run_point

Task = tuple[int, dict, dict, dict]  # index, base, overrides, run


def serial(tasks: list[Task]) -> Iterator[tuple[int, dict]]:
    """Run points one after the other in this process."""
    for i, base, over, run in tasks:
        yield i, run_point(base, over, run)


def processes(tasks: list[Task], workers: int | None = None) -> Iterator[tuple[int, dict]]:
    """Run points in a pool of ``workers`` processes (default: all cores)."""
    workers = workers or os.cpu_count() or 1
    ctx = multiprocessing.get_context("fork" if hasattr(os, "fork") else "spawn")
    with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
        futures = {pool.submit(run_point, base, over, run): i for i, base, over, run in tasks}
        for f in as_completed(futures):
            yield futures[f], f.result()


def dask(tasks: list[Task], address: str) -> Iterator[tuple[int, dict]]:
    """Run points on the Dask distributed scheduler at ``address``.

    The workers need blademodel installed; each compiles (or loads from its cache)
    the kernel once.
    """
    try:
        from distributed import Client, as_completed as dask_completed
    except ImportError:
        raise ValueError("--scheduler needs Dask: pip install 'blademodel[dask]'") from None
    with Client(address) as client:
        futures = {}
        for i, base, over, run in tasks:
            futures[client.submit(run_point, base, over, run, pure=False)] = i
        for f in dask_completed(list(futures)):
            yield futures[f], f.result()


def choose(workers: int | None, scheduler: str | None) -> Callable[[list[Task]], Iterator[tuple[int, dict]]]:
    """The executor for the given options (``workers=1`` is serial)."""
    if scheduler:
        return lambda tasks: dask(tasks, scheduler)
    if workers == 1:
        return serial
    return lambda tasks: processes(tasks, workers)
