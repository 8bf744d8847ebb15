"""The per-contact hybrid kernel's loop: fixed steps, clusters stepped through their events.

The per-contact kernel is a set of *templates* pasted, in this order, into a
module generated for the model's friction-law kinds (:mod:`.contact_codegen`),
after the laws' functions and tables (``law_force``, ``law_rates``,
``law_guards``, ``law_transition``, ``law_dissipation`` dispatch on the law kind
``K``; ``NG[K, mode]``, ``GDIR[K, mode, gi]``, ``IS_STICK[K, mode]``,
``RIGID[K] = (stick, slip+, slip-)``, ``NSTATES[K]``, ``OPEN_RATES[K]`` describe
the kinds): :mod:`.bracket`, :mod:`.contact_flow` (views, the active set, forces,
``dy/dt``, Runge-Kutta steps), :mod:`.contact_stick` (the coupled rigid stick),
:mod:`.contact_guards`, :mod:`.contact_locate`, :mod:`.contact_events`,
:mod:`.contact_clusters`, this loop, and :mod:`.contact_replay` (for the replayed tangent,
compiled only when it is used). Nothing in them grows with the number of
contacts: every contact holds one mode integer ``cm[j]`` and is handled by index.

**A step.** The whole model takes the step (``h = period / steps_per_period``);
the guards at its end are compared with those at its start. Without a crossing
(or a grazing candidate) the step is accepted. Otherwise the contacts that crossed
are the step's seeds, and each seed's *cluster* (:mod:`.contact_clusters`: all
that is coupled to it) is stepped through its events on its own, from the step's
start to its end, exactly as the whole model would be: the earliest crossing is
bracketed to ``event_tol * h`` (:mod:`.contact_locate`) and the state taken past
it, its transition fires, then the guards of other contacts that crossed in the
same bracket, then the friction problem settles the rigid contacts
(:mod:`.contact_events`), and the rest of the step follows. The rest of the model
keeps the whole step. If, at the step's end, a contact on a cluster's boundary
has crossed after all (its cluster moved differently through its events), the
step starts again from its beginning with that contact a seed too (its two sides
one cluster). An event thus costs work in proportion to its cluster, and a
bladed disk's cost per step and contact stays flat as the ring grows.

**Buffers.** Tables and work arrays are four flat arrays (``I``, ``R``, ``WI``,
``WF``) whose layout is part of the kernel contract
(:mod:`blademodel.numeric.contract`, built by
:func:`blademodel.numeric.contact_kernel.pack_tables`): the header of ``I`` holds
the sizes and the offset of every table, and each function takes *views* of what
it needs (no copies; every function is compiled without reference counting).

``I``: ``Kp, Ki`` (stiffness, CSR rows), ``Cp, Ci`` (damping, CSR), ``fi, fg``
(forcing entries, sorted by coordinate: coordinate, frequency group), ``Fp``
(each coordinate's forcing entries), ``cidx`` (contact slots, ``4`` per contact,
-1 unused), ``claw`` (law kind), ``cso`` (offset of the law's states after ``q``
and ``u``), ``LP`` (the law's parameter indices into ``p``, ``(nc, LPW)``), ``Wp,
Wi`` (the contacts coupled to each contact through ``W``, CSR), ``cnk`` (each
contact's normal law: ``NK_SPRING``, ``NK_DAMPED``, ``NK_LOAD``), ``Dp, Di`` (the
contacts touching each coordinate), ``Ap, Ai`` (the coordinates a spring or damper
couples to each).

``R``: ``invm`` (inverse masses), ``Kv``, ``Cv`` (CSR values), ``fs, fc`` (forcing
``fs sin(w t) + fc cos(w t)``), ``om`` (group frequencies), ``cgn, cgr`` (gradients
of the penetration and of the relative slip, ``4`` per contact), ``cgap``, ``ck``
(gap, normal stiffness), ``cc``, ``cn0`` (normal damping, constant normal load),
``p`` (parameter values), ``W`` (Delassus matrix ``G M^-1 G^T`` of the tangential
directions, ``nc * nc``).

``WI``: a header (``W_*``: sticking contacts, the null pivot, the active set's
kind and sizes, the cluster stamp, boundary and event counts, contacts marked ``WC_NEAR``), per-contact arrays
(``WC_*``), per-coordinate arrays (``WD_*``), the active state rows.

``WF``: ``F`` (generalized forces), ``cN, cNd, cv, cf, cdl`` (per contact normal
force, its rate, slip velocity, friction force, penetration), ``xst`` (stick
forces, by contact), ``Dd`` and ``Lf`` (envelope LDL^T factor of the stick matrix,
by contact), ``nullv`` (its null vector), ``bst`` (stick right-hand side), ``sg, cg``
(sin and cos of each frequency group), ``ztmp`` (law-state scratch), ``yev``
(state at an event before the friction problem), ``cdr`` (penetration rates),
``tsc`` (the time of ``sg, cg``; NaN when none), ``Fd`` and ``xd`` (rates of the
generalized forces and of the stick forces, for the stick guards' rates at an
event), ``acc`` (a cluster's share of the energy accumulators over the whole step), ``goff`` (guard offsets of
the contacts marked ``WC_NEAR``), ``tlast`` (each contact's last transition) and ``noise`` (until when a
suspect's crossings are rounding noise, ``mark_suspects``).

``integrate`` also takes ``SC`` (``(SC_ROWS + s - 1, n_state)``: RK4 stages 0-4,
the step's or bracket's end 5, the trial 6, the sub-step start 7, ``dy/dt`` at the
step's end 8, the state at the step's start ``SC_Y0``, then the stages 1 ... s-1
of a tableau method (``I[H_NS] = s``; its stage 0 is row 0)) and ``GS``
(``(GS_ROWS, nc, GMAX)``: guard values at the step start 0, end 1, trial 2,
sub-step start 3, bracket start 7, their rates 4, 5, 6, 8 (NaN where unknown),
and the guards and rates at the start of a step whose events are handled, 9 and
10). The kernel allocates nothing.
"""

