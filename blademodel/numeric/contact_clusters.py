"""The per-contact kernel's clusters: the part of a model an event can reach within one step.

A *template* (see :mod:`.contact_loop`). A step first advances the whole model;
the contacts whose guards crossed (or may have crossed and come back: grazing)
are the step's *seeds*. A seed's *cluster* is everything coupled to it: starting
from its coordinates, a search follows the static coupling of springs and dampers
(``Ap``, ``Ai``: the symmetric sparsity of ``K`` and ``C``) and the contacts that
couple their coordinates (closed ones, those of a law whose states move while
open, and the other seeds). It collects the coordinates reached, the contacts all
of whose coordinates were reached (the cluster's, in ascending order), and those
touching it from outside (its *boundary*: open contacts that couple nothing).
Nothing outside a cluster feels its events within the step, so each cluster is
stepped through its events on its own while the rest of the model keeps the
whole step, and the work of an event grows with its cluster, not with the model.
"""

import math  # noqa: F401

from blademodel.numeric.contract import (NONNEG, H_N, H_NC, H_NLAW, O_AI, O_AP, O_CIDX, O_CLAW, O_CNK, O_CSO, O_DI, O_DP,
                                         R_CC, R_GAP, R_GN, R_K, R_N0, W_FULL, W_NB, W_NCA, W_ND, W_NSA, W_STAMP,
                                         WC_AC, WC_BL, WC_MARK, WC_SEED, WD_AD, WD_MARK)


def mark_seeds(cm, I, WI, G0, G1, D0, D1, dt, width, grazing):
    """Flag (``WC_SEED``) every contact with a guard that crossed over the step, or that may have crossed and
    come back (``grazing``); returns how many."""
    nc = I[H_NC]
    seed, claw = wvec(WI, nc, WC_SEED), vec(I, I, O_CLAW, nc)  # noqa: F821
    count = 0
    for j in range(nc):
        K = claw[j]
        m = cm[j]
        s = contact_crossing(j, m, K, G0, G1) >= 0  # noqa: F821
        if not s and grazing:
            s = contact_grazing(j, m, K, G0, G1, D0, D1, dt, width) > 0.0  # noqa: F821
        seed[j] = 1 if s else 0
        if s:
            count += 1
    return count


def next_cluster(js, local, cm, I, WI, n_state, first_stamp):
    """Make the cluster of the next seed after contact ``js`` not yet in a cluster of this pass the active set;
    return that seed, or -1 when none is left. Without ``local`` the whole model is the one cluster."""
    if not local:
        if js >= 0:
            return -1
        set_full(WI)  # noqa: F821
        return 0
    nc = I[H_NC]
    seed, cmark = wvec(WI, nc, WC_SEED), wvec(WI, nc, WC_MARK)  # noqa: F821
    for j in range(js + 1, nc):
        if seed[j] != 0 and cmark[j] < first_stamp:
            build_cluster(j, cm, I, WI, n_state, first_stamp)
            return j
    return -1


def push_contact(j, cidx, dmark, ad, nd, stamp):
    """Append contact ``j``'s coordinates not yet in the cluster to the search list ``ad``; the new length."""
    for k in range(4):
        i = cidx[4 * j + k]
        if i >= 0 and dmark[i] != stamp:
            dmark[i] = stamp
            ad[nd] = i
            nd += 1
    return nd


