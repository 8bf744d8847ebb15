"""The per-contact kernel's sub-step derivatives, guard differences and cluster steps, for the replayed tangent.

A *template* (see :mod:`.contact_loop`), used by
:class:`~blademodel.numeric.contact_tangent.ContactTangent` only: it is compiled
the first time a ring's period map is differentiated, not when the kernel runs.

Within a mode the flow is affine, ``f(t, y) = A y + b(t)``. One sub-step of the
kernel's explicit Runge-Kutta method from ``(t, y)`` of length ``h`` has stages
``K_i = f(T_i, Y_i)``, ``T_i = t + c_i h``, ``Y_i = y + h sum_j a_ij K_j``, and ends
at ``y + h sum_i b_i K_i``. Its derivatives in its length and in its start time
(the state fixed) are those of the stages::

    dK_i/dh  = A dY_i/dh + c_i b'(T_i),   dY_i/dh  = sum_j a_ij (K_j + h dK_j/dh)
    dK_i/dt0 = A dY_i/dt0 + b'(T_i),      dY_i/dt0 = h sum_j a_ij dK_j/dt0

``b'(T)`` is a central difference of ``f(T, 0)`` with the step ``d``. The
derivatives are formed on ``rows`` only, the cluster's state rows, which ``A``
couples to nothing outside (``Ar`` is ``A``'s block on them); the end state is whole.

A guard's rate in time is a central difference; its gradient in the state is kept
from the zero state where it predicts the guard's change along a probe at the
event, and where it does not (the joint stick forces of a closed ring make a guard
affine only piecewise) it is central differences at the event's state
(``guard_derivatives``).

``cluster_step`` takes a cluster's whole step through its events in one call: the
sub-steps, the event times' rows, the resets' central differences and the stick
projections, applied to the identity on the cluster's rows (the step is linear in the
tangent), on the kernel's own cluster of those events as the active set. A law with
labels (Iwan) decides them from the state: its resets follow a plan recorded from the
Python step (the labels each sets, their Jacobian for those labels), and the step checks
that its transitions set those labels (``decided_transition``).
"""

import math  # noqa: F401

from blademodel.numeric.contract import H_N, H_NC, NONNEG, O_CLAW, W_NB, W_STAMP, WC_SEED


def substep_derivatives(t, y, h, cm, d, Ar, rows, ta, tb, tc, I, R, WI, WF, K, Kh, Kt, BT, Y, Z, F, end, Pt, Ph):
    """The sub-step of length ``h`` from ``(t, y)`` in ``cm``: its end into ``end``, and on ``rows`` its end's
    derivatives in the start time into ``Pt`` and in the length into ``Ph``.

    ``ta, tb, tc``: the method's tableau. Work arrays: ``K`` (stages, full rows),
    ``Kh, Kt, BT`` (stages by cluster rows), ``Y``, ``F`` (a full state each), ``Z``
    (a full zero state, left zero). The stick problem of ``cm`` must be factored.
    """
    replay_substep(t, y, h, cm, d, Ar, rows, ta, tb, tc, I, R, WI, WF, K, Kh, Kt, BT, Y, Z, F, end, Pt, Ph)


