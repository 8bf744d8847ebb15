"""Grazing points located on period maps of their own, in a thread beside the continuation where one is free.

Locating a grazing point (bisection on the orbit's events) decides nothing
the continuation goes on with: the branch's points are the same whether and however
finely grazing points are located (``tests/test_grazing_tolerance.py``). So the location
runs on period maps of its own (a period map keeps its last run and its integrator's
work arrays, which two threads must not share; and bisecting on the continuation's maps
pushed out of its few kept maps those it needed again), and where a second CPU is free,
in a thread of its own while the continuation steps on. The kernels release the GIL while
they integrate, which is most of a location. The branch's list of special points holds a
:class:`PendingPoint` until :func:`resolve` has its result.
"""

from __future__ import annotations

from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import replace
from typing import Callable


class Locator:
    """Where special points are located: a context of their own, made on the first task, in a worker thread or
    in the caller's.

    Parameters
    ----------
    make_context : callable
        ``make_context()``: the context (its own period maps) the tasks run in.
    thread : bool
        Run the tasks in a worker thread (else at once, in :meth:`submit`).
    """

    def __init__(self, make_context: Callable, thread: bool = True):
        self._make_context = make_context
        self.context = None
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="blademodel-grazing") if thread else None

    def submit(self, task: Callable) -> Future:
        """``task(context)``, in the worker thread if there is one; else now (a Ctrl-C in it is raised again)."""
        if self._pool is not None:
            return self._pool.submit(self._run, task)
        f: Future = Future()
        try:
            f.set_result(self._run(task))
        except BaseException as e:
            f.set_exception(e)
            if not isinstance(e, Exception):
                raise
        return f

    def _run(self, task):
        if self.context is None:
            self.context = self._make_context()
        return task(self.context)

    def shutdown(self) -> None:
        """Drop the tasks not yet started; one running finishes in the worker, which then stops (not waited for)."""
        if self._pool is not None:
            self._pool.shutdown(wait=False, cancel_futures=True)


class PendingPoint:
    """A special point still to be located: its place in a branch's list of special points until it is known.

    Parameters
    ----------
    task : callable
        ``task(context)``: the located point (a dict with ``param``, ``state``, ``mode``), or a
        list of them (several grazing points within one step), in order.
    locator : Locator
    finish : callable
        ``finish(located)``: the :class:`~blademodel.orbits.branch.SpecialPoint`.
    index : int
        The branch point after which it lies.
    bracket : tuple of float, optional
        The field's values across a border collision found in the same step: where the
        located point lies between them, the border collision is placed there.
    unlocated : dict, optional
        What ``finish`` takes where the location was cut short by Ctrl-C: the first
        branch point past the grazing.
    """

    kind = "grazing"

    def __init__(self, task: Callable, locator: Locator, finish: Callable, index: int, bracket: tuple | None = None,
                 unlocated: dict | None = None):
        self.task, self.locator, self.finish, self.index, self.bracket = task, locator, finish, index, bracket
        self.unlocated = unlocated
        self.future: Future | None = None

    def start(self) -> None:
        """Begin (once the step that found it is taken): in the locator's thread, or now."""
        if self.future is None:
            # the locator holds the task until it has run; kept here too, its copies of the points around the
            # grazing (their orbits' records and Jacobians: 1.8 MB on a 24-blade ring) would stay to the branch's end
            self.future, self.task = self.locator.submit(self.task), None

    def done(self) -> bool:
        return self.future is not None and self.future.done()

    def located(self):
        """The located point, waiting for the location (or making it)."""
        self.start()
        return self.future.result()


def resolve(special: list) -> None:
    """Replace every :class:`PendingPoint` in ``special`` by its special points, in place, waiting for each.

    A border collision (or the nonsmooth fold it became) of the same step whose bracket
    holds a located point is placed at the first such: the kink of the map is that
    grazing. A location that a Ctrl-C cut short (or one pressed while waiting) leaves its
    grazing point at the first branch point past it, and the rest are not waited for.
    """
    hurry = False
    i = 0
    while i < len(special):
        q = special[i]
        if not isinstance(q, PendingPoint):
            i += 1
            continue
        located = None
        if not hurry or q.done():
            try:
                located = q.located()
            except KeyboardInterrupt:
                hurry = True
        located = [q.unlocated] if located is None else located if isinstance(located, list) else [located]
        points = [q.finish(at) for at in located]
        special[i:i + 1] = points
        i += len(points)
        inside = [p for p in points if q.bracket is not None and min(q.bracket) <= p.param <= max(q.bracket)]
        if not inside:
            continue
        point = inside[0]
        for k, r in enumerate(special):
            if all(r is not p for p in points) and not isinstance(r, PendingPoint) and r.index == q.index \
                    and r.kind in ("border-collision", "nonsmooth-fold"):
                special[k] = replace(r, param=point.param, state=point.state, mode=point.mode, bracket=point.bracket)
