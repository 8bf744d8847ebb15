"""The derived hybrid system against the paper's equations, written here independently.

Eq. 3 (symmetric pair), Eq. 2 (per-blade values), Eq. 9 (Coulomb stick force), the
Jenkins state rates, the stick constraint for unequal masses, the mode/state
inventory, and the smooth part against ``sympy.physics.mechanics.LagrangesMethod``.
"""

from functools import cache

import pytest
import sympy as sp
from sympy.physics.mechanics import (
    LagrangesMethod,
    Point,
    ReferenceFrame,
    dynamicsymbols,
)

from blademodel import Model
from blademodel.components import Damper, HarmonicForce, Mass, Param, Spring
from blademodel.config import BladeValues
from blademodel.zheng2022 import BladePair
from blademodel.symbolic import derive


def S(name):
    return sp.Symbol(name, real=True)


t = S("t")
x1, y1, x2, y2 = S("x1"), S("y1"), S("x2"), S("y2")
vx1, vy1, vx2, vy2 = S("vx1"), S("vy1"), S("vx2"), S("vy2")
m, kx, ky, cx, cy = S("m"), S("kx"), S("ky"), S("cx"), S("cy")
F0, omega, phi1, phi2, beta = S("F0"), S("omega"), S("phi1"), S("phi2"), S("beta")
alpha, k, Delta, mu, kd, z = S("alpha"), S("k"), S("Delta"), S("mu"), S("kd"), S("z")

Q1 = F0 * sp.sin(omega * t + phi1)
Q2 = F0 * sp.sin(omega * t + phi2)
ca, sa = sp.cos(alpha), sp.sin(alpha)
n1, n2 = x1 * sa - y1 * ca, x2 * sa - y2 * ca          # Eq. 1
N_closed = k * (n1 - n2 - Delta)                         # Eq. 4
v_rel = (vx1 * ca + vy1 * sa) - (vx2 * ca + vy2 * sa)    # d/dt (r1 - r2)
Ndot_closed = k * ((vx1 * sa - vy1 * ca) - (vx2 * sa - vy2 * ca))

# Eq. 9, as printed
F_STICK_EQ9 = sp.Rational(1, 2) * (
    (Q1 - Q2) * (ca * sp.cos(beta) + sa * sp.sin(beta))
    - cx * (vx1 - vx2) * ca - cy * (vy1 - vy2) * sa
    - kx * (x1 - x2) * ca - ky * (y1 - y2) * sa)


def eq2_rhs(N, f, *, m1=m, m2=m, kx1=kx, kx2=kx, ky1=ky, ky2=ky):
    """Right sides of Eq. 2 (Eq. 3 with the defaults), ``m_i * accel`` per coordinate."""
    return {
        "x1": Q1 * sp.cos(beta) - cx * vx1 - kx1 * x1 - N * sa - f * ca,
        "y1": Q1 * sp.sin(beta) - cy * vy1 - ky1 * y1 + N * ca - f * sa,
        "x2": Q2 * sp.cos(beta) - cx * vx2 - kx2 * x2 + N * sa + f * ca,
        "y2": Q2 * sp.sin(beta) - cy * vy2 - ky2 * y2 - N * ca + f * sa,
    }


def expected_forces(friction, mode):
    """(N, f) of the paper in each mode."""
    if mode == "open":
        return sp.Integer(0), sp.Integer(0)
    N = N_closed
    if friction == "none":
        return N, sp.Integer(0)
    if friction == "bilinear":
        return N, kd * z                                 # Eq. 10
    return N, {"stick": F_STICK_EQ9, "slip+": mu * N, "slip-": -mu * N}[mode]


@cache
def system(friction, unequal=False):
    if unequal:
        return derive(BladePair(friction=friction, blade1=BladeValues(m=0.1, kx=2e5)).build())
    return derive(BladePair(friction=friction).build())


def is_zero(expr):
    return sp.simplify(sp.expand(expr)) == 0


CASES = [("coulomb", "open"), ("coulomb", "stick"), ("coulomb", "slip+"), ("coulomb", "slip-"),
         ("bilinear", "open"), ("bilinear", "stick"), ("bilinear", "slip+"), ("bilinear", "slip-"),
         ("none", "open"), ("none", "closed")]


def test_cases_cover_every_mode():
    for friction in ("coulomb", "bilinear", "none"):
        assert {m_.name for m_ in system(friction).modes} == {md for f, md in CASES if f == friction}


