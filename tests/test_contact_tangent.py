"""The per-contact kernel's replayed tangent against difference quotients of its period map.

Every column of the monodromy matrix is compared, off the stick manifold too: the
kernel projects the velocities onto the stick constraints where a rigid contact starts
to stick, and the replay must do the same. The difference quotients are central ones of
the kernel's own map with a relative step of ``1e-5`` (their error, measured against
steps of ``1e-4`` and ``1e-6``, is about ``5e-8`` of the matrix).
"""

import numpy as np
import pytest

from blademodel.config import BladedDisk
from blademodel.numeric.contact_tangent import (amplification_powers, sparse_amplification_powers,
                                                sparse_stability_matrix, sparse_stability_matrix_from_powers,
                                                stability_matrix, stability_matrix_from_powers)
from blademodel.numeric.methods import get_method
from blademodel.numeric.tangent import SensitivityError
from blademodel.numeric.kernels import make_integrator
from blademodel.orbits import find_periodic_orbit
from blademodel.orbits.period_map import PeriodMap, hold_discrete
from blademodel.components._sympy import sp
from blademodel.components.friction.base import Candidate, FrictionLaw
from blademodel.components.parameter import as_param

SPP = 600


def ring_orbit(friction, blades=4, engine_order=1, **values):
    model = BladedDisk(blades=blades, engine_order=engine_order, friction=friction, omega=286.0, **values).build()
    ig = make_integrator(model, steps_per_period=SPP)
    orbit = find_periodic_orbit(model, integrator=ig, transient=50, jacobian="forward", workers=1)
    return ig, orbit


def scaled_error(J, ref, scale):
    """The largest difference of two Jacobians in the orbit's scaled states, relative to the largest entry."""
    S = scale[None, :] / scale[:, None]
    return np.max(np.abs((J - ref) * S)) / np.max(np.abs(ref * S))


@pytest.mark.parametrize("name", ["rk4", "rk8"])
def test_the_stability_matrix_is_the_step_jacobian_of_a_linear_flow(name):
    """One step of the method on ``y' = A y``, stepped column by column from the identity, is ``R(hA)``."""
    method = get_method(name)
    rng = np.random.default_rng(3)
    A = rng.normal(size=(6, 6))
    h = 0.3
    Y = np.eye(6)
    K = []
    for i in range(method.stages):
        K.append(A @ (Y + h * sum(method.A[i, j] * K[j] for j in range(i))))
    step = Y + h * sum(b * k for b, k in zip(method.b, K))
    np.testing.assert_allclose(stability_matrix(h * A, method.amplification_coefficients()), step,
                               rtol=0, atol=1e-13)


@pytest.mark.parametrize("name", ["rk4", "rk8"])
def test_the_step_matrix_from_kept_powers_is_horner_s_at_any_step(name):
    """``sum_k c_k h^k A^k`` from ``A``'s powers, kept once, is Horner's ``R(hA)`` at every step ``h`` (a whole step
    and sub-steps down to ``1e-9`` of it), to rounding; one power short, it lacks the highest term."""
    coefficients = get_method(name).amplification_coefficients()
    rng = np.random.default_rng(5)
    A = rng.normal(size=(7, 7))
    P = amplification_powers(A, coefficients.size - 1)
    for h in (0.3, 0.0217, 1e-9):
        np.testing.assert_allclose(stability_matrix_from_powers(P, h, coefficients),
                                   stability_matrix(h * A, coefficients), rtol=0, atol=1e-14)
    d = coefficients.size - 1
    short = amplification_powers(A, d - 1)
    full = stability_matrix(A, coefficients)
    highest = coefficients[-1] * np.linalg.matrix_power(A, d)
    rounding = 1e-13 * np.max(np.abs(full))
    assert np.max(np.abs(highest)) > 1e3 * rounding
    np.testing.assert_allclose(full - stability_matrix_from_powers(short, 1.0, coefficients), highest, rtol=0,
                               atol=rounding)


