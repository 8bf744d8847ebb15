r"""Readable equations of motion of a derived system, per mode.

The equations are written as in the paper (Eq. 2-3): the mass, damping and
stiffness terms on the left, the excitation and the contact forces ``N_c`` and
``f_c`` (kept as symbols) on the right::

    m x1'' + cx x1' + kx x1 = F0 sin(omega t + phi1) cos(beta) - N_c sin(alpha) - f_c cos(alpha)

:func:`definitions` gives what ``N_c`` and ``f_c`` are in a mode (in a stick
mode, ``f_c`` is the constraint force derived by :func:`~blademodel.symbolic.derive`)
and the rates of the friction laws' own states. Coordinates are displayed as
functions of time, ``x1(t)``, with ``sympy.physics.vector`` dot notation.

The printed forms (:func:`pretty`, :func:`latex` and their contact versions)
show every symbol by its display name (:mod:`~blademodel.symbolic.names`):
``c_{x} \dot{x}_{1}``, not the product ``cx \dot{x}_{1}``. The symbols themselves,
and so the generated code, keep the model's names.
"""

from __future__ import annotations

from typing import Optional, Union

import sympy as sp
from sympy.physics.vector import dynamicsymbols
from sympy.physics.vector.printing import vlatex, vpprint

from .names import readable_symbols
from .system import ContactEquations, HybridSystem, Mode, ModeSystem

#: A whole derived system, or one mode derived alone (:func:`~blademodel.symbolic.assembly.derive_mode`).
System = Union[HybridSystem, ModeSystem]


def _time_functions(system: System, readable: bool = False) -> tuple[sp.Symbol, dict]:
    """``t`` and the substitution of state symbols by functions of time (and of names by display names)."""
    t = dynamicsymbols._t
    sub = {system.t: t}
    for q, u in zip(system.q, system.u):
        f = dynamicsymbols(q.name)
        sub[q] = f
        sub[u] = f.diff(t)
        sub[sp.Symbol(f"a{q.name}", real=True)] = f.diff(t, 2)   # in a damped contact's Ndot
    for s in system.s:
        sub[s] = dynamicsymbols(s.name)
    if readable:
        sub = _readable(sub, [*system.params, *system.normal_symbols, *system.friction_symbols])
    return t, sub


def _readable(sub: dict, symbols: list) -> dict:
    """``sub`` followed by the display names of its values and of ``symbols``."""
    names = readable_symbols([*sub.values(), *symbols])
    out = {k: v.xreplace(names) for k, v in sub.items()}
    out.update((k, v) for k, v in names.items() if k not in out and isinstance(k, sp.Symbol))
    return out


def _ordered_add(terms: list) -> sp.Expr:
    """An unevaluated sum keeping the order of ``terms`` (print with ``order='none'``)."""
    terms = [x for x in terms if x != 0]
    if not terms:
        return sp.Integer(0)
    return terms[0] if len(terms) == 1 else sp.Add(*terms, evaluate=False)


def _mode(system: System, mode_name: str) -> Mode:
    return system.modes[system.mode_index(mode_name)]  # KeyError naming the valid modes


