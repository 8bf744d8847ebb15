"""The per-contact hybrid kernel: RK4, located events, coupled rigid stick.

This file is a *template* pasted into a generated module (:mod:`.contact_codegen`)
after the friction laws' functions and tables: ``law_force``, ``law_rates``,
``law_guards``, ``law_transition``, ``law_dissipation`` dispatch on the law kind
``K``; ``NG[K, mode]``, ``GDIR[K, mode, gi]``, ``IS_STICK[K, mode]`` and
``RIGID[K] = (stick, slip+, slip-)`` describe the kinds. Nothing here grows with
the number of contacts: every contact holds one mode integer ``cm[j]`` and is
handled by index.

Tables and work arrays are four flat arrays (``I``, ``R``, ``WI``, ``WF``) whose
layout is part of the kernel contract (:mod:`blademodel.numeric.contract`, built by
:func:`blademodel.numeric.contact_kernel.pack_tables`): the header of ``I`` holds the
sizes and the offset of every table, and each function takes *views* of what it
needs (no copies; every function is compiled without reference counting, see
:mod:`.contact_codegen`). The tables:

``I``: ``Kp, Ki`` (stiffness, CSR rows), ``Cp, Ci`` (damping, CSR), ``fi, fg``
(forcing entries: coordinate, frequency group), ``cidx`` (contact slots, ``(nc, 4)``,
-1 unused), ``claw`` (law kind), ``cso`` (offset of the law's states after ``q`` and
``u``), ``LP`` (the law's parameter indices into ``p``, ``(nc, LPW)``), ``Wp, Wi``
(the contacts coupled to each contact through ``W``, CSR), ``cnk`` (each contact's normal law:
``NK_SPRING``, ``NK_DAMPED``, ``NK_LOAD``).

``R``: ``invm`` (inverse masses), ``Kv``, ``Cv`` (CSR values), ``fs, fc`` (forcing
``fs sin(w t) + fc cos(w t)``), ``om`` (group frequencies), ``cgn, cgr`` (gradients
of the penetration and of the relative slip, ``(nc, 4)``), ``cgap``, ``ck`` (gap,
normal stiffness), ``cc``, ``cn0`` (normal damping, constant normal load), ``p``
(parameter values), ``W`` (Delassus matrix ``G M^-1 G^T`` of the tangential
directions, ``(nc, nc)``).

``WI``: ``[ns, null pivot or -1]``, then ``nc`` each: ``sl`` (the sticking rigid
contacts, ascending), ``env`` (first column of each row of the stick matrix's
envelope), ``U`` (contacts of the current friction problem), ``cm0`` (modes before
an event), ``before`` (modes before the friction problem, for the log), ``fired``
(1 + the log row of the contact's transition in the current event, 0 if none, -1
unlogged), ``pos`` (each contact's row in ``sl``, or -1).

``WF``: ``F`` (generalized forces), ``cN, cNd, cv, cf, cdl`` (per contact normal
force, its rate, slip velocity, friction force, penetration), ``xst`` (stick
forces), ``Dd`` and ``Lf`` (envelope LDL^T factor of the stick matrix), ``nullv``
(its null vector), ``bst`` (stick right-hand side), ``sg, cg`` (sin and cos of each
frequency group), ``ztmp`` (law-state scratch), ``yev`` (state at an event before
the friction problem), ``cdr`` (penetration rates), ``tsc`` (the time of ``sg, cg``;
NaN when none), ``Fd`` and ``xd`` (rates of the generalized forces and of the stick
forces, for the stick guards' rates at an event).

``integrate`` also takes ``SC`` (``(SC_ROWS + s - 1, n_state)``: RK4 stages 0-4, the
step's or bracket's end 5, the trial 6, the sub-step start 7, ``dy/dt`` at the step's
end 8, then the stages 1 ... s-1 of a tableau method (``I[H_NS] = s``; its stage 0 is
row 0))
and ``GS`` (``(9, nc, GMAX)``: guard values at the step start 0, end 1, trial 2,
sub-step start 3, bracket start 7, and their rates 4, 5, 6, 8, NaN where unknown).
The kernel allocates nothing.

Rigid stick (Coulomb) is solved jointly: the stick forces ``x`` of the sticking
contacts satisfy ``W_SS x = G_S M^-1 F_known`` (zero relative tangential
acceleration). ``W_SS`` changes only at events, so it is factored there
(``factor_stick``) and each evaluation only substitutes. If the sticking
contacts close a ring, ``W_SS`` is singular (a uniform circulating force changes
no blade's motion): the factor then has one zero pivot, the motion is that of
any solution, and the force distribution reported and checked against the
friction cones is the one that minimises the largest cone ratio
``max |x_j| / (mu N_j)``. Sticking holds while that ratio is at most 1, i.e.
while *some* admissible distribution exists.
"""

import math  # noqa: F401

from blademodel.numeric.contract import (C_LOCATION_SUBSTEPS, C_EVENTS, C_FRICTION_PIVOTS, C_GRAZING, C_LOGGED, C_RECORDS, C_RHS,
                                         C_STEPS, F_B, F_CG, F_D, F_DL, F_F, F_FR, F_L, F_N, F_ND, F_NULL, F_SG,
                                         F_V, F_X, F_YEV, F_Z, F_DR, F_T, F_FD, F_XD, H_N, H_NS, R_RK, SC_ROWS, H_NC, H_NF, H_NG, H_NLAW, MAX_LAW_STATES,
                                         O_CI, O_CIDX, O_CLAW, O_CP, O_CSO, O_FG, O_FI, O_KI, O_KP, O_WI, O_WP, R_CV, R_FC,
                                         R_FS, R_GAP, R_GN, R_GR, R_INVM, R_K, R_KV, R_OM, R_W, S_MAX_CONE_RATIO,
                                         NK_DAMPED, NK_LOAD, NK_SPRING, O_CNK, R_CC, R_N0,
                                         STATUS_EVENT_STORM, STATUS_FRICTION_UNRESOLVED, STATUS_NONFINITE,
                                         STATUS_OK)

#: Relative size of a pivot of the stick matrix below which it counts as zero (a closed ring).
NULL_PIVOT = 1e-10
#: Relative tolerance on the sign of a slipping contact's acceleration in the friction problem.
SLIP_SIGN_TOL = 1e-9
#: Cap on the trial sub-steps of one event's location (a bisection at least every third
#: trial halves the bracket: 2**-50 of a step long before the cap).
MAX_LOCATE_TRIALS = 160


def runtime(x):
    """``x`` (an int or bool) as a run-time value: Numba types a constant argument as a
    literal and compiles a copy of the callee, and of all it calls, for each literal
    (``x | x`` is ``x``, and no longer a literal)."""
    return x | x


# ---- views of the flat buffers --------------------------------------------------------------
def vec(a, I, key, size):
    """The table at offset ``I[key]`` of ``a``, ``size`` long."""
    o = I[key]
    return a[o:o + size]


def mat(a, I, key, rows, cols):
    """The ``(rows, cols)`` table at offset ``I[key]`` of ``a``."""
    o = I[key]
    return a[o:o + rows * cols].reshape((rows, cols))


