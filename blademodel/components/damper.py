"""Linear viscous damper on one coordinate, to ground or to another coordinate."""

from __future__ import annotations

from dataclasses import dataclass, field

from ._sympy import sp

from .parameter import Number, Param, as_param


@dataclass(frozen=True)
class Damper:
    """Viscous damper of coefficient ``c`` on the rate ``u_a - u_b``.

    Sign convention: the force on ``a`` is ``-c (u_a - u_b)`` and on ``b`` the
    opposite; without ``b`` the damper is grounded. Dissipated power
    ``c (u_a - u_b)^2``.

    Parameters
    ----------
    a : str
        Coordinate name (``"x1"``).
    c : float or Param
        Damping coefficient in N s/m, >= 0. Default symbol ``c_<a>``.
    b : str, optional
        Second coordinate; ``None`` grounds the damper.
    """

    a: str
    c: Number
    b: str | None = None
    _c: Param = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        if self.b == self.a:
            raise ValueError(f"{type(self).__name__.lower()} joins {self.a!r} to itself")
        tag = self.a if self.b is None else f"{self.a}_{self.b}"
        object.__setattr__(self, "_c", as_param(self.c, f"c_{tag}", field=f"damper on {tag}: c", minimum=0.0))

    @property
    def coordinates(self) -> tuple[str, ...]:
        return (self.a,) if self.b is None else (self.a, self.b)

    def parameters(self) -> dict[str, Param]:
        return {"c": self._c}

    def rate(self, u: dict[str, sp.Symbol]) -> sp.Expr:
        return u[self.a] - (u[self.b] if self.b is not None else 0)

    def loads(self, q, u, t) -> dict[str, sp.Expr]:
        """Generalized forces, by coordinate name."""
        f = -self._c.symbol * self.rate(u)
        out = {self.a: f}
        if self.b is not None:
            out[self.b] = -f
        return out

    def dissipation_rate(self, u) -> sp.Expr:
        return self._c.symbol * self.rate(u) ** 2
