"""SymPy, imported on first use.

Components build SymPy expressions only when equations are derived. A run whose
compiled kernel is cached never derives them, so it never pays SymPy's import
(about 0.2 s, a fifth of a cached start-up).
"""

from __future__ import annotations

import importlib


class _LazyModule:
    """Stands in for a module and imports it at the first attribute access."""

    def __init__(self, name: str):
        self._name = name

    def __getattr__(self, attr: str):
        return getattr(importlib.import_module(self._name), attr)


sp = _LazyModule("sympy")
