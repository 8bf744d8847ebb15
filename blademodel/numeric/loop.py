"""The generic hybrid RK4 loop with event location by bisection.

This file is a *template*: its functions call ``rhs``, ``guards`` and
``transition`` and read the tables ``N_GUARDS``, ``GUARD_DIR`` and
``CLOSE_GUARD``, which the code generator (:mod:`.codegen`) writes for each model
into the same generated module. It knows nothing of friction laws or contacts:
only modes, guards with a crossing direction, and transitions.

Status codes returned by :func:`integrate`: ``0`` done, ``1`` non-finite state,
``2`` event storm (more than ``max_events`` events in one step).
"""

import math  # noqa: F401  (used by the generated code appended to this template)

import numpy as np

STATUS_OK = 0
STATUS_NONFINITE = 1
STATUS_EVENT_STORM = 2

C_STEPS, C_EVENTS, C_LOCATION_SUBSTEPS, C_RHS, C_LOGGED, C_RECORDS = 0, 1, 2, 3, 4, 5
#: Cap on the trial sub-steps of one event's location.
MAX_LOCATE_TRIALS = 160


def rk4_step(mode, t, y, h, p, k1, k2, k3, k4, tmp, out):
    """One classical RK4 step of size ``h`` from ``(t, y)`` in ``mode`` into ``out``.

    The reference definition: each generated module replaces it by a fused version
    with the same arithmetic (:func:`blademodel.numeric.codegen.fused_rk4_source`).
    """
    n = y.shape[0]
    rhs(mode, t, y, p, k1)  # noqa: F821
    for i in range(n):
        tmp[i] = y[i] + 0.5 * h * k1[i]
    rhs(mode, t + 0.5 * h, tmp, p, k2)  # noqa: F821
    for i in range(n):
        tmp[i] = y[i] + 0.5 * h * k2[i]
    rhs(mode, t + 0.5 * h, tmp, p, k3)  # noqa: F821
    for i in range(n):
        tmp[i] = y[i] + h * k3[i]
    rhs(mode, t + h, tmp, p, k4)  # noqa: F821
    for i in range(n):
        out[i] = y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])


def rk_step(mode, t, y, h, p, k1, k2, k3, k4, tmp, out, tab, K):
    """One step of the method: classical RK4 (fused) if ``tab`` is empty, else the tableau ``tab``.

    ``tab`` holds ``A`` (``s x s``, row by row), ``b`` and ``c``; ``K`` has a row per
    stage. Returns the right-hand-side evaluations spent.
    """
    if tab.shape[0] == 0:
        rk4_step(mode, t, y, h, p, k1, k2, k3, k4, tmp, out)
        return 4
    s = K.shape[0]
    for st in range(s):
        stage_sum(y, h, tab, st * s, st, K, tmp)                 # y + h sum_q a[st, q] k_q
        rhs(mode, t + tab[s * s + s + st] * h, tmp, p, K[st])  # noqa: F821
    stage_sum(y, h, tab, s * s, s, K, out)                       # y + h sum_q b_q k_q
    return s


def stage_sum(y, h, tab, o, count, K, out):
    """``out = y + h sum_{q < count} tab[o + q] K[q]`` (zero coefficients skipped)."""
    n = y.shape[0]
    for i in range(n):
        out[i] = y[i]
    for q in range(count):
        a = h * tab[o + q]
        if a != 0.0:
            for i in range(n):
                out[i] += a * K[q, i]


def crossed(g0, g1, direction):
    """Whether a guard went from ``g0`` to ``g1`` through zero in ``direction``.

    A falling guard fires from ``>= 0`` to ``< 0``, a rising one from ``<= 0`` to
    ``> 0``: the state after the event lies strictly beyond the root, so the guard
    cannot fire again at once.
    """
    if direction < 0:
        return g0 >= 0.0 and g1 < 0.0
    if direction > 0:
        return g0 <= 0.0 and g1 > 0.0
    return (g0 > 0.0 and g1 <= 0.0) or (g0 < 0.0 and g1 >= 0.0)


