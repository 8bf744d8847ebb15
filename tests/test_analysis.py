"""Analyses against signals and systems whose answer is known exactly."""

import math

import numpy as np
import pytest

from blademodel.analysis import (CHAOS_THRESHOLD, amplitude_spectrum, classify_motion, largest_lyapunov,
                                 mean_square, poincare_period, vibration_reduction)
from blademodel.zheng2022 import BladePair
from blademodel.numeric import HybridIntegrator
from blademodel.sweep.point import run_point


def test_spectrum_of_known_multiharmonic_signal():
    S, K = 64, 4
    t = np.arange(K * S + 1) / S          # in periods, closing sample included
    x = 1.5 + 2 * np.cos(2 * np.pi * t) + 0.5 * np.sin(2 * np.pi * 3 * t + 0.2) + 0.25 * np.cos(np.pi * t + 0.3)
    ratio, amp = amplitude_spectrum(x, S)
    expected = {0.0: 1.5, 0.5: 0.25, 1.0: 2.0, 3.0: 0.5}
    for r, a in expected.items():
        assert amp[np.argmin(abs(ratio - r))] == pytest.approx(a, abs=1e-12)
    others = [i for i, r in enumerate(ratio) if r not in expected]
    assert np.max(amp[others]) < 1e-12


def test_spectrum_rejects_partial_periods():
    with pytest.raises(ValueError, match="whole number of periods"):
        amplitude_spectrum(np.zeros(100), 64)


@pytest.mark.parametrize("n", [1, 2, 3, 5, 16])
def test_period_of_constructed_sequences(n):
    rng = np.random.default_rng(n)
    cycle = rng.normal(size=(n, 3))
    seq = np.tile(cycle, (64 // n + 2, 1))[:64] + 1e-9 * rng.normal(size=(64, 3))
    assert poincare_period(seq) == n
    assert classify_motion(seq) == f"P{n}"


def test_chaotic_map_has_no_period():
    x = np.empty(200)
    x[0] = 0.1234
    for k in range(199):
        x[k + 1] = 4 * x[k] * (1 - x[k])   # the logistic map at r = 4 is chaotic
    assert poincare_period(x) == 0
    assert classify_motion(x, lyapunov=math.log(2)) == "chaos"   # its exponent is ln 2
    assert classify_motion(x, lyapunov=0.0) == "quasi-periodic"
    assert classify_motion(x, lyapunov=-0.3) == "nonperiodic"   # attracting, but no period <= 16
    assert CHAOS_THRESHOLD < math.log(2)


def test_lyapunov_of_linear_system_is_its_slowest_decay():
    cfg = BladePair()
    integ = HybridIntegrator(cfg.build(contact=False), steps_per_period=500)
    y = integ.initial_state()
    integ.advance(y, 0, 0, 50)
    scale = [cfg.gap] * 4 + [cfg.gap * cfg.omega] * 4
    lam = largest_lyapunov(integ, y, 0, start_period=50, periods=200, scale=scale)
    exact = -cfg.cx / (2 * cfg.m) * cfg.period    # x-modes decay slowest: exp(-cx t / 2m)
    assert lam == pytest.approx(exact, rel=2e-2)


def test_mean_square_of_harmonic_motion():
    S, K = 100, 3
    t = np.arange(K * S + 1) / S
    states = np.stack([0.3 * np.cos(2 * np.pi * t + 0.1), 0.4 * np.sin(2 * np.pi * 2 * t)], axis=1)
    assert mean_square(states, ["x1", "y1"]) == pytest.approx(0.3 ** 2 / 2 + 0.4 ** 2 / 2, rel=1e-12)


def test_vibration_reduction_sign_and_errors():
    assert vibration_reduction(0.25, 1.0) == pytest.approx(75.0)
    assert vibration_reduction(2.0, 1.0) == pytest.approx(-100.0)
    with pytest.raises(ValueError, match="P0"):
        vibration_reduction(1.0, 0.0)


def test_pd_is_zero_when_the_gap_is_too_large_for_contact():
    run = dict(transient=20, periods=10, steps_per_period=400, event_tol=1e-10, vibration_reduction=True)
    out = run_point({"model": "blade_pair", "friction": "bilinear"}, {"gap": 1.0}, run)
    assert out["events"] == 0
    # Bit-identical trajectories; the two means are summed in a different order.
    assert abs(out["Pd"]) < 1e-10 and out["P"] == pytest.approx(out["P0"], rel=1e-12) and out["P0"] > 0
    touching = run_point({"model": "blade_pair", "friction": "bilinear"}, {"gap": 4e-5}, run)
    assert touching["Pd"] > 10   # the contact does remove vibration when it closes


def test_streamed_mean_square_equals_the_mean_over_full_records():
    from blademodel.numeric import simulate
    from blademodel.numeric.mean_square import mean_square_run
    model = BladePair(friction="coulomb").build()
    r = simulate(model, transient=7, periods=13, steps_per_period=300)
    full = mean_square(r.y, r.state_names, ("x1", "y1"))
    streamed = mean_square_run(model, transient=7, periods=13, steps_per_period=300, chunk_periods=4)
    assert streamed == pytest.approx(full, rel=1e-13)


def test_simulate_json_reports_pd(tmp_path):
    import json
    import subprocess
    import sys
    out = subprocess.run([sys.executable, "-m", "blademodel", "simulate", "models/blade_pair_bilinear.yaml",
                          "--json", "--transient", "20", "--periods", "10", "--steps-per-period", "400"],
                         capture_output=True, text=True, check=True)
    rep = json.loads(out.stdout)
    run = dict(transient=20, periods=10, steps_per_period=400, event_tol=1e-10, vibration_reduction=True)
    point = run_point({"model": "blade_pair", "friction": "bilinear"}, {}, run)
    assert rep["Pd"] == pytest.approx(point["Pd"], rel=1e-10)
    assert rep["poincare"]["X1"] == pytest.approx(list(point["poincare_x1"] / 4e-5), rel=1e-12)
