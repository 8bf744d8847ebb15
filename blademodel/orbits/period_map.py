"""The map from a state at ``t = 0`` to the state ``n`` excitation periods later, and its Jacobian."""

from __future__ import annotations

import os
import threading
import time
from dataclasses import dataclass, field

import numpy as np

from ..numeric.contract import C_EVENTS, C_LOGGED, N_COUNTERS

#: How a :class:`PeriodMap` differentiates: ``"auto"`` (the tangent where the kernel has one, else
#: differences), ``"tangent"`` (variational equations and saltation matrices, or an error),
#: ``"differences"`` (central differences of the map, ``2 n`` integrations) or ``"forward"``
#: (forward differences from ``P(y)``, ``n`` integrations more, an error of about the step).
JACOBIAN_METHODS = ("auto", "tangent", "differences", "forward")


class FlowError(RuntimeError):
    """The integration behind the period map stopped early (status and message of the kernel)."""


@dataclass
class MapRun:
    """One integration of the period map, kept so that what it computed is not computed again.

    Attributes
    ----------
    start : ndarray
        The full start state, settled (:func:`settle`).
    mode : int or ndarray
        The settled start mode.
    fired : list
        The transitions :func:`settle` fired at ``t = 0`` (as it appends them).
    end : ndarray
        The full end state.
    mode_end : int or ndarray
    t, Y : ndarray
        The orbit at every step (``Y``: physical states), ``t = 0`` included.
    states : ndarray
        The same, full states (``Y`` is a view of it).
    log : tuple
        The event log (``integrator.log_buffer``) and ``n_log`` its length.
    n_log : int
    events : int
        Events crossed.
    modes : ndarray or None
        The modes at every step: the per-contact kernel's contact modes (a row a step), the
        product-mode kernel's mode number (None where the run recorded none).
    anonymous : bool
        The contacts are all alike (a run of a map reduced by a ring's symmetry): the
        signature leaves out which contact an event was at.
    rebuild : callable or None
        For a run of a map reduced by a ring's symmetry, what rebuilds the orbit over the
        symmetry's periods from ``Y`` (:meth:`period_orbit`).
    instant : float
        Events of one cascade (s): :meth:`signature` counts a law's reset within one mode
        (an Iwan element's label) once where it repeats within this of itself
        (:data:`CASCADE_BRACKETS` of the kernel's event brackets, ``event_tol h``).
    """

    start: np.ndarray
    mode: object
    fired: list
    end: np.ndarray
    mode_end: object
    t: np.ndarray
    Y: np.ndarray
    states: np.ndarray
    log: tuple
    n_log: int
    events: int
    modes: np.ndarray | None = None
    anonymous: bool = False
    rebuild: object = None
    instant: float = 0.0
    _signature: tuple | None = field(default=None, repr=False)
    _whole: np.ndarray | None = field(default=None, repr=False)

    def period_orbit(self) -> np.ndarray:
        """The orbit at every step over the map's periods (physical states, both ends included): ``Y``, or on a map
        reduced by a ring's symmetry, the whole period rebuilt from it (once)."""
        if self.rebuild is None:
            return self.Y
        if self._whole is None:
            self._whole = self.rebuild(self.Y)
        return self._whole

    def signature(self) -> tuple:
        """The run's events as a multiset: each transition (its guard, from and to modes, and on the
        per-contact kernel its contact) as often as it occurred, in no order.

        Two orbits of a branch with equal signatures cross the same events; one whose
        signature differs has crossed a grazing (a phase that appears or vanishes adds or
        removes transitions), even where the number of events is the same (one phase that
        appears and another that vanishes). Where a switching time passes the section the
        sequence only turns round, and the multiset stays. On a map reduced by a ring's
        symmetry (``anonymous``) a switching time that passes the section of ``T / d`` hands
        an event from one contact to another, alike: there the contacts are left out.

        A transition that keeps its mode (a law's reset within one mode: the Iwan law's elements,
        whose labels change and whose contact stays ``closed``) counts once where it repeats
        within :attr:`instant` of itself: when an Iwan contact closes, the elements the motion
        loads reach their slip force within the closing's own bracket, in one event or two as
        rounding decides (the Iwan pair's branch reported 148 grazing points from 280 to 320
        rad/s, most of them such flips: 77, 76, 77 events a period at steps of `5e-5` rad/s).
        """
        if self._signature is None:   # sorted tuples: a few microseconds for the pair's dozen events
            columns = self.log[2:] if self.anonymous else self.log[1:]
            rows = list(zip(*(c[:self.n_log].tolist() for c in columns)))
            if not np.any(columns[-2][:self.n_log] == columns[-1][:self.n_log]):
                self._signature = tuple(sorted(rows))   # every transition changes its mode: nothing repeats
                return self._signature
            t = self.log[0][:self.n_log]
            last: dict = {}
            kept = []
            for k, row in enumerate(rows):
                if row[-2] == row[-1] and row in last and abs(t[k] - last[row]) <= self.instant:
                    last[row] = t[k]
                    continue
                last[row] = t[k]
                kept.append(row)
            self._signature = tuple(sorted(kept))
        return self._signature


