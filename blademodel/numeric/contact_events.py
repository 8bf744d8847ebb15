"""The per-contact kernel's events: transitions, the friction complementarity problem, the event log.

A *template* (see :mod:`.contact_loop`). Everything here acts on the active set:
an event of one cluster changes the modes, states and stick factor of that
cluster only.
"""

import math  # noqa: F401

from blademodel.numeric.contract import (WC_ALL, NONNEG, C_EVENTS, C_FRICTION_PIVOTS, C_LOGGED, F_F, F_FR, F_N, F_ND,
                                         F_TLAST, F_V, F_YEV, F_Z, H_N, H_NC, MAX_LAW_STATES, O_CIDX, O_CLAW, R_GR,
                                         R_INVM, R_W, WC_AC, WC_BEFORE, WC_CM0, WC_FIRED, WC_U)

#: Relative tolerance on the sign of a slipping contact's acceleration in the friction problem.
SLIP_SIGN_TOL = 1e-9

#: A slipping contact's relative acceleration within this fraction of the size of its terms has no sign (the
#: friction problem; ``resolve_friction``): where the rest of a ring sticks, it is zero but for rounding.
ACC_ROUNDING = 1e-12


def apply_transition(t, y, cm, j, gi, I, R, WI, WF, G):
    """Fire guard ``gi`` of contact ``j`` at ``(t, y)``; returns the new mode (``G``: guard scratch, not touched)."""
    evaluate(t, y, cm, I, R, WI, WF, y, G, G, runtime(0))  # noqa: F821 (the forces only)
    K = I[I[O_CLAW] + j]
    return law_transition(K, cm[j], gi, WF[I[F_N] + j], WF[I[F_ND] + j], WF[I[F_V] + j],  # noqa: F821
                          WF[I[F_FR] + j], y, law_offset(I, j), R, I, j,  # noqa: F821
                          vec(WF, I, F_Z, MAX_LAW_STATES))  # noqa: F821


def transition_at(t, y, cm, j, gi, I, R, WI, WF, G):
    """``apply_transition`` for Python (an entry point: the tangent of the period map differentiates resets)."""
    return apply_transition(t, y, cm, j, gi, I, R, WI, WF, G)


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
    full, nca = active_contacts(WI, nc)  # noqa: F821
    ac = wvec(WI, nc, WC_ALL if full else WC_AC)  # noqa: F821
    claw, cidx = vec(I, I, O_CLAW, nc), vec(I, I, O_CIDX, 4 * nc)  # noqa: F821
    invm, cgr, W = vec(R, I, R_INVM, n), vec(R, I, R_GR, 4 * nc), vec(R, I, R_W, nc * nc)  # noqa: F821
    U, cm0 = wvec(WI, nc, WC_U), wvec(WI, nc, WC_CM0)  # noqa: F821
    yev = vec(WF, I, F_YEV, y.shape[0])  # noqa: F821
    F, cf = vec(WF, I, F_F, n), vec(WF, I, F_FR, nc)  # noqa: F821
    copy_rows(WI, nc, n, yev, y)  # noqa: F821
    for it in range(max_pivots):
        copy_rows(WI, nc, n, y, yev)  # noqa: F821
        factor_stick(cm, I, R, WI, WF)  # noqa: F821
        newly = False
        for jj in range(nca):
            j = ac[jj] & NONNEG
            K = claw[j]
            if IS_STICK[K, cm[j]] and not IS_STICK[K, cm0[j]]:  # noqa: F821
                newly = True
        if newly:
            project_onto_stick(y, I, R, WI, WF)  # noqa: F821
        contact_forces(t, y, cm, I, R, WI, WF)  # noqa: F821
        flip = -1
        for jj in range(nca):
            j = ac[jj] & NONNEG
            if not U[j]:
                continue
            K = claw[j]
            m = cm[j]
            b = slip_bound(j, y, I, R, WF)  # noqa: F821
            if m == RIGID[K, 0]:  # noqa: F821
                if b - abs(cf[j]) < 0.0:
                    flip = j
                    cm[j] = RIGID[K, 1] if cf[j] > 0.0 else RIGID[K, 2]  # noqa: F821
                    break
            else:
                s = 1.0 if m == RIGID[K, 1] else -1.0  # noqa: F821
                a = 0.0
                size = 0.0   # of the terms of a: their rounding is no sign
                for k in range(4):
                    i = cidx[4 * j + k]
                    if i >= 0:
                        term = cgr[4 * j + k] * invm[i] * F[i]
                        a += term
                        size += abs(term)
                tol = max(SLIP_SIGN_TOL * W[j * nc + j] * b, ACC_ROUNDING * size)
                if b > 0.0 and s * a < -tol:   # unloaded (b = 0): no force either way
                    flip = j
                    cm[j] = RIGID[K, 0]  # noqa: F821
                    break
        if flip < 0:
            return True
        counters[C_FRICTION_PIVOTS] += 1
    return False


