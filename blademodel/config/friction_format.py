"""The ``friction:`` block of a contact in the component-list format.

``law`` selects the friction law. ``coulomb``, ``bilinear`` and ``none`` have
their own fixed set of keys (:data:`BUILTIN_LAWS`). Any other value is a law
name of the registry (:mod:`blademodel.components.friction.registry`: ``iwan``,
or a name another package registers under the ``blademodel.friction_laws``
entry-point group) or the import path of a
:class:`~blademodel.components.friction.base.FrictionLaw` subclass,
``"package.module:ClassName"``; the remaining keys are passed to its constructor
as keyword arguments (a string value naming a declared parameter is passed as
that :class:`~blademodel.components.Param`)::

    friction: {law: iwan, mu: 0.5, kd: 1e6, elements: 8}
    friction: {law: "mypackage.friction:Dahl", mu: mu, sigma0: 1e7}
"""

from __future__ import annotations

from typing import Annotated, Callable, Literal, Optional, Union

from pydantic import BaseModel, BeforeValidator, ConfigDict, Discriminator, Tag, field_validator

from ..components import Coulomb, FrictionLaw, Jenkins, NoFriction, Param
from ..components.friction import registry
from .values import number

#: ``resolve(value, default_name)``: a plain number (named ``default_name`` if given)
#: or the declared parameter a string names.
Resolver = Callable[[Union[float, str], Optional[str]], Union[float, Param]]


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
    """The :class:`FrictionLaw` subclass of a registered law name or ``"package.module:ClassName"``.

    Raises
    ------
    ValueError
        If ``path`` is neither a known name nor an importable FrictionLaw subclass;
        the message lists the known names.
    """
    return registry.law_class(path)


class ExternalLawSpec(BaseModel):
    """A law by registered name or import path; the other keys are its keyword arguments."""

    model_config = ConfigDict(extra="allow", allow_inf_nan=False)

    law: str

    @field_validator("law")
    @classmethod
    def _importable(cls, v: str) -> str:
        import_law(v)
        return v

    def build(self, resolve: Resolver, contact: str) -> FrictionLaw:
        kwargs = {k: resolve(v, None) if isinstance(v, str) else v for k, v in (self.model_extra or {}).items()}
        return registry.make_law(import_law(self.law), kwargs)


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
