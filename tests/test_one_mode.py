"""One mode derived alone (``derive_mode``) and one contact's own equations (``contact_equations``).

``derive_mode`` must give the very expressions ``derive`` gives for the same mode
(it shares the code), without enumerating the product of the contacts' modes: a
24-blade ring has ``4**24`` of them, and one of its modes derives in seconds.
"""

import time
from pathlib import Path

import pytest
import sympy as sp
from sympy.physics.vector import dynamicsymbols

from blademodel.components.friction.base import STICK
from blademodel.config import load_model
from blademodel.zheng2022 import BladePair
from blademodel.symbolic import derive
from blademodel.symbolic.assembly import contact_equations, derive_mode, mode_count, parse_assignment
from blademodel.symbolic.display import definitions, equations, latex, pretty

MODELS = Path(__file__).resolve().parents[1] / "models"
ROW = MODELS / "blade_row_3.yaml"
RING = MODELS / "bladed_disk_24.yaml"


def S(name):
    return sp.Symbol(name, real=True)


@pytest.fixture(scope="module")
def row():
    return load_model(ROW)


@pytest.fixture(scope="module")
def row_system(row):
    return derive(row)


@pytest.fixture(scope="module")
def ring():
    return load_model(RING)


def assignment_of(model, mode):
    return {c.name: m for c, m in zip(model.contacts, mode.local)}


def assert_same_mode(hs, mode, ms):
    """``ms`` (derive_mode) holds exactly ``mode`` of ``hs`` (derive), guards and transitions included."""
    one = ms.mode
    assert (one.name, one.local, one.constrained) == (mode.name, mode.local, mode.constrained)
    assert one.accelerations == mode.accelerations
    assert one.state_rates == mode.state_rates
    assert one.normal_forces == mode.normal_forces
    assert one.friction_forces == mode.friction_forces
    assert ms.generalized_forces == {mode.name: hs.generalized_forces[mode.name]}
    assert [g.name for g in one.guards] == [g.name for g in mode.guards]
    for g1, g in zip(one.guards, mode.guards):
        assert (g1.expr, g1.direction, g1.contact) == (g.expr, g.direction, g.contact), g.name
        assert len(g1.candidates) == len(g.candidates), g.name
        for t1, t in zip(g1.candidates, g.candidates):
            target = hs.modes[t.target]
            assert ms.targets[t1.target] == target.local, g.name
            assert ms.target_name(t1.target) == target.name
            if len(target.constrained) <= 1:
                assert t1.condition == t.condition, (g.name, target.name)
                assert t1.reset == t.reset, (g.name, target.name)
            else:  # several stick forces: solved per group, not by one joint LUsolve
                assert same_condition(t1.condition, t.condition), (g.name, target.name)
                assert t1.reset.keys() == t.reset.keys()
                assert all(same_value(t1.reset[x], t.reset[x]) for x in t.reset), (g.name, target.name)


def same_value(a, b, points=2):
    """``a`` and ``b`` agree at a few points (to 1e-9, evaluated with 30 digits)."""
    a, b = sp.sympify(a), sp.sympify(b)
    symbols = sorted(a.free_symbols | b.free_symbols, key=str)
    for i in range(points):
        point = {x: sp.Float(sp.Rational(3 + (7 * i + 5 * n) % 11, 5 + n % 3), 30)
                 for n, x in enumerate(symbols)}
        va, vb = float(a.xreplace(point)), float(b.xreplace(point))
        if abs(va - vb) > 1e-9 * max(1.0, abs(va)):
            return False
    return True


def same_condition(a, b):
    """Two conditions of the same kind whose sides agree at a few points.

    SymPy rewrites ``Abs(f)`` (it takes constant factors out), so the stick
    force inside a condition is compared as a value, not by its form.
    """
    if a == b:
        return True
    if type(a) is not type(b) or not isinstance(a, sp.core.relational.Relational):
        return False
    return same_value(a.lhs - a.rhs, b.lhs - b.rhs)


# --- derive_mode is derive, one mode at a time ---------------------------------------------

