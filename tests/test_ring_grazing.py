"""A ring's grazing points carry the multipliers of the branch beside them, not a difference quotient across the kink."""

import numpy as np

from blademodel.config import BladedDisk
from blademodel.orbits import continuation


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