def test_the_ring_s_monodromy_is_the_same_with_horner_s_step_matrices(monkeypatch):
    """The replay with each whole step's ``R(hA)`` from the mode's kept powers is the replay with Horner's rule
    (as sparse, larger rings take it), to rounding: a mistuned ring whose events fall in several clusters."""
    from blademodel.numeric import contact_tangent
    ig, orbit = ring_orbit("coulomb", blades=6, engine_order=2, mistuning_std=0.05, mistuning_seed=1, F0=120.0)
    contact_tangent._CACHES.clear()
    by_powers = PeriodMap(ig, 1, jacobian="tangent", workers=1).derivatives(orbit.state, orbit.mode.copy())
    monkeypatch.setattr(contact_tangent, "POWERS_BELOW", 0)
    contact_tangent._CACHES.clear()
    horner = PeriodMap(ig, 1, jacobian="tangent", workers=1).derivatives(orbit.state, orbit.mode.copy())
    contact_tangent._CACHES.clear()
    assert by_powers.events == horner.events >= 80
    assert scaled_error(by_powers.monodromy, horner.monodromy, orbit.scale) < 1e-12


@pytest.mark.parametrize("name", ["rk4", "rk8"])
def test_a_sparse_step_matrix_is_horner_s_and_keeps_the_band_of_its_polynomial(name):
    """Of a banded ``hA`` (each state coupled to its neighbours), ``R(hA)`` in sparse products equals the dense
    Horner's rule to rounding and is nonzero only within ``d`` of the diagonal (``d`` the polynomial's degree), the
    band a step couples; denser than :data:`SPARSE_STEPS_DENSITY` it comes back dense."""
    from scipy.sparse import diags
    from blademodel.numeric.contact_tangent import SPARSE_STEPS_DENSITY
    coefficients = get_method(name).amplification_coefficients()
    d = coefficients.size - 1
    n = 12 * d
    rng = np.random.default_rng(7)
    hA = diags([rng.normal(size=n - 1), rng.normal(size=n), rng.normal(size=n - 1)], [-1, 0, 1], format="csr") * 0.3
    R = sparse_stability_matrix(hA, coefficients)
    assert hasattr(R, "toarray") and R.nnz <= SPARSE_STEPS_DENSITY * n * n
    dense = stability_matrix(hA.toarray(), coefficients)
    np.testing.assert_allclose(R.toarray(), dense, rtol=0, atol=1e-14 * np.max(np.abs(dense)))
    i, j = np.nonzero(dense)
    assert np.max(np.abs(i - j)) == d   # the band is the polynomial's (the test sees it)
    i, j = R.nonzero()
    assert np.max(np.abs(i - j)) <= d
    full = rng.normal(size=(n, n)) * 0.05
    out = sparse_stability_matrix(full, coefficients)
    assert isinstance(out, np.ndarray)
    np.testing.assert_allclose(out, stability_matrix(full, coefficients), rtol=0, atol=1e-13)


@pytest.mark.parametrize("name", ["rk4", "rk8"])
def test_a_sparse_step_matrix_from_kept_powers_is_horner_s_at_any_step(name):
    """A sparse ``A``'s powers kept on their common pattern give Horner's sparse ``R(hA)`` at every step, to
    rounding, on the pattern of the whole polynomial: a ring-like ``A`` (closed, so the band wraps round) whose
    square cancels exactly where two paths meet (kept on the pattern all the same)."""
    from scipy.sparse import csr_matrix
    coefficients = get_method(name).amplification_coefficients()
    n = 40
    rng = np.random.default_rng(11)
    A = np.zeros((n, n))
    for i in range(n):
        A[i, (i + 1) % n], A[i, (i - 1) % n], A[i, i] = rng.normal(size=3)
    A[0, 0], A[1, 1] = 1.0, -1.0   # (A^2)[0, 1] = A[0, 1] (A[0, 0] + A[1, 1]) = 0
    assert (A @ A)[0, 1] == 0.0
    powers = sparse_amplification_powers(csr_matrix(A), coefficients.size - 1)
    for h in (0.3, 0.0217, 1e-9):
        R = sparse_stability_matrix_from_powers(powers, h, coefficients)
        ref = sparse_stability_matrix(csr_matrix(h * A), coefficients)
        ref = ref.toarray() if hasattr(ref, "toarray") else ref
        np.testing.assert_allclose(R.toarray(), ref, rtol=0, atol=1e-14 * np.max(np.abs(ref)))
        np.testing.assert_allclose(R.toarray(), stability_matrix(h * A, coefficients), rtol=0,
                                   atol=1e-14 * np.max(np.abs(ref)))
    assert R.nnz == n * min(n, 2 * (coefficients.size - 1) + 1)   # the band of the polynomial, wrapped round


@pytest.mark.parametrize("run_max, method, density", [(0, "rk4", None), (16, "rk4", None), (10 ** 9, "rk4", None),
                                                      (16, "rk8", None), (16, "rk8", 0.0)])
