"""Where a switched branch ends: back at another special point of the branch it left (``switching._back_to``),
landed on that branch itself (``switching._landed_on``), or, on a tuned ring's ``G^2``, past the travelling waves
(``switching._back_to_the_waves``). The rules on made-up points; the models' branches are in
``tests/test_branch_points.py`` and ``tests/test_cyclic.py`` (slow)."""

from types import SimpleNamespace

import numpy as np

from blademodel.orbits.branch import SpecialPoint
from blademodel.orbits.switching import _back_to, _back_to_the_waves, _landed_on


def _ctx():
    return SimpleNamespace(scale=np.ones(2), span=10.0, fam=SimpleNamespace(name="omega"))


def _point(param, state, split=1.0):
    return {"param": param, "state": np.asarray(state, dtype=float), "split": split}


def _special(param, state):
    return SpecialPoint(kind="period-doubling", param=param, state=np.asarray(state, dtype=float),
                        multiplier=-1.0 + 0j, index=0)


def test_a_branch_ends_at_its_closest_point_to_the_special_point_it_comes_back_to():
    """Coming within ``reach`` of the point and leaving again, the branch ends with the point before the newest, the
    closest; running past at a distance, or with the orbits still split (``splitting`` above ``COLLAPSED`` of its
    largest), it goes on."""
    target = _special(5.0, [0.0, 0.0])
    stop = _back_to(_ctx(), [target], 0.05, "came back to it at", "past it: more", lambda q: q["split"])
    path = [_point(2.0, [0.3, 0.0]), _point(3.0, [0.2, 0.0]), _point(4.0, [0.1, 0.0]), _point(5.0, [0.01, 0.0], 0.05),
            _point(6.0, [0.1, 0.0])]
    assert [stop(path[:k]) for k in range(1, 5)] == [None] * 4
    assert stop(path) == "came back to it at omega = 5 (its point at 5 the closest; past it: more)"
    still_split = _back_to(_ctx(), [target], 0.05, "at", "past", lambda q: q["split"])
    split = [dict(q, split=1.0) for q in path]
    assert all(still_split(split[:k]) is None for k in range(1, 6))
    far = [_point(q["param"], q["state"] + np.array([0.0, 0.2]), q["split"]) for q in path]
    stop_far = _back_to(_ctx(), [target], 0.05, "at", "past", lambda q: q["split"])
    assert all(stop_far(far[:k]) is None for k in range(1, 6))


def test_a_doubled_branch_ends_where_its_orbits_are_of_the_old_period_again():
    stop = _landed_on(lambda q: q["split"], 1e-10, "omega", 1)
    pts = [_point(1.0, [0, 0], 0.0), _point(1.1, [0, 0], 0.1), _point(1.2, [0, 0], 3e-10)]
    assert stop(pts[:2]) is None
    assert stop(pts).startswith("landed on the period-1 orbits at omega = 1.2 (its orbit a period apart differs by "
                                "3e-10")
    assert stop(pts[:2] + [_point(1.2, [0, 0], 2e-7)]) is None


def _wave_point(param, broken):
    """A point on ``G^2`` whose symmetry breaking ``y - G(y)`` is ``broken``: ``G`` read off its record ``Y`` (three
    samples, the middle one at ``T / 2`` of a map over ``T / 2``), the ring's turn the identity here."""
    Y = np.zeros((3, 2))
    return {"param": param, "state": np.asarray(broken, dtype=float), "Y": Y}


def _kept(q):
    """A point's orbit, as every one of these keeps it."""
    return q["Y"]


def _sym():
    return SimpleNamespace(n=2, fraction=2, periods=1, turned=lambda y: y)


def test_a_crossing_branch_on_g2_ends_where_its_symmetry_breaking_changes_sign_and_names_where():
    """The projection of ``y - G(y)`` on its value at the first point past the switch changes sign between the
    last two points: the branch ends, at the crossed branch's branch point within a step of their values where one
    is given, else at the vertex of the parabola through them (the value interpolated linearly where their
    projections are of one size); where the last point is a travelling wave itself (its step landed on the crossed
    branch) no value inside the step is claimed."""
    path = [_wave_point(1.0, [0.0, 0.0]), _wave_point(2.0, [1.0, 0.1]), _wave_point(3.0, [0.5, 0.0]),
            _wave_point(4.0, [-0.5, 0.0])]
    stop = _back_to_the_waves(_sym(), "omega", _kept)
    assert [stop(path[:k]) for k in range(1, 4)] == [None] * 3
    assert stop(path).startswith("came back to the travelling waves near omega = 3.5, where they have another "
                                 "branch point (between its points at 3 and 4;")
    other = _special(3.8, [0.0, 0.0])
    named = _back_to_the_waves(_sym(), "omega", _kept, [_special(9.0, [0.0, 0.0]), other])
    assert named(path[:3]) is None
    assert named(path).startswith("came back to the travelling waves at their branch point omega = 3.8 (between "
                                  "its points at 3 and 4;")
    landed = path[:3] + [_wave_point(4.0, [1e-9, 0.0])]
    stop_landed = _back_to_the_waves(_sym(), "omega", _kept)
    assert stop_landed(landed[:3]) is None
    assert stop_landed(landed).startswith("came back to the travelling waves between its points at 3 and 4, where "
                                          "they have another branch point (its last point is a travelling wave")
    # a step that turns across the meeting: the vertex of the parabola through both points (the field even in the
    # breaking, which G reverses), not a value between them
    turned = path[:2] + [_wave_point(3.2 - 0.4 ** 2, [0.4, 0.0]), _wave_point(3.2 - 0.3 ** 2, [-0.3, 0.0])]
    stop_turned = _back_to_the_waves(_sym(), "omega", _kept)
    assert stop_turned(turned[:3]) is None
    assert stop_turned(turned).startswith("came back to the travelling waves near omega = 3.2, where")
    # a branch that only comes close to the waves and leaves them again goes on
    close = path[:3] + [_wave_point(4.0, [0.01, 0.0])]
    stop_close = _back_to_the_waves(_sym(), "omega", _kept)
    assert all(stop_close(close[:k]) is None for k in range(1, 5))
