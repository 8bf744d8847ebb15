"""Derive the hybrid system of a model: a direct assembly of generalized forces.

Every component is a lumped element acting on Cartesian coordinates of point
masses, so the mass matrix is diagonal and each load's generalized force is its
projection on the coordinates. A Lagrangian/Kane formulation would give the same
equations with more machinery; the direct assembly keeps each load visible and
makes the stick constraint force a plain linear solve. ``tests/test_assembly.py``
checks the smooth part against ``sympy.physics.mechanics.LagrangesMethod``.
"""

from __future__ import annotations

import itertools

import sympy as sp

from ..components.friction.base import STICK, Candidate, ContactContext
from ..model import Model
from .system import GuardSpec, HybridSystem, Mode, Transition


def _state_symbols(model: Model):
    q = {c: sp.Symbol(c, real=True) for c in model.coordinates}
    u = {c: sp.Symbol(f"v{c}", real=True) for c in model.coordinates}
    names = [s for c in model.contacts for s in c.friction.states]
    s = {}
    for c in model.contacts:
        for st in c.friction.states:
            label = st if names.count(st) == 1 else f"{st}_{c.name}"
            s[(c.name, st)] = sp.Symbol(label, real=True)
    return q, u, s


def _derivative(expr, q, u):
    """Time derivative of a function of the coordinates (no explicit time)."""
    return sum(sp.diff(expr, q[c]) * u[c] for c in q)


def _tidy(expr):
    """Collect a solved constraint force over a trig-simplified common denominator."""
    num, den = sp.fraction(sp.together(sp.expand(expr)))
    return sp.expand(num) / sp.factor(sp.trigsimp(den))