def replay_substep(t, y, h, cm, d, Ar, rows, ta, tb, tc, I, R, WI, WF, K, Kh, Kt, BT, Y, Z, F, end, Pt, Ph):
    """:func:`substep_derivatives`, linked into the compiled functions that call it."""
    s = tb.shape[0]
    ns = y.shape[0]
    nr = rows.shape[0]
    for i in range(s):
        for k in range(ns):
            Y[k] = y[k]
        for j in range(i):
            a = ta[i, j]
            if a != 0.0:
                for k in range(ns):
                    Y[k] += h * a * K[j, k]
        T = t + tc[i] * h
        rhs(T, Y, cm, I, R, WI, WF, K[i])  # noqa: F821
        # the forcing's rate at T: once per distinct node
        same = -1
        for j in range(i):
            if tc[j] == tc[i]:
                same = j
                break
        if same >= 0:
            for r in range(nr):
                BT[i, r] = BT[same, r]
        else:
            rhs(T + d, Z, cm, I, R, WI, WF, F)  # noqa: F821
            for r in range(nr):
                BT[i, r] = F[rows[r]]
            rhs(T - d, Z, cm, I, R, WI, WF, F)  # noqa: F821
            for r in range(nr):
                BT[i, r] = (BT[i, r] - F[rows[r]]) / (2.0 * d)
        for r in range(nr):
            yh = 0.0
            yt = 0.0
            for j in range(i):
                a = ta[i, j]
                if a != 0.0:
                    yh += a * (K[j, rows[r]] + h * Kh[j, r])
                    yt += h * a * Kt[j, r]
            Pt[r] = yh   # the stage's dY/dh and dY/dt0, kept until every row's product is formed
            Ph[r] = yt
        for r in range(nr):
            ah = 0.0
            at = 0.0
            for c in range(nr):
                ah += Ar[r, c] * Pt[c]
                at += Ar[r, c] * Ph[c]
            Kh[i, r] = ah + tc[i] * BT[i, r]
            Kt[i, r] = at + BT[i, r]
    for k in range(ns):
        end[k] = y[k]
    for i in range(s):
        bi = tb[i]
        if bi != 0.0:
            for k in range(ns):
                end[k] += h * bi * K[i, k]
    for r in range(nr):
        ph = 0.0
        pt = 0.0
        for i in range(s):
            ph += tb[i] * (K[i, rows[r]] + h * Kh[i, r])
            pt += h * tb[i] * Kt[i, r]
        Ph[r] = ph
        Pt[r] = pt


def guard_derivatives(t, y, cm, j, gi, rows, steps, d, gyr, I, R, WI, WF, G, Y, out):
    """``(g_t, kept)`` of contact ``j``'s guard ``gi`` at ``(t, y)`` in ``cm``: ``g_t`` a central difference in
    time (step ``d``), and ``kept`` 1 if the kept gradient ``gyr`` (on ``rows``) predicts the guard's change
    along the probe ``steps`` (on ``rows``) to ``1e-7``, else 0 with the gradient on ``rows`` in ``out``, central
    differences at ``y`` with those steps (``Y``: a full state, work). The stick problem of ``cm`` must be
    factored."""
    return replay_guard(t, y, cm, j, gi, rows, steps, d, gyr, I, R, WI, WF, G, Y, out)


def replay_guard(t, y, cm, j, gi, rows, steps, d, gyr, I, R, WI, WF, G, Y, out):
    """:func:`guard_derivatives`, linked into the compiled functions that call it."""
    eval_guards(t + d, y, cm, I, R, WI, WF, G)  # noqa: F821
    gp = G[j, gi]
    eval_guards(t - d, y, cm, I, R, WI, WF, G)  # noqa: F821
    gt = (gp - G[j, gi]) / (2.0 * d)
    for k in range(y.shape[0]):
        Y[k] = y[k]
    predicted = 0.0
    for r in range(rows.shape[0]):
        Y[rows[r]] = y[rows[r]] + steps[r]
        predicted += gyr[r] * steps[r]
    eval_guards(t, Y, cm, I, R, WI, WF, G)  # noqa: F821
    gp = G[j, gi]
    for r in range(rows.shape[0]):
        Y[rows[r]] = y[rows[r]] - steps[r]
    eval_guards(t, Y, cm, I, R, WI, WF, G)  # noqa: F821
    change = gp - G[j, gi]
    if abs(change - 2.0 * predicted) <= 1e-7 * (abs(change) + abs(predicted)):
        return gt, 1
    for r in range(rows.shape[0]):
        Y[rows[r]] = y[rows[r]]
    for r in range(rows.shape[0]):
        i = rows[r]
        e = steps[r]
        Y[i] = y[i] + e
        eval_guards(t, Y, cm, I, R, WI, WF, G)  # noqa: F821
        gp = G[j, gi]
        Y[i] = y[i] - e
        eval_guards(t, Y, cm, I, R, WI, WF, G)  # noqa: F821
        out[r] = (gp - G[j, gi]) / (2.0 * e)
        Y[i] = y[i]
    return gt, 0