def first_crossing(mode, g0, g1):
    """Index of the first guard of ``mode`` that crossed, or -1."""
    for i in range(N_GUARDS[mode]):  # noqa: F821
        if crossed(g0[i], g1[i], GUARD_DIR[mode, i]):  # noqa: F821
            return i
    return -1


def earliest_predicted(mode, glo, g1, dlo, d1, lo, hi, dt):
    """The crossed guard of ``mode`` whose root in ``(lo, hi)`` is predicted first, and that root.

    The root of the cubic Hermite interpolant where the guard's rates ``dlo, d1`` are
    known, else of the chord (:func:`predicted_root`).
    """
    best = -1
    xbest = hi
    for i in range(N_GUARDS[mode]):  # noqa: F821
        if crossed(glo[i], g1[i], GUARD_DIR[mode, i]):  # noqa: F821
            x = predicted_root(glo[i], g1[i], dlo[i], d1[i], lo, hi, dt)  # noqa: F821
            if best < 0 or x < xbest:
                best = i
                xbest = x
    return best, xbest


def copy_guards(g, d, gm, dm):
    """``g, d = gm, dm`` (guards and their rates)."""
    for i in range(g.shape[0]):
        g[i] = gm[i]
        d[i] = dm[i]


def drift_offsets(mode, g, goff):
    """``goff``: the offsets of the friction guards of elastic laws (``DRIFT_GUARD``) of ``mode``, whose values ``g``
    a transition into it has just left a rounding error on their wrong side (``wrong_side``, within ``DRIFTED`` of
    the largest of them), zero for the others. Returns whether any offset is not zero (else the guards need none
    subtracted).

    A reset that puts a state on a guard's boundary puts it there to rounding: an Iwan element that sticks takes the
    stretch of its slip force exactly, and its stick guard ``mu N phi - kd z`` (shared with the other sticking
    elements, the least of theirs) reads an ulp either side of zero. A crossing is a change of sign, so from below
    zero the guard never fired however far it fell: another element of the same contact reaching its slip force
    later in the step was missed, and it stuck on past it (the guard at ``-9e-3`` of the largest, the Iwan pair at
    166.48 rad/s) until another event's reset let it slip, a step later. Where rounding put the guard above zero it
    fired in time: the period map jumped between neighbouring values of a parameter. Read minus its offset until
    the next transition, such a guard starts on the boundary, fires as soon as it falls further and stays quiet
    while it returns (as the per-contact kernel's ``mark_drifted`` reads its friction guards). A rigid stick's guards
    and the normal guards keep their values, as there: a rigid slip that ends at the friction limit while the
    contact unloads is settled by its transition, and a damped contact opens with its penetration still positive
    and closes where it crosses zero.
    """
    scale = 0.0
    for i in range(N_GUARDS[mode]):  # noqa: F821
        if DRIFT_GUARD[mode, i]:  # noqa: F821
            scale = max(scale, abs(g[i]))
    drifting = False
    for i in range(goff.shape[0]):
        goff[i] = 0.0
    for i in range(N_GUARDS[mode]):  # noqa: F821
        drifted = wrong_side(g[i], GUARD_DIR[mode, i]) and abs(g[i]) <= DRIFTED * scale  # noqa: F821
        if DRIFT_GUARD[mode, i] and drifted:  # noqa: F821
            goff[i] = g[i]
            drifting = True
    return drifting


def offset_guards(g, goff):
    """``g -= goff`` (guards read from their boundaries, :func:`drift_offsets`)."""
    for i in range(goff.shape[0]):
        g[i] -= goff[i]


