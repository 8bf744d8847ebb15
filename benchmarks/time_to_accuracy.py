"""Time to accuracy: the cost of reaching a final-state error, kernel against solve_ivp.

    python benchmarks/time_to_accuracy.py [--law coulomb|bilinear]

The periodic case (defaults: gap 4e-5 m, gamma 4, F0 60 N; Coulomb friction unless
``--law bilinear``), 200 excitation periods from rest (~2600 events). For each
target error 1e-4 ... 1e-10 (max over the state of |y - y_ref| / (gap, gap*omega),
the paper's units), the cheapest run that reaches it:

* the kernel with ``steps_per_period`` from the ladder 250 ... 48000 (event_tol 1e-10);
* the kernel with ``method="rk8"`` and predicted event roots (``event_location``), S from
  200 ... 2000 (event_tol 1e-13, so the location never limits it); the last columns
  compare ``solve_ivp`` with the cheaper of the two kernel runs (the higher-order method
  where it wins);
* the C baseline (benchmarks/rk4_blades.c, gcc -O3) at the kernel's S (same error);
* ``solve_ivp`` (DOP853 with events and restarts, ``numeric/reference.py``) with
  rtol from the ladder 1e-4 ... 1e-11 (atol = rtol * (gap, gap*omega)).

Reference: Richardson extrapolation of kernel runs at S = 32000 and 64000
(event_tol 1e-13), the kernel being 4th order through events (see
work_precision.py); its agreement with the tightest solve_ivp run is printed.
Cost: thread CPU time (kernel and C: minimum of interleaved repeats; solve_ivp:
one run each, seconds long) and wall time, and right-hand-side evaluations.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common as C  # noqa: E402

from blademodel.zheng2022 import BladePair  # noqa: E402
from blademodel.numeric import HybridIntegrator  # noqa: E402
from blademodel.numeric.reference import simulate_reference  # noqa: E402

PERIODS = 200
TARGETS = [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10]
S_LADDER = [250, 500, 1000, 2000, 4000, 8000, 16000, 32000, 48000]
S8_LADDER = [200, 250, 350, 500, 700, 1000, 1400, 2000]
RTOLS = [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11]
TOL = 1e-10


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--law", default="coulomb", choices=["coulomb", "bilinear"])
    args = ap.parse_args(argv)
    t_start = time.time()
    C.print_load("at start")
    cfg = BladePair(friction=args.law)
    model = cfg.build()
    T = cfg.period

    def integ(S, tol=TOL, **kw):
        return HybridIntegrator(model, steps_per_period=S, event_tol=tol, check_stability=False, **kw)

    i0 = integ(1000)
    y0 = i0.initial_state()
    m0 = i0.mode_of(y0)
    sc = C.scale_vector(cfg, i0.n_state)
    _, y64, _, c64 = C.kernel_runner(integ(64000, 1e-13), y0, m0, 0, PERIODS)()
    _, y32, _, _ = C.kernel_runner(integ(32000, 1e-13), y0, m0, 0, PERIODS)()
    y_ref = y64 + (y64 - y32) / 15.0
    print(f"reference ready: {int(c64[1])} events in {PERIODS} periods; |y64k - y_ref| = "
          f"{C.state_error(y64, y_ref, sc):.1e}  ({time.time() - t_start:.0f} s)", flush=True)

    # kernel and C ladders, interleaved repeats
    ckern = C.CKernel(("-O3",))
    kr = {S: C.kernel_runner(integ(S), y0, m0, 0, PERIODS) for S in S_LADDER}
    krun = {S: f() for S, f in kr.items()}
    k8 = {S: C.kernel_runner(integ(S, 1e-13, method="rk8", event_location="predicted"), y0, m0, 0, PERIODS)
          for S in S8_LADDER}
    k8run = {S: f() for S, f in k8.items()}
    funcs = {}
    for S in S_LADDER:
        funcs[("k", S)] = kr[S]
        funcs[("c", S)] = (lambda S=S: ckern.run(cfg, model, y0, m0, i0.period, S, 0, PERIODS, TOL))
    for S in S8_LADDER:
        funcs[("k8", S)] = k8[S]
    cpu = C.interleaved(funcs, 2)
    wall = C.interleaved(funcs, 1, clock=time.perf_counter)
    kern_rows = []
    for S in S_LADDER:
        st, y, _, c = krun[S]
        kern_rows.append(dict(S=S, error=C.state_error(y, y_ref, sc) if st == 0 else np.inf, rhs=int(c[3]),
                              cpu=min(cpu[("k", S)]), wall=min(wall[("k", S)]), c_cpu=min(cpu[("c", S)])))
    rk8_rows = []
    for S in S8_LADDER:
        st, y, _, c = k8run[S]
        rk8_rows.append(dict(S=S, error=C.state_error(y, y_ref, sc) if st == 0 else np.inf, rhs=int(c[3]),
                             events=int(c[1]), cpu=min(cpu[("k8", S)]), wall=min(wall[("k8", S)])))
    print(f"kernel ladder done ({time.time() - t_start:.0f} s)", flush=True)

    # solve_ivp ladder (stops once the smallest target is reached)
    simulate_reference(model, T, rtol=1e-6, atol=1e-6 * sc)  # lambdify outside the timing
    ivp_rows = []
    for rtol in RTOLS:
        w0, t0 = time.perf_counter(), C.cpu_time()
        r = simulate_reference(model, PERIODS * T, rtol=rtol, atol=rtol * sc)
        ivp_rows.append(dict(rtol=rtol, error=C.state_error(r.y_final, y_ref, sc), rhs=int(r.nfev),
                             events=int(r.n_events), cpu=C.cpu_time() - t0, wall=time.perf_counter() - w0))
        print(f"  solve_ivp rtol {rtol:.0e}: error {ivp_rows[-1]['error']:.1e}, {ivp_rows[-1]['cpu']:.1f} s CPU "
              f"({time.time() - t_start:.0f} s)", flush=True)
        if ivp_rows[-1]["error"] <= min(TARGETS):
            break

    rows = []
    for E in TARGETS:
        k = min((r for r in kern_rows if r["error"] <= E), key=lambda r: r["cpu"], default=None)
        v = min((r for r in ivp_rows if r["error"] <= E), key=lambda r: r["cpu"], default=None)
        rows.append(dict(target=E, S=k and k["S"], k_err=k and k["error"], k_rhs=k and k["rhs"],
                         c_over_k=k and k["c_cpu"] / k["cpu"],
                         rtol=v and v["rtol"], v_err=v and v["error"], v_rhs=v and v["rhs"],
                         cpu_ratio=(v["cpu"] / k["cpu"]) if (k and v) else None,
                         wall_ratio=(v["wall"] / k["wall"]) if (k and v) else None,
                         rhs_ratio=(v["rhs"] / k["rhs"]) if (k and v) else None,
                         k_vs_default=k and k["cpu"] / next(r["cpu"] for r in kern_rows if r["S"] == 1000)))
        k8 = min((r for r in rk8_rows if r["error"] <= E), key=lambda r: r["cpu"], default=None)
        best = min([r for r in (k, k8) if r], key=lambda r: r["cpu"], default=None)
        rows[-1].update(S8=k8 and k8["S"], k8_err=k8 and k8["error"],
                        rk4_over_rk8=(k["cpu"] / k8["cpu"]) if (k and k8) else None,
                        best="rk8" if best is not None and best is k8 else ("rk4" if best else None),
                        cpu_ratio_best=(v["cpu"] / best["cpu"]) if (best and v) else None)
    la = C.print_load("at end")
    print(f"\n{args.law}, defaults, {PERIODS} periods from rest; cheapest run reaching each target "
          "(kernel event_tol 1e-10; '-' = not reached by the ladder)")
    print(C.table(rows, [("target", "target error", ".0e"), ("S", "kernel S", "d"), ("k_err", "its error", ".1e"),
                         ("k_vs_default", "cost / S=1000", ".2f"), ("c_over_k", "C/kernel", ".2f"),
                         ("rtol", "ivp rtol", ".0e"), ("v_err", "its error", ".1e"),
                         ("cpu_ratio", "ivp/kernel CPU", ".0f"), ("wall_ratio", "ivp/kernel wall", ".0f"),
                         ("rhs_ratio", "ivp/kernel rhs evals", ".2f")]))
    print("\nwith the eighth-order method (RK8, predicted event roots, event_tol 1e-13) where it is cheaper")
    print(C.table(rows, [("target", "target error", ".0e"), ("S8", "RK8 S", "d"), ("k8_err", "its error", ".1e"),
                         ("rk4_over_rk8", "RK4/RK8 CPU", ".1f"), ("best", "cheaper", ""),
                         ("cpu_ratio_best", "ivp/best kernel CPU", ".0f")]))
    tight = ivp_rows[-1]
    print(f"\nreference vs tightest solve_ivp (rtol {tight['rtol']:.0e}): {tight['error']:.1e}")
    out = {"benchmark": "time_to_accuracy", "law": args.law, "periods": PERIODS, "event_tol": TOL,
           "machine": C.machine(), "load_end": la, "targets": rows, "kernel_ladder": kern_rows,
           "ivp_ladder": ivp_rows, "rk8_ladder": rk8_rows,
           "reference": "Richardson(S=32000, 64000, event_tol 1e-13)",
           "elapsed_s": time.time() - t_start}
    name = "time_to_accuracy" + ("" if args.law == "coulomb" else f"_{args.law}")
    path = C.write_json(name, out)
    plot(kern_rows, ivp_rows, path.with_suffix(".png"), args.law)
    print(f"\nwrote {path} and {path.with_suffix('.png').name}  ({time.time() - t_start:.0f} s)")


def plot(kern_rows, ivp_rows, path, law):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    ax.loglog([r["cpu"] for r in kern_rows], [r["error"] for r in kern_rows], "o-", label="kernel (S ladder)")
    ax.loglog([r["c_cpu"] for r in kern_rows], [r["error"] for r in kern_rows], "x--", label="C -O3 (same S)")
    ax.loglog([r["cpu"] for r in ivp_rows], [r["error"] for r in ivp_rows], "s-", label="solve_ivp DOP853 (rtol ladder)")
    for r in kern_rows:
        ax.annotate(str(r["S"]), (r["cpu"], r["error"]), fontsize=6, xytext=(3, 3), textcoords="offset points")
    for r in ivp_rows:
        ax.annotate(f"{r['rtol']:.0e}", (r["cpu"], r["error"]), fontsize=6, xytext=(3, 3), textcoords="offset points")
    for E in TARGETS:
        ax.axhline(E, color="0.85", lw=0.6, zorder=0)
    ax.set_xlabel("thread CPU time, s (shared machine: compare, do not quote)")
    ax.set_ylabel("final-state error after 200 periods")
    ax.set_title(f"time to accuracy, {law} (defaults)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


if __name__ == "__main__":
    main()
