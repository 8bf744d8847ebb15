"""Scaling to bladed disks: cold set-up, warm per-step cost and memory against the number of contacts.

    python benchmarks/scale.py [--full] [--repeats 7] [--skip-cold] [--skip-warm] [--reuse-cold]

Models: ``BladedDisk(blades=N, friction=law, engine_order=1).build()``, a ring of N
2-DOF blades with N shroud contacts (run by the per-contact kernel,
``kernel="auto"``), for the laws ``none`` (frictionless), ``coulomb`` and
``bilinear``; the paper's pair ``BladePair(friction=law)`` (one contact, run by the
product-mode kernel) is the reference. Settings: the defaults, ``S = 1000`` steps
per period, ``event_tol = 1e-10``.

1. Cold set-up. Every measurement is a fresh interpreter with its own empty,
   temporary ``BLADEMODEL_CACHE_DIR`` (kernels are shared by law kind, so in one
   cache only the first N of a law would compile). Phases, CPU time of the
   subprocess (``time.process_time``: all its threads, not the time the OS gave to
   other jobs), wall time for information:

   * interpreter start (CPU the interpreter spent before the probe's first line);
   * import: ``import blademodel.config, blademodel.numeric``;
   * build: the config and ``.build()``;
   * set-up: ``make_integrator(model)`` (numeric tables or symbolic derivation with
     SymPy, code generation, stability check), ``mode_of`` and ``advance`` over
     zero periods, i.e. every entry point compiled by Numba (as in
     ``benchmarks/startup.py``); split into *derive + generate* (``cached_tables``
     and ``compile_contact_kernel``, or ``compile_model`` for the pair) and the rest
     (*compile + first calls*);
   * first period: ``advance`` over period 0.

   Cold set-up = process start to the end of the first period. N in {2, 8, 32, 96}
   by default, all of 2 ... 96 with ``--full``; one repeat each (a cold compile takes
   10-30 s). Peak memory: ``ru_maxrss`` of the subprocess.
2. Warm per-step cost, in this process with the kernel cache warm (the user's
   cache, ``$BLADEMODEL_CACHE_DIR`` or ``~/.cache/blademodel``; the first call
   compiles into it if needed and is not timed): thread CPU time of ``advance`` over
   20 periods after a 20-period transient, divided by the steps and by the number
   of contacts, every N in 2 ... 96 and every law, repeats interleaved over all
   cases, minimum taken. Events per step and bisection sub-steps per event from
   the kernel's counters. The pair is shown on the product kernel (the reference)
   and, for information, on the per-contact kernel (``kernel="contact"``).

   With engine order 1 the work per contact is not the same at every N: the phase
   lag between neighbours is 2 pi / N, so the shrouds of a large ring hardly move
   against each other (at N = 96 no contact closes at all). The disks are therefore
   also run with engine order N / 2 (neighbours in anti-phase, as the pair's blades):
   then every contact of every even N follows the same motion (identical events per
   contact per step, see the table), and the per-contact cost measures the kernel,
   not the physics. The kernel steps each cluster (a contact whose guard crossed
   and what is coupled to it) through its events on its own, so the coincident
   events of a tuned ring are located cluster by cluster, as in a real disk; a
   third series adds 1 % random mistuning (``mistuning_std = 0.01``, seed 0): the
   same events per contact per step. The goal is evaluated on all three series,
   over all N and (in brackets) over N >= 4: N = 2 is two contacts between the same
   two blades, where the fixed cost of a step weighs most per contact. A fourth
   series runs the mistuned rings with ``local_events=False`` (every event splits
   the whole ring's step, as the kernel did before clusters), side by side in the
   same run: the ratio of the two costs, by N, is what clusters save.

   The cost of a run is split into the smooth step's (a fifth series: the tuned
   EO = N/2 rings with their contacts open, gap 1 m, no events) and what its events
   add, per event: where the events per contact change with N (engine order 1),
   "linear in the contacts" means both are flat across N, not the sum. Each timed run
   is a whole multiple of 20 periods lasting at least ``MIN_RUN_S`` (0.15 s): the
   small rings' 20-period runs (15 ms) were within the shared machine's noise; seven
   repeats, as three left one model's two measurements 1.4x apart.

Takes about 14 min on the shared 2-core machine (822 s in the last run; cold part 6 min, 15 compiles;
``--full`` adds 9 more); ``--skip-cold`` / ``--skip-warm`` run one part (nothing written).

Goals (the issue "Bladed disks"): cold set-up of the 96-blade disk <= 2 x that of the
pair; per-step cost per contact within a factor 1.5 across N (max / min); peak memory
of the cold run at N = 96 < 600 MB.
"""

