"""Generate the derivatives that a tangent (sensitivity) integration needs, per mode.

For every mode of a :class:`~blademodel.symbolic.system.HybridSystem` SymPy
differentiates, once per model structure:

* the flow ``f(t, y, p)``: ``df/dy`` and ``df/dp`` (``flow_jacobian``), and whether
  ``df/dy`` is constant in the mode (``FLOW_AFFINE``: the flow is affine in the state,
  as every built-in law's is), with ``df/dp`` along a direction and ``df/dt``
  (``flow_partials``) for such modes;
* every guard ``g(t, y, p)``: ``dg/dy``, ``dg/dp`` and ``dg/dt`` (``guard_gradient``);
* every transition's reset ``y+ = R(t, y-, p)``: ``dR/dy`` and ``dR/dp``
  (``reset_jacobian``), chosen by the mode the transition went to.

``p`` here means the model's *raw* parameters (the first slots of the parameter
array), not the hoisted constants of :mod:`.codegen`, so a parameter derivative is
one column. Only the physical states (coordinates, velocities, friction-law states)
are differentiated; energy accumulators never feed back into them.

The source is plain Python over ``math`` and NumPy, like the kernel's, and is
compiled with it into a separate module only when sensitivities are asked for
(:mod:`.tangent`): a simulation never pays for it.
"""

from __future__ import annotations

import sympy as sp

from ..symbolic.system import HybridSystem
from .codegen import _block, _Printer


class SensitivityUnavailable(NotImplementedError):
    """The model has a transition whose reset cannot be told from its target mode."""


def _fill(exprs_by_target: list[tuple[str, sp.Expr]], printer, indent: int, tag: str) -> list[str]:
    """Source lines assigning the non-zero expressions to their targets (zero entries left as they are)."""
    nz = [(tgt, e) for tgt, e in exprs_by_target if e != 0]
    if not nz:
        return [" " * indent + "pass"]
    return _block([e for _, e in nz], [tgt for tgt, _ in nz], printer, indent, tag)


