"""Scalar steps of an event's bracketing, shared by both kernels.

A *template*: pasted into each generated module before the kernel's own template
(:mod:`.loop`, :mod:`.contact_loop`), which calls these with the fractions of the
sub-step that bracket the earliest crossing.
"""

import math


def inverse_quadratic(xa, ga, xb, gb, xc, gc, lo, hi):
    """Root estimate from the last points of a guard: inverse quadratic through three (``xc`` may be NaN:
    two), else the secant through ``a`` and ``b``, else the bracket's middle."""
    if math.isfinite(xc) and ga != gb and ga != gc and gb != gc:
        return (xa * gb * gc / ((ga - gb) * (ga - gc)) + xb * ga * gc / ((gb - ga) * (gb - gc))
                + xc * ga * gb / ((gc - ga) * (gc - gb)))
    if gb != ga:
        return xb - gb * (xb - xa) / (gb - ga)
    return 0.5 * (lo + hi)


def safeguarded_trial(x, lo, hi, width, halve, reach=0.5):
    """The trial fraction for a predicted root ``x`` in the bracket ``(lo, hi)``.

    The bracket's middle if ``halve`` (the last two trials did not halve it) or if
    ``x`` lies outside; a prediction within half a tolerance ``width`` of ``lo``, or
    within ``reach`` tolerances of ``hi``, is set three quarters of a tolerance past
    that end, so the trial closes the bracket whichever side of the root it falls.
    (A ``reach`` above one half keeps the bracket's far end, the state taken past the
    event, clear of the root when the first trial was aimed past it.)
    """
    if halve or not lo < x < hi:
        x = 0.5 * (lo + hi)
    if x - lo < 0.5 * width:
        x = lo + 0.75 * width
    elif hi - x < reach * width:
        x = hi - 0.75 * width
    return x
