"""The rigid-stick part of the per-contact kernel, for law kinds that have no rigid stick.

A *template* like :mod:`.contact_stick`: pasted after the other templates into a
generated module (:mod:`.contact_codegen`) when no friction-law kind has a rigid
stick mode (frictionless contacts, Jenkins, Iwan ...). It redefines the functions
of the stick solver and of the friction complementarity problem with what they
reduce to when no contact can stick rigidly: the stick set is always empty and
every event is settled by the guard transitions alone. The kernel's results are
the same; what is saved is compiling a solver that could never run (about a
quarter of the cold compile).
"""

from blademodel.numeric.contract import H_NC, NONNEG, W_NS, W_NULL, WC_AC, WC_U, WC_ALL


def factor_stick(cm, I, R, WI, WF):
    """No contact sticks rigidly: the stick set is empty."""
    WI[W_NS] = 0
    WI[W_NULL] = -1


def null_pivot_active(I, WI):
    """No stick set, no null pivot."""
    return False


def stick_rates_known(I, WI):
    """No stick forces."""
    return False


def solve_stick(I, WI, WF, b, x):
    """Never called with a non-empty stick set."""
    return


def stick_solution(F, b, x, I, R, WI, WF):
    """Never called (no stick set)."""
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
    """No rigid contact: no friction problem (``U`` cleared on the active set)."""
    nc = I[H_NC]
    full, nca = active_contacts(WI, nc)  # noqa: F821 (the templates' helpers, defined before this file)
    U, ac = wvec(WI, nc, WC_U), wvec(WI, nc, WC_ALL if full else WC_AC)  # noqa: F821
    for jj in range(nca):
        U[ac[jj] & NONNEG] = 0
    return False


def resolve_friction(t, y, cm, I, R, WI, WF, counters, max_pivots):
    """Never called (``rigid_problem`` is False); resolved."""
    return True


def stick_force_rates(y, dy, cm, I, R, WI, WF):
    """Never called (no stick set)."""
    return
