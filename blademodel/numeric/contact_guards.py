"""The per-contact kernel's guards: values, rates, crossings and grazing candidates, on the active set.

A *template* (see :mod:`.contact_loop`). Guard 0 of every contact is its normal
law's (``normal_guard``), the friction law's guards follow (``law_guards``);
``G[j, gi]`` holds contact ``j``'s guard ``gi``, ``D[j, gi]`` its rate (NaN where
unknown). The tables ``NG``, ``GDIR`` describe each law kind's guards.
"""

import math  # noqa: F401

from blademodel.numeric.contract import (F_DL, F_DR, F_FR, F_GOFF, F_N, F_ND, F_NOISE, F_TLAST, F_V, F_XD, H_N, H_NC,
                                         NK_DAMPED, NK_LOAD, NK_SPRING, NONNEG, O_CIDX, O_CLAW, O_CNK, R_CC, R_GN,
                                         R_GR, R_K, R_N0, W_NNEAR, WC_AC, WC_ALL, WC_FIRED, WC_NEAR, WC_STK,
                                         WC_SUSPECT)


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
            i = cidx[4 * j + k]
            if i >= 0:
                a += cgn[4 * j + k] * dy[n + i]
        r += cc[j] * a
    return r


def eval_guards(t, y, cm, I, R, WI, WF, G):
    """The active contacts' guards into ``G[j, :]``: 0 the normal law's (``normal_guard``), then the law's."""
    evaluate(t, y, cm, I, R, WI, WF, y, G, G, EV_GUARDS | runtime(0))  # noqa: F821


def guards_at(t, y, cm, I, R, WI, WF, G):
    """``eval_guards`` for Python (an entry point: the tangent of the period map differentiates the guards)."""
    eval_guards(t, y, cm, I, R, WI, WF, G)


def guards_of_forces(y, cm, I, R, WI, WF, G):
    """The active contacts' guards from the forces of the last ``contact_forces``."""
    nc = I[H_NC]
    full, nca = active_contacts(WI, nc)  # noqa: F821
    ac = wvec(WI, nc, WC_ALL if full else WC_AC)  # noqa: F821
    claw = vec(I, I, O_CLAW, nc)  # noqa: F821
    cN, cNd, cv, cf, cdl = (vec(WF, I, F_N, nc), vec(WF, I, F_ND, nc), vec(WF, I, F_V, nc),  # noqa: F821
                            vec(WF, I, F_FR, nc), vec(WF, I, F_DL, nc))  # noqa: F821
    cnk, cc, cn0, ck = vec(I, I, O_CNK, nc), vec(R, I, R_CC, nc), vec(R, I, R_N0, nc), vec(R, I, R_K, nc)  # noqa: F821
    cdr = vec(WF, I, F_DR, nc)  # noqa: F821
    for jj in range(nca):
        j = ac[jj] & NONNEG
        G[j, 0] = normal_guard(j, cm[j], cnk[j], cdl[j], cdr[j], cN[j], ck, cc, cn0)
        law_guards(claw[j], cm[j], cN[j], cNd[j], cv[j], cf[j], y, law_offset(I, j), R, I, j, G)  # noqa: F821
    if WI[W_NNEAR] > 0:
        guard_offsets(cm, I, WI, WF, G)


def slot_sum(j, cidx, g, x, off):
    """``sum_k g[4 j + k] x[off + cidx[4 j + k]]`` over contact ``j``'s used slots: the rate of its penetration
    (``g = cgn``) or slip (``g = cgr``) from the velocities (``off = n``) or accelerations of ``x``."""
    s = 0.0
    for k in range(4):
        i = cidx[4 * j + k]
        if i >= 0:
            s += g[4 * j + k] * x[off + i]
    return s


def contact_rates(j, dy, n, cidx, cgn, cgr, ck):
    """``(dNd/dt, dv/dt)`` of contact ``j``: its normal force's second derivative and slip acceleration."""
    return ck[j] * slot_sum(j, cidx, cgn, dy, n), slot_sum(j, cidx, cgr, dy, n)


