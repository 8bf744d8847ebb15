"""A branch's next point: its prediction, its correction, and the bifurcations and grazing points between two points.

The context of one branch (:class:`_Context`: its period maps, scaling and tolerances)
predicts a point from the last ones, corrects it (Broyden's method from the predicted
Jacobian, then Newton's, the arclength condition exact), takes the Jacobian at the
corrected point, and compares two points: a change in the multipliers outside the unit
circle is located by regula falsi and classified (fold, branch point, period doubling,
Neimark-Sacker, border collision), a change in the orbit's events (a grazing) by
bisection at fixed values of the field.
"""


from __future__ import annotations

import math

import numpy as np

from ..analysis.spectrum import dft_bin
from .background import Locator, PendingPoint
from .branch import SpecialPoint
from .family import _Family
from .period_map import FlowError, _copy, _key
from .shooting import ROUNDING_LEVEL, ShootingError, _same, _shoot, residual_size, scaled_residual


def _turns(p, q, T_p=None) -> bool:
    """Whether the branch turns back in the field between its points ``p`` and ``q``: the field components of
    their tangents (``T_p``, where known, else from ``p``'s Jacobian) have opposite signs.

    A multiplier through ``+1`` is a **fold** where the branch turns, and a **branch
    point** where it goes on: another branch crosses it there (a tuned ring's
    travelling waves meet orbits that break their symmetry, the blades' amplitudes
    differing), and the map's Jacobian along the branch, ``[A; t]``, is singular without
    the field's component of ``t`` vanishing.
    """
    if T_p is None:
        T_p = _tangent(p["A"], np.append(np.zeros(p["A"].shape[0]), 1.0))
    T_q = _tangent(q["A"], T_p)
    return float(T_p[-1]) * float(T_q[-1]) < 0.0


def _chord(p, q) -> float:
    """The distance from ``p`` to ``q``."""
    d = q - p
    return math.sqrt(float(np.dot(d, d)))


def _end_tangent(points, chords=None):
    """The unit tangent at the last of ``points`` of the polynomial through them in their chord length (None where two
    coincide): the derivative of its Lagrange form there. ``chords``: the distances between successive points, where
    known (:func:`_chord`)."""
    if chords is None:
        chords = [_chord(p, q) for p, q in zip(points[:-1], points[1:])]
    s = [0.0]
    for c in chords:
        s.append(s[-1] + c)
    s = [v - s[-1] for v in s]
    if any(b <= a for a, b in zip(s[:-1], s[1:])):
        return None
    # the Lagrange basis' derivatives at the last point, s = 0: for the others only the product without (s - 0)
    # survives; the last one's is -sum(1 / s_j)
    weights = [math.prod(-v for k, v in enumerate(s[:-1]) if k != i)
               / math.prod(si - v for k, v in enumerate(s) if k != i) for i, si in enumerate(s[:-1])]
    weights.append(-sum(1.0 / v for v in s[:-1]))
    t = np.dot(weights, points)
    return t / math.sqrt(float(np.dot(t, t)))


def _tangent(A, previous):
    """The unit null vector of ``A`` (``n x (n + 1)``) pointing the way of ``previous``."""
    M = np.vstack([A, previous])
    rhs = np.zeros(A.shape[0] + 1)
    rhs[-1] = 1.0
    t = np.linalg.solve(M, rhs)
    t /= np.linalg.norm(t)
    return t if np.dot(t, previous) >= 0 else -t


#: The branch points that keep their orbit's record (``"Y"``, every step of the period: 72 kB on the pair, 0.77 MB on
#: the 24-blade ring): the last ones. Older points drop it (:meth:`_Context.orbit` makes it again where asked), so that a
#: branch's memory does not grow with its points by the orbit's size.
KEPT_ORBITS = 2
#: The branch points that keep their monodromy matrix (``"J"``, physical units, beside the scaled Jacobian ``"A"`` that
#: every point keeps): the last ones, whose matrices the predictor extrapolates. Older points drop it
#: (:meth:`_Context.monodromy` rebuilds it from ``"A"`` where a branch goes back to them), halving what a point keeps of
#: its Jacobians: ``n (n + 1)`` numbers, 1.2 MB on a 96-blade ring.
KEPT_JACOBIANS = 3
#: :meth:`_Context.column_rule` takes a Jacobian's field column from the tangent of the branch's last points where
#: that tangent's estimated error, relative to its field component, is at most this (else a difference quotient).
COLUMN_ACCURACY = 1e-2
#: Halvings of a correction step whose residual did not fall, before the step is taken as it is.
MAX_HALVINGS = 4
#: Corrections in a row that do not halve the best residual, after which a correction gives up.
STALL = 5
#: A trial of the grazing bisection is solved to this fraction of the bracket's width (scaled residual).
TRIAL_ACCURACY = 1e-4
#: A stability change is a border collision (a multiplier jumps across the unit circle at a kink of the map)
#: once its bracket has shrunk to JUMP_NARROWING of its first width (JUMP_NARROWING_FAILED where a trial
#: inside it failed, as trials beside a kink do) while the crossing multiplier's modulus still differs
#: between the ends by at least JUMP_KEPT of what it differed by at first: a modulus that is continuous
#: there would have closed that gap with the bracket.
JUMP_NARROWING = 1e-3
JUMP_NARROWING_FAILED = 1e-1
JUMP_KEPT = 0.5
#: A stability change whose bracket closed to ``locate_tol`` before it could narrow that far (the step across it was
#: already short: the steps shrink before a kink) is a border collision where the crossing multiplier's modulus
#: still differs between the ends by this much. A continuous one changes by about ``MULTIPLIER_STEP`` at most over
#: a step no shorter than ``4 ds_min`` (what the step control aims at), so by about ``2.5e-4`` at most over
#: ``locate_tol`` at the defaults (the tuned 24-blade ring at 1481.1533 rad/s: 1.40 and 0.95 across a bracket of
#: ``6e-7`` rad/s, reported as a Neimark-Sacker point before).
JUMP_CLOSED = 1e-2