def rigid_problem(cm, I, WI):
    """Mark in ``U`` the active closed rigid contacts whose mode an event leaves open; True if any.

    Those are the contacts sticking before the event (``cm0``) or sent to stick by
    it: a slipping contact whose velocity has not reached zero keeps its slip.
    """
    nc = I[H_NC]
    full, nca = active_contacts(WI, nc)  # noqa: F821
    ac = wvec(WI, nc, WC_ALL if full else WC_AC)  # noqa: F821
    claw, U, cm0 = vec(I, I, O_CLAW, nc), wvec(WI, nc, WC_U), wvec(WI, nc, WC_CM0)  # noqa: F821
    anyu = False
    for jj in range(nca):
        j = ac[jj] & NONNEG
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


#: A guard of a contact the friction problem moved that lies within this fraction of the state's largest
#: velocity on its wrong side is there by rounding (``settle_event``): about 1e-17 m/s measured, against a
#: state's 1e-2 m/s.
RELEASE_ROUNDING = 1e-10


def projected_across(j, cm, y, I, R, WF):
    """Whether contact ``j``, slipping on through the friction problem in a rigid law's slip, had its velocity
    taken across zero, against its slip, by the problem's projection (from the state at the event ``yev``)."""
    K = I[I[O_CLAW] + j]
    m = cm[j]
    if RIGID[K, 0] < 0 or (m != RIGID[K, 1] and m != RIGID[K, 2]):  # noqa: F821
        return False
    n, nc = I[H_N], I[H_NC]
    cidx, cgr, yev = vec(I, I, O_CIDX, 4 * nc), vec(R, I, R_GR, 4 * nc), vec(WF, I, F_YEV, y.shape[0])  # noqa: F821
    s = 1.0 if m == RIGID[K, 1] else -1.0  # noqa: F821
    return s * slot_sum(j, cidx, cgr, yev, n) >= 0.0 and s * slot_sum(j, cidx, cgr, y, n) < 0.0  # noqa: F821


def settle_event(t, y, cm, I, R, WI, WF, G, counters, max_pivots, log_t, log_c, log_g, log_from, log_to,
                 recording):
    """After guard transitions: the friction problem of the active rigid contacts, logged; False if unresolved.

    A contact the problem moves to a new mode (a stuck one released into a slip, whether
    it had been stuck or its own guard had just sent it to stick) enters it with its new
    guards where the motion puts them: a slip velocity of zero, to a rounding error. So
    does a rigid contact that slips on through the problem when the problem's projection
    (onto the constraints of the contacts that newly stick) takes its velocity across zero
    (``projected_across``): in a tuned ring at engine order ``N / 2`` the ring's closure
    holds every other contact's slip at a velocity of zero while the rest stick, and the
    projection moves it by a rounding error. One left a rounding error on its wrong side
    would never change sign, and the contact would slip on against its friction's
    direction (measured on a tuned Coulomb ring: ``-7e-3`` m/s in ``slip+`` six steps on,
    the period map jumping there; on tuned preloaded rings of 6 and 8 blades at engine
    order ``N / 2``, before this applied to a contact whose own guard had fired or to one
    slipping on, up to ``1.4e-4`` m/s, ``6.5e-3`` of the largest velocity), so such a
    contact is marked as one fired early (``mark_near``): its guards read from the
    boundary. Only a rounding error, ``RELEASE_ROUNDING`` of the largest velocity of the
    state: a contact whose velocity a perturbation moved (the difference quotients of a
    period map do) keeps its guards as they are, and the map stays differentiable as the
    tangent has it. Not every slip of the problem's set: marks are a run's state, and a
    ring's reduced map (runs over ``T / 4`` that start without them) then followed a
    branch-point branch ``3e-2`` rad/s apart from the whole map. ``G`` is guard scratch.
    """
    nc = I[H_NC]
    full, nca = active_contacts(WI, nc)  # noqa: F821
    ac = wvec(WI, nc, WC_ALL if full else WC_AC)  # noqa: F821
    cm0, before, fired = wvec(WI, nc, WC_CM0), wvec(WI, nc, WC_BEFORE), wvec(WI, nc, WC_FIRED)  # noqa: F821
    ok = True
    moved = False   # a contact the friction problem moved, or a slip its projection took across zero (``before`` -1)
    if rigid_problem(cm, I, WI):
        for jj in range(nca):
            j = ac[jj] & NONNEG
            before[j] = cm[j]
        ok = resolve_friction(t, y, cm, I, R, WI, WF, counters, max_pivots)
        for jj in range(nca):
            j = ac[jj] & NONNEG
            if cm[j] == before[j]:
                continue
            unmark_near(j, I, WI)  # noqa: F821
            WF[I[F_TLAST] + j] = t
            if fired[j] != 0:
                # the guard of this very contact fired in this event: one event, to the settled mode
                k = fired[j] - 1
                if k >= 0 and k < log_to.shape[0]:
                    log_to[k] = cm[j]
            else:
                log_event(t, j, runtime(-1), before[j], cm[j], log_t, log_c, log_g, log_from, log_to,  # noqa: F821
                          counters, recording, fired)
            before[j] = -1
            moved = True
        for jj in range(nca):
            j = ac[jj] & NONNEG
            if before[j] != -1 and projected_across(j, cm, y, I, R, WF):
                before[j] = -1
                moved = True
    factor_stick(cm, I, R, WI, WF)  # noqa: F821
    if moved:
        eval_guards(t, y, cm, I, R, WI, WF, G)  # noqa: F821
        claw = vec(I, I, O_CLAW, nc)  # noqa: F821
        n = I[H_N]
        speed = 0.0
        for i in range(n, 2 * n):
            speed = max(speed, abs(y[i]))
        for jj in range(nca):
            j = ac[jj] & NONNEG
            if before[j] != -1:
                continue
            for gi in range(NG[claw[j], cm[j]]):  # noqa: F821
                g = G[j, gi]
                if wrong_side(g, GDIR[claw[j], cm[j], gi]) and abs(g) <= RELEASE_ROUNDING * speed:  # noqa: F821
                    mark_near(j, cm, I, WI, WF, G)  # noqa: F821
                    break
    for jj in range(nca):
        j = ac[jj] & NONNEG
        cm0[j] = cm[j]
        fired[j] = 0
    return ok