def guard_rates(y, dy, cm, I, R, WI, WF, D, with_stick):
    """Time derivatives of the active contacts' guards at ``y`` (``dy = dy/dt`` there; the forces of its last
    ``contact_forces``).

    The penetration's rate is known in every mode; a law guard's where the law's
    generated ``law_guard_rates`` knows it; a guard on a rigid stick force's only
    ``with_stick`` (:func:`stick_force_rates`, one more pass over the forces and a stick solve)
    and not in a closed ring of sticking contacts (whose forces are not determined by
    the motion); NaN elsewhere.
    """
    n, nc = I[H_N], I[H_NC]
    full, nca = active_contacts(WI, nc)  # noqa: F821
    ac, stk = wvec(WI, nc, WC_ALL if full else WC_AC), wvec(WI, nc, WC_STK)  # noqa: F821
    claw, cidx = vec(I, I, O_CLAW, nc), vec(I, I, O_CIDX, 4 * nc)  # noqa: F821
    cgn, cgr, ck = vec(R, I, R_GN, 4 * nc), vec(R, I, R_GR, 4 * nc), vec(R, I, R_K, nc)  # noqa: F821
    cN, cNd, cv, cf = vec(WF, I, F_N, nc), vec(WF, I, F_ND, nc), vec(WF, I, F_V, nc), vec(WF, I, F_FR, nc)  # noqa: F821
    cdr, xd = vec(WF, I, F_DR, nc), vec(WF, I, F_XD, nc)  # noqa: F821
    stick_known = with_stick and stick_rates_known(I, WI)  # noqa: F821
    if stick_known:
        stick_force_rates(y, dy, cm, I, R, WI, WF)  # noqa: F821
    cnk, cc = vec(I, I, O_CNK, nc), vec(R, I, R_CC, nc)  # noqa: F821
    for jj in range(nca):
        j = ac[jj] & NONNEG
        D[j, 0] = normal_guard_rate(j, cm[j], cnk[j], cdr[j], cNd[j], dy, n, cidx, cgn, ck, cc)
        for gi in range(1, D.shape[1]):
            D[j, gi] = math.nan
        if cm[j] == 0:
            continue
        Ndd, vd = contact_rates(j, dy, n, cidx, cgn, cgr, ck)
        if cnk[j] == NK_DAMPED:
            Ndd = math.nan   # k d2delta/dt2 + c d3delta/dt3: the jerk is not known
        fd = xd[j] if stick_known and stk[j] else math.nan
        law_guard_rates(claw[j], cm[j], cN[j], cNd[j], Ndd, cv[j], vd, cf[j], fd, y,  # noqa: F821
                        law_offset(I, j), R, I, j, dy, D)  # noqa: F821


def guard_offsets(cm, I, WI, WF, G):
    """Shift the guards of the contacts marked ``WC_NEAR`` (still in the mode they were marked in) by their
    offsets (``F_GOFF``)."""
    nc = I[H_NC]
    full, nca = active_contacts(WI, nc)  # noqa: F821
    ac, near = wvec(WI, nc, WC_ALL if full else WC_AC), wvec(WI, nc, WC_NEAR)  # noqa: F821
    claw, goff = vec(I, I, O_CLAW, nc), vec(WF, I, F_GOFF, nc * GMAX)  # noqa: F821
    for jj in range(nca):
        j = ac[jj] & NONNEG
        if near[j] != cm[j] + 1:
            continue
        for gi in range(NG[claw[j], cm[j]]):  # noqa: F821
            G[j, gi] -= goff[j * GMAX + gi]  # noqa: F821


def mark_near(j, cm, I, WI, WF, G):
    """Mark contact ``j``, just fired before its own root (``first_near_crossing``), with the offsets of its
    new mode's guards ``G[j]`` at the event; ``G[j]`` is shifted by them.

    Fired with another contact because its own root lies within the event tolerance
    after the event, the contact enters its new mode a rounding error short of the
    boundary: closed at a penetration of -8e-22 m, its normal force is negative and its
    stick guard ``mu N - |f|`` starts below zero. A crossing is a change of sign, so that
    guard would never fire however far it fell (the contact would stick with
    ``|f| > mu N``). A guard found on the side its mode forbids is therefore read, until
    the contact's next transition, minus that value (``guard_offsets``): it starts on
    the boundary, fires as soon as it falls further and stays quiet while it returns.
    Only such contacts, those the friction problem alone moves (a stuck contact released
    into a slip at a velocity a rounding error past zero: ``settle_event``), and an
    elastic law's friction guards that a regular transition leaves on their wrong side
    (``mark_drifted``). Other guards that a regular transition leaves a rounding error on
    their wrong side (a rigid slip ending exactly at the friction limit while the
    contact unloads, which the friction problem settles) keep their values, or two modes
    could chatter at one instant.
    """
    nc = I[H_NC]
    near, goff = wvec(WI, nc, WC_NEAR), vec(WF, I, F_GOFF, nc * GMAX)  # noqa: F821
    K = I[I[O_CLAW] + j]
    m = cm[j]
    again = near[j] == m + 1   # marked in this mode already: G[j] is read shifted, the offsets add up
    if near[j] == 0:
        WI[W_NNEAR] += 1
    near[j] = m + 1
    for gi in range(NG[K, m]):  # noqa: F821
        g = G[j, gi]
        off = g if wrong_side(g, GDIR[K, m, gi]) else 0.0  # noqa: F821
        goff[j * GMAX + gi] = goff[j * GMAX + gi] + off if again else off  # noqa: F821
        G[j, gi] = g - off