def cluster_step(X0, X1, out, rows, t0, t1, y0, cm, H, ng, gtime, gfc, gfg, goff, gmc, gmto, gmg, mlo, mn, Ab, proj,
                 PB, gyr, rk, RB, RM, lfo, lrow, ltg, hs, poly, nphys, ta, tb, tc, I, R, WI, WF, G, K, Kh, Kt, BT, Y, Z,
                 F, end, ya, Pt, Ph, dta, dtb, Rb, Rb2, steps, cols, Y2, D, RW, info):
    """A step through a cluster's transition groups applied to ``X0`` (on the cluster's ``rows``), into ``out``;
    0, or 1 where a guard that fired has no rate (its time in ``info[0]``).

    The compiled form of ``ContactTangent._cluster_step`` for laws without labels; its
    caller passes the identity as ``X0`` (overwritten; ``X1`` the same shape, work) and gets
    the step's matrix on ``rows``. The sub-steps evaluate the kernel's cluster of these
    events only (its active set, as the kernel stepped them) where that cluster holds
    ``rows`` (``info[1]`` 1), else the whole model (``info[1]`` 0); the whole model is
    active again on return.

    The step from ``t0`` to ``t1`` (``H`` the whole step's length) starts at ``y0`` in the
    modes ``cm`` (changed to the step's end modes). Group ``g < ng`` of transitions, all at
    ``gtime[g]``: the guard ``gfg[g]`` of contact ``gfc[g]`` fired it (``-1``: none, a mode
    the friction problem set, no event time to move); its transitions ``q`` in ``goff[g] ..
    goff[g + 1]`` set contact ``gmc[q]`` to mode ``gmto[q]`` by its guard ``gmg[q]`` and
    reset the ``mn[q]`` law states from row ``mlo[q]`` (none where ``mn[q]`` is 0), whose
    rows of the block become the reset's central differences in ``rows`` (as
    ``ContactTangent._reset_jacobian``'s; ``nphys``: the physical states); where
    ``proj[g]`` is not 0 a rigid contact starts to stick and the block is projected by
    ``PB[proj[g] - 1]``. ``gyr[g]``: the fired guard's kept gradient on ``rows`` (NaN: none,
    central differences at the event).

    A law with labels (the Iwan elements' modes): its transitions ``q`` with ``rk[q] > 0``
    are *recorded* (from the Python step's first run of the plan): their reset is taken past
    the guard's root where the state lies short of it, and a little farther along the flow
    (``1e-14`` of the kernel's step ``hs``, ten times more each try, up to ``1e-8``) until it
    sets the labels ``lrow[lfo[q]:lfo[q + 1]]`` to the recorded ``ltg[...]``
    (:func:`decided_transition`), and the block's rows ``RM[rk[q] - 1, s]`` (its law states'
    among ``rows``, up to the first ``-1``) become ``RB[rk[q] - 1, s]`` times the block (the
    reset's Jacobian for these labels, affine, as ``ContactTangent._reset_jacobian`` took
    it). Where no try sets them, 2 and the time in ``info[0]``: the caller steps the cluster
    in Python. ``Ab[g]``: ``A``'s block on ``rows`` in the modes of the sub-step before
    group ``g`` (``Ab[ng]``: after the last). ``poly``: the method's stability polynomial,
    lowest power first (``R(hA)`` on the block by Horner's rule). The rest are work arrays:
    the sub-step's (:func:`substep_derivatives`), ``ya`` and ``Y2`` (a full state each),
    ``dta, dtb`` (a row of the block each), ``Rb, Rb2`` (a block of ``A``'s each),
    ``steps, cols`` (a row's
    length each), ``D`` and ``RW`` (the most law states by a row's length and by a row of
    the block).
    """
    nr = rows.shape[0]
    m = X0.shape[1]
    ns = y0.shape[0]
    deg = poly.shape[0] - 1
    d = 1e-6 * H
    info[1] = activate_cluster(rows, gmc, cm, I, WI, ns)
    status = through_groups(X0, X1, out, rows, t0, t1, y0, cm, ng, gtime, gfc, gfg, goff, gmc, gmto, gmg, mlo, mn, Ab,
                            proj, PB, gyr, rk, RB, RM, lfo, lrow, ltg, hs, poly, nphys, ta, tb, tc, I, R, WI, WF, G, K,
                            Kh, Kt, BT, Y, Z, F, end, ya, Pt, Ph, dta, dtb, Rb, Rb2, steps, cols, Y2, D, RW, info, nr,
                            m, ns, deg, d)
    set_full(WI)  # noqa: F821
    return status


