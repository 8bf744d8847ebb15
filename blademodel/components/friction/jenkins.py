"""Bilinear hysteresis (Jenkins element) friction (MODEL.md section 4.2)."""

from __future__ import annotations

from dataclasses import dataclass, field

from .._sympy import sp

from ..parameter import Number, as_param
from .base import Candidate, ContactContext, FrictionLaw, Guard


@dataclass(frozen=True)
class Jenkins(FrictionLaw):
    """A spring ``kd`` in series with a Coulomb slider of limit ``mu N``.

    State
        ``z``: the spring's stretch, ``z = r1 - r_b`` (``r_b``: the slider). The
        friction force is always ``f = kd z``.
    Modes
        ``stick``: the slider moves with body 2, ``dz/dt = v``.
        ``slip+`` / ``slip-``: ``kd z = s mu N``, so ``dz/dt = s mu Ndot / kd``.
    Guards
        stick: ``mu N - s kd z`` falls through zero, slip ``s`` follows.
        slip s: ``s (v - dz/dt)`` falls through zero (the spring unloads), stick follows.
    Entry / exit
        The contact closes in stick with ``z = 0`` (points 1, 2 and b coincide) and
        opens with ``z = 0`` (continuous, since ``mu N -> 0``).

    Parameters
    ----------
    mu : float or Param
        Friction coefficient, >= 0. Default symbol ``mu``.
    kd : float or Param
        Tangential stiffness in N/m, > 0. Default symbol ``kd``.
    """

    mu: Number = 0.5
    kd: Number = 1e6
    _p: dict = field(init=False, repr=False, compare=False)

    modes = ("stick", "slip+", "slip-")
    states = ("z",)

    def __post_init__(self):
        object.__setattr__(self, "_p", {
            "mu": as_param(self.mu, "mu", field="friction: mu", minimum=0.0),
            "kd": as_param(self.kd, "kd", field="friction: kd", minimum=0.0, strict=True),
        })

    def parameters(self):
        return dict(self._p)

    def force(self, mode, ctx: ContactContext):
        return ctx.params["kd"] * ctx.states["z"]

    def _slip_rate(self, s, ctx):
        return s * ctx.params["mu"] * ctx.Ndot / ctx.params["kd"]

    def rates(self, mode, ctx: ContactContext):
        if mode == "stick":
            return {"z": ctx.v}
        return {"z": self._slip_rate(1 if mode == "slip+" else -1, ctx)}

    def guards(self, mode, ctx: ContactContext):
        mu, kd, N, z, v = ctx.params["mu"], ctx.params["kd"], ctx.N, ctx.states["z"], ctx.v
        if mode == "stick":
            return [Guard(mu * N - kd * z, -1, [Candidate("slip+")], "stick->slip+"),
                    Guard(mu * N + kd * z, -1, [Candidate("slip-")], "stick->slip-")]
        s = 1 if mode == "slip+" else -1
        return [Guard(s * (v - self._slip_rate(s, ctx)), -1, [Candidate("stick")], f"{mode}->stick")]

    def entry(self, ctx: ContactContext):
        return [Candidate("stick", sp.true, {"z": sp.Integer(0)})]

    def exit_reset(self, ctx: ContactContext):
        return {"z": sp.Integer(0)}

    def stored_energy(self, ctx: ContactContext):
        return ctx.params["kd"] * ctx.states["z"] ** 2 / 2
