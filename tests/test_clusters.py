"""The per-contact kernel steps each cluster (all that is coupled to a contact whose guard crossed) through
its events on its own; the rest of the model keeps the whole step (``docs/solver.md``)."""

import sys
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_array_equal

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs" / "tools"))
from ring_invariants import over_the_limit, slip_against, turned_residual  # noqa: E402

from blademodel.components import Contact, HarmonicForce, Mass, Spring
from blademodel.config import BladedDisk
from blademodel.model import Model
from blademodel.numeric import simulate

#: The cut that splits a 6-blade ring into two chains: contacts c3 (blades 3-4) and c6 (blades 6-1) never close.
CUT = {2: {"gap": 1.0}, 5: {"gap": 1.0}}


def _two_chains(law, b_contacts):
    """A 6-blade ring cut into chain A (blades 1-3, contacts c1, c2) and chain B (blades 4-6, c4, c5).

    ``b_contacts=False`` opens chain B's gaps so wide that it never touches: a linear chain, no events.
    """
    contacts = dict(CUT)
    if not b_contacts:
        contacts.update({3: {"gap": 1.0}, 4: {"gap": 1.0}})
    return BladedDisk(blades=6, engine_order=3, friction=law, mistuning_std=0.02, mistuning_seed=4,
                      contacts=contacts).build()


@pytest.mark.parametrize("law", ["coulomb", "bilinear"])
def test_events_elsewhere_leave_a_chain_unchanged_to_the_bit(law):
    """Chain A's motion is the same, bit for bit, whether or not chain B has events.

    A kernel that splits every step of the whole model at every event (as this one did before it
    stepped clusters) moves chain A along a different grid of sub-steps whenever chain B hits or slips,
    and chain A then differs by the integration error.
    """
    a_dofs = 12   # x1, y1 ... x3, y3 and their velocities: rows 0-5 and 12-17 of the state
    rows = [*range(0, 6), *range(12, 18)]
    both = simulate(_two_chains(law, True), transient=10, periods=4)
    alone = simulate(_two_chains(law, False), transient=10, periods=4)
    assert len(rows) == a_dofs
    b_events = [g for g in both.events["guard"] if g.split(":")[0] in ("c4", "c5")]
    a_events = [g for g in both.events["guard"] if g.split(":")[0] in ("c1", "c2")]
    assert len(b_events) > 50 and len(a_events) > 50
    assert len(alone.events["t"]) == len(a_events)
    assert_array_equal(both.y[:, rows], alone.y[:, rows])
    assert_array_equal(both.final_state[rows], alone.final_state[rows])
    t_a = [t for t, g in zip(both.events["t"], both.events["guard"]) if g.split(":")[0] in ("c1", "c2")]
    assert_array_equal(t_a, alone.events["t"])
    assert np.all(np.diff(both.events["t"]) >= 0)   # the log is in time order across clusters


def _cradle():
    """Three masses on a line; mass 1 hits mass 2, which is 1e-8 m from mass 3 (which nothing else moves)."""
    ms = [Mass(str(i), 1.0, dofs=("x",)) for i in (1, 2, 3)]
    contacts = (Contact(ms[0], ms[1], gap=1e-4, alpha=np.pi / 2, k=1e7, name="c12"),
                Contact(ms[1], ms[2], gap=1e-8, alpha=np.pi / 2, k=1e7, name="c23"))
    return Model(tuple(ms), tuple(Spring(f"x{i}", 100.0) for i in (1, 2, 3)), (),
                 (HarmonicForce(ms[0], 1.0, 10.0),), contacts)


def test_a_boundary_contact_that_closes_after_all_restarts_the_step():
    """Mass 1's impact pushes mass 2 onto mass 3 within the same step; c23 did not cross in the whole model's
    step (mass 2 was still), so the kernel begins that step again with masses 1-3 as one cluster.

    The reference splits every coordinate's step at every event (``local_events=False``). Mass 3 is exactly
    at rest until c23 first closes (splitting its steps changes nothing), so up to and including that step
    the two runs must agree to the bit; without the restart mass 3 would still be at rest there.
    """
    S = 8000
    y0 = np.zeros(6)
    y0[3] = 1.0                                            # mass 1 at 1 m/s toward mass 2
    local = simulate(_cradle(), periods=1, steps_per_period=S, y0=y0, max_log=100)
    whole = simulate(_cradle(), periods=1, steps_per_period=S, y0=y0, max_log=100, local_events=False)
    assert local.counters["cluster_restarts"] >= 1 and whole.counters["cluster_restarts"] == 0
    assert local.settings["local_events"] and not whole.settings["local_events"]
    first = min(t for t, g in zip(local.events["t"], local.events["guard"]) if g == "c23: close")
    k = int(np.ceil(first / (local.period / S)))           # the step in which c23 first closed
    assert np.all(local.y[:k, 2] == 0.0) and local.y[k, 2] != 0.0 and local.y[k, 5] != 0.0
    assert_array_equal(local.y[:k + 1], whole.y[:k + 1])
    assert np.max(np.abs(local.y[-1] - whole.y[-1])) > 0   # later, mass 3's steps are split in one run only


