"""The paper's pair of shrouded blades as a validated config (Table 1 defaults)."""

from __future__ import annotations

import math
from typing import Any, Literal, Optional

from pydantic import Field, field_validator, model_validator

from ..components import Contact, Damper, HarmonicForce, Mass, Param, Spring
from ..components.friction import registry
from ..config.blade_values import BladeValues
from ..config.friction_law import check_friction_options, make_friction_law
from ..config.strict import StrictConfig
from ..model import Model

_Strict = StrictConfig


class BladePair(_Strict):
    """Two shrouded blades, 2 DOF each, with a gapped frictional shroud contact.

    Defaults are the paper's Table 1 with the base case of section 3.1.3
    (``gap = 4e-5`` m, ``gamma = 4``, ``F0 = 60`` N). SI units, angles in radians.
    ``k = gamma * kx`` (or ``gamma * ky`` with ``gamma_reference="ky"``).

    ``friction`` is any registered law name (``coulomb``, ``bilinear``, ``none``,
    ``iwan``, or one registered by another package under the
    ``blademodel.friction_laws`` entry points) or an import path
    ``"package.module:ClassName"``. The pair passes its own ``mu`` and ``kd`` (as the
    shared symbols ``mu``, ``kd``) to a law whose constructor takes them;
    ``friction_options`` holds the law's other keyword arguments, e.g.
    ``friction: iwan, friction_options: {elements: 8}``, checked by the law's
    constructor.
    """

    model: Literal["blade_pair"] = "blade_pair"
    m: float = Field(0.085, gt=0, description="blade mass, kg")
    kx: float = Field(1e5, ge=0, description="tangential stiffness, N/m")
    ky: float = Field(3e6, ge=0, description="axial stiffness, N/m")
    cx: float = Field(3.5, ge=0, description="tangential damping, N s/m")
    cy: float = Field(20.0, ge=0, description="axial damping, N s/m")
    kd: float = Field(1e6, gt=0, description="Jenkins tangential stiffness, N/m")
    mu: float = Field(0.5, ge=0, description="friction coefficient")
    alpha: float = Field(math.pi / 3, description="contact angle, rad")
    beta: float = Field(math.pi / 6, description="excitation angle, rad")
    phi1: float = Field(math.pi / 3, description="phase of blade 1's force, rad")
    phi2: float = Field(4 * math.pi / 3, description="phase of blade 2's force, rad")
    omega: float = Field(290.0, gt=0, description="excitation frequency, rad/s")
    F0: float = Field(60.0, ge=0, description="excitation amplitude, N")
    gap: float = Field(4e-5, description="initial shroud gap Delta, m (< 0: preload)")
    gamma: float = Field(4.0, ge=0, description="contact stiffness ratio k / kx")
    friction: str = Field("coulomb", description="friction law: a registered name or 'package.module:Class'")
    friction_options: dict[str, Any] = Field(
        default_factory=dict, description="the friction law's own keyword arguments (besides mu, kd)")
    gamma_reference: Literal["kx", "ky"] = Field("kx", description="stiffness that gamma multiplies")
    stick: Literal["exact", "band"] = Field("exact", description="Coulomb stick treatment")
    stick_velocity_tol: float = Field(1e-4, gt=0, description="band half-width, m/s (stick='band')")
    equations: Literal["derived", "eq11_as_printed"] = Field(
        "derived", description="derived: the physical model; eq11_as_printed: the paper's Eq. 11 read literally")
    blade1: Optional[BladeValues] = None
    blade2: Optional[BladeValues] = None

    @field_validator("friction")
    @classmethod
    def _known_law(cls, v: str) -> str:
        return registry.check_name(v)

    @model_validator(mode="after")
    def _check(self):
        if self.stick == "band" and self.friction != "coulomb":
            raise ValueError(f"stick='band' applies to friction='coulomb' only, not {self.friction!r}")
        check_friction_options(self.friction_law, self.friction, self.friction_options, type(self).model_fields,
                               owner="pair")
        if self.equations == "eq11_as_printed" and (self.blade1 or self.blade2):
            raise ValueError("equations='eq11_as_printed' is defined for the symmetric pair (no blade1/blade2)")
        return self

    @property
    def k(self) -> float:
        """Normal contact stiffness ``gamma * kx`` (or ``gamma * ky``)."""
        return self.gamma * (self.kx if self.gamma_reference == "kx" else self.ky)

    @property
    def effective_omega(self) -> float:
        """Excitation frequency of the integrated system (``sqrt(kx/m)`` for Eq. 11 as printed)."""
        return math.sqrt(self.kx / self.m) if self.equations == "eq11_as_printed" else self.omega

    @property
    def period(self) -> float:
        """Excitation period ``2 pi / effective_omega``."""
        return 2 * math.pi / self.effective_omega

    @property
    def length_scale(self) -> float:
        """Scale of the non-dimensional displacement ``X = x / gap``."""
        return self.gap

    def blade_value(self, blade: int, name: str) -> float:
        own = self.blade1 if blade == 1 else self.blade2
        v = getattr(own, name) if own is not None else None
        return getattr(self, name) if v is None else v

    def _symbol(self, name: str) -> callable:
        """Shared symbol ``kx`` unless the blades differ, then ``kx1``/``kx2``."""
        differs = self.blade_value(1, name) != self.blade_value(2, name)
        return lambda i: Param(f"{name}{i}" if differs else name, self.blade_value(i, name))

    def friction_law(self):
        """The friction law of the contact: ``friction`` built with ``mu``, ``kd`` and ``friction_options``.

        Raises
        ------
        registry.LawOptionError
            If the law rejects an option (its key is named when it can be told).
        """
        forced = {}
        if self.friction == "coulomb" and self.stick == "band":
            forced["stick_velocity_tol"] = Param("v_tol", self.stick_velocity_tol)
        return make_friction_law(self.friction, self.friction_options,
                                 {name: Param(name, getattr(self, name)) for name in ("mu", "kd")}, forced)

    def build(self, *, contact: bool = True) -> Model:
        """The components of the pair as a :class:`~blademodel.model.Model`.

        Parameters
        ----------
        contact : bool
            ``False`` drops the contact (the reference system of ``P_d``).
        """
        sym = {n: self._symbol(n) for n in ("m", "kx", "ky", "cx", "cy")}
        omega, my, cy = Param("omega", self.omega), None, sym["cy"]
        if self.equations == "eq11_as_printed":
            # Eq. 11 as printed, X'' + 2 eps X' + X = ..., with ' = d/dtau, is the physical
            # model in the time t' = tau / omega_x: driven at omega_x, with the axial
            # modal mass m ky/kx and axial damping cy sqrt(ky/kx) (docs: nondimensional).
            omega = Param("omega", self.effective_omega)
            my = Param("my", self.m * self.ky / self.kx)
            cy = lambda i: Param("cy", self.cy * math.sqrt(self.ky / self.kx))  # noqa: E731
        masses = [Mass(str(i), sym["m"](i), my=my) for i in (1, 2)]
        springs, dampers, forces = [], [], []
        for i, b in zip((1, 2), masses):
            springs += [Spring(f"x{i}", sym["kx"](i)), Spring(f"y{i}", sym["ky"](i))]
            dampers += [Damper(f"x{i}", sym["cx"](i)), Damper(f"y{i}", cy(i))]
            forces.append(HarmonicForce(b, Param("F0", self.F0), omega,
                                        Param(f"phi{i}", getattr(self, f"phi{i}")), Param("beta", self.beta)))
        contacts = []
        if contact:
            contacts.append(Contact(masses[0], masses[1], gap=Param("Delta", self.gap),
                                    alpha=Param("alpha", self.alpha), k=Param("k", self.k),
                                    friction=self.friction_law(), name="c"))
        return Model(tuple(masses), tuple(springs), tuple(dampers), tuple(forces), tuple(contacts),
                     name=f"blade_pair_{self.friction}")