class _Context:
    """Residuals, Jacobians, corrections and bifurcation tests in the scaled unknowns."""

    def __init__(self, fam: _Family, scale, span, tol, rel_step, max_corrections, grazing_tol=None):
        self.fam, self.scale, self.span = fam, scale, span
        self.tol, self.rel_step, self.max_corrections = tol, rel_step, max_corrections
        self.grazing_tol = grazing_tol   # grazing points' location tolerance (None: the bifurcations' locate_tol)
        self.locator: Locator | None = None   # where grazing points are located (set by _run for its branch)
        self.n = scale.size
        self._discrete = None
        self.iterations = 0
        self._run = None   # the last residual's run (its events and signature: :attr:`events`, :attr:`signature`)
        self.why = ""
        # the least residual at which a correction or a shot since the last correction began stopped falling at the
        # integration's rounding errors (below ROUNDING_LEVEL), or None: tol is then below what the arithmetic gives
        self.rounding = None

    @property
    def discrete(self) -> np.ndarray:
        """Positions of the friction laws' discrete states among the unknowns (held as labels, scaled by
        :data:`~.shooting.LABEL_SCALE`)."""
        if self._discrete is None:
            self._discrete = self.fam.discrete
        return self._discrete

    def hold(self, G: np.ndarray) -> np.ndarray:
        """``G`` (the orbit rows of a Jacobian in the scaled unknowns, and more rows) with the discrete states'
        rows and columns as :func:`~.period_map.hold_discrete` leaves them: ``-1`` on the diagonal, else zero."""
        d = self.discrete
        if d.size:
            G[:self.n, d] = 0.0
            G[d, :] = 0.0
            G[d, d] = -1.0
        return G

    @property
    def events(self) -> int:
        """The events of the orbit of the last residual's run (``-1`` before any)."""
        return -1 if self._run is None else self._run.events

    @property
    def signature(self) -> tuple | None:
        """The event signature (:meth:`~.period_map.MapRun.signature`) of the last residual's run."""
        return None if self._run is None else self._run.signature()

    def correct_at_value(self, X, mode, jacobian=True):
        """Shooting at the field's value of the prediction ``X`` (no arclength condition); ``(None, ..)`` on failure.

        Without ``jacobian`` the point's Jacobian is not taken (None), and ``self.events``
        holds its orbit's events.
        """
        lam = X[-1] * self.span
        try:
            P = self.fam.map_at(lam)
            y, mode = _shoot(P, X[:-1] * self.scale, _copy(mode), self.scale, self.tol, self.max_corrections,
                             self.rel_step, [])
        except (ShootingError, FlowError, np.linalg.LinAlgError, ValueError) as e:
            self.why = f"{self.why}; shooting at {self.fam.name} = {lam:.6g}: {e}"
            if getattr(e, "least_tol", None) is not None:
                self._met_rounding(min(e.history))
            return None, mode, None
        Xc = np.append(y / self.scale, X[-1])
        self.iterations = self.max_corrections // 2
        r, _ = self.residual(Xc, mode)   # (and the orbit's events)
        res = residual_size(r, self.discrete)
        if res > self.tol:
            # the state, scaled and back, moved by its rounding, and the map moved by much more: the orbit
            # lies on a switching boundary of the discrete flow (the Iwan pair at 157.4329 rad/s: 8e-12 shot,
            # 3.3e-4 rounded), where the continuation cannot stand
            self.why = (f"{self.why}; shooting at {self.fam.name} = {lam:.6g}: the orbit's residual "
                        f"{res:.3g} once its state is rounded to the continuation's "
                        f"scaled unknowns (it lies on a switching boundary)")
            return None, mode, None
        if not jacobian:
            return Xc, mode, None
        A = self._jacobian_at(Xc, mode)
        return (Xc, mode, A) if A is not None else (None, mode, None)

    def _met_rounding(self, residual: float) -> None:
        """Note a residual that stopped falling at the integration's rounding errors (:attr:`rounding`)."""
        self.rounding = residual if self.rounding is None else min(self.rounding, residual)

    def _jacobian_at(self, X, mode, column=None):
        """:meth:`jacobian` at a corrected point, or None (with ``why``) where a perturbed integration fails."""
        try:
            return self.jacobian(X, mode, column)
        except (FlowError, ValueError) as e:
            self.why = f"the Jacobian at the corrected point: {e}"
            return None

    def twin(self) -> "_Context":
        """A context on period maps of its own (:meth:`_Family.twin`): for work in another thread."""
        return _Context(self.fam.twin(), self.scale.copy(), self.span, self.tol, self.rel_step, self.max_corrections,
                        self.grazing_tol)

    def rescale(self, scale, X, T, A):
        """``X``, the tangent ``T`` and the Jacobian ``A`` in the state scale ``scale`` (was ``self.scale``)."""
        n, r = self.n, self.scale / scale
        X, T, A = X.copy(), T.copy(), A.copy()
        X[:n] *= r
        T[:n] *= r
        T /= np.linalg.norm(T)
        A[:, :n] *= r[:, None] / r[None, :]
        A[:, n] *= r
        self.scale = scale.copy()
        return X, T, A

    def residual(self, X, mode):
        """``(P(y) - y) / scale`` and the mode the map ends in."""
        P = self.fam.map_at(X[-1] * self.span)
        y = X[:-1] * self.scale
        Py, mode_end = P(y, _copy(mode))
        self._run = P.last_run
        return scaled_residual(Py, y, self.scale, self.discrete), mode_end

    def jacobian(self, X, mode, column=None):
        """``d residual / dX`` (``n x (n + 1)``): the tangent of the flow where it exists, else central differences.

        The state columns are the monodromy matrix (the tangent replays the run the
        residual at ``X`` already made); the field's column is a forward difference of
        the map, ``(P(y; lambda + delta) - P(y; lambda)) / delta`` with ``P(y; lambda)``
        from that same run: one integration, where the tangent's own parameter column,
        which follows the parameters and the moving period step by step, costs about
        seven. Its error, about ``delta`` relative, only slows the corrections by as
        much; the orbits are solved to ``tol`` whatever the column, and the multipliers
        come from the exact monodromy. ``column``, where given (:meth:`column_rule`), is
        asked first for the field's column from the state columns and may spare that
        integration.
        """
        n, d = self.n, self.rel_step
        lam = X[-1] * self.span
        P = self.fam.map_at(lam)
        y = X[:-1] * self.scale
        A = np.empty((n, n + 1))
        J = None
        if P.exact:
            s = P.try_derivatives(y, mode)
            if s is not None:
                J = s.monodromy
        if J is None:
            J = P.differences(y, mode, self.scale, d)
        A[:, :n] = (J - np.eye(n)) * self.scale[None, :] / self.scale[:, None]
        c = None if column is None else column(X, mode, A[:, :n])
        A[:, n] = c if c is not None else \
            (self.fam.map_at(lam + d * self.span).plain(y, mode) - P(y, mode)[0]) / self.scale / d
        A[self.discrete, n] = 0.0   # labels do not move with the field (a difference would read a jump)
        return A

    def correct(self, X, T, mode, A=None, jacobian=True, tol=None, newton=True, column=None, quick=False):
        """Newton on the orbit and arclength conditions from the prediction ``X``; ``(None, ..)`` on failure.

        With ``A`` (the Jacobian at the last point) the first attempt is Broyden's
        method: that matrix, corrected by a rank-one update after every step, only
        residuals evaluated (the arclength row is exact and stays so); then Newton with
        the Jacobian taken afresh. The orbit must come back to the mode it starts in at the
        section: converged in another one, or failing where the flow from the
        prediction ends in another one (the section state crossed a switching boundary
        between the points), the correction is done again from that mode. Returns the
        point, its mode and its Jacobian (None without ``jacobian``: for a test that needs
        only the orbit's events, ``self.events``, which the last residual's run counted).
        ``tol`` replaces ``self.tol`` for this correction. Without ``newton`` (and with
        ``A``) only Broyden's method is tried, in each mode: a trial that may fail cheaply.
        ``column`` goes to :meth:`jacobian` for the converged point's Jacobian. A ``quick``
        correction (Broyden's method only) gives up at the first residual that does not fall,
        without the halvings that may rescue it: for trials that have others beside them.
        """
        tol = self.tol if tol is None else tol
        Xp = X.copy()
        self.why = ""
        self.rounding = None
        if not newton and A is None:
            raise ValueError("a correction without Newton's method needs A, the matrix Broyden's method starts from")
        retry = not newton   # how a retry from another mode corrects: Broyden's method (True) or Newton's
        tries = ([(mode, True)] if A is not None else []) + ([(mode, False)] if newton else [])
        tried = set()
        while tries:
            mode, chord = tries.pop(0)
            tried.add((_key(mode), chord))
            Xc = Xp.copy()
            first_end = None
            best = np.inf
            try:
                G = np.vstack([A, T]) if chord else None
                X_old = F_old = None
                res_old = np.inf
                halvings = since_best = 0
                for it in range(2 * self.max_corrections if chord else self.max_corrections):
                    r, mode_end = self.residual(Xc, mode)
                    first_end = mode_end if first_end is None else first_end
                    res = residual_size(r, self.discrete)
                    if res <= tol:
                        break
                    if res < 0.5 * best:
                        best, since_best = res, 0
                    else:
                        since_best += 1
                        if since_best > STALL:
                            raise FlowError(f"the corrections stalled at a residual of {best:.2g}")
                    if quick and res >= res_old:
                        raise FlowError(f"a quick trial's residual rose from {res_old:.2g} to {res:.2g}")
                    F = np.append(r, np.dot(T, Xc - Xp))
                    if chord and X_old is not None:   # Broyden: the secant condition along the step taken
                        step = Xc - X_old
                        G = self.hold(G + np.outer(F - F_old - G @ step, step) / np.dot(step, step))
                    if res >= res_old and halvings < MAX_HALVINGS:
                        # no decrease (the step crossed a kink of the map, where an event appears or
                        # leaves, and undamped corrections cycle between its sides): back halfway
                        halvings += 1
                        labels = Xc[self.discrete]
                        Xc = X_old + 0.5 * (Xc - X_old)
                        Xc[self.discrete] = labels   # a label is set whole, not halved
                        continue
                    halvings = 0
                    if not chord:
                        G = np.vstack([self.jacobian(Xc, mode), T])
                    X_old, F_old, res_old = Xc, F, res
                    Xc = Xc + np.linalg.solve(G, -F)
                    if not (np.all(np.isfinite(Xc)) and np.linalg.norm(Xc - Xp) < 1.0):
                        raise FlowError("the correction diverged (moved by more than the orbit's excursion)")
                else:
                    raise FlowError(f"no convergence in {it + 1} corrections (residual {res:.2g})")
            except (FlowError, np.linalg.LinAlgError, ValueError) as e:   # ValueError: a field out of its range
                self.why = str(e)
                if best <= ROUNDING_LEVEL:
                    self._met_rounding(best)
                if first_end is not None and (_key(first_end), retry) not in tried and \
                        all(_key(first_end) != _key(m) for m, _ in tries):
                    tries.append((_copy(first_end), retry))
                continue
            self.iterations = it
            if _same(mode_end, mode):
                if not jacobian:
                    return Xc, mode, None
                A = self._jacobian_at(Xc, mode, column)
                if A is None:
                    continue
                return Xc, mode, A
            # converged, but to an orbit that comes back in another mode: solving again from the
            # same mode (Newton after Broyden) lands there too; that mode is the one to try
            tries = [(m, c) for m, c in tries if _key(m) != _key(mode)]
            if (_key(mode_end), retry) not in tried:
                tries.append((_copy(mode_end), retry))
            self.why = "the orbit's mode at the section keeps changing (it switches exactly there)"
        return None, mode, None

    def predict(self, pts, X, T, A, h):
        """The prediction a step ``h`` along the branch from ``X`` and the matrix Broyden's method starts from.

        On a smooth stretch (the last three points in one mode with the same number of
        events, the last two reached by regular steps), the quadratic
        through the three points in their arclength, for the unknowns and for the Jacobian
        alike: the corrections start about a hundred times closer than from the tangent
        step, and from a Jacobian close enough that one correction brings the residual from
        about ``1e-6`` to ``1e-11`` (measured on the bilinear pair at ``ds_max = 1/200``;
        extrapolated linearly from the last two, to about ``5e-10``, so that most points
        took a third residual). A cubic through four points predicts closer still, but
        at the default steps it made the Coulomb pair's branch zigzag across its fold at
        420.35 rad/s (207 folds), so it is not used. Elsewhere the tangent step and the
        last Jacobian.
        """
        if A is None or len(pts) < 3:
            return X + h * T, A
        a, b, c = pts[-3], pts[-2], pts[-1]
        if not (b.get("regular") and c.get("regular") and a["events"] == b["events"] == c["events"]
                and _key(a["mode"]) == _key(b["mode"]) == _key(c["mode"])):
            return X + h * T, A
        Xa, Xb = (self.unknowns(q) for q in (a, b))
        d0, d1 = float(np.linalg.norm(Xb - Xa)), float(np.linalg.norm(X - Xb))
        if not (d0 > 0 and d1 > 0):
            return X + h * T, A
        s0, s1 = -(d0 + d1), -d1       # arclength of a and b; X is at 0, the prediction at h
        La = (h - s1) * h / ((s0 - s1) * s0)
        Lb = (h - s0) * h / ((s1 - s0) * s1)
        Lc = (h - s0) * (h - s1) / (s0 * s1)
        Aa, Ab = (self._jacobian_of(q) for q in (a, b))
        Xp = La * Xa + Lb * Xb + Lc * X
        Xp[self.discrete] = X[self.discrete]   # the last point's labels
        return Xp, La * Aa + Lb * Ab + Lc * A

    def column_rule(self, pts):
        """The field's column of a new point's Jacobian from the branch's own points, or None.

        On a smooth stretch (the last three points in one mode and with one event
        signature, the last two reached by regular steps), where the new point keeps that
        mode and signature, the branch's tangent ``t`` at the new point is that of the cubic
        through the last three points and it, in their arclength, to third order in the
        step. Along the branch the residual stays zero, ``A_y t_y + a t_lambda = 0``, which
        gives the field's column ``a = -A_y t_y / t_lambda`` from the exact state columns
        ``A_y``, without the integration at a shifted value of the field that the difference
        quotient takes. The quadratic through the last two points and the new one (second
        order) estimates the error, as an embedded Runge-Kutta pair's lower order does: where
        ``|t_cubic - t_quadratic| / |t_lambda|`` exceeds :data:`COLUMN_ACCURACY` (a bent
        stretch, or near a fold, where the division magnifies the error) the rule returns
        None and the difference is taken. The column
        only starts Broyden's method at the next point and orients the next tangent: the
        orbits are solved to ``tol`` and the multipliers come from the exact monodromy
        whatever it is. Returns ``column(X, mode, A_y)``, the column at the corrected
        point ``X`` or None, for :meth:`jacobian`.
        """
        if len(pts) < 3:
            return None
        z, a, b = pts[-3], pts[-2], pts[-1]
        if not (a.get("regular") and b.get("regular") and z["signature"] == a["signature"] == b["signature"]
                and _key(z["mode"]) == _key(a["mode"]) == _key(b["mode"])):
            return None
        before = [self.unknowns(q) for q in (z, a, b)]
        chords = [_chord(p, q) for p, q in zip(before[:-1], before[1:])]

        def column(X, mode, A_y):
            if self.signature != b["signature"] or _key(mode) != _key(b["mode"]):
                return None
            last = chords + [_chord(before[-1], X)]
            t = _end_tangent(before[1:] + [X], last[1:])
            t_cubic = _end_tangent(before + [X], last)
            if t is None or t_cubic is None or \
                    np.linalg.norm(t_cubic - t) > COLUMN_ACCURACY * abs(t[-1]):
                return None
            return -(A_y @ t_cubic[:-1]) / t_cubic[-1]

        return column

    def unknowns(self, q):
        """The scaled unknowns ``X`` (state, then field) of the branch point ``q`` in the current state scale."""
        return np.append(q["state"] / self.scale, q["param"] / self.span)

    def monodromy(self, q) -> np.ndarray:
        """The monodromy matrix (physical units) of the branch point ``q``: the one it keeps (the last
        :data:`KEPT_JACOBIANS` points keep theirs), else from its scaled Jacobian ``A`` in the scale it was stored in
        (the same matrix to rounding)."""
        J = q.get("J")
        return J if J is not None else self._physical(q["A"], q["scale"])

    def _jacobian_of(self, q):
        """The scaled Jacobian of the branch point ``q`` in the current state scale."""
        n = self.n
        A = np.empty((n, n + 1))
        A[:, :n] = (self.monodromy(q) - np.eye(n)) * self.scale[None, :] / self.scale[:, None]
        A[:, n] = q["dl"] * self.span / self.scale
        return A

    def multipliers(self, A):
        """Floquet multipliers from the scaled Jacobian ``A``, largest modulus first."""
        return self._multipliers_of(self._physical(A))

    def _multipliers_of(self, J):
        """The orbit's Floquet multipliers from its map's Jacobian ``J`` (physical units), largest modulus first:
        ``J``'s eigenvalues, or with a cyclic reduction those of the whole period's monodromy it gives."""
        sym = self.fam.symmetry
        return _largest_first(np.linalg.eigvals(J if sym is None else sym.monodromy(J)))

    def _physical(self, A, scale=None):
        """The monodromy matrix in physical units from the scaled Jacobian ``A`` (in ``scale``, by default the
        current state scale)."""
        n = self.n
        scale = self.scale if scale is None else scale
        return A[:, :n] * scale[:, None] / scale[None, :] + np.eye(n)

    def point(self, X, mode, A):
        """The branch point's record from its scaled unknowns and Jacobian."""
        n = self.n
        J = self._physical(A)   # kept in physical units: the scale changes from point to point
        mu = self._multipliers_of(J)
        lam = X[-1] * self.span
        P = self.fam.map_at(lam)
        y = X[:-1] * self.scale
        r = P.run(y, mode)
        Y = r.period_orbit()
        residual = float(np.max(np.abs(r.end[:self.n] - y) / self.scale))
        # each state's extremes along its own contiguous row: numpy's reduction down the columns of a
        # (steps x states) array is several times slower (51 against 7 us for the pair's 1001 x 8)
        rows = np.ascontiguousarray(Y.T)
        top, bottom = rows.max(axis=1), rows.min(axis=1)
        amp = 0.5 * (top - bottom)
        ms = np.einsum("ij,ij->i", rows[:, :-1], rows[:, :-1]) / (rows.shape[1] - 1)   # (the closing sample left out)
        c = dft_bin(Y[:-1], self.fam.periods) * 2.0 / (Y.shape[0] - 1)
        S = (Y.shape[0] - 1) // self.fam.periods
        return {"param": lam, "state": y, "sections": Y[:-1:S].copy(), "mu": mu,
                "stable": bool(np.max(np.abs(mu)) < 1.0), "amp": amp, "ms": ms,
                "h1": c, "unstable": _unstable_count(mu), "X": X.copy(), "mode": _copy(mode), "A": A, "Y": Y,
                "events": r.events, "signature": r.signature(), "regular": True, "residual": residual,
                "magnitude": np.maximum(top, -bottom),   # each state's largest |value| on the orbit
                "J": J, "dl": A[:, n] * self.scale / self.span}

    def orbit(self, q) -> np.ndarray:
        """The orbit of the branch point ``q`` at every step (physical states, both ends included): the record its run
        left, where the point still keeps it (a branch keeps its last :data:`KEPT_ORBITS` points'), else that run
        made again, from the point's state and mode at its value of the field (the same orbit to rounding: the map
        there may be another integrator than the one that made it, the branch's first built from the model and
        the others its copies, whose derived parameters can round otherwise)."""
        Y = q.get("Y")
        if Y is None:
            Y = self.fam.map_at(q["param"]).run(q["state"], q["mode"]).period_orbit()
        return Y

    def detect(self, a, b, Xa, Ta, mode, index, locate_tol, before=None):
        """The bifurcations between consecutive points ``a`` and ``b``, each located on the arclength.

        A change in the number of multipliers outside the unit circle (fold, branch point,
        period doubling, Neimark-Sacker: :meth:`_locate_crossing`), and a change in the orbit's
        events (which transitions it crosses, counted: its signature,
        :meth:`~.period_map.MapRun.signature`): a guard of the orbit touches zero there (a
        contact that grazes, a slip that comes to rest: **grazing**, including the end of
        continuous sliding; every one between the two points, :meth:`_locate_grazings`).
        Not the number of events alone: where one phase appears and another vanishes
        within a step the number stays (the Coulomb pair from 314.02 to 314.21 rad/s at
        ``ds_max = 0.02``: 15 events, a stick phase appearing at 314.137 and a short slip
        before the contact opens vanishing at 314.182).

        Where ``a`` and ``b`` have the same count, a multiplier may still have crossed the
        circle and come back within the step (:meth:`_window`, from ``before``, the point
        before ``a``); both crossings are then located.
        """
        found = []
        bracket = None
        pairs = [(a, b, Xa)]
        if before is not None and a["unstable"] == b["unstable"]:
            m = self._window(before, a, b, Xa, mode)
            if m is not None:
                pairs = [(a, m, Xa), (m, b, m["X"])]
        for p, q, Xp in pairs:
            if p["unstable"] == q["unstable"]:
                continue
            best, jump = self._locate_crossing(p, q, Xp, Ta, mode, locate_tol)
            mu = best["mu"][np.argmin(np.abs(np.abs(best["mu"]) - 1.0))]
            if jump is not None:
                kind = "border-collision"   # with the multiplier that jumped across the circle
                mu = _crossing_multiplier(best["mu"], min(p["unstable"], q["unstable"]))
                bracket = jump
            elif abs(mu.imag) > 1e-6 * abs(mu):
                kind = "neimark-sacker"
            elif mu.real < 0:
                kind = "period-doubling"
            else:
                kind = "fold" if _turns(p, q, Ta if p is a else None) else "branch-point"
                if kind == "fold" and abs(abs(mu) - 1.0) > JUMP_CLOSED:
                    # located with its multiplier off the circle by more than a continuous one moves over the
                    # location's bracket: the turn lies at a kink (the Iwan pair in F0 up from 3 N, 3.712318 N:
                    # trials on either side at 0.987 and 1.051 to the last, one failing beside the kink)
                    kind = "nonsmooth-fold"
            found.append(_special(kind, best, index, mu, jump))
        if a["signature"] != b["signature"]:
            # the largest multiplier of the point before: at the grazing the map is not differentiable, and
            # difference quotients there straddle the kink (measured on 4- to 12-blade rings: 2e4 to 2.4e5 between
            # points at about 0.62)
            tol = locate_tol if self.grazing_tol is None else self.grazing_tol
            multiplier = a["mu"][0]

            def finish(at):
                return _special("grazing", at, index, multiplier)
            # located later, elsewhere (.background): on what the step has now (the points' dicts are
            # rescaled later, their arrays never changed in place; the task, and these copies with it, are let
            # go once it has run: PendingPoint.start); a border collision whose bracket holds the grazing is placed
            # there (background.resolve): that is its kink
            args = (self.scale.copy(), dict(a), dict(b), Xa.copy(), Ta, _copy(mode), tol)
            found.append(PendingPoint(lambda ctx: _locate_grazings_in(ctx, *args), self.locator, finish, index,
                                      bracket, unlocated=_unlocated(b, _field_bracket(Xa, b["X"], self.span))))
        return found

    def _window(self, before, a, b, Xa, mode):
        """A point between ``a`` and ``b`` (which have the same number of multipliers outside the unit circle)
        where that number differs, or None.

        A step can jump a window of stability or instability whose two ends it does not
        resolve (the bilinear pair at ``ds_max = 0.2``: unstable at 416.73 and 417.98 rad/s,
        its period-doubling multiplier 1.0003 and 1.0099 in modulus there, and stable between
        the period doublings at 416.73 and 417.80). The moduli of the multipliers on either
        side of the circle (the last outside and the first inside, largest first) are
        interpolated by the parabola through ``before``, ``a`` and ``b`` in their arclength;
        where it crosses the circle and comes back between ``a`` and ``b``, the point at its
        extremum is corrected (on the hyperplane normal to the chord), and returned where its
        count differs. One correction where the parabola says so, none elsewhere.
        """
        u = a["unstable"]
        Xb = b["X"]
        d0 = d1 = None
        for j in (u - 1, u):
            if j < 0 or j >= a["mu"].size:
                continue
            g0, g1, g2 = (float(abs(q["mu"][j])) - 1.0 for q in (before, a, b))
            if not (min(g0, g1, g2) > 0.0 or max(g0, g1, g2) < 0.0):
                continue
            if d0 is None:   # (in floats: this runs at every step, numpy's polyfit cost a tenth of the branch)
                X0 = self.unknowns(before)
                d0, d1 = float(np.linalg.norm(Xa - X0)), float(np.linalg.norm(Xb - Xa))
            if not (d0 > 0.0 and d1 > 0.0):
                return None
            # the parabola through (-d0, g0), (0, g1), (d1, g2) in Newton's form, and its extremum
            f01, f12 = (g1 - g0) / d0, (g2 - g1) / d1
            c2 = (f12 - f01) / (d0 + d1)
            if c2 == 0.0:
                continue
            at = 0.5 * (-f01 / c2 - d0)
            if not 0.0 < at < d1 or (g0 + f01 * (at + d0) + c2 * (at + d0) * at > 0.0) == (g1 > 0.0):
                continue
            Xm, mm, Am = self._corrected(Xa, Xb, at / d1, mode, a["A"] if at <= 0.5 * d1 else b["A"], True)
            if Xm is not None and _unstable_count(self.multipliers(Am)) != u:
                return self.point(Xm, mm, Am)
        return None

    def _corrected(self, X_lo, X_hi, theta, mode, A, jacobian, tol=None, at_value=False, newton=True, step=None,
                   quick=False):
        """The branch point between two of its points ``X_lo``, ``X_hi``, a fraction ``theta`` of the way.

        Predicted on the chord between them and corrected with ``A`` as Broyden's first
        matrix and ``tol`` for :meth:`correct`: on the hyperplane normal to the chord, or
        with ``at_value`` at the predicted value of the field if the ends have different
        values. A trial near a grazing point sits on a kink of the branch, where the map's
        difference in the field straddles the event that appears: the field's column of
        the Jacobian is then wrong and Newton on the arclength system cycles, while
        shooting at a fixed value never uses it (the branch may be all but vertical there:
        measured, ends ``2.7e-4`` apart in the scaled states and ``2e-7`` in the field).
        Around a fold the field does not move monotonically between the ends, so the
        hyperplane is needed there. A point corrected farther from either end than they
        are from each other has left the bracket and is refused, unless (with ``step``,
        the ends of the continuation step the bracket lies in) it was solved at a fixed
        value and lies within the step's length of one of its ends: where the branch bows
        between the ends of a bracket its points there lie farther from them than they
        from each other (the Coulomb pair between 224.23 and 224.60 rad/s, where the
        friction states rise and fall again), and refusing them stopped the grazing's
        location with a bracket 0.09 to 0.28 rad/s wide. ``(X, mode, A)``, or ``X`` None.
        """
        width = np.linalg.norm(X_hi - X_lo)
        Xp = X_lo + theta * (X_hi - X_lo)
        normal = (X_hi - X_lo) / width
        fixed = at_value and abs(X_hi[-1] - X_lo[-1]) > 1e-12 * max(abs(X_hi[-1]), abs(X_lo[-1]))
        if fixed:
            normal = np.zeros_like(normal)
            normal[-1] = 1.0
        Xm, mm, Am = self.correct(Xp, normal, mode, A, jacobian=jacobian, tol=tol, newton=newton, quick=quick)
        if Xm is None and not fixed and newton:
            Xm, mm, Am = self.correct_at_value(Xp, mode, jacobian=jacobian)
        if Xm is not None and not (_between(Xm, X_lo, X_hi) or (fixed and step is not None and _near(Xm, *step))):
            # corrected away from the bracket (a kink of the map, a fold of the branch across
            # the chord's hyperplane): the location stops at the bracket it has
            self.why = "a correction inside the bracket left it"
            return None, mm, None
        return Xm, mm, Am

    def _locate_crossing(self, a, b, Xa, Ta, mode, locate_tol):
        """The first point past a change of the number of unstable multipliers from ``a`` to ``b``.

        The test function is ``|mu| - 1`` of the multiplier nearest the unit circle, smooth
        along the branch: regula falsi with the Illinois modification between the
        bracket's two corrected points, each trial kept at least half ``locate_tol`` inside
        it, so the bracket closes to ``locate_tol`` of arclength in a few corrected points
        where bisection took about twenty; which side a trial lies on is decided by its
        count of unstable multipliers.

        Returns the point and, for a **border collision**, the field's values at the
        bracket's ends (else None). A border collision is found where the bracket shrank
        to ``JUMP_NARROWING`` of its first width (``JUMP_NARROWING_FAILED`` if a trial
        failed) while the modulus of the crossing multiplier (the one whose count changes)
        still differs between its ends by ``JUMP_KEPT`` of its first difference, or where
        it closed to ``locate_tol`` with that modulus still differing by ``JUMP_CLOSED``: a
        multiplier jumps across the circle at a kink of the map (a grazing where the
        orbit's event sequence changes). There the location stops: regula falsi would
        close such a bracket only linearly, with trials ever nearer the kink, where
        corrections struggle (measured on the 24-blade ring at 274.2262 rad/s: 0.875 on one
        side, 1.04 to 1.08 on the other, 31 trials; or 0.991 and 1.16 across a second kink
        1e-5 rad/s above the first, seven location sequences ended by failed trials).
        """
        def test(mu):
            return float(np.abs(mu[np.argmin(np.abs(np.abs(mu) - 1.0))]) - 1.0)

        k = min(a["unstable"], b["unstable"])

        def crossing(mu):
            return float(abs(_crossing_multiplier(mu, k)))

        X_lo, X_hi = Xa, b["X"]
        A_lo, A_hi = a["A"], b["A"]
        f_lo, f_hi = test(a["mu"]), test(b["mu"])
        c_lo, c_hi = crossing(a["mu"]), crossing(b["mu"])
        first, first_gap = float(np.linalg.norm(X_hi - X_lo)), abs(c_hi - c_lo)
        best = b
        last = 0
        jump = False

        def jumped(width, narrowing):
            return width <= narrowing * first and abs(c_hi - c_lo) >= JUMP_KEPT * first_gap > 0.0

        for _ in range(100):
            width = float(np.linalg.norm(X_hi - X_lo))
            if width <= locate_tol:
                jump = abs(c_hi - c_lo) >= JUMP_CLOSED
                break
            if jumped(width, JUMP_NARROWING):
                jump = True
                break
            theta = 0.5
            if f_lo * f_hi < 0.0:
                theta = f_lo / (f_lo - f_hi)
            margin = min(0.5 * locate_tol / width, 0.5)
            theta = min(max(theta, margin), 1.0 - margin)
            Xm, mm, Am = self._corrected(X_lo, X_hi, theta, mode, A_lo if theta <= 0.5 else A_hi, True)
            if Xm is None:
                jump = jumped(width, JUMP_NARROWING_FAILED)
                break
            mu = self.multipliers(Am)
            f = test(mu)
            if _unstable_count(mu) == a["unstable"]:
                X_lo, A_lo, f_lo, c_lo = Xm, Am, f, crossing(mu)
                if last < 0:
                    f_hi *= 0.5
                last = -1
            else:
                X_hi, A_hi, f_hi, c_hi = Xm, Am, f, crossing(mu)
                best = (Xm, mm, Am)
                if last > 0:
                    f_lo *= 0.5
                last = 1
        bracket = (X_lo[-1] * self.span, X_hi[-1] * self.span) if jump else None
        return (self.point(*best) if isinstance(best, tuple) else best), bracket

    def _locate_grazing(self, a, b, Xa, Ta, mode, locate_tol, step=None, near=False):
        """The first point past a change of the orbit's events (its signature) from ``a``'s, toward ``b``, by
        bisection.

        The signature has no smooth test function, so the bracket is halved; each trial needs
        only its orbit's events (no Jacobian, no multipliers), and its prediction, halfway
        between the bracket's corrected ends, comes ever closer to the branch. Trials are
        solved at a fixed value of the field (where the ends' values differ). The bracket
        is closed when it is ``locate_tol`` wide in the scaled unknowns, or in the field
        alone once a halving no longer shrinks it by a quarter: an arm of the branch may
        end at the grazing (a small hysteresis loop whose arms end where their guards
        touch zero: the bilinear pair at 313.1142 rad/s, where orbits with 20 and 22
        events coexist over 1e-4 rad/s), and then the state across the bracket does not
        close at all. A trial only has to tell on which side of the grazing point it
        lies, so it is solved to :data:`TRIAL_ACCURACY` of the bracket's width (never
        looser than the branch's ``tol`` needs less): where the bracket is wide, one or
        two corrections, by Broyden's method alone, from the Jacobian of the end nearer
        the trial (``a``'s up to the bracket's middle, ``b``'s past it); a trial that
        fails is tried beside. The located point is solved to ``tol``; it gets no
        Jacobian (the map has a kink there). Returns the located point's field value,
        state, mode, scaled unknowns ``X``, signature and ``bracket``: None where the
        bisection closed, else the field's values across the last bracket, where no trial
        inside it could be solved (:class:`SpecialPoint`); the first point past the change
        found (``b`` if none was). With ``near`` the change is looked for near ``Xa`` first:
        trials at twice ``locate_tol`` from it, then four times as far each, until one lies
        past the change or halfway across the bracket; then the bisection.
        """
        X_lo, X_hi = Xa, b["X"]
        step = (Xa, b["X"]) if step is None else step
        best = None
        previous = np.inf
        closed = False
        reach = 2.0 * locate_tol if near else np.inf   # the first trials' distance from X_lo, growing fourfold
        X_before = None   # the lower end before X_lo: their secant predicts where the chord to X_hi does not
        while True:
            width = float(np.linalg.norm(X_hi - X_lo))
            if width <= locate_tol or (abs(X_hi[-1] - X_lo[-1]) <= locate_tol and width > 0.75 * previous):
                closed = True   # closed, or closed in the field while the state across it no longer closes
                break
            previous = width
            trial_tol = max(self.tol, TRIAL_ACCURACY * width)
            if reach < 0.5 * width:
                Xm, mm, _ = self._corrected(X_lo, X_hi, reach / width, mode, a["A"], False, trial_tol, at_value=True,
                                            newton=False, step=step)
                if Xm is None:
                    Xm, mm = self._along_secant(X_before, X_lo, X_hi, reach / width, mode, a["A"], trial_tol, step)
                if Xm is not None and self.signature == a["signature"]:
                    X_before, X_lo, reach = X_lo, Xm, 4.0 * reach
                    continue
                reach = np.inf
                if Xm is not None:
                    X_hi, best = Xm, (Xm, mm, self.signature)
                    continue
            for theta in (0.5, 0.25, 0.75):   # a trial right at the grazing point can stall: one beside it
                Xm, mm, _ = self._corrected(X_lo, X_hi, theta, mode, a["A"] if theta <= 0.5 else b["A"], False,
                                            trial_tol, at_value=True, newton=False, step=step, quick=True)
                if Xm is not None:
                    break
            if Xm is None:
                Xm, mm = self._along_secant(X_before, X_lo, X_hi, 0.5, mode, a["A"], trial_tol, step)
            if Xm is None:   # Broyden's method from the ends' Jacobians failed: Newton's, once
                Xm, mm, _ = self._corrected(X_lo, X_hi, 0.5, mode, a["A"], False, trial_tol, at_value=True,
                                            step=step)
            if Xm is None:
                break
            if self.signature == a["signature"]:
                X_before, X_lo = X_lo, Xm
            else:
                X_hi, best = Xm, (Xm, mm, self.signature)
        bracket = None if closed else _field_bracket(X_lo, X_hi, self.span)
        if best is not None:
            Xt, mt, signature = best
            r, _ = self.residual(Xt, mt)
            Xb, mb = Xt, mt
            if float(np.max(np.abs(r))) > self.tol:
                d = X_hi - X_lo
                Xb, mb, _ = self.correct(Xt, d / np.linalg.norm(d), mt, a["A"], jacobian=False)
            if Xb is not None:
                signature = self.signature
                if bracket is not None:   # (solved to tol, the point may have moved just out of it: by 2e-10 rad/s)
                    value = float(Xb[-1] * self.span)
                    bracket = (min(bracket[0], value), max(bracket[1], value))
            else:
                # the trial, solved only to tell its side, is no orbit to tol: it may lie where none is (a gap of
                # the discrete flow, from 305.7811 to 305.7831 rad/s on the Coulomb pair, where trials solved to
                # 1e-6 were found). It stands as the estimate; the first orbit past the change is only known to
                # lie before b
                Xb, mb = Xt, mt
                bracket = _field_bracket(X_lo, b["X"], self.span)
            # no Jacobian: the map is not differentiable here, and the special point takes the multiplier
            # of the point before (detect)
            return {"param": Xb[-1] * self.span, "state": Xb[:-1] * self.scale, "mode": _copy(mb), "X": Xb,
                    "signature": signature, "bracket": bracket}
        return b if bracket is None else _unlocated(b, bracket)

    def _along_secant(self, X_before, X_lo, X_hi, theta, mode, A, tol, step):
        """A trial a fraction ``theta`` of the way from ``X_lo`` to ``X_hi`` in the field, its state predicted on the
        secant through ``X_before`` and ``X_lo`` (not on the chord to ``X_hi``) and solved at that value of the field
        by Broyden's method from ``A``: ``(X, mode)``, or ``(None, mode)``.

        Where the branch bends between a bracket's ends the chord's prediction lies far from
        it and the corrections stall (the Coulomb pair from 201.14 to 202.17 rad/s, a
        second grazing point's bracket: residuals of 0.016 to 0.048 at the chord's trials,
        Newton's method 1.2e-4), while the lower end's last two points lie on the branch.
        """
        if X_before is None or X_lo[-1] == X_before[-1]:
            return None, mode
        lam = X_lo[-1] + theta * (X_hi[-1] - X_lo[-1])
        Xp = X_lo + (lam - X_lo[-1]) / (X_lo[-1] - X_before[-1]) * (X_lo - X_before)
        Xp[-1] = lam
        normal = np.zeros_like(Xp)
        normal[-1] = 1.0
        Xm, mm, _ = self.correct(Xp, normal, mode, A, jacobian=False, tol=tol, newton=False)
        if Xm is None or not _near(Xm, *step):
            return None, mm
        return Xm, mm

    def _locate_grazings(self, a, b, Xa, Ta, mode, locate_tol, most=16):
        """Every grazing point between consecutive points ``a`` and ``b`` (whose signatures differ), in order.

        :meth:`_locate_grazing` finds the first past ``a``; where the orbit just past it
        does not yet have ``b``'s signature, another grazing lies between it and ``b``,
        located the same way from it (its trials start from ``a``'s Jacobian), and so on,
        up to ``most``: a step long enough to cross several (the Coulomb pair from 159.71
        to 160.37 rad/s at ``ds_max = 0.3``: 12 events, then 16) reports each, as shorter
        steps, which cross them one at a time, do. The next change is looked for near the
        last first (``near``): on a tuned ring the contacts that graze together change the
        orbit's events in stages a few ``locate_tol`` apart (the 24-blade ring at
        277.40165527, 277.40166105 and 277.40166913 rad/s), each of which a bisection
        across the rest of the step took about 19 trials to find. Two changes found within
        twice ``locate_tol`` of each other are one grazing point (each is located only to
        ``locate_tol``: the Coulomb pair at 183.745228 rad/s, 15 events, then 16 over
        2e-6 rad/s, then 13). Where a location finds no orbit past the change (or an
        integration in it fails) the list ends with ``b``'s orbit, the first branch point
        past that grazing, with the bracket that holds it.
        """
        found = []
        lo, X_lo = a, Xa
        for _ in range(most):
            try:
                at = self._locate_grazing(lo, b, X_lo, Ta, mode, locate_tol, step=(Xa, b["X"]), near=bool(found))
            except (FlowError, np.linalg.LinAlgError, ValueError):
                # an integration of the location failed: a grazing point's place is not worth the branch
                at = _unlocated(b, _field_bracket(X_lo, b["X"], self.span))
            at_b = at["X"] is b["X"]
            if not at_b and at["signature"] == lo["signature"]:
                break   # solved to tol, the point past the grazing fell back before it: that one is known
            if not (found and not at_b and abs(float(at["X"][-1] - X_lo[-1])) <= 2.0 * locate_tol):
                # (two changes closer in the field than their locations' tolerance, which bounds the field's
                # bracket, are one grazing point)
                found.append(at)
            if at_b or at["signature"] == b["signature"] or not _between(at["X"], X_lo, b["X"]):
                break
            lo = {"X": at["X"], "A": a["A"], "signature": at["signature"]}
            X_lo, mode = at["X"], at["mode"]
        return found


