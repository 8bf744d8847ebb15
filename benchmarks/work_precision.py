"""Work-precision of the kernel: error against cost for the step and the event tolerance.

    python benchmarks/work_precision.py

For both friction laws at the defaults (period-1 motion), 20 excitation periods
from rest (Coulomb: ~265 contact and stick/slip events, bilinear: ~520), the
final state of the kernel with ``steps_per_period`` S = 250 ... 32000 (doubling) and
``event_tol`` = 1e-6, 1e-10, 1e-13, and without event location (``event_tol = 1``:
the switch happens at the end of the step), against a reference run (S = 64000,
``event_tol = 1e-13``; its own error is estimated from the S = 32000 run, as for a
4th-order method, and printed). Error = max over the state of
``|y - y_ref| / (gap, gap * omega)``, i.e. in the paper's units X = x / gap,
X' = v / (gap omega). Cost = thread CPU time (minimum of interleaved repeats;
shown relative to the S = 1000, event_tol = 1e-10 default) and right-hand-side
evaluations. Observed order = -d log(error) / d log(S) between neighbours.

Writes docs/benchmarks/work_precision.json and .png (the page docs/accuracy.md
summarises them).
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common as C  # noqa: E402

from blademodel.zheng2022 import BladePair  # noqa: E402
from blademodel.numeric import HybridIntegrator  # noqa: E402

LAWS = ["coulomb", "bilinear"]
STEPS = [250, 500, 1000, 2000, 4000, 8000, 16000, 32000]
TOLS = [1e-6, 1e-10, 1e-13, 1.0]
PERIODS = 20
REF_S, REF_TOL = 64000, 1e-13


def run(model, S, tol, periods=PERIODS):
    integ = HybridIntegrator(model, steps_per_period=S, event_tol=tol, check_stability=False)
    y = integ.initial_state()
    m0 = integ.mode_of(y)
    return C.kernel_runner(integ, y, m0, 0, periods)


def main():
    t_start = time.time()
    C.print_load("at start")
    results, summary = [], {}
    for law in LAWS:
        cfg = BladePair(friction=law)
        model = cfg.build()
        st, y_ref, _, c_ref = run(model, REF_S, REF_TOL)()
        _, y_half, _, _ = run(model, REF_S // 2, REF_TOL)()
        sc = C.scale_vector(cfg, y_ref.size)
        ref_err = C.state_error(y_half, y_ref, sc) / 15.0
        runners = {(S, tol): run(model, S, tol) for tol in TOLS for S in STEPS}
        outs = {k: f() for k, f in runners.items()}
        reps = 3
        times = C.interleaved(runners, reps)
        t_def = min(times[(1000, 1e-10)])
        rows = []
        for tol in TOLS:
            prev = None
            for S in STEPS:
                stt, y, _, c = outs[(S, tol)]
                err = C.state_error(y, y_ref, sc) if stt == 0 else math.nan
                order = None
                if prev is not None and err > 0 and prev > 0:
                    order = -math.log(err / prev) / math.log(2.0)
                rows.append(dict(law=law, event_tol=tol, S=S, error=err, order=order, status=int(stt),
                                 rhs=int(c[3]), events=int(c[1]), location_substeps=int(c[2]),
                                 cost=min(times[(S, tol)]) / t_def, time_s=min(times[(S, tol)])))
                prev = err
        results += rows
        summary[law] = {"reference_error_estimate": ref_err, "reference_events": int(c_ref[1]),
                        "scale": sc.tolist()}
        print(f"{law}: reference S={REF_S} event_tol={REF_TOL:g}: {int(c_ref[1])} events in {PERIODS} periods, "
              f"estimated error {ref_err:.1e}", flush=True)

    la = C.print_load("at end")
    for law in LAWS:
        print(f"\n{law}, {PERIODS} periods from rest (cost relative to S=1000, event_tol=1e-10)")
        sub = [r for r in results if r["law"] == law]
        # one wide table: rows S, columns per tolerance (error, order, cost)
        wide = []
        for S in STEPS:
            row = {"S": S}
            for tol in TOLS:
                r = next(x for x in sub if x["S"] == S and x["event_tol"] == tol)
                key = "none" if tol >= 1 else f"{tol:g}"
                row[f"e_{key}"], row[f"o_{key}"], row[f"c_{key}"] = r["error"], r["order"], r["cost"]
            wide.append(row)
        cols = [("S", "S", "d")]
        for tol in TOLS:
            key = "none" if tol >= 1 else f"{tol:g}"
            head = "no location" if tol >= 1 else f"tol {tol:g}"
            cols += [(f"e_{key}", f"{head}: error", ".1e"), (f"o_{key}", "order", ".1f"), (f"c_{key}", "cost", ".2f")]
        print(C.table(wide, cols))
    # fitted orders over S = 500 ... 8000 (above every floor of the located runs)
    fits = {}
    for law in LAWS:
        for tol in TOLS:
            pts = [(r["S"], r["error"]) for r in results
                   if r["law"] == law and r["event_tol"] == tol and 500 <= r["S"] <= 8000]
            s, e = np.log([p[0] for p in pts]), np.log([p[1] for p in pts])
            fits[f"{law}, " + ("no location" if tol >= 1 else f"event_tol {tol:g}")] = float(-np.polyfit(s, e, 1)[0])
    print("\nobserved order, least-squares fit over S = 500 ... 8000:")
    print("  " + ", ".join(f"{k}: {v:.2f}" for k, v in fits.items()))
    out = {"benchmark": "work_precision", "periods": PERIODS, "reference": {"S": REF_S, "event_tol": REF_TOL},
           "steps": STEPS, "event_tols": TOLS, "machine": C.machine(), "load_end": la, "rows": results,
           "summary": summary, "fitted_orders": fits, "elapsed_s": time.time() - t_start}
    path = C.write_json("work_precision", out)
    plot(results, path.with_suffix(".png"))
    print(f"\nwrote {path} and {path.with_suffix('.png').name}  ({time.time() - t_start:.0f} s)")


def plot(results, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.3), sharey=True)
    for ax, law in zip(axes, LAWS):
        for tol, mk in zip(TOLS, "osd^"):
            sub = sorted((r for r in results if r["law"] == law and r["event_tol"] == tol), key=lambda r: r["S"])
            lab = "no event location (event_tol = 1)" if tol >= 1 else f"event_tol = {tol:g}"
            ax.loglog([r["rhs"] for r in sub], [max(r["error"], 1e-16) for r in sub], marker=mk, label=lab)
            if tol == 1e-10:
                for r in sub:
                    ax.annotate(str(r["S"]), (r["rhs"], max(r["error"], 1e-16)), fontsize=6,
                                xytext=(3, 3), textcoords="offset points")
        x = np.array([4e5, 4e6])
        ax.loglog(x, 1e-4 * (x / x[0]) ** -4, "k:", lw=0.8, label="slope -4")
        ax.set_title(f"{law} (defaults), {PERIODS} periods from rest")
        ax.set_xlabel("right-hand-side evaluations")
        ax.grid(True, which="major", alpha=0.3)
    axes[0].set_ylabel("final-state error (units of gap, gap*omega)")
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


if __name__ == "__main__":
    main()
