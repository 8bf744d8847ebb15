"""The per-contact kernel: build or load the compiled module, set up a model, integrate.

Cache layout (in :func:`~blademodel.numeric.compiled.cache_dir`):

``ck_<kinds>_<code>.json``
    Index by the law kinds (their :meth:`structure` and class sources) and the
    sources that shape the generated code; it names the module file and holds its
    metadata.
``ck_<hash>.py``
    The generated module, named by the hash of its own text and of the Python,
    NumPy and Numba versions, so an edited law, template or library can never run
    a stale compiled kernel (Numba's cache is keyed by that file).
``tables_<structure>_<components>.json``
    The model's derived tables (:mod:`.contact_tables`).
"""

from __future__ import annotations

import copy
import hashlib
import json
import math
import os
from pathlib import Path

import numpy as np

from ..model import Model
from .compiled import PACKAGE, _load, cache_dir, hash_sources, law_source_hash, library_versions, package_sources
from .contact_tables import NumericTables, cached_tables
from . import contract
from .contract import N_COUNTERS, N_STATS
from .integrator import Integrator
from .methods import get_method

_MEMO: dict = {}


def _code_version() -> str:
    """Hash of the template, the generators, the contract and the package's friction laws."""
    from .contact_codegen import TEMPLATES
    here = PACKAGE / "numeric"
    return hash_sources([Path(m.__file__) for m in TEMPLATES]
                        + [here / n for n in ("contact_rigid_stubs.py", "contact_codegen.py", "law_codegen.py",
                                              "contract.py", "code_libraries.py")]
                        + package_sources("components/friction"))


def _module_name(source: str) -> str:
    """File name of a generated module: the hash of its text and of the library versions."""
    return f"ck_{hashlib.sha256((source + library_versions()).encode()).hexdigest()[:20]}.py"


def _law_key(law) -> str:
    return json.dumps([str(x) for x in law.structure()])


def law_kinds(model: Model) -> tuple[list, list[int]]:
    """One law instance per distinct :meth:`structure` (sorted), and each contact's kind."""
    keys = [_law_key(c.friction) for c in model.contacts]
    by_key: dict = {}
    for key, c in zip(keys, model.contacts):
        by_key.setdefault(key, c.friction)
    order = sorted(by_key)
    return [by_key[k] for k in order], [order.index(k) for k in keys]


def compile_contact_kernel(model: Model):
    """The compiled per-contact module for the law kinds of ``model`` and its metadata."""
    laws, _ = law_kinds(model)
    kinds_key = json.dumps([_law_key(law) for law in laws])
    key = hashlib.sha256(f"{kinds_key}|{law_source_hash(laws)}|{_code_version()}".encode()).hexdigest()[:16]
    if key in _MEMO:
        return _MEMO[key]
    folder = cache_dir()
    index = folder / f"ck_{key}.json"
    info = json.loads(index.read_text()) if index.exists() else None
    if info is not None:
        path = folder / info["file"]
        if not path.exists() or _module_name(path.read_text()) != path.name:
            info = None   # a module edited, damaged or built for other library versions
    if info is None:
        from .contact_codegen import generate_contact_kernel
        source, meta = generate_contact_kernel(laws)
        path = folder / _module_name(source)
        if not path.exists() or path.read_text() != source:
            tmp = path.with_suffix(f".tmp{os.getpid()}")
            tmp.write_text(source)
            os.replace(tmp, path)
        info = {"file": path.name, "meta": meta}
        tmp = index.with_suffix(f".tmp{os.getpid()}")
        tmp.write_text(json.dumps(info))
        os.replace(tmp, index)
    out = (_load(folder / info["file"]), info["meta"])
    _MEMO[key] = out
    return out


#: The longest phase table (``2 steps_per_period``) kept; finer steps evaluate sin and cos at every time.
MAX_PHASE_TABLE = 1 << 16