@pytest.mark.parametrize("local", [True, False], ids=["clusters", "whole model"])
def test_a_tuned_bilinear_ring_converges_at_fourth_order(local):
    """Symmetric contacts of a tuned ring have simultaneous events, in separate clusters or, stepped as one,
    in one event.

    The final state converges as ``h^4`` with the same events at every step size (stepped as one, the kernel
    did not converge here, errors of 2.5 to 7 % at every step size, until a contact fired with another kept
    its guards on the boundary: ``mark_near``).
    """
    model = BladedDisk(blades=4, engine_order=2, friction="bilinear").build()
    runs = {S: simulate(model, transient=20, periods=5, steps_per_period=S, event_tol=1e-12, record_every=S,
                        local_events=local)
            for S in (1000, 2000, 4000, 16000)}
    ref = runs[16000].final_state
    err = [np.max(np.abs(runs[S].final_state - ref)) / np.max(np.abs(ref)) for S in (1000, 2000, 4000)]
    assert len({r.counters["events"] for r in runs.values()}) == 1
    assert err[0] < 1e-4 and all(e1 / e2 > 12 for e1, e2 in zip(err, err[1:])), err


@pytest.mark.parametrize("local", [True, False], ids=["clusters", "whole model"])
def test_contacts_closing_in_the_same_instant_keep_their_friction_limit(local):
    """The symmetric contacts 0 and 2 of a tuned ring close in the same instant; one is fired a rounding error
    before its own root (``first_near_crossing``), so its stick guard ``mu N - |f|`` starts at -2e-16.

    It must still slip when ``|f|`` reaches ``mu N``. Stepped as one (``local_events=False``) the kernel used to
    miss that guard (it never changed sign) and kept the contact sticking at ``|f| = mu N + 38 N``.
    """
    model = BladedDisk(blades=4, engine_order=2, friction="bilinear").build()
    r = simulate(model, periods=1, steps_per_period=8000, event_tol=1e-12, local_events=local)
    c = r.contacts
    stick = c["modes"] == c["mode_names"][0].index("stick")
    assert stick.any() and (c["modes"] > 1).any()
    assert over_the_limit(r, "stick") <= 1e-9
    contact = np.asarray(r.events["contact"])
    t0, t2 = (r.events["t"][contact == c["names"][j]][:4] for j in (0, 2))
    np.testing.assert_allclose(t0, t2, rtol=0, atol=1e-9 * r.period)   # both close, then slip, at once


def test_marks_of_early_fired_contacts_are_a_runs_state():
    """A contact fired before its own root reads its guards shifted until its next transition (``mark_near``).

    The marks belong to the run: a run split into one call per period equals one call to the bit while marks
    stay alive across the calls; a new start (``mode_of``, or a call from another state) forgets them.
    """
    from blademodel.numeric import make_integrator
    from blademodel.numeric.contract import W_NNEAR

    model = BladedDisk(blades=4, engine_order=2, friction="bilinear").build()
    integ = make_integrator(model, steps_per_period=8000, event_tol=1e-12, local_events=False)
    y0 = integ.initial_state()
    m0 = integ.mode_of(y0)
    whole = y0.copy()
    integ.advance(whole, m0, 0, 6)
    split, m, alive = y0.copy(), integ.mode_of(y0.copy()), []
    for p in range(6):
        _, m, _ = integ.advance(split, m, p, p + 1)
        alive.append(int(integ.WI[W_NNEAR]))
    assert any(alive[:-1]), alive           # marks carried across at least one call
    assert_array_equal(split, whole)
    integ.mode_of(y0.copy())
    assert integ.WI[W_NNEAR] == 0
    for p in range(6, 30):                   # on from the last end, until a call ends with marks alive
        _, m, _ = integ.advance(split, m, p, p + 1)
        if integ.WI[W_NNEAR] > 0:
            break
    assert integ.WI[W_NNEAR] > 0
    a, b = y0.copy(), y0.copy()
    integ.advance(a, m0, 0, 2)              # another state than the last call's end: a new run
    fresh = make_integrator(model, steps_per_period=8000, event_tol=1e-12, local_events=False)
    fresh.advance(b, fresh.mode_of(y0.copy()), 0, 2)
    assert_array_equal(a, b)


