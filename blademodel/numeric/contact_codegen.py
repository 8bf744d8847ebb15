"""Generate the per-contact kernel's module for a set of friction-law kinds.

The module holds, in this order: each law kind's functions
(:func:`~blademodel.numeric.law_codegen.law_code`), dispatchers on the kind
number ``K``, the tables describing the kinds (modes, guards, directions, rigid
stick, states), and the kernel's templates (``TEMPLATES``, described in
:mod:`.contact_loop`). Its size depends on the law kinds only, never on the number
of contacts or blades.
"""

from __future__ import annotations

import ast
import inspect

from ..components.friction.base import FrictionLaw
from . import (bracket, code_libraries, contact_clusters, contact_events, contact_flow, contact_guards, contact_locate,
               contact_loop, contact_replay, contact_rigid_stubs, contact_stick)
from .compiled import hash_sources
from .law_codegen import law_code
from .view_rewrite import direct_views

#: The kernel's templates, in the order they are pasted (:mod:`.contact_loop` describes them);
#: ``contact_rigid_stubs`` follows when no law kind has a rigid stick mode.
TEMPLATES = (bracket, contact_flow, contact_stick, contact_guards, contact_locate, contact_events, contact_clusters,
             contact_loop, contact_replay)

#: Functions compiled with Numba (``njit(cache=True)``).
#: Functions called from Python: cached on disk with all they call compiled into them.
#: The others are not cached on their own: a function loaded from the cache is a
#: separate library that callers cannot inline, and each call to one cost ~0.4 us.
_ENTRY_POINTS = ("integrate", "initial_modes", "settle_start", "rhs", "factor_stick", "forces", "law_energy",
                 "guards_at", "transition_at", "substep_derivatives", "guard_derivatives", "cluster_step")

#: Entry points that release the GIL while they run: a period map's difference quotients run
#: in threads (:meth:`~blademodel.orbits.period_map.PeriodMap.differences`), each with its own
#: work arrays (:meth:`~blademodel.numeric.contact_kernel.ContactIntegrator.worker`).
_NOGIL = ("integrate",)

#: Entry points never called from compiled code: what they link becomes internal to them
#: (:class:`~blademodel.numeric.code_libraries.EntryPointCompiler`).
_TOP_LEVEL = ("integrate", "initial_modes", "settle_start", "rhs", "forces", "law_energy", "guards_at",
              "transition_at", "substep_derivatives", "guard_derivatives", "cluster_step")

#: Helpers that return views of the flat buffers: inlined (a function compiled without
#: reference counting may only return an array it was given).
_VIEWS = ("vec", "wvec", "wdof", "wrow", "law_offset")

#: Functions inlined by LLVM at every call site (``forceinline``): each is called once per step or
#: evaluation, from one or two places (``contact_forces``, ``rates``, ``guards_of_forces`` and
#: ``guard_rates`` from ``evaluate``), and a call passes every array argument as 7 to 11 words.
_FORCEINLINE = ("contact_forces", "forcing_phase", "rates", "guards_of_forces", "guard_rates", "rk4_step", "mark_seeds",
                "copy_all_guards")


def template_functions(source: str) -> list[str]:
    """Names of the functions a template's ``source`` defines, in source order.

    Read from the source that is pasted, not from the imported module: a process that
    imported the templates before they were edited would otherwise compile the new text
    with the old list of functions, and cache a module that cannot compile under the new
    sources' hash."""
    return [node.name for node in ast.parse(source).body if isinstance(node, ast.FunctionDef)]


# Every function is compiled without Numba's reference counting (``_nrt=False``):
# passing the table tuples to a function costs about 0.6 us a call in atomic
# reference-count updates otherwise, 40 times the work of a pair's right-hand side.
# The kernel allocates nothing; every array belongs to the Python caller and outlives
# the call, so no count is needed.

_DISPATCH = {
    "law_force": ("mode, N, Nd, v, y, so, R, I, j", "return {call}", "return 0.0"),
    "law_rates": ("mode, N, Nd, v, f, y, so, R, I, j, out, oo", "{call}", ""),
    "law_guards": ("mode, N, Nd, v, f, y, so, R, I, j, G", "{call}", ""),
    "law_guard_rates": ("mode, N, Nd, Ndd, v, vd, f, fd, y, so, R, I, j, a, D", "{call}", ""),
    "law_force_rate": ("mode, N, Nd, Ndd, v, vd, y, so, R, I, j, a", "return {call}", "return 0.0"),
    "law_transition": ("mode, gi, N, Nd, v, f, y, so, R, I, j, ztmp", "return {call}", "return mode"),
    "law_energy": ("y, so, R, I, j", "return {call}", "return 0.0"),
    "law_dissipation": ("mode, N, Nd, v, f, y, so, R, I, j", "return {call}", "return 0.0"),
}