def test_a_large_ring_s_monodromy_is_the_same_with_sparse_step_matrices(monkeypatch, run_max, method, density):
    """A mistuned 40-blade ring (160 states, sparse ``A``): the replay with sparse step matrices, runs of whole
    steps applied step by step up to ``run_max`` long and by dense powers beyond, is the replay with dense step
    matrices, to rounding, over a period with its contacts' events; for RK4 and RK8 (whose polynomial, of degree
    12, leaves them 10 % nonzero here, against 6.5 % under RK4), and with every mode's step taken as too dense to
    keep sparse (``density`` 0: its powers not kept, ``R(hA)`` made dense)."""
    from blademodel.numeric import contact_tangent
    model = BladedDisk(blades=40, engine_order=3, friction="coulomb", omega=1300.0, mistuning_std=0.02,
                       mistuning_seed=1).build()
    ig = make_integrator(model, method=method)
    y = np.zeros(ig.n_state)
    status, mode, _ = ig.advance(y, ig.mode_of(y), 0, 20)
    assert status == 0 and ig.n_physical >= contact_tangent.SPARSE_STEPS_FROM
    start = y[:ig.n_physical].copy()

    def monodromy():
        contact_tangent._CACHES.clear()
        return PeriodMap(ig, 1, jacobian="tangent", workers=1).derivatives(start, mode.copy())

    monkeypatch.setattr(contact_tangent, "SPARSE_RUN_MAX", run_max)
    if density is not None:
        monkeypatch.setattr(contact_tangent, "SPARSE_STEPS_DENSITY", density)
    sparse = monodromy()
    kept = [v for c in contact_tangent._CACHES.values() for v in c["sparse_powers"]._d.values()]
    too_dense = [len(v) == 0 for v in kept]   # modes whose powers were not kept: their R(hA) dense
    assert kept and (all(too_dense) if density == 0.0 else not any(too_dense))
    monkeypatch.setattr(contact_tangent, "SPARSE_STEPS_FROM", 10 ** 9)
    dense = monodromy()
    contact_tangent._CACHES.clear()
    assert sparse.events == dense.events >= 100
    scale = np.maximum(np.abs(start), 1e-3 * np.max(np.abs(start)))
    assert scaled_error(sparse.monodromy, dense.monodromy, scale) < 1e-12


def _tangent_and_differences(ig, orbit, rel_step=1e-5):
    P = PeriodMap(ig, 1, jacobian="tangent", workers=1)
    s = P.derivatives(orbit.state, orbit.mode.copy())
    ref = PeriodMap(ig, 1, jacobian="differences", workers=1).differences(orbit.state, orbit.mode.copy(),
                                                                         orbit.scale, rel_step)
    return P, s, ref


@pytest.mark.parametrize("friction", ["coulomb", "bilinear"])
def test_a_rings_monodromy_is_its_difference_quotients(friction):
    """The tuned 4-blade ring at 286 rad/s: contacts close in slip and stick, leave stick through either
    side of the cone, open; with Coulomb a contact sticks beside one that already sticks (the joint
    projection) and the friction problem makes a third slip at that instant; with the bilinear law
    (Jenkins) every opening and closing resets the law's state."""
    ig, orbit = ring_orbit(friction)
    P, s, ref = _tangent_and_differences(ig, orbit)
    r = P.run(orbit.state, orbit.mode.copy())
    named = ig.named_events(r.log, r.n_log)
    assert any("friction problem" in g for g in named["guard"]) == (friction == "coulomb")
    assert s.events >= 40 and P.evaluations == 1   # one run, replayed
    assert scaled_error(s.monodromy, ref, orbit.scale) < 1e-6
    np.testing.assert_allclose(np.sort(np.abs(np.linalg.eigvals(s.monodromy))),
                               np.sort(np.abs(np.linalg.eigvals(ref))), rtol=0, atol=1e-6)


def test_a_mistuned_rings_monodromy_is_its_difference_quotients():
    """Six mistuned blades under engine order 2 with a stronger force: events of several clusters in one step,
    each stepped through its own sub-steps while the other rows take the whole step."""
    ig, orbit = ring_orbit("coulomb", blades=6, engine_order=2, mistuning_std=0.05, mistuning_seed=1, F0=120.0)
    _, s, ref = _tangent_and_differences(ig, orbit)
    assert s.events >= 80
    assert scaled_error(s.monodromy, ref, orbit.scale) < 1e-6


