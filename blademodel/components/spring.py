"""Linear spring on one coordinate, to ground or to another coordinate."""

from __future__ import annotations

from dataclasses import dataclass, field

from ._sympy import sp

from .parameter import Number, Param, as_param


@dataclass(frozen=True)
class Spring:
    """Linear spring of stiffness ``k`` on the stretch ``q_a - q_b``.

    Sign convention: the force on ``a`` is ``-k (q_a - q_b)`` and on ``b`` the
    opposite; without ``b`` the spring is grounded (``q_b = 0``). Potential
    energy ``k (q_a - q_b)^2 / 2``.

    Parameters
    ----------
    a : str
        Coordinate name (``"x1"``).
    k : float or Param
        Stiffness in N/m, >= 0. Default symbol ``k_<a>`` (or ``k_<a>_<b>``).
    b : str, optional
        Second coordinate; ``None`` grounds the spring.
    """

    a: str
    k: Number
    b: str | None = None
    _k: Param = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        if self.b == self.a:
            raise ValueError(f"{type(self).__name__.lower()} joins {self.a!r} to itself")
        tag = self.a if self.b is None else f"{self.a}_{self.b}"
        object.__setattr__(self, "_k", as_param(self.k, f"k_{tag}", field=f"spring on {tag}: k", minimum=0.0))

    @property
    def coordinates(self) -> tuple[str, ...]:
        return (self.a,) if self.b is None else (self.a, self.b)

    def parameters(self) -> dict[str, Param]:
        return {"k": self._k}

    def stretch(self, q: dict[str, sp.Symbol]) -> sp.Expr:
        return q[self.a] - (q[self.b] if self.b is not None else 0)

    def loads(self, q, u, t) -> dict[str, sp.Expr]:
        """Generalized forces, by coordinate name."""
        f = -self._k.symbol * self.stretch(q)
        out = {self.a: f}
        if self.b is not None:
            out[self.b] = -f
        return out

    def potential_energy(self, q) -> sp.Expr:
        return self._k.symbol * self.stretch(q) ** 2 / 2
