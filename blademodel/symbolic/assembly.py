"""Derive the hybrid system of a model: a direct assembly of generalized forces.

Every component is a lumped element acting on Cartesian coordinates of point
masses, so the mass matrix is diagonal and each load's generalized force is its
projection on the coordinates. A Lagrangian/Kane formulation would give the same
equations with more machinery; the direct assembly keeps each load visible and
makes the stick constraint force a plain linear solve. ``tests/test_assembly.py``
checks the smooth part against ``sympy.physics.mechanics.LagrangesMethod``.

Three entry points share the same pieces:

* :func:`derive` derives every mode, the product of all contacts' modes (the
  single-contact kernel compiles them all);
* :func:`derive_mode` derives *one* mode assignment (``{"c1": "stick"}``, the
  others open) with its guards, at a cost that grows with the model, not with
  the number of mode combinations (a bladed disk has ``4**24`` of them);
* :func:`contact_equations` gives one contact's own equations: penetration,
  relative slip, normal force and its friction law in each of its modes.
"""

from __future__ import annotations

import functools
import itertools
import math
from dataclasses import dataclass
from typing import Callable, Mapping

import sympy as sp
from sympy.matrices.exceptions import NonInvertibleMatrixError

from ..components.friction.base import STICK, Candidate, ContactContext, Guard
from ..model import Model
from .system import (
    ContactEquations,
    ContactModeEquations,
    GuardSpec,
    HybridSystem,
    Mode,
    ModeSystem,
    Transition,
)


def _state_symbols(model: Model):
    q = {c: sp.Symbol(c, real=True) for c in model.coordinates}
    u = {c: sp.Symbol(f"v{c}", real=True) for c in model.coordinates}
    s = {(c, st): sp.Symbol(label, real=True) for label, c, st in model.law_state_labels()}
    return q, u, s


def _derivative(expr, q, u):
    """Time derivative of a function of the coordinates (no explicit time)."""
    return sum(sp.diff(expr, q[c]) * u[c] for c in q)


def _tidy(expr):
    """Collect a solved constraint force over a trig-simplified common denominator."""
    num, den = sp.fraction(sp.together(sp.expand(expr)))
    return sp.expand(num) / sp.factor(sp.trigsimp(den))


# --- the pieces every mode is made of ------------------------------------------------------

@dataclass
class _Assembly:
    """What does not depend on the mode: symbols, masses, smooth loads, contact geometry."""

    model: Model
    t: sp.Symbol
    q: dict
    u: dict
    s: dict
    coords: list
    params: list
    masses: dict
    M: sp.Matrix
    F_smooth: dict
    contacts: tuple
    ctxs: list
    geom: list
    f_sym: list
    N_sym: list
    state_syms: list
    #: ``d u_c / dt`` placeholders: a damped contact's ``Ndot`` needs the mode's accelerations
    acc_syms: list

    @functools.cached_property
    def Minv(self) -> sp.Matrix:
        """The inverse of the (diagonal) mass matrix; do not modify it in place."""
        return sp.diag(*[1 / self.masses[c] for c in self.coords])


