"""The least period of an orbit sought over several excitation periods."""

import json
from pathlib import Path

import numpy as np

from blademodel.cli import main
from blademodel.orbits import find_periodic_orbit
from blademodel.orbits.least_period import LEAST_PERIOD_TOL, least_period
from blademodel.orbits.shooting import LABEL_SCALE
from blademodel.zheng2022 import BladePair

MODELS = Path(__file__).resolve().parents[1] / "models"


def test_the_least_period_is_the_fewest_periods_after_which_every_sample_comes_back():
    a, b, c = np.array([1.0, 2.0]), np.array([1.5, -2.0]), np.array([0.3, 0.1])
    scale = np.ones(2)
    assert least_period(np.array([a]), scale) == 1
    assert least_period(np.array([a, a * (1 + 1e-9)]), scale) == 1
    assert least_period(np.array([a, b]), scale) == 2
    assert least_period(np.array([a, b, a, b]), scale) == 2       # period 4 sought, period 2 found
    assert least_period(np.array([a, b, c, b]), scale) == 4       # samples 2 apart differ at one of them
    assert least_period(np.array([a, b, c]), scale) == 3           # 2 does not divide 3
    # within the tolerance of the scale, not of the samples' size
    near = a + np.array([0.0, 2 * LEAST_PERIOD_TOL])
    assert least_period(np.array([a, near]), scale) == 2
    assert least_period(np.array([a, near]), np.array([1.0, 4.0])) == 1


def test_a_discrete_label_must_come_back_exactly():
    """A friction law's label scaled by LABEL_SCALE moves its scaled value by 1e-12 when it changes by 1: that
    still breaks the period, which the scaled distance alone would not see."""
    scale = np.array([1.0, LABEL_SCALE])
    s = np.array([[0.5, 1.0], [0.5, 0.0]])
    assert np.max(np.abs(s[1] - s[0]) / scale) < LEAST_PERIOD_TOL
    assert least_period(s, scale) == 2
    s[1, 1] = 1.0 + 1e-12   # rounding of a label is no change
    assert least_period(s, scale) == 1


def test_a_period_2_orbit_of_the_bilinear_pair_is_the_period_1_orbit_run_twice_where_that_is_the_only_one():
    """At 290 rad/s shooting over 2 T finds the stable period-1 orbit run twice (the same state that shooting over
    T finds, to 1e-8 of the scale); at gamma = 7.4, past the period doubling (7.325), it finds a true period-2
    orbit, whose samples differ by far more than the tolerance. The command line says which."""
    cfg = BladePair(friction="bilinear")
    twice = find_periodic_orbit(cfg.build(), periods=2, workers=1)
    once = find_periodic_orbit(cfg.build(), periods=1, guess=twice.state, mode=twice.mode, workers=1)
    assert twice.least_period() == 1 and once.least_period() == 1
    assert np.max(np.abs(twice.state - once.state) / twice.scale) < 1e-8
    doubled = find_periodic_orbit(BladePair(friction="bilinear", gamma=7.4).build(), periods=2, workers=1)
    steps = (doubled.y.shape[0] - 1) // 2
    assert np.max(np.abs(doubled.y[steps] - doubled.y[0]) / doubled.scale) > 1e-3
    assert doubled.least_period() == 2


def test_the_commands_report_the_least_period(capsys):
    model = str(MODELS / "blade_pair_bilinear.yaml")
    assert main(["orbit", model, "--period", "2", "--set", "omega=290"]) == 0
    assert "period-2 orbit (of least period 1: the period-1 orbit run 2 times)" in capsys.readouterr().out
    assert main(["orbit", model, "--period", "2", "--set", "gamma=7.4", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["least_period"] == 2
    assert main(["continue", model, "--param", "omega", "--from", "289", "--to", "290", "--periods", "2",
                 "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert set(rep["least_periods"]) == {1} and len(rep["least_periods"]) == rep["points"]
    assert main(["continue", model, "--param", "gamma", "--from", "7.2", "--to", "7.5", "--switch"]) == 0
    out = capsys.readouterr().out   # the doubled branch starts at the doubling, the period-1 orbit run twice
    assert "from the period doubling 1" in out and "; 1 of them the period-1 orbit run 2 times (gamma = 7.32" in out