def phase_table(om, period: float | None, steps_per_period: int | None) -> tuple[list, list]:
    """``(tg, tab)``: the forcing's phase table (``R_TG``, ``R_TAB`` of :mod:`.contract`).

    ``tab`` holds ``sin(om_g * (k * hh))`` and ``cos(...)`` for ``k = 0 ... M - 1``,
    ``hh = period / (2 steps_per_period)``, ``M = 2 steps_per_period``: the forcing at
    the times of a period's steps and RK4 midpoints, libm's values (at the first
    period's step ends, where ``k hh`` equals the loop's time to the bit, the values
    ``math.sin`` gave the kernel before the table). NumPy evaluates them in one call
    (its float64 ``sin`` and ``cos`` give libm's values to the bit: the table's tests
    compare them with ``math.sin``, and a million random arguments agreed). Empty (``M = 0``)
    when some group's frequency is not a whole multiple of ``2 pi / period`` (the
    table would not repeat), without a period, or when it would be longer than
    :data:`MAX_PHASE_TABLE`.
    """
    none = [0.0, 0.0, 0.0], []
    if period is None or not steps_per_period or len(om) == 0:
        return none
    M = 2 * int(steps_per_period)
    if M > MAX_PHASE_TABLE:
        return none
    for w in om:
        m = w * period / (2.0 * math.pi)
        if abs(m - round(m)) > 1e-9 * max(1.0, abs(m)):
            return none
    hh = period / M
    tab = np.empty((len(om), M, 2))
    times = np.arange(M) * hh          # k * hh, as the loop forms them
    for g, w in enumerate(om):
        phase = w * times
        np.sin(phase, out=tab[g, :, 0])
        np.cos(phase, out=tab[g, :, 1])
    return [hh, 1.0 / hh, float(M)], tab.ravel()


def pack_tables(tables: NumericTables, n_state: int, method: str = "rk4", gmax: int = 1,
                period: float | None = None, steps_per_period: int | None = None) -> tuple[
        np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The flat arrays ``I``, ``R``, ``WI``, ``WF`` of the kernel (layout: :mod:`.contract`).

    ``method``: the stepping method (:mod:`.methods`); classical RK4 is written out in
    the kernel, any other enters as its tableau. ``gmax``: the most guards of a
    contact's mode (the generated module's ``GMAX``). ``period``, ``steps_per_period``:
    the step grid the forcing's phase table is for (:func:`phase_table`; without them,
    none). The integer tables and the work arrays' layout depend on the structure only
    and are built once for it (:func:`_structure`); a parameter change packs ``R``.
    """
    s = _structure(tables, n_state, method, gmax)
    header = s.header.copy()
    om = tables.forcing[4]
    fs, fc = tables.forcing[2][s.order], tables.forcing[3][s.order]
    tableau = np.zeros(0) if method == "rk4" else get_method(method).tableau()
    tg, tab = phase_table(om, period, steps_per_period)
    R = _pack(header, [tables.invm, tables.K[2], tables.C[2], fs, fc, om, tables.cgn, tables.cgr, tables.cgap,
                       tables.ck, tables.p, tables.W, tableau, tables.cc, tables.cn0, tg, tab],
              [*range(contract.R_INVM, contract.R_RK + 1), contract.R_CC, contract.R_N0, contract.R_TG,
               contract.R_TAB], np.float64, 0)
    return np.concatenate([header, s.ints]), R, s.WI.copy(), s.WF.copy()


def _pack(header, parts, keys, dtype, start) -> np.ndarray:
    """``parts`` flattened one after another from offset ``start``, each one's offset written to ``header[key]``."""
    chunks, pos = [], start
    for key, part in zip(keys, parts):
        part = np.ascontiguousarray(part, dtype=dtype).ravel()
        header[key] = pos
        chunks.append(part)
        pos += max(part.size, 1)
        if part.size == 0:
            chunks.append(np.zeros(1, dtype=dtype))
    return np.concatenate(chunks) if chunks else np.zeros(0, dtype=dtype)


class _Structure:
    """What :func:`pack_tables` builds from a model's structure alone: the header's integer and work offsets, the
    integer tables, the work arrays' initial contents and the forcing entries' order."""

    __slots__ = ("header", "ints", "WI", "WF", "order")


#: :class:`_Structure` by the structure's key (:func:`_structure`), a few kept
_STRUCTURES: dict = {}
_MOST_STRUCTURES = 64


def _structure(tables: NumericTables, n_state: int, method: str, gmax: int) -> _Structure:
    """The :class:`_Structure` of ``tables``: built once for every distinct structure and shared.

    The key holds every integer input (including which couplings ``W`` has: a value that
    falls to zero drops a coupling), so tables that differ in values only share one.
    """
    n, nc = tables.n, len(tables.cgap)
    Kp, Ki, _ = tables.K
    Cp, Ci, _ = tables.C
    fi, fg, _, _, om = tables.forcing
    parts = [np.asarray(a) for a in (Kp, Ki, Cp, Ci, fi, fg, tables.cidx, tables.claw, tables.cso, tables.LP,
                                     tables.cnk, np.asarray(tables.W) != 0.0)]
    key = (n, nc, len(om), tables.LP.shape, tables.n_law, method, gmax, n_state,
           *((a.dtype.str, a.shape, a.tobytes()) for a in parts))
    found = _STRUCTURES.get(key)
    if found is None:
        if len(_STRUCTURES) >= _MOST_STRUCTURES:
            _STRUCTURES.clear()
        found = _STRUCTURES[key] = _build_structure(tables, n_state, method, gmax)
    return found


