"""A friction law's discrete states (the Iwan elements' stick/slip labels) in shooting and continuation.

The labels ``s_i`` are whole numbers that only resets set. Taken as unknowns, Newton's method nudged them
by a difference step or a correction (``s = 1e-19`` reads as a slipping element), which made every Iwan
orbit that a transient had not already settled unreachable, and the differences gave multipliers of
``5e5`` (``1 / (2 rel_step)``) on a continued branch.
"""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from blademodel.components.friction.base import Candidate, FrictionLaw
from blademodel.components.friction.validation import FrictionLawError, check_law
from blademodel.components._sympy import sp
from blademodel.components.parameter import as_param
from blademodel.config import BladedDisk
from blademodel.numeric import simulate
from blademodel.numeric.kernels import make_integrator
from blademodel.orbits import PeriodMap, continuation, find_periodic_orbit
from blademodel.zheng2022 import BladePair


def _iwan_pair(omega=300.0):
    return BladePair(friction="iwan", omega=omega).build()


def test_the_labels_are_the_iwan_elements_modes_in_both_kernels():
    pair = make_integrator(_iwan_pair(), kernel="product")
    assert [pair.state_names[i] for i in pair.discrete_states] == ["s1", "s2", "s3", "s4"]
    ring = make_integrator(BladedDisk(blades=4, friction="iwan").build(), kernel="contact")
    names = [ring.state_names[i] for i in ring.discrete_states]
    assert names == [f"s{e}_c{c}" for c in range(1, 5) for e in range(1, 5)]


def test_an_iwan_orbit_is_found_from_a_short_transient_and_is_the_attractor():
    """Five periods from rest leave the residual at 2e-3; Newton's method must take it from there (before, it
    stalled at the first step: the labels it moved made every trial another motion). The orbit is checked
    against the state that 300 periods from rest settle to (the pair contracts by 0.65 a period)."""
    model = _iwan_pair()
    orbit = find_periodic_orbit(model, transient=5)
    assert len(orbit.history) >= 3 and orbit.history[0] > 1e-4   # Newton's method did the work
    r = simulate(model, periods=300, steps_per_period=1000)
    settled = r.final_state[:orbit.state.size]
    scale = np.max(np.abs(orbit.y), axis=0)
    continuous = [i for i, name in enumerate(orbit.state_names) if not name.startswith("s")]
    assert_allclose(orbit.state[continuous] / scale[continuous], settled[continuous] / scale[continuous],
                    atol=1e-8)
    assert np.array_equal(orbit.state[12:], settled[12:])   # the labels, exactly
    assert set(orbit.state[12:]) <= {-1.0, 0.0, 1.0}


def test_the_monodromy_in_the_continuous_states_is_their_difference_quotient_and_zero_in_the_labels():
    model = _iwan_pair()
    orbit = find_periodic_orbit(model, transient=100)
    ig = make_integrator(model)
    P = PeriodMap(ig, 1, jacobian="differences", workers=1)
    d = ig.discrete_states
    free = np.setdiff1d(np.arange(P.n), d)
    J = orbit.monodromy
    assert np.all(J[d] == 0.0) and np.all(J[:, d] == 0.0)
    # each continuous column by central differences of the map, the labels held
    D = np.empty((P.n, free.size))
    for k, i in enumerate(free):
        e = 1e-6 * orbit.scale[i]
        yp, ym = orbit.state.copy(), orbit.state.copy()
        yp[i] += e
        ym[i] -= e
        D[:, k] = (P(yp, orbit.mode)[0] - P(ym, orbit.mode)[0]) / (2 * e)
    scaled = J[:, free] * orbit.scale[free][None, :] / orbit.scale[:, None]
    assert np.max(np.abs(scaled - D * orbit.scale[free][None, :] / orbit.scale[:, None])) < 1e-6 * np.max(
        np.abs(scaled))
    assert np.count_nonzero(np.abs(orbit.multipliers) < 1e-12) >= d.size


