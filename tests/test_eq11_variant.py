"""The 'eq11_as_printed' variant integrates the paper's Eq. 11 exactly as printed."""

import math

import numpy as np
import pytest
import sympy as sp

from blademodel.zheng2022 import BladePair
from blademodel.symbolic import derive


@pytest.mark.parametrize("friction", ["coulomb", "bilinear"])
def test_variant_is_eq11_as_printed(friction):
    cfg = BladePair(friction=friction, equations="eq11_as_printed")
    base = BladePair(friction=friction)   # the paper's parameters, used by the printed equations
    model = cfg.build()
    system = derive(model)
    p = model.parameters
    wx, wy = math.sqrt(base.kx / base.m), math.sqrt(base.ky / base.m)
    eps1, eps2 = base.cx / (2 * base.m * wx), base.cy / (2 * base.m * wy)
    D, a, b = base.gap, base.alpha, base.beta
    rng = np.random.default_rng(1)
    for mode in system.modes:
        if mode.constrained:
            continue  # Eq. 11 states no stick force; the slip and open modes carry the comparison
        f_acc = sp.lambdify([system.t, system.state, system.params], mode.accelerations)
        f_N = sp.lambdify([system.state, system.params], mode.normal_forces[0])
        f_f = sp.lambdify([system.state, system.params], mode.friction_forces[0])
        for _ in range(3):
            tau = rng.uniform(0, 20)
            X = rng.normal(size=4)            # X1, Y1, X2, Y2
            dX = rng.normal(size=4)           # dX/dtau
            z = [rng.normal() * 1e-6] if friction == "bilinear" else []
            state = [*(D * X), *(D * wx * dX), *z]   # t' = tau / wx, so dx/dt' = D wx dX/dtau
            acc = np.array(f_acc(tau / wx, state, list(p.values())))
            N, f = f_N(state, list(p.values())), f_f(state, list(p.values()))
            Xpp = acc / (D * wx ** 2)          # d2X/dtau2
            Q = [base.F0 * math.sin(tau + base.phi1), base.F0 * math.sin(tau + base.phi2)]
            for i, s in ((0, 1), (1, -1)):
                # Eq. 11 as printed, blade i (s: +1 for blade 1, -1 for blade 2)
                rx = Q[i] * math.cos(b) / (base.m * D * wx ** 2) + s * (-N * math.sin(a) - f * math.cos(a)) / (base.m * D * wx ** 2)
                ry = Q[i] * math.sin(b) / (base.m * D * wy ** 2) + s * (N * math.cos(a) - f * math.sin(a)) / (base.m * D * wy ** 2)
                lhs_x = Xpp[2 * i] + 2 * eps1 * dX[2 * i] + X[2 * i]
                lhs_y = Xpp[2 * i + 1] + 2 * eps2 * dX[2 * i + 1] + X[2 * i + 1]
                assert lhs_x == pytest.approx(rx, rel=1e-9, abs=1e-9), mode.name
                assert lhs_y == pytest.approx(ry, rel=1e-9, abs=1e-9), mode.name


def test_variant_period_is_two_pi_over_omega_x():
    cfg = BladePair(equations="eq11_as_printed")
    assert cfg.period == pytest.approx(2 * math.pi / math.sqrt(cfg.kx / cfg.m))
    assert BladePair().period == pytest.approx(2 * math.pi / 290.0)