def wvec(WI, nc, k):
    """The ``k``-th per-contact array of ``WI`` (0 ``sl``, 1 ``env``, 2 ``U``, 3 ``cm0``, 4 ``before``, 5 ``fired``,
    6 ``pos``)."""
    o = 2 + k * nc
    return WI[o:o + nc]


def law_offset(I, j):
    """Offset in ``y`` of contact ``j``'s law states."""
    return 2 * I[H_N] + I[I[O_CSO] + j]


# ---- the stick matrix ---------------------------------------------------------------
def factor_stick(cm, I, R, WI, WF):
    """Collect the sticking rigid contacts and factor their Delassus block (envelope LDL^T)."""
    nc = I[H_NC]
    claw = vec(I, I, O_CLAW, nc)
    W = mat(R, I, R_W, nc, nc)
    sl, env = wvec(WI, nc, 0), wvec(WI, nc, 1)
    Lf = mat(WF, I, F_L, nc, nc)
    Dd, nullv = vec(WF, I, F_D, nc), vec(WF, I, F_NULL, nc)
    ns = 0
    for j in range(nc):
        if IS_STICK[claw[j], cm[j]]:  # noqa: F821
            sl[ns] = j
            ns += 1
    WI[0] = ns
    WI[1] = -1
    pos = wvec(WI, nc, 6)   # each contact's row in the stick set, or -1
    for j in range(nc):
        pos[j] = -1
    for a in range(ns):
        pos[sl[a]] = a
    Wp, Wi = vec(I, I, O_WP, nc + 1), I[I[O_WI]:]
    for a in range(ns):
        e = a
        for q in range(Wp[sl[a]], Wp[sl[a] + 1]):
            b = pos[Wi[q]]
            if 0 <= b < e:
                e = b
        env[a] = e
    for i in range(ns):
        for jj in range(env[i], i):
            s = W[sl[i], sl[jj]]
            for k in range(max(env[i], env[jj]), jj):
                s -= Lf[i, k] * Dd[k] * Lf[jj, k]
            Lf[i, jj] = s / Dd[jj] if Dd[jj] != 0.0 else 0.0
        d = W[sl[i], sl[i]]
        for k in range(env[i], i):
            d -= Lf[i, k] * Lf[i, k] * Dd[k]
        if d <= NULL_PIVOT * W[sl[i], sl[i]]:
            d = 0.0
            WI[1] = i
        Dd[i] = d
    if WI[1] >= 0:
        for a in range(ns):
            nullv[a] = 0.0
        nullv[WI[1]] = 1.0
        back_substitute(ns, env, Lf, nullv)


def back_substitute(ns, env, Lf, x):
    """Solve ``L^T x = z`` in place (unit lower ``L`` in envelope storage)."""
    for k in range(ns - 1, -1, -1):
        xk = x[k]
        if xk != 0.0:
            for i in range(env[k], k):
                x[i] -= Lf[k, i] * xk


def solve_stick(ns, env, Lf, Dd, b, x):
    """A solution of ``W_SS x = b`` from the factor (the free variable at a null pivot is 0)."""
    for i in range(ns):
        s = b[i]
        for k in range(env[i], i):
            s -= Lf[i, k] * x[k]
        x[i] = s
    for i in range(ns):
        x[i] = x[i] / Dd[i] if Dd[i] != 0.0 else 0.0
    back_substitute(ns, env, Lf, x)


def slip_bound(j, y, I, R, WF):
    """The slip force magnitude ``mu N`` of rigid contact ``j`` (its slip+ force)."""
    K = I[I[O_CLAW] + j]
    return law_force(K, RIGID[K, 1], WF[I[F_N] + j], WF[I[F_ND] + j], WF[I[F_V] + j], y,  # noqa: F821
                     law_offset(I, j), R, I, j)


def least_cone_ratio(y, I, R, WI, WF):
    """Shift the stick forces along the null vector to minimise ``max |x| / bound``."""
    ns, nc = WI[0], I[H_NC]
    sl = wvec(WI, nc, 0)
    xst, nullv = vec(WF, I, F_X, nc), vec(WF, I, F_NULL, nc)
    lo = math.inf
    hi = -math.inf
    for a in range(ns):
        if nullv[a] != 0.0:
            c = -xst[a] / nullv[a]
            lo = min(lo, c)
            hi = max(hi, c)
    if not lo < hi:
        return
    for _ in range(80):
        c = 0.5 * (lo + hi)
        worst = -1.0
        slope = 0.0
        for a in range(ns):
            w = 1.0 / max(slip_bound(sl[a], y, I, R, WF), 1e-300)
            val = (xst[a] + c * nullv[a]) * w
            if abs(val) > worst:
                worst = abs(val)
                slope = (1.0 if val >= 0.0 else -1.0) * nullv[a] * w
        if slope > 0.0:
            hi = c
        else:
            lo = c
    c = 0.5 * (lo + hi)
    for a in range(ns):
        xst[a] += c * nullv[a]


# ---- forces and flow --------------------------------------------------------------------
def contact_forces(t, y, cm, I, R, WI, WF):
    """Generalized forces ``F`` and each contact's ``N``, ``Nd``, ``v``, ``f``, penetration.

    Returns the input power of the forcing (for the energy accumulators).
    """
    n, nc, nf, ng = I[H_N], I[H_NC], I[H_NF], I[H_NG]
    Kp, Ki = vec(I, I, O_KP, n + 1), I[I[O_KI]:]
    Cp, Ci = vec(I, I, O_CP, n + 1), I[I[O_CI]:]
    Kv, Cv = R[I[R_KV]:], R[I[R_CV]:]
    fi, fg = vec(I, I, O_FI, nf), vec(I, I, O_FG, nf)
    fs, fc, om = vec(R, I, R_FS, nf), vec(R, I, R_FC, nf), vec(R, I, R_OM, ng)
    cidx, claw = mat(I, I, O_CIDX, nc, 4), vec(I, I, O_CLAW, nc)
    cgn, cgr = mat(R, I, R_GN, nc, 4), mat(R, I, R_GR, nc, 4)
    cgap, ck = vec(R, I, R_GAP, nc), vec(R, I, R_K, nc)
    cnk, cc, cn0 = vec(I, I, O_CNK, nc), vec(R, I, R_CC, nc), vec(R, I, R_N0, nc)
    F = vec(WF, I, F_F, n)
    cN, cNd, cv, cf, cdl = (vec(WF, I, F_N, nc), vec(WF, I, F_ND, nc), vec(WF, I, F_V, nc),
                            vec(WF, I, F_FR, nc), vec(WF, I, F_DL, nc))
    sg, cg = vec(WF, I, F_SG, ng), vec(WF, I, F_CG, ng)
    cdr = vec(WF, I, F_DR, nc)
    if WF[I[F_T]] != t:   # RK4's middle stages and a step's end share their time: sin and cos kept
        for g in range(ng):
            sg[g] = math.sin(om[g] * t)
            cg[g] = math.cos(om[g] * t)
        WF[I[F_T]] = t
    for i in range(n):
        s = 0.0
        for e in range(Kp[i], Kp[i + 1]):
            s -= Kv[e] * y[Ki[e]]
        for e in range(Cp[i], Cp[i + 1]):
            s -= Cv[e] * y[n + Ci[e]]
        F[i] = s
    power = 0.0
    for e in range(nf):
        load = fs[e] * sg[fg[e]] + fc[e] * cg[fg[e]]
        F[fi[e]] += load
        power += load * y[n + fi[e]]
    for j in range(nc):
        dl = -cgap[j]
        dd = 0.0
        vv = 0.0
        for k in range(4):
            i = cidx[j, k]
            if i >= 0:
                dl += cgn[j, k] * y[i]
                dd += cgn[j, k] * y[n + i]
                vv += cgr[j, k] * y[n + i]
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
            i = cidx[j, k]
            if i >= 0:
                F[i] -= N * cgn[j, k] + f * cgr[j, k]
    ns = WI[0]
    if ns > 0:
        sl = wvec(WI, nc, 0)
        xst = vec(WF, I, F_X, nc)
        stick_solution(F, vec(WF, I, F_B, nc), xst, I, R, WI, WF)
        if WI[1] >= 0:
            least_cone_ratio(y, I, R, WI, WF)
        for a in range(ns):
            j = sl[a]
            cf[j] = xst[a]
            for k in range(4):
                i = cidx[j, k]
                if i >= 0:
                    F[i] -= xst[a] * cgr[j, k]
    invm = vec(R, I, R_INVM, n)
    for j in range(nc):
        if cnk[j] == NK_DAMPED and cm[j] != 0:   # dN/dt = k ddelta/dt + c d2delta/dt2
            cNd[j] += cc[j] * penetration_acceleration(j, F, invm, cidx, cgn)
    return power


