"""A ring mode's flow matrix and guard gradients from column groups of its pattern, against column by column.

The replayed tangent of the per-contact kernel (:mod:`blademodel.numeric.contact_tangent`)
takes each mode's ``A = df/dy`` and each guard's gradient from differences of the compiled
``rhs`` and guards at the zero state. With the model's pattern
(:mod:`blademodel.numeric.contact_flow_pattern`) columns that share no row are perturbed
together, and the matrix is kept sparse, on rings of ``GROUPED_FROM`` states and more;
these tests lower that threshold to the small rings they use, take every column on its own
instead, with the compiled functions directly, and compare to the bit, over every mode and
guard an orbit's run meets, with rigid stick clusters (Coulomb), law states (bilinear) and
a ring that sticks closed.
"""

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from blademodel.config import BladedDisk, load_config
from blademodel.numeric import contact_flow_pattern, contact_tangent
from blademodel.numeric.contact_flow_pattern import FlowPattern, flow_pattern, grouped_flow_matrix
from blademodel.numeric.contract import NK_DAMPED
from blademodel.numeric.kernels import make_integrator
from blademodel.orbits import find_periodic_orbit
from blademodel.orbits.period_map import PeriodMap
from blademodel.zheng2022 import BladePair

MODELS_DIR = Path(__file__).resolve().parent.parent / "models"

RINGS = {
    "coulomb": dict(blades=16, engine_order=2, friction="coulomb", mistuning_std=0.05, mistuning_seed=1),
    "bilinear": dict(blades=16, engine_order=2, friction="bilinear"),
    "closed": dict(blades=4, engine_order=0, friction="coulomb", gap=-4e-5, mu=0.3, F0=60.0,
                   mistuning_std=0.2, mistuning_seed=2),
}


@pytest.fixture
def grouped(monkeypatch):
    """Group the columns and keep ``A`` sparse on the tests' small rings too."""
    monkeypatch.setattr(contact_tangent, "GROUPED_FROM", 0)


def replayed(name):
    """The ring's integrator, its orbit and the period map that replayed the orbit's run (a fresh cache)."""
    contact_tangent._CACHES.clear()
    model = BladedDisk(omega=286.0, **RINGS[name]).build()
    ig = make_integrator(model, steps_per_period=600)
    orbit = find_periodic_orbit(model, integrator=ig, transient=50, jacobian="forward", workers=1)
    P = PeriodMap(ig, 1, jacobian="tangent", workers=1)
    P.derivatives(orbit.state, orbit.mode.copy())
    return ig, orbit, P


def column_by_column(f, n):
    """``f(e_i) - f(0)`` for every ``i``: the reference, each column on its own."""
    y = np.zeros(n)
    f0 = f(y)
    cols = []
    for i in range(n):
        y[i] = 1.0
        cols.append(f(y) - f0)
        y[i] = 0.0
    return np.array(cols).T


def rhs_of(ig, cm):
    out = np.empty(ig.n_state)

    def f(y):
        z = np.zeros(ig.n_state)
        z[:ig.n_physical] = y
        ig.module.factor_stick(cm, ig.I, ig.R, ig.WI, ig.WF)
        ig.module.rhs(0.0, z, cm, ig.I, ig.R, ig.WI, ig.WF, out)
        return out[:ig.n_physical].copy()
    return f


@pytest.mark.parametrize("name", sorted(RINGS))
def test_each_modes_grouped_flow_matrix_is_the_column_by_column_one(name, grouped):
    """Every mode the run met: ``A`` from the groups equals ``A`` column by column, to the bit, with fewer
    calls of ``rhs``; the modes include rigid stick clusters of several contacts (Coulomb) and, on the closed
    ring, every contact sticking (its columns then each need a group of their own)."""
    ig, orbit, P = replayed(name)
    tan = P._contact_tangent
    pattern, n = tan._pattern, ig.n_physical
    assert pattern is not None
    kept = contact_tangent._caches(ig)["A"]
    assert len(kept) >= 10 and not tan._ungrouped
    calls, clusters = [], 0
    for key, A in list(kept._d.items()):
        cm = np.frombuffer(key, dtype=np.int64).copy()
        ref = column_by_column(rhs_of(ig, cm), n)
        np.testing.assert_array_equal(A.toarray(), ref)
        sticking = tan._sticking(cm)
        groups, owners = pattern.groups(sticking)
        calls.append(len(groups))
        clusters = max(clusters, max((len(c) for c in pattern._clusters(sticking)),
                                     default=0))
        assert sorted(np.concatenate(groups).tolist()) == list(range(n))   # every column, once
    if name == "closed":
        assert clusters == 4 and max(calls) == n    # the whole ring one cluster: no two columns share a group
    else:
        assert max(calls) < n   # every mode grouped some columns (how far: benchmarks/ring_tangent.py)
    if name == "coulomb":
        assert clusters >= 2