def _assemble(model: Model) -> _Assembly:
    """The mode-independent part of the derivation (linear in the model's size)."""
    t = sp.Symbol("t", real=True)
    q, u, s = _state_symbols(model)
    coords = list(model.coordinates)
    params = [sp.Symbol(n, real=True) for n in model.parameters]

    masses = {m.coordinate(d): m.inertia(d).symbol for m in model.masses for d in m.dofs}
    M = sp.diag(*[masses[c] for c in coords])

    F_smooth = {c: sp.Integer(0) for c in coords}
    for comp in (*model.springs, *model.dampers, *model.forces):
        for c, f in comp.loads(q, u, t).items():
            F_smooth[c] += f

    contacts = model.contacts
    ctxs, geom = [], []
    f_sym = [sp.Symbol(f"f_{c.name}", real=True) for c in contacts]
    N_sym = [sp.Symbol(f"N_{c.name}", real=True) for c in contacts]
    acc = {cc: sp.Symbol(f"_acc_{cc}", real=True) for cc in coords}
    for j, c in enumerate(contacts):
        delta = c.penetration(q)
        slip = c.relative_slip(q)
        rate = _derivative(delta, q, u)
        dn = {cc: sp.diff(delta, q[cc]) for cc in coords}
        dr = {cc: sp.diff(slip, q[cc]) for cc in coords}
        ctx = ContactContext(
            N=c.normal_force(delta, rate),
            Ndot=c.normal_force_rate(rate, sum(dn[cc] * acc[cc] for cc in coords)),
            v=_derivative(slip, q, u), f=f_sym[j],
            states={st: s[(c.name, st)] for st in c.friction.states},
            params={name: p.symbol for name, p in c.friction.parameters().items()})
        ctxs.append(ctx)
        geom.append({"delta": delta, "rate": rate, "dn": dn, "dr": dr,
                     "close": c.closing_guard(delta, rate), "open": c.opening_guard(delta, rate),
                     # the coordinates the contact acts on (its loads are zero on the others)
                     "touched": [cc for cc in coords if dn[cc] != 0 or dr[cc] != 0],
                     "slides": [cc for cc in coords if dr[cc] != 0]})

    state_syms = [s[(c.name, st)] for c in contacts for st in c.friction.states]
    return _Assembly(model, t, q, u, s, coords, params, masses, M, F_smooth, contacts, ctxs, geom,
                     f_sym, N_sym, state_syms, [acc[cc] for cc in coords])


def _with_accelerations(asm: _Assembly, expr, accelerations):
    """``expr`` with the acceleration placeholders of a damped contact's ``Ndot`` replaced."""
    expr = sp.sympify(expr)
    if not any(a in expr.free_symbols for a in asm.acc_syms):
        return expr
    return expr.xreplace(dict(zip(asm.acc_syms, accelerations)))


def _mode_name(contacts, combo) -> str:
    if not contacts:
        return "free"
    if len(contacts) == 1:
        return combo[0]
    return ",".join(f"{c.name}={m}" for c, m in zip(contacts, combo))


def _law_mode(combo, j):
    """The friction law's mode of contact ``j``, ``None`` when the contact is open."""
    return None if combo[j] == "open" else combo[j]


def _local_force(asm: _Assembly, combo, j):
    """Friction force of contact ``j`` in ``combo`` from its law alone: an expression or ``STICK``."""
    lm = _law_mode(combo, j)
    return sp.Integer(0) if lm is None else asm.contacts[j].friction.force(lm, asm.ctxs[j])


def _loads(asm: _Assembly, combo):
    """Generalized forces of ``combo`` before the stick forces are known.

    Returns
    -------
    F : dict
        Coordinate -> load, the contacts' ``N`` and non-stick ``f`` included.
    Fdisp : dict
        The same with ``N_c`` and ``f_c`` of every closed contact kept as symbols (display).
    Nj, fj : list
        Normal and friction force of every contact (``None`` for a stick force).
    constrained : list of int
        Contacts whose friction force is a stick constraint force.
    """
    geom = asm.geom
    F = dict(asm.F_smooth)
    Fdisp = dict(asm.F_smooth)
    Nj, fj, constrained = [], [], []
    for j, c in enumerate(asm.contacts):
        lm = _law_mode(combo, j)
        if lm is None:
            Nj.append(sp.Integer(0))
            fj.append(sp.Integer(0))
            continue
        Nj.append(asm.ctxs[j].N)
        force = c.friction.force(lm, asm.ctxs[j])
        if force is STICK:
            constrained.append(j)
            fj.append(None)
        else:
            fj.append(force)
        for cc in geom[j]["touched"]:
            F[cc] += -asm.ctxs[j].N * geom[j]["dn"][cc]
            Fdisp[cc] += -asm.N_sym[j] * geom[j]["dn"][cc] - asm.f_sym[j] * geom[j]["dr"][cc]
            if force is not STICK:
                F[cc] += -force * geom[j]["dr"][cc]
    return F, Fdisp, Nj, fj, constrained