#: The window, in the kernel's event brackets (``event_tol h``), within which a law's reset that keeps its mode and
#: repeats counts once in a run's signature (:attr:`MapRun.instant`). When an Iwan contact closes, its normal load
#: and so its elements' slip forces start from zero, and every element the motion loads slips at the closing: in
#: one event or in several located one after another, as rounding decides. Measured on the Iwan pair (the branch
#: from 280 to 320 rad/s, and 150 orbits over five stretches of 0.03 to 0.05 rad/s around its former clusters of
#: grazing points): repeats of such a reset follow each other within 2.1e-9 steps (21 brackets; 146 at most in a
#: finer scan at 288.4595 rad/s), or 1.5e-3 steps apart and more (the elements' own slips); nothing in between.
#: With a window of 2 brackets, 288.4662 and 292.3468 rad/s each had two or three grazing points within 1.5e-5
#: rad/s (flips of one repeat, 5 brackets apart or one event), and with 100, 288.4595 rad/s (54 and 146 brackets
#: at neighbouring values). 1e4 brackets (1e-6 of a step at the default ``event_tol``) lies two decades above the
#: cascades and three below the slips.
CASCADE_BRACKETS = 1e4


class PeriodMap:
    """``P(y) = `` the state ``periods`` excitation periods after ``(y, mode)`` at ``t = 0``.

    The forcing is ``T``-periodic, so the map is the same from any whole period;
    ``y`` holds the physical states only (coordinates, velocities, friction-law
    states; no energy accumulators).

    Each evaluation records the orbit at every step and logs its events
    (:meth:`run`), and the last one is kept: the tangent at the same point replays
    that run instead of integrating again, and the orbit's samples are read from it.

    Parameters
    ----------
    integrator : Integrator
        From :func:`blademodel.numeric.kernels.make_integrator` (either kernel).
    periods : int
        ``n``: the map covers ``n T``.
    jacobian : {"auto", "tangent", "differences", "forward"}
        How :meth:`jacobian` differentiates. The tangent is the derivative of the
        kernel's discrete flow, saltation matrices at the events: for the product-mode
        kernel the variational equations replayed in compiled code
        (:mod:`blademodel.numeric.tangent`), for the per-contact kernel the modes'
        step matrices and the events' saltation replayed from the record
        (:mod:`blademodel.numeric.contact_tangent`). ``"auto"`` takes it and falls back
        to central differences where it fails (an event with a zero guard rate).
        ``"forward"`` takes forward differences everywhere: half the integrations of
        central ones, the multipliers to about ``rel_step`` (``docs/orbits.md``, ``docs/frf.md``).
    workers : int, optional
        Threads that integrate the difference quotients of :meth:`differences` (each
        with its own copy of the integrator's work arrays; the kernels release the GIL):
        ``None`` or ``-1`` for every CPU this process may use, ``1`` for none; used
        where a column takes at least :attr:`thread_column_seconds`. The Jacobian is
        the same to the bit whatever the number.
    symmetry : CyclicSymmetry, optional
        A tuned ring's travelling-wave symmetry (:mod:`.cyclic`): the map is then the
        reduced one, ``G(y) = S^s Phi(0 -> T / d)(y)``, integrated over a ``d``-th of the
        period (``periods`` must be 1), its Jacobian ``S^s dPhi``; the runs are the reduced
        ones (``t``, ``Y``, ``states``, ``modes``, ``log``), with the end state and modes
        turned, and :meth:`MapRun.period_orbit` rebuilds the orbit over the symmetry's
        ``periods`` excitation periods.
        ``integrator`` may be the whole period's (the map integrates with a copy over
        ``T / d``) or that copy already (:meth:`~blademodel.orbits.cyclic.CyclicSymmetry.reduced`).
    log_size : int
        Entries of the event log a run starts with. A run that logs more is integrated
        again with room for them, and the map keeps the larger size (:attr:`log_size`).
        A continuation's maps at new values of its field start from the size their
        predecessors learned: a mistuned 24-blade ring logs about 170 events a period,
        and each first run at a new value was integrated twice.
    """

    #: A Jacobian by differences is shared among threads only where one column (two integrations) takes at
    #: least this long (s): on the pair (0.6 ms a column) a thread pool costs more than it saves.
    thread_column_seconds = 2e-3

    def __init__(self, integrator, periods: int = 1, jacobian: str = "auto", workers: int | None = None,
                 symmetry=None, log_size: int = 64):
        if int(periods) < 1:
            raise ValueError(f"periods must be a whole number >= 1, got {periods!r}")
        if jacobian not in JACOBIAN_METHODS:
            raise ValueError(f"jacobian = {jacobian!r} must be one of {', '.join(JACOBIAN_METHODS)}")
        self.workers = worker_count(workers)
        kernel = getattr(integrator, "kernel", "")
        if jacobian == "tangent" and kernel not in ("product", "contact"):
            raise ValueError(f"jacobian = 'tangent' needs one of blademodel's kernels, not {type(integrator).__name__}")
        self.integrator = integrator
        self.symmetry = symmetry
        if symmetry is not None and (int(periods) != 1 or kernel != "contact"):
            raise ValueError(f"the cyclic reduction maps one period's orbits on the per-contact kernel only, not "
                             f"periods = {periods!r} on the {kernel or type(integrator).__name__} kernel")
        self._ig = integrator if symmetry is None else symmetry.reduced(integrator)   # the one that integrates
        self.periods = int(periods)
        self.n = integrator.n_physical
        #: the friction laws' discrete states (labels only resets set): held as part of the mode, their rows and
        #: columns of every Jacobian zero (:func:`hold_discrete`)
        self.discrete = integrator.discrete_states
        #: the friction laws' other states: those a period leaves alone are held too (:func:`relaxed_law_states`)
        self.law_states = integrator.continuous_law_states
        self.evaluations = 0   # integrations of the map (each over ``periods`` excitation periods)
        self.replays = 0       # tangent replays of a kept run (no integration)
        self.method = jacobian
        self.exact = jacobian in ("auto", "tangent") and kernel in ("product", "contact")
        self._contact_tangent = None
        self._last: tuple | None = None   # (key, MapRun) of the last run
        self._log_size = max(int(log_size), 1)

    def run(self, y, mode) -> MapRun:
        """Integrate the map from ``(y, mode)``, recording every step and logging every event.

        The last run is kept and returned again for the same ``y`` and ``mode``.

        Raises
        ------
        FlowError
            If the integration stopped early.
        """
        ig = self._ig
        y = np.asarray(y, dtype=float)
        key = (y[:self.n].tobytes(), _key(mode))
        if self._last is not None and self._last[0] == key:
            return self._last[1]
        full = np.zeros(ig.n_state)
        rec = ig.record_buffer(self.periods * ig.steps_per_period + 1)
        while True:
            # settled again for each attempt: the per-contact kernel's run goes on with the marks its settling
            # left (ContactIntegrator.settle), which a run before it has cleared
            full[:] = 0.0
            full[:self.n] = y[:self.n]
            full[self.discrete] = np.rint(full[self.discrete])   # labels: whole numbers, whatever Newton made
            fired: list = []
            m0 = settle(ig, full, _copy(mode), fired)
            start = full.copy()
            counters = np.zeros(N_COUNTERS, dtype=np.int64)
            log = ig.log_buffer(self._log_size)
            status, mode_end, t = ig.advance(full, _copy(m0), 0, self.periods, n_transient=0, record=rec, log=log,
                                             counters=counters, check=False)
            if status != 0:
                raise FlowError(f"the integration stopped at t = {t:.6g} s with status {status}")
            if counters[C_LOGGED] <= self._log_size:
                break
            self._log_size = int(counters[C_LOGGED]) + 16
        self.evaluations += 1
        if self.symmetry is not None:   # G(y) = S^s Phi(y)
            full[:self.n] = self.symmetry.turned(full)
            mode_end = self.symmetry.turned_modes(mode_end)
        r = MapRun(start=start, mode=m0, fired=fired, end=full, mode_end=mode_end, t=rec[0], Y=rec[1][:, :self.n],
                   states=rec[1], log=log, n_log=int(counters[C_LOGGED]), events=int(counters[C_EVENTS]),
                   modes=rec[2] if len(rec) > 2 else None, anonymous=self.symmetry is not None,
                   rebuild=None if self.symmetry is None else self.symmetry.whole_period,
                   instant=CASCADE_BRACKETS * ig.event_tol * float(rec[0][1] - rec[0][0]))
        self._last = (key, r)
        return r

    @property
    def log_size(self) -> int:
        """The event log's entries a run starts with: at least the most any run of this map logged."""
        return self._log_size

    @property
    def last_run(self) -> MapRun | None:
        """The last run :meth:`run` made or returned again (the one it keeps)."""
        return None if self._last is None else self._last[1]

    @property
    def last_events(self) -> int:
        """The events the last run crossed (``-1`` before any)."""
        return -1 if self._last is None else self._last[1].events

    def derivatives(self, y, mode, dp=None, dperiod: float = 0.0):
        """``P(y)``, its mode, ``dP/dy`` and (with ``dp``) ``dP/dlambda`` by the tangent of the flow.

        Parameters
        ----------
        y : array_like
            Physical start state.
        mode : int or ndarray
        dp : array_like, optional
            The direction ``d p / d lambda`` in the raw parameters.
        dperiod : float
            ``d T / d lambda``.

        Returns
        -------
        FlowSensitivity
            With ``state`` the map's value (:class:`blademodel.numeric.tangent.FlowSensitivity`).

        Raises
        ------
        SensitivityError
            Where the tangent cannot follow the flow (on the per-contact kernel also
            :class:`~blademodel.numeric.contact_tangent.ContactTangentError`, a subclass, and
            for any ``dp``: its tangent is in the state only).
        """
        from ..numeric.tangent import FlowSensitivity, SensitivityError, flow_sensitivity, settle_jacobian
        ig = self._ig
        contact = ig.kernel == "contact"
        if contact and dp is not None:
            raise SensitivityError("parameter derivatives by the tangent need the product-mode kernel")
        try:
            r = self.run(y, mode)
        except FlowError as e:
            raise SensitivityError(str(e)) from None
        self.replays += 1
        if contact:
            from ..numeric.contact_tangent import ContactTangent
            if self._contact_tangent is None:
                self._contact_tangent = ContactTangent(ig)
            M = self._contact_tangent.monodromy(r.t, r.states, r.modes, r.log, r.n_log)   # or ContactTangentError
            if r.fired:
                M = M @ self._contact_tangent.settle_jacobian(*r.fired[0])
            if self.symmetry is not None:
                M = self.symmetry.jacobian(M)
            return FlowSensitivity(state=r.end[:self.n].copy(), mode=_copy(r.mode_end),
                                   monodromy=self.hold(M), parameter=None, events=r.n_log)
        s = flow_sensitivity(ig, r.start[:self.n], r.mode, self.periods, dp=dp, dperiod=dperiod,
                             run=(r.end, r.mode_end, r.log, r.n_log), record=r.states)
        if r.fired:
            D, dl = settle_jacobian(ig, r.fired, dp)
            if s.parameter is not None:
                s.parameter = s.parameter + s.monodromy @ dl
            s.monodromy = s.monodromy @ D
        s.monodromy = self.hold(s.monodromy)
        if s.parameter is not None:
            s.parameter[self.discrete] = 0.0
        return s

    def hold(self, M: np.ndarray) -> np.ndarray:
        """``M`` (a Jacobian of this map, in place) with the rows and columns of the discrete states and of the law
        states the period left alone zero (:func:`hold_discrete`, :func:`relaxed_law_states`)."""
        relaxed = relaxed_law_states(M, self.law_states) if self.law_states.size else self.law_states
        return hold_discrete(M, np.union1d(self.discrete, relaxed) if relaxed.size else self.discrete)

    def __call__(self, y, mode):
        """The state and mode ``n T`` after ``(y, mode)``; ``last_events`` holds the events the run crossed."""
        r = self.run(y, mode)
        return r.end[:self.n].copy(), _copy(r.mode_end)

    def try_derivatives(self, y, mode, dp=None, dperiod: float = 0.0):
        """:meth:`derivatives`, or None where the tangent fails and differences may stand in.

        With ``jacobian="tangent"`` a failure is not excused: it raises :class:`FlowError`.
        """
        from ..numeric.tangent import SensitivityError
        try:
            return self.derivatives(y, _copy(mode), dp, dperiod)
        except SensitivityError as e:
            if self.method == "tangent":
                raise FlowError(str(e)) from None
            return None

    def jacobian(self, y, mode, scale, rel_step: float = 1e-6) -> np.ndarray:
        """``dP/dy`` at ``(y, mode)``: the tangent of the flow, or central differences.

        With the tangent (``exact``), the derivative of the kernel's discrete flow along
        its events. Otherwise column ``i`` is a central difference with step
        ``rel_step * scale[i]``; every perturbed start keeps ``mode``, so the map is
        differentiated along the event sequence of ``(y, mode)``, which is what its
        eigenvalues describe as long as no event of the orbit is grazing (a
        perturbation of ``rel_step`` would then change the sequence).
        """
        if self.exact:
            s = self.try_derivatives(y, mode)
            if s is not None:
                return s.monodromy
        return self.differences(y, mode, scale, rel_step)

    def plain(self, y, mode):
        """``P(y)`` alone: no record, no log, nothing kept (the runs of difference quotients)."""
        Py = self._plain(self._ig, y, mode)
        self.evaluations += 1
        return Py

    def _plain(self, ig, y, mode) -> np.ndarray:
        """The map's value from ``(y, mode)`` by :func:`_plain_map` on ``ig`` (this map's integrator or a worker's
        copy), turned where the map is reduced by a symmetry."""
        Py = _plain_map(ig, self.periods, y, mode)
        return Py if self.symmetry is None else self.symmetry.turned(Py)

    def differences(self, y, mode, scale, rel_step: float = 1e-6) -> np.ndarray:
        """``dP/dy`` by differences, column ``i`` with step ``rel_step * scale[i]`` (see :meth:`jacobian`).

        Central differences (``2 n`` integrations), or forward ones from ``P(y)`` where
        the map was made with ``jacobian="forward"`` (``n``, and ``P(y)`` from the kept
        run where the residual at ``y`` was just evaluated). The columns and rows of the
        discrete states are zero (:func:`hold_discrete`), nothing integrated for them. The first column is
        timed; if it took at least :attr:`thread_column_seconds`, the others are shared
        among ``workers`` threads, each integrating with its own copy of the integrator
        (:meth:`~blademodel.numeric.integrator.Integrator.worker`). The result does not
        depend on how they were shared.
        """
        y = np.asarray(y, dtype=float)
        J = np.zeros((self.n, self.n))
        held = set(self.discrete.tolist())
        free = [i for i in range(self.n) if i not in held]
        base = self(y, mode)[0] if self.method == "forward" else None   # counted by run()
        stop = threading.Event()

        def columns(ig, cols):
            for i in cols:
                if stop.is_set():
                    return
                d = rel_step * scale[i]
                yp = y.copy()
                yp[i] += d
                if base is not None:
                    J[:, i] = (self._plain(ig, yp, mode) - base) / d
                    continue
                ym = y.copy()
                ym[i] -= d
                J[:, i] = (self._plain(ig, yp, mode) - self._plain(ig, ym, mode)) / (2.0 * d)

        t0 = time.perf_counter()
        columns(self._ig, free[:1])
        w = min(self.workers, len(free) - 1)
        if w <= 1 or time.perf_counter() - t0 < self.thread_column_seconds:
            columns(self._ig, free[1:])
        else:
            from concurrent.futures import ThreadPoolExecutor
            with ThreadPoolExecutor(max_workers=w) as pool:
                # round robin: columns of neighbouring states cost alike, so each thread gets its share
                jobs = [pool.submit(columns, self._ig.worker(), free[1 + k::w]) for k in range(w)]
                try:
                    for job in jobs:
                        job.result()   # re-raises a worker's FlowError here
                finally:
                    stop.set()   # after an error or a Ctrl-C the other threads end at their next column
        self.evaluations += len(free) if base is not None else 2 * len(free)
        return self.hold(J)


