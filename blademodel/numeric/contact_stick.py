"""The per-contact kernel's rigid stick: the Delassus factor, stick forces and their rates, the projection.

A *template* (see :mod:`.contact_loop`), after :mod:`.contact_flow`; replaced by
:mod:`.contact_rigid_stubs` when no law kind has a rigid stick mode.

Rigid stick (Coulomb) is solved jointly: the stick forces ``x`` of the sticking
contacts satisfy ``W_SS x = G_S M^-1 F_known`` (zero relative tangential
acceleration). ``W = G M^-1 G^T`` couples two contacts only if they share a moved
coordinate, so ``W_SS`` is block diagonal over chains of sticking contacts, and a
chain never leaves its cluster. Everything is stored **by contact index**
(``WC_STK`` flags the sticking contacts; ``Lf[j * nc + k]``, ``Dd[j]``, ``x[j]``),
in contact order: the envelope of row ``j`` starts at ``WC_ENV[j]``, the lowest
sticking contact it is coupled to. Refactoring one cluster's chains leaves every
other chain's rows as they are, and a solve restricted to a cluster touches its
rows only: every entry of an envelope that belongs to another chain is an exact
zero. A refactor writes those zeros itself, for every contact in the envelope that
does not stick or lies outside the active set. It cannot compute them instead: a
row's envelope can span other clusters (a ring's closing contact, coupled to its
first, spans the whole ring), whose stick flags and rows change at their own events
while this row is not refactored; an entry left from an older factor (when the ring's
chain reached that contact) would be read as soon as that contact sticks again, and
the closing chain's stick forces would take a share of another cluster's.

``W_SS`` changes only at events, so it is factored there (``factor_stick``) and
each evaluation only substitutes. If the sticking contacts close a ring, ``W_SS``
is singular (a uniform circulating force changes no blade's motion): the factor
then has one zero pivot (``WI[W_NULL]``), the motion is that of any solution, and
the force distribution reported and checked against the friction cones is the one
that minimises the largest cone ratio ``max |x_j| / (mu N_j)``. Sticking holds
while that ratio is at most 1, i.e. while *some* admissible distribution exists.
"""

import math  # noqa: F401

from blademodel.numeric.contract import (WD_ALL, WC_ALL, NONNEG, F_B, F_CG, F_D, F_FD, F_FR, F_L, F_N, F_ND, F_NULL, F_SG, F_V, F_X,
                                         F_XD, H_N, H_NC, H_NF, H_NG, O_CI, O_CIDX, O_CLAW, O_CP, O_FG, O_FP,
                                         O_KI, O_KP, O_WI, O_WP, R_CV, R_FC, R_FS, R_GN, R_GR, R_INVM, R_K, R_KV,
                                         R_OM, R_W, W_FULL, W_NS, W_NULL, W_STAMP, WC_AC, WC_ENV, WC_MARK,
                                         WC_STK, WD_AD)

#: Relative size of a pivot of the stick matrix below which it counts as zero (a closed ring).
NULL_PIVOT = 1e-10


def in_active_set(j, I, WI):
    """Whether contact ``j`` belongs to the active set (the whole model, or the cluster of the last stamp)."""
    return WI[W_FULL] != 0 or wvec(WI, I[H_NC], WC_MARK)[j] == WI[W_STAMP]  # noqa: F821


def null_pivot_active(I, WI):
    """Whether the stick factor's zero pivot (a closed ring that sticks) lies in the active set."""
    z = WI[W_NULL]
    return z >= 0 and in_active_set(z, I, WI)


def stick_rates_known(I, WI):
    """Whether the active set's stick forces have rates: some contact sticks and no ring of them is closed."""
    nc = I[H_NC]
    if WI[W_NS] == 0 or null_pivot_active(I, WI):
        return False
    full, nca = active_contacts(WI, nc)  # noqa: F821
    ac, stk = wvec(WI, nc, WC_ALL if full else WC_AC), wvec(WI, nc, WC_STK)  # noqa: F821
    for jj in range(nca):
        if stk[ac[jj] & NONNEG]:
            return True
    return False


