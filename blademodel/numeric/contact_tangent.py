"""The monodromy matrix of the per-contact kernel's period map, replayed from its record and event log.

Every mode of a per-contact model is affine in the state: the structure is linear
(:mod:`.contact_tables`), a contact's normal law is a spring, a damped spring or a
constant load, and each friction law's force is linear within a mode (Coulomb's
rigid stick is a linear constraint, solved jointly). Along a recorded run the
kernel's discrete map is then differentiated exactly, up to the difference
quotients named below, as the product of

* the Runge-Kutta step's Jacobian of each whole step, the method's stability
  polynomial ``R(h A)`` of the mode's constant ``A = df/dy`` (taken once per mode by
  differences of ``rhs``, exact for an affine flow up to rounding);
* at each event, the discrete saltation matrix: the sub-step to the event, whose
  end time moves with the start state as the guard ``g(t_e, y_e) = 0`` requires
  (``dt_e = -g_y W / (g_t + g_y Phi_h)``, ``Phi_h`` the sub-step's derivative in its
  length), the transition's reset (a law state set to zero), the kernel's velocity
  projection onto the stick constraints where a rigid contact starts to stick, and
  the sub-step from the event to the end of the step, whose start time moved.

The kernel steps each *cluster* of an event through its sub-steps while the rest of
the model keeps the whole step (:mod:`.contact_loop`); the replay does the same:
the rows coupled to a step's event contacts (the connected component of the modes'
``A`` and the contacts' coordinates) take the sub-steps, the others ``R(h A)``.
Guard gradients are differences of the compiled guards at the zero state, as ``A`` is
(affine within a mode, so their error is rounding; checked at each event), reset
Jacobians central differences of the compiled transitions at the event; the sub-steps'
derivatives in their start time and length follow from the stages, ``A`` and the
forcing's rate ``b'(t)``, a central difference in time (its error, about ``1e-12``
relative, is far below what a difference quotient of the whole map resolves). A
mode whose flow is not affine (a law whose force is nonlinear within a mode) is
found by a probe and refused (:class:`ContactTangentError`): the period map then
falls back to differences.

A law with labels (the Iwan elements' modes, ``discrete_states``) is affine for given
labels: the matrices are kept by mode and labels, nothing is differentiated in a label
(their rows and columns are held), and its resets are taken as the kernel decided them
(:meth:`ContactTangent._reset_jacobian`): past the guard's root, with the labels the
record shows, differentiated with those decisions fixed.
"""

from __future__ import annotations

from collections import OrderedDict, namedtuple

import numpy as np

from .blas_threads import blas_threads_for
from .contact_flow_pattern import flow_pattern, grouped_flow_matrix
from .kept import Kept as _Kept
from .tangent import SensitivityError

#: The modes' matrices and guard gradients of the last few models, by what they are computed from
#: (:meth:`~blademodel.numeric.contact_kernel.ContactIntegrator.flow_digest`): a continuation in the
#: excitation frequency reuses them from point to point, and a kept one is the one a fresh computation
#: would give, bit for bit, so a branch does not depend on what was computed before it.
_CACHES: OrderedDict = OrderedDict()
_KEEP = 4
#: The most bytes the modes' matrices ``A`` of one model may hold; the guard gradients, clusters, projections and
#: resets get an eighth of it each, the powers of ``A`` (:data:`POWERS_BELOW`) and of its blocks a quarter, a
#: sparse ``A``'s powers on their pattern (:data:`SPARSE_STEPS_FROM`) another quarter, and the compiled cluster
#: steps' plans a half (an Iwan ring's are keyed by its labels too: a 24-blade ring's period holds 66 MB).
#: A long continuation of a ring meets thousands of modes (4888 on the
#: 24-blade ring from 270 to 300 rad/s, 360 MB of dense ``A``; from :data:`GROUPED_FROM` states on they are
#: sparse, 22-28 kB each at 96 blades, where dense they were 1.2 MB and a period's 2672 overflowed the budget).
KEEP_BYTES = 1 << 29
#: From this many physical states on (rings of 32 blades), a mode's ``A`` is taken by column groups
#: (:mod:`.contact_flow_pattern`) and kept as a sparse matrix (a 96-blade ring's is 1.1 % nonzero: 22 kB a mode
#: instead of 1.2 MB). Below, column by column and dense, as the grouping's own work and the sparse products'
#: overhead cost more than they save there (``benchmarks/ring_tangent.py``: 0.7-0.95 times as fast cold at 8 to
#: 24 blades, 1.2 times as fast at 48, 2.2-2.4 cold and 4.8-5.0 warm at 96).
GROUPED_FROM = 128
#: Below this many physical states (where ``A`` is dense), a whole step's ``R(hA)`` is assembled from the mode's
#: kept powers ``A, A^2, ..., A^d`` (:func:`amplification_powers`): one combination of ``d`` arrays instead of the
#: ``d - 1`` products of Horner's rule. ``A`` does not depend on the step, which moves with the excitation
#: frequency from point to point of a continuation, so the powers are reused where ``R(hA)`` is not
#: (``benchmarks/ring_step_matrices.py``). Sparse ``A`` keeps Horner's rule below :data:`SPARSE_STEPS_FROM` states,
#: and from there its powers kept on their pattern (:func:`sparse_amplification_powers`).
POWERS_BELOW = GROUPED_FROM
#: From this many physical states on (where ``A`` is sparse), a whole step's ``R(hA)`` is sparse too: its
#: polynomial of degree ``d`` couples each blade only to the ``d`` blades either side (11 nonzeros a row on the
#: 48- and 96-blade rings' RK4 steps), so its product with the monodromy's columns costs a fraction of the dense
#: one, and a short run of whole steps is cheaper as that many sparse products than as a dense power. It is
#: assembled from the mode's powers of ``A`` kept on their pattern (:func:`sparse_amplification_powers`): Horner's
#: rule in sparse products costs more than a whole step's product (``benchmarks/ring_sparse_steps.py``).
SPARSE_STEPS_FROM = 160
#: A sparse step matrix denser than this is made dense, its powers not kept (a safeguard: RK8's polynomial, of
#: degree 12, leaves the mistuned 40-blade ring's steps 10 % nonzero, RK4's 6.5 %).
SPARSE_STEPS_DENSITY = 0.25
#: Runs of whole steps up to this long are applied step by step where the step matrix is sparse; longer ones by
#: the dense power (squarings), which costs a product for each bit of the run's length.
SPARSE_RUN_MAX = 16

#: Step a cluster through its events in compiled code (``cluster_step`` of :mod:`.contact_replay`; laws with labels
#: from plans of the Python step's decisions); with False in Python (:meth:`ContactTangent._cluster_step`, the
#: reference the compiled step is tested against).
COMPILED_CLUSTER_STEPS = True

#: Clusters of up to this many rows are stepped compiled; larger ones (a ring that sticks closed is one cluster) in
#: Python, whose products of the cluster's size go to BLAS: the compiled step's are loops, its work the cube of the
#: cluster's rows (measured on preloaded rings stuck closed: one replay 17.1 against 18.4 ms in Python at 48 rows,
#: 22.8 against 16.2 ms at 96).
COMPILED_CLUSTER_ROWS = 64


#: A step's plan for the compiled ``cluster_step`` (:meth:`ContactTangent._cluster_plan`): where each transition
#: group starts among the step's events, then the arrays that function takes, by its names.
ClusterPlan = namedtuple("ClusterPlan", "starts gfc gfg goff gmc gmto gmg mlo mn Ab proj PB gyr rk RB RM lfo lrow ltg")