def activate_cluster(rows, gmc, cm, I, WI, ns):
    """Make the kernel's cluster of the contacts ``gmc`` (its seeds; ``cm`` the modes at the step's start) the
    active set, as the kernel steps it: 1 if it holds every one of ``rows``, else the whole model active and 0."""
    nc, n = I[H_NC], I[H_N]
    seed = wvec(WI, nc, WC_SEED)  # noqa: F821
    for j in range(nc):
        seed[j] = 0
    for q in range(gmc.shape[0]):
        seed[gmc[q]] = 1
    WI[W_NB] = 0
    build_cluster(gmc[0], cm, I, WI, ns, WI[W_STAMP] + 1)  # noqa: F821
    full, nsa = active_rows(WI, ns)  # noqa: F821
    active = wrow(WI, nc, n, ns, 0)  # noqa: F821
    for r in range(rows.shape[0]):
        held = False
        for ii in range(nsa):
            if (active[ii] & NONNEG) == rows[r]:
                held = True
                break
        if not held:
            set_full(WI)  # noqa: F821
            return 0
    return 1


def through_groups(X0, X1, out, rows, t0, t1, y0, cm, ng, gtime, gfc, gfg, goff, gmc, gmto, gmg, mlo, mn, Ab, proj,
                   PB, gyr, rk, RB, RM, lfo, lrow, ltg, hs, poly, nphys, ta, tb, tc, I, R, WI, WF, G, K, Kh, Kt, BT, Y,
                   Z, F, end, ya, Pt, Ph, dta, dtb, Rb, Rb2, steps, cols, Y2, D, RW, info, nr, m, ns, deg, d):
    """:func:`cluster_step`'s sequence, on the active set it chose."""
    for k in range(ns):
        ya[k] = y0[k]
    for c in range(m):
        dta[c] = 0.0
    start = t0
    cur = 0   # the block is in X0 (0) or X1 (1)
    for g in range(ng + 1):
        te = gtime[g] if g < ng else t1
        h = te - start
        factor_stick(cm, I, R, WI, WF)  # noqa: F821
        replay_substep(start, ya, h, cm, d, Ab[g], rows, ta, tb, tc, I, R, WI, WF, K, Kh, Kt, BT, Y, Z, F, end,
                       Pt, Ph)
        # R(h A) on the block by Horner's rule: c_0 I + h A (c_1 I + h A (c_2 I + ...))
        for r in range(nr):
            for c in range(nr):
                Rb[r, c] = poly[deg] * h * Ab[g, r, c]
            Rb[r, r] += poly[deg - 1]
        for k in range(deg - 2, -1, -1):
            for r in range(nr):
                for c in range(nr):
                    Rb2[r, c] = 0.0
                for q in range(nr):
                    a = h * Ab[g, r, q]
                    if a != 0.0:
                        for c in range(nr):
                            Rb2[r, c] += a * Rb[q, c]
            for r in range(nr):
                for c in range(nr):
                    Rb[r, c] = Rb2[r, c]
                Rb[r, r] += poly[k]
        src = X0 if cur == 0 else X1
        dst = out if g == ng else (X1 if cur == 0 else X0)
        for r in range(nr):
            w = Pt[r] - Ph[r]
            for c in range(m):
                dst[r, c] = w * dta[c]
            for q in range(nr):
                a = Rb[r, q]
                if a != 0.0:
                    for c in range(m):
                        dst[r, c] += a * src[q, c]
        if g == ng:
            return 0
        j = gfc[g]
        if j >= 0:
            big = 0.0
            for r in range(nr):
                big = max(big, abs(end[rows[r]]))
            for r in range(nr):
                steps[r] = 1e-6 * max(abs(end[rows[r]]), 1e-3 * big)
            gt, kept = replay_guard(te, end, cm, j, gfg[g], rows, steps, d, gyr[g], I, R, WI, WF, G, Y, cols)
            if kept == 1:
                for r in range(nr):
                    cols[r] = gyr[g, r]
            rate = gt
            for r in range(nr):
                rate += cols[r] * Ph[r]
            if rate == 0.0 or not math.isfinite(rate):
                info[0] = te
                return 1
            for c in range(m):
                dtb[c] = 0.0
            for r in range(nr):
                a = cols[r]
                if a != 0.0:
                    for c in range(m):
                        dtb[c] += a * dst[r, c]
            for c in range(m):
                dtb[c] = -dtb[c] / rate
        else:
            for c in range(m):
                dtb[c] = 0.0
        for r in range(nr):
            a = Ph[r]
            for c in range(m):
                dst[r, c] += a * dtb[c]
        for q in range(goff[g], goff[g + 1]):
            if rk[q] > 0:
                if decided_transition(te, end, cm, gmc[q], gmg[q], lrow[lfo[q]:lfo[q + 1]], ltg[lfo[q]:lfo[q + 1]],
                                      hs, I, R, WI, WF, G, Y2, F, Y) == 0:
                    info[0] = te
                    return 2
                replace_rows(dst, RB[rk[q] - 1], RM[rk[q] - 1], RW)
            elif mn[q] > 0:
                reset_rows(te, end, y0, cm, gmc[q], gmg[q], mlo[q], mn[q], rows, nphys, dst, I, R, WI,
                           WF, G, Y2, D, RW)
            cm[gmc[q]] = gmto[q]
        cur = 1 - cur   # the block is in dst now
        if proj[g] != 0:
            rows_times(PB[proj[g] - 1], nr, dst, src)   # (src is free: the block is in dst)
            cur = 1 - cur
        start = te
        for k in range(ns):
            ya[k] = end[k]
        for c in range(m):
            dta[c] = dtb[c]
    return 0