def factor_stick(cm, I, R, WI, WF):
    """Flag the active set's sticking rigid contacts and factor their Delassus rows (envelope LDL^T)."""
    nc = I[H_NC]
    full, nca = active_contacts(WI, nc)  # noqa: F821
    ac, stk, env = wvec(WI, nc, WC_ALL if full else WC_AC), wvec(WI, nc, WC_STK), wvec(WI, nc, WC_ENV)  # noqa: F821
    claw = vec(I, I, O_CLAW, nc)  # noqa: F821
    W, Lf = vec(R, I, R_W, nc * nc), vec(WF, I, F_L, nc * nc)  # noqa: F821
    Dd, nullv = vec(WF, I, F_D, nc), vec(WF, I, F_NULL, nc)  # noqa: F821
    Wp, Wi = vec(I, I, O_WP, nc + 1), I[I[O_WI]:]  # noqa: F821
    if null_pivot_active(I, WI):
        WI[W_NULL] = -1
    ns = WI[W_NS] & NONNEG
    for jj in range(nca):
        j = ac[jj] & NONNEG
        s = 1 if IS_STICK[claw[j], cm[j]] else 0  # noqa: F821
        ns += s - (0 if full else stk[j])
        stk[j] = s
    WI[W_NS] = ns
    for jj in range(nca):
        j = ac[jj] & NONNEG
        if not stk[j]:
            continue
        e = j
        for q in range(Wp[j] & NONNEG, Wp[j + 1]):
            k = Wi[q]
            if stk[k] and k < e:
                e = k
        env[j] = e
        r = j * nc
        for k in range(e, j):
            if not stk[k] or not in_active_set(k, I, WI):
                Lf[r + k] = 0.0   # another chain's contact, or none: see the module docstring
                continue
            s = W[r + k]
            for m in range(max(e, env[k]), k):
                if stk[m]:
                    s -= Lf[r + m] * Dd[m] * Lf[k * nc + m]
            Lf[r + k] = s / Dd[k] if Dd[k] != 0.0 else 0.0
        d = W[r + j]
        for k in range(e, j):
            if stk[k]:
                d -= Lf[r + k] * Lf[r + k] * Dd[k]
        if d <= NULL_PIVOT * W[r + j]:
            d = 0.0
            WI[W_NULL] = j
        Dd[j] = d
    if null_pivot_active(I, WI):
        for jj in range(nca):
            j = ac[jj] & NONNEG
            nullv[j] = 0.0
        nullv[WI[W_NULL]] = 1.0
        back_substitute(I, WI, WF, nullv)


def back_substitute(I, WI, WF, x):
    """Solve ``L^T x = z`` in place on the active set's sticking rows (unit lower ``L``, envelope storage)."""
    nc = I[H_NC]
    full, nca = active_contacts(WI, nc)  # noqa: F821
    ac, stk, env = wvec(WI, nc, WC_ALL if full else WC_AC), wvec(WI, nc, WC_STK), wvec(WI, nc, WC_ENV)  # noqa: F821
    Lf = vec(WF, I, F_L, nc * nc)  # noqa: F821
    for jj in range(nca - 1, -1, -1):
        k = ac[jj] & NONNEG
        if not stk[k]:
            continue
        xk = x[k]
        if xk != 0.0:
            r = k * nc
            for i in range(env[k], k):
                if stk[i]:
                    x[i] -= Lf[r + i] * xk


def solve_stick(I, WI, WF, b, x):
    """A solution of ``W_SS x = b`` on the active set's sticking rows (the free variable at a null pivot is 0).

    ``b`` may be ``x``.
    """
    nc = I[H_NC]
    full, nca = active_contacts(WI, nc)  # noqa: F821
    ac, stk, env = wvec(WI, nc, WC_ALL if full else WC_AC), wvec(WI, nc, WC_STK), wvec(WI, nc, WC_ENV)  # noqa: F821
    Lf, Dd = vec(WF, I, F_L, nc * nc), vec(WF, I, F_D, nc)  # noqa: F821
    for jj in range(nca):
        j = ac[jj] & NONNEG
        if not stk[j]:
            continue
        s = b[j]
        r = j * nc
        for k in range(env[j], j):
            if stk[k]:
                s -= Lf[r + k] * x[k]
        x[j] = s
    for jj in range(nca):
        j = ac[jj] & NONNEG
        if stk[j]:
            x[j] = x[j] / Dd[j] if Dd[j] != 0.0 else 0.0
    back_substitute(I, WI, WF, x)


def stick_solution(F, b, x, I, R, WI, WF):
    """The stick forces ``x`` for generalized forces ``F``: ``W_SS x = b = G_S M^-1 F`` (``b`` may be ``x``)."""
    n, nc = I[H_N], I[H_NC]
    full, nca = active_contacts(WI, nc)  # noqa: F821
    ac, stk = wvec(WI, nc, WC_ALL if full else WC_AC), wvec(WI, nc, WC_STK)  # noqa: F821
    cidx, cgr, invm = vec(I, I, O_CIDX, 4 * nc), vec(R, I, R_GR, 4 * nc), vec(R, I, R_INVM, n)  # noqa: F821
    for jj in range(nca):
        j = ac[jj] & NONNEG
        if not stk[j]:
            continue
        s = 0.0
        for k in range(4):
            i = cidx[4 * j + k]
            if i >= 0:
                s += cgr[4 * j + k] * invm[i] * F[i]
        b[j] = s
    solve_stick(I, WI, WF, b, x)


