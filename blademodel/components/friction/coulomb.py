"""Coulomb friction with rigid stick (MODEL.md section 4.1)."""

from __future__ import annotations

from dataclasses import dataclass, field

from .._sympy import sp

from ..parameter import Number, Param, as_param
from .base import STICK, Candidate, ContactContext, FrictionLaw, Guard


@dataclass(frozen=True)
class Coulomb(FrictionLaw):
    """Coulomb's law, static = kinetic coefficient ``mu``.

    Modes
        ``slip+`` / ``slip-``: ``f = s mu N`` with ``s = +1 / -1``, the sign of ``v``.
        ``stick``: ``v`` is held at zero; ``f`` is the constraint force (derived by
        the symbolic layer from ``dv/dt = 0``, so unequal masses work).
    Guards
        slip s: ``v`` crosses zero; stick follows if ``|f_stick| <= mu N``, else the
        slip reverses. stick: ``mu N - s f`` falls through zero; slip ``s`` follows.
    Entry (contact closes)
        slip with the sign of ``v``; if ``v = 0`` exactly, stick if it holds, else
        slip along the stick force.

    Parameters
    ----------
    mu : float or Param
        Friction coefficient, >= 0. Default symbol ``mu``.
    stick_velocity_tol : float or Param
        Velocity band in m/s: slip ends when ``|v|`` falls to this value rather
        than to zero (the paper's "error limit" on the relative velocity). The
        default 0 is the exact treatment; the velocity jump to ``v = 0`` at stick
        entry is then of the order of round-off.
    """

    mu: Number = 0.5
    stick_velocity_tol: Number = 0.0
    _p: dict = field(init=False, repr=False, compare=False)

    modes = ("stick", "slip+", "slip-")

    def __post_init__(self):
        object.__setattr__(self, "_p", {
            "mu": as_param(self.mu, "mu", field="friction: mu", minimum=0.0),
        })
        if isinstance(self.stick_velocity_tol, Param) or float(self.stick_velocity_tol) != 0.0:
            self._p["stick_velocity_tol"] = as_param(
                self.stick_velocity_tol, "v_tol", field="friction: stick_velocity_tol", minimum=0.0)

    def parameters(self):
        return dict(self._p)

    def force(self, mode, ctx: ContactContext):
        mu = ctx.params["mu"]
        if mode == "stick":
            return STICK
        s = 1 if mode == "slip+" else -1
        return s * mu * ctx.N

    def guards(self, mode, ctx: ContactContext):
        mu, N, f, v = ctx.params["mu"], ctx.N, ctx.f, ctx.v
        stick_holds = mu * N - sp.Abs(f) >= 0
        if mode == "stick":
            return [Guard(mu * N - f, -1, [Candidate("slip+")], "stick->slip+"),
                    Guard(mu * N + f, -1, [Candidate("slip-")], "stick->slip-")]
        s = 1 if mode == "slip+" else -1
        other = "slip-" if s == 1 else "slip+"
        band = ctx.params.get("stick_velocity_tol", sp.Integer(0))
        return [Guard(s * v - band, -1, [Candidate("stick", stick_holds), Candidate(other)],
                      f"{mode}: v=0")]

    def entry(self, ctx: ContactContext):
        mu, N, f, v = ctx.params["mu"], ctx.N, ctx.f, ctx.v
        return [Candidate("slip+", sp.StrictGreaterThan(v, 0)),
                Candidate("slip-", sp.StrictLessThan(v, 0)),
                Candidate("stick", mu * N - sp.Abs(f) >= 0),
                Candidate("slip+", sp.StrictGreaterThan(f, 0)),
                Candidate("slip-")]
