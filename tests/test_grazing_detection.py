"""Grazing points found by a continuation do not depend on how many a step crosses.

A grazing changes which transitions the orbit crosses; the continuation compares the
orbits' event signatures (the multiset of transitions), not their numbers of events, and
locates every grazing between two points. The reference is the same branch at steps short
enough to cross the grazings one at a time.
"""

from __future__ import annotations

import numpy as np
import pytest

from blademodel.orbits import continuation
from blademodel.zheng2022 import BladePair


def _grazings(start, stop, ds_max):
    b = continuation(BladePair(friction="coulomb"), "omega", start, stop, ds_max=ds_max, workers=1)
    assert b.message.startswith("reached")
    inside = [p for p in b.points("grazing") if min(start, stop) <= p.param <= max(start, stop)]
    return b, np.array(sorted(p.param for p in inside)), [p.index for p in inside]


def _same_points(long, short, tol):
    assert long.size == short.size, (long, short)
    np.testing.assert_allclose(long, short, rtol=0, atol=tol)


@pytest.mark.parametrize("ds_max", [0.3, 1.0])
def test_a_step_across_two_grazings_reports_both(ds_max):
    """The Coulomb pair from 157 to 161 rad/s: one long step goes from an orbit of 12 events to one of 16,
    across the grazings at 160.2212 and 160.3522 rad/s; both are reported, where the shorter steps find them."""
    long, at_long, index = _grazings(157.0, 161.0, ds_max)
    _, at_short, index_short = _grazings(157.0, 161.0, 0.01)
    assert len(set(index_short)) == len(index_short)              # the short steps cross one at a time
    i = next(i for i in index if index.count(i) == 2)               # the long run has a step across two
    assert long.events[i + 1] - long.events[i] == 4
    _same_points(at_long, at_short, 1e-6 * 161.0)


def test_a_step_whose_number_of_events_stays_reports_its_grazings():
    """The Coulomb pair from 313.5 to 315 rad/s: a stick phase appears at 314.1365 rad/s (15 to 16 events) and a
    short slip before the contact opens vanishes at 314.1818 (16 to 15). A long step across both has 15 events
    at either end, so that comparing numbers of events sees nothing; both are reported."""
    long, at_long, index = _grazings(313.5, 315.0, 0.3)
    _, at_short, _ = _grazings(313.5, 315.0, 0.01)
    assert at_short.size == 2
    i = index[0]
    assert index == [i, i] and long.events[i] == long.events[i + 1]
    _same_points(at_long, at_short, 1e-6 * 315.0)


def test_a_grazing_whose_bisection_cannot_close_reports_the_bracket_that_holds_it(tmp_path):
    """The Coulomb pair near 305.78 rad/s: a stick phase appears (13 events, then 15), and just past it shooting
    stalls (the discrete flow sees the phase only once it spans a step). The bisection stops there, and the
    grazing point says between which values of the field it lies. Shooting at fixed values across that bracket,
    each from the last orbit, finds the change inside it; the bracket survives the branch file."""
    from blademodel.config import apply_overrides
    from blademodel.orbits import ShootingError, find_periodic_orbit
    from blademodel.orbits.branch_file import load_branch, save_branch
    from blademodel.orbits.period_map import PeriodMap
    from blademodel.numeric.kernels import make_integrator

    cfg = BladePair(friction="coulomb")
    b = continuation(cfg, "omega", 305.6, 306.0, ds_max=0.05, workers=1)
    (g,) = b.points("grazing")
    lo, hi = g.bracket
    assert b.params[g.index] <= lo <= g.param <= hi <= b.params[g.index + 1] and lo < hi

    before, after = b.events[g.index], b.events[g.index + 1]
    y, mode, seen = b.states[g.index], int(b.modes[g.index][0]), {}
    for w in np.linspace(b.params[g.index], hi, 61):   # from the branch point before the grazing
        model = apply_overrides(cfg, {"omega": float(w)}).build()
        try:
            orbit = find_periodic_orbit(model, guess=y, mode=mode, transient=0)
        except ShootingError:   # the discrete flow's gap
            continue
        y, mode = orbit.state, orbit.mode
        seen[float(w)] = PeriodMap(make_integrator(model)).run(y, mode).events
    assert set(seen.values()) == {before, after} and before != after
    last_before = max(w for w, e in seen.items() if e == before)
    first_after = min(w for w, e in seen.items() if e == after)
    assert last_before < first_after and lo <= first_after and last_before <= hi   # the change is in the bracket

    path = tmp_path / "branch.nc"
    save_branch(b, path, cfg)
    assert [p.bracket for p in load_branch(path).special] == [p.bracket for p in b.special]


def test_the_continue_command_says_where_a_grazing_point_is_only_bracketed(capsys):
    """``blademodel continue``: the report gives the bracket of a grazing point that could not be located to the
    tolerance (the Coulomb pair near 305.78 rad/s), in its text and in its JSON, and none elsewhere."""
    import json
    from pathlib import Path

    from blademodel.cli import main
    yaml = str(Path(__file__).resolve().parents[1] / "models" / "blade_pair_coulomb.yaml")
    args = ["continue", yaml, "--param", "omega", "--from", "305.6", "--to", "306", "--ds-max", "0.05"]
    assert main(args + ["--json"]) == 0
    (g,) = [p for p in json.loads(capsys.readouterr().out)["special"] if p["kind"] == "grazing"]
    lo, hi = g["bracket"]
    # shooting at fixed values finds no orbit at 305.78125 and one of 15 events at 305.78325
    assert lo <= g["value"] <= hi and lo < 305.78125 and 305.78325 <= hi
    assert main(args) == 0
    assert f"somewhere in [{lo:.8g}, {hi:.8g}]" in capsys.readouterr().out


def test_quick_trials_find_the_same_grazing_points_for_fewer_integrations(monkeypatch):
    """The bisection's trials at the chord give up at the first Broyden residual that does not fall (a trial at the
    kink the grazing makes cycles there) and the next one beside it is taken: on the bilinear pair from 255 to 262
    rad/s the grazing points are the same, to their location tolerance, as where each trial was rescued by halved
    steps, for fewer integrations (540 against 621)."""
    from blademodel.orbits import arclength as al

    def run():
        b = continuation(BladePair(friction="bilinear"), "omega", 255.0, 262.0, workers=1)
        assert b.message == "reached omega = 262"
        return b, np.array([p.param for p in b.points("grazing")]), [p.bracket is None for p in b.points("grazing")]

    quick, at_quick, closed_quick = run()
    corrected = al._Context._corrected
    monkeypatch.setattr(al._Context, "_corrected",
                        lambda self, *args, **kwargs: corrected(self, *args, **{**kwargs, "quick": False}))
    slow, at_slow, closed_slow = run()
    assert at_quick.size >= 3 and closed_quick == closed_slow   # (the same ones closed, the others bracketed)
    _same_points(at_quick, at_slow, 1e-7 * 7.0)
    assert np.array_equal(quick.params, slow.params)
    assert quick.integrations < slow.integrations