def _joint_solve(asm: _Assembly, constrained: list, Fvec: sp.Matrix) -> list:
    """Stick forces of ``constrained``, solved together: one linear solve over all of them."""
    # a = M^-1 (F - J^T lam);  J a = 0  ->  (J M^-1 J^T) lam = J M^-1 F
    Minv = asm.Minv
    J = sp.Matrix([[asm.geom[j]["dr"][c] for c in asm.coords] for j in constrained])
    A = J * Minv * J.T
    lam = A.LUsolve(J * Minv * Fvec)
    return [_tidy(x) for x in lam]


def _contact_forces(asm: _Assembly, combo, solve=_joint_solve):
    """Loads of ``combo`` with the stick forces solved jointly.

    ``solve(asm, constrained, Fvec)`` gives the stick forces (:func:`_joint_solve`
    for :func:`derive`; :class:`_GroupSolver` for :func:`derive_mode`).

    Returns
    -------
    Fvec : sympy.Matrix
        Generalized forces, the solved stick constraint forces included.
    Fdisp : dict
        The same with ``N_c`` and ``f_c`` kept as symbols (display).
    Nj, fj : list
        Normal and friction force of every contact.
    constrained : list of int
    """
    coords, geom = asm.coords, asm.geom
    F, Fdisp, Nj, fj, constrained = _loads(asm, combo)
    Fvec = sp.Matrix([F[c] for c in coords])
    if constrained:
        lam = solve(asm, constrained, Fvec)
        for i, j in enumerate(constrained):
            fj[j] = lam[i]
        J = sp.Matrix([[geom[j]["dr"][c] for c in coords] for j in constrained])
        Fvec = Fvec - J.T * sp.Matrix(lam)
    return Fvec, Fdisp, Nj, fj, constrained


def _flow(asm: _Assembly, combo, solve=_joint_solve) -> tuple[Mode, dict]:
    """The mode ``combo`` (accelerations, state rates, contact forces; no guards) and its display forces."""
    Fvec, Fdisp, Nj, fj, constrained = _contact_forces(asm, combo, solve)
    acc = [sp.expand(x) for x in asm.Minv * Fvec]
    rates = []
    for j, c in enumerate(asm.contacts):
        lm = _law_mode(combo, j)
        sub = {asm.f_sym[j]: fj[j]}
        r = c.friction.rates(lm, asm.ctxs[j]) if lm else c.friction.open_rates(asm.ctxs[j])
        for st in c.friction.states:
            rates.append(_with_accelerations(asm, sp.sympify(r.get(st, 0)).xreplace(sub), acc))
    name = _mode_name(asm.contacts, combo)
    return Mode(name, combo, acc, rates, Nj, fj, constrained), Fdisp


def _projection(asm: _Assembly, constrained) -> dict:
    """Velocity reset onto ``v = 0`` of every stick constraint in ``constrained``."""
    if not constrained:
        return {}
    coords, u = asm.coords, asm.u
    u_vec = sp.Matrix([u[c] for c in coords])
    Minv = asm.Minv
    J = sp.Matrix([[asm.geom[j]["dr"][c] for c in coords] for j in constrained])
    A = J * Minv * J.T
    du = Minv * J.T * A.LUsolve(J * u_vec)
    return {u[c]: sp.expand(u[c] - du[i]) for i, c in enumerate(coords)}


def _contact_guards(c, lm, ctx: ContactContext, close, open_) -> list[Guard]:
    """One contact's guards in its mode ``lm`` (``None``: open), named without the contact.

    Open: the contact closes when ``close`` rises through zero (the law's entry
    candidates). Closed: it opens when ``open_`` falls through zero, then the
    law's own guards, in the law's order. Both are the penetration for a contact
    spring (:meth:`~blademodel.components.contact.Contact.closing_guard`).
    """
    if lm is None:
        return [Guard(close, +1, list(c.friction.entry(ctx)), "close")]
    out = [Guard(open_, -1, [Candidate("open", sp.true, c.friction.exit_reset(ctx))], "open")]
    for g in c.friction.guards(lm, ctx):
        if g.direction not in (-1, 0, 1):
            raise ValueError(f"guard {g.name!r}: direction must be -1, 0 or +1")
        out.append(g)
    return out


#: ``resolve(combo) -> (target id, constrained contacts, friction force of contact j)``
_Resolver = Callable[[tuple], tuple]


