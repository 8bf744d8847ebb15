"""The field's column of the continuation's Jacobian where a difference quotient crosses a change of the events.

A difference across a kink of a map continuous in the field lies between the derivatives of the pieces either
side; across a jump of the map it is the jump over the shift. The Iwan pair's map jumps where its events change,
and the forward difference there turned the branch's tangent back along the part passed
(:meth:`blademodel.orbits.corrector._Context._field_column`).
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from blademodel.orbits import continuation, corrector, find_periodic_orbit
from blademodel.orbits.corrector import FIELD_SHIFTS, JUMP_RATIO, _Context
from blademodel.orbits.family import _Family
from blademodel.zheng2022 import BladePair


class _SteppedMap:
    """A period map whose value does not depend on the state: ``slope * lam`` below ``at``, above it the same
    continued with ``slope_above`` and ``jump`` added; the runs' signatures say which side they ran on."""

    def __init__(self, lam, at, slope, slope_above, jump):
        self.lam, self.at, self.slope, self.slope_above, self.jump = lam, at, slope, slope_above, jump
        self.last_run = SimpleNamespace(signature=lambda: self._side(lam))

    def _side(self, lam):
        return ("above",) if lam >= self.at else ("below",)

    def value(self, lam):
        if lam < self.at:
            return self.slope * lam
        return self.slope * self.at + self.slope_above * (lam - self.at) + self.jump

    def __call__(self, y, mode):
        return self.value(self.lam), mode

    def plain_signed(self, y, mode):
        return self.value(self.lam), self._side(self.lam)


def _stepped_context(at, slope_above, jump, lam=1.0):
    slope = np.array([2.0, -1.0])
    maps = {}

    def map_at(value):
        return maps.setdefault(value, _SteppedMap(value, at, slope, slope_above, jump))

    fam = SimpleNamespace(map_at=map_at, admits=lambda value: True, discrete=np.array([], dtype=np.int64))
    ctx = _Context(fam, np.ones(2), 1.0, 1e-10, 1e-6, 8)
    return ctx, map_at(lam), slope


@pytest.mark.parametrize("slope_above, jump, kept", [(np.array([3.0, -1.5]), 0.0, True),       # a kink
                                                     (np.array([2.0, -1.0]), 1e-5, False),     # a jump
                                                     (np.array([40.0, -20.0]), 0.0, False)])   # a steep kink
def test_the_forward_difference_is_kept_across_a_kink_and_not_across_a_jump(slope_above, jump, kept):
    """A change of the events half a shift ahead: across a kink (the pieces' slopes within a factor 1.5) the forward
    difference, the mean of the two slopes, is kept; across a jump of ``1e-5`` (ten times the slope over the shift) or
    a kink whose slopes differ twentyfold it lies more than ``JUMP_RATIO`` times the column from the difference back,
    which keeps the events, and that one is taken (the slope below, to rounding)."""
    d = FIELD_SHIFTS[0] * 1e-6
    ctx, P, slope = _stepped_context(1.0 + d / 2, slope_above, jump)
    column = ctx._field_column(P, 1.0, None, 0)
    forward = (P.value(1.0 + d) - P.value(1.0)) / d
    assert (np.linalg.norm(forward - slope) <= JUMP_RATIO * np.linalg.norm(slope)) == kept
    if kept:
        np.testing.assert_array_equal(column, forward)
        np.testing.assert_allclose(column, (slope + slope_above) / 2, rtol=1e-8)
    else:
        np.testing.assert_allclose(column, slope, rtol=1e-8)