def build_cluster(js, cm, I, WI, n_state, first_stamp):
    """Make the cluster of seed contact ``js`` the active set; append its boundary to ``WC_BL``.

    ``first_stamp`` is the stamp of the step's first cluster: a boundary contact
    already listed by an earlier cluster of the step is not listed again.
    """
    n, nc = I[H_N], I[H_NC]
    stamp = WI[W_STAMP] + 1
    WI[W_STAMP] = stamp
    ad, dmark = wdof(WI, nc, n, WD_AD), wdof(WI, nc, n, WD_MARK)  # noqa: F821
    ac, cmark, seed, bl = wvec(WI, nc, WC_AC), wvec(WI, nc, WC_MARK), wvec(WI, nc, WC_SEED), wvec(WI, nc, WC_BL)  # noqa: F821
    Ap, Ai = vec(I, I, O_AP, n + 1), I[I[O_AI]:]  # noqa: F821
    Dp, Di = vec(I, I, O_DP, n + 1), I[I[O_DI]:]  # noqa: F821
    cidx, claw = vec(I, I, O_CIDX, 4 * nc), vec(I, I, O_CLAW, nc)  # noqa: F821
    nd = push_contact(js, cidx, dmark, ad, runtime(0), stamp)  # noqa: F821
    q = 0
    while q < nd:
        i = ad[q]
        q += 1
        for e in range(Ap[i] & NONNEG, Ap[i + 1]):
            k = Ai[e]
            if dmark[k] != stamp:
                dmark[k] = stamp
                ad[nd] = k
                nd += 1
        for e in range(Dp[i] & NONNEG, Dp[i + 1]):
            j = Di[e]
            if cm[j] != 0 or OPEN_RATES[claw[j]] != 0 or seed[j] != 0:  # noqa: F821
                nd = push_contact(j, cidx, dmark, ad, nd, stamp)
    nca = runtime(0)  # noqa: F821
    nb = WI[W_NB]
    for qq in range(nd):
        i = ad[qq]
        for e in range(Dp[i] & NONNEG, Dp[i + 1]):
            j = Di[e]
            if cmark[j] == stamp or cmark[j] == -stamp:
                continue
            inside = True
            for k in range(4):
                i2 = cidx[4 * j + k]
                if i2 >= 0 and dmark[i2] != stamp:
                    inside = False
            if inside:
                cmark[j] = stamp
                ac[nca] = j
                nca += 1
            else:
                if not -cmark[j] >= first_stamp:   # not yet listed by an earlier cluster of this step
                    bl[nb] = j
                    nb += 1
                cmark[j] = -stamp
    WI[W_NB] = nb
    sort_ascending(ac, nca, cmark, stamp, nc)
    rows = wrow(WI, nc, n, n_state, 0)  # noqa: F821
    nsa = 0
    for qq in range(nd):
        i = ad[qq]
        rows[nsa] = i
        rows[nsa + 1] = n + i
        nsa += 2
    cso = vec(I, I, O_CSO, nc)  # noqa: F821
    for jj in range(nca):
        j = ac[jj]
        so = 2 * n + cso[j]
        for s in range(NSTATES[claw[j]]):  # noqa: F821
            rows[nsa] = so + s
            nsa += 1
    for i in range(2 * n + I[H_NLAW], n_state):   # the energy accumulators: the cluster's share
        rows[nsa] = i
        nsa += 1
    WI[W_ND] = nd
    WI[W_NCA] = nca
    WI[W_NSA] = nsa
    WI[W_FULL] = 0


def sort_ascending(a, m, mark, stamp, nc):
    """Sort ``a[:m]`` (the contacts marked ``stamp``) in place: insertion sort when short, a scan of the marks
    otherwise."""
    if m * m <= 8 * nc:
        for p in range(1, m):
            v = a[p]
            q = p - 1
            while q >= 0 and a[q] > v:
                a[q + 1] = a[q]
                q -= 1
            a[q + 1] = v
        return
    p = 0
    for j in range(nc):
        if mark[j] == stamp:
            a[p] = j
            p += 1


def boundary_crossing(y, dy, cm, I, R, WI, G0, G1, D0, D1, dt, width, grazing):
    """A contact on the boundary of the step's clusters whose guard crossed (or grazed) by the step's end, or -1.

    ``y`` and ``dy`` are the state and its rate at the step's end (each cluster's
    through its events, the rest from the whole step). A boundary contact is
    open; its guard and rate at the end are written into ``G1``, ``D1``.
    """
    n, nc = I[H_N], I[H_NC]
    bl, claw = wvec(WI, nc, WC_BL), vec(I, I, O_CLAW, nc)  # noqa: F821
    cidx, cgn, cgap = vec(I, I, O_CIDX, 4 * nc), vec(R, I, R_GN, 4 * nc), vec(R, I, R_GAP, nc)  # noqa: F821
    cnk, ck, cc, cn0 = vec(I, I, O_CNK, nc), vec(R, I, R_K, nc), vec(R, I, R_CC, nc), vec(R, I, R_N0, nc)  # noqa: F821
    for b in range(WI[W_NB]):
        j = bl[b]
        dl = -cgap[j]
        dd = 0.0
        for k in range(4):
            i = cidx[4 * j + k]
            if i >= 0:
                dl += cgn[4 * j + k] * y[i]
                dd += cgn[4 * j + k] * y[n + i]
        G1[j, 0] = normal_guard(j, cm[j], cnk[j], dl, dd, 0.0, ck, cc, cn0)  # noqa: F821
        D1[j, 0] = normal_guard_rate(j, cm[j], cnk[j], dd, 0.0, dy, n, cidx, cgn, ck, cc)  # noqa: F821
        K = claw[j]
        if contact_crossing(j, cm[j], K, G0, G1) >= 0:  # noqa: F821
            return j
        if grazing and contact_grazing(j, cm[j], K, G0, G1, D0, D1, dt, width) > 0.0:  # noqa: F821
            return j
    return -1


def sort_log(k0, k1, log_t, log_c, log_g, log_from, log_to):
    """Order the log entries ``k0 ... k1 - 1`` (one step's, cluster after cluster) by time, stably."""
    k1 = min(k1, log_t.shape[0])
    for p in range(k0 + 1, k1):
        t, c, g, f, to = log_t[p], log_c[p], log_g[p], log_from[p], log_to[p]
        q = p - 1
        while q >= k0 and log_t[q] > t:
            log_t[q + 1], log_c[q + 1], log_g[q + 1] = log_t[q], log_c[q], log_g[q]
            log_from[q + 1], log_to[q + 1] = log_from[q], log_to[q]
            q -= 1
        log_t[q + 1], log_c[q + 1], log_g[q + 1], log_from[q + 1], log_to[q + 1] = t, c, g, f, to
