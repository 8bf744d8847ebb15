"""The paper's Eq. 11 as printed, and how it differs from the derived non-dimensional equations.

Zheng et al. (2022) print their non-dimensional equations without the frequency
ratios that ``tau = omega t`` brings in; :mod:`blademodel.symbolic.scaling`
derives the correct form, and this module sets the printed one beside it.
"""

from __future__ import annotations

import sympy as sp

from ..model import Model
from ..symbolic.scaling import TAU, ScaledSystem, scaled_equations
from ..symbolic.system import HybridSystem

__all__ = ["eq11_discrepancy", "paper_eq11"]


def paper_eq11() -> list[sp.Eq]:
    """The paper's Eq. 11 exactly as printed (Zheng et al. 2022).

    ::

        X1'' + 2 eps1 X1' + X1 = Qbar_1x - Nbar_x sin(alpha) - fbar_x cos(alpha)
        Y1'' + 2 eps2 Y1' + Y1 = Qbar_1y + Nbar_y cos(alpha) - fbar_y sin(alpha)
        X2'' + 2 eps1 X2' + X2 = Qbar_2x + Nbar_x sin(alpha) + fbar_x cos(alpha)
        Y2'' + 2 eps2 Y2' + Y2 = Qbar_2y - Nbar_y cos(alpha) + fbar_y sin(alpha)

    with ``(.)' = d/dtau``, ``tau = omega t``. The symbols are those of
    ``ScaledSystem.generic`` for the symmetric blade pair, so the two can be
    subtracted (:func:`eq11_discrepancy`). The printed form omits the factors
    ``(omega/omega_x)^2`` and ``omega/omega_x`` that ``tau = omega t`` introduces.

    Returns
    -------
    list of sympy.Eq
        The equations of ``x1, y1, x2, y2``.
    """
    S = lambda n: sp.Symbol(n, real=True)
    alpha, e1, e2 = S("alpha"), S("epsilon1"), S("epsilon2")
    Nx, Ny, fx, fy = S("Nbar_x"), S("Nbar_y"), S("fbar_x"), S("fbar_y")
    out = []
    for name, eps, sign in (("X1", e1, -1), ("Y1", e2, -1), ("X2", e1, 1), ("Y2", e2, 1)):
        F = sp.Function(name, real=True)(TAU)
        lhs = F.diff(TAU, 2) + 2 * eps * F.diff(TAU) + F
        Q = S(f"Qbar_{name[1]}{name[0].lower()}")
        if name[0] == "X":
            rhs = Q + sign * (Nx * sp.sin(alpha) + fx * sp.cos(alpha))
        else:
            rhs = Q + sign * (-Ny * sp.cos(alpha) + fy * sp.sin(alpha))
        out.append(sp.Eq(lhs, rhs))
    return out


def eq11_discrepancy(system: Model | HybridSystem | ScaledSystem) -> list[sp.Expr]:
    """Derived minus printed Eq. 11, equation by equation.

    Parameters
    ----------
    system : Model, HybridSystem or ScaledSystem
        The symmetric blade pair (coordinates ``x1, y1, x2, y2`` with shared
        ``omega_x``, ``omega_y``), e.g. ``BladePair().build()``.

    Returns
    -------
    list of sympy.Expr
        ``(lhs - rhs)_derived - (lhs - rhs)_printed`` for ``x1, y1, x2, y2``; for
        ``x1`` it is ``((omega/omega_x)^2 - 1) X1'' + 2 eps1 (omega/omega_x - 1) X1'``.
        It vanishes for the x-equations only at ``omega = omega_x`` and for the
        y-equations only at ``omega = omega_y``.

    Raises
    ------
    ValueError
        If ``system`` is not the symmetric four-coordinate blade pair.
    """
    sc = system if isinstance(system, ScaledSystem) else scaled_equations(system)
    if sc.coordinates != ["x1", "y1", "x2", "y2"] or \
            {s.name for s in sc.omegas.values()} != {"omega_x", "omega_y"}:
        raise ValueError("Eq. 11 is printed for the symmetric blade pair (x1, y1, x2, y2 with "
                         f"shared omega_x, omega_y); got coordinates {sc.coordinates} and "
                         f"{sorted(s.name for s in sc.omegas.values())}")
    printed = paper_eq11()
    return [sp.expand((d.lhs - d.rhs) - (p.lhs - p.rhs)) for d, p in zip(sc.generic, printed)]