def slip_bound(j, y, I, R, WF):
    """The slip force magnitude ``mu N`` of rigid contact ``j`` (its slip+ force)."""
    K = I[I[O_CLAW] + j]
    return law_force(K, RIGID[K, 1], WF[I[F_N] + j], WF[I[F_ND] + j], WF[I[F_V] + j], y,  # noqa: F821
                     law_offset(I, j), R, I, j)  # noqa: F821


def least_cone_ratio(y, I, R, WI, WF):
    """Shift the active set's stick forces along the null vector to minimise ``max |x| / bound``.

    ``f(c) = max_j |x_j + c n_j| / b_j`` is convex and piecewise linear in ``c``; its
    minimum lies where the steepest rising and falling pieces meet. Bisection on the
    sign of the slope narrows the bracket until the pieces active at its two ends
    meet inside it with no piece above them there; ``c`` is then their exact
    intersection (two or three bisections when few contacts stick). The inverse
    bounds are kept in ``bst`` (free once the stick forces are solved).
    """
    nc = I[H_NC]
    full, nca = active_contacts(WI, nc)  # noqa: F821
    ac, stk = wvec(WI, nc, WC_ALL if full else WC_AC), wvec(WI, nc, WC_STK)  # noqa: F821
    xst, nullv, w = vec(WF, I, F_X, nc), vec(WF, I, F_NULL, nc), vec(WF, I, F_B, nc)  # noqa: F821
    lo = math.inf
    hi = -math.inf
    for jj in range(nca):
        j = ac[jj] & NONNEG
        if stk[j]:
            w[j] = 1.0 / max(slip_bound(j, y, I, R, WF), 1e-300)
            if nullv[j] != 0.0:
                c = -xst[j] / nullv[j]
                lo = min(lo, c)
                hi = max(hi, c)
    if not lo < hi:
        return
    # the pieces active at lo (falling: value a0 + s0 c) and at hi (rising: a1 + s1 c)
    _, a0, s0 = cone_piece(lo, nca, ac, stk, xst, nullv, w)
    _, a1, s1 = cone_piece(hi, nca, ac, stk, xst, nullv, w)
    c = 0.5 * (lo + hi)
    for _ in range(200):
        if s1 > s0:
            cx = (a0 - a1) / (s1 - s0)
            if lo <= cx <= hi and cone_piece(cx, nca, ac, stk, xst, nullv, w)[0] <= (a1 + s1 * cx) * (1.0 + 1e-12):
                c = cx
                break
        c = 0.5 * (lo + hi)
        if not lo < c < hi:
            break
        _, a, slope = cone_piece(c, nca, ac, stk, xst, nullv, w)
        if slope > 0.0:
            hi, a1, s1 = c, a, slope
        else:
            lo, a0, s0 = c, a, slope
    for jj in range(nca):
        j = ac[jj] & NONNEG
        if stk[j]:
            xst[j] += c * nullv[j]


def cone_piece(c, nca, ac, stk, xst, nullv, w):
    """``(f(c), a, s)``: the largest cone ratio at ``c`` and its piece ``a + s c`` (see ``least_cone_ratio``)."""
    worst = -1.0
    a = 0.0
    s = 0.0
    for jj in range(nca):
        j = ac[jj] & NONNEG
        if not stk[j]:
            continue
        val = (xst[j] + c * nullv[j]) * w[j]
        if abs(val) > worst:
            worst = abs(val)
            sign = 1.0 if val >= 0.0 else -1.0
            a = sign * xst[j] * w[j]
            s = sign * nullv[j] * w[j]
    return worst, a, s


def cone_ratio(y, I, R, WI, WF):
    """Largest ``|f| / bound`` over the active set's sticking rigid contacts (after ``contact_forces``)."""
    nc = I[H_NC]
    full, nca = active_contacts(WI, nc)  # noqa: F821
    ac, stk, cf = wvec(WI, nc, WC_ALL if full else WC_AC), wvec(WI, nc, WC_STK), vec(WF, I, F_FR, nc)  # noqa: F821
    worst = 0.0
    for jj in range(nca):
        j = ac[jj] & NONNEG
        if not stk[j]:
            continue
        b = slip_bound(j, y, I, R, WF)
        r = abs(cf[j]) / b if b > 0.0 else (0.0 if cf[j] == 0.0 else math.inf)
        worst = max(worst, r)
    return worst


