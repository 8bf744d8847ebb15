"""The per-contact hybrid kernel: RK4, located events, coupled rigid stick.

This file is a *template* pasted into a generated module (:mod:`.contact_codegen`)
after the friction laws' functions and tables: ``law_force``, ``law_rates``,
``law_guards``, ``law_transition``, ``law_dissipation`` dispatch on the law kind
``K``; ``NG[K, mode]``, ``GDIR[K, mode, gi]``, ``IS_STICK[K, mode]`` and
``RIGID[K] = (stick, slip+, slip-)`` describe the kinds. Nothing here grows with
the number of contacts: every contact holds one mode integer ``cm[j]`` and is
handled by index.

Tables (constant during a run), grouped in two tuples:

``ti`` (int64): ``Kp, Ki`` (stiffness, CSR rows), ``Cp, Ci`` (damping, CSR),
``fi, fg`` (forcing entries: coordinate and frequency group), ``cidx`` (contact
slots, ``(nc, 4)``, -1 unused), ``claw`` (law kind), ``cso`` (state offset of the
law's states after ``q`` and ``u``), ``LP`` (the law's parameter indices into ``p``).

``tf`` (float64): ``invm`` (inverse masses), ``Kv``, ``Cv`` (CSR values),
``fs, fc`` (forcing ``fs sin(w t) + fc cos(w t)``), ``om`` (group frequencies),
``cgn, cgr`` (gradients of the penetration and of the relative slip, per slot),
``cgap``, ``ck`` (gap, normal stiffness), ``p`` (parameter values), ``W``
(Delassus matrix ``G M^-1 G^T`` of the tangential directions, ``(nc, nc)``).

Work arrays (the run buffer), grouped likewise:

``wi`` (int64): ``ws`` (``ws[0]`` number of sticking rigid contacts, ``ws[1]``
position of the null pivot or -1), ``sl`` (the sticking contacts, ascending),
``env`` (first column of each row of the stick matrix's envelope), ``U``
(contacts of the current friction problem), ``cm0`` (modes before an event),
``before`` (modes before the friction problem, for the log), ``fired`` (per
contact, 1 + the log row of its transition in the current event, 0 if none).

``wf`` (float64): ``F`` (generalized forces), ``cN, cNd, cv, cf, cdl`` (per
contact normal force, its rate, slip velocity, friction force, penetration),
``xst`` (stick forces), ``Lf, Dd`` (envelope LDL^T factor of the stick matrix),
``nullv`` (its null vector, a closed ring of sticking contacts), ``bst`` (stick
right-hand side), ``sg, cg`` (sin and cos of each frequency group), ``ztmp``
(law-state scratch), ``yev`` (state at an event before the friction problem).

``sc`` (scratch of ``integrate``): ``k1 .. k4, tmp, y1, ymid, ysub`` (states) and
``G0, G1, Gm, Gs`` (guard values, ``(nc, GMAX)``). The kernel allocates nothing:
every function is compiled without reference counting (see :mod:`.contact_codegen`).
:func:`blademodel.numeric.contact_kernel.run_buffer` allocates both.

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

import numpy as np

from blademodel.numeric.contract import (C_BISECTIONS, C_EVENTS, C_FRICTION_PIVOTS, C_LOGGED, C_RECORDS, C_RHS,
                                         C_STEPS, S_MAX_CONE_RATIO, STATUS_EVENT_STORM,
                                         STATUS_FRICTION_UNRESOLVED, STATUS_NONFINITE, STATUS_OK)

#: Relative size of a pivot of the stick matrix below which it counts as zero (a closed ring).
NULL_PIVOT = 1e-10
#: Relative tolerance on the sign of a slipping contact's acceleration in the friction problem.
SLIP_SIGN_TOL = 1e-9


# ---- the stick matrix ---------------------------------------------------------------
def factor_stick(cm, ti, tf, wi, wf):
    """Collect the sticking rigid contacts and factor their Delassus block (envelope LDL^T)."""
    claw = ti[7]
    W = tf[11]
    ws, sl, env = wi[0], wi[1], wi[2]
    Lf, Dd, nullv = wf[7], wf[8], wf[9]
    ns = 0
    for j in range(cm.shape[0]):
        if IS_STICK[claw[j], cm[j]]:  # noqa: F821
            sl[ns] = j
            ns += 1
    ws[0] = ns
    ws[1] = -1
    for a in range(ns):
        env[a] = a
        for b in range(a):
            if W[sl[a], sl[b]] != 0.0:
                env[a] = b
                break
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
            ws[1] = i
        Dd[i] = d
    if ws[1] >= 0:
        k0 = ws[1]
        for a in range(ns):
            nullv[a] = 0.0
        nullv[k0] = 1.0
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


def slip_bound(j, y, ti, tf, wf):
    """The slip force magnitude ``mu N`` of rigid contact ``j`` (its slip+ force)."""
    claw, cso, LP = ti[7], ti[8], ti[9]
    p = tf[10]
    K = claw[j]
    n = tf[0].shape[0]
    return law_force(K, RIGID[K, 1], wf[1][j], wf[2][j], wf[3][j], y, 2 * n + cso[j], p, LP, j)  # noqa: F821


def least_cone_ratio(y, ti, tf, wi, wf):
    """Shift the stick forces along the null vector to minimise ``max |x| / bound``."""
    ns, sl = wi[0][0], wi[1]
    xst, nullv = wf[6], wf[9]
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
            w = 1.0 / max(slip_bound(sl[a], y, ti, tf, wf), 1e-300)
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
def contact_forces(t, y, cm, ti, tf, wi, wf):
    """Generalized forces ``F`` and each contact's ``N``, ``Nd``, ``v``, ``f``, penetration.

    Returns the input power of the forcing (for the energy accumulators).
    """
    Kp, Ki, Cp, Ci, fi, fg, cidx, claw, cso, LP = ti
    invm, Kv, Cv, fs, fc, om, cgn, cgr, cgap, ck, p, W = tf
    F, cN, cNd, cv, cf, cdl, bst, xst = wf[0], wf[1], wf[2], wf[3], wf[4], wf[5], wf[10], wf[6]
    sg, cg = wf[11], wf[12]
    n = invm.shape[0]
    for g in range(om.shape[0]):
        sg[g] = math.sin(om[g] * t)
        cg[g] = math.cos(om[g] * t)
    for i in range(n):
        s = 0.0
        for e in range(Kp[i], Kp[i + 1]):
            s -= Kv[e] * y[Ki[e]]
        for e in range(Cp[i], Cp[i + 1]):
            s -= Cv[e] * y[n + Ci[e]]
        F[i] = s
    power = 0.0
    for e in range(fi.shape[0]):
        load = fs[e] * sg[fg[e]] + fc[e] * cg[fg[e]]
        F[fi[e]] += load
        power += load * y[n + fi[e]]
    for j in range(cm.shape[0]):
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
        cv[j] = vv
        mode = cm[j]
        if mode == 0:
            cN[j] = 0.0
            cNd[j] = 0.0
            cf[j] = 0.0
            continue
        N = ck[j] * dl
        cN[j] = N
        cNd[j] = ck[j] * dd
        K = claw[j]
        f = 0.0
        if not IS_STICK[K, mode]:  # noqa: F821
            f = law_force(K, mode, N, cNd[j], vv, y, 2 * n + cso[j], p, LP, j)  # noqa: F821
        cf[j] = f
        for k in range(4):
            i = cidx[j, k]
            if i >= 0:
                F[i] -= N * cgn[j, k] + f * cgr[j, k]
    ws, sl, env = wi[0], wi[1], wi[2]
    ns = ws[0]
    if ns > 0:
        for a in range(ns):
            j = sl[a]
            s = 0.0
            for k in range(4):
                i = cidx[j, k]
                if i >= 0:
                    s += cgr[j, k] * invm[i] * F[i]
            bst[a] = s
        solve_stick(ns, env, wf[7], wf[8], bst, xst)
        if ws[1] >= 0:
            least_cone_ratio(y, ti, tf, wi, wf)
        for a in range(ns):
            j = sl[a]
            cf[j] = xst[a]
            for k in range(4):
                i = cidx[j, k]
                if i >= 0:
                    F[i] -= xst[a] * cgr[j, k]
    return power


def rhs(t, y, cm, ti, tf, wi, wf, out):
    """``dy/dt`` with every contact in its mode ``cm[j]``."""
    power = contact_forces(t, y, cm, ti, tf, wi, wf)
    claw, cso, LP = ti[7], ti[8], ti[9]
    invm, Cp, Ci, Cv, p = tf[0], ti[2], ti[3], tf[2], tf[10]
    F, cN, cNd, cv, cf = wf[0], wf[1], wf[2], wf[3], wf[4]
    n = invm.shape[0]
    for i in range(n):
        out[i] = y[n + i]
        out[n + i] = invm[i] * F[i]
    for j in range(cm.shape[0]):
        law_rates(claw[j], cm[j], cN[j], cNd[j], cv[j], cf[j], y, 2 * n + cso[j], p, LP, j, out,  # noqa: F821
                  2 * n + cso[j])
    nc = cm.shape[0]
    n_law = 2 * n + (cso[nc - 1] + NSTATES[claw[nc - 1]] if nc > 0 else 0)  # noqa: F821
    if y.shape[0] > n_law:
        visc = 0.0
        for i in range(n):
            s = 0.0
            for e in range(Cp[i], Cp[i + 1]):
                s += Cv[e] * y[n + Ci[e]]
            visc += y[n + i] * s
        fric = 0.0
        for j in range(cm.shape[0]):
            if cm[j] != 0:
                fric += law_dissipation(claw[j], cm[j], cN[j], cNd[j], cv[j], cf[j], y,  # noqa: F821
                                        2 * n + cso[j], p, LP, j)
        out[n_law] = power
        out[n_law + 1] = visc
        out[n_law + 2] = fric


def rk4_step(t, y, h, cm, ti, tf, wi, wf, k1, k2, k3, k4, tmp, out):
    """One classical RK4 step of size ``h`` from ``(t, y)`` into ``out``."""
    n = y.shape[0]
    rhs(t, y, cm, ti, tf, wi, wf, k1)
    for i in range(n):
        tmp[i] = y[i] + 0.5 * h * k1[i]
    rhs(t + 0.5 * h, tmp, cm, ti, tf, wi, wf, k2)
    for i in range(n):
        tmp[i] = y[i] + 0.5 * h * k2[i]
    rhs(t + 0.5 * h, tmp, cm, ti, tf, wi, wf, k3)
    for i in range(n):
        tmp[i] = y[i] + h * k3[i]
    rhs(t + h, tmp, cm, ti, tf, wi, wf, k4)
    for i in range(n):
        out[i] = y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])


# ---- guards -------------------------------------------------------------------------------
def eval_guards(t, y, cm, ti, tf, wi, wf, G):
    """Every contact's guards into ``G[j, :]``: 0 the penetration, then the law's."""
    contact_forces(t, y, cm, ti, tf, wi, wf)
    claw, cso, LP = ti[7], ti[8], ti[9]
    p = tf[10]
    n = tf[0].shape[0]
    cN, cNd, cv, cf, cdl = wf[1], wf[2], wf[3], wf[4], wf[5]
    for j in range(cm.shape[0]):
        G[j, 0] = cdl[j]
        law_guards(claw[j], cm[j], cN[j], cNd[j], cv[j], cf[j], y, 2 * n + cso[j], p, LP, j, G)  # noqa: F821


def crossed(g0, g1, direction):
    """Whether a guard went from ``g0`` to ``g1`` through zero in ``direction`` (see ``loop.crossed``)."""
    if direction < 0:
        return g0 >= 0.0 and g1 < 0.0
    if direction > 0:
        return g0 <= 0.0 and g1 > 0.0
    return (g0 > 0.0 and g1 <= 0.0) or (g0 < 0.0 and g1 >= 0.0)


def first_crossing(cm, claw, G0, G1, fired, use_fired):
    """``j * GMAX + gi`` of the first guard that crossed (contacts in order), or -1.

    With ``use_fired``, contacts with ``fired[j] != 0`` are passed over: a contact
    whose transition fired in this event has been settled by its law, and its new
    mode's guards compared across the bracket mean nothing.
    """
    for j in range(cm.shape[0]):
        if use_fired and fired[j] != 0:
            continue
        K = claw[j]
        m = cm[j]
        for gi in range(NG[K, m]):  # noqa: F821
            if crossed(G0[j, gi], G1[j, gi], GDIR[K, m, gi]):  # noqa: F821
                return j * GMAX + gi  # noqa: F821
    return -1


def cone_ratio(y, cm, ti, tf, wi, wf):
    """Largest ``|f| / bound`` over the sticking rigid contacts (after ``contact_forces``)."""
    ns, sl = wi[0][0], wi[1]
    worst = 0.0
    for a in range(ns):
        j = sl[a]
        b = slip_bound(j, y, ti, tf, wf)
        r = abs(wf[4][j]) / b if b > 0.0 else (0.0 if wf[4][j] == 0.0 else math.inf)
        worst = max(worst, r)
    return worst


# ---- events -------------------------------------------------------------------------------
def apply_transition(t, y, cm, j, gi, ti, tf, wi, wf):
    """Fire guard ``gi`` of contact ``j`` at ``(t, y)``; returns the new mode."""
    claw, cso, LP = ti[7], ti[8], ti[9]
    p = tf[10]
    n = tf[0].shape[0]
    contact_forces(t, y, cm, ti, tf, wi, wf)
    K = claw[j]
    new = law_transition(K, cm[j], gi, wf[1][j], wf[2][j], wf[3][j], wf[4][j], y, 2 * n + cso[j], p,  # noqa: F821
                         LP, j, wf[13])
    return new


def project_onto_stick(y, ti, tf, wi, wf):
    """Project the velocities onto zero slip of every sticking contact (``u -= M^-1 G^T W^-1 G u``)."""
    cidx = ti[6]
    invm, cgr = tf[0], tf[7]
    ns, sl, env = wi[0][0], wi[1], wi[2]
    bst, xst = wf[10], wf[6]
    n = invm.shape[0]
    for a in range(ns):
        j = sl[a]
        s = 0.0
        for k in range(4):
            i = cidx[j, k]
            if i >= 0:
                s += cgr[j, k] * y[n + i]
        bst[a] = s
    solve_stick(ns, env, wf[7], wf[8], bst, xst)
    for a in range(ns):
        j = sl[a]
        for k in range(4):
            i = cidx[j, k]
            if i >= 0:
                y[n + i] -= invm[i] * cgr[j, k] * xst[a]


def resolve_friction(t, y, cm, ti, tf, wi, wf, counters, max_pivots):
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
    claw, cidx = ti[7], ti[6]
    invm, cgr, W = tf[0], tf[7], tf[11]
    U, cm0 = wi[3], wi[4]
    yev = wf[14]
    F = wf[0]
    n = invm.shape[0]
    nc = cm.shape[0]
    for i in range(y.shape[0]):
        yev[i] = y[i]
    for it in range(max_pivots):
        for i in range(y.shape[0]):
            y[i] = yev[i]
        factor_stick(cm, ti, tf, wi, wf)
        newly = False
        for j in range(nc):
            K = claw[j]
            if IS_STICK[K, cm[j]] and not IS_STICK[K, cm0[j]]:  # noqa: F821
                newly = True
        if newly:
            project_onto_stick(y, ti, tf, wi, wf)
        contact_forces(t, y, cm, ti, tf, wi, wf)
        flip = -1
        for j in range(nc):
            if not U[j]:
                continue
            K = claw[j]
            m = cm[j]
            b = slip_bound(j, y, ti, tf, wf)
            if m == RIGID[K, 0]:  # noqa: F821
                if b - abs(wf[4][j]) < 0.0:
                    flip = j
                    cm[j] = RIGID[K, 1] if wf[4][j] > 0.0 else RIGID[K, 2]  # noqa: F821
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


def rigid_problem(cm, ti, wi):
    """Mark in ``U`` the closed rigid contacts whose mode an event leaves open; True if any.

    Those are the contacts sticking before the event (``cm0``) or sent to stick by
    it: a slipping contact whose velocity has not reached zero keeps its slip.
    """
    claw = ti[7]
    U, cm0 = wi[3], wi[4]
    anyu = False
    for j in range(cm.shape[0]):
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


def settle_event(t, y, cm, ti, tf, wi, wf, counters, max_pivots, log_t, log_c, log_g, log_from, log_to,
                 recording):
    """After guard transitions: the friction problem of the rigid contacts, logged; False if unresolved."""
    cm0, fired = wi[4], wi[6]
    ok = True
    if rigid_problem(cm, ti, wi):
        before = wi[5]
        for j in range(cm.shape[0]):
            before[j] = cm[j]
        ok = resolve_friction(t, y, cm, ti, tf, wi, wf, counters, max_pivots)
        for j in range(cm.shape[0]):
            if cm[j] == before[j]:
                continue
            if fired[j] != 0:
                # the guard of this very contact fired in this event: one event, to the settled mode
                k = fired[j] - 1
                if k >= 0 and k < log_to.shape[0]:
                    log_to[k] = cm[j]
            else:
                log_event(t, j, -1, before[j], cm[j], log_t, log_c, log_g, log_from, log_to, counters,
                          recording, fired)
    factor_stick(cm, ti, tf, wi, wf)
    for j in range(cm.shape[0]):
        cm0[j] = cm[j]
        fired[j] = 0
    return ok


def initial_modes(t, y, cm, ti, tf, wi, wf, sc, counters, max_pivots, e, ei):
    """Close every contact with penetration ``>= 0`` through its law's entry rule; resolve friction.

    ``e`` and ``ei`` are empty float and int arrays (no event log).
    """
    claw = ti[7]
    cm0 = wi[4]
    G = sc[8]
    for j in range(cm.shape[0]):
        cm[j] = 0
        cm0[j] = 0
    factor_stick(cm, ti, tf, wi, wf)
    eval_guards(t, y, cm, ti, tf, wi, wf, G)
    for j in range(cm.shape[0]):
        if G[j, 0] >= 0.0 and NG[claw[j], 0] > 0:  # noqa: F821
            cm[j] = apply_transition(t, y, cm, j, 0, ti, tf, wi, wf)
            factor_stick(cm, ti, tf, wi, wf)
    return settle_event(t, y, cm, ti, tf, wi, wf, counters, max_pivots, e, ei, ei, ei, ei, False)


def integrate(y, cm, ti, tf, wi, wf, sc, period, steps_per_period, start_period, end_period, n_transient,
              record_every, event_tol, max_events, max_pivots, rec_t, rec_y, rec_cm, rec_N, rec_f, poincare,
              log_t, log_c, log_g, log_from, log_to, counters, stats):
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
    nc = cm.shape[0]
    claw = ti[7]
    h = period / steps_per_period
    k1, k2, k3, k4, tmp, y1, ymid, ysub, G0, G1, Gm, Gs = sc
    keep_forces = rec_N.shape[0] > 0
    t = period * start_period
    irec = counters[C_RECORDS]
    g0_valid = False
    factor_stick(cm, ti, tf, wi, wf)
    for j in range(nc):
        wi[4][j] = cm[j]
    for per in range(start_period, end_period):
        recording = per >= n_transient
        if recording and per == n_transient and irec < rec_t.shape[0]:
            rec_t[irec] = t
            for i in range(n):
                rec_y[irec, i] = y[i]
            contact_forces(t, y, cm, ti, tf, wi, wf)
            for j in range(nc):
                rec_cm[irec, j] = cm[j]
                if keep_forces:
                    rec_N[irec, j] = wf[1][j]
                    rec_f[irec, j] = wf[4][j]
            irec += 1
        for js in range(steps_per_period):
            t_end = period * per + (js + 1) * h
            n_events = 0
            while t < t_end:
                dt = t_end - t
                rk4_step(t, y, dt, cm, ti, tf, wi, wf, k1, k2, k3, k4, tmp, y1)
                counters[C_RHS] += 4
                if not g0_valid:
                    eval_guards(t, y, cm, ti, tf, wi, wf, G0)
                eval_guards(t_end, y1, cm, ti, tf, wi, wf, G1)
                if first_crossing(cm, claw, G0, G1, wi[6], False) < 0:
                    for i in range(n):
                        y[i] = y1[i]
                    for j in range(nc):
                        for gi in range(GMAX):  # noqa: F821
                            G0[j, gi] = G1[j, gi]
                    g0_valid = True
                    t = t_end
                    if wi[0][0] > 0:
                        stats[S_MAX_CONE_RATIO] = max(stats[S_MAX_CONE_RATIO], cone_ratio(y, cm, ti, tf, wi, wf))
                    break
                lo = 0.0
                hi = 1.0
                while (hi - lo) * dt > event_tol * h:
                    mid = 0.5 * (lo + hi)
                    rk4_step(t, y, mid * dt, cm, ti, tf, wi, wf, k1, k2, k3, k4, tmp, ymid)
                    eval_guards(t + mid * dt, ymid, cm, ti, tf, wi, wf, Gm)
                    counters[C_BISECTIONS] += 1
                    counters[C_RHS] += 4
                    if first_crossing(cm, claw, G0, Gm, wi[6], False) >= 0:
                        hi = mid
                        for i in range(n):
                            y1[i] = ymid[i]
                        for j in range(nc):
                            for gi in range(GMAX):  # noqa: F821
                                G1[j, gi] = Gm[j, gi]
                    else:
                        lo = mid
                code = first_crossing(cm, claw, G0, G1, wi[6], False)
                t_sub = t
                for i in range(n):
                    ysub[i] = y[i]
                t = t_end if hi == 1.0 else t + hi * dt
                for i in range(n):
                    y[i] = y1[i]
                while code >= 0:
                    j = code // GMAX  # noqa: F821
                    gi = code - j * GMAX  # noqa: F821
                    old = cm[j]
                    cm[j] = apply_transition(t, y, cm, j, gi, ti, tf, wi, wf)
                    log_event(t, j, gi, old, cm[j], log_t, log_c, log_g, log_from, log_to, counters, recording,
                              wi[6])
                    n_events += 1
                    if n_events > max_events:
                        counters[C_RECORDS] = irec
                        return STATUS_EVENT_STORM, t
                    factor_stick(cm, ti, tf, wi, wf)
                    eval_guards(t_sub, ysub, cm, ti, tf, wi, wf, Gs)
                    eval_guards(t, y, cm, ti, tf, wi, wf, G1)
                    code = first_crossing(cm, claw, Gs, G1, wi[6], True)
                if not settle_event(t, y, cm, ti, tf, wi, wf, counters, max_pivots, log_t, log_c, log_g,
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
                rec_t[irec] = t
                for i in range(n):
                    rec_y[irec, i] = y[i]
                if keep_forces:
                    contact_forces(t, y, cm, ti, tf, wi, wf)
                for j in range(nc):
                    rec_cm[irec, j] = cm[j]
                    if keep_forces:
                        rec_N[irec, j] = wf[1][j]
                        rec_f[irec, j] = wf[4][j]
                irec += 1
        if recording:
            for i in range(n):
                poincare[per - n_transient, i] = y[i]
    counters[C_RECORDS] = irec
    return STATUS_OK, t