def test_every_mode_of_the_row_is_the_derived_one(row, row_system):
    assert len(row_system.modes) == 16 == mode_count(row)
    for mode in row_system.modes:
        assert_same_mode(row_system, mode, derive_mode(row, assignment_of(row, mode)))


@pytest.mark.parametrize("friction", ["coulomb", "bilinear", "none"])
def test_every_mode_of_the_pair_is_the_derived_one(friction):
    model = BladePair(friction=friction).build()
    hs = derive(model)
    for mode in hs.modes:
        assert_same_mode(hs, mode, derive_mode(model, assignment_of(model, mode)))


def test_unnamed_contacts_are_open(row, row_system):
    ms = derive_mode(row, {"c23": "slip-"})
    assert ms.mode.name == "c12=open,c23=slip-"
    assert ms.assignment == {"c23": "slip-"} and ms.label == "c23=slip- (others open)"
    everything_open = derive_mode(row)
    assert everything_open.mode.local == ("open", "open")
    assert everything_open.label == "open (every contact)"
    assert everything_open.mode.accelerations == row_system.modes[row_system.open_mode].accelerations


def test_two_sticking_contacts_match_derive():
    """Two Coulomb contacts sticking together: derive_mode solves the 2x2 group its own way."""
    model = load_model(ROW, {"contacts.1.friction": "{law: coulomb, mu: mu}"})
    hs = derive(model)
    mode = hs.mode("c12=stick,c23=stick")
    ms = derive_mode(model, {"c12": "stick", "c23": "stick"})
    assert ms.mode.constrained == mode.constrained == [0, 1]
    for a, b in zip(ms.mode.friction_forces, mode.friction_forces):
        assert same_value(a, b)
        assert sp.count_ops(a) < sp.count_ops(b) / 5        # and much shorter
    assert not same_value(ms.mode.friction_forces[0], ms.mode.friction_forces[1])
    for a, b in zip(ms.mode.accelerations, mode.accelerations):
        assert same_value(a, b)
    for g1, g in zip(ms.mode.guards, mode.guards):
        assert g1.name == g.name and g1.direction == g.direction
        assert same_value(g1.expr, g.expr), g.name
        for t1, t in zip(g1.candidates, g.candidates):
            assert ms.targets[t1.target] == hs.modes[t.target].local
            assert same_condition(t1.condition, t.condition)
    # the modes with at most one stick force are exactly derive's
    for mode in hs.modes:
        if len(mode.constrained) <= 1:
            assert_same_mode(hs, mode, derive_mode(model, assignment_of(model, mode)))


# --- the 24-blade ring ------------------------------------------------------------------

def relative_acceleration(ms, model, name):
    """``dv/dt`` of contact ``name`` in the mode of ``ms``."""
    q = {x.name: x for x in ms.q}
    slip = next(c for c in model.contacts if c.name == name).relative_slip(q)
    return sum(sp.diff(slip, x) * a for x, a in zip(ms.q, ms.mode.accelerations))


def test_ring_mode_derives_quickly_and_holds_both_stick_constraints(ring):
    assert len(ring.contacts) == 24 and mode_count(ring) == 4 ** 24
    t0 = time.perf_counter()
    ms = derive_mode(ring, {"c1": "stick", "c2": "stick"})
    elapsed = time.perf_counter() - t0
    # one mode of 4^24 is derived, not the product: seconds on an idle machine, a little more on a loaded one
    # (10 s failed at a load of 3 on 2 cores); enumerating the modes would never end
    assert elapsed < 60, elapsed
    assert ms.mode.constrained == [0, 1]
    assert ms.label == "c1=stick,c2=stick (others open)"
    f1, f2 = ms.mode.friction_forces[:2]
    assert f1 != 0 and f2 != 0 and sp.simplify(f1 - f2) != 0
    # the joint constraint: both contacts' relative tangential accelerations vanish
    for name in ("c1", "c2"):
        assert sp.simplify(relative_acceleration(ms, ring, name)) == 0, name
    # an open contact slides freely
    assert not same_value(relative_acceleration(ms, ring, "c3"), 0)
    # guards of every contact, in contact order: 22 close guards, open + 2 law guards per sticking one
    assert len(ms.mode.guards) == 22 + 2 * 3
    assert [g.name for g in ms.mode.guards[:4]] == ["c1: open", "c1: stick->slip+", "c1: stick->slip-",
                                                    "c2: open"]
    close3 = next(g for g in ms.mode.guards if g.name == "c3: close")
    targets = [ms.target_name(t.target) for t in close3.candidates]
    assert targets[2].startswith("c1=stick,c2=stick,c3=stick,c4=open")
    # closing c3 in stick joins the c1-c2 group: the condition uses the 3-contact stick force
    cond = close3.candidates[2].condition
    assert S("f_c3") not in cond.free_symbols and S("vx2") in cond.free_symbols