def test_a_closed_ring_that_sticks_is_differentiated_through_its_singular_stick_problem():
    """Four preloaded, mistuned blades driven in phase: for 249 of the 600 steps every contact sticks and the
    stick constraints close the ring (a uniform circulating force changes no blade's motion, so ``W`` is
    singular). The ring enters that state by a stick event, where the kernel projects the velocities onto
    all four constraints, and so does the replay (without its projection the error is 0.65). (A near-grazing
    stick-slip event of this orbit bends the map within ``1e-5`` of the state, so the quotients take a
    step of ``1e-7``: at ``1e-5`` they differ from the tangent, and from the quotients at ``1e-7``, by
    ``9e-5``.)"""
    ig, orbit = ring_orbit("coulomb", engine_order=0, gap=-4e-5, mu=0.3, F0=60.0, mistuning_std=0.2,
                           mistuning_seed=2)
    P, s, ref = _tangent_and_differences(ig, orbit, rel_step=1e-7)
    modes = P.run(orbit.state, orbit.mode.copy()).modes
    all_stick = np.all(modes == 1, axis=1)
    assert all_stick.sum() >= 200 and np.any(all_stick[1:] & ~all_stick[:-1])   # entered by an event
    assert scaled_error(s.monodromy, ref, orbit.scale) < 1e-6


def test_a_csr_block_is_scipy_s_fancy_indexing():
    """``csr_block`` and ``csr_submatrix`` read ``A[rows][:, rows]`` from a CSR matrix's arrays: the same entries as
    scipy's fancy indexing, dense or in the same CSR arrays (so products with them round alike); a matrix with
    duplicate entries is summed, as scipy does."""
    from scipy.sparse import csr_matrix, random as sparse_random
    from blademodel.numeric.contact_tangent import csr_block, csr_submatrix
    rng = np.random.default_rng(3)
    for n in (5, 60, 288):
        A = sparse_random(n, n, density=0.1, random_state=n, format="csr")
        for _ in range(10):
            rows = np.sort(rng.choice(n, size=int(rng.integers(1, n + 1)), replace=False))
            ref = A[rows][:, rows]
            np.testing.assert_array_equal(csr_block(A, rows), ref.toarray())
            sub = csr_submatrix(A, rows)
            for part in ("indptr", "indices", "data"):
                np.testing.assert_array_equal(getattr(sub, part), getattr(ref, part))
    twice = csr_matrix((np.array([1.0, 2.0, 4.0]), np.array([1, 1, 0]), np.array([0, 2, 3])), shape=(2, 2))
    np.testing.assert_array_equal(csr_block(twice, np.arange(2)), [[0.0, 3.0], [4.0, 0.0]])


@pytest.mark.parametrize("case", ["mistuned", "closed", "bilinear"])
def test_the_compiled_cluster_step_is_the_python_one(monkeypatch, case):
    """The replay stepping each cluster through its events in compiled code (``cluster_step``) gives the
    monodromy that the Python steps give, to rounding: on six mistuned blades (several clusters in a step),
    on the closed ring that sticks (the joint projection through its singular stick problem) and on the
    bilinear ring, whose openings and closings reset the law's state (the reset's central differences).
    Where the kernel's cluster of a step's events holds the replay's rows, the compiled sub-steps evaluate that
    cluster alone (its active set), as the kernel stepped it."""
    from blademodel.numeric import contact_tangent
    if case == "mistuned":
        ig, orbit = ring_orbit("coulomb", blades=6, engine_order=2, mistuning_std=0.05, mistuning_seed=1, F0=120.0)
    elif case == "closed":
        ig, orbit = ring_orbit("coulomb", engine_order=0, gap=-4e-5, mu=0.3, F0=60.0, mistuning_std=0.2,
                               mistuning_seed=2)
    else:
        ig, orbit = ring_orbit("bilinear")
    calls = {"compiled": 0, "python": 0}
    compiled, python = (contact_tangent.ContactTangent._compiled_cluster_step,
                        contact_tangent.ContactTangent._cluster_step)

    def counted(name, f):
        def g(*a, **k):
            calls[name] += 1
            return f(*a, **k)
        return g

    monkeypatch.setattr(contact_tangent.ContactTangent, "_compiled_cluster_step", counted("compiled", compiled))
    monkeypatch.setattr(contact_tangent.ContactTangent, "_cluster_step", counted("python", python))

    def monodromy(compiled_steps):
        monkeypatch.setattr(contact_tangent, "COMPILED_CLUSTER_STEPS", compiled_steps)
        contact_tangent._CACHES.clear()
        P = PeriodMap(ig, 1, jacobian="tangent", workers=1)
        return P.derivatives(orbit.state, orbit.mode.copy()).monodromy, P._contact_tangent.cluster_steps

    fast, (whole, local, fallen_back) = monodromy(True)
    taken = dict(calls)
    calls.update(compiled=0, python=0)
    reference, _ = monodromy(False)
    assert calls["compiled"] == 0 and calls["python"] == taken["compiled"] + taken["python"] >= 20
    assert taken["python"] == 0 and whole + local == taken["compiled"] and fallen_back == 0
    if case == "mistuned":   # clusters of a few blades: their sub-steps evaluate them alone, as the kernel did
        assert local > 0
    assert scaled_error(fast, reference, orbit.scale) < 1e-12


