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
    """A guard of a mode: expression, crossing direction, candidates in order.

    ``kind`` says what the guard is, as data: ``"close"`` (an open contact's
    penetration rising through zero), ``"open"`` (a closed contact's falling
    through zero) or ``"law"`` (a friction law's own guard); ``name`` is a label.
    """

    expr: sp.Expr
    direction: int
    name: str
    contact: int
    candidates: list[Transition]
    kind: str = "law"


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
class SymbolicModel:
    """The symbols every derived system of a model shares (base of :class:`HybridSystem`, :class:`ModeSystem`).

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
    normal_symbols, friction_symbols : list of sympy.Symbol
        ``N_c``, ``f_c`` per contact (display only).
    """

    model: object
    t: sp.Symbol
    q: list
    u: list
    s: list
    params: list
    mass_matrix: sp.Matrix
    normal_symbols: list
    friction_symbols: list

    @property
    def state(self) -> list:
        """State symbols in state-vector order: ``q``, ``u``, ``s``."""
        return [*self.q, *self.u, *self.s]

    @property
    def state_names(self) -> list[str]:
        return [x.name for x in self.state]


@dataclass
class HybridSystem(SymbolicModel):
    """Symbolic hybrid system derived from a :class:`~blademodel.model.Model`.

    It has the attributes of :class:`SymbolicModel`, and those below.

    Attributes
    ----------
    generalized_forces : dict
        Per mode name: ``M q'' = F`` right-hand side with ``N_c`` and ``f_c`` kept as
        symbols, for display.
    modes : list of Mode
    open_mode : int
        Index of the mode with every contact open.
    """

    generalized_forces: dict
    modes: list
    open_mode: int
    energy: dict

    def mode_index(self, name: str) -> int:
        for i, m in enumerate(self.modes):
            if m.name == name:
                return i
        raise KeyError(f"no mode {name!r}; modes are {[m.name for m in self.modes]}")

    def mode(self, name: str) -> Mode:
        return self.modes[self.mode_index(name)]


@dataclass
class ModeSystem(SymbolicModel):
    """One mode of a model, derived alone by :func:`~blademodel.symbolic.assembly.derive_mode`.

    Reads like a :class:`HybridSystem` holding one mode (``modes``, ``mode_index()``,
    ``generalized_forces`` work the same), so the display functions take either.

    Attributes
    ----------
    model : Model
    t : sympy.Symbol
    q, u, s, params : list of sympy.Symbol
        As in :class:`HybridSystem`.
    mass_matrix : sympy.Matrix
    normal_symbols, friction_symbols : list of sympy.Symbol
        ``N_c``, ``f_c`` per contact (display only).
    mode : Mode
        The mode, with its guards. Unlike in a :class:`HybridSystem`, the
        ``target`` of each :class:`Transition` indexes :attr:`targets`.
    forces : dict
        ``M q'' = F`` right-hand side per coordinate name, ``N_c``, ``f_c`` as symbols.
    targets : list of tuple of str
        Local modes (one per contact) of the modes the guards lead to.
    contact_names : list of str
    """

    mode: Mode
    forces: dict
    targets: list
    contact_names: list

    @property
    def modes(self) -> list:
        return [self.mode]

    @property
    def generalized_forces(self) -> dict:
        return {self.mode.name: self.forces}

    @property
    def assignment(self) -> dict:
        """The contacts that are not open: name -> mode."""
        return {c: m for c, m in zip(self.contact_names, self.mode.local) if m != "open"}

    @property
    def label(self) -> str:
        """Short name of the mode: its closed contacts, ``c1=stick,c2=slip+``, then ``others open``."""
        if len(self.contact_names) <= 1:
            return self.mode.name
        closed = ",".join(f"{c}={m}" for c, m in self.assignment.items())
        if not closed:
            return "open (every contact)"
        return closed + (" (others open)" if len(self.assignment) < len(self.contact_names) else "")

    def target_name(self, index: int) -> str:
        """Full mode name (as in :func:`derive`) of ``targets[index]``."""
        local = self.targets[index]
        if len(local) == 1:
            return local[0]
        return ",".join(f"{c}={m}" for c, m in zip(self.contact_names, local))

    def mode_index(self, name: str) -> int:
        if name in (self.mode.name, self.label):
            return 0
        raise KeyError(f"no mode {name!r}; this system holds only {self.mode.name!r}")



@dataclass
class ContactModeEquations:
    """One contact in one of its modes (:func:`~blademodel.symbolic.assembly.contact_equations`).

    Attributes
    ----------
    mode : str
        ``open`` or a mode of the friction law.
    normal_force : sympy.Expr
        ``0`` when open, the symbol ``N_c`` when closed.
    friction_force : sympy.Expr or StickConstraint
        The law's force in terms of ``N_c``, ``v_c``, its states and parameters;
        :data:`~blademodel.components.friction.base.STICK` for a rigid stick (the
        constraint force holding ``dv_c/dt = 0``).
    rates : dict
        State symbol -> its rate.
    guards : list of Guard
        The friction law's :class:`~blademodel.components.friction.base.Guard`
        objects with the contact's ``close`` / ``open`` guard first; candidate
        conditions and resets may use ``f_c`` (the force in the candidate mode).
    """

    mode: str
    normal_force: sp.Expr
    friction_force: object
    rates: dict
    guards: list


@dataclass
class ContactEquations:
    """A contact's own equations: geometry, normal force and friction law per mode.

    Attributes
    ----------
    model : Model
    name : str
    bodies : tuple of str
        Names of the contact's bodies (one when ``ground``).
    ground : bool
        Whether the second surface is fixed.
    law : str
        Class name of the friction law.
    q, u : list of sympy.Symbol
        The model's coordinates and velocities.
    penetration, slip : sympy.Expr
        ``delta = n1 - n2 - gap`` and ``r1 - r2``.
    k : sympy.Symbol or None
        Normal contact stiffness (``None`` for a constant normal load).
    N, Ndot, v, f : sympy.Symbol
        ``N_c``, its rate, the relative slip velocity ``v_c`` and the friction force ``f_c``.
    definitions : dict
        ``N_c``, ``v_c``, ``Ndot_c`` (symbol) -> expression of the state (``N_c`` while closed;
        a damped contact's ``Ndot_c`` has the accelerations ``a<coordinate>``).
    states : dict of str to sympy.Symbol
        The law's states.
    params : list of sympy.Symbol
        Parameters of the contact and of its law.
    modes : list of ContactModeEquations
        ``open`` first, then the law's modes.
    normal_kind : str
        The normal law: ``"spring"``, ``"damped"`` or ``"load"``
        (:attr:`~blademodel.components.contact.Contact.normal_kind`).
    penetration_rate : sympy.Expr or None
        ``ddelta/dt`` as an expression of the velocities.
    """

    model: object
    name: str
    bodies: tuple
    ground: bool
    law: str
    q: list
    u: list
    penetration: sp.Expr
    slip: sp.Expr
    k: sp.Symbol
    N: sp.Symbol
    Ndot: sp.Symbol
    v: sp.Symbol
    f: sp.Symbol
    definitions: dict
    states: dict
    params: list
    modes: list
    normal_kind: str = "spring"
    penetration_rate: sp.Expr = None