def locate_event(mode, t, y, dt, h, p, event_tol, predicted, k1, k2, k3, k4, tmp, y1, ymid, g0, g1, gm, glo,
                 d0, d1, dm, dlo, tab, K, counters, goff, drifting):
    """Bracket the earliest crossing of the sub-step ``[t, t + dt]`` below ``event_tol * h``.

    ``y1`` and ``g1`` hold the state and guards at the sub-step's end on entry, and
    at the bracket's far end ``hi`` (returned, a fraction of ``dt``) on exit. Every
    trial is the true RK4 sub-step from ``(t, y)``; the bracket is kept by
    ``first_crossing`` over every guard. Without ``predicted``, bisection (34 trials
    at ``1e-10``). With it, the trials follow the crossed guard whose root is
    predicted first: the root of the cubic Hermite interpolant of its values and
    rates where the state gives its rates (the penetration: ``guard_rates``), else of
    the chord, aimed half a tolerance past it; then a Newton step on the guard's rate
    at the trial, or inverse quadratic interpolation through the last three trials of
    that guard and secants, inside the bracket, a bisection when two trials did not
    halve it, and a trial predicted within half a tolerance of the start or three
    quarters of one of the end set three quarters of a tolerance inside, so the last
    trial closes the bracket. Either way the location ends when the bracket cannot be
    split any further in floating point. ``d0, d1, dm, dlo`` are the rates' work arrays; ``goff`` the guards'
    offsets (:func:`drift_offsets`), subtracted where ``drifting``.
    """
    n = y.shape[0]
    ng = g0.shape[0]
    tol_t = event_tol * h
    width = tol_t / dt
    if predicted:
        guard_rates(mode, t, y, p, d0)  # noqa: F821
        guard_rates(mode, t + dt, y1, p, d1)  # noqa: F821
    else:
        for i in range(ng):
            d0[i] = math.nan
            d1[i] = math.nan
    copy_guards(glo, dlo, g0, d0)
    lo = 0.0
    hi = 1.0
    gi, x = earliest_predicted(mode, glo, g1, dlo, d1, lo, hi, dt)
    if gi < 0:
        gi = first_crossing(mode, g0, g1)
    xa, ga, xb, gb = lo, glo[gi], hi, g1[gi]
    xc, gc = math.nan, math.nan
    slope = math.nan
    k = 0
    k_pred = 0
    w_old = 1.0
    while (hi - lo) * dt > tol_t and k < MAX_LOCATE_TRIALS:
        if not predicted:
            x = 0.5 * (lo + hi)
        else:
            halve = False
            if k > k_pred:
                if math.isfinite(slope) and slope != 0.0:
                    x = xb - gb / slope
                    slope = math.nan
                else:
                    x = inverse_quadratic(xa, ga, xb, gb, xc, gc, lo, hi)  # noqa: F821
                if k % 2 == 0:
                    halve = hi - lo > 0.5 * w_old
                    w_old = hi - lo
            else:
                x += 0.5 * width   # the first trial on a target: aimed past its root (see contact_loop)
            x = safeguarded_trial(x, lo, hi, width, halve, 0.75)  # noqa: F821
        if not lo < x < hi:
            break   # the bracket is as narrow as the floating-point resolution allows
        k += 1
        if tab.shape[0] == 0:
            rk4_step(mode, t, y, x * dt, p, k1, k2, k3, k4, tmp, ymid)
            counters[C_RHS] += 4
        else:
            counters[C_RHS] += rk_step(mode, t, y, x * dt, p, k1, k2, k3, k4, tmp, ymid, tab, K)
        guards(mode, t + x * dt, ymid, p, gm)  # noqa: F821
        if drifting:
            offset_guards(gm, goff)
        if predicted:
            guard_rates(mode, t + x * dt, ymid, p, dm)  # noqa: F821
        else:
            for i in range(ng):
                dm[i] = math.nan
        counters[C_LOCATION_SUBSTEPS] += 1
        c = first_crossing(mode, g0, gm)
        if c >= 0:
            hi = x
            for i in range(n):
                y1[i] = ymid[i]
            copy_guards(g1, d1, gm, dm)
        else:
            lo = x
            copy_guards(glo, dlo, gm, dm)
        if c >= 0 and c != gi:
            gi, x = earliest_predicted(mode, glo, g1, dlo, d1, lo, hi, dt)   # an earlier crossing of another guard
            if gi < 0:
                gi = c
            xa, ga, xb, gb = lo, glo[gi], hi, g1[gi]
            xc, gc = math.nan, math.nan
            slope = math.nan
            k_pred = k
            continue
        if k == k_pred + 1 and math.isfinite(dm[gi]):
            slope = dm[gi] * dt   # the next trial: a Newton step on the guard's own rate
        xc, gc = xa, ga
        xa, ga = xb, gb
        xb, gb = x, gm[gi]
    return hi


