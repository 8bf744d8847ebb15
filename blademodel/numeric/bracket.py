"""Scalar steps of an event's bracketing, and the sides of a guard, shared by both kernels.

A *template*: pasted into each generated module before the kernel's own template
(:mod:`.loop`, :mod:`.contact_loop`), which calls these with the fractions of the
sub-step that bracket the earliest crossing.
"""

import math

#: How far (relative to the largest friction guard of its mode) an elastic law's friction guard may lie on its
#: wrong side after a transition and still be taken for a rounding error of a state the reset put on its boundary,
#: or the drift of an integrated one (``mark_drifted`` in the per-contact kernel, ``drift_offsets`` in the
#: product-mode one): ``8e-13`` measured (``-9.7e-11`` N against ``2 mu N = 117`` N).
DRIFTED = 1e-10


def wrong_side(g, d):
    """Whether a guard of value ``g`` and crossing direction ``d`` lies on the side its mode forbids."""
    return (d < 0 and g < 0.0) or (d > 0 and g > 0.0)


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


def hermite(s, g0, g1, d0, d1):
    """The cubic Hermite interpolant on ``[0, 1]`` of values ``g0, g1`` and slopes ``d0, d1``; value and slope."""
    s2 = s * s
    s3 = s2 * s
    v = (2.0 * s3 - 3.0 * s2 + 1.0) * g0 + (s3 - 2.0 * s2 + s) * d0 + (3.0 * s2 - 2.0 * s3) * g1 + (s3 - s2) * d1
    d = (6.0 * s2 - 6.0 * s) * (g0 - g1) + (3.0 * s2 - 4.0 * s + 1.0) * d0 + (3.0 * s2 - 2.0 * s) * d1
    return v, d


def hermite_root(g0, g1, d0, d1, s):
    """A root in ``(0, 1)`` of the Hermite interpolant by Newton from ``s``; ``s`` itself if it fails."""
    x = s
    for _ in range(8):
        v, d = hermite(x, g0, g1, d0, d1)
        if d == 0.0 or not math.isfinite(d):
            return s
        dx = v / d
        x -= dx
        if not 0.0 < x < 1.0:
            return s
        if abs(dx) <= 1e-15:
            break
    return x


def predicted_root(g0, g1, d0, d1, lo, hi, dt):
    """Predicted root in ``(lo, hi)`` of a guard with values ``g0, g1`` and rates ``d0, d1`` at the ends."""
    x = g0 / (g0 - g1) if g0 != g1 else 0.5
    if math.isfinite(d0) and math.isfinite(d1):
        span = (hi - lo) * dt
        x = hermite_root(g0, g1, d0 * span, d1 * span, x)
    return lo + x * (hi - lo)
