"""``grazing_tol`` trades where grazing points are reported for integrations, and never moves the branch."""

import numpy as np
import pytest

from blademodel.orbits import continuation
from blademodel.zheng2022 import BladePair

START, STOP = 312.3, 313.4   # the Coulomb pair gains or loses events a period at five points in here


def _branch(grazing_tol=None):
    return continuation(BladePair(friction="coulomb"), "omega", START, STOP, workers=1, grazing_tol=grazing_tol)


def test_a_coarser_grazing_tolerance_moves_only_the_grazing_points():
    """The same points to the bit (states, multipliers, events); each grazing point within the two tolerances of
    the finely located one and still between the branch points it was found between; fewer integrations; and
    with ``inf`` no location at all: each grazing point is the first branch point past it."""
    fine, coarse, none = _branch(), _branch(1e-4), _branch(np.inf)
    span = STOP - START
    for b in (coarse, none):
        for name in ("params", "states", "multipliers", "events"):
            np.testing.assert_array_equal(getattr(b, name), getattr(fine, name))
    located = [p.param for p in fine.points("grazing")]
    assert len(located) >= 3
    assert [p.index for p in coarse.points("grazing")] == [p.index for p in fine.points("grazing")]
    for p, q in zip(coarse.points("grazing"), located):
        assert abs(p.param - q) <= (1e-4 + 1e-7) * span
        assert min(coarse.params[p.index], coarse.params[p.index + 1]) <= p.param \
            <= max(coarse.params[p.index], coarse.params[p.index + 1])
    for p in none.points("grazing"):
        assert p.param == none.params[p.index + 1]
    assert fine.integrations > coarse.integrations > none.integrations


@pytest.mark.parametrize("bad", [0.0, -1e-3, float("nan")])
def test_a_grazing_tolerance_that_is_not_positive_is_refused(bad):
    with pytest.raises(ValueError, match="grazing_tol"):
        _branch(bad)


def test_the_continue_command_takes_a_grazing_tolerance(tmp_path, capsys):
    """``--grazing-tol inf``: each reported grazing point is the first branch point past it; 0 is refused by name."""
    import json
    from pathlib import Path

    from blademodel.cli import main
    yaml = str(Path(__file__).resolve().parent.parent / "models" / "blade_pair_coulomb.yaml")
    args = ["continue", yaml, "--param", "omega", "--from", str(START), "--to", str(STOP)]
    assert main(args + ["--grazing-tol", "inf", "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    grazing = [p["value"] for p in rep["special"] if p["kind"] == "grazing"]
    assert grazing and set(grazing) <= set(rep["values"])
    assert main(args + ["--grazing-tol", "0"]) == 2
    assert "--grazing-tol must be > 0 (or inf), got 0.0" in capsys.readouterr().err