def _build_structure(tables: NumericTables, n_state: int, method: str, gmax: int) -> _Structure:
    n, nc = tables.n, len(tables.cgap)
    m = max(nc, 1)
    Kp, Ki, _ = tables.K
    Cp, Ci, _ = tables.C
    fi, fg, _, _, om = tables.forcing
    if len(om) > contract.MAX_GROUPS:
        raise ValueError(f"the model's forces have {len(om)} distinct frequencies; the per-contact kernel takes "
                         f"at most {contract.MAX_GROUPS}")
    header = np.zeros(contract.H_SIZE, dtype=np.int64)
    header[contract.H_N], header[contract.H_NC], header[contract.H_NF] = n, nc, len(fi)
    header[contract.H_NG], header[contract.H_LPW] = len(om), tables.LP.shape[1]
    header[contract.H_NLAW] = tables.n_law
    header[contract.H_NS] = 0 if method == "rk4" else get_method(method).stages
    # contacts coupled through W (sharing a moved coordinate), per contact in ascending order (CSR)
    W = np.asarray(tables.W, dtype=float).reshape(nc, nc) if nc else np.zeros((0, 0))
    Wp, Wi = [0], []
    for j in range(nc):
        Wi += [k for k in range(nc) if k != j and W[j, k] != 0.0]
        Wp.append(len(Wi))
    # locality: forcing entries by coordinate, contacts by coordinate, coordinates coupled by K and C
    order = np.argsort(np.asarray(fi, dtype=np.int64), kind="stable")
    fi, fg = (np.asarray(a)[order] for a in (fi, fg))
    Fp = np.searchsorted(fi, np.arange(n + 1)) if len(fi) else np.zeros(n + 1, dtype=np.int64)
    touching: list[list[int]] = [[] for _ in range(n)]
    for j in range(nc):
        for i in sorted({int(i) for i in tables.cidx[j] if i >= 0}):
            touching[i].append(j)
    Dp, Di = _csr_lists(touching)
    coupled: list[set] = [set() for _ in range(n)]
    for p, ix in (Kp, Ki), (Cp, Ci):
        for i in range(n):
            for e in range(p[i], p[i + 1]):
                if ix[e] != i:
                    coupled[i].add(int(ix[e]))
                    coupled[int(ix[e])].add(i)
    Ap, Ai = _csr_lists([sorted(c) for c in coupled])
    s = _Structure()
    s.order = order
    s.ints = _pack(header, [Kp, Ki, Cp, Ci, fi, fg, tables.cidx, tables.claw, tables.cso, tables.LP, Wp, Wi,
                            tables.cnk, Fp, Dp, Di, Ap, Ai],
                   [*range(contract.O_KP, contract.O_WI + 1), contract.O_CNK, contract.O_FP, contract.O_DP,
                    contract.O_DI, contract.O_AP, contract.O_AI], np.int64, contract.H_SIZE)
    sizes = [n] + [m] * 9 + [contract.MAX_GROUPS, contract.MAX_GROUPS, contract.MAX_LAW_STATES, n_state, m * m,
                             m, 1, n, m, 3, m * gmax, m, m]
    s.WF = _pack(header, [np.zeros(k) for k in sizes],
                 [contract.F_F, contract.F_N, contract.F_ND, contract.F_V, contract.F_FR, contract.F_DL, contract.F_X,
                  contract.F_D, contract.F_NULL, contract.F_B, contract.F_SG, contract.F_CG, contract.F_Z,
                  contract.F_YEV, contract.F_L, contract.F_DR, contract.F_T, contract.F_FD, contract.F_XD,
                  contract.F_ACC, contract.F_GOFF, contract.F_TLAST, contract.F_NOISE],
                 np.float64, 0)
    s.WF[header[contract.F_T]] = math.nan   # the time of the forcing's sin and cos in F_SG, F_CG: none yet
    o_dof = contract.W_HEAD + contract.WC_COUNT * nc
    o_rows = o_dof + contract.WD_COUNT * n
    WI = np.zeros(o_rows + 2 * n_state, dtype=np.int64)
    WI[contract.W_HEAD + contract.WC_ALL * nc:contract.W_HEAD + (contract.WC_ALL + 1) * nc] = np.arange(nc)
    WI[o_dof + contract.WD_ALL * n:o_dof + (contract.WD_ALL + 1) * n] = np.arange(n)
    WI[o_rows + n_state:o_rows + 2 * n_state] = np.arange(n_state)
    WI[contract.W_FULL] = 1
    WI[contract.W_NULL] = -1
    s.WI = WI
    s.header = header
    return s


