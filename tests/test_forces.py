"""Constant forces, phased harmonic forces and several harmonics, against exact linear solutions on both kernels."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from numpy.testing import assert_allclose
from scipy.linalg import expm

from blademodel.analysis.periodicity import poincare_period
from blademodel.components import (
    ConstantForce,
    Contact,
    Damper,
    Harmonic,
    HarmonicForce,
    Mass,
    MultiHarmonicForce,
    NoFriction,
    Param,
    Spring,
)
from blademodel.config import config_from_data
from blademodel.config.errors import ConfigError
from blademodel.model import Model
from blademodel.numeric import excitation_period, simulate
from blademodel.numeric.contact_tables import NumericTables, derive_tables
from blademodel.symbolic import derive


def S(name):
    return sp.Symbol(name, real=True)


t = S("t")


# --- symbolic: each force's loads ---------------------------------------------------------------------------

def test_constant_force_loads_and_default_names():
    m2 = Mass("1", 2.0)
    f = ConstantForce(m2, -19.6, angle=Param("beta", 0.5))
    assert f.loads({}, {}, t) == {"x1": S("F_1") * sp.cos(S("beta")), "y1": S("F_1") * sp.sin(S("beta"))}
    assert ConstantForce(m2, 1.0).parameters()["angle"].name == "beta_F_1"
    assert f.frequency is None and f.parameters()["value"].value == -19.6
    on_x = ConstantForce(Mass("tip", 1.0, dofs=("y",)), 3.0, angle=math.pi / 2)
    assert set(on_x.loads({}, {}, t)) == {"y_tip"}          # no x axis: the x component is dropped


def test_multiharmonic_loads_are_the_sum_of_their_terms():
    m = Mass("1", 1.0)
    f = MultiHarmonicForce(m, Param("omega", 3.0), [(1, 2.0, 0.1), Harmonic(3, Param("A3", 0.5), Param("p3", 1.2))],
                           angle=Param("beta", 0.4))
    w, b = S("omega"), S("beta")
    Q = S("F1_1") * sp.sin(w * t + S("phi1_1")) + S("A3") * sp.sin(3 * w * t + S("p3"))
    loads = f.loads({}, {}, t)
    assert sp.expand(loads["x1"] - Q * sp.cos(b)) == 0 and sp.expand(loads["y1"] - Q * sp.sin(b)) == 0
    assert f.orders == (1, 3) and f.frequency.name == "omega"
    one = MultiHarmonicForce(m, Param("omega", 3.0), [(1, Param("F0", 2.0), Param("phi", 0.1))],
                             angle=Param("beta", 0.4))
    same = HarmonicForce(m, Param("F0", 2.0), Param("omega", 3.0), Param("phi", 0.1), Param("beta", 0.4))
    assert one.loads({}, {}, t) == same.loads({}, {}, t)       # one harmonic of order 1 is a HarmonicForce


@pytest.mark.parametrize("harmonics, match", [
    ([], "harmonics is empty"),
    ([(0, 1.0)], "order = 0 must be an integer >= 1"),
    ([(1.5, 1.0)], "order = 1.5 must be an integer >= 1"),
    ([(True, 1.0)], "order = True"),
    ([(2, 1.0), (2, 3.0)], "order 2 is given twice"),
    ([(2, -1.0)], "harmonic 2 amplitude = -1.0 must be >= 0"),
])
def test_multiharmonic_rejects_bad_terms(harmonics, match):
    with pytest.raises(ValueError, match=match):
        MultiHarmonicForce(Mass("1", 1.0), 3.0, harmonics)


def test_constant_force_rejects_a_non_finite_value():
    with pytest.raises(ValueError, match="constant force on 1: value = inf is not finite"):
        ConstantForce(Mass("1", 1.0), math.inf)


def test_the_period_is_the_base_frequency_and_constant_forces_have_none():
    m = Mass("1", 1.0, dofs=("x",))
    base = (Spring("x1", 1.0),)
    forces = (ConstantForce(m, 1.0), MultiHarmonicForce(m, 4.0, [(2, 1.0), (5, 1.0)]))
    assert excitation_period(Model((m,), base, (), forces)) == pytest.approx(2 * math.pi / 4.0, rel=1e-15)
    with pytest.raises(ValueError, match="0 distinct base frequencies"):
        excitation_period(Model((m,), base, (), (ConstantForce(m, 1.0),)))


def test_per_contact_tables_hold_the_constant_as_the_frequency_zero_group():
    m = Mass("1", 1.0)
    model = Model((m,), (Spring("x1", 1.0), Spring("y1", 1.0)), (),
                  (ConstantForce(m, Param("G", -2.0), Param("g", math.pi / 2)),
                   MultiHarmonicForce(m, Param("w", 5.0), [(1, Param("A", 1.0)), (2, Param("B", 0.5), Param("p", 0.3))],
                                      Param("beta", 0.0))))
    tables = derive_tables(model)
    assert sorted(tables["constant"]) == [[0, "G*cos(g)"], [1, "G*sin(g)"]]
    assert sorted(tables["forcing"]) == [[0, "A*cos(beta)", "w", "phi1_1"], [0, "B*cos(beta)", "2*w", "p"],
                                         [1, "A*sin(beta)", "w", "phi1_1"], [1, "B*sin(beta)", "2*w", "p"]]
    fi, fg, fs, fc, om = NumericTables(tables, model.parameters, [], [], list(model.parameters), 0).forcing
    assert sorted(om) == [0.0, 5.0, 10.0]
    zero = [e for e in range(len(fi)) if om[fg[e]] == 0.0]
    assert_allclose(sorted(fc[zero]), [-2.0, -2.0 * math.cos(math.pi / 2)])
    assert not fs[zero].any()


# --- the exact linear response ------------------------------------------------------------------------------

def exact_linear(M, C, K, loads, t_end):
    """State ``[q, u]`` at ``t_end`` from rest of ``M q'' + C q' + K q = sum of loads``, by one matrix exponential.

    ``loads``: ``(coordinate, amplitude, w, phi)`` for ``amplitude sin(w t + phi)`` (``w = 0``, ``phi = pi/2``: a
    constant). Each distinct ``w`` adds the states ``sin(w t), cos(w t)`` to the linear system.
    """
    n = len(M)
    Minv = np.linalg.inv(M)
    freqs = sorted({w for _, _, w, _ in loads})
    size = 2 * n + 2 * len(freqs)
    A = np.zeros((size, size))
    A[:n, n:2 * n] = np.eye(n)
    A[n:2 * n, :n], A[n:2 * n, n:2 * n] = -Minv @ K, -Minv @ C
    z0 = np.zeros(size)
    for g, w in enumerate(freqs):
        s, c = 2 * n + 2 * g, 2 * n + 2 * g + 1
        A[s, c], A[c, s] = w, -w                       # (sin wt)' = w cos wt, (cos wt)' = -w sin wt
        z0[c] = 1.0
    for i, a, w, phi in loads:
        s = 2 * n + 2 * freqs.index(w)
        load = np.zeros(size)
        load[s], load[s + 1] = a * math.cos(phi), a * math.sin(phi)
        A[n:2 * n] += np.outer(Minv[:, i], load)
    return (expm(A * t_end) @ z0)[:2 * n]


def two_dof(forces_on_1, forces_on_2, contacts=()):
    """Two masses on x: grounded springs and dampers and a coupling spring; ``forces_on_*(mass)`` make the forces."""
    m1, m2 = Mass("1", 1.2, dofs=("x",)), Mass("2", 0.8, dofs=("x",))
    model = Model((m1, m2), (Spring("x1", 400.0), Spring("x2", 250.0), Spring("x1", 150.0, "x2")),
                  (Damper("x1", 1.5), Damper("x2", 0.9)), (*forces_on_1(m1), *forces_on_2(m2)),
                  tuple(c(m1, m2) for c in contacts))
    M = np.diag([1.2, 0.8])
    K = np.array([[550.0, -150.0], [-150.0, 400.0]])
    C = np.diag([1.5, 0.9])
    return model, M, C, K


def far_walls(m1, m2):
    """Two contacts that never close (gaps of 1 m): the model runs on the per-contact kernel, as a linear one."""
    return (lambda a, b: Contact(a, None, gap=1.0, alpha=math.pi / 2, k=1e4, friction=NoFriction(), name="w1"),
            lambda a, b: Contact(b, None, gap=1.0, alpha=math.pi / 2, k=1e4, friction=NoFriction(), name="w2"))


KERNELS = [("product", ()), ("contact", ()), ("auto", far_walls(None, None))]
#: The same, with the two-contact case slow (a cold compile of its own: ~12 s in CI).
KERNELS_LEAN = KERNELS[:2] + [pytest.param(*KERNELS[2], marks=pytest.mark.slow)]
#: Only the product kernel by default (the per-contact kernel's cold compile here: ~30 s in CI).
KERNELS_PRODUCT = KERNELS[:1] + [pytest.param(*k, marks=pytest.mark.slow) for k in KERNELS[1:]]


def _check_exact(model, M, C, K, loads, kernel, periods, period=None):
    r = simulate(model, periods=periods, steps_per_period=2000, kernel=kernel, period=period)
    n = len(M)
    names = list(model.coordinates)
    got = np.array([r.final[c] for c in names] + [r.final[f"v{c}"] for c in names])
    want = exact_linear(M, C, K, loads, r.t[-1])
    scale = np.abs(want[:n]).max(), np.abs(want[n:]).max()
    assert_allclose(got[:n], want[:n], rtol=0, atol=1e-8 * scale[0])
    assert_allclose(got[n:], want[n:], rtol=0, atol=1e-8 * scale[1])
    return r


@pytest.mark.parametrize("kernel, contacts", KERNELS_PRODUCT, ids=[k for k, _ in KERNELS])
def test_a_released_oscillator_settles_at_the_shifted_equilibrium(kernel, contacts):
    """A constant force alone: the exact step response, which ends at ``K^-1 F`` (gravity: ``m g / k``)."""
    g = 9.81
    model, M, C, K = two_dof(lambda m: (ConstantForce(m, -1.2 * g),), lambda m: (ConstantForce(m, 2.5),), contacts)
    loads = [(0, -1.2 * g, 0.0, math.pi / 2), (1, 2.5, 0.0, math.pi / 2)]
    _check_exact(model, M, C, K, loads, kernel, periods=3, period=0.5)
    r = simulate(model, periods=2, transient=100, steps_per_period=400, kernel=kernel, period=0.5)
    assert_allclose([r.final["x1"], r.final["x2"]], np.linalg.solve(K, [-1.2 * g, 2.5]), rtol=1e-9)


@pytest.mark.parametrize("kernel, contacts", KERNELS_PRODUCT, ids=[k for k, _ in KERNELS])
def test_phased_harmonic_and_constant_forces_add_up_exactly(kernel, contacts):
    """``F0 sin(omega t + phi)`` with any phase plus a preload: the exact transient from rest."""
    w = 21.0
    model, M, C, K = two_dof(lambda m: (HarmonicForce(m, 3.0, Param("omega", w), phase=2.2), ConstantForce(m, 4.0)),
                             lambda m: (HarmonicForce(m, 1.5, Param("omega", w), phase=-0.7, angle=math.pi),),
                             contacts)
    loads = [(0, 3.0, w, 2.2), (0, 4.0, 0.0, math.pi / 2), (1, -1.5, w, -0.7)]
    _check_exact(model, M, C, K, loads, kernel, periods=4)


@pytest.mark.parametrize("kernel, contacts", KERNELS_LEAN, ids=[k for k, _ in KERNELS])
def test_several_harmonics_are_the_superposition_of_their_responses(kernel, contacts):
    w = 13.0
    terms = [(1, 2.0, 0.4), (2, 1.0, -1.0), (5, 0.6, 2.5)]
    model, M, C, K = two_dof(lambda m: (MultiHarmonicForce(m, Param("omega", w), terms),),
                             lambda m: (ConstantForce(m, -1.0),), contacts)
    loads = [(0, a, k * w, phi) for k, a, phi in terms] + [(1, -1.0, 0.0, math.pi / 2)]
    r = _check_exact(model, M, C, K, loads, kernel, periods=3)
    assert r.period == pytest.approx(2 * math.pi / w, rel=1e-15)


def test_several_harmonics_keep_the_base_period_of_the_poincare_section():
    """After the transient a linear oscillator under harmonics 2 and 3 of omega repeats once per base period."""
    m = Mass("1", 1.0, dofs=("x",))
    model = Model((m,), (Spring("x1", 100.0),), (Damper("x1", 4.0),),
                  (MultiHarmonicForce(m, 7.0, [(2, 1.0), (3, 0.5, 1.0)]),))
    r = simulate(model, transient=60, periods=8, steps_per_period=1000)
    assert r.period == pytest.approx(2 * math.pi / 7.0) and poincare_period(r.poincare[:, :2]) == 1
    half = simulate(model, transient=60, periods=16, steps_per_period=500, period=math.pi / 7.0)
    assert poincare_period(half.poincare[:, :2]) == 2      # sampled at half the base period: not a period of Q


# --- a constant force against a contact ---------------------------------------------------------------------

@pytest.mark.parametrize("kernel", ["product", pytest.param("contact", marks=pytest.mark.slow)])   # contact: ~30 s
def test_a_preload_presses_a_mass_into_its_contact(kernel):
    """``k x = F - kc (x - gap)`` while closed: the mass rests at ``(F + kc gap) / (k + kc)``."""
    k, kc, gap, F = 1e3, 4e3, 1e-3, 10.0
    m = Mass("1", 0.5, dofs=("x",))
    model = Model((m,), (Spring("x1", k),), (Damper("x1", 20.0),), (ConstantForce(m, F),),
                  (Contact(m, None, gap=gap, alpha=math.pi / 2, k=kc, friction=NoFriction()),))
    r = simulate(model, transient=40, periods=2, steps_per_period=400, period=0.05, kernel=kernel)
    assert r.final["x1"] == pytest.approx((F + kc * gap) / (k + kc), rel=1e-9)
    assert r.final["x1"] > gap                                 # closed: the contact carries F - k x


def test_two_preloaded_contacts_on_the_per_contact_kernel():
    """Each mass of the two-DOF chain rests on its wall: ``(K + diag(kc)) x = F + kc gap``."""
    kc, gap = 5e3, 1e-3
    model, M, C, K = two_dof(lambda m: (ConstantForce(m, 8.0),), lambda m: (ConstantForce(m, 6.0),),
                             (lambda a, b: Contact(a, None, gap=gap, alpha=math.pi / 2, k=kc, friction=NoFriction(),
                                                   name="w1"),
                              lambda a, b: Contact(b, None, gap=gap, alpha=math.pi / 2, k=kc, friction=NoFriction(),
                                                   name="w2")))
    r = simulate(model, transient=100, periods=2, steps_per_period=500, period=0.5)   # 50 s: settled to 1e-12
    x = np.linalg.solve(K + kc * np.eye(2), [8.0 + kc * gap, 6.0 + kc * gap])
    assert (x > gap).all()
    assert_allclose([r.final["x1"], r.final["x2"]], x, rtol=1e-9)


# --- the components format ----------------------------------------------------------------------------------

BASE = {"model": "components", "parameters": {"omega": 9.0},
        "masses": [{"name": "m", "m": 1.0, "dofs": ["x", "y"]}],
        "springs": [{"a": "x_m", "k": 100.0}, {"a": "y_m", "k": 100.0}]}


def test_yaml_builds_each_force_type():
    cfg = config_from_data({**BASE, "forces": [
        {"mass": "m", "amplitude": 2.0, "omega": "omega", "phase": 0.3},
        {"type": "constant", "mass": "m", "value": -9.81, "angle": 1.5707963267948966},
        {"type": "multiharmonic", "mass": "m", "omega": "omega",
         "harmonics": [{"order": 2, "amplitude": 1.0}, {"order": 3, "amplitude": 0.5, "phase": 1.0}]}]})
    forces = cfg.build().forces
    assert [type(f) for f in forces] == [HarmonicForce, ConstantForce, MultiHarmonicForce]
    assert forces[1].parameters()["value"].value == -9.81 and forces[2].orders == (2, 3)
    assert forces[0].frequency.name == forces[2].frequency.name == "omega"
    system = derive(cfg.build())
    rhs = sp.expand(system.generalized_forces[system.modes[0].name]["y_m"])
    assert S("F_m") * sp.sin(S("beta_F_m")) in sp.Add.make_args(rhs)        # gravity's own angle symbol


@pytest.mark.parametrize("force, where, message", [
    ({"type": "gravity", "mass": "m", "value": 1.0}, "forces.0", "gravity"),
    ({"type": "constant", "mass": "m"}, "forces.0.value", "Field required"),
    ({"type": "constant", "mass": "m", "value": 1.0, "amplitude": 2.0}, "forces.0.amplitude", "Extra inputs"),
    ({"type": "multiharmonic", "mass": "m", "omega": 1.0, "harmonics": []}, "forces.0.harmonics", "at least 1"),
    ({"type": "multiharmonic", "mass": "m", "omega": 1.0, "harmonics": [{"order": 0, "amplitude": 1.0}]},
     "forces.0.harmonics.0.order", "greater than or equal to 1"),
    ({"type": "multiharmonic", "mass": "m", "omega": 1.0,
      "harmonics": [{"order": 2, "amplitude": 1.0}, {"order": 2, "amplitude": 3.0}]},
     "forces.0.harmonics", "orders [2, 2] must be distinct"),
    ({"type": "multiharmonic", "mass": "m", "omega": "nope", "harmonics": [{"order": 1, "amplitude": 1.0}]},
     "forces.0.omega", "unknown parameter"),
    ({"type": "constant", "mass": "q", "value": 1.0}, "forces.0.mass", "unknown mass"),
])
def test_yaml_force_errors_name_the_field(force, where, message):
    with pytest.raises(ConfigError) as info:
        config_from_data({**BASE, "forces": [force]}, source="f.yaml")
    text = str(info.value)
    assert where in text and message in text, text


def test_the_yaml_example_of_the_docs_builds():
    """The ``forces:`` example of docs/components.md, on the pair's two masses."""
    import yaml
    text = (Path(__file__).resolve().parents[1] / "docs" / "components.md").read_text()
    block = text.split("## Forces", 1)[1].split("```yaml\n", 1)[1].split("```", 1)[0]
    data = yaml.safe_load(block)
    cfg = config_from_data({"model": "components", "masses": [{"name": 1, "m": 0.085}, {"name": 2, "m": 0.085}],
                            **data})
    forces = cfg.build().forces
    assert [type(f) for f in forces] == [HarmonicForce, ConstantForce, MultiHarmonicForce]
    gravity = forces[1].loads({}, {}, t)["y1"].subs({S(p.name): p.value for p in forces[1].parameters().values()})
    assert float(gravity) == pytest.approx(-0.085 * 9.81, rel=1e-3)


