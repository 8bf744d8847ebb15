"""Fault injection: a sweep killed (parent or a worker) at random moments, its result file cut
short or with flipped bytes, and re-run, ends with the file of an uninterrupted run, bit for bit,
and leaves no process behind.

A handful of faults with a fixed seed on a tiny study (6 points of about a quarter
of a second); about 17 s.
"""

import os
import signal
import sys
import time

import numpy as np
import pytest

from blademodel.sweep import Study, run_study
from blademodel.sweep import storage
from blademodel.sweep.errors import ResultFileError
from blademodel.sweep.lock import lock_path

from sweep_tools import SLOW, cli, done_count, kill_all, raw_contents, start, tagged, wait_until, write_study

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="processes found through /proc")

STUDY = {**SLOW, "name": "faults", "run": {**SLOW["run"], "transient": 800}}
N = len(STUDY["sweep"]["gamma"]["values"])
SEED = 20261123
#: The faults, in order: each kill is followed by the next run, each damage too.
FAULTS = ["kill_parent", "kill_worker", "truncate", "kill_parent", "flip", "kill_worker", "kill_parent", "flip",
          "truncate"]


def _header_end(path, tmp):
    """Bytes before the data: the shortest prefix of the file that opens as a result file."""
    lo, hi = 0, path.stat().st_size
    blob = path.read_bytes()
    probe = tmp / "probe.nc"
    while lo < hi:
        mid = (lo + hi) // 2
        probe.write_bytes(blob[:mid])
        try:
            storage.open_dataset(probe).close()
            hi = mid
        except ResultFileError:
            lo = mid + 1
    return lo


def _verified(path):
    """Points of the file that pass their checksum (None if it cannot be read)."""
    try:
        return len(storage.check(path).done)
    except (ResultFileError, FileNotFoundError):
        return None


def _no_process_left(tag):
    assert wait_until(lambda: not tagged(tag), 5), f"processes left running: {tagged(tag)}"


def test_killed_and_damaged_sweeps_end_bit_identical(tmp_path):
    reference = tmp_path / "reference.nc"
    run_study(Study.model_validate(STUDY), reference, workers=1, progress=None, log=None)
    header = _header_end(reference, tmp_path)
    study = write_study(tmp_path, STUDY)
    out = tmp_path / "faults.nc"
    args = ("sweep", study, "--out", out, "--workers", "2", "--no-plot")
    rng = np.random.default_rng(SEED)
    interrupted = damaged = 0
    history = []   # (fault, points done after it): shown when the test fails
    stale_lock = False   # a killed owner's lock file stays until the next run takes it over
    for k, fault in enumerate(FAULTS):
        tag = f"faults-{os.getpid()}-{k}"
        try:
            if fault == "kill_parent":
                target = int(rng.integers(0, N))          # kill once this many points are done (or at once)
                delay = float(rng.uniform(0, 0.4))
                proc = start(*args, tag=tag)
                wait_until(lambda: proc.poll() is not None or done_count(out) >= target, 60)
                time.sleep(delay)
                proc.kill()
                proc.communicate()
                _no_process_left(tag)
            elif fault == "kill_worker":
                delay = float(rng.uniform(0, 0.5))
                proc = start(*args, tag=tag)
                wait_until(lambda: proc.poll() is not None or len(tagged(tag)) >= 3, 60)
                time.sleep(delay)
                workers = [p for p in tagged(tag) if p != proc.pid]
                if workers and proc.poll() is None:
                    os.kill(workers[int(rng.integers(0, len(workers)))], signal.SIGKILL)
                _, err = proc.communicate(timeout=60)
                if proc.returncode != 0:   # the kill reached a worker before the sweep ended
                    assert proc.returncode == 1, err
                    assert err.strip().splitlines()[-1].startswith("error: a worker process of the sweep died")
                    assert "Traceback" not in err
                _no_process_left(tag)
            elif out.exists() and out.stat().st_size > header:
                size = out.stat().st_size
                if fault == "truncate":
                    os.truncate(out, int(rng.integers(header, size)))
                else:
                    blob = bytearray(out.read_bytes())
                    for at in rng.integers(header, size, size=3):
                        blob[at] ^= 1 << int(rng.integers(0, 8))
                    out.write_bytes(bytes(blob))
                damaged += 1
        finally:
            kill_all(tag)
        history.append((fault, _verified(out)))
        if fault.startswith("kill") and 0 < (history[-1][1] or 0) < N:
            interrupted += 1
        if fault.startswith("kill"):   # a run: it leaves no lock file unless its owner was killed
            stale_lock = fault == "kill_parent"
        assert not lock_path(out).exists() or stale_lock             # a killed owner's lock file stays...
    r = cli(*args)                                                    # ...and does not block the next run
    assert r.returncode == 0, (r.stderr, history)
    assert "Traceback" not in r.stderr
    assert raw_contents(out) == raw_contents(reference), history      # bit for bit
    assert not lock_path(out).exists()
    assert interrupted >= 1 and damaged >= 2, history
    assert sorted(p.name for p in tmp_path.iterdir()) == ["faults.nc", "probe.nc", "reference.nc", "study.yaml"]