def test_ring_stick_force_is_local_to_its_group(ring):
    """Two separate sticking contacts: each force reads only its own blades' loads."""
    ms = derive_mode(ring, {"c1": "stick", "c10": "stick"}, guards=False)
    f1, f10 = ms.mode.friction_forces[0], ms.mode.friction_forces[9]
    names1 = {s.name for s in f1.free_symbols}
    assert {"x1", "x2"} <= names1 and not {"x10", "x11"} & names1
    assert {"x10", "x11"} <= {s.name for s in f10.free_symbols}
    assert ms.mode.guards == []


def test_ring_all_sticking_is_a_clear_error(ring):
    every = {c.name: "stick" for c in ring.contacts}
    with pytest.raises(ValueError, match="not independent"):
        derive_mode(ring, every, guards=False)


def test_closing_a_ring_of_sticking_contacts_keeps_the_force_unresolved():
    """Three blades, c1 and c2 sticking: c3 closing in stick makes the ring rigid, its force not unique."""
    model = load_model(RING, {"blades": "3"})
    ms = derive_mode(model, {"c1": "stick", "c2": "stick"})
    close = next(g for g in ms.mode.guards if g.name == "c3: close")
    stick = close.candidates[2]
    assert ms.targets[stick.target] == ("stick", "stick", "stick")
    assert S("f_c3") in stick.condition.free_symbols
    # the velocity reset still projects onto v = 0 of every contact (implied for the third)
    u_new = {u: stick.reset[u] for u in ms.u}
    q = {x.name: x for x in ms.q}
    for c in model.contacts:
        slip = c.relative_slip(q)
        v = sum(sp.diff(slip, x) * u_new[u] for x, u in zip(ms.q, ms.u))
        assert sp.simplify(v) == 0, c.name


# --- errors --------------------------------------------------------------------------------

@pytest.mark.parametrize("assignment, needles", [
    ({"c99": "stick"}, ["no contact 'c99'", "c12, c23"]),
    ({"c12": "glide"}, ["contact c12 has no mode 'glide'", "open, stick, slip+, slip-"]),
])
def test_unknown_names_are_reported_with_the_valid_ones(row, assignment, needles):
    with pytest.raises(KeyError) as info:
        derive_mode(row, assignment)
    for needle in needles:
        assert needle in info.value.args[0]


def test_long_contact_lists_are_shortened(ring):
    with pytest.raises(KeyError, match=r"c1, c2, c3, \.\.\., c24 \(24 contacts\)"):
        derive_mode(ring, {"c25": "stick"})


@pytest.mark.parametrize("text, expected", [
    ("c12=stick,c23=open", {"c12": "stick", "c23": "open"}),
    (" c12 = slip+ ", {"c12": "slip+"}),
    ("open", {}),
])
def test_parse_assignment(text, expected):
    assert parse_assignment(text) == expected


@pytest.mark.parametrize("text, match", [("stick", "not CONTACT=MODE"), ("c12=", "not CONTACT=MODE"),
                                         ("c12=stick,c12=open", "named twice")])
def test_parse_assignment_errors(text, match):
    with pytest.raises(ValueError, match=match):
        parse_assignment(text)


# --- display of one mode -----------------------------------------------------------------------

