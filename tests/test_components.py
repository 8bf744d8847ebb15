"""One exact test per component: its loads / projections / law, and its validation."""

import math

import pytest
import sympy as sp

from blademodel import Model
from blademodel.components import (
    Contact,
    Coulomb,
    Damper,
    HarmonicForce,
    Jenkins,
    Mass,
    NoFriction,
    Param,
    Spring,
    coordinate_name,
)
from blademodel.components.friction import (
    STICK,
    Candidate,
    ContactContext,
    FrictionLaw,
    Guard,
)
from blademodel.zheng2022 import BladePair


def S(name):
    return sp.Symbol(name, real=True)


x1, y1, x2, y2 = S("x1"), S("y1"), S("x2"), S("y2")
vx1, vx2 = S("vx1"), S("vx2")
t = S("t")
Q = {c: S(c) for c in ("x1", "y1", "x2", "y2", "x_tip")}
U = {c: S("v" + c) for c in Q}


# --- Mass --------------------------------------------------------------------------

def test_mass_coordinates_and_parameter():
    m = Mass("1", 0.085)
    assert m.coordinates == ("x1", "y1")
    assert m.coordinate("y") == "y1"
    assert m.parameters()["m"] == Param("m_1", 0.085)
    assert m.parameters()["m"].symbol == S("m_1")
    tip = Mass("tip", 1.0, dofs=("x",))
    assert tip.coordinates == ("x_tip",) and tip.coordinate("y") is None
    assert coordinate_name("y", "2") == "y2" and coordinate_name("x", "tip") == "x_tip"
    assert Mass("1", Param("m", 0.1)).parameters()["m"].symbol == S("m")


def test_mass_rejects_bad_dofs_and_names():
    with pytest.raises(ValueError, match="dofs"):
        Mass("1", 1.0, dofs=("x", "z"))
    with pytest.raises(ValueError, match="dofs"):
        Mass("1", 1.0, dofs=("x", "x"))
    with pytest.raises(ValueError, match="identifier"):
        Mass("a b", 1.0)


# --- Spring, Damper ----------------------------------------------------------------

def test_spring_grounded_and_coupled():
    k = S("k_x1")
    s = Spring("x1", 3.0)
    assert s.parameters()["k"] == Param("k_x1", 3.0)
    assert s.loads(Q, U, t) == {"x1": -k * x1}
    assert s.potential_energy(Q) == k * x1 ** 2 / 2
    c = Spring("x1", Param("kc", 2.0), b="x2")
    kc = S("kc")
    loads = c.loads(Q, U, t)
    assert sp.expand(loads["x1"] + kc * (x1 - x2)) == 0
    assert sp.expand(loads["x2"] - kc * (x1 - x2)) == 0
    assert c.coordinates == ("x1", "x2")
    assert sp.expand(c.potential_energy(Q) - kc * (x1 - x2) ** 2 / 2) == 0
    # the load is minus the gradient of the potential
    for name in ("x1", "x2"):
        assert sp.expand(loads[name] + sp.diff(c.potential_energy(Q), Q[name])) == 0


def test_damper_grounded_and_coupled():
    c = S("c_x1")
    d = Damper("x1", 3.5)
    assert d.loads(Q, U, t) == {"x1": -c * vx1}
    assert d.dissipation_rate(U) == c * vx1 ** 2
    dc = Damper("x1", Param("cc", 1.0), b="x2")
    cc = S("cc")
    loads = dc.loads(Q, U, t)
    assert sp.expand(loads["x1"] + cc * (vx1 - vx2)) == 0
    assert sp.expand(loads["x2"] - cc * (vx1 - vx2)) == 0
    # dissipated power = minus the power of its loads
    power = sum(f * U[n] for n, f in loads.items())
    assert sp.expand(dc.dissipation_rate(U) + power) == 0


# --- HarmonicForce -----------------------------------------------------------------

def test_harmonic_force_projects_on_beta():
    m = Mass("1", 1.0)
    F0, w, phi, beta = S("F0"), S("omega"), S("phi1"), S("beta")
    f = HarmonicForce(m, Param("F0", 60.0), Param("omega", 290.0), Param("phi1", 1.0), Param("beta", 0.5))
    Qt = F0 * sp.sin(w * t + phi)
    assert f.magnitude(t) == Qt
    assert f.loads(Q, U, t) == {"x1": Qt * sp.cos(beta), "y1": Qt * sp.sin(beta)}
    assert set(f.parameters()) == {"amplitude", "omega", "phase", "angle"}


