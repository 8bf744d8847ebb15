"""Harmonic excitation force on a mass."""

from __future__ import annotations

from dataclasses import dataclass, field

from ._sympy import sp

from .mass import Mass
from .parameter import Number, Param, as_param


@dataclass(frozen=True)
class HarmonicForce:
    """Force ``Q = F0 sin(omega t + phase)`` acting along the angle ``angle``.

    Sign convention: the force on the mass is ``Q cos(angle)`` along ``x`` and
    ``Q sin(angle)`` along ``y`` (``angle`` measured from ``x`` towards ``y``;
    the paper's ``beta``). A component along an axis the mass does not move on
    is dropped. Its power ``Q . u`` is the input work rate.

    Parameters
    ----------
    mass : Mass
        The mass the force acts on.
    amplitude : float or Param
        ``F0`` in N, >= 0. Default symbol ``F0_<mass>``.
    omega : float or Param
        Angular frequency in rad/s, > 0. Default symbol ``omega_<mass>``.
    phase : float or Param
        Phase in rad. Default symbol ``phi_<mass>``.
    angle : float or Param
        Direction angle in rad. Default symbol ``beta_<mass>``.
    """

    mass: Mass
    amplitude: Number
    omega: Number
    phase: Number = 0.0
    angle: Number = 0.0
    _p: dict = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        n = self.mass.name
        object.__setattr__(self, "_p", {
            "amplitude": as_param(self.amplitude, f"F0_{n}", field=f"force on {n}: amplitude", minimum=0.0),
            "omega": as_param(self.omega, f"omega_{n}", field=f"force on {n}: omega", minimum=0.0, strict=True),
            "phase": as_param(self.phase, f"phi_{n}", field=f"force on {n}: phase"),
            "angle": as_param(self.angle, f"beta_{n}", field=f"force on {n}: angle"),
        })

    @property
    def coordinates(self) -> tuple[str, ...]:
        return self.mass.coordinates

    def parameters(self) -> dict[str, Param]:
        return dict(self._p)

    def magnitude(self, t: sp.Symbol) -> sp.Expr:
        """``Q(t)``."""
        p = {k: v.symbol for k, v in self._p.items()}
        return p["amplitude"] * sp.sin(p["omega"] * t + p["phase"])

    def loads(self, q, u, t) -> dict[str, sp.Expr]:
        """Generalized forces, by coordinate name."""
        Q = self.magnitude(t)
        beta = self._p["angle"].symbol
        out = {}
        for dof, proj in (("x", sp.cos(beta)), ("y", sp.sin(beta))):
            c = self.mass.coordinate(dof)
            if c is not None:
                out[c] = Q * proj
        return out
