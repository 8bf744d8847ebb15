"""Grazing points located on period maps of their own, in a thread beside the continuation where one is free.

Locating a grazing point (bisection on the number of events per orbit) decides nothing
the continuation goes on with: the branch's points are the same whether and however
finely grazing points are located (``tests/test_grazing_tolerance.py``). So the location
runs on period maps of its own (a period map keeps its last run and its integrator's
work arrays, which two threads must not share, and bisecting on the continuation's maps
pushed out of its few kept maps those it needed again), and where a second CPU is free,
in a thread of its own while the continuation steps on. The kernels release the GIL while
they integrate, which is most of a location. The branch's list of special points holds a
:class:`PendingPoint` until :func:`resolve` has its result.
"""

from __future__ import annotations

from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import replace
from typing import Callable


class _Later:
    """A task run where its result is first asked for (the part of a :class:`Future` that is used here)."""

    def __init__(self, run: Callable):
        self._run, self._done, self._value = run, False, None

    def result(self):
        if not self._done:
            self._value, self._done = self._run(), True
        return self._value


class Locator:
    """Where special points are located: a context of their own, made on the first task, in a worker thread or
    in the caller's.

    Parameters
    ----------
    make_context : callable
        ``make_context()``: the context (its own period maps) the tasks run in.
    thread : bool
        Run each task in a worker thread from :meth:`submit` on (else in the caller's
        thread, where its result is first asked for).
    """

    def __init__(self, make_context: Callable, thread: bool = True):
        self._make_context = make_context
        self.context = None
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="blademodel-grazing") if thread else None

    def submit(self, task: Callable):
        """``task(context)``: a :class:`Future`, or (without a thread) a result computed when asked for."""
        if self._pool is not None:
            return self._pool.submit(self._run, task)
        return _Later(lambda: self._run(task))

    def _run(self, task):
        if self.context is None:
            self.context = self._make_context()
        return task(self.context)

    def shutdown(self) -> None:
        """Stop the worker once its tasks are done (a task not yet started is dropped)."""
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)


class PendingPoint:
    """A special point still to be located: its place in a branch's list of special points until it is known.

    Parameters
    ----------
    task : callable
        ``task(context)``: the located point (a dict with ``param``, ``state``, ``mode``).
    locator : Locator
    finish : callable
        ``finish(located)``: the :class:`~blademodel.orbits.arclength.SpecialPoint`.
    index : int
        The branch point after which it lies.
    bracket : tuple of float, optional
        The field's values across a border collision found in the same step: where the
        located point lies between them, the border collision is placed there.
    """

    kind = "grazing"

    def __init__(self, task: Callable, locator: Locator, finish: Callable, index: int, bracket: tuple | None = None):
        self.task, self.locator, self.finish, self.index, self.bracket = task, locator, finish, index, bracket
        self.future: Future | _Later | None = None

    def start(self) -> None:
        """Begin (once the step that found it is taken): in the locator's thread if it has one."""
        if self.future is None:
            self.future = self.locator.submit(self.task)

    def result(self):
        """The special point, waiting for (or making) the location."""
        self.start()
        return self.finish(self.future.result())


def resolve(special: list) -> None:
    """Replace every :class:`PendingPoint` in ``special`` by its special point, in place.

    A border collision (or the nonsmooth fold it became) of the same step whose bracket
    holds the located point is placed at it: the kink of the map is that grazing.
    """
    for i, q in enumerate(special):
        if not isinstance(q, PendingPoint):
            continue
        point = q.result()
        special[i] = point
        if q.bracket is None or not min(q.bracket) <= point.param <= max(q.bracket):
            continue
        for k, r in enumerate(special):
            if r is not point and not isinstance(r, PendingPoint) and r.index == q.index \
                    and r.kind in ("border-collision", "nonsmooth-fold"):
                special[k] = replace(r, param=point.param, state=point.state, mode=point.mode)
