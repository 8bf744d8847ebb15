"""A single-DOF Jenkins oscillator: the shooting orbit's first harmonic against an independent harmonic balance.

``m x'' + c x' + k x + f = F0 sin(omega t)``, ``f`` the force of a spring ``kd`` in series with a Coulomb
slider of limit ``mu N`` (constant ``N``: a preloaded contact with the ground). The harmonic balance below
shares nothing with blademodel: the unknowns are the Fourier coefficients of ``x``, the hysteretic force is
evaluated in time on a fine grid (the elastic-perfectly-plastic return map, two cycles so its start is
forgotten) and transformed back (alternating frequency-time), and the residual of every harmonic up to ``H``
is solved by ``scipy.optimize.root``.
"""

import numpy as np
import yaml
from numba import njit
from scipy.optimize import root

from blademodel.config import config_from_data
from blademodel.orbits import find_periodic_orbit

M, K, C, F0, MU_N, KD = 0.085, 1e5, 3.5, 30.0, 10.0, 2e5

YAML = f"""
model: components
name: jenkins_oscillator
parameters: {{m: {M}, k: {K}, c: {C}, F0: {F0}, omega: 1200.0, mu: 0.5, kc: 1e6, Delta: -2e-5, kd: {KD}}}
masses: [{{name: m, m: m, dofs: [x]}}]
springs: [{{a: x_m, k: k}}]
dampers: [{{a: x_m, c: c}}]
forces: [{{mass: m, amplitude: F0, omega: omega, phase: 0.0, angle: 0.0}}]
contacts:
  - {{name: c, bodies: [m, ground], alpha: 0.0, gap: Delta, k: kc, friction: {{law: bilinear, mu: mu, kd: kd}}}}
"""


@njit(cache=True)
def _jenkins(x, kd, limit):
    """The slider force along the samples ``x`` of one period, after a first period that sets its state."""
    n = x.size
    f = 0.0
    out = np.empty(n)
    for cycle in range(3):
        for j in range(n):
            f += kd * (x[j] - x[j - 1])       # x[-1]: the period's last sample, the one before x[0]
            f = min(max(f, -limit), limit)
            if cycle == 2:
                out[j] = f
    return out


def _harmonic_balance(omega, H, n_time):
    """First-harmonic amplitude of ``x`` by harmonic balance with ``H`` harmonics and ``n_time`` time samples."""
    h = np.arange(H + 1)
    dyn = K - M * (h * omega) ** 2 + 1j * C * h * omega      # the linear part, per harmonic
    exc = np.zeros(H + 1, dtype=complex)
    exc[1] = -1j * F0                                          # F0 sin(wt) = Re(-i F0 e^{iwt})

    def unpack(u):
        X = np.zeros(H + 1, dtype=complex)
        X[0] = u[0]
        X[1:] = u[1:H + 1] + 1j * u[H + 1:]
        return X

    def residual(u):
        X = unpack(u)
        spec = np.zeros(n_time // 2 + 1, dtype=complex)
        spec[:H + 1] = X * n_time / 2
        spec[0] = X[0] * n_time
        x = np.fft.irfft(spec, n_time)
        F = np.fft.rfft(_jenkins(x, KD, MU_N))[:H + 1] * 2 / n_time
        F[0] /= 2
        R = dyn * X + F - exc
        R[0] = R[0].real
        return np.concatenate([[R[0].real], R[1:].real, R[1:].imag]) / F0

    X1 = -1j * F0 / (K + KD - M * omega ** 2 + 1j * C * omega)   # the stuck linear response as the guess
    u0 = np.zeros(2 * H + 1)
    u0[1], u0[H + 1] = X1.real, X1.imag
    sol = root(residual, u0, method="hybr", options={"xtol": 1e-14})
    assert np.max(np.abs(residual(sol.x))) < 1e-12
    return abs(unpack(sol.x)[1])


def test_jenkins_oscillator_first_harmonic_against_harmonic_balance():
    """At omega = 1200 rad/s (between the free, 1085, and the stuck, 1879 rad/s, natural frequencies) the
    slider sticks and slips every half period. The harmonic balance converges with the number of harmonics
    (its change from 31 to 63 harmonics bounds its own error); the orbit found by shooting (RK8, 2000 steps a
    period) has the same first-harmonic amplitude to 1e-5."""
    omega = 1200.0
    cfg = config_from_data(yaml.safe_load(YAML))
    o = find_periodic_orbit(cfg.build(), method="rk8", steps_per_period=2000, event_tol=1e-12, transient=100)
    shooting = abs(o.harmonic("x_m"))
    hb = {H: _harmonic_balance(omega, H, 16384) for H in (31, 63)}
    assert abs(hb[63] - hb[31]) < 2e-6 * hb[63]         # the harmonic balance's own truncation error
    assert abs(shooting - hb[63]) < 1e-5 * hb[63]
    # the slider does slip: the force amplitude kd X exceeds the limit, so this is not the stuck linear response
    assert KD * np.max(np.abs(o.y[:, 0])) > 2 * MU_N
    stuck = abs(F0 / (K + KD - M * omega ** 2 + 1j * C * omega))
    assert abs(shooting - stuck) > 0.05 * stuck
