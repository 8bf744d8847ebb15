"""The per-contact kernel's forcing phase table: the same forcing as sin and cos, read at the step grid."""

import math

import mpmath
import numpy as np
import pytest

from blademodel.config import BladedDisk
from blademodel.numeric import ContactIntegrator, contract
from blademodel.numeric.contact_kernel import phase_table

S = 1000


def _open_ring(**kw):
    """Three blades, engine order 1, gaps too wide to close: at rest the generalized forces are the forcing."""
    return ContactIntegrator(BladedDisk(blades=3, engine_order=1, gap=1.0).build(), steps_per_period=S, **kw)


def _three_groups():
    """Two masses, an open contact, and loads in three frequency groups: a constant, omega and 3 omega."""
    from blademodel.config import config_from_data
    cfg = config_from_data({
        "model": "components", "name": "groups", "parameters": {"omega": 290.0},
        "masses": [{"name": 1, "m": 0.085}, {"name": 2, "m": 0.085}],
        "springs": [{"a": "x1", "k": 1e5}, {"a": "y1", "k": 3e6}, {"a": "x2", "k": 1e5}, {"a": "y2", "k": 3e6}],
        "dampers": [{"a": "x1", "c": 3.5}, {"a": "x2", "c": 3.5}],
        "forces": [{"mass": 1, "amplitude": 60, "omega": "omega", "phase": 1.047, "angle": 0.524},
                   {"type": "constant", "mass": 1, "value": -0.834, "angle": 1.5707963267948966},
                   {"type": "multiharmonic", "mass": 2, "omega": "omega", "angle": 0.524,
                    "harmonics": [{"order": 1, "amplitude": 60}, {"order": 3, "amplitude": 6, "phase": 0.5}]}],
        "contacts": [{"name": "c", "bodies": [1, 2], "gap": 1.0, "alpha": 1.047, "k": 4e5,
                      "friction": {"law": "coulomb", "mu": 0.5}}]})
    return ContactIntegrator(cfg.build(), steps_per_period=S)


def _forcing(integ, t):
    """The kernel's generalized forces at ``t`` at rest, contacts open: the forcing."""
    n, o = integ.I[contract.H_N], integ.I[contract.F_F]
    integ.contact_forces(t, np.zeros(integ.n_state), np.zeros(integ.nc, dtype=np.int64))
    return integ.WF[o:o + n].copy()


def _direct(integ, t, phase):
    """``sum fs sin(om t) + fc cos(om t)`` per coordinate, with ``phase(om, t) = (sin, cos)``."""
    fi, fg, fs, fc, om = integ.tables.forcing
    F = np.zeros(integ.I[contract.H_N])
    for i, g, a, b in zip(fi, fg, fs, fc):
        s, c = phase(om[g], t)
        F[i] += a * s + b * c
    return F


def _grid_times(period, per):
    """The step ends and RK4 midpoints of period ``per``, computed as the kernel's loop computes them."""
    h = period / S
    t = period * per if per == 0 else period * (per - 1) + S * h
    out = []
    for js in range(S):
        te = period * per + (js + 1) * h
        out += [t + 0.5 * (te - t), te]
        t = te
    return out


@pytest.mark.parametrize("make", [_open_ring, _three_groups], ids=["ring", "three groups"])
def test_grid_times_read_the_table_and_other_times_call_sin_and_cos(make):
    integ = make()
    hh, _, M = integ.R[integ.I[contract.R_TG]:integ.I[contract.R_TG] + 3]
    assert M == 2 * S
    period = integ.period

    if make is _three_groups:
        assert sorted(integ.tables.forcing[4]) == [0.0, 290.0, 870.0]

    def table(om, t):
        kk = round(t / hh) % int(M)
        return math.sin(om * (kk * hh)), math.cos(om * (kk * hh))

    def libm(om, t):
        return math.sin(om * t), math.cos(om * t)

    def exact(om, t):   # the phase of the float t, to 40 digits
        with mpmath.workdps(40):
            x = mpmath.mpf(om) * mpmath.mpf(t)
            return float(mpmath.sin(x)), float(mpmath.cos(x))

    F0 = np.max(np.abs(_direct(integ, 0.0, libm)))
    for per in (0, 3, 1000, 100_000):
        times = _grid_times(period, per)
        differ = 0
        for t in times[::97] + times[-2:]:
            F = _forcing(integ, t)
            assert np.array_equal(F, _direct(integ, t, table)), (per, t)      # the table, to the bit
            # rounding only: a unit in the last place of t, and the period's own rounding once a period
            # (measured: 3.4 times libm's own error, 2.1e-10 F0 at per = 100000)
            err = np.max(np.abs(F - _direct(integ, t, exact)))
            assert err <= 1e-15 * F0 * (8 + 2 * 2 * math.pi * per), (per, t, err)
            differ += not np.array_equal(F, _direct(integ, t, libm))
        if per:
            assert differ > 0     # the table was read: libm's values differ in the last places
        for t in (times[10] + 0.3 * period / S, times[-1] - 1e-9 * period):
            assert np.array_equal(_forcing(integ, t), _direct(integ, t, libm)), (per, t)   # off the grid


def test_no_table_for_a_period_the_forcing_does_not_repeat_in():
    integ = _open_ring()
    other = ContactIntegrator(BladedDisk(blades=3, engine_order=1, gap=1.0).build(), steps_per_period=S,
                              period=1.1 * integ.period, check_stability=False)
    assert other.R[other.I[contract.R_TG] + 2] == 0.0
    om = integ.tables.forcing[4]
    assert phase_table(om, integ.period, S)[0][2] == 2 * S
    assert phase_table(om, 2 * integ.period, S)[0][2] == 2 * S        # two forcing periods repeat too
    assert phase_table(om, integ.period, 10 ** 6)[0][2] == 0          # too long a table: sin and cos
    t = 7 * other.period + 0.25 * other.period
    assert np.array_equal(_forcing(other, t),
                          _direct(other, t, lambda om, t: (math.sin(om * t), math.cos(om * t))))


def test_a_run_with_the_table_is_a_run_with_sin_and_cos_to_rounding():
    """A mistuned ring whose contacts open and close, 30 periods with and without the table."""
    model = BladedDisk(blades=6, friction="bilinear", engine_order=3, mistuning_std=0.01, mistuning_seed=0).build()
    runs = []
    for table in (True, False):
        integ = ContactIntegrator(model, steps_per_period=S)
        if not table:
            integ.R[integ.I[contract.R_TG] + 2] = 0.0
        y = integ.initial_state()
        cm = integ.mode_of(y)
        counters = np.zeros(contract.N_COUNTERS, dtype=np.int64)
        status, cm, _ = integ.advance(y, cm, 0, 30, counters=counters)
        assert status == 0
        runs.append((y, cm, counters[contract.C_EVENTS]))
    (y1, cm1, ev1), (y2, cm2, ev2) = runs
    assert ev1 == ev2 > 100 and np.array_equal(cm1, cm2)
    for rows in slice(0, 12), slice(12, 24):     # displacements, velocities
        assert np.max(np.abs(y1[rows] - y2[rows])) <= 1e-10 * np.max(np.abs(y2[rows]))
    assert not np.array_equal(y1, y2)     # the two runs did read different values
