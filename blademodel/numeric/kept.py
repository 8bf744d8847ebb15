"""Values kept by key to a budget of bytes, the least recently used dropped first.

The replayed tangent of the per-contact kernel (:mod:`.contact_tangent`) keeps each
mode's matrices, guard gradients, blocks and clusters this way, and its flow pattern
(:mod:`.contact_flow_pattern`) the clusters' rows: a long continuation of a large ring
meets thousands of them.
"""

from __future__ import annotations

import threading
from collections import OrderedDict

import numpy as np


def nbytes(value) -> int:
    """The bytes ``value`` holds: an array, a sparse matrix, or a list or tuple of them (64 for anything else)."""
    if isinstance(value, np.ndarray):
        return value.nbytes
    if hasattr(value, "indptr"):   # a sparse matrix (a mode's A)
        return value.data.nbytes + value.indices.nbytes + value.indptr.nbytes
    if isinstance(value, (list, tuple)):
        return 64 + sum(nbytes(v) for v in value)
    return 64


class Kept:
    """Values by key, the least recently used dropped once they hold more than ``budget`` bytes.

    What is kept here is computed from the model's values alone, so a dropped value is
    computed again bit for bit the same: the budget moves the cost, never a result. (One
    exception: the Iwan law's reset Jacobians, and the cluster steps' plans that hold them,
    are differences at the state where they were first needed, the same to their rounding.)
    Safe between threads (the grazing locator's thread replays on the same model's kept
    matrices as the continuation's): a lookup and its move to the end, an insertion and
    the drops it makes, each happen whole.
    """

    def __init__(self, budget: int):
        self.budget, self.size, self._d = int(budget), 0, OrderedDict()
        self.dropped = 0
        self._lock = threading.Lock()

    def get(self, key):
        with self._lock:
            value = self._d.get(key)
            if value is not None:
                self._d.move_to_end(key)
            return value

    def __setitem__(self, key, value):
        with self._lock:
            old = self._d.pop(key, None)
            if old is not None:
                self.size -= nbytes(old)
            self._d[key] = value
            self.size += nbytes(value)
            while self.size > self.budget and len(self._d) > 1:
                self.size -= nbytes(self._d.popitem(last=False)[1])
                self.dropped += 1

    def __len__(self):
        return len(self._d)