def _locate_grazings_in(ctx: _Context, scale, a, b, Xa, Ta, mode, tol):
    """:meth:`_Context._locate_grazings` in ``ctx`` (the locator's), in the scale of the step that found them."""
    ctx.scale = scale
    return ctx._locate_grazings(a, b, Xa, Ta, mode, tol)


def _field_bracket(X_lo, X_hi, span) -> tuple:
    """The field's values at two scaled points, lower first."""
    lo, hi = sorted((float(X_lo[-1] * span), float(X_hi[-1] * span)))
    return lo, hi


def _unlocated(b: dict, bracket) -> dict:
    """A grazing point left at the branch point ``b`` past it, known to lie in the field's ``bracket``."""
    return {"param": b["param"], "state": b["state"], "mode": b["mode"], "X": b["X"], "signature": b["signature"],
            "bracket": bracket}


def _special(kind: str, point: dict, index: int, multiplier=None, bracket=None) -> SpecialPoint:
    """A special point at the branch point ``point`` (``multiplier``: by default its largest; ``bracket``: by
    default the point's own, if it has one)."""
    mu = point["mu"][0] if multiplier is None else multiplier
    bracket = point.get("bracket") if bracket is None else bracket
    return SpecialPoint(kind=kind, param=point["param"], state=point["state"], multiplier=complex(mu), index=index,
                        mode=_copy(point["mode"]), bracket=None if bracket is None else tuple(map(float, bracket)))


