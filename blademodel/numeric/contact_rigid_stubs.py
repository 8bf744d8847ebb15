"""The rigid-stick part of the per-contact kernel, for law kinds that have no rigid stick.

A *template* like :mod:`.contact_loop`: pasted after it into a generated module
(:mod:`.contact_codegen`) when no friction-law kind has a rigid stick mode
(frictionless contacts, Jenkins, Iwan ...). It redefines the functions of the stick
solver and of the friction complementarity problem with what they reduce to when
no contact can stick rigidly: the stick set is always empty and every event is
settled by the guard transitions alone. The kernel's results are the same; what
is saved is compiling a solver that could never run (about a quarter of the cold
compile).
"""

from blademodel.numeric.contract import H_NC


def factor_stick(cm, I, R, WI, WF):
    """No contact sticks rigidly: the stick set is empty."""
    WI[0] = 0
    WI[1] = -1


def solve_stick(ns, env, Lf, Dd, b, x):
    """Never called with a non-empty stick set."""
    return


def least_cone_ratio(y, I, R, WI, WF):
    """Never called (no null pivot without a stick set)."""
    return


def cone_ratio(y, I, R, WI, WF):
    """No sticking rigid contact: 0."""
    return 0.0


def project_onto_stick(y, I, R, WI, WF):
    """Nothing to project onto."""
    return


def rigid_problem(cm, I, WI):
    """No rigid contact: no friction problem (``U`` cleared)."""
    nc = I[H_NC]
    U = wvec(WI, nc, 2)  # noqa: F821 (the template's view, defined before this file)
    for j in range(nc):
        U[j] = 0
    return False


def resolve_friction(t, y, cm, I, R, WI, WF, counters, max_pivots):
    """Never called (``rigid_problem`` is False); resolved."""
    return True


def stick_force_rates(y, dy, cm, I, R, WI, WF):
    """Never called (no stick set)."""
    return
