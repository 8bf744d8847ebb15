"""Contact normal damping and the constant normal load, against closed-form solutions.

The damped contact opens when its normal force ``N = k delta + c ddelta/dt`` falls
to zero (``docs/components.md``). For a mass hitting a damped unilateral spring
that rule gives the coefficient of restitution of Schwager and Poeschel (2007)::

    e = exp(-zeta / s * (pi - atan(2 zeta s / (1 - 2 zeta^2)))),  s = sqrt(1 - zeta^2)

(``zeta < 1/sqrt(2)``): on ``delta(t) = v0/wd exp(-zeta w t) sin(wd t)``, ``N = 0``
at ``tan(wd t) = -2 zeta s / (1 - 2 zeta^2)``, where the rebound velocity is exactly
``-v0 exp(-zeta w t)``. The constant-load contact is Den Hartog's oscillator.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import sympy as sp
import pytest

from blademodel.components import Contact, Coulomb, HarmonicForce, Jenkins, Mass, Param, Spring
from blademodel.config import load_model
from blademodel.model import Model
from blademodel.numeric import simulate
from blademodel.numeric.energy import energy_balance
from blademodel.numeric.kernels import make_integrator
from blademodel.numeric.tangent import flow_sensitivity
from blademodel.symbolic.assembly import contact_equations, derive
from blademodel.symbolic.display import pretty_contact
from test_tangent import _differences   # central differences of the kernel's map

KERNELS = ("product", "contact")


def restitution(zeta):
    s = math.sqrt(1 - zeta ** 2)
    return math.exp(-zeta / s * (math.pi - math.atan(2 * zeta * s / (1 - 2 * zeta ** 2))))


def impact_model(m=1.0, k=1e4, zeta=0.2):
    mass = Mass("1", m, ("x",))
    c = 2 * zeta * math.sqrt(k * m)
    return Model((mass,), contacts=(Contact(mass, None, gap=0.0, alpha=math.pi / 2, k=k, damping=c),))


@pytest.mark.parametrize("kernel", KERNELS)
def test_damped_impact_loses_the_closed_form_energy(kernel):
    m, v0, zeta = 1.0, 1.0, 0.2
    model = impact_model(m=m, zeta=zeta)
    r = simulate(model, periods=1, period=0.1, steps_per_period=8000, y0={"x1": -1e-3, "vx1": v0},
                 energy=True, kernel=kernel)
    e = restitution(zeta)
    assert list(r.events["guard"]) == ["c: close", "c: open"]
    assert r.final["vx1"] == pytest.approx(-e * v0, rel=1e-9)
    # the contact's dissipation is the kinetic energy lost in the impact ...
    bal = energy_balance(model, r)
    assert bal["D_visc"] == pytest.approx((1 - e ** 2) * m * v0 ** 2 / 2, rel=1e-7)
    # ... and balances the energy change, up to the quadrature of the accumulators, which
    # shrinks with the step (1.1e-7 of the throughput at 2000 steps: the release power
    # -k delta ddelta/dt has a kink at delta = 0 inside a step).
    assert abs(bal["residual"]) < 1e-8 * bal["throughput"]


def test_damped_contact_opens_at_zero_normal_force_with_penetration_left():
    zeta, k, m = 0.3, 1e4, 1.0
    r = simulate(impact_model(m=m, k=k, zeta=zeta), periods=1, period=0.1, steps_per_period=4000,
                 y0={"x1": -1e-3, "vx1": 1.0}, kernel="contact")
    t_close, t_open = r.events["t"]
    s = math.sqrt(1 - zeta ** 2)
    wd = math.sqrt(k / m) * s
    assert t_open - t_close == pytest.approx((math.pi - math.atan(2 * zeta * s / (1 - 2 * zeta ** 2))) / wd,
                                             rel=1e-8)
    N = r.contacts["N"][:, 0]
    assert N.min() >= 0.0                     # never tensile
    i = np.searchsorted(r.t, t_open)
    assert r.y[i, r.index("x1")] > 0.0        # the surface lets go with delta > 0


def pair_like(damping=None, law=None, normal_load=None):
    """A 2-DOF mass, forced, on a preloaded inclined ground contact with friction."""
    mass = Mass("b", 0.1, ("x", "y"))
    springs = (Spring("x_b", 1e5), Spring("y_b", 2e5))
    force = HarmonicForce(mass, Param("F0", 40.0), Param("omega", 300.0), angle=0.6)
    kw = dict(alpha=0.4, friction=law or Coulomb(0.3))
    if normal_load is None:
        kw.update(gap=-2e-5, k=4e5)
        if damping is not None:
            kw["damping"] = damping
    else:
        kw["normal_load"] = normal_load
    return Model((mass,), springs, forces=(force,), contacts=(Contact(mass, None, name="c", **kw),))


@pytest.mark.slow   # a cold compile of its own structures: ~20-80 s in CI; the default run checks the same physics elsewhere
def test_zero_damping_parameter_reproduces_the_contact_spring():
    base = simulate(pair_like(), periods=4, steps_per_period=1000)
    zero = simulate(pair_like(damping=Param("cn", 0.0)), periods=4, steps_per_period=1000)
    assert pair_like(damping=0.0).structure_key() == pair_like().structure_key()   # 0.0: the same code
    assert base.counters["events"] == zero.counters["events"] > 4
    np.testing.assert_allclose(zero.final_state, base.final_state, rtol=0, atol=1e-12 * np.abs(base.y).max())


# Slow, both: a cold compile of two kernels each (~45 s in CI); the default run checks the damped contact
# against its closed-form energy loss (test_damped_impact_loses_the_closed_form_energy) on both kernels.
@pytest.mark.parametrize("law", [pytest.param(Coulomb(0.3), marks=pytest.mark.slow),
                                 pytest.param(Jenkins(0.3, 2e5), marks=pytest.mark.slow)],
                         ids=["coulomb", "jenkins"])   # jenkins: slow (a cold compile)
def test_kernels_agree_on_a_damped_friction_contact(law):
    model = pair_like(damping=30.0, law=law)
    # 4000 steps: the damped contact's dissipation converges from 1.4e-7 of the throughput at 1000
    runs = {k: simulate(model, periods=6, steps_per_period=4000, energy=True, kernel=k) for k in KERNELS}
    a, b = runs["product"], runs["contact"]
    assert a.counters["events"] > 6 and a.counters["events"] == b.counters["events"]
    scale = np.abs(a.y[:, :4]).max(axis=0)
    np.testing.assert_allclose(b.final_state[:4] / scale, a.final_state[:4] / scale, rtol=0, atol=1e-9)
    for r in runs.values():
        bal = energy_balance(model, r)
        assert bal["D_visc"] > 0 and abs(bal["residual"]) < 1e-8 * bal["throughput"]


def loaded_oscillator(law, m=1.0, k=1e4, N0=10.0):
    mass = Mass("1", m, ("x",))
    return Model((mass,), (Spring("x1", k),),
                 contacts=(Contact(mass, None, alpha=0.0, normal_load=N0, friction=law),))


@pytest.mark.parametrize("kernel", KERNELS)
def test_constant_load_coulomb_decay_is_den_hartogs(kernel):
    m, k, mu, N0, A0 = 1.0, 1e4, 0.3, 10.0, 0.01
    band = mu * N0 / k
    T = 2 * math.pi / math.sqrt(k / m)
    r = simulate(loaded_oscillator(Coulomb(mu), m, k, N0), periods=10, period=T, steps_per_period=2000,
                 y0={"x1": A0}, kernel=kernel, energy=True)
    # every half cycle is harmonic about +-band: the extremes fall at t = n T/2, 2 band apart
    x = r.y[::1000, r.index("x1")]
    n = int((A0 - band) // (2 * band)) + 1     # half cycles that slip
    expected = [(-1) ** i * (A0 - 2 * band * i) for i in range(n + 1)]
    np.testing.assert_allclose(x[:n + 1], expected, rtol=0, atol=1e-9 * A0)
    assert abs(x[n]) <= band                    # inside the stick band: it sticks there for good
    assert r.final["x1"] == pytest.approx(x[n], abs=1e-12) and r.final["vx1"] == 0.0
    bal = energy_balance(loaded_oscillator(Coulomb(mu), m, k, N0), r)
    assert bal["D_fric"] == pytest.approx(k * (A0 ** 2 - x[n] ** 2) / 2, rel=1e-9)


def test_constant_load_jenkins_loop_energy():
    """A heavy oscillator keeps its amplitude X; one steady Jenkins loop dissipates 4 mu N0 (X - mu N0 / kd)."""
    mu, N0, kd, X = 0.3, 10.0, 1e4, 1e-3
    m, k = 1e6, 1e10                            # stored energy 5e3 J: the loop (8.4e-3 J) barely decays it
    T = 2 * math.pi / math.sqrt(k / m)
    model = loaded_oscillator(Jenkins(mu, kd), m, k, N0)
    for kernel in KERNELS:
        r = simulate(model, periods=2, period=T, steps_per_period=4000, y0={"x1": X}, energy=True, kernel=kernel)
        i, j = 2000, 6000                           # t = T/2 and 3T/2: the same point of the loop
        loop = r.y[j, r.index("D_fric")] - r.y[i, r.index("D_fric")]
        amp = (abs(r.y[i, r.index("x1")]) + abs(r.y[j, r.index("x1")])) / 2
        assert loop == pytest.approx(4 * mu * N0 * (amp - mu * N0 / kd), rel=1e-6)


@pytest.mark.slow   # two cold compiles (~30 s in CI); the default run checks the constant-load contact against Den Hartog
def test_kernels_agree_on_a_constant_load_friction_contact():
    model = pair_like(normal_load=3.0)
    a, b = (simulate(model, periods=6, steps_per_period=1000, kernel=k) for k in KERNELS)
    assert a.counters["events"] > 6
    scale = np.abs(a.y[:, :4]).max(axis=0)
    np.testing.assert_allclose(b.final_state[:4] / scale, a.final_state[:4] / scale, rtol=0, atol=1e-9)


def test_symbolic_forms():
    damped = pair_like(damping=Param("cn", 30.0))
    hs = derive(damped)
    N = hs.mode("slip+").normal_forces[0]
    x, y, vx, vy = (sp.Symbol(n, real=True) for n in ("x_b", "y_b", "vx_b", "vy_b"))
    k, cn, a, gap = (sp.Symbol(n, real=True) for n in ("k_c", "cn", "alpha_c", "Delta_c"))
    delta = x * sp.sin(a) - y * sp.cos(a) - gap
    rate = vx * sp.sin(a) - vy * sp.cos(a)
    assert sp.simplify(N - (k * delta + cn * rate)) == 0
    opening = hs.mode("slip+").guards[0]
    assert opening.kind == "open" and sp.simplify(opening.expr - N) == 0
    closing = hs.mode("open").guards[0].expr
    for d, r in ((-1e-5, 0.2), (1e-5, -0.2), (1e-5, 0.2), (1e-6, -1.0)):   # k delta + c min(rate, 0)
        vals = {k: 4e5, cn: 30.0, a: 0.4, gap: 0.0, x: d / math.sin(0.4), y: 0, vx: r / math.sin(0.4), vy: 0}
        assert float(closing.subs(vals)) == pytest.approx(4e5 * d + 30.0 * min(r, 0.0))
    # Jenkins' slip rate mu Ndot / kd uses dN/dt = k ddelta/dt + c d2delta/dt2 with the mode's accelerations
    jh = derive(pair_like(damping=Param("cn", 30.0), law=Jenkins(0.3, 2e5)))
    mode = jh.mode("slip+")
    acc = dict(zip([vx, vy], mode.accelerations))
    d2 = acc[vx] * sp.sin(a) - acc[vy] * sp.cos(a)
    mu, kd = sp.Symbol("mu", real=True), sp.Symbol("kd", real=True)
    assert sp.simplify(mode.state_rates[0] - mu * (k * rate + cn * d2) / kd) == 0
    loaded = derive(pair_like(normal_load=Param("N0", 3.0)))
    assert loaded.mode("stick").normal_forces[0] == sp.Symbol("N0", real=True)
    assert all(g.expr == sp.Symbol("N0", real=True) for g in loaded.mode("stick").guards[:1])
    text = pretty_contact(contact_equations(damped, "c"), unicode=False)
    assert "N_c = c_n*deltadot_c + delta_c*k_c" in text   # display names: cn prints as c_n
    assert "N_0" in pretty_contact(contact_equations(pair_like(normal_load=Param("N0", 3.0)), "c"), unicode=False)


def test_contact_rejects_inconsistent_normal_laws():
    b = Mass("1", 1.0, ("x",))
    with pytest.raises(ValueError, match="contact c: k = 1.0 cannot be given with normal_load"):
        Contact(b, None, alpha=0.0, k=1.0, normal_load=2.0)
    with pytest.raises(ValueError, match="contact c: damping = 3.0 cannot be given with normal_load"):
        Contact(b, None, alpha=0.0, damping=3.0, normal_load=2.0)
    with pytest.raises(ValueError, match=r"contact c: normal_load = 0.0 must be > 0"):
        Contact(b, None, alpha=0.0, normal_load=0.0)
    with pytest.raises(ValueError, match=r"contact c: damping = -1.0 must be >= 0"):
        Contact(b, None, gap=0.0, alpha=0.0, k=1.0, damping=-1.0)
    with pytest.raises(ValueError, match="contact c: gap is required"):
        Contact(b, None, alpha=0.0, k=1.0)


def test_components_yaml_takes_damping_and_normal_load(tmp_path):
    text = """
