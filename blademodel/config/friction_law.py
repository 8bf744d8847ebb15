"""The one route from a law name and its options to a friction law, for every config.

Every config builds its laws here: the ``friction:`` block of a contact in the
component-list format (:mod:`.friction_format`), ``friction`` with
``friction_options`` of the blade pair and of the bladed disk and its contacts.
Built-in and external laws take the same steps:

1. **resolve** the name through the registry
   (:func:`~blademodel.components.friction.registry.law_class`: ``coulomb``,
   ``bilinear``, ``none``, ``iwan``, an entry-point name or ``"package.module:Class"``);
2. **build** the law from its keyword arguments
   (:func:`~blademodel.components.friction.registry.make_law`), the config's shared
   values (``mu``, ``kd``) passed if the constructor takes them;
3. **name its parameters per contact** when asked: every parameter of the law
   (:meth:`~blademodel.components.friction.base.FrictionLaw.parameters`) that was not
   given as a named :class:`~blademodel.components.Param` gets the symbol
   ``<its default symbol>_<suffix>``, e.g. ``mu_c2``, so two contacts with their
   own plain numbers never share a symbol. A law opts in by taking its parameters
   as constructor keyword arguments named as in ``parameters()``, as the built-in
   laws do;
4. **report** a rejected option at its field (:func:`option_error`), in the
   config's words.
"""

from __future__ import annotations

from typing import Any, Callable, Collection, Mapping, Optional

from ..components import FrictionLaw, Param
from ..components.friction import registry
from .errors import FieldError


def make_friction_law(friction: str, options: Mapping[str, Any], values: Optional[Mapping[str, Param]] = None,
                      forced: Optional[Mapping[str, Any]] = None, *, suffix: Optional[str] = None) -> FrictionLaw:
    """The law ``friction`` built from ``values``, ``forced`` and ``options``.

    Parameters
    ----------
    friction : str
        A registered law name or ``"package.module:ClassName"``.
    options : mapping
        The law's own keyword arguments (``friction_options``, the keys of a
        ``friction:`` block); a :class:`Param` keeps its symbol.
    values : mapping of str to Param, optional
        Values of the config passed to the law if its constructor takes them
        (``{"mu": Param("mu", 0.5), "kd": Param("kd", 1e6)}``).
    forced : mapping, optional
        Keyword arguments passed whether or not the constructor names them.
    suffix : str, optional
        Name the law's parameters per contact: each one not given as a
        :class:`Param` (a plain number, or the law's default) gets the symbol
        ``<default symbol>_<suffix>``.

    Raises
    ------
    registry.LawOptionError
        If the law rejects an option (its key is named when it can be told), or a
        parameter is given as a boolean.
    """
    cls = registry.law_class(friction)
    accepted, _ = registry.accepted_options(cls)
    shared = {name: p for name, p in (values or {}).items() if name in accepted}
    kwargs = {**shared, **(forced or {}), **options}
    law = registry.make_law(cls, kwargs)
    for key in law.parameters():
        if isinstance(kwargs.get(key), bool):   # YAML's `yes`: a number to float(), not to the reader
            raise registry.LawOptionError(key, kwargs[key], f"{key} = {kwargs[key]!r} must be a number, "
                                                            f"not a boolean")
    return law if suffix is None else _per_contact(cls, law, kwargs, suffix)


def _per_contact(cls: type, law: FrictionLaw, kwargs: Mapping[str, Any], suffix: str) -> FrictionLaw:
    """``law`` rebuilt with ``<symbol>_<suffix>`` for each parameter not given as a Param."""
    accepted, var_kw = registry.accepted_options(cls)
    own = {key: Param(f"{p.name}_{suffix}", p.value) for key, p in law.parameters().items()
           if (key in accepted or var_kw) and not isinstance(kwargs.get(key), Param)}
    return registry.make_law(cls, {**kwargs, **own}) if own else law


def parameter_fields(friction: str, options: Mapping[str, Any], without: str) -> Collection[str]:
    """Keys of the parameters of the law built from ``options`` less ``without`` (empty if it cannot be).

    Tells whether a rejected option is one of the law's numeric parameters (it is
    among ``parameters()`` when the law is built with its default instead).
    """
    rest = {k: v for k, v in options.items() if k != without}
    try:
        return set(make_friction_law(friction, rest).parameters())
    except (TypeError, ValueError):
        return set()


def option_error(e: registry.LawOptionError, friction: str, options: Mapping[str, Any], loc: tuple,
                 shown: Optional[Mapping[str, Any]] = None) -> FieldError:
    """The :class:`FieldError` of an option ``friction`` rejected, at ``loc + (key,)``.

    Parameters
    ----------
    e : registry.LawOptionError
        What the law (or the registry) said.
    friction : str
        The law's name, which starts the message (``"iwan: elements = 0 must be ..."``).
    options : mapping
        The options the law was given.
    loc : tuple
        Field path of the options from the root of the config.
    shown : mapping, optional
        The values to show, as the config wrote them (default: ``options``).
    """
    shown = options if shown is None else shown
    reason = f"{friction}: {e.reason.removeprefix('friction: ')}"
    if e.key in options:
        return FieldError(loc + (e.key,), shown.get(e.key), reason)
    return FieldError(loc, None, reason)


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
        raise option_error(e, friction, options, loc) from None
