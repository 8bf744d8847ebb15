"""The ``friction:`` block of a contact in the component-list format.

``law`` names the friction law: a built-in name (``coulomb``, ``bilinear``,
``none``, ``iwan``), a name another package registers under the
``blademodel.friction_laws`` entry-point group, or the import path of a
:class:`~blademodel.components.friction.base.FrictionLaw` subclass,
``"package.module:ClassName"``. Every other key is a keyword argument of the law's
constructor. Built-in and external laws take the same route
(:func:`~blademodel.config.friction_law.make_friction_law`)::

    friction: {law: iwan, mu: 0.5, kd: 1e6, elements: 8}
    friction: {law: "mypackage.friction:Dahl", mu: mu, sigma0: 1e7}
    friction: bilinear                      # the law's defaults

A value is a number, the name of an entry of ``parameters:`` (passed as that
:class:`~blademodel.components.Param`, so contacts naming it share its symbol), or
any other value the law takes (``distribution: uniform``). A law parameter given
as a plain number, or left at its default, gets a symbol of its contact: ``mu_c2``,
``kd_c2`` for contact ``c2``; so two contacts with ``{law: iwan, mu: 0.5}`` and
``{law: iwan, mu: 0.3}`` have their own coefficients. A value the law rejects is
reported at its key: ``contacts.1.friction.elements = 0: iwan: elements = 0 must
be an integer >= 1``.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Mapping

from pydantic import BaseModel, BeforeValidator, ConfigDict, field_validator, model_serializer, model_validator

from ..components import FrictionLaw, Param
from ..components.friction import registry
from .errors import FieldError, format_loc
from .friction_law import make_friction_law, option_error, parameter_fields


def _number(key: str, value: Any) -> Any:
    """``value`` with a string that reads as a number made that number (PyYAML reads ``1e6`` as text)."""
    number = value
    if isinstance(value, str):
        try:
            number = float(value.strip())
        except ValueError:
            return value
    if isinstance(number, float) and not math.isfinite(number):
        raise FieldError((key,), value, "Input should be a finite number")
    return number


class LawSpec(BaseModel):
    """A contact's friction law by name, with the law's keyword arguments as the other keys.

    Attributes
    ----------
    law : str
        A registered law name or ``"package.module:ClassName"``.
    """

    model_config = ConfigDict(extra="allow")

    law: str

    @field_validator("law")
    @classmethod
    def _known_law(cls, v: str) -> str:
        return registry.check_name(v)

    @model_validator(mode="after")
    def _numbers(self):
        extra = self.__pydantic_extra__
        for key, value in extra.items():
            extra[key] = _number(key, value)
        return self

    @model_serializer(mode="wrap")
    def _with_defaults(self, handler) -> dict:
        """The written keys and the law's numeric defaults, so ``--set contacts.0.friction.mu=...`` finds ``mu``."""
        data = handler(self)
        defaults = registry.numeric_defaults(registry.law_class(self.law))
        return {"law": data.pop("law"), **{k: data.pop(k, v) for k, v in defaults.items()}, **data}

    @property
    def options(self) -> dict[str, Any]:
        """The law's keyword arguments as written (numbers, parameter names, other values)."""
        return dict(self.__pydantic_extra__)

    def build(self, parameters: Mapping[str, float], contact: str, loc: tuple = ()) -> FrictionLaw:
        """The law of contact ``contact``, its unnamed parameters named ``<symbol>_<contact>``.

        Parameters
        ----------
        parameters : mapping of str to float
            The model's ``parameters:``; a string value naming one is passed as that Param.
        contact : str
            The contact's name.
        loc : tuple
            Field path of this block from the root of the config, for errors.

        Raises
        ------
        FieldError
            At the offending key (or at ``parameters.<name>`` for a declared
            parameter the law refuses), in the words of the YAML file.
        """
        given = self.options
        options = {k: Param(v, parameters[v]) if isinstance(v, str) and v in parameters else v
                   for k, v in given.items()}
        while True:
            try:
                law = make_friction_law(self.law, options, suffix=contact)
                break
            except registry.LawOptionError as e:
                if isinstance(options.get(e.key), Param) and e.key not in parameter_fields(self.law, options, e.key):
                    options[e.key] = given[e.key]   # text that names a parameter, for an option that is no parameter
                    continue
                raise self._error(e, given, options, parameters, loc) from None
        return law

    def _error(self, e: registry.LawOptionError, given: Mapping[str, Any], options: Mapping[str, Any],
               parameters: Mapping[str, float], loc: tuple) -> FieldError:
        """The FieldError of an option the law rejected."""
        key = e.key
        if isinstance(options.get(key), Param):
            name = given[key]
            return FieldError(("parameters", name), parameters[name],
                              f"{self.law}: {e.reason.removeprefix('friction: ')} "
                              f"(used by {format_loc(loc + (key,))})")
        value = given.get(key)
        if isinstance(value, str) and value.isidentifier() and key in parameter_fields(self.law, options, key):
            known = ", ".join(parameters) or "none declared under 'parameters:'"
            return FieldError(loc + (key,), value, f"unknown parameter (known: {known})")
        return option_error(e, self.law, options, loc, shown=given)


def _shorthand(v):
    """``friction: coulomb`` means ``friction: {law: coulomb}``."""
    return {"law": v} if isinstance(v, str) else v


#: The type of ``contacts[].friction``: a :class:`LawSpec`, or a law name alone.
FrictionSpec = Annotated[LawSpec, BeforeValidator(_shorthand)]
