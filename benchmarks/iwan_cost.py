"""Wall time per RK4 step of the Iwan law against the bilinear law, on the paper's blade pair.

Usage::

    python benchmarks/iwan_cost.py [--periods 100] [--rounds 7] [--elements 1 4 16]

Each law's kernel is compiled (or loaded from the cache) and warmed up first; then
the laws are timed *interleaved*, round after round, each integrating the same
periods from rest (base case: gamma = 4, gap = 40 um, F0 = 60 N, T/1000), so a
change of machine load hits all of them alike. Printed: the median time per step
over the rounds and its ratio to the bilinear law's, with the events per period.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from blademodel.zheng2022 import BladePair
from blademodel.numeric import HybridIntegrator
from blademodel.numeric.contract import N_COUNTERS


def per_step(integ: HybridIntegrator, periods: int) -> tuple[float, int, int]:
    """Seconds per step of one run of ``periods`` from rest, its steps and events."""
    y = integ.initial_state()
    mode = integ.mode_of(y)
    counters = np.zeros(N_COUNTERS, dtype=np.int64)
    t0 = time.perf_counter()
    status, _, _ = integ.advance(y, mode, 0, periods, counters=counters)
    dt = time.perf_counter() - t0
    if status:
        raise RuntimeError(f"integration failed (status {status})")
    return dt / counters[0], int(counters[0]), int(counters[1])


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--periods", type=int, default=100)
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--elements", type=int, nargs="+", default=[1, 4, 16])
    args = ap.parse_args(argv)

    laws = {"bilinear": BladePair(friction="bilinear")}
    for n in args.elements:
        laws[f"iwan n={n}"] = BladePair(friction="iwan", friction_options={"elements": n})
    integs = {}
    for name, cfg in laws.items():
        t0 = time.perf_counter()
        integs[name] = HybridIntegrator(cfg.build(), steps_per_period=1000)
        per_step(integs[name], 2)     # warm-up (JIT dispatch, caches)
        print(f"{name:12s} kernel ready in {time.perf_counter() - t0:6.1f} s", flush=True)

    times = {name: [] for name in laws}
    events = {}
    for _ in range(args.rounds):
        for name, integ in integs.items():      # interleaved: one run of each law per round
            t, steps, ev = per_step(integ, args.periods)
            times[name].append(t)
            events[name] = ev / args.periods
    ref = statistics.median(times["bilinear"])
    print(f"\n{args.periods} periods x {args.rounds} rounds, 1000 steps per period, median per step:")
    print(f"{'law':12s} {'us/step':>8s} {'ratio':>6s} {'events/period':>14s}")
    for name in laws:
        med = statistics.median(times[name])
        print(f"{name:12s} {med * 1e6:8.3f} {med / ref:6.2f} {events[name]:14.1f}")


if __name__ == "__main__":
    main()