def test_a_continued_iwan_branch_keeps_its_labels_whole_and_matches_brute_force():
    """Before, the branch from 280 rad/s stalled near 286.9 after 400 points, with multipliers of 5e5."""
    branch = continuation(BladePair(friction="iwan"), "omega", 284.0, 290.0)
    assert branch.message.startswith("reached")
    assert np.max(np.abs(branch.multipliers)) < 1.0
    labels = branch.states[:, 12:]
    assert np.array_equal(labels, np.rint(labels))
    for k in (0, len(branch.params) // 2, -1):
        model = BladePair(friction="iwan", omega=float(branch.params[k])).build()
        settled = simulate(model, periods=300, steps_per_period=1000).final_state[:12]
        scale = np.max(np.abs(branch.states[:, :12]), axis=0)
        assert_allclose(branch.states[k, :12] / scale, settled / scale, atol=1e-8)


def test_an_iwan_ring_orbit_is_found_from_a_short_transient():
    """A preloaded Iwan ring: a few periods from rest leave a residual Newton's method must take to tol
    (before, no step along the Newton direction reduced it). The Jacobian is the replayed tangent (the Iwan
    flow is affine for given labels), nothing of it in a label."""
    model = BladedDisk(blades=4, engine_order=1, friction="iwan", gap=-1e-5, omega=280.0).build()
    ig = make_integrator(model, kernel="contact")
    orbit = find_periodic_orbit(model, transient=5, integrator=ig, workers=1)
    assert orbit.history[0] > 1e-8 and orbit.history[-1] <= 1e-10
    r = simulate(model, periods=400, kernel="contact")
    n = orbit.state.size
    free = np.setdiff1d(np.arange(n), ig.discrete_states)
    scale = np.max(np.abs(orbit.y), axis=0)
    assert_allclose(orbit.state[free] / scale[free], r.final_state[:n][free] / scale[free], atol=1e-8)


def test_a_preloaded_iwan_ring_s_reduced_branch_starts_on_an_orbit_of_the_whole_ring():
    """The first orbit of a cyclic continuation carries labels with the rounding of its scaling; read as they are,
    the turn's check refused it on every preloaded Iwan ring whose period turns a blade onto another (8 blades
    under engine order 2 here; the README's 24-blade ring). It is an orbit of the whole ring over a period: the
    whole map, integrated from it, brings it back, labels and all."""
    values = dict(blades=8, engine_order=2, friction="iwan", gap=-1e-5)
    branch = continuation(BladedDisk(**values), "omega", 280.0, 280.3, cyclic=True, max_points=3, workers=1)
    assert len(branch.params) == 3
    ig = make_integrator(BladedDisk(**values, omega=float(branch.params[0])).build(), kernel="contact")
    y = branch.states[0]
    mode = ig.mode_of(np.append(y, np.zeros(ig.n_state - y.size)))
    Py, _ = PeriodMap(ig, 1, jacobian="differences", workers=1)(y, mode)
    d = ig.discrete_states
    free = np.setdiff1d(np.arange(y.size), d)
    scale = np.max(np.abs(branch.states[:, free]), axis=0)
    scale = np.maximum(scale, 1e-3 * scale.max())
    assert_allclose(Py[free] / scale, y[free] / scale, rtol=0, atol=1e-9)
    assert np.array_equal(np.rint(Py[d]), np.rint(y[d])) and np.any(np.rint(y[d]) != 0.0)


def test_a_label_that_the_ring_s_turn_does_not_bring_back_is_no_travelling_wave():
    """``CyclicSymmetry.comes_back`` counts a label that differs from the one it is turned onto as 1 (as
    ``residual_size`` does): scaled by ``LABEL_SCALE`` it read as ``1e-12`` before, below ``WAVE_TOL``."""
    from blademodel.orbits.cyclic import CyclicSymmetry
    from blademodel.orbits.shooting import _scale_of_excursions
    # engine order 2 on 4 blades: the reduced map covers T / 2, and a period's two turns bring each blade's
    # state onto the blade two places on (for engine order 1 they would bring it back onto itself)
    cfg = BladedDisk(blades=4, engine_order=2, friction="iwan", gap=-1e-5, omega=280.0)
    ig = make_integrator(cfg.build(), kernel="contact")
    sym = CyclicSymmetry(cfg, ig)
    assert not np.array_equal(sym._powers[-1], np.arange(ig.n_physical))
    n, d = ig.n_physical, ig.discrete_states
    y = np.zeros(n)
    free = np.setdiff1d(np.arange(n), d)
    y[free] = 1e-6   # every blade alike: any turn brings the state back
    scale = _scale_of_excursions(np.full(n, 1e-6), 0, d)
    assert sym.comes_back(y, scale) == 0.0
    y[d[0]] = 1.0   # one element of one contact slips, the contact two places on sticks
    assert sym.comes_back(y, scale) >= 1.0
    y[d] = 1.0      # all alike again
    assert sym.comes_back(y, scale) == 0.0
    # labels carrying the rounding of a corrected point's scaling (1e-11 on the preloaded 24-blade ring, whose
    # first orbit was refused so) are read as whole numbers, as the map reads them
    y[d] += np.random.default_rng(0).uniform(-1e-11, 1e-11, d.size)
    assert sym.comes_back(y, scale) == 0.0
    y[d[0]] = -1.0
    assert sym.comes_back(y, scale) >= 1.0


class _DriftingLabel(FrictionLaw):
    """A Coulomb-like law with a 'label' whose rate is not zero: refused."""

    modes = ("slip",)
    states = ("s",)
    discrete_states = ("s",)

    def __init__(self, rate=1, names=("s",)):
        self._rate = rate
        self.discrete_states = names

    def parameters(self):
        return {"mu": as_param(0.5, "mu", field="friction: mu")}

    def force(self, mode, ctx):
        return ctx.params["mu"] * ctx.N

    def rates(self, mode, ctx):
        return {"s": sp.Integer(self._rate) * ctx.v}

    def guards(self, mode, ctx):
        return []

    def entry(self, ctx):

        return [Candidate("slip")]


def test_a_discrete_state_must_be_a_state_with_zero_rate():
    with pytest.raises(FrictionLawError, match=r"rates\('slip', ctx\)\['s'\].*discrete_states"):
        check_law(_DriftingLabel(rate=1))
    with pytest.raises(FrictionLawError, match=r"discrete_states = \('q',\) names \['q'\]"):
        check_law(_DriftingLabel(rate=0, names=("q",)))
    check_law(_DriftingLabel(rate=0))


def test_a_reset_within_one_mode_repeated_within_an_instant_counts_once_in_the_signature():
    """The signature (a multiset of transitions) counts a law's reset that keeps its mode (an Iwan element's label)
    once where it repeats within the kernel's event bracket; a transition that changes the mode, or one repeated
    later, counts each time."""
    from blademodel.orbits.period_map import MapRun
    h = 1e-5
    t = np.array([0.0, 0.6e-10 * h, 1.2e-10 * h, 0.3 * h, 0.5 * h, 0.5 * h + 1e-10 * h])
    guard = np.array([0, 1, 1, 1, 2, 2])
    frm = np.array([0, 1, 1, 1, 1, 2])
    to = np.array([1, 1, 1, 1, 2, 1])
    log = (t, guard, frm, to)
    run = MapRun(start=None, mode=0, fired=[], end=None, mode_end=0, t=None, Y=None, states=None, log=log, n_log=6,
                 events=6, instant=2e-10 * h)
    assert run.signature() == ((0, 0, 1), (1, 1, 1), (1, 1, 1), (2, 1, 2), (2, 2, 1))
    never = MapRun(start=None, mode=0, fired=[], end=None, mode_end=0, t=None, Y=None, states=None, log=log, n_log=6,
                   events=6)
    assert len(never.signature()) == 6


def test_a_closing_cascade_located_event_by_event_does_not_read_as_grazing():
    """At 288.4662 rad/s the second element that slips as the contact closes was located 5 brackets after the first
    at one value and in the same event at the next (and 54 or 146 brackets after it at 288.4595), so that the
    branch reported three grazing points within 1.5e-5 rad/s there. The window of ``CASCADE_BRACKETS`` takes such a
    cascade as one: the orbits over 288.4660 ... 288.4665 have one signature."""
    from blademodel.orbits.period_map import CASCADE_BRACKETS
    signatures, gaps = set(), []
    guess = None
    for omega in np.linspace(288.4660, 288.4665, 11):
        model = _iwan_pair(float(omega))
        ig = make_integrator(model)
        orbit = find_periodic_orbit(model, transient=100, integrator=ig) if guess is None else \
            find_periodic_orbit(model, guess=guess, integrator=ig)
        guess = orbit.state
        P = PeriodMap(ig, 1)
        P(orbit.state, orbit.mode)
        run = P.last_run
        signatures.add(run.signature())
        t, guard, frm, to = (c[:run.n_log] for c in run.log)
        bracket = ig.event_tol * float(run.t[1] - run.t[0])
        kept = np.flatnonzero(frm == to)
        gaps += [(t[j] - t[i]) / bracket for i, j in zip(kept[:-1], kept[1:]) if guard[i] == guard[j]]
    gaps = np.array(gaps)
    assert len(signatures) == 1
    # the cascades' gaps lie far inside the window, the elements' own slips far outside
    assert np.max(gaps[gaps < CASCADE_BRACKETS]) < 0.01 * CASCADE_BRACKETS
    assert np.min(gaps[gaps >= CASCADE_BRACKETS]) > 100 * CASCADE_BRACKETS


def test_the_iwan_closing_cascade_does_not_read_as_grazing():
    """At 283.3122 rad/s one stick->slip+ follows the contact's closing within its bracket, at 283.31225 two: 76
    and 77 events a period, and the signatures differed, so that the branch reported a grazing point at nearly
    every step there (148 from 280 to 320 rad/s). Over 283.3120 ... 283.3128 the orbits' signatures are one."""
    signatures = set()
    for omega in np.linspace(283.3120, 283.3128, 9):
        model = _iwan_pair(float(omega))
        ig = make_integrator(model)
        orbit = find_periodic_orbit(model, transient=100, integrator=ig)
        P = PeriodMap(ig, 1)
        P(orbit.state, orbit.mode)
        signatures.add(P.last_run.signature())
    assert len(signatures) == 1