def project_onto_stick(y, I, R, WI, WF):
    """Project the active velocities onto zero slip of every sticking contact (``u -= M^-1 G^T W^-1 G u``)."""
    n, nc = I[H_N], I[H_NC]
    full, nca = active_contacts(WI, nc)  # noqa: F821
    ac, stk = wvec(WI, nc, WC_ALL if full else WC_AC), wvec(WI, nc, WC_STK)  # noqa: F821
    cidx, cgr, invm = vec(I, I, O_CIDX, 4 * nc), vec(R, I, R_GR, 4 * nc), vec(R, I, R_INVM, n)  # noqa: F821
    bst, xst = vec(WF, I, F_B, nc), vec(WF, I, F_X, nc)  # noqa: F821
    for jj in range(nca):
        j = ac[jj] & NONNEG
        if not stk[j]:
            continue
        s = 0.0
        for k in range(4):
            i = cidx[4 * j + k]
            if i >= 0:
                s += cgr[4 * j + k] * y[n + i]
        bst[j] = s
    solve_stick(I, WI, WF, bst, xst)
    for jj in range(nca):
        j = ac[jj] & NONNEG
        if not stk[j]:
            continue
        for k in range(4):
            i = cidx[4 * j + k]
            if i >= 0:
                y[n + i] -= invm[i] * cgr[4 * j + k] * xst[j]


def stick_force_rates(y, dy, cm, I, R, WI, WF):
    """Rates ``xd`` of the active set's stick forces at ``y`` (``dy = dy/dt``; the forces of its last
    ``contact_forces``).

    The time derivative of the stick condition ``W_SS x = G_S M^-1 F``: the same
    factor solves ``W_SS xd = G_S M^-1 dF/dt``, with ``dF/dt`` of the springs, dampers,
    forcing, normal forces and explicit friction forces (``law_force_rate``).
    """
    n, nc = I[H_N], I[H_NC]
    full, nd = active_dofs(WI, n)  # noqa: F821
    full, nca = active_contacts(WI, nc)
    ad, ac = wdof(WI, nc, n, WD_ALL if full else WD_AD), wvec(WI, nc, WC_ALL if full else WC_AC)  # noqa: F821
    Kp, Ki = vec(I, I, O_KP, n + 1), I[I[O_KI]:]  # noqa: F821
    Cp, Ci = vec(I, I, O_CP, n + 1), I[I[O_CI]:]  # noqa: F821
    Kv, Cv = R[I[R_KV]:], R[I[R_CV]:]
    Fp, fg = vec(I, I, O_FP, n + 1), vec(I, I, O_FG, I[H_NF])  # noqa: F821
    fs, fc, om = vec(R, I, R_FS, I[H_NF]), vec(R, I, R_FC, I[H_NF]), vec(R, I, R_OM, I[H_NG])  # noqa: F821
    sg, cg = vec(WF, I, F_SG, I[H_NG]), vec(WF, I, F_CG, I[H_NG])  # noqa: F821
    cidx, claw = vec(I, I, O_CIDX, 4 * nc), vec(I, I, O_CLAW, nc)  # noqa: F821
    cgn, cgr, ck = vec(R, I, R_GN, 4 * nc), vec(R, I, R_GR, 4 * nc), vec(R, I, R_K, nc)  # noqa: F821
    cN, cNd, cv = vec(WF, I, F_N, nc), vec(WF, I, F_ND, nc), vec(WF, I, F_V, nc)  # noqa: F821
    Fd, xd = vec(WF, I, F_FD, n), vec(WF, I, F_XD, nc)  # noqa: F821
    for ii in range(nd):
        i = ad[ii] & NONNEG
        s = 0.0
        for e in range(Kp[i] & NONNEG, Kp[i + 1]):
            s -= Kv[e] * y[n + (Ki[e] & NONNEG)]
        for e in range(Cp[i] & NONNEG, Cp[i + 1]):
            s -= Cv[e] * dy[n + (Ci[e] & NONNEG)]
        for e in range(Fp[i] & NONNEG, Fp[i + 1]):
            g = fg[e] & NONNEG
            s += om[g] * (fs[e] * cg[g] - fc[e] * sg[g])
        Fd[i] = s
    for jj in range(nca):
        j = ac[jj] & NONNEG
        mode = cm[j]
        if mode == 0:
            continue
        K = claw[j]
        fdj = 0.0
        if not IS_STICK[K, mode]:  # noqa: F821
            Ndd, vd = contact_rates(j, dy, n, cidx, cgn, cgr, ck)  # noqa: F821
            fdj = law_force_rate(K, mode, cN[j], cNd[j], Ndd, cv[j], vd, y,  # noqa: F821
                                 law_offset(I, j), R, I, j, dy)  # noqa: F821
        for k in range(4):
            i = cidx[4 * j + k]
            if i >= 0:
                Fd[i] -= cNd[j] * cgn[4 * j + k] + fdj * cgr[4 * j + k]
    stick_solution(Fd, xd, xd, I, R, WI, WF)