def _three_fold_residual(r, blades):
    """Largest difference between the final state and the state a third of the ring around, over the largest."""
    return turned_residual(r, blades, blades // 3)


@pytest.mark.parametrize("local", [True, False], ids=["clusters", "whole model"])
def test_a_tuned_ring_keeps_its_symmetry_through_slips_that_end_together(local):
    """24 blades at EO 3: the contacts a third of the ring apart end their slips in the same instant, where the
    stick guard starts at zero with a zero rate (the spring unloads exactly as the slip ends).

    Stepped as one, the third twin's event came 1e-17 s after the others'; in that bracket a stuck contact's
    guard read +1e-20, then -1e-20, and it slipped again while its twins stuck: the symmetry was broken by 6e-2
    after one period. Crossings inside a sub-step of a contact that has just changed mode and did not cross over
    the sub-step are rounding noise (``mark_suspects``).
    """
    model = BladedDisk(blades=24, engine_order=3, friction="bilinear").build()
    r = simulate(model, periods=3, steps_per_period=2000, event_tol=1e-12, local_events=local, record_every=2000)
    assert r.counters["events"] > 200
    assert _three_fold_residual(r, 24) < 1e-10


@pytest.mark.parametrize("local", [True, False], ids=["clusters", "whole model"])
def test_a_preloaded_coulomb_ring_keeps_its_symmetry_where_its_closing_contact_sticks(local):
    """24 blades at EO 3, every contact pressed (``gap < 0``): rigid stick chains form and break all round the
    ring, among them the closing contact's (c24 with c1), whose stick factor's row spans the whole ring.

    Per cluster, that row kept entries of an older factor (when its chain reached c4 and c5) and read them
    once c4 and c5 stuck again in another cluster: the closing chain's stick forces took a share of that
    cluster's, and the blades a third of the ring apart differed by 1e-4 after two periods from rest (the cyclic
    reduction then refused the ring's orbit). A refactor now writes the zeros of another chain's entries.
    """
    model = BladedDisk(blades=24, engine_order=3, friction="coulomb", gap=-1e-5, omega=250.0).build()
    r = simulate(model, periods=2, local_events=local, record_every=1000)
    assert r.counters["events"] > 600
    assert _three_fold_residual(r, 24) < 1e-10


def test_a_jenkins_slider_that_stops_for_a_dip_of_its_velocity_slips_again_at_its_limit():
    """A tuned bilinear ring of 24 blades (``gap = 2e-5`` m, ``F0 = 150`` N, 290 rad/s) from rest: at
    ``t = 2.304 T`` three twin sliders stop for a dip of their velocity shorter than a step, and their stick guards
    ``mu N - kd z`` start at the drift of ``z`` through the slip: ``+2e-14`` N on one, ``-9.7e-11`` N on the two
    others. A guard that starts below zero never crossed it, so those two stuck on with ``|f|`` up to
    ``1.27 mu N`` while the first slipped again. An elastic law's friction guard that a regular transition
    leaves on its wrong side by such a drift is now read from the boundary (``mark_drifted``)."""
    model = BladedDisk(blades=24, engine_order=3, friction="bilinear", gap=2e-5, F0=150.0, omega=290.0).build()
    r = simulate(model, periods=3)
    c = r.contacts
    stick = c["modes"] == c["mode_names"][0].index("stick")
    assert stick.any() and (c["modes"] > 1).any()
    assert over_the_limit(r, "stick") <= 1e-6


def test_a_coulomb_contact_a_neighbour_s_event_pushes_past_its_limit_is_left_to_the_friction_problem():
    """A mistuned Coulomb ring of 24 blades (engine order 1, ``F0 = 150`` N, 330 rad/s): at ``t = 2.9 T`` contact
    10, which had just stuck (a suspect: ``mark_suspects``), reads its stick guard at ``-11`` N at a neighbour's
    event, before the friction problem redistributes the chain's stick forces. Put on the boundary there, it kept
    that offset after the problem left it stuck, and stuck on at up to ``1.19 mu N``. The friction problem
    settles a rigid contact's guards; suspects are now put on the boundary only where it does not."""
    model = BladedDisk(blades=24, engine_order=1, friction="coulomb", F0=150.0, omega=330.0, mistuning_std=0.02,
                       mistuning_seed=3).build()
    r = simulate(model, periods=3)
    assert r.counters["friction_pivots"] > 0
    assert r.counters["max_cone_ratio"] <= 1.0 + 1e-9


def test_an_iwan_ring_keeps_every_element_within_its_limit():
    """The Iwan law sets a stopping element's stretch to its slip force exactly, and still its shared stick guard
    can start a rounding error below zero, never to cross it. On a tuned 8-blade Iwan ring at engine order 4
    (``F0 = 150`` N, 330 rad/s) contacts so stuck carried up to 9 % more than ``mu N`` (and 65 of 113 Iwan rings
    drawn by ``docs/tools/ring_invariants.py`` failed its checks). Read from the boundary (``mark_drifted``),
    every element slips at its limit."""
    model = BladedDisk(blades=8, engine_order=4, friction="iwan", F0=150.0, omega=330.0).build()
    r = simulate(model, periods=4)
    assert (r.contacts["modes"] != 0).any()
    assert over_the_limit(r) <= 1e-6


@pytest.mark.parametrize("local", [True, False], ids=["clusters", "whole model"])
def test_iwan_elements_that_slip_as_their_contact_closes_keep_a_tuned_ring_symmetric(local):
    """A tuned, preloaded Iwan ring of 24 blades at engine order 2 (``F0 = 60`` N, 290 rad/s): contacts 3 and 15
    (twins) close at ``t = 0.47403 T`` with every element at a slip force of nearly zero, and the motion loads
    elements 1 and 2. The closing's located root left contact 15 a larger normal force than contact 3 (rounding),
    so element 2 of contact 15 was still a hair inside its limit when element 1 slipped. Its guard, the least of
    the elements' through ``Min``, then dipped through zero and back within the step; without a rate for a
    ``Min`` guard the grazing check could not see it, the element stuck on, and the twins differed by ``5e-7``
    at the step's end, ``8e-6`` after two periods. The shared guard now has its critical element's rate
    (``law_codegen.rate_expr``)."""
    model = BladedDisk(blades=24, engine_order=2, friction="iwan", gap=-1e-5, F0=60.0, omega=290.0).build()
    r = simulate(model, periods=2, local_events=local, record_every=1000)
    assert r.counters["grazing_events"] > 0
    assert turned_residual(r, 24, 12) < 1e-10


def test_a_contact_released_by_the_friction_problem_after_its_own_event_slips_along_its_velocity():
    """A tuned, preloaded Coulomb ring of 6 blades at engine order 3 (``F0 = 60`` N, 290 rad/s): at ``t = 2.8537 T``
    contact 2's slip ends, its guard sends it to stick and the friction problem releases it into the opposite
    slip, at a velocity a rounding error past zero on the side its new mode forbids (``-6e-18`` m/s). Its guard then
    never crossed: it slipped on in ``slip+`` while its velocity fell to ``-1.4e-4`` m/s (``6.5e-3`` of the largest),
    friction feeding the motion. A contact the problem moves is read from the boundary whether or not its own
    guard fired in the event (``settle_event``)."""
    model = BladedDisk(blades=6, engine_order=3, friction="coulomb", gap=-1e-5, F0=60.0, omega=290.0).build()
    r = simulate(model, periods=3)
    assert r.counters["friction_pivots"] > 0
    assert slip_against(model, r) <= 1e-12


def test_a_slip_held_at_zero_velocity_by_the_ring_keeps_its_direction_through_a_neighbour_s_stick():
    """A tuned, preloaded Coulomb ring of 8 blades at engine order 4 (``F0 = 60`` N, 290 rad/s): adjacent blades are
    driven in antiphase, and while every other contact sticks the ring's closure holds the others' slip velocities
    at zero (their sum is zero and they are alike). At ``t = 1.35391 T`` contacts 1 and 3 stick; the friction
    problem projects the velocities onto their constraints, and contact 5, slipping on in ``slip+`` at ``+9e-19``
    m/s, is left at ``-9e-19``. Its guard then never crossed: 0.02 T later it slipped in ``slip+`` at ``-4e-5`` m/s
    (``1.7e-3`` of the largest velocity) and the ring's symmetry broke by ``6e-4``. A rigid slip whose velocity the
    problem's projection takes across zero is now read from the boundary (``settle_event``)."""
    model = BladedDisk(blades=8, engine_order=4, friction="coulomb", gap=-1e-5, F0=60.0, omega=290.0).build()
    r = simulate(model, periods=2)
    assert r.counters["friction_pivots"] > 0
    assert slip_against(model, r) <= 1e-12
    assert turned_residual(r, 8, 2) < 1e-10