def simultaneous_crossing(mode, contact, gs, ge):
    """First guard of ``mode`` owned by another contact than ``contact`` that crossed.

    ``gs`` and ``ge`` are the guards at the sub-step start and at an event just
    handled. A transition settles its own contact (its law's candidates and
    resets); a guard of another contact that lay before its root at the sub-step
    start and lies past it now crossed within the same bracket and must fire too,
    or it would stay dormant past its root.
    """
    for i in range(N_GUARDS[mode]):  # noqa: F821
        if GUARD_CONTACT[mode, i] != contact and crossed(gs[i], ge[i], GUARD_DIR[mode, i]):  # noqa: F821
            return i
    return -1


def initial_mode(t, y, p, g, ytmp):
    """Mode of the state ``y``: every contact with ``delta >= 0`` is closed.

    Contacts are closed one at a time through their own closing transitions, so
    the friction law's entry rules choose the closed mode.
    """
    mode = OPEN_MODE  # noqa: F821
    for j in range(CLOSE_GUARD.shape[1]):  # noqa: F821
        gi = CLOSE_GUARD[mode, j]  # noqa: F821
        if gi < 0:
            continue
        guards(mode, t, y, p, g)  # noqa: F821
        if g[gi] >= 0.0:
            mode = transition(mode, gi, t, y, p, ytmp)  # noqa: F821
    return mode


