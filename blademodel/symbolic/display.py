"""Readable equations of motion of a derived system, per mode.

The equations are written as in the paper (Eq. 2-3): the mass, damping and
stiffness terms on the left, the excitation and the contact forces ``N_c`` and
``f_c`` (kept as symbols) on the right::

    m x1'' + cx x1' + kx x1 = F0 sin(omega t + phi1) cos(beta) - N_c sin(alpha) - f_c cos(alpha)

:func:`definitions` gives what ``N_c`` and ``f_c`` are in a mode (in a stick
mode, ``f_c`` is the constraint force derived by :func:`~blademodel.symbolic.derive`)
and the rates of the friction laws' own states. Coordinates are displayed as
functions of time, ``x1(t)``, with ``sympy.physics.vector`` dot notation.
"""

from __future__ import annotations

from typing import Optional

import sympy as sp
from sympy.physics.vector import dynamicsymbols
from sympy.physics.vector.printing import vlatex, vpprint

from .system import HybridSystem, Mode


def _time_functions(system: HybridSystem) -> tuple[sp.Symbol, dict]:
    """``t`` and the substitution of state symbols by functions of time."""
    t = dynamicsymbols._t
    sub = {system.t: t}
    for q, u in zip(system.q, system.u):
        f = dynamicsymbols(q.name)
        sub[q] = f
        sub[u] = f.diff(t)
    for s in system.s:
        sub[s] = dynamicsymbols(s.name)
    return t, sub


def _ordered_add(terms: list) -> sp.Expr:
    """An unevaluated sum keeping the order of ``terms`` (print with ``order='none'``)."""
    terms = [x for x in terms if x != 0]
    if not terms:
        return sp.Integer(0)
    return terms[0] if len(terms) == 1 else sp.Add(*terms, evaluate=False)


def _mode(system: HybridSystem, mode_name: str) -> Mode:
    return system.mode(mode_name)  # KeyError naming the valid modes


def equations(system: HybridSystem, mode_name: str) -> list[sp.Eq]:
    """Equations of motion of the coordinates in one mode, ``M q'' + ... = RHS``.

    Parameters
    ----------
    system : HybridSystem
    mode_name : str
        A name from ``[m.name for m in system.modes]``.

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
    _mode(system, mode_name)
    t, sub = _time_functions(system)
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
        inertia = system.mass_matrix[i, i] * dynamicsymbols(q.name).diff(t, 2)
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


def definitions(system: HybridSystem, mode_name: str) -> list[sp.Eq]:
    """What the contact symbols are in one mode, and the law states' rates.

    Parameters
    ----------
    system : HybridSystem
    mode_name : str

    Returns
    -------
    list of sympy.Eq
        ``N_c = ...`` and ``f_c = ...`` for every contact (zero when open; in a
        stick mode ``f_c`` is the derived constraint force), then ``z' = ...`` for
        every internal state of the friction laws.
    """
    mode = _mode(system, mode_name)
    t, sub = _time_functions(system)
    out = []
    for N, f, Nv, fv in zip(system.normal_symbols, system.friction_symbols,
                            mode.normal_forces, mode.friction_forces):
        out.append(sp.Eq(N, sp.sympify(Nv).xreplace(sub), evaluate=False))
        out.append(sp.Eq(f, _over_common_denominator(sp.sympify(fv), sub), evaluate=False))
    for s, rate in zip(system.s, mode.state_rates):
        out.append(sp.Eq(dynamicsymbols(s.name).diff(t), sp.sympify(rate).xreplace(sub), evaluate=False))
    return out


def _modes(system: HybridSystem, mode: Optional[str]) -> list[str]:
    if mode is None:
        return [m.name for m in system.modes]
    return [_mode(system, mode).name]


def _heading(system: HybridSystem, name: str) -> str:
    model = getattr(system.model, "name", "model")
    return f"{model}: mode {name}"


def pretty(system: HybridSystem, mode: Optional[str] = None, *, unicode: bool = True) -> str:
    """Pretty-printed equations of every mode (or of ``mode``), one headed block each.

    Parameters
    ----------
    system : HybridSystem
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
        lines += [vpprint(eq, **settings) for eq in equations(system, name)]
        defs = definitions(system, name)
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


def latex(system: HybridSystem, mode: Optional[str] = None) -> str:
    """LaTeX of every mode (or of ``mode``): a headed ``align*`` block per mode.

    Needs ``amsmath``. Contact definitions follow the equations after an
    ``\\intertext{where}``.

    Parameters
    ----------
    system : HybridSystem
    mode : str, optional

    Returns
    -------
    str
    """
    blocks = []
    for name in _modes(system, mode):
        rows = [_tex_eq(eq) for eq in equations(system, name)]
        defs = definitions(system, name)
        body = " \\\\\n".join(rows)
        if defs:
            body += " \\\\\n\\intertext{where}\n" + " \\\\\n".join(_tex_eq(eq) for eq in defs)
        blocks.append(f"\\paragraph{{Mode \\texttt{{{_tex_text(name)}}}}}\n"
                      f"\\begin{{align*}}\n{body}\n\\end{{align*}}")
    return "\n\n".join(blocks) + "\n"
