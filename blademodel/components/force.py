"""Applied forces on a mass: constant, harmonic, or a sum of harmonics.

Every force here is a magnitude ``Q(t)`` along a direction angle ``angle``
(measured from ``x`` towards ``y``; the paper's ``beta``): the load on the mass
is ``Q cos(angle)`` along ``x`` and ``Q sin(angle)`` along ``y``, and a
component along an axis the mass does not move on is dropped. Its power
``Q . u`` is the input work rate. ``frequency`` is the base angular frequency
that sets the excitation period ``2 pi / omega`` (``None`` for a constant force,
which has no period of its own).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence, Union

from ._sympy import sp

from .mass import Mass
from .parameter import Number, Param, as_param


def _directed(mass: Mass, Q: sp.Expr, angle: Param) -> dict[str, sp.Expr]:
    """The loads of magnitude ``Q`` along ``angle`` on the axes ``mass`` moves along.

    Each term of ``Q`` is projected on its own, so that a load is a sum of terms
    ``A sin(w t + phi)`` and constants (as the per-contact kernel's forcing tables take it).
    """
    beta = angle.symbol
    out = {}
    for dof, proj in (("x", sp.cos(beta)), ("y", sp.sin(beta))):
        c = mass.coordinate(dof)
        if c is not None:
            out[c] = sp.Add(*[term * proj for term in sp.Add.make_args(Q)])
    return out


@dataclass(frozen=True)
class ConstantForce:
    """Constant force ``Q = value`` along ``angle``: gravity, a preload.

    Under a constant force the static equilibrium of a linear structure shifts by
    ``K^-1 F``; everything else about its motion is unchanged.

    Parameters
    ----------
    mass : Mass
        The mass the force acts on.
    value : float or Param
        ``Q`` in N, of either sign (negative: against ``angle``). Default symbol
        ``F_<mass>``.
    angle : float or Param
        Direction angle in rad. Default symbol ``beta_F_<mass>`` (not a harmonic
        force's ``beta_<mass>``: gravity and a drive on one mass point different
        ways). Gravity along ``-y``: ``ConstantForce(m, -m g, angle=math.pi / 2)``.
    """

    mass: Mass
    value: Number
    angle: Number = 0.0
    _p: dict = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        n = self.mass.name
        object.__setattr__(self, "_p", {
            "value": as_param(self.value, f"F_{n}", field=f"constant force on {n}: value"),
            "angle": as_param(self.angle, f"beta_F_{n}", field=f"constant force on {n}: angle"),
        })

    @property
    def coordinates(self) -> tuple[str, ...]:
        return self.mass.coordinates

    @property
    def frequency(self) -> None:
        """No base frequency: a constant force does not set a period."""
        return None

    def parameters(self) -> dict[str, Param]:
        return dict(self._p)

    def magnitude(self, t: sp.Symbol) -> sp.Expr:
        """``Q``."""
        return self._p["value"].symbol

    def loads(self, q, u, t) -> dict[str, sp.Expr]:
        """Generalized forces, by coordinate name."""
        return _directed(self.mass, self.magnitude(t), self._p["angle"])


@dataclass(frozen=True)
class HarmonicForce:
    """Force ``Q = F0 sin(omega t + phase)`` acting along the angle ``angle``.

    Sign convention: the force on the mass is ``Q cos(angle)`` along ``x`` and
    ``Q sin(angle)`` along ``y`` (``angle`` measured from ``x`` towards ``y``;
    the paper's ``beta``). A component along an axis the mass does not move on
    is dropped. Its power ``Q . u`` is the input work rate. A cosine is
    ``phase = pi / 2``; a pair ``a sin(omega t) + b cos(omega t)`` is
    ``F0 = hypot(a, b)``, ``phase = atan2(b, a)``.

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

    @property
    def frequency(self) -> Param:
        """``omega``: the excitation period is ``2 pi / omega``."""
        return self._p["omega"]

    def parameters(self) -> dict[str, Param]:
        return dict(self._p)

    def magnitude(self, t: sp.Symbol) -> sp.Expr:
        """``Q(t)``."""
        p = {k: v.symbol for k, v in self._p.items()}
        return p["amplitude"] * sp.sin(p["omega"] * t + p["phase"])

    def loads(self, q, u, t) -> dict[str, sp.Expr]:
        """Generalized forces, by coordinate name."""
        return _directed(self.mass, self.magnitude(t), self._p["angle"])


@dataclass(frozen=True)
class Harmonic:
    """One term ``amplitude sin(order omega t + phase)`` of a :class:`MultiHarmonicForce`.

    Parameters
    ----------
    order : int
        Multiple of the base frequency, >= 1.
    amplitude : float or Param
        In N, >= 0. Default symbol ``F<order>_<mass>``.
    phase : float or Param
        In rad. Default symbol ``phi<order>_<mass>``.
    """

    order: int
    amplitude: Number
    phase: Number = 0.0


def _order(k, mass: str) -> int:
    """``k`` as a harmonic order (an integer >= 1), else ``ValueError`` naming it."""
    whole = isinstance(k, int) or (isinstance(k, float) and k.is_integer())
    if isinstance(k, bool) or not whole or k < 1:
        raise ValueError(f"force on {mass}: harmonic order = {k!r} must be an integer >= 1")
    return int(k)


@dataclass(frozen=True)
class MultiHarmonicForce:
    """Force ``Q = sum_k A_k sin(k omega t + phi_k)`` along ``angle``: several harmonics of one base frequency.

    The orders ``k`` are positive integers, so ``Q`` repeats with the base period
    ``2 pi / omega`` and Poincare sections and periods keep their meaning. The
    sign convention is :class:`HarmonicForce`'s; a single harmonic of order 1 is
    a :class:`HarmonicForce`.

    Parameters
    ----------
    mass : Mass
        The mass the force acts on.
    omega : float or Param
        Base angular frequency in rad/s, > 0. Default symbol ``omega_<mass>``.
    harmonics : sequence of Harmonic or tuple
        The terms, each a :class:`Harmonic` or a tuple ``(order, amplitude[, phase])``;
        distinct orders.
    angle : float or Param
        Direction angle in rad. Default symbol ``beta_<mass>``.
    """

    mass: Mass
    omega: Number
    harmonics: Sequence[Union[Harmonic, tuple]]
    angle: Number = 0.0
    _p: dict = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        n = self.mass.name
        terms = tuple(h if isinstance(h, Harmonic) else Harmonic(*h) for h in self.harmonics)
        terms = tuple(Harmonic(_order(h.order, n), h.amplitude, h.phase) for h in terms)
        if not terms:
            raise ValueError(f"force on {n}: harmonics is empty; give at least one (order, amplitude)")
        p = {"omega": as_param(self.omega, f"omega_{n}", field=f"force on {n}: omega", minimum=0.0, strict=True),
             "angle": as_param(self.angle, f"beta_{n}", field=f"force on {n}: angle")}
        for h in terms:
            k = h.order
            if f"amplitude{k}" in p:
                raise ValueError(f"force on {n}: harmonic order {k} is given twice")
            p[f"amplitude{k}"] = as_param(h.amplitude, f"F{k}_{n}", field=f"force on {n}: harmonic {k} amplitude",
                                          minimum=0.0)
            p[f"phase{k}"] = as_param(h.phase, f"phi{k}_{n}", field=f"force on {n}: harmonic {k} phase")
        object.__setattr__(self, "harmonics", terms)
        object.__setattr__(self, "_p", p)

    @property
    def coordinates(self) -> tuple[str, ...]:
        return self.mass.coordinates

    @property
    def orders(self) -> tuple[int, ...]:
        """The harmonic orders, in the given order."""
        return tuple(h.order for h in self.harmonics)

    @property
    def frequency(self) -> Param:
        """The base frequency ``omega``: the excitation period is ``2 pi / omega``."""
        return self._p["omega"]

    def parameters(self) -> dict[str, Param]:
        return dict(self._p)

    def magnitude(self, t: sp.Symbol) -> sp.Expr:
        """``Q(t)``."""
        w = self._p["omega"].symbol
        return sp.Add(*[self._p[f"amplitude{k}"].symbol * sp.sin(k * w * t + self._p[f"phase{k}"].symbol)
                        for k in self.orders])

    def loads(self, q, u, t) -> dict[str, sp.Expr]:
        """Generalized forces, by coordinate name."""
        return _directed(self.mass, self.magnitude(t), self._p["angle"])


#: Any applied force of this module.
Force = Union[ConstantForce, HarmonicForce, MultiHarmonicForce]


def base_frequencies(forces) -> set:
    """The distinct base frequencies (``Param`` values) of ``forces``; constant forces have none."""
    return {f.frequency.value for f in forces if f.frequency is not None}