def penetration_acceleration(j, F, invm, cidx, cgn):
    """``d2delta/dt2`` of contact ``j`` from the generalized forces ``F``."""
    s = 0.0
    for k in range(4):
        i = cidx[j, k]
        if i >= 0:
            s += cgn[j, k] * invm[i] * F[i]
    return s


def normal_guard(j, mode, nk, dl, dd, N, ck, cc, cn0):
    """The guard of contact ``j``'s normal law: the penetration (spring), the normal force (damped,
    closed), ``k delta + c min(ddelta/dt, 0)`` (damped, open) or the constant load."""
    if nk == NK_SPRING:
        return dl
    if nk == NK_LOAD:
        return cn0[j]
    if mode != 0:
        return N
    return ck[j] * dl + cc[j] * min(dd, 0.0)


def rhs(t, y, cm, I, R, WI, WF, out):
    """``dy/dt`` with every contact in its mode ``cm[j]``."""
    rates(y, cm, I, R, WI, WF, out, contact_forces(t, y, cm, I, R, WI, WF))


def rhs_guards(t, y, cm, I, R, WI, WF, out, G):
    """``dy/dt`` into ``out`` and the guards into ``G`` from one evaluation of the forces."""
    rates(y, cm, I, R, WI, WF, out, contact_forces(t, y, cm, I, R, WI, WF))
    guards_of_forces(y, cm, I, R, WF, G)


def rates(y, cm, I, R, WI, WF, out, power):
    """``dy/dt`` from the forces of the last ``contact_forces`` (``power``: the forcing's input power)."""
    n, nc = I[H_N], I[H_NC]
    claw = vec(I, I, O_CLAW, nc)
    invm, F = vec(R, I, R_INVM, n), vec(WF, I, F_F, n)
    cN, cNd, cv, cf = vec(WF, I, F_N, nc), vec(WF, I, F_ND, nc), vec(WF, I, F_V, nc), vec(WF, I, F_FR, nc)
    for i in range(n):
        out[i] = y[n + i]
        out[n + i] = invm[i] * F[i]
    for j in range(nc):
        so = law_offset(I, j)
        law_rates(claw[j], cm[j], cN[j], cNd[j], cv[j], cf[j], y, so, R, I, j, out, so)  # noqa: F821
    n_law = 2 * n + I[H_NLAW]
    if y.shape[0] > n_law:
        Cp, Ci, Cv = vec(I, I, O_CP, n + 1), I[I[O_CI]:], R[I[R_CV]:]
        visc = 0.0
        for i in range(n):
            s = 0.0
            for e in range(Cp[i], Cp[i + 1]):
                s += Cv[e] * y[n + Ci[e]]
            visc += y[n + i] * s
        cnk, cc, ck = vec(I, I, O_CNK, nc), vec(R, I, R_CC, nc), vec(R, I, R_K, nc)
        cdl, cdr = vec(WF, I, F_DL, nc), vec(WF, I, F_DR, nc)
        for j in range(nc):
            if cnk[j] == NK_DAMPED:   # the dashpot while closed; the spring's release while open
                if cm[j] != 0:
                    visc += cc[j] * cdr[j] * cdr[j]
                elif cdl[j] > 0.0:
                    visc -= ck[j] * cdl[j] * cdr[j]
        fric = 0.0
        for j in range(nc):
            if cm[j] != 0:
                fric += law_dissipation(claw[j], cm[j], cN[j], cNd[j], cv[j], cf[j], y,  # noqa: F821
                                        law_offset(I, j), R, I, j)
        out[n_law] = power
        out[n_law + 1] = visc
        out[n_law + 2] = fric


def rk4_step(t, y, h, cm, I, R, WI, WF, SC, out, have_k1):
    """One classical RK4 step of size ``h`` from ``(t, y)`` into ``out`` (stages in ``SC[0:5]``).

    With ``have_k1``, ``SC[0]`` already holds ``dy/dt`` at ``(t, y)`` (the end of the
    previous step, or the first trial from the same point).
    """
    n = y.shape[0]
    k1, k2, k3, k4, tmp = SC[0], SC[1], SC[2], SC[3], SC[4]
    if not have_k1:
        rhs(t, y, cm, I, R, WI, WF, k1)
    for i in range(n):
        tmp[i] = y[i] + 0.5 * h * k1[i]
    rhs(t + 0.5 * h, tmp, cm, I, R, WI, WF, k2)
    for i in range(n):
        tmp[i] = y[i] + 0.5 * h * k2[i]
    rhs(t + 0.5 * h, tmp, cm, I, R, WI, WF, k3)
    for i in range(n):
        tmp[i] = y[i] + h * k3[i]
    rhs(t + h, tmp, cm, I, R, WI, WF, k4)
    for i in range(n):
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
    n = y.shape[0]
    o = I[R_RK]
    ob = o + s * s
    oc = ob + s
    tmp = SC[4]
    if not have_k1:
        rhs(t, y, cm, I, R, WI, WF, SC[0])
    for st in range(1, s):
        for i in range(n):
            tmp[i] = y[i]
        for q in range(st):
            a = h * R[o + st * s + q]
            if a != 0.0:
                kq = SC[0] if q == 0 else SC[SC_ROWS + q - 1]
                for i in range(n):
                    tmp[i] += a * kq[i]
        rhs(t + R[oc + st] * h, tmp, cm, I, R, WI, WF, SC[SC_ROWS + st - 1])
    for i in range(n):
        out[i] = y[i]
    for q in range(s):
        bq = h * R[ob + q]
        if bq != 0.0:
            kq = SC[0] if q == 0 else SC[SC_ROWS + q - 1]
            for i in range(n):
                out[i] += bq * kq[i]
    return s - 1 if have_k1 else s


