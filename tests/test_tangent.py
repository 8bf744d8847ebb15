"""Sensitivities of the hybrid flow: the tangent replay against differences, exact identities and the orbit tools."""

from dataclasses import dataclass, field

import numpy as np
import pytest

from blademodel.components import Contact, HarmonicForce, Mass, Spring
from blademodel.components.friction import Candidate, ContactContext, FrictionLaw
from blademodel.components.parameter import Number, as_param
from blademodel.model import Model
from blademodel.zheng2022 import BladePair
from blademodel.numeric.contract import C_LOGGED, N_COUNTERS
from blademodel.numeric.kernels import make_integrator
from blademodel.numeric.methods import get_method
from blademodel.numeric.tangent import SensitivityError, flow_sensitivity
from blademodel.orbits import PeriodMap
from blademodel.orbits.family import _Family
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


def test_the_tangent_along_a_config_field():
    """The tangent along a config field's ``d p / d omega`` (from the field's path) with the moving period equals
    central differences of period maps built at ``omega +- delta`` from the config."""
    cfg, ig, y, mode = _settled("bilinear")
    fam = _Family(cfg, "omega", 1, dict(steps_per_period=1000, event_tol=1e-13, event_location="predicted"),
                  cfg.omega, bounds=(cfg.omega - 10, cfg.omega + 10))
    d = 1e-6 * cfg.omega
    dp, dT = fam.parameter_direction(cfg.omega, d, ig.meta["params"])
    s = PeriodMap(ig, 1, jacobian="tangent").derivatives(y, mode, dp, dT)
    fd = (fam.map_at(cfg.omega + d)(y, mode)[0] - fam.map_at(cfg.omega - d)(y, mode)[0]) / (2 * d)
    assert np.max(np.abs(s.parameter - fd)) < 1e-6 * np.max(np.abs(s.parameter))


def test_the_period_map_takes_the_tangent_on_either_kernel():
    """``PeriodMap.jacobian`` is the tangent on the product kernel (equal to ``differences`` to 1e-6). The
    pair on the per-contact kernel is differentiated by that kernel's replayed tangent
    (:mod:`blademodel.numeric.contact_tangent`: no generated variational equations at all), which equals the
    product kernel's compiled one to 1e-6; the product kernel's ``flow_sensitivity`` refuses the other
    kernel's integrator, naming its own."""
    _, ig, y, mode = _settled("coulomb")
    P = PeriodMap(ig, 1)
    assert P.exact
    sc = np.maximum(np.abs(y), 1e-3 * np.max(np.abs(y)))
    J = P.jacobian(y, mode, sc)
    D = P.differences(y, mode, sc, 1e-5)
    assert np.max(np.abs(J - D)) < 1e-6 * np.max(np.abs(J))
    ig_c = make_integrator(BladePair().build(), kernel="contact", steps_per_period=ig.steps_per_period)
    P_c = PeriodMap(ig_c, 1)
    assert P_c.exact
    J_c = P_c.jacobian(y, ig_c.mode_of(np.append(y, np.zeros(ig_c.n_state - y.size))), sc)
    assert P_c.replays == 1 and P.last_events > 0
    assert np.max(np.abs((J_c - J) * sc[None, :] / sc[:, None])) < 1e-6 * np.max(np.abs(J * sc[None, :] / sc[:, None]))
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


def test_whole_steps_of_affine_modes_read_from_the_record_give_the_same_tangent():
    """The replay takes a run of whole steps in a mode whose flow is affine in the state as one matrix power and
    reads their states from the kernel's record (``PeriodMap`` passes it); stepping every one of them, as
    ``flow_sensitivity`` does on its own, gives the same monodromy and end state, through impacts and stick-slip."""
    from blademodel.numeric.tangent import sensitivity_module
    for law in ("coulomb", "bilinear"):
        _, ig, y, mode = _settled(law)
        assert sensitivity_module(ig).FLOW_AFFINE.all()   # every built-in law's flow is affine in each mode
        P = PeriodMap(ig, 2)
        r = P.run(y, mode)
        assert r.n_log >= 20
        n = ig.n_physical
        fast = flow_sensitivity(ig, r.start[:n], r.mode, 2, run=(r.end, r.mode_end, r.log, r.n_log), record=r.states)
        each = flow_sensitivity(ig, y, mode, 2)
        assert np.array_equal(fast.state, each.state)
        assert np.max(np.abs(fast.monodromy - each.monodromy)) <= 1e-12 * np.max(np.abs(each.monodromy))


