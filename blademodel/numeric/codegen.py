"""Generate the Python source of a model's flows, guards and transitions.

The source is plain Python over ``math`` and NumPy arrays, written so that Numba
compiles it (and so that it runs as is with ``NUMBA_DISABLE_JIT=1``). Two
optimisations keep SymPy's output fast:

* every maximal sub-expression that depends on parameters only (``sin(alpha)``,
  ``kx/m``) is *hoisted*: computed once per run by ``derived()`` into extra slots
  of the parameter array, never inside the step loop;
* common sub-expressions are shared within each mode's block (``sympy.cse``);
* the RK4 step is *fused*: :func:`fused_rk4_source` writes ``rk4_step`` with each
  mode's flow inlined four times and the stages held in scalar locals (no work
  arrays, no calls but ``math``). It replaces the template's
  :func:`blademodel.numeric.loop.rk4_step` with the same operations in the same
  order (bit-identical results) at about two thirds of the cost: Numba neither
  inlines ``rhs`` into the generic step nor removes the reference counting of its
  eleven array arguments (``docs/benchmarks``, ``benchmarks/per_step.py``).
"""

from __future__ import annotations

import inspect

import sympy as sp
from sympy.printing.pycode import PythonCodePrinter

from ..symbolic.system import HybridSystem
from . import bracket, loop


class _Printer(PythonCodePrinter):
    """Python printer that writes state and parameter symbols as array slots."""

    def __init__(self, names: dict):
        super().__init__({"fully_qualified_modules": True, "standard": "python3"})
        self._names = names

    def _print_Symbol(self, expr):
        return self._names.get(expr, expr.name)

    def _print_BooleanTrue(self, expr):
        return "True"

    def _print_BooleanFalse(self, expr):
        return "False"


class _Hoister:
    """Replace parameter-only sub-expressions by constant slots ``c_k``."""

    def __init__(self, params):
        self.params = set(params)
        self.constants: dict[sp.Expr, sp.Symbol] = {}

    def _const(self, expr):
        if expr not in self.constants:
            self.constants[expr] = sp.Symbol(f"c_{len(self.constants)}", real=True)
        return self.constants[expr]

    def _param_only(self, expr):
        fs = expr.free_symbols
        return bool(fs) and fs <= self.params

    def __call__(self, expr):
        expr = sp.sympify(expr)
        if expr.is_Atom:
            return expr
        if self._param_only(expr):
            return self._const(expr)
        if isinstance(expr, (sp.Add, sp.Mul)):
            fixed = [a for a in expr.args if self._param_only(a)]
            rest = [self(a) for a in expr.args if not self._param_only(a)]
            if len(fixed) > 1 or (fixed and not fixed[0].is_Atom):
                fixed = [self._const(expr.func(*fixed))]
            return expr.func(*fixed, *rest)
        return expr.func(*[self(a) for a in expr.args])


def _cse(exprs, tag):
    """``sympy.cse`` of ``exprs`` with sub-expressions named ``{tag}_k``."""
    return sp.cse(list(exprs), symbols=sp.numbered_symbols(f"{tag}_"), optimizations="basic")


def _print_cse(cse, targets, printer, indent, number_as_float=False):
    """Source lines of a ``_cse`` result assigning the reduced expressions to ``targets``."""
    reps, reduced = cse
    pad = " " * indent

    def show(e):
        if number_as_float and e.is_Number:
            return repr(float(e))  # scalar locals stay float64 in every mode
        return printer.doprint(e)

    lines = [f"{pad}{s} = {printer.doprint(e)}" for s, e in reps]
    lines += [f"{pad}{tgt} = {show(e)}" for tgt, e in zip(targets, reduced)]
    return lines


def _block(exprs, targets, printer, indent, tag):
    """Source lines assigning ``exprs`` to ``targets`` with shared sub-expressions."""
    return _print_cse(_cse(exprs, tag), targets, printer, indent)