# ---- guards -------------------------------------------------------------------------------
def eval_guards(t, y, cm, I, R, WI, WF, G):
    """Every contact's guards into ``G[j, :]``: 0 the normal law's (``normal_guard``), then the law's."""
    contact_forces(t, y, cm, I, R, WI, WF)
    guards_of_forces(y, cm, I, R, WF, G)


def guards_of_forces(y, cm, I, R, WF, G):
    """The guards from the forces of the last ``contact_forces``."""
    nc = I[H_NC]
    claw = vec(I, I, O_CLAW, nc)
    cN, cNd, cv, cf, cdl = (vec(WF, I, F_N, nc), vec(WF, I, F_ND, nc), vec(WF, I, F_V, nc),
                            vec(WF, I, F_FR, nc), vec(WF, I, F_DL, nc))
    cnk, cc, cn0, ck = vec(I, I, O_CNK, nc), vec(R, I, R_CC, nc), vec(R, I, R_N0, nc), vec(R, I, R_K, nc)
    cdr = vec(WF, I, F_DR, nc)
    for j in range(nc):
        G[j, 0] = normal_guard(j, cm[j], cnk[j], cdl[j], cdr[j], cN[j], ck, cc, cn0)
        law_guards(claw[j], cm[j], cN[j], cNd[j], cv[j], cf[j], y, law_offset(I, j), R, I, j, G)  # noqa: F821


def crossed(g0, g1, direction):
    """Whether a guard went from ``g0`` to ``g1`` through zero in ``direction`` (see ``loop.crossed``)."""
    if direction < 0:
        return g0 >= 0.0 and g1 < 0.0
    if direction > 0:
        return g0 <= 0.0 and g1 > 0.0
    return (g0 > 0.0 and g1 <= 0.0) or (g0 < 0.0 and g1 >= 0.0)


def first_crossing(cm, I, WI, G0, G1):
    """``j * GMAX + gi`` of the first guard that crossed (contacts in order), or -1.

    Contacts whose transition fired in the current event are passed over: their law
    has settled them, and their new mode's guards compared across the bracket mean
    nothing (outside an event no contact is marked).
    """
    nc = I[H_NC]
    claw, fired = vec(I, I, O_CLAW, nc), wvec(WI, nc, 5)
    for j in range(nc):
        if fired[j] != 0:
            continue
        K = claw[j]
        m = cm[j]
        for gi in range(NG[K, m]):  # noqa: F821
            if crossed(G0[j, gi], G1[j, gi], GDIR[K, m, gi]):  # noqa: F821
                return j * GMAX + gi  # noqa: F821
    return -1


def guard_rates(y, dy, cm, I, R, WI, WF, D, with_stick):
    """Time derivatives of the guards at ``y`` (``dy = dy/dt`` there; the forces of its last ``contact_forces``).

    The penetration's rate is known in every mode; a law guard's where the law's
    generated ``law_guard_rates`` knows it; a guard on a rigid stick force's only
    ``with_stick`` (:func:`stick_force_rates`, one more pass over the forces and a stick solve)
    and not in a closed ring of sticking contacts (whose forces are not determined by
    the motion); NaN elsewhere.
    """
    n, nc = I[H_N], I[H_NC]
    claw, cidx = vec(I, I, O_CLAW, nc), mat(I, I, O_CIDX, nc, 4)
    cgn, cgr, ck = mat(R, I, R_GN, nc, 4), mat(R, I, R_GR, nc, 4), vec(R, I, R_K, nc)
    cN, cNd, cv, cf = vec(WF, I, F_N, nc), vec(WF, I, F_ND, nc), vec(WF, I, F_V, nc), vec(WF, I, F_FR, nc)
    cdr, xd, pos = vec(WF, I, F_DR, nc), vec(WF, I, F_XD, nc), wvec(WI, nc, 6)
    stick_known = with_stick and WI[0] > 0 and WI[1] < 0
    if stick_known:
        stick_force_rates(y, dy, cm, I, R, WI, WF)
    cnk, cc = vec(I, I, O_CNK, nc), vec(R, I, R_CC, nc)
    for j in range(nc):
        D[j, 0] = normal_guard_rate(j, cm[j], cnk[j], cdr[j], cNd[j], dy, n, cidx, cgn, ck, cc)
        for gi in range(1, D.shape[1]):
            D[j, gi] = math.nan
        if cm[j] == 0:
            continue
        Ndd, vd = contact_rates(j, dy, n, cidx, cgn, cgr, ck)
        if cnk[j] == NK_DAMPED:
            Ndd = math.nan   # k d2delta/dt2 + c d3delta/dt3: the jerk is not known
        fd = xd[pos[j]] if stick_known and pos[j] >= 0 else math.nan
        law_guard_rates(claw[j], cm[j], cN[j], cNd[j], Ndd, cv[j], vd, cf[j], fd, y,  # noqa: F821
                        law_offset(I, j), R, I, j, dy, D)


def normal_guard_rate(j, mode, nk, dd, Nd, dy, n, cidx, cgn, ck, cc):
    """Time derivative of ``normal_guard`` (``Nd``: the closed contact's ``dN/dt``)."""
    if nk == NK_SPRING:
        return dd
    if nk == NK_LOAD:
        return 0.0
    if mode != 0:
        return Nd
    r = ck[j] * dd
    if dd < 0.0:
        a = 0.0
        for k in range(4):
            i = cidx[j, k]
            if i >= 0:
                a += cgn[j, k] * dy[n + i]
        r += cc[j] * a
    return r


def contact_rates(j, dy, n, cidx, cgn, cgr, ck):
    """``(dNd/dt, dv/dt)`` of contact ``j``: its normal force's second derivative and slip acceleration."""
    add = 0.0
    vd = 0.0
    for k in range(4):
        i = cidx[j, k]
        if i >= 0:
            add += cgn[j, k] * dy[n + i]
            vd += cgr[j, k] * dy[n + i]
    return ck[j] * add, vd