model: components
name: damper
parameters: {cn: 12.0}
masses: [{name: m, m: 1.0, dofs: [x]}]
springs: [{a: x_m, k: 1e4}]
contacts:
  - {name: wall, bodies: [m, ground], gap: 1e-3, alpha: 1.5707963267948966, k: 1e5, damping: cn}
  - {name: d, bodies: [m, ground], alpha: 0, normal_load: 10, friction: {law: coulomb, mu: 0.3}}
"""
    path = tmp_path / "m.yaml"
    path.write_text(text)
    model = load_model(str(path))
    wall, d = model.contacts
    assert wall.normal_kind == "damped" and wall.parameters()["damping"] == Param("cn", 12.0)
    assert d.normal_kind == "load" and d.parameters()["normal_load"].value == 10.0
    for bad, edit, message in (
            ("normal_load: 10", "normal_load: 0", "contacts.1.normal_load = 0: Input should be greater than 0"),
            ("normal_load: 10", "normal_load: 10, k: 5", "contacts.1: contact d: k = 5.0 cannot be given with "
                                                         "normal_load"),
            ("damping: cn", "damping: -1", "contacts.0.damping = -1: Input should be greater than or equal to 0"),
            (", k: 1e5", "", "contacts.0.k: Field required (or give normal_load")):
        path.write_text(text.replace(bad, edit, 1))
        with pytest.raises(ValueError, match=re.escape(message)):
            load_model(str(path))


# Slow, each a cold compile of its own tangent (50-110 s in CI); the default run differentiates the pair's
# impacts and stick/slip in tests/test_tangent.py.
@pytest.mark.parametrize("case", [pytest.param("damped coulomb", marks=pytest.mark.slow),
                                  pytest.param("damped jenkins", marks=pytest.mark.slow),
                                  pytest.param("load coulomb", marks=pytest.mark.slow)])
def test_tangent_monodromy_equals_differences(case):
    """The product-mode kernel's tangent differentiates through the new guards (a damped contact's
    opening at ``N = 0``, its Piecewise closing guard, Jenkins' ``Ndot`` with accelerations)."""
    model = {"damped coulomb": lambda: pair_like(damping=30.0),
             "damped jenkins": lambda: pair_like(damping=30.0, law=Jenkins(0.3, 2e5)),
             "load coulomb": lambda: pair_like(normal_load=3.0)}[case]()
    ig = make_integrator(model, steps_per_period=1000, event_tol=1e-13, event_location="predicted")
    y = ig.initial_state()
    status, mode, _ = ig.advance(y, ig.mode_of(y), 0, 20)
    assert status == 0
    y = y[:ig.n_physical].copy()
    s = flow_sensitivity(ig, y, mode, 2)
    assert s.events >= 4
    J = _differences(ig, y, mode, 2)
    assert np.max(np.abs(s.monodromy - J)) < 1e-6 * np.max(np.abs(s.monodromy))


