"""Numba compiler pipelines for the code libraries of the per-contact kernel's functions.

Numba compiles every function into a code library of its own, links the libraries
of all it calls into it, optimizes the whole module again and generates machine code
for it. In a call tree ``integrate -> step_clusters -> process_cluster ->
locate_event -> ... -> contact_forces`` a function nine calls deep is therefore
optimized and compiled to machine code nine times over, and the functions linked in
stay visible to other modules (``linkonce_odr``), so LLVM keeps every argument of
every call: an array is passed as seven to eleven words, of which the callee reads
one or two.

* :class:`LinkedOnlyCompiler`, for a function that is only called from compiled code
  (no Python or C wrapper: the kernel's functions other than its entry points): its
  code library keeps its LLVM IR for linking (optimized function by function, as every
  library's) but skips the module's optimization and its machine code, which would
  never run (its callers run their own copy of its code, optimized in the module of
  the entry point that links it); only the module's environment globals are emitted
  (Numba writes the address of each function's environment there). On the
  frictionless kernel this took the LLVM work of a cold compile from about 12.7 to
  3.8 s of CPU time on a loaded machine.
* :class:`EntryPointCompiler`, for an entry point called from Python only (never
  linked into another function): before its module is optimized, every function
  linked into it becomes internal to it, so LLVM may drop the arguments a function
  does not read, inline a function called once, and discard what nothing calls.

The code that runs is compiled from the same IR as before with the same
floating-point semantics (no fast-math): the kernel computes the same numbers, to
the bit. This reaches into Numba's code library (``JITCodeLibrary``: its final
module, module optimization and finalization), so it is used only on the Numba
releases it was checked on (:data:`CHECKED_NUMBA`); elsewhere, or if the code library
lacks what it uses, :data:`SUPPORTED` is False and both pipelines are Numba's default.
"""

from __future__ import annotations

import llvmlite.binding as ll
import numba
from numba.core import codegen as _codegen
from numba.core.compiler import CompilerBase, DefaultPassBuilder
from numba.core.compiler_machinery import FunctionPass, register_pass
from numba.core.typed_passes import NopythonTypeInference

#: The Numba releases these pipelines were checked on (bit-identical results, the kernel tests): the code
#: library's internals are private and may change in any release, so another one takes Numba's own pipelines
#: (the same results, a slower cold compile) until it is checked and added here.
CHECKED_NUMBA = ("0.68.",)

#: Whether this Numba is a checked release and its code library has what the pipelines replace.
SUPPORTED = (numba.__version__.startswith(CHECKED_NUMBA)
             and all(hasattr(_codegen.JITCodeLibrary, m) for m in ("_optimize_final_module", "_finalize_final_module",
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


class EntryPointLibrary(_codegen.JITCodeLibrary):
    """The code library of an entry point called from Python only: what it links becomes internal to it."""

    def _optimize_final_module(self):
        for fn in self._final_module.functions:
            if not fn.is_declaration and fn.linkage == ll.Linkage.linkonce_odr:
                fn.linkage = ll.Linkage.internal
        super()._optimize_final_module()


def _use_library(state, cls):
    """Give the function being compiled a code library of class ``cls`` (before lowering creates Numba's)."""
    if state.library is None:
        codegen = state.targetctx.codegen()
        if type(codegen) is _codegen.JITCPUCodegen:
            state.library = cls(codegen, state.func_id.func_qualname)
            state.library.enable_object_caching()


class _UseLibrary(FunctionPass):
    """Give the function a code library of class ``library`` (before lowering creates the default one)."""

    library = None

    def __init__(self):
        FunctionPass.__init__(self)

    def run_pass(self, state):
        _use_library(state, self.library)
        return False


@register_pass(mutates_CFG=False, analysis_only=False)
class UseLinkedOnlyLibrary(_UseLibrary):
    """Give the function a :class:`LinkedOnlyLibrary`."""

    _name = "blademodel_use_linked_only_library"
    library = LinkedOnlyLibrary


@register_pass(mutates_CFG=False, analysis_only=False)
class UseEntryPointLibrary(_UseLibrary):
    """Give the function an :class:`EntryPointLibrary`."""

    _name = "blademodel_use_entry_point_library"
    library = EntryPointLibrary


class LinkedOnlyCompiler(CompilerBase):
    """Numba's nopython pipeline, the function's code library a :class:`LinkedOnlyLibrary` (if
    :data:`SUPPORTED`). For functions without a Python or C wrapper, called from compiled code only."""

    def define_pipelines(self):
        pm = DefaultPassBuilder.define_nopython_pipeline(self.state)
        if SUPPORTED:
            pm.add_pass_after(UseLinkedOnlyLibrary, NopythonTypeInference)
            pm.finalize()
        return [pm]


class EntryPointCompiler(CompilerBase):
    """Numba's nopython pipeline, the function's code library an :class:`EntryPointLibrary` (if
    :data:`SUPPORTED`). For entry points called from Python only, never from compiled code."""

    def define_pipelines(self):
        pm = DefaultPassBuilder.define_nopython_pipeline(self.state)
        if SUPPORTED:
            pm.add_pass_after(UseEntryPointLibrary, NopythonTypeInference)
            pm.finalize()
        return [pm]