def _guards(asm: _Assembly, mode: Mode, resolve: _Resolver, project=_projection) -> list[GuardSpec]:
    """Guards of ``mode`` with their transitions.

    ``resolve(combo)`` identifies a target mode (see :data:`_Resolver`);
    ``project(asm, constrained)`` gives the velocity reset onto its stick constraints.
    """
    contacts, ctxs = asm.contacts, asm.ctxs
    projections: dict = {}

    def here(expr):
        return _with_accelerations(asm, expr, mode.accelerations)

    def subs_f(expr, force, j):
        return sp.sympify(expr).xreplace({asm.f_sym[j]: force})

    def transitions(j, candidates):
        c = contacts[j]
        out = []
        for cand in candidates:
            if cand.mode not in c.modes:
                raise ValueError(f"friction law {type(c.friction).__name__} names mode {cand.mode!r}, "
                                 f"which is not among its modes {c.modes}")
            combo = list(mode.local)
            combo[j] = cand.mode
            target, constrained, force_of = resolve(tuple(combo))
            reset = {}
            for st, expr in cand.reset.items():
                reset[ctxs[j].states[st]] = here(subs_f(expr, mode.friction_forces[j], j))
            if set(constrained) - set(mode.constrained):
                key = tuple(constrained)
                if key not in projections:
                    projections[key] = project(asm, constrained)
                reset.update(projections[key])
            cond = subs_f(cand.when, force_of(j), j)
            if any(a in cond.free_symbols for a in asm.acc_syms):
                raise NotImplementedError(
                    f"contact {c.name}: the {type(c.friction).__name__} law's condition for mode {cand.mode!r} "
                    f"uses dN/dt, which a damped contact knows only from the target mode's accelerations; "
                    f"this combination is not supported")
            out.append(Transition(target, cond, reset))
        return out

    guards = []
    for j, c in enumerate(contacts):
        lm = _law_mode(mode.local, j)
        for k, g in enumerate(_contact_guards(c, lm, ctxs[j], asm.geom[j]["close"], asm.geom[j]["open"])):
            expr = here(subs_f(g.expr, mode.friction_forces[j], j))  # (the contact's own guard: unchanged)
            kind = "law" if k else ("close" if lm is None else "open")
            guards.append(GuardSpec(expr, g.direction, f"{c.name}: {g.name}", j,
                                    transitions(j, list(g.candidates)), kind))
    return guards


def _energy(asm: _Assembly, modes: list[Mode]) -> dict:
    """Energy terms of the system and, per mode, of the contacts and laws."""
    model, q, u, t, coords, masses = asm.model, asm.q, asm.u, asm.t, asm.coords, asm.masses
    kinetic = sum(masses[c] * u[c] ** 2 / 2 for c in coords)
    potential = sum((sp.sympify(sp_.potential_energy(q)) for sp_ in model.springs), sp.Integer(0))
    input_power = sum((sum(f * u[c] for c, f in comp.loads(q, u, t).items()) for comp in model.forces),
                      sp.Integer(0))
    viscous = sum((d.dissipation_rate(u) for d in model.dampers), sp.Integer(0))
    energy = {"kinetic": kinetic, "potential": potential, "input_power": input_power,
              "viscous_power": viscous, "contact": [], "law": [], "friction_power": [], "contact_power": []}
    for mode in modes:
        contact_e, law_e, fric_p, contact_p = sp.Integer(0), sp.Integer(0), sp.Integer(0), sp.Integer(0)
        for j, c in enumerate(asm.contacts):
            E_law = c.friction.stored_energy(asm.ctxs[j])
            law_e += E_law
            closed = _law_mode(mode.local, j) is not None
            contact_e += c.stored_energy(asm.geom[j]["delta"], closed)
            contact_p += c.dissipation_rate(asm.geom[j]["delta"], asm.geom[j]["rate"], closed)
            if not closed:
                continue
            dE = sum(sp.diff(E_law, st) * mode.state_rates[asm.state_syms.index(st)]
                     for st in asm.ctxs[j].states.values())
            fric_p += mode.friction_forces[j] * asm.ctxs[j].v - dE
        energy["contact"].append(contact_e)
        energy["law"].append(law_e)
        energy["friction_power"].append(fric_p)
        energy["contact_power"].append(contact_p)
    return energy