def mark_drifted(j, old, cm, I, WI, WF, G):
    """After a regular transition of contact ``j`` from mode ``old``: where it is a friction transition of an
    elastic law (no rigid stick; closed before and after: a contact that closes enters through its law's entry
    rule, and one that opens has no friction) and a friction guard of its new mode (``gi >= 1``; 0 is the normal
    guard) lies on its wrong side in ``G[j]``, read its guards from the boundary (``mark_near``).

    An elastic law's force is continuous at its transitions, so its new friction guards
    start on their boundary: a Jenkins slip ends where the slider stops with its spring at
    ``mu N``, and the stick guard ``mu N - kd z`` starts at zero with a zero rate. Its
    value is then the drift of ``z`` integrated through the slip (``-9.7e-11`` N on a
    tuned bilinear ring of 24 blades, ``+2e-14`` on a twin contact). Where the slider
    stopped only for a dip of its velocity, the guard rises less than that drift before it
    falls again; from below zero it never crossed, and the contact stuck on with ``|f|``
    up to ``1.27 mu N`` while its twin, a hair above zero, slipped again as it should. The
    normal guard is left as it is: a damped contact opens with its penetration still
    positive, and closes again where it crosses zero, not where it returns to that value.

    Only drift: a value within ``DRIFTED`` of the largest of the mode's friction guards
    (``2 mu N`` for a Jenkins stick, whose two guards are ``mu N -+ kd z``; a mode with one
    friction guard has no such scale and is left as it is). A law state a perturbation
    moved off the friction limit (the difference quotients of a period map do: the slip
    keeps ``kd z - mu N`` as it is) keeps its guards, and the map stays differentiable as
    the tangent has it.
    """
    K = I[I[O_CLAW] + j]
    m = cm[j]
    if old == 0 or m == 0 or RIGID[K, 0] >= 0:  # noqa: F821
        return
    scale = 0.0
    for gi in range(1, NG[K, m]):  # noqa: F821
        scale = max(scale, abs(G[j, gi]))
    for gi in range(1, NG[K, m]):  # noqa: F821
        g = G[j, gi]
        if wrong_side(g, GDIR[K, m, gi]) and abs(g) <= DRIFTED * scale:  # noqa: F821
            mark_near(j, cm, I, WI, WF, G)
            return



def mark_suspects(t, cm, I, WI, WF, G0, G1, window):
    """Mark the sub-step's suspects: the active contacts that changed mode at most ``window`` before its
    start ``t`` and none of whose guards crossed from ``G0`` to ``G1`` over it.

    Such a contact can sit on a guard with zero value and zero rate: a Jenkins slip that
    ends as its spring unloads starts the stick guard ``mu N + kd z`` at 0 with rate 0.
    Its sign is then a rounding error, and in a bracket 1e-17 s long (a neighbour's
    event) it can read +1e-20 at one end and -1e-20 at the other; coincident events
    1e-17 s apart can bring several such brackets in a row. So a suspect's crossing
    found in a bracket that ends within ``window`` (``SUSPECT_WINDOW`` event
    tolerances) of its transition is passed over (``suspects_at``). A real one either
    shows over the whole sub-step (a contact that closes and at once slips is no
    suspect) or later in it (a slip shorter than a step, found by the grazing check),
    and one left on its wrong side at an event is put on the boundary
    (``settle_suspects``), so that a later fall still fires.
    """
    nc = I[H_NC]
    full, nca = active_contacts(WI, nc)  # noqa: F821
    ac, sus = wvec(WI, nc, WC_ALL if full else WC_AC), wvec(WI, nc, WC_SUSPECT)  # noqa: F821
    claw, tlast, noise = vec(I, I, O_CLAW, nc), vec(WF, I, F_TLAST, nc), vec(WF, I, F_NOISE, nc)  # noqa: F821
    for jj in range(nca):
        j = ac[jj] & NONNEG
        recent = t - tlast[j] <= window   # False while NaN (no transition yet)
        sus[j] = 1 if recent and contact_crossing(j, cm[j], claw[j], G0, G1) < 0 else 0
        noise[j] = tlast[j] + window