import math  # noqa: F401

from blademodel.numeric.contract import (C_CLUSTERS, C_RESTARTS, C_EVENTS, C_GRAZING, C_LOGGED, C_RECORDS, C_RHS, C_STEPS, F_ACC, F_FR,
                                         F_TLAST, F_N, H_N, H_NC, H_NLAW, S_MAX_CONE_RATIO, SC_Y0, STATUS_EVENT_STORM,
                                         STATUS_FRICTION_UNRESOLVED, STATUS_NONFINITE, STATUS_OK, W_NB, W_NEV,
                                         W_NS, W_STAMP, WC_CM0, WC_CMSTEP, WC_FIRED, WC_SEED)


def process_cluster(t, t_end, y, cm, I, R, WI, WF, SC, GS, reuse, tol_t, max_events, max_pivots, detect_grazing,
                    predicted, log_t, log_c, log_g, log_from, log_to, counters, recording):
    """Step the active cluster from ``t`` to ``t_end`` through its events.

    With ``reuse``, the whole step's rows (``SC[0]``, ``SC[5]``, ``SC[8]``, the guards
    and rates at both ends) are the cluster's first sub-step: a restricted step
    computes the same numbers. On return the cluster's rows of ``y`` and ``SC[5]``
    hold its state at ``t_end``, ``SC[8]``, ``GS[1]``, ``GS[5]`` its rates, guards and
    their rates there; ``WF[acc]`` its share of the whole step's energy increments.

    Returns ``(status, t)``.
    """
    n, nc = I[H_N], I[H_NC]
    fired = wvec(WI, nc, WC_FIRED)  # noqa: F821
    y1, ymid, ysub, knext = SC[5], SC[6], SC[7], SC[8]
    G0, G1, Gs = GS[0], GS[1], GS[3]
    D0, D1 = GS[4], GS[5]
    n_law = 2 * n + I[H_NLAW]
    acc = vec(WF, I, F_ACC, 3)  # noqa: F821
    g0_valid = reuse
    first = True
    end_valid = True
    while t < t_end:
        dt = t_end - t
        if not g0_valid:
            evaluate(t, y, cm, I, R, WI, WF, SC[0], G0, D0, EV_ALL | EV_STICK | runtime(0))  # noqa: F821
            counters[C_RHS] += 1
        if not (first and reuse):
            spent = rk_step(t, y, dt, cm, I, R, WI, WF, SC, y1, True)  # noqa: F821
            evaluate(t_end, y1, cm, I, R, WI, WF, knext, G1, D1, EV_ALL | runtime(0))  # noqa: F821
            counters[C_RHS] += spent + 1
        if first and y.shape[0] > n_law:
            for k in range(3):
                acc[k] = y1[n_law + k] - y[n_law + k]
        first = False
        code = first_crossing(cm, I, WI, G0, G1)  # noqa: F821
        mark_suspects(t, cm, I, WI, WF, G0, G1, SUSPECT_WINDOW * tol_t)  # noqa: F821
        if code >= 0 and stick_rates_known(I, WI):  # noqa: F821
            # the stick guards' rates at both ends (kept without them on a step with no event)
            guard_rates(y1, knext, cm, I, R, WI, WF, D1, runtime(True))  # noqa: F821
            evaluate(t, y, cm, I, R, WI, WF, SC[0], G0, D0, EV_GUARD_RATES | EV_STICK | runtime(0))  # noqa: F821
            counters[C_RHS] += 1
        sub = dt   # the sub-step whose end lies past the event
        if code < 0 and detect_grazing:
            xg = grazing_candidate(cm, I, WI, G0, G1, D0, D1, dt, tol_t / dt)  # noqa: F821
            if xg > 0.0:
                Gm, Dm = GS[2], GS[6]
                code = locate_trial(t, y, dt, xg, cm, I, R, WI, WF, SC, ymid, G0, Gm, Dm, counters)  # noqa: F821
                if code >= 0:   # it did cross: the event's bracket ends at the extremum
                    sub = xg * dt
                    copy_rows(WI, nc, n, y1, ymid)  # noqa: F821
                    copy_guards(I, WI, G1, Gm, D1, Dm)  # noqa: F821
                    counters[C_GRAZING] += 1
        if code < 0:
            clear_suspects(I, WI)  # noqa: F821
            copy_rows(WI, nc, n, y, y1)  # noqa: F821
            copy_rows(WI, nc, n, SC[0], knext)  # noqa: F821
            copy_guards(I, WI, G0, G1, D0, D1)  # noqa: F821
            g0_valid = True
            end_valid = True
            t = t_end
            break
        hi = locate_event(t, y, sub, cm, I, R, WI, WF, SC, GS, tol_t / sub, predicted, counters)  # noqa: F821
        t_ev = t_end if hi == 1.0 and sub == dt else t + hi * sub
        suspects_at(t_ev, I, WI, WF)  # noqa: F821
        code = first_crossing(cm, I, WI, G0, G1)  # noqa: F821
        t_sub = t
        copy_rows(WI, nc, n, ysub, y)  # noqa: F821
        t = t_ev
        copy_rows(WI, nc, n, y, y1)  # noqa: F821
        is_near = False
        while code >= 0:
            j = code // GMAX  # noqa: F821
            gi = code - j * GMAX  # noqa: F821
            unmark_near(j, I, WI)  # noqa: F821
            old = cm[j]
            cm[j] = apply_transition(t, y, cm, j, gi, I, R, WI, WF, Gs)  # noqa: F821
            WF[I[F_TLAST] + j] = t
            log_event(t, j, gi, old, cm[j], log_t, log_c, log_g, log_from, log_to, counters, recording,  # noqa: F821
                      fired)
            WI[W_NEV] += 1
            if WI[W_NEV] > max_events:
                return STATUS_EVENT_STORM, t
            factor_stick(cm, I, R, WI, WF)  # noqa: F821
            eval_guards(t_sub, ysub, cm, I, R, WI, WF, Gs)  # noqa: F821
            eval_guards(t, y, cm, I, R, WI, WF, G1)  # noqa: F821
            if is_near:
                mark_near(j, cm, I, WI, WF, G1)  # noqa: F821
            else:
                mark_drifted(j, old, cm, I, WI, WF, G1)  # noqa: F821
            code = first_crossing(cm, I, WI, Gs, G1)  # noqa: F821
            is_near = False
            if code < 0:
                code = first_near_crossing(cm, I, WI, Gs, G1, t - t_sub, tol_t)  # noqa: F821
                is_near = code >= 0
        settle_suspects(cm, I, WI, WF, G1)  # noqa: F821
        if not settle_event(t, y, cm, I, R, WI, WF, Gs, counters, max_pivots, log_t, log_c, log_g,  # noqa: F821
                            log_from, log_to, recording):
            return STATUS_FRICTION_UNRESOLVED, t
        g0_valid = False
        end_valid = False
    if not end_valid:
        # the last event fell on the step's end: the state, its rate and the guards there, after it
        copy_rows(WI, nc, n, y1, y)  # noqa: F821
        evaluate(t, y, cm, I, R, WI, WF, knext, G1, D1, EV_ALL | runtime(0))  # noqa: F821
        counters[C_RHS] += 1
    return STATUS_OK, t


