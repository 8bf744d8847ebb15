"""The per-contact kernel's flow: buffer views, the active set, forces, ``dy/dt`` and Runge-Kutta steps.

A *template* (see :mod:`.contact_loop`): pasted into the generated module after the
friction laws' functions and tables (``law_force``, ``law_rates``,
``law_dissipation``, ``IS_STICK`` ...), compiled with Numba.

**The active set.** Every function here works on the *active set* held in the
work array ``WI``: the whole model (``WI[W_FULL] == 1``, the lists are not read),
or one *cluster* (coordinates ``WD_AD``, contacts ``WC_AC`` in ascending order,
state rows ``wrow``; built by :mod:`.contact_clusters`). A cluster is closed
under coupling: no spring, damper, closed contact or stick constraint joins one
of its coordinates to a coordinate outside it, so its forces, accelerations and
stick forces depend on its own rows alone, and a function restricted to it
computes, operation for operation, what the whole model's would on those rows.
The energy accumulators (the last three states, when kept) are sums over the
model: restricted, they receive the cluster's share.
"""

import math  # noqa: F401

from blademodel.numeric.contract import (WD_ALL, WC_ALL, NONNEG, F_CG, F_DL, F_DR, F_F, F_FR, F_N, F_ND, F_SG, F_T, F_V, F_X, F_B,
                                         H_N, H_NC, H_NF, H_NG, H_NLAW, H_NS, NK_DAMPED, NK_LOAD, NK_SPRING,
                                         O_CI, O_CIDX, O_CLAW, O_CNK, O_CP, O_CSO, O_FG, O_FI, O_FP, O_KI, O_KP,
                                         R_CC, R_CV, R_FC, R_FS, R_GN, R_GR, R_GAP, R_INVM, R_K, R_KV, R_N0,
                                         R_OM, R_RK, R_TAB, R_TG, SC_ROWS, SNAP_ULPS, W_FULL, W_HEAD, W_NCA, W_ND,
                                         W_NS, W_NSA, WC_AC, WC_COUNT, WC_STK, WD_AD, WD_COUNT)


def runtime(x):
    """``x`` (an int or bool) as a run-time value: Numba types a constant argument as a
    literal and compiles a copy of the callee, and of all it calls, for each literal
    (``x | x`` is ``x``, and no longer a literal)."""
    return x | x


# ---- views of the flat buffers --------------------------------------------------------------
def vec(a, I, key, size):
    """The table at offset ``I[key]`` of ``a``, ``size`` long (a table of rows is read as ``t[row * width + col]``)."""
    o = I[key]
    return a[o:o + size]


def wvec(WI, nc, k):
    """The ``k``-th per-contact array of ``WI`` (``WC_*``)."""
    o = W_HEAD + k * nc
    return WI[o:o + nc]


def wdof(WI, nc, n, k):
    """The ``k``-th per-coordinate array of ``WI`` (``WD_*``)."""
    o = W_HEAD + WC_COUNT * nc + k * n
    return WI[o:o + n]


def wrow(WI, nc, n, ns, k):
    """State rows (``ns`` = the state's length): a cluster's (``k = 0``) or every row (``k = 1``)."""
    o = W_HEAD + WC_COUNT * nc + WD_COUNT * n + k * ns
    return WI[o:o + ns]


def law_offset(I, j):
    """Offset in ``y`` of contact ``j``'s law states."""
    return 2 * I[H_N] + I[I[O_CSO] + j]


def set_full(WI):
    """Make the whole model the active set."""
    WI[W_FULL] = 1


def active_dofs(WI, n):
    """``(full, count)`` of the active coordinates (``n``: the model's)."""
    if WI[W_FULL] != 0:
        return True, n
    return False, WI[W_ND]


def active_contacts(WI, nc):
    """``(full, count)`` of the active contacts (``nc``: the model's)."""
    if WI[W_FULL] != 0:
        return True, nc
    return False, WI[W_NCA]


def active_rows(WI, ns):
    """``(full, count)`` of the active state rows (``ns``: the state's length)."""
    if WI[W_FULL] != 0:
        return True, ns
    return False, WI[W_NSA]


def copy_rows(WI, nc, n, dst, src):
    """``dst = src`` on the active state rows."""
    full, nsa = active_rows(WI, dst.shape[0])
    rows = wrow(WI, nc, n, dst.shape[0], 1 if full else 0)
    for ii in range(nsa):
        i = rows[ii] & NONNEG
        dst[i] = src[i]


