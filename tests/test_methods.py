"""The stepping methods: the eighth-order tableau and its order through located events."""

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from blademodel.zheng2022 import BladePair
from blademodel.numeric import simulate
from blademodel.numeric.methods import get_method

sys.path.insert(0, str(Path(__file__).resolve().parent))
from test_bladed_disk import _disk  # noqa: E402


def _order_conditions(m):
    """Residuals of the Butcher order conditions up to order 5 (the rooted trees of order <= 5)."""
    A, b, c = m.A, m.b, m.c
    one = np.ones(len(b))
    Ac, Ac2, AAc = A @ c, A @ c ** 2, A @ (A @ c)
    cond = [(b @ one, 1), (b @ c, 1 / 2), (b @ c ** 2, 1 / 3), (b @ Ac, 1 / 6), (b @ c ** 3, 1 / 4),
            (b @ (c * Ac), 1 / 8), (b @ Ac2, 1 / 12), (b @ AAc, 1 / 24), (b @ c ** 4, 1 / 5),
            (b @ (c ** 2 * Ac), 1 / 10), (b @ (Ac * Ac), 1 / 20), (b @ (c * Ac2), 1 / 15),
            (b @ (c * AAc), 1 / 30), (b @ (A @ c ** 3), 1 / 20), (b @ (A @ (c * Ac)), 1 / 40),
            (b @ (A @ Ac2), 1 / 60), (b @ (A @ AAc), 1 / 120)]
    return np.array([v - w for v, w in cond])


@pytest.mark.parametrize("name, order", [("rk4", 4), ("rk8", 8)])
def test_tableau_is_explicit_consistent_and_of_its_order(name, order):
    m = get_method(name)
    assert m.order == order and np.all(np.triu(m.A) == 0)        # explicit
    np.testing.assert_allclose(m.A.sum(axis=1), m.c, atol=1e-15)  # row sums are the nodes
    res = _order_conditions(m)
    assert np.max(np.abs(res[:8 if order == 4 else None])) < 1e-14
    # the stability function R(z) = sum_k (b A^(k-1) 1) z^k is exp(z) up to z^p, not beyond
    v, coef = np.ones(m.stages), []
    for _ in range(order + 1):
        coef.append(m.b @ v)
        v = m.A @ v
    exact = np.array([1 / math.factorial(k) for k in range(1, order + 2)])
    assert np.max(np.abs(np.array(coef[:order]) / exact[:order] - 1)) < 1e-12
    assert abs(coef[order] / exact[order] - 1) > 1e-3   # order p exactly (RK8: 2 % off at z^9)
    z = 0.3 + 0.2j
    assert abs(m.amplification(z) - sum(c * z ** (k + 1) for k, c in enumerate(coef)) - 1) < 1e-8


def _orders(errors, steps):
    e, s = np.array(errors), np.array(steps, dtype=float)
    return np.log(e[:-1] / e[1:]) / np.log(s[1:] / s[:-1])


def test_rk8_is_eighth_order_through_the_pairs_events():
    """Coulomb pair, product kernel: 83 located events in 6 periods, order ~8 until rounding."""
    m = BladePair(friction="coulomb").build()
    run = dict(periods=6, event_tol=1e-14, method="rk8")
    ref = simulate(m, steps_per_period=4000, **run)
    steps = (170, 240, 340, 480)
    runs = [simulate(m, steps_per_period=S, **run) for S in steps]
    assert all(r.counters["events"] == ref.counters["events"] > 50 for r in runs)
    amp = np.max(np.abs(ref.y), axis=0)
    err = [np.max(np.abs(r.final_state - ref.final_state) / amp) for r in runs]
    assert (_orders(err, steps) > 7).all(), (err, _orders(err, steps))


@pytest.mark.parametrize("law", ["coulomb", "bilinear"])
def test_rk8_is_eighth_order_through_a_rings_events(law):
    """Mistuned 6-blade ring, per-contact kernel: ~640 events (contact, stick/slip, friction problem)."""
    model = _disk(blades=6, engine_order=2, friction=law, mistuning=[0.0, 0.02, -0.01, 0.03, 0.0, -0.02]).build()
    run = dict(periods=6, event_tol=1e-14, method="rk8")
    ref = simulate(model, steps_per_period=4000, record_every=4000, **run)
    steps = (240, 340, 480)
    runs = [simulate(model, steps_per_period=S, record_every=S, **run) for S in steps]
    # the same events; near-simultaneous ones of neighbouring contacts may be counted as one (within
    # the tolerance) at one step and as two at another (bilinear: 645 to 649)
    assert all(abs(r.counters["events"] - ref.counters["events"]) <= 0.01 * ref.counters["events"] for r in runs)
    assert ref.counters["events"] > 600
    err = [np.max(np.abs(r.final_state - ref.final_state)) / np.max(np.abs(ref.final_state)) for r in runs]
    assert (_orders(err, steps) > 7).all(), (err, _orders(err, steps))


def test_an_unknown_method_is_refused():
    with pytest.raises(ValueError, match="method = 'rk5'"):
        simulate(BladePair().build(), periods=1, method="rk5")


def test_simulate_command_takes_the_method_and_the_event_location(capsys):
    """``--method rk8 --event-location predicted``: the report says so, and the run equals the API's."""
    import json
    from blademodel.cli import main
    models = Path(__file__).resolve().parents[1] / "models"
    code = main(["simulate", str(models / "blade_pair_coulomb.yaml"), "--transient", "2", "--periods", "2",
                 "--method", "rk8", "--event-location", "predicted", "--json"])
    rep = json.loads(capsys.readouterr().out)
    assert code == 0
    assert rep["params"]["method"] == "rk8" and rep["params"]["event_location"] == "predicted"
    r = simulate(BladePair(friction="coulomb").build(), transient=2, periods=2, method="rk8",
                 event_location="predicted")
    assert rep["counters"]["events"] == r.counters["events"] and rep["counters"]["rhs_evaluations"] == \
        r.counters["rhs_evaluations"]
