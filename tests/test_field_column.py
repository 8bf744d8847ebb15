"""The field's column of a continuation point's Jacobian taken from the branch's own points (``_Context.column_rule``)."""

import numpy as np
import pytest

from blademodel.orbits import continuation
from blademodel.orbits import arclength as al
from blademodel.orbits import corrector
from blademodel.zheng2022 import BladePair


def _curve(u):
    return np.array([np.cos(u), 0.5 * np.sin(2 * u), u ** 2, np.exp(0.3 * u)])


def _curve_tangent(u):
    d = np.array([-np.sin(u), np.cos(2 * u), 2 * u, 0.3 * np.exp(0.3 * u)])
    return d / np.linalg.norm(d)


@pytest.mark.parametrize("points, order", [(3, 2.0), (4, 3.0)])
def test_the_end_tangent_converges_at_the_polynomial_s_order(points, order):
    """The tangent at the last of three (four) points of a space curve, by the quadratic (cubic) through them in
    their chord length, converges at second (third) order in the spacing: the error estimate of the rule, the cubic
    against the quadratic, rests on that."""
    offsets = np.array([-3.0, -1.7, -1.0, 0.0])[-points:]
    hs = [0.02, 0.01, 0.005]
    errors = [np.linalg.norm(corrector._end_tangent([_curve(0.7 + h * o) for o in offsets]) - _curve_tangent(0.7))
              for h in hs]
    measured = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(measured - order) < 0.25), measured
    assert corrector._end_tangent([_curve(0.1), _curve(0.1), _curve(0.3)]) is None   # coinciding points


class _Run:
    """What the rule reads of the last residual's run: its event signature."""

    def signature(self):
        return ("same",)


def test_the_rule_s_column_converges_at_third_order_on_a_known_branch():
    """On a branch whose tangent is known (the space curve above, its residual's state columns a fixed matrix and
    its field column the one that makes the exact tangent a null vector), the rule's column converges at third order
    in the spacing: it is taken from the cubic through the last four points, whose tangent is third order, while
    the quadratic's (second order) only estimates the error. The quadratic's column would converge at second
    order."""
    rng = np.random.default_rng(3)
    A_y = rng.standard_normal((3, 3))
    ctx = al._Context(None, np.ones(3), 1.0, 1e-10, 1e-6, 8)
    ctx._run = _Run()
    u0, offsets = 0.7, np.array([-3.0, -1.7, -1.0, 0.0])
    t = _curve_tangent(u0)
    exact = -(A_y @ t[:-1]) / t[-1]
    errors = []
    for h in (0.02, 0.01, 0.005):
        X = [_curve(u0 + h * o) for o in offsets]
        pts = [{"state": x[:-1], "param": x[-1], "signature": ("same",), "mode": 0, "regular": True} for x in X[:-1]]
        column = ctx.column_rule(pts)(X[-1], 0, A_y)
        errors.append(np.linalg.norm(column - exact) / np.linalg.norm(exact))
    measured = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(measured - 3.0) < 0.3), measured
    ctx._run = None   # another signature at the new point: no column
    assert ctx.column_rule(pts)(X[-1], 0, A_y) is None


def test_the_column_from_the_points_equals_central_differences_and_leaves_the_branch_as_it_was():
    """Along the bilinear pair's branch the column the rule gives (where it gives one) equals central differences of
    the period map in the field, with a step small enough not to cross a grazing, to ``COLUMN_ACCURACY``; and the
    branch continued with the rule has the same bifurcations (to their location tolerance) and every point an orbit
    to ``tol``, as the branch whose columns are all difference quotients: the column only steers the corrections."""
    checked = []
    jacobian = al._Context.jacobian

    def checking(self, X, mode, column=None):
        A = jacobian(self, X, mode, column)
        if column is not None and column(X, mode, A[:, :-1]) is not None:
            lam, y, d = X[-1] * self.span, X[:-1] * self.scale, 1e-8
            central = (self.fam.map_at(lam + d * self.span).plain(y, mode)
                       - self.fam.map_at(lam - d * self.span).plain(y, mode)) / self.scale / (2 * d)
            checked.append(np.linalg.norm(A[:, -1] - central) / np.linalg.norm(central))
        return A

    cfg = BladePair(friction="bilinear")
    mp = pytest.MonkeyPatch()
    mp.setattr(al._Context, "jacobian", checking)
    try:
        with_rule = continuation(cfg, "omega", 408.0, 420.0, ds=0.0025, ds_max=0.005, workers=1)
    finally:
        mp.undo()
    assert len(checked) > 0.8 * with_rule.params.size
    assert max(checked) < corrector.COLUMN_ACCURACY
    mp.setattr(al._Context, "column_rule", lambda self, pts: None)
    try:
        without = continuation(cfg, "omega", 408.0, 420.0, ds=0.0025, ds_max=0.005, workers=1)
    finally:
        mp.undo()
    # (less the two integrations of each central difference above)
    assert with_rule.integrations - 2 * len(checked) < 0.85 * without.integrations
    for branch in (with_rule, without):
        assert np.max(branch.residuals) <= 1e-10
    bifurcations = [[p for p in b.special if p.kind != "grazing"] for b in (with_rule, without)]
    assert [p.kind for p in bifurcations[0]] == [p.kind for p in bifurcations[1]] and bifurcations[0]
    for p, q in zip(*bifurcations):
        assert abs(p.param - q.param) < 1e-6 * 12.0
