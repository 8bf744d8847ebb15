"""A shrouded bladed disk: a ring of blades with a frictional shroud contact between neighbours.

Every blade is the paper's blade (Table 1 defaults, as in the paper's pair,
:class:`blademodel.zheng2022.BladePair`); the
blades are driven by a travelling wave of engine order ``EO``, may be mistuned, and
each shroud contact may have its own gap, angle, stiffness ratio and friction.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal, Optional

import numpy as np
from pydantic import Field, field_validator, model_validator

from ..components import Contact, Damper, FrictionLaw, HarmonicForce, Mass, Param, Spring
from ..components.friction import registry
from ..model import Model
from .blade_values import BladeValues
from .strict import StrictConfig as _Strict
from .errors import FieldError
from .friction_law import check_friction_options, make_friction_law

#: Blade values that mistuning scales by ``1 + delta_i``.
STIFFNESSES = ("kx", "ky")

#: Symbol of each contact value (``gamma`` sets ``k``); a contact that overrides it gets ``<symbol>_c<n>``.
CONTACT_SYMBOLS = {"gap": "Delta", "alpha": "alpha", "gamma": "k", "mu": "mu", "kd": "kd"}


class ContactValues(_Strict):
    """Values of one shroud contact of a disk (unset values fall back to the disk's).

    ``friction_options`` unset means the disk's options if the contact uses the
    disk's law, none otherwise (the disk's options belong to the disk's law).
    """

    gap: Optional[float] = Field(None, description="initial gap Delta, m (< 0: preload)")
    alpha: Optional[float] = Field(None, description="contact angle, rad")
    gamma: Optional[float] = Field(None, ge=0, description="contact stiffness ratio k / kx")
    mu: Optional[float] = Field(None, ge=0, description="friction coefficient")
    kd: Optional[float] = Field(None, gt=0, description="Jenkins tangential stiffness, N/m")
    friction: Optional[str] = Field(None, description="friction law: a registered name or 'package.module:Class'")
    friction_options: Optional[dict[str, Any]] = Field(None, description="the law's own keyword arguments")

    @field_validator("friction")
    @classmethod
    def _known_law(cls, v: Optional[str]) -> Optional[str]:
        return v if v is None else registry.check_name(v)


class BladedDisk(_Strict):
    """``blades`` shrouded blades in a ring, 2 DOF each, with a gapped frictional contact between neighbours.

    Blades and contacts are indexed from 0 in the config and named from 1 in the
    model: blade ``i`` is mass ``"{i+1}"`` (coordinates ``x{i+1}``, ``y{i+1}``);
    contact ``i``, named ``c{i+1}``, joins blade ``i`` (its body 1) to blade
    ``(i + 1) mod N`` (body 2), so ``c{N}`` closes the ring from blade ``N`` to blade 1.

    Blade ``i`` is driven by ``F0 sin(omega t + phi_i)`` along ``beta`` with
    ``phi_i = phase0 + 2 pi EO i / N`` (a travelling wave of engine order ``EO``).
    Its stiffnesses are ``kx (1 + delta_i)`` and ``ky (1 + delta_i)``, with the
    deviations ``delta_i`` given as ``mistuning`` or drawn from
    ``numpy.random.default_rng(mistuning_seed).normal(0, mistuning_std, N)``
    (see :attr:`deviations`). ``blade_values`` overrides values of single blades
    (the mistuning scales the overridden stiffness).

    Every contact has ``k = gamma * kx`` (or ``gamma * ky``) with the tuned
    ``kx`` and the disk's ``gap``, ``alpha``, ``mu``, ``kd`` and friction law
    (see :class:`blademodel.zheng2022.BladePair` for ``friction`` and ``friction_options``) unless
    ``contacts`` overrides them for that contact.

    Symbols: a value common to all blades or contacts is one shared symbol
    (``m``, ``kx``, ``cx``, ``F0``, ``omega``, ``beta``, ``Delta``, ``alpha``, ``k``,
    ``mu``, ``kd``). A blade value set in ``blade_values`` is ``<name><n>`` for
    that blade (``m3``); mistuned stiffnesses are ``kx<n>``, ``ky<n>`` for every
    blade; phases are ``phi1`` ... ``phiN``; a contact value set in ``contacts``
    is ``<symbol>_c<n>`` for that contact (``Delta_c3``, ``k_c3`` for its gamma,
    ``mu_c3``), as is every parameter of a contact's own law (``friction`` or
    ``friction_options`` set for that contact) other than ``mu`` and ``kd``
    (``mu_s_c3``). Which names exist depends only on which fields are set, so a
    sweep over a value keeps one compiled kernel.
    """

    model: Literal["bladed_disk"] = "bladed_disk"
    blades: int = Field(24, ge=2, description="number of blades N")
    m: float = Field(0.085, gt=0, description="blade mass, kg")
    kx: float = Field(1e5, ge=0, description="tangential stiffness, N/m")
    ky: float = Field(3e6, ge=0, description="axial stiffness, N/m")
    cx: float = Field(3.5, ge=0, description="tangential damping, N s/m")
    cy: float = Field(20.0, ge=0, description="axial damping, N s/m")
    kd: float = Field(1e6, gt=0, description="Jenkins tangential stiffness, N/m")
    mu: float = Field(0.5, ge=0, description="friction coefficient")
    alpha: float = Field(math.pi / 3, description="contact angle, rad")
    beta: float = Field(math.pi / 6, description="excitation angle, rad")
    omega: float = Field(290.0, gt=0, description="excitation frequency, rad/s")
    F0: float = Field(60.0, ge=0, description="excitation amplitude, N")
    engine_order: int = Field(1, ge=0, description="engine order EO of the travelling-wave excitation")
    phase0: float = Field(math.pi / 3, description="phase of blade 0's force, rad")
    gap: float = Field(4e-5, description="initial shroud gap Delta, m (< 0: preload)")
    gamma: float = Field(4.0, ge=0, description="contact stiffness ratio k / kx")
    gamma_reference: Literal["kx", "ky"] = Field("kx", description="stiffness that gamma multiplies")
    friction: str = Field("coulomb", description="friction law: a registered name or 'package.module:Class'")
    friction_options: dict[str, Any] = Field(
        default_factory=dict, description="the friction law's own keyword arguments (besides mu, kd)")
    mistuning: Optional[list[Annotated[float, Field(gt=-1)]]] = Field(
        None, description="relative stiffness deviation delta_i of each blade (> -1)")
    mistuning_std: Optional[float] = Field(None, ge=0, description="standard deviation of random delta_i")
    mistuning_seed: int = Field(0, ge=0, description="seed of the random delta_i")
    blade_values: Optional[dict[int, BladeValues]] = Field(None, description="values of single blades, by index")
    contacts: Optional[dict[int, ContactValues]] = Field(None, description="values of single contacts, by index")

    @field_validator("blades", "engine_order", "mistuning_seed", mode="before")
    @classmethod
    def _not_bool(cls, v):
        if isinstance(v, bool):  # YAML reads `yes` as True, which int would take for 1
            raise ValueError("Input should be a valid integer, not a boolean")
        return v

    @field_validator("friction")
    @classmethod
    def _known_law(cls, v: str) -> str:
        return registry.check_name(v)

    @model_validator(mode="after")
    def _check(self):
        n = self.blades
        if self.mistuning is not None and self.mistuning_std is not None:
            raise FieldError(("mistuning_std",), self.mistuning_std,
                             "give either mistuning (one deviation per blade) or mistuning_std (a random draw), "
                             "not both")
        if self.mistuning is not None and len(self.mistuning) != n:
            raise FieldError(("mistuning",), self.mistuning,
                             f"has {len(self.mistuning)} values; blades = {n} needs one per blade")
        for name, what, table in (("blade_values", "blade", self.blade_values),
                                  ("contacts", "contact", self.contacts)):
            for i in table or {}:
                if not 0 <= i < n:
                    raise FieldError((name, i), i, f"no {what} {i}: {what}s are numbered 0..{n - 1} "
                                                   f"(blades = {n})")
        if self.mistuning_std is not None:
            dev = self.deviations
            bad = np.flatnonzero(dev <= -1)
            if bad.size:
                i = int(bad[0])
                raise FieldError(("mistuning_std",), self.mistuning_std,
                                 f"mistuning_seed = {self.mistuning_seed} draws delta_{i} = {dev[i]:.4g} <= -1 "
                                 f"(blade {i}'s stiffness would be <= 0); use a smaller mistuning_std or another seed")
        check_friction_options(self.friction_law, self.friction, self.friction_options, type(self).model_fields,
                               owner="disk")
        for i in sorted(self.contacts or {}):
            law, options = self.contact_law(i)
            check_friction_options(lambda: self.friction_law(i), law, options, ContactValues.model_fields,
                                   owner="contact", loc=("contacts", i, "friction_options"))
        self.build()  # raises ValueError on a conflict the fields cannot show (e.g. a law's own symbols)
        return self

    # --- derived values ------------------------------------------------------------------
    @property
    def k(self) -> float:
        """Normal contact stiffness ``gamma * kx`` (or ``gamma * ky``) of a contact without overrides."""
        return self.gamma * self._reference_stiffness

    @property
    def _reference_stiffness(self) -> float:
        return self.kx if self.gamma_reference == "kx" else self.ky

    @property
    def effective_omega(self) -> float:
        """Excitation frequency of the integrated system, ``omega``."""
        return self.omega

    @property
    def period(self) -> float:
        """Excitation period ``2 pi / omega``."""
        return 2 * math.pi / self.omega

    @property
    def length_scale(self) -> float:
        """Scale of the non-dimensional displacement ``X = x / gap`` (the disk's gap)."""
        return self.gap

    @property
    def mistuned(self) -> bool:
        """Whether ``mistuning`` or ``mistuning_std`` is given (then stiffnesses are per blade)."""
        return self.mistuning is not None or self.mistuning_std is not None

    @property
    def deviations(self) -> np.ndarray:
        """The relative stiffness deviations ``delta_i`` of the blades (zeros if tuned), shape ``(blades,)``."""
        if self.mistuning is not None:
            return np.array(self.mistuning, dtype=float)
        if self.mistuning_std is not None:
            return np.random.default_rng(self.mistuning_seed).normal(0.0, self.mistuning_std, self.blades)
        return np.zeros(self.blades)

    def phase(self, i: int) -> float:
        """Phase of blade ``i``'s force, ``phase0 + 2 pi EO i / N``, rad."""
        return self.phase0 + 2 * math.pi * self.engine_order * i / self.blades

    def blade_value(self, i: int, name: str) -> float:
        """Value ``name`` (``m``, ``kx``, ``ky``, ``cx``, ``cy``) of blade ``i``, mistuning included."""
        return self._blade_params(name, self.deviations)[i].value

    def contact_value(self, i: Optional[int], name: str) -> float:
        """Value ``name`` (``gap``, ``alpha``, ``gamma``, ``mu``, ``kd``) of contact ``i`` (``None``: the disk's)."""
        own = self._override(i)
        v = getattr(own, name) if own is not None else None
        return getattr(self, name) if v is None else v

    def contact_k(self, i: Optional[int]) -> float:
        """Normal stiffness of contact ``i``: its ``gamma`` times the tuned ``kx`` (or ``ky``)."""
        return self.contact_value(i, "gamma") * self._reference_stiffness

    def contact_law(self, i: Optional[int]) -> tuple[str, dict[str, Any]]:
        """``(friction, friction_options)`` of contact ``i`` (``None``: the disk's)."""
        own = self._override(i)
        law = own.friction if own is not None and own.friction is not None else self.friction
        if own is not None and own.friction_options is not None:
            return law, dict(own.friction_options)
        return law, dict(self.friction_options) if law == self.friction else {}

    def friction_law(self, contact: Optional[int] = None) -> FrictionLaw:
        """The friction law of contact ``contact`` (``None``: of a contact without overrides).

        A contact that sets its own ``friction`` or ``friction_options`` has its own
        law: its parameters other than the shared ``mu``, ``kd`` are named
        ``<symbol>_c<n>`` (``mu_s_c3``), so contacts with their own values never share
        a symbol; the disk's law and options keep the shared symbols.

        Raises
        ------
        registry.LawOptionError
            If the law rejects an option (its key is named when it can be told).
        """
        law, options = self.contact_law(contact)
        own = self._override(contact)
        own_law = own is not None and (own.friction is not None or own.friction_options is not None)
        return make_friction_law(law, options, {n: self._contact_param(contact, n) for n in ("mu", "kd")},
                                 suffix=f"c{contact + 1}" if own_law else None)

    # --- model ---------------------------------------------------------------------------
    def _override(self, i: Optional[int]) -> Optional[ContactValues]:
        return None if i is None else (self.contacts or {}).get(i)

    def _contact_param(self, i: Optional[int], name: str) -> Param:
        """Symbol of value ``name`` of contact ``i`` (for ``gamma``: the stiffness ``k``)."""
        own = self._override(i)
        symbol = CONTACT_SYMBOLS[name]
        if own is not None and getattr(own, name) is not None:
            symbol = f"{symbol}_c{i + 1}"
        return Param(symbol, self.contact_k(i) if name == "gamma" else self.contact_value(i, name))

    def _blade_params(self, name: str, deviations: np.ndarray) -> list[Param]:
        own = self.blade_values or {}
        per_blade = name in STIFFNESSES and self.mistuned
        out = []
        for i in range(self.blades):
            v = getattr(own[i], name) if i in own else None
            value = getattr(self, name) if v is None else v
            if name in STIFFNESSES:
                value = value * (1 + float(deviations[i]))
            out.append(Param(f"{name}{i + 1}" if per_blade or v is not None else name, value))
        return out

    def build(self, *, contact: bool = True) -> Model:
        """The components of the disk as a :class:`~blademodel.model.Model`.

        Parameters
        ----------
        contact : bool
            ``False`` drops the contacts (the reference system of ``P_d``).
        """
        dev = self.deviations
        sym = {n: self._blade_params(n, dev) for n in ("m", "kx", "ky", "cx", "cy")}
        F0, omega, beta = Param("F0", self.F0), Param("omega", self.omega), Param("beta", self.beta)
        masses = [Mass(str(i + 1), sym["m"][i]) for i in range(self.blades)]
        springs, dampers, forces = [], [], []
        for i, b in enumerate(masses):
            springs += [Spring(f"x{b.name}", sym["kx"][i]), Spring(f"y{b.name}", sym["ky"][i])]
            dampers += [Damper(f"x{b.name}", sym["cx"][i]), Damper(f"y{b.name}", sym["cy"][i])]
            forces.append(HarmonicForce(b, F0, omega, Param(f"phi{b.name}", self.phase(i)), beta))
        contacts = []
        if contact:
            for i in range(self.blades):
                contacts.append(Contact(masses[i], masses[(i + 1) % self.blades],
                                        gap=self._contact_param(i, "gap"), alpha=self._contact_param(i, "alpha"),
                                        k=self._contact_param(i, "gamma"), friction=self.friction_law(i),
                                        name=f"c{i + 1}"))
        return Model(tuple(masses), tuple(springs), tuple(dampers), tuple(forces), tuple(contacts),
                     name=f"bladed_disk_{self.blades}_{self.friction}")