def suspects_at(tb, I, WI, WF):
    """Activate (2) the suspects whose crossings in a bracket ending at ``tb`` are noise; the others are 1."""
    nc = I[H_NC]
    full, nca = active_contacts(WI, nc)  # noqa: F821
    ac, sus = wvec(WI, nc, WC_ALL if full else WC_AC), wvec(WI, nc, WC_SUSPECT)  # noqa: F821
    noise = vec(WF, I, F_NOISE, nc)  # noqa: F821
    for jj in range(nca):
        j = ac[jj] & NONNEG
        if sus[j] != 0:
            sus[j] = 2 if tb <= noise[j] else 1


#: How long after its own transition a contact's crossings inside a sub-step may be rounding noise, in
#: event tolerances (``mark_suspects``).
SUSPECT_WINDOW = 64.0


def settle_suspects(cm, I, WI, WF, G):
    """At an event: suspects left on a wrong side of their guards ``G`` are put on the boundary
    (``mark_near``); the marks ``WC_SUSPECT`` are cleared.

    Not a closed contact of a law with a rigid stick: the friction problem that follows
    settles its mode (``settle_event``), and a neighbour's event can move its stick force
    by any amount, so its guards here, before that problem, may lie far on their wrong
    side. Put on the boundary, such a contact kept that offset after the problem left it
    stuck: on a mistuned Coulomb ring of 24 blades (engine order 1, ``F0 = 150`` N, 330
    rad/s) contact 10, marked with its stick guard at ``-11`` N, stuck on at up to
    ``1.19 mu N``.
    """
    nc = I[H_NC]
    full, nca = active_contacts(WI, nc)  # noqa: F821
    ac, sus = wvec(WI, nc, WC_ALL if full else WC_AC), wvec(WI, nc, WC_SUSPECT)  # noqa: F821
    claw = vec(I, I, O_CLAW, nc)  # noqa: F821
    for jj in range(nca):
        j = ac[jj] & NONNEG
        if sus[j] == 0:
            continue
        sus[j] = 0
        K = claw[j]
        m = cm[j]
        if m != 0 and RIGID[K, 0] >= 0:  # noqa: F821
            continue
        for gi in range(NG[K, m]):  # noqa: F821
            if wrong_side(G[j, gi], GDIR[K, m, gi]):  # noqa: F821
                mark_near(j, cm, I, WI, WF, G)
                break


def clear_suspects(I, WI):
    """Clear ``WC_SUSPECT`` on the active contacts."""
    nc = I[H_NC]
    full, nca = active_contacts(WI, nc)  # noqa: F821
    ac, sus = wvec(WI, nc, WC_ALL if full else WC_AC), wvec(WI, nc, WC_SUSPECT)  # noqa: F821
    for jj in range(nca):
        sus[ac[jj] & NONNEG] = 0


def unmark_near(j, I, WI):
    """Clear contact ``j``'s ``WC_NEAR`` mark (it fired again, or the friction problem changed its mode)."""
    near = wvec(WI, I[H_NC], WC_NEAR)  # noqa: F821
    if near[j] != 0:
        near[j] = 0
        WI[W_NNEAR] -= 1


def copy_guards(I, WI, G, Gm, D, Dm):
    """``G, D = Gm, Dm`` (guards and their rates) on the active contacts."""
    nc = I[H_NC]
    full, nca = active_contacts(WI, nc)  # noqa: F821
    ac = wvec(WI, nc, WC_ALL if full else WC_AC)  # noqa: F821
    for jj in range(nca):
        j = ac[jj] & NONNEG
        for gi in range(G.shape[1]):
            G[j, gi] = Gm[j, gi]
            D[j, gi] = Dm[j, gi]


# ---- crossings ------------------------------------------------------------------------------
def crossed(g0, g1, direction):
    """Whether a guard went from ``g0`` to ``g1`` through zero in ``direction`` (see ``loop.crossed``)."""
    if direction < 0:
        return g0 >= 0.0 and g1 < 0.0
    if direction > 0:
        return g0 <= 0.0 and g1 > 0.0
    return (g0 > 0.0 and g1 <= 0.0) or (g0 < 0.0 and g1 >= 0.0)


def contact_crossing(j, m, K, G0, G1):
    """The first guard of contact ``j`` (mode ``m``, law kind ``K``) that crossed from ``G0`` to ``G1``, or -1."""
    for gi in range(NG[K, m]):  # noqa: F821
        if crossed(G0[j, gi], G1[j, gi], GDIR[K, m, gi]):  # noqa: F821
            return gi
    return -1


