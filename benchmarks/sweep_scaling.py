"""Sweep throughput: serial, a process pool and a Dask LocalCluster, 1 and 2 workers.

    python benchmarks/sweep_scaling.py [--points 100] [--budget 240]

A bifurcation sweep of the bilinear pair over gamma in [6, 10], 500 transient + 200
recorded periods per point (700 periods, S = 1000), run through
``blademodel.sweep.run_study`` into a NetCDF file, with

* ``workers=1``: the serial executor (in this process),
* ``workers=2``: the process pool,
* ``scheduler=<address>`` of a ``distributed.LocalCluster`` with 1 and 2 worker
  processes (one thread each).

The points are split into two interleaved halves (even and odd gamma indices) and
the executors take turns on each half (serial, pool, Dask 1, Dask 2, then again),
so that a change of the machine's load hits all of them alike. Every executor is
warm before timing: this process and every Dask worker have loaded the kernel
(cluster start-up and the workers' kernel loading are reported separately; pool
workers are forked from this warm process). Wall time; the load average is printed
at every turn. If the estimated time exceeds the budget, the number of points is
reduced and the output says so.
"""

from __future__ import annotations

import argparse
import logging
import resource
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common as C  # noqa: E402

from blademodel.sweep import Axis, RunSettings, Study, run_study  # noqa: E402
from blademodel.sweep.point import run_point  # noqa: E402

BASE = {"model": "blade_pair", "friction": "bilinear"}
RUN = RunSettings(transient=500, periods=200)


def study(values, name):
    return Study(name=name, base=BASE, sweep={"gamma": Axis(values=[float(v) for v in values])}, run=RUN)