def stick_force_rates(y, dy, cm, I, R, WI, WF):
    """Rates ``xd`` of the stick forces at ``y`` (``dy = dy/dt``; the forces of its last ``contact_forces``).

    The time derivative of the stick condition ``W_SS x = G_S M^-1 F``: the same
    factor solves ``W_SS xd = G_S M^-1 dF/dt``, with ``dF/dt`` of the springs, dampers,
    forcing, normal forces and explicit friction forces (``law_force_rate``).
    """
    n, nc, nf = I[H_N], I[H_NC], I[H_NF]
    Kp, Ki = vec(I, I, O_KP, n + 1), I[I[O_KI]:]
    Cp, Ci = vec(I, I, O_CP, n + 1), I[I[O_CI]:]
    Kv, Cv = R[I[R_KV]:], R[I[R_CV]:]
    fi, fg = vec(I, I, O_FI, nf), vec(I, I, O_FG, nf)
    fs, fc, om = vec(R, I, R_FS, nf), vec(R, I, R_FC, nf), vec(R, I, R_OM, I[H_NG])
    sg, cg = vec(WF, I, F_SG, I[H_NG]), vec(WF, I, F_CG, I[H_NG])
    cidx, claw = mat(I, I, O_CIDX, nc, 4), vec(I, I, O_CLAW, nc)
    cgn, cgr, ck = mat(R, I, R_GN, nc, 4), mat(R, I, R_GR, nc, 4), vec(R, I, R_K, nc)
    cN, cNd, cv = vec(WF, I, F_N, nc), vec(WF, I, F_ND, nc), vec(WF, I, F_V, nc)
    Fd, xd = vec(WF, I, F_FD, n), vec(WF, I, F_XD, nc)
    for i in range(n):
        s = 0.0
        for e in range(Kp[i], Kp[i + 1]):
            s -= Kv[e] * y[n + Ki[e]]
        for e in range(Cp[i], Cp[i + 1]):
            s -= Cv[e] * dy[n + Ci[e]]
        Fd[i] = s
    for e in range(nf):
        g = fg[e]
        Fd[fi[e]] += om[g] * (fs[e] * cg[g] - fc[e] * sg[g])
    for j in range(nc):
        mode = cm[j]
        if mode == 0:
            continue
        K = claw[j]
        fdj = 0.0
        if not IS_STICK[K, mode]:  # noqa: F821
            Ndd, vd = contact_rates(j, dy, n, cidx, cgn, cgr, ck)
            fdj = law_force_rate(K, mode, cN[j], cNd[j], Ndd, cv[j], vd, y,  # noqa: F821
                                 law_offset(I, j), R, I, j, dy)
        for k in range(4):
            i = cidx[j, k]
            if i >= 0:
                Fd[i] -= cNd[j] * cgn[j, k] + fdj * cgr[j, k]
    stick_solution(Fd, xd, xd, I, R, WI, WF)


def stick_solution(F, b, x, I, R, WI, WF):
    """The stick forces ``x`` for generalized forces ``F``: ``W_SS x = b = G_S M^-1 F`` (``b`` may be ``x``)."""
    n, nc, ns = I[H_N], I[H_NC], WI[0]
    sl, env = wvec(WI, nc, 0), wvec(WI, nc, 1)
    cidx, cgr, invm = mat(I, I, O_CIDX, nc, 4), mat(R, I, R_GR, nc, 4), vec(R, I, R_INVM, n)
    for a in range(ns):
        j = sl[a]
        s = 0.0
        for k in range(4):
            i = cidx[j, k]
            if i >= 0:
                s += cgr[j, k] * invm[i] * F[i]
        b[a] = s
    solve_stick(ns, env, mat(WF, I, F_L, nc, nc), vec(WF, I, F_D, nc), b, x)


def locate_trial(t, y, dt, frac, cm, I, R, WI, WF, SC, ymid, G0, Gm, Dm, counters):
    """RK4 sub-step to the fraction ``frac`` of the step, its guards and their rates.

    ``SC[0]`` holds ``dy/dt`` at ``(t, y)`` (every trial starts there). Returns the
    first crossing since the start.
    """
    spent = rk_step(t, y, frac * dt, cm, I, R, WI, WF, SC, ymid, True)
    rhs_guards(t + frac * dt, ymid, cm, I, R, WI, WF, SC[4], Gm)   # SC[4]: the stages' scratch, free now
    guard_rates(ymid, SC[4], cm, I, R, WI, WF, Dm, True)
    counters[C_LOCATION_SUBSTEPS] += 1
    counters[C_RHS] += spent + 1
    return first_crossing(cm, I, WI, G0, Gm)


def copy_guards(G, Gm, D, Dm):
    """``G, D = Gm, Dm`` (guards and their rates)."""
    for j in range(G.shape[0]):
        for gi in range(G.shape[1]):
            G[j, gi] = Gm[j, gi]
            D[j, gi] = Dm[j, gi]


def hermite_extremum(g0, g1, d0, d1):
    """Where the Hermite interpolant's slope, ``d0`` and ``d1`` of opposite signs at the ends, is zero."""
    lo = 0.0
    hi = 1.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        d = hermite(mid, g0, g1, d0, d1)[1]  # noqa: F821
        if (d > 0.0) == (d0 > 0.0):
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def grazing_candidate(cm, I, G0, G1, D0, D1, dt, width):
    """The earliest fraction of a step at which a guard that did not cross may have crossed and come back.

    A guard with known rates that moves toward its crossing at the step's start and
    away from it at the end, both ends on the side before the crossing, has an
    extremum inside the step; if the cubic Hermite interpolant of its values and
    rates puts that extremum past zero, the guard crossed and returned within the
    step (a brief contact, a grazing touch). Returns that extremum's fraction, or -1.
    An extremum within ``width`` (the event tolerance) of the start is the turn of an
    event just handled there, not a new one: it is passed over.
    """
    nc = I[H_NC]
    claw = vec(I, I, O_CLAW, nc)
    best = -1.0
    for j in range(nc):
        K = claw[j]
        m = cm[j]
        for gi in range(NG[K, m]):  # noqa: F821
            d0 = D0[j, gi] * dt
            d1 = D1[j, gi] * dt
            if not (math.isfinite(d0) and math.isfinite(d1)):
                continue
            g0 = G0[j, gi]
            g1 = G1[j, gi]
            dr = GDIR[K, m, gi]  # noqa: F821
            rising = dr >= 0 and g0 < 0.0 and g1 < 0.0 and d0 > 0.0 and d1 < 0.0
            falling = dr <= 0 and g0 > 0.0 and g1 > 0.0 and d0 < 0.0 and d1 > 0.0
            if rising or falling:
                s = hermite_extremum(g0, g1, d0, d1)
                v = hermite(s, g0, g1, d0, d1)[0]  # noqa: F821
                if s > width and ((rising and v > 0.0) or (falling and v < 0.0)) and (best < 0.0 or s < best):
                    best = s
    return best


def earliest_crossing(cm, I, WI, Glo, G1, Dlo, D1, lo, hi, dt):
    """``j * GMAX + gi`` of the crossed guard with the earliest predicted root in ``(lo, hi)``, and that root."""
    nc = I[H_NC]
    claw = vec(I, I, O_CLAW, nc)
    best = -1
    xbest = hi
    for j in range(nc):
        K = claw[j]
        m = cm[j]
        for gi in range(NG[K, m]):  # noqa: F821
            if crossed(Glo[j, gi], G1[j, gi], GDIR[K, m, gi]):  # noqa: F821
                x = predicted_root(Glo[j, gi], G1[j, gi], Dlo[j, gi], D1[j, gi], lo, hi, dt)  # noqa: F821
                if best < 0 or x < xbest:
                    best = j * GMAX + gi  # noqa: F821
                    xbest = x
    return best, xbest


