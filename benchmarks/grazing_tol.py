"""What locating grazing points costs a continuation, what ``grazing_tol`` trades for it, and a second thread.

    python benchmarks/grazing_tol.py [--blades 24] [--mistuning 0.02] [--from 276] [--to 280] [--repeats 2]

A mistuned ring's contacts graze one by one, and each grazing point is bisected to
``locate_tol`` (``1e-7``) by default. The same branch (``models/bladed_disk_24.yaml``,
``steps_per_period = 600``, mistuning seed 1) is continued with ``grazing_tol`` = the
default, ``1e-5``, ``1e-3`` and ``inf`` (no location: each grazing point reported at the
first point past it), repeats interleaved, CPU time of the thread (minimum), after one
short run that compiles the kernel, all in one thread (``workers=1``). Printed: each
run's CPU time against the default's, its integrations of the period map, its grazing
points and how far the farthest lies from the nearest of the default's; every branch is
checked to have the default's points to the bit. Then the default with its grazing points located in a second thread
beside the continuation (``workers=2``, :mod:`blademodel.orbits.background`) against one
thread, interleaved: wall time (what a user waits) and the process's CPU time (both
threads), the branch and its special points checked to be the same to the bit.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parent))
import _common as C  # noqa: E402

from blademodel.config import apply_overrides, load_config  # noqa: E402
from blademodel.orbits import continuation  # noqa: E402

TOLERANCES = (None, 1e-5, 1e-3, float("inf"))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--blades", type=int, default=24)
    ap.add_argument("--mistuning", type=float, default=0.02)
    ap.add_argument("--from", dest="start", type=float, default=276.0)
    ap.add_argument("--to", dest="stop", type=float, default=280.0)
    ap.add_argument("--repeats", type=int, default=2)
    args = ap.parse_args()
    cfg = apply_overrides(load_config(C.ROOT / "models" / "bladed_disk_24.yaml"),
                          {"blades": str(args.blades), "mistuning_std": str(args.mistuning), "mistuning_seed": "1"})

    def run(g, workers=1):
        return continuation(cfg, "omega", args.start, args.stop, max_points=2000, steps_per_period=600,
                            transient=50, grazing_tol=g, workers=workers)

    C.print_load("at start")
    continuation(cfg, "omega", args.start, args.stop, max_points=3, steps_per_period=600, transient=50, workers=1)
    branches = {}

    def timed(g):
        def f():
            branches[g] = run(g)
        return f
    times = C.interleaved({g: timed(g) for g in TOLERANCES}, args.repeats)
    ref = branches[None]
    located = np.array([p.param for p in ref.points("grazing")])
    rows = []
    for g in TOLERANCES:
        b = branches[g]
        for name in ("params", "states", "multipliers", "events"):
            if not np.array_equal(getattr(b, name), getattr(ref, name)):
                raise SystemExit(f"grazing_tol = {g}: the branch's {name} differ from the default's")
        found = np.array([p.param for p in b.points("grazing")])
        rows.append({"grazing_tol": "default (1e-7)" if g is None else f"{g:g}", "cpu": min(times[g]),
                     "ratio": min(times[None]) / min(times[g]), "integrations": b.integrations,
                     "grazing": found.size, "shift": _farthest(found, located)})
    print(f"{args.blades} blades, mistuning {args.mistuning:g}, omega {args.start:g} to {args.stop:g}: "
          f"{ref.params.size} points, {located.size} grazing points; the same points to the bit at every grazing_tol")
    print(C.table(rows, [("grazing_tol", "grazing_tol", ""), ("cpu", "CPU s", ".1f"),
                         ("ratio", "default / this", ".2f"), ("integrations", "integrations", "d"),
                         ("grazing", "grazing points", "d"), ("shift", "largest shift (rad/s)", ".2g")]))
    threads = {}

    def threaded(workers, clock):
        def f():
            t0, c0 = time.perf_counter(), time.process_time()
            threads.setdefault(workers, []).append(run(None, workers))
            clock.setdefault(workers, []).append((time.perf_counter() - t0, time.process_time() - c0))
        return f
    clocks: dict = {}
    C.interleaved({w: threaded(w, clocks) for w in (1, 2)}, args.repeats)
    for b in threads[2]:
        for name in ("params", "states", "multipliers", "events"):
            if not np.array_equal(getattr(b, name), getattr(ref, name)):
                raise SystemExit(f"workers=2: the branch's {name} differ from one thread's")
        if [(p.kind, p.param) for p in b.special] != [(p.kind, p.param) for p in ref.special]:
            raise SystemExit("workers=2: the special points differ from one thread's")
    wall = {w: min(c[0] for c in clocks[w]) for w in clocks}
    cpu = {w: min(c[1] for c in clocks[w]) for w in clocks}
    print(f"grazing points in a second thread (workers=2) / one thread: wall {wall[1]:.1f} / {wall[2]:.1f} s = "
          f"{wall[1] / wall[2]:.2f} times faster; process CPU {cpu[2]:.1f} / {cpu[1]:.1f} s = {cpu[2] / cpu[1]:.2f}; "
          f"the same branch and special points to the bit")
    C.print_load("at end")
    path = C.write_json("grazing_tol", {"benchmark": "grazing_tol", "args": vars(args), "rows": rows,
                                        "times": {str(k): v for k, v in times.items()},
                                        "second_thread": {"wall": wall, "cpu": cpu}, "machine": C.machine()})
    print(f"wrote {path}")


def _farthest(found, located) -> float:
    """How far the grazing point of ``found`` farthest from all of ``located`` lies from the nearest (a coarser
    tolerance may report as one point several changes closer than it)."""
    if not found.size or not located.size:
        return 0.0
    return float(np.max(np.min(np.abs(found[:, None] - located[None, :]), axis=1)))


if __name__ == "__main__":
    main()