@pytest.mark.parametrize("friction,mode", CASES)
def test_accelerations_are_eq3(friction, mode):
    hs = system(friction)
    md = hs.mode(mode)
    N, f = expected_forces(friction, mode)
    rhs = eq2_rhs(N, f)
    assert [q.name for q in hs.q] == ["x1", "y1", "x2", "y2"]
    for q, a in zip(hs.q, md.accelerations):
        assert is_zero(m * a - rhs[q.name]), (friction, mode, q)
    assert is_zero(md.normal_forces[0] - N)
    assert is_zero(md.friction_forces[0] - f)


def test_coulomb_stick_force_is_eq9():
    md = system("coulomb").mode("stick")
    assert md.constrained == [0]
    assert sp.simplify(md.friction_forces[0] - F_STICK_EQ9) == 0


@pytest.mark.parametrize("mode", ["open", "slip+", "slip-", "stick"])
def test_unequal_blades_follow_eq2(mode):
    hs = system("coulomb", unequal=True)
    m1, m2, kx1, kx2 = S("m1"), S("m2"), S("kx1"), S("kx2")
    md = hs.mode(mode)
    N, f = expected_forces("coulomb", mode)
    if mode == "stick":
        # the constraint force for unequal masses, by hand: r1'' = (F1r - f)/m1, r2'' = (F2r + f)/m2
        F1r = (Q1 * sp.cos(beta) - cx * vx1 - kx1 * x1) * ca + (Q1 * sp.sin(beta) - cy * vy1 - ky * y1) * sa
        F2r = (Q2 * sp.cos(beta) - cx * vx2 - kx2 * x2) * ca + (Q2 * sp.sin(beta) - cy * vy2 - ky * y2) * sa
        f = (m2 * F1r - m1 * F2r) / (m1 + m2)
        assert is_zero(md.friction_forces[0] - f)
    rhs = eq2_rhs(N, f, m1=m1, m2=m2, kx1=kx1, kx2=kx2)
    masses = {"x1": m1, "y1": m1, "x2": m2, "y2": m2}
    for q, a in zip(hs.q, md.accelerations):
        assert is_zero(masses[q.name] * a - rhs[q.name]), (mode, q)


def test_unequal_blades_stick_holds_the_constraint():
    hs = system("coulomb", unequal=True)
    md = hs.mode("stick")
    acc = dict(zip([q.name for q in hs.q], md.accelerations))
    vdot = (acc["x1"] * ca + acc["y1"] * sa) - (acc["x2"] * ca + acc["y2"] * sa)
    # exact: the numerator reduces to zero modulo cos(alpha)^2 + sin(alpha)^2 = 1
    C, Sn = sp.symbols("C Sn")
    num = sp.expand(sp.fraction(sp.together(vdot))[0].xreplace({ca: C, sa: Sn}))
    assert sp.rem(num, C ** 2 + Sn ** 2 - 1, C) == 0
    # and the equal-mass Eq. 9 is not what holds here
    diff = md.friction_forces[0] - F_STICK_EQ9.subs(kx, S("kx1"))
    point = {sym: sp.Rational(i + 2, 7) for i, sym in enumerate(sorted(diff.free_symbols, key=str))}
    assert diff.xreplace(point).evalf() != 0


def test_stick_entry_projects_velocities_onto_v_zero():
    hs = system("coulomb", unequal=True)
    slip = hs.mode("slip+")
    guard = next(g for g in slip.guards if "v=0" in g.name)
    to_stick = next(tr for tr in guard.candidates if hs.modes[tr.target].name == "stick")
    u_new = [to_stick.reset[u] for u in hs.u]
    v_new = (u_new[0] * ca + u_new[1] * sa) - (u_new[2] * ca + u_new[3] * sa)
    assert sp.simplify(v_new) == 0
    # momentum along r is conserved by the (internal) impulse
    m1, m2 = S("m1"), S("m2")
    p_old = m1 * (vx1 * ca + vy1 * sa) + m2 * (vx2 * ca + vy2 * sa)
    p_new = m1 * (u_new[0] * ca + u_new[1] * sa) + m2 * (u_new[2] * ca + u_new[3] * sa)
    assert sp.simplify(p_new - p_old) == 0


@pytest.mark.parametrize("mode,rate", [("open", sp.Integer(0)), ("stick", v_rel),
                                       ("slip+", mu * Ndot_closed / kd),
                                       ("slip-", -mu * Ndot_closed / kd)])
def test_jenkins_state_rates(mode, rate):
    hs = system("bilinear")
    assert hs.s == [z]
    assert is_zero(hs.mode(mode).state_rates[0] - rate)


