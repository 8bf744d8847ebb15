"""Guards that a transition leaves a rounding error on their wrong side, read from their boundary by the product-mode
kernel (``blademodel/numeric/loop.py: drift_offsets``).

An Iwan element that sticks takes the stretch of its slip force exactly, so the contact's shared stick guard (the
least over the sticking elements of ``mu N phi - kd z``) starts an ulp either side of zero. From below zero it never
crossed: another element reaching its slip force later in the step stuck on past it until another event let it slip,
and the period map jumped between neighbouring parameter values as rounding put that ulp on one side or the other.
"""

from __future__ import annotations

import numpy as np
import pytest

from blademodel.orbits import continuation, find_periodic_orbit
from blademodel.orbits.family import _Family
from blademodel.zheng2022 import BladePair

OMEGA = 166.48
SETTINGS = dict(steps_per_period=2000, event_tol=1e-10, method="rk4", kernel="auto")


@pytest.fixture(scope="module")
def iwan_orbit():
    fam = _Family(BladePair(friction="iwan"), "omega", 1, SETTINGS, OMEGA, bounds=(150.0, 170.0))
    orbit = find_periodic_orbit(None, integrator=fam.map_at(OMEGA).integrator, transient=50)
    return fam, orbit


def test_the_iwan_map_is_continuous_in_the_field(iwan_orbit):
    """The Iwan pair at 166.48 rad/s, 2000 steps a period (its orbit after 50 periods from rest): difference quotients
    of the period map in omega over 2e-7 to 2e-5 rad/s, both ways, agree with the tangent's own parameter column
    (through the moving period) to 1e-3 of its size (measured: 8.4e-5 at most). With the stick guard read from below
    zero the quotient over 2e-6 rad/s read 40 times the column's size off, over 2e-7 400 times, over -2e-5 4.0
    times: a jump of the map, not a kink."""
    fam, orbit = iwan_orbit
    P = fam.map_at(OMEGA)
    y, mode, scale = orbit.state, orbit.mode, orbit.scale
    dp, dT = fam.parameter_direction(OMEGA, 1e-6 * OMEGA, P.integrator.meta["params"])
    exact = P.derivatives(y, mode, dp, dT).parameter / scale
    base = P(y, mode)[0]
    for d in (2e-7, 2e-6, 2e-5, -2e-6, -2e-5):
        quotient = (fam.map_at(OMEGA + d)(y, mode)[0] - base) / d / scale
        assert np.linalg.norm(quotient - exact) < 1e-3 * np.linalg.norm(exact), d


def test_no_iwan_element_sticks_past_its_slip_force(iwan_orbit):
    """The run from that orbit at 166.48 + 2e-6 rad/s, where the missed crossing was met: at every step of the period,
    both shared stick guards of the closed contact are at least zero to 1e-10 of the mode's largest guard (no
    sticking element's force past its slip force). It read -9e-3 of the mode's largest guard for a step, until the next
    element's reset let the element slip."""
    fam, orbit = iwan_orbit
    P = fam.map_at(OMEGA + 2e-6)
    ig = P.integrator
    run = P.run(orbit.state, orbit.mode)
    names = ig.meta["guards"]
    g = np.empty(max(len(n) for n in names) + 1)
    worst = np.inf
    for k in range(run.t.size):
        m = int(run.modes[k])
        if ig.meta["modes"][m] != "closed":
            continue
        ig.module.guards(m, run.t[k], run.states[k], ig.p, g)
        stick = [g[i] for i, name in enumerate(names[m]) if "stick->slip" in name]
        worst = min(worst, min(stick) / np.max(np.abs(g[:len(names[m])])))
    assert np.isfinite(worst) and worst >= -1e-10


@pytest.mark.slow
def test_the_iwan_branch_through_its_grazings_reaches_its_end():
    """The Iwan pair over 150 to 170 rad/s at 2000 steps a period (its events changing at almost every step): every
    orbit stable, the field rising at every point to 170 rad/s. With the stick guard read from below zero, the
    forward difference of the field's column at 166.4829 rad/s crossed a jump of the map and pointed the tangent back
    along the part passed: the branch crept on by shots and turned back onto itself near 165.7 rad/s."""
    b = continuation(BladePair(friction="iwan"), "omega", 150.0, 170.0, max_points=400, workers=1,
                     steps_per_period=2000)
    assert b.message == "reached omega = 170"
    assert np.all(np.diff(b.params) > 0) and b.stable.all()


