"""Non-dimensional form of the equations of motion (MODEL.md section 5, the paper's Eq. 11).

The scaled equations are *derived* here, not transcribed: starting from the
dimensional accelerations of every mode (as :func:`~blademodel.symbolic.assembly.derive`
returns them), the coordinates are written as ``x_i(t) = Delta X_i(tau)`` with
``tau = omega t`` and the chain rule is applied by SymPy
(``d/dt = omega d/dtau``). Each equation of a coordinate ``c`` of mass ``m_c`` is
then divided by ``m_c Delta omega_c^2`` with ``omega_c^2 = k_c / m_c`` (``k_c`` the
grounded spring of ``c``), and the structural parameters are replaced by

.. math::

    k_c = m_c \\omega_c^2, \\qquad c_c = 2 m_c \\omega_c \\varepsilon_c .

For the paper's symmetric blade pair the result reads (x-equation of blade 1)

.. math::

    \\left(\\frac{\\omega}{\\omega_x}\\right)^2 X_1''
    + 2 \\varepsilon_1 \\frac{\\omega}{\\omega_x} X_1' + X_1
    = \\bar Q_{1x} - \\bar N_x \\sin\\alpha - \\bar f_x \\cos\\alpha ,

whereas the paper prints Eq. 11 without the two frequency ratios
(:func:`blademodel.zheng2022.eq11.paper_eq11`). Both agree only when
``omega = omega_x`` (and ``omega = omega_y`` for the y-equations);
:func:`blademodel.zheng2022.eq11.eq11_discrepancy` returns the difference.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp

from ..model import Model
from .assembly import derive
from .system import HybridSystem

__all__ = ["TAU", "ScaledSystem", "scaled_equations"]

#: Symbol of the non-dimensional time ``tau = omega t``.
TAU = sp.Symbol("tau", real=True)

_EPS_AXIS = {"x": "1", "y": "2"}


@dataclass
class ScaledSystem:
    """The non-dimensional equations of a model, per mode.

    Every equation is a :class:`sympy.Eq` in the scaled coordinates ``X_c(tau)``.
    Its left side is the structural part common to all modes,
    ``(omega/omega_c)^2 X_c'' + 2 eps_c (omega/omega_c) X_c' + X_c`` for a
    coordinate with one grounded spring and damper; its right side holds the
    excitation and the contact loads.

    Attributes
    ----------
    tau : sympy.Symbol
        The non-dimensional time ``tau = omega t``.
    length : sympy.Symbol
        The length scale (the contact gap ``Delta`` by default).
    frequency : sympy.Symbol
        The time scale's angular frequency (the excitation ``omega`` by default).
    coordinates : list of str
        Dimensional coordinate names, in model order (``"x1"``).
    functions : dict of str to sympy.Expr
        The scaled coordinate ``X_c(tau)`` of each coordinate ``c``.
    state_functions : dict of str to sympy.Expr
        The scaled internal state ``Z(tau) = z / length`` of each friction-law
        state, by the state's symbol name (``"z"``).
    omegas : dict of str to sympy.Symbol
        Natural frequency symbol of each coordinate (``omega_x``, or
        ``omega_x1`` when the blades differ).
    epsilons : dict of str to sympy.Symbol
        Damping ratio symbol of each coordinate (``epsilon1`` for ``x``,
        ``epsilon2`` for ``y``, or ``epsilon_x1`` when the blades differ);
        coordinates without a grounded damper are absent.
    definitions : dict of sympy.Symbol to sympy.Expr
        ``omega_c = sqrt(k_c / m_c)`` and ``eps_c = c_c / (2 m_c omega_c)``.
    equations : dict of str to list of sympy.Eq
        Per mode name, the scaled equation of every coordinate, fully
        substituted (normal and friction forces written in the scaled state).
    generic : list of sympy.Eq
        The scaled equations with the loads kept as symbols ``Qbar_1x``,
        ``Nbar_x``, ``fbar_x`` (the form the paper prints).
    forcing : dict of sympy.Symbol to sympy.Expr
        Definition of every ``Qbar`` symbol, a function of ``tau``.
    contact_forces : dict of str to dict
        Per mode name, the value of every ``Nbar`` and ``fbar`` symbol in the
        scaled state (zero while the contact is open).
    state_equations : dict of str to list of sympy.Eq
        Per mode name, ``Z'(tau) = ...`` for every friction-law state.
    """

    tau: sp.Symbol
    length: sp.Symbol
    frequency: sp.Symbol
    coordinates: list
    functions: dict
    state_functions: dict
    omegas: dict
    epsilons: dict
    definitions: dict
    equations: dict
    generic: list
    forcing: dict
    contact_forces: dict
    state_equations: dict = field(default_factory=dict)

    @property
    def modes(self) -> list[str]:
        """Mode names, in the order of the hybrid system."""
        return list(self.equations)

    def ratio(self, coordinate: str) -> sp.Expr:
        """``omega / omega_c``, the frequency ratio of ``coordinate``'s equation.

        Parameters
        ----------
        coordinate : str
            A dimensional coordinate name (``"x1"``).

        Returns
        -------
        sympy.Expr
        """
        return self.frequency / self.omegas[coordinate]


def _scaled_name(name: str) -> str:
    return name[0].upper() + name[1:]


def _axis_of(model: Model) -> dict[str, tuple[str, object]]:
    """``coordinate -> (axis, mass)``."""
    return {m.coordinate(d): (d, m) for m in model.masses for d in m.dofs}


def _structure(model: Model):
    """Grounded spring and damper symbols of every coordinate, and the mass symbol."""
    springs = {c: [] for c in model.coordinates}
    dampers = {c: [] for c in model.coordinates}
    for s in model.springs:
        if s.b is None:
            springs[s.a].append(s.parameters()["k"].symbol)
    for d in model.dampers:
        if d.b is None:
            dampers[d.a].append(d.parameters()["c"].symbol)
    out = {}
    for c, (axis, mass) in _axis_of(model).items():
        if len(springs[c]) != 1:
            raise ValueError(f"scaling needs exactly one grounded spring on coordinate {c!r} "
                             f"(it has {len(springs[c])}): omega_{c}^2 = k/m is undefined")
        if len(dampers[c]) > 1:
            raise ValueError(f"scaling needs at most one grounded damper on coordinate {c!r} "
                             f"(it has {len(dampers[c])})")
        out[c] = {"axis": axis, "mass": mass.name, "m": mass.parameters()["m"].symbol,
                  "k": springs[c][0], "c": dampers[c][0] if dampers[c] else None}
    return out


def _name_scales(info: dict):
    """Natural-frequency and damping-ratio symbols, shared where the blades agree."""
    omegas, epsilons = {}, {}
    for axis in ("x", "y"):
        coords = [c for c in info if info[c]["axis"] == axis]
        groups = {(info[c]["m"], info[c]["k"]) for c in coords}
        for c in coords:
            name = f"omega_{axis}" if len(groups) == 1 else f"omega_{c}"
            omegas[c] = sp.Symbol(name, positive=True)
        damped = [c for c in coords if info[c]["c"] is not None]
        egroups = {(info[c]["m"], info[c]["k"], info[c]["c"]) for c in damped}
        for c in damped:
            name = f"epsilon{_EPS_AXIS[axis]}" if len(egroups) == 1 else f"epsilon_{c}"
            epsilons[c] = sp.Symbol(name, real=True)
    return omegas, epsilons


def _identities(eq_coord: str, info: dict, omegas: dict, epsilons: dict) -> dict:
    """``k -> m omega^2`` and ``c -> 2 m omega eps`` as used in the equation of ``eq_coord``.

    A stiffness symbol shared by coordinates of different masses has one
    ``omega`` per mass; the equation of ``eq_coord`` then uses the identity of the
    coordinate on its own mass (same axis first). Every identity holds exactly by
    the definitions ``omega_c^2 = k_c/m_c``, ``eps_c = c_c/(2 m_c omega_c)``.
    """
    me = info[eq_coord]

    def pick(coords):
        if eq_coord in coords:
            return eq_coord
        for test in (lambda c: info[c]["mass"] == me["mass"],
                     lambda c: info[c]["axis"] == me["axis"]):
            hits = [c for c in coords if test(c)]
            if hits:
                return hits[0]
        return coords[0]

    by_k, by_c = {}, {}
    for c, d in info.items():
        by_k.setdefault(d["k"], []).append(c)
        if d["c"] is not None:
            by_c.setdefault(d["c"], []).append(c)
    sub = {}
    for k, coords in by_k.items():
        p = pick(coords)
        sub[k] = info[p]["m"] * omegas[p] ** 2
    for csym, coords in by_c.items():
        p = pick(coords)
        sub[csym] = 2 * info[p]["m"] * omegas[p] * epsilons[p]
    return sub


def _tidy(expr: sp.Expr) -> sp.Expr:
    """Expand, then cancel each term on its own (``m1 m2/(m1^2 + m1 m2) -> m2/(m1 + m2)``)."""
    return sp.Add(*[sp.cancel(a) for a in sp.Add.make_args(sp.expand(expr))])


def _unique_symbol(symbols: set, what: str, hint: str) -> sp.Symbol:
    if len(symbols) != 1:
        raise ValueError(f"cannot choose the {what}: found {sorted(map(str, symbols)) or 'none'}; "
                         f"pass {hint}")
    return next(iter(symbols))


def scaled_equations(system: Model | HybridSystem, *, length: sp.Symbol | None = None,
                     frequency: sp.Symbol | None = None,
                     substitutions: dict | None = None) -> ScaledSystem:
    """Derive the non-dimensional equations of every mode of a model.

    The substitution ``x_c(t) = L X_c(tau)``, ``tau = Omega t`` is applied to the
    dimensional equation ``m_c x_c'' = m_c a_c`` of each mode (``a_c`` from
    :func:`~blademodel.symbolic.assembly.derive`), SymPy carries out the chain rule, and the
    equation is divided by ``m_c L omega_c^2``. Friction-law states (the Jenkins
    stretch ``z``) are lengths and are scaled by ``L`` too.

    Parameters
    ----------
    system : Model or HybridSystem
        The model (derived on the fly) or its derived hybrid system.
    length : sympy.Symbol, optional
        Length scale ``L``; by default the gap ``Delta`` of the model's only contact.
    frequency : sympy.Symbol, optional
        Time scale ``Omega``; by default the excitation frequency shared by all
        harmonic forces.
    substitutions : dict, optional
        Applied to the dimensional equations first, e.g. ``{k: gamma*kx}`` to
        write the contact stiffness through the ratio ``gamma``.

    Returns
    -------
    ScaledSystem

    Raises
    ------
    ValueError
        If a coordinate has no (or several) grounded springs, or the scales are
        ambiguous and not given.

    Examples
    --------
    >>> from blademodel.zheng2022 import BladePair
    >>> sc = scaled_equations(BladePair().build())
    >>> sc.ratio("x1")
    omega/omega_x
    >>> sc.generic[0].rhs
    -Nbar_x*sin(alpha) + Qbar_1x - fbar_x*cos(alpha)
    """
    hs = system if isinstance(system, HybridSystem) else derive(system)
    model = hs.model
    t = hs.t
    subs0 = dict(substitutions or {})
    coords = list(model.coordinates)

    if length is None:
        length = _unique_symbol({c.parameters()["gap"].symbol for c in model.contacts if "gap" in c.parameters()},
                                "length scale (one contact gap)", "length=")
    if frequency is None:
        frequency = _unique_symbol({f.frequency.symbol for f in model.forces if f.frequency is not None},
                                   "time scale (one excitation frequency)", "frequency=")
    L, W = length, frequency

    info = _structure(model)
    omegas, epsilons = _name_scales(info)
    definitions = {}
    for c in coords:
        definitions[omegas[c]] = sp.sqrt(info[c]["k"] / info[c]["m"])
        if c in epsilons:
            definitions[epsilons[c]] = info[c]["c"] / (2 * info[c]["m"] * omegas[c])
    idents = {c: _identities(c, info, omegas, epsilons) for c in coords}

    # the scaled unknowns and the chain rule -------------------------------------
    X = {c: sp.Function(_scaled_name(c), real=True)(TAU) for c in coords}
    Z = {s: sp.Function(_scaled_name(s.name), real=True)(TAU) for s in hs.s}
    xt = {c: sp.Function(c, real=True)(t) for c in coords}
    zt = {s: sp.Function(s.name, real=True)(t) for s in hs.s}
    to_time = {**{q: xt[c] for q, c in zip(hs.q, coords)},
               **{u: xt[c].diff(t) for u, c in zip(hs.u, coords)},
               **{s: zt[s] for s in hs.s}}
    scale_map = {**{xt[c]: L * X[c].func(W * t) for c in coords},
                 **{zt[s]: L * Z[s].func(W * t) for s in hs.s}}

    def scale(expr):
        """An expression of the dimensional state (symbols) in the scaled state."""
        e = sp.sympify(expr).xreplace(subs0).xreplace(to_time)
        e = e.subs(scale_map).doit()
        return e.subs(t, TAU / W).doit()

    def divisor(c):
        return info[c]["m"] * L * omegas[c] ** 2

    acc = {c: info[c]["m"] * xt[c].diff(t, 2) for c in coords}  # m_c x_c'' before scaling

    def residual_from_time(c, rhs_state):
        e = (acc[c] - sp.sympify(rhs_state).xreplace(subs0).xreplace(to_time))
        e = e.subs(scale_map).doit().subs(t, TAU / W).doit()
        return sp.expand(e.xreplace(idents[c]) / divisor(c))

    unknowns = set(X.values()) | set(Z.values())

    def structural(expr):
        """Terms of an expanded expression that contain the scaled unknowns."""
        return sp.Add(*[a for a in sp.Add.make_args(expr) if a.has(*unknowns)])

    # structural left side, from the open (all contacts open) mode --------------------
    open_mode = hs.modes[hs.open_mode]
    lhs = {}
    for i, c in enumerate(coords):
        r = residual_from_time(c, info[c]["m"] * open_mode.accelerations[i])
        lhs[c] = structural(r)

    equations, state_equations = {}, {}
    for mode in hs.modes:
        eqs = []
        for i, c in enumerate(coords):
            r = residual_from_time(c, info[c]["m"] * mode.accelerations[i])
            eqs.append(sp.Eq(lhs[c], _tidy(lhs[c] - r)))
        equations[mode.name] = eqs
        seqs = []
        for s, rate in zip(hs.s, mode.state_rates):
            seqs.append(sp.Eq(Z[s].diff(TAU), _tidy(scale(rate) / (L * W))))
        state_equations[mode.name] = seqs

    # generic form: loads kept as symbols ---------------------------------------------
    def suffix(c):
        return omegas[c].name.split("_", 1)[1]

    Qbar = {c: sp.Symbol("Qbar_" + (f"{info[c]['mass']}{info[c]['axis']}" if info[c]["mass"].isdigit()
                                     else f"{info[c]['mass']}_{info[c]['axis']}"), real=True)
            for c in coords}
    loads = {c: sp.Integer(0) for c in coords}
    for fc in model.forces:
        for c, expr in fc.loads({}, {}, t).items():
            loads[c] += expr
    many = len(model.contacts) > 1

    def cbar(kind, j, c):
        tag = f"_{model.contacts[j].name}" if many else ""
        return sp.Symbol(f"{kind}bar_{suffix(c)}{tag}", real=True)

    Nsym, fsym = hs.normal_symbols, hs.friction_symbols
    closed = [m for m in hs.modes if all(lm != "open" for lm in m.local)]
    display = hs.generalized_forces[closed[0].name if closed else hs.modes[hs.open_mode].name]
    Qdim = sp.Symbol("_Q", real=True)
    generic = []
    forcing = {}
    for c in coords:
        F = sp.expand(display[c])
        rest = sp.expand(F - loads[c])
        if rest.has(t):
            raise ValueError(f"coordinate {c}: a time-dependent load is not a harmonic force")
        # m x'' = Q + rest(N, f), then Q -> Qbar m L omega^2, N -> Nbar m L omega^2, ...
        e = acc[c] - Qdim - rest.xreplace(subs0).xreplace(to_time)
        e = e.subs(scale_map).doit().subs(t, TAU / W).doit().xreplace(idents[c])
        rep = {Qdim: Qbar[c] * divisor(c)}
        for j in range(len(model.contacts)):
            rep[Nsym[j]] = cbar("N", j, c) * divisor(c)
            rep[fsym[j]] = cbar("f", j, c) * divisor(c)
        e = sp.expand(e.xreplace(rep) / divisor(c))
        s_part = structural(e)
        generic.append(sp.Eq(s_part, sp.expand(s_part - e)))
        forcing[Qbar[c]] = sp.expand(scale(loads[c]).xreplace(idents[c]) / divisor(c))

    contact_forces = {}
    reps = {}  # one representative coordinate per Nbar/fbar symbol
    for c in coords:
        for j in range(len(model.contacts)):
            reps.setdefault(cbar("N", j, c), (c, j, "N"))
            reps.setdefault(cbar("f", j, c), (c, j, "f"))
    for mode in hs.modes:
        vals = {}
        for sym, (c, j, kind) in reps.items():
            dim = mode.normal_forces[j] if kind == "N" else mode.friction_forces[j]
            vals[sym] = _tidy(scale(dim).xreplace(idents[c]) / divisor(c))
        contact_forces[mode.name] = vals

    return ScaledSystem(tau=TAU, length=L, frequency=W, coordinates=coords, functions=X,
                        state_functions={s.name: f for s, f in Z.items()},
                        omegas=omegas, epsilons=epsilons,
                        definitions=definitions, equations=equations, generic=generic,
                        forcing=forcing, contact_forces=contact_forces,
                        state_equations=state_equations)
