"""Generated state Jacobians per mode, for the RK4 stability check.

The flows of the built-in laws are affine in the state in every mode, so the
Jacobian is a constant matrix of the parameters; it is taken at the rest state
``y = 0, t = 0``. This code runs once per simulation, never in the step loop.
"""

from __future__ import annotations

import sympy as sp
from sympy.printing.pycode import PythonCodePrinter

from ..symbolic.system import HybridSystem


def jacobians(system: HybridSystem) -> str:
    """Source of ``jacobian(mode, p) -> ndarray`` (raw parameter vector ``p``) and of ``JACOBIAN_PARAMS``.

    ``JACOBIAN_PARAMS`` holds the indices of the raw parameters that some mode's
    Jacobian depends on: a change of the others (the forcing's amplitude and
    frequency, a gap) leaves every mode's eigenvalues as they were, so the
    stability check can reuse them (:meth:`~blademodel.numeric.integrator.Integrator.with_parameters`).
    """
    state = system.state
    at_rest = {s: 0 for s in state}
    at_rest[system.t] = 0
    names = {p: f"p[{i}]" for i, p in enumerate(system.params)}

    class Printer(PythonCodePrinter):
        def _print_Symbol(self, expr):
            return names.get(expr, expr.name)

    pr = Printer({"fully_qualified_modules": True})
    n = len(state)
    used: set = set()
    lines = ["def jacobian(mode, p):", f"    J = np.zeros(({n}, {n}))"]
    for m, mode in enumerate(system.modes):
        lines.append(f"    {'if' if m == 0 else 'elif'} mode == {m}:")
        flow = [*system.u, *mode.accelerations, *mode.state_rates]
        body = []
        for i, f in enumerate(flow):
            for j, s in enumerate(state):
                d = sp.diff(f, s)
                if d != 0:
                    d = d.subs(at_rest)
                    used |= d.free_symbols
                    body.append(f"        J[{i}, {j}] = {pr.doprint(d)}")
        lines += body or ["        pass"]
    lines.append("    return J")
    lines.append("")
    lines.append(f"JACOBIAN_PARAMS = {tuple(i for i, p in enumerate(system.params) if p in used)!r}")
    return "\n".join(lines) + "\n"