def equations(system: System, mode_name: str, *, readable: bool = False) -> list[sp.Eq]:
    """Equations of motion of the coordinates in one mode, ``M q'' + ... = RHS``.

    Parameters
    ----------
    system : HybridSystem or ModeSystem
    mode_name : str
        A name from ``[m.name for m in system.modes]``.
    readable : bool
        Symbols by their display names (``c_x`` for ``cx``; for printing) instead
        of the model's symbols.

    Returns
    -------
    list of sympy.Eq
        One per coordinate, in coordinate order. The left side holds the
        inertia term and every term linear in the state without contact forces
        (damping, stiffness; the order ``m q'' + c q' + k q`` is kept for
        printing with ``order='none'``); the right side the excitation and the
        contact forces ``N_c``, ``f_c`` of the contacts closed in this mode.

    Raises
    ------
    KeyError
        For an unknown mode; the message lists the valid ones.
    """
    mode_name = _mode(system, mode_name).name
    t, sub = _time_functions(system, readable)
    rhs_all = system.generalized_forces[mode_name]
    contact_syms = set(system.normal_symbols) | set(system.friction_symbols)
    u_set, q_set = set(system.u), set(system.q)
    out = []
    for i, q in enumerate(system.q):
        lhs_u, lhs_q, forcing, contact = [], [], [], []
        for term in sp.Add.make_args(sp.expand(rhs_all[q.name])):
            free = term.free_symbols
            if free & contact_syms:
                contact.append(term)
            elif free & u_set:
                lhs_u.append(-term)
            elif free & q_set:
                lhs_q.append(-term)
            else:
                forcing.append(term)
        inertia = system.mass_matrix[i, i] * sub[q].diff(t, 2)
        key = sp.default_sort_key
        lhs = [inertia] + sorted(lhs_u, key=key) + sorted(lhs_q, key=key)
        rhs = sorted(forcing, key=key) + sorted(contact, key=key)
        out.append(sp.Eq(_ordered_add([x.xreplace(sub) for x in lhs]),
                         _ordered_add([x.xreplace(sub) for x in rhs]), evaluate=False))
    return out


def _over_common_denominator(expr: sp.Expr, sub: dict) -> sp.Expr:
    """``expr`` as one fraction (unevaluated, so that SymPy does not distribute ``1/2``)."""
    num, den = sp.fraction(sp.together(expr))
    num, den = sp.expand(num).xreplace(sub), den.xreplace(sub)
    return num if den == 1 else sp.Mul(num, sp.Pow(den, -1, evaluate=False), evaluate=False)


def definitions(system: System, mode_name: str, *, open_contacts: bool = True,
                readable: bool = False) -> list[sp.Eq]:
    """What the contact symbols are in one mode, and the law states' rates.

    Parameters
    ----------
    system : HybridSystem or ModeSystem
    mode_name : str
    open_contacts : bool
        ``False`` leaves out the open contacts' ``N_c = 0``, ``f_c = 0`` and their
        states' rates when zero (many contacts, few closed).
    readable : bool
        Symbols by their display names (for printing).

    Returns
    -------
    list of sympy.Eq
        ``N_c = ...`` and ``f_c = ...`` for every contact (zero when open; in a
        stick mode ``f_c`` is the derived constraint force), then ``z' = ...`` for
        every internal state of the friction laws.
    """
    mode = _mode(system, mode_name)
    t, sub = _time_functions(system, readable)
    out = []
    shown = [open_contacts or local != "open" for local in mode.local]
    for N, f, Nv, fv, show in zip(system.normal_symbols, system.friction_symbols,
                                  mode.normal_forces, mode.friction_forces, shown):
        if not show:
            continue
        out.append(sp.Eq(sub.get(N, N), sp.sympify(Nv).xreplace(sub), evaluate=False))
        out.append(sp.Eq(sub.get(f, f), _over_common_denominator(sp.sympify(fv), sub), evaluate=False))
    owners = ([j for j, c in enumerate(system.model.contacts) for _ in c.friction.states]
              if not open_contacts else [None] * len(system.s))
    for s, rate, j in zip(system.s, mode.state_rates, owners):
        if j is not None and not shown[j] and sp.sympify(rate) == 0:
            continue
        out.append(sp.Eq(sub[s].diff(t), sp.sympify(rate).xreplace(sub), evaluate=False))
    return out


def _modes(system: System, mode: Optional[str]) -> list[str]:
    if mode is None:
        return [m.name for m in system.modes]
    return [_mode(system, mode).name]


def _heading(system: System, name: str) -> str:
    model = getattr(system.model, "name", "model")
    if isinstance(system, ModeSystem):
        name = system.label
    return f"{model}: mode {name}"


def _definitions(system: System, name: str) -> list[sp.Eq]:
    """The definitions printed: a mode derived alone leaves out its open contacts."""
    return definitions(system, name, open_contacts=not isinstance(system, ModeSystem), readable=True)