def locate_event(t, y, dt, cm, I, R, WI, WF, SC, GS, width, predicted, counters):
    """Bracket the earliest guard crossing of the sub-step ``[t, t + dt]`` to ``width`` (a fraction of it).

    On entry ``SC[0]`` holds ``dy/dt`` at ``(t, y)``, ``SC[5]`` the state at the
    sub-step's end and ``GS[0]``, ``GS[1]`` (``GS[4]``, ``GS[5]``) the guards (rates) at
    its two ends. Every trial is the true RK4 sub-step of that length, so the root
    is the one of the discrete flow. The first trial is the root of the cubic
    Hermite interpolant of the target guard where its rates are known (the
    penetration), else of the chord; the next ones are Newton steps on the
    interpolant's slope, then secants through the last two trials, kept inside the
    bracket, with a bisection when two trials did not halve it; a trial predicted
    within half a tolerance of one end is set three quarters of a tolerance past it,
    to close the bracket in one trial. The bracket is kept by ``first_crossing``
    over every guard (an earlier crossing of another guard becomes the target).

    Returns the bracket's far end ``hi``; ``SC[5]`` and ``GS[1]`` then hold the state
    and guards there, past the root by at most ``width`` of the sub-step (or by the
    floating-point resolution of the step, if the tolerance is finer).
    """
    y1, ymid = SC[5], SC[6]
    G0, G1, Gm, Glo = GS[0], GS[1], GS[2], GS[7]
    D0, D1, Dm, Dlo = GS[4], GS[5], GS[6], GS[8]
    copy_guards(Glo, G0, Dlo, D0)
    lo = 0.0
    hi = 1.0
    code, x = earliest_crossing(cm, I, WI, Glo, G1, Dlo, D1, lo, hi, dt)
    if code < 0:
        code = first_crossing(cm, I, WI, G0, G1)
    jt = code // GMAX  # noqa: F821
    gt = code - jt * GMAX  # noqa: F821
    # the last two trials of the target guard (fraction, value), for the secant
    xa, ga, xb, gb = lo, Glo[jt, gt], hi, G1[jt, gt]
    slope = math.nan
    k = 0
    w_old = 1.0
    k_pred = 0
    halve = False
    while hi - lo > width and k < MAX_LOCATE_TRIALS:
        if not predicted:
            x = 0.5 * (lo + hi)   # bisection (for comparison: the product kernel's default)
        elif k > k_pred:
            if math.isfinite(slope) and slope != 0.0:
                x = xb - gb / slope
                slope = math.nan
            else:
                x = inverse_quadratic(xa, ga, xb, gb, math.nan, math.nan, lo, hi)  # noqa: F821 (the secant)
            if k % 2 == 0:
                halve = hi - lo > 0.5 * w_old
                w_old = hi - lo
        if predicted:
            if k == k_pred:
                # the first trial on a target is aimed half a tolerance past its predicted root, and
                # the next one closes the bracket from the far end: that end, the state taken past
                # the event, then clears the root by about what a bisection leaves, not by a rounding
                # error of the guard (an event then fired again at once, at a fine tolerance)
                x += 0.5 * width
            x = safeguarded_trial(x, lo, hi, width, halve, 0.75)  # noqa: F821
            halve = False
        elif not lo < x < hi:
            x = 0.5 * (lo + hi)
        if not lo < x < hi:
            break   # the bracket is as narrow as the floating-point resolution allows
        k += 1
        c = locate_trial(t, y, dt, x, cm, I, R, WI, WF, SC, ymid, G0, Gm, Dm, counters)
        if c >= 0:
            hi = x
            for i in range(y1.shape[0]):
                y1[i] = ymid[i]
            copy_guards(G1, Gm, D1, Dm)
        else:
            lo = x
            copy_guards(Glo, Gm, Dlo, Dm)
        if c >= 0 and c != code:
            # an earlier crossing of another guard: the earliest predicted in the new bracket is the target
            code, xnext = earliest_crossing(cm, I, WI, Glo, G1, Dlo, D1, lo, hi, dt)
            if code < 0:
                code = c
            jt = code // GMAX  # noqa: F821
            gt = code - jt * GMAX  # noqa: F821
            xa, ga, xb, gb = lo, Glo[jt, gt], hi, G1[jt, gt]
            slope = math.nan
            x = xnext
            k_pred = k
            continue
        if k == k_pred + 1 and math.isfinite(Dm[jt, gt]):
            slope = Dm[jt, gt] * dt   # the next trial: a Newton step on the guard's own rate
        xa, ga = xb, gb
        xb, gb = x, Gm[jt, gt]
    return hi


def first_near_crossing(cm, I, WI, Gs, G1, span, tol):
    """``j * GMAX + gi`` of the first guard of a contact not yet fired that will cross within ``tol``.

    ``Gs`` and ``G1`` are the guards at the sub-step start and at the event, ``span``
    apart in time. A guard moving toward its crossing whose root, extrapolated
    linearly, lies within the event tolerance ``tol`` after the event is
    simultaneous with it (the two roots are not told apart by the location), so it
    fires now; otherwise roots equal but for round-off, as in a symmetric ring, could
    split into two events in either order.
    """
    if span <= 0.0:
        return -1
    nc = I[H_NC]
    claw, fired = vec(I, I, O_CLAW, nc), wvec(WI, nc, 5)
    for j in range(nc):
        if fired[j] != 0:
            continue
        K = claw[j]
        m = cm[j]
        for gi in range(NG[K, m]):  # noqa: F821
            d = GDIR[K, m, gi]  # noqa: F821
            gs = Gs[j, gi]
            ge = G1[j, gi]
            toward = (d <= 0 and 0.0 <= ge < gs) or (d >= 0 and gs < ge <= 0.0)
            if toward and abs(ge) * span <= abs(ge - gs) * tol:
                return j * GMAX + gi  # noqa: F821
    return -1


def cone_ratio(y, I, R, WI, WF):
    """Largest ``|f| / bound`` over the sticking rigid contacts (after ``contact_forces``)."""
    ns, nc = WI[0], I[H_NC]
    sl, cf = wvec(WI, nc, 0), vec(WF, I, F_FR, nc)
    worst = 0.0
    for a in range(ns):
        j = sl[a]
        b = slip_bound(j, y, I, R, WF)
        r = abs(cf[j]) / b if b > 0.0 else (0.0 if cf[j] == 0.0 else math.inf)
        worst = max(worst, r)
    return worst


# ---- events -------------------------------------------------------------------------------
def apply_transition(t, y, cm, j, gi, I, R, WI, WF):
    """Fire guard ``gi`` of contact ``j`` at ``(t, y)``; returns the new mode."""
    contact_forces(t, y, cm, I, R, WI, WF)
    K = I[I[O_CLAW] + j]
    return law_transition(K, cm[j], gi, WF[I[F_N] + j], WF[I[F_ND] + j], WF[I[F_V] + j],  # noqa: F821
                          WF[I[F_FR] + j], y, law_offset(I, j), R, I, j, vec(WF, I, F_Z, MAX_LAW_STATES))