class _Dependent(ValueError):
    """Sticking contacts whose constraints are not independent: their forces are not unique."""


def _simplify_parameters(expr):
    """Simplify an expression of the parameters only (an entry of ``J M^-1 J^T`` or its inverse)."""
    expr = sp.cancel(expr)
    return sp.factor(sp.trigsimp(expr) if expr.has(sp.sin, sp.cos, sp.tan) else expr)


def _dependent(asm: _Assembly, group) -> str:
    names = [asm.contacts[j].name for j in group]
    return (f"contacts {_name_list(names)} cannot all stick rigidly: their stick constraints are not "
            f"independent (J M^-1 J^T is singular), so the stick forces are not unique; "
            f"let one of them slip (e.g. {names[-1]}=slip+)" if len(names) > 1 else
            f"contact {names[0]} cannot stick rigidly: its relative slip does not move")


def _name_list(names, limit: int = 12) -> str:
    """``c1, c2, c3`` (long lists shortened to ``c1, c2, c3, ..., c24 (24 contacts)``)."""
    names = list(names)
    if len(names) <= limit:
        return ", ".join(names)
    return ", ".join(names[:3]) + f", ..., {names[-1]} ({len(names)} contacts)"


class _GroupSolver:
    """Stick forces and velocity projections solved per group of coupled sticking contacts.

    Two sticking contacts are coupled when they slide a common coordinate;
    ``J M^-1 J^T`` is block diagonal over the groups, so each group is solved on
    its own and the solution is cached (keyed by the loads it reads). A ring with
    two sticking neighbours solves one 2x2 group, however many contacts it has.

    A group of one contact is solved exactly as :func:`derive` solves it (same
    expressions). A larger group first simplifies ``J M^-1 J^T`` (it depends on
    parameters only: ``cos(a)**2 + sin(a)**2`` becomes 1) and inverts it, which
    keeps the forces compact where the joint ``LUsolve`` of :func:`derive` nests
    fractions; the forces are the same functions, written differently.
    """

    def __init__(self, asm: _Assembly):
        self.asm = asm
        self.index = {c: i for i, c in enumerate(asm.coords)}
        self._inverse: dict = {}
        self._forces: dict = {}
        self._resets: dict = {}

    def groups(self, constrained) -> list[list[int]]:
        """``constrained`` split into groups of contacts coupled through shared sliding coordinates."""
        groups: list[tuple[set, list]] = []
        for j in constrained:
            cj = set(self.asm.geom[j]["slides"])
            merged = [g for g in groups if g[0] & cj]
            rest = [g for g in groups if not g[0] & cj]
            coords, members = set(cj), [j]
            for g in merged:
                coords |= g[0]
                members += g[1]
            groups = rest + [(coords, members)]
        return sorted(sorted(m) for _, m in groups)

    def _coords(self, group) -> list:
        slides = set().union(*(self.asm.geom[j]["slides"] for j in group))
        return [c for c in self.asm.coords if c in slides]

    def _system(self, group):
        """``(coords, J, M^-1, (J M^-1 J^T)^-1 simplified)`` of a group of several contacts.

        Raises
        ------
        _Dependent
            When the group's stick constraints are not independent.
        """
        key = tuple(group)
        if key not in self._inverse:
            asm = self.asm
            coords = self._coords(group)
            J = sp.Matrix([[asm.geom[j]["dr"][c] for c in coords] for j in group])
            Minv = sp.diag(*[1 / asm.masses[c] for c in coords])
            A = (J * Minv * J.T).applyfunc(_simplify_parameters)
            try:
                Ainv = A.inv().applyfunc(_simplify_parameters)
            except NonInvertibleMatrixError:
                self._inverse[key] = None
            else:
                self._inverse[key] = (coords, J, Minv, Ainv)
        if self._inverse[key] is None:
            raise _Dependent(_dependent(self.asm, group))
        return self._inverse[key]

    def solve_group(self, group, Fvec) -> list:
        """Stick forces of one group, in the order of ``group``, for the loads ``Fvec``.

        Raises
        ------
        _Dependent
            When the group's stick constraints are not independent.
        """
        coords = self._coords(group)
        key = (tuple(group), tuple(Fvec[self.index[c]] for c in coords))
        if key not in self._forces:
            if len(group) == 1:
                try:
                    lam = _joint_solve(self.asm, group, Fvec)
                except NonInvertibleMatrixError:
                    raise _Dependent(_dependent(self.asm, group)) from None
            else:
                coords, J, Minv, Ainv = self._system(group)
                b = J * Minv * sp.Matrix([Fvec[self.index[c]] for c in coords])
                lam = [_tidy(x) for x in Ainv * b]
            self._forces[key] = lam
        return self._forces[key]

    def __call__(self, asm, constrained, Fvec) -> list:
        """The stick forces of ``constrained`` (the ``solve`` of :func:`_contact_forces`)."""
        lam = {}
        for group in self.groups(constrained):
            lam.update(zip(group, self.solve_group(group, Fvec)))
        return [lam[j] for j in constrained]

    def force(self, combo, j):
        """Stick force of contact ``j`` in the target mode ``combo``: only ``j``'s group is solved.

        When that group's constraints are dependent (closing the last open contact
        of a ring of sticking ones) the force is not unique: ``f_c`` is returned
        unresolved, so the transition's condition keeps the symbol.
        """
        F, _, _, _, constrained = _loads(self.asm, combo)
        group = next(g for g in self.groups(constrained) if j in g)
        Fvec = sp.Matrix([F[c] for c in self.asm.coords])
        try:
            return self.solve_group(group, Fvec)[group.index(j)]
        except _Dependent:
            return self.asm.f_sym[j]

    def _independent(self, group) -> list:
        """``group`` without one contact whose constraint the others imply (same velocity projection)."""
        if len(group) > 1:
            for j in reversed(group):
                rest = [i for i in group if i != j]
                try:
                    if len(rest) > 1:
                        self._system(rest)
                    return rest
                except _Dependent:
                    continue
        raise _Dependent(_dependent(self.asm, group))

    def _reset(self, group) -> dict:
        """Velocity reset onto ``v = 0`` of one group's contacts, on the coordinates they slide."""
        asm, u = self.asm, self.asm.u
        if len(group) > 1:
            try:
                self._system(group)
            except _Dependent:  # v = 0 of the others implies the dropped contact's
                group = self._independent(group)
        if len(group) == 1:
            full = _projection(asm, group)
            return {u[c]: full[u[c]] for c in self._coords(group)}
        coords, J, Minv, Ainv = self._system(group)
        u_vec = sp.Matrix([u[c] for c in coords])
        du = Minv * J.T * (Ainv * (J * u_vec))
        return {u[c]: sp.expand(u[c] - du[i]) for i, c in enumerate(coords)}

    def projection(self, asm, constrained) -> dict:
        """Velocity reset onto ``v = 0`` of every stick constraint (the ``project`` of :func:`_guards`)."""
        u = asm.u
        reset = {u[c]: u[c] for c in asm.coords}
        for group in self.groups(constrained):
            key = tuple(group)
            if key not in self._resets:
                self._resets[key] = self._reset(group)
            reset.update(self._resets[key])
        return reset


