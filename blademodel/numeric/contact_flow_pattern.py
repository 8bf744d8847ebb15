"""Where a per-contact mode's flow matrix ``A = df/dy`` can be nonzero, and ``A`` from a few calls of ``rhs``.

A ring's ``A`` is sparse (about 1 % of a 96-blade ring's entries): a coordinate moves its
own blade's accelerations and, through its contacts, its neighbours'. Taken column by
column it costs ``n + 1`` calls of the compiled ``rhs`` a mode (385 at 96 blades), and a
long run meets thousands of modes. Columns that share no row can be perturbed together
(Curtis, Powell and Reid's grouping), so this module gives, for a mode, a *pattern* that
holds every entry that can be nonzero and groups of columns without a common row in it:
``A`` then costs one call a group.

The pattern follows the kernel's forces (:func:`~blademodel.numeric.contact_flow.contact_forces`):

* a position's rate is its velocity;
* springs and dampers couple the coordinates of their entries;
* a contact's normal force, friction force and law states depend on its own slots'
  positions and velocities and on its law states, and act on its slots;
* a *cluster* of rigidly sticking contacts (joined by shared coordinates) is held by
  stick forces solved jointly from every force on its coordinates: its coordinates'
  accelerations depend on every column that any of those forces depends on.

The same rows tell which columns a contact's guards can depend on
(:meth:`FlowPattern.guard_columns`). The pattern is computed from the tables alone (it
holds for every value of the parameters). A contact whose normal law is damped reads the
accelerations (its ``dN/dt``), which this pattern does not follow: such models are not
grouped (:func:`flow_pattern` returns ``None``). The build checks itself: a change in a
row that no column of the group owns means the pattern missed an entry, and the caller
(:class:`~blademodel.numeric.contact_tangent.ContactTangent`) then takes every column on
its own; it also checks each matrix along a random direction, which finds an entry read
into the wrong column.
"""

from __future__ import annotations

import numpy as np

from .contract import NK_DAMPED
from .kept import Kept

#: The most bytes the clusters' rows, columns and block pairs may keep (a ring sticking in arcs of every length
#: has thousands of clusters, the longest with blocks of about ``16 k^2`` pairs for ``k`` contacts).
CLUSTER_BYTES = 1 << 26


