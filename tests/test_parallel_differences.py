"""Difference Jacobians of the period map in threads: the same numbers as one thread, and a ring's branch.

The per-contact kernel has no tangent, so a bladed disk's Jacobian is ``2 n`` integrations
of a period; ``PeriodMap(workers=...)`` shares them among threads, each integrating with its
own copy of the integrator's work arrays. Nothing here times anything: the threads must give
the same Jacobian, orbit and branch as one thread, to the bit (``benchmarks/ring_jacobian.py``
measures the speed).
"""

import numpy as np
import pytest

from blademodel.config import BladedDisk
from blademodel.numeric import simulate
from blademodel.numeric.kernels import make_integrator
from blademodel.orbits import FlowError, PeriodMap, continuation, find_periodic_orbit
from blademodel.orbits.period_map import worker_count
from blademodel.zheng2022 import BladePair

RING = dict(blades=4, engine_order=1, friction="coulomb", mistuning=[0, 0.03, -0.02, 0.01])


@pytest.fixture(autouse=True)
def always_threads(monkeypatch):
    """Threads for every Jacobian here, however short its columns (these models are small)."""
    monkeypatch.setattr(PeriodMap, "thread_column_seconds", 0.0)


def _section(ig, periods=30):
    """A state at ``t = 0`` on the attractor's way (events in every period) and its modes."""
    y = ig.initial_state()
    mode = ig.mode_of(y)
    status, mode, _ = ig.advance(y, mode, 0, periods)
    assert status == 0
    return y[:ig.n_physical].copy(), mode


@pytest.fixture(scope="module")
def ring():
    ig = make_integrator(BladedDisk(**RING).build())
    y, mode = _section(ig)
    return ig, y, mode


def test_a_worker_integrates_as_its_integrator_with_arrays_of_its_own(ring):
    ig, y, mode = ring
    w = ig.worker()
    for a, b in ((ig.WI, w.WI), (ig.WF, w.WF), (ig.SC, w.SC), (ig.GS, w.GS)):
        assert not np.shares_memory(a, b)
    assert w.I is ig.I and w.R is ig.R   # the model's tables are shared, read only
    ends = []
    for g in (ig, w):
        full = np.zeros(ig.n_state)
        full[:y.size] = y
        status, m_end, _ = g.advance(full, mode, 0, 2)
        ends.append((status, full, m_end))
    assert ends[0][0] == ends[1][0] == 0
    assert np.array_equal(ends[0][1], ends[1][1]) and np.array_equal(ends[0][2], ends[1][2])


@pytest.mark.parametrize("workers", [2, 3])
def test_a_ring_jacobian_in_threads_is_the_serial_one_to_the_bit(ring, workers):
    ig, y, mode = ring
    scale = np.maximum(np.abs(y), 1e-3 * np.abs(y).max())
    serial = PeriodMap(ig, workers=1)
    J1 = serial.differences(y, mode, scale)
    threaded = PeriodMap(ig, workers=workers)
    Jw = threaded.differences(y, mode, scale)
    assert np.array_equal(J1, Jw)
    assert serial.evaluations == threaded.evaluations == 2 * y.size
    # and it is the derivative: a step along a random direction agrees to second order
    d = np.random.default_rng(0).standard_normal(y.size) * scale * 1e-7
    P0, P1 = serial.plain(y, mode), serial.plain(y + d, mode)
    assert np.linalg.norm(P1 - P0 - J1 @ d) < 1e-4 * np.linalg.norm(P1 - P0)


def test_the_pair_differences_in_threads_equal_one_thread():
    """The product-mode kernel's integrate releases the GIL too; its worker owns its guard buffers."""
    ig = make_integrator(BladePair(friction="bilinear").build())
    y, mode = _section(ig, 20)
    scale = np.maximum(np.abs(y), 1e-3 * np.abs(y).max())
    J1 = PeriodMap(ig, jacobian="differences", workers=1).differences(y, mode, scale)
    J2 = PeriodMap(ig, jacobian="differences", workers=2).differences(y, mode, scale)
    assert np.array_equal(J1, J2)


def test_a_failing_integration_in_a_thread_is_the_map_error(ring):
    ig, y, mode = ring
    bad = y.copy()
    bad[0] = np.inf
    with pytest.raises(FlowError, match="status"):
        PeriodMap(ig, workers=2).differences(bad, mode, np.ones(y.size))


@pytest.mark.parametrize("bad", [0, -2, 1.5, True, "2"])
def test_workers_must_be_a_count(bad):
    with pytest.raises(ValueError, match=f"workers = {bad!r}"):
        worker_count(bad)


def test_every_cpu_by_default():
    assert worker_count(None) == worker_count(-1) >= 1 and worker_count(3) == 3


def test_a_ring_branch_in_threads_is_the_serial_one_and_where_long_runs_settle():
    """A mistuned 4-blade Coulomb ring continued in omega through changes of its stick-slip sequence
    (grazing points): two threads give the same branch as one, and at its stable points long runs from
    rest settle onto its orbits."""
    cfg = BladedDisk(**RING)
    b1 = continuation(cfg, "omega", 285.0, 295.0, max_points=10, workers=1)
    b2 = continuation(cfg, "omega", 285.0, 295.0, max_points=10, workers=2)
    for a in ("params", "states", "multipliers", "harmonics", "events"):
        assert np.array_equal(getattr(b1, a), getattr(b2, a)), a
    assert [(s.kind, s.param) for s in b1.special] == [(s.kind, s.param) for s in b2.special]
    assert len(set(b1.events.tolist())) > 1   # the branch crosses changes of its event sequence
    scale = np.max(np.abs(b1.states), axis=0)
    for k in (0, len(b1.params) - 1):
        assert b1.stable[k]
        r = simulate(cfg.model_copy(update={"omega": float(b1.params[k])}).build(), transient=300, periods=1)
        assert np.max(np.abs(r.poincare[-1][:scale.size] - b1.states[k]) / scale) < 1e-8


