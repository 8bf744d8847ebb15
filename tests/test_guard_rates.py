"""Guard rates of the per-contact kernel against central differences along the flow.

The kernel predicts each event's root from the guards' values *and* rates (a cubic
Hermite interpolant, then a Newton step), so a wrong rate costs sub-steps, not
accuracy: these tests check the rates themselves. The generated module is run as
plain Python (its ``njit`` made the identity) so that functions without a Python
wrapper can be called; the differences evaluate the guards at ``t +- e`` and
``y +- e dy/dt`` in the same modes, which is ``dG/dt + O(e^2)``.
"""

import numpy as np
import pytest

from blademodel.config import BladedDisk
from blademodel.numeric.contact_codegen import generate_contact_kernel
from blademodel.numeric.contact_kernel import law_kinds
from blademodel.numeric.kernels import make_integrator


def python_kernel(model):
    """The generated per-contact module for ``model``'s laws, executed without Numba."""
    source, _ = generate_contact_kernel(law_kinds(model)[0])
    source = source.replace("from numba import njit", "def njit(*a, **k):\n    return lambda f: f")
    namespace = {}
    exec(compile(source, "<per-contact kernel>", "exec"), namespace)
    return namespace


def sampled_states(model, n_samples=40):
    """States and contact modes recorded along a run with closed contacts in each law mode."""
    ig = make_integrator(model, kernel="contact", steps_per_period=400)
    y = np.zeros(ig.n_state)
    mode = ig.mode_of(y)
    ig.advance(y, mode, 0, 8)   # past the transient's start
    n = 4 * 400
    rec = ig.record_buffer(n)
    status, _, _ = ig.advance(y, ig.mode_of(y.copy()), 8, 12, n_transient=8, record=rec)
    assert status == 0
    pick = np.linspace(0, n - 1, n_samples).astype(int)
    return ig, rec[0][pick], rec[1][pick], rec[2][pick].astype(np.int64)


#: The (mode, guard) pairs each law's samples must check: every closed mode's friction guards. The Iwan law's are
#: ``Min`` over its elements of ``Piecewise`` branches (one closed mode), whose rate is the critical element's.
CHECKED = {"coulomb": {(1, 1), (1, 2), (2, 1), (3, 1)}, "bilinear": {(1, 1), (1, 2), (2, 1), (3, 1)},
           "iwan": {(1, 1), (1, 2), (1, 3)}}


@pytest.mark.parametrize("law", ["coulomb", "bilinear", "iwan"])
def test_guard_rates_are_the_derivatives_along_the_flow(law):
    model = BladedDisk(blades=6, engine_order=2, friction=law, mistuning_std=0.05, mistuning_seed=1,
                       F0=120.0).build()
    ig, ts, ys, cms = sampled_states(model)
    k = python_kernel(model)
    I, R, WI, WF = ig.I, ig.R, ig.WI.copy(), ig.WF.copy()
    nc, gmax = ig.nc, ig.GS.shape[2]
    h = ig.period / 400
    seen = set()
    for t, y, cm in zip(ts, ys, cms):
        k["factor_stick"](cm, I, R, WI, WF)
        dy = np.empty(ig.n_state)
        G = np.empty((nc, gmax))
        D = np.empty((nc, gmax))
        k["rhs_guards"](t, y, cm, I, R, WI, WF, dy, G)
        k["guard_rates"](y, dy, cm, I, R, WI, WF, D, True)
        e = 1e-4 * h
        Gp, Gm = np.zeros((nc, gmax)), np.zeros((nc, gmax))
        k["eval_guards"](t + e, y + e * dy, cm, I, R, WI, WF, Gp)
        k["eval_guards"](t - e, y - e * dy, cm, I, R, WI, WF, Gm)
        fd = (Gp - Gm) / (2 * e)
        guards = ig.kmeta["kinds"][0]["guards"]   # one law kind: every contact's guards per mode
        known = [(j, gi) for j in range(nc) for gi in range(len(guards[cm[j]])) if np.isfinite(D[j, gi])]
        scale = max(abs(fd[j, gi]) for j, gi in known)
        for j, gi in known:
            assert abs(D[j, gi] - fd[j, gi]) <= 1e-6 * scale, (law, j, cm[j], gi, D[j, gi], fd[j, gi])
            seen.add((int(cm[j]), gi))
    # the rates were checked in every closed law mode, stick guards included
    assert CHECKED[law] <= seen, seen
