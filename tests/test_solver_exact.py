"""The hybrid RK4 kernel against exact solutions, balances and convergence orders."""

import collections
import math
import os
import subprocess
import sys

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.optimize import fsolve

from blademodel.components import Contact, Coulomb, HarmonicForce, Jenkins, Mass, Spring
from blademodel.zheng2022 import BladePair
from blademodel.model import Model
from blademodel.numeric import SimulationError, simulate
from blademodel.numeric.energy import energy_balance


def linear_exact(m, c, k, F, omega, phi, t):
    """Exact response of m x'' + c x' + k x = F sin(omega t + phi) from rest."""
    Z = k - m * omega ** 2 + 1j * c * omega
    Xc = F * np.exp(1j * phi) / Z  # particular solution Im(Xc e^{i w t})
    xp0, vp0 = Xc.imag, (1j * omega * Xc).imag
    zeta_wn = c / (2 * m)
    wd = math.sqrt(k / m - zeta_wn ** 2)
    a = -xp0
    b = (-vp0 + zeta_wn * a) / wd
    e = np.exp(-zeta_wn * t)
    xh = e * (a * np.cos(wd * t) + b * np.sin(wd * t))
    vh = e * (-zeta_wn * (a * np.cos(wd * t) + b * np.sin(wd * t)) + wd * (-a * np.sin(wd * t) + b * np.cos(wd * t)))
    w = np.exp(1j * omega * t)
    return xh + (Xc * w).imag, vh + (1j * omega * Xc * w).imag


def test_no_contact_matches_exact_linear_solution():
    cfg = BladePair()
    r = simulate(cfg.build(contact=False), periods=20, steps_per_period=2000)
    t = r.t[-1]
    for i, phi in ((1, cfg.phi1), (2, cfg.phi2)):
        for axis, (k, c, proj) in {"x": (cfg.kx, cfg.cx, math.cos(cfg.beta)),
                                   "y": (cfg.ky, cfg.cy, math.sin(cfg.beta))}.items():
            x, v = linear_exact(cfg.m, c, k, cfg.F0 * proj, cfg.omega, phi, t)
            assert abs(r.final[f"{axis}{i}"] - x) <= 1e-8 * abs(x)
            assert abs(r.final[f"v{axis}{i}"] - v) <= 1e-8 * abs(v)
    assert r.mode_names == ["free"] and r.counters["events"] == 0


def den_hartog_oscillator(m=1.0, k=1e4, P=10.0, F=2.0, omega=80.0, mu=0.5, kc=1e5):
    """1-DOF oscillator with constant-load Coulomb friction, from the framework's components.

    The contact presses the mass on the ground (alpha = 0, gap = -F/(mu kc)), so the
    normal load is the constant F/mu and the friction force is +-F.
    """
    wn = math.sqrt(k / m)
    beta = omega / wn
    U = math.sin(math.pi / beta) / (beta * (1 + math.cos(math.pi / beta)))
    amplitude = (P / k) * math.sqrt(1 / (1 - beta ** 2) ** 2 - (F / P * U) ** 2)   # Den Hartog (1931)

    def half_cycle(z):
        """Moving right from x = -A, v = 0 for T/2 under P cos(w t + psi) - F must end at x = A, v = 0."""
        A, psi = z
        C = P / (m * (wn ** 2 - omega ** 2))
        a = -A - (C * math.cos(psi) - F / k)
        b = C * omega * math.sin(psi) / wn
        T2 = math.pi / omega
        x = a * math.cos(wn * T2) + b * math.sin(wn * T2) + C * math.cos(omega * T2 + psi) - F / k
        v = -a * wn * math.sin(wn * T2) + b * wn * math.cos(wn * T2) - C * omega * math.sin(omega * T2 + psi)
        return [x - A, v]

    A, psi = fsolve(half_cycle, [amplitude, 3.0], xtol=1e-14)
    mass = Mass("1", m, dofs=("x",))
    model = Model((mass,), (Spring("x1", k),), (), (HarmonicForce(mass, P, omega, phase=psi + math.pi / 2),),
                  (Contact(mass, None, gap=-F / mu / kc, alpha=0.0, k=kc, friction=Coulomb(mu)),))
    return model, amplitude, A


def test_den_hartog_continuous_slip_amplitude():
    model, amplitude, A = den_hartog_oscillator()
    assert abs(A / amplitude - 1) < 1e-12      # the closed form and the piecewise-exact orbit agree
    r = simulate(model, periods=20, steps_per_period=2000, y0={"x1": -A})
    # Started on the exact periodic orbit (x = -A, v = 0 at t = 0) it stays there.
    assert abs(r.final["x1"] + amplitude) <= 1e-6 * amplitude
    assert abs(r.final["vx1"]) <= 1e-6 * amplitude * 80.0
    assert set(r.events["guard"]) == {"c: slip+: v=0", "c: slip-: v=0"}   # non-stop: reversals only
    assert r.counters["events"] >= 39