# --- every mode --------------------------------------------------------------------------

def derive(model: Model) -> HybridSystem:
    """Derive every reachable mode of ``model`` with its flow, guards and transitions.

    The modes are the product of every contact's modes, so the cost grows as
    ``prod(len(c.modes))``; for many contacts derive one mode with
    :func:`derive_mode`.

    Parameters
    ----------
    model : Model

    Returns
    -------
    HybridSystem
    """
    asm = _assemble(model)
    contacts = asm.contacts
    local_modes = [c.modes for c in contacts]
    combos = list(itertools.product(*local_modes)) if contacts else [()]

    display_F = {}
    modes: list[Mode] = []
    for combo in combos:
        mode, Fdisp = _flow(asm, combo)
        display_F[mode.name] = Fdisp
        modes.append(mode)

    index = {m.local: i for i, m in enumerate(modes)}

    def resolve(combo):
        target = modes[index[combo]]
        return index[combo], target.constrained, lambda j: target.friction_forces[j]

    for mode in modes:
        mode.guards.extend(_guards(asm, mode, resolve))

    return HybridSystem(model=model, t=asm.t, q=[asm.q[c] for c in asm.coords],
                        u=[asm.u[c] for c in asm.coords], s=asm.state_syms, params=asm.params,
                        mass_matrix=asm.M, generalized_forces=display_F, normal_symbols=asm.N_sym,
                        friction_symbols=asm.f_sym, modes=modes,
                        open_mode=index[tuple("open" for _ in contacts)] if contacts else 0,
                        energy=_energy(asm, modes))