def reset_rows(t, y, y0, cm, j, gi, lo, nst, rows, nphys, V, I, R, WI, WF, G, Y2, D, RW):
    """Contact ``j``'s reset by guard ``gi`` at ``(t, y)`` in ``cm`` applied to the block ``V`` on ``rows`` (its
    law states' rows ``lo .. lo + nst`` become the reset's central differences in ``rows``) and to ``y``.

    A difference's step is ``1e-6`` of its state, at least ``1e-9`` of the largest physical
    state at the step's start ``y0`` (``y`` is valid on the active set only)."""
    nr = rows.shape[0]
    m = V.shape[1]
    ns = y.shape[0]
    big = 0.0
    for i in range(nphys):
        big = max(big, abs(y0[i]))
    big = 1e-3 * max(big, 1e-300)
    for rc in range(nr):
        c = rows[rc]
        e = 1e-6 * max(abs(y[c]), big)
        for k in range(ns):
            Y2[k] = y[k]
        Y2[c] = y[c] + e
        apply_transition(t, Y2, cm, j, gi, I, R, WI, WF, G)  # noqa: F821
        for s in range(nst):
            D[s, rc] = Y2[lo + s]
        for k in range(ns):
            Y2[k] = y[k]
        Y2[c] = y[c] - e
        apply_transition(t, Y2, cm, j, gi, I, R, WI, WF, G)  # noqa: F821
        for s in range(nst):
            D[s, rc] = (D[s, rc] - Y2[lo + s]) / (2.0 * e)
    rows_times(D, nst, V, RW)
    for r in range(nr):
        if lo <= rows[r] < lo + nst:
            for c in range(m):
                V[r, c] = RW[rows[r] - lo, c]
    apply_transition(t, y, cm, j, gi, I, R, WI, WF, G)  # noqa: F821