def test_a_cluster_larger_than_the_compiled_bound_is_stepped_in_python(monkeypatch):
    """Clusters of more than ``COMPILED_CLUSTER_ROWS`` rows (a ring that sticks closed is one) take the Python
    steps, whose products go to BLAS; the monodromy is the same to rounding."""
    from blademodel.numeric import contact_tangent
    ig, orbit = ring_orbit("coulomb", blades=6, engine_order=2, mistuning_std=0.05, mistuning_seed=1, F0=120.0)
    sizes = {"compiled": [], "python": []}
    compiled, python = (contact_tangent.ContactTangent._compiled_cluster_step,
                        contact_tangent.ContactTangent._cluster_step)

    def sized(name, f):
        def g(self, Vc, rows, *a, **k):
            sizes[name].append(rows.size)
            return f(self, Vc, rows, *a, **k)
        return g

    monkeypatch.setattr(contact_tangent.ContactTangent, "_compiled_cluster_step", sized("compiled", compiled))
    monkeypatch.setattr(contact_tangent.ContactTangent, "_cluster_step", sized("python", python))

    def monodromy():
        contact_tangent._CACHES.clear()
        return PeriodMap(ig, 1, jacobian="tangent", workers=1).derivatives(orbit.state, orbit.mode.copy()).monodromy

    compiled_all = monodromy()
    assert not sizes["python"] and max(sizes["compiled"]) <= contact_tangent.COMPILED_CLUSTER_ROWS
    bound, taken = min(sizes["compiled"]) - 1, len(sizes["compiled"])
    sizes.update(compiled=[], python=[])
    monkeypatch.setattr(contact_tangent, "COMPILED_CLUSTER_ROWS", bound)   # every cluster larger than the bound
    in_python = monodromy()
    assert not sizes["compiled"] and len(sizes["python"]) == taken
    assert scaled_error(in_python, compiled_all, orbit.scale) < 1e-12


def test_auto_takes_the_tangent_on_a_ring():
    """``jacobian="auto"`` on the per-contact kernel replays the residual's own run: one integration, not the
    ``2 n`` of central differences, and the matrix is the tangent's."""
    ig, orbit = ring_orbit("coulomb")
    P = PeriodMap(ig, 1, jacobian="auto", workers=1)
    J = P.jacobian(orbit.state, orbit.mode.copy(), orbit.scale)
    assert (P.evaluations, P.replays) == (1, 1)
    T = PeriodMap(ig, 1, jacobian="tangent", workers=1).derivatives(orbit.state, orbit.mode.copy()).monodromy
    np.testing.assert_array_equal(J, T)


class SmoothSlip(FrictionLaw):
    """A slider whose force saturates smoothly with the slip velocity, ``mu N tanh(v / v0)``: not affine in the
    state within its one mode (a law of this file, by its import path)."""

    modes = ("slip",)
    states = ()

    def parameters(self):
        return {"mu": as_param(0.3, "mu", field="friction: mu")}

    def force(self, mode, ctx):
        return ctx.params["mu"] * ctx.N * sp.tanh(ctx.v / sp.Float(1e-3))

    def rates(self, mode, ctx):
        return {}

    def guards(self, mode, ctx):
        return []

    def entry(self, ctx):
        return [Candidate("slip")]


