"""A Numba compiler pipeline for functions that are only ever linked into others.

Numba compiles every function into a code library of its own, links the libraries
of all it calls into it, optimizes the whole module again and generates machine code
for it. In a call tree ``integrate -> step_clusters -> process_cluster ->
locate_event -> ... -> contact_forces`` a function nine calls deep is therefore
optimized and compiled to machine code nine times over. For a function that is only
called from compiled code (no Python or C wrapper: the per-contact kernel's functions
other than its entry points) neither is needed: its machine code is never run (its
callers run their own copy of its code) and its callers optimize its code once more
anyway, in the module of the entry point that links it.

:class:`LinkedOnlyCompiler` (``njit(pipeline_class=LinkedOnlyCompiler)``) gives such a
function a code library that keeps its LLVM IR for linking (optimized function by
function, as every library's) but skips the module's optimization and its machine
code; only the module's environment globals are emitted (Numba writes the address
of each function's environment there). The code that runs, the entry points', is
optimized and compiled as before, from the same IR: the kernel computes the same
numbers (the per-contact kernel's per-step cost is unchanged within noise, its
results identical to the bit). On the frictionless per-contact kernel (Numba 0.68,
LLVM 22) this took the LLVM work of a cold compile from about 13.8 to 7.4 s of CPU
time on a loaded machine (module optimization 7.5 -> 1.8 s, machine code of
libraries nobody runs no longer generated).

This reaches into Numba's code library (``JITCodeLibrary``: its final module,
module optimization and finalization); if a Numba version lacks what it uses,
:data:`SUPPORTED` is False and the pipeline is Numba's default.
"""

from __future__ import annotations

import llvmlite.binding as ll
from numba.core import codegen as _codegen
from numba.core.compiler import CompilerBase, DefaultPassBuilder
from numba.core.compiler_machinery import FunctionPass, register_pass
from numba.core.typed_passes import NopythonTypeInference

#: Whether this Numba's code library has what :class:`LinkedOnlyCompiler` replaces.
SUPPORTED = (all(hasattr(_codegen.JITCodeLibrary, m) for m in ("_optimize_final_module", "_finalize_final_module",
                                                                  "enable_object_caching"))
             and hasattr(_codegen.JITCPUCodegen, "_add_module"))


class LinkedOnlyLibrary(_codegen.JITCodeLibrary):
    """The code library of a function only ever linked into others: no module optimization, no machine code."""

    def _optimize_final_module(self):
        """Left to the entry points that link this library (they optimize the linked module as a whole)."""

    def _finalize_final_module(self):
        """Emit only the module's common globals (the environments ``set_env`` writes), not its functions."""
        for step in ("_finalize_dynamic_globals", "_verify_declare_only_symbols"):
            if hasattr(self, step):
                getattr(self, step)()
        text = "".join(f"{gv}\n" for gv in self._final_module.global_variables
                       if gv.linkage == ll.Linkage.common)
        stub = ll.parse_assembly(text)
        stub.triple = self._final_module.triple
        stub.data_layout = self._final_module.data_layout
        self._codegen._add_module(stub)
        self._codegen._engine.finalize_object()
        self._finalized = True


@register_pass(mutates_CFG=False, analysis_only=False)
class UseLinkedOnlyLibrary(FunctionPass):
    """Give the function a :class:`LinkedOnlyLibrary` (before lowering creates the default one)."""

    _name = "blademodel_use_linked_only_library"

    def __init__(self):
        FunctionPass.__init__(self)

    def run_pass(self, state):
        if state.library is None:
            codegen = state.targetctx.codegen()
            if type(codegen) is _codegen.JITCPUCodegen:
                state.library = LinkedOnlyLibrary(codegen, state.func_id.func_qualname)
                state.library.enable_object_caching()
        return False


class LinkedOnlyCompiler(CompilerBase):
    """Numba's nopython pipeline, the function's code library a :class:`LinkedOnlyLibrary` (if
    :data:`SUPPORTED`). For functions without a Python or C wrapper, called from compiled code only."""

    def define_pipelines(self):
        pm = DefaultPassBuilder.define_nopython_pipeline(self.state)
        if SUPPORTED:
            pm.add_pass_after(UseLinkedOnlyLibrary, NopythonTypeInference)
            pm.finalize()
        return [pm]
