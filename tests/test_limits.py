"""Limits and extreme parameters of the blade pair: tests that can fail.

* bilinear -> Coulomb as ``kd`` grows;
* ``mu = 0`` is frictionless;
* a huge gap is contact-free;
* extreme parameters either run or are refused cleanly with a usable step count;
* the RK4 stability estimate behind the refusals is tight.

Measured values these tests rest on (10 periods from rest):

* ``|y_jenkins - y_coulomb| / |y_coulomb|`` at the end, gap 2.5e-4 m:
  1.37 (kd = 1e6), 0.293 (1e7), 0.129 (1e8), 0.023 (1e9).
* ``mu = 0`` vs ``friction="none"``, largest relative difference over the Poincare
  samples: ~1e-11 (Coulomb) and ~1e-11 (bilinear) at ``S = 4000`` with the default
  ``event_tol``, 1e-13 for both at ``S = 16000``, ``event_tol = 1e-13``. The
  residual is not physics: the extra ``v = 0`` / stick events split RK4 steps
  (an O(h^5) change per split), and for the Jenkins law the slip constraint
  ``kd z = s mu N`` is integrated in rate form from the bisection's far end, so a
  stretch ``z`` of order ``|v| event_tol h`` (a force ~1e-11 N) persists through
  each slip. Both vanish with the step and ``event_tol``.
"""

from __future__ import annotations

import math
import re
from itertools import pairwise

import numpy as np
import pytest

from blademodel.zheng2022.blade_pair import BladePair
from blademodel.numeric import StepTooLargeError, compile_model, simulate
from blademodel.numeric.reference import ReferenceSystem, simulate_reference
from blademodel.numeric.stability import rk4_amplification

_NEED = re.compile(r"steps_per_period >= (\d+)")


def _required_steps(model) -> int:
    """The step count the stability check asks for (from its refusal of S = 1)."""
    with pytest.raises(StepTooLargeError) as info:
        simulate(model, periods=1, steps_per_period=1)
    match = _NEED.search(str(info.value))
    assert match, f"refusal without a suggested step count: {info.value}"
    return int(match.group(1))


def _rel(a, b):
    a, b = np.atleast_2d(a), np.atleast_2d(b)
    return float(np.max(np.linalg.norm(a - b, axis=1) / np.linalg.norm(b, axis=1)))


# --- bilinear -> Coulomb ------------------------------------------------------------------

def test_bilinear_tends_to_coulomb_as_kd_grows():
    periods, gap = 10, 2.5e-4  # a period-1 case: differences reflect kd, not sensitivity
    kds = [1e6, 1e7, 1e8, 1e9]
    steps = {kd: max(4000, 10 * _required_steps(BladePair(friction="bilinear", kd=kd, gap=gap).build()))
             for kd in kds}
    assert steps[1e9] > 4000  # the stiff Jenkins spring really does need a smaller step
    S_ref = max(steps.values())
    coulomb = simulate(BladePair(friction="coulomb", gap=gap).build(), periods=periods,
                       steps_per_period=S_ref).final_state
    diffs = []
    for kd in kds:
        r = simulate(BladePair(friction="bilinear", kd=kd, gap=gap).build(), periods=periods,
                     steps_per_period=steps[kd])
        diffs.append(_rel(r.final_state[:8], coulomb))
    for a, b in pairwise(diffs):
        assert b < 0.75 * a, f"no monotone convergence to Coulomb: {diffs}"
    assert diffs[-1] < 0.05, diffs


# --- mu = 0 is frictionless -----------------------------------------------------------------

@pytest.mark.parametrize("friction", ["coulomb", "bilinear"])
@pytest.mark.parametrize("case", [{}, {"gap": 2.5e-4}], ids=["base", "gap250um"])
def test_zero_friction_matches_frictionless(friction, case):
    kw = {"periods": 10, "steps_per_period": 16000, "event_tol": 1e-13}
    none = simulate(BladePair(friction="none", **case).build(), **kw)
    r = simulate(BladePair(friction=friction, mu=0.0, **case).build(), **kw)
    assert r.counters["events"] > none.counters["events"] > 0  # the law's own events do happen
    err = max(_rel(r.poincare[:, :8], none.poincare), _rel(r.final_state[:8], none.final_state))
    assert err <= 1e-12, f"mu = 0 {friction} vs none: {err:.3e}"
    if friction == "bilinear":
        assert abs(r.final["z"]) * BladePair().kd < 1e-9  # the Jenkins force stays ~0 N


@pytest.mark.parametrize("friction", ["coulomb", "bilinear"])
def test_zero_friction_flows_equal_frictionless_flows(friction):
    """Every sliding mode's flow is the frictionless one (the generated kernel code)."""
    model = BladePair(friction=friction, mu=0.0).build()
    free = BladePair(friction="none").build()
    cm, cf = compile_model(model), compile_model(free)
    p, pf = cm.parameter_array(model), cf.parameter_array(free)
    closed = cf.mode_names.index("closed")
    rng = np.random.default_rng(1)
    modes = ["slip+", "slip-"] + (["stick"] if friction == "bilinear" else [])
    for _ in range(20):
        t = rng.uniform(0, 0.1)
        y = np.concatenate([rng.normal(0, 1e-4, 4), rng.normal(0, 0.05, 4)])
        out_f = np.empty(8)
        cf.module.rhs(closed, t, y, pf, out_f)
        for name in modes:
            yy = np.concatenate([y, np.zeros(len(cm.state_names) - 8)])
            out = np.empty(len(yy))
            cm.module.rhs(cm.mode_names.index(name), t, yy, p, out)
            np.testing.assert_allclose(out[:8], out_f, rtol=1e-13, atol=1e-13 * np.abs(out_f).max())


