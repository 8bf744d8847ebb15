"""Guards that a transition leaves a rounding error on their wrong side, read from their boundary by the product-mode
kernel (``blademodel/numeric/loop.py: drift_offsets``).

An Iwan element that sticks takes the stretch of its slip force exactly, so the contact's shared stick guard (the
least over the sticking elements of ``mu N phi - kd z``) starts an ulp either side of zero. From below zero it never
crossed: another element reaching its slip force later in the step stuck on past it until another event let it slip,
and the period map jumped between neighbouring parameter values as rounding put that ulp on one side or the other.
"""

from __future__ import annotations

import numpy as np
import pytest

from blademodel.orbits import continuation, find_periodic_orbit
from blademodel.orbits.family import _Family
from blademodel.zheng2022 import BladePair

OMEGA = 166.48
SETTINGS = dict(steps_per_period=2000, event_tol=1e-10, method="rk4", kernel="auto")


@pytest.fixture(scope="module")
def iwan_orbit():
    fam = _Family(BladePair(friction="iwan"), "omega", 1, SETTINGS, OMEGA, bounds=(150.0, 170.0))
    orbit = find_periodic_orbit(None, integrator=fam.map_at(OMEGA).integrator, transient=50)
    return fam, orbit


def test_the_iwan_map_is_continuous_in_the_field(iwan_orbit):
    """The Iwan pair at 166.48 rad/s, 2000 steps a period (its orbit after 50 periods from rest): difference quotients
    of the period map in omega over 2e-7 to 2e-5 rad/s, both ways, agree with the tangent's own parameter column
    (through the moving period) to 1e-3 of its size (measured: 8.4e-5 at most). With the stick guard read from below
    zero the quotient over 2e-6 rad/s read 40 times the column's size off, over 2e-7 400 times, over -2e-5 4.0
    times: a jump of the map, not a kink."""
    fam, orbit = iwan_orbit
    P = fam.map_at(OMEGA)
    y, mode, scale = orbit.state, orbit.mode, orbit.scale
    dp, dT = fam.parameter_direction(OMEGA, 1e-6 * OMEGA, P.integrator.meta["params"])
    exact = P.derivatives(y, mode, dp, dT).parameter / scale
    base = P(y, mode)[0]
    for d in (2e-7, 2e-6, 2e-5, -2e-6, -2e-5):
        quotient = (fam.map_at(OMEGA + d)(y, mode)[0] - base) / d / scale
        assert np.linalg.norm(quotient - exact) < 1e-3 * np.linalg.norm(exact), d


def test_no_iwan_element_sticks_past_its_slip_force(iwan_orbit):
    """The run from that orbit at 166.48 + 2e-6 rad/s, where the missed crossing was met: at every step of the period,
    both shared stick guards of the closed contact are at least zero to 1e-10 of the mode's largest guard (no
    sticking element's force past its slip force). It read -9e-3 of the mode's largest guard for a step, until the next
    element's reset let the element slip."""
    fam, orbit = iwan_orbit
    P = fam.map_at(OMEGA + 2e-6)
    ig = P.integrator
    run = P.run(orbit.state, orbit.mode)
    names = ig.meta["guards"]
    g = np.empty(max(len(n) for n in names) + 1)
    worst = np.inf
    for k in range(run.t.size):
        m = int(run.modes[k])
        if ig.meta["modes"][m] != "closed":
            continue
        ig.module.guards(m, run.t[k], run.states[k], ig.p, g)
        stick = [g[i] for i, name in enumerate(names[m]) if "stick->slip" in name]
        worst = min(worst, min(stick) / np.max(np.abs(g[:len(names[m])])))
    assert np.isfinite(worst) and worst >= -1e-10


@pytest.mark.slow
def test_the_iwan_branch_through_its_grazings_reaches_its_end():
    """The Iwan pair over 150 to 170 rad/s at 2000 steps a period (its events changing at almost every step): every
    orbit stable, the field rising at every point to 170 rad/s. With the stick guard read from below zero, the
    forward difference of the field's column at 166.4829 rad/s crossed a jump of the map and pointed the tangent back
    along the part passed: the branch crept on by shots and turned back onto itself near 165.7 rad/s."""
    b = continuation(BladePair(friction="iwan"), "omega", 150.0, 170.0, max_points=400, workers=1,
                     steps_per_period=2000)
    assert b.message == "reached omega = 170"
    assert np.all(np.diff(b.params) > 0) and b.stable.all()