def test_the_period_map_differentiates_the_run_it_made():
    """A derivative at the point the map was just evaluated at replays that run (no new integration) and equals a
    fresh map's; a start the map has not seen runs the kernel again."""
    _, ig, y, mode = _settled("bilinear")
    P = PeriodMap(ig, 1)
    Py, _ = P(y, mode)
    runs = P.evaluations
    s = P.derivatives(y, mode)
    assert P.evaluations == runs
    fresh = PeriodMap(ig, 1).derivatives(y, mode)
    assert np.array_equal(s.state, Py) and np.array_equal(s.monodromy, fresh.monodromy)
    P.derivatives(y * (1 + 1e-9), mode)
    assert P.evaluations == runs + 1


@dataclass(frozen=True)
class CubicDrag(FrictionLaw):
    """``f = c3 v^3`` while closed: a law whose flow is not affine in the state (one mode, no guard)."""

    c3: Number = 1.0
    _p: dict = field(init=False, repr=False, compare=False)

    modes = ("drag",)

    def __post_init__(self):
        object.__setattr__(self, "_p", {"c3": as_param(self.c3, "c3", field="friction: c3", minimum=0.0)})

    def parameters(self):
        return dict(self._p)

    def force(self, mode, ctx: ContactContext):
        return ctx.params["c3"] * ctx.v ** 3

    def guards(self, mode, ctx: ContactContext):
        return []

    def entry(self, ctx: ContactContext):
        return [Candidate("drag")]


@pytest.mark.slow   # a cold compile of its own law and tangent (~50 s in CI)
def test_a_flow_not_affine_in_the_state_is_differentiated_step_by_step():
    """A mass on a spring against a cubic drag (``m x'' + k x + c3 x'^3 = F sin wt``): its mode is not affine, so
    the replay differentiates every step with the Jacobian at the stages; monodromy and a parameter derivative
    equal central differences of the map."""
    from blademodel.numeric.tangent import sensitivity_module
    mass = Mass("1", 1.0, dofs=("x",))
    model = Model((mass,), (Spring("x1", 1e4),), (), (HarmonicForce(mass, 50.0, 80.0),),
                  (Contact(mass, None, alpha=0.0, normal_load=1.0, friction=CubicDrag(2.0)),))
    ig = make_integrator(model, steps_per_period=2000, event_tol=1e-13)
    y = ig.initial_state()
    mode = ig.mode_of(y)
    assert sensitivity_module(ig).FLOW_AFFINE[mode] == 0   # the drag mode, which the load never lets open
    assert ig.advance(y, mode, 0, 30)[0] == 0
    y = y[:ig.n_physical].copy()
    names = ig.meta["params"]
    dp = np.zeros(len(names))
    dp[names.index("c3")] = 1.0
    s = PeriodMap(ig, 1).derivatives(y, mode, dp)
    assert np.max(np.abs(s.monodromy - _differences(ig, y, mode, 1))) < 1e-7 * np.max(np.abs(s.monodromy))
    d = 1e-6 * ig.p_raw[names.index("c3")]
    fd = (_map(ig, y, mode, 1, p_raw=ig.p_raw + d * dp) - _map(ig, y, mode, 1, p_raw=ig.p_raw - d * dp)) / (2 * d)
    assert np.max(np.abs(s.parameter - fd)) < 1e-6 * np.max(np.abs(s.parameter))


def test_the_replay_links_the_kernels_functions_and_its_helpers_are_only_linked():
    """The tangent module takes the kernel's own compiled functions (it does not compile their source again)
    and, where this process compiled it, the replay is an entry point whose helpers were only linked
    (``blademodel.numeric.code_libraries``); where it came from the cache, no helper was compiled at all."""
    import numba
    from numba.core.codegen import JITCodeLibrary

    from blademodel.numeric import code_libraries
    from blademodel.numeric.tangent import sensitivity_module
    _, ig, y, mode = _settled("coulomb")
    PeriodMap(ig).derivatives(y, mode)
    mod = sensitivity_module(ig)
    for name in ("rk4_step", "rhs", "guards", "transition", "GUARD_DIR"):
        assert getattr(mod, name) is getattr(ig.module, name)
    if not numba.__version__.startswith(code_libraries.CHECKED_NUMBA):
        pytest.skip(f"Numba {numba.__version__} is not a release the pipelines were checked on: Numba's own run")
    replay = next(iter(mod.replay_tangent.overloads.values())).library
    helpers = [mod.flow_jacobian, mod.tangent_step, mod.event_time_tangent, mod.queue_whole_steps]
    if type(replay) is JITCodeLibrary:   # loaded from the cache: its helpers' code is inside it
        assert not any(h.overloads for h in helpers)
    else:
        assert isinstance(replay, code_libraries.EntryPointLibrary)
        assert all(isinstance(next(iter(h.overloads.values())).library, code_libraries.LinkedOnlyLibrary)
                   for h in helpers)