class FlowPattern:
    """The nonzero pattern of a per-contact model's ``A`` by which contacts stick rigidly, and its column groups.

    Parameters
    ----------
    tables : NumericTables
        The model's tables (coordinates, springs, dampers, contacts' slots).
    n : int
        The physical states: positions, velocities, then the contacts' law states.
    law_states : sequence of int
        Each contact's number of law states (from its law's ``NSTATES``).
    """

    def __init__(self, tables, n: int, law_states):
        nq = tables.n
        self.n, self.nq = int(n), nq
        nc = tables.cidx.shape[0]
        base = np.zeros((n, n), dtype=bool)
        base[np.arange(nq), nq + np.arange(nq)] = True
        for (ptr, col, _), shift in ((tables.K, 0), (tables.C, nq)):
            for i in range(nq):
                base[nq + i, shift + col[ptr[i]:ptr[i + 1]]] = True
        self._slots = [np.array(sorted({int(i) for i in tables.cidx[j] if i >= 0}), dtype=np.int64) for j in range(nc)]
        self._law_rows = [2 * nq + int(tables.cso[j]) + np.arange(int(law_states[j])) for j in range(nc)]
        own_rows = []
        for j in range(nc):
            rows = np.concatenate([self._slots[j], nq + self._slots[j], self._law_rows[j]])
            base[np.ix_(rows, rows)] = True
            own_rows.append(rows)
        self.base = base
        #: the columns each contact's own rows hold (what its forces, law states and guards can depend on)
        self._own_columns = [np.flatnonzero(base[r].any(axis=0)) for r in own_rows]
        by_slot: dict = {}
        for j in range(nc):
            for i in self._slots[j].tolist():
                by_slot.setdefault(i, []).append(j)
        self._neighbours = [sorted({k for i in self._slots[j].tolist() for k in by_slot[i]} - {j}) for j in range(nc)]
        self._groups = _greedy_groups(base)
        self._group_of = np.empty(n, dtype=np.int64)
        for k, g in enumerate(self._groups):
            self._group_of[g] = k
        rows, cols = np.nonzero(base)
        order = np.argsort(cols, kind="stable")
        self._rows_by_column = rows[order]   # the rows of column c: [self._column_ptr[c], self._column_ptr[c + 1])
        self._column_ptr = np.concatenate([[0], np.cumsum(np.bincount(cols, minlength=n))])
        self._owners = np.full((len(self._groups), n), -1, dtype=np.int64)
        self._owners[self._group_of[cols], rows] = cols
        self._cluster_rows = Kept(CLUSTER_BYTES)

    def _rows_of(self, columns: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(rows, columns)`` of every entry of the base pattern in ``columns``."""
        lo, hi = self._column_ptr[columns], self._column_ptr[columns + 1]
        counts = hi - lo
        idx = np.repeat(lo - np.cumsum(counts) + counts, counts) + np.arange(int(counts.sum()))
        return self._rows_by_column[idx], np.repeat(columns, counts)

    def _clusters(self, sticking: tuple) -> list:
        """The contacts of ``sticking`` joined by shared coordinates: each cluster a sorted tuple."""
        left, out = set(sticking), []
        for j in sticking:
            if j not in left:
                continue
            left.discard(j)
            cluster, todo = [j], [j]
            while todo:
                for k in self._neighbours[todo.pop()]:
                    if k in left:
                        left.discard(k)
                        cluster.append(k)
                        todo.append(k)
            out.append(tuple(sorted(cluster)))
        return out

    def _cluster(self, cluster: tuple) -> tuple:
        """A cluster's rows (its coordinates' velocities, its law states), the columns they hold, and the
        (row, column) pairs of that block (kept)."""
        found = self._cluster_rows.get(cluster)
        if found is None:
            rows = np.unique(np.concatenate([self.nq + self._slots[j] for j in cluster]
                                            + [self._law_rows[j] for j in cluster]))
            cols = np.flatnonzero(self.base[rows].any(axis=0))
            found = self._cluster_rows[cluster] = (rows, cols, np.repeat(rows, cols.size), np.tile(cols, rows.size))
        return found

    def guard_columns(self, sticking: tuple, j: int) -> np.ndarray:
        """The columns (states) on which contact ``j``'s guards can depend while ``sticking`` stick rigidly.

        Its own rows' columns (its slots' positions and velocities, its law states, and
        what moves those), and, where it sticks, every column of its cluster's rows (its
        stick force is solved from every force on the cluster).
        """
        if j not in sticking:
            return self._own_columns[j]
        cluster = next(c for c in self._clusters(sticking) if j in c)
        return np.union1d(self._own_columns[j], self._cluster(cluster)[1])

    def groups(self, sticking: tuple) -> tuple[list, np.ndarray]:
        """Column groups for the rigidly sticking contacts ``sticking`` (sorted), and each group's row owners.

        Returns ``(groups, owners)``: ``groups[g]`` the columns perturbed together,
        ``owners[g, r]`` the column of the group whose entry row ``r`` holds (``-1``: none
        may be nonzero there). The model's own groups, with the columns that a cluster's
        stick forces couple taken out (their entries now reach the cluster's rows too);
        those go in new groups by their rank in their cluster, so that clusters far apart
        share groups, and each one that would share a row with another there in a group of
        its own.
        """
        clusters = self._clusters(sticking)
        if not clusters:
            return self._groups, self._owners
        n, G = self.n, len(self._groups)
        info = [self._cluster(c) for c in clusters]
        ranked = np.concatenate([c[1] for c in info])
        if ranked.size == 0:
            return self._groups, self._owners
        ranks = np.concatenate([np.arange(c[1].size) for c in info])
        coupled, first = np.unique(ranked, return_index=True)
        gid = self._group_of.copy()
        gid[coupled] = G + ranks[first]
        # their entries: the base pattern's and the clusters' rows
        br, bc = self._rows_of(coupled)
        pc = np.concatenate([bc] + [c[3] for c in info])
        pr = np.concatenate([br] + [c[2] for c in info])
        # a row held by two columns of one new group: all but the least of them get groups of their own
        slot = gid[pc] * n + pr
        order = np.lexsort((pc, slot))
        slot, col = slot[order], pc[order]
        clash = (slot[1:] == slot[:-1]) & (col[1:] != col[:-1])
        alone = np.unique(col[1:][clash])
        gid[alone] = G + ranks.max() + 1 + np.arange(alone.size)
        owners = np.full((int(gid.max()) + 1, n), -1, dtype=np.int64)
        owners[:G] = self._owners
        owners[self._group_of[bc], br] = -1      # taken out of the model's own groups
        owners[gid[pc], pr] = pc
        members = np.argsort(gid, kind="stable")
        bounds = np.searchsorted(gid[members], np.arange(owners.shape[0] + 1))
        keep = np.flatnonzero(np.diff(bounds))
        return [members[bounds[g]:bounds[g + 1]] for g in keep], owners[keep]


def flow_pattern(tables, n: int, law_states) -> FlowPattern | None:
    """A :class:`FlowPattern` of the model, or ``None`` where a contact's normal law is damped (not followed)."""
    if np.any(np.asarray(tables.cnk) == NK_DAMPED):
        return None
    return FlowPattern(tables, n, law_states)


def grouped_flow_matrix(flow, n: int, groups, owners):
    """``A`` (``n x n``, as ``(rows, cols, values)`` of its nonzero entries) from one call of ``flow`` a group.

    ``flow(y)`` is ``f(y)`` on the ``n`` physical states of an affine flow; ``A[:, c]`` is
    ``f(e_c) - f(0)``, here ``f(sum of e_c over a group) - f(0)`` read in the rows each
    column owns (``owners[g, r]``). Returns ``None`` where a row that no column of the
    group owns changed: the pattern missed an entry.
    """
    y = np.zeros(n)
    f0 = flow(y)
    D = np.empty((len(groups), n))
    for k, g in enumerate(groups):
        y[g] = 1.0
        D[k] = flow(y)
        y[g] = 0.0
    D -= f0
    g, rows = np.nonzero(D)
    cols = np.asarray(owners)[g, rows]
    if np.any(cols < 0):
        return None
    return rows, cols, D[g, rows]


def _greedy_groups(P: np.ndarray) -> list:
    """The columns of the pattern ``P`` in groups of which no two share a row (greedy, in column order)."""
    n = P.shape[1]
    used = []   # per group, the rows its columns hold
    color = np.empty(n, dtype=np.int64)
    for c in range(n):
        rows = P[:, c]
        for k, u in enumerate(used):
            if not np.any(u & rows):
                u |= rows
                break
        else:
            k = len(used)
            used.append(rows.copy())
        color[c] = k
    return [np.flatnonzero(color == k) for k in range(len(used))]
