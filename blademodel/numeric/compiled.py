"""Build, cache and load the compiled kernel of a model.

The generated module is written once per model *structure* (what fixes the form
of the equations, not the parameter values) into the cache folder, with a JSON
file of metadata beside it. A later process with the same structure loads both
without SymPy, and Numba's own cache (``cache=True``) skips compilation. Changing
a parameter value never regenerates or recompiles anything.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.util
import inspect
import json
import os
import sys
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

import numpy as np

from ..model import Model

_MEMO: dict[str, "CompiledSystem"] = {}


def cache_dir() -> Path:
    """Folder of generated kernels: ``$BLADEMODEL_CACHE_DIR`` or ``~/.cache/blademodel``."""
    d = Path(os.environ.get("BLADEMODEL_CACHE_DIR", Path.home() / ".cache" / "blademodel"))
    d.mkdir(parents=True, exist_ok=True)
    return d


def _law_sources(model: Model) -> str:
    """Hash of the source of every friction law class the model uses (external ones too)."""
    return law_source_hash(c.friction for c in model.contacts)


def law_source_hash(laws) -> str:
    """Hash of the source of the classes of ``laws`` outside the package (its own are in the code version)."""
    return _class_source_hash(tuple(sorted({type(law) for law in laws}, key=lambda c: f"{c.__module__}.{c.__qualname__}")))


@functools.lru_cache(maxsize=64)
def _class_source_hash(classes: tuple) -> str:
    """:func:`law_source_hash` of sorted classes, once per process (reading source files parses them)."""
    h = hashlib.sha256()
    for cls in classes:
        for klass in cls.__mro__:
            if klass.__module__.startswith("blademodel.components.friction") or klass is object:
                continue  # the package's own laws are in _code_version
            try:
                h.update(inspect.getsource(klass).encode())
            except (OSError, TypeError):
                h.update(f"{klass.__module__}.{klass.__qualname__}".encode())
    return h.hexdigest()[:8]


PACKAGE = Path(__file__).resolve().parent.parent


def library_versions() -> str:
    """The Python, NumPy and Numba versions: compiled code is only valid for these."""
    import platform

    import numba
    return f"{platform.python_version()}|{np.__version__}|{numba.__version__}"


def hash_sources(paths, *extra: str) -> str:
    """Hash of the files ``paths`` (read, not imported) and the strings ``extra``."""
    h = hashlib.sha256()
    for path in paths:
        h.update(Path(path).read_bytes())
    for text in extra:
        h.update(text.encode())
    return h.hexdigest()[:12]


def package_sources(*folders: str) -> list[Path]:
    """The ``.py`` files of the package's ``folders`` (relative to ``blademodel/``), sorted."""
    return [p for f in folders for p in sorted((PACKAGE / f).glob("*.py"))]


_CODE_VERSION: list[str] = []

#: Sources of the symbolic layer that only print equations: editing them changes no kernel.
DISPLAY_ONLY = frozenset({"symbolic/display.py", "symbolic/names.py"})


def _code_version() -> str:
    """Hash of the sources that shape generated code and of the library versions, so edits invalidate the cache.

    The files are read, not imported: a process that finds its kernel in the cache
    never imports the symbolic layer or the code generator (start-up time). Every
    component and the symbolic layer shape the equations, so an edited one regenerates;
    the display of the equations (:data:`DISPLAY_ONLY`) does not.
    """
    if not _CODE_VERSION:
        here = PACKAGE / "numeric"
        files = [here / "codegen.py", here / "bracket.py", here / "loop.py", here / "jacobian.py", here / "contract.py",
                 *(p for p in package_sources("symbolic", "components", "components/friction")
                   if p.relative_to(PACKAGE).as_posix() not in DISPLAY_ONLY)]
        _CODE_VERSION.append(hash_sources(files, library_versions()))
    return _CODE_VERSION[0]


@dataclass
class CompiledSystem:
    """A model's generated module and its metadata.

    Attributes
    ----------
    module : module
        The generated module (``integrate``, ``initial_mode``, ``derived``, ...).
    meta : dict
        ``state``, ``params``, ``modes``, ``guards``, ``coordinates``, ``energy``.
    path : Path
        The generated source file.
    """

    module: ModuleType
    meta: dict
    path: Path

    @property
    def state_names(self) -> list[str]:
        return self.meta["state"]

    @property
    def mode_names(self) -> list[str]:
        return self.meta["modes"]

    def parameter_array(self, model: Model) -> np.ndarray:
        """Raw parameter vector of ``model`` plus the hoisted constants."""
        values = model.parameters
        p = np.array([values[n] for n in self.meta["params"]], dtype=float)
        return self.module.derived(p)


def _load(path: Path) -> ModuleType:
    name = f"blademodel_generated_{path.stem}"
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def compile_model(model: Model, *, energy: bool = False) -> CompiledSystem:
    """Return the compiled kernel of ``model``, generating it only if needed.

    Parameters
    ----------
    model : Model
    energy : bool
        Include the work/dissipation accumulators (a separate kernel).
    """
    key = f"{model.structure_key()}_{_code_version()}{_law_sources(model)}_{'e' if energy else 'n'}"
    if key in _MEMO:
        return _MEMO[key]
    folder = cache_dir()
    src_path = folder / f"k_{key}.py"
    meta_path = folder / f"k_{key}.json"
    if not (src_path.exists() and meta_path.exists()):
        from .codegen import generate
        from .jacobian import jacobians
        system = derive_cached(model)
        source, meta = generate(system, energy=energy)
        source += "\n" + jacobians(system)
        tmp = src_path.with_suffix(f".tmp{os.getpid()}")
        tmp.write_text(source)
        os.replace(tmp, src_path)
        tmp = meta_path.with_suffix(f".tmp{os.getpid()}")
        tmp.write_text(json.dumps(meta))
        os.replace(tmp, meta_path)
    meta = json.loads(meta_path.read_text())
    compiled = CompiledSystem(_load(src_path), meta, src_path)
    _MEMO[key] = compiled
    return compiled


_DERIVED: dict = {}


def derive_cached(model: Model):
    """``symbolic.derive(model)``, memoised per structure within the process."""
    from ..symbolic import derive
    key = model.structure_key()
    if key not in _DERIVED:
        _DERIVED[key] = derive(model)
    return _DERIVED[key]
