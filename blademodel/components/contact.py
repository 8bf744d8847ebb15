"""Gapped contact between two masses (or a mass and the ground), with friction."""

from __future__ import annotations

from dataclasses import dataclass, field

from ._sympy import sp

from .friction.base import FrictionLaw
from .friction.none import NoFriction
from .friction.validation import FrictionLawError, check_law
from .mass import Mass
from .parameter import Number, Param, as_param


@dataclass(frozen=True)
class Contact:
    """A contact face at angle ``alpha`` between ``body1`` and ``body2``.

    Projection (MODEL.md Eq. 1), for each body ``i``::

        r_i = x_i cos(alpha) + y_i sin(alpha)     (tangential)
        n_i = x_i sin(alpha) - y_i cos(alpha)     (normal)

    An axis a body does not move on counts as zero; ``body2=None`` is the ground.
    Penetration ``delta = n1 - n2 - gap``; the normal force is ``N = k delta`` while
    ``delta >= 0`` and zero otherwise (``gap < 0`` is a preload).

    Sign convention: ``N`` pushes body 1 along ``-n`` and body 2 along ``+n``; the
    friction force ``f`` acts on body 1 along ``-r`` and on body 2 along ``+r``
    (MODEL.md Eq. 2). The contact spring stores ``k delta^2 / 2`` while closed.

    Parameters
    ----------
    body1, body2 : Mass or None
        The two bodies; ``body2=None`` makes the second surface fixed.
    gap : float or Param
        Initial gap ``Delta`` in m (any sign). Default symbol ``Delta_<name>``.
    alpha : float or Param
        Contact angle in rad. Default symbol ``alpha_<name>``.
    k : float or Param
        Normal contact stiffness in N/m, >= 0. Default symbol ``k_<name>``.
    friction : FrictionLaw
        The tangential law; :class:`NoFriction` by default.
    name : str
        Label used in mode names and default symbols.
    """

    body1: Mass
    body2: Mass | None
    gap: Number
    alpha: Number
    k: Number
    friction: FrictionLaw = field(default_factory=NoFriction)
    name: str = "c"
    _p: dict = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        if not self.name.isidentifier():
            raise ValueError(f"contact name {self.name!r} must be an identifier")
        if not isinstance(self.friction, FrictionLaw):
            raise TypeError(f"contact {self.name}: friction = {self.friction!r} is not a FrictionLaw")
        try:
            check_law(self.friction)
        except FrictionLawError as e:
            raise FrictionLawError(f"contact {self.name}: {e}") from None
        if self.body2 is not None and self.body2.name == self.body1.name:
            raise ValueError(f"contact {self.name}: a body cannot touch itself ({self.body1.name})")
        n = self.name
        object.__setattr__(self, "_p", {
            "gap": as_param(self.gap, f"Delta_{n}", field=f"contact {n}: gap"),
            "alpha": as_param(self.alpha, f"alpha_{n}", field=f"contact {n}: alpha"),
            "k": as_param(self.k, f"k_{n}", field=f"contact {n}: k", minimum=0.0),
        })

    @property
    def bodies(self) -> tuple[Mass, ...]:
        return (self.body1,) if self.body2 is None else (self.body1, self.body2)

    @property
    def modes(self) -> tuple[str, ...]:
        """Modes of this contact: ``open`` and the friction law's closed modes."""
        return ("open",) + tuple(self.friction.modes)

    def parameters(self) -> dict[str, Param]:
        return dict(self._p)

    def _project(self, body: Mass | None, q: dict) -> tuple[sp.Expr, sp.Expr]:
        if body is None:
            return sp.Integer(0), sp.Integer(0)
        a = self._p["alpha"].symbol
        x = q[body.coordinate("x")] if body.coordinate("x") else 0
        y = q[body.coordinate("y")] if body.coordinate("y") else 0
        return x * sp.cos(a) + y * sp.sin(a), x * sp.sin(a) - y * sp.cos(a)

    def tangential(self, q: dict) -> tuple[sp.Expr, sp.Expr]:
        """``(r1, r2)`` as expressions of the coordinates ``q``."""
        return self._project(self.body1, q)[0], self._project(self.body2, q)[0]

    def normal(self, q: dict) -> tuple[sp.Expr, sp.Expr]:
        """``(n1, n2)`` as expressions of the coordinates ``q``."""
        return self._project(self.body1, q)[1], self._project(self.body2, q)[1]

    def penetration(self, q: dict) -> sp.Expr:
        """``delta = n1 - n2 - gap``."""
        n1, n2 = self.normal(q)
        return n1 - n2 - self._p["gap"].symbol

    def relative_slip(self, q: dict) -> sp.Expr:
        """``r1 - r2``; its time derivative is ``v``."""
        r1, r2 = self.tangential(q)
        return r1 - r2
