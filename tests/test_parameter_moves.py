"""Moving a model's parameters without rebuilding it: the field path, ``with_parameter_values`` and the
step's stability check behind them."""

import math

import numpy as np
import pytest

from blademodel.config import apply_overrides
from blademodel.numeric import StepTooLargeError
from blademodel.numeric.kernels import make_integrator
from blademodel.numeric.methods import get_method
from blademodel.numeric.stability import certain_step, ray_limits, step_is_stable
from blademodel.orbits.field_path import AffineFieldPath
from blademodel.zheng2022 import BladePair


def _values(cfg, field, names):
    def build(v):
        model = apply_overrides(cfg, {field: v}).build()
        return np.array([model.parameters[k] for k in names]), 2 * math.pi / model.parameters["omega"]
    return build


@pytest.mark.parametrize("field,lo,hi", [("omega", 250.0, 350.0), ("gamma", 2.0, 9.0), ("F0", 10.0, 90.0),
                                         ("gap", 1e-5, 8e-5)])
def test_the_field_path_gives_the_built_models_parameters(field, lo, hi):
    """Every field of the pair enters its raw parameters affinely (``k = gamma kx``, ``omega`` ...): the path
    interpolates them to rounding at values it never built, its period equals ``2 pi / omega`` and its
    derivative equals the built models' central difference."""
    cfg = BladePair(friction="coulomb")
    names = make_integrator(cfg.build()).meta["params"]
    build = _values(cfg, field, names)
    path = AffineFieldPath.probe(build, lo, hi)
    assert path is not None and path.covers(lo) and path.covers(hi) and not path.covers(hi + (hi - lo))
    for v in np.linspace(lo, hi, 7)[1:-1] + 0.123 * (hi - lo) / 7:
        p, T = path.at(v)
        p_ref, T_ref = build(v)
        assert np.max(np.abs(p - p_ref) / np.maximum(np.abs(p_ref), 1e-300)) <= 4e-16 * 8
        assert abs(T - T_ref) <= 1e-15 * T_ref
        d = 1e-4 * (hi - lo)
        dp, dT = path.derivative(v)
        (pp, Tp), (pm, Tm) = build(v + d), build(v - d)
        assert np.allclose(dp, (pp - pm) / (2 * d), rtol=1e-6, atol=0)
        assert abs(dT - (Tp - Tm) / (2 * d)) <= 1e-6 * abs(dT) + 1e-300


def test_a_field_that_is_not_affine_has_no_path():
    """A parameter quadratic in the field, or a period neither affine nor reciprocal, is refused; a field that
    does not build at the range's ends too."""
    assert AffineFieldPath.probe(lambda x: (np.array([x, x * x]), None), 1.0, 2.0) is None
    assert AffineFieldPath.probe(lambda x: (np.array([x]), 1.0 / x ** 2), 1.0, 2.0) is None

    def refuses(x):
        if x > 1.5:
            raise ValueError("out of range")
        return np.array([x]), None
    assert AffineFieldPath.probe(refuses, 1.0, 2.0) is None
    path = AffineFieldPath.probe(lambda x: (np.array([2 * x + 1, 3.0]), 2 * math.pi / x), 1.0, 2.0)
    p, T = path.at(1.7)
    assert p[1] == 3.0 and abs(p[0] - 4.4) < 1e-15 and abs(T - 2 * math.pi / 1.7) < 1e-15


def test_parameter_values_make_the_integrator_with_parameters_makes():
    """``with_parameter_values`` and ``with_parameters`` give the same parameters, period and run, bit for bit;
    a wrong vector is refused naming the parameters, and an unstable step is refused as at construction."""
    ig = make_integrator(BladePair(friction="bilinear").build())
    model = BladePair(friction="bilinear", omega=310.0, gamma=5.0).build()
    a = ig.with_parameters(model)
    b = ig.with_parameter_values([model.parameters[k] for k in ig.meta["params"]], 2 * math.pi / 310.0)
    assert np.array_equal(a.p, b.p) and a.period == b.period
    ya, yb = a.initial_state(), b.initial_state()
    a.advance(ya, a.mode_of(ya), 0, 5)
    b.advance(yb, b.mode_of(yb), 0, 5)
    assert np.array_equal(ya, yb)
    with pytest.raises(ValueError, match="one per parameter"):
        ig.with_parameter_values(ig.p_raw[:3])
    stiff = ig.p_raw.copy()
    stiff[ig.meta["params"].index("kd")] *= 1e4
    with pytest.raises(StepTooLargeError, match="steps_per_period >="):
        ig.with_parameter_values(stiff)


def _assert_same_run(a, b, periods: int = 10):
    """Both integrators from their initial state: both succeed and end in the same state and modes, bit for bit."""
    ends = []
    for g in (a, b):
        y = g.initial_state()
        status, mode, _ = g.advance(y, g.mode_of(y), 0, periods)
        ends.append((status, y, mode))
    assert ends[0][0] == ends[1][0] == 0
    assert np.array_equal(ends[0][1], ends[1][1]) and np.array_equal(ends[0][2], ends[1][2])


