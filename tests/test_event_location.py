"""Locating events: few sub-steps, the same roots, and a bounded iteration at any tolerance."""

import time

import numpy as np
import pytest

from blademodel.config import BladedDisk
from blademodel.zheng2022 import BladePair
from blademodel.numeric import simulate
from blademodel.numeric.contact_locate import MAX_LOCATE_TRIALS
from blademodel.numeric.integrator import EVENT_TOL_FLOOR


@pytest.mark.slow   # a cold compile of both kernels of the pair per law (40-50 s in CI); the rings' events run by default
@pytest.mark.parametrize("law", ["coulomb", "bilinear"])
def test_pair_events_are_the_bisection_roots(law):
    """Predicted roots (per-contact kernel; product kernel on request) equal the bisection's to the tolerance.

    Both take the state past the root by at most ``event_tol * h``; the per-contact kernel gets there
    from a predicted root in a few sub-steps, the product kernel by bisection. Compared from the same
    states (a dozen points of a run, each with its mode): the first event after each, where the two
    kernels still follow the same trajectory up to round-off (later events inherit each kernel's own
    overshoot past the earlier roots).
    """
    tol, S = 1e-10, 1000
    m = BladePair(friction=law).build()
    run = simulate(m, transient=20, periods=2, kernel="product", event_tol=tol, steps_per_period=S)
    h = run.period / S
    starts = np.linspace(0, len(run.t) - 1, 12).astype(int)
    per_event = []
    for k in starts:
        y0, mode0 = run.y[k], int(run.mode[k])
        a = simulate(m, periods=1, kernel="product", event_tol=tol, steps_per_period=S, y0=y0, mode0=mode0,
                     max_log=1)
        b = simulate(m, periods=1, kernel="contact", event_tol=tol, steps_per_period=S, y0=y0, mode0=[mode0],
                     max_log=1)
        c = simulate(m, periods=1, kernel="product", event_tol=tol, steps_per_period=S, y0=y0, mode0=mode0,
                     max_log=1, event_location="predicted")
        assert a.events["to"] == b.events["to"] == c.events["to"] and len(a.events["t"]) == 1
        assert abs(a.events["t"][0] - b.events["t"][0]) <= 1.01 * tol * h
        assert abs(a.events["t"][0] - c.events["t"][0]) <= 1.01 * tol * h
        per_event.append((b.counters["location_substeps"] / b.counters["events"],
                          c.counters["location_substeps"] / c.counters["events"]))
    assert np.mean(per_event, axis=0)[0] <= 4 and np.mean(per_event, axis=0)[1] <= 4.5


@pytest.mark.parametrize("law", ["none", "coulomb", pytest.param("bilinear", marks=pytest.mark.slow)])  # ~40 s
def test_a_mistuned_ring_locates_each_event_in_a_few_sub_steps(law):
    """Every event of a mistuned ring is located on its own (no shared roots) in at most 4 sub-steps on average.

    Guards with known rates (the penetration, slip velocities, explicit friction forces, and the
    rigid stick forces at an event) start from the root of a cubic Hermite interpolant and
    continue with a Newton step; with the chord alone friction events took 4.4-4.8.
    """
    model = BladedDisk(blades=8, engine_order=4, friction=law, mistuning_std=0.01, mistuning_seed=0).build()
    r = simulate(model, transient=10, periods=5)
    assert r.counters["events"] > 50
    assert r.counters["location_substeps"] / r.counters["events"] <= 4.0


@pytest.mark.parametrize("kernel", ["product", "contact"])
def test_a_tolerance_below_rounding_ends_at_the_resolution(kernel):
    """``event_tol`` below what double precision resolves: a warning, and each location ends (bounded)."""
    m = BladePair(friction="bilinear").build()
    simulate(m, periods=1, kernel=kernel)   # compiled (or loaded) before timing
    ref = simulate(m, transient=2, periods=2, kernel=kernel, event_tol=1e-13)
    for tol in (1e-16, 1e-300):
        with pytest.warns(UserWarning, match="event_tol") as warned:
            t0 = time.process_time()
            r = simulate(m, transient=2, periods=2, kernel=kernel, event_tol=tol)
            assert time.process_time() - t0 < 5.0
        assert r.counters["events"] == ref.counters["events"] > 0
        cap = 60 if kernel == "product" else MAX_LOCATE_TRIALS
        assert r.counters["location_substeps"] <= cap * r.counters["events"]
        amp = np.max(np.abs(ref.y), axis=0)
        assert np.max(np.abs(r.final_state - ref.final_state) / amp) < 1e-9
        assert f"about {EVENT_TOL_FLOOR:g} of it" in str(warned[0].message)   # the floor it names


@pytest.mark.parametrize("tol", [0.0, -1e-10, float("nan"), float("inf")])
def test_a_tolerance_that_is_not_positive_is_refused(tol):
    with pytest.raises(ValueError, match="event_tol"):
        simulate(BladePair().build(), periods=1, event_tol=tol)


@pytest.mark.parametrize("law", ["coulomb", "bilinear"])
def test_predicted_location_on_the_pair_keeps_its_periodic_orbit(law):
    """The pair's period-1 orbit over 100 periods: the same events, states within 1e-10 of their amplitudes,
    about a sixth of the location sub-steps."""
    m = BladePair(friction=law).build()
    a = simulate(m, transient=100, periods=100)
    b = simulate(m, transient=100, periods=100, event_location="predicted")
    assert a.settings["event_location"] == "bisection" and b.settings["event_location"] == "predicted"
    amp = np.max(np.abs(a.y), axis=0)
    assert np.max(np.abs(a.final_state - b.final_state) / amp) < 1e-10
    assert a.counters["events"] == b.counters["events"] and a.events["to"] == b.events["to"]
    assert b.counters["location_substeps"] < a.counters["location_substeps"] / 5


def test_an_unknown_event_location_is_refused():
    with pytest.raises(ValueError, match="event_location = 'secant'"):
        simulate(BladePair().build(), periods=1, event_location="secant")


def test_the_location_counter_keeps_its_former_name_with_a_warning():
    """``counters["location_substeps"]`` (sub-steps spent locating events; ``bisections`` before)."""
    r = simulate(BladePair().build(), transient=1, periods=1)
    assert "bisections" not in r.counters and r.counters["location_substeps"] > 0
    with pytest.warns(DeprecationWarning, match="location_substeps"):
        assert r.counters["bisections"] == r.counters["location_substeps"]
    with pytest.raises(KeyError):
        r.counters["no_such_counter"]