# Slow, both (35 s in CI for the product kernel's cold compile); tests/test_bladed_disk.py balances the energy
# of rings with Coulomb contacts by default.
@pytest.mark.slow
@pytest.mark.parametrize("kernel", ["product", "contact"])
def test_the_work_of_gravity_enters_the_energy_balance(kernel):
    """Gravity presses a driven mass on a Coulomb contact: the balance closes with gravity's work in ``W_in``."""
    from blademodel.components import Coulomb
    from blademodel.numeric.energy import energy_balance
    m = Mass("1", 1.0)
    model = Model((m,), (Spring("x1", 1e4), Spring("y1", 1e4)), (Damper("x1", 2.0), Damper("y1", 2.0)),
                  (ConstantForce(m, -50.0, angle=math.pi / 2), HarmonicForce(m, 20.0, 80.0)),
                  (Contact(m, None, gap=0.0, alpha=0.0, k=1e5, friction=Coulomb(0.3)),))
    r = simulate(model, periods=10, steps_per_period=2000, energy=True, kernel=kernel)   # from rest: it settles
    assert r.counters["events"] >= 20                        # stick and slip under the weight's normal load
    b = energy_balance(model, r)
    assert abs(b["residual"]) <= 1e-8 * b["throughput"] and b["D_fric"] > 0.1 * b["W_in"]
    gravity = -50.0 * (r.final["y1"] - r.y[0, r.index("y1")])               # the work of the weight
    assert abs(gravity) > 1e-3 * b["throughput"]            # without it the balance would not close