def _off_circle(p: SpecialPoint) -> bool:
    """A fold, branch point, period doubling or Neimark-Sacker point whose critical multiplier is not on the unit
    circle."""
    return p.kind not in ("grazing", "border-collision", "gap") and abs(abs(p.multiplier) - 1.0) > 0.05


def _at_kink(p) -> bool:
    """A change of stability with no multiplier on the unit circle: off it (:func:`_off_circle`), or a border
    collision (a multiplier jumping across it)."""
    return _off_circle(p) or p.kind == "border-collision"


def _between(X, X_lo, X_hi) -> bool:
    """Whether ``X`` lies strictly between two points: nearer to each than they are to each other."""
    width = np.linalg.norm(X_hi - X_lo)
    d_lo, d_hi = np.linalg.norm(X - X_lo), np.linalg.norm(X - X_hi)
    return bool(min(d_lo, d_hi) > 1e-6 * width and max(d_lo, d_hi) < width)


def _near(X, X_a, X_b) -> bool:
    """Whether ``X`` lies within a step's length of either end of the step from ``X_a`` to ``X_b``."""
    reach = np.linalg.norm(X_b - X_a)
    return bool(min(np.linalg.norm(X - X_a), np.linalg.norm(X - X_b)) <= reach)


def _crossing_multiplier(mu, k: int) -> complex:
    """The multiplier whose count outside the unit circle changes between ``k`` and ``k + 1``: the ``k + 1``-th
    largest in modulus."""
    return mu[np.argsort(-np.abs(mu), kind="stable")[k]]


def _largest_first(mu):
    """Multipliers sorted by modulus, largest first (ties in their order)."""
    return mu[np.argsort(-np.abs(mu), kind="stable")]


def _unstable_count(mu) -> int:
    return int(np.sum(np.abs(mu) > 1.0))
