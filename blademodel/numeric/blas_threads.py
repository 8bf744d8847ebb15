"""BLAS in one thread where the matrices are small: OpenBLAS's threads cost more than they gain there.

A ring's tangent and a continuation's linear algebra (its multipliers, corrections and
predictions) work with matrices of the ring's size, one product or factorization after
another. Measured on the 2-CPU machine with numpy's OpenBLAS: a 96 x 96 product in
47 us in one thread and 62 us in two; at 192 x 192, 352 us against 296 us (two threads
gain a little, for twice the CPU). :func:`blas_threads_for` limits BLAS to one thread
up to :data:`ONE_THREAD_STATES` and leaves it alone above.
"""

from __future__ import annotations

import contextlib

#: The most states for which :func:`blas_threads_for` runs BLAS in one thread.
ONE_THREAD_STATES = 128

#: The BLAS thread pools (``threadpoolctl``), found at first use.
_POOLS = None


def blas_threads_for(n: int):
    """A context in which numpy's BLAS runs in one thread if the matrices are ``n <= ONE_THREAD_STATES`` square.

    Nested uses are cheap (about 25 us each) and restore the limits they found.
    """
    global _POOLS
    if n > ONE_THREAD_STATES:
        return contextlib.nullcontext()
    from threadpoolctl import ThreadpoolController
    if _POOLS is None:
        _POOLS = ThreadpoolController()
    return _POOLS.limit(limits=1, user_api="blas")
