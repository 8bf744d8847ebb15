"""Friction laws by name: the built-in laws and those of the ``blademodel.friction_laws`` entry points.

Every place that takes a law *name* — ``BladePair.friction``, a study's ``laws``,
``friction: {law: ...}`` in the components format — resolves it here, so a law
installed by another package is usable everywhere by its name. A package
registers its laws in its own ``pyproject.toml``::

    [project.entry-points."blademodel.friction_laws"]
    dahl = "mypackage.friction:Dahl"

A law can also be given without registration by its import path,
``"mypackage.friction:Dahl"`` (the module must be importable, e.g. on
``PYTHONPATH``). blademodel registers its own laws in the same group; the table
:data:`BUILTIN` below is used as well, so they resolve even from a source tree that
was never installed, and a built-in name cannot be taken over by another package.
"""

from __future__ import annotations

import functools
import importlib
import inspect
import re
import warnings
from importlib import metadata
from typing import Any, Mapping

from .base import FrictionLaw
from .validation import check_law_class

#: Entry-point group of friction laws (name -> ``"module:Class"``).
ENTRY_POINT_GROUP = "blademodel.friction_laws"

#: The laws that ship with blademodel, by name.
BUILTIN: dict[str, str] = {
    "coulomb": "blademodel.components.friction.coulomb:Coulomb",
    "bilinear": "blademodel.components.friction.jenkins:Jenkins",
    "none": "blademodel.components.friction.none:NoFriction",
    "iwan": "blademodel.components.friction.iwan:Iwan",
}

_IMPORT_PATH = re.compile(r"^[A-Za-z_]\w*(\.[A-Za-z_]\w*)*:[A-Za-z_]\w*(\.[A-Za-z_]\w*)*$")
_ENTRY_POINTS: dict[str, str] | None = None


def _entry_points() -> dict[str, str]:
    """``name -> "module:Class"`` of the installed ``blademodel.friction_laws`` entry points."""
    global _ENTRY_POINTS
    if _ENTRY_POINTS is None:
        found: dict[str, str] = {}
        for ep in metadata.entry_points(group=ENTRY_POINT_GROUP):
            if ep.name in BUILTIN:
                if ep.value != BUILTIN[ep.name]:
                    warnings.warn(f"entry point {ep.name!r} = {ep.value!r} of group {ENTRY_POINT_GROUP!r} "
                                  f"is ignored: {ep.name!r} is a built-in friction law", stacklevel=3)
                continue
            if ep.name in found and found[ep.name] != ep.value:
                warnings.warn(f"friction law {ep.name!r} is registered twice ({found[ep.name]!r} and "
                              f"{ep.value!r}); using the first", stacklevel=3)
                continue
            found[ep.name] = ep.value
        _ENTRY_POINTS = found
    return _ENTRY_POINTS


def refresh() -> None:
    """Forget the entry points read so far (after installing a package in a running process)."""
    global _ENTRY_POINTS
    _ENTRY_POINTS = None


def registered_laws() -> dict[str, str]:
    """Every registered law name and its ``"module:Class"``: built-ins first, then entry points."""
    return {**BUILTIN, **_entry_points()}


def known_names() -> list[str]:
    """Sorted names of the registered laws."""
    return sorted(registered_laws())


def is_import_path(text: str) -> bool:
    """Whether ``text`` has the form ``"package.module:ClassName"``."""
    return bool(_IMPORT_PATH.match(text))


def _unknown(name: str) -> ValueError:
    return ValueError(f"unknown friction law {name!r}: known laws are {', '.join(known_names())} "
                      f"(or give an import path 'package.module:ClassName')")


def _load(path: str, label: str) -> type:
    module, _, qualname = path.partition(":")
    try:
        obj: Any = importlib.import_module(module)
    except ImportError as e:
        raise ValueError(f"cannot import friction law {label!r}: {e}") from None
    for part in qualname.split("."):
        try:
            obj = getattr(obj, part)
        except AttributeError:
            raise ValueError(f"cannot import friction law {label!r}: module {module!r} has no "
                             f"{qualname!r}") from None
    if not (isinstance(obj, type) and issubclass(obj, FrictionLaw)):
        raise ValueError(f"{label!r} is not a FrictionLaw subclass")
    return check_law_class(obj, label)


def law_class(name: str) -> type:
    """The :class:`FrictionLaw` subclass for a registered name or an import path.

    Parameters
    ----------
    name : str
        ``"coulomb"``, ``"iwan"``, an entry-point name, or ``"package.module:ClassName"``.

    Raises
    ------
    ValueError
        For an unknown name (the message lists the known ones), a path that cannot
        be imported, or an object that is not a FrictionLaw subclass.
    """
    if not isinstance(name, str):
        raise ValueError(f"a friction law is given by name, got {name!r}")
    laws = registered_laws()
    if name in laws:
        where = f"{name!r} ({laws[name]})" if name not in BUILTIN else name
        return _load(laws[name], where)
    if is_import_path(name):
        return _load(name, name)
    raise _unknown(name)


def check_name(name: str) -> str:
    """``name`` if it resolves to a law (see :func:`law_class`), else ``ValueError``."""
    law_class(name)
    return name


class LawOptionError(ValueError):
    """A law's constructor rejected its options; :attr:`key` names the option when known.

    Attributes
    ----------
    key : str or None
        The offending option (keyword argument), if it could be told.
    value : object
        Its value.
    reason : str
        The law's message.
    """

    def __init__(self, key: str | None, value: Any, reason: str):
        self.key, self.value, self.reason = key, value, reason
        super().__init__(f"{key} = {value!r}: {reason}" if key else reason)


def accepted_options(cls: type) -> tuple[list[str], bool]:
    """Keyword arguments of ``cls``'s constructor, and whether it takes ``**kwargs``."""
    names, var_kw = _signature_options(cls)
    return list(names), var_kw


@functools.lru_cache(maxsize=256)
def _signature_options(cls: type) -> tuple[tuple[str, ...], bool]:
    """:func:`accepted_options`, once per class (reading a signature costs tens of microseconds)."""
    params = inspect.signature(cls).parameters.values()
    names = tuple(p.name for p in params if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY))
    return names, any(p.kind is p.VAR_KEYWORD for p in params)


def numeric_defaults(cls: type) -> dict[str, float]:
    """The constructor's keyword arguments whose defaults are numbers (``{"mu": 0.5, "kd": 1e6}``)."""
    return dict(_numeric_defaults(cls))


@functools.lru_cache(maxsize=256)
def _numeric_defaults(cls: type) -> tuple[tuple[str, float], ...]:
    params = inspect.signature(cls).parameters.values()
    return tuple((p.name, p.default) for p in params
                 if isinstance(p.default, (int, float)) and not isinstance(p.default, bool))


def make_law(cls: type, options: Mapping[str, Any]) -> FrictionLaw:
    """``cls(**options)``, with errors that name the offending option.

    Raises
    ------
    LawOptionError
        For an option the constructor does not take, or one it rejects (the key
        is the first option whose name the law's message mentions).
    """
    names, var_kw = accepted_options(cls)
    if not var_kw:
        for key, value in options.items():
            if key not in names:
                raise LawOptionError(key, value, f"unknown option of {cls.__name__} "
                                                 f"(known: {', '.join(names) or 'none'})")
    try:
        return cls(**options)
    except (TypeError, ValueError) as e:
        msg = str(e)
        key = next((k for k in options if re.search(rf"(?<![\w.]){re.escape(k)}(?!\w)", msg)), None)
        raise LawOptionError(key, options.get(key), msg) from e
