"""Guards of different contacts that cross in the same instant all fire."""

import numpy as np

from blademodel.components import Contact, HarmonicForce, Mass, Spring
from blademodel.model import Model
from blademodel.numeric import simulate


def _walls(gap2):
    m = Mass("1", 1.0, dofs=("x",))
    # alpha = pi/2: n = x, so each wall is hit when x reaches its gap
    walls = (Contact(m, None, gap=1e-3, alpha=np.pi / 2, k=1e5, name="c1"),
             Contact(m, None, gap=gap2, alpha=np.pi / 2, k=2e5, name="c2"))
    return Model((m,), (Spring("x1", 1e4),), (), (HarmonicForce(m, 20.0, 50.0),), walls)


def test_two_contacts_closing_in_the_same_instant_both_close():
    r = simulate(_walls(1e-3), periods=3, steps_per_period=1000)
    closes = [g for g in r.events["guard"] if g.endswith("close")]
    assert "c1: close" in closes and "c2: close" in closes
    assert closes.count("c1: close") == closes.count("c2: close")
    assert "c1=open,c2=open" in r.events["from"] and "c1=closed,c2=closed" in r.events["to"]


def test_coincident_walls_act_as_one_wall_of_summed_stiffness():
    # Two walls at the same place behave as one of stiffness k1 + k2.
    both = simulate(_walls(1e-3), periods=3, steps_per_period=2000)
    m = Mass("1", 1.0, dofs=("x",))
    one = Model((m,), (Spring("x1", 1e4),), (), (HarmonicForce(m, 20.0, 50.0),),
                (Contact(m, None, gap=1e-3, alpha=np.pi / 2, k=3e5, name="c"),))
    single = simulate(one, periods=3, steps_per_period=2000)
    np.testing.assert_allclose(both.final_state, single.final_state, rtol=1e-9, atol=1e-12)
