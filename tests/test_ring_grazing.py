"""A ring's grazing points carry the multipliers of the branch beside them, not a difference quotient across the kink."""

from pathlib import Path

import numpy as np
import pytest

from blademodel.config import BladedDisk, load_config
from blademodel.orbits import continuation

MODELS = Path(__file__).resolve().parent.parent / "models"


def test_a_grazing_on_a_ring_reports_the_multiplier_of_the_branch_beside_it():
    """The tuned 4-blade Coulomb ring (engine order 1) gains 20 events a period near 273.91 rad/s. Its period map
    is differentiated by forward differences, which, at the located grazing, straddle the kink: the largest
    multiplier there came out as 1.1e5 over this range (1.7e5 continuing from 273.5 rad/s) while the points on
    either side have 0.6236. The grazing point's
    multiplier lies between those of its two neighbours."""
    b = continuation(BladedDisk(blades=4, engine_order=1, friction="coulomb"), "omega", 273.85, 274.0,
                     jacobian="forward", workers=1, transient=50, steps_per_period=600)
    grazing = b.points("grazing")
    assert grazing and b.message.startswith("reached")
    largest = np.abs(b.multipliers[:, 0])
    for p in grazing:
        k = p.index
        assert b.events[k] != b.events[k + 1] and b.params[k] <= p.param <= b.params[k + 1]
        assert min(largest[k], largest[k + 1]) - 1e-12 <= abs(p.multiplier) <= max(largest[k], largest[k + 1]) + 1e-12


@pytest.mark.slow
def test_the_bilinear_ring_stalls_near_290_84_at_500_steps_a_period_and_not_at_2000():
    """The bilinear 24-blade ring continued from 290.8 rad/s: at 500 steps a period it stops near 290.84 rad/s (the
    step falls below ``ds_min``; at 1000 steps, shooting at 290.85 rad/s finds only an orbit that starts three
    contacts in slip off their friction limit and comes back in stick, which the mode check refuses), and the
    message says that more steps a period may get through; at 2000 the branch passes that value (290.92 reached).
    (Shooting past the stall for a gap reaches only 3e-2 of this 0.15 rad/s range, 4.5e-3 rad/s, and finds none.)"""
    cfg = load_config(MODELS / "bladed_disk_24_bilinear.yaml")
    coarse = continuation(cfg, "omega", 290.8, 290.95, workers=1, steps_per_period=500, max_points=60, ds_min=1e-4)
    assert not coarse.message.startswith("reached")
    assert 290.8 < coarse.params[-1] < 290.9
    assert "steps_per_period (--steps-per-period) 1000 instead of 500" in coarse.message
    fine = continuation(cfg, "omega", 290.8, 290.92, workers=1, steps_per_period=2000, max_points=60)
    assert fine.message == "reached omega = 290.92"


@pytest.mark.slow
def test_the_bilinear_ring_goes_on_across_its_gap_near_290_9_and_reports_it():
    """The bilinear 24-blade ring from 280 to 300 rad/s at 1000 steps a period: shooting from the orbit at 290.81
    to 290.85 rad/s finds no orbit at 290.85, 290.86, 290.88 and 290.90 rad/s (it stalls at residuals of 4e-4 to
    9e-3) and finds one at 290.95 and beyond. The branch used to stop there or, on another path, to step across
    it unawares. It now goes on to 300 rad/s and reports a special point whose bracket holds that stretch, with
    nothing located inside it: a ``gap`` where its step stalled inside the stretch and it shot farther on from
    the last orbit, or (since start states are settled, on the path that this takes) a grazing point whose
    location found no orbit inside the bracket."""
    cfg = load_config(MODELS / "bladed_disk_24_bilinear.yaml")
    b = continuation(cfg, "omega", 280.0, 300.0, workers=1)
    assert b.message == "reached omega = 300"
    (held,) = [p for p in b.special if p.bracket is not None and p.bracket[0] <= 290.85 and 290.90 <= p.bracket[1]]
    lo, hi = held.bracket
    assert held.kind in ("gap", "grazing") and hi < 291.2 and held.param == hi
    assert not [p for p in b.special if p is not held and lo < p.param < hi]
    assert len(b.points("neimark-sacker")) >= 10