def test_harmonic_force_drops_missing_axis():
    tip = Mass("tip", 1.0, dofs=("x",))
    f = HarmonicForce(tip, 2.0, 3.0)
    A, w, phi, beta = S("F0_tip"), S("omega_tip"), S("phi_tip"), S("beta_tip")
    assert f.loads(Q, U, t) == {"x_tip": A * sp.sin(w * t + phi) * sp.cos(beta)}


def test_harmonic_force_needs_positive_frequency():
    with pytest.raises(ValueError, match=r"force on 1: omega = 0.0 must be > 0"):
        HarmonicForce(Mass("1", 1.0), 1.0, 0.0)


# --- Contact -----------------------------------------------------------------------

def _pair_contact(friction=None):
    b1, b2 = Mass("1", 1.0), Mass("2", 1.0)
    return Contact(b1, b2, gap=Param("Delta", 4e-5), alpha=Param("alpha", 1.0), k=Param("k", 4e5),
                   friction=friction or NoFriction())


def test_contact_projection_is_eq1():
    c = _pair_contact()
    a, D = S("alpha"), S("Delta")
    r1, r2 = c.tangential(Q)
    n1, n2 = c.normal(Q)
    assert r1 == x1 * sp.cos(a) + y1 * sp.sin(a)
    assert r2 == x2 * sp.cos(a) + y2 * sp.sin(a)
    assert n1 == x1 * sp.sin(a) - y1 * sp.cos(a)
    assert n2 == x2 * sp.sin(a) - y2 * sp.cos(a)
    assert sp.expand(c.penetration(Q) - (n1 - n2 - D)) == 0
    assert sp.expand(c.relative_slip(Q) - (r1 - r2)) == 0
    # r and n are an orthonormal pair: r^2 + n^2 = x^2 + y^2
    assert sp.simplify(r1 ** 2 + n1 ** 2 - x1 ** 2 - y1 ** 2) == 0


def test_contact_with_ground_and_missing_axes():
    tip = Mass("tip", 1.0, dofs=("x",))
    c = Contact(tip, None, gap=0.1, alpha=0.3, k=10.0, name="wall")
    a, D = S("alpha_wall"), S("Delta_wall")
    assert c.tangential(Q) == (Q["x_tip"] * sp.cos(a), 0)
    assert c.normal(Q) == (Q["x_tip"] * sp.sin(a), 0)
    assert c.penetration(Q) == Q["x_tip"] * sp.sin(a) - D
    assert c.bodies == (tip,)
    assert set(c.parameters()) == {"gap", "alpha", "k"}


def test_contact_modes_and_validation():
    assert _pair_contact().modes == ("open", "closed")
    assert _pair_contact(Coulomb()).modes == ("open", "stick", "slip+", "slip-")
    assert _pair_contact(Jenkins()).modes == ("open", "stick", "slip+", "slip-")
    b = Mass("1", 1.0)
    with pytest.raises(ValueError, match="cannot touch itself"):
        Contact(b, b, 0.0, 0.0, 1.0)
    with pytest.raises(TypeError, match="not a FrictionLaw"):
        Contact(b, None, 0.0, 0.0, 1.0, friction="coulomb")
    with pytest.raises(ValueError, match=r"contact c: k = -1.0 must be >= 0"):
        Contact(b, None, 0.0, 0.0, -1.0)


# --- friction laws -----------------------------------------------------------------

N, Nd, v, f, z = S("N"), S("Ndot"), S("v"), S("f"), S("z")
mu, kd, vtol = S("mu"), S("kd"), S("v_tol")


def ctx(law: FrictionLaw) -> ContactContext:
    params = {name: p.symbol for name, p in law.parameters().items()}
    return ContactContext(N=N, Ndot=Nd, v=v, f=f, states={s: S(s) for s in law.states}, params=params)


def _guards(law, mode):
    return [(g.expr, g.direction, [(c.mode, c.when, dict(c.reset)) for c in g.candidates])
            for g in law.guards(mode, ctx(law))]


