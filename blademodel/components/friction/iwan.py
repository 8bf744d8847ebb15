"""Iwan micro-slip friction: Jenkins elements in parallel (written against the public interface)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Optional, Sequence

from .._sympy import sp

from ..parameter import Number, as_param
from .base import Candidate, ContactContext, FrictionLaw, Guard

#: Names of the built-in element distributions.
DISTRIBUTIONS = ("uniform", "custom")


def uniform_fractions(n: int) -> tuple[tuple[sp.Rational, ...], tuple[sp.Rational, ...]]:
    """Stiffness and slip-force fractions of the ``uniform`` distribution of ``n`` elements.

    Every element has the stiffness ``kd / n`` and element ``i = 1..n`` the slip force
    ``mu N (2 i - 1) / n**2``, so its slip displacement is ``(2 i - 1) / n * mu N / kd``:
    the midpoints of ``n`` equal cells of ``(0, 2 mu N / kd)``. Exact rationals.

    Returns
    -------
    stiffness, slip : tuple of sympy.Rational
        ``kd_i / kd`` and ``phi_i``; each sums to 1.
    """
    return (tuple(sp.Rational(1, n) for _ in range(n)),
            tuple(sp.Rational(2 * i - 1, n * n) for i in range(1, n + 1)))


def energy_per_cycle(a: float, *, mu: float, N: float, kd: float, stiffness: Sequence[float],
                     slip: Sequence[float]) -> float:
    """Energy dissipated per cycle of an imposed slip ``a sin(w t)`` at constant ``N``.

    Element ``i`` (stiffness ``kd_i = stiffness[i] kd``, slip force
    ``mu N slip[i]``, slip displacement ``d_i = mu N slip[i] / kd_i``) dissipates
    ``4 kd_i d_i (a - d_i)`` if ``a > d_i``, else nothing.
    """
    total = 0.0
    for c, phi in zip(stiffness, slip):
        k_i = float(c) * kd
        d_i = mu * N * float(phi) / k_i
        if a > d_i:
            total += 4.0 * k_i * d_i * (a - d_i)
    return total


def continuous_energy_per_cycle(a: float, *, mu: float, N: float, kd: float) -> float:
    """The ``n -> infinity`` limit of :func:`energy_per_cycle` for the ``uniform`` distribution.

    With ``d0 = mu N / kd``: ``kd a**3 / (3 d0)`` for ``a <= 2 d0`` (micro-slip, the
    contact is never fully sliding) and ``4 mu N (a - 4 d0 / 3)`` beyond (gross slip).
    """
    d0 = mu * N / kd
    if a <= 2 * d0:
        return kd * a ** 3 / (3 * d0)
    return 4 * mu * N * (a - 4 * d0 / 3)


def _least(terms: list):
    """``min`` of the terms (the term itself if there is one)."""
    return terms[0] if len(terms) == 1 else sp.Min(*terms, evaluate=False)


@dataclass(frozen=True)
class Iwan(FrictionLaw):
    """An Iwan model: ``n`` Jenkins elements in parallel, one closed mode.

    Element ``i`` is a spring ``kd_i`` in series with a slider of limit force
    ``mu N phi_i``, with ``sum kd_i = kd`` and ``sum phi_i = 1``: the total initial
    stiffness and the limit force are those of the bilinear law
    (:class:`~blademodel.components.friction.jenkins.Jenkins`), and ``n = 1`` *is*
    the bilinear law. The elements reach their slip force one after another, so the
    force-displacement loop is rounded (micro-slip) instead of bilinear.

    States
        ``z1 .. zn``: the elements' stretches; ``s1 .. sn``: the elements' modes as
        numbers, ``0`` stick, ``+1`` / ``-1`` slip in that direction. The ``s_i``
        have zero rate and change only in resets, so the law has a **single**
        closed mode ``closed`` (per-element modes would make ``3**n`` global modes).
        They are its ``discrete_states``: a periodic orbit holds them as part of its
        mode, they are not unknowns of the shooting.
    Force
        ``f = sum_i kd_i z_i``.
    Rates
        ``dz_i/dt = v`` while element ``i`` sticks (``s_i = 0``), else
        ``s_i mu phi_i Ndot / kd_i`` (``kd_i z_i = s_i mu N phi_i`` is held), written
        as ``sympy.Piecewise`` in ``s_i``.
    Guards (three, shared by the elements; each falls through zero)
        ``stick->slip+``: the least over the sticking elements of
        ``mu N phi_i - kd_i z_i`` (a slipping element counts as ``1``, which never
        crosses); ``stick->slip-``: likewise with ``mu N phi_i + kd_i z_i``;
        ``slip->stick``: the least over the slipping elements of
        ``s_i (v - dz_i/dt)`` (the element unloads).
    Reset (the same for the three guards)
        Every element takes the mode its own conditions call for: a sticking
        element past its slip force and loading further (``mu N phi_i - kd_i z_i
        < 0`` and ``v > mu phi_i Ndot / kd_i``) slips, ``s_i = +1``, and likewise
        ``-1``; a slipping element that unloads (``s_i (v - dz_i/dt) < 0``)
        sticks, ``s_i = 0``, with its stretch set to its slip force exactly
        (``kd_i z_i = s_i mu N phi_i``, which the slip phase holds only to the
        integration error: a stretch a rounding error past it would start the
        shared stick guard below zero, where it is never seen to cross; even set
        so, the guard can start an ulp below zero, and the per-contact kernel
        reads such a guard from the boundary, ``contact_guards.mark_drifted``);
        every other element keeps its mode.
    Why shared guards
        The solver fires one guard per event and evaluates the guards afresh
        after it, so a guard that crossed zero in the same instant as the one that
        fired is already below zero and is never seen to cross. Elements do
        switch together: when the contact closes all of them stick at ``z = 0``
        under a vanishing slip force, and every one that the motion loads slips
        within the same event bracket; at constant ``N`` all slipping elements
        unload together at ``v = 0``. Shared guards whose reset settles every
        element keep each such event whole, and keep the generated code linear in
        ``n``. The loading condition keeps an element that has just stuck, still
        a rounding error past its slip force while it unloads, from being sent
        back to slip by another element's event.
    Entry / exit
        The contact closes with every element sticking unstretched (``z_i = 0``,
        ``s_i = 0``, as the bilinear law) and opens the same way.

    Distributions
        ``uniform`` (default): equal stiffnesses ``kd / n`` and slip forces
        ``phi_i = (2 i - 1) / n**2``, so the slip displacements
        ``d_i = (2 i - 1) / n * mu N / kd`` are spread evenly over
        ``(0, 2 mu N / kd)``: the midpoint discretisation of an Iwan density that is
        uniform on that interval. Under an imposed slip ``a sin(w t)`` at constant
        ``N`` the energy per cycle is ``sum_{d_i < a} 4 (kd / n) d_i (a - d_i)``
        (:func:`energy_per_cycle`); its limit (:func:`continuous_energy_per_cycle`)
        is ``kd a**3 / (3 d0)`` below gross slip ``a <= 2 d0``, ``d0 = mu N / kd``.
        ``custom``: ``stiffness_fractions`` ``kd_i / kd`` and ``slip_fractions``
        ``phi_i``, each positive, ``n`` long and summing to 1.

    Parameters
    ----------
    mu : float or Param
        Friction coefficient, >= 0. Default symbol ``mu``.
    kd : float or Param
        Total tangential stiffness in N/m, > 0. Default symbol ``kd``.
    elements : int
        Number of Jenkins elements ``n`` >= 1 (fixes the generated code).
    distribution : str, optional
        ``"uniform"`` (the default) or ``"custom"`` (the default when the fractions
        are given).
    stiffness_fractions, slip_fractions : sequence of float, optional
        The ``custom`` distribution.
    """

    mu: Number = 0.5
    kd: Number = 1e6
    elements: int = 4
    distribution: Optional[str] = None
    stiffness_fractions: Optional[Sequence[float]] = None
    slip_fractions: Optional[Sequence[float]] = None
    _p: dict = field(init=False, repr=False, compare=False)
    _frac: tuple = field(init=False, repr=False, compare=False)

    modes = ("closed",)

    def __post_init__(self):
        n = self.elements
        if isinstance(n, bool) or not isinstance(n, (int, float)) or n != int(n) or n < 1:
            raise ValueError(f"friction: elements = {n!r} must be an integer >= 1")
        n = int(n)
        object.__setattr__(self, "elements", n)
        custom = self.stiffness_fractions is not None or self.slip_fractions is not None
        dist = self.distribution or ("custom" if custom else "uniform")
        if dist not in DISTRIBUTIONS:
            raise ValueError(f"friction: distribution = {self.distribution!r} must be one of "
                             f"{', '.join(DISTRIBUTIONS)}")
        if dist == "uniform" and custom:
            raise ValueError("friction: distribution = 'uniform' takes no stiffness_fractions or slip_fractions "
                             "(give distribution: custom)")
        object.__setattr__(self, "distribution", dist)
        if dist == "uniform":
            frac = uniform_fractions(n)
        else:
            frac = tuple(self._fractions(name, n) for name in ("stiffness_fractions", "slip_fractions"))
            for name, fr in zip(("stiffness_fractions", "slip_fractions"), frac):
                object.__setattr__(self, name, fr)
        object.__setattr__(self, "_frac", frac)
        object.__setattr__(self, "_p", {
            "mu": as_param(self.mu, "mu", field="friction: mu", minimum=0.0),
            "kd": as_param(self.kd, "kd", field="friction: kd", minimum=0.0, strict=True),
        })
        object.__setattr__(self, "states", tuple(f"z{i}" for i in range(1, n + 1))
                           + tuple(f"s{i}" for i in range(1, n + 1)))
        object.__setattr__(self, "discrete_states", tuple(f"s{i}" for i in range(1, n + 1)))

    def _fractions(self, name: str, n: int) -> tuple[float, ...]:
        values = getattr(self, name)
        if values is None:
            raise ValueError(f"friction: {name} is missing: the custom distribution needs both "
                             "stiffness_fractions and slip_fractions")
        try:
            out = tuple(float(x) for x in values)
        except (TypeError, ValueError):
            raise ValueError(f"friction: {name} = {values!r} must be a list of numbers") from None
        if len(out) != n:
            raise ValueError(f"friction: {name} has {len(out)} values, expected elements = {n}")
        if not all(math.isfinite(x) and x > 0 for x in out):
            raise ValueError(f"friction: {name} = {list(out)} must be positive and finite")
        if abs(math.fsum(out) - 1.0) > 1e-12:
            raise ValueError(f"friction: {name} = {list(out)} must sum to 1 (sum {math.fsum(out)!r})")
        return out

    # --- the law ------------------------------------------------------------------
    @property
    def fractions(self) -> tuple[tuple, tuple]:
        """``(kd_i / kd, phi_i)`` of the elements."""
        return self._frac

    def _elements(self, ctx: ContactContext):
        """Per element: ``(z_i, s_i, kd_i, mu N phi_i, mu phi_i Ndot / kd_i)``.

        The last is the rate of ``z_i`` in slip ``+1``; in slip ``s_i`` it is ``s_i`` times that.
        """
        mu, kd = ctx.params["mu"], ctx.params["kd"]
        out = []
        for i, (c, phi) in enumerate(zip(*self._frac), start=1):
            z, s = ctx.states[f"z{i}"], ctx.states[f"s{i}"]
            k_i = c * kd
            out.append((z, s, k_i, mu * phi * ctx.N, mu * phi * ctx.Ndot / k_i))
        return out

    def parameters(self):
        return dict(self._p)

    def force(self, mode, ctx: ContactContext):
        return sp.Add(*[k_i * z for z, _, k_i, _, _ in self._elements(ctx)])

    def rates(self, mode, ctx: ContactContext):
        return {f"z{i}": sp.Piecewise((ctx.v, sp.Eq(s, 0)), (s * rate, True))
                for i, (_, s, _, _, rate) in enumerate(self._elements(ctx), start=1)}

    def guards(self, mode, ctx: ContactContext):
        one = sp.Integer(1)
        loads, unloads, switch = ([], []), [], {}
        for i, (z, s, k_i, limit, rate) in enumerate(self._elements(ctx), start=1):
            sticking = sp.Eq(s, 0)
            up, down = limit - k_i * z, limit + k_i * z          # stick holds while both are >= 0
            unloading = s * (ctx.v - s * rate)                   # slip s holds while >= 0
            loads[0].append(sp.Piecewise((up, sticking), (one, True)))
            loads[1].append(sp.Piecewise((down, sticking), (one, True)))
            unloads.append(sp.Piecewise((one, sticking), (unloading, True)))
            sticks_now = sp.And(sp.Not(sticking), unloading < 0)
            switch[f"s{i}"] = sp.Piecewise(
                (1, sp.And(sticking, up < 0, ctx.v - rate > 0)),
                (-1, sp.And(sticking, down < 0, ctx.v + rate < 0)),
                (0, sticks_now),
                (s, True))
            # An element that sticks keeps the stretch of its slip force exactly: the slip phase holds
            # kd_i z_i = s mu N phi_i only to the integration error, and a stretch a rounding error past
            # the force would start the shared stick guard below zero, where it never crosses.
            switch[f"z{i}"] = sp.Piecewise((s * limit / k_i, sticks_now), (z, True))
        settle = [Candidate("closed", sp.true, switch)]
        return [Guard(_least(loads[0]), -1, settle, "stick->slip+"),
                Guard(_least(loads[1]), -1, settle, "stick->slip-"),
                Guard(_least(unloads), -1, settle, "slip->stick")]

    def _relaxed(self) -> dict:
        return {st: sp.Integer(0) for st in self.states}

    def entry(self, ctx: ContactContext):
        return [Candidate("closed", sp.true, self._relaxed())]

    def exit_reset(self, ctx: ContactContext):
        return self._relaxed()

    def stored_energy(self, ctx: ContactContext):
        return sp.Add(*[k_i * z ** 2 / 2 for z, _, k_i, _, _ in self._elements(ctx)])

    def structure(self) -> tuple:
        return super().structure() + (self.distribution, tuple(str(x) for x in self._frac[0]),
                                      tuple(str(x) for x in self._frac[1]))
