"""Contact between two masses (or a mass and the ground), with friction.

Three kinds of normal law, fixed by which fields are given (see :class:`Contact`):
a gapped contact spring, the same with a normal dashpot, and a constant normal
load that never lifts off.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ._sympy import sp

from .friction.base import STICK, ContactContext, FrictionLaw
from .friction.none import NoFriction
from .friction.validation import FrictionLawError, check_law
from .mass import Mass
from .parameter import Number, Param, as_param

#: The normal laws, as :attr:`Contact.normal_kind` names them.
NORMAL_KINDS = ("spring", "damped", "load")


@dataclass(frozen=True)
class Contact:
    """A contact face at angle ``alpha`` between ``body1`` and ``body2``.

    Projection (``docs/model.md`` Eq. 1), for each body ``i``::

        r_i = x_i cos(alpha) + y_i sin(alpha)     (tangential)
        n_i = x_i sin(alpha) - y_i cos(alpha)     (normal)

    An axis a body does not move on counts as zero; ``body2=None`` is the ground.
    Penetration ``delta = n1 - n2 - gap``.

    The normal force ``N`` of the closed contact follows one of three laws:

    ``spring`` (``gap``, ``k``)
        ``N = k delta``; the contact closes when ``delta`` rises through zero and
        opens when it falls through zero (``gap < 0`` is a preload). The contact
        spring stores ``k delta^2 / 2`` while closed.
    ``damped`` (``gap``, ``k`` and ``damping`` ``c_n``)
        A Kelvin-Voigt contact, ``N = k delta + c_n ddelta/dt``. A surface cannot
        pull: the contact **opens when N falls through zero**, not when ``delta``
        does (on restitution ``ddelta/dt < 0``, so ``N`` reaches zero first, with
        ``delta > 0``), and it closes again when ``N`` would become compressive
        with ``delta > 0``: the closing guard is ``k delta + c_n min(ddelta/dt, 0)``,
        whose positive set is exactly ``{delta > 0, k delta + c_n ddelta/dt > 0}``
        (an approach from ``delta < 0`` closes at ``delta = 0``, as without
        damping). This is the linear dashpot with its tension cut off (Schwager
        and Poeschel 2007): ``N >= 0`` always, so friction laws, which use this
        ``N``, never see a tensile load, and both guards are continuous functions
        of the state. The spring stores ``k max(delta, 0)^2 / 2`` in *every*
        mode (a separation at ``N = 0`` leaves ``delta > 0``), and the contact
        dissipates ``c_n (ddelta/dt)^2`` while closed and ``-k delta ddelta/dt``
        (``>= 0`` there) while open with ``delta > 0``. A law's ``Ndot`` is then
        ``k ddelta/dt + c_n d2delta/dt2``, so its friction *force* must not use
        it (none of the built-in laws does; its rates and guards may).
    ``load`` (``normal_load`` ``N0``, no ``gap``, ``k`` nor ``damping``)
        A friction contact pressed with a fixed force, ``N = N0 > 0``: it is closed
        from the start and never opens (a friction damper under a known normal
        load). ``N0`` acts on the bodies' normal coordinates like any ``N``, so
        its potential is ``N0 (n1 - n2)`` (``delta = n1 - n2``); on bodies that do not move along the
        normal only the friction feels it.

    Sign convention: ``N`` pushes body 1 along ``-n`` and body 2 along ``+n``; the
    friction force ``f`` acts on body 1 along ``-r`` and on body 2 along ``+r``
    (``docs/model.md`` Eq. 2).

    Parameters
    ----------
    body1, body2 : Mass or None
        The two bodies; ``body2=None`` makes the second surface fixed.
    gap : float or Param
        Initial gap ``Delta`` in m (any sign). Default symbol ``Delta_<name>``.
        Required unless ``normal_load`` is given (then it must be left out).
    alpha : float or Param
        Contact angle in rad. Default symbol ``alpha_<name>``.
    k : float or Param
        Normal contact stiffness in N/m, >= 0. Default symbol ``k_<name>``.
        Required unless ``normal_load`` is given (then it must be left out).
    friction : FrictionLaw
        The tangential law; :class:`NoFriction` by default.
    name : str
        Label used in mode names and default symbols.
    damping : float or Param
        Normal damping coefficient ``c_n`` in N s/m, >= 0. Default symbol
        ``cn_<name>``. The default 0 (a plain number) is the ``spring`` law,
        with the same equations and compiled code as before damping existed; a
        :class:`Param` (of any value) or a non-zero number makes it ``damped``.
    normal_load : float or Param, optional
        Constant normal force ``N0`` in N, > 0: the ``load`` law. Default symbol
        ``N0_<name>``.
    """

    body1: Mass
    body2: Mass | None
    gap: Number | None = None
    alpha: Number | None = None
    k: Number | None = None
    friction: FrictionLaw = field(default_factory=NoFriction)
    name: str = "c"
    damping: Number = 0.0
    normal_load: Number | None = None
    _p: dict = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        if not self.name.isidentifier():
            raise ValueError(f"contact name {self.name!r} must be an identifier")
        if not isinstance(self.friction, FrictionLaw):
            raise TypeError(f"contact {self.name}: friction = {self.friction!r} is not a FrictionLaw")
        try:
            check_law(self.friction)
        except FrictionLawError as e:
            raise FrictionLawError(f"contact {self.name}: {e}") from None
        if self.body2 is not None and self.body2.name == self.body1.name:
            raise ValueError(f"contact {self.name}: a body cannot touch itself ({self.body1.name})")
        n = self.name
        if self.alpha is None:
            raise ValueError(f"contact {n}: alpha (the contact angle) is required")
        p = {}
        if self.normal_load is None:
            for f in ("gap", "k"):
                if getattr(self, f) is None:
                    raise ValueError(f"contact {n}: {f} is required (or give normal_load for a contact "
                                     f"pressed with a constant force)")
            p["gap"] = as_param(self.gap, f"Delta_{n}", field=f"contact {n}: gap")
        else:
            for f in ("gap", "k"):
                if getattr(self, f) is not None:
                    raise ValueError(f"contact {n}: {f} = {getattr(self, f)!r} cannot be given with normal_load "
                                     f"(a constant-load contact has no gap or stiffness: it never opens)")
            if _given(self.damping):
                raise ValueError(f"contact {n}: damping = {self.damping!r} cannot be given with normal_load "
                                 f"(the normal force is the constant N0)")
        p["alpha"] = as_param(self.alpha, f"alpha_{n}", field=f"contact {n}: alpha")
        if self.normal_load is None:
            p["k"] = as_param(self.k, f"k_{n}", field=f"contact {n}: k", minimum=0.0)
            if _given(self.damping):
                p["damping"] = as_param(self.damping, f"cn_{n}", field=f"contact {n}: damping", minimum=0.0)
        else:
            p["normal_load"] = as_param(self.normal_load, f"N0_{n}", field=f"contact {n}: normal_load",
                                        minimum=0.0, strict=True)
        object.__setattr__(self, "_p", p)
        if self.normal_kind == "damped":
            self._check_force_without_Ndot()

    def _check_force_without_Ndot(self):
        """A damped contact's ``Ndot`` needs the accelerations, which its friction force must not need."""
        Ndot = sp.Symbol("Ndot", real=True)
        ctx = ContactContext(N=sp.Symbol("N", real=True), Ndot=Ndot, v=sp.Symbol("v", real=True),
                             f=sp.Symbol("f", real=True),
                             states={st: sp.Symbol(f"_state_{st}", real=True) for st in self.friction.states},
                             params={k: p.symbol for k, p in self.friction.parameters().items()})
        for mode in self.friction.modes:
            force = self.friction.force(mode, ctx)
            if force is not STICK and sp.sympify(force).has(Ndot):
                raise ValueError(f"contact {self.name}: damping is not supported with the "
                                 f"{type(self.friction).__name__} law, whose friction force in mode {mode!r} "
                                 f"uses Ndot (with damping dN/dt depends on the accelerations, which depend "
                                 f"on the friction force)")

    @property
    def normal_kind(self) -> str:
        """The normal law: ``"spring"``, ``"damped"`` or ``"load"`` (see the class docstring)."""
        if "normal_load" in self._p:
            return "load"
        return "damped" if "damping" in self._p else "spring"

    @property
    def bodies(self) -> tuple[Mass, ...]:
        return (self.body1,) if self.body2 is None else (self.body1, self.body2)

    @property
    def modes(self) -> tuple[str, ...]:
        """Modes of this contact: ``open`` and the friction law's closed modes."""
        return ("open",) + tuple(self.friction.modes)

    def parameters(self) -> dict[str, Param]:
        return dict(self._p)

    def _project(self, body: Mass | None, q: dict) -> tuple[sp.Expr, sp.Expr]:
        if body is None:
            return sp.Integer(0), sp.Integer(0)
        a = self._p["alpha"].symbol
        x = q[body.coordinate("x")] if body.coordinate("x") else 0
        y = q[body.coordinate("y")] if body.coordinate("y") else 0
        return x * sp.cos(a) + y * sp.sin(a), x * sp.sin(a) - y * sp.cos(a)

    def tangential(self, q: dict) -> tuple[sp.Expr, sp.Expr]:
        """``(r1, r2)`` as expressions of the coordinates ``q``."""
        return self._project(self.body1, q)[0], self._project(self.body2, q)[0]

    def normal(self, q: dict) -> tuple[sp.Expr, sp.Expr]:
        """``(n1, n2)`` as expressions of the coordinates ``q``."""
        return self._project(self.body1, q)[1], self._project(self.body2, q)[1]

    def penetration(self, q: dict) -> sp.Expr:
        """``delta = n1 - n2 - gap`` (``n1 - n2`` for a constant-load contact)."""
        n1, n2 = self.normal(q)
        gap = self._p["gap"].symbol if "gap" in self._p else 0
        return n1 - n2 - gap

    def relative_slip(self, q: dict) -> sp.Expr:
        """``r1 - r2``; its time derivative is ``v``."""
        r1, r2 = self.tangential(q)
        return r1 - r2

    # --- the normal law, in terms of delta and its time derivatives ----------------------------
    def _sym(self, key):
        return self._p[key].symbol

    def normal_force(self, delta, rate) -> sp.Expr:
        """``N`` of the closed contact from ``delta`` and ``rate = ddelta/dt``."""
        kind = self.normal_kind
        if kind == "load":
            return self._sym("normal_load")
        N = self._sym("k") * delta
        return N + self._sym("damping") * rate if kind == "damped" else N

    def normal_force_rate(self, rate, acceleration) -> sp.Expr:
        """``dN/dt`` of the closed contact (``acceleration = d2delta/dt2``, used only when damped)."""
        kind = self.normal_kind
        if kind == "load":
            return sp.Integer(0)
        Nd = self._sym("k") * rate
        return Nd + self._sym("damping") * acceleration if kind == "damped" else Nd

    def closing_guard(self, delta, rate) -> sp.Expr:
        """The open contact closes when this rises through zero."""
        kind = self.normal_kind
        if kind == "spring":
            return delta
        if kind == "load":
            return self._sym("normal_load")
        k, c = self._sym("k"), self._sym("damping")
        # k delta + c min(rate, 0), written as a Piecewise so that it differentiates
        return sp.Piecewise((k * delta + c * rate, rate < 0), (k * delta, True))

    def opening_guard(self, delta, rate) -> sp.Expr:
        """The closed contact opens when this falls through zero."""
        kind = self.normal_kind
        if kind == "spring":
            return delta
        return self.normal_force(delta, rate)

    def stored_energy(self, delta, closed: bool) -> sp.Expr:
        """Elastic energy of the normal law in a closed or open mode."""
        kind = self.normal_kind
        if kind == "load":
            return self._sym("normal_load") * delta if closed else sp.Integer(0)
        k = self._sym("k")
        if kind == "spring":
            return k * delta ** 2 / 2 if closed else sp.Integer(0)
        return k * delta ** 2 / 2 if closed else sp.Piecewise((k * delta ** 2 / 2, delta > 0), (0, True))

    def dissipation_rate(self, delta, rate, closed: bool) -> sp.Expr:
        """Power the normal law dissipates (``>= 0``) in a closed or open mode."""
        if self.normal_kind != "damped":
            return sp.Integer(0)
        if closed:
            return self._sym("damping") * rate ** 2
        return sp.Piecewise((-self._sym("k") * delta * rate, delta > 0), (0, True))


def _given(value) -> bool:
    """Whether an optional number field was set: a :class:`Param`, or a non-zero number."""
    return isinstance(value, Param) or float(value) != 0.0