# ---- forces and flow --------------------------------------------------------------------
def contact_forces(t, y, cm, I, R, WI, WF):
    """Generalized forces ``F`` and each contact's ``N``, ``Nd``, ``v``, ``f``, penetration, on the active set.

    Returns the input power of the forcing (for the energy accumulators).
    """
    n, nc, ng = I[H_N], I[H_NC], I[H_NG]
    full, nd = active_dofs(WI, n)
    full, nca = active_contacts(WI, nc)
    ad, ac = wdof(WI, nc, n, WD_ALL if full else WD_AD), wvec(WI, nc, WC_ALL if full else WC_AC)
    Kp, Ki = vec(I, I, O_KP, n + 1), I[I[O_KI]:]
    Cp, Ci = vec(I, I, O_CP, n + 1), I[I[O_CI]:]
    Kv, Cv = R[I[R_KV]:], R[I[R_CV]:]
    Fp = vec(I, I, O_FP, n + 1)
    fg, fs, fc = vec(I, I, O_FG, I[H_NF]), vec(R, I, R_FS, I[H_NF]), vec(R, I, R_FC, I[H_NF])
    cidx, claw = vec(I, I, O_CIDX, 4 * nc), vec(I, I, O_CLAW, nc)
    cgn, cgr = vec(R, I, R_GN, 4 * nc), vec(R, I, R_GR, 4 * nc)
    cgap, ck = vec(R, I, R_GAP, nc), vec(R, I, R_K, nc)
    cnk, cc, cn0 = vec(I, I, O_CNK, nc), vec(R, I, R_CC, nc), vec(R, I, R_N0, nc)
    F = vec(WF, I, F_F, n)
    cN, cNd, cv, cf, cdl = (vec(WF, I, F_N, nc), vec(WF, I, F_ND, nc), vec(WF, I, F_V, nc),
                            vec(WF, I, F_FR, nc), vec(WF, I, F_DL, nc))
    sg, cg = vec(WF, I, F_SG, ng), vec(WF, I, F_CG, ng)
    cdr = vec(WF, I, F_DR, nc)
    if WF[I[F_T]] != t:   # RK4's middle stages and a step's end share their time: sin and cos kept
        forcing_phase(t, I, R, WF)
    power = 0.0
    for ii in range(nd):
        i = ad[ii] & NONNEG
        s = 0.0
        for e in range(Kp[i] & NONNEG, Kp[i + 1]):
            s -= Kv[e] * y[Ki[e] & NONNEG]
        for e in range(Cp[i] & NONNEG, Cp[i + 1]):
            s -= Cv[e] * y[n + (Ci[e] & NONNEG)]
        for e in range(Fp[i] & NONNEG, Fp[i + 1]):
            load = fs[e] * sg[fg[e] & NONNEG] + fc[e] * cg[fg[e] & NONNEG]
            s += load
            power += load * y[n + i]
        F[i] = s
    for jj in range(nca):
        j = ac[jj] & NONNEG
        dl = -cgap[j]
        dd = 0.0
        vv = 0.0
        for k in range(4):
            i = cidx[4 * j + k]
            if i >= 0:
                dl += cgn[4 * j + k] * y[i]
                dd += cgn[4 * j + k] * y[n + i]
                vv += cgr[4 * j + k] * y[n + i]
        cdl[j] = dl
        cdr[j] = dd
        cv[j] = vv
        mode = cm[j]
        if mode == 0:
            cN[j] = 0.0
            cNd[j] = 0.0
            cf[j] = 0.0
            continue
        nk = cnk[j]
        if nk == NK_SPRING:
            N = ck[j] * dl
            cNd[j] = ck[j] * dd
        elif nk == NK_DAMPED:
            N = ck[j] * dl + cc[j] * dd
            cNd[j] = ck[j] * dd   # completed below, once the accelerations are known
        else:
            N = cn0[j]
            cNd[j] = 0.0
        cN[j] = N
        K = claw[j]
        f = 0.0
        if not IS_STICK[K, mode]:  # noqa: F821
            f = law_force(K, mode, N, cNd[j], vv, y, law_offset(I, j), R, I, j)  # noqa: F821
        cf[j] = f
        for k in range(4):
            i = cidx[4 * j + k]
            if i >= 0:
                F[i] -= N * cgn[4 * j + k] + f * cgr[4 * j + k]
    if WI[W_NS] > 0:
        stk, xst = wvec(WI, nc, WC_STK), vec(WF, I, F_X, nc)
        stick_solution(F, vec(WF, I, F_B, nc), xst, I, R, WI, WF)  # noqa: F821
        if null_pivot_active(I, WI):  # noqa: F821
            least_cone_ratio(y, I, R, WI, WF)  # noqa: F821
        for jj in range(nca):
            j = ac[jj] & NONNEG
            if stk[j]:
                cf[j] = xst[j]
                for k in range(4):
                    i = cidx[4 * j + k]
                    if i >= 0:
                        F[i] -= xst[j] * cgr[4 * j + k]
    invm = vec(R, I, R_INVM, n)
    for jj in range(nca):
        j = ac[jj] & NONNEG
        if cnk[j] == NK_DAMPED and cm[j] != 0:   # dN/dt = k ddelta/dt + c d2delta/dt2
            cNd[j] += cc[j] * penetration_acceleration(j, F, invm, cidx, cgn)
    return power