# --- one mode ----------------------------------------------------------------------------

def mode_count(model: Model) -> int:
    """Number of modes :func:`derive` would derive, ``prod(len(c.modes))``, without enumerating them."""
    return math.prod(len(c.modes) for c in model.contacts)


def _combo(contacts, assignment: Mapping[str, str]) -> tuple:
    """The local modes of ``assignment`` (contact name -> mode; unnamed contacts open).

    Raises
    ------
    KeyError
        For an unknown contact or a mode the contact does not have; the message
        names the valid ones.
    """
    by_name = {c.name: c for c in contacts}
    for name, mode in assignment.items():
        if name not in by_name:
            valid = _name_list(by_name) if by_name else "none (the model has no contact)"
            raise KeyError(f"no contact {name!r}; contacts are {valid}")
        if mode not in by_name[name].modes:
            raise KeyError(f"contact {name} has no mode {mode!r}; its modes are "
                           f"{', '.join(by_name[name].modes)}")
    return tuple(assignment.get(c.name, "open") for c in contacts)


def parse_assignment(text: str) -> dict[str, str]:
    """``"c12=stick, c23=open"`` -> ``{"c12": "stick", "c23": "open"}``; ``"open"`` -> ``{}``.

    Only the syntax is checked here; :func:`derive_mode` checks the names.

    Raises
    ------
    ValueError
        For an item without ``=`` or a contact named twice.
    """
    if text.strip() == "open":
        return {}
    out: dict[str, str] = {}
    for item in text.split(","):
        name, sep, mode = (x.strip() for x in item.partition("="))
        if not sep or not name or not mode:
            raise ValueError(f"{item.strip()!r} is not CONTACT=MODE (a list like c12=stick,c23=slip+; "
                             f"contacts not named are open)")
        if name in out:
            raise ValueError(f"contact {name} is named twice")
        out[name] = mode
    return out


def derive_mode(model: Model, assignment: Mapping[str, str] | None = None, *,
                guards: bool = True) -> ModeSystem:
    """Derive one mode of ``model``: its flow, contact forces and guards, nothing else.

    Nothing is enumerated: the cost grows with the model (coordinates, contacts
    and the transitions out of this mode), not with the number of mode
    combinations, so one mode of a 24-blade ring derives in about a second. The
    expressions are those of the same mode in :func:`derive` (same code).

    Parameters
    ----------
    model : Model
    assignment : dict of str to str, optional
        Contact name -> mode (``{"c12": "stick"}``); contacts not named are
        ``open``. ``None`` or ``{}``: every contact open.
    guards : bool
        Derive the guards and their transitions (most of the work: each
        transition into a stick mode solves that mode's stick force). ``False``
        leaves ``mode.guards`` empty, which is all the display needs.

    Returns
    -------
    ModeSystem
        The mode (``.mode``: accelerations with the stick forces of every
        sticking contact solved jointly, ``N``, ``f``, state rates, and guards of
        every contact), its generalized forces with ``N_c``, ``f_c`` kept as
        symbols for display, and the targets of the guards' transitions
        (``Transition.target`` indexes ``.targets``).

    Raises
    ------
    KeyError
        For an unknown contact or mode; the message names the valid ones.
    ValueError
        When sticking contacts' constraints are dependent (every contact of a
        ring sticking): their forces are not unique.
    """
    asm = _assemble(model)
    combo = _combo(asm.contacts, dict(assignment or {}))
    solver = _GroupSolver(asm)
    mode, Fdisp = _flow(asm, combo, solver)

    targets: list[tuple] = []
    ids: dict = {}

    def resolve(target):
        if target not in ids:
            ids[target] = len(targets)
            targets.append(target)
        changed = [j for j, (a, b) in enumerate(zip(target, combo)) if a != b]
        constrained = sorted((set(mode.constrained) - set(changed))
                             | {j for j in changed if _local_force(asm, target, j) is STICK})

        def force_of(j):
            force = _local_force(asm, target, j)
            return solver.force(target, j) if force is STICK else force

        return ids[target], constrained, force_of

    if guards:
        mode.guards.extend(_guards(asm, mode, resolve, solver.projection))
    return ModeSystem(model=model, t=asm.t, q=[asm.q[c] for c in asm.coords],
                      u=[asm.u[c] for c in asm.coords], s=asm.state_syms, params=asm.params,
                      mass_matrix=asm.M, normal_symbols=asm.N_sym, friction_symbols=asm.f_sym,
                      mode=mode, forces=Fdisp, targets=targets,
                      contact_names=[c.name for c in asm.contacts])