def project_onto_stick(y, I, R, WI, WF):
    """Project the velocities onto zero slip of every sticking contact (``u -= M^-1 G^T W^-1 G u``)."""
    n, nc, ns = I[H_N], I[H_NC], WI[0]
    cidx, cgr, invm = mat(I, I, O_CIDX, nc, 4), mat(R, I, R_GR, nc, 4), vec(R, I, R_INVM, n)
    sl, env = wvec(WI, nc, 0), wvec(WI, nc, 1)
    bst, xst = vec(WF, I, F_B, nc), vec(WF, I, F_X, nc)
    for a in range(ns):
        j = sl[a]
        s = 0.0
        for k in range(4):
            i = cidx[j, k]
            if i >= 0:
                s += cgr[j, k] * y[n + i]
        bst[a] = s
    solve_stick(ns, env, mat(WF, I, F_L, nc, nc), vec(WF, I, F_D, nc), bst, xst)
    for a in range(ns):
        j = sl[a]
        for k in range(4):
            i = cidx[j, k]
            if i >= 0:
                y[n + i] -= invm[i] * cgr[j, k] * xst[a]


def resolve_friction(t, y, cm, I, R, WI, WF, counters, max_pivots):
    """Modes of the contacts in ``U`` from the friction complementarity problem.

    With the normal loads fixed, each contact of ``U`` either sticks (zero relative
    tangential acceleration, ``|f| <= mu N``) or slips (``f = +-mu N`` with the
    relative acceleration along the slip). The stick forces of the sticking set
    solve ``W_SS f = b``; a least-index principal pivoting (Murty) changes one
    violated contact at a time until none is violated: the unique solution of the
    strictly convex box QP ``min 1/2 f^T W f - b^T f, |f| <= mu N``. Velocities are
    projected onto the stick constraints of contacts that were not sticking
    before the event (``cm0``), from the state at the event (``yev``).

    Returns True if resolved, False at the pivot cap.
    """
    n, nc = I[H_N], I[H_NC]
    claw, cidx = vec(I, I, O_CLAW, nc), mat(I, I, O_CIDX, nc, 4)
    invm, cgr, W = vec(R, I, R_INVM, n), mat(R, I, R_GR, nc, 4), mat(R, I, R_W, nc, nc)
    U, cm0 = wvec(WI, nc, 2), wvec(WI, nc, 3)
    yev = vec(WF, I, F_YEV, y.shape[0])
    F, cf = vec(WF, I, F_F, n), vec(WF, I, F_FR, nc)
    for i in range(y.shape[0]):
        yev[i] = y[i]
    for it in range(max_pivots):
        for i in range(y.shape[0]):
            y[i] = yev[i]
        factor_stick(cm, I, R, WI, WF)
        newly = False
        for j in range(nc):
            K = claw[j]
            if IS_STICK[K, cm[j]] and not IS_STICK[K, cm0[j]]:  # noqa: F821
                newly = True
        if newly:
            project_onto_stick(y, I, R, WI, WF)
        contact_forces(t, y, cm, I, R, WI, WF)
        flip = -1
        for j in range(nc):
            if not U[j]:
                continue
            K = claw[j]
            m = cm[j]
            b = slip_bound(j, y, I, R, WF)
            if m == RIGID[K, 0]:  # noqa: F821
                if b - abs(cf[j]) < 0.0:
                    flip = j
                    cm[j] = RIGID[K, 1] if cf[j] > 0.0 else RIGID[K, 2]  # noqa: F821
                    break
            else:
                s = 1.0 if m == RIGID[K, 1] else -1.0  # noqa: F821
                a = 0.0
                for k in range(4):
                    i = cidx[j, k]
                    if i >= 0:
                        a += cgr[j, k] * invm[i] * F[i]
                if s * a < -SLIP_SIGN_TOL * W[j, j] * b:
                    flip = j
                    cm[j] = RIGID[K, 0]  # noqa: F821
                    break
        if flip < 0:
            return True
        counters[C_FRICTION_PIVOTS] += 1
    return False


def rigid_problem(cm, I, WI):
    """Mark in ``U`` the closed rigid contacts whose mode an event leaves open; True if any.

    Those are the contacts sticking before the event (``cm0``) or sent to stick by
    it: a slipping contact whose velocity has not reached zero keeps its slip.
    """
    nc = I[H_NC]
    claw, U, cm0 = vec(I, I, O_CLAW, nc), wvec(WI, nc, 2), wvec(WI, nc, 3)
    anyu = False
    for j in range(nc):
        K = claw[j]
        u = False
        if RIGID[K, 0] >= 0 and cm[j] != 0:  # noqa: F821
            u = IS_STICK[K, cm[j]] != 0 or IS_STICK[K, cm0[j]] != 0  # noqa: F821
        U[j] = 1 if u else 0
        if u:
            anyu = True
    return anyu


def log_event(t, j, gi, old, new, log_t, log_c, log_g, log_from, log_to, counters, recording, fired):
    """Log and count a mode change of contact ``j``; ``fired[j]`` remembers it for this event."""
    k = counters[C_LOGGED]
    if recording:
        if k < log_t.shape[0]:
            log_t[k] = t
            log_c[k] = j
            log_g[k] = gi
            log_from[k] = old
            log_to[k] = new
        counters[C_LOGGED] += 1
    fired[j] = k + 1 if recording else -1
    counters[C_EVENTS] += 1


def settle_event(t, y, cm, I, R, WI, WF, counters, max_pivots, log_t, log_c, log_g, log_from, log_to,
                 recording):
    """After guard transitions: the friction problem of the rigid contacts, logged; False if unresolved."""
    nc = I[H_NC]
    cm0, before, fired = wvec(WI, nc, 3), wvec(WI, nc, 4), wvec(WI, nc, 5)
    ok = True
    if rigid_problem(cm, I, WI):
        for j in range(nc):
            before[j] = cm[j]
        ok = resolve_friction(t, y, cm, I, R, WI, WF, counters, max_pivots)
        for j in range(nc):
            if cm[j] == before[j]:
                continue
            if fired[j] != 0:
                # the guard of this very contact fired in this event: one event, to the settled mode
                k = fired[j] - 1
                if k >= 0 and k < log_to.shape[0]:
                    log_to[k] = cm[j]
            else:
                log_event(t, j, runtime(-1), before[j], cm[j], log_t, log_c, log_g, log_from, log_to, counters,
                          recording, fired)
    factor_stick(cm, I, R, WI, WF)
    for j in range(nc):
        cm0[j] = cm[j]
        fired[j] = 0
    return ok


def initial_modes(t, y, cm, I, R, WI, WF, G, counters, max_pivots, e, ei):
    """Close every contact whose normal guard is ``>= 0`` (penetration ``>= 0`` for a contact spring)
    through its law's entry rule; resolve friction.

    ``G`` is guard scratch ``(nc, GMAX)``; ``e`` and ``ei`` are empty float and int
    arrays (no event log).
    """
    nc = I[H_NC]
    claw, cm0 = vec(I, I, O_CLAW, nc), wvec(WI, nc, 3)
    for j in range(nc):
        cm[j] = 0
        cm0[j] = 0
    factor_stick(cm, I, R, WI, WF)
    eval_guards(t, y, cm, I, R, WI, WF, G)
    for j in range(nc):
        if G[j, 0] >= 0.0 and NG[claw[j], 0] > 0:  # noqa: F821
            cm[j] = apply_transition(t, y, cm, j, runtime(0), I, R, WI, WF)
            factor_stick(cm, I, R, WI, WF)
    return settle_event(t, y, cm, I, R, WI, WF, counters, max_pivots, e, ei, ei, ei, ei, runtime(False))