def relaxed_law_states(M: np.ndarray, law_states: np.ndarray) -> np.ndarray:
    """The friction laws' states that the period map ``M`` leaves alone: each one's row and column of ``M`` is a
    unit vector at a law state (the state itself, or on a ring's cyclic reduction the state it is turned into),
    and so is every such state's.

    A law whose contact stays open all period holds its states relaxed (a Jenkins element's stretch at 0,
    ``docs/MODEL.md``): nothing moves them and they move nothing. Their unit rows would give the map a
    multiplier 1 that no admissible perturbation has (a state open all period with a stretch is none the model
    reaches), reporting a stable orbit as unstable, and make ``dP/dy - I`` singular, so that a branch
    running into contact-free orbits stopped with "Singular matrix". Held as labels are
    (:func:`hold_discrete`), Newton's step leaves them alone and each has a multiplier zero. A law stuck all
    period is not among them: its stretch moves the blades (a family of orbits with residual stretch, whose
    multiplier 1 is real).
    """
    law = set(int(i) for i in law_states)

    def unit(v):
        nz = np.flatnonzero(v)
        return int(nz[0]) if nz.size == 1 and int(nz[0]) in law and v[nz[0]] == 1.0 else None

    targets = {i: (unit(M[i, :]), unit(M[:, i])) for i in law}
    held = {i for i, (r, c) in targets.items() if r is not None and c is not None}
    while True:   # each kept state's row and column lead to kept states only
        kept = {i for i in held if targets[i][0] in held and targets[i][1] in held}
        if kept == held:
            return np.array(sorted(held), dtype=np.int64)
        held = kept