@pytest.mark.slow   # a cold compile of its own structures: ~20-80 s in CI; the default run checks the same physics elsewhere
def test_normal_load_replaces_the_preloaded_ground_contact(tmp_path):
    """``models/friction_oscillator.yaml`` presses its mass with ``normal_load: N`` (20 N); the old way, a
    ground contact with a preload (a negative gap, N = -kc Delta = 20 N), is the same oscillator, to rounding."""
    source = (Path(__file__).resolve().parents[1] / "models" / "friction_oscillator.yaml").read_text()
    old = "    normal_load: N  # constant: no gap, no contact stiffness\n"
    assert old in source
    path = tmp_path / "preloaded.yaml"
    path.write_text(source.replace(old, "    gap: -2e-5\n    k: 1e6\n"))
    loaded = load_model(str(Path(__file__).resolve().parents[1] / "models" / "friction_oscillator.yaml"))
    preload = load_model(str(path))
    assert loaded.contacts[0].normal_kind == "load"
    a, b = (simulate(m, periods=8, steps_per_period=1000) for m in (preload, loaded))
    assert a.counters["events"] == b.counters["events"] > 8
    np.testing.assert_allclose(b.y[:, :2], a.y[:, :2], rtol=0, atol=1e-12 * np.abs(a.y[:, :2]).max())