def whole_step(t, t_end, y, cm, I, R, WI, WF, SC, GS, g0_valid, width, detect_grazing, counters):
    """The whole model's step from ``(t, y)`` to ``t_end`` into ``SC[5]``, its rate into ``SC[8]``, the guards and
    their rates at both ends; returns the number of seeds (``mark_seeds``).

    ``SC[0]`` holds ``dy/dt`` at ``(t, y)`` and ``GS[0]``, ``GS[4]`` the guards and rates
    there if ``g0_valid`` (the end of the last step), else they are evaluated first.
    (A function of its own: inside ``integrate`` the compiler inlined less of it,
    and a step cost a third more.)
    """
    y1, knext = SC[5], SC[8]
    G0, G1, D0, D1 = GS[0], GS[1], GS[4], GS[5]
    if not g0_valid:
        evaluate(t, y, cm, I, R, WI, WF, SC[0], G0, D0, EV_ALL | EV_STICK | runtime(0))  # noqa: F821
        counters[C_RHS] += 1
    spent = rk_step(t, y, t_end - t, cm, I, R, WI, WF, SC, y1, True)  # noqa: F821
    evaluate(t_end, y1, cm, I, R, WI, WF, knext, G1, D1, EV_ALL | runtime(0))  # noqa: F821
    counters[C_RHS] += spent + 1
    return mark_seeds(cm, I, WI, G0, G1, D0, D1, t_end - t, width, detect_grazing)  # noqa: F821


