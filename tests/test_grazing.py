"""Grazing contacts: a contact entered and left within one step, which neither end of the step shows."""

import math

import numpy as np
import pytest

from blademodel.config import config_from_data
from blademodel.numeric import simulate

M, K, F0, OMEGA, KC = 0.085, 1e5, 60.0, 290.0, 1e6
S = 40                                        # coarse: h = T / 40
AMP = F0 / (K - M * OMEGA ** 2)               # the forced response's amplitude (no damping)
#: Phase putting the response's peak in the middle of step 10 (not on a step end).
PHASE = math.pi / 2 - 10.5 * 2 * math.pi / S


def _oscillator(excess: float):
    """A mass on a spring, driven so its peak passes a gap by ``excess`` of the amplitude (a brief contact).

    Undamped and started on its forced response ``x = AMP sin(omega t + PHASE)``, so the peak of
    the first period is known: at ``t = 10.5 h`` the mass enters the contact (normal along ``x``,
    ``alpha = pi/2``) for ``2 sqrt(2 excess) / omega`` (0.64 h at ``excess = 1e-3``).
    """
    data = {"model": "components", "name": "grazing_oscillator",
            "parameters": {"m": M, "k": K, "F0": F0, "omega": OMEGA, "phi": PHASE, "kc": KC,
                           "Delta": AMP * (1 - excess)},
            "masses": [{"name": "m", "m": "m", "dofs": ["x"]}],
            "springs": [{"a": "x_m", "k": "k"}],
            "forces": [{"mass": "m", "amplitude": "F0", "omega": "omega", "phase": "phi", "angle": 0.0}],
            "contacts": [{"name": "c", "bodies": ["m", "ground"], "alpha": math.pi / 2, "gap": "Delta",
                          "k": "kc", "friction": "none"}]}
    model = config_from_data(data).build()
    y0 = {"x_m": AMP * math.sin(PHASE), "vx_m": AMP * OMEGA * math.cos(PHASE)}
    return model, y0


def test_a_contact_shorter_than_a_step_is_detected_and_located():
    """At S = 40 the contact (0.64 of a step) falls between two step ends. With grazing detection the
    coarse run finds it and locates its entry, and the contact's *effect* on the trajectory (the run
    minus the same run with the gap out of reach, so each step size's own error cancels) matches that
    of a fine run which resolves the contact with its ordinary guard check; without, it is missed."""
    model, y0 = _oscillator(1e-3)
    free, _ = _oscillator(-1.0)                # the gap twice the amplitude: never touched

    def run(m, steps, grazing):
        return simulate(m, periods=1, steps_per_period=steps, y0=y0, kernel="contact", detect_grazing=grazing)
    fine, fine_free = run(model, 20 * S, False), run(free, 20 * S, False)
    on, off, coarse_free = run(model, S, True), run(model, S, False), run(free, S, False)
    assert fine.counters["events"] == 2 and fine.events["to"] == ["closed", "open"]
    assert fine.counters["grazing_events"] == 0
    assert on.counters["grazing_events"] == 1 and on.events["to"] == ["closed", "open"]
    assert off.counters["events"] == 0 and np.array_equal(off.final_state, coarse_free.final_state)
    h = on.period / S
    assert abs(on.events["t"][0] - fine.events["t"][0]) < 0.05 * h   # the entry, to the coarse step's error
    scale = np.max(np.abs(fine.y), axis=0)     # each state's amplitude
    effect_fine = (fine.final_state - fine_free.final_state) / scale
    effect_on = (on.final_state - coarse_free.final_state) / scale
    assert np.max(np.abs(effect_fine)) > 1e-3
    assert np.max(np.abs(effect_on - effect_fine)) < 0.1 * np.max(np.abs(effect_fine))


def test_no_contact_no_grazing_event():
    """A peak that stays short of the gap: the check runs (rates turn at the peak) and finds nothing."""
    model, y0 = _oscillator(-1e-3)
    r = simulate(model, periods=2, steps_per_period=S, y0=y0, kernel="contact")
    assert r.counters["events"] == 0 and r.counters["grazing_events"] == 0
    free = simulate(model, periods=2, steps_per_period=S, y0=y0, kernel="contact", detect_grazing=False)
    assert np.array_equal(r.final_state, free.final_state)


def test_the_pairs_brief_contacts_are_the_ones_a_finer_step_resolves():
    """The paper's pair, bilinear, gamma = 8, F0 = 80: at S = 1000 some contacts last less than a step.

    The product kernel (no grazing detection) misses them; the per-contact kernel finds them at the same
    step, and then sees the same events as the product kernel at S = 4000, where every contact spans
    steps (and the per-contact kernel there finds no grazing left)."""
    from blademodel.zheng2022 import BladePair
    m = BladePair(friction="bilinear", gamma=8.0, F0=80.0).build()
    run = dict(transient=60, periods=20)
    coarse_product = simulate(m, kernel="product", **run)
    coarse_contact = simulate(m, kernel="contact", **run)
    fine_product = simulate(m, kernel="product", steps_per_period=4000, **run)
    fine_contact = simulate(m, kernel="contact", steps_per_period=4000, **run)
    assert coarse_contact.counters["grazing_events"] > 10 and fine_contact.counters["grazing_events"] == 0
    assert coarse_product.counters["events"] < fine_product.counters["events"]
    assert coarse_contact.counters["events"] == fine_product.counters["events"] == fine_contact.counters["events"]
    assert coarse_contact.events["to"] == fine_product.events["to"]


def test_a_slip_phase_shorter_than_a_step_is_detected():
    """Grazing of the law guards (rates from the law's SymPy derivatives): bilinear pair, gamma = 8, F0 = 80.

    With RK8 at S = 250 some stick phases are interrupted by a slip shorter than a step (the stick
    guard ``mu N - kd z`` dips below zero and back). With grazing detection the coarse run sees every
    event of a fine RK4 run (S = 8000, which resolves them with its ordinary check), in the same order,
    and ends on its state; without, it misses stick->slip transitions and drifts away.
    """
    from collections import Counter

    from blademodel.zheng2022 import BladePair
    m = BladePair(friction="bilinear", gamma=8.0, F0=80.0).build()
    run = dict(transient=0, periods=20, kernel="contact")
    fine = simulate(m, steps_per_period=8000, detect_grazing=False, **run)
    on = simulate(m, steps_per_period=250, method="rk8", **run)
    off = simulate(m, steps_per_period=250, method="rk8", detect_grazing=False, **run)
    assert on.counters["grazing_events"] > 0 and on.events["guard"] == fine.events["guard"]
    assert np.max(np.abs(np.array(on.events["t"]) - fine.events["t"])) < 1e-5 * on.period / 250
    missed = Counter(fine.events["guard"]) - Counter(off.events["guard"])
    assert any("stick->slip" in g for g in missed), missed
    scale = np.max(np.abs(fine.y), axis=0)
    err_on = np.max(np.abs(on.final_state - fine.final_state) / scale)
    err_off = np.max(np.abs(off.final_state - fine.final_state) / scale)
    assert err_on < 1e-8 and err_off > 100 * err_on
