"""A branch of periodic orbits and its special points: what :func:`~.arclength.continuation` returns."""


from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

import numpy as np



@dataclass
class SpecialPoint:
    """A bifurcation found on a branch.

    Attributes
    ----------
    kind : str
        ``"fold"`` (a multiplier through ``+1`` where the branch turns back in the field),
        ``"branch-point"`` (one through ``+1`` where it goes on: another branch crosses it,
        :func:`branch_point_branch`), ``"period-doubling"``, ``"neimark-sacker"`` or ``"grazing"`` (the orbit's
        events change, which transitions or how many: a guard of the orbit touches zero), or
        ``"gap"``: no orbit was found between the branch point before and this one (``bracket``),
        where the step fell below ``ds_min``; the branch goes on from the first orbit that
        shooting at fixed values past the stall found from the last one (the integrator's
        discrete flow can lack orbits over a short stretch, which moves with the step: more
        steps a period may close it; the orbits either side may lie on different branches;
        ``multiplier`` is the largest of the orbit past it);
        ``"nonsmooth-fold"``: the branch turns back at a kink of the map (a grazing), its
        stability changing with no multiplier on the unit circle (one jumps across it);
        located only to within the last step across the kink; or ``"border-collision"``:
        the stability changes at a kink of the map where the branch goes on, a multiplier
        jumping across the unit circle (its modulus differs across a bracket a thousandth
        of the step about as much as across the step; ``multiplier`` is that one, past the
        kink); located to within that bracket (a tenth of the step where a trial beside the
        kink failed), or at the grazing found in it (to ``locate_tol``), then its kink.
    param : float
        The field's value there (located to ``locate_tol`` of the range).
    state : ndarray
        The orbit's section state there.
    multiplier : complex
        The multiplier that crossed the unit circle, at the located point; at a grazing
        point, the largest multiplier of the branch point before it (the map is not
        differentiable at the grazing); at a border collision, the one that jumps across
        the circle, past the kink; at a nonsmooth fold, one beside it, off the circle.
    index : int
        The branch point after which it lies.
    mode : int or ndarray, optional
        The orbit's hybrid mode at the section (not kept in branch files).
    bracket : tuple of float, optional
        The field's values ``(lo, hi)`` between which the point lies, where its location
        ended wider than ``locate_tol``: a border collision's bracket, or a grazing whose
        bisection stopped because no orbit could be solved inside (the discrete flow sees
        a phase that appears only once it spans a step, and just past a grazing
        shooting then stalls: the Coulomb pair between 305.7811 and 305.7831 rad/s).
        ``param`` is then the best estimate inside it: the first orbit found past the
        change, or where that could not be solved to ``tol`` (in such a gap) the trial,
        solved only to tell its side, that lay past it. None where located to
        ``locate_tol``.
    """

    kind: str
    param: float
    state: np.ndarray
    multiplier: complex
    index: int
    mode: object = None
    bracket: tuple | None = None

    def __repr__(self) -> str:
        # what a reader looks for; the state and the mode are attributes to ask for
        within = "" if self.bracket is None else f", bracket=({self.bracket[0]:.10g}, {self.bracket[1]:.10g})"
        mu = complex(self.multiplier)
        return (f"SpecialPoint(kind={self.kind!r}, param={float(self.param):.10g}, "
                f"multiplier={mu.real:.6g}{mu.imag:+.6g}j, index={self.index}{within})")


