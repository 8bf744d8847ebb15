"""The labels of stability changes located at a kink of the period map, where no multiplier lies on the unit
circle (:func:`blademodel.orbits.arclength._kinds_at_kink`)."""

from __future__ import annotations

import numpy as np
import pytest

from blademodel.orbits import continuation
from blademodel.orbits.arclength import _kinds_at_kink
from blademodel.orbits.branch import SpecialPoint
from blademodel.zheng2022 import BladePair

#: The kinds of the smooth bifurcations, whose critical multiplier lies on the unit circle.
SMOOTH = ("fold", "branch-point", "period-doubling", "neimark-sacker")


def _point(kind, multiplier):
    return SpecialPoint(kind=kind, param=1.0, state=np.zeros(2), multiplier=complex(multiplier), index=0, mode=0)


@pytest.mark.parametrize("turned", [False, True])
def test_a_stability_change_off_the_circle_is_a_kink_s(turned):
    """Off the circle (by more than 0.05) a Neimark-Sacker or period-doubling label is a border collision where the
    branch goes on, and a nonsmooth fold where it turns (a border collision too); on the circle a label stays, and a
    grazing point stays what it is."""
    found = [_point("neimark-sacker", 0.458 * np.exp(2.8j)), _point("period-doubling", -0.9),
             _point("neimark-sacker", np.exp(1j)), _point("grazing", 0.3), _point("border-collision", 4.97)]
    kinds = [q.kind for q in _kinds_at_kink(found, turned)]
    if turned:
        assert kinds == ["nonsmooth-fold", "nonsmooth-fold", "neimark-sacker", "grazing", "nonsmooth-fold"]
    else:
        assert kinds == ["border-collision", "border-collision", "neimark-sacker", "grazing", "border-collision"]
    assert [q.multiplier for q in _kinds_at_kink(found, turned)] == [q.multiplier for q in found]


def test_a_turn_located_off_the_circle_is_a_nonsmooth_fold_both_ways():
    """The Iwan pair in F0 up from 3 N turns at the kink near 3.712318 N that the branch down from 4 N reports as a
    nonsmooth fold (tests/test_continuation.py): its location's trials lie on either side at 0.987 and 1.051 to the
    last, and the point it returns has a multiplier of modulus 0.987, off the circle by more than a continuous one
    moves over the location's bracket. It was labelled a fold, as the multiplier lay within 0.05 of the circle; it is
    a nonsmooth fold, as going down. The smooth fold at 3.848 N keeps its label and its multiplier on the circle."""
    b = continuation(BladePair(friction="iwan", F0=3.0), "F0", 3.0, 5.0, workers=1)
    assert b.message == "reached F0 = 5"
    (nf,), (fold,) = b.points("nonsmooth-fold"), b.points("fold")
    assert 3.7123 < nf.param < 3.7124 and abs(abs(nf.multiplier) - 1) > 1e-2
    assert 3.84 < fold.param < 3.86 and abs(abs(fold.multiplier) - 1) < 1e-3


@pytest.mark.slow
def test_the_iwan_branch_s_smooth_bifurcations_lie_on_the_circle():
    """The Iwan pair down in omega from 600 to 150 rad/s at 2000 steps a period: every fold, period doubling and
    Neimark-Sacker bifurcation it reports has its multiplier on the unit circle (to 1e-3), and it reports the same
    eight turns (folds, smooth or not) and eight period doublings as the branch up (to 1e-3 rad/s).

    One turn is not the same kind both ways, and rounding decides which part of it each way resolves. Measured
    (2026-11-29): near 450.41 rad/s, where the orbits' events change at every point, the stable arm ends at a kink at
    450.41007 rad/s, its real multiplier 0.784 there against 1.027 on the unstable arm: going down, that is a nonsmooth
    fold. Going up, the step past it landed at 450.409758 rad/s on the unstable side, and the location between there
    and the last stable point found a short arm that turns smoothly at 450.4097598 rad/s (orbits with multipliers
    0.998 to 1.00004 at that value to 3e-10 rad/s, over 1.3e-4 of the scaled state): a fold with multiplier
    1.0000004, 3.1e-4 rad/s below the kink, which the branch down steps over. At the stop before (the same
    continuation code, another environment) the two ways had it the other way round: up reported the kink, as a fold
    with a multiplier of modulus 1.026 (a nonsmooth fold now: test_a_turn_located_off_the_circle_is_a_nonsmooth_fold_
    both_ways), and down a fold on the circle 3e-4 rad/s from it.

    With the Iwan elements' missed slips (tests/test_drifted_guards.py) and a rule for the field's column since
    taken out, the branch down reported windows of instability at kinks near 165.56 rad/s, three of their stability
    changes as Neimark-Sacker bifurcations with a multiplier of modulus 0.458: border collisions."""
    down = continuation(BladePair(friction="iwan"), "omega", 600.0, 150.0, max_points=3000, workers=1,
                        steps_per_period=2000)
    up = continuation(BladePair(friction="iwan"), "omega", 150.0, 600.0, max_points=3000, workers=1,
                      steps_per_period=2000)
    assert down.message == "reached omega = 150" and up.message == "reached omega = 600"
    smooth = [q for q in down.special if q.kind in SMOOTH]
    assert smooth and all(abs(abs(q.multiplier) - 1) < 1e-3 for q in smooth)
    for kinds in (("fold", "nonsmooth-fold"), ("period-doubling",)):
        a = np.sort([q.param for q in down.special if q.kind in kinds])
        b = np.sort([q.param for q in up.special if q.kind in kinds])
        assert a.size == b.size == 8
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-3)