def _caches(integrator) -> dict:
    """The kept matrices of ``integrator``'s model and values (its ``flow_digest``)."""
    key = integrator.flow_digest()
    c = _CACHES.pop(key, None) or {"A": _Kept(KEEP_BYTES), "gy": _Kept(KEEP_BYTES // 8),
                                   "clusters": _Kept(KEEP_BYTES // 8),
                                   "checked": set(), "projections": _Kept(KEEP_BYTES // 8), "pattern": [],
                                   "ungrouped": set(), "resets": _Kept(KEEP_BYTES // 8),
                                   "powers": _Kept(KEEP_BYTES // 4), "sparse_powers": _Kept(KEEP_BYTES // 4),
                                   "plans": _Kept(KEEP_BYTES // 2)}
    _CACHES[key] = c
    while len(_CACHES) > _KEEP:
        _CACHES.popitem(last=False)
    return c


class ContactTangentError(SensitivityError):
    """The replay cannot differentiate this run (a grazing event, or a mode that is not affine)."""


def stability_matrix(hA: np.ndarray, coefficients: np.ndarray) -> np.ndarray:
    """``d y1 / d y0`` of one explicit Runge-Kutta step of the affine flow ``y' = A y + b(t)``: ``R(hA)``.

    ``coefficients``: the method's stability polynomial, lowest power first
    (:meth:`~blademodel.numeric.methods.Method.amplification_coefficients`).
    """
    m = hA.shape[0]
    out = coefficients[-1] * hA   # Horner, its first product (hA times a multiple of I) written out
    if hasattr(out, "toarray"):   # a sparse hA: the products hA @ out are sparse times dense
        out = out.toarray()
    out.flat[::m + 1] += coefficients[-2]
    for c in coefficients[-3::-1]:
        out = hA @ out
        out.flat[::m + 1] += c
    return out


def sparse_stability_matrix(hA, coefficients: np.ndarray):
    """:func:`stability_matrix` of a sparse ``hA`` by Horner's rule in sparse products, sparse (CSR) unless it is
    denser than :data:`SPARSE_STEPS_DENSITY` (then dense). The replay assembles ``R(hA)`` from kept powers instead
    (:func:`sparse_stability_matrix_from_powers`); this is what they are checked and measured against."""
    from scipy.sparse import csr_matrix, identity
    hA = csr_matrix(hA)
    eye = identity(hA.shape[0], format="csr")
    out = coefficients[-1] * hA + coefficients[-2] * eye
    for c in coefficients[-3::-1]:
        out = hA @ out + c * eye
    out = csr_matrix(out)
    if out.nnz > SPARSE_STEPS_DENSITY * out.shape[0] * out.shape[1]:
        return out.toarray()
    return out


def sparse_amplification_powers(A, degree: int) -> tuple:
    """``A, A^2, ..., A^degree`` of a sparse ``A`` on one pattern, that of their sum with the identity:
    ``(P, indices, indptr, diagonal)``, ``P`` their values, a ``(degree, nnz)`` array, on the CSR pattern
    ``indices, indptr``, and ``diagonal`` the positions of its diagonal entries."""
    from scipy.sparse import csr_matrix, identity
    A = csr_matrix(A)
    n = A.shape[0]
    powers = [A]
    for _ in range(1, degree):
        powers.append(A @ powers[-1])
    pattern = identity(n, format="csr")
    for M in powers:
        M = M.copy()
        M.data[:] = 1.0   # the structure (a sum could cancel an entry)
        pattern = pattern + M
    pattern.sort_indices()
    rows = np.repeat(np.arange(n), np.diff(pattern.indptr))
    keys = rows * n + pattern.indices
    P = np.zeros((degree, keys.size))
    for k, M in enumerate(powers):
        M = M.tocoo()
        P[k, np.searchsorted(keys, M.row.astype(np.int64) * n + M.col)] = M.data
    diagonal = np.searchsorted(keys, np.arange(n) * (n + 1))
    return P, pattern.indices.copy(), pattern.indptr.copy(), diagonal


def sparse_stability_matrix_from_powers(powers: tuple, h: float, coefficients: np.ndarray):
    """:func:`sparse_stability_matrix` of ``h A`` from ``A``'s powers on their pattern
    (:func:`sparse_amplification_powers`): one combination of the scaled coefficients with them, sparse."""
    from scipy.sparse import csr_matrix
    P, indices, indptr, diagonal = powers
    degree = P.shape[0]
    n = indptr.size - 1
    data = (coefficients[1:degree + 1] * h ** np.arange(1, degree + 1)) @ P
    data[diagonal] += coefficients[0]
    return csr_matrix((data, indices, indptr), shape=(n, n))


def _csr_entries(A, rows: np.ndarray):
    """The entries of a canonical CSR matrix ``A`` in ``rows`` and columns ``rows`` (sorted, distinct): their
    positions in ``A``'s arrays, rows and columns within ``rows``, in ``A``'s order."""
    starts = A.indptr[rows]
    counts = A.indptr[rows + 1] - starts
    at = np.repeat(starts - (np.cumsum(counts) - counts), counts) + np.arange(int(counts.sum()))
    where = np.full(A.shape[1], -1, dtype=np.int64)
    where[rows] = np.arange(rows.size)
    cols = where[A.indices[at]]
    inside = cols >= 0
    return at[inside], np.repeat(np.arange(rows.size), counts)[inside], cols[inside]


def csr_block(A, rows: np.ndarray) -> np.ndarray:
    """The dense block ``A[rows][:, rows]`` of a CSR matrix (``rows`` sorted, distinct), read from its arrays.

    What scipy's fancy indexing gives, without its checks and intermediate matrices (a
    fifth of its time on a 60-row block of an Iwan ring's ``A``, taken thousands of times a
    replay). A matrix with duplicate entries is indexed by scipy, which sums them."""
    if not A.has_canonical_format:
        return A[rows][:, rows].toarray()
    at, r, c = _csr_entries(A, rows)
    out = np.zeros((rows.size, rows.size))
    out[r, c] = A.data[at]
    return out


def csr_submatrix(A, rows: np.ndarray):
    """:func:`csr_block`, sparse: ``A[rows][:, rows]`` as a CSR matrix with the same entries in the same order."""
    from scipy.sparse import csr_matrix
    if not A.has_canonical_format:
        return A[rows][:, rows]
    at, r, c = _csr_entries(A, rows)
    indptr = np.zeros(rows.size + 1, dtype=A.indptr.dtype)
    np.cumsum(np.bincount(r, minlength=rows.size), out=indptr[1:])
    return csr_matrix((A.data[at], c.astype(A.indices.dtype), indptr), shape=(rows.size, rows.size))


def continuous_block(M, c: np.ndarray):
    """``M[c][:, c]``, dense or CSR (:func:`csr_submatrix`)."""
    return csr_submatrix(M, c) if hasattr(M, "toarray") else M[np.ix_(c, c)]


def amplification_powers(A: np.ndarray, degree: int) -> np.ndarray:
    """``A, A^2, ..., A^degree`` of a dense square ``A``, each flattened: a ``(degree, n * n)`` array."""
    n = A.shape[0]
    P = np.empty((degree, n * n))
    Ak = np.asarray(A, dtype=float)
    P[0] = Ak.ravel()
    for k in range(1, degree):
        Ak = A @ Ak
        P[k] = Ak.ravel()
    return P


def stability_matrix_from_powers(P: np.ndarray, h: float, coefficients: np.ndarray) -> np.ndarray:
    """:func:`stability_matrix` of ``h A`` from ``A``'s powers ``P`` (:func:`amplification_powers`, to the
    polynomial's degree): ``sum_k c_k h^k A^k`` as one product of the scaled coefficients with ``P``."""
    degree = P.shape[0]
    n = int(round(P.shape[1] ** 0.5))
    c = coefficients[1:degree + 1] * h ** np.arange(1, degree + 1)
    out = (c @ P).reshape(n, n)
    out.flat[::n + 1] += coefficients[0]
    return out


class ContactTangent:
    """The replayed tangent of a :class:`~blademodel.numeric.contact_kernel.ContactIntegrator`'s runs.

    Parameters
    ----------
    integrator : ContactIntegrator
        The integrator whose runs are differentiated; its parameters must not change
        while this object is used (the modes' matrices are kept).
    """

    def __init__(self, integrator):
        if getattr(integrator, "kernel", "") != "contact":
            raise ValueError("ContactTangent differentiates the per-contact kernel's runs only")
        self.ig = integrator
        self.mod = integrator.module
        self.n = integrator.n_physical
        self.tables = integrator.tables
        self.nq = self.tables.n
        self.nc = len(self.tables.claw)
        method = integrator.method
        self._b, self._a, self._c = method.b, method.A, method.c
        self._poly = method.amplification_coefficients()
        caches = _caches(integrator)
        self._A, self._gy = caches["A"], caches["gy"]
        self._large = self.n >= GROUPED_FROM
        if self._large and not caches["pattern"]:
            caches["pattern"].append(flow_pattern(self.tables, self.n, [int(self.mod.NSTATES[int(K)])
                                                                        for K in self.tables.claw]))
        self._pattern = caches["pattern"][0] if self._large else None
        mod = self.mod
        # by law and mode: a rigid stick (the law's stick mode that its stick force holds rigidly)
        self._stick_table = (mod.IS_STICK != 0) & (np.arange(mod.IS_STICK.shape[1])[None, :] == mod.RIGID[:, :1])
        self._ungrouped: set = caches["ungrouped"]   # modes whose grouped A failed the probe: built column by column
        self._checked: set = caches["checked"]   # modes whose kept matrix was checked for affinity
        #: the friction laws' discrete states (labels, held: :func:`~blademodel.orbits.period_map.hold_discrete`),
        #: by contact; a mode's flow is affine for given labels, so its matrices are kept by mode and labels
        self._labels = np.asarray(getattr(integrator, "discrete_states", ()), dtype=np.int64)
        self._probe = np.random.default_rng(0).uniform(-1.0, 1.0, self.n)
        self._probe[self._labels] = 0.0   # a probe moves no label (a label a little off 0 reads as slip)
        self._factored = None   # the contact modes the stick problem in the work arrays is factored for
        self._cluster_sets, self._projections = caches["clusters"], caches["projections"]
        self._resets = caches["resets"]   # labelled laws' reset Jacobians, by contact, guard, mode and labels
        self._reset_sets: dict = {}   # the resets' rows and columns, by contact and cluster (:meth:`_reset_rows`)
        self._plans = caches["plans"]   # the compiled cluster steps' (:meth:`_cluster_plan`)
        self._cluster_work: dict = {}   # their work arrays, by the cluster's size
        #: compiled cluster steps taken on the whole model (0) and on the kernel's cluster alone (1), and those
        #: whose recorded labels a transition did not set, stepped in Python (2)
        self.cluster_steps = [0, 0, 0]
        # the modes' powers of A and of its blocks (the blocks themselves the first), from which R(hA) is assembled
        # at any step
        self._powers_of_A = caches["powers"]
        self._sparse_powers = caches["sparse_powers"]   # a sparse A's, on their pattern (SPARSE_STEPS_FROM)
        # else a whole step's R(hA) from a sparse A's powers on their pattern, or by Horner's rule
        self._whole_by_powers = self.n < POWERS_BELOW and not self._large
        self._sparse_steps = self._large and self.n >= SPARSE_STEPS_FROM
        self._R = _Kept(KEEP_BYTES // 8)   # the step matrices R(hA) of this integrator's step
        self._powers = _Kept(KEEP_BYTES // 8)   # their powers, for runs of whole steps without events
        self._G = np.zeros_like(integrator.GS[0])
        self._rows = [self._contact_rows(j) for j in range(self.nc)]
        self._contact_labels = [np.intersect1d(self._law_rows(j), self._labels) for j in range(self.nc)]
        self._stateless = [int(self.mod.NSTATES[int(K)]) == 0 for K in self.tables.claw]   # by contact: no reset
        self._most_states = max([int(x) for x in self.mod.NSTATES] + [1])
        # with labels, the replay carries the continuous states only: no matrix couples them to a label (its rows
        # and columns are zero), and the labels' block is held (a third of an Iwan ring's states, so the products
        # cost (2/3)^3 of the whole)
        self._continuous = np.setdiff1d(np.arange(self.n), self._labels)
        self._local = np.full(self.n, -1, dtype=np.int64)
        self._local[self._continuous] = np.arange(self._continuous.size)
        self._tableau = tuple(np.ascontiguousarray(x, dtype=float) for x in (method.A, method.b, method.c))
        s, ns = self._b.size, integrator.n_state
        # the compiled sub-step's work arrays: stages (full rows), their derivatives (cluster rows), states
        self._work = (np.zeros((s, ns)), np.zeros((s, self.n)), np.zeros((s, self.n)), np.zeros((s, self.n)),
                      np.zeros(ns), np.zeros(ns), np.zeros(ns))

    # --- the pieces -------------------------------------------------------------------------------
    def _contact_rows(self, j: int) -> list:
        """The state rows of contact ``j``'s coordinates: positions, then velocities."""
        q = sorted({int(i) for i in self.tables.cidx[j] if i >= 0})
        return q + [self.nq + i for i in q]

    def _law_rows(self, j: int) -> np.ndarray:
        """The state rows of contact ``j``'s law states."""
        return np.arange(int(self.mod.NSTATES[int(self.tables.claw[j])])) + 2 * self.nq + int(self.tables.cso[j])

    def _key(self, cm, y) -> bytes:
        """What a mode's kept matrices are keyed by: its contact modes, and the labels of ``y`` where the laws have
        any."""
        if not self._labels.size:
            return cm.tobytes()
        return cm.tobytes() + np.rint(y[self._labels]).astype(np.int8).tobytes()

    def _factor(self, cm) -> None:
        """The stick problem of ``cm`` factored in the work arrays (once for consecutive calls in one mode)."""
        key = cm.tobytes()
        if self._factored != key:
            ig = self.ig
            self.mod.factor_stick(cm, ig.I, ig.R, ig.WI, ig.WF)
            self._factored = key

    def _rhs(self, t, y, cm):
        """``dy/dt`` in ``cm``."""
        ig = self.ig
        self._factor(cm)
        out = np.empty(ig.n_state)
        self.mod.rhs(float(t), y, cm, ig.I, ig.R, ig.WI, ig.WF, out)
        return out

    @staticmethod
    def _linear_along(f, y, probe, predicted, tol: float = 1e-7) -> bool:
        """Whether ``f(y + probe) - f(y - probe)`` is ``2 predicted`` (a kept derivative along the probe), to ``tol``."""
        change = np.atleast_1d(f(y + probe) - f(y - probe))
        size = np.max(np.abs(change)) + np.max(np.abs(predicted))
        return bool(np.max(np.abs(change - 2.0 * np.atleast_1d(predicted))) <= tol * size)

    @staticmethod
    def _columns(f, y, indices, steps) -> np.ndarray:
        """Central differences of ``f`` in the states ``indices`` of ``y`` (a column each, ``f``'s shape by index)."""
        cols = []
        for i, e in zip(indices, steps):
            yp = y.copy()
            yp[i] += e
            ym = y.copy()
            ym[i] -= e
            cols.append((f(yp) - f(ym)) / (2 * e))
        return np.array(cols).T

    def flow_matrix(self, cm, y) -> np.ndarray:
        """``A = df/dy`` of the physical states in the contact modes ``cm`` (kept per mode).

        Built from ``n + 1`` calls of ``rhs`` at the zero state (with ``y``'s labels, where the laws have any:
        kept by mode and labels, its labels' rows and columns zero). Before its first use
        (for these values, whatever the excitation frequency: the check is kept with
        ``A``) the flow's change along a probe direction at ``y`` (a state where the
        mode holds) is checked against ``A``: a mode that is not affine (a friction law
        whose force is not linear within a mode) raises :class:`ContactTangentError`.
        """
        key = self._key(cm, y)
        A = self._A.get(key)
        if A is None:
            A = self._A[key] = self._build_flow_matrix(cm, y)
        if key not in self._checked:
            agrees = self._flow_agrees(A, cm, y)
            if not agrees and self._pattern is not None and key not in self._ungrouped:
                # a pattern that missed an entry reads it into another column: take every column on its own
                self._ungrouped.add(key)
                A = self._A[key] = self._build_flow_matrix(cm, y)
                agrees = self._flow_agrees(A, cm, y)
            if not agrees:
                raise ContactTangentError(f"the flow in contact modes {cm.tolist()} is not affine in the state")
            self._checked.add(key)
        return A

    def _build_flow_matrix(self, cm, y):
        """``A`` of ``cm``: from :data:`GROUPED_FROM` states on sparse, by column groups of the model's pattern
        (:mod:`.contact_flow_pattern`) unless there is none or it missed an entry; else dense, column by column."""
        from scipy.sparse import csr_matrix
        ig, n = self.ig, self.n
        z, out = np.zeros(ig.n_state), np.empty(ig.n_state)
        self._factor(cm)   # once: nothing below uses the work arrays for another mode
        rhs, args = self.mod.rhs, (cm, ig.I, ig.R, ig.WI, ig.WF, out)
        labels = self._labels
        base = np.zeros(n)
        base[labels] = np.rint(np.asarray(y)[labels])   # the zero state with y's labels (none moved below)

        def flow(v):
            z[:n] = v
            z[labels] = 0.0
            z[:n] += base
            rhs(0.0, z, *args)
            out[labels] = 0.0
            return out[:n].copy()

        entries = None
        if self._pattern is not None and self._key(cm, y) not in self._ungrouped:
            entries = grouped_flow_matrix(flow, n, *self._pattern.groups(self._sticking(cm)))
        if entries is None:
            v = np.zeros(n)
            f0 = flow(v)
            A = np.empty((n, n))
            for i in range(n):
                v[i] = 1.0
                A[:, i] = flow(v) - f0
                v[i] = 0.0
            return csr_matrix(A) if self._large else A
        rows, cols, values = entries
        return csr_matrix((values, (rows, cols)), shape=(n, n))

    def _flow_agrees(self, A, cm, y) -> bool:
        """Whether ``f(y + p) - f(y - p) = 2 A p`` for the probe ``p`` (scaled to ``y``), to rounding."""
        n = self.n
        base = np.asarray(y, dtype=float).copy()
        size = max(float(np.max(np.abs(base[:n]))), 1e-300)
        p = np.zeros_like(base)
        p[:n] = 1e-3 * size * self._probe
        return self._linear_along(lambda z: self._rhs(0.0, z, cm)[:n], base, p, A @ p[:n], tol=1e-8)

    def _block_powers(self, cm, y, rows) -> np.ndarray:
        """The powers (:func:`amplification_powers`) of ``A``'s block on ``rows`` in the mode ``cm``: kept, as ``A``
        is (a kept block's ``A`` was built and checked); the block itself is the first."""
        key = (self._key(cm, y), rows.tobytes())
        P = self._powers_of_A.get(key)
        if P is None:
            P = self._powers_of_A[key] = amplification_powers(self._block_of_A(cm, y, rows), self._poly.size - 1)
        return P

    def _block_of_A(self, cm, y, rows) -> np.ndarray:
        """``A``'s block on ``rows`` in the mode ``cm``, from the kept ``A`` (built and checked once)."""
        A = self.flow_matrix(cm, y)
        return csr_block(A, rows) if hasattr(A, "toarray") else A[np.ix_(rows, rows)]

    def _block(self, cm, y, rows) -> np.ndarray:
        """``A``'s block on ``rows`` in the mode ``cm`` (the first of its kept powers)."""
        return self._block_powers(cm, y, rows)[0].reshape(rows.size, rows.size)

    def _step_matrix(self, h: float, cm, y, rows=None) -> np.ndarray:
        """``R(hA)`` of the mode ``cm`` (``y``: a state where it holds), or its block of ``rows`` (from the block's
        kept powers, whatever the ring's size: a cluster's block is small and dense)."""
        if rows is None:
            key = (h, self._key(cm, y))
            M = self._R.get(key)
            if M is None:
                M = self._R[key] = self._whole_step_matrix(h, cm, y)
            return M
        return stability_matrix_from_powers(self._block_powers(cm, y, rows), h, self._poly)

    def _kept_step_matrix(self, h: float, cm, y):
        """:meth:`_step_matrix` on the continuous states (the states the replay carries where the laws have labels),
        kept with it."""
        key = (h, self._key(cm, y), "continuous")
        M = self._R.get(key)
        if M is None:
            c = self._continuous
            M = self._R[key] = continuous_block(self._step_matrix(h, cm, y), c)
        return M

    def _whole_step_matrix(self, h: float, cm, y) -> np.ndarray:
        """``R(hA)`` of the mode ``cm``: from its kept powers of ``A`` where ``A`` is dense or (sparse, from
        :data:`SPARSE_STEPS_FROM` states on) kept on their pattern, else by Horner's rule."""
        if self._sparse_steps:
            key = self._key(cm, y)
            P = self._sparse_powers.get(key)
            if P is None:
                P = sparse_amplification_powers(self.flow_matrix(cm, y), self._poly.size - 1)
                if P[0].shape[1] > SPARSE_STEPS_DENSITY * self.n * self.n:
                    P = ()   # the polynomial fills in: not kept, R(hA) dense by Horner's rule
                self._sparse_powers[key] = P
            if P:
                return sparse_stability_matrix_from_powers(P, h, self._poly)
        if not self._whole_by_powers:   # (dense, by Horner's rule: also a sparse A whose step fills in)
            return stability_matrix(h * self.flow_matrix(cm, y), self._poly)
        key = self._key(cm, y)
        P = self._powers_of_A.get(key)
        if P is None:
            P = self._powers_of_A[key] = amplification_powers(self.flow_matrix(cm, y), self._poly.size - 1)
        return stability_matrix_from_powers(P, h, self._poly)

    def _step_power(self, h: float, cm, y, m: int) -> np.ndarray:
        """``R(hA)^m`` of the mode ``cm``: ``m`` whole steps (kept, with the powers of two it is made of)."""
        if m == 1:
            return self._step_matrix(h, cm, y)
        mk = self._key(cm, y)
        key = (h, mk, m)
        P = self._powers.get(key)
        if P is None:
            base, e, b = self._step_matrix(h, cm, y), m, 1
            if hasattr(base, "toarray"):   # a sparse step's powers fill in: squared dense
                base = base.toarray()
            while e:
                if e & 1:
                    P = base if P is None else base @ P   # powers of one matrix commute
                e >>= 1
                if e:
                    b *= 2
                    square = self._powers.get((h, mk, b))
                    if square is None:
                        square = self._powers[(h, mk, b)] = base @ base
                    base = square
            self._powers[key] = P
        return P

    def _substep_derivatives(self, t, y, h, cm, H, rows):
        """The method's sub-step of length ``h`` from ``(t, y)`` in ``cm``: its end (the full state) and, on the
        cluster's ``rows``, the derivatives of its end in its start time and its length.

        Compiled (:mod:`.contact_replay`, which gives the formulas): the flow is affine,
        ``f = A y + b(t)``, and the stages' derivatives follow from ``A``'s block on
        ``rows`` and ``b'`` at the stages' times, a central difference of ``f(t, 0)``
        with the step ``1e-6 H``.
        """
        ig = self.ig
        self._factor(cm)
        Ar = self._block(cm, y, rows)
        end = np.empty(ig.n_state)
        Pt = np.empty(rows.size)
        Ph = np.empty(rows.size)
        self.mod.substep_derivatives(float(t), y, float(h), cm, 1e-6 * H, Ar, rows, *self._tableau, ig.I, ig.R, ig.WI,
                                     ig.WF, *self._work, end, Pt, Ph)
        return end, Pt, Ph

    def _guard(self, t, y, cm, j, gi) -> float:
        ig = self.ig
        self._factor(cm)
        self.mod.guards_at(float(t), y, cm, ig.I, ig.R, ig.WI, ig.WF, self._G)
        return float(self._G[j, gi])

    def _guard_gradient(self, t, y, cm, j, gi, rows, H):
        """``g_y`` on ``rows`` and ``g_t`` of contact ``j``'s guard ``gi`` in ``cm``.

        A guard is affine in the state within a mode: its gradient is taken once per mode
        and guard at the zero state (as ``A`` is, so it does not depend on where it was
        first needed) and checked at ``y`` along a probe at every use; where that fails
        (the joint stick forces of a closed ring make a guard piecewise affine) it is taken
        by central differences at ``y``, and not kept.
        """
        ig = self.ig
        steps = 1e-6 * np.maximum(np.abs(y[rows]), 1e-3 * np.max(np.abs(y[rows])))
        cols = np.empty(rows.size)
        if self._contact_labels[j].size:
            # a law with labels: its guards are the least over its elements (the Iwan law's), whose gradient is
            # the element's that crosses; a gradient kept from the zero state, whose labels are all zero, is
            # another's, and the probe along which it is checked moves the contact's two sides alike (their
            # relative velocity not at all). Central differences at y, row by row
            gy = np.full(self.n, np.nan)
        else:
            gy = self._kept_guard_gradient(cm, j, gi)
        self._factor(cm)
        gt, kept = self.mod.guard_derivatives(float(t), y, cm, int(j), int(gi), rows, steps, 1e-6 * H, gy[rows],
                                              ig.I, ig.R, ig.WI, ig.WF, self._G, self._work[4], cols)
        if kept:
            return gy, gt
        local = np.zeros(self.n)
        local[rows] = cols
        return local, gt

    def _kept_guard_gradient(self, cm, j: int, gi: int) -> np.ndarray:
        """Contact ``j``'s guard ``gi``'s gradient in ``cm`` from the zero state (:meth:`_guard_gradient_at_zero`),
        kept by mode and guard."""
        key = (cm.tobytes(), int(j), int(gi))
        gy = self._gy.get(key)
        if gy is None:
            self._gy[key] = gy = self._guard_gradient_at_zero(cm, j, gi)
        return gy

    def _sticking(self, cm) -> tuple:
        """The contacts that stick rigidly in ``cm``."""
        return tuple(np.flatnonzero(self._stick_table[self.tables.claw, cm]).tolist())

    def _guard_columns(self, cm, j: int):
        """The states contact ``j``'s guards in ``cm`` can depend on (every one without a pattern)."""
        if self._pattern is None:
            return range(self.n)
        return self._pattern.guard_columns(self._sticking(cm), j)

    def _guard_gradient_at_zero(self, cm, j: int, gi: int) -> np.ndarray:
        """Contact ``j``'s guard ``gi``'s gradient in ``cm`` by unit differences at the zero state: in the columns the
        pattern lets it depend on, checked by one difference along the others with weights drawn once (which a
        missed entry would move: then every column is taken)."""
        zero = np.zeros(self.ig.n_state)
        g0 = self._guard(0.0, zero, cm, j, gi)
        gy = np.zeros(self.n)
        columns = self._guard_columns(cm, j)
        if len(columns) < self.n:
            rest = np.ones(self.n, dtype=bool)
            rest[columns] = False
            zero[:self.n][rest] = self._probe[rest]
            if self._guard(0.0, zero, cm, j, gi) != g0:
                columns = range(self.n)
            zero[:] = 0.0
        for i in columns:
            zero[i] = 1.0
            gy[i] = self._guard(0.0, zero, cm, j, gi) - g0
            zero[i] = 0.0
        return gy

    def _rigid_stick(self, j: int, m: int) -> bool:
        return bool(self._stick_table[self.tables.claw[j], m])

    def _along_flow(self, t, y, cm):
        """``y`` moved along the flow of ``cm`` by ``1e-14`` of a step, then ten times more each, up to ``1e-8``:
        far less than the kernel's event bracket (``event_tol h``). ``(time, state)`` each."""
        rate = self._rhs(t, y, cm)
        h = self.ig.period / self.ig.steps_per_period
        for k in range(14, 7, -1):
            dt = 10.0 ** -k * h
            yield t + dt, y + dt * rate

    def _past_root(self, t, y, cm, j, gi, K):
        """``y``, or where contact ``j``'s guard ``gi`` has not yet crossed there, ``y`` a little farther along the
        flow (:meth:`_along_flow`), where it has.

        The kernel fires a transition at the far end of its event's bracket, past the guard's root (by at most its
        ``event_tol``), and a law with labels (the Iwan elements' modes) decides them there from the state: the
        element whose guard crossed slips. The replay's state at the logged time can lie a rounding error short of
        the root (``5e-15`` of the state on a 4-blade ring), where the same reset keeps the element stuck; moved
        along the flow by ``1e-14`` of a step or more it decides as the kernel did. A guard that has not crossed
        within ``1e-8`` of a step was fired short of its root, with another contact's event
        (:func:`~blademodel.numeric.contact_guards.mark_near`): ``y`` as it is.
        """
        d = int(self.mod.GDIR[K, int(cm[j]), int(gi)])

        def crossed(tt, yy):
            g = self._guard(tt, yy, cm, j, gi)
            return (d < 0 and g < 0.0) or (d > 0 and g > 0.0)

        if d == 0 or crossed(t, y):
            return y
        return next((moved for tt, moved in self._along_flow(t, y, cm) if crossed(tt, moved)), y)

    def _as_the_kernel(self, fire, t, y, cm, labels, target, j):
        """``(y, fire(y))`` with ``y`` moved along the flow (:meth:`_along_flow`) until the reset ``fire`` sets the
        contact's ``labels`` to ``target``.

        Raises
        ------
        ContactTangentError
            Where it does not within ``1e-8`` of a step.
        """
        for _, moved in self._along_flow(t, y, cm):
            after = fire(moved)
            if np.array_equal(after[labels], target):
                return moved, after
        raise ContactTangentError(f"the transition of contact {j} at t = {t:.9g} sets other labels than the kernel did")

    def _reset_jacobian(self, t, y, cm, j, gi, rows, target=None, y0=None):
        """``d y+ / d y`` of contact ``j``'s transition by guard ``gi`` at ``y``, as its rows that differ from the
        identity's, and the state after it: ``((j, free, cols, block), after)``, or ``None`` and ``y`` where the
        contact's law has no state to reset (:meth:`_apply_reset` applies it).

        A transition writes its contact's law states ``own`` only: the Jacobian is the
        identity but for their rows, zero but for those of ``free`` (``own`` but the
        labels) in the columns ``cols`` (the cluster's ``rows`` and ``own``, what those
        states can depend on, but the labels), which are ``block``: central differences of
        the transition, each of step ``1e-6`` of its state and at least ``1e-9`` of the
        largest physical state at the step's start ``y0`` (``y`` itself where None), as the
        compiled cluster step takes them.

        A law with labels (the Iwan elements' modes) decides them from the state, at the guard's root: the
        replay's state there and the kernel's differ by rounding, and a difference step moves the guard across
        its root. ``target``, the contact's labels after the transition as the kernel set them (where known),
        fixes the decision: the state after is taken with those labels, and a column whose central difference
        straddles the decision is a one-sided difference on the side that keeps it (exact to rounding: with its
        decisions fixed the reset is affine). The labels' own rows and columns are zero (held).
        """
        ig = self.ig
        K = int(self.tables.claw[j])
        n_states = int(self.mod.NSTATES[K])
        if n_states == 0:
            return None, y

        def fire(yy):
            yy = yy.copy()
            self._factored = None
            self.mod.transition_at(float(t), yy, cm.copy(), int(j), int(gi), ig.I, ig.R, ig.WI, ig.WF, self._G)
            return yy

        n = self.n
        free, cols = self._reset_rows(j, rows)[1:3]
        labels = self._contact_labels[j]
        y0 = y if y0 is None else y0
        steps = 1e-6 * np.maximum(np.abs(y[cols]), 1e-3 * max(float(np.max(np.abs(y0[:n]))), 1e-300))
        if labels.size:
            y = self._past_root(t, y, cm, j, gi, K)
        after = fire(y)
        if not labels.size:
            return (j, free, cols, self._columns(lambda z: fire(z)[free], y, cols, steps)), after
        if target is None:
            target = after[labels].copy()
        target = np.asarray(target, dtype=float)
        if not np.array_equal(after[labels], target):
            # the guard the kernel fired is read from the boundary after a drifted transition (``mark_drifted``)
            # while the reset decides from the raw state: a little farther along the flow it decides as the
            # kernel did (the 24-blade ring at 290-300 rad/s: an element that stops slipping, 4 points in 183)
            y, after = self._as_the_kernel(fire, t, y, cm, labels, target, j)
        after[labels] = target
        # with its labels fixed the reset is affine (an element that sticks takes the stretch of its slip force,
        # affine in the contact's normal state; the others keep theirs): its block is kept for these labels
        key = (int(j), int(gi), int(cm[j]), np.rint(y[labels]).astype(np.int8).tobytes(),
               target.astype(np.int8).tobytes(), cols.tobytes())
        block = self._resets.get(key)
        if block is None:
            block = np.empty((free.size, cols.size))
            for c, (i, e) in enumerate(zip(cols, steps)):
                block[:, c] = self._decided_column(fire, y, after[free], i, e, labels, target, free, j, t)
            self._resets[key] = block
        return (j, free, cols, block), after

    def _reset_rows(self, j: int, rows) -> tuple:
        """Contact ``j``'s law states ``own``, ``free`` (``own`` but its labels), the reset's columns ``cols``
        (:meth:`_reset_jacobian`) and, for :meth:`_apply_reset` on the cluster's ``rows``: the positions in ``rows``
        of ``own``, of ``free`` and of ``cols``, and which of ``free`` and ``cols`` are among ``rows`` (kept by
        contact and rows)."""
        key = (int(j), rows.tobytes())
        found = self._reset_sets.get(key)
        if found is None:
            own = self._law_rows(j)
            labels = self._contact_labels[j]
            cols = np.setdiff1d(np.union1d(rows, own), labels)
            free = np.setdiff1d(own, labels)
            in_f, in_c = np.isin(free, rows), np.isin(cols, rows)
            found = self._reset_sets[key] = (own, free, cols, np.searchsorted(rows, own[np.isin(own, rows)]),
                                             np.searchsorted(rows, free[in_f]), np.searchsorted(rows, cols[in_c]),
                                             np.flatnonzero(in_f), np.flatnonzero(in_c))
        return found

    def _apply_reset(self, V, rows, reset) -> np.ndarray:
        """``V`` (on the sorted ``rows``) after the reset ``reset`` (:meth:`_reset_jacobian`'s): the rows of its law
        states that are among ``rows`` become the block's product with ``V``'s rows of its columns (zero for the
        labels, held), the others unchanged. ``V`` is overwritten."""
        j, free, cols, block = reset
        own_at, free_at, cols_at, f, c = self._reset_rows(j, rows)[3:]
        new = block[np.ix_(f, c)] @ V[cols_at]
        V[own_at] = 0.0
        V[free_at] = new
        return V

    @staticmethod
    def _decided_column(fire, y, base, i, e, labels, target, free, j, t) -> np.ndarray:
        """The column ``i`` of the reset ``fire``'s rows ``free`` at ``y`` (``base``: their values there), its labels
        held at ``target``.

        The central difference of step ``e`` where both sides keep those labels; a one-sided one on the side
        that does where only one does (the reset is affine for fixed labels, so either is exact to rounding).
        Where neither does (at an Iwan contact's closing every element's guard is zero, and any step sends all
        of them to slip or none), the central difference still holds where the rows do not depend on the labels
        the steps set: the one-sided differences either side agree (an element that starts to slip keeps its
        stretch, whatever the others do). Else at steps a hundred times shorter, then an error.
        """
        for scale in (1.0, 1e-2, 1e-4):
            step = e * scale
            sides = []
            for way in (1.0, -1.0):
                yy = y.copy()
                yy[i] += way * step
                out = fire(yy)
                sides.append((np.array_equal(out[labels], target), out[free]))
            (keep_p, fp), (keep_m, fm) = sides
            if keep_p and keep_m:
                return (fp - fm) / (2 * step)
            if keep_p or keep_m:
                way = 1.0 if keep_p else -1.0
                yy = y.copy()
                yy[i] += 2 * way * step
                out = fire(yy)
                if np.array_equal(out[labels], target):
                    return way * (out[free] - (fp if keep_p else fm)) / step
                continue
            up, down = fp - base, base - fm
            if np.max(np.abs(up - down)) <= 1e-9 * max(float(np.max(np.abs(up) + np.abs(down))), 1e-300) + \
                    4.0 * np.finfo(float).eps * float(np.max(np.abs(base))):
                return (fp - fm) / (2 * step)
        raise ContactTangentError(f"the transition of contact {j} at t = {t:.9g} decides its labels otherwise than "
                                  f"the kernel on both sides of its state")

    def _projection_block(self, contacts, rows) -> np.ndarray:
        """:meth:`_projection`'s block on ``rows`` (kept: it depends on the geometry and the masses only)."""
        key = (tuple(contacts), rows.tobytes())
        P = self._projections.get(key)
        if P is None:
            P = self._projections[key] = np.ascontiguousarray(self._projection(contacts)[np.ix_(rows, rows)])
        return P

    def _projection(self, contacts) -> np.ndarray:
        """The kernel's projection of the velocities onto zero slip of ``contacts``: ``u -= M^-1 G^T W^+ G u``."""
        nq = self.nq
        G = self.tables.G[contacts]
        MG = self.tables.invm[:, None] * G.T
        # a closed ring that sticks makes W singular; G^T x is the same for every solution
        P = np.eye(self.n)
        P[nq:2 * nq, nq:2 * nq] -= MG @ np.linalg.pinv(G @ MG) @ G
        return P

    def _clusters(self, modes, seeds, y) -> list:
        """``(rows, contacts)`` of each cluster of the event contacts ``seeds`` in a step through ``modes``: the
        state rows that the modes' ``A`` and the contacts' own coordinates couple to them, transitively, and the
        contacts whose coordinates are among them (kept by the modes and seeds)."""
        key = (b"".join(self._key(cm, y) for cm in modes), seeds)
        found = self._cluster_sets.get(key)
        if found is not None:
            return found
        coupled = np.zeros((self.n, self.n), dtype=bool)
        for cm in modes:
            A = self.flow_matrix(cm, y)
            if hasattr(A, "toarray"):
                coupled[A.nonzero()] = True
            else:
                coupled |= A != 0.0
        coupled |= coupled.T
        for j in seeds:
            r = self._rows[j]
            coupled[np.ix_(r, r)] = True
        clusters, seen = [], np.zeros(self.n, dtype=bool)
        for j in seeds:
            if seen[self._rows[j][0]]:
                continue
            reach = np.zeros(self.n, dtype=bool)
            reach[self._rows[j]] = True
            while True:
                grown = coupled[reach].any(axis=0) | reach
                if np.array_equal(grown, reach):
                    break
                reach = grown
            seen |= reach
            contacts = tuple(c for c in range(self.nc) if reach[self._rows[c][0]])
            clusters.append((np.flatnonzero(reach), contacts))
        self._cluster_sets[key] = clusters
        return clusters

    # --- the replay -------------------------------------------------------------------------------
    def monodromy(self, rec_t, rec_y, rec_cm, log, n_log: int) -> np.ndarray:
        """``d y(t_end) / d y(t_0)`` of the recorded run (physical states by physical states).

        Parameters
        ----------
        rec_t, rec_y, rec_cm : ndarray
            The run recorded at every step (``record_buffer``), its start in row 0.
        log : tuple
            Its event log (``log_buffer``) and ``n_log`` the entries used.

        Raises
        ------
        ContactTangentError
            At an event whose guard has no rate along the flow (grazing), or where the
            log and the record disagree.
        """
        with blas_threads_for(self.n):   # the replay's products are of the ring's size
            return self._monodromy(rec_t, rec_y, rec_cm, log, n_log)

    def _monodromy(self, rec_t, rec_y, rec_cm, log, n_log: int) -> np.ndarray:
        n = self.n
        lt, lc, lg, lf, lto = log
        c, loc = (self._continuous, self._local) if self._labels.size else (None, np.arange(n))

        def kept(M):   # a matrix of the whole state on the states V carries
            return M if c is None else continuous_block(M, c)

        V = np.eye(n if c is None else c.size)
        ie = 0
        H = float(rec_t[1] - rec_t[0])
        self.ig._clear_near_marks()   # guards without the kernel's offsets for early-fired contacts
        self._factored = None         # the kernel has used the work arrays since
        steps = rec_t.shape[0] - 1
        # the steps whose modes differ from the step's before: a run of whole steps ends at the first of them
        changes = np.append(np.flatnonzero(np.any(rec_cm[1:steps] != rec_cm[:steps - 1], axis=1)) + 1, steps)
        k = 0
        while k < steps:
            t0, t1 = float(rec_t[k]), float(rec_t[k + 1])
            cm0 = rec_cm[k].astype(np.int64)
            if not (ie < n_log and lt[ie] <= t1):
                # a run of whole steps without events in one mode: one product by R(hA) to the run's length. It ends
                # at the next change of modes, the step that holds the next event, or the record's end
                j = int(changes[np.searchsorted(changes, k, side="right")])
                if ie < n_log:
                    j = min(j, int(np.searchsorted(rec_t[1:steps + 1], lt[ie], side="left")))
                short = self._sparse_steps and j - k <= SPARSE_RUN_MAX
                R = self._step_matrix(H, cm0, rec_y[k]) if short else None
                if R is not None and hasattr(R, "toarray"):   # sparse: a short run step by step
                    R = kept(R)
                    for _ in range(j - k):
                        V = R @ V
                else:
                    V = kept(self._step_power(H, cm0, rec_y[k], j - k)) @ V
                k = j
                continue
            i0 = ie
            while ie < n_log and lt[ie] <= t1:
                ie += 1
            order = sorted(range(i0, ie), key=lambda i: lt[i])
            cmx = cm0.copy()
            modes = [cm0]
            for i in order:
                if cmx[lc[i]] != lf[i]:
                    raise ContactTangentError(f"the event log disagrees with the record at t = {lt[i]:.9g}")
                cmx[lc[i]] = lto[i]
                modes.append(cmx.copy())
            if not np.array_equal(cmx, rec_cm[k + 1]):
                raise ContactTangentError(f"the event log disagrees with the record at t = {t1:.9g}")
            seeds = tuple(sorted({int(lc[i]) for i in order}))
            Vn = (self._step_matrix(H, cm0, rec_y[k]) if c is None else self._kept_step_matrix(H, cm0, rec_y[k])) @ V
            for rows, contacts in self._clusters(modes, seeds, rec_y[k]):
                events = [i for i in order if int(lc[i]) in contacts]
                Vn[loc[rows]] = self._step_cluster(V[loc[rows]], rows, contacts, events, log, t0, t1, rec_y[k], cm0,
                                                   H, rec_y[k + 1])
            V = Vn
            k += 1
        if c is None:
            return V
        M = np.zeros((n, n))
        M[np.ix_(c, c)] = V
        return M

    def settle_jacobian(self, y, cm, events) -> np.ndarray:
        """``d y+ / d y`` of the transitions a start state's settling fired at ``t = 0``
        (:meth:`~blademodel.numeric.contact_kernel.ContactIntegrator.settle`): physical states by physical states.

        Fired at the fixed time 0 because the start lies past their guards, they move no
        event time: only their resets and the stick projection of the contacts they send
        to stick are differentiated, as at an event (:meth:`_cluster_step`).

        Parameters
        ----------
        y : ndarray
            The full state before the settling.
        cm : ndarray
            The modes before it.
        events : list of ``(contact, guard, from, to)``
        """
        cm = np.asarray(cm, dtype=np.int64)
        seen = cm.copy()
        for j, _, frm, to in events:
            if seen[j] != frm:
                raise ContactTangentError(f"the settling's log disagrees with the modes at contact {j}")
            seen[j] = to
        self._factor(cm)
        D, _, _ = self._through_transitions(np.eye(self.n), 0.0, np.asarray(y, dtype=float).copy(), cm,
                                            [(j, gi, to) for j, gi, _, to in events], np.arange(self.n),
                                            range(self.nc))
        return D

    def _through_transitions(self, V, t, y, cm, group, rows, contacts, targets=None, y0=None, record=None):
        """``V`` (on ``rows``) taken through the transitions ``group`` at ``(t, y)`` from the modes ``cm``: each
        ``(contact, guard, to)``'s reset (``guard`` ``-1``: a mode the friction problem set, no reset), then the
        stick projection of ``contacts`` where one of them starts to stick. Returns ``(V, y, modes)`` after them.
        ``targets``: by contact, its labels after its transitions as the kernel set them, where known; ``y0``: the
        step's start state (:meth:`_reset_jacobian`); ``record``: :meth:`_cluster_step`'s."""
        cm2 = cm.copy()
        copied = False
        for j, gi, to in group:
            if gi >= 0:
                target = None if targets is None else targets.get(j)
                reset, y = self._reset_jacobian(t, y, cm2, j, gi, rows, target, y0)
                if reset is not None:
                    if not copied:
                        V, copied = V.copy(), True
                    V = self._apply_reset(V, rows, reset)
                    if record is not None:
                        record["resets"].append((j, reset, y[self._contact_labels[j]].copy()))
            cm2[j] = to
        if any(self._rigid_stick(j, cm2[j]) and not self._rigid_stick(j, cm[j]) for j in contacts):
            stick = [j for j in contacts if self._rigid_stick(j, cm2[j])]
            V = self._projection_block(stick, rows) @ V
        return V, y, cm2

    def _step_cluster(self, Vc, rows, in_cluster, events, log, t0, t1, y0, cm0, H, y1):
        """:meth:`_cluster_step`, compiled (:meth:`_compiled_cluster_step`) where the cluster has at most
        :data:`COMPILED_CLUSTER_ROWS` rows."""
        if COMPILED_CLUSTER_STEPS and rows.size <= COMPILED_CLUSTER_ROWS:
            return self._compiled_cluster_step(Vc, rows, in_cluster, events, log, t0, t1, y0, cm0, H, y1)
        return self._cluster_step(Vc, rows, in_cluster, events, log, t0, t1, y0, cm0, H, y1)

    def _compiled_cluster_step(self, Vc, rows, in_cluster, events, log, t0, t1, y0, cm0, H, y1):
        """:meth:`_cluster_step` by the compiled ``cluster_step``, from the step's plan (:meth:`_cluster_plan`): the
        step's matrix on the cluster's rows (the sequence applied to the identity), then its product with ``Vc``.

        Where the laws have labels (Iwan), the plan is also keyed by the labels at the step's
        start and end, and made of the kept matrices where they hold it all
        (:meth:`_kept_record`), else recorded from the Python step run once on no columns
        (what it decides: its blocks of ``A``, the labels each transition set and their
        resets' Jacobians, kept for those labels); the compiled step follows, from the first
        time on, so a step's result does not depend on whether its plan was kept. A step whose
        transitions do not set the recorded labels (``cluster_step``'s status 2) is stepped in
        Python (``cluster_steps[2]`` counts them)."""
        lt, lc, lg, lf, lto = log
        ev = np.asarray(events, dtype=np.int64)
        times = lt[ev]
        key = (rows.tobytes(), cm0.tobytes(), lc[ev].tobytes(), lg[ev].tobytes(), lto[ev].tobytes(),
               np.diff(times).astype(bool).tobytes())   # (which events share a time: the groups)
        labelled = bool(self._labels.size)
        if labelled:
            key += (np.rint(y0[self._labels]).astype(np.int8).tobytes(),
                    np.rint(y1[self._labels]).astype(np.int8).tobytes())
        plan = self._plans.get(key)
        if plan is None:
            record = None
            if labelled:
                record = self._kept_record(events, log, cm0, y0, y1, rows)
                if record is None:   # the Python step on no columns: what it decides, not what it multiplies
                    record = {"A": [], "resets": []}
                    self._cluster_step(np.empty((rows.size, 0)), rows, in_cluster, events, log, t0, t1, y0, cm0, H,
                                       y1, record)
            plan = self._plans[key] = self._cluster_plan(rows, in_cluster, events, log, cm0, y0, record)
        gtime, first = times[plan.starts], plan[1:]
        nr = rows.size
        work = self._cluster_work.get(nr)
        if work is None:
            n_state = self.ig.n_state
            work = self._cluster_work[nr] = (
                np.empty((nr, nr)), np.empty((nr, nr)), np.empty((nr, nr)), np.empty(n_state), np.empty(n_state),
                np.empty(nr), np.empty(nr), np.empty(nr), np.empty(nr), np.empty((nr, nr)), np.empty((nr, nr)),
                np.empty(nr), np.empty(nr), np.empty(n_state), np.empty((self._most_states, nr)),
                np.empty((self._most_states, nr)), np.zeros(2))
        X0, X1, C, end, ya, Pt, Ph, dta, dtb, Rb, Rb2, steps, cols, Y2, D, RW, info = work
        X0[:] = 0.0
        X0.flat[::nr + 1] = 1.0
        ig = self.ig
        status = self.mod.cluster_step(X0, X1, C, rows, float(t0), float(t1), y0, cm0.copy(), float(H), gtime.size,
                                       gtime, *first, ig.period / ig.steps_per_period, self._poly, self.n,
                                       *self._tableau, ig.I, ig.R, ig.WI, ig.WF, self._G, *self._work, end, ya, Pt, Ph,
                                       dta, dtb, Rb, Rb2, steps, cols, Y2, D, RW, info)
        self._factored = None   # the compiled step factored other modes in the work arrays
        if status == 2:   # a recorded transition decided other labels: the Python step decides them
            self.cluster_steps[2] += 1
            return self._cluster_step(Vc, rows, in_cluster, events, log, t0, t1, y0, cm0, H, y1)
        self.cluster_steps[int(info[1])] += 1
        if status:
            raise ContactTangentError(f"a grazing event at t = {info[0]:.9g} (its guard has no rate)")
        return C @ Vc   # the step is linear in the block: its matrix, then one product

    def _kept_record(self, events, log, cm0, y0, y1, rows):
        """What the Python step would record of a step of a model with labels (:meth:`_cluster_step`), without
        stepping: None where a reset's Jacobian is not kept (it is taken at the event's state), or where a contact
        with labels resets more than once in the step (the labels between its resets are known to no record).

        Each contact's labels are ``y0``'s until its reset and ``y1``'s after it (the kernel's
        end state: the labels it set), and its resets' Jacobians are kept by those
        (:meth:`_reset_jacobian`), as the modes' ``A`` are by mode and labels (built where
        not kept, and checked at ``y0`` with those labels: the flow is affine in a mode for
        given labels, wherever it is checked)."""
        lt, lc, lg, lf, lto = log
        resetting = [int(lc[i]) for i in events if lg[i] >= 0 and not self._stateless[int(lc[i])]]
        if any(resetting.count(j) > 1 for j in resetting if self._contact_labels[j].size):
            return None
        y = y0.copy()   # (its labels only are read: the matrices' keys)
        cm = cm0.copy()
        record = {"A": [], "resets": []}

        def block():   # (y: the step's start state with the labels of this sub-step, where A is checked)
            return self._block_of_A(cm, y, rows)

        q = 0
        while q < len(events):
            te = lt[events[q]]
            record["A"].append(block())
            while q < len(events) and lt[events[q]] == te:
                i = events[q]
                j, gi = int(lc[i]), int(lg[i])
                if gi >= 0 and not self._stateless[j]:
                    labels = self._contact_labels[j]
                    reset = None
                    if labels.size:
                        free, cols = self._reset_rows(j, rows)[1:3]
                        target = y1[labels]
                        reset = self._resets.get((j, gi, int(cm[j]), np.rint(y[labels]).astype(np.int8).tobytes(),
                                                  target.astype(np.int8).tobytes(), cols.tobytes()))
                        if reset is None:
                            return None
                        reset = (j, free, cols, reset)
                        y[labels] = target
                    record["resets"].append((j, reset, y[labels].copy()))
                cm[j] = int(lto[i])
                q += 1
        record["A"].append(block())
        return record

    def _cluster_plan(self, rows, in_cluster, events, log, cm0, y0, record=None) -> tuple:
        """What the compiled ``cluster_step`` takes of a step's cluster besides its times and states: where each
        transition group starts among ``events`` (by time) and, as that function names them, ``gfc, gfg, goff,
        gmc, gmto, gmg, mlo, mn, Ab, proj, PB, gyr, rk, RB, RM, lfo, lrow, ltg``: the groups' fired guards and
        transitions (each one's contact, mode, guard and the law states it resets), each sub-step's block of ``A``,
        the stick projections, the fired guards' kept gradients and the recorded transitions of laws with labels.
        It depends on the modes, the rows and the transitions only (and the labels, where there are any), so it
        is kept with the model's matrices.

        ``record``: where the laws have labels, the Python step's record of this step
        (:meth:`_cluster_step`): the blocks of ``A`` it stepped with and, for each reset, the
        contact, its Jacobian (:meth:`_reset_jacobian`) and the labels it set."""
        lt, lc, lg, lf, lto = log
        groups, starts = [], []   # [(contact, guard, to), ...] by time, and each one's first event
        for q, i in enumerate(events):
            if not groups or lt[i] != lt[events[starts[-1]]]:
                groups.append([])
                starts.append(q)
            groups[-1].append((int(lc[i]), int(lg[i]), int(lto[i])))
        ng, nr = len(groups), rows.size
        Ab = np.empty((ng + 1, nr, nr))
        gyr = np.zeros((ng, nr))
        gfc = np.full(ng, -1, dtype=np.int64)
        gfg = np.zeros(ng, dtype=np.int64)
        goff = np.zeros(ng + 1, dtype=np.int64)
        gmc, gmto, gmg, mlo, mn, rk = [], [], [], [], [], []
        proj = np.zeros(ng, dtype=np.int64)
        PB, RB, RM, lfo, lrow, ltg = [], [], [], [0], [], []
        resets = iter(record["resets"]) if record is not None else None
        cm = cm0.copy()
        for g, group in enumerate(groups):
            # (the compiled step builds R(hA) by Horner's rule from A's block)
            Ab[g] = record["A"][g] if record is not None else self._block_of_A(cm, y0, rows)
            fired = next(((j, gi) for j, gi, _ in group if gi >= 0), None)
            if fired is not None:
                gfc[g], gfg[g] = fired
                if self._contact_labels[fired[0]].size:
                    gyr[g] = np.nan   # differences at the event (:meth:`_guard_gradient`)
                else:
                    gyr[g] = self._kept_guard_gradient(cm, *fired)[rows]
            after = cm.copy()
            for j, gi, to in group:
                after[j] = to
                gmc.append(j)
                gmto.append(to)
                gmg.append(gi)
                resets_states = gi >= 0 and not self._stateless[j]
                own = self._law_rows(j)
                mlo.append(int(own[0]) if resets_states else 0)
                mn.append(own.size if resets_states else 0)
                rk.append(0)
                if resets_states and resets is not None:
                    jr, reset, labels_set = next(resets)
                    if jr != j:
                        raise ContactTangentError("the Python step's record disagrees with the step's transitions")
                    if self._contact_labels[j].size:
                        # the reset's rows among the cluster's (its labels' zero), padded to the most law states
                        own_at, free_at, cols_at, f, c = self._reset_rows(j, rows)[3:]
                        B, M = np.zeros((self._most_states, nr)), np.full(self._most_states, -1, dtype=np.int64)
                        M[:own_at.size] = own_at
                        B[np.ix_(np.searchsorted(own_at, free_at), cols_at)] = reset[3][np.ix_(f, c)]
                        RB.append(B)
                        RM.append(M)
                        rk[-1] = len(RB)
                        lrow.extend(self._contact_labels[j].tolist())
                        ltg.extend(labels_set.tolist())
                lfo.append(len(lrow))
            goff[g + 1] = len(gmc)
            if any(self._rigid_stick(j, after[j]) and not self._rigid_stick(j, cm[j]) for j in in_cluster):
                PB.append(self._projection_block([j for j in in_cluster if self._rigid_stick(j, after[j])], rows))
                proj[g] = len(PB)
            cm = after
        Ab[ng] = record["A"][ng] if record is not None else self._block_of_A(cm, y0, rows)
        members = (np.array(x, dtype=np.int64) for x in (gmc, gmto, gmg, mlo, mn))

        def stack(blocks, shape, dtype=float):
            return np.array(blocks, dtype=dtype) if blocks else np.zeros((0,) + shape, dtype=dtype)

        return ClusterPlan(np.array(starts, dtype=np.int64), gfc, gfg, goff, *members, Ab, proj, stack(PB, (nr, nr)),
                           gyr, np.array(rk, dtype=np.int64), stack(RB, (self._most_states, nr)),
                           stack(RM, (self._most_states,), np.int64), np.array(lfo, dtype=np.int64),
                           np.array(lrow, dtype=np.int64), np.array(ltg, dtype=float))

    def _cluster_step(self, Vc, rows, in_cluster, events, log, t0, t1, y0, cm0, H, y1=None, record=None):
        """The rows ``rows`` of a step's tangent through the cluster's ``events`` (log indices, in time order);
        ``in_cluster``: the contacts whose coordinates are in ``rows``. ``y1``: the kernel's state at the step's end,
        whose labels are those each contact's last transition in the step set. ``record``: None, or a dict whose
        lists ``"A"`` and ``"resets"`` get each sub-step's block of ``A`` and each reset's ``(contact, Jacobian,
        labels set)`` (:meth:`_cluster_plan`)."""
        lt, lc, lg, lf, lto = log
        last = {}
        if y1 is not None and self._labels.size:
            for i in events:
                last[int(lc[i])] = float(lt[i])
        cm = cm0.copy()
        ta, ya = t0, y0.copy()
        dta = np.zeros(Vc.shape[1])
        q = 0
        while q < len(events):
            te = float(lt[events[q]])
            group = []
            while q < len(events) and lt[events[q]] == te:
                i = events[q]
                group.append((int(lc[i]), int(lg[i]), int(lto[i])))
                q += 1
            if record is not None:
                record["A"].append(self._block(cm, ya, rows))
            ye, Pt, Ph = self._substep_derivatives(ta, ya, te - ta, cm, H, rows)
            W = self._step_matrix(te - ta, cm, ya, rows) @ Vc + np.outer(Pt - Ph, dta)
            fired = next(((j, gi) for j, gi, _ in group if gi >= 0), None)
            if fired is None:
                dtb = np.zeros(Vc.shape[1])
            else:
                gy, gt = self._guard_gradient(te, ye, cm, *fired, rows, H)
                rate = gt + float(gy[rows] @ Ph)
                if rate == 0.0 or not np.isfinite(rate):
                    raise ContactTangentError(f"a grazing event at t = {te:.9g} (its guard has no rate)")
                dtb = -(gy[rows] @ W) / rate
            targets = {j: y1[self._contact_labels[j]] for j, _, _ in group
                       if j in last and last[j] == te and self._contact_labels[j].size}
            Vc, ye, cm2 = self._through_transitions(W + np.outer(Ph, dtb), te, ye, cm, group, rows, in_cluster,
                                                    targets, y0, record)
            ta, ya, cm, dta = te, ye, cm2, dtb
        if record is not None:
            record["A"].append(self._block(cm, ya, rows))
        _, Pt, Ph = self._substep_derivatives(ta, ya, t1 - ta, cm, H, rows)
        return self._step_matrix(t1 - ta, cm, ya, rows) @ Vc + np.outer(Pt - Ph, dta)
