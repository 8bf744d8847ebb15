"""Guards of different contacts that cross in the same instant all fire."""

import numpy as np
import pytest

from blademodel.components import Contact, HarmonicForce, Mass, Spring
from blademodel.model import Model
from blademodel.numeric import simulate


def _walls(gap2):
    m = Mass("1", 1.0, dofs=("x",))
    # alpha = pi/2: n = x, so each wall is hit when x reaches its gap
    walls = (Contact(m, None, gap=1e-3, alpha=np.pi / 2, k=1e5, name="c1"),
             Contact(m, None, gap=gap2, alpha=np.pi / 2, k=2e5, name="c2"))
    return Model((m,), (Spring("x1", 1e4),), (), (HarmonicForce(m, 20.0, 50.0),), walls)


@pytest.mark.parametrize("kernel", ["product", "contact"])
def test_two_contacts_closing_in_the_same_instant_both_close(kernel):
    r = simulate(_walls(1e-3), periods=3, steps_per_period=1000, kernel=kernel)
    closes = [(g, t) for g, t in zip(r.events["guard"], r.events["t"]) if g.endswith("close")]
    names = [g for g, _ in closes]
    assert "c1: close" in names and "c2: close" in names
    assert names.count("c1: close") == names.count("c2: close")
    t1 = [t for g, t in closes if g == "c1: close"]
    t2 = [t for g, t in closes if g == "c2: close"]
    assert t1 == t2                       # in the same instant: the same located event
    if kernel == "product":
        assert "c1=open,c2=open" in r.events["from"] and "c1=closed,c2=closed" in r.events["to"]
    else:
        assert "c1=closed,c2=closed" in r.mode_names


@pytest.mark.parametrize("kernel", ["product", "contact"])
def test_coincident_walls_act_as_one_wall_of_summed_stiffness(kernel):
    # Two walls at the same place behave as one of stiffness k1 + k2.
    both = simulate(_walls(1e-3), periods=3, steps_per_period=2000, kernel=kernel)
    m = Mass("1", 1.0, dofs=("x",))
    one = Model((m,), (Spring("x1", 1e4),), (), (HarmonicForce(m, 20.0, 50.0),),
                (Contact(m, None, gap=1e-3, alpha=np.pi / 2, k=3e5, name="c"),))
    single = simulate(one, periods=3, steps_per_period=2000)
    np.testing.assert_allclose(both.final_state, single.final_state, rtol=1e-9, atol=1e-12)