def initial_modes(t, y, cm, I, R, WI, WF, G, counters, max_pivots, e, ei):
    """Close every contact whose normal guard is ``>= 0`` (penetration ``>= 0`` for a contact spring)
    through its law's entry rule; resolve friction (the whole model).

    ``G`` is guard scratch ``(nc, GMAX)``; ``e`` and ``ei`` are empty float and int
    arrays (no event log).
    """
    set_full(WI)  # noqa: F821
    nc = I[H_NC]
    claw, cm0 = vec(I, I, O_CLAW, nc), wvec(WI, nc, WC_CM0)  # noqa: F821
    for j in range(nc):
        cm[j] = 0
        cm0[j] = 0
    factor_stick(cm, I, R, WI, WF)  # noqa: F821
    eval_guards(t, y, cm, I, R, WI, WF, G)  # noqa: F821
    for j in range(nc):
        if G[j, 0] >= 0.0 and NG[claw[j], 0] > 0:  # noqa: F821
            cm[j] = apply_transition(t, y, cm, j, runtime(0), I, R, WI, WF, G)  # noqa: F821
            factor_stick(cm, I, R, WI, WF)  # noqa: F821
    return settle_event(t, y, cm, I, R, WI, WF, G, counters, max_pivots, e, ei, ei, ei, ei,  # noqa: F821
                        runtime(False))


def settle_start(t, y, cm, I, R, WI, WF, G, counters, max_pivots, log_t, log_c, log_g, log_from, log_to):
    """Fire, at ``(t, y)``, the guards of ``cm`` that already lie on the side their mode forbids; then the
    friction problem of the rigid contacts (the whole model). Logged; returns the log entries written, or -1
    where the friction problem was not resolved.

    The loop fires a guard when it *crosses* zero within a step. A start state already
    past one (a section state on the far side of a switching boundary of ``cm``: a
    Newton iterate, where the orbit's switching time passes the section) would
    otherwise keep ``cm``'s flow, a contact closed in tension or stuck beyond its
    friction limit, and the period map would jump there. Fired at once, the map is
    continuous across the boundary. Each contact fires once, as in an event; what its
    new mode leaves unsettled is the friction problem's (``settle_event``).
    """
    set_full(WI)  # noqa: F821
    nc = I[H_NC]
    claw, cm0, fired = vec(I, I, O_CLAW, nc), wvec(WI, nc, WC_CM0), wvec(WI, nc, WC_FIRED)  # noqa: F821
    for j in range(nc):
        cm0[j] = cm[j]
        fired[j] = 0
    start = counters[C_LOGGED]
    factor_stick(cm, I, R, WI, WF)  # noqa: F821
    any_fired = False
    for _ in range(nc + 1):
        eval_guards(t, y, cm, I, R, WI, WF, G)  # noqa: F821
        code = -1
        for j in range(nc):
            if fired[j] != 0 or code >= 0:
                continue
            K = claw[j]
            for gi in range(NG[K, cm[j]]):  # noqa: F821
                if wrong_side(G[j, gi], GDIR[K, cm[j], gi]):  # noqa: F821
                    code = j * GMAX + gi  # noqa: F821
                    break
        if code < 0:
            break
        j = code // GMAX  # noqa: F821
        gi = code - j * GMAX  # noqa: F821
        old = cm[j]
        cm[j] = apply_transition(t, y, cm, j, gi, I, R, WI, WF, G)
        WF[I[F_TLAST] + j] = t
        log_event(t, j, gi, old, cm[j], log_t, log_c, log_g, log_from, log_to, counters, True, fired)
        factor_stick(cm, I, R, WI, WF)  # noqa: F821
        any_fired = True
    if not any_fired:
        return 0
    if not settle_event(t, y, cm, I, R, WI, WF, G, counters, max_pivots, log_t, log_c, log_g, log_from, log_to,
                        True):
        return -1
    return counters[C_LOGGED] - start