def fused_rk4_source(flow_cses, state, t, params: dict) -> list[str]:
    """Source lines of ``rk4_step`` with every mode's flow inlined, stages in scalars.

    The arithmetic is that of :func:`blademodel.numeric.loop.rk4_step` calling the
    generated ``rhs``: the same printed expressions, the same stage sums in the same
    order, so the result is bit-identical. The state enters as ``y_i``, the stage
    states are ``s_i``, the slopes ``k1_i ... k4_i``; only ``y`` and ``out`` are
    arrays (the work-array arguments are kept for the template's signature).

    Parameters
    ----------
    flow_cses : list
        ``_cse`` of each mode's (hoisted) flow, in mode order.
    state : list of Symbol
    t : Symbol
    params : dict
        Symbol to printed name for parameters and hoisted constants.
    """
    n = len(state)

    def printer(arg, time):
        names = {s: f"{arg}_{i}" for i, s in enumerate(state)}
        names[t] = time
        return _Printer({**names, **params})

    pad = " " * 8
    L = ["def rk4_step(mode, t, y, h, p, k1, k2, k3, k4, tmp, out):",
         '    """One RK4 step (fused, generated): see ``blademodel.numeric.loop.rk4_step``."""']
    for m, cse in enumerate(flow_cses):
        L.append(f"    {'if' if m == 0 else 'elif'} mode == {m}:")
        L += [f"{pad}y_{i} = y[{i}]" for i in range(n)]
        L += _print_cse(cse, [f"k1_{i}" for i in range(n)], printer("y", "t"), 8, True)
        L.append(f"{pad}t_half = t + 0.5 * h")
        L += [f"{pad}s_{i} = y_{i} + 0.5 * h * k1_{i}" for i in range(n)]
        L += _print_cse(cse, [f"k2_{i}" for i in range(n)], printer("s", "t_half"), 8, True)
        L += [f"{pad}s_{i} = y_{i} + 0.5 * h * k2_{i}" for i in range(n)]
        L += _print_cse(cse, [f"k3_{i}" for i in range(n)], printer("s", "t_half"), 8, True)
        L += [f"{pad}s_{i} = y_{i} + h * k3_{i}" for i in range(n)]
        L.append(f"{pad}t_end = t + h")
        L += _print_cse(cse, [f"k4_{i}" for i in range(n)], printer("s", "t_end"), 8, True)
        L += [f"{pad}out[{i}] = y_{i} + h / 6.0 * (k1_{i} + 2.0 * k2_{i} + 2.0 * k3_{i} + k4_{i})"
              for i in range(n)]
    return L


