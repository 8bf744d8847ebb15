"""The generic component-list model format (``model: components``).

A model is a list of masses and the springs, dampers, harmonic forces and
contacts acting on them, one entry per component of :mod:`blademodel.components`.
Every numeric field takes a number or the name of an entry of ``parameters:``;
fields naming the same parameter share one symbol (``omega`` of two forces, say).
A plain number gets the component's default symbol (``m_1``, ``k_x1``, ``Delta_c``;
friction values ``mu_<contact>``).

Example::

    model: components
    name: oscillator
    parameters: {omega: 290}
    masses:   [{name: m, m: 0.085, dofs: [x]}]
    springs:  [{a: x_m, k: 1e5}]
    dampers:  [{a: x_m, c: 3.5}]
    forces:   [{mass: m, amplitude: 60, omega: omega}]
    contacts:
      - {name: c, bodies: [m, ground], gap: -1e-4, alpha: 0, k: 4e5,
         friction: {law: coulomb, mu: 0.5}}

A contact may add a normal ``damping`` (``N = k delta + damping ddelta/dt``, the
contact opening when ``N`` falls to zero), or replace ``gap`` and ``k`` by a
constant ``normal_load`` (a friction damper that never lifts off)::

      - {name: d, bodies: [m, ground], alpha: 0, normal_load: 10,
         friction: {law: jenkins, mu: 0.3, kd: 1e4}}
"""

from __future__ import annotations

from typing import Literal, Optional, Union

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from ..components import Contact, Damper, HarmonicForce, Mass, Param, Spring, coordinate_name
from ..model import Model
from .errors import FieldError
from .friction_format import FrictionSpec, NoFrictionSpec
from .values import Name, field_bound, number

#: The name of the fixed surface in ``contacts[].bodies``.
GROUND = "ground"


class _Spec(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, validate_assignment=True)


class MassSpec(_Spec):
    """A point mass; ``dofs`` are the axes it moves along."""

    name: Name
    m: number(gt=0)
    dofs: list[Literal["x", "y"]] = Field(default_factory=lambda: ["x", "y"], min_length=1, max_length=2)

    @field_validator("name")
    @classmethod
    def _name(cls, v: str) -> str:
        if not (v.isidentifier() or v.isdigit()):
            raise ValueError("a mass name must be an identifier or a number")
        if v == GROUND:
            raise ValueError(f"{GROUND!r} is reserved for the fixed surface of a contact")
        return v

    @field_validator("dofs")
    @classmethod
    def _distinct(cls, v: list) -> list:
        if len(set(v)) != len(v):
            raise ValueError("the axes must be distinct")
        return v


class SpringSpec(_Spec):
    """A linear spring on coordinate ``a`` (``x1``), to ground or to coordinate ``b``."""

    a: str
    b: Optional[str] = None
    k: number(ge=0)


class DamperSpec(_Spec):
    """A viscous damper on coordinate ``a``, to ground or to coordinate ``b``."""

    a: str
    b: Optional[str] = None
    c: number(ge=0)


class ForceSpec(_Spec):
    """``amplitude * sin(omega t + phase)`` on ``mass``, along ``angle`` from ``x``."""

    mass: Name
    amplitude: number(ge=0)
    omega: number(gt=0)
    phase: number() = 0.0
    angle: number() = 0.0


class ContactSpec(_Spec):
    """A contact between two masses, or a mass and ``ground``.

    A gapped contact gives ``gap`` and ``k`` (and optionally the normal
    ``damping``); a friction contact pressed with a constant force gives
    ``normal_load`` instead (see :class:`~blademodel.components.Contact`).
    """

    name: str
    bodies: list[Name] = Field(min_length=2, max_length=2)
    gap: number(optional=True) = None
    alpha: number()
    k: number(ge=0, optional=True) = None
    damping: number(ge=0) = 0.0
    normal_load: number(gt=0, optional=True) = None
    friction: FrictionSpec = Field(default_factory=lambda: NoFrictionSpec(law="none"))

    @field_validator("name")
    @classmethod
    def _name(cls, v: str) -> str:
        if not v.isidentifier():
            raise ValueError("a contact name must be an identifier")
        return v


