"""The public interface every friction law implements.

A friction law describes what happens on the tangential direction of a *closed*
contact. It reads like a page of theory: its internal states, its discrete modes,
the friction force in each mode, the rate of its states, its guards (when a mode
ends) and what follows a guard (candidate next modes with their resets).

Everything is written with SymPy in terms of a :class:`ContactContext`, which the
symbolic layer fills for each contact. The hybrid solver is generic: it never
knows which law it integrates. A law is one subclass of :class:`FrictionLaw`;
nothing else changes to add one, inside the package or outside it
(``docs/friction_laws.md`` walks through one; laws are found by name through
:mod:`blademodel.components.friction.registry`).

Sign convention shared by every law: the friction force ``f`` acts on the first
body of the contact along ``-r`` and on the second along ``+r``, so its power on
the system is ``-f v`` with ``v = dr1/dt - dr2/dt``.

What the solver does with a law (the contract a law relies on):

* **Modes.** The global modes are the product of every contact's modes
  (``"open"`` plus the law's :attr:`FrictionLaw.modes`), each derived and compiled
  ahead of time, so a law keeps its modes few. Discrete internal states that would
  multiply the modes (the stick/slip flags of many elements) are better held as
  continuous states with zero rate that only resets change (see
  :class:`~blademodel.components.friction.iwan.Iwan`).
* **Expressions** may use the context's symbols, numbers, the usual elementary
  functions, ``Abs``, ``Min``/``Max`` and ``Piecewise`` (printed as Python
  conditional expressions, which the compiled kernel supports). The solver's
  stability check takes each mode's Jacobian at rest (every state zero), so a
  ``Piecewise`` branch chosen by a state is taken at its value zero there.
* **Events.** After every RK4 step each guard of the mode is compared with its
  value at the step start; a crossing in the guard's ``direction`` is located by
  bisection and the state is taken just *past* the root (so the guard cannot fire
  again at once). Then the guard's candidates are tried and its reset applied,
  and every guard is evaluated afresh, in the new mode, from the new state.
* **One guard per event.** If several guards cross within the same located
  bracket, only one fires (the first in the mode's guard order); the others are
  already past zero afterwards and are never seen to cross. A law whose switches
  can coincide (several elements switching in one instant) must settle all of
  them in the reset of the guard that fires.
* **Resets** are evaluated on the state before the reset (values past the root);
  candidate conditions are evaluated in the candidate mode on the state after it.
* **Compiled code is cached** per model :meth:`~FrictionLaw.structure` and per
  source of the law's class: a law whose constructor options change its
  expressions (not just parameter values) must say so in ``structure()``.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Mapping, Sequence

from .._sympy import sp

from ..parameter import Param


@dataclass(frozen=True)
class ContactContext:
    """The symbols a law writes its expressions with, for one contact.

    Attributes
    ----------
    N : sympy.Expr
        Normal force of the closed contact: ``k * delta``, ``k * delta + c_n * ddelta/dt``
        (normal damping) or a constant ``N0`` (:class:`~blademodel.components.contact.Contact`).
    Ndot : sympy.Expr
        Its time derivative, a function of the state (with normal damping, also of
        the accelerations, which the symbolic layer fills in per mode; a law's
        friction force must then not use it).
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
    when: sp.Basic = field(default_factory=lambda: sp.true)
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

    Subclasses set :attr:`modes` and :attr:`states` (class attributes, or instance
    attributes set by the constructor when they depend on its options) and
    implement the abstract methods. Nothing outside the subclass's own file has to
    change. The built-in laws are frozen dataclasses whose fields are the
    constructor's keyword arguments: numbers or :class:`~blademodel.components.parameter.Param`
    (checked with :func:`~blademodel.components.parameter.as_param`, whose errors name the field as
    ``"friction: <field> = <value> ..."``) and structural options; the config
    layer passes ``friction_options`` and the keys of a YAML ``friction:`` block
    to the constructor by name and reports a rejected one at its field. It names a
    parameter given as a plain number per contact (``mu_c2``) by passing it back as
    a :class:`~blademodel.components.parameter.Param` under its key in
    :meth:`parameters`, so those keys should be constructor keyword arguments
    (:mod:`blademodel.config.friction_law`).

    Attributes
    ----------
    modes : tuple of str
        Modes of the closed contact (``"open"`` is added by the contact).
    states : tuple of str
        Names of the law's continuous internal states (``()`` for none).
    discrete_states : tuple of str
        Those of :attr:`states` that are labels, not quantities: modes of the law's
        parts held as numbers (an Iwan element's stick or slip, ``0`` or ``+-1``). Their
        rate is zero in every mode, open included, and only resets set them. Periodic
        orbits hold them as part of the orbit's mode (:mod:`blademodel.orbits`): they are
        not unknowns of the shooting, and the period map is not differentiated in them
        (nudged by a difference step, such a label would read as another part's mode).
        ``()`` by default.
    """

    modes: tuple[str, ...] = ()
    states: tuple[str, ...] = ()
    discrete_states: tuple[str, ...] = ()

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

        Two laws with equal ``structure()`` share a compiled kernel. The default
        covers the class, modes, states and parameter symbol names; override it
        (extending ``super().structure()``) if other options shape the
        expressions, e.g. numeric constants written into them.
        """
        cls = type(self)
        return (f"{cls.__module__}:{cls.__qualname__}", self.modes, self.states,
                tuple(p.name for p in self.parameters().values()))