def derive(model: Model) -> HybridSystem:
    """Derive every reachable mode of ``model`` with its flow, guards and transitions.

    Parameters
    ----------
    model : Model

    Returns
    -------
    HybridSystem
    """
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
    for j, c in enumerate(contacts):
        delta = c.penetration(q)
        slip = c.relative_slip(q)
        k = c.parameters()["k"].symbol
        ctx = ContactContext(
            N=k * delta, Ndot=k * _derivative(delta, q, u), v=_derivative(slip, q, u), f=f_sym[j],
            states={st: s[(c.name, st)] for st in c.friction.states},
            params={name: p.symbol for name, p in c.friction.parameters().items()})
        ctxs.append(ctx)
        geom.append({"delta": delta,
                     "dn": {cc: sp.diff(delta, q[cc]) for cc in coords},
                     "dr": {cc: sp.diff(slip, q[cc]) for cc in coords}})

    state_syms = [s[(c.name, st)] for c in contacts for st in c.friction.states]
    local_modes = [c.modes for c in contacts]
    combos = list(itertools.product(*local_modes)) if contacts else [()]

    def mode_name(combo):
        if not contacts:
            return "free"
        if len(contacts) == 1:
            return combo[0]
        return ",".join(f"{c.name}={m}" for c, m in zip(contacts, combo))

    def law_mode(j, combo):
        return None if combo[j] == "open" else combo[j]

    # --- flows ------------------------------------------------------------------
    display_F = {}
    modes: list[Mode] = []
    for combo in combos:
        F = dict(F_smooth)
        Fdisp = dict(F_smooth)
        Nj, fj, constrained = [], [], []
        for j, c in enumerate(contacts):
            lm = law_mode(j, combo)
            if lm is None:
                Nj.append(sp.Integer(0))
                fj.append(sp.Integer(0))
                continue
            Nj.append(ctxs[j].N)
            force = c.friction.force(lm, ctxs[j])
            if force is STICK:
                constrained.append(j)
                fj.append(None)
            else:
                fj.append(force)
            for cc in coords:
                F[cc] += -ctxs[j].N * geom[j]["dn"][cc]
                Fdisp[cc] += -N_sym[j] * geom[j]["dn"][cc] - f_sym[j] * geom[j]["dr"][cc]
                if force is not STICK:
                    F[cc] += -force * geom[j]["dr"][cc]
        Fvec = sp.Matrix([F[c] for c in coords])
        Minv = sp.diag(*[1 / masses[c] for c in coords])
        if constrained:
            # a = M^-1 (F - J^T lam);  J a = 0  ->  (J M^-1 J^T) lam = J M^-1 F
            J = sp.Matrix([[geom[j]["dr"][c] for c in coords] for j in constrained])
            A = J * Minv * J.T
            lam = A.LUsolve(J * Minv * Fvec)
            lam = [_tidy(x) for x in lam]
            for i, j in enumerate(constrained):
                fj[j] = lam[i]
            Fvec = Fvec - J.T * sp.Matrix(lam)
        acc = [sp.expand(x) for x in Minv * Fvec]
        rates = []
        for j, c in enumerate(contacts):
            lm = law_mode(j, combo)
            sub = {f_sym[j]: fj[j]}
            r = c.friction.rates(lm, ctxs[j]) if lm else c.friction.open_rates(ctxs[j])
            for st in c.friction.states:
                rates.append(sp.sympify(r.get(st, 0)).xreplace(sub))
        display_F[mode_name(combo)] = Fdisp
        modes.append(Mode(mode_name(combo), combo, acc, rates, Nj, fj, constrained))

    index = {m.local: i for i, m in enumerate(modes)}
    u_vec = sp.Matrix([u[c] for c in coords])
    Minv = sp.diag(*[1 / masses[c] for c in coords])

    def projection(target: Mode) -> dict:
        """Velocity reset onto ``v = 0`` of every stick constraint of ``target``."""
        if not target.constrained:
            return {}
        J = sp.Matrix([[geom[j]["dr"][c] for c in coords] for j in target.constrained])
        A = J * Minv * J.T
        du = Minv * J.T * A.LUsolve(J * u_vec)
        return {u[c]: sp.expand(u[c] - du[i]) for i, c in enumerate(coords)}

    def subs_f(expr, mode: Mode, j):
        return sp.sympify(expr).xreplace({f_sym[j]: mode.friction_forces[j]})

    def make_transitions(j, mode: Mode, candidates: list[Candidate]):
        c = contacts[j]
        out = []
        for cand in candidates:
            if cand.mode not in c.modes:
                raise ValueError(f"friction law {type(c.friction).__name__} names mode {cand.mode!r}, "
                                 f"which is not among its modes {c.modes}")
            combo = list(mode.local)
            combo[j] = cand.mode
            target = modes[index[tuple(combo)]]
            reset = {}
            for st, expr in cand.reset.items():
                reset[ctxs[j].states[st]] = subs_f(expr, mode, j)
            reset.update(projection(target) if set(target.constrained) - set(mode.constrained)
                         else {})
            cond = subs_f(cand.when, target, j)
            out.append(Transition(index[tuple(combo)], cond, reset))
        return out

    # --- guards -------------------------------------------------------------------
    for mode in modes:
        for j, c in enumerate(contacts):
            lm = law_mode(j, mode.local)
            ctx = ctxs[j]
            delta = geom[j]["delta"]
            if lm is None:
                mode.guards.append(GuardSpec(delta, +1, f"{c.name}: close", j,
                                             make_transitions(j, mode, c.friction.entry(ctx))))
                continue
            exit_c = Candidate("open", sp.true, c.friction.exit_reset(ctx))
            mode.guards.append(GuardSpec(delta, -1, f"{c.name}: open", j,
                                         make_transitions(j, mode, [exit_c])))
            for g in c.friction.guards(lm, ctx):
                if g.direction not in (-1, 0, 1):
                    raise ValueError(f"guard {g.name!r}: direction must be -1, 0 or +1")
                mode.guards.append(GuardSpec(subs_f(g.expr, mode, j), g.direction,
                                             f"{c.name}: {g.name}", j,
                                             make_transitions(j, mode, list(g.candidates))))

    # --- energy -------------------------------------------------------------------
    kinetic = sum(masses[c] * u[c] ** 2 / 2 for c in coords)
    potential = sum((sp.sympify(sp_.potential_energy(q)) for sp_ in model.springs), sp.Integer(0))
    input_power = sum((sum(f * u[c] for c, f in comp.loads(q, u, t).items()) for comp in model.forces),
                      sp.Integer(0))
    viscous = sum((d.dissipation_rate(u) for d in model.dampers), sp.Integer(0))
    energy = {"kinetic": kinetic, "potential": potential, "input_power": input_power,
              "viscous_power": viscous, "contact": [], "law": [], "friction_power": []}
    for mode in modes:
        contact_e, law_e, fric_p = sp.Integer(0), sp.Integer(0), sp.Integer(0)
        for j, c in enumerate(contacts):
            E_law = c.friction.stored_energy(ctxs[j])
            law_e += E_law
            if law_mode(j, mode.local) is None:
                continue
            k = c.parameters()["k"].symbol
            contact_e += k * geom[j]["delta"] ** 2 / 2
            dE = sum(sp.diff(E_law, st) * mode.state_rates[state_syms.index(st)]
                     for st in ctxs[j].states.values())
            fric_p += mode.friction_forces[j] * ctxs[j].v - dE
        energy["contact"].append(contact_e)
        energy["law"].append(law_e)
        energy["friction_power"].append(fric_p)

    return HybridSystem(model=model, t=t, q=[q[c] for c in coords], u=[u[c] for c in coords],
                        s=state_syms, params=params, mass_matrix=M, generalized_forces=display_F,
                        normal_symbols=N_sym, friction_symbols=f_sym, modes=modes,
                        open_mode=index[tuple("open" for _ in contacts)] if contacts else 0,
                        energy=energy)
