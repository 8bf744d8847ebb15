"""Where a switched branch ends: back at another special point of the branch it left (``switching._back_to``), or
landed on that branch itself (``switching._landed_on``). The rules on made-up points; the models' branches are in
``tests/test_branch_points.py`` and ``tests/test_cyclic.py`` (slow)."""

from types import SimpleNamespace

import numpy as np

from blademodel.orbits.branch import SpecialPoint
from blademodel.orbits.switching import _back_to, _landed_on


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

