"""Per-step cost of the compiled kernel against the alternatives, on the paper's model.

    python benchmarks/per_step.py [--quick]

Cases: Coulomb and bilinear friction at the defaults (gap 4e-5 m, gamma 4, F0 60 N,
both period-1) and the chaotic bilinear case gamma = 10. The kernel runs with its
defaults, ``steps_per_period = 1000``, ``event_tol = 1e-10`` (events located by
bisection), from rest.

Compared, side by side in this process, repeats interleaved, minimum CPU time of
the thread (so time the OS gave to the other jobs on this shared machine does not
count):

(a) ``benchmarks/rk4_blades.c``: a minimal hand-written C RK4 of the same
    equations with the same mode switching, guards and bisection, compiled by this
    script with plain ``gcc -O3`` (no ``-march=native``, no ``-ffast-math``; a
    ``-O3 -march=native`` build is shown for information: Numba compiles for the
    host CPU). Before timing, its final state and event counts are checked
    against the kernel's.
(a') the kernel with the template's generic ``rk4_step`` (``loop.py`` calling
    ``rhs``) instead of the fused, generated one: the kernel as it was before the
    fused step, compiled here without cache, for the before/after record.
(b) pure Python: the *generated module itself* run with ``NUMBA_DISABLE_JIT=1`` in a
    subprocess (exactly the kernel's code, interpreted).
(c) ``scipy.integrate.solve_ivp`` (DOP853, events, restarts: ``numeric/reference.py``)
    at the tolerance that gives the *same final-state error* as the kernel run,
    errors measured against a very accurate run (the kernel at 64000 steps per
    period, ``event_tol = 1e-13``, itself checked against ``solve_ivp`` at
    ``rtol = 1e-12``). The cost at the kernel's error is interpolated (log-log)
    between the bracketing tolerances of a ladder.

Goals (the project's issue): kernel <= 1.3 x the C code per step; kernel >= 100 x
faster than solve_ivp to the same error.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
import types

import numpy as np

sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parent))
import _common as C  # noqa: E402

from blademodel.zheng2022 import BladePair  # noqa: E402
from blademodel.numeric import HybridIntegrator, simulate  # noqa: E402
from blademodel.numeric.reference import simulate_reference  # noqa: E402
from blademodel.numeric.contract import N_COUNTERS  # noqa: E402

CASES = [("coulomb P1", dict(friction="coulomb")),
         ("bilinear P1", dict(friction="bilinear")),
         ("bilinear chaos g=10", dict(friction="bilinear", gamma=10.0))]
S, TOL = 1000, 1e-10
GOAL_C, GOAL_IVP = 1.3, 100.0


def generic_step_module(integ):
    """The kernel's generated module with the template's generic rk4_step (no cache)."""
    src = integ.compiled.path.read_text()
    a = src.index("# ---- the template's rk4_step, fused")
    b = src.index("rhs = njit(", a)
    src = (src[:a] + src[b:]).replace("njit(cache=True)", "njit")
    mod = types.ModuleType("generic_step_" + integ.compiled.path.stem)
    exec(compile(src, f"<generic {integ.compiled.path.name}>", "exec"), mod.__dict__)
    return mod


def generic_runner(mod, integ, y0, mode0, start, end):
    n = integ.n_state
    args = (np.empty(0), np.empty((0, n)), np.empty(0, dtype=np.int64), np.empty((end - start, n)),
            np.empty(0), np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64))

    def run():
        y = np.array(y0, dtype=float)
        c = np.zeros(N_COUNTERS, dtype=np.int64)
        st, mode, _, _ = mod.integrate(y, mode0, integ.p, integ.period, integ.steps_per_period, start, end, start, 1,
                                    integ.event_tol, integ.max_events_per_step, False, np.zeros(0), *args, c,
                                    np.zeros_like(integ._goff), False)
        return st, y, mode, c
    return run


PY_CODE = """
import json, time, numpy as np
from blademodel.zheng2022 import BladePair
from blademodel.numeric import HybridIntegrator
cfg = BladePair(**{cfg})
integ = HybridIntegrator(cfg.build(), steps_per_period={S}, event_tol={TOL})
y = integ.initial_state(); c = np.zeros(N_COUNTERS, dtype=np.int64)
t0 = time.thread_time()
st, mode, _ = integ.advance(y, integ.mode_of(y), 0, {P}, counters=c)
dt = time.thread_time() - t0
print(json.dumps({{"time": dt, "counters": c.tolist(), "y": y.tolist(), "python_only": integ.module.integrate.__class__.__name__}}))
"""


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer repeats")
    args = ap.parse_args(argv)
    t_start = time.time()
    reps = 7 if args.quick else 21
    C.print_load("at start")
    print(__doc__.split("\n\n")[0].strip())
    c_o3 = C.CKernel(("-O3",))
    c_nat = C.CKernel(("-O3", "-march=native"))
    print(f"C baseline: {c_o3.command}   (info: {c_nat.command})\n")

    rows, ivp_rows, details = [], [], {}
    for name, kw in CASES:
        cfg = BladePair(**kw)
        model = cfg.build()
        integ = HybridIntegrator(model, steps_per_period=S, event_tol=TOL)
        y0 = integ.initial_state()
        m0 = integ.mode_of(y0)
        sc = C.scale_vector(cfg, integ.n_state)
        chaotic = cfg.gamma > 8

        # -- verification: C against the kernel, from rest
        nv = 10 if chaotic else 50
        _, yk, _, ck = C.kernel_runner(integ, y0, m0, 0, nv)()
        st, yc, _, cc = c_o3.run(cfg, model, y0, m0, integ.period, S, 0, nv, TOL)
        rel = float(np.max(np.abs(yc - yk)) / np.max(np.abs(yk)))
        same_events = bool(np.array_equal(ck[:4], cc))
        ok = st == 0 and same_events and rel <= 1e-8

        # -- per-step timing, interleaved
        np_ = 20
        fk = C.kernel_runner(integ, y0, m0, 0, np_)
        _, _, _, counters = fk()
        gmod = generic_step_module(integ)
        fg = generic_runner(gmod, integ, y0, m0, 0, np_)
        _, yg, _, _ = fg()
        generic_identical = bool(np.array_equal(yg, fk()[1]))
        funcs = {"kernel": fk, "generic": fg,
                 "C": lambda: c_o3.run(cfg, model, y0, m0, integ.period, S, 0, np_, TOL),
                 "Cnative": lambda: c_nat.run(cfg, model, y0, m0, integ.period, S, 0, np_, TOL)}
        times = C.interleaved(funcs, reps)
        steps = int(counters[0])
        tmin = {k: min(v) for k, v in times.items()}
        pair = np.median(np.array(times["kernel"]) / np.array(times["C"]))

        # -- pure Python: the generated module interpreted, in a subprocess
        p_py = 2
        kt = C.interleaved({"kernel": C.kernel_runner(integ, y0, m0, 0, p_py)}, 5)["kernel"]
        py = C.run_python(PY_CODE.format(cfg=repr(kw), S=S, TOL=TOL, P=p_py), NUMBA_DISABLE_JIT=1)
        kt += C.interleaved({"kernel": C.kernel_runner(integ, y0, m0, 0, p_py)}, 5)["kernel"]
        py_ratio = py["time"] / min(kt)

        row = dict(case=name, verified=ok, c_rel_diff=rel, events=int(counters[1]) / np_,
                   bis_per_step=counters[2] / steps, rhs_per_step=counters[3] / steps,
                   bisection_share=4 * counters[2] / counters[3],
                   ns_C=tmin["C"] / steps * 1e9, kernel_C=tmin["kernel"] / tmin["C"], kernel_C_median=pair,
                   generic_C=tmin["generic"] / tmin["C"], native_C=tmin["Cnative"] / tmin["C"],
                   python_kernel=py_ratio, python_C=py_ratio * tmin["kernel"] / tmin["C"],
                   generic_identical=generic_identical, goal_C=tmin["kernel"] / tmin["C"] <= GOAL_C)
        rows.append(row)
        details[name] = {"times_s": times, "steps": steps, "counters": counters.tolist(), "python": py,
                         "verification_periods": nv, "c_counters": cc.tolist(), "kernel_counters": ck.tolist()}
        print(f"  {name}: C verified={ok} (max rel diff {rel:.1e} after {nv} periods, "
              f"identical event counts {same_events}); kernel/C = {row['kernel_C']:.2f}", flush=True)

        # -- solve_ivp to the same error. The chaotic case is compared over 2 periods
        # only: from the third period on, the reference runs themselves part ways (a
        # contact closing where the Jenkins stick guard starts at zero, see the README).
        n_ivp = 2 if chaotic else 10
        T = integ.period
        ref = simulate(model, periods=n_ivp, steps_per_period=64000, event_tol=1e-13).final_state
        chk = simulate_reference(model, n_ivp * T, rtol=1e-12, atol=1e-12 * sc)
        ref_agree = C.state_error(chk.y_final, ref, sc)
        fk_ivp = C.kernel_runner(integ, y0, m0, 0, n_ivp)
        _, yk10, _, ck10 = fk_ivp()
        err_k = C.state_error(yk10, ref, sc)
        lad, ktimes = [], []
        for rtol in [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10]:
            ktimes += C.interleaved({"k": fk_ivp}, 3)["k"]
            t0 = C.cpu_time()
            r = simulate_reference(model, n_ivp * T, rtol=rtol, atol=rtol * sc)
            dt = C.cpu_time() - t0
            lad.append({"rtol": rtol, "time": dt, "nfev": r.nfev, "events": r.n_events,
                        "error": C.state_error(r.y_final, ref, sc)})
            below = [d for d in lad if d["error"] <= err_k]
            if below and (len(below) >= 2 or len(lad) > len(below)):
                break  # bracketed (or two runs at least as accurate)
        tk = min(ktimes)
        # cheapest ladder run at least as accurate; log-log interpolation at err_k
        ok_runs = [d for d in lad if d["error"] <= err_k]
        cheapest = min(ok_runs, key=lambda d: d["time"]) if ok_runs else None
        interp = None
        for lo, hi in zip(lad, lad[1:]):   # errors usually fall along the ladder
            if (lo["error"] - err_k) * (hi["error"] - err_k) <= 0 and lo["error"] != hi["error"]:
                w = (math.log(err_k) - math.log(lo["error"])) / (math.log(hi["error"]) - math.log(lo["error"]))
                interp = {"time": math.exp(math.log(lo["time"]) + w * (math.log(hi["time"]) - math.log(lo["time"]))),
                          "nfev": math.exp(math.log(lo["nfev"]) + w * (math.log(hi["nfev"]) - math.log(lo["nfev"])))}
                break
        ivp = dict(case=name, periods=n_ivp, err_kernel=err_k, ref_check=ref_agree,
                   rtol_match=cheapest["rtol"] if cheapest else None,
                   err_ivp=cheapest["error"] if cheapest else None,
                   ivp_kernel=cheapest["time"] / tk if cheapest else None,
                   ivp_kernel_interp=interp["time"] / tk if interp else None,
                   nfev_ratio=cheapest["nfev"] / ck10[3] if cheapest else None,
                   nfev_ratio_interp=interp["nfev"] / ck10[3] if interp else None)
        ivp["goal_ivp"] = (ivp["ivp_kernel_interp"] or ivp["ivp_kernel"] or 0) >= GOAL_IVP
        ivp_rows.append(ivp)
        details[name]["ivp_ladder"] = lad
        details[name]["kernel_time_ivp_horizon_s"] = tk
        details[name]["kernel_rhs_ivp_horizon"] = int(ck10[3])
        print(f"  {name}: solve_ivp ladder done ({time.time() - t_start:.0f} s so far)", flush=True)

    la = C.print_load("at end")
    print("\nPer-step cost, ratios (min thread CPU time of", reps, "interleaved repeats, 20 periods from rest,",
          f"S = {S}, event_tol = {TOL:g})")
    print(C.table(rows, [("case", "case", ""), ("verified", "C verified", ""), ("c_rel_diff", "C rel.diff", ".0e"),
                         ("events", "events/period", ".1f"), ("bis_per_step", "bisect./step", ".2f"),
                         ("rhs_per_step", "rhs/step", ".2f"), ("bisection_share", "bisect. share", ".0%"),
                         ("kernel_C", "kernel/C", ".2f"), ("kernel_C_median", "(median)", ".2f"),
                         ("generic_C", "generic step/C", ".2f"), ("native_C", "C native/C", ".2f"),
                         ("python_kernel", "pure Python/kernel", ".0f"), ("python_C", "pure Python/C", ".0f")]))
    print("\nC -O3 absolute (for orientation only, shared machine): "
          + ", ".join(f"{r['case']} {r['ns_C']:.0f} ns/step" for r in rows))
    print("\nsolve_ivp (DOP853, events, restarts) to the kernel's final-state error, from rest; "
          "error = max |y - y_ref| / (gap, gap*omega)")
    print(C.table(ivp_rows, [("case", "case", ""), ("periods", "periods", "d"), ("err_kernel", "kernel error", ".1e"),
                             ("ref_check", "ref vs ivp(1e-12)", ".0e"),
                             ("rtol_match", "rtol reaching it", ".0e"), ("err_ivp", "its error", ".1e"),
                             ("ivp_kernel", "ivp/kernel time", ".0f"), ("ivp_kernel_interp", "(interp.)", ".0f"),
                             ("nfev_ratio", "ivp/kernel rhs", ".1f"), ("nfev_ratio_interp", "(interp.)", ".1f")]))
    worst_c = max(r["kernel_C"] for r in rows)
    worst_ivp = min((r["ivp_kernel_interp"] or r["ivp_kernel"] or 0.0) for r in ivp_rows)
    print(f"\nGoal kernel <= {GOAL_C} x C per step: {'MET' if worst_c <= GOAL_C else 'MISSED'} "
          f"(worst case {worst_c:.2f} x)")
    print(f"Goal kernel >= {GOAL_IVP:.0f} x faster than solve_ivp to the same error: "
          f"{'MET' if worst_ivp >= GOAL_IVP else 'MISSED'} (worst case {worst_ivp:.0f} x)")
    print(f"Before the fused RK4 step (generic step column): worst {max(r['generic_C'] for r in rows):.2f} x C")

    out = {"benchmark": "per_step", "settings": {"steps_per_period": S, "event_tol": TOL, "repeats": reps,
                                                 "c_command": c_o3.command, "clock": "thread CPU time, min"},
           "machine": C.machine(), "load_end": la, "per_step": rows, "solve_ivp": ivp_rows, "details": details,
           "goals": {"kernel_over_C_max": GOAL_C, "worst_kernel_over_C": worst_c, "met_C": worst_c <= GOAL_C,
                     "ivp_over_kernel_min": GOAL_IVP, "worst_ivp_over_kernel": worst_ivp,
                     "met_ivp": worst_ivp >= GOAL_IVP},
           "elapsed_s": time.time() - t_start}
    path = C.write_json("per_step", out)
    plot(rows, ivp_rows, path.with_suffix(".png"))
    print(f"\nwrote {path} and {path.with_suffix('.png').name}  ({time.time() - t_start:.0f} s)")


def plot(rows, ivp_rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4))
    names = [r["case"] for r in rows]
    x = np.arange(len(rows))
    series = [("kernel", "kernel_C"), ("kernel, generic step", "generic_C"), ("C -O3 -march=native", "native_C"),
              ("pure Python", "python_C")]
    w = 0.2
    for i, (lab, key) in enumerate(series):
        vals = [r[key] for r in rows]
        a.bar(x + (i - 1.5) * w, vals, w, label=lab)
    a.axhline(1.0, color="k", lw=0.8)
    a.axhline(GOAL_C, color="r", ls="--", lw=0.8, label=f"goal {GOAL_C} x")
    a.set_yscale("log")
    a.set_xticks(x, names, fontsize=8)
    a.set_ylabel("cost per step / C -O3")
    a.legend(fontsize=7)
    a.set_title("per-step cost relative to hand-written C")
    vals = [(r["ivp_kernel_interp"] or r["ivp_kernel"] or 0.0) for r in ivp_rows]
    b.bar(x, vals, 0.5, color="C4")
    b.axhline(GOAL_IVP, color="r", ls="--", lw=0.8, label=f"goal {GOAL_IVP:.0f} x")
    b.set_yscale("log")
    b.set_ylim(10, 3000)
    b.set_xticks(x, names, fontsize=8)
    b.set_ylabel("solve_ivp time / kernel time")
    b.set_title("to the same final-state error")
    b.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


if __name__ == "__main__":
    main()