def pretty(system: System, mode: Optional[str] = None, *, unicode: bool = True) -> str:
    """Pretty-printed equations of every mode (or of ``mode``), one headed block each.

    Parameters
    ----------
    system : HybridSystem or ModeSystem
        A :class:`ModeSystem` is headed by its short label and leaves out the
        open contacts' zero definitions.
    mode : str, optional
        Only this mode.
    unicode : bool
        Unicode symbols and dot notation; ``False`` gives plain ASCII.

    Returns
    -------
    str
    """
    settings = {"order": "none", "use_unicode": unicode, "wrap_line": False}
    blocks = []
    for name in _modes(system, mode):
        head = _heading(system, name)
        lines = [head, ("═" if unicode else "=") * len(head)]
        lines += [vpprint(eq, **settings) for eq in equations(system, name, readable=True)]
        defs = _definitions(system, name)
        if defs:
            lines.append("where")
            lines += ["  " + vpprint(eq, **settings).replace("\n", "\n  ") for eq in defs]
        blocks.append("\n".join(lines))
    return "\n\n".join(blocks) + "\n"


def _tex_text(text: str) -> str:
    for a, b in (("\\", r"\textbackslash{}"), ("_", r"\_"), ("&", r"\&"), ("%", r"\%"), ("#", r"\#"),
                 ("$", r"\$"), ("{", r"\{"), ("}", r"\}")):
        text = text.replace(a, b)
    return text


def _tex_eq(eq: sp.Eq) -> str:
    return f"{vlatex(eq.lhs, order='none')} &= {vlatex(eq.rhs, order='none')}"


def latex(system: System, mode: Optional[str] = None) -> str:
    """LaTeX of every mode (or of ``mode``): a headed ``align*`` block per mode.

    Needs ``amsmath``. Contact definitions follow the equations after an
    ``\\intertext{where}``.

    Parameters
    ----------
    system : HybridSystem or ModeSystem
    mode : str, optional

    Returns
    -------
    str
    """
    blocks = []
    for name in _modes(system, mode):
        rows = [_tex_eq(eq) for eq in equations(system, name, readable=True)]
        defs = _definitions(system, name)
        body = " \\\\\n".join(rows)
        if defs:
            body += " \\\\\n\\intertext{where}\n" + " \\\\\n".join(_tex_eq(eq) for eq in defs)
        title = system.label if isinstance(system, ModeSystem) else name
        blocks.append(f"\\paragraph{{Mode \\texttt{{{_tex_text(title)}}}}}\n"
                      f"\\begin{{align*}}\n{body}\n\\end{{align*}}")
    return "\n\n".join(blocks) + "\n"


# --- one contact's own equations -------------------------------------------------------------

_DIRECTION = {-1: "falls through 0", 1: "rises through 0", 0: "crosses 0"}
_NORMAL_NOTE = {"spring": "normal force while closed, 0 while open",
                "damped": "normal force while closed (>= 0: it opens when N falls through 0), 0 while open",
                "load": "constant normal load: closed from the start, never opens"}


def _contact_sub(ce: ContactEquations, shown: list) -> dict:
    """The substitution of the state symbols by functions of time (``Ndot_c`` prints as a dotted N).

    The names are display names, also of the symbols ``shown`` (those the rows add).
    """
    t = dynamicsymbols._t
    sub = {}
    for q, u in zip(ce.q, ce.u):
        f = dynamicsymbols(q.name)
        sub[q] = f
        sub[u] = f.diff(t)
        sub[sp.Symbol(f"a{q.name}", real=True)] = f.diff(t, 2)   # in a damped contact's Ndot
    for s in ce.states.values():
        sub[s] = dynamicsymbols(s.name)
    named = [*ce.params, ce.k, ce.N, ce.Ndot, ce.v, ce.f, *shown]
    return _readable(sub, [s for s in named if s is not None])   # a constant-load contact has no k