@pytest.mark.parametrize("name", ["coulomb", "bilinear"])
def test_each_guards_gradient_from_its_columns_is_the_column_by_column_one(name, grouped):
    """Every guard gradient the replay took (kept per mode and guard): from the columns the pattern allows it to
    depend on, the same as from every column, to the bit."""
    ig, orbit, P = replayed(name)
    tan = P._contact_tangent
    kept = contact_tangent._caches(ig)["gy"]
    assert len(kept) >= 10
    G = np.zeros_like(ig.GS[0])
    for (cmb, j, gi), gy in list(kept._d.items()):
        cm = np.frombuffer(cmb, dtype=np.int64).copy()

        def guard(y):
            z = np.zeros(ig.n_state)
            z[:ig.n_physical] = y
            ig.module.factor_stick(cm, ig.I, ig.R, ig.WI, ig.WF)
            ig.module.guards_at(0.0, z, cm, ig.I, ig.R, ig.WI, ig.WF, G)
            return np.array([G[j, gi]])
        np.testing.assert_array_equal(gy, column_by_column(guard, ig.n_physical)[0])


def test_a_pattern_that_misses_entries_is_found_and_every_column_taken_on_its_own(grouped):
    """A pattern without the springs, dampers and contacts: the grouped build sees changes in rows no column of
    the group owns and refuses; the tangent then takes every column on its own, and its monodromy is the one with the full
    pattern, to the bit."""
    ig, orbit, P = replayed("coulomb")
    good = P.derivatives(orbit.state, orbit.mode.copy()).monodromy
    tables = ig.tables
    empty = (np.zeros(tables.n + 1, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0))
    law_states = [int(ig.module.NSTATES[int(K)]) for K in tables.claw]
    blind = FlowPattern(SimpleNamespace(n=tables.n, K=empty, C=empty, cidx=-np.ones_like(tables.cidx), cso=tables.cso),
                        ig.n_physical, law_states)
    cm = orbit.mode.copy()
    assert grouped_flow_matrix(rhs_of(ig, cm), ig.n_physical, *blind.groups(())) is None
    contact_tangent._CACHES.clear()
    contact_tangent._caches(ig)["pattern"].append(blind)
    again = PeriodMap(ig, 1, jacobian="tangent", workers=1).derivatives(orbit.state, orbit.mode.copy()).monodromy
    np.testing.assert_array_equal(again, good)


def test_a_grouped_matrix_that_fails_the_probe_is_taken_again_column_by_column(monkeypatch, grouped):
    """A grouped build that reads an entry into the wrong column (simulated: one value moved) passes the
    build's own check but not the probe along a random direction: that mode is then built column by column,
    remembered as such, and the monodromy is the right one, to the bit."""
    ig, orbit, P = replayed("coulomb")
    good = P.derivatives(orbit.state, orbit.mode.copy()).monodromy
    real = contact_tangent.grouped_flow_matrix

    def misread(flow, n, groups, owners):
        rows, cols, values = real(flow, n, groups, owners)
        cols = cols.copy()
        cols[0] = (cols[0] + 1) % n
        return rows, cols, values
    monkeypatch.setattr(contact_tangent, "grouped_flow_matrix", misread)
    contact_tangent._CACHES.clear()
    again = PeriodMap(ig, 1, jacobian="tangent", workers=1)
    M = again.derivatives(orbit.state, orbit.mode.copy()).monodromy
    np.testing.assert_array_equal(M, good)
    assert len(again._contact_tangent._ungrouped) == len(contact_tangent._caches(ig)["A"])


def test_a_damped_normal_law_is_not_grouped():
    """A damped contact's ``dN/dt`` reads the accelerations, which the pattern does not follow: no pattern."""
    assert flow_pattern(SimpleNamespace(cnk=np.array([0, NK_DAMPED])), 8, [0, 0]) is None


