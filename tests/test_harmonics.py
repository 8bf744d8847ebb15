"""First-harmonic amplitudes: of sampled signals, of ``simulate``'s report and of a sweep point."""

import numpy as np
import pytest

from blademodel.analysis import harmonic_amplitudes
from blademodel.commands.simulate import first_harmonics
from blademodel.zheng2022 import BladePair
from blademodel.numeric import simulate
from blademodel.numeric.kernels import make_integrator
from blademodel.sweep.point import run_point
from linear_reference import forced_response


def test_one_dft_bin_of_every_column_is_the_fft_s():
    """``dft_bin`` (a real product with the bin's cosine and sine rows) equals the FFT's bin of each column, for a
    strided view of a record (the orbit's physical states) and for several bins of the same length."""
    from blademodel.analysis.spectrum import dft_bin
    rng = np.random.default_rng(3)
    record = rng.standard_normal((1001, 13))
    Y = record[:-1, :9]                       # not contiguous: every row skips four columns
    for cycles in (1, 2, 7):
        assert np.allclose(dft_bin(Y, cycles), np.fft.fft(Y, axis=0)[cycles], rtol=0, atol=1e-12)


def test_the_amplitude_of_each_harmonic_of_a_sampled_signal():
    """Three whole periods of ``a0 + 2 cos(wt + 0.3) + 0.5 sin(3 wt)`` (and a closing sample): exact amplitudes."""
    S, K = 40, 3
    t = np.arange(K * S + 1) / S
    x = 0.7 + 2.0 * np.cos(2 * np.pi * t + 0.3) + 0.5 * np.sin(6 * np.pi * t)
    Y = np.c_[x, -x]
    assert harmonic_amplitudes(Y, S) == pytest.approx([2.0, 2.0], rel=1e-13)
    assert harmonic_amplitudes(x, S, k=3) == pytest.approx([0.5], rel=1e-12)
    assert harmonic_amplitudes(x, S, k=2) == pytest.approx([0.0], abs=1e-13)
    with pytest.raises(ValueError, match="whole number of periods"):
        harmonic_amplitudes(x[:-5], S)


def test_simulate_and_a_sweep_point_report_the_exact_linear_first_harmonics():
    """Contact-free pair (gap 1 m): the first harmonics over the recorded periods, in ``simulate``'s report (every
    step and every fourth step recorded) and in a sweep point's output, equal the exact forced response."""
    cfg = BladePair(gap=1.0)
    model = cfg.build()
    ig = make_integrator(model)
    Y = forced_response(ig)
    n = 2 * len(model.coordinates)
    exact = np.abs(Y[:n])
    for every in (1, 4):
        r = simulate(model, transient=200, periods=3, record_every=every)
        h = first_harmonics(r, n)
        assert np.allclose([h[s] for s in r.state_names[:n]], exact, rtol=1e-8)
    out = run_point({"model": "blade_pair", "gap": 1.0}, {},
                    dict(transient=200, periods=3, steps_per_period=1000, event_tol=1e-10))
    assert np.allclose(out["harmonic1"], exact, rtol=1e-8)
