"""The symbolic hybrid system: modes, flows, guards and transitions of a model."""

from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp


@dataclass
class Transition:
    """One candidate outcome of a guard: target mode, condition, reset.

    ``reset`` maps state symbols to expressions of the pre-event state (velocity
    projection for newly constrained modes included); ``condition`` is evaluated
    on the post-reset state in the target mode.
    """

    target: int
    condition: sp.Basic
    reset: dict


@dataclass
class GuardSpec:
    """A guard of a mode: expression, crossing direction, candidates in order."""

    expr: sp.Expr
    direction: int
    name: str
    contact: int
    candidates: list[Transition]


@dataclass
class Mode:
    """One discrete mode of the hybrid system.

    Attributes
    ----------
    name : str
        ``"open"``, ``"stick"``, ``"slip+"`` for one contact; ``"c1=stick,c2=open"``
        for several; ``"free"`` without contacts.
    local : tuple of str
        The mode of each contact.
    accelerations : list of sympy.Expr
        ``d u_i / dt`` for every coordinate, fully in state, time and parameters.
    state_rates : list of sympy.Expr
        Rates of the friction laws' internal states.
    normal_forces, friction_forces : list of sympy.Expr
        ``N`` and ``f`` of every contact in this mode (zero when open).
    constrained : list of int
        Contacts whose friction force is a stick constraint force here.
    guards : list of GuardSpec
    """

    name: str
    local: tuple
    accelerations: list
    state_rates: list
    normal_forces: list
    friction_forces: list
    constrained: list
    guards: list = field(default_factory=list)


@dataclass
class HybridSystem:
    """Symbolic hybrid system derived from a :class:`~blademodel.model.Model`.

    Attributes
    ----------
    model : Model
    t : sympy.Symbol
    q, u : list of sympy.Symbol
        Coordinates and their velocities (``x1`` and ``vx1``).
    s : list of sympy.Symbol
        Internal states of the friction laws.
    params : list of sympy.Symbol
        Parameters in the order of ``model.parameters``.
    mass_matrix : sympy.Matrix
    generalized_forces : dict
        Per mode name: ``M q'' = F`` right-hand side with ``N_c`` and ``f_c`` kept as
        symbols, for display.
    normal_symbols, friction_symbols : list of sympy.Symbol
        ``N_c``, ``f_c`` per contact (display only).
    modes : list of Mode
    open_mode : int
        Index of the mode with every contact open.
    """

    model: object
    t: sp.Symbol
    q: list
    u: list
    s: list
    params: list
    mass_matrix: sp.Matrix
    generalized_forces: dict
    normal_symbols: list
    friction_symbols: list
    modes: list
    open_mode: int
    energy: dict

    @property
    def state(self) -> list:
        """State symbols in state-vector order: ``q``, ``u``, ``s``."""
        return [*self.q, *self.u, *self.s]

    @property
    def state_names(self) -> list[str]:
        return [x.name for x in self.state]

    def mode_index(self, name: str) -> int:
        for i, m in enumerate(self.modes):
            if m.name == name:
                return i
        raise KeyError(f"no mode {name!r}; modes are {[m.name for m in self.modes]}")

    def mode(self, name: str) -> Mode:
        return self.modes[self.mode_index(name)]