def test_short_columns_stay_in_one_thread(ring, monkeypatch):
    """Where a column takes less than ``thread_column_seconds`` no thread (and no worker copy) is made."""
    from blademodel.numeric.integrator import Integrator
    ig, y, mode = ring
    scale = np.maximum(np.abs(y), 1e-3 * np.abs(y).max())
    J1 = PeriodMap(ig, workers=1).differences(y, mode, scale)

    def no_copies(self):
        raise AssertionError("a worker copy was made")
    monkeypatch.setattr(Integrator, "worker", no_copies)
    monkeypatch.setattr(PeriodMap, "thread_column_seconds", 60.0)
    assert np.array_equal(PeriodMap(ig, workers=2).differences(y, mode, scale), J1)
    monkeypatch.setattr(PeriodMap, "thread_column_seconds", 0.0)
    with pytest.raises(AssertionError, match="worker copy"):
        PeriodMap(ig, workers=2).differences(y, mode, scale)


def test_after_a_failure_the_other_threads_stop_at_their_next_column(ring, monkeypatch):
    """A FlowError (or a Ctrl-C) in one column ends the Jacobian promptly: the other threads do not go on
    integrating their remaining columns."""
    import threading
    import time

    from blademodel.orbits import period_map
    ig, y, mode = ring
    scale = np.ones(y.size)
    plain = period_map._plain_map
    calls, lock = [], threading.Lock()

    def slow_or_failing(g, periods, yy, m):
        i = int(np.argmax(np.abs(yy - y)))
        with lock:
            calls.append(i)
        if i == 1:   # thread 0's first column after the timed one
            raise FlowError("the integration stopped at t = 0 s with status 1")
        time.sleep(0.05)
        return plain(g, periods, yy, m)
    monkeypatch.setattr(period_map, "_plain_map", slow_or_failing)
    with pytest.raises(FlowError):
        PeriodMap(ig, workers=2).differences(y, mode, scale)
    others = [i for i in calls if i not in (0, 1)]
    assert len(others) <= 4 < 2 * (y.size - 2) // 2   # at most two columns of thread 1's seven


def test_forward_differences_halve_the_integrations_and_keep_the_orbit():
    """``jacobian="forward"``: ``n + 1`` integrations a Jacobian instead of ``2 n``, the same in threads as in
    one thread, and shooting with it finds the orbit central differences find (the residual decides where
    Newton stops, not the Jacobian) with the multipliers to about the step (``rel_step = 1e-6``)."""
    m = BladedDisk(**RING).build()
    ig = make_integrator(m)
    y, mode = _section(ig)
    scale = np.maximum(np.abs(y), 1e-3 * np.abs(y).max())
    one, two = PeriodMap(ig, jacobian="forward", workers=1), PeriodMap(ig, jacobian="forward", workers=2)
    Jf = one.differences(y, mode, scale)
    assert np.array_equal(Jf, two.differences(y, mode, scale))
    assert one.evaluations == two.evaluations == y.size + 1
    before = one.evaluations   # again at the same point: P(y) is the map's kept run, n integrations
    assert np.array_equal(one.differences(y, mode, scale), Jf) and one.evaluations - before == y.size
    Jc = PeriodMap(ig, workers=1).differences(y, mode, scale)
    rel = np.abs(Jf - Jc) * scale[None, :] / scale[:, None]
    assert 0 < np.max(rel) < 1e-3   # a first-order error: not zero, small
    oc = find_periodic_orbit(m, transient=5, jacobian="differences", workers=1)
    of = find_periodic_orbit(m, transient=5, jacobian="forward", workers=1)
    assert np.max(np.abs(of.state - oc.state) / oc.scale) < 1e-10
    gap = np.max(np.abs(np.sort_complex(of.multipliers) - np.sort_complex(oc.multipliers)))
    assert 0 < gap < 1e-5


def test_the_orbit_command_on_a_ring_with_forward_differences_in_threads(tmp_path, capsys):
    """``blademodel orbit RING.yaml --jacobian forward --workers 2 --json`` gives the orbit of the Python call
    with central differences (to the tolerance) and a bad ``--workers`` exits 2 naming it."""
    import json

    import yaml

    from blademodel.cli import main
    path = tmp_path / "ring.yaml"
    path.write_text(yaml.safe_dump({"model": "bladed_disk", **RING}))
    assert main(["orbit", str(path), "--transient", "5", "--jacobian", "forward", "--workers", "2", "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    o = find_periodic_orbit(BladedDisk(**RING).build(), transient=5, jacobian="differences", workers=1)
    got = np.array([rep["state"][n] for n in o.state_names])
    assert np.max(np.abs(got - o.state) / o.scale) < 1e-9
    assert abs(rep["multipliers"][0]["abs"] - abs(o.multipliers[0])) < 1e-5
    assert main(["orbit", str(path), "--workers", "0"]) == 2
    assert "workers = 0" in capsys.readouterr().err
