"""Grazing points located in a second thread: the same branch and special points as in one, to the bit."""

import threading
import time

import numpy as np

from blademodel.orbits import continuation
from blademodel.orbits.branch import SpecialPoint
from blademodel.orbits.background import Locator, PendingPoint, resolve
from blademodel.zheng2022 import BladePair


def _same(b1, b2):
    for name in ("params", "states", "multipliers", "events", "harmonics"):
        np.testing.assert_array_equal(getattr(b1, name), getattr(b2, name))
    assert [(p.kind, p.index) for p in b1.special] == [(p.kind, p.index) for p in b2.special]
    for p, q in zip(b1.special, b2.special):
        assert p.param == q.param and p.multiplier == q.multiplier
        np.testing.assert_array_equal(p.state, q.state)


def test_a_branch_is_the_same_with_its_grazing_points_located_in_a_second_thread():
    """The Coulomb pair from 415 to 425 rad/s: grazing points, a nonsmooth fold where the branch turns at a
    grazing, and a fold; located in the continuation's thread (``workers=1``) and in a thread of their own on
    period maps of their own (``workers=2``). The second thread's integrations are counted: they are what the
    branch costs beyond the same branch with its grazing points not located (``grazing_tol=inf``)."""
    cfg = BladePair(friction="coulomb")
    one, two = (continuation(cfg, "omega", 415.0, 425.0, workers=w) for w in (1, 2))
    assert {p.kind for p in one.special} >= {"grazing", "nonsmooth-fold", "fold"}
    _same(one, two)
    unlocated = continuation(cfg, "omega", 415.0, 425.0, workers=2, grazing_tol=np.inf)
    assert two.integrations == one.integrations > unlocated.integrations


def _point(kind, param, index):
    return SpecialPoint(kind=kind, param=param, state=np.array([param]), multiplier=1.5, index=index)


def test_resolve_waits_and_places_a_border_collision_at_the_grazing_in_its_bracket():
    """A grazing located in the worker thread (which finishes after ``resolve`` starts waiting) replaces its
    placeholder; the border collision (or the nonsmooth fold it became) of the same step is moved onto it where
    it lies in that collision's bracket, and nothing else moves."""
    locator = Locator(lambda: "context")
    gate = threading.Event()

    def slow(context):
        gate.wait(5.0)
        assert context == "context" and threading.current_thread() is not threading.main_thread()
        return {"param": 1.01, "state": np.array([1.01]), "mode": None}

    def finish(at):
        return SpecialPoint(kind="grazing", param=at["param"], state=at["state"], multiplier=0.5, index=3)

    pending = PendingPoint(slow, locator, finish, 3, bracket=(1.0, 1.03))
    pending.start()
    special = [_point("border-collision", 1.02, 3), _point("nonsmooth-fold", 2.0, 7), pending, _point("fold", 5.0, 3)]
    threading.Timer(0.2, gate.set).start()
    t0 = time.monotonic()
    resolve(special)
    assert time.monotonic() - t0 >= 0.15   # it waited for the location
    locator.shutdown()
    assert [(q.kind, q.param) for q in special] == [("border-collision", 1.01), ("nonsmooth-fold", 2.0),
                                                     ("grazing", 1.01), ("fold", 5.0)]


def test_a_location_that_finds_several_grazing_points_puts_each_in_its_place():
    """A step across two grazing points: its placeholder becomes both, in order, where it stood; the border
    collision of the step goes to the first that lies in its bracket, with that point's own bracket."""
    def two(context):
        return [{"param": 1.005, "state": np.array([1.005]), "mode": None},
                {"param": 1.02, "state": np.array([1.02]), "mode": None, "bracket": (1.015, 1.02)}]

    def finish(at):
        return SpecialPoint(kind="grazing", param=at["param"], state=at["state"], multiplier=0.5, index=3,
                            bracket=at.get("bracket"))

    pending = PendingPoint(two, Locator(lambda: None, thread=False), finish, 3, bracket=(1.01, 1.03))
    special = [_point("border-collision", 1.03, 3), pending, _point("fold", 5.0, 3)]
    resolve(special)
    assert [(q.kind, q.param, q.bracket) for q in special] == [
        ("border-collision", 1.02, (1.015, 1.02)), ("grazing", 1.005, None), ("grazing", 1.02, (1.015, 1.02)),
        ("fold", 5.0, None)]


def test_without_a_thread_a_location_runs_when_its_step_is_taken_and_once():
    """The continuation's thread: ``start`` runs it, once; a point outside the border collision's bracket leaves the
    collision where it is."""
    runs = []

    def task(context):
        runs.append(context)
        return {"param": 1.2, "state": np.array([1.2]), "mode": None}

    locator = Locator(lambda: "own maps", thread=False)
    pending = PendingPoint(task, locator, lambda at: _point("grazing", at["param"], 3), 3, bracket=(1.0, 1.03))
    assert runs == []
    pending.start()
    assert runs == ["own maps"] and pending.done()
    special = [_point("nonsmooth-fold", 1.02, 3), pending]
    resolve(special)
    resolve(special)
    assert runs == ["own maps"]
    assert [(q.kind, q.param) for q in special] == [("nonsmooth-fold", 1.02), ("grazing", 1.2)]


def test_a_location_cut_short_by_ctrl_c_leaves_its_grazing_point_at_the_first_point_past_it():
    """Ctrl-C inside a location run in the continuation's thread reaches the continuation (which then stops), and
    the branch it keeps has that grazing point at the point past it, not lost."""
    def interrupted(context):
        raise KeyboardInterrupt

    pending = PendingPoint(interrupted, Locator(lambda: None, thread=False), lambda at: _point("grazing", at["param"], 3),
                           3, unlocated={"param": 1.5})
    try:
        pending.start()
    except KeyboardInterrupt:
        pass
    else:
        raise AssertionError("the Ctrl-C was swallowed")
    special = [pending]
    resolve(special)
    assert [(q.kind, q.param) for q in special] == [("grazing", 1.5)]


def test_a_location_whose_integration_fails_leaves_its_grazing_point_at_the_first_point_past_it(monkeypatch):
    """A grazing point's place is not worth the branch: where its location's integration fails, the branch goes on
    and reports it at the branch point after it (here every location fails), the branch's points unchanged."""
    from blademodel.orbits import arclength
    from blademodel.orbits.period_map import FlowError

    cfg = BladePair(friction="coulomb")
    fine = continuation(cfg, "omega", 312.3, 313.4, workers=1)

    def failing(self, *args, **kwargs):
        raise FlowError("the integration stopped")
    monkeypatch.setattr(arclength._Context, "_locate_grazing", failing)
    failed = continuation(cfg, "omega", 312.3, 313.4, workers=1)
    np.testing.assert_array_equal(failed.params, fine.params)
    grazing = failed.points("grazing")
    assert len(grazing) == len(fine.points("grazing")) >= 3
    assert all(p.param == failed.params[p.index + 1] for p in grazing)
    # and says it is somewhere in that step
    assert all(p.bracket == tuple(sorted(failed.params[p.index:p.index + 2])) for p in grazing)