def generate_contact_kernel(laws: list[FrictionLaw]) -> tuple[str, dict]:
    """Source and metadata of the kernel for ``laws`` (one instance per kind, in kind order).

    Returns
    -------
    source : str
    meta : dict
        Per kind: ``modes``, ``guards`` (names per mode), ``states``, ``params``
        (field names in ``LP`` order), ``rigid``; and ``gmax``.
    """
    codes = [law_code(law, K) for K, law in enumerate(laws)]
    nk = max(len(codes), 1)
    maxm = max([len(c.modes) for c in codes] + [1])
    gmax = max([len(g) for c in codes for g in c.guard_names] + [1])
    L = ["# Generated by blademodel.numeric.contact_codegen: do not edit.",
         "import math", "import numpy as np", "from numba import njit",
         "from blademodel.numeric.contract import H_LPW, O_LP, R_P",
         "from blademodel.numeric.code_libraries import EntryPointCompiler, LinkedOnlyCompiler",
         # the pipelines shape the compiled code: an edit of them names another module (Numba's cache)
         f"# code_libraries {hash_sources([code_libraries.__file__])}", ""]
    for c in codes:
        L.append(c.source)
    for name, (args, call, default) in _DISPATCH.items():
        L.append(f"def {name}(K, {args}):")
        for K in range(len(codes)):
            fn = name.replace("law_", f"law{K}_")
            L.append(f"    {'if' if K == 0 else 'elif'} K == {K}:")
            L.append("        " + call.format(call=f"{fn}({args})"))
        L.append(f"    {default}" if default else "    return")
        L.append("")

    def table(rows):
        return repr(rows)

    ng = [[len(c.guard_names[m]) if m < len(c.modes) else 0 for m in range(maxm)] for c in codes] or [[0]]
    gdir = [[[(c.guard_dirs[m][g] if m < len(c.modes) and g < len(c.guard_dirs[m]) else 0) for g in range(gmax)]
             for m in range(maxm)] for c in codes] or [[[0]]]
    stick = [[int(c.stick[m]) if m < len(c.modes) else 0 for m in range(maxm)] for c in codes] or [[0]]
    rigid = [list(c.rigid) if c.rigid else [-1, -1, -1] for c in codes] or [[-1, -1, -1]]
    nst = [c.n_states for c in codes] or [0]
    open_rates = [int(c.open_rates) for c in codes] or [0]
    L.append(f"GMAX = {gmax}")
    L.append(f"NG = np.array({table(ng)}, dtype=np.int64).reshape({nk}, {maxm})")
    L.append(f"GDIR = np.array({table(gdir)}, dtype=np.int64).reshape({nk}, {maxm}, {gmax})")
    L.append(f"IS_STICK = np.array({table(stick)}, dtype=np.int64).reshape({nk}, {maxm})")
    L.append(f"RIGID = np.array({table(rigid)}, dtype=np.int64).reshape({nk}, 3)")
    L.append(f"NSTATES = np.array({table(nst)}, dtype=np.int64)")
    L.append(f"OPEN_RATES = np.array({table(open_rates)}, dtype=np.int64)")
    L.append("")
    templates = list(TEMPLATES)
    if not any(c.rigid for c in codes):
        templates.append(contact_rigid_stubs)
    functions: list[str] = []
    for mod in templates:
        L.append(f"# ---- {mod.__name__} ----")
        source = inspect.getsource(mod)
        L.append(direct_views(source))
        L.append("")
        functions += [f for f in template_functions(source) if f not in functions]
    fns = [f"law{K}_{f}" for K in range(len(codes))
           for f in ("force", "rates", "guards", "guard_rates", "force_rate", "transition", "energy",
                      "dissipation")]
    for fn in (*fns, *_DISPATCH, *functions):
        inline = ", inline='always'" if fn in _VIEWS else ", forceinline=True" if fn in _FORCEINLINE else ""
        # Only entry points are called from Python: the others need no CPython or C wrapper, and neither
        # module optimization nor machine code of their own (code_libraries: the entry points compile them).
        cache = ("cache=True, " + ("pipeline_class=EntryPointCompiler, " if fn in _TOP_LEVEL else "")
                 if fn in _ENTRY_POINTS else
                 "no_cpython_wrapper=True, no_cfunc_wrapper=True, pipeline_class=LinkedOnlyCompiler, ")
        nogil = "nogil=True, " if fn in _NOGIL else ""
        L.append(f"{fn} = njit({cache}{nogil}_nrt=False{inline})({fn})")
    meta = {"kinds": [{"modes": c.modes, "guards": c.guard_names, "states": c.state_names,
                       "params": c.param_fields, "rigid": list(c.rigid) if c.rigid else None} for c in codes],
            "gmax": gmax}
    return "\n".join(L) + "\n", meta