def _uses_Ndot(ce: ContactEquations) -> bool:
    exprs = []
    for m in ce.modes:
        exprs += [m.friction_force, *m.rates.values()]
        for g in m.guards:
            exprs.append(g.expr)
            for c in g.candidates:
                exprs += [c.when, *c.reset.values()]
    return any(isinstance(x, sp.Basic) and x.has(ce.Ndot) for x in exprs)


def _contact_rows(ce: ContactEquations) -> list[tuple]:
    """The content of a contact's display as ``(kind, ...)`` rows, shared by text and LaTeX.

    Kinds: ``("eq", Eq, note)``, ``("mode", name)``, ``("stick", f, Eq)``,
    ``("guard", name, expr, direction text)``, ``("candidate", mode, condition or None, resets)``.
    """
    t = dynamicsymbols._t
    delta = sp.Symbol(f"delta_{ce.name}")
    r = sp.Symbol(f"r_{ce.name}")
    vdot = sp.Symbol(f"vdot_{ce.name}")
    deltadot = sp.Symbol(f"deltadot_{ce.name}")
    sub = _contact_sub(ce, [delta, r, vdot, deltadot])

    # a damped contact's guards and N read in delta and its rate
    named = {} if ce.normal_kind == "spring" else {ce.penetration: delta}
    if ce.normal_kind == "damped":
        named[ce.penetration_rate] = deltadot

    def X(expr):
        expr = sp.sympify(expr)
        return sub.get(delta, delta) if expr == ce.penetration else expr.xreplace(named).xreplace(sub)

    N, f = X(ce.N), X(ce.f)
    rows = [("eq", sp.Eq(X(delta), ce.penetration.xreplace(sub), evaluate=False),
             "penetration: closed while positive"),
            ("eq", sp.Eq(X(r), X(ce.slip), evaluate=False), "relative slip"),
            ("eq", sp.Eq(X(ce.v), X(ce.definitions[ce.v]), evaluate=False), "relative slip velocity, dr/dt"),
            ("eq", sp.Eq(N, sp.Mul(X(ce.k), X(delta), evaluate=False) if ce.normal_kind == "spring"
                         else X(ce.definitions[ce.N]), evaluate=False),
             _NORMAL_NOTE[ce.normal_kind])]
    if _uses_Ndot(ce):
        rows.append(("eq", sp.Eq(X(ce.Ndot), X(ce.definitions[ce.Ndot]), evaluate=False), "dN/dt while closed"))
    for m in ce.modes:
        rows.append(("mode", m.mode))
        if m.mode == "open":
            rows.append(("eq", sp.Eq(N, 0, evaluate=False), None))
        if isinstance(m.friction_force, sp.Basic):
            rows.append(("eq", sp.Eq(f, X(m.friction_force), evaluate=False), None))
        else:
            rows.append(("stick", f, sp.Eq(X(vdot), 0, evaluate=False)))
        for s, rate in m.rates.items():
            rows.append(("eq", sp.Eq(X(s).diff(t), X(rate), evaluate=False), None))
        for g in m.guards:
            rows.append(("guard", g.name, X(g.expr), _DIRECTION[g.direction]))
            for c in g.candidates:
                reset = [sp.Eq(X(ce.states[k]), X(v), evaluate=False) for k, v in c.reset.items()
                         if k in ce.states]
                rows.append(("candidate", c.mode, None if c.when == sp.true else X(c.when), reset))
    return rows


def _heading_contact(ce: ContactEquations) -> str:
    model = getattr(ce.model, "name", "model")
    bodies = f"bodies {ce.bodies[0]} and {ce.bodies[1]}" if len(ce.bodies) == 2 else \
        f"body {ce.bodies[0]} and the ground"
    return f"{model}: contact {ce.name} ({bodies}; friction law {ce.law})"


