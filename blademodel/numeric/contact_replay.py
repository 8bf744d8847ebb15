"""The per-contact kernel's sub-step derivatives and guard differences, for the replayed tangent of its runs.

A *template* (see :mod:`.contact_loop`), used by
:class:`~blademodel.numeric.contact_tangent.ContactTangent` only: it is compiled
the first time a ring's period map is differentiated, not when the kernel runs.

Within a mode the flow is affine, ``f(t, y) = A y + b(t)``. One sub-step of the
kernel's explicit Runge-Kutta method from ``(t, y)`` of length ``h`` has stages
``K_i = f(T_i, Y_i)``, ``T_i = t + c_i h``, ``Y_i = y + h sum_j a_ij K_j``, and ends
at ``y + h sum_i b_i K_i``. Its derivatives in its length and in its start time
(the state fixed) are those of the stages::

    dK_i/dh  = A dY_i/dh + c_i b'(T_i),   dY_i/dh  = sum_j a_ij (K_j + h dK_j/dh)
    dK_i/dt0 = A dY_i/dt0 + b'(T_i),      dY_i/dt0 = h sum_j a_ij dK_j/dt0

``b'(T)`` is a central difference of ``f(T, 0)`` with the step ``d``. The
derivatives are formed on ``rows`` only, the cluster's state rows, which ``A``
couples to nothing outside (``Ar`` is ``A``'s block on them); the end state is whole.

A guard's rate in time is a central difference; its gradient in the state is kept
from the zero state where it predicts the guard's change along a probe at the
event, and where it does not (the joint stick forces of a closed ring make a guard
affine only piecewise) it is central differences at the event's state
(``guard_derivatives``).
"""

import math  # noqa: F401


def substep_derivatives(t, y, h, cm, d, Ar, rows, ta, tb, tc, I, R, WI, WF, K, Kh, Kt, BT, Y, Z, F, end, Pt, Ph):
    """The sub-step of length ``h`` from ``(t, y)`` in ``cm``: its end into ``end``, and on ``rows`` its end's
    derivatives in the start time into ``Pt`` and in the length into ``Ph``.

    ``ta, tb, tc``: the method's tableau. Work arrays: ``K`` (stages, full rows),
    ``Kh, Kt, BT`` (stages by cluster rows), ``Y``, ``F`` (a full state each), ``Z``
    (a full zero state, left zero). The stick problem of ``cm`` must be factored.
    """
    s = tb.shape[0]
    ns = y.shape[0]
    nr = rows.shape[0]
    for i in range(s):
        for k in range(ns):
            Y[k] = y[k]
        for j in range(i):
            a = ta[i, j]
            if a != 0.0:
                for k in range(ns):
                    Y[k] += h * a * K[j, k]
        T = t + tc[i] * h
        rhs(T, Y, cm, I, R, WI, WF, K[i])  # noqa: F821
        # the forcing's rate at T: once per distinct node
        same = -1
        for j in range(i):
            if tc[j] == tc[i]:
                same = j
                break
        if same >= 0:
            for r in range(nr):
                BT[i, r] = BT[same, r]
        else:
            rhs(T + d, Z, cm, I, R, WI, WF, F)  # noqa: F821
            for r in range(nr):
                BT[i, r] = F[rows[r]]
            rhs(T - d, Z, cm, I, R, WI, WF, F)  # noqa: F821
            for r in range(nr):
                BT[i, r] = (BT[i, r] - F[rows[r]]) / (2.0 * d)
        for r in range(nr):
            yh = 0.0
            yt = 0.0
            for j in range(i):
                a = ta[i, j]
                if a != 0.0:
                    yh += a * (K[j, rows[r]] + h * Kh[j, r])
                    yt += h * a * Kt[j, r]
            Pt[r] = yh   # the stage's dY/dh and dY/dt0, kept until every row's product is formed
            Ph[r] = yt
        for r in range(nr):
            ah = 0.0
            at = 0.0
            for c in range(nr):
                ah += Ar[r, c] * Pt[c]
                at += Ar[r, c] * Ph[c]
            Kh[i, r] = ah + tc[i] * BT[i, r]
            Kt[i, r] = at + BT[i, r]
    for k in range(ns):
        end[k] = y[k]
    for i in range(s):
        bi = tb[i]
        if bi != 0.0:
            for k in range(ns):
                end[k] += h * bi * K[i, k]
    for r in range(nr):
        ph = 0.0
        pt = 0.0
        for i in range(s):
            ph += tb[i] * (K[i, rows[r]] + h * Kh[i, r])
            pt += h * tb[i] * Kt[i, r]
        Ph[r] = ph
        Pt[r] = pt


def guard_derivatives(t, y, cm, j, gi, rows, steps, d, gyr, I, R, WI, WF, G, Y, out):
    """``(g_t, kept)`` of contact ``j``'s guard ``gi`` at ``(t, y)`` in ``cm``: ``g_t`` a central difference in
    time (step ``d``), and ``kept`` 1 if the kept gradient ``gyr`` (on ``rows``) predicts the guard's change
    along the probe ``steps`` (on ``rows``) to ``1e-7``, else 0 with the gradient on ``rows`` in ``out``, central
    differences at ``y`` with those steps (``Y``: a full state, work). The stick problem of ``cm`` must be
    factored."""
    eval_guards(t + d, y, cm, I, R, WI, WF, G)  # noqa: F821
    gp = G[j, gi]
    eval_guards(t - d, y, cm, I, R, WI, WF, G)  # noqa: F821
    gt = (gp - G[j, gi]) / (2.0 * d)
    for k in range(y.shape[0]):
        Y[k] = y[k]
    predicted = 0.0
    for r in range(rows.shape[0]):
        Y[rows[r]] = y[rows[r]] + steps[r]
        predicted += gyr[r] * steps[r]
    eval_guards(t, Y, cm, I, R, WI, WF, G)  # noqa: F821
    gp = G[j, gi]
    for r in range(rows.shape[0]):
        Y[rows[r]] = y[rows[r]] - steps[r]
    eval_guards(t, Y, cm, I, R, WI, WF, G)  # noqa: F821
    change = gp - G[j, gi]
    if abs(change - 2.0 * predicted) <= 1e-7 * (abs(change) + abs(predicted)):
        return gt, 1
    for r in range(rows.shape[0]):
        Y[rows[r]] = y[rows[r]]
    for r in range(rows.shape[0]):
        i = rows[r]
        e = steps[r]
        Y[i] = y[i] + e
        eval_guards(t, Y, cm, I, R, WI, WF, G)  # noqa: F821
        gp = G[j, gi]
        Y[i] = y[i] - e
        eval_guards(t, Y, cm, I, R, WI, WF, G)  # noqa: F821
        out[r] = (gp - G[j, gi]) / (2.0 * e)
        Y[i] = y[i]
    return gt, 0