class ComponentsModel(_Spec):
    """A model given as a list of components; :meth:`build` makes the :class:`Model`.

    Attributes
    ----------
    model : "components"
    name : str
        Label of the model.
    parameters : dict of str to float
        Shared parameters; a numeric field naming one becomes ``Param(name, value)``.
    masses, springs, dampers, forces, contacts : list
        The components (see the ``*Spec`` classes of this module).
    """

    model: Literal["components"] = "components"
    name: str = "model"
    parameters: dict[str, float] = Field(default_factory=dict)
    masses: list[MassSpec] = Field(min_length=1)
    springs: list[SpringSpec] = Field(default_factory=list)
    dampers: list[DamperSpec] = Field(default_factory=list)
    forces: list[ForceSpec] = Field(default_factory=list)
    contacts: list[ContactSpec] = Field(default_factory=list)

    @model_validator(mode="after")
    def _check(self):
        self._check_names()
        self._check_parameters()
        self.build()  # component-level checks, re-raised at the component's field path
        return self

    # --- validation ---------------------------------------------------------------
    def _check_names(self):
        for key in self.parameters:
            if not key.isidentifier():
                raise FieldError(("parameters", key), key, "a parameter name must be an identifier")
        masses = {}
        for i, m in enumerate(self.masses):
            if m.name in masses:
                raise FieldError(("masses", i, "name"), m.name, "duplicate mass name")
            masses[m.name] = m
        coords = [coordinate_name(d, m.name) for m in self.masses for d in m.dofs]
        for group, items in (("springs", self.springs), ("dampers", self.dampers)):
            for i, s in enumerate(items):
                for end in ("a", "b"):
                    c = getattr(s, end)
                    if c is not None and c not in coords:
                        raise FieldError((group, i, end), c, f"unknown coordinate (known: {', '.join(coords)})")
                if s.a == s.b:
                    raise FieldError((group, i, "b"), s.b, "both ends are the same coordinate")
        for i, f in enumerate(self.forces):
            if f.mass not in masses:
                raise FieldError(("forces", i, "mass"), f.mass, f"unknown mass (known: {', '.join(masses)})")
        seen = set()
        for i, c in enumerate(self.contacts):
            if c.name in seen:
                raise FieldError(("contacts", i, "name"), c.name, "duplicate contact name")
            seen.add(c.name)
            for j, b in enumerate(c.bodies):
                if b not in masses and not (j == 1 and b == GROUND):
                    known = ", ".join(list(masses) + ([GROUND] if j == 1 else []))
                    raise FieldError(("contacts", i, "bodies", j), b, f"unknown body (known: {known})")
            if c.bodies[0] == c.bodies[1]:
                raise FieldError(("contacts", i, "bodies", 1), c.bodies[1], "a body cannot touch itself")
            for f in ("gap", "k"):
                if c.normal_load is None and getattr(c, f) is None:
                    raise FieldError(("contacts", i, f), None, "Field required (or give normal_load for a "
                                                                "contact pressed with a constant force)")

    def _references(self):
        """``(loc, name, bound)`` of every numeric field that names a parameter."""
        def walk(obj, loc):
            if isinstance(obj, BaseModel):
                for key, info in type(obj).model_fields.items():
                    val = getattr(obj, key)
                    bound = field_bound(info)
                    if bound is not None and isinstance(val, str):
                        yield loc + (key,), val, bound
                    else:
                        yield from walk(val, loc + (key,))
            elif isinstance(obj, list):
                for i, item in enumerate(obj):
                    yield from walk(item, loc + (i,))
        for group in ("masses", "springs", "dampers", "forces", "contacts"):
            yield from walk(getattr(self, group), (group,))

    def _check_parameters(self):
        known = ", ".join(self.parameters) or "none declared under 'parameters:'"
        for loc, name, bound in self._references():
            if name not in self.parameters:
                raise FieldError(loc, name, f"unknown parameter (known: {known})")
            err = bound.error(self.parameters[name])
            if err is not None:
                raise FieldError(("parameters", name), self.parameters[name],
                                 f"{err.message()} (used by {'.'.join(map(str, loc))})")

    # --- build --------------------------------------------------------------------
    def _resolve(self, value: Union[float, str], default: Optional[str] = None):
        if isinstance(value, str):
            return Param(value, self.parameters[value]) if value in self.parameters else value
        return Param(default, value) if default else value

    def build(self) -> Model:
        """The :class:`~blademodel.model.Model` of these components.

        Raises
        ------
        FieldError
            If a component rejects its values (located at the component).
        """
        P = self._resolve

        def make(loc, factory, *args, **kwargs):
            try:
                return factory(*args, **kwargs)
            except (TypeError, ValueError) as e:
                raise FieldError(loc, None, str(e)) from e

        masses = {m.name: make(("masses", i), Mass, m.name, P(m.m), tuple(m.dofs))
                  for i, m in enumerate(self.masses)}
        springs = [make(("springs", i), Spring, s.a, P(s.k), s.b) for i, s in enumerate(self.springs)]
        dampers = [make(("dampers", i), Damper, d.a, P(d.c), d.b) for i, d in enumerate(self.dampers)]
        forces = [make(("forces", i), HarmonicForce, masses[f.mass], P(f.amplitude), P(f.omega),
                       P(f.phase), P(f.angle)) for i, f in enumerate(self.forces)]
        contacts = []
        for i, c in enumerate(self.contacts):
            law = make(("contacts", i, "friction"), c.friction.build, P, c.name)
            b1, b2 = c.bodies
            optional = {f: P(getattr(c, f)) for f in ("gap", "k", "normal_load") if getattr(c, f) is not None}
            contacts.append(make(("contacts", i), Contact, masses[b1], None if b2 == GROUND else masses[b2],
                                 alpha=P(c.alpha), friction=law, name=c.name, damping=P(c.damping), **optional))
        try:
            return Model(tuple(masses.values()), tuple(springs), tuple(dampers), tuple(forces),
                         tuple(contacts), name=self.name)
        except ValueError as e:
            raise FieldError((), None, str(e)) from e
