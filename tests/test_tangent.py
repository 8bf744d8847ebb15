"""Sensitivities of the hybrid flow: the tangent replay against differences, exact identities and the orbit tools."""

import numpy as np
import pytest

from blademodel.zheng2022 import BladePair
from blademodel.numeric.contract import C_LOGGED, N_COUNTERS
from blademodel.numeric.kernels import make_integrator
from blademodel.numeric.methods import get_method
from blademodel.numeric.tangent import SensitivityError, flow_sensitivity
from blademodel.orbits import PeriodMap
from blademodel.orbits.arclength import _Family
from linear_reference import linear_parts


def _settled(law, gamma=None, steps=1000):
    """A pair integrator at ``event_tol = 1e-13`` (so differences resolve) and its state after 50 periods."""
    cfg = BladePair(friction=law) if gamma is None else BladePair(friction=law, gamma=gamma)
    ig = make_integrator(cfg.build(), steps_per_period=steps, event_tol=1e-13, event_location="predicted")
    y = ig.initial_state()
    mode = ig.mode_of(y)
    status, mode, _ = ig.advance(y, mode, 0, 50)
    assert status == 0
    return cfg, ig, y[:ig.n_physical].copy(), mode


def _map(ig, y, mode, periods, p_raw=None, period=None):
    """The kernel's state after ``periods`` from ``(y, mode)``, optionally with other raw parameters and period."""
    p0, T0 = ig.p, ig.period
    if p_raw is not None:
        ig.p = ig.module.derived(p_raw)
    if period is not None:
        ig.period = period
    try:
        full = np.zeros(ig.n_state)
        full[:ig.n_physical] = y
        status, _, _ = ig.advance(full, mode, 0, periods)
        assert status == 0
        return full[:ig.n_physical]
    finally:
        ig.p, ig.period = p0, T0


def _differences(ig, y, mode, periods, d=1e-5):
    """Central differences of the map, each state's step ``d`` times its size."""
    n = y.size
    sc = np.maximum(np.abs(y), 1e-3 * np.max(np.abs(y)))
    J = np.empty((n, n))
    for i in range(n):
        e = np.zeros(n)
        e[i] = d * sc[i]
        J[:, i] = (_map(ig, y + e, mode, periods) - _map(ig, y - e, mode, periods)) / (2 * e[i])
    return J


def _transitions(ig, y, mode, periods):
    """The set of ``(from, to)`` mode names of the run's events."""
    log = ig.log_buffer(4096)
    c = np.zeros(N_COUNTERS, dtype=np.int64)
    full = np.zeros(ig.n_state)
    full[:ig.n_physical] = y
    ig.advance(full, mode, 0, periods, log=log, counters=c)
    ev = ig.named_events(log, int(c[C_LOGGED]))
    return {(a.split()[-1], b.split()[-1]) for a, b in zip(ev["from"], ev["to"])}


@pytest.mark.parametrize("law", ["coulomb", "bilinear"])
def test_the_monodromy_equals_differences_of_the_flow(law):
    """Two periods with impacts, separations and stick-slip transitions: the tangent's monodromy equals central
    differences of the kernel's map to 1e-6 (the differences' own error is about 1e-8)."""
    _, ig, y, mode = _settled(law)
    seen = _transitions(ig, y, mode, 2)
    assert {"open", "stick"} <= {m for pair in seen for m in pair}
    assert any(a == "stick" and b.startswith("slip") for a, b in seen)      # stick -> slip
    assert any(a.startswith("slip") and b == "stick" for a, b in seen)      # slip -> stick
    s = flow_sensitivity(ig, y, mode, 2)
    J = _differences(ig, y, mode, 2)
    assert s.events >= 10
    assert np.max(np.abs(s.monodromy - J)) < 1e-6 * np.max(np.abs(s.monodromy))
    assert np.allclose(s.state, _map(ig, y, mode, 2), rtol=0, atol=0)


@pytest.mark.parametrize("law,name", [("coulomb", "mu"), ("coulomb", "Delta"), ("bilinear", "kd"),
                                      ("bilinear", "omega")])
def test_a_parameter_derivative_equals_differences(law, name):
    """``d P / d p`` for a friction coefficient, the gap, the slider stiffness and the excitation frequency (whose
    period, and so the section time, moves with it) against central differences of the map, to 1e-6."""
    _, ig, y, mode = _settled(law)
    names = ig.meta["params"]
    j = names.index(name)
    dp = np.zeros(len(names))
    dp[j] = 1.0
    p0, T0 = ig.p_raw.copy(), ig.period
    dT = -T0 / p0[j] if name == "omega" else 0.0
    s = flow_sensitivity(ig, y, mode, 2, dp=dp, dperiod=dT)
    h = 1e-6 * abs(p0[j])
    pp, pm = p0.copy(), p0.copy()
    pp[j] += h
    pm[j] -= h
    fd = (_map(ig, y, mode, 2, pp, T0 + dT * h) - _map(ig, y, mode, 2, pm, T0 - dT * h)) / (2 * h)
    assert np.max(np.abs(s.parameter - fd)) < 1e-6 * np.max(np.abs(s.parameter))