def test_a_law_that_is_not_affine_within_a_mode_falls_back_to_differences():
    """A law whose force is nonlinear in the state within a mode: the replay's probe finds the flow not affine and
    says so, and ``"auto"`` takes central differences instead."""
    ig = make_integrator(BladedDisk(blades=4, engine_order=1, friction="test_contact_tangent:SmoothSlip",
                                    gap=-1e-5, omega=286.0).build(), steps_per_period=SPP)
    y = ig.initial_state()
    _, mode, _ = ig.advance(y, ig.mode_of(y), 0, 20)
    y = y[:ig.n_physical].copy()
    scale = np.maximum(np.abs(y), 1e-3 * np.abs(y).max())
    with pytest.raises(SensitivityError, match="not affine"):
        PeriodMap(ig, 1, jacobian="tangent", workers=1).derivatives(y, mode.copy())
    auto = PeriodMap(ig, 1, jacobian="auto", workers=1)
    J = auto.jacobian(y, mode.copy(), scale)
    assert auto.evaluations > ig.n_physical
    np.testing.assert_array_equal(J, PeriodMap(ig, 1, jacobian="differences", workers=1).differences(y, mode.copy(),
                                                                                                     scale))


def _iwan_ring_orbit(blades=4, **values):
    model = BladedDisk(blades=blades, engine_order=1, friction="iwan", gap=-1e-5, omega=286.0, **values).build()
    ig = make_integrator(model, steps_per_period=SPP)
    return ig, find_periodic_orbit(model, integrator=ig, transient=50, jacobian="forward", workers=1)


def test_the_iwan_ring_s_tangent_holds_the_labels_the_kernel_set():
    """The Iwan law's flow is affine for given labels (its elements' modes), so the replay keys its matrices by
    mode and labels. A preloaded 4-blade ring of four elements a contact, whose contacts open and close (every
    element then sticks unstretched under a vanishing slip force, and those the motion loads slip at once): the
    monodromy agrees with central differences of the map, the labels held (measured ``3.6e-7`` at 600 steps a
    period, ``3.3e-8`` at 1000).

    Each of the pieces the labels need fails this test without it: the matrices keyed by the labels (the probe
    finds the flow not affine: the fallback); the reset taken a little past its guard's root where the replay's
    state lies a rounding error short of it (the reset then keeps an element stuck that the kernel sent to slip);
    and its Jacobian with the kernel's decisions fixed, one-sided where a difference step crosses the decision
    (``7.9e-5`` with central differences throughout)."""
    ig, orbit = _iwan_ring_orbit()
    P = PeriodMap(ig, 1, jacobian="tangent", workers=1)
    run = P.run(orbit.state, orbit.mode.copy())
    guard, frm, to = (c[:run.n_log] for c in run.log[2:])
    assert np.sum(guard == 0) >= 4 and np.sum(frm == to) >= 50   # closings and openings, element slips
    M = P.derivatives(orbit.state, orbit.mode.copy()).monodromy
    ref = hold_discrete(P.differences(orbit.state, orbit.mode.copy(), orbit.scale, 1e-5), ig.discrete_states)
    assert scaled_error(M, ref, orbit.scale) < 2e-6
    assert P.replays == 1


def test_the_iwan_ring_s_compiled_cluster_step_is_the_python_one(monkeypatch):
    """On the preloaded 4-blade Iwan ring (labels, resets decided from the state, one-sided differences), the
    compiled cluster steps follow plans of the Python step's decisions (its blocks of ``A``, the labels each
    transition set and the resets' Jacobians for them: recorded from it, or from the kept matrices where they
    hold them all) and give the Python steps' monodromy to rounding, from the first replay on: a second replay
    records nothing and is the first to the bit. The compiled step uses the recorded resets (dropped, the
    monodromy changes) and checks the labels: a plan whose recorded labels a transition does not set is stepped
    in Python, with the Python steps' monodromy."""
    from blademodel.numeric import contact_tangent
    ig, orbit = _iwan_ring_orbit()
    recorded, from_kept = [], []
    python_step, kept_record = contact_tangent.ContactTangent._cluster_step, contact_tangent.ContactTangent._kept_record

    def counted(self, Vc, *a, **k):
        recorded.append(Vc.shape[1] == 0)
        return python_step(self, Vc, *a, **k)

    def kept(self, *a):
        record = kept_record(self, *a)
        from_kept.append(record is not None)
        return record

    monkeypatch.setattr(contact_tangent.ContactTangent, "_cluster_step", counted)
    monkeypatch.setattr(contact_tangent.ContactTangent, "_kept_record", kept)

    def replay(compiled_steps, clear=True):
        monkeypatch.setattr(contact_tangent, "COMPILED_CLUSTER_STEPS", compiled_steps)
        if clear:
            contact_tangent._CACHES.clear()
        P = PeriodMap(ig, 1, jacobian="tangent", workers=1)
        return P.derivatives(orbit.state, orbit.mode.copy()).monodromy, P._contact_tangent

    reference, _ = replay(False)
    steps = len(recorded)
    assert steps >= 20 and not any(recorded)
    recorded.clear()
    first, tangent = replay(True)
    # each step's plan made once: from the kept matrices, or recorded from the Python step on no columns
    assert len(from_kept) == steps and all(recorded) and len(recorded) == from_kept.count(False)
    assert sum(from_kept) >= 10 and len(recorded) >= 10
    assert sum(tangent.cluster_steps[:2]) == steps and tangent.cluster_steps[2] == 0
    assert scaled_error(first, reference, orbit.scale) < 1e-12
    recorded.clear()
    from_kept.clear()
    second, tangent = replay(True, clear=False)
    assert not recorded and not from_kept and sum(tangent.cluster_steps[:2]) == steps
    np.testing.assert_array_equal(second, first)

    plans = next(iter(contact_tangent._CACHES.values()))["plans"]
    kept = {key: plans.get(key) for key in list(plans._d)}
    assert any(plan.RB.size for plan in kept.values())
    for key, plan in kept.items():   # the recorded resets' rows dropped
        plans[key] = plan._replace(RB=np.zeros_like(plan.RB))
    dropped, _ = replay(True, clear=False)
    assert scaled_error(dropped, reference, orbit.scale) > 1e-3
    for key, plan in kept.items():
        plans[key] = plan._replace(ltg=plan.ltg + 2.0)   # labels no transition sets
    checked, tangent = replay(True, clear=False)
    assert tangent.cluster_steps[2] > 0
    assert scaled_error(checked, reference, orbit.scale) < 1e-12