def forcing_phase(t, I, R, WF):
    """``sin(om_g t)`` and ``cos(om_g t)`` of every frequency group into ``F_SG``, ``F_CG``; ``t`` into ``F_T``.

    A time within ``SNAP_ULPS`` units in the last place of a half-step time ``k hh``
    (every step's end and RK4 midpoint) reads the phase table (``R_TG``, ``R_TAB``:
    the values at ``(k mod M) hh``, the forcing being periodic); any other time, or
    without a table, calls ``sin`` and ``cos``. Which branch a time takes depends on the
    time alone, so every path to the same time (a whole step, a cluster's sub-steps)
    reads the same forcing. The table's value differs from ``sin(om_g t)`` by rounding
    only: the phase ``om_g t`` itself is rounded to a unit in the last place of ``om_g t``,
    a snapped time is off by ``SNAP_ULPS`` of ``t``, and the table's repetition is off
    by ``om_g`` times the period's own rounding once a period. It saves the two ``sin``
    and ``cos`` pairs of a step (about 28 ns a pair), 5 % of a two-blade ring's step.
    """
    ng = I[H_NG]
    sg, cg, om, tg = vec(WF, I, F_SG, ng), vec(WF, I, F_CG, ng), vec(R, I, R_OM, ng), vec(R, I, R_TG, 3)
    WF[I[F_T]] = t
    M = tg[2]
    if M > 0.0:
        k = math.floor(t * tg[1] + 0.5)
        if abs(t - k * tg[0]) <= SNAP_ULPS * 2.220446049250313e-16 * abs(t):
            kk = int(k - math.floor(k / M) * M)
            Mi = int(M)
            if kk >= Mi:   # k / M rounded up to a whole number
                kk -= Mi
            elif kk < 0:
                kk += Mi
            tab = R[I[R_TAB]:]
            for g in range(ng):
                e = 2 * (g * Mi + kk)
                sg[g] = tab[e]
                cg[g] = tab[e + 1]
            return
    for g in range(ng):
        sg[g] = math.sin(om[g] * t)
        cg[g] = math.cos(om[g] * t)


def forces(t, y, cm, I, R, WI, WF):
    """``contact_forces`` for Python (an entry point: ``contact_forces`` itself is only inlined where the kernel
    calls it, and compiled as an entry point only when Python asks for the forces)."""
    contact_forces(t, y, cm, I, R, WI, WF)


def penetration_acceleration(j, F, invm, cidx, cgn):
    """``d2delta/dt2`` of contact ``j`` from the generalized forces ``F``."""
    s = 0.0
    for k in range(4):
        i = cidx[4 * j + k]
        if i >= 0:
            s += cgn[4 * j + k] * invm[i] * F[i]
    return s


def rhs(t, y, cm, I, R, WI, WF, out):
    """``dy/dt`` with every contact in its mode ``cm[j]`` (on the active set)."""
    rates(y, cm, I, R, WI, WF, out, contact_forces(t, y, cm, I, R, WI, WF))