def first_crossing(cm, I, WI, G0, G1):
    """``j * GMAX + gi`` of the first active guard that crossed (contacts in order), or -1.

    Contacts whose transition fired in the current event are passed over: their law
    has settled them, and their new mode's guards compared across the bracket mean
    nothing (outside an event no contact is marked). So are the sub-step's suspects
    (``mark_suspects``).
    """
    nc = I[H_NC]
    full, nca = active_contacts(WI, nc)  # noqa: F821
    ac, fired = wvec(WI, nc, WC_ALL if full else WC_AC), wvec(WI, nc, WC_FIRED)  # noqa: F821
    sus = wvec(WI, nc, WC_SUSPECT)  # noqa: F821
    claw = vec(I, I, O_CLAW, nc)  # noqa: F821
    for jj in range(nca):
        j = ac[jj] & NONNEG
        if fired[j] != 0 or sus[j] == 2:
            continue
        gi = contact_crossing(j, cm[j], claw[j], G0, G1)
        if gi >= 0:
            return j * GMAX + gi  # noqa: F821
    return -1


def earliest_crossing(cm, I, WI, Glo, G1, Dlo, D1, lo, hi, dt):
    """``j * GMAX + gi`` of the crossed active guard with the earliest predicted root in ``(lo, hi)``, and that
    root."""
    nc = I[H_NC]
    full, nca = active_contacts(WI, nc)  # noqa: F821
    ac = wvec(WI, nc, WC_ALL if full else WC_AC)  # noqa: F821
    claw, sus = vec(I, I, O_CLAW, nc), wvec(WI, nc, WC_SUSPECT)  # noqa: F821
    best = -1
    xbest = hi
    for jj in range(nca):
        j = ac[jj] & NONNEG
        if sus[j] == 2:
            continue
        K = claw[j]
        m = cm[j]
        for gi in range(NG[K, m]):  # noqa: F821
            if crossed(Glo[j, gi], G1[j, gi], GDIR[K, m, gi]):  # noqa: F821
                x = predicted_root(Glo[j, gi], G1[j, gi], Dlo[j, gi], D1[j, gi], lo, hi, dt)  # noqa: F821
                if best < 0 or x < xbest:
                    best = j * GMAX + gi  # noqa: F821
                    xbest = x
    return best, xbest


def first_near_crossing(cm, I, WI, Gs, G1, span, tol):
    """``j * GMAX + gi`` of the first active guard of a contact not yet fired that will cross within ``tol``.

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
    full, nca = active_contacts(WI, nc)  # noqa: F821
    ac, fired = wvec(WI, nc, WC_ALL if full else WC_AC), wvec(WI, nc, WC_FIRED)  # noqa: F821
    sus = wvec(WI, nc, WC_SUSPECT)  # noqa: F821
    claw = vec(I, I, O_CLAW, nc)  # noqa: F821
    for jj in range(nca):
        j = ac[jj] & NONNEG
        if fired[j] != 0 or sus[j] == 2:
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


# ---- grazing --------------------------------------------------------------------------------
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


def contact_grazing(j, m, K, G0, G1, D0, D1, dt, width):
    """The earliest fraction of a step at which a guard of contact ``j`` that did not cross may have crossed and
    come back, or -1.

    A guard with known rates that moves toward its crossing at the step's start and
    away from it at the end, both ends on the side before the crossing, has an
    extremum inside the step; if the cubic Hermite interpolant of its values and
    rates puts that extremum past zero, the guard crossed and returned within the
    step (a brief contact, a grazing touch). An extremum within ``width`` (the event
    tolerance) of the start is the turn of an event just handled there, not a new
    one: it is passed over.
    """
    best = -1.0
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


def grazing_candidate(cm, I, WI, G0, G1, D0, D1, dt, width):
    """The earliest grazing fraction (``contact_grazing``) over the active contacts, or -1."""
    nc = I[H_NC]
    full, nca = active_contacts(WI, nc)  # noqa: F821
    ac = wvec(WI, nc, WC_ALL if full else WC_AC)  # noqa: F821
    claw = vec(I, I, O_CLAW, nc)  # noqa: F821
    best = -1.0
    for jj in range(nca):
        j = ac[jj] & NONNEG
        s = contact_grazing(j, cm[j], claw[j], G0, G1, D0, D1, dt, width)
        if s > 0.0 and (best < 0.0 or s < best):
            best = s
    return best