def test_displayed_equations_of_one_mode_hold(row):
    """Substituting N_c, f_c and the accelerations makes every displayed equation hold."""
    ms = derive_mode(row, {"c12": "stick", "c23": "slip+"})
    t = dynamicsymbols._t
    back = {ms.t: t}
    for q, u in zip(ms.q, ms.u):
        back[q] = dynamicsymbols(q.name)
        back[u] = dynamicsymbols(q.name).diff(t)
    for s in ms.s:
        back[s] = dynamicsymbols(s.name)
    defs = definitions(ms, ms.mode.name)
    contact = {d.lhs: d.rhs for d in defs if d.lhs in set(ms.normal_symbols + ms.friction_symbols)}
    for i, (eq, q) in enumerate(zip(equations(ms, ms.mode.name), ms.q)):
        acc = sp.sympify(ms.mode.accelerations[i]).xreplace(back)
        residual = (eq.lhs - eq.rhs).xreplace(contact).subs(dynamicsymbols(q.name).diff(t, 2), acc)
        assert sp.simplify(residual) == 0, q


def test_pretty_of_one_mode_leaves_out_open_contacts(row):
    ms = derive_mode(row, {"c12": "stick"})
    text = pretty(ms, unicode=False)
    assert text.startswith("blade_row_3: mode c12=stick (others open)\n")
    assert "N_c12 = k*" in text and "f_c12 = " in text
    assert "N_c23 =" not in text and "f_c23 =" not in text and "z'(t)" not in text   # c23 open, z at rest
    full = definitions(ms, ms.mode.name)
    assert [d.lhs.name for d in full[:4]] == ["N_c12", "f_c12", "N_c23", "f_c23"]
    tex = latex(ms)
    assert tex.count(r"\begin{align*}") == 1 and r"\texttt{c12=stick (others open)}" in tex


# --- one contact's own equations --------------------------------------------------------------

def test_contact_equations_of_a_coulomb_contact(row):
    ce = contact_equations(row, "c12")
    assert [m.mode for m in ce.modes] == ["open", "stick", "slip+", "slip-"]
    x1, y1, x2, y2 = S("x1"), S("y1"), S("x2"), S("y2")
    alpha, Delta, k, mu = S("alpha"), S("Delta"), S("k"), S("mu")
    ca, sa = sp.cos(alpha), sp.sin(alpha)
    assert sp.expand(ce.penetration - (x1 * sa - y1 * ca - x2 * sa + y2 * ca - Delta)) == 0
    assert sp.expand(ce.slip - (x1 * ca + y1 * sa - x2 * ca - y2 * sa)) == 0
    assert ce.definitions[ce.N] == k * ce.penetration
    modes = {m.mode: m for m in ce.modes}
    assert modes["open"].friction_force == 0 and modes["open"].normal_force == 0
    assert modes["stick"].friction_force is STICK
    assert modes["slip+"].friction_force == mu * ce.N and modes["slip-"].friction_force == -mu * ce.N
    assert [g.name for g in modes["open"].guards] == ["close"]
    assert [g.name for g in modes["stick"].guards] == ["open", "stick->slip+", "stick->slip-"]
    assert modes["stick"].guards[1].expr == mu * ce.N - ce.f      # f stays the symbol: a constraint force
    assert modes["open"].guards[0].expr == ce.penetration and modes["open"].guards[0].direction == 1


def test_contact_equations_of_a_jenkins_contact(row):
    ce = contact_equations(row, "c23")
    z = S("z")
    modes = {m.mode: m for m in ce.modes}
    assert modes["stick"].rates == {z: ce.v}
    assert modes["slip+"].rates == {z: S("mu") * ce.Ndot / S("kd")}
    assert modes["open"].guards[0].candidates[0].reset == {"z": 0}


def test_contact_equations_of_the_ring_are_local(ring):
    t0 = time.perf_counter()
    ce = contact_equations(ring, "c24")
    assert time.perf_counter() - t0 < 5
    assert ce.bodies == ("24", "1")
    names = {s.name for s in ce.penetration.free_symbols}
    assert names >= {"x24", "y24", "x1", "y1"} and not names & {"x2", "x12"}


def test_contact_equations_unknown_contact(row):
    with pytest.raises(KeyError, match="no contact 'c9'; contacts are c12, c23"):
        contact_equations(row, "c9")