def _csr_lists(rows) -> tuple[np.ndarray, np.ndarray]:
    """``(p, i)`` of a CSR structure holding the lists ``rows``."""
    p = np.zeros(len(rows) + 1, dtype=np.int64)
    p[1:] = np.cumsum([len(r) for r in rows]) if rows else []
    return p, np.array([x for r in rows for x in r], dtype=np.int64)


class ContactIntegrator(Integrator):
    """Fixed-step RK4 with located events, every contact holding its own mode.

    The counterpart of :class:`~blademodel.numeric.integrator.HybridIntegrator` for
    any number of contacts: the compiled code depends only on the friction-law
    kinds, the model enters as numeric tables, and the hybrid mode is an integer
    array ``cm`` with one entry per contact (``0`` open, ``1..`` the law's modes).
    Rigid (Coulomb) stick is solved jointly over the sticking contacts at run time,
    and every event settles the rigid contacts by the friction complementarity
    problem (``docs/solver.md``).

    Parameters
    ----------
    model : Model
    steps_per_period, event_tol, max_events_per_step, energy, period, check_stability
        As for :class:`~blademodel.numeric.integrator.HybridIntegrator`.
    max_pivots : int
        Cap on pivots of one friction problem (an unresolved problem stops the run).
    detect_grazing : bool
        After every step without a crossing, look for a guard that crossed and came
        back within the step (a brief contact, a grazing touch) where the cubic Hermite
        interpolant of its values and rates says so, and locate it (counter
        ``grazing_events``). Guards with known rates only: the penetration.
    method : {"rk4", "rk8"}
        Stepping method (:mod:`~blademodel.numeric.methods`).
    local_events : bool
        Step each *cluster* (the coordinates and contacts coupled to a contact whose
        guard crossed) through its events on its own while the rest of the model
        keeps the whole step (the default: the work of an event grows with its
        cluster, not with the model); ``False`` takes every step of the whole model
        through every event, for comparison (``docs/solver.md``).
    event_location : {"predicted", "bisection"}
        How an event's bracket is shrunk: from predicted roots (the default here) or
        by bisection (:class:`~blademodel.numeric.integrator.HybridIntegrator`).
    """

    kernel = "contact"
    #: The integrator covers ``1 / period_fraction`` of the excitation period (in as many fewer steps): a tuned
    #: ring's map reduced by its symmetry (:mod:`blademodel.orbits.cyclic`). A new excitation period given to
    #: :meth:`with_parameter_values` is divided by it.
    period_fraction = 1

    def __init__(self, model: Model, *, steps_per_period: int = 1000, event_tol: float = 1e-10,
                 max_events_per_step: int = 100, energy: bool = False, period: float | None = None,
                 check_stability: bool = True, max_pivots: int | None = None, detect_grazing: bool = True,
                 event_location: str = "predicted", method: str = "rk4", local_events: bool = True):
        self._settings(model, steps_per_period, event_tol, max_events_per_step, period, check_stability)
        self.module, self.kmeta = compile_contact_kernel(model)
        laws, kind = law_kinds(model)
        self.kind = kind
        coords = list(model.coordinates)
        n = len(coords)
        offsets, pos = [], 0
        for c in model.contacts:
            offsets.append(pos)
            pos += len(c.friction.states)
        names = [label for label, _, _ in model.law_state_labels()]
        self.n_physical = 2 * n + pos
        self._layout = (offsets, pos)
        self._step_limits: dict = {}   # stable step by the modes' Jacobians, shared by with_parameters copies
        self.n_state = self.n_physical + (3 if energy else 0)
        self.energy = energy
        self.param_names = list(model.parameters)
        self._table_source = cached_tables(model)   # the structure's tables (expressions); values fill them in
        self.tables = NumericTables(self._table_source, model.parameters, kind, offsets, self.param_names, pos)
        self.meta = {"state": [*coords, *(f"v{c}" for c in coords), *names]
                     + (["W_in", "D_visc", "D_fric"] if energy else []),
                     "coordinates": coords, "params": self.param_names, "energy": energy,
                     "contacts": [c.name for c in model.contacts],
                     "contact_modes": [self.kmeta["kinds"][k]["modes"] for k in kind],
                     "contact_guards": [self.kmeta["kinds"][k]["guards"] for k in kind]}
        self.nc = len(model.contacts)
        self.detect_grazing = bool(detect_grazing)
        self.local_events = bool(local_events)
        from .integrator import check_event_location
        self.event_location = check_event_location(event_location)
        self.max_pivots = int(max_pivots) if max_pivots is not None else 4 * self.nc + 20
        self.method = get_method(method)
        self._pack()
        if max([len(k["states"]) for k in self.kmeta["kinds"]] + [0]) > contract.MAX_LAW_STATES:
            raise ValueError(f"a friction law has more than {contract.MAX_LAW_STATES} states")
        self._check_step()
        self._empty_log = self.log_buffer(0)

    def _pack(self) -> None:
        """The kernel's tables from ``self.tables``, and fresh work arrays."""
        self.I, self.R, self.WI, self.WF = pack_tables(self.tables, self.n_state, self.method.name, self.kmeta["gmax"],
                                                       self.period, self.steps_per_period)
        self.SC = np.zeros((contract.SC_ROWS + max(self.method.stages - 1, 0), self.n_state))
        self.GS = np.zeros((contract.GS_ROWS, max(self.nc, 1), self.kmeta["gmax"]))
        self._run_end = None
        self._digest = None   # flow_digest of these tables, taken at first use

    def _check_step(self) -> None:
        if self._check_stability:
            from .stability import check_step
            key = ("limit", self.flow_digest())
            if key not in self._step_limits:
                self._step_limits[key] = self.max_stable_step()
            h_max, which = self._step_limits[key]
            check_step(self.period, self.steps_per_period, h_max, which, self.method.name)

    def flow_digest(self) -> str:
        """A digest of everything the flow's right-hand side and guards read at ``t = 0``: the generated module,
        the integer tables and the values, without the excitation frequencies and the forcing's phase table (at
        ``t = 0`` every forcing term is ``A sin(phi)``, whatever its frequency) and without the parameters that
        no friction law reads (the frequency among them).

        Two integrators with the same digest have the same modes' matrices ``df/dy``
        (and so the same stable step): a continuation in the excitation frequency keeps it.
        Taken once per set of tables (the step's check and the tangent's kept matrices both ask).
        """
        if self._digest is None:
            self._digest = self._flow_digest()
        return self._digest

    def _flow_digest(self) -> str:
        I = self.I
        R = self.R[:int(I[contract.R_TG])].copy()   # the phase table (R_TG, R_TAB) last, left out
        R[int(I[contract.R_OM]):int(I[contract.R_GN])] = 0.0
        p = R[int(I[contract.R_P]):int(I[contract.R_P]) + self.tables.p.size]
        unread = np.ones(p.size, dtype=bool)
        unread[np.unique(self.tables.LP)] = False
        p[unread] = 0.0
        h = hashlib.sha1(self.module.__name__.encode())
        h.update(np.ascontiguousarray(I).tobytes())
        h.update(R.tobytes())
        return h.hexdigest()

    def _with_values_of(self, model: Model, period: float | None) -> "ContactIntegrator":
        return self.with_parameter_values([model.parameters[k] for k in self.param_names], period)

    def with_parameter_values(self, p_raw, period: float | None = None) -> "ContactIntegrator":
        """This integrator with the raw parameter values ``p_raw`` (in ``meta["params"]`` order).

        The cheap form of :meth:`with_parameters` for callers that know the values
        already (continuation, which moves one config field at every correction): no
        model is built. ``period`` is the new excitation period (ignored if the period
        was given explicitly; ``None`` keeps it; divided by :attr:`period_fraction`). The
        copy packs the values into tables of its own and checks the step from the modes'
        Jacobians, whose limit is computed
        once for each :meth:`flow_digest` and shared by every copy (the excitation
        frequency moves none).

        Raises
        ------
        ValueError
            If ``p_raw`` does not hold one finite value per parameter.
        StepTooLargeError
            If the step is unstable with the new parameters.
        """
        from .integrator import StructureMismatch, checked_parameter_values
        p_raw = checked_parameter_values(p_raw, self.param_names)
        new = copy.copy(self)
        if period is not None and not self._explicit_period:
            new.period = float(period) / self.period_fraction
        offsets, pos = self._layout
        values = dict(zip(self.param_names, p_raw.tolist()))
        new.tables = NumericTables(self._table_source, values, self.kind, offsets, self.param_names, pos)
        new._pack()
        if not np.array_equal(new.I, self.I):
            raise StructureMismatch("with_parameters: the model's tables are laid out differently "
                                    "(only parameter values may differ)")
        new._check_step()
        return new

    # --- modes and states ---------------------------------------------------------------------
    def record_buffer(self, n_records: int) -> tuple:
        """``(t, y, cm)`` arrays for ``n_records`` records (``advance(record=...)``)."""
        return (np.empty(n_records), np.empty((n_records, self.n_state)),
                np.empty((n_records, self.nc), dtype=np.int8))

    def mode_of(self, y: np.ndarray, t: float = 0.0) -> np.ndarray:
        """Contact modes of the state ``y`` (closed where the penetration is ``>= 0``).

        May apply entry resets and the stick projection to ``y``, in place.
        """
        cm = np.zeros(self.nc, dtype=np.int64)
        counters = np.zeros(N_COUNTERS, dtype=np.int64)
        self._clear_near_marks()
        if self.nc:
            ok = self.module.initial_modes(float(t), y, cm, self.I, self.R, self.WI, self.WF, self.GS[0], counters,
                                           self.max_pivots, *self._empty_log[:2])
            if not ok:
                raise RuntimeError("the friction problem of the initial state was not resolved")
        return cm

    def settle(self, y: np.ndarray, mode, t: float = 0.0) -> tuple[np.ndarray, list]:
        """The modes ``y`` starts in at ``t``: ``mode`` with every guard already on the side its mode forbids
        fired, and the friction problem of the rigid contacts solved (``contact_events.settle_start``).

        ``y`` may be reset in place (a transition's reset, the stick projection). A call of
        :meth:`advance` that starts from ``(y, modes)`` at ``t`` goes on with the marks the
        settling left (contacts a rounding error past a guard of their new mode).

        Returns
        -------
        modes : ndarray of int
        events : list of ``(contact, guard, from, to)``
            In the order they fired; ``guard`` ``-1`` for a mode the friction problem set.

        Raises
        ------
        RuntimeError
            Where the friction problem was not resolved.
        """
        cm = np.array(mode, dtype=np.int64).reshape(self.nc)
        self._clear_near_marks()
        if not self.nc:
            return cm, []
        log = self.log_buffer(2 * self.nc)
        counters = np.zeros(N_COUNTERS, dtype=np.int64)
        k = int(self.module.settle_start(float(t), y, cm, self.I, self.R, self.WI, self.WF, self.GS[0], counters,
                                         self.max_pivots, *log))
        if k < 0:
            raise RuntimeError(f"the friction problem of the state at t = {t:.6g} was not resolved")
        if k == 0:
            return cm, []
        self._run_end = (float(t), y.copy(), cm.copy())   # advance keeps the marks from here
        _, lc, lg, lf, lto = log
        return cm, [(int(lc[i]), int(lg[i]), int(lf[i]), int(lto[i])) for i in range(min(k, lc.shape[0]))]

    def _own_work_arrays(self) -> None:
        self.WI, self.WF, self.SC, self.GS = self.WI.copy(), self.WF.copy(), self.SC.copy(), self.GS.copy()
        self._clear_near_marks()

    def _clear_near_marks(self):
        """Forget the contacts marked as fired before their own root (``WC_NEAR``) and the times of the last
        transitions (``F_TLAST``): a run's hybrid state."""
        o = contract.W_HEAD + contract.WC_NEAR * self.nc
        self.WI[o:o + self.nc] = 0
        self.WI[contract.W_NNEAR] = 0
        o = contract.W_HEAD + contract.WC_SUSPECT * self.nc
        self.WI[o:o + self.nc] = 0
        o = self.I[contract.F_TLAST]
        self.WF[o:o + self.nc] = math.nan
        self._run_end = None

    def log_buffer(self, n: int) -> tuple:
        """``(t, contact, guard, from, to)`` arrays for an event log of ``n`` entries."""
        return (np.empty(n), *(np.empty(n, dtype=np.int64) for _ in range(4)))

    def named_events(self, log: tuple, n: int) -> dict:
        """The first ``n`` log entries by name: ``t``, ``contact``, ``guard`` and its ``from``/``to`` modes.

        A mode set by the friction problem has the guard ``"<contact>: friction problem"``.
        """
        names, cmodes, cguards = self.meta["contacts"], self.meta["contact_modes"], self.meta["contact_guards"]
        log_t, log_c, log_g, log_f, log_to = log
        one = len(names) == 1

        def local(j, m):
            return cmodes[j][m] if one else f"{names[j]}={cmodes[j][m]}"
        return {"t": log_t[:n].copy(),
                "contact": [names[j] for j in log_c[:n]],
                "guard": [f"{names[j]}: " + (cguards[j][f][g] if g >= 0 else "friction problem")
                          for j, g, f in zip(log_c[:n], log_g[:n], log_f[:n])],
                "from": [local(j, m) for j, m in zip(log_c[:n], log_f[:n])],
                "to": [local(j, m) for j, m in zip(log_c[:n], log_to[:n])]}

    def mode_table(self, rec_cm: np.ndarray, final_cm) -> tuple[list, np.ndarray, int]:
        """Names of the mode combinations met, the records as indices into them, the final one's index."""
        combos = [tuple(int(x) for x in row) for row in rec_cm]
        final = tuple(int(x) for x in final_cm)
        index: dict = {}
        for c in [*combos, final]:
            index.setdefault(c, len(index))
        return ([self.mode_label(c) for c in index], np.array([index[c] for c in combos], dtype=np.int64),
                index[final])

    def mode_label(self, cm) -> str:
        """``"c1=stick,c2=open"`` (the law mode's name alone for one contact; ``"free"`` for none)."""
        names = self.meta["contacts"]
        modes = self.meta["contact_modes"]
        if not names:
            return "free"
        if len(names) == 1:
            return modes[0][int(cm[0])]
        return ",".join(f"{c}={modes[j][int(m)]}" for j, (c, m) in enumerate(zip(names, cm)))

    # --- flow ----------------------------------------------------------------------------------
    def rhs(self, t: float, y: np.ndarray, cm) -> np.ndarray:
        """``dy/dt`` in the contact modes ``cm`` (factors the stick set; for checks, not speed)."""
        cm = np.asarray(cm, dtype=np.int64)
        out = np.empty(self.n_state)
        self.module.factor_stick(cm, self.I, self.R, self.WI, self.WF)
        self.module.rhs(float(t), np.asarray(y, dtype=float), cm, self.I, self.R, self.WI, self.WF, out)
        return out

    def contact_forces(self, t: float, y: np.ndarray, cm) -> tuple[np.ndarray, np.ndarray]:
        """Normal and friction force of every contact at ``(t, y)`` in modes ``cm``."""
        cm = np.asarray(cm, dtype=np.int64)
        self.module.factor_stick(cm, self.I, self.R, self.WI, self.WF)
        self.module.forces(float(t), np.asarray(y, dtype=float), cm, self.I, self.R, self.WI, self.WF)
        N0, f0 = self.I[contract.F_N], self.I[contract.F_FR]
        return self.WF[N0:N0 + self.nc].copy(), self.WF[f0:f0 + self.nc].copy()

    def max_stable_step(self) -> tuple[float, str]:
        """Largest stable step of the method over the open configuration and each closed mode of every law.

        The Jacobians are taken by finite differences of the (affine) flow at rest.
        A rigid stick mode is replaced by slip: a constraint cannot raise the
        highest natural frequency (Rayleigh), so slip bounds it.
        """
        from .stability import stable_step
        configs = [np.zeros(self.nc, dtype=np.int64)]
        kinds = self.kmeta["kinds"]
        depth = max([len(k["modes"]) for k in kinds] + [1])
        for m in range(1, depth):
            cm = np.zeros(self.nc, dtype=np.int64)
            for j, K in enumerate(self.kind):
                mm = min(m, len(kinds[K]["modes"]) - 1)
                if kinds[K]["rigid"] and mm == kinds[K]["rigid"][0]:
                    mm = kinds[K]["rigid"][1]
                cm[j] = mm
            configs.append(cm)
        n = self.n_physical
        best, which = math.inf, "-"
        for cm in configs:
            y0 = np.zeros(self.n_state)
            f0 = self.rhs(0.0, y0, cm)[:n]
            J = np.empty((n, n))
            for i in range(n):
                y1 = y0.copy()
                y1[i] = 1.0
                J[:, i] = self.rhs(0.0, y1, cm)[:n] - f0
            key = hashlib.blake2b(J.tobytes(), digest_size=16).digest()   # not the matrix: 73 kB at 24 blades
            if key not in self._step_limits:
                if len(self._step_limits) >= 256:   # a continuation in a stiffness makes new ones at every value
                    self._step_limits.pop(next(iter(self._step_limits)))
                self._step_limits[key] = stable_step(J, self.method.amplification)
            h = self._step_limits[key]
            if h < best:
                best, which = h, self.mode_label(cm)
        return best, which

    # --- integration ------------------------------------------------------------------------------
    def advance(self, y: np.ndarray, mode, start_period: int, end_period: int, *, n_transient: int | None = None,
                record=None, forces=None, poincare=None, log=None, counters=None, stats=None,
                record_every: int = 1, check: bool = True) -> tuple[int, np.ndarray, float]:
        """Integrate periods ``start_period`` to ``end_period``; ``y`` is updated in place.

        Parameters
        ----------
        y : ndarray
        mode : array of int
            Contact modes (not modified; the new modes are returned).
        record : tuple of arrays, optional
            ``(t, y, cm)`` with ``cm`` of shape ``(n_records, n_contacts)`` (int8).
        forces : tuple of arrays, optional
            ``(N, f)`` of shape ``(n_records, n_contacts)``: each contact's forces per record.
        log : tuple of arrays, optional
            ``(t, contact, guard, from, to)``; ``guard`` is ``-1`` for a mode set by the
            friction problem.
        counters : ndarray of int64, optional
            ``contract.N_COUNTERS`` counters, accumulated.
        stats : ndarray of float, optional
            ``contract.N_STATS`` statistics (``max_cone_ratio``), accumulated.
        check : bool
            Validate the arguments first; only a caller whose arrays come from this
            integrator and whose mode it returned may skip it (the period map).

        Returns
        -------
        status, mode, t

        Raises
        ------
        ValueError
            For an argument the kernel cannot take
            (:func:`~blademodel.numeric.integrator.check_advance_arguments`).
        """
        from .integrator import check_advance_arguments, goes_on
        if check:
            check_advance_arguments(self, y, mode, start_period, end_period, n_transient, record=record, poincare=poincare,
                                    log=log, counters=counters, record_every=record_every, stats=stats, forces=forces)
        cm = np.array(mode, dtype=np.int64).reshape(self.nc)
        if y.shape != (self.n_state,):
            raise ValueError(f"y has shape {y.shape}, expected ({self.n_state},)")
        if counters is None:
            counters = np.zeros(N_COUNTERS, dtype=np.int64)
        if stats is None:
            stats = np.zeros(N_STATS)
        nrec = 0 if record is None else record[0].shape[0]
        rec_t, rec_y, rec_cm = record if record is not None else (
            np.empty(0), np.empty((0, self.n_state)), np.empty((0, self.nc), dtype=np.int8))
        rec_N, rec_f = forces if forces is not None else (np.empty((0, self.nc)), np.empty((0, self.nc)))
        if forces is not None and rec_N.shape[0] != nrec:
            raise ValueError("forces must have as many rows as the record")
        if poincare is None:
            # rows from the first recorded period on (n_transient = 0 is a period, not 'unset')
            first = start_period if n_transient is None else n_transient
            poincare = np.empty((max(end_period - first, 0), self.n_state))
        log_t, log_c, log_g, log_f, log_to = log if log is not None else self._empty_log
        # A contact fired before its own root reads its guards shifted until its next transition
        # (contact_guards.mark_near): hybrid state of the run, kept only where a call goes on from the
        # state and modes where the last one ended.
        if not goes_on(self._run_end, start_period, self.period, y, cm):
            self._clear_near_marks()
        status, t = self.module.integrate(
            y, cm, self.I, self.R, self.WI, self.WF, self.SC, self.GS, self.period, self.steps_per_period, int(start_period),
            int(end_period), int(start_period if n_transient is None else n_transient), int(record_every),
            self.event_tol, self.max_events_per_step, self.max_pivots, self.detect_grazing,
            self.event_location == "predicted", self.local_events, rec_t, rec_y, rec_cm, rec_N, rec_f, poincare,
            log_t, log_c, log_g, log_f, log_to, counters, stats)
        self._run_end = (float(t), y.copy(), cm.copy()) if status == 0 else None
        return int(status), cm, float(t)

    # --- energy -----------------------------------------------------------------------------------
    def mechanical_energy(self, y: np.ndarray, cm) -> float:
        """Kinetic + spring + closed-contact + friction-law energy of the state ``y``."""
        n = self.tables.n
        q, u = y[:n], y[n:2 * n]
        E = 0.5 * float(np.sum(u * u / self.tables.invm)) + 0.5 * float(q @ self.tables.stiffness_matrix() @ q)
        delta = np.array([sum(self.tables.cgn[j, k] * q[self.tables.cidx[j, k]] for k in range(4)
                              if self.tables.cidx[j, k] >= 0) - self.tables.cgap[j] for j in range(self.nc)])
        for j in range(self.nc):
            kind = self.tables.cnk[j]
            if kind == contract.NK_DAMPED:   # the spring holds k delta^2 / 2 in every mode (docs/components.md)
                E += 0.5 * self.tables.ck[j] * max(delta[j], 0.0) ** 2
            elif cm[j] != 0:
                E += (self.tables.cn0[j] * delta[j] if kind == contract.NK_LOAD
                      else 0.5 * self.tables.ck[j] * delta[j] ** 2)
            E += self.module.law_energy(self.kind[j], y, 2 * n + int(self.tables.cso[j]), self.R, self.I, j)
        return E