# --- one contact -------------------------------------------------------------------------

def contact_equations(model: Model, name: str) -> ContactEquations:
    """One contact's own equations, in every one of its modes, independent of the others.

    The friction law is written with the contact's ``N_c``, ``v_c`` (and ``Ndot_c``)
    as symbols, defined once from the penetration and the relative slip; ``f_c``
    in a stick mode stays a symbol: it is the constraint force holding
    ``dv_c/dt = 0``, which depends on the other contacts (see :func:`derive_mode`).

    Parameters
    ----------
    model : Model
    name : str
        A contact name.

    Returns
    -------
    ContactEquations

    Raises
    ------
    KeyError
        For an unknown contact; the message names the valid ones.
    """
    by_name = {c.name: c for c in model.contacts}
    if name not in by_name:
        valid = _name_list(by_name) if by_name else "none (the model has no contact)"
        raise KeyError(f"no contact {name!r}; contacts are {valid}")
    c = by_name[name]
    q, u, s = _state_symbols(model)
    delta = c.penetration(q)
    slip = c.relative_slip(q)
    rate = _derivative(delta, q, u)
    acc = sum(sp.diff(delta, x) * sp.Symbol(f"a{x.name}", real=True) for x in q.values())
    k = c.parameters()["k"].symbol if "k" in c.parameters() else None
    N, Ndot, v, f = (sp.Symbol(f"{x}_{name}", real=True) for x in ("N", "Ndot", "v", "f"))
    states = {st: s[(name, st)] for st in c.friction.states}
    ctx = ContactContext(N=N, Ndot=Ndot, v=v, f=f, states=states,
                         params={n: p.symbol for n, p in c.friction.parameters().items()})
    modes = []
    for mode in c.modes:
        lm = None if mode == "open" else mode
        r = c.friction.rates(lm, ctx) if lm else c.friction.open_rates(ctx)
        modes.append(ContactModeEquations(
            mode=mode, normal_force=sp.Integer(0) if lm is None else N,
            friction_force=sp.Integer(0) if lm is None else c.friction.force(lm, ctx),
            rates={states[st]: sp.sympify(r.get(st, 0)) for st in c.friction.states},
            guards=_contact_guards(c, lm, ctx, c.closing_guard(delta, rate), c.opening_guard(delta, rate))))
    return ContactEquations(
        model=model, name=name, bodies=tuple(b.name for b in c.bodies), ground=c.body2 is None,
        law=type(c.friction).__name__, q=list(q.values()), u=list(u.values()),
        penetration=delta, slip=slip, k=k, N=N, Ndot=Ndot, v=v, f=f,
        definitions={N: c.normal_force(delta, rate), v: _derivative(slip, q, u),
                     Ndot: c.normal_force_rate(rate, acc)},
        normal_kind=c.normal_kind, penetration_rate=rate,
        states=states,
        params=[p.symbol for p in (*c.parameters().values(), *c.friction.parameters().values())],
        modes=modes)