def test_jenkins_guards():
    hs = system("bilinear")
    stick = hs.mode("stick")
    exprs = {g.name: (g.expr, g.direction) for g in stick.guards}
    assert exprs["c: stick->slip+"][1] == -1
    assert is_zero(exprs["c: stick->slip+"][0] - (mu * N_closed - kd * z))
    assert is_zero(exprs["c: stick->slip-"][0] - (mu * N_closed + kd * z))
    slip = hs.mode("slip+")
    g = next(g for g in slip.guards if g.name == "c: slip+->stick")
    assert g.direction == -1
    assert is_zero(g.expr - (v_rel - mu * Ndot_closed / kd))
    # closing enters stick with z = 0, opening relaxes z to 0
    close = hs.mode("open").guards[0]
    assert [hs.modes[tr.target].name for tr in close.candidates] == ["stick"]
    assert close.candidates[0].reset == {z: 0}
    opening = next(g for g in stick.guards if g.name == "c: open")
    assert opening.candidates[0].reset == {z: 0}


def test_contact_guards_are_the_penetration():
    hs = system("coulomb")
    delta = n1 - n2 - Delta
    close = hs.mode("open").guards
    assert len(close) == 1 and close[0].direction == +1 and is_zero(close[0].expr - delta)
    for name in ("stick", "slip+", "slip-"):
        g = next(g for g in hs.mode(name).guards if g.name == "c: open")
        assert g.direction == -1 and is_zero(g.expr - delta)
    # closing: slip with the sign of v first, then stick if it holds, else along f
    cands = close[0].candidates
    assert [hs.modes[tr.target].name for tr in cands] == ["slip+", "slip-", "stick", "slip+", "slip-"]
    first = cands[0].condition
    assert isinstance(first, sp.StrictGreaterThan) and first.rhs == 0 and is_zero(first.lhs - v_rel)
    stick_ok = cands[2].condition          # mu N - |f_stick| >= 0, f from the stick mode
    assert isinstance(stick_ok, sp.GreaterThan)
    assert is_zero(stick_ok.lhs - stick_ok.rhs - (mu * N_closed - sp.Abs(F_STICK_EQ9)))


def test_coulomb_stick_guards_use_the_derived_force():
    hs = system("coulomb")
    g = {g.name: g for g in hs.mode("stick").guards}
    assert is_zero(g["c: stick->slip+"].expr - (mu * N_closed - F_STICK_EQ9))
    assert is_zero(g["c: stick->slip-"].expr - (mu * N_closed + F_STICK_EQ9))
    slip = hs.mode("slip-")
    vg = next(x for x in slip.guards if "v=0" in x.name)
    assert is_zero(vg.expr + v_rel) and vg.direction == -1
    assert [hs.modes[tr.target].name for tr in vg.candidates] == ["stick", "slip+"]


# --- only what the scene needs -------------------------------------------------------

def test_model_without_contact_has_one_mode_no_guards():
    hs = derive(BladePair().build(contact=False))
    assert [m_.name for m_ in hs.modes] == ["free"]
    assert hs.modes[0].guards == []
    assert hs.s == [] and hs.modes[0].state_rates == []
    assert hs.open_mode == 0


def test_coulomb_has_no_internal_state():
    hs = system("coulomb")
    assert hs.s == []
    assert all(md.state_rates == [] for md in hs.modes)
    assert kd not in hs.params and S("v_tol") not in hs.params


def test_coulomb_band_adds_only_its_tolerance():
    hs = derive(BladePair(stick="band", stick_velocity_tol=1e-3).build())
    assert S("v_tol") in hs.params and hs.s == []
    g = next(g for g in hs.mode("slip+").guards if "v=0" in g.name)
    assert is_zero(g.expr - (v_rel - S("v_tol")))


def test_frictionless_has_open_and_closed_only():
    hs = system("none")
    assert [m_.name for m_ in hs.modes] == ["open", "closed"]
    assert hs.s == [] and mu not in hs.params
    assert [g.name for g in hs.mode("closed").guards] == ["c: open"]
    assert hs.mode("closed").constrained == []


# --- smooth part against sympy.physics.mechanics --------------------------------------

def _lagrange_accelerations(coords, T, V, loads):
    """Accelerations from LagrangesMethod; ``loads`` maps a point to a force vector."""
    LM = LagrangesMethod(T - V, coords, forcelist=loads, frame=FRAME)
    LM.form_lagranges_equations()
    rhs = LM.rhs()
    return list(rhs[len(coords):])


FRAME = ReferenceFrame("Nf")


def _to_state(expr, coords, names):
    tt = dynamicsymbols._t
    rep = {}
    for c, n in zip(coords, names):
        rep[c.diff(tt)] = S("v" + n)
        rep[c] = S(n)
    return expr.xreplace(rep).xreplace({tt: t})


