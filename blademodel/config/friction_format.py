"""The ``friction:`` block of a contact in the component-list format.

``law`` selects the friction law. A built-in name (``coulomb``, ``bilinear``,
``none``) has its own fixed set of keys; any other value must be the import path
of a :class:`~blademodel.components.friction.base.FrictionLaw` subclass,
``"package.module:ClassName"``, and the remaining keys are passed to it as
keyword arguments (a string value naming a declared parameter is passed as that
:class:`~blademodel.components.Param`). A new built-in law is one more spec class
here and one more entry in :data:`BUILTIN_LAWS`.
"""

from __future__ import annotations

import importlib
import re
from typing import Annotated, Callable, Literal, Optional, Union

from pydantic import BaseModel, BeforeValidator, ConfigDict, Discriminator, Tag, field_validator

from ..components import Coulomb, FrictionLaw, Jenkins, NoFriction, Param
from .values import number

#: ``resolve(value, default_name)``: a plain number (named ``default_name`` if given)
#: or the declared parameter a string names.
Resolver = Callable[[Union[float, str], Optional[str]], Union[float, Param]]

_IMPORT_PATH = re.compile(r"^[A-Za-z_][\w]*(\.[A-Za-z_][\w]*)*:[A-Za-z_][\w]*$")


class _Spec(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, validate_assignment=True)


class CoulombSpec(_Spec):
    """Coulomb friction with rigid stick (MODEL.md 4.1).

    Plain numbers get per-contact symbols ``mu_<contact>``, ``v_tol_<contact>``.
    """

    law: Literal["coulomb"]
    mu: number(ge=0) = 0.5
    stick_velocity_tol: number(ge=0) = 0.0

    def build(self, resolve: Resolver, contact: str) -> FrictionLaw:
        tol = self.stick_velocity_tol
        tol = resolve(tol, f"v_tol_{contact}") if isinstance(tol, str) or tol != 0 else 0.0
        return Coulomb(mu=resolve(self.mu, f"mu_{contact}"), stick_velocity_tol=tol)


class BilinearSpec(_Spec):
    """Bilinear hysteresis, the Jenkins element (MODEL.md 4.2).

    Plain numbers get per-contact symbols ``mu_<contact>``, ``kd_<contact>``.
    """

    law: Literal["bilinear"]
    mu: number(ge=0) = 0.5
    kd: number(gt=0) = 1e6

    def build(self, resolve: Resolver, contact: str) -> FrictionLaw:
        return Jenkins(mu=resolve(self.mu, f"mu_{contact}"), kd=resolve(self.kd, f"kd_{contact}"))


class NoFrictionSpec(_Spec):
    """A frictionless contact."""

    law: Literal["none"]

    def build(self, resolve: Resolver, contact: str) -> FrictionLaw:
        return NoFriction()


def import_law(path: str) -> type:
    """The :class:`FrictionLaw` subclass at ``"package.module:ClassName"``.

    Raises
    ------
    ValueError
        If ``path`` is malformed, cannot be imported or is not a FrictionLaw subclass.
    """
    if not _IMPORT_PATH.match(path):
        raise ValueError(f"unknown friction law {path!r}: expected one of {', '.join(BUILTIN_LAWS)} "
                         f"or an import path 'package.module:ClassName'")
    module, _, name = path.partition(":")
    try:
        cls = getattr(importlib.import_module(module), name)
    except ImportError as e:
        raise ValueError(f"cannot import friction law {path!r}: {e}") from None
    except AttributeError:
        raise ValueError(f"cannot import friction law {path!r}: module {module!r} has no {name!r}") from None
    if not (isinstance(cls, type) and issubclass(cls, FrictionLaw)):
        raise ValueError(f"{path!r} is not a FrictionLaw subclass")
    return cls


class ExternalLawSpec(BaseModel):
    """A friction law given by import path; other keys are its keyword arguments."""

    model_config = ConfigDict(extra="allow", allow_inf_nan=False)

    law: str

    @field_validator("law")
    @classmethod
    def _importable(cls, v: str) -> str:
        import_law(v)
        return v

    def build(self, resolve: Resolver, contact: str) -> FrictionLaw:
        kwargs = {k: resolve(v, None) if isinstance(v, str) else v for k, v in (self.model_extra or {}).items()}
        return import_law(self.law)(**kwargs)


BUILTIN_LAWS = {"coulomb": CoulombSpec, "bilinear": BilinearSpec, "none": NoFrictionSpec}


def _tag(v) -> str:
    law = v.get("law") if isinstance(v, dict) else getattr(v, "law", None)
    return law if law in BUILTIN_LAWS else "external"


def _shorthand(v):
    """``friction: coulomb`` means ``friction: {law: coulomb}``."""
    return {"law": v} if isinstance(v, str) else v


FrictionSpec = Annotated[
    Annotated[Union[tuple(Annotated[cls, Tag(tag)] for tag, cls in BUILTIN_LAWS.items())
                    + (Annotated[ExternalLawSpec, Tag("external")],)],
              Discriminator(_tag)],
    BeforeValidator(_shorthand),
]
