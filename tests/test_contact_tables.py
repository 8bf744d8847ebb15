"""The per-contact kernel's numeric tables at a parameter set: gathered by index arrays from one evaluation of
the distinct expressions (``contact_tables._Plan``), and packed with the integer layout built once per
structure (``contact_kernel._structure``)."""

import math

import numpy as np
import pytest

from blademodel.config import BladedDisk, load_config
from blademodel.numeric.contact_tables import _NAMESPACE, NumericTables
from blademodel.numeric.integrator import StructureMismatch
from blademodel.numeric.kernels import make_integrator

from test_forcing_phase import _three_groups


def _reference(tables: dict, values: dict, param_order) -> dict:
    """The tables entry by entry, each expression evaluated on its own, entries summed one after another."""
    ns = {**_NAMESPACE, **values}

    def ev(e):
        return float(eval(e, ns))

    n = len(tables["coordinates"])

    def csr(entries):
        acc: dict = {}
        for i, j, e in entries:
            acc[(i, j)] = acc.get((i, j), 0.0) + ev(e)
        kept = sorted((ij, v) for ij, v in acc.items() if v != 0.0)
        ptr = np.zeros(n + 1, dtype=np.int64)
        for (i, _), _ in kept:
            ptr[i + 1:] += 1
        return ptr, np.array([j for (_, j), _ in kept], dtype=np.int64), np.array([v for _, v in kept])

    groups, fi, fg, fs, fc = [], [], [], [], []
    terms = [(i, ev(a), ev(w), ev(ph)) for i, a, w, ph in tables["forcing"]]
    terms += [(i, None, 0.0, ev(a)) for i, a in tables["constant"]]
    for i, a, w, x in terms:
        if w not in groups:
            groups.append(w)
        fi.append(i)
        fg.append(groups.index(w))
        fs.append(0.0 if a is None else a * math.cos(x))
        fc.append(x if a is None else a * math.sin(x))
    cs = tables["contacts"]
    cgr = np.zeros((len(cs), 4))
    G = np.zeros((len(cs), n))
    for j, c in enumerate(cs):
        for k, slot in enumerate(c["slots"]):
            cgr[j, k] = ev(c["gr"][k])
            G[j, slot] += cgr[j, k]
    invm = np.array([1.0 / ev(e) for e in tables["inertia"]])
    return {"invm": invm, "K": csr(tables["stiffness"]), "C": csr(tables["damping"]),
            "forcing": (np.array(fi), np.array(fg), np.array(fs), np.array(fc), np.array(groups)),
            "cgr": cgr, "cgap": np.array([ev(c["gap"]) for c in cs]), "ck": np.array([ev(c["k"]) for c in cs]),
            "cc": np.array([ev(c.get("c", "0")) for c in cs]), "G": G, "W": (G * invm) @ G.T,
            "LP": _padded([[param_order.index(p) for p in c["law"]] for c in cs])}


def _padded(rows) -> np.ndarray:
    """Rows of unequal length as a matrix, zeros after each row's end."""
    out = np.zeros((len(rows), max([len(r) for r in rows] + [1])), dtype=np.int64)
    for j, r in enumerate(rows):
        out[j, :len(r)] = r
    return out


def _mistuned_bilinear_ring():
    return make_integrator(BladedDisk(blades=6, friction="bilinear", engine_order=3, mistuning_std=0.01,
                                      mistuning_seed=0).build())


@pytest.mark.parametrize("make", [_mistuned_bilinear_ring, _three_groups,
                                  lambda: make_integrator(load_config("models/blade_row_3.yaml").build())],
                         ids=["mistuned ring", "three groups", "blade row"])
def test_the_gathered_tables_are_the_entry_by_entry_ones(make):
    """At the model's values and at moved ones (each parameter scaled differently), every table equals the one
    evaluated entry by entry, bit for bit: the gathering reads each entry's own expression, sums repeated
    entries in their order, and drops the sums that vanish."""
    ig = make()
    base = dict(zip(ig.param_names, ig.tables.p.tolist()))
    offsets, pos = ig._layout
    for scale in (None, 1.0 + 0.01 * np.arange(len(base))):
        values = base if scale is None else {k: v * s for (k, v), s in zip(base.items(), scale)}
        mine = NumericTables(ig._table_source, values, ig.kind, offsets, ig.param_names, pos)
        ref = _reference(ig._table_source, values, ig.param_names)
        for name, want in ref.items():
            got = getattr(mine, name)
            for g, w in zip(got, want) if isinstance(want, tuple) else [(got, want)]:
                assert np.array_equal(np.asarray(g), np.asarray(w).reshape(np.shape(g))), name


def test_a_value_that_removes_an_entry_is_another_structure():
    """Damping set to zero drops its entries: an integrator built so has the smaller layout, one moved there by
    ``with_parameter_values`` is refused as another structure, and the layout shared by the first structure is
    not changed by it (moving back gives the original tables to the bit)."""
    cfg = BladedDisk(blades=4, engine_order=1, friction="coulomb")
    ig = make_integrator(cfg.build())
    undamped = make_integrator(cfg.model_copy(update={"cx": 0.0}).build())
    p = ig.tables.p.copy()
    cx = ig.param_names.index("cx")
    q = p.copy()
    q[cx] = 0.0
    with pytest.raises(StructureMismatch, match="laid out differently"):
        ig.with_parameter_values(q)
    assert ig.tables.C[1].size > 0
    offsets, pos = ig._layout
    dropped = NumericTables(ig._table_source, dict(zip(ig.param_names, q.tolist())), ig.kind, offsets,
                            ig.param_names, pos)
    assert dropped.C[1].size == ig.tables.C[1].size // 2          # the cy entries stay
    back = ig.with_parameter_values(p)
    assert np.array_equal(back.I, ig.I) and np.array_equal(back.R, ig.R)
    assert undamped.I.size < ig.I.size and undamped.tables.C[1].size == dropped.C[1].size


def test_a_zero_inertia_is_named():
    ig = make_integrator(BladedDisk(blades=4, engine_order=1, friction="coulomb").build())
    p = ig.tables.p.copy()
    p[ig.param_names.index("m")] = 0.0
    with pytest.raises(ValueError, match="coordinate x1: the inertia is zero"):
        ig.with_parameter_values(p)