def step_clusters(t0, t_end, y, cm, I, R, WI, WF, SC, GS, tol_t, max_events, max_pivots, detect_grazing, predicted,
                  local, log_t, log_c, log_g, log_from, log_to, counters, recording):
    """Step the clusters of the step's seeds through their events; the rest keeps the whole step.

    Without ``local`` the whole model is the one cluster (every event splits every
    coordinate's step: for comparison).

    On entry ``y`` is the state at ``t0`` and ``SC[5]``, ``SC[8]``, ``GS[1]``, ``GS[5]``
    hold the whole model's step to ``t_end``; on return (``STATUS_OK``) they hold the
    state, its rate, the guards and their rates at ``t_end`` with every event taken.
    The energy accumulators get each cluster's own increments in place of its share
    of the whole step's. The log entries of the step are ordered by time.

    Returns ``(status, t)``.
    """
    n_state = y.shape[0]
    n, nc = I[H_N], I[H_NC]
    y1, knext, Y0 = SC[5], SC[8], SC[SC_Y0]
    G0, G1, D0, D1 = GS[0], GS[1], GS[4], GS[5]
    seed, cmstep, cm0 = wvec(WI, nc, WC_SEED), wvec(WI, nc, WC_CMSTEP), wvec(WI, nc, WC_CM0)  # noqa: F821
    n_law = 2 * n + I[H_NLAW]
    energy = n_state > n_law
    acc = vec(WF, I, F_ACC, 3)  # noqa: F821
    for i in range(n_state):
        Y0[i] = y[i]
    for j in range(nc):
        cmstep[j] = cm[j]
    copy_all_guards(GS[9], G0, GS[10], D0)
    events0, logged0 = counters[C_EVENTS], counters[C_LOGGED]
    a0 = a1 = a2 = 0.0
    if energy:
        a0, a1, a2 = y1[n_law], y1[n_law + 1], y1[n_law + 2]
    reuse = not energy   # a cluster's share of the energy rates must come from its own evaluations
    while True:
        WI[W_NB] = 0
        WI[W_NEV] = 0
        first_stamp = WI[W_STAMP] + 1
        d0 = d1 = d2 = 0.0
        js = runtime(-1)  # noqa: F821
        while True:
            js = next_cluster(js, local, cm, I, WI, n_state, first_stamp)  # noqa: F821
            if js < 0:
                break
            counters[C_CLUSTERS] += 1
            status, te = process_cluster(t0, t_end, y, cm, I, R, WI, WF, SC, GS, reuse, tol_t, max_events,
                                         max_pivots, detect_grazing, predicted, log_t, log_c, log_g, log_from,
                                         log_to, counters, recording)
            if status != STATUS_OK:
                set_full(WI)  # noqa: F821
                return status, te
            if energy:
                d0 += y[n_law] - Y0[n_law] - acc[0]
                d1 += y[n_law + 1] - Y0[n_law + 1] - acc[1]
                d2 += y[n_law + 2] - Y0[n_law + 2] - acc[2]
                for k in range(3):
                    y[n_law + k] = Y0[n_law + k]   # the next cluster starts from the step's start
            copy_rows(WI, nc, n, y1, y)  # noqa: F821
        set_full(WI)  # noqa: F821
        dt = t_end - t0
        jb = boundary_crossing(y1, knext, cm, I, R, WI, G0, G1, D0, D1, dt, tol_t / dt, detect_grazing)  # noqa: F821
        if jb < 0:
            break
        # a boundary contact crossed after all: again from the step's start, with it a seed too
        for i in range(n_state):
            y[i] = Y0[i]
        for j in range(nc):
            cm[j] = cmstep[j]
            cm0[j] = cmstep[j]
        copy_all_guards(G0, GS[9], D0, GS[10])
        counters[C_EVENTS] = events0
        counters[C_LOGGED] = logged0
        factor_stick(cm, I, R, WI, WF)  # noqa: F821
        seed[jb] = 1
        reuse = False
        counters[C_RESTARTS] += 1
    if energy:
        y1[n_law] = a0 + d0
        y1[n_law + 1] = a1 + d1
        y1[n_law + 2] = a2 + d2
    sort_log(logged0, counters[C_LOGGED], log_t, log_c, log_g, log_from, log_to)  # noqa: F821
    for j in range(nc):
        seed[j] = 0
    return STATUS_OK, t_end


