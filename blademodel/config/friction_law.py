"""Friction laws of the configs with named fields (blade pair, bladed disk).

Such a config names its law (``friction``), gives the law's shared values as its
own fields (``mu``, ``kd``) and the law's other keyword arguments in
``friction_options``. These helpers build the law and report a rejected option
at its field path.
"""

from __future__ import annotations

from typing import Any, Callable, Collection, Mapping

from ..components import FrictionLaw, Param
from ..components.friction import registry
from .errors import FieldError


def make_friction_law(friction: str, options: Mapping[str, Any], values: Mapping[str, Param],
                      forced: Mapping[str, Any] | None = None) -> FrictionLaw:
    """The law ``friction`` built from ``values``, ``forced`` and ``options``.

    Parameters
    ----------
    friction : str
        A registered law name or ``"package.module:ClassName"``.
    options : mapping
        The law's own keyword arguments (``friction_options``).
    values : mapping of str to Param
        Values of the config passed to the law if its constructor takes them
        (``{"mu": Param("mu", 0.5), "kd": Param("kd", 1e6)}``).
    forced : mapping, optional
        Keyword arguments passed whether or not the constructor names them.

    Raises
    ------
    registry.LawOptionError
        If the law rejects an option (its key is named when it can be told).
    """
    cls = registry.law_class(friction)
    accepted, _ = registry.accepted_options(cls)
    shared = {name: p for name, p in values.items() if name in accepted}
    return registry.make_law(cls, {**shared, **(forced or {}), **options})


def check_friction_options(build: Callable[[], FrictionLaw], friction: str, options: Mapping[str, Any],
                           fields: Collection[str], *, owner: str, loc: tuple = ("friction_options",)) -> None:
    """Check ``options`` against ``fields`` and the law's constructor.

    Parameters
    ----------
    build : callable
        Builds the law (raising :class:`registry.LawOptionError`).
    friction : str
        The law's name, used in messages.
    options : mapping
        The ``friction_options`` being checked.
    fields : collection of str
        Names that must be set as fields of the config instead.
    owner : str
        What the fields belong to, for messages (``"pair"``).
    loc : tuple
        Field path of ``options`` from the root of the config.

    Raises
    ------
    FieldError
        At ``loc + (key,)`` for an offending option, else at ``loc``.
    """
    for key, value in options.items():
        if key in fields:
            raise FieldError(loc + (key,), value,
                             f"{key!r} is a field of the {owner}; set it there, not in friction_options")
    try:
        build()
    except registry.LawOptionError as e:
        known = e.key in options
        raise FieldError(loc + (e.key,) if known else loc, options.get(e.key) if known else None,
                         f"{friction}: {e.reason.removeprefix('friction: ')}") from None