from __future__ import annotations

import argparse
import functools
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common as C  # noqa: E402

LAWS = ("none", "coulomb", "bilinear")
N_ALL = (2, 4, 8, 16, 32, 64, 96)
N_COLD = (2, 8, 32, 96)
S, TOL = 1000, 1e-10
TRANSIENT, PERIODS = 20, 20
GOAL_COLD, GOAL_FLAT, GOAL_MB = 2.0, 1.5, 600.0
#: The controlled series of the warm part: engine order N/2, the same motion at every contact for every even N.
SYM = "disk EO=N/2"
#: The same, mistuned (random stiffness deviations, std 1 %, seed 0): events of different contacts no longer coincide.
MIS = "disk EO=N/2 mist."
#: The mistuned series stepped without clusters (``local_events=False``: every event splits the whole ring's
#: step), side by side: what the clusters save.
WHOLE = "disk EO=N/2 mist., whole-ring events"
MISTUNING = 0.01
#: The tuned EO=N/2 rings with their contacts open (gap 1 m): no events, the smooth step's cost alone.
OPEN = "disk EO=N/2, contacts open"
#: A timed run lasts at least this long (whole multiples of PERIODS): a 20-period run of a small ring takes
#: about 15 ms, where the shared machine's noise made one model's two measurements in one run differ by 1.4x.
MIN_RUN_S = 0.15
#: Warm series of disks, each evaluated against the flatness goal.
SERIES = (("disk", "", "engine order 1"), (SYM, "_sym", "engine order N/2, tuned"),
          (MIS, "_mis", "engine order N/2, mistuned 1 %"))