def test_a_reset_that_decides_otherwise_than_the_kernel_is_taken_a_little_farther_along_the_flow():
    """Where the kernel read a guard from the boundary (a drifted transition's offset) and fired it while the reset,
    which decides from the raw state, would not yet (the 24-blade ring from 290 to 300 rad/s: an element that stops
    slipping, at 4 of 183 points, which then fell back to differences), the replay moves the state along the flow,
    by ``1e-14`` of a step and ten times more each try, until the reset sets the labels the kernel set; it says so
    where it never does within ``1e-8`` of a step. Here a stand-in reset whose decision flips ``3e-12`` of a step
    along the flow."""
    from blademodel.numeric.contact_tangent import ContactTangent, ContactTangentError
    ig, orbit = _iwan_ring_orbit()
    ct = ContactTangent(ig)
    y = np.zeros(ig.n_state)
    y[:ig.n_physical] = orbit.state
    cm = orbit.mode.copy()
    labels = ct._contact_labels[0]
    rate = ct._rhs(0.0, y, cm)
    h = ig.period / ig.steps_per_period
    i = int(np.argmax(np.abs(rate[:ig.n_physical])))   # a state the flow moves
    flip = y[i] + 3e-12 * h * rate[i]

    def fire(state):
        out = state.copy()
        out[labels] = 0.0
        out[labels[0]] = 1.0 if (state[i] - flip) * rate[i] >= 0 else 0.0   # slips once past the flip
        return out

    target = np.zeros(labels.size)
    target[0] = 1.0
    moved, after = ct._as_the_kernel(fire, 0.0, y, cm, labels, target, 0)
    assert np.array_equal(after[labels], target)
    assert 3e-12 * h <= (moved[i] - y[i]) / rate[i] <= 1e-10 * h   # the first try past the flip (1e-11 of a step)
    with pytest.raises(ContactTangentError, match="sets other labels than the kernel did"):
        ct._as_the_kernel(fire, 0.0, y, cm, labels, np.zeros(labels.size) + 2.0, 0)


@pytest.mark.slow
def test_the_iwan_24_blade_ring_s_reduced_tangent_matches_differences():
    """The README's preloaded 24-blade Iwan ring on its map reduced by the symmetry, at 295 rad/s: the replay's
    guard gradients for the Iwan law are central differences at the event (a gradient kept from the zero state,
    where every label is zero, is another element's, and the probe that checks it moves both sides of a contact
    alike; the replay stopped there with a guard of no rate). Measured ``3e-8``."""
    from blademodel.config import apply_overrides, load_config
    from blademodel.orbits.cyclic import CyclicSymmetry
    from pathlib import Path
    cfg = apply_overrides(load_config(Path(__file__).resolve().parents[1] / "models" / "bladed_disk_24.yaml"),
                          {"friction": "iwan", "gap": -1e-5, "omega": 295.0})
    model = cfg.build()
    ig = make_integrator(model, kernel="contact")
    orbit = find_periodic_orbit(model, integrator=ig, transient=20, workers=1)
    G = PeriodMap(ig, 1, jacobian="tangent", workers=1, symmetry=CyclicSymmetry(cfg, ig))
    M = G.derivatives(orbit.state, orbit.mode.copy()).monodromy
    ref = hold_discrete(G.differences(orbit.state, orbit.mode.copy(), orbit.scale, 1e-5), ig.discrete_states)
    assert scaled_error(M, ref, orbit.scale) < 1e-6


