"""Where sweep points run: in this process, in a process pool, or on a Dask cluster.

Every executor yields ``(index, output)`` as points finish, in any order; the
caller writes them. Points start from rest and are deterministic, so the three
give bit-identical results.

Pool workers die with the sweep (:mod:`blademodel.sweep.workers`); when the
caller stops early (Ctrl-C, an error) the pool's workers are killed at once
rather than left to finish their points; a worker that dies makes the sweep
stop with :class:`~blademodel.sweep.errors.WorkerLostError` (the finished points
are kept, a re-run resumes).
"""

from __future__ import annotations

import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from typing import Callable, Iterator

from .errors import SchedulerError, WorkerLostError
from .point import run_point
from .workers import init_worker

Task = tuple[int, dict, dict, dict]  # index, base, overrides, run


def serial(tasks: list[Task]) -> Iterator[tuple[int, dict]]:
    """Run points one after the other in this process."""
    for i, base, over, run in tasks:
        yield i, run_point(base, over, run)


def _kill_workers(pool: ProcessPoolExecutor) -> None:
    """Kill the pool's worker processes now (a point in progress is abandoned)."""
    kill = getattr(pool, "kill_workers", None)   # Python 3.14+
    if kill is not None:
        kill()
        return
    for proc in list((getattr(pool, "_processes", None) or {}).values()):
        try:
            proc.kill()
        except (OSError, ValueError, AttributeError):
            pass


def processes(tasks: list[Task], workers: int | None = None) -> Iterator[tuple[int, dict]]:
    """Run points in a pool of ``workers`` processes (default: all cores).

    Raises
    ------
    WorkerLostError
        If a worker process dies (killed from outside, out of memory).
    """
    workers = workers or os.cpu_count() or 1
    ctx = multiprocessing.get_context("fork" if hasattr(os, "fork") else "spawn")
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=init_worker,
                               initargs=(os.getpid(),))
    finished = False
    try:
        futures = {pool.submit(run_point, base, over, run): i for i, base, over, run in tasks}
        for f in as_completed(futures):
            try:
                result = f.result()
            except BrokenProcessPool:
                raise WorkerLostError("a worker process of the sweep died (killed from outside, or out of "
                                      "memory?); the finished points are saved, run the sweep again to "
                                      "resume") from None
            yield futures[f], result
        finished = True
    finally:
        if not finished:   # Ctrl-C, an error, or the caller stopped early: stop the work now
            _kill_workers(pool)
        pool.shutdown(wait=True, cancel_futures=True)


def dask(tasks: list[Task], address: str) -> Iterator[tuple[int, dict]]:
    """Run points on the Dask distributed scheduler at ``address``.

    The workers need blademodel installed; each compiles (or loads from its cache)
    the kernel once.

    Raises
    ------
    SchedulerError
        If the scheduler cannot be reached (within Dask's connect timeout,
        ``distributed.comm.timeouts.connect``).
    ValueError
        If ``address`` is not an address.
    """
    try:
        from distributed import Client, as_completed as dask_completed
    except ImportError:
        raise ValueError("--scheduler needs Dask: pip install 'blademodel[dask]'") from None
    try:
        client = Client(address)
    except (OSError, TimeoutError) as e:
        why = str(e).splitlines()[0] if str(e) else type(e).__name__
        raise SchedulerError(f"cannot reach the Dask scheduler at {address} ({why}); check the address and "
                             f"that the scheduler is running") from None
    except (ValueError, TypeError) as e:
        raise ValueError(f"--scheduler {address!r} is not a scheduler address: {e}") from None
    with client:
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