def hold_discrete(M: np.ndarray, discrete: np.ndarray) -> np.ndarray:
    """``M`` (a period map's Jacobian, in place) with the rows and columns of the ``discrete`` states zero.

    A friction law's discrete states (:attr:`~blademodel.components.friction.base.FrictionLaw.discrete_states`)
    are labels, piecewise constant along the flow and set by resets: the map's derivative in them is not
    defined (a difference step would read as another label) and their own derivative is zero wherever it is.
    Zero rows and columns make Newton's step on ``P(y) - y`` take them to ``P``'s labels and leave the other
    unknowns alone, and give each a multiplier zero.
    """
    if discrete.size:
        M[discrete, :] = 0.0
        M[:, discrete] = 0.0
    return M


def worker_count(workers: int | None) -> int:
    """The threads ``workers`` asks for: ``None`` or ``-1`` is every CPU this process may use.

    Raises
    ------
    ValueError
        For anything but ``None``, ``-1`` or a whole number ``>= 1``.
    """
    if workers is None or (isinstance(workers, (int, np.integer)) and int(workers) == -1):
        try:
            return max(len(os.sched_getaffinity(0)), 1)
        except AttributeError:   # not on Linux
            return max(os.cpu_count() or 1, 1)
    if isinstance(workers, bool) or not isinstance(workers, (int, np.integer)) or int(workers) < 1:
        raise ValueError(f"workers = {workers!r} must be a whole number >= 1, or -1 (or None) for every CPU")
    return int(workers)


