"""A Coulomb contact that the friction problem releases from stick into slip never slips against its direction.

When a contact's event changes the joint stick problem of a ring, the friction problem may
release a stuck neighbour into ``slip+`` or ``slip-``. It enters that mode at a slip
velocity of zero to a rounding error; one left a rounding error on the wrong side of its
guard (which fires as the velocity falls through zero) never changed sign, and the contact
slipped on the wrong way, friction pushing along its motion: on this ring at ``F0 = 70.65``
N, ``-0.0135`` m/s in ``slip+`` within three periods from rest (4 % of the largest velocity),
and the period map jumped where such a release happened (continuation in ``F0`` stopped at
70.65 N). ``settle_event`` now puts such guards on their boundary (``mark_near``).
"""

import numpy as np

from blademodel.config import BladedDisk
from blademodel.numeric.kernels import make_integrator
from blademodel.orbits import continuation
from blademodel.orbits.period_map import PeriodMap

RING = dict(blades=6, engine_order=1, friction="coulomb", omega=286.0)


def test_no_slipping_contact_moves_against_its_slip_direction():
    """Ten periods from rest, every recorded step: each contact in ``slip+``/``slip-`` has its slip guard (the
    velocity in the slip's direction) on the allowed side, to 1e-9 of the largest velocity."""
    ig = make_integrator(BladedDisk(**RING, F0=70.65).build(), steps_per_period=600)
    modes = ig.meta["contact_modes"][0]
    y = np.zeros(ig.n_state)
    mode = ig.mode_of(y)
    P = PeriodMap(ig)
    mod, G = ig.module, np.zeros_like(ig.GS[0])
    state, slipping, worst = y[:ig.n_physical].copy(), 0, 0.0
    for _ in range(10):
        state, mode = P(state, mode)
        run = P._last[1]
        ig._clear_near_marks()   # the guards themselves, not as the run read them
        speed = np.max(np.abs(run.states[:, ig.tables.n:2 * ig.tables.n]))
        for t, s, cm in zip(run.t, run.states, run.modes.astype(np.int64)):
            mod.factor_stick(cm, ig.I, ig.R, ig.WI, ig.WF)
            mod.guards_at(float(t), s.copy(), cm, ig.I, ig.R, ig.WI, ig.WF, G)
            for j, m in enumerate(cm):
                if modes[m] in ("slip+", "slip-"):   # guard 1: the velocity in the slip's direction
                    slipping += 1
                    worst = max(worst, -G[j, 1] / speed)
    assert slipping > 1000
    assert worst <= 1e-9


def test_the_ring_is_continued_in_the_force_through_such_releases():
    """The same ring continued in ``F0`` from 60 to 80 N reaches the end (it stopped at 70.6458 N before)."""
    b = continuation(BladedDisk(**RING), "F0", 60.0, 80.0, steps_per_period=600, transient=50, workers=1)
    assert b.message == "reached F0 = 80" and len(b.points("grazing")) >= 4