def integrate(y, mode, p, period, steps_per_period, start_period, end_period, n_transient,
              record_every, event_tol, max_events, predicted, tab, rec_t, rec_y, rec_mode, poincare, log_t,
              log_guard, log_from, log_to, counters, goff, carry):
    """Integrate excitation periods ``start_period`` to ``end_period`` (exclusive).

    Periods before ``n_transient`` are not recorded. A run may be split into calls
    over consecutive period ranges: the record and log positions live in
    ``counters`` and the guards' drift offsets (:func:`drift_offsets`) in ``goff``
    (in and out; read where ``carry``, the call going on from where the last one
    ended, else cleared), so the pieces fill the same arrays and read the same guards
    as one call would.

    The step is ``h = period / steps_per_period``, so ``t = n * period`` falls on
    step ends (the Poincare section). After each (sub)step every guard of the
    current mode is checked; on a crossing, the earliest event is bracketed
    (:func:`locate_event`: by bisection, or with ``predicted`` from predicted roots),
    re-integrating from the step start, until the bracket is below ``event_tol * h``;
    the state is taken at the bracket's far end (past the root), the transition is
    applied and the rest of the step follows.

    ``y`` is updated in place. Returns ``(status, mode, t, drifting)``: ``drifting``
    where ``goff`` ends with offsets set, which a call that goes on from ``(y, mode, t)``
    is to start with.
    """
    n = y.shape[0]
    h = period / steps_per_period
    k1 = np.empty(n)
    k2 = np.empty(n)
    k3 = np.empty(n)
    k4 = np.empty(n)
    tmp = np.empty(n)
    y1 = np.empty(n)
    ymid = np.empty(n)
    ytmp = np.empty(n)
    ysub = np.empty(n)
    ng = GUARD_DIR.shape[1] + 1  # noqa: F821
    g0 = np.empty(ng)
    g1 = np.empty(ng)
    gm = np.empty(ng)
    glo = np.empty(ng)
    d0 = np.empty(ng)
    d1 = np.empty(ng)
    dm = np.empty(ng)
    dlo = np.empty(ng)
    drifting = False   # guards read from their boundaries until the next transition (drift_offsets)
    for i in range(ng):
        if not carry:
            goff[i] = 0.0
        elif goff[i] != 0.0:
            drifting = True
    # stages of a tableau method (``tab``: A, b, c; empty for the fused RK4): s^2 + 2 s entries
    s_tab = int(round(math.sqrt(tab.shape[0] + 1.0))) - 1 if tab.shape[0] > 0 else 0
    K = np.empty((s_tab, n))
    max_log = log_t.shape[0]
    t = period * start_period
    irec = counters[C_RECORDS]
    g0_valid = False
    for per in range(start_period, end_period):
        recording = per >= n_transient
        if recording and per == n_transient and irec < rec_t.shape[0]:
            rec_t[irec] = t
            rec_mode[irec] = mode
            for i in range(n):
                rec_y[irec, i] = y[i]
            irec += 1
        for j in range(steps_per_period):
            t_end = period * per + (j + 1) * h
            n_events = 0
            while t < t_end:
                dt = t_end - t
                if tab.shape[0] == 0:   # the fused RK4 called directly: the hot path has no extra call
                    rk4_step(mode, t, y, dt, p, k1, k2, k3, k4, tmp, y1)
                    counters[C_RHS] += 4
                else:
                    counters[C_RHS] += rk_step(mode, t, y, dt, p, k1, k2, k3, k4, tmp, y1, tab, K)
                if not g0_valid:
                    guards(mode, t, y, p, g0)  # noqa: F821
                    if drifting:
                        offset_guards(g0, goff)
                guards(mode, t_end, y1, p, g1)  # noqa: F821
                if drifting:
                    offset_guards(g1, goff)
                gi = first_crossing(mode, g0, g1)
                if gi < 0:
                    for i in range(n):
                        y[i] = y1[i]
                    for i in range(ng):
                        g0[i] = g1[i]
                    g0_valid = True
                    t = t_end
                    break
                hi = locate_event(mode, t, y, dt, h, p, event_tol, predicted, k1, k2, k3, k4, tmp, y1, ymid,
                                  g0, g1, gm, glo, d0, d1, dm, dlo, tab, K, counters, goff, drifting)
                gi = first_crossing(mode, g0, g1)
                t_sub = t
                for i in range(n):
                    ysub[i] = y[i]
                t = t_end if hi == 1.0 else t + hi * dt
                for i in range(n):
                    y[i] = y1[i]
                while gi >= 0:
                    owner = GUARD_CONTACT[mode, gi]  # noqa: F821
                    new_mode = transition(mode, gi, t, y, p, ytmp)  # noqa: F821
                    if recording:
                        k = counters[C_LOGGED]
                        if k < max_log:
                            log_t[k] = t
                            log_guard[k] = gi
                            log_from[k] = mode
                            log_to[k] = new_mode
                        counters[C_LOGGED] += 1
                    counters[C_EVENTS] += 1
                    mode = new_mode
                    n_events += 1
                    if n_events > max_events:
                        counters[C_RECORDS] = irec
                        return STATUS_EVENT_STORM, mode, t, drifting
                    guards(mode, t_sub, ysub, p, gm)  # noqa: F821
                    guards(mode, t, y, p, g1)  # noqa: F821
                    gi = simultaneous_crossing(mode, owner, gm, g1)
                    if gi < 0:   # the last transition: g1 holds the new mode's guards at the event
                        drifting = drift_offsets(mode, g1, goff)
                g0_valid = False
            counters[C_STEPS] += 1
            for i in range(n):
                if not math.isfinite(y[i]):
                    counters[C_RECORDS] = irec
                    return STATUS_NONFINITE, mode, t, drifting
            if recording and (j + 1) % record_every == 0 and irec < rec_t.shape[0]:
                rec_t[irec] = t
                rec_mode[irec] = mode
                for i in range(n):
                    rec_y[irec, i] = y[i]
                irec += 1
        if recording:
            for i in range(n):
                poincare[per - n_transient, i] = y[i]
    counters[C_RECORDS] = irec
    return STATUS_OK, mode, t, drifting