PROBE = r"""
import time, sys, json, resource
w0 = time.time(); c0 = time.process_time(); t0 = time.perf_counter()
import blademodel.config, blademodel.numeric
from blademodel.numeric import make_integrator
t1 = time.perf_counter(); c1 = time.process_time()
args = json.loads(sys.argv[1])
if args["model"] == "pair":
    from blademodel.zheng2022 import BladePair
    model = BladePair(friction=args["law"]).build()
else:
    from blademodel.config import BladedDisk
    model = BladedDisk(blades=args["blades"], friction=args["law"], engine_order=1).build()
t2 = time.perf_counter(); c2 = time.process_time()
from blademodel.numeric.kernels import choose_kernel
kernel = choose_kernel(model, "auto")
if kernel == "contact":
    from blademodel.numeric.contact_tables import cached_tables
    from blademodel.numeric.contact_kernel import compile_contact_kernel
    cached_tables(model)           # SymPy derivation of the tables (cached on disk)
    compile_contact_kernel(model)  # code generation per law kind (memoised in the process)
else:
    from blademodel.numeric.compiled import compile_model
    compile_model(model)           # symbolic derivation and code generation (memoised)
tg = time.perf_counter(); cg = time.process_time()
integ = make_integrator(model, steps_per_period=args["S"], event_tol=args["tol"])
y = integ.initial_state()
m = integ.mode_of(y)
integ.advance(y, m, 0, 0)
t3 = time.perf_counter(); c3 = time.process_time()
import numpy as np
from blademodel.numeric.contract import N_COUNTERS
cnt = np.zeros(N_COUNTERS, dtype=np.int64)
st, m, _ = integ.advance(y, m, 0, 1, counters=cnt)
t4 = time.perf_counter(); c4 = time.process_time()
w4 = time.time()
print(json.dumps({"kernel": getattr(integ, "kernel", "product"), "contacts": len(model.contacts),
                  "status": st, "counters": cnt.tolist(), "wall_start": w0, "wall_ready": w4,
                  "cpu": {"interpreter": c0, "import": c1 - c0, "build": c2 - c1, "generate": cg - c2,
                          "compile": c3 - cg, "setup": c3 - c2, "first_period": c4 - c3, "total": c4},
                  "wall": {"import": t1 - t0, "build": t2 - t1, "generate": tg - t2, "compile": t3 - tg,
                           "setup": t3 - t2, "first_period": t4 - t3},
                  "maxrss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""


def source_state() -> dict:
    """Digest of the package's sources (and the git commit, if any): the working tree is
    shared, and an edit during the run would mix two versions of the code."""
    import hashlib
    h = hashlib.sha256()
    for path in sorted((C.ROOT / "blademodel").rglob("*.py")):
        h.update(str(path.relative_to(C.ROOT)).encode())
        h.update(path.read_bytes())
    out = {"digest": h.hexdigest()[:16], "commit": None, "dirty": None}
    try:
        git = ["git", "-C", str(C.ROOT)]
        out["commit"] = subprocess.run(git + ["rev-parse", "HEAD"], capture_output=True, text=True,
                                       check=True).stdout.strip()
        out["dirty"] = subprocess.run(git + ["status", "--porcelain", "blademodel"], capture_output=True, text=True,
                                      check=True).stdout.split("\n")[:-1]
    except (OSError, subprocess.CalledProcessError):
        pass
    return out


def cold_run(model: str, law: str, blades: int | None) -> dict:
    """One cold measurement: a fresh interpreter with an empty, temporary kernel cache."""
    args = json.dumps({"model": model, "law": law, "blades": blades, "S": S, "tol": TOL})
    with tempfile.TemporaryDirectory(prefix="bm_scale_") as cache:
        env = C.python_env(BLADEMODEL_CACHE_DIR=cache)
        w0 = time.time()
        out = subprocess.run([sys.executable, "-c", PROBE, args], capture_output=True, text=True, env=env)
        w1 = time.time()
    if out.returncode:
        raise RuntimeError(f"cold run {model} {law} {blades} failed:\n{out.stderr[-3000:]}")
    res = json.loads(out.stdout.strip().splitlines()[-1])
    res["wall"]["interpreter"] = res["wall_start"] - w0
    res["wall"]["total"] = res["wall_ready"] - w0     # launch to the end of the first period
    res["wall"]["process"] = w1 - w0
    return res


def cold_part(ns, laws) -> list[dict]:
    """Pairs first, then the disks by N, the laws interleaved within each N."""
    jobs = [("pair", law, None) for law in laws] + [("disk", law, n) for n in ns for law in laws]
    rows = []
    for k, (model, law, n) in enumerate(jobs):
        la = C.print_load(f"cold {k + 1}/{len(jobs)}: {model} {law}" + (f" N={n}" if n else ""))
        r = cold_run(model, law, n)
        c, w = r["cpu"], r["wall"]
        row = dict(model=model, law=law, N=r["contacts"] if model == "disk" else 1, blades=n or 2,
                   kernel=r["kernel"], status=r["status"], load1=la[0],
                   interpreter=c["interpreter"], imp=c["import"], build=c["build"], generate=c["generate"],
                   compile=c["compile"], setup=c["setup"], first=c["first_period"], total=c["total"],
                   wall_total=w["total"], wall_setup=w["setup"], maxrss_mb=r["maxrss_mb"],
                   first_events=r["counters"][1], raw=r)
        rows.append(row)
        print(f"    CPU {c['total']:.1f} s (set-up {c['setup']:.1f} s), wall {w['total']:.1f} s, "
              f"max RSS {r['maxrss_mb']:.0f} MB, status {r['status']}", flush=True)
    return rows


def _reused_cold(src, ns) -> list[dict] | None:
    """The cold part of the last written run, if it measured these sources and these N (else None)."""
    path = C.OUT / "scale.json"
    if not path.exists():
        return None
    old = json.loads(path.read_text())
    if old.get("sources_end", {}).get("digest") != src["digest"] or old["settings"]["n_cold"] != list(ns):
        print("  --reuse-cold: the last run measured other sources or other N; measuring again", flush=True)
        return None
    print(f"  cold part reused from {path.name} (sources {src['digest']}, measured {old['machine']['date']})",
          flush=True)
    return old["cold"]


def warm_part(ns, laws, repeats: int) -> tuple[list[dict], dict]:
    """Per-step thread CPU time with the cache warm, all cases interleaved."""
    from blademodel.config import BladedDisk
    from blademodel.zheng2022 import BladePair
    from blademodel.numeric import make_integrator
    from blademodel.numeric.contract import C_LOCATION_SUBSTEPS, C_EVENTS, C_STEPS, N_COUNTERS

    cases = {}
    for law in laws:
        cases[("pair", law, 1)] = (BladePair(friction=law).build(), "auto")
        cases[("pair/contact", law, 1)] = (BladePair(friction=law).build(), "contact")
        for n in ns:
            cases[("disk", law, n)] = (BladedDisk(blades=n, friction=law, engine_order=1).build(), "auto")
        for n in ns:
            cases[(SYM, law, n)] = (BladedDisk(blades=n, friction=law, engine_order=n // 2).build(), "auto")
        for n in ns:
            cases[(MIS, law, n)] = (BladedDisk(blades=n, friction=law, engine_order=n // 2, mistuning_std=MISTUNING,
                                               mistuning_seed=0).build(), "auto")
        for n in ns:
            cases[(WHOLE, law, n)] = (cases[(MIS, law, n)][0], "auto")
        for n in ns:
            cases[(OPEN, law, n)] = (BladedDisk(blades=n, friction=law, engine_order=n // 2, gap=1.0).build(), "auto")
    funcs, info = {}, {}
    for key, (model, kernel) in cases.items():
        t0 = time.perf_counter()
        integ = make_integrator(model, kernel=kernel, steps_per_period=S, event_tol=TOL,
                                **({"local_events": False} if key[0] == WHOLE else {}))
        y = integ.initial_state()
        m = integ.mode_of(y)
        st, m, _ = integ.advance(y, m, 0, TRANSIENT)   # the first call (compiles or loads) and the transient
        if st:
            raise RuntimeError(f"{key}: transient failed with status {st}")
        y_T, m_T = y.copy(), m.copy() if isinstance(m, np.ndarray) else m

        def run(integ=integ, y_T=y_T, m_T=m_T, periods=PERIODS):
            yy = y_T.copy()
            c = np.zeros(N_COUNTERS, dtype=np.int64)
            st, _, _ = integ.advance(yy, m_T, TRANSIENT, TRANSIENT + periods, counters=c)
            return st, c
        c0 = C.cpu_time()
        st, cnt = run()
        if st:
            raise RuntimeError(f"{key}: timed interval failed with status {st}")
        reps = max(1, int(np.ceil(MIN_RUN_S / max(C.cpu_time() - c0, 1e-6))))
        if reps > 1:
            run = functools.partial(run, periods=reps * PERIODS)
            st, cnt = run()
        funcs[key] = run
        info[key] = {"kernel": getattr(integ, "kernel", "product"), "counters": cnt.tolist(),
                     "setup_s": time.perf_counter() - t0}
        print(f"  warm case {key[0]} {key[1]} N={key[2]} ready ({info[key]['setup_s']:.1f} s, "
              f"{info[key]['kernel']} kernel)", flush=True)
    loads = []
    times = {k: [] for k in funcs}
    for r in range(repeats):
        loads.append(C.print_load(f"warm repeat {r + 1}/{repeats}")[0])
        for k, v in C.interleaved(funcs, 1).items():
            times[k] += v
    rows = []
    for (model, law, n), ts in times.items():
        c = info[(model, law, n)]["counters"]
        steps = c[C_STEPS]
        tmin = min(ts)
        rows.append(dict(model=model, law=law, N=n, kernel=info[(model, law, n)]["kernel"],
                         us_step=tmin / steps * 1e6, us_step_contact=tmin / steps / n * 1e6,
                         spread=float(np.median(ts) / tmin), events_step=c[C_EVENTS] / steps,
                         events_step_contact=c[C_EVENTS] / steps / n,
                         bis_event=c[C_LOCATION_SUBSTEPS] / c[C_EVENTS] if c[C_EVENTS] else None,
                         steps=steps, counters=c, times_s=ts))
    _event_costs(rows)
    return rows, {"loads_before_each_repeat": loads}


def _event_costs(rows):
    """Each run's cost split into the smooth step's (the same ring with its contacts open, same N and law)
    and what its events add: ``us_event``, microseconds per event (None without events)."""
    smooth = {(r["law"], r["N"]): r["us_step"] for r in rows if r["model"] == OPEN}
    for r in rows:
        base = smooth.get((r["law"], r["N"]))
        r["us_event"] = ((r["us_step"] - base) / r["events_step"]
                         if base is not None and r["events_step"] > 0 and r["model"] != OPEN else None)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--full", action="store_true", help="cold set-up for every N (2 ... 96), not only 2, 8, 32, 96")
    ap.add_argument("--repeats", type=int, default=7, help="interleaved repeats of the warm part")
    ap.add_argument("--reuse-cold", action="store_true",
                    help="take the cold part from docs/benchmarks/scale.json if it was measured on these sources")
    ap.add_argument("--skip-cold", action="store_true", help="only the warm part (no JSON/PNG written)")
    ap.add_argument("--skip-warm", action="store_true", help="only the cold part (no JSON/PNG written)")
    args = ap.parse_args(argv)
    t_start = time.time()
    C.print_load("at start")
    src0 = source_state()
    print(f"blademodel sources {src0['digest']}" + (f", commit {src0['commit'][:10]}" if src0["commit"] else "")
          + (f", uncommitted: {' '.join(x.split()[-1] for x in src0['dirty'])}" if src0["dirty"] else ""), flush=True)
    ns_cold = N_ALL if args.full else N_COLD
    reused = _reused_cold(src0, ns_cold) if args.reuse_cold and not args.skip_cold else None
    cold = [] if args.skip_cold else reused or cold_part(ns_cold, LAWS)
    t_cold = time.time() - t_start
    warm, wmeta = ([], {}) if args.skip_warm else warm_part(N_ALL, LAWS, args.repeats)
    la = C.print_load("at end")
    src1 = source_state()
    if src1["digest"] != src0["digest"]:
        print(f"WARNING: the blademodel sources changed during the run ({src0['digest']} -> {src1['digest']}): "
              "the measurements mix two versions of the code", flush=True)

    fmt_c = [("model", "model", ""), ("law", "law", ""), ("N", "contacts", "d"), ("kernel", "kernel", ""),
             ("interpreter", "interp.", ".2f"), ("imp", "import", ".2f"), ("build", "build", ".3f"),
             ("generate", "derive+gen.", ".2f"), ("compile", "compile+1st calls", ".2f"),
             ("setup", "set-up", ".2f"), ("first", "1st period", ".3f"), ("total", "cold total", ".2f"),
             ("wall_total", "(wall)", ".1f"), ("maxrss_mb", "max RSS MB", ".0f"), ("load1", "load", ".1f")]
    if cold:
        print(f"\nCold set-up, fresh process, empty kernel cache each (CPU s of the subprocess; wall for "
              f"information; S = {S}; one run each)")
        print(C.table(cold, fmt_c))
    if warm:
        print(f"\nWarm per-step cost (min thread CPU time of {args.repeats} interleaved repeats, a multiple of {PERIODS} "
              f"periods lasting at least {MIN_RUN_S:g} s after a {TRANSIENT}-period transient, S = {S}, event_tol = {TOL:g})")
        print(C.table(warm, [("model", "model", ""), ("law", "law", ""), ("N", "contacts", "d"),
                             ("kernel", "kernel", ""), ("us_step", "us/step", ".2f"),
                             ("us_step_contact", "us/step/contact", ".3f"), ("spread", "median/min", ".2f"),
                             ("events_step", "events/step", ".4f"), ("us_event", "us/event", ".1f"),
                             ("events_step_contact", "events/step/contact", ".4f"),
                             ("bis_event", "sub-steps/event", ".1f")]))

    goals = {}
    if cold and warm:
        print("\nGoals, side by side (cold: CPU time of the subprocess; per step: min thread CPU time)")
        glines = []
        for law in LAWS:
            pair = next(r for r in cold if r["model"] == "pair" and r["law"] == law)
            d96 = next(r for r in cold if r["model"] == "disk" and r["law"] == law and r["N"] == max(ns_cold))
            g = dict(law=law, cold_pair=pair["total"], cold_96=d96["total"], cold_ratio=d96["total"] / pair["total"],
                     cold_ratio_wall=d96["wall_total"] / pair["wall_total"], setup_ratio=d96["setup"] / pair["setup"],
                     rss_96=d96["maxrss_mb"], rss_pair=pair["maxrss_mb"])
            for series, tag, _ in SERIES:
                disk = [r for r in warm if r["model"] == series and r["law"] == law]
                per = [r["us_step_contact"] for r in disk]
                g["flat" + tag] = max(per) / min(per)
                g["flat_where" + tag] = f"max N={disk[int(np.argmax(per))]['N']}, min N={disk[int(np.argmin(per))]['N']}"
                g["flat_met" + tag] = g["flat" + tag] <= GOAL_FLAT
                per4 = [r["us_step_contact"] for r in disk if r["N"] >= 4]
                g["flat4" + tag] = max(per4) / min(per4)
            # the cost model behind "linear in the contacts": a smooth step costs a * N, an event b
            smooth = [r["us_step_contact"] for r in warm if r["model"] == OPEN and r["law"] == law]
            g["flat_open"] = max(smooth) / min(smooth)
            g["flat_met_open"] = g["flat_open"] <= GOAL_FLAT
            for series, tag, _ in SERIES:
                ev = [r["us_event"] for r in warm if r["model"] == series and r["law"] == law
                      and r["us_event"] is not None]
                g["event_us" + tag] = [min(ev), max(ev)] if ev else None
            whole = {r["N"]: r["us_step_contact"] for r in warm if r["model"] == WHOLE and r["law"] == law}
            local = {r["N"]: r["us_step_contact"] for r in warm if r["model"] == MIS and r["law"] == law}
            g["whole_over_local"] = {n: whole[n] / local[n] for n in sorted(local)}
            g["flat_whole"] = max(whole.values()) / min(whole.values())
            g["cold_met"] = g["cold_ratio"] <= GOAL_COLD
            g["rss_met"] = g["rss_96"] < GOAL_MB
            goals[law] = g
            glines.append(g)
        yn = {True: "MET", False: "MISSED"}
        print(C.table([dict(g, cm=yn[g["cold_met"]], rm=yn[g["rss_met"]]) for g in glines],
                      [("law", "law", ""), ("cold_pair", "pair cold s", ".1f"), ("cold_96", "N=96 cold s", ".1f"),
                       ("cold_ratio", f"N=96/pair (goal <= {GOAL_COLD:g})", ".2f"),
                       ("cold_ratio_wall", "(wall)", ".2f"), ("setup_ratio", "(set-up only)", ".2f"), ("cm", "", ""),
                       ("rss_96", f"max RSS N=96 MB (goal < {GOAL_MB:.0f})", ".0f"), ("rm", "", "")]))
        print(f"per-step cost per contact, max/min across N = {', '.join(map(str, N_ALL))} (goal <= {GOAL_FLAT:g}); "
              "in brackets: N >= 4")
        print(C.table([dict(law=g["law"], **{f"v{t}": f"{g['flat' + t]:.2f} ({g['flat_where' + t]}) "
                                                      f"{yn[g['flat_met' + t]]} [{g['flat4' + t]:.2f}]"
                                             for _, t, _ in SERIES})
                       for g in glines], [("law", "law", "")] + [(f"v{t}", lab, "") for _, t, lab in SERIES]))
        print("the same split into a smooth step per contact (the tuned EO=N/2 rings with their contacts open: "
              "max/min across N, goal <= 1.5) and the cost of an event (the run's cost less the open ring's, per "
              "event: least and largest microseconds across N)")
        print(C.table([dict(law=g["law"], open=f"{g['flat_open']:.2f} {yn[g['flat_met_open']]}",
                            **{f"e{t}": (f"{g['event_us' + t][0]:.1f} ... {g['event_us' + t][1]:.1f}"
                                         if g["event_us" + t] else "-") for _, t, _ in SERIES})
                       for g in glines], [("law", "law", ""), ("open", "smooth step per contact, max/min", "")]
                      + [(f"e{t}", f"us per event, {lab}", "") for _, t, lab in SERIES]))
        print("mistuned series stepped without clusters (every event splits the whole ring's step), same run: "
              "its cost per contact-step / the clustered one's, by N; its own max/min across N")
        print(C.table([dict(law=g["law"], **{f"n{n}": f"{v:.2f}" for n, v in g["whole_over_local"].items()},
                            flat=g["flat_whole"]) for g in glines],
                      [("law", "law", "")] + [(f"n{n}", f"N={n}", "") for n in N_ALL] + [("flat", "max/min", ".2f")]))
        checks = [("cold set-up of the 96-blade disk / the pair's", "cold_met", f"<= {GOAL_COLD:g}")]
        checks += [(f"per-step cost per contact, max/min across N, {lab}", "flat_met" + t, f"<= {GOAL_FLAT:g}")
                   for _, t, lab in SERIES]
        checks += [("peak memory of the cold run at N = 96", "rss_met", f"< {GOAL_MB:.0f} MB")]
        for name, key, goal in checks:
            met = [law for law in LAWS if goals[law][key]]
            print(f"  {name} (goal {goal}): " + ("MET for all laws" if len(met) == len(LAWS) else
                                                  f"MISSED for {', '.join(x for x in LAWS if x not in met)}"
                                                  + (f" (met for {', '.join(met)})" if met else "")))
        loads = [r["load1"] for r in cold] + wmeta["loads_before_each_repeat"]
        print(f"load average during the runs: min {min(loads):.2f}, max {max(loads):.2f} on {C.machine()['cpus']} "
              "cpus (shared machine; cold times are CPU times of the subprocess, per-step times thread CPU time)")

    if args.skip_cold or args.skip_warm:
        print(f"\npartial run (--skip-*): nothing written  ({time.time() - t_start:.0f} s)")
        return
    out = {"benchmark": "scale", "settings": {"steps_per_period": S, "event_tol": TOL, "transient": TRANSIENT,
                                              "periods": PERIODS, "repeats": args.repeats, "full": args.full,
                                              "engine_order": [1, "N/2"], "mistuning_std": MISTUNING, "n_cold": list(ns_cold), "n_warm": list(N_ALL)},
           "sources_start": src0, "sources_end": src1, "cold": cold, "warm": warm, "goals": goals, "warm_meta": wmeta, "machine": C.machine(), "load_end": la,
           "cold_elapsed_s": t_cold, "cold_reused": reused is not None, "elapsed_s": time.time() - t_start}
    path = C.write_json("scale", out)
    plot(cold, warm, path.with_suffix(".png"))
    print(f"\nwrote {path} and {path.with_suffix('.png').name}  ({time.time() - t_start:.0f} s)")


def plot(cold, warm, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a, b, c) = plt.subplots(1, 3, figsize=(15, 4.8))
    col = {"none": "C0", "coulomb": "C1", "bilinear": "C2"}
    for law in LAWS:
        d = [r for r in cold if r["model"] == "disk" and r["law"] == law]
        p = next(r for r in cold if r["model"] == "pair" and r["law"] == law)
        a.plot([r["N"] for r in d], [r["total"] for r in d], "o-", color=col[law], label=f"disk, {law}")
        a.axhline(p["total"], color=col[law], ls="--", lw=0.9, label=f"pair, {law}")
        c.plot([r["N"] for r in d], [r["maxrss_mb"] for r in d], "o-", color=col[law], label=f"disk, {law}")
        c.axhline(p["maxrss_mb"], color=col[law], ls="--", lw=0.9)
        w = [r for r in warm if r["model"] == "disk" and r["law"] == law]
        b.plot([r["N"] for r in w], [r["us_step_contact"] for r in w], "o-", color=col[law], label=f"EO=1, {law}")
        w = [r for r in warm if r["model"] == SYM and r["law"] == law]
        b.plot([r["N"] for r in w], [r["us_step_contact"] for r in w], "s:", color=col[law], ms=4,
               label=f"EO=N/2, {law}")
        w = [r for r in warm if r["model"] == MIS and r["law"] == law]
        b.plot([r["N"] for r in w], [r["us_step_contact"] for r in w], "^-.", color=col[law], ms=4,
               label=f"EO=N/2 mistuned 1 %, {law}")
        w = [r for r in warm if r["model"] == OPEN and r["law"] == law]
        b.plot([r["N"] for r in w], [r["us_step_contact"] for r in w], "d-", color=col[law], ms=3, lw=0.6,
               alpha=0.6, label=f"contacts open (smooth step), {law}")
        w = [r for r in warm if r["model"] == WHOLE and r["law"] == law]
        b.plot([r["N"] for r in w], [r["us_step_contact"] for r in w], "x--", color=col[law], ms=4, lw=0.8,
               label=f"mistuned, whole-ring events, {law}")
        wp = next(r for r in warm if r["model"] == "pair" and r["law"] == law)
        b.axhline(wp["us_step_contact"], color=col[law], ls="--", lw=0.9, label=f"pair, product kernel, {law}")
    a.set_xscale("log", base=2)
    a.set_ylim(bottom=0)
    a.set_xlabel("contacts N (ring of N blades)")
    a.set_ylabel("CPU s, process start to end of 1st period")
    a.set_title("cold set-up, empty kernel cache", fontsize=9)
    a.legend(fontsize=6, ncol=2)
    b.set_xscale("log", base=2)
    b.set_yscale("log")
    b.set_xlabel("contacts N")
    b.set_ylabel("us per RK4 step per contact")
    b.set_title("warm per-step cost per contact (min thread CPU)", fontsize=9)
    b.legend(fontsize=5.5, ncol=2)
    c.axhline(GOAL_MB, color="r", ls=":", lw=0.9, label=f"goal < {GOAL_MB:.0f} MB")
    c.set_xscale("log", base=2)
    c.set_ylim(bottom=0)
    c.set_xlabel("contacts N")
    c.set_ylabel("max RSS of the cold process, MB")
    c.set_title("peak memory, cold run (dashed: pair)", fontsize=9)
    c.legend(fontsize=6)
    for ax in (a, b, c):
        ax.set_xticks([2, 4, 8, 16, 32, 64, 96], ["2", "4", "8", "16", "32", "64", "96"])
    fig.tight_layout()
    fig.savefig(path, dpi=110)


if __name__ == "__main__":
    main()