def test_coulomb_force_per_mode():
    law = Coulomb(mu=0.5)
    assert law.states == () and law.modes == ("stick", "slip+", "slip-")
    assert law.parameters() == {"mu": Param("mu", 0.5)}
    c = ctx(law)
    assert law.force("slip+", c) == mu * N
    assert law.force("slip-", c) == -mu * N
    assert law.force("stick", c) is STICK
    assert all(law.rates(md, c) == {} for md in law.modes)
    assert law.exit_reset(c) == {} and law.stored_energy(c) == 0


def test_coulomb_guards():
    law = Coulomb()
    holds = mu * N - sp.Abs(f) >= 0
    assert _guards(law, "stick") == [(mu * N - f, -1, [("slip+", sp.true, {})]),
                                     (mu * N + f, -1, [("slip-", sp.true, {})])]
    assert _guards(law, "slip+") == [(v, -1, [("stick", holds, {}), ("slip-", sp.true, {})])]
    assert _guards(law, "slip-") == [(-v, -1, [("stick", holds, {}), ("slip+", sp.true, {})])]
    # the stick condition reads |f| <= mu N
    assert holds.subs({mu: 0.5, N: 10, f: -5}) == sp.true
    assert holds.subs({mu: 0.5, N: 10, f: 5.01}) == sp.false


def test_coulomb_velocity_band():
    law = Coulomb(stick_velocity_tol=1e-4)
    assert law.parameters()["stick_velocity_tol"] == Param("v_tol", 1e-4)
    assert [g[0] for g in _guards(law, "slip+")] == [v - vtol]
    assert [g[0] for g in _guards(law, "slip-")] == [-v - vtol]
    assert Coulomb().structure() != law.structure()
    assert Coulomb(mu=0.1).structure() == Coulomb(mu=0.9).structure()


def test_coulomb_entry_candidates():
    law = Coulomb()
    got = [(c.mode, c.when, dict(c.reset)) for c in law.entry(ctx(law))]
    assert got == [("slip+", sp.StrictGreaterThan(v, 0), {}),
                   ("slip-", sp.StrictLessThan(v, 0), {}),
                   ("stick", mu * N - sp.Abs(f) >= 0, {}),
                   ("slip+", sp.StrictGreaterThan(f, 0), {}),
                   ("slip-", sp.true, {})]


def test_jenkins_force_rates_energy():
    law = Jenkins(mu=0.5, kd=1e6)
    assert law.states == ("z",)
    assert set(law.parameters()) == {"mu", "kd"}
    c = ctx(law)
    for md in law.modes:
        assert law.force(md, c) == kd * z                     # Eq. 10 in every mode
    assert law.rates("stick", c) == {"z": v}
    assert law.rates("slip+", c) == {"z": mu * Nd / kd}
    assert law.rates("slip-", c) == {"z": -mu * Nd / kd}
    assert law.open_rates(c) == {}
    assert law.exit_reset(c) == {"z": 0}
    assert law.stored_energy(c) == kd * z ** 2 / 2
    # the stick rate keeps the friction power equal to the spring's power: f v = dE/dt
    assert sp.expand(law.force("stick", c) * v - sp.diff(law.stored_energy(c), z) * v) == 0


def test_jenkins_guards_and_entry():
    law = Jenkins()
    assert _guards(law, "stick") == [(mu * N - kd * z, -1, [("slip+", sp.true, {})]),
                                     (mu * N + kd * z, -1, [("slip-", sp.true, {})])]
    assert _guards(law, "slip+") == [(v - mu * Nd / kd, -1, [("stick", sp.true, {})])]
    g = _guards(law, "slip-")
    assert len(g) == 1 and sp.expand(g[0][0] - (-(v + mu * Nd / kd))) == 0
    assert g[0][1:] == (-1, [("stick", sp.true, {})])
    entry = law.entry(ctx(law))
    assert [(c.mode, c.when, dict(c.reset)) for c in entry] == [("stick", sp.true, {"z": 0})]


def test_no_friction_law():
    law = NoFriction()
    c = ctx(law)
    assert law.modes == ("closed",) and law.states == () and law.parameters() == {}
    assert law.force("closed", c) == 0
    assert law.guards("closed", c) == []
    assert [(x.mode, x.when) for x in law.entry(c)] == [("closed", sp.true)]


def test_guard_and_candidate_are_plain_data():
    g = Guard(v, -1, [Candidate("stick")], "x")
    assert g.candidates[0].when == sp.true and dict(g.candidates[0].reset) == {}