def _warm(base, run):
    """Load the kernel in a Dask worker (run by client.run on every worker)."""
    import time as _t
    t0 = _t.perf_counter()
    run_point(base, {"gamma": 6.0}, run)
    return _t.perf_counter() - t0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=100)
    ap.add_argument("--budget", type=float, default=240.0, help="seconds for the timed part (estimate)")
    args = ap.parse_args(argv)
    t_start = time.time()
    C.print_load("at start")
    from distributed import Client, LocalCluster
    logging.getLogger("distributed").setLevel(logging.ERROR)

    run = RUN.model_dump()
    # warm this process and estimate the per-point cost (serial)
    run_point(BASE, {"gamma": 6.0}, run)
    pilot = np.linspace(6, 10, 4)
    t0 = time.perf_counter()
    for g in pilot:
        run_point(BASE, {"gamma": float(g)}, run)
    per_point = (time.perf_counter() - t0) / len(pilot)
    # serial 1 + pool 2 workers ~0.5-1 + dask 1 + dask 2 ~0.5-1, plus overheads
    factor = 1.0 + 0.8 + 1.1 + 0.9
    n = args.points
    est = per_point * n * factor
    reduced = False
    if est > args.budget:
        n = max(8, int(args.budget / (per_point * factor)) // 2 * 2)
        reduced = True
    note = (f"REDUCED from {args.points} to {n} points to fit the {args.budget:.0f} s budget "
            f"(estimated {per_point:.2f} s per point serially, {est:.0f} s for {args.points} points)"
            if reduced else f"{n} points (estimated {per_point:.2f} s per point serially, ~{est:.0f} s in all)")
    print(note, flush=True)
    gammas = np.linspace(6.0, 10.0, n)
    halves = [gammas[0::2], gammas[1::2]]

    # clusters, started and warmed outside the timing
    clusters, startup = {}, {}
    for k in (1, 2):
        t0 = time.perf_counter()
        cl = LocalCluster(n_workers=k, threads_per_worker=1, processes=True, dashboard_address=None,
                          silence_logs=logging.ERROR)
        client = Client(cl)
        t1 = time.perf_counter()
        loads = client.run(_warm, BASE, run)
        startup[k] = {"cluster_start_s": t1 - t0, "worker_kernel_load_s": sorted(loads.values())}
        clusters[k] = (cl, client)
    print("clusters ready: " + ", ".join(f"{k} worker(s): start {v['cluster_start_s']:.1f} s, kernel load "
                                         f"{max(v['worker_kernel_load_s']):.1f} s" for k, v in startup.items()),
          flush=True)

    configs = [("serial (workers=1)", 1, dict(workers=1)), ("process pool, 2 workers", 2, dict(workers=2)),
               ("Dask LocalCluster, 1 worker", 1, dict(scheduler=clusters[1][0].scheduler_address)),
               ("Dask LocalCluster, 2 workers", 2, dict(scheduler=clusters[2][0].scheduler_address))]
    times = {c[0]: [] for c in configs}
    cpu = {c[0]: [] for c in configs}
    loads = []

    def cpu_now(kw):
        """CPU seconds of this process + its reaped children (pool) + the Dask workers of ``kw``."""
        ch = resource.getrusage(resource.RUSAGE_CHILDREN)
        total = time.process_time() + ch.ru_utime + ch.ru_stime
        if "scheduler" in kw:
            client = next(c for cl, c in clusters.values() if cl.scheduler_address == kw["scheduler"])
            total += sum(client.run(time.process_time).values())
        return total
    with tempfile.TemporaryDirectory() as tmp:
        for h, vals in enumerate(halves):
            st = study(vals, f"bench_half{h}")
            for ic, (name, _, kw) in enumerate(configs):
                out = Path(tmp) / f"config{ic}_{h}.nc"
                la = C.print_load(f"before {name}, half {h + 1}")
                loads.append(la[0])
                c0 = cpu_now(kw)
                t0 = time.perf_counter()
                run_study(st, out, progress=None, **kw)
                times[name].append(time.perf_counter() - t0)
                cpu[name].append(cpu_now(kw) - c0)
                print(f"    {len(vals)} points in {times[name][-1]:.1f} s", flush=True)
        # the results are identical across executors (points are deterministic)
        import xarray as xr
        ref = xr.load_dataset(Path(tmp) / "config0_0.nc")
        same = all(np.array_equal(xr.load_dataset(p)["poincare_x1"].values, ref["poincare_x1"].values,
                                  equal_nan=True) for p in Path(tmp).glob("*_0.nc"))
    for cl, client in clusters.values():
        client.close()
        cl.close()

    rows = []
    t_serial = sum(times[configs[0][0]])
    t_dask1 = sum(times[configs[2][0]])
    for name, workers, _ in configs:
        total = sum(times[name])
        thr = n / total
        one = t_dask1 if name.startswith("Dask") else t_serial
        rows.append(dict(config=name, workers=workers, time_s=total, points_per_s=thr,
                         per_worker=thr / workers, speedup_vs_serial=t_serial / total,
                         efficiency=(one / total) / workers, points_per_cpu_s=n / sum(cpu[name]),
                         cpu_share=sum(cpu[name]) / (total * workers)))
    la = C.print_load("at end")
    print(f"\n{n} points, gamma in [6, 10], bilinear, {RUN.transient} + {RUN.periods} periods, S = {RUN.steps_per_period}"
          f"; two interleaved halves; wall time. {'(' + note + ')' if reduced else ''}")
    print(C.table(rows, [("config", "executor", ""), ("workers", "workers", "d"),
                         ("points_per_s", "points/s", ".2f"), ("per_worker", "points/s/worker", ".2f"),
                         ("speedup_vs_serial", "speed-up vs serial", ".2f"),
                         ("efficiency", "parallel efficiency", ".0%"), ("points_per_cpu_s", "points/CPU-s", ".2f"),
                         ("cpu_share", "CPU obtained per worker", ".0%")]))
    print("parallel efficiency: pool vs serial, Dask 2 vs Dask 1 (throughput per worker / single-worker throughput);"
          "\npoints/CPU-s counts the CPU time of this process, its pool children and the Dask workers; 'CPU obtained'"
          " = that CPU time / (wall time x workers): below 100 % the workers waited for a core held by other jobs")
    print(f"identical Poincare samples across executors: {same}")
    print(f"load average during the runs: min {min(loads):.2f}, max {max(loads):.2f} on {C.machine()['cpus']} cpus "
          "(other jobs share the machine: 2-worker efficiency is bounded by the free cores)")
    out = {"benchmark": "sweep_scaling", "points": n, "requested_points": args.points, "reduced": reduced,
           "note": note, "run": RUN.model_dump(), "law": "bilinear", "gamma": [6.0, 10.0], "rows": rows,
           "times_s": times, "cpu_s": cpu, "dask_startup": startup, "loads_before_each": loads, "identical_results": same,
           "machine": C.machine(), "load_end": la, "elapsed_s": time.time() - t_start}
    path = C.write_json("sweep_scaling", out)
    plot(rows, path.with_suffix(".png"), n)
    print(f"\nwrote {path} and {path.with_suffix('.png').name}  ({time.time() - t_start:.0f} s)")


def plot(rows, path, n):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 3.8))
    names = [r["config"] for r in rows]
    ax.barh(names, [r["points_per_s"] for r in rows], color=["C0", "C0", "C1", "C1"])
    for i, r in enumerate(rows):
        ax.text(r["points_per_s"], i, f"  {r['points_per_s']:.2f}/s, eff. {r['efficiency']:.0%}", va="center", fontsize=8)
    ax.set_xlabel(f"points per second ({n}-point sweep, 700 periods each)")
    ax.invert_yaxis()
    ax.set_xlim(0, max(r["points_per_s"] for r in rows) * 1.5)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


if __name__ == "__main__":
    main()
