"""Generated code of one friction law for the per-contact kernel.

A law's expressions are written once per law *kind* (its :meth:`structure`), in
scalar context symbols: the contact's normal force ``N``, its rate ``Nd``, the
relative tangential velocity ``v`` and the friction force ``f``, which the kernel
computes for each contact at run time. The law's states are read from the state
vector at the contact's offset (``y[so + i]``) and its parameters through the
contact's row of the parameter-index table (``p[LP[j, k]]``, in the kernel's flat
buffers ``R`` and ``I``: :mod:`blademodel.numeric.contract`), so one compiled
function serves every contact of that law, whatever the number of contacts.

Functions written for law kind ``K`` (``mode`` 0 is ``open``, ``1..`` the law's
modes in order; guard 0 of every mode is the penetration guard, ``close`` when
open and ``open`` when closed, the law's guards follow from 1):

``lawK_force(mode, N, Nd, v, y, so, R, I, j)``
    Friction force of an explicit-force mode (0 when open or in a rigid stick mode).
``lawK_rates(mode, N, Nd, v, f, y, so, R, I, j, out, oo)``
    Rates of the law's states into ``out[oo + i]``.
``lawK_guards(mode, N, Nd, v, f, y, so, R, I, j, G)``
    Law guard values into ``G[j, 1 + i]``.
``lawK_guard_rates(mode, N, Nd, Ndd, v, vd, f, fd, y, so, R, I, j, a, D)``
    Time derivatives of the law guards into ``D[j, 1 + i]`` (``Ndd``, ``vd``, ``fd``:
    the rates of ``Nd``, ``v`` and of a rigid stick force; ``a``: ``dy/dt``, whose
    law-state rates sit at ``a[so + i]``). A ``Piecewise`` has its branch's rate, a
    guard that is a ``Min`` or ``Max`` its chosen argument's (``rate_expr``,
    ``_choice_rate_lines``); not written (NaN) where a guard uses ``Abs``, ``sign`` or
    ``Heaviside``, or a ``Min`` inside an expression; NaN through ``fd`` where the stick
    force's rate is not known.
``lawK_force_rate(mode, N, Nd, Ndd, v, vd, y, so, R, I, j, a)``
    Rate of an explicit-force mode's friction force (0 open or in rigid stick; NaN
    if not smooth).
``lawK_transition(mode, gi, N, Nd, v, f, y, so, R, I, j, ztmp)``
    Apply guard ``gi``'s first admissible candidate (reset into ``y``) and return the
    target mode. A candidate whose target is a rigid stick mode is taken at once,
    reset applied: the kernel then decides stick or slip for that contact together
    with every other sticking contact (the friction complementarity problem).
``lawK_energy(y, so, R, I, j)``, ``lawK_dissipation(mode, N, Nd, v, f, y, so, R, I, j)``
    Stored energy of the law's states; friction power ``f v - dE/dt``.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp
from ..components.friction.base import STICK, Candidate, ContactContext, FrictionLaw
from .codegen import _Printer

#: Names of the rigid-stick law modes the friction complementarity problem needs.
RIGID_STICK_MODES = ("stick", "slip+", "slip-")


@dataclass
class LawCode:
    """Generated source and tables of one law kind.

    Attributes
    ----------
    source : str
        The ``lawK_*`` functions.
    modes : list of str
        ``["open", *law.modes]``.
    stick : list of bool
        Per mode: the friction force is a rigid stick constraint.
    guard_names : list of list of str
        Per mode, guard 0 (penetration) then the law's guards.
    guard_dirs : list of list of int
    n_states, n_params : int
    param_fields : list of str
        The law's parameter field names, in ``LP`` column order.
    rigid : tuple of int or None
        ``(stick, slip+, slip-)`` mode indices if the law has a rigid stick mode.
    open_rates : bool
        The law's states move while the contact is open (``open_rates``): the contact
        then couples its coordinates even when open.
    """

    source: str
    modes: list
    stick: list
    guard_names: list
    guard_dirs: list
    n_states: int
    n_params: int
    param_fields: list
    state_names: list
    rigid: tuple | None
    open_rates: bool = False


def _context(law: FrictionLaw):
    N, Nd, v, f = (sp.Symbol(n, real=True) for n in ("N", "Nd", "v", "f"))
    states = {st: sp.Symbol(f"_z{i}", real=True) for i, st in enumerate(law.states)}
    fields = list(law.parameters())
    params = {name: sp.Symbol(f"_p{k}", real=True) for k, name in enumerate(fields)}
    ctx = ContactContext(N=N, Ndot=Nd, v=v, f=f, states=states, params=params)
    return ctx, fields


def _names(ctx: ContactContext, state_array: str = "y") -> dict:
    out = {ctx.N: "N", ctx.Ndot: "Nd", ctx.v: "v", ctx.f: "f"}
    for i, s in enumerate(ctx.states.values()):
        out[s] = f"{state_array}[so + {i}]" if state_array == "y" else f"{state_array}[{i}]"
    for k, s in enumerate(ctx.params.values()):
        out[s] = f"R[I[R_P] + I[I[O_LP] + j * I[H_LPW] + {k}]]"
    return out


def _assign(exprs, targets, printer, pad, tag):
    """Source lines assigning ``exprs`` to ``targets`` with shared sub-expressions (floats)."""
    exprs = [sp.sympify(e) for e in exprs]
    if not exprs:
        return []
    reps, reduced = sp.cse(exprs, symbols=sp.numbered_symbols(f"{tag}_"), optimizations="basic")
    lines = [f"{pad}{s} = {printer.doprint(e)}" for s, e in reps]
    for tgt, e in zip(targets, reduced):
        text = repr(float(e)) if e.is_Number else printer.doprint(e)
        lines.append(f"{pad}{tgt} = {text}")
    return lines


def _check_rigid(law: FrictionLaw, ctx: ContactContext, name: str):
    """The contract of a law with a rigid stick mode, or a clear error."""
    if tuple(law.modes) != RIGID_STICK_MODES:
        raise ValueError(f"friction law {name}: a law with a rigid stick mode (force STICK) must have the modes "
                         f"{RIGID_STICK_MODES} for the per-contact kernel, not {tuple(law.modes)}")
    fp, fm = law.force("slip+", ctx), law.force("slip-", ctx)
    if fp is STICK or fm is STICK or sp.simplify(fp + fm) != 0:
        raise ValueError(f"friction law {name}: the slip forces must be opposite (+F in slip+, -F in slip-), "
                         f"got {fp} and {fm}")


#: Functions whose derivative is not an expression of the state: a guard using one gets no rate (a guard that *is*
#: a ``Min`` or ``Max`` has its chosen argument's: ``_choice_rate_lines``).
_NONSMOOTH = (sp.Abs, sp.sign, sp.Heaviside, sp.Min, sp.Max)


def _substituted(g, ctx: ContactContext, force):
    g = sp.sympify(g)
    return g if force is None else g.xreplace({ctx.f: force})


def rate_expr(g, ctx: ContactContext, force, Ndd, vd, fd, zd):
    """``dg/dt`` of an expression of a contact's ``N, Nd, v, f`` and law states, or None if it has no rate.

    ``force`` is the mode's explicit friction force, substituted for ``f``; None in a
    rigid stick mode, whose force is the stick solution with rate ``fd``. ``Ndd``,
    ``vd`` and ``zd`` (per law state) are the rates of ``Nd``, ``v`` and the states.

    A ``Piecewise`` (one branch per discrete state, as an Iwan element's stick or slip)
    has its branch's rate (SymPy differentiates it branch by branch). ``Abs``, ``sign``,
    ``Heaviside``, ``Min`` and ``Max`` give none; a guard that is a ``Min`` or ``Max``
    gets the rate of the argument it takes from :func:`_choice_rate_lines`.
    """
    g = _substituted(g, ctx, force)
    if any(g.has(fn) for fn in _NONSMOOTH):
        return None
    chain = [(ctx.N, ctx.Ndot), (ctx.Ndot, Ndd), (ctx.v, vd), (ctx.f, fd)] + list(zip(ctx.states.values(), zd))
    return sp.Add(*[sp.diff(g, s) * rate for s, rate in chain])


def _choice_rate_lines(g, target, ctx, force, Ndd, vd, fd, zd, printer, pad, tag):
    """Source lines that write into ``target`` the rate of a guard ``g`` that is a ``Min`` (``Max``) of arguments:
    the rate of the first argument equal to it (the one-sided rate at the instant), found by one pass over the
    arguments, so the code and the time to write it grow linearly with their number. A guard shared by several
    elements (the Iwan law's) moves as its critical element does, and the grazing check needs that rate to see
    the element's guard dip through zero and come back inside a step. None if an argument has no rate."""
    g = _substituted(g, ctx, force)
    rates = [rate_expr(a, ctx, None, Ndd, vd, fd, zd) for a in g.args]
    if any(r is None for r in rates):
        return None
    better = "<" if isinstance(g, sp.Min) else ">"
    L = _assign([g.args[0], rates[0]], [f"{tag}_g", f"{tag}_r"], printer, pad, f"{tag}_0")
    for k, (a, r) in enumerate(zip(g.args[1:], rates[1:]), start=1):
        L += _assign([a], [f"{tag}_a"], printer, pad, f"{tag}_{k}v")
        L.append(f"{pad}if {tag}_a {better} {tag}_g:")
        L.append(f"{pad}    {tag}_g = {tag}_a")
        L += _assign([r], [f"{tag}_r"], printer, pad + "    ", f"{tag}_{k}r")
    L.append(f"{pad}{target} = {tag}_r")
    return L


def _rates_source(K, ctx, modes, guard_lists, stick, explicit):
    """Source lines of ``lawK_guard_rates`` and ``lawK_force_rate``."""
    Ndd, vd, fd = (sp.Symbol(n, real=True) for n in ("Ndd", "vd", "fd"))
    zd = [sp.Symbol(f"_zd{i}", real=True) for i in range(len(ctx.states))]
    names = _names(ctx)
    names.update({Ndd: "Ndd", vd: "vd", fd: "fd"})
    names.update({s: f"a[so + {i}]" for i, s in enumerate(zd)})
    pr = _Printer(names)
    L = [f"def law{K}_guard_rates(mode, N, Nd, Ndd, v, vd, f, fd, y, so, R, I, j, a, D):"]
    body = []
    for m in range(1, len(modes)):
        force = None if stick[m] else explicit[m]
        chosen = {i: _choice_rate_lines(g.expr, f"D[j, {1 + i}]", ctx, force, Ndd, vd, fd, zd, pr, " " * 8, f"c{i}")
                  for i, g in enumerate(guard_lists[m]) if isinstance(g.expr, (sp.Min, sp.Max))}
        rates = [None if i in chosen else rate_expr(g.expr, ctx, force, Ndd, vd, fd, zd)
                 for i, g in enumerate(guard_lists[m])]
        known = [(i, r) for i, r in enumerate(rates) if r is not None]
        lines = [line for i in sorted(chosen) if chosen[i] is not None for line in chosen[i]]
        if known or lines:
            body.append(f"    {'if' if not body else 'elif'} mode == {m}:")
            body += _assign([r for _, r in known], [f"D[j, {1 + i}]" for i, _ in known], pr, " " * 8, "x")
            body += lines
    L += body or ["    pass"]
    L.append("")
    L.append(f"def law{K}_force_rate(mode, N, Nd, Ndd, v, vd, y, so, R, I, j, a):")
    for m in range(1, len(modes)):
        if not stick[m] and explicit[m] != 0:
            r = rate_expr(explicit[m], ctx, explicit[m], Ndd, vd, fd, zd)
            L.append(f"    if mode == {m}:")
            if r is None:
                L.append("        return math.nan")
            else:
                L += _assign([r], ["fdm"], pr, " " * 8, "x")
                L.append("        return fdm")
    L.append("    return 0.0")
    L.append("")
    return L


def law_code(law: FrictionLaw, K: int) -> LawCode:
    """Generate the functions of law kind ``K`` from ``law``'s symbolic expressions.

    Parameters
    ----------
    law : FrictionLaw
        Any instance of the kind (only its structure matters).
    K : int
        The kind's number in the generated module.

    Returns
    -------
    LawCode
    """
    name = type(law).__name__
    ctx, fields = _context(law)
    modes = ["open", *law.modes]
    pr = _Printer(_names(ctx))
    pr_tmp = _Printer(_names(ctx, "ztmp"))
    states = list(ctx.states.values())
    forces = [sp.Integer(0)] + [law.force(m, ctx) for m in law.modes]
    stick = [f is STICK for f in forces]
    rigid = None
    if any(stick):
        _check_rigid(law, ctx, name)
        rigid = tuple(modes.index(m) for m in RIGID_STICK_MODES)
    explicit = [sp.Integer(0) if f is STICK else sp.sympify(f) for f in forces]
    L = []

    def branch(m, first):
        return f"    {'if' if first else 'elif'} mode == {m}:"

    # force
    L.append(f"def law{K}_force(mode, N, Nd, v, y, so, R, I, j):")
    for m in range(1, len(modes)):
        if explicit[m] != 0:
            L.append(f"    if mode == {m}:")
            L += _assign([explicit[m]], ["fm"], pr, " " * 8, "x")
            L.append("        return fm")
    L.append("    return 0.0")
    L.append("")

    # rates
    L.append(f"def law{K}_rates(mode, N, Nd, v, f, y, so, R, I, j, out, oo):")
    body = []
    open_moves = False
    for m, mode in enumerate(modes):
        r = law.open_rates(ctx) if m == 0 else law.rates(mode, ctx)
        exprs = [sp.sympify(r.get(st, 0)) for st in law.states]
        if m == 0:
            open_moves = any(e != 0 for e in exprs)
        if not exprs:
            continue
        body.append(branch(m, not body))
        body += _assign(exprs, [f"out[oo + {i}]" for i in range(len(exprs))], pr, " " * 8, "x")
    L += body or ["    pass"]
    L.append("")

    # guards
    guard_names, guard_dirs, guard_lists = [], [], []
    L.append(f"def law{K}_guards(mode, N, Nd, v, f, y, so, R, I, j, G):")
    body = []
    for m, mode in enumerate(modes):
        gl = [] if m == 0 else list(law.guards(mode, ctx))
        for g in gl:
            if g.direction not in (-1, 0, 1):
                raise ValueError(f"friction law {name}: guard {g.name!r}: direction must be -1, 0 or +1")
        guard_lists.append(gl)
        guard_names.append(["close" if m == 0 else "open"] + [g.name for g in gl])
        guard_dirs.append([1 if m == 0 else -1] + [g.direction for g in gl])
        if gl:
            body.append(branch(m, not body))
            body += _assign([g.expr for g in gl], [f"G[j, {1 + i}]" for i in range(len(gl))], pr, " " * 8, "x")
    L += body or ["    pass"]
    L.append("")
    L += _rates_source(K, ctx, modes, guard_lists, stick, explicit)

    # transitions
    L.append(f"def law{K}_transition(mode, gi, N, Nd, v, f, y, so, R, I, j, ztmp):")
    first = True
    for m, mode in enumerate(modes):
        if m == 0:
            per_guard = [law.entry(ctx)]
        else:
            per_guard = [[Candidate("open", sp.true, law.exit_reset(ctx))]] + [list(g.candidates)
                                                                             for g in guard_lists[m]]
        for gi, cands in enumerate(per_guard):
            L.append(f"    {'if' if first else 'elif'} mode == {m} and gi == {gi}:")
            first = False
            for ci, cand in enumerate(cands):
                if cand.mode not in modes:
                    raise ValueError(f"friction law {name} names mode {cand.mode!r}, which is not among its "
                                     f"modes {tuple(modes)}")
                target = modes.index(cand.mode)
                L += [f"        ztmp[{i}] = y[so + {i}]" for i in range(len(states))]
                keys = list(cand.reset)
                L += _assign([cand.reset[k] for k in keys], [f"ztmp[{law.states.index(k)}]" for k in keys],
                             pr, " " * 8, "r")
                last = ci == len(cands) - 1
                if last or stick[target] or cand.when is sp.true:
                    test = "True"
                else:
                    fc = explicit[target]
                    L += _assign([fc], ["fc"], pr_tmp, " " * 8, "c")
                    cond = sp.sympify(cand.when).xreplace({ctx.f: sp.Symbol("fc", real=True)})
                    test = pr_tmp.doprint(cond)
                L.append(f"        if {test}:")
                L += [f"            y[so + {i}] = ztmp[{i}]" for i in range(len(states))]
                L.append(f"            return {target}")
                if test == "True":
                    break
    L.append("    return mode")
    L.append("")

    # energy and friction power
    E = sp.sympify(law.stored_energy(ctx))
    L.append(f"def law{K}_energy(y, so, R, I, j):")
    L += _assign([E], ["e"], pr, " " * 4, "x")
    L.append("    return e")
    L.append("")
    L.append(f"def law{K}_dissipation(mode, N, Nd, v, f, y, so, R, I, j):")
    body = []
    for m in range(1, len(modes)):
        r = law.rates(modes[m], ctx)
        dE = sum((sp.diff(E, s) * sp.sympify(r.get(st, 0)) for st, s in ctx.states.items()), sp.Integer(0))
        body.append(f"    if mode == {m}:")
        body += _assign([ctx.f * ctx.v - dE], ["d"], pr, " " * 8, "x")
        body.append("        return d")
    L += body
    L.append("    return 0.0")
    L.append("")
    return LawCode(source="\n".join(L), modes=modes, stick=stick, guard_names=guard_names, guard_dirs=guard_dirs,
                   n_states=len(states), n_params=len(fields), param_fields=fields, state_names=list(law.states),
                   rigid=rigid, open_rates=open_moves)
