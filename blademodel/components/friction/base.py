"""The public interface every friction law implements.

A friction law describes what happens on the tangential direction of a *closed*
contact. It reads like a page of theory: its internal states, its discrete modes,
the friction force in each mode, the rate of its states, its guards (when a mode
ends) and what follows a guard (candidate next modes with their resets).

Everything is written with SymPy in terms of a :class:`ContactContext`, which the
symbolic layer fills for each contact. The hybrid solver is generic: it never
knows which law it integrates.

Sign convention shared by every law: the friction force ``f`` acts on the first
body of the contact along ``-r`` and on the second along ``+r``, so its power on
the system is ``-f v`` with ``v = dr1/dt - dr2/dt``.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Mapping, Sequence

import sympy as sp

from ..parameter import Param


@dataclass(frozen=True)
class ContactContext:
    """The symbols a law writes its expressions with, for one contact.

    Attributes
    ----------
    N : sympy.Expr
        Normal force of the closed contact, ``k * delta``.
    Ndot : sympy.Expr
        Its time derivative, a function of the state.
    v : sympy.Expr
        Relative tangential velocity ``dr1/dt - dr2/dt``.
    f : sympy.Symbol
        The friction force of this contact in the mode where an expression is
        evaluated (in a stick mode: the constraint force). Use it in candidate
        conditions, e.g. ``mu*N - Abs(f) >= 0``.
    states : dict of str to sympy.Symbol
        The law's own continuous states.
    params : dict of str to sympy.Symbol
        The law's parameters, by field name.
    """

    N: sp.Expr
    Ndot: sp.Expr
    v: sp.Expr
    f: sp.Symbol
    states: Mapping[str, sp.Symbol]
    params: Mapping[str, sp.Symbol]


class StickConstraint:
    """Marker returned by :meth:`FrictionLaw.force` for a rigid stick mode.

    The friction force is then the constraint force that keeps ``dv/dt = 0``;
    the symbolic layer solves for it (jointly with every other sticking contact)
    and projects the velocities onto ``v = 0`` when the mode is entered.
    """

    def __repr__(self):
        return "StickConstraint()"


STICK = StickConstraint()


@dataclass(frozen=True)
class Candidate:
    """A possible next mode after a guard fires.

    Candidates are tried in order; the first whose ``when`` holds, evaluated in the
    candidate mode on the state after ``reset``, is taken.

    Attributes
    ----------
    mode : str
        Target mode of this contact (a law mode, or ``"open"``).
    when : sympy.Basic
        A SymPy relational (or ``True``) in context symbols.
    reset : dict of str to sympy.Expr
        New values of the law's states (unlisted states are kept).
    """

    mode: str
    when: sp.Basic = sp.true
    reset: Mapping[str, sp.Expr] = field(default_factory=dict)


@dataclass(frozen=True)
class Guard:
    """A scalar function whose zero crossing ends the current mode.

    Attributes
    ----------
    expr : sympy.Expr
        The guard function of the state and time.
    direction : int
        ``-1`` fires when ``expr`` falls through zero (from ``>= 0`` to ``< 0``),
        ``+1`` when it rises through zero, ``0`` either way.
    candidates : sequence of Candidate
        What follows, in order of preference; the last should be unconditional.
    name : str
        Label for the event log.
    """

    expr: sp.Expr
    direction: int
    candidates: Sequence[Candidate]
    name: str = ""


class FrictionLaw(ABC):
    """Base class of friction laws; subclass it to add a law.

    Subclasses set :attr:`modes` and :attr:`states` and implement the abstract
    methods. Nothing outside the subclass's own file has to change.

    Attributes
    ----------
    modes : tuple of str
        Modes of the closed contact (``"open"`` is added by the contact).
    states : tuple of str
        Names of the law's continuous internal states (``()`` for none).
    """

    modes: tuple[str, ...] = ()
    states: tuple[str, ...] = ()

    @abstractmethod
    def parameters(self) -> dict[str, Param]:
        """Numeric parameters by field name (``{"mu": Param("mu", 0.5)}``)."""

    @abstractmethod
    def force(self, mode: str, ctx: ContactContext):
        """Friction force in ``mode``: a SymPy expression, or :data:`STICK`."""

    def rates(self, mode: str, ctx: ContactContext) -> dict[str, sp.Expr]:
        """Time derivatives of the law's states in ``mode`` (default: zero)."""
        return {}

    @abstractmethod
    def guards(self, mode: str, ctx: ContactContext) -> list[Guard]:
        """Guards that end ``mode`` (contact opening is added by the contact)."""

    @abstractmethod
    def entry(self, ctx: ContactContext) -> list[Candidate]:
        """Candidates when the contact closes, and for the initial mode."""

    def exit_reset(self, ctx: ContactContext) -> dict[str, sp.Expr]:
        """Law states when the contact opens (default: unchanged)."""
        return {}

    def open_rates(self, ctx: ContactContext) -> dict[str, sp.Expr]:
        """State rates while the contact is open (default: zero)."""
        return {}

    def stored_energy(self, ctx: ContactContext) -> sp.Expr:
        """Elastic energy held by the law's own states (default: none)."""
        return sp.Integer(0)

    def structure(self) -> tuple:
        """What fixes the generated code: class and structural options, no values.

        Two laws with equal ``structure()`` share a compiled kernel.
        """
        cls = type(self)
        return (f"{cls.__module__}:{cls.__qualname__}", self.modes, self.states,
                tuple(p.name for p in self.parameters().values()))