def generate(system: HybridSystem, *, energy: bool = False) -> tuple[str, dict]:
    """Source of the generated module for ``system`` and its metadata.

    Parameters
    ----------
    system : HybridSystem
    energy : bool
        Also integrate the input work, the viscous and the friction dissipation as
        three extra states (``W_in``, ``D_visc``, ``D_fric``) for energy balances.

    Returns
    -------
    source : str
    meta : dict
        State, parameter, mode and guard names, and table sizes.
    """
    t = system.t
    state = system.state
    n_state = len(state) + (3 if energy else 0)
    hoist = _Hoister(system.params)
    pnames = {p: f"p[{i}]" for i, p in enumerate(system.params)}
    n_p = len(system.params)

    def names(arr):
        d = {s: f"{arr}[{i}]" for i, s in enumerate(state)}
        d[t] = "t"
        return d

    # Hoist everything first so that the constant slots are known.
    flows, guards, transitions = [], [], []
    for mode in system.modes:
        f = [*system.u, *mode.accelerations, *mode.state_rates]
        if energy:
            m = system.modes.index(mode)
            # a contact's normal damping counts as viscous (its power is 0 without one: same code)
            f += [system.energy["input_power"], system.energy["viscous_power"] + system.energy["contact_power"][m],
                  system.energy["friction_power"][m]]
        flows.append([hoist(e) for e in f])
        guards.append([hoist(g.expr) for g in mode.guards])
        transitions.append([[(c.target, hoist(c.condition), {s: hoist(e) for s, e in c.reset.items()})
                             for c in g.candidates] for g in mode.guards])

    const_names = {c: f"p[{n_p + i}]" for i, c in enumerate(hoist.constants.values())}
    pr_y = _Printer({**names("y"), **pnames, **const_names})
    pr_tmp = _Printer({**names("ytmp"), **pnames, **const_names})
    pr_p = _Printer(pnames)

    L = ["# Generated by blademodel.numeric.codegen: do not edit.", ""]
    L.append("def derived(p):")
    L.append(f"    out = np.empty({n_p + len(hoist.constants)})")
    L.append(f"    out[:{n_p}] = p")
    for i, expr in enumerate(hoist.constants):
        L.append(f"    out[{n_p + i}] = {pr_p.doprint(expr)}")
    L.append("    return out")
    L.append("")

    flow_cses = [_cse(f, "x") for f in flows]
    L.append("def rhs(mode, t, y, p, out):")
    for m, f in enumerate(flows):
        L.append(f"    {'if' if m == 0 else 'elif'} mode == {m}:")
        L += _print_cse(flow_cses[m], [f"out[{i}]" for i in range(len(f))], pr_y, 8)
    L.append("")

    L.append("def guards(mode, t, y, p, out):")
    for m, g in enumerate(guards):
        L.append(f"    {'if' if m == 0 else 'elif'} mode == {m}:")
        L += _block(g, [f"out[{i}]" for i in range(len(g))], pr_y, 8, "x") if g else ["        pass"]
    L.append("")

    # Rates of the guards that the state alone gives: a guard of the coordinates (and time) only,
    # the penetration, has the rate sum dg/dq u + dg/dt; one of velocities or law states would need
    # the accelerations (a right-hand side) and is left NaN.
    later = set(state[len(system.q):])
    L.append("def guard_rates(mode, t, y, p, out):")
    for m, g in enumerate(guards):
        L.append(f"    {'if' if m == 0 else 'elif'} mode == {m}:")
        L += [f"        out[{i}] = math.nan" for i in range(len(g))] or ["        pass"]
        known = [(i, sum((sp.diff(e, q) * u for q, u in zip(system.q, system.u)), sp.diff(e, t)))
                 for i, e in enumerate(g) if not (e.free_symbols & later)]
        if known:
            L += _block([r for _, r in known], [f"out[{i}]" for i, _ in known], pr_y, 8, "d")
    L.append("")

    L.append("def transition(mode, gi, t, y, p, ytmp):")
    L.append("    n = y.shape[0]")
    first = True
    for m, per_guard in enumerate(transitions):
        for gi, cands in enumerate(per_guard):
            L.append(f"    {'if' if first else 'elif'} mode == {m} and gi == {gi}:")
            first = False
            for ci, (target, cond, reset) in enumerate(cands):
                L.append("        for i in range(n):")
                L.append("            ytmp[i] = y[i]")
                if reset:
                    keys = list(reset)
                    L += _block([reset[k] for k in keys], [f"ytmp[{state.index(k)}]" for k in keys],
                                pr_y, 8, "r")
                last = ci == len(cands) - 1
                test = "True" if last else pr_tmp.doprint(cond)
                L.append(f"        if {test}:")
                L.append("            for i in range(n):")
                L.append("                y[i] = ytmp[i]")
                L.append(f"            return {target}")
    L.append("    return mode")
    L.append("")

    # Tables for the loop.
    n_modes = len(system.modes)
    max_g = max([len(g) for g in guards] + [1])
    dirs = [[g.direction for g in m.guards] + [0] * (max_g - len(m.guards)) for m in system.modes]
    n_contacts = len(system.model.contacts)
    close = []
    for m in system.modes:
        row = [-1] * max(n_contacts, 1)
        for gi, g in enumerate(m.guards):
            if g.kind == "close":
                row[g.contact] = gi
        close.append(row)
    L.append(f"N_GUARDS = np.array({[len(g) for g in guards]}, dtype=np.int64)")
    L.append(f"GUARD_DIR = np.array({dirs}, dtype=np.int64).reshape({n_modes}, {max_g})")
    L.append(f"CLOSE_GUARD = np.array({close}, dtype=np.int64).reshape({n_modes}, {max(n_contacts, 1)})")
    owner = [[g.contact for g in m.guards] + [-1] * (max_g - len(m.guards)) for m in system.modes]
    L.append(f"GUARD_CONTACT = np.array({owner}, dtype=np.int64).reshape({n_modes}, {max_g})")
    # the friction guards of elastic laws (no rigid stick), which a transition may leave a rounding error on their
    # wrong side and loop.drift_offsets reads from their boundary; a rigid stick's guards keep their values
    rigid = {j for m in system.modes for j in m.constrained}
    drift = [[int(g.kind == "law" and g.contact not in rigid) for g in m.guards] + [0] * (max_g - len(m.guards))
             for m in system.modes]
    L.append(f"DRIFT_GUARD = np.array({drift}, dtype=np.int64).reshape({n_modes}, {max_g})")
    L.append(f"OPEN_MODE = {system.open_mode}")
    L.append("")

    L.append("# ---- event bracketing (blademodel/numeric/bracket.py) ----")
    L.append(inspect.getsource(bracket))
    L.append("# ---- generic loop (blademodel/numeric/loop.py) ----")
    L.append(inspect.getsource(loop))
    L.append("")
    L.append("# ---- the template's rk4_step, fused for this model (codegen.fused_rk4_source) ----")
    full_state = list(state) + [sp.Symbol(f"_energy_{i}") for i in range(n_state - len(state))]
    L += fused_rk4_source(flow_cses, full_state, t, {**pnames, **const_names})
    L.append("")
    for fn in ("rhs", "guards", "guard_rates", "transition", "rk4_step", "stage_sum", "rk_step", "crossed",
               "first_crossing", "inverse_quadratic", "safeguarded_trial", "hermite", "hermite_root",
               "predicted_root", "earliest_predicted", "copy_guards", "wrong_side", "drift_offsets",
               "offset_guards",
               "locate_event", "simultaneous_crossing", "initial_mode",
               "integrate"):
        # integrate releases the GIL: difference quotients of a period map run in threads
        L.append(f"{fn} = njit(cache=True{', nogil=True' if fn == 'integrate' else ''})({fn})")

    header = ["import math", "import numpy as np", "from numba import njit", ""]
    meta = {
        "state": [s.name for s in state] + (["W_in", "D_visc", "D_fric"] if energy else []),
        "n_state": n_state,
        "params": [p.name for p in system.params],
        "n_derived": n_p + len(hoist.constants),
        "modes": [m.name for m in system.modes],
        "guards": [[g.name for g in m.guards] for m in system.modes],
        "coordinates": [q.name for q in system.q],
        "energy": energy,
    }
    return "\n".join(header + L) + "\n", meta