@pytest.mark.parametrize("closed", [False, True])
def test_smooth_modes_match_lagranges_method(closed):
    """Open mode, and the frictionless closed mode (contact spring as a potential)."""
    hs = derive(BladePair(friction="none", blade1=BladeValues(m=0.1, kx=2e5)).build())
    m1, m2, kx1, kx2 = S("m1"), S("m2"), S("kx1"), S("kx2")
    q = dynamicsymbols("x1 y1 x2 y2")
    qd = [c.diff() for c in q]
    O = Point("O")
    P1 = O.locatenew("P1", q[0] * FRAME.x + q[1] * FRAME.y)
    P2 = O.locatenew("P2", q[2] * FRAME.x + q[3] * FRAME.y)
    P1.set_vel(FRAME, qd[0] * FRAME.x + qd[1] * FRAME.y)
    P2.set_vel(FRAME, qd[2] * FRAME.x + qd[3] * FRAME.y)
    T = m1 * (qd[0] ** 2 + qd[1] ** 2) / 2 + m2 * (qd[2] ** 2 + qd[3] ** 2) / 2
    V = (kx1 * q[0] ** 2 + ky * q[1] ** 2 + kx2 * q[2] ** 2 + ky * q[3] ** 2) / 2
    if closed:
        delta = (q[0] * sa - q[1] * ca) - (q[2] * sa - q[3] * ca) - Delta
        V += k * delta ** 2 / 2
    tt = dynamicsymbols._t
    Q1t = F0 * sp.sin(omega * tt + phi1)
    Q2t = F0 * sp.sin(omega * tt + phi2)
    loads = [(P1, (Q1t * sp.cos(beta) - cx * qd[0]) * FRAME.x + (Q1t * sp.sin(beta) - cy * qd[1]) * FRAME.y),
             (P2, (Q2t * sp.cos(beta) - cx * qd[2]) * FRAME.x + (Q2t * sp.sin(beta) - cy * qd[3]) * FRAME.y)]
    acc = _lagrange_accelerations(q, T, V, loads)
    md = hs.mode("closed" if closed else "open")
    for a_lm, a, n in zip(acc, md.accelerations, ["x1", "y1", "x2", "y2"]):
        assert is_zero(_to_state(a_lm, q, ["x1", "y1", "x2", "y2"]) - a), n


def test_coupled_spring_and_damper_match_lagranges_method():
    """Two-mass chain with a coupling spring (potential) and damper (Rayleigh form)."""
    a, b = Mass("a", 2.0, dofs=("x",)), Mass("b", 3.0, dofs=("x",))
    model = Model(masses=(a, b),
                  springs=(Spring("x_a", 10.0), Spring("x_a", 4.0, b="x_b")),
                  dampers=(Damper("x_a", 0.3, b="x_b"),),
                  forces=(HarmonicForce(b, 1.5, 7.0, phase=0.2, angle=0.0),))
    hs = derive(model)
    assert [md.name for md in hs.modes] == ["free"]
    ma, mb, k1, k2, c = S("m_a"), S("m_b"), S("k_x_a"), S("k_x_a_x_b"), S("c_x_a_x_b")
    F, w, ph, bb = S("F0_b"), S("omega_b"), S("phi_b"), S("beta_b")
    qa, qb = dynamicsymbols("x_a x_b")
    tt = dynamicsymbols._t
    Pa, Pb = Point("Pa"), Point("Pb")
    Pa.set_vel(FRAME, qa.diff() * FRAME.x)
    Pb.set_vel(FRAME, qb.diff() * FRAME.x)
    T = ma * qa.diff() ** 2 / 2 + mb * qb.diff() ** 2 / 2
    V = k1 * qa ** 2 / 2 + k2 * (qa - qb) ** 2 / 2
    R = c * (qa.diff() - qb.diff()) ** 2 / 2                  # Rayleigh dissipation
    loads = [(Pa, -sp.diff(R, qa.diff()) * FRAME.x),
             (Pb, (-sp.diff(R, qb.diff()) + F * sp.sin(w * tt + ph) * sp.cos(bb)) * FRAME.x)]
    acc = _lagrange_accelerations([qa, qb], T, V, loads)
    for a_lm, a_ in zip(acc, hs.modes[0].accelerations):
        assert is_zero(_to_state(a_lm, [qa, qb], ["x_a", "x_b"]) - a_)


def test_parameter_names_cannot_shadow_state_symbols():
    m1 = Mass("1", 1.0, dofs=("x",))
    with pytest.raises(ValueError, match="t"):
        derive(Model((m1,), springs=(Spring("x1", 1.0),), dampers=(Damper("x1", Param("t", 0.5)),)))
