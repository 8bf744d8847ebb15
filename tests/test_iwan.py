"""The Iwan micro-slip law: bilinear limit, closed-form energy per cycle, convergence in n."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from blademodel.components import Contact, HarmonicForce, Iwan, Mass
from blademodel.components.friction.iwan import continuous_energy_per_cycle, energy_per_cycle, uniform_fractions
from blademodel.zheng2022 import BladePair
from blademodel.model import Model
from blademodel.numeric import HybridIntegrator, simulate
from blademodel.numeric.energy import energy_balance
from blademodel.numeric.stability import max_stable_step

# Imposed motion (as tests/test_solver_exact.py does for the Jenkins element): a very
# heavy mass driven harmonically moves as x = -a sin(w t) whatever the friction force;
# the contact presses it on the ground (alpha = 0, gap < 0) with the constant load N.
M, OMEGA, MU, N, KD, KC = 1e12, 100.0, 0.5, 10.0, 2e5, 1e6
D0 = MU * N / KD          # slip displacement of the bilinear law


def imposed_energy_per_cycle(n: int, a: float, **options) -> np.ndarray:
    """Friction dissipation D_fric in each of 3 periods after 1, for Iwan(n) at amplitude a."""
    mass = Mass("1", M, dofs=("x",))
    law = Iwan(MU, KD, elements=n, **options)
    model = Model((mass,), (), (), (HarmonicForce(mass, M * a * OMEGA ** 2, OMEGA),),
                  (Contact(mass, None, gap=-N / KC, alpha=0.0, k=KC, friction=law),))
    r = simulate(model, periods=4, transient=1, steps_per_period=2000, energy=True,
                 y0={"x1": 0.0, "vx1": -a * OMEGA})
    return np.diff(r.poincare[:, r.index("D_fric")])


def closed_form(n: int, a: float) -> float:
    c, phi = uniform_fractions(n)
    return energy_per_cycle(a, mu=MU, N=N, kd=KD, stiffness=c, slip=phi)


def test_uniform_distribution_matches_the_bilinear_totals():
    for n in (1, 2, 3, 7, 16):
        c, phi = uniform_fractions(n)
        assert sum(c) == 1 and sum(phi) == 1                       # exact rationals
        d = [p / k for k, p in zip(c, phi)]                        # slip displacements / D0
        assert_allclose(np.diff([float(x) for x in d]), 2.0 / n)   # evenly spread ...
        assert float(d[0]) == 1.0 / n and float(d[-1]) == 2.0 - 1.0 / n   # ... over (0, 2 D0)
    assert uniform_fractions(1) == ((1,), (1,))


@pytest.mark.parametrize("gamma, F0", [(4.0, 60.0), (8.0, 90.0)])
def test_one_element_is_the_bilinear_law(gamma, F0):
    bil = BladePair(friction="bilinear", gamma=gamma, F0=F0)
    iwan = BladePair(friction="iwan", friction_options={"elements": 1}, gamma=gamma, F0=F0)
    rb = simulate(bil.build(), periods=40, steps_per_period=1000)
    ri = simulate(iwan.build(), periods=40, steps_per_period=1000)
    assert rb.counters["events"] >= 400
    assert ri.counters["events"] == rb.counters["events"]
    assert_allclose(ri.events["t"], rb.events["t"], rtol=1e-12, atol=0)
    yb, yi = rb.final_state, ri.final_state
    assert ri.state_names[:9] == rb.state_names[:8] + ["z1"]
    # Iwan sets a sticking element's stretch to its slip force exactly (its shared stick guard must not
    # start below zero), the bilinear law keeps the slip phase's integration drift: the runs differ by
    # that correction (measured 6e-12 and 5e-11 of the largest state after 40 periods).
    assert np.max(np.abs(yi[:9] - yb)) <= 1e-10 * np.max(np.abs(yb))
    # the element's flag agrees with the bilinear law's final mode
    flag = {"stick": 0.0, "slip+": 1.0, "slip-": -1.0, "open": 0.0}[rb.mode_names[rb.final_mode]]
    assert yi[ri.index("s1")] == flag


def test_stability_limit_is_set_by_the_stick_branch():
    # At rest every s_i = 0: the Jacobian takes the stick branch, the stiffest.
    limits = []
    for cfg in (BladePair(friction="bilinear"), BladePair(friction="iwan", friction_options={"elements": 1})):
        integ = HybridIntegrator(cfg.build())
        limits.append(max_stable_step(integ.module.jacobian, len(integ.mode_names), integ.p_raw,
                                      integ.n_physical)[0])
    assert limits[0] == limits[1]


# Slow: a cold compile per element count (25-55 s in CI); test_one_element_is_the_bilinear_law runs Iwan by default.
@pytest.mark.slow
@pytest.mark.parametrize("n", [1, 3, 7])
@pytest.mark.parametrize("ratio", [0.5, 1.2])
def test_energy_per_cycle_matches_the_closed_form(n, ratio):
    a = ratio * D0
    c, phi = uniform_fractions(n)
    slipping = sum(MU * N * float(p) / (KD * float(k)) < a for k, p in zip(c, phi))
    if n > 1:
        assert 0 < slipping < n          # micro-slip: some elements slip, not all
    per_cycle = imposed_energy_per_cycle(n, a)
    exact = closed_form(n, a)
    assert_allclose(per_cycle, exact, rtol=1e-8, atol=1e-12 * 4 * MU * N * a)
    if n == 1:   # the bilinear law's 4 mu N (a - mu N / kd) when it slips
        assert exact == (4 * MU * N * (a - D0) if a > D0 else 0.0)


@pytest.mark.slow   # a cold compile (~30 s in CI); one element's equality with the bilinear law runs by default
def test_elements_that_switch_together():
    # Two elements with the same slip displacement (and a third, stiffer one) switch in
    # the same instants, when the contact closes and at every reversal (constant N):
    # each shared event must switch both. Together they act as one element.
    options = dict(stiffness_fractions=[0.25, 0.25, 0.5], slip_fractions=[0.125, 0.125, 0.75])
    a = 1.2 * D0
    d = [s / c * D0 for c, s in zip(options["stiffness_fractions"], options["slip_fractions"])]
    assert d[0] == d[1] < a < d[2]
    per_cycle = imposed_energy_per_cycle(3, a, **options)
    assert_allclose(per_cycle, 4 * MU * N * 0.25 * (a - d[0]), rtol=1e-8)
    assert_allclose(per_cycle, energy_per_cycle(a, mu=MU, N=N, kd=KD, stiffness=options["stiffness_fractions"],
                                                slip=options["slip_fractions"]), rtol=1e-8)


@pytest.mark.slow
@pytest.mark.parametrize("ratio", [1.5, 3.0])
def test_energy_per_cycle_converges_to_the_continuous_iwan_model(ratio):
    # 1.5 D0: micro-slip (the continuous model never slides as a whole below 2 D0);
    # 3 D0: gross slip. The midpoint rule converges as 1/n^2.
    # Slow: it compiles kernels of 1 to 16 elements that nothing else uses (113 s cold in CI). The default
    # run keeps the simulated energy against the closed form (test_energy_per_cycle_matches_the_closed_form)
    # and the closed form's continuous limit (test_continuous_limit_formula).
    a = ratio * D0
    limit = continuous_energy_per_cycle(a, mu=MU, N=N, kd=KD)
    ns = (1, 2, 4, 8, 16)
    sims = [float(np.mean(imposed_energy_per_cycle(n, a))) for n in ns]
    assert_allclose(sims, [closed_form(n, a) for n in ns], rtol=1e-8)
    errors = np.abs(np.array(sims) / limit - 1)
    assert np.all(np.diff(errors) < 0), errors
    orders = np.log2(errors[2:-1] / errors[3:])
    assert np.all(orders > 1.9), orders
    assert errors[-1] < 4e-3


def test_continuous_limit_formula():
    # kd a^3 / (3 D0) below gross slip, 4 mu N (a - 4 D0 / 3) above, continuous at a = 2 D0
    lo = continuous_energy_per_cycle(2 * D0 * (1 - 1e-12), mu=MU, N=N, kd=KD)
    hi = continuous_energy_per_cycle(2 * D0 * (1 + 1e-12), mu=MU, N=N, kd=KD)
    assert math.isclose(lo, hi, rel_tol=1e-9)
    assert math.isclose(closed_form(4096, 0.7 * D0), continuous_energy_per_cycle(0.7 * D0, mu=MU, N=N, kd=KD),
                        rel_tol=1e-6)


@pytest.mark.slow   # ~35 s in CI; tests/test_solver_exact.py balances the pair's energy with Coulomb friction
def test_energy_balance_paper_model():
    model = BladePair(friction="iwan", friction_options={"elements": 3}).build()
    r = simulate(model, periods=50, steps_per_period=2000, energy=True)
    assert r.counters["events"] >= 100
    b = energy_balance(model, r)
    assert abs(b["residual"]) <= 1e-8 * b["throughput"]
    assert b["D_fric"] > 0.1 * b["W_in"]


def test_custom_distribution_and_errors():
    law = Iwan(elements=2, stiffness_fractions=[0.25, 0.75], slip_fractions=[0.5, 0.5])
    assert law.distribution == "custom" and law.fractions == ((0.25, 0.75), (0.5, 0.5))
    assert law.states == ("z1", "z2", "s1", "s2")
    with pytest.raises(ValueError, match="elements = 0 must be an integer >= 1"):
        Iwan(elements=0)
    with pytest.raises(ValueError, match="distribution = 'gauss'"):
        Iwan(distribution="gauss")
    with pytest.raises(ValueError, match="slip_fractions has 1 values, expected elements = 2"):
        Iwan(elements=2, stiffness_fractions=[0.5, 0.5], slip_fractions=[1.0])
    with pytest.raises(ValueError, match="must sum to 1"):
        Iwan(elements=2, stiffness_fractions=[0.5, 0.6], slip_fractions=[0.5, 0.5])
    with pytest.raises(ValueError, match="takes no stiffness_fractions"):
        Iwan(elements=2, distribution="uniform", stiffness_fractions=[0.5, 0.5], slip_fractions=[0.3, 0.7])
    # the structure (which fixes the generated code) tells distributions apart
    assert Iwan(elements=2).structure() != law.structure()