def copy_all_guards(G, Gm, D, Dm):
    """``G, D = Gm, Dm`` for every contact."""
    for j in range(G.shape[0]):
        for gi in range(G.shape[1]):
            G[j, gi] = Gm[j, gi]
            D[j, gi] = Dm[j, gi]


def record(irec, t, y, cm, I, R, WI, WF, G, rec_t, rec_y, rec_cm, rec_N, rec_f):
    """Write record ``irec`` (state, contact modes and, if kept, contact forces; ``G``: guard scratch, not
    touched)."""
    n, nc = y.shape[0], I[H_NC]
    rec_t[irec] = t
    for i in range(n):
        rec_y[irec, i] = y[i]
    keep = rec_N.shape[0] > 0
    if keep:
        evaluate(t, y, cm, I, R, WI, WF, y, G, G, runtime(0))  # noqa: F821 (the forces only)
    for j in range(nc):
        rec_cm[irec, j] = cm[j]
        if keep:
            rec_N[irec, j] = WF[I[F_N] + j]
            rec_f[irec, j] = WF[I[F_FR] + j]


def integrate(y, cm, I, R, WI, WF, SC, GS, period, steps_per_period, start_period, end_period, n_transient,
              record_every, event_tol, max_events, max_pivots, detect_grazing, predicted, local, rec_t, rec_y, rec_cm,
              rec_N, rec_f, poincare, log_t, log_c, log_g, log_from, log_to, counters, stats):
    """Integrate excitation periods ``start_period`` to ``end_period`` (exclusive).

    The same schedule as the product-mode kernel (:func:`blademodel.numeric.loop.integrate`):
    ``h = period / steps_per_period``; after each step every contact's guards are
    compared with the step start, and the clusters of the contacts that crossed are
    stepped through their events (``step_clusters``). ``y`` and ``cm`` are updated in
    place.

    Returns ``(status, t)``.
    """
    n = y.shape[0]
    nc = I[H_NC]
    set_full(WI)  # noqa: F821
    fired, cm0, seed = wvec(WI, nc, WC_FIRED), wvec(WI, nc, WC_CM0), wvec(WI, nc, WC_SEED)  # noqa: F821
    h = period / steps_per_period
    y1, knext = SC[5], SC[8]
    G0, G1 = GS[0], GS[1]
    D0, D1 = GS[4], GS[5]
    energy = n > 2 * I[H_N] + I[H_NLAW]
    t = period * start_period
    irec = counters[C_RECORDS]
    g0_valid = runtime(False)  # noqa: F821 (a literal would compile whole_step twice)
    factor_stick(cm, I, R, WI, WF)  # noqa: F821
    for j in range(nc):
        cm0[j] = cm[j]
        fired[j] = 0
        seed[j] = 0
    for per in range(start_period, end_period):
        recording = per >= n_transient
        if recording and per == n_transient and irec < rec_t.shape[0]:
            record(irec, t, y, cm, I, R, WI, WF, GS[2], rec_t, rec_y, rec_cm, rec_N, rec_f)
            irec += 1
        for js in range(steps_per_period):
            t_end = period * per + (js + 1) * h
            tol_t = event_tol * h
            dt = t_end - t
            seeds = whole_step(t, t_end, y, cm, I, R, WI, WF, SC, GS, g0_valid, tol_t / dt, detect_grazing, counters)
            g0_valid = True
            if seeds > 0:
                status, te = step_clusters(t, t_end, y, cm, I, R, WI, WF, SC, GS, tol_t, max_events, max_pivots,
                                           detect_grazing, predicted, local, log_t, log_c, log_g, log_from, log_to,
                                           counters, recording)
                if status != STATUS_OK:
                    counters[C_RECORDS] = irec
                    return status, te
                g0_valid = not energy   # dy/dt of the energy accumulators at the end: re-evaluated
            for i in range(n):
                y[i] = y1[i]
                SC[0, i] = knext[i]
            copy_all_guards(G0, G1, D0, D1)
            t = t_end
            if WI[W_NS] > 0:
                stats[S_MAX_CONE_RATIO] = max(stats[S_MAX_CONE_RATIO], cone_ratio(y, I, R, WI, WF))  # noqa: F821
            counters[C_STEPS] += 1
            for i in range(n):
                if not math.isfinite(y[i]):
                    counters[C_RECORDS] = irec
                    return STATUS_NONFINITE, t
            if recording and (js + 1) % record_every == 0 and irec < rec_t.shape[0]:
                record(irec, t, y, cm, I, R, WI, WF, GS[2], rec_t, rec_y, rec_cm, rec_N, rec_f)
                irec += 1
        if recording:
            for i in range(n):
                poincare[per - n_transient, i] = y[i]
    counters[C_RECORDS] = irec
    return STATUS_OK, t
