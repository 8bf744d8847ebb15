"""``Kept``: values by key to a budget of bytes, shared by the continuation's thread and the grazing locator's."""

from __future__ import annotations

import threading
from collections import OrderedDict

import numpy as np

from blademodel.numeric.kept import Kept, nbytes


def test_the_least_recently_used_is_dropped_first_and_the_bytes_are_counted():
    k = Kept(3 * 64)   # three arrays of eight floats
    for key in "abc":
        k[key] = np.zeros(8)
    assert k.get("a") is not None   # "a" used: "b" is now the least recently used
    k["d"] = np.zeros(8)
    assert k.get("b") is None and all(k.get(key) is not None for key in "acd")
    assert k.size == sum(nbytes(v) for v in k._d.values()) == 3 * 64 and k.dropped == 1
    k["a"] = np.zeros(16)   # replaced by a larger value: the least recently used go
    assert k.size <= k.budget and k.size == sum(nbytes(v) for v in k._d.values())


class _PausingDict(OrderedDict):
    """An ordered dict whose ``get`` calls ``pause()`` after its lookup: where another thread may run."""

    pause = None

    def get(self, key, default=None):
        value = super().get(key, default)
        if self.pause is not None:
            self.pause()
        return value


def test_a_value_dropped_by_another_thread_between_lookup_and_use_is_no_error():
    """The grazing locator's thread and the continuation's replay the same model's kept matrices. A thread that has
    looked a key up and is preempted there (forced here: it waits for the other) must not find the key dropped under
    it: the other thread's insertion, which drops it, waits for the lookup to finish."""
    k = Kept(100)   # room for one array of eight floats
    k._d = _PausingDict()
    k["a"] = np.zeros(8)
    looked, dropped, errors = threading.Event(), threading.Event(), []

    def pause():
        looked.set()
        dropped.wait(0.5)   # without the lock the other thread drops "a" meanwhile

    def reader():
        try:
            k.get("a")
        except Exception as e:   # KeyError from move_to_end without the lock
            errors.append(e)

    def writer():
        looked.wait(5.0)
        k._d.pause = None
        k["b"] = np.zeros(8)   # drops "a"
        dropped.set()

    k._d.pause = pause
    threads = [threading.Thread(target=reader), threading.Thread(target=writer)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(10.0)
    assert not errors
    assert k.get("a") is None and k.get("b") is not None and k.size == 64 and k.dropped == 1
