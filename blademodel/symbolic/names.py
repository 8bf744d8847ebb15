"""Display names of symbols: subscripts read from the parameter names.

A parameter keeps its name in the generated code (``cx``, ``kd_c12``); only the
printed equations show it as a symbol with subscripts::

    cx -> c_x        kd -> k_d        F0 -> F_0        kx1 -> k_x1
    mu -> mu         Delta_c3 -> Delta_c3     kx_2 -> k_x,2     F0_m -> F_0,m

The display name is a SymPy symbol name, so SymPy's printers give ``c_{x}``,
``\\Delta_{c3}`` and ``k_{x,2}`` in LaTeX and ``cₓ`` in Unicode. The rule: the
part before the first underscore is the *head*; trailing digits of the head are
a subscript; a head of two letters that is not a Greek letter (``mu``, ``nu``,
``pi``, ``xi``) is a letter with a one-letter subscript; every part after an
underscore is a further subscript, all joined by commas. Greek names, longer
words and SymPy's modifiers (``Ndot``, ``Qbar``) stay as SymPy prints them.
"""

from __future__ import annotations

import re

import sympy as sp
from sympy.core.function import AppliedUndef
from sympy.printing.latex import greek_letters_set, modifier_dict

_HEAD = re.compile(r"([A-Za-z]+)([0-9]*)")


def _keeps_letters(head: str) -> bool:
    """A head SymPy already prints as one symbol: a Greek letter or a modified one (``Ndot``)."""
    low = head.lower()
    return low in greek_letters_set or low == "lamda" or any(
        head.endswith(m) and len(head) > len(m) for m in modifier_dict)


def display_name(name: str) -> str:
    """The display name of the symbol ``name`` (``"cx"`` -> ``"c_x"``); see the module docstring.

    Parameters
    ----------
    name : str
        A symbol name (a Python identifier).

    Returns
    -------
    str
        ``name`` itself when it has no subscript to show or does not fit the rule.
    """
    head, *rest = name.split("_")
    match = _HEAD.fullmatch(head)
    if match is None:
        return name
    letters, digits = match.groups()
    subs = []
    if len(letters) == 2 and not _keeps_letters(letters):
        letters, subs = letters[0], [letters[1] + digits]
    elif digits:
        subs = [digits]
    subs += [part for part in rest if part]
    return letters + ("_" + ",".join(subs) if subs else "")


def readable_symbols(expressions) -> dict:
    """The substitution that shows every symbol and function of time of ``expressions`` by its display name.

    Two names that would show alike (``kx2`` and ``k_x2``) both keep their own
    names, so the display never merges distinct symbols.

    Parameters
    ----------
    expressions : iterable of sympy.Basic

    Returns
    -------
    dict
        ``{Symbol: Symbol}`` (same assumptions) and ``{f(t): g(t)}`` for the
        undefined functions (the coordinates as functions of time); only names
        that change.
    """
    atoms = set()
    for expr in expressions:
        expr = sp.sympify(expr)
        atoms |= expr.atoms(sp.Symbol) | expr.atoms(AppliedUndef)
    name = {a: (a.name if isinstance(a, sp.Symbol) else a.func.__name__) for a in atoms}
    shown = {a: display_name(n) for a, n in name.items()}
    count: dict = {}
    for a in atoms:
        count[shown[a]] = count.get(shown[a], set()) | {name[a]}
    out = {}
    for a in atoms:
        if shown[a] == name[a] or len(count[shown[a]]) > 1:
            continue
        out[a] = (sp.Symbol(shown[a], **a.assumptions0) if isinstance(a, sp.Symbol)
                  else sp.Function(shown[a])(*a.args))
    return out
