"""The generated, fused RK4 step is the template's step, operation for operation."""

import types

import numpy as np
import pytest

from blademodel.zheng2022 import BladePair
from blademodel.numeric import HybridIntegrator, compile_model, loop


def _template_step(module):
    """``loop.rk4_step`` run as plain Python against the module's compiled ``rhs``."""
    return types.FunctionType(loop.rk4_step.__code__, {**vars(module), "rhs": module.rhs})


@pytest.mark.parametrize("friction", ["coulomb", "bilinear"])
@pytest.mark.parametrize("energy", [False, True])
def test_fused_rk4_step_matches_template(friction, energy):
    cfg = BladePair(friction=friction)
    model = cfg.build()
    cs = compile_model(model, energy=energy)
    p = cs.parameter_array(model)
    n = cs.meta["n_state"]
    generic = _template_step(cs.module)
    rng = np.random.default_rng(1)
    scale = np.r_[np.full(4, cfg.gap), np.full(4, cfg.gap * cfg.omega), np.full(n - 8, cfg.gap)]
    for mode in range(len(cs.meta["modes"])):
        for _ in range(5):
            y = rng.normal(size=n) * scale
            t, h = rng.uniform(0, 1), rng.uniform(1e-7, 3e-5)
            work = [np.empty(n) for _ in range(5)]
            a, b = np.empty(n), np.empty(n)
            cs.module.rk4_step(mode, t, y, h, p, *work, a)
            generic(mode, t, y, h, p, *[np.empty(n) for _ in range(5)], b)
            np.testing.assert_array_equal(a, b)


def test_fused_step_is_generated():
    """The kernel uses the generated step, not the template's (which calls ``rhs``)."""
    integ = HybridIntegrator(BladePair(friction="bilinear").build())
    src = integ.compiled.path.read_text()
    fused = src[src.index("# ---- the template's rk4_step, fused"):]
    body = fused[fused.index("def rk4_step("):fused.index("rhs = njit(")]
    assert "rhs(" not in body and "k1[" not in body