def _plain_map(ig, periods: int, y, mode) -> np.ndarray:
    """``periods`` periods of ``ig`` from ``(y, mode)`` at ``t = 0``, nothing recorded: the end state's physical part."""
    n = ig.n_physical
    full = np.zeros(ig.n_state)
    full[:n] = y
    full[ig.discrete_states] = np.rint(full[ig.discrete_states])   # labels, as in PeriodMap.run
    mode = settle(ig, full, _copy(mode))
    status, _, t = ig.advance(full, mode, 0, periods, check=False)
    if status != 0:
        raise FlowError(f"the integration stopped at t = {t:.6g} s with status {status}")
    return full[:n].copy()


def settle(integrator, y, mode, fired: list | None = None):
    """The mode ``y`` starts in: ``mode`` with every guard already past zero at ``t = 0`` fired.

    The kernels fire a guard when it *crosses* zero within a step; a start state that
    already lies past one (a section state on the far side of a stick-slip or contact
    boundary of ``mode``) would otherwise follow ``mode``'s flow. Firing it makes the
    period map continuous across the boundary, which shooting and continuation cross
    when the orbit's switching time passes the section. ``y`` may be reset in place (a
    transition's reset, the stick projection). On the product-mode kernel each transition
    fired is appended to ``fired`` as ``(mode, guard, target, state before)``; on the
    per-contact kernel (:meth:`~blademodel.numeric.contact_kernel.ContactIntegrator.settle`,
    which also solves the friction problem) one entry, ``(state before, modes before,
    events)``, where any fired.

    Raises
    ------
    FlowError
        Where the per-contact kernel's friction problem was not resolved.
    """
    if getattr(integrator, "kernel", "") == "contact":
        before, cm_before = y.copy(), np.array(mode, dtype=np.int64)
        try:
            cm, events = integrator.settle(y, mode)
        except RuntimeError as e:
            raise FlowError(str(e)) from None
        if events and fired is not None:
            fired.append((before, cm_before, events))
        return cm
    if isinstance(mode, np.ndarray) or not hasattr(integrator, "module"):
        return mode
    mod = integrator.module
    g = np.empty(mod.GUARD_DIR.shape[1] + 1)
    tmp = np.empty(y.shape[0])
    for _ in range(4):
        mod.guards(mode, 0.0, y, integrator.p, g)
        past = [i for i in range(mod.N_GUARDS[mode])
                if (mod.GUARD_DIR[mode, i] < 0 and g[i] < 0.0) or (mod.GUARD_DIR[mode, i] > 0 and g[i] > 0.0)]
        if not past:
            break
        before = y.copy()
        target = int(mod.transition(mode, past[0], 0.0, y, integrator.p, tmp))
        if fired is not None:
            fired.append((mode, past[0], target, before))
        mode = target
    return mode


def _key(mode):
    """A hashable form of a mode (an int, or the per-contact kernel's array)."""
    if isinstance(mode, (int, np.integer)):
        return (int(mode),)
    return tuple(np.atleast_1d(mode).tolist())


def kernel_mode(integrator, mode):
    """``mode`` as ``integrator`` takes it: a number on the product-mode kernel (also from a one-entry row of
    :attr:`~blademodel.orbits.branch.Branch.modes`), an array of each contact's mode on the per-contact
    kernel; ``None`` stays None.

    Raises
    ------
    ValueError
        For a row of more than one entry on the product-mode kernel (it names the value).
    """
    if mode is None or getattr(integrator, "kernel", "") == "contact" or isinstance(mode, (int, np.integer)):
        return mode
    row = np.atleast_1d(np.asarray(mode))
    if row.size != 1 or not np.issubdtype(row.dtype, np.integer):
        raise ValueError(f"mode = {mode!r}: the product-mode kernel takes one mode number (or a row of Branch.modes "
                         f"with one entry)")
    return int(row[0])


def _copy(mode):
    """A mode the kernel may update in place (the per-contact kernel's is an array)."""
    return mode.copy() if isinstance(mode, np.ndarray) else mode