# --- the offsets as state of a run: handed from one call to the next only where the call goes on ---------------------

def _pair_at_290():
    from blademodel.numeric import HybridIntegrator
    return HybridIntegrator(BladePair(friction="bilinear", omega=290.0).build(), steps_per_period=1000)


class _KernelSpy:
    """A compiled model module whose ``integrate`` calls ``seen(args, out, offsets before the call)`` after each run."""

    def __init__(self, module, seen):
        self._module, self._seen = module, seen

    def __getattr__(self, name):
        return getattr(self._module, name)

    def integrate(self, *args):
        before = args[-2].copy()
        out = self._module.integrate(*args)
        self._seen(args, out, before)
        return out


def _kernel_run(ig, y, mode, start, goff):
    """One period of the compiled kernel from ``(start * T, y, mode)`` with the drift offsets ``goff``: its record
    (every step) and its event log."""
    from blademodel.numeric.contract import C_LOGGED, N_COUNTERS
    S = ig.steps_per_period
    rec, log = ig.record_buffer(S + 1), ig.log_buffer(64)
    counters = np.zeros(N_COUNTERS, dtype=np.int64)
    ig.module.integrate(y, mode, ig.p, ig.period, S, start, start + 1, start, 1, ig.event_tol, ig.max_events_per_step,
                        False, np.zeros(0), *rec, np.empty((1, y.size)), *log, counters, goff, True)
    return rec, [a[:int(counters[C_LOGGED])] for a in log]


def test_the_kernel_reads_a_guard_from_the_offset_it_is_handed():
    """The bilinear pair at 290 rad/s in the last step of a stick that ends in a slip forwards, its stretch moved so
    that the stick guard ``mu N - kd z`` reads -1e-13 of the mode's largest guard (a slip force a rounding error
    exceeded), still falling. Handed that value as the guard's offset, the kernel slips at once (1e-15 s on); from
    zero offsets (a run that starts there) the guard never crosses, and the contact sticks on past its slip force
    (measured: for 78 steps, the guard down to -0.39 of the mode's largest). That is what a call going on from a
    transition did before ``advance`` handed the offsets on."""
    from blademodel.numeric import HybridIntegrator
    ig = _pair_at_290()
    y = ig.initial_state()
    mode = ig.mode_of(y)
    _, mode, _ = ig.advance(y, mode, 0, 50)
    rec = ig.record_buffer(ig.steps_per_period + 1)
    ig.advance(y, mode, 50, 51, record=rec)
    g = np.empty_like(ig._goff)
    stick = ig.meta["modes"].index("stick")

    def stick_guard(j):
        ig.module.guards(stick, rec[0][j], rec[1][j], ig.p, g)
        return g[1]

    # the last step of a stick that ends in a slip forwards, its guard falling over the steps before
    slip = ig.meta["modes"].index("slip+")
    k = next(j for j in range(3, rec[0].size - 1) if all(rec[2][j - 3:j + 1] == stick) and rec[2][j + 1] == slip
             and all(stick_guard(i + 1) < stick_guard(i) for i in range(j - 3, j)))
    t0, y0 = rec[0][k], rec[1][k].copy()
    ig.module.guards(stick, t0, y0, ig.p, g)
    y0[ig.meta["state"].index("z")] += (g[1] + 1e-13 * max(abs(g[1]), abs(g[2]))) / ig.p_raw[
        ig.meta["params"].index("kd")]
    ig.module.guards(stick, t0, y0, ig.p, g)
    scale = max(abs(g[1]), abs(g[2]))
    assert -1e-10 * scale < g[1] < 0.0
    # the same step grid, its section moved to t0 (h = t0 / (50 S'), S' the steps nearest the pair's own h)
    S = round(t0 / 50 / (ig.period / ig.steps_per_period))
    at = HybridIntegrator(ig.model, steps_per_period=S, period=t0 / 50)
    goff = np.zeros_like(g)
    goff[1] = g[1]
    rec_on, log_on = _kernel_run(at, y0.copy(), stick, 50, goff)
    rec_off, log_off = _kernel_run(at, y0.copy(), stick, 50, np.zeros_like(g))
    h = at.period / S
    assert at.meta["guards"][stick][log_on[1][0]] == "c: stick->slip+" and log_on[0][0] - t0 < h
    worst = np.inf
    for j in range(rec_off[0].size):
        if rec_off[2][j] != stick:
            break
        at.module.guards(stick, rec_off[0][j], rec_off[1][j], at.p, g)
        worst = min(worst, g[1] / scale)
    assert log_off[0][0] - t0 > 2 * h and worst < -1e-3