def rhs_guards(t, y, cm, I, R, WI, WF, out, G):
    """``dy/dt`` into ``out`` and the guards into ``G`` from one evaluation of the forces."""
    rates(y, cm, I, R, WI, WF, out, contact_forces(t, y, cm, I, R, WI, WF))
    guards_of_forces(y, cm, I, R, WI, WF, G)  # noqa: F821


#: What ``evaluate`` computes besides the forces (bits of ``what``): ``dy/dt``, the guards, their rates (from
#: ``dy/dt`` in ``out``), with the rates of rigid stick forces. Passed as ``EV_X | runtime(0)``: a constant
#: would compile a copy of ``evaluate`` per set of flags, ``runtime(EV_X)`` a copy of ``runtime``.
EV_RATES, EV_GUARDS, EV_GUARD_RATES, EV_STICK = 1, 2, 4, 8
#: ``dy/dt``, the guards and their rates.
EV_ALL = 7


def evaluate(t, y, cm, I, R, WI, WF, out, G, D, what):
    """The forces at ``(t, y)`` and, by the bits of ``what`` (``EV_*``), ``dy/dt`` into ``out``, the guards into
    ``G`` and their rates into ``D`` (from ``dy/dt`` in ``out``; with the stick forces' rates if ``EV_STICK``).

    The one function through which the kernel evaluates the flow (only the entry
    point ``rhs`` and the friction problem's pivots call ``contact_forces`` themselves,
    and ``rhs_guards`` is kept for tests): ``contact_forces``, ``rates``,
    ``guards_of_forces`` and ``guard_rates`` are inlined here (``forceinline``), once, so
    an evaluation is one call, not up to six (a call passes each array as seven to
    eleven words). An argument not asked for is not touched (any array of its type
    will do: ``what = 0`` computes the forces only).
    """
    power = contact_forces(t, y, cm, I, R, WI, WF)
    if what & EV_RATES:
        rates(y, cm, I, R, WI, WF, out, power)
    if what & EV_GUARDS:
        guards_of_forces(y, cm, I, R, WI, WF, G)  # noqa: F821
    if what & EV_GUARD_RATES:
        guard_rates(y, out, cm, I, R, WI, WF, D, (what & EV_STICK) != 0)  # noqa: F821


def rates(y, cm, I, R, WI, WF, out, power):
    """``dy/dt`` from the forces of the last ``contact_forces`` (``power``: the forcing's input power)."""
    n, nc = I[H_N], I[H_NC]
    full, nd = active_dofs(WI, n)
    full, nca = active_contacts(WI, nc)
    ad, ac = wdof(WI, nc, n, WD_ALL if full else WD_AD), wvec(WI, nc, WC_ALL if full else WC_AC)
    claw = vec(I, I, O_CLAW, nc)
    invm, F = vec(R, I, R_INVM, n), vec(WF, I, F_F, n)
    cN, cNd, cv, cf = vec(WF, I, F_N, nc), vec(WF, I, F_ND, nc), vec(WF, I, F_V, nc), vec(WF, I, F_FR, nc)
    for ii in range(nd):
        i = ad[ii] & NONNEG
        out[i] = y[n + i]
        out[n + i] = invm[i] * F[i]
    for jj in range(nca):
        j = ac[jj] & NONNEG
        so = law_offset(I, j)
        law_rates(claw[j], cm[j], cN[j], cNd[j], cv[j], cf[j], y, so, R, I, j, out, so)  # noqa: F821
    n_law = 2 * n + I[H_NLAW]
    if y.shape[0] > n_law:
        Cp, Ci, Cv = vec(I, I, O_CP, n + 1), I[I[O_CI]:], R[I[R_CV]:]
        visc = 0.0
        for ii in range(nd):
            i = ad[ii] & NONNEG
            s = 0.0
            for e in range(Cp[i] & NONNEG, Cp[i + 1]):
                s += Cv[e] * y[n + (Ci[e] & NONNEG)]
            visc += y[n + i] * s
        cnk, cc, ck = vec(I, I, O_CNK, nc), vec(R, I, R_CC, nc), vec(R, I, R_K, nc)
        cdl, cdr = vec(WF, I, F_DL, nc), vec(WF, I, F_DR, nc)
        fric = 0.0
        for jj in range(nca):
            j = ac[jj] & NONNEG
            if cnk[j] == NK_DAMPED:   # the dashpot while closed; the spring's release while open
                if cm[j] != 0:
                    visc += cc[j] * cdr[j] * cdr[j]
                elif cdl[j] > 0.0:
                    visc -= ck[j] * cdl[j] * cdr[j]
        for jj in range(nca):
            j = ac[jj] & NONNEG
            if cm[j] != 0:
                fric += law_dissipation(claw[j], cm[j], cN[j], cNd[j], cv[j], cf[j], y,  # noqa: F821
                                        law_offset(I, j), R, I, j)
        out[n_law] = power
        out[n_law + 1] = visc
        out[n_law + 2] = fric


