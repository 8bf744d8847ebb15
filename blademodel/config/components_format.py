"""The generic component-list model format (``model: components``).

A model is a list of masses and the springs, dampers, forces and contacts
acting on them, one entry per component of :mod:`blademodel.components`. A
force's ``type`` is ``harmonic`` (the default), ``constant`` or
``multiharmonic`` (several harmonics of one base frequency).
Every numeric field takes a number or the name of an entry of ``parameters:``;
fields naming the same parameter share one symbol (``omega`` of two forces, say).
A plain number gets the component's default symbol (``m_1``, ``k_x1``, ``Delta_c``;
a friction law's values ``<symbol>_<contact>``, ``mu_c``, see :mod:`.friction_format`).

Example::

    model: components
    name: oscillator
    parameters: {omega: 290}
    masses:   [{name: m, m: 0.085, dofs: [x]}]
    springs:  [{a: x_m, k: 1e5}]
    dampers:  [{a: x_m, c: 3.5}]
    forces:
      - {mass: m, amplitude: 60, omega: omega}
      - {type: constant, mass: m, value: -0.834}
      - {type: multiharmonic, mass: m, omega: omega,
         harmonics: [{order: 2, amplitude: 5}, {order: 3, amplitude: 2, phase: 0.5}]}
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

from typing import Annotated, Literal, Optional, Union

from pydantic import BaseModel, ConfigDict, Discriminator, Field, Tag, field_validator, model_validator

from ..components import (Contact, ConstantForce, Damper, Harmonic, HarmonicForce, Mass, MultiHarmonicForce, Param,
                          Spring, coordinate_name)
from ..model import Model
from .errors import FieldError, format_loc
from .friction_format import FrictionSpec, LawSpec
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


class HarmonicForceSpec(_Spec):
    """``amplitude * sin(omega t + phase)`` on ``mass``, along ``angle`` from ``x`` (``type: harmonic``, default)."""

    type: Literal["harmonic"] = "harmonic"
    mass: Name
    amplitude: number(ge=0)
    omega: number(gt=0)
    phase: number() = 0.0
    angle: number() = 0.0

    def build(self, resolve, mass: Mass) -> HarmonicForce:
        return HarmonicForce(mass, resolve(self.amplitude), resolve(self.omega), resolve(self.phase),
                             resolve(self.angle))


class ConstantForceSpec(_Spec):
    """A constant ``value`` (N, either sign) on ``mass``, along ``angle`` from ``x``: gravity, a preload."""

    type: Literal["constant"]
    mass: Name
    value: number()
    angle: number() = 0.0

    def build(self, resolve, mass: Mass) -> ConstantForce:
        return ConstantForce(mass, resolve(self.value), resolve(self.angle))


class HarmonicSpec(_Spec):
    """One term ``amplitude * sin(order omega t + phase)`` of a ``multiharmonic`` force."""

    order: int = Field(ge=1, strict=True)
    amplitude: number(ge=0)
    phase: number() = 0.0


class MultiHarmonicForceSpec(_Spec):
    """``sum amplitude_k sin(order_k omega t + phase_k)`` on ``mass``, along ``angle`` (``type: multiharmonic``)."""

    type: Literal["multiharmonic"]
    mass: Name
    omega: number(gt=0)
    harmonics: list[HarmonicSpec] = Field(min_length=1)
    angle: number() = 0.0

    @field_validator("harmonics")
    @classmethod
    def _distinct(cls, v: list) -> list:
        orders = [h.order for h in v]
        if len(set(orders)) != len(orders):
            raise ValueError(f"the harmonic orders {orders} must be distinct")
        return v

    def build(self, resolve, mass: Mass) -> MultiHarmonicForce:
        return MultiHarmonicForce(mass, resolve(self.omega),
                                  [Harmonic(h.order, resolve(h.amplitude), resolve(h.phase)) for h in self.harmonics],
                                  resolve(self.angle))


#: Force specs by the value of ``type``.
FORCE_TYPES = {"harmonic": HarmonicForceSpec, "constant": ConstantForceSpec, "multiharmonic": MultiHarmonicForceSpec}


def _force_type(v) -> str:
    return (v.get("type", "harmonic") if isinstance(v, dict) else getattr(v, "type", None)) or "harmonic"


ForceSpec = Annotated[Union[tuple(Annotated[cls, Tag(tag)] for tag, cls in FORCE_TYPES.items())],
                      Discriminator(_force_type)]


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
    friction: FrictionSpec = Field(default_factory=lambda: LawSpec(law="none"))

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

    def _symbols(self, groups: dict[str, list]):
        """``(field path, Param)`` of every parameter of the built components, their friction laws' included."""
        for group, comps in groups.items():
            for i, (spec, comp) in enumerate(zip(getattr(self, group), comps)):
                owners = [((group, i), spec, comp)]
                if isinstance(comp, Contact):
                    owners.append(((group, i, "friction"), spec.friction, comp.friction))
                for loc, owner_spec, owner in owners:
                    written = set(type(owner_spec).model_fields) | set(owner_spec.model_extra or {})
                    for key, p in owner.parameters().items():
                        yield (loc + (key,) if key in written else loc), p

    def _check_symbols(self, groups: dict[str, list]):
        """Refuse one symbol standing for two values, naming both fields (the model would say it in Python terms)."""
        seen: dict[str, tuple[float, tuple]] = {}
        for where, p in self._symbols(groups):
            value, other = seen.setdefault(p.name, (p.value, where))
            if value != p.value:
                raise FieldError(where, p.value, f"its symbol {p.name} already stands for {value} at "
                                                 f"{format_loc(other)}; declare the values under 'parameters:' "
                                                 f"and write their names in these fields")

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
        forces = [make(("forces", i), f.build, P, masses[f.mass]) for i, f in enumerate(self.forces)]
        contacts = []
        for i, c in enumerate(self.contacts):
            law = c.friction.build(self.parameters, c.name, loc=("contacts", i, "friction"))
            b1, b2 = c.bodies
            optional = {f: P(getattr(c, f)) for f in ("gap", "k", "normal_load") if getattr(c, f) is not None}
            contacts.append(make(("contacts", i), Contact, masses[b1], None if b2 == GROUND else masses[b2],
                                 alpha=P(c.alpha), friction=law, name=c.name, damping=P(c.damping), **optional))
        self._check_symbols({"masses": list(masses.values()), "springs": springs, "dampers": dampers,
                             "forces": forces, "contacts": contacts})
        try:
            return Model(tuple(masses.values()), tuple(springs), tuple(dampers), tuple(forces),
                         tuple(contacts), name=self.name)
        except ValueError as e:
            raise FieldError((), None, str(e)) from e