@dataclass
class Branch:
    """A continued branch of periodic orbits.

    Attributes
    ----------
    field : str
        The continued config field.
    periods : int
    params : ndarray, shape (points,)
    states : ndarray, shape (points, states)
        Section states at ``t = 0``.
    multipliers : ndarray, shape (points, states), complex
        Floquet multipliers per point, largest modulus first.
    stable : ndarray of bool
    amplitudes : ndarray, shape (points, states)
        Half the peak-to-peak excursion of each state over the orbit.
    harmonics : ndarray, shape (points, states), complex
        First harmonic (of the excitation) of each state.
    events : ndarray of int
        Events per orbit (over ``periods`` excitation periods).
    residuals : ndarray, shape (points,)
        Each orbit's scaled residual ``max |P(y) - y| / scale`` in the mode it is recorded
        in (at most ``tol``; the scale is each state's excursion on the branch).
    sections : ndarray, shape (points, periods, states)
        The states at ``t = k T``, ``k = 0 .. periods - 1``: the orbit's Poincare samples
        (a period-2 orbit has two; a bifurcation diagram draws them all).
    special : list of SpecialPoint
        In their order along the branch (by the point after which each lies, then along
        the step from it).
    state_names : list of str
    message : str
        Why the continuation ended.
    integrations : int
        What the branch cost, after its first orbit: the integrations of the period map
        (each over ``periods`` excitation periods; residuals, difference quotients,
        trials that locate special points), counted whatever the machine's speed.
    replays : int
        The tangent replays of a kept run (variational equations and saltation matrices
        along the run's logged events, no integration of the flow).
    modes : ndarray of int, shape (points, width)
        Each orbit's hybrid mode at the section: one entry on the product-mode kernel,
        one per contact on the per-contact kernel (what a resumed continuation starts
        its first orbit in); ``-1`` where unknown (points from a file written before
        modes were kept).
    mean_squares : ndarray, shape (points, states)
        Each state's time-mean square over the orbit (its closing sample left out): the
        ``P`` of the vibration reduction ``P_d``
        (:func:`~blademodel.orbits.branch_reduction.branch_vibration_reduction`); NaN in
        points from a file written before they were kept.
    complete : bool
        False for a branch saved or returned before its continuation ended (a
        checkpoint, or after Ctrl-C): :func:`~.arclength.continuation` resumes it (``resume``).
    """

    field: str
    periods: int
    params: np.ndarray
    states: np.ndarray
    multipliers: np.ndarray
    stable: np.ndarray
    amplitudes: np.ndarray
    harmonics: np.ndarray
    events: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    residuals: np.ndarray = field(default_factory=lambda: np.zeros(0))
    sections: np.ndarray = field(default_factory=lambda: np.zeros((0, 1, 0)))
    special: list = field(default_factory=list)
    state_names: list = field(default_factory=list)
    message: str = ""
    integrations: int = 0
    replays: int = 0
    modes: np.ndarray = field(default_factory=lambda: np.zeros((0, 1), dtype=np.int64))
    complete: bool = True
    mean_squares: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))

    def points(self, kind: str) -> list:
        """The special points of one kind."""
        return [p for p in self.special if p.kind == kind]

    def special_counts(self) -> str:
        """The special points counted by kind, in the order their kinds first occur along the branch, e.g.
        ``"1 period-doubling, 58 grazing"`` (empty where there are none)."""
        return ", ".join(f"{k} {kind}" for kind, k in Counter(p.kind for p in self.special).items())

    def __repr__(self) -> str:
        # a summary: the arrays (thousands of numbers on an FRF) are attributes to ask for
        n = len(self.params)
        if n == 0:
            return f"Branch({self.field}: no points; {self.message})"
        special = self.special_counts() or "none"
        ended = self.message if self.complete else f"unfinished: {self.message}"
        return (f"Branch({self.field} from {self.params[0]:.6g} to {self.params[-1]:.6g}: {n} period-{self.periods} "
                f"orbits, {int(np.sum(~np.asarray(self.stable, dtype=bool)))} unstable; special points: {special}; "
                f"{ended})")


class ContinuationInterrupted(KeyboardInterrupt):
    """Ctrl-C (or a signal raised as one) during a continuation; ``branch`` holds the points found.

    A :class:`KeyboardInterrupt`, so it stops a program as Ctrl-C does; the branch
    (``complete`` False) can be saved, drawn, or passed back as ``resume``.
    """

    def __init__(self, message: str, branch: Branch):
        super().__init__(message)
        self.branch = branch