def rk4_step(t, y, h, cm, I, R, WI, WF, SC, out, have_k1):
    """One classical RK4 step of size ``h`` from ``(t, y)`` into ``out`` (stages in ``SC[0:5]``), active rows.

    With ``have_k1``, ``SC[0]`` already holds ``dy/dt`` at ``(t, y)`` (the end of the
    previous step, or the first trial from the same point).
    """
    n, nc = I[H_N], I[H_NC]
    full, nsa = active_rows(WI, y.shape[0])
    rows = wrow(WI, nc, n, y.shape[0], 1 if full else 0)
    k1, k2, k3, k4, tmp = SC[0], SC[1], SC[2], SC[3], SC[4]
    ev = EV_RATES | runtime(0)   # the stage buffer SC stands in for the guards, which are not asked for
    if not have_k1:
        evaluate(t, y, cm, I, R, WI, WF, k1, SC, SC, ev)
    for ii in range(nsa):
        i = rows[ii] & NONNEG
        tmp[i] = y[i] + 0.5 * h * k1[i]
    evaluate(t + 0.5 * h, tmp, cm, I, R, WI, WF, k2, SC, SC, ev)
    for ii in range(nsa):
        i = rows[ii] & NONNEG
        tmp[i] = y[i] + 0.5 * h * k2[i]
    evaluate(t + 0.5 * h, tmp, cm, I, R, WI, WF, k3, SC, SC, ev)
    for ii in range(nsa):
        i = rows[ii] & NONNEG
        tmp[i] = y[i] + h * k3[i]
    evaluate(t + h, tmp, cm, I, R, WI, WF, k4, SC, SC, ev)
    for ii in range(nsa):
        i = rows[ii] & NONNEG
        out[i] = y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])


def rk_step(t, y, h, cm, I, R, WI, WF, SC, out, have_k1):
    """One step of the kernel's method: classical RK4 written out, or the tableau in ``R`` (``I[H_NS]`` stages).

    A tableau's stage ``q`` is kept in ``SC[0]`` (``q = 0``, shared as with RK4) or
    ``SC[SC_ROWS + q - 1]``. Returns the right-hand-side evaluations spent.
    """
    s = I[H_NS]
    if s == 0:
        rk4_step(t, y, h, cm, I, R, WI, WF, SC, out, have_k1)
        return 3 if have_k1 else 4
    n, nc = I[H_N], I[H_NC]
    full, nsa = active_rows(WI, y.shape[0])
    rows = wrow(WI, nc, n, y.shape[0], 1 if full else 0)
    o = I[R_RK]
    ob = o + s * s
    oc = ob + s
    tmp = SC[4]
    ev = EV_RATES | runtime(0)
    if not have_k1:
        evaluate(t, y, cm, I, R, WI, WF, SC[0], SC, SC, ev)
    for st in range(1, s):
        for ii in range(nsa):
            i = rows[ii] & NONNEG
            tmp[i] = y[i]
        for q in range(st):
            a = h * R[o + st * s + q]
            if a != 0.0:
                kq = SC[0] if q == 0 else SC[SC_ROWS + q - 1]
                for ii in range(nsa):
                    i = rows[ii] & NONNEG
                    tmp[i] += a * kq[i]
        evaluate(t + R[oc + st] * h, tmp, cm, I, R, WI, WF, SC[SC_ROWS + st - 1], SC, SC, ev)
    for ii in range(nsa):
        i = rows[ii] & NONNEG
        out[i] = y[i]
    for q in range(s):
        bq = h * R[ob + q]
        if bq != 0.0:
            kq = SC[0] if q == 0 else SC[SC_ROWS + q - 1]
            for ii in range(nsa):
                i = rows[ii] & NONNEG
                out[i] += bq * kq[i]
    return s - 1 if have_k1 else s