@pytest.mark.parametrize("update", [{"omega": 287.0}, {"gamma": 6.0}, {"mu": 0.3, "gap": 1e-5},
                                    {"mistuning": [0.0, 0.05, -0.01, 0.02]}])
def test_a_ring_integrator_with_new_parameters_is_the_one_built_for_them(update):
    """The per-contact kernel's ``with_parameters``: the same tables, period, stability limit and run as an
    integrator built for the new model, bit for bit (its stability limits are cached by the modes'
    Jacobians, so a stiffer contact must not reuse the old limit); another structure is refused, and an
    unstable step is refused as at construction."""
    from blademodel.config import BladedDisk
    from blademodel.numeric.integrator import StructureMismatch
    cfg = BladedDisk(blades=4, engine_order=1, friction="coulomb", mistuning=[0, 0.03, -0.02, 0.01])
    ig = make_integrator(cfg.build())
    model = cfg.model_copy(update=update).build()
    a, b = ig.with_parameters(model), make_integrator(model)
    assert a.period == b.period and np.array_equal(a.R, b.R) and np.array_equal(a.I, b.I)
    assert a.max_stable_step() == b.max_stable_step()
    _assert_same_run(a, b)
    with pytest.raises(StructureMismatch, match="same structure"):
        ig.with_parameters(BladedDisk(blades=5, friction="coulomb").build())
    with pytest.raises(StepTooLargeError, match="steps_per_period >="):
        ig.with_parameters(cfg.model_copy(update={"gamma": 1e5}).build())


def test_a_ring_integrator_takes_parameter_values_as_with_parameters_does():
    """The per-contact kernel's ``with_parameter_values`` (no model built): the same tables, period and run as
    ``with_parameters``, bit for bit; a wrong vector is refused naming the parameters, a stiff contact's step
    as at construction; and a continuation of a ring in omega moves its parameters along the field's path."""
    from blademodel.config import BladedDisk
    from blademodel.orbits.family import _Family
    # the Coulomb ring of the test above: its kernel is compiled once for both
    cfg = BladedDisk(blades=4, engine_order=1, friction="coulomb", mistuning=[0, 0.03, -0.02, 0.01])
    ig = make_integrator(cfg.build())
    model = cfg.model_copy(update={"omega": 283.0, "mu": 0.25}).build()
    a = ig.with_parameters(model)
    b = ig.with_parameter_values([model.parameters[k] for k in ig.meta["params"]], 2 * math.pi / 283.0)
    assert a.period == b.period and np.array_equal(a.R, b.R) and np.array_equal(a.I, b.I)
    assert a.flow_digest() == b.flow_digest() != ig.flow_digest()   # mu moves the friction law's values
    _assert_same_run(a, b)
    with pytest.raises(ValueError, match="one per parameter"):
        ig.with_parameter_values([1.0, 2.0])
    stiff = cfg.model_copy(update={"gamma": 1e5}).build()
    with pytest.raises(StepTooLargeError, match="steps_per_period >="):
        ig.with_parameter_values([stiff.parameters[k] for k in ig.meta["params"]])
    # the frequency moves no mode's matrix: the digest (and so the kept stable step) stays
    w = cfg.model_copy(update={"omega": 300.0}).build()
    moved = ig.with_parameter_values([w.parameters[k] for k in ig.meta["params"]], 2 * math.pi / 300.0)
    assert moved.flow_digest() == ig.flow_digest() and not np.array_equal(moved.R, ig.R)
    fam = _Family(cfg, "omega", 1, {}, 280.0, bounds=(280.0, 290.0))
    fam.map_at(280.0)
    assert fam.path() is not None and fam.path().covers(285.0)


@pytest.mark.parametrize("method", ["rk4", "rk8"])
def test_a_certain_step_is_stable_up_to_the_first_root_on_each_ray(method):
    """``certain_step`` is the first positive root of ``|R(r lam)|^2 = 1`` over the eigenvalues: every step up to
    it is stable (sampled densely), a step just past it is not, and it equals the ray bisection's limit."""
    m = get_method(method)
    rng = np.random.default_rng(3)
    for _ in range(40):
        lam = -rng.uniform(0, 1, 4) * 10 ** rng.uniform(-3, 2, 4) + 1j * rng.uniform(-1, 1, 4) * 10 ** rng.uniform(0, 3, 4)
        h = certain_step(lam, m.amplification_coefficients())
        assert abs(h / np.min(ray_limits(lam, m.amplification)) - 1) < 1e-9
        for x in np.linspace(0, 1, 400)[1:]:
            assert step_is_stable(x * h * (1 - 1e-9), lam, m.amplification)
        assert not step_is_stable(h * (1 + 1e-6), lam, m.amplification)
    assert certain_step([0j], m.amplification_coefficients()) == math.inf