def test_a_small_ring_keeps_the_column_by_column_dense_replay_and_a_large_one_the_same_monodromy(monkeypatch):
    """Below ``GROUPED_FROM`` states a ring's modes are taken column by column and kept dense (the grouping's own
    work costs more than it saves there). This 16-blade ring's monodromy that way and grouped (the threshold
    lowered) agree to rounding (a sparse ``A`` sums the step matrices' products in another order), and the
    grouped one keeps a fraction of the bytes."""
    ig, orbit, P = replayed("coulomb")
    n = ig.n_physical
    assert n < contact_tangent.GROUPED_FROM and P._contact_tangent._pattern is None
    dense = P.derivatives(orbit.state, orbit.mode.copy()).monodromy
    kept = contact_tangent._caches(ig)["A"]
    assert kept.size == len(kept) * n * n * 8
    monkeypatch.setattr(contact_tangent, "GROUPED_FROM", 0)
    contact_tangent._CACHES.clear()
    sparse = PeriodMap(ig, 1, jacobian="tangent", workers=1).derivatives(orbit.state, orbit.mode.copy()).monodromy
    kept = contact_tangent._caches(ig)["A"]
    assert all(hasattr(A, "indptr") for A in kept._d.values()) and kept.size < len(kept) * n * n * 8 / 3
    np.testing.assert_allclose(sparse, dense, rtol=0, atol=1e-12 * np.max(np.abs(dense)))


MODELS = {
    "pair-coulomb": lambda: BladePair(friction="coulomb").build(),
    "pair-bilinear": lambda: BladePair(friction="bilinear").build(),
    "row-of-three": lambda: load_config(MODELS_DIR / "blade_row_3.yaml").build(),
    "den-hartog": lambda: load_config(MODELS_DIR / "friction_oscillator.yaml").build(),
    "ring-bilinear-mistuned": lambda: BladedDisk(blades=6, engine_order=2, friction="bilinear", mistuning_std=0.05,
                                                 mistuning_seed=4, omega=286.0).build(),
}


@pytest.mark.parametrize("name", sorted(MODELS))
def test_the_pattern_holds_on_every_kind_of_per_contact_model(name, grouped):
    """The pattern is read from the tables of any per-contact model, not only rings: the pair, a row of three
    blades with one Coulomb and one Jenkins shroud, Den Hartog's oscillator (a ground contact under a constant
    load), a mistuned ring. On each, after 30 periods from rest, the grouped replay needs no column-by-column
    fallback and its monodromy is the dense one's to rounding."""
    from blademodel.numeric.kernels import make_integrator as make
    ig = make(MODELS[name](), kernel="contact", steps_per_period=600)
    y = ig.initial_state()
    _, mode, _ = ig.advance(y, ig.mode_of(y), 0, 30)
    y = y[:ig.n_physical].copy()
    P = PeriodMap(ig, 1, jacobian="tangent", workers=1)
    M = P.derivatives(y, mode.copy()).monodromy
    tan = P._contact_tangent
    assert tan._pattern is not None and not tan._ungrouped and len(contact_tangent._caches(ig)["A"]) >= 2
    contact_tangent.GROUPED_FROM = 1 << 62    # the fixture puts it back
    contact_tangent._CACHES.clear()
    ref = PeriodMap(ig, 1, jacobian="tangent", workers=1).derivatives(y, mode.copy()).monodromy
    np.testing.assert_allclose(M, ref, rtol=0, atol=1e-12 * np.max(np.abs(ref)))


def test_the_clusters_kept_are_bounded_and_move_no_result(monkeypatch, grouped):
    """The clusters' rows and block pairs are kept to ``CLUSTER_BYTES`` (a ring sticking in arcs has thousands):
    with the bound at 2 kB (most dropped and computed again) every mode's ``A`` is the one kept with room for
    all of them, to the bit, and the kept bytes stay within the bound."""
    ig, orbit, P = replayed("coulomb")
    roomy = {k: A.toarray() for k, A in contact_tangent._caches(ig)["A"]._d.items()}
    monkeypatch.setattr(contact_flow_pattern, "CLUSTER_BYTES", 2048)
    contact_tangent._CACHES.clear()
    Q = PeriodMap(ig, 1, jacobian="tangent", workers=1)
    Q.derivatives(orbit.state, orbit.mode.copy())
    tight = contact_tangent._caches(ig)["A"]._d
    assert tight.keys() == roomy.keys()
    for k, A in tight.items():
        np.testing.assert_array_equal(A.toarray(), roomy[k])
    pattern = Q._contact_tangent._pattern
    assert pattern._cluster_rows.size <= 2048 or len(pattern._cluster_rows) == 1
