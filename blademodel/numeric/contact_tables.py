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


def _csr(entries, n, values):
    """CSR arrays of summed ``(row, col, value)`` entries."""
    acc: dict = {}
    for (i, j, _), v in zip(entries, values):
        acc[(i, j)] = acc.get((i, j), 0.0) + v
    rows = [[] for _ in range(n)]
    for (i, j), v in sorted(acc.items()):
        if v != 0.0:
            rows[i].append((j, v))
    ptr = np.zeros(n + 1, dtype=np.int64)
    for i in range(n):
        ptr[i + 1] = ptr[i] + len(rows[i])
    col = np.array([j for r in rows for j, _ in r], dtype=np.int64)
    val = np.array([v for r in rows for _, v in r], dtype=float)
    return ptr, col, val


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
        ns = {**_NAMESPACE, **values}
        ev = _Evaluator(ns)
        n = len(tables["coordinates"])
        self.n = n
        self.invm = np.array([1.0 / ev(e) for e in tables["inertia"]])
        self.K = _csr(tables["stiffness"], n, [ev(e[2]) for e in tables["stiffness"]])
        self.C = _csr(tables["damping"], n, [ev(e[2]) for e in tables["damping"]])
        groups: list[float] = []
        fi, fg, fs, fc = [], [], [], []
        for i, a, w, ph in tables["forcing"]:
            a, w, ph = ev(a), ev(w), ev(ph)
            if w not in groups:
                groups.append(w)
            fi.append(i)
            fg.append(groups.index(w))
            fs.append(a * math.cos(ph))  # a sin(w t + ph) = a cos(ph) sin(w t) + a sin(ph) cos(w t)
            fc.append(a * math.sin(ph))
        for i, a in tables["constant"]:   # the group w = 0: fs sin(0) + fc cos(0) = fc
            if 0.0 not in groups:
                groups.append(0.0)
            fi.append(i)
            fg.append(groups.index(0.0))
            fs.append(0.0)
            fc.append(ev(a))
        self.forcing = (np.array(fi, dtype=np.int64), np.array(fg, dtype=np.int64), np.array(fs, dtype=float),
                        np.array(fc, dtype=float), np.array(groups, dtype=float))
        cs = tables["contacts"]
        nc = len(cs)
        self.cidx = -np.ones((nc, 4), dtype=np.int64)
        self.cgn = np.zeros((nc, 4))
        self.cgr = np.zeros((nc, 4))
        self.cgap = np.array([ev(c["gap"]) for c in cs], dtype=float)
        self.ck = np.array([ev(c["k"]) for c in cs], dtype=float)
        # tables cached before contacts had normal laws hold springs only
        kinds = {"spring": NK_SPRING, "damped": NK_DAMPED, "load": NK_LOAD}
        self.cnk = np.array([kinds[c.get("normal", "spring")] for c in cs], dtype=np.int64)
        self.cc = np.array([ev(c.get("c", "0")) for c in cs], dtype=float)
        self.cn0 = np.array([ev(c.get("N0", "0")) for c in cs], dtype=float)
        pos = {name: i for i, name in enumerate(param_order)}
        width = max([len(c["law"]) for c in cs] + [1])
        self.LP = np.zeros((nc, width), dtype=np.int64)
        for j, c in enumerate(cs):
            for k, s in enumerate(c["slots"]):
                self.cidx[j, k] = s
                self.cgn[j, k] = ev(c["gn"][k])
                self.cgr[j, k] = ev(c["gr"][k])
            for k, name in enumerate(c["law"]):
                self.LP[j, k] = pos[name]
        #: each contact's relative-slip gradient in the coordinates (rows: contacts)
        self.G = np.zeros((nc, n))
        for j in range(nc):
            for k in range(4):
                if self.cidx[j, k] >= 0:
                    self.G[j, self.cidx[j, k]] += self.cgr[j, k]
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


class _Evaluator:
    """Evaluate expression strings with compiled code objects, memoised."""

    _code: dict = {}

    def __init__(self, namespace: dict):
        self.ns = namespace

    def __call__(self, text: str) -> float:
        code = self._code.get(text)
        if code is None:
            code = self._code[text] = compile(text, "<table>", "eval")
        return float(eval(code, self.ns))