def test_the_iwan_pair_s_field_columns_across_its_jumps_are_the_field_derivative():
    """The Iwan pair from 166.48 rad/s, 2000 steps a period (its orbit after 50 periods from rest, then shot at
    twelve values 1e-3 rad/s apart): where its events change the map jumps (where, rounding decides), and a forward
    difference that crosses one reads the field's derivative (the tangent's own parameter column, through the moving
    period) more than its own size off. Every column taken agrees with that derivative to 1e-4 (the differences' own
    error)."""
    cfg = BladePair(friction="iwan")
    w = 166.48
    span = 20.0
    fam = _Family(cfg, "omega", 1, dict(steps_per_period=2000, event_tol=1e-10, method="rk4", kernel="auto"), w,
                  bounds=(150.0, 170.0))
    orbit = find_periodic_orbit(None, integrator=fam.map_at(w).integrator, transient=50)
    ctx = _Context(fam, orbit.scale, span, 1e-10, 1e-6, 8)
    X, mode = np.append(orbit.state / orbit.scale, w / span), orbit.mode
    errors, forward_errors = [], []
    for k in range(12):
        lam = w + 1e-3 * k
        X[-1] = lam / span
        Xc, m, _ = ctx.correct_at_value(X, mode, jacobian=False)
        if Xc is None:   # (a shot refused on a switching boundary of the discrete flow)
            continue
        X, mode = Xc, m
        P, y = fam.map_at(lam), X[:-1] * ctx.scale
        dp, dT = fam.parameter_direction(lam, 1e-6 * lam, P.integrator.meta["params"])
        s = P.try_derivatives(y, mode, dp, dT)
        if s is None:   # (the tangent's replay left the logged events)
            continue
        exact = s.parameter / ctx.scale * span
        size = np.linalg.norm(exact)
        errors.append(np.linalg.norm(ctx._field_column(P, lam, y, mode) - exact) / size)
        forward = (fam.map_at(lam + 1e-6 * span).plain_signed(y, mode)[0] - P(y, mode)[0]) / ctx.scale / 1e-6
        forward_errors.append(np.linalg.norm(forward - exact) / size)
    assert len(errors) >= 8
    assert max(forward_errors) > JUMP_RATIO
    assert max(errors) < 1e-4


@pytest.mark.slow
def test_the_iwan_branch_through_its_jumps_reaches_its_end(monkeypatch):
    """The Iwan pair over 150 to 170 rad/s at 2000 steps a period (its events changing at almost every step). With
    the forward differences across the map's jumps, the tangent at 166.4829 rad/s pointed back along the part passed:
    every correction landed behind and was refused, the branch crept on by shots and turned back onto itself near
    165.7 rad/s (169 points; here it runs out of its 400). With the columns that keep the events it reaches 170 rad/s, every correction ahead."""
    from blademodel.orbits import arclength
    behind = []
    original = arclength._ran_back_unturned

    def watched(*args):
        refused = original(*args)
        behind.append(refused)
        return refused

    monkeypatch.setattr(arclength, "_ran_back_unturned", watched)
    b = continuation(BladePair(friction="iwan"), "omega", 150.0, 170.0, max_points=400, workers=1,
                     steps_per_period=2000)
    assert b.message == "reached omega = 170"
    assert behind and not any(behind)
    assert np.all(np.diff(b.params) > 0)   # every orbit stable, no turn: the field rises throughout
    monkeypatch.setattr(corrector, "FIELD_SHIFTS", (1.0,))   # the forward differences alone
    behind.clear()
    b = continuation(BladePair(friction="iwan"), "omega", 150.0, 170.0, max_points=400, workers=1,
                     steps_per_period=2000)
    assert b.message != "reached omega = 170" and any(behind)


@pytest.mark.parametrize("reduced", [False, True])
def test_an_unrecorded_run_has_the_recorded_run_s_end_and_signature(reduced):
    """``PeriodMap.plain_signed`` (the difference quotients' run: its event log kept, nothing recorded) ends where the
    recorded run ends, to the bit, with its signature: on the Iwan pair (its resets within one mode counted once
    where they repeat within an instant), and on a tuned 8-blade ring's map reduced by its symmetry (the contacts
    left out of the signature, the end turned)."""
    from blademodel.config import BladedDisk
    from blademodel.numeric.kernels import make_integrator
    from blademodel.orbits import PeriodMap
    from blademodel.orbits.cyclic import CyclicSymmetry
    if reduced:
        cfg = BladedDisk(blades=8, engine_order=3, friction="coulomb", omega=286.0)
        ig = make_integrator(cfg.build(), steps_per_period=600)
        orbit = find_periodic_orbit(None, integrator=ig, transient=50, jacobian="forward", workers=1)
        P = PeriodMap(ig, 1, symmetry=CyclicSymmetry(cfg, ig))
    else:
        ig = make_integrator(BladePair(friction="iwan").build(), steps_per_period=2000)
        orbit = find_periodic_orbit(None, integrator=ig, transient=30)
        P = PeriodMap(ig, 1)
    y = orbit.state * (1 + 1e-3)   # off the orbit: a run that does not come back
    run = P.run(y, orbit.mode)
    end, signature = P.plain_signed(y, orbit.mode)
    np.testing.assert_array_equal(end, P(y, orbit.mode)[0])
    assert signature == run.signature() and len(signature) > 0
    assert reduced == run.anonymous and (not reduced or np.max(np.abs(end - run.states[-1][:y.size])) > 0)
