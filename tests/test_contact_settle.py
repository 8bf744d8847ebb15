"""A start state past a guard of its modes, on the per-contact kernel: settled at ``t = 0``.

The kernel fires a guard when it crosses zero within a step. A section state on the far
side of a switching boundary of the modes it is given (a Newton iterate, where an orbit's
switching time passes the section) is settled first
(:meth:`~blademodel.numeric.contact_kernel.ContactIntegrator.settle`): its guards past zero
fire at once, the friction problem follows, and the period map's tangent takes their
resets and stick projection (:meth:`~blademodel.numeric.contact_tangent.ContactTangent.settle_jacobian`).
Each case takes a state of a ring's orbit a few steps after one of its events and gives it
the modes from before that event.
"""

import numpy as np
import pytest

from blademodel.orbits.period_map import PeriodMap
from test_contact_tangent import ring_orbit, scaled_error


def _past_an_event(ig, orbit, guard_name, frm, to, after=2, push=None):
    """A recorded state of ``orbit``'s run ``after`` steps past the first isolated event of ``guard_name`` from
    mode ``frm`` to ``to``, its modes there, and the same modes with that contact still in ``frm``."""
    P = PeriodMap(ig, 1, jacobian="tangent", workers=1)
    r = P.run(orbit.state, orbit.mode.copy())
    lt, lc, lg, lf, lto = r.log
    names = ig.meta["contact_guards"]
    for i in range(r.n_log):
        j = int(lc[i])
        if lg[i] < 0 or names[j][lf[i]][lg[i]] != guard_name or (lf[i], lto[i]) != (frm, to):
            continue
        k = int(np.searchsorted(r.t, lt[i])) + after
        near = [q for q in range(r.n_log) if q != i and r.t[k - after - 1] <= lt[q] <= r.t[k] + 1e-12]
        if near or k >= r.t.size - 1:
            continue
        right = r.modes[k].astype(np.int64)
        wrong = right.copy()
        wrong[j] = frm
        y = r.states[k, :ig.n_physical].copy()
        if push is not None:
            push(ig, y, j)
        return y, right, wrong, j
    raise AssertionError(f"no isolated {guard_name!r} event from {frm} to {to} in the orbit")


def _slipping_backwards(ig, y, j):
    """Give contact ``j`` (stuck, its slip velocity zero) a slip velocity of ``-1e-3`` of the state's largest
    velocity, along ``M^-1 G_j^T``."""
    t = ig.tables
    d = t.invm * t.G[j]
    u = y[t.n:2 * t.n]
    u -= 1e-3 * np.max(np.abs(u)) * d / float(t.G[j] @ d)


def _beyond_its_limit(ig, y, j):
    """Stretch contact ``j``'s Jenkins spring (slipping, ``kd z = mu N``) by ``1e-3`` more."""
    y[2 * ig.tables.n + int(ig.tables.cso[j])] *= 1.0 + 1e-3


def _check_settled_map(ig, orbit, y, wrong, j, frm, to):
    """The settled start fired ``j``'s transition from ``frm`` to ``to``; the map's tangent is the difference
    quotients of the settled map; unsettled, the kernel ends elsewhere. Returns the map and its end."""
    P = PeriodMap(ig, 1, jacobian="tangent", workers=1)
    end, _ = P(y, wrong.copy())
    r = P.last_run
    assert r.fired and any(e[0] == j and e[2:] == (frm, to) for e in r.fired[0][2])
    s = P.derivatives(y, wrong.copy())
    ref = P.differences(y, wrong.copy(), orbit.scale, 1e-5)
    assert scaled_error(s.monodromy, ref, orbit.scale) < 1e-6
    full = np.zeros(ig.n_state)
    full[:ig.n_physical] = y
    status, _, _ = ig.advance(full, wrong.copy(), 0, 1, n_transient=0)   # the kernel unsettled
    assert status == 0
    assert np.max(np.abs(full[:ig.n_physical] - end) / orbit.scale) > 1e-3
    return P, end


@pytest.mark.parametrize("friction, guard, frm, to", [("coulomb", "close", 0, 2), ("bilinear", "open", 3, 0)])
def test_a_start_past_a_guard_ends_as_the_flow_that_crossed_it(friction, guard, frm, to):
    """The tuned 4-blade ring's orbit at 286 rad/s, two steps after a contact closed (in slip) or opened (the
    bilinear law's state reset to zero), given the modes from before. Settled, the start takes the modes that
    the flow took and the map ends where it ends from them; its tangent is the difference quotients of the
    settled map, and so the tangent from those modes (the opening's reset of the law state is differentiated,
    though its closing again later in the period makes it moot for the map). Unsettled, the
    contact would stay open and penetrating, or closed in tension: another end altogether."""
    ig, orbit = ring_orbit(friction)
    y, right, wrong, j = _past_an_event(ig, orbit, guard, frm, to)
    P, end = _check_settled_map(ig, orbit, y, wrong, j, frm, to)
    assert np.array_equal(P.last_run.mode, right)
    end_right, _ = P(y, right.copy())
    assert not P.last_run.fired
    np.testing.assert_allclose(end / orbit.scale, end_right / orbit.scale, rtol=0, atol=1e-9)
    assert scaled_error(P.derivatives(y, wrong.copy()).monodromy, P.derivatives(y, right.copy()).monodromy,
                        orbit.scale) < 1e-9


@pytest.mark.parametrize("friction, guard, frm, to, push", [
    ("coulomb", "slip+: v=0", 2, 1, _slipping_backwards),
    ("bilinear", "stick->slip+", 1, 2, _beyond_its_limit)])
def test_a_start_pushed_past_a_guard_is_settled_with_its_projection(friction, guard, frm, to, push):
    """Two steps after a contact stuck (Coulomb), given ``slip+`` and a slip velocity a little below zero:
    settled, it sticks and its velocities are projected onto the stick constraint, which the tangent takes
    (its derivative has the projection's rank). Two steps after a Jenkins contact began to slip, its spring
    stretched a little beyond ``mu N`` and given ``stick``: settled, it slips."""
    ig, orbit = ring_orbit(friction)
    y, right, wrong, j = _past_an_event(ig, orbit, guard, frm, to, push=push)
    P, _ = _check_settled_map(ig, orbit, y, wrong, j, frm, to)
    if friction == "coulomb":
        D = P._contact_tangent.settle_jacobian(*P.last_run.fired[0])
        assert np.linalg.matrix_rank(D) < ig.n_physical


def test_a_consistent_start_is_left_as_it_is():
    """On the orbit itself nothing fires and the state is not touched."""
    ig, orbit = ring_orbit("coulomb")
    full = np.zeros(ig.n_state)
    full[:ig.n_physical] = orbit.state
    before = full.copy()
    cm, events = ig.settle(full, orbit.mode.copy())
    assert events == [] and np.array_equal(cm, orbit.mode) and np.array_equal(full, before)
