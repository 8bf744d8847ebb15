"""The per-contact kernel's generated module compiles every function of the text it pastes.

The module is cached under a hash of the templates' files, so the functions it compiles
must be read from the text it pastes, not from the templates as the running process
imported them: a process that imported them before an edit (a long run during an
upgrade) wrote a module whose new functions were pasted but never compiled, and every
later process with the same law kinds failed on it ("Untyped global name").
"""

import ast
import inspect

from blademodel.config import BladedDisk
from blademodel.numeric import contact_replay
from blademodel.numeric.contact_codegen import generate_contact_kernel
from blademodel.numeric.contact_kernel import law_kinds


def compiled_names(source: str) -> set:
    """The names the generated module passes to ``njit``: ``name = njit(...)(name)``."""
    out = set()
    for node in ast.parse(source).body:
        if isinstance(node, ast.Assign) and isinstance(node.value, ast.Call) and \
                isinstance(node.value.func, ast.Call) and getattr(node.value.func.func, "id", "") == "njit":
            out.add(node.targets[0].id)
    return out


def defined_names(source: str) -> set:
    return {node.name for node in ast.parse(source).body if isinstance(node, ast.FunctionDef)}


def test_every_pasted_function_is_compiled(monkeypatch):
    """The templates' text holds a function the imported module does not (as after an edit): it is compiled
    with the rest, and every function the module defines is."""
    laws = law_kinds(BladedDisk(blades=4, friction="bilinear").build())[0]
    source, _ = generate_contact_kernel(laws)
    assert defined_names(source) <= compiled_names(source)
    edited = inspect.getsource(contact_replay) + "\n\ndef added_after_import(x):\n    return x\n"
    real = inspect.getsource
    monkeypatch.setattr(inspect, "getsource", lambda m: edited if m is contact_replay else real(m))
    source, _ = generate_contact_kernel(laws)
    assert "added_after_import" in compiled_names(source)
    assert defined_names(source) <= compiled_names(source)