def crossed_to(g, d):
    """Whether a guard of value ``g`` lies past its root in its direction ``d`` (``-1``: falling, ``1``: rising)."""
    return (d < 0 and g < 0.0) or (d > 0 and g > 0.0)


def same_labels(y, lrow, ltg):
    """Whether ``y``'s labels ``lrow`` are ``ltg``."""
    for i in range(lrow.shape[0]):
        if y[lrow[i]] != ltg[i]:
            return False
    return True


def decided_transition(t, y, cm, j, gi, lrow, ltg, hs, I, R, WI, WF, G, Y2, F, Y):
    """Contact ``j``'s transition by guard ``gi`` at ``(t, y)`` in ``cm`` where its law decides labels from the
    state, as the kernel decided them (``ContactTangent._past_root`` and ``_as_the_kernel``): 1 with ``y`` the
    state after it, its labels ``lrow`` the recorded ``ltg``; 0 (``y`` unchanged) where no try sets them.

    The kernel fires at the far end of its event's bracket: a state short of the guard's
    root (by rounding) is moved along the flow by ``1e-14`` of the step ``hs``, ten times
    more each try up to ``1e-8``, until the guard has crossed; then, from there, likewise
    until the transition sets the recorded labels. ``Y2``, ``F``, ``Y``: full states, work."""
    ns = y.shape[0]
    K = I[I[O_CLAW] + j]
    d = GDIR[K, cm[j], gi]  # noqa: F821
    for k in range(ns):
        Y2[k] = y[k]
    if d != 0:
        factor_stick(cm, I, R, WI, WF)  # noqa: F821
        eval_guards(t, y, cm, I, R, WI, WF, G)  # noqa: F821
        if not crossed_to(G[j, gi], d):
            rhs(t, y, cm, I, R, WI, WF, F)  # noqa: F821
            for e in range(14, 7, -1):
                dt = 10.0 ** -e * hs
                for k in range(ns):
                    Y[k] = y[k] + dt * F[k]
                eval_guards(t + dt, Y, cm, I, R, WI, WF, G)  # noqa: F821
                if crossed_to(G[j, gi], d):
                    for k in range(ns):
                        Y2[k] = Y[k]
                    break
    for k in range(ns):
        Y[k] = Y2[k]
    apply_transition(t, Y, cm, j, gi, I, R, WI, WF, G)  # noqa: F821
    if not same_labels(Y, lrow, ltg):
        factor_stick(cm, I, R, WI, WF)  # noqa: F821
        rhs(t, Y2, cm, I, R, WI, WF, F)  # noqa: F821
        decided = False
        for e in range(14, 7, -1):
            dt = 10.0 ** -e * hs
            for k in range(ns):
                Y[k] = Y2[k] + dt * F[k]
            apply_transition(t, Y, cm, j, gi, I, R, WI, WF, G)  # noqa: F821
            if same_labels(Y, lrow, ltg):
                decided = True
                break
        if not decided:
            return 0
    for k in range(ns):
        y[k] = Y[k]
    return 1


def replace_rows(V, B, M, RW):
    """The rows ``M[s]`` of ``V`` replaced by ``B[s] @ V``, for ``s`` up to the first ``M[s] < 0`` (all formed
    before any is written; ``RW``: as many rows as ``B``, work)."""
    n = 0
    while n < M.shape[0] and M[n] >= 0:
        n += 1
    rows_times(B, n, V, RW)
    for s in range(n):
        for c in range(V.shape[1]):
            V[M[s], c] = RW[s, c]


def rows_times(B, n, V, out):
    """``out[s] = B[s] @ V`` for ``s < n`` (``B``'s zeros skipped); ``out`` must not be ``V``."""
    for s in range(n):
        for c in range(V.shape[1]):
            out[s, c] = 0.0
        for q in range(V.shape[0]):
            a = B[s, q]
            if a != 0.0:
                for c in range(V.shape[1]):
                    out[s, c] += a * V[q, c]
