"""Telling a branch that runs onto itself (a retrace, a closed branch) from one that turns at a fold."""

import numpy as np
import pytest

from blademodel.orbits.self_overlap import CHECK_EVERY, CHECKS, SelfOverlap

WEIGHTS = np.ones(3)   # two states and the field, unscaled


def _verdicts(curve):
    """Feed the points of ``curve`` (rows: two states, then the field) one by one: ``[(k, verdict)]`` where one."""
    track, pts, found = SelfOverlap(2), [], []
    for k, row in enumerate(curve):
        pts.append({"state": row[:2], "param": row[2]})
        step = float(np.linalg.norm(curve[k] - curve[k - 1])) if k else 0.0
        found_here = track.verdict(pts, WEIGHTS, step)
        if found_here is not None:
            found.append((k, found_here[0]))
    return found


def _helix(s):
    return np.column_stack([np.cos(3 * s), np.sin(3 * s), s])


def test_a_branch_that_turns_back_along_its_points_is_a_retrace():
    """Out along a helix and back along it (between its points, at other steps): a retrace, found within the
    checks it takes after the turn, and not before it."""
    out = _helix(np.linspace(0.0, 1.0, 101))
    back = _helix(np.arange(0.9963, 0.3, -0.0137))
    found = _verdicts(np.vstack([out, back]))
    assert found and found[0][1] == "back"
    assert 101 < found[0][0] <= 101 + (CHECKS + 1) * CHECK_EVERY


def test_a_closed_branch_is_found_once_it_comes_round():
    """A circle in (state, field) gone round twice, the second time at other steps: it comes round onto itself,
    found on the second round only."""
    first = np.linspace(0.0, 2 * np.pi, 120, endpoint=False)
    second = np.arange(2 * np.pi + 0.011, 4 * np.pi, 0.047)
    theta = np.concatenate([first, second])
    found = _verdicts(np.column_stack([np.sin(theta), 0.3 * np.sin(theta), np.cos(theta)]))
    assert found and found[0][1] == "round"
    assert 120 < found[0][0] <= 120 + (CHECKS + 1) * CHECK_EVERY


@pytest.mark.parametrize("curvature", [1.0, 30.0, 1000.0])
def test_a_smooth_fold_is_not_a_retrace(curvature):
    """Through a fold, the field turning back as a parabola of the state, however sharp: no verdict."""
    s = np.linspace(-1.0, 1.0, 201)
    curve = np.column_stack([s, 0.5 * s, 1.0 - curvature * s ** 2])
    assert _verdicts(curve) == []


def test_a_kink_whose_arms_part_is_not_a_retrace_and_one_too_sharp_to_tell_is():
    """Into a kink along one arm and out along another at an angle: arms 0.1 rad apart are two arms; 1e-3 rad
    apart they lie within ``NEAR`` of each other over every check, as a retrace does (the limit the module
    states)."""
    s = np.linspace(1.0, 0.0, 60)

    def kink(angle):
        return np.vstack([_turn(s, 0.0), _turn(s[::-1][1:], angle)])

    assert _verdicts(kink(0.1)) == []
    found = _verdicts(kink(1e-3))
    assert found and found[0][1] == "back"


def _turn(s, angle):
    """Points ``s`` along ``(1, 0.2, 1)`` turned by ``angle`` about the first state's axis."""
    way = np.array([1.0, 0.2, 1.0])
    c, r = np.cos(angle), np.sin(angle)
    turned = np.array([way[0], c * way[1] - r * way[2], r * way[1] + c * way[2]])
    return s[:, None] * turned


@pytest.mark.parametrize("dropped", [True, False])
def test_points_the_branch_dropped_are_forgotten(dropped):
    """A branch that drops its last points (going back to undo a shot) and then runs the same way again, at other
    steps, over where they were: new points, no verdict. Had it kept them, it would have gone round."""
    out = _helix(np.linspace(0.0, 1.0, 101))
    track, pts = SelfOverlap(2), [{"state": row[:2], "param": row[2]} for row in out]
    track.sync(pts, WEIGHTS)
    if dropped:
        del pts[60:]
        track.truncate(len(pts))
    found = []
    for row in _helix(np.arange(0.6037, 1.0, 0.0093)):
        pts.append({"state": row[:2], "param": row[2]})
        found_here = track.verdict(pts, WEIGHTS, 0.0093)
        found.append(None if found_here is None else found_here[0])
    assert set(found) == ({None} if dropped else {None, "round"})