# --- a huge gap is contact-free -----------------------------------------------------------

@pytest.mark.parametrize("friction", ["coulomb", "bilinear", "none"])
def test_huge_gap_is_contact_free(friction):
    kw = {"periods": 10, "steps_per_period": 4000}
    free = simulate(BladePair().build(contact=False), **kw)
    r = simulate(BladePair(friction=friction, gap=1.0).build(), **kw)
    assert r.counters["events"] == 0
    assert np.all(r.mode == r.mode_names.index("open"))
    np.testing.assert_array_equal(r.y[:, :8], free.y)  # bitwise: the same equations
    np.testing.assert_array_equal(r.poincare[:, :8], free.poincare)


# --- extreme parameters: run, or refuse cleanly with a usable step count -------------------

def _run_or_refuse(model, steps_per_period=200, periods=4):
    """Simulate; on a stability refusal, simulate again with the suggested step count."""
    try:
        return simulate(model, periods=periods, steps_per_period=steps_per_period), None
    except StepTooLargeError as exc:
        match = _NEED.search(str(exc))
        assert match, f"refusal without a suggested step count: {exc}"
        need = int(match.group(1))
        assert need > steps_per_period
        r = simulate(model, periods=periods, steps_per_period=need)  # must succeed
        return r, need


EXTREMES = {
    "gamma=1000": ({"gamma": 1000.0}, True),
    "kd=1e9": ({"kd": 1e9}, None),  # refused for the bilinear law only
    "gap=0": ({"gap": 0.0}, False),
    "preload": ({"gap": -2e-4}, False),
    "F0=0": ({"F0": 0.0}, False),
    "mu=100": ({"mu": 100.0}, False),
}


@pytest.mark.parametrize("friction", ["coulomb", "bilinear"])
@pytest.mark.parametrize("name", list(EXTREMES))
def test_extreme_parameters_run_or_refuse_cleanly(friction, name):
    kw, refused = EXTREMES[name]
    if refused is None:
        refused = friction == "bilinear"
    model = BladePair(friction=friction, **kw).build()
    r, need = _run_or_refuse(model)
    assert (need is not None) == refused, f"{name}: refused={need}"
    assert r.status == 0 and np.all(np.isfinite(r.final_state)) and np.all(np.isfinite(r.y))
    modes = r.mode_names
    if name in ("preload", "gap=0"):
        assert modes[r.mode[0]] != "open"  # penetration >= 0 at rest: the contact starts closed
        ref_mode, _ = ReferenceSystem(model).initial_mode(0.0, np.zeros(len(r.state_names)))
        assert ref_mode == r.mode[0]
    if name == "F0=0":
        assert np.all(r.y == 0.0) and np.all(r.final_state == 0.0)
        assert r.counters["events"] == 0
    if name == "mu=100":
        closed = r.mode != modes.index("open")
        stick = r.mode == modes.index("stick")
        assert closed.mean() > 0.1  # the contact does close
        assert stick.sum() > 0.9 * closed.sum(), "mu = 100 should mostly stick while in contact"


# --- the stability estimate is tight --------------------------------------------------------

def _fd_jacobian(ref: ReferenceSystem, mode: int) -> np.ndarray:
    """Central-difference Jacobian of the SymPy-lambdified flow (affine: exact to round-off)."""
    n = ref.n_state
    J = np.empty((n, n))
    y0 = np.zeros(n)
    for j in range(n):
        e = np.zeros(n)
        e[j] = 1e-3 if j >= 4 else 1e-6
        J[:, j] = (ref.rhs(mode, 0.0, y0 + e) - ref.rhs(mode, 0.0, y0 - e)) / (2 * e[j])
    return J


def _max_amplification(model, h):
    ref = ReferenceSystem(model)
    worst = 0.0
    for mode in range(len(ref.mode_names)):
        for lam in np.linalg.eigvals(_fd_jacobian(ref, mode)):
            if lam.real > 1e-9 * max(abs(lam), 1.0):
                continue
            worst = max(worst, abs(rk4_amplification(h * lam)))
    return worst


@pytest.mark.parametrize("friction,kw", [("bilinear", {"kd": 1e9}), ("coulomb", {"gamma": 1000.0}),
                                         ("bilinear", {})])
def test_stability_estimate_is_tight(friction, kw):
    model = BladePair(friction=friction, **kw).build()
    N = _required_steps(model)
    low = math.floor(0.95 * N)
    with pytest.raises(StepTooLargeError, match=f"steps_per_period >= {N}"):
        simulate(model, periods=1, steps_per_period=low)
    simulate(model, periods=1, steps_per_period=N)  # passes the check
    # independent check from the SymPy flows: |R(h lambda)| <= 1 at N, > 1 at 0.95 N
    T = BladePair(**kw).period
    assert _max_amplification(model, T / N) <= 1.0 + 1e-9
    assert _max_amplification(model, T / low) > 1.0 + 1e-6


def test_reference_agrees_on_preload_and_stiff_stick():
    """The reference integrator sees the same preloaded start and stiff-stick motion."""
    model = BladePair(friction="bilinear", gap=-2e-4).build()
    r = simulate(model, periods=3, steps_per_period=8000)
    ref = simulate_reference(model, 3 * r.period)
    assert ref.initial_mode == r.mode[0] != r.mode_names.index("open")
    assert ref.event_log["guard"] == r.events["guard"]
    assert _rel(r.final_state, ref.y_final) < 1e-7