def record(irec, t, y, cm, I, R, WI, WF, rec_t, rec_y, rec_cm, rec_N, rec_f):
    """Write record ``irec`` (state, contact modes and, if kept, contact forces)."""
    n, nc = y.shape[0], I[H_NC]
    rec_t[irec] = t
    for i in range(n):
        rec_y[irec, i] = y[i]
    keep = rec_N.shape[0] > 0
    if keep:
        contact_forces(t, y, cm, I, R, WI, WF)
    for j in range(nc):
        rec_cm[irec, j] = cm[j]
        if keep:
            rec_N[irec, j] = WF[I[F_N] + j]
            rec_f[irec, j] = WF[I[F_FR] + j]


def integrate(y, cm, I, R, WI, WF, SC, GS, period, steps_per_period, start_period, end_period, n_transient,
              record_every, event_tol, max_events, max_pivots, detect_grazing, predicted, rec_t, rec_y, rec_cm,
              rec_N, rec_f, poincare, log_t, log_c, log_g, log_from, log_to, counters, stats):
    """Integrate excitation periods ``start_period`` to ``end_period`` (exclusive).

    The same schedule as the product-mode kernel (:func:`blademodel.numeric.loop.integrate`):
    ``h = period / steps_per_period``; after each (sub)step every contact's guards are
    compared with the step start; the earliest crossing is bracketed by bisection
    to ``event_tol * h`` and the state taken past it; its transition fires, then the
    guards of other contacts that crossed in the same bracket, then the friction
    problem settles the rigid contacts. ``y`` and ``cm`` are updated in place.

    Returns ``(status, t)``.
    """
    n = y.shape[0]
    nc = I[H_NC]
    fired = wvec(WI, nc, 5)
    h = period / steps_per_period
    y1, ymid, ysub, knext = SC[5], SC[6], SC[7], SC[8]
    G0, G1, Gs = GS[0], GS[1], GS[3]
    D0, D1 = GS[4], GS[5]
    t = period * start_period
    irec = counters[C_RECORDS]
    g0_valid = False
    factor_stick(cm, I, R, WI, WF)
    cm0 = wvec(WI, nc, 3)
    for j in range(nc):
        cm0[j] = cm[j]
        fired[j] = 0
    for per in range(start_period, end_period):
        recording = per >= n_transient
        if recording and per == n_transient and irec < rec_t.shape[0]:
            record(irec, t, y, cm, I, R, WI, WF, rec_t, rec_y, rec_cm, rec_N, rec_f)
            irec += 1
        for js in range(steps_per_period):
            t_end = period * per + (js + 1) * h
            tol_t = event_tol * h
            n_events = 0
            while t < t_end:
                dt = t_end - t
                if not g0_valid:
                    rhs_guards(t, y, cm, I, R, WI, WF, SC[0], G0)
                    guard_rates(y, SC[0], cm, I, R, WI, WF, D0, True)
                    counters[C_RHS] += 1
                # SC[0] holds dy/dt at (t, y): from the line above or the end of the last step
                spent = rk_step(t, y, dt, cm, I, R, WI, WF, SC, y1, True)
                rhs_guards(t_end, y1, cm, I, R, WI, WF, knext, G1)
                guard_rates(y1, knext, cm, I, R, WI, WF, D1, False)
                counters[C_RHS] += spent + 1
                code = first_crossing(cm, I, WI, G0, G1)
                if code >= 0 and WI[0] > 0 and WI[1] < 0:
                    # the stick guards' rates at both ends (kept without them on a step with no event)
                    guard_rates(y1, knext, cm, I, R, WI, WF, D1, True)
                    contact_forces(t, y, cm, I, R, WI, WF)
                    guard_rates(y, SC[0], cm, I, R, WI, WF, D0, True)
                    counters[C_RHS] += 1
                sub = dt   # the sub-step whose end lies past the event
                if code < 0 and detect_grazing:
                    xg = grazing_candidate(cm, I, G0, G1, D0, D1, dt, tol_t / dt)
                    if xg > 0.0:
                        Gm, Dm = GS[2], GS[6]
                        code = locate_trial(t, y, dt, xg, cm, I, R, WI, WF, SC, ymid, G0, Gm, Dm, counters)
                        if code >= 0:   # it did cross: the event's bracket ends at the extremum
                            sub = xg * dt
                            for i in range(n):
                                y1[i] = ymid[i]
                            copy_guards(G1, Gm, D1, Dm)
                            counters[C_GRAZING] += 1
                if code < 0:
                    for i in range(n):
                        y[i] = y1[i]
                        SC[0, i] = knext[i]
                    copy_guards(G0, G1, D0, D1)
                    g0_valid = True
                    t = t_end
                    if WI[0] > 0:
                        stats[S_MAX_CONE_RATIO] = max(stats[S_MAX_CONE_RATIO], cone_ratio(y, I, R, WI, WF))
                    break
                hi = locate_event(t, y, sub, cm, I, R, WI, WF, SC, GS, tol_t / sub, predicted, counters)
                code = first_crossing(cm, I, WI, G0, G1)
                t_sub = t
                for i in range(n):
                    ysub[i] = y[i]
                t = t_end if hi == 1.0 and sub == dt else t + hi * sub
                for i in range(n):
                    y[i] = y1[i]
                while code >= 0:
                    j = code // GMAX  # noqa: F821
                    gi = code - j * GMAX  # noqa: F821
                    old = cm[j]
                    cm[j] = apply_transition(t, y, cm, j, gi, I, R, WI, WF)
                    log_event(t, j, gi, old, cm[j], log_t, log_c, log_g, log_from, log_to, counters, recording,
                              fired)
                    n_events += 1
                    if n_events > max_events:
                        counters[C_RECORDS] = irec
                        return STATUS_EVENT_STORM, t
                    factor_stick(cm, I, R, WI, WF)
                    eval_guards(t_sub, ysub, cm, I, R, WI, WF, Gs)
                    eval_guards(t, y, cm, I, R, WI, WF, G1)
                    code = first_crossing(cm, I, WI, Gs, G1)
                    if code < 0:
                        code = first_near_crossing(cm, I, WI, Gs, G1, t - t_sub, tol_t)
                if not settle_event(t, y, cm, I, R, WI, WF, counters, max_pivots, log_t, log_c, log_g,
                                    log_from, log_to, recording):
                    counters[C_RECORDS] = irec
                    return STATUS_FRICTION_UNRESOLVED, t
                g0_valid = False
            counters[C_STEPS] += 1
            for i in range(n):
                if not math.isfinite(y[i]):
                    counters[C_RECORDS] = irec
                    return STATUS_NONFINITE, t
            if recording and (js + 1) % record_every == 0 and irec < rec_t.shape[0]:
                record(irec, t, y, cm, I, R, WI, WF, rec_t, rec_y, rec_cm, rec_N, rec_f)
                irec += 1
        if recording:
            for i in range(n):
                poincare[per - n_transient, i] = y[i]
    counters[C_RECORDS] = irec
    return STATUS_OK, t