@pytest.mark.parametrize("friction", ["coulomb", "bilinear"])
def test_the_replayed_tangent_is_the_compiled_one_on_the_pair(friction):
    """The paper's pair on both kernels, from its state after 50 periods: the product-mode kernel's tangent
    integrates variational equations generated by SymPy for every mode, guard and reset; the per-contact
    kernel's is replayed here from ``rhs``, guards and transitions alone. One period with 13 (Coulomb) and
    26 (bilinear) events: they agree to 1e-8 of the matrix (measured 1.1e-9 and 1.3e-9)."""
    from blademodel.zheng2022 import BladePair
    model = BladePair(friction=friction).build()
    settings = dict(steps_per_period=1000, event_tol=1e-13, event_location="predicted")
    ig = make_integrator(model, kernel="product", **settings)
    y = ig.initial_state()
    _, mode, _ = ig.advance(y, ig.mode_of(y), 0, 50)
    y = y[:ig.n_physical].copy()
    scale = np.maximum(np.abs(y), 1e-3 * np.abs(y).max())
    compiled = PeriodMap(ig, 1, jacobian="tangent")
    J = compiled.jacobian(y, mode, scale)
    ig_c = make_integrator(model, kernel="contact", **settings)
    replayed = PeriodMap(ig_c, 1, jacobian="tangent")
    J_c = replayed.jacobian(y, ig_c.mode_of(np.append(y, np.zeros(ig_c.n_state - y.size))), scale)
    assert compiled.last_events == replayed.last_events >= 13
    assert scaled_error(J_c, J, scale) < 1e-8


def test_a_branch_does_not_depend_on_what_was_computed_before_it():
    """The modes' matrices and guard gradients kept from earlier runs are the ones a fresh computation gives, bit
    for bit (they are taken at the zero state, from values that include everything they read): a branch
    continued after another one of the same ring is the branch continued alone."""
    from blademodel.numeric import contact_tangent
    from blademodel.orbits import continuation
    cfg = BladedDisk(blades=4, engine_order=1, friction="coulomb", mistuning_std=0.05, mistuning_seed=3)
    continuation(cfg, "omega", 287.0, 295.0, max_points=8, workers=1)
    after = continuation(cfg, "omega", 285.0, 290.0, max_points=12, workers=1)
    contact_tangent._CACHES.clear()
    alone = continuation(cfg, "omega", 285.0, 290.0, max_points=12, workers=1)
    for a in ("params", "states", "multipliers"):
        np.testing.assert_array_equal(getattr(after, a), getattr(alone, a), err_msg=a)


def test_a_bounded_cache_moves_the_cost_and_never_the_result(monkeypatch):
    """With the kept matrices bounded to a few kilobytes (most dropped and computed again), a branch is the one
    computed with room for all of them, bit for bit, and the kept bytes stay within the bounds."""
    from blademodel.numeric import contact_tangent
    from blademodel.orbits import continuation
    cfg = BladedDisk(blades=4, engine_order=1, friction="coulomb", mistuning_std=0.05, mistuning_seed=3)
    contact_tangent._CACHES.clear()
    roomy = continuation(cfg, "omega", 285.0, 290.0, max_points=12, workers=1)
    contact_tangent._CACHES.clear()
    monkeypatch.setattr(contact_tangent, "KEEP_BYTES", 16 * 1024)
    tight = continuation(cfg, "omega", 285.0, 290.0, max_points=12, workers=1)
    for a in ("params", "states", "multipliers"):
        np.testing.assert_array_equal(getattr(tight, a), getattr(roomy, a), err_msg=a)
    kept = [c for caches in contact_tangent._CACHES.values() for c in caches.values()
            if isinstance(c, contact_tangent._Kept)]
    assert kept and all(c.size <= c.budget or len(c) == 1 for c in kept)
    assert any(len(c) > 0 for c in kept) and any(c.dropped > 0 for c in kept)
    contact_tangent._CACHES.clear()
