"""A window of stability or instability that one step jumps is found: both its crossings, where short steps put them."""

from __future__ import annotations

import numpy as np
import pytest

from blademodel.orbits import continuation
from blademodel.zheng2022 import BladePair


def _doublings(ds_max):
    b = continuation(BladePair(friction="bilinear"), "omega", 412.0, 422.0, ds_max=ds_max, workers=1)
    assert b.message.startswith("reached")
    return b, b.points("period-doubling")


@pytest.mark.parametrize("ds_max", [0.3, 0.4])
def test_a_long_step_across_a_stable_window_reports_both_its_period_doublings(ds_max):
    """The bilinear pair from 412 to 422 rad/s: at long steps one step goes from an unstable orbit to another across
    the stable window between the period doublings at 416.73 and 417.80 rad/s (its doubling multiplier just
    outside the circle at both ends). Both doublings are reported, where steps short enough to resolve the window
    put them, on the circle."""
    long, found = _doublings(ds_max)
    _, short = _doublings(0.05)
    assert len(short) == 2 and short[0].index != short[1].index               # short steps: one at a time
    assert len(found) == 2 and found[0].index == found[1].index               # here both in one step
    i = found[0].index
    assert not long.stable[i] and not long.stable[i + 1]                      # whose ends are both unstable
    np.testing.assert_allclose([p.param for p in found], [p.param for p in short], rtol=0, atol=1e-5)
    assert all(abs(abs(p.multiplier) - 1.0) < 1e-3 and p.multiplier.real < 0 for p in found)
