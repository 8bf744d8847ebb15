"""A model's numeric tables for the per-contact kernel, derived per component with SymPy.

SymPy derives each component's own contribution once per model *structure*:
the inertia of each coordinate, the stiffness and damping entries of springs and
dampers (``-dQ/dq``, ``-dQ/du`` of their loads, which must be linear), each
force's load as a sum of harmonic terms ``A sin(w t + phi)`` and a constant
(a constant is the frequency group ``w = 0``: ``sin 0 = 0``, ``cos 0 = 1``), and each contact's penetration and
relative-slip gradients (its n/r projection), gap and normal law (spring, damped
or constant load, with ``k``, ``c``, ``N0``). The entries are kept as
expressions of the parameter names (a JSON form cached on disk), so a run with a
cached structure evaluates them with :mod:`math` and never imports SymPy, and a
parameter change re-evaluates them in microseconds. The work grows linearly with
the number of components; nothing is compiled per model.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np

from ..model import Model
from .contract import NK_DAMPED, NK_LOAD, NK_SPRING

_NAMESPACE = {"sin": math.sin, "cos": math.cos, "tan": math.tan, "sqrt": math.sqrt, "exp": math.exp,
              "pi": math.pi, "E": math.e, "Abs": abs, "__builtins__": {}}


def _components_version() -> str:
    """Hash of the component sources and of this file: an edited component re-derives the tables."""
    from .compiled import hash_sources, package_sources
    return hash_sources([*package_sources("components"), Path(__file__)])


def derive_tables(model: Model) -> dict:
    """The structural tables of ``model`` as expressions (strings) of its parameter names.

    Raises
    ------
    ValueError
        For a component the per-contact kernel cannot take (a nonlinear spring or
        damper, a load that is not a constant plus harmonic terms, a contact that
        is not affine in the coordinates).
    """
    import sympy as sp

    t = sp.Symbol("t", real=True)
    coords = list(model.coordinates)
    q = {c: sp.Symbol(c, real=True) for c in coords}
    u = {c: sp.Symbol(f"v{c}", real=True) for c in coords}
    linear_symbols = set(q.values()) | set(u.values()) | {t}
    idx = {c: i for i, c in enumerate(coords)}
    inertia = {m.coordinate(d): str(m.inertia(d).symbol) for m in model.masses for d in m.dofs}

    by_symbol = {**{s: c for c, s in q.items()}, **{s: c for c, s in u.items()}}

    def involved(expr, var):
        """Coordinates whose ``var`` symbol appears in ``expr`` (never a scan of all coordinates)."""
        names = {by_symbol[s] for s in sp.sympify(expr).free_symbols if s in by_symbol}
        return [c for c in names if var[c] in expr.free_symbols]

    def linear(comps, var, what):
        out = []
        for comp in comps:
            for c, load in comp.loads(q, u, t).items():
                load = sp.sympify(load)
                for c2 in sorted(involved(load, var), key=idx.get):
                    coef = -sp.diff(load, var[c2])
                    if coef == 0:
                        continue
                    if coef.free_symbols & linear_symbols:
                        raise ValueError(f"{what} on {c}: the per-contact kernel needs linear loads, got {load}")
                    out.append([idx[c], idx[c2], str(coef)])
        return out

    A, W, P = (sp.Wild(n, exclude=[t]) for n in ("A", "W", "P"))
    forcing, constant = [], []
    for comp in model.forces:
        for c, load in comp.loads(q, u, t).items():
            load = sp.sympify(load)
            if load.free_symbols & (linear_symbols - {t}):
                raise ValueError(f"force on {c}: a force must not depend on the state, got {load}")
            steady = sp.Add(*[term for term in sp.Add.make_args(load) if not term.has(t)])
            if steady != 0:
                constant.append([idx[c], str(steady)])
            for term in sp.Add.make_args(load):
                if not term.has(t):
                    continue
                m = term.match(A * sp.sin(W * t + P))
                if m is None or m[W] == 0:
                    raise ValueError(f"force on {c}: the per-contact kernel takes loads made of constants and "
                                     f"harmonic terms A sin(w t + phi), got {load}")
                forcing.append([idx[c], str(m[A]), str(m[W]), str(m[P])])

    contacts = []
    for ct in model.contacts:
        delta = ct.penetration(q)
        slip = ct.relative_slip(q)
        slots, gn, gr = [], [], []
        for c in sorted(set(involved(delta, q)) | set(involved(slip, q)), key=idx.get):
            dn, dr = sp.diff(delta, q[c]), sp.diff(slip, q[c])
            if dn == 0 and dr == 0:
                continue
            if (dn.free_symbols | dr.free_symbols) & linear_symbols:
                raise ValueError(f"contact {ct.name}: the per-contact kernel needs a projection affine in the "
                                 f"coordinates")
            slots.append(idx[c])
            gn.append(str(dn))
            gr.append(str(dr))
        if len(slots) > 4:
            raise ValueError(f"contact {ct.name} moves {len(slots)} coordinates; at most 4 (two 2-D bodies)")
        pars = ct.parameters()
        contacts.append({"slots": slots, "gn": gn, "gr": gr, "gap": str(-delta.xreplace({q[c]: 0 for c in involved(delta, q)})),
                         "k": str(pars["k"].symbol) if "k" in pars else "0",
                         "normal": ct.normal_kind,
                         "c": str(pars["damping"].symbol) if "damping" in pars else "0",
                         "N0": str(pars["normal_load"].symbol) if "normal_load" in pars else "0",
                         "law": [str(p.symbol) for p in ct.friction.parameters().values()]})
    return {"coordinates": coords, "inertia": [inertia[c] for c in coords],
            "stiffness": linear(model.springs, q, "spring"), "damping": linear(model.dampers, u, "damper"),
            "forcing": forcing, "constant": constant, "contacts": contacts}


def cached_tables(model: Model) -> dict:
    """:func:`derive_tables`, cached on disk per model structure and component sources."""
    from .compiled import cache_dir
    key = f"{model.structure_key()}_{_components_version()}"
    path = cache_dir() / f"tables_{key}.json"
    if path.exists():
        return json.loads(path.read_text())
    tables = derive_tables(model)
    tmp = path.with_suffix(f".tmp{os.getpid()}")
    tmp.write_text(json.dumps(tables))
    os.replace(tmp, path)
    return tables


class _Plan:
    """How a table source's entries are read from its evaluated expressions: built once per source.

    The distinct expressions (a ring repeats a few dozen over hundreds of entries) are
    compiled into one tuple expression, so a parameter change costs one ``eval``; every
    table is then gathered from that vector by index arrays made here.
    """

    def __init__(self, tables: dict):
        texts = sorted(_expressions(tables))
        self.code = compile(f"({''.join(t + ',' for t in texts)})", "<tables>", "eval")
        at = {t: k for k, t in enumerate(texts)}

        def index(items):
            return np.array([at[t] for t in items], dtype=np.int64)

        self.n = n = len(tables["coordinates"])
        self.inertia = index(tables["inertia"])
        self.K = _CsrPattern(tables["stiffness"], n, index)
        self.C = _CsrPattern(tables["damping"], n, index)
        forcing, constant = tables["forcing"], tables["constant"]
        self.fi = np.array([e[0] for e in forcing] + [e[0] for e in constant], dtype=np.int64)
        self.fa, self.fw, self.fph = (index([e[k] for e in forcing]) for k in (1, 2, 3))
        self.const = index([e[1] for e in constant])
        cs = tables["contacts"]
        nc = len(cs)
        self.gap, self.k = index([c["gap"] for c in cs]), index([c["k"] for c in cs])
        self.c, self.N0 = index([c.get("c", "0") for c in cs]), index([c.get("N0", "0") for c in cs])
        # tables cached before contacts had normal laws hold springs only
        kinds = {"spring": NK_SPRING, "damped": NK_DAMPED, "load": NK_LOAD}
        self.cnk = np.array([kinds[c.get("normal", "spring")] for c in cs], dtype=np.int64)
        self.cidx = -np.ones((nc, 4), dtype=np.int64)
        self.gn, self.gr = np.zeros((nc, 4), dtype=np.int64), np.zeros((nc, 4), dtype=np.int64)
        for j, c in enumerate(cs):
            for k, slot in enumerate(c["slots"]):
                self.cidx[j, k] = slot
                self.gn[j, k], self.gr[j, k] = at[c["gn"][k]], at[c["gr"][k]]
        self.slot = self.cidx >= 0
        self.slot_contact, self.slot_k = np.nonzero(self.slot)   # contact by contact, slots in order
        self.law_names = [list(c["law"]) for c in cs]
        self._law_positions: dict = {}

    def values(self, namespace: dict) -> np.ndarray:
        """Every distinct expression evaluated in ``namespace``, as :attr:`code` orders them."""
        return np.array([float(x) for x in eval(self.code, namespace)], dtype=float)

    def law_positions(self, param_order) -> np.ndarray:
        """``LP``: each contact's law parameters as positions in ``param_order``."""
        key = tuple(param_order)
        found = self._law_positions.get(key)
        if found is None:
            pos = {name: i for i, name in enumerate(param_order)}
            found = np.zeros((len(self.law_names), max([len(c) for c in self.law_names] + [1])), dtype=np.int64)
            for j, names in enumerate(self.law_names):
                for k, name in enumerate(names):
                    found[j, k] = pos[name]
            self._law_positions[key] = found
        return found


