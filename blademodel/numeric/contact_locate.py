"""The per-contact kernel's event location: bracket the earliest guard crossing of a sub-step.

A *template* (see :mod:`.contact_loop`). Every trial is the true Runge-Kutta
sub-step of the active set, so the root is the one of the discrete flow; the
scalar steps of the bracketing (predicted roots, secants, safeguards) come from
:mod:`.bracket`.
"""

import math  # noqa: F401

from blademodel.numeric.contract import C_LOCATION_SUBSTEPS, C_RHS, H_N, H_NC

#: Cap on the trial sub-steps of one event's location (a bisection at least every third
#: trial halves the bracket: 2**-50 of a step long before the cap).
MAX_LOCATE_TRIALS = 160


def locate_trial(t, y, dt, frac, cm, I, R, WI, WF, SC, ymid, G0, Gm, Dm, counters):
    """Sub-step of the active set to the fraction ``frac`` of the step, its guards and their rates.

    ``SC[0]`` holds ``dy/dt`` at ``(t, y)`` (every trial starts there). Returns the
    first crossing since the start.
    """
    spent = rk_step(t, y, frac * dt, cm, I, R, WI, WF, SC, ymid, True)  # noqa: F821
    # SC[4]: the stages' scratch, free now
    evaluate(t + frac * dt, ymid, cm, I, R, WI, WF, SC[4], Gm, Dm, EV_ALL | EV_STICK | runtime(0))  # noqa: F821
    counters[C_LOCATION_SUBSTEPS] += 1
    counters[C_RHS] += spent + 1
    suspects_at(t + frac * dt, I, WI, WF)  # noqa: F821
    return first_crossing(cm, I, WI, G0, Gm)  # noqa: F821


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
    and guards there (on the active set), past the root by at most ``width`` of the
    sub-step (or by the floating-point resolution of the step, if the tolerance is finer).
    """
    y1, ymid = SC[5], SC[6]
    G0, G1, Gm, Glo = GS[0], GS[1], GS[2], GS[7]
    D0, D1, Dm, Dlo = GS[4], GS[5], GS[6], GS[8]
    copy_guards(I, WI, Glo, G0, Dlo, D0)
    lo = 0.0
    hi = 1.0
    suspects_at(t + dt, I, WI, WF)  # noqa: F821
    code, x = earliest_crossing(cm, I, WI, Glo, G1, Dlo, D1, lo, hi, dt)  # noqa: F821
    if code < 0:
        code = first_crossing(cm, I, WI, G0, G1)  # noqa: F821
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
        c = locate_trial(t, y, dt, x, cm, I, R, WI, WF, SC, ymid, G0, Gm, Dm, counters)  # noqa: F821
        if c >= 0:
            hi = x
            copy_rows(WI, I[H_NC], I[H_N], y1, ymid)  # noqa: F821
            copy_guards(I, WI, G1, Gm, D1, Dm)  # noqa: F821
        else:
            lo = x
            copy_guards(I, WI, Glo, Gm, Dlo, Dm)  # noqa: F821
        if c >= 0 and c != code:
            # an earlier crossing of another guard: the earliest predicted in the new bracket is the target
            code, xnext = earliest_crossing(cm, I, WI, Glo, G1, Dlo, D1, lo, hi, dt)  # noqa: F821
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

