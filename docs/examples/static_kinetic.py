"""Coulomb friction with separate static and kinetic coefficients.

The worked example of ``docs/friction_laws.md``: a friction law written outside
the blademodel package, against the public interface of
:mod:`blademodel.components.friction.base` only. Use it from YAML with
``law: static_kinetic:StaticKineticCoulomb`` (this folder on ``PYTHONPATH``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp

from blademodel.components.friction import STICK, Candidate, ContactContext, FrictionLaw, Guard
from blademodel.components.parameter import Number, as_param


@dataclass(frozen=True)
class StaticKineticCoulomb(FrictionLaw):
    """Rigid stick while ``|f| <= mu_s N``; slip at ``f = s mu_k N`` with ``mu_k <= mu_s``.

    Modes
        ``stick``: ``v`` is held at zero, ``f`` is the constraint force.
        ``slip+`` / ``slip-``: ``f = s mu_k N``, ``s`` the sign of ``v``.
    Guards
        stick: ``mu_s N - s f`` falls through zero: slip ``s`` follows.
        slip s: ``s v`` falls through zero: stick if ``|f_stick| <= mu_s N``,
        otherwise the slip reverses.
    Entry
        slip with the sign of ``v``; if ``v = 0``, stick if it holds.

    Parameters
    ----------
    mu_s, mu_k : float or Param
        Static and kinetic friction coefficients, ``0 <= mu_k <= mu_s``.
    """

    mu_s: Number = 0.6
    mu_k: Number = 0.5
    _p: dict = field(init=False, repr=False, compare=False)

    modes = ("stick", "slip+", "slip-")

    def __post_init__(self):
        p = {"mu_s": as_param(self.mu_s, "mu_s", field="friction: mu_s", minimum=0.0),
             "mu_k": as_param(self.mu_k, "mu_k", field="friction: mu_k", minimum=0.0)}
        if p["mu_k"].value > p["mu_s"].value:
            raise ValueError(f"friction: mu_k = {p['mu_k'].value} must not exceed mu_s = {p['mu_s'].value}")
        object.__setattr__(self, "_p", p)

    def parameters(self):
        return dict(self._p)

    def force(self, mode, ctx: ContactContext):
        if mode == "stick":
            return STICK
        s = 1 if mode == "slip+" else -1
        return s * ctx.params["mu_k"] * ctx.N

    def guards(self, mode, ctx: ContactContext):
        mu_s, N, f, v = ctx.params["mu_s"], ctx.N, ctx.f, ctx.v
        if mode == "stick":
            return [Guard(mu_s * N - f, -1, [Candidate("slip+")], "stick->slip+"),
                    Guard(mu_s * N + f, -1, [Candidate("slip-")], "stick->slip-")]
        s = 1 if mode == "slip+" else -1
        other = "slip-" if s == 1 else "slip+"
        holds = mu_s * N - sp.Abs(f) >= 0
        return [Guard(s * v, -1, [Candidate("stick", holds), Candidate(other)], f"{mode}: v=0")]

    def entry(self, ctx: ContactContext):
        mu_s, N, f, v = ctx.params["mu_s"], ctx.N, ctx.f, ctx.v
        return [Candidate("slip+", sp.StrictGreaterThan(v, 0)),
                Candidate("slip-", sp.StrictLessThan(v, 0)),
                Candidate("stick", mu_s * N - sp.Abs(f) >= 0),
                Candidate("slip+", sp.StrictGreaterThan(f, 0)),
                Candidate("slip-")]