@pytest.mark.parametrize("method", ["rk4", "rk8"])
def test_without_contact_the_monodromy_is_the_methods_amplification_matrix(method):
    """Gap out of reach, the flow is ``A y + b(t)``: the discrete map over ``S`` steps has the derivative
    ``R(h A)^S``, ``R`` the method's stability polynomial, exactly (to rounding); and the map is affine in the
    force amplitude, so its derivative there is ``(P(y) - M y) / F0``."""
    cfg = BladePair(gap=1.0)
    S = 200
    ig = make_integrator(cfg.build(), steps_per_period=S, method=method)
    A = linear_parts(ig)[0]
    h = ig.period / S
    meth = get_method(method)
    # R(hA) = I + sum_k (b^T A_tab^(k-1) 1) (hA)^k
    R = np.eye(A.shape[0])
    v = np.ones(meth.stages)
    Z = np.eye(A.shape[0])
    for _ in range(meth.stages):
        Z = Z @ (h * A)
        R = R + float(meth.b @ v) * Z
        v = meth.A @ v
    M = np.linalg.matrix_power(R, S)
    y = np.array([1e-4, -2e-4, 3e-4, 1e-4, 0.1, -0.2, 0.05, 0.3])
    mode = ig.mode_of(np.append(y, np.zeros(ig.n_state - y.size)))
    names = ig.meta["params"]
    dp = np.zeros(len(names))
    dp[names.index("F0")] = 1.0
    s = flow_sensitivity(ig, y, mode, 1, dp=dp)
    assert s.events == 0
    assert np.max(np.abs(s.monodromy - M)) < 1e-11 * np.max(np.abs(M))
    F0 = ig.p_raw[names.index("F0")]
    assert np.max(np.abs(s.parameter - (s.state - M @ y) / F0)) < 1e-10 * np.max(np.abs(s.parameter))


def test_the_continuation_column_along_a_config_field():
    """The field's column of the continuation Jacobian, the tangent along ``d p / d omega`` with the moving period,
    equals central differences of period maps built at ``omega +- delta`` from the config."""
    cfg, ig, y, mode = _settled("bilinear")
    fam = _Family(cfg, "omega", 1, dict(steps_per_period=1000, event_tol=1e-13, event_location="predicted"),
                  cfg.omega)
    d = 1e-6 * cfg.omega
    dp, dT = fam.parameter_direction(cfg.omega, d, ig.meta["params"])
    s = PeriodMap(ig, 1, jacobian="tangent").derivatives(y, mode, dp, dT)
    fd = (fam.map_at(cfg.omega + d)(y, mode)[0] - fam.map_at(cfg.omega - d)(y, mode)[0]) / (2 * d)
    assert np.max(np.abs(s.parameter - fd)) < 1e-6 * np.max(np.abs(s.parameter))


def test_the_period_map_takes_the_tangent_and_falls_back_to_differences():
    """``PeriodMap.jacobian`` is the tangent on the product kernel (equal to ``differences`` to 1e-6); on the
    per-contact kernel ``auto`` falls back to differences and ``tangent`` is refused, naming the kernel."""
    _, ig, y, mode = _settled("coulomb")
    P = PeriodMap(ig, 1)
    assert P.exact
    sc = np.maximum(np.abs(y), 1e-3 * np.max(np.abs(y)))
    J = P.jacobian(y, mode, sc)
    D = P.differences(y, mode, sc, 1e-5)
    assert np.max(np.abs(J - D)) < 1e-6 * np.max(np.abs(J))
    ig_c = make_integrator(BladePair().build(), kernel="contact")
    assert not PeriodMap(ig_c, 1).exact
    with pytest.raises(ValueError, match="product-mode kernel"):
        PeriodMap(ig_c, 1, jacobian="tangent")
    with pytest.raises(ValueError, match="jacobian = 'newton'"):
        PeriodMap(ig, 1, jacobian="newton")
    with pytest.raises(SensitivityError, match="product-mode kernel"):
        flow_sensitivity(ig_c, y, np.zeros(1, dtype=np.int64), 1)


def test_a_wrong_parameter_direction_is_refused():
    _, ig, y, mode = _settled("coulomb")
    with pytest.raises(ValueError, match="one entry per raw parameter"):
        flow_sensitivity(ig, y, mode, 1, dp=np.ones(3))


def test_a_start_past_a_guard_is_settled_and_differentiated_through_its_reset():
    """A closed-contact state given in the open mode: the period map first closes the contact (the Jenkins
    slider reset to zero, ``settle``), so the map does not depend on the given slider state. The tangent carries
    that reset's Jacobian: it equals central differences of the settled map to 1e-6, and its slider column is
    zero."""
    _, ig, y, mode = _settled("bilinear")
    P = PeriodMap(ig, 1, jacobian="tangent")
    g = np.empty(ig.module.GUARD_DIR.shape[1] + 1)
    # a point of the orbit where the contact is closed, given as "open"
    rec = ig.record_buffer(ig.steps_per_period + 1)
    full = np.zeros(ig.n_state)
    full[:y.size] = y
    ig.advance(full, mode, 0, 1, n_transient=0, record=rec)
    for k in range(ig.steps_per_period):
        ig.module.guards(0, rec[0][k], rec[1][k], ig.p, g)
        if rec[2][k] != 0 and g[0] > 1e-7:
            break
    else:
        pytest.fail("the orbit never closes its contact")
    y_closed = rec[1][k, :ig.n_physical].copy()
    y_closed[ig.meta["state"].index("z")] = 1e-7          # a slider state the closing reset discards
    s = P.derivatives(y_closed, 0)
    sc = np.maximum(np.abs(y_closed), 1e-3 * np.max(np.abs(y_closed)))
    D = P.differences(y_closed, 0, sc, 1e-5)
    assert np.max(np.abs(s.monodromy - D)) < 1e-6 * np.max(np.abs(s.monodromy))
    assert np.all(s.monodromy[:, ig.meta["state"].index("z")] == 0.0)