def test_a_call_that_goes_on_is_handed_the_offsets_of_the_last():
    """``advance`` hands the kernel the offsets the last call ended with where the call goes on from the time, state
    and mode where that one ended (the bilinear pair at 290 rad/s ends every period with one set: measured), and
    zeros to any other call: a call from another state, or one that does not start at the last one's end. The run
    split into one call a period reads the same guards as one call: the same events in the same order, at the same
    times to 1e-12 of the period, and the same end state to 1e-12 of its scale."""
    from blademodel.numeric.contract import C_LOGGED, N_COUNTERS
    ig = _pair_at_290()
    handed = []   # the offsets each kernel call was handed, and those it ended with

    def seen(args, out, before):
        goff, carry = args[-2:]
        handed.extend([before if carry else np.zeros_like(goff), goff.copy()])

    y0 = ig.initial_state()
    mode0 = ig.mode_of(y0)
    whole, log_whole = y0.copy(), ig.log_buffer(4000)
    counters = np.zeros(N_COUNTERS, dtype=np.int64)
    ig.advance(whole, mode0, 0, 20, log=log_whole, counters=counters, n_transient=0)
    n_whole = int(counters[C_LOGGED])
    ig.module = _KernelSpy(ig.module, seen)
    split, mode, log_split = y0.copy(), mode0, ig.log_buffer(4000)
    counters = np.zeros(N_COUNTERS, dtype=np.int64)
    for k in range(20):
        _, mode, _ = ig.advance(split, mode, k, k + 1, log=log_split, counters=counters, n_transient=0)
    ends, starts = handed[1::2], handed[0::2]
    assert all(e.any() for e in ends)   # offsets set at every period's end
    for k in range(1, 20):
        np.testing.assert_array_equal(starts[k], ends[k - 1])
    assert int(counters[C_LOGGED]) == n_whole
    for a, b in zip(log_whole[1:], log_split[1:]):
        np.testing.assert_array_equal(a[:n_whole], b[:n_whole])
    np.testing.assert_allclose(log_split[0][:n_whole], log_whole[0][:n_whole], rtol=0, atol=1e-12 * ig.period)
    np.testing.assert_allclose(split, whole, rtol=0, atol=1e-12 * np.max(np.abs(whole)))
    # not handed on: a call from another state, then one from split's end after that call ended elsewhere
    other = split.copy()
    other[0] *= 1.0 + 1e-9
    ig.advance(other, mode, 20, 21)
    assert not handed[-2].any()
    ig.advance(split.copy(), mode, 20, 21)
    assert not handed[-2].any()


def test_the_lyapunov_reference_keeps_its_offsets_between_periods():
    """The Lyapunov estimate alternates one period of its reference with one of its companion (pulled back each
    period). On one integrator the companion's calls cleared the reference's offsets every period; the reference now
    runs on a worker of its own, and each of its calls after one that ended with offsets set (the bilinear pair at
    290 rad/s ends every period so: measured) is handed them."""
    from blademodel.analysis.lyapunov import largest_lyapunov
    ig = _pair_at_290()
    calls = []   # (handed the offsets, ended with offsets set) of each kernel call, in order

    y = ig.initial_state()
    mode = ig.mode_of(y)
    _, mode, _ = ig.advance(y, mode, 0, 20)
    ig.module = _KernelSpy(ig.module, lambda args, out, before: calls.append((bool(args[-1]), bool(out[3]))))
    largest_lyapunov(ig, y, mode, start_period=20, periods=10, scale=np.ones(ig.n_state))
    reference = calls[0::2]   # the reference's period, then the companion's
    assert len(calls) == 20 and all(ended for _, ended in reference)
    assert all(handed for handed, _ in reference[1:])