@pytest.mark.parametrize("make,match", [
    (lambda: Jenkins(kd=0.0), r"friction: kd = 0.0 must be > 0"),
    (lambda: Coulomb(mu=-0.1), r"friction: mu = -0.1 must be >= 0"),
    (lambda: Coulomb(stick_velocity_tol=-1.0), r"friction: stick_velocity_tol = -1.0 must be >= 0"),
])
def test_friction_parameter_validation(make, match):
    with pytest.raises(ValueError, match=match):
        make()


# --- parameter validation ----------------------------------------------------------

@pytest.mark.parametrize("make,field,value", [
    (lambda: Mass("1", -1.0), "mass 1: m", "-1.0"),
    (lambda: Mass("1", 0.0), "mass 1: m", "0.0"),
    (lambda: Spring("x1", -5.0), "spring on x1: k", "-5.0"),
    (lambda: Damper("y2", -0.5), "damper on y2: c", "-0.5"),
])
def test_out_of_range_value_names_field_and_value(make, field, value):
    with pytest.raises(ValueError) as err:
        make()
    assert field in str(err.value) and value in str(err.value)


def test_non_finite_param_names_parameter_and_value():
    with pytest.raises(ValueError, match=r"parameter kx = inf is not finite"):
        Param("kx", math.inf)
    with pytest.raises(ValueError, match=r"parameter m = nan is not finite"):
        Param("m", float("nan"))


@pytest.mark.parametrize("make,field", [
    (lambda: Mass("1", float("nan")), "mass 1: m"),
    (lambda: Spring("x1", math.inf), "spring on x1: k"),
])
def test_non_finite_value_names_field(make, field):
    with pytest.raises(ValueError) as err:
        make()
    assert field in str(err.value)


def test_non_finite_value_is_rejected():
    for make in (lambda: Mass("1", float("nan")), lambda: Spring("x1", math.inf),
                 lambda: Contact(Mass("1", 1.0), None, math.nan, 0.0, 1.0)):
        with pytest.raises(ValueError, match=r"(nan|inf) is not finite"):
            make()


def test_model_rejects_one_param_with_two_values():
    m = Mass("1", 1.0)
    with pytest.raises(ValueError, match=r"parameter k is shared with two values: 1.0 and 2.0"):
        Model((m,), springs=(Spring("x1", Param("k", 1.0)), Spring("y1", Param("k", 2.0))))
    # the same value is one shared symbol
    model = Model((m,), springs=(Spring("x1", Param("k", 1.0)), Spring("y1", Param("k", 1.0))))
    assert model.parameters == {"m_1": 1.0, "k": 1.0}


def test_model_rejects_unknown_coordinates_and_masses():
    m = Mass("1", 1.0)
    with pytest.raises(ValueError, match="'x2'"):
        Model((m,), springs=(Spring("x2", 1.0),))
    with pytest.raises(ValueError, match="not in the model"):
        Model((m,), forces=(HarmonicForce(Mass("2", 1.0), 1.0, 1.0),))
    with pytest.raises(ValueError, match="unique"):
        Model((m, Mass("1", 2.0)))


def test_blade_pair_config_names_field_and_value():
    from pydantic import ValidationError
    with pytest.raises(ValidationError) as err:
        BladePair(m=-1)
    text = str(err.value)
    assert "m\n" in text and "input_value=-1" in text
    with pytest.raises(ValidationError, match="finite"):
        BladePair(kx=float("nan"))
    with pytest.raises(ValidationError, match="band"):
        BladePair(friction="bilinear", stick="band")


def test_spring_and_damper_cannot_join_a_coordinate_to_itself():
    with pytest.raises(ValueError, match="joins 'x1' to itself"):
        Spring("x1", 1.0, b="x1")
    with pytest.raises(ValueError, match="joins 'x1' to itself"):
        Damper("x1", 1.0, b="x1")


def test_structure_key_ignores_values_not_structure():
    assert BladePair(gamma=4.0).build().structure_key() == BladePair(gamma=5.0, mu=0.2).build().structure_key()
    assert BladePair(friction="coulomb").build().structure_key() != \
        BladePair(friction="bilinear").build().structure_key()
    assert BladePair().build().structure_key() != BladePair(stick="band").build().structure_key()