def sensitivity_source(system: HybridSystem) -> str:
    """Source of ``flow_jacobian``, ``guard_gradient`` and ``reset_jacobian`` for ``system``.

    Signatures (arrays are filled in place; the caller zeroes ``Jy``, ``Jp``, ``Jt``,
    ``gy``, ``gp``, ``Rp``, ``Rt`` and sets ``Ry`` to the identity first):

    * ``flow_jacobian(mode, t, y, p, Jy, Jp, Jt)``: ``Jy`` is ``n`` by ``n``, ``Jp``
      ``n`` by the number of raw parameters, ``Jt`` the explicit time derivative;
    * ``flow_partials(mode, t, y, p, dp, fp, ft)``: ``fp = (df/dp) dp`` and ``ft = df/dt``
      (every entry written);
    * ``FLOW_AFFINE[mode]``: 1 if ``df/dy`` depends on neither the state nor the time;
    * ``guard_gradient(mode, gi, t, y, p, gy, gp) -> dg/dt``;
    * ``reset_jacobian(mode, gi, target, t, y, p, Ry, Rp, Rt) -> bool``: whether
      guard ``gi`` of ``mode`` has a transition to ``target``.

    Raises
    ------
    SensitivityUnavailable
        If a guard has two transitions to the same mode with different resets (the
        target would not say which reset was applied).
    """
    t = system.t
    state = system.state
    n = len(state)
    params = system.params
    names = {s: f"y[{i}]" for i, s in enumerate(state)}
    names[t] = "t"
    names.update({q: f"p[{i}]" for i, q in enumerate(params)})
    pr = _Printer(names)

    L = ["def flow_jacobian(mode, t, y, p, Jy, Jp, Jt):",
         '    """``df/dy``, ``df/dp`` (raw parameters) and ``df/dt`` of ``mode``\'s flow (generated)."""']
    for m, mode in enumerate(system.modes):
        flow = [*system.u, *mode.accelerations, *mode.state_rates]
        L.append(f"    {'if' if m == 0 else 'elif'} mode == {m}:")
        entries = [(f"Jy[{i}, {j}]", sp.diff(f, s)) for i, f in enumerate(flow) for j, s in enumerate(state)]
        entries += [(f"Jp[{i}, {j}]", sp.diff(f, q)) for i, f in enumerate(flow) for j, q in enumerate(params)]
        entries += [(f"Jt[{i}]", sp.diff(f, t)) for i, f in enumerate(flow)]
        L += _fill(entries, pr, 8, "x")
    L.append("")

    dps = sp.symbols(f"_dp0:{len(params)}")
    pr_d = _Printer({**names, **{d: f"dp[{j}]" for j, d in enumerate(dps)}})
    L.append("def flow_partials(mode, t, y, p, dp, fp, ft):")
    L.append('    """``fp = (df/dp) dp`` (``dp`` a direction in the raw parameters) and ``ft = df/dt`` of ``mode`` (generated)."""')
    affine = []
    for m, mode in enumerate(system.modes):
        flow = [*system.u, *mode.accelerations, *mode.state_rates]
        L.append(f"    {'if' if m == 0 else 'elif'} mode == {m}:")
        exprs = [sum((sp.diff(f, q) * d for q, d in zip(params, dps)), sp.Integer(0)) for f in flow]
        exprs += [sp.diff(f, t) for f in flow]
        L += _block(exprs, [f"fp[{i}]" for i in range(n)] + [f"ft[{i}]" for i in range(n)], pr_d, 8, "x")
        varying = set(state) | {t}
        affine.append(int(all(not (sp.diff(f, s_).free_symbols & varying) for f in flow for s_ in state)))
    L.append("")
    L.append(f"FLOW_AFFINE = np.array({affine!r}, dtype=np.int64)")
    L.append("")

    L.append("def guard_gradient(mode, gi, t, y, p, gy, gp):")
    L.append('    """``dg/dy`` and ``dg/dp`` of guard ``gi`` of ``mode`` into ``gy``, ``gp``; returns ``dg/dt`` (generated)."""')
    def gradient(expr, indent):
        entries = [(f"gy[{j}]", sp.diff(expr, s)) for j, s in enumerate(state)]
        entries += [(f"gp[{j}]", sp.diff(expr, q)) for j, q in enumerate(params)]
        entries.append(("gt", sp.diff(expr, t)))
        pad = " " * indent
        return [f"{pad}gt = 0.0", *_fill(entries, pr, indent, "x"), f"{pad}return gt"]

    first = True
    for m, mode in enumerate(system.modes):
        for gi, g in enumerate(mode.guards):
            L.append(f"    {'if' if first else 'elif'} mode == {m} and gi == {gi}:")
            first = False
            if isinstance(g.expr, (sp.Min, sp.Max)):
                # a guard that is the least (greatest) of several, e.g. the first of an Iwan
                # law's elements to slip: the gradient of the argument that is active here
                # (SymPy's own derivative of Min weighs tied arguments by Heaviside(0) = 1/2)
                args = list(g.expr.args)
                L += _block(args, [f"a_{k}" for k in range(len(args))], pr, 8, "v")
                L.append("        j = 0")
                L.append("        best = a_0")
                cmp = "<" if isinstance(g.expr, sp.Min) else ">"
                for k in range(1, len(args)):
                    L.append(f"        if a_{k} {cmp} best:")
                    L.append(f"            j = {k}")
                    L.append(f"            best = a_{k}")
                for k, a in enumerate(args):
                    L.append(f"        {'if' if k == 0 else 'elif'} j == {k}:")
                    L += gradient(a, 12)
            else:
                L += gradient(g.expr, 8)
    L.append("    return 0.0")
    L.append("")

    L.append("def reset_jacobian(mode, gi, target, t, y, p, Ry, Rp, Rt):")
    L.append('    """``dR/dy``, ``dR/dp``, ``dR/dt`` of the transition of guard ``gi`` of ``mode`` to ``target`` (generated)."""')
    first = True
    for m, mode in enumerate(system.modes):
        for gi, g in enumerate(mode.guards):
            by_target: dict[int, dict] = {}
            for c in g.candidates:
                if c.target in by_target and by_target[c.target] != c.reset:
                    raise SensitivityUnavailable(
                        f"guard {g.name!r} of mode {mode.name!r} has two transitions to mode "
                        f"{system.modes[c.target].name!r} with different resets")
                by_target.setdefault(c.target, c.reset)
            for target, reset in by_target.items():
                L.append(f"    {'if' if first else 'elif'} mode == {m} and gi == {gi} and target == {target}:")
                first = False
                entries = []
                for s, e in reset.items():
                    i = state.index(s)
                    entries += [(f"Ry[{i}, {j}]", sp.diff(e, v)) for j, v in enumerate(state)]
                    entries += [(f"Rp[{i}, {j}]", sp.diff(e, q)) for j, q in enumerate(params)]
                    entries.append((f"Rt[{i}]", sp.diff(e, t)))
                # a reset row replaces the identity's row: zero it first
                L += [f"        Ry[{state.index(s)}, {state.index(s)}] = 0.0" for s in reset]
                L += _fill(entries, pr, 8, "r")
                L.append("        return True")
    L.append("    return False")
    L.append("")
    L.append(f"N_PHYSICAL = {n}")
    L.append(f"N_RAW_PARAMS = {len(params)}")
    return "\n".join(L) + "\n"