def pretty_contact(ce: ContactEquations, *, unicode: bool = True) -> str:
    """Pretty-printed equations of one contact: geometry, then each of its modes.

    ``N_c``, ``v_c`` and ``f_c`` stay symbols in the law's expressions; a stick
    mode's ``f_c`` is the constraint force, which depends on the other contacts'
    modes (``blademodel equations MODEL --mode c=stick,...`` derives it).

    Parameters
    ----------
    ce : ContactEquations
        From :func:`~blademodel.symbolic.assembly.contact_equations`.
    unicode : bool

    Returns
    -------
    str
    """
    settings = {"use_unicode": unicode, "wrap_line": False}
    arrow = "→" if unicode else "->"

    def art(expr, indent):
        return vpprint(expr, **settings).replace("\n", "\n" + " " * indent)

    def joined(prefix, expr, indent):
        text = vpprint(expr, **settings)
        if "\n" in text:  # a two-dimensional expression goes below its label
            return prefix.rstrip() + "\n" + " " * indent + text.replace("\n", "\n" + " " * indent)
        return prefix + text

    head = _heading_contact(ce)
    lines = [head, ("═" if unicode else "=") * len(head)]
    for row in _contact_rows(ce):
        kind = row[0]
        if kind == "eq":
            eq, note = row[1], row[2]
            lines.append("  " + art(eq, 2) + (f"    ({note})" if note else ""))
        elif kind == "mode":
            lines.append(f"mode {row[1]}")
        elif kind == "stick":
            lines.append(f"  {vpprint(row[1], **settings)}: the stick constraint force, which holds "
                         f"{vpprint(row[2], **settings)}")
            lines.append("    (it depends on the other contacts' modes: see --mode)")
        elif kind == "guard":
            lines.append(joined(f"  guard {row[1]}: ", row[2], 4) + f"   {row[3]}")
        elif kind == "candidate":
            _, mode, when, reset = row
            text = f"    {arrow} {mode}"
            if reset:
                text += ", " + ", ".join(vpprint(eq, **settings) for eq in reset)
            lines.append(joined(text + " if ", when, 8) if when is not None else text)
    return "\n".join(lines) + "\n"


def latex_contact(ce: ContactEquations) -> str:
    """LaTeX of one contact's equations: a headed ``align*`` block (needs ``amsmath``).

    Parameters
    ----------
    ce : ContactEquations

    Returns
    -------
    str
    """
    rows = []
    for row in _contact_rows(ce):
        kind = row[0]
        if kind == "eq":
            rows.append(_tex_eq_sorted(row[1]) + (f" && \\text{{{_tex_text(row[2])}}}" if row[2] else ""))
        elif kind == "mode":
            rows.append(f"\\intertext{{mode \\texttt{{{_tex_text(row[1])}}}}}")
        elif kind == "stick":
            rows.append(f"{vlatex(row[1])} &: \\text{{the stick constraint force, which holds }} "
                        f"{vlatex(row[2].lhs)} = 0")
        elif kind == "guard":
            rows.append(f"\\texttt{{{_tex_text(row[1])}}} &: {vlatex(row[2])} "
                        f"\\quad \\text{{{row[3]}}}")
        elif kind == "candidate":
            _, mode, when, reset = row
            text = f"&\\to \\texttt{{{_tex_text(mode)}}}"
            if reset:
                text += ",\\ " + ",\\ ".join(f"{vlatex(eq.lhs)} = {vlatex(eq.rhs)}" for eq in reset)
            if when is not None:
                text += f" \\text{{ if }} {vlatex(when)}"
            rows.append(text)
    body = rows[0]
    for prev, row in zip(rows, rows[1:]):
        body += ("\n" if prev.startswith("\\intertext") else " \\\\\n") + row
    return (f"\\paragraph{{Contact \\texttt{{{_tex_text(ce.name)}}}}}\n"
            f"\\begin{{align*}}\n{body}\n\\end{{align*}}\n")


def _tex_eq_sorted(eq: sp.Eq) -> str:
    return f"{vlatex(eq.lhs)} &= {vlatex(eq.rhs)}"