def test_damping_refuses_a_law_whose_force_uses_Ndot():
    from blademodel.components.friction.base import Candidate, FrictionLaw

    class RateFriction(FrictionLaw):
        """A (made-up) friction force proportional to dN/dt: an algebraic loop with damping."""
        modes = ("slip",)

        def parameters(self):
            return {"eta": Param("eta", 0.1)}

        def force(self, mode, ctx):
            return ctx.params["eta"] * ctx.Ndot

        def guards(self, mode, ctx):
            return []

        def entry(self, ctx):
            return [Candidate("slip")]

    b = Mass("1", 1.0, ("x",))
    Contact(b, None, gap=0.0, alpha=0.0, k=1.0, friction=RateFriction())      # fine without damping
    with pytest.raises(ValueError, match="contact c: damping is not supported with the RateFriction law, whose "
                                         "friction force in mode 'slip' uses Ndot"):
        Contact(b, None, gap=0.0, alpha=0.0, k=1.0, damping=2.0, friction=RateFriction())


@pytest.mark.slow   # a cold compile of its own structures: ~20-80 s in CI; the default run checks the same physics elsewhere
def test_two_contacts_damped_and_loaded_both_kernels(tmp_path):
    """A damped wall and a constant-load friction damper on one forced mass, from YAML: the
    per-contact kernel (the default for two contacts) and the product-mode kernel agree, and
    each balances its energy."""
    path = tmp_path / "two.yaml"
    path.write_text("""
model: components
name: two
masses: [{name: m, m: 0.1, dofs: [x, y]}]
springs: [{a: x_m, k: 1e5}, {a: y_m, k: 1.5e5}]
dampers: [{a: x_m, c: 1.0}]
forces: [{mass: m, amplitude: 40, omega: 300, angle: 0.8}]
contacts:
  - {name: wall, bodies: [m, ground], gap: 1e-4, alpha: 1.2, k: 4e5, damping: 20.0,
     friction: {law: coulomb, mu: 0.2}}
  - {name: d, bodies: [m, ground], alpha: 0.1, normal_load: 2.0, friction: {law: bilinear, mu: 0.4, kd: 5e4}}
""")
    model = load_model(str(path))
    runs = {k: simulate(model, periods=8, steps_per_period=4000, energy=True, kernel=k)
            for k in ("auto", "product")}
    a, b = runs["auto"], runs["product"]
    assert a.settings["kernel"] == "contact"
    assert {"wall: close", "wall: open"} <= set(a.events["guard"])
    scale = np.abs(a.y[:, :4]).max(axis=0)
    np.testing.assert_allclose(b.final_state[:4] / scale, a.final_state[:4] / scale, rtol=0, atol=1e-8)
    for r in runs.values():
        bal = energy_balance(model, r)
        assert bal["D_fric"] > 0 and abs(bal["residual"]) < 1e-8 * bal["throughput"]