class _CsrPattern:
    """The summed ``(row, col, value)`` entries of a linear table, as CSR arrays once the values are known."""

    def __init__(self, entries, n: int, index):
        self.n = n
        keys = np.array([i * n + j for i, j, _ in entries], dtype=np.int64)
        self.pairs, self.inverse = np.unique(keys, return_inverse=True)   # sorted by row, then column
        self.value = index([e[2] for e in entries])

    def arrays(self, vals: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(ptr, col, val)``, entries that sum to zero left out."""
        n = self.n
        summed = np.bincount(self.inverse, weights=vals[self.value], minlength=self.pairs.size) \
            if self.pairs.size else np.zeros(0)
        kept = summed != 0.0
        rows, col = np.divmod(self.pairs[kept], n) if n else (np.zeros(0, dtype=np.int64),) * 2
        ptr = np.zeros(n + 1, dtype=np.int64)
        ptr[1:] = np.cumsum(np.bincount(rows, minlength=n))
        return ptr, col.astype(np.int64), summed[kept]


#: :class:`_Plan` of table sources, by the source's ``id``; each entry holds its source so that the ``id`` is not
#: reused while the entry lives
_PLANS: dict = {}
_MOST_PLANS = 64


def _plan_of(tables: dict) -> _Plan:
    entry = _PLANS.get(id(tables))
    if entry is None or entry[0] is not tables:
        if len(_PLANS) >= _MOST_PLANS:
            _PLANS.clear()
        entry = _PLANS[id(tables)] = (tables, _Plan(tables))
    return entry[1]


class NumericTables:
    """The tables of one model at one parameter set, as the kernel takes them.

    Parameters
    ----------
    tables : dict
        From :func:`cached_tables`.
    values : dict
        Parameter values by name (``model.parameters``).
    law_kind : sequence of int
        Law kind of each contact in the generated module.
    state_offset : sequence of int
        Offset of each contact's law states after ``q`` and ``u``.
    n_law : int
        Number of law states in all.
    param_order : list of str
        Parameter names in ``p`` order.
    """

    def __init__(self, tables: dict, values: dict, law_kind, state_offset, param_order, n_law: int):
        plan = _plan_of(tables)
        vals = plan.values({**_NAMESPACE, **values})
        n = plan.n
        self.n = n
        inertia = vals[plan.inertia]
        if not np.all(inertia != 0.0):
            c = tables["coordinates"][int(np.argmin(inertia != 0.0))]
            raise ValueError(f"coordinate {c}: the inertia is zero")
        self.invm = 1.0 / inertia
        self.K = plan.K.arrays(vals)
        self.C = plan.C.arrays(vals)
        # a sin(w t + ph) = a cos(ph) sin(w t) + a sin(ph) cos(w t); a constant is the group w = 0, whose
        # sin(0) = 0 and cos(0) = 1 leave fc
        a, w, ph = vals[plan.fa], vals[plan.fw], vals[plan.fph]
        groups: list[float] = []
        fg = []
        for x in [*w.tolist(), *([0.0] * plan.const.size)]:   # groups in order of appearance
            if x not in groups:
                groups.append(x)
            fg.append(groups.index(x))
        fs = np.concatenate([a * np.cos(ph), np.zeros(plan.const.size)])
        fc = np.concatenate([a * np.sin(ph), vals[plan.const]])
        self.forcing = (plan.fi.copy(), np.array(fg, dtype=np.int64), fs, fc, np.array(groups, dtype=float))
        self.cidx = plan.cidx.copy()
        self.cgn = np.zeros(plan.cidx.shape)
        self.cgr = np.zeros(plan.cidx.shape)
        self.cgn[plan.slot] = vals[plan.gn[plan.slot]]
        self.cgr[plan.slot] = vals[plan.gr[plan.slot]]
        self.cgap, self.ck = vals[plan.gap], vals[plan.k]
        self.cnk = plan.cnk.copy()
        self.cc, self.cn0 = vals[plan.c], vals[plan.N0]
        self.LP = plan.law_positions(param_order).copy()
        #: each contact's relative-slip gradient in the coordinates (rows: contacts)
        nc = plan.cidx.shape[0]
        self.G = np.zeros((nc, n))
        j, k = plan.slot_contact, plan.slot_k
        np.add.at(self.G, (j, plan.cidx[j, k]), self.cgr[j, k])
        self.W = (self.G * self.invm) @ self.G.T
        self.claw = np.array(law_kind, dtype=np.int64)
        self.cso = np.array(state_offset, dtype=np.int64)
        self.p = np.array([values[name] for name in param_order], dtype=float)
        self.n_law = int(n_law)

    def stiffness_matrix(self) -> np.ndarray:
        """Dense ``K`` of the springs (for energies and checks)."""
        return _dense(*self.K, self.n)

    def damping_matrix(self) -> np.ndarray:
        """Dense ``C`` of the dampers."""
        return _dense(*self.C, self.n)


def _dense(ptr, col, val, n):
    out = np.zeros((n, n))
    for i in range(n):
        for e in range(ptr[i], ptr[i + 1]):
            out[i, col[e]] += val[e]
    return out


def _expressions(tables: dict) -> set:
    """The expression strings of a table source (:func:`derive_tables`)."""
    out = set(tables["inertia"])
    out.update(e[2] for e in tables["stiffness"])
    out.update(e[2] for e in tables["damping"])
    for _, a, w, ph in tables["forcing"]:
        out.update((a, w, ph))
    out.update(a for _, a in tables["constant"])
    for c in tables["contacts"]:
        out.update((c["gap"], c["k"], c.get("c", "0"), c.get("N0", "0")))
        out.update(c["gn"])
        out.update(c["gr"])
    return out
