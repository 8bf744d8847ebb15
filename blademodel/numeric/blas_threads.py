"""BLAS in one thread where the matrices are small: OpenBLAS's threads cost more than they gain there.

A ring's tangent and a continuation's linear algebra (its multipliers, corrections and
predictions) work with matrices of the ring's size, one product or factorization after
another. Measured on the 2-CPU machine with numpy's OpenBLAS: a 96 x 96 product in
47 us in one thread and 62 us in two; at 192 x 192, 352 us against 296 us (two threads
gain a little, for twice the CPU). :func:`blas_threads_for` limits BLAS to one thread
up to :data:`ONE_THREAD_STATES` and leaves it alone above.

Whole continuations (``blademodel continue``, two runs each way, one after the other, on
the idle machine, the second quoted; the grazing locator's thread works beside the continuation's):
a mistuned 48-blade ring (192 states) 22.3 s wall and 25.2 s of CPU in one BLAS thread
against 22.0 s and 42.5 s in two; the README's preloaded 24-blade Iwan ring (288) 32.3 s
and 45.1 s against 41.1 s and 75.9 s; the README's 96-blade ring on ``T / 8`` (384)
11.5 s and 15.2 s against 10.5 s and 18.8 s. Two threads gain wall time only at 384
states, and lose it where the locator's thread and OpenBLAS's contend for the cores.
"""

from __future__ import annotations

import contextlib

#: The most states for which :func:`blas_threads_for` runs BLAS in one thread.
ONE_THREAD_STATES = 320

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