def test_jenkins_energy_per_cycle_under_imposed_motion():
    # A very heavy mass driven harmonically moves as x = -a sin(w t) whatever the
    # friction force (relative deviation ~ mu N / (M w^2 a) = 1e-14).
    M, a, omega, mu, N, kd, kc = 1e12, 1e-4, 100.0, 0.5, 10.0, 2e5, 1e6
    mass = Mass("1", M, dofs=("x",))
    model = Model((mass,), (), (), (HarmonicForce(mass, M * a * omega ** 2, omega),),
                  (Contact(mass, None, gap=-N / kc, alpha=0.0, k=kc, friction=Jenkins(mu, kd)),))
    r = simulate(model, periods=3, transient=1, steps_per_period=2000, energy=True,
                 y0={"x1": 0.0, "vx1": -a * omega})
    D = r.poincare[:, r.index("D_fric")]
    per_cycle = np.diff(D)
    exact = 4 * mu * N * (a - mu * N / kd)
    assert_allclose(per_cycle, exact, rtol=1e-8)


# Slow: a cold compile of the pair's energy kernel each (30-65 s in CI); the default run balances the energy
# of rings with both laws (tests/test_bladed_disk.py) and of a Coulomb contact under gravity (test_forces.py).
@pytest.mark.slow
@pytest.mark.parametrize("friction", ["coulomb", "bilinear", "none"])
def test_energy_balance_paper_model(friction):
    model = BladePair(friction=friction).build()
    r = simulate(model, periods=50, steps_per_period=2000, energy=True)
    assert r.counters["events"] >= 24   # dozens of contact (and stick/slip) events
    b = energy_balance(model, r)
    assert abs(b["residual"]) <= 1e-8 * b["throughput"]
    if friction != "none":
        assert b["D_fric"] > 0.1 * b["W_in"]   # friction really is at work


def _scaled_error(r, ref, cfg):
    scale = np.array([cfg.gap] * 4 + [cfg.gap * cfg.omega] * 4 + [cfg.gap] * (len(ref.final_state) - 8))
    return np.max(np.abs(r.final_state - ref.final_state) / scale)


@pytest.mark.parametrize("friction", ["coulomb", "bilinear"])
def test_fourth_order_convergence_through_events(friction):
    cfg = BladePair(friction=friction)
    model = cfg.build()
    periods = 20
    ref = simulate(model, periods=periods, steps_per_period=32000, event_tol=1e-12)
    kinds = collections.Counter("contact" if g.endswith(("open", "close")) else "friction"
                                for g in ref.events["guard"])
    assert kinds["contact"] >= 60 and kinds["friction"] >= 60
    errs = [_scaled_error(simulate(model, periods=periods, steps_per_period=S), ref, cfg)
            for S in (1000, 2000, 4000)]
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all(orders >= 3.9), (errs, orders)
    # Without event location (switch at the step end) the order collapses.
    errs0 = [_scaled_error(simulate(model, periods=periods, steps_per_period=S, event_tol=1.0), ref, cfg)
             for S in (1000, 2000, 4000)]
    assert np.log2(errs0[0] / errs0[-1]) / 2 < 2.0


def test_jit_and_pure_python_give_the_same_result(tmp_path):
    code = ("from blademodel.zheng2022 import BladePair; from blademodel.numeric import simulate; "
            "import numpy as np, sys; r = simulate(BladePair(friction='bilinear', F0=90).build(), periods=2, "
            "steps_per_period=400); np.save(sys.argv[1], r.final_state)")
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    subprocess.run([sys.executable, "-c", code, str(tmp_path / "py.npy")], env=env, check=True)
    r = simulate(BladePair(friction="bilinear", F0=90).build(), periods=2, steps_per_period=400)
    assert r.counters["events"] > 5
    assert_allclose(np.load(tmp_path / "py.npy"), r.final_state, rtol=1e-12, atol=0)


def test_non_finite_state_is_reported_with_time_and_mode():
    model = BladePair(gamma=1000).build()
    with pytest.raises(SimulationError, match=r"non-finite at t = .* in mode"):
        simulate(model, periods=5, steps_per_period=100, check_stability=False)


def test_event_storm_is_capped():
    model = BladePair(friction="bilinear").build()
    with pytest.raises(SimulationError, match="event storm"):
        simulate(model, periods=20, steps_per_period=100, max_events_per_step=1)


def test_poincare_samples_are_states_at_period_ends():
    r = simulate(BladePair().build(), periods=3, transient=2, steps_per_period=500)
    assert_allclose(r.poincare_t, r.period * np.array([3, 4, 5]))
    ends = [np.argmin(abs(r.t - tp)) for tp in r.poincare_t]
    assert_allclose(r.y[ends], r.poincare, rtol=0, atol=0)
