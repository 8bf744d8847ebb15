"""Figures of the periodic-orbits page: the pair's FRFs, its period-doubled branch, a bladed disk's FRF.

Run from the repository root: ``python docs/tools/orbit_figures.py [--only NAME]``. Writes
``docs/figures/frf_pair.png``, ``period_doubling_bilinear.png``, ``nonsmooth_fold_coulomb.png``,
``frf_bladed_disk.png``, ``doublings_bladed_disk.png``, ``branch_points_twin_blades.png``,
``branch_points_ring.png`` and ``mistuned_envelope.png`` and prints what each branch found.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from blademodel.config import apply_overrides, load_config  # noqa: E402
from blademodel.zheng2022 import BladePair
from blademodel.orbits import branch_point_branch, continuation, period_doubled_branch  # noqa: E402
from blademodel.plots.branch import branch_figure, stability_runs  # noqa: E402

OUT = Path(__file__).resolve().parents[1] / "figures"


def _report(label, b, t):
    print(f"{label}: {len(b.params)} points, {int(np.sum(~b.stable))} unstable, special points: "
          f"{b.special_counts() or 'none'}; {b.message}; {time.process_time() - t:.0f} s CPU", flush=True)


def frf_pair():
    """Both laws, omega from 225 to 405 rad/s (the paper's 290 inside).

    Both branches reach 200 rad/s and 430 rad/s (the Coulomb one through a nonsmooth fold at
    420.684 rad/s: ``nonsmooth_fold``); docs/orbits.md and docs/frf.md.
    """
    fig = Figure(figsize=(9, 3.6))
    for j, law in enumerate(("coulomb", "bilinear")):
        t = time.process_time()
        b = continuation(BladePair(friction=law), "omega", 225.0, 405.0, ds_max=0.02, max_points=3000)
        _report(f"pair, {law}", b, t)
        ax = fig.add_subplot(1, 2, j + 1)
        branch_figure(b, "x1", ax=ax)
        ax.set_title(f"blade pair, {law} friction", fontsize=9)
        ax.set_xlabel("ω (rad/s)")
    fig.tight_layout()
    fig.savefig(OUT / "frf_pair.png", dpi=110)


def period_doubling():
    """The bilinear pair in gamma, with the branch born at its period doubling (Poincare samples)."""
    cfg = BladePair(friction="bilinear")
    t = time.process_time()
    b1 = continuation(cfg, "gamma", 7.0, 7.6)
    _report("pair, bilinear, gamma", b1, t)
    pd = b1.points("period-doubling")[0]
    t = time.process_time()
    b2 = period_doubled_branch(cfg, "gamma", pd, 7.0, 7.6)
    _report("  its period-2 branch", b2, t)
    branch_figure([b1, b2], "x1", quantity="section").savefig(OUT / "period_doubling_bilinear.png", dpi=110)


def _warm_sweep(law, values, periods=300):
    """First-harmonic amplitude of x1 at each value of omega by a warm-started sweep (``blademodel sweep`` with
    ``warm_start``: each value from the last one's state, the first from rest), ``periods`` discarded."""
    import tempfile

    from blademodel.sweep import Study, open_result, run_study
    study = Study(name="warm", base={"model": "blade_pair", "friction": law},
                  sweep={"omega": {"values": [float(w) for w in values]}},
                  run={"transient": periods, "periods": 2, "warm_start": True})
    with tempfile.TemporaryDirectory() as tmp:
        ds = open_result(run_study(study, Path(tmp) / "warm.nc", progress=None))
        return ds["harmonic1"].sel(state="x1").values


def nonsmooth_fold():
    """The Coulomb pair between 410 and 430 rad/s, continued up and down: a nonsmooth fold at 420.684, a smooth one at
    420.350, and warm sweeps up and down (0.01 rad/s apart, 300 periods a value) across both. Going down, the
    branch reaches the nonsmooth fold along its unstable arm and goes on down the stable one."""
    cfg = BladePair(friction="coulomb")
    branches = []
    for a, b_ in ((410.0, 430.0), (430.0, 410.0)):
        t = time.process_time()
        b = continuation(cfg, "omega", a, b_, ds=0.002, ds_max=0.002, max_points=3000, workers=1)
        _report(f"pair, coulomb, {a:g}-{b_:g}", b, t)
        branches.append(b)
    up_w = np.round(np.arange(420.20, 420.80, 0.01), 4)
    down_w = up_w[::-1]
    up = _warm_sweep("coulomb", [419.0, 420.0, *up_w])[2:]
    down = _warm_sweep("coulomb", [422.0, 421.0, *down_w])[2:]
    fig = Figure(figsize=(10, 4.2))
    axes = fig.subplots(1, 2, sharey=True)
    for ax, b, way in zip(axes, branches, ("up from 410 rad/s", "down from 430 rad/s")):
        branch_figure(b, "x1", ax=ax)
        ax.plot(up_w, up, "^", color="C3", ms=4, mfc="none", label="warm sweep, up")
        ax.plot(down_w, down, "v", color="C2", ms=4, mfc="none", label="warm sweep, down")
        ax.set_xlim(420.15, 420.85)
        ax.legend(fontsize=7)
        ax.set_title(f"continued {way}", fontsize=9)
        ax.set_xlabel("ω (rad/s)")
    inside = (branches[0].params > 420.15) & (branches[0].params < 420.85)
    hh = np.abs(branches[0].harmonics[inside, branches[0].state_names.index("x1")])
    axes[0].set_ylim(hh.min() * 0.998, hh.max() * 1.002)
    fig.suptitle("blade pair, Coulomb: a nonsmooth fold (a grazing, right) and a smooth fold (left)", fontsize=9)
    fig.tight_layout()
    fig.savefig(OUT / "nonsmooth_fold_coulomb.png", dpi=110)


def frf_bladed_disk():
    """The 24-blade tuned Coulomb ring (engine order 3) in omega from 270 to 300 rad/s (the ring's tangent)."""
    cfg = apply_overrides(load_config("models/bladed_disk_24.yaml"), {"blades": "24"})
    t = time.process_time()
    b = continuation(cfg, "omega", 270.0, 300.0, max_points=600, steps_per_period=600, transient=50,
                     progress=lambda k, v: print(f"  point {k}: omega = {v:.2f}", flush=True))
    _report("bladed disk, 24 blades", b, t)
    fig = branch_figure(b, "x1")
    fig.axes[0].set_title("24-blade shrouded disk, Coulomb, engine order 3: blade 1 (tuned: every blade alike)",
                          fontsize=9)
    fig.savefig(OUT / "frf_bladed_disk.png", dpi=110)


def doublings_bladed_disk():
    """The tuned 96-blade Coulomb ring (engine order 12, 600 steps a period) on the cyclic reduction from 271.5 to
    276.5 rad/s, and the period-doubled branch born at each of its doublings, followed on the reduced map too
    (docs/orbits_rings.md, *Period doublings on the reduced map*): Poincare samples of blade 1's x."""
    cfg = apply_overrides(load_config("models/bladed_disk_24.yaml"), {"blades": "96", "engine_order": "12"})
    kw = dict(steps_per_period=600, workers=2)
    t = time.process_time()
    b = continuation(cfg, "omega", 271.5, 276.5, cyclic=True, max_points=1000, **kw)
    _report("bladed disk, 96 blades, cyclic", b, t)
    branches = [b]
    for k, pd in enumerate(b.points("period-doubling"), 1):
        t = time.process_time()
        d = period_doubled_branch(cfg, "omega", pd, 271.5, 276.5, cyclic=True, max_points=300, parent=b, **kw)
        _report(f"  doubled branch {k} (from {pd.param:.6f})", d, t)
        branches.append(d)
    fig = Figure(figsize=(10, 4.4))
    ax = fig.add_subplot()
    labels = ["period-1 waves"] + [f"doubled at {pd.param:.2f}" for pd in b.points("period-doubling")]
    branch_figure(branches, "x1", quantity="section", ax=ax, labels=labels)
    ax.set_title("96-blade ring, Coulomb, EO 12, on T / 8: the period-1 waves and the branches doubled at "
                 + ", ".join(f"{pd.param:.2f}" for pd in b.points("period-doubling")) + " rad/s", fontsize=9)
    ax.set_xlabel("ω (rad/s)")
    ax.legend(fontsize=6, loc="center left", bbox_to_anchor=(1.01, 0.5))
    fig.tight_layout()
    fig.savefig(OUT / "doublings_bladed_disk.png", dpi=110)


def branch_points_twin_blades():
    """Two identical blades on gapped stops (``models/twin_blades_stops.yaml``) in omega from 900 to 2200 rad/s: the
    branch of orbits with the blades alike and the branches that cross it at its two branch points (docs/orbits_rings.md,
    *Branch points*), the first harmonic of each blade."""
    cfg = load_config("models/twin_blades_stops.yaml")
    t = time.process_time()
    b = continuation(cfg, "omega", 900.0, 2200.0)
    _report("twin blades, symmetric", b, t)
    branches = [b]
    for k, bp in enumerate(b.points("branch-point"), 1):
        t = time.process_time()
        c = branch_point_branch(cfg, "omega", bp, 900.0, 2200.0, crossed=b)
        _report(f"  crossing branch {k} (from {bp.param:.5f})", c, t)
        branches.append(c)
    # both run along the loop between the two branch points, from either end: one drawn
    branches = branches[:2]
    labels = ["blades alike", f"crossing at {b.points('branch-point')[0].param:.2f}"]
    fig = Figure(figsize=(10, 4.0))
    for j, state in enumerate(("x1", "x2")):
        ax = fig.add_subplot(1, 2, j + 1)
        branch_figure(branches, state, ax=ax, labels=labels)
        ax.set_xlim(1200, 1700)
        ax.set_ylim(8e-6, 2e-3)
        ax.set_yscale("log")
        ax.set_title(f"blade {j + 1}", fontsize=9)
        ax.set_xlabel("ω (rad/s)")
        if j == 0:
            ax.get_legend().remove()
        else:
            ax.legend(fontsize=6, loc="center left", bbox_to_anchor=(1.01, 0.5))
    fig.suptitle("two identical blades on gapped stops, driven alike: the blades alike, and the localised orbits "
                 "that cross that branch at its branch points", fontsize=9)
    fig.tight_layout()
    fig.savefig(OUT / "branch_points_twin_blades.png", dpi=110)


def branch_points_ring():
    """The tuned 24-blade Coulomb ring driven twice as hard (F0 = 120 N) on the cyclic reduction from 315 to 330
    rad/s, the branch crossing its travelling waves at their first branch point (on the map over T / 4), and
    integrations from rest (docs/orbits_rings.md, *Branch points*): the spread of the blades' first harmonics."""
    from blademodel.numeric.kernels import make_integrator
    cfg = apply_overrides(load_config("models/bladed_disk_24.yaml"), {"F0": "120"})
    t = time.process_time()
    b = continuation(cfg, "omega", 315.0, 330.0, cyclic=True)
    _report("24-blade ring, F0 = 120 N, cyclic", b, t)
    bp = b.points("branch-point")[0]
    t = time.process_time()
    c = branch_point_branch(cfg, "omega", bp, 315.0, 330.0, cyclic=True, ds_max=0.01)
    _report(f"  crossing branch (from {bp.param:.5f})", c, t)
    xs = [i for i, name in enumerate(c.state_names) if name.startswith("x")]

    def spread(h, columns=xs):
        a = np.abs(h[..., columns])
        return (a.max(axis=-1) - a.min(axis=-1)) * 1e6

    rest = []
    for w in np.linspace(316.0, 328.0, 13):
        ig = make_integrator(apply_overrides(cfg, {"omega": str(w)}).build())
        z = np.zeros(ig.n_state)
        _, mode, _ = ig.advance(z, ig.mode_of(z), 0, 400)
        rec = ig.record_buffer(ig.steps_per_period + 1)
        ig.advance(z, mode, 0, 1, n_transient=0, record=rec)
        X = rec[1][:-1][:, xs]
        rest.append((w, spread(2 * np.fft.rfft(X, axis=0)[1] / X.shape[0], slice(None))))
    fig = Figure(figsize=(10, 3.8))
    ax = fig.add_subplot(1, 2, 1)
    branch_figure([b, c], "x1", ax=ax, labels=["travelling waves", "crossing"])
    ax.set_title("blade 1", fontsize=9)
    ax.set_xlabel("ω (rad/s)")
    ax.legend(fontsize=6)
    ax = fig.add_subplot(1, 2, 2)
    for first, last, solid in stability_runs(c.stable):
        ax.plot(c.params[first:last + 1], spread(c.harmonics[first:last + 1]), "-" if solid else "--",
                color="C2" if solid else "C1")
    ax.plot(b.params, spread(b.harmonics), "-", color="C0", lw=1, label="travelling waves (all blades alike)")
    ax.plot(*zip(*rest), "o", color="k", mfc="none", ms=5, label="integration from rest, 400 periods")
    ax.plot([], [], "-", color="C2", label="crossing, stable")
    ax.plot([], [], "--", color="C1", label="crossing, unstable")
    ax.set_xlabel("ω (rad/s)")
    ax.set_ylabel("spread of the blades' first harmonics of x (µm)")
    ax.set_title("how much the blades differ", fontsize=9)
    ax.legend(fontsize=6)
    ax.grid(alpha=0.3)
    fig.suptitle("tuned 24-blade ring, Coulomb, EO 3, F0 = 120 N: between its branch points the ring settles on "
                 "orbits whose blades differ", fontsize=9)
    fig.tight_layout()
    fig.savefig(OUT / "branch_points_ring.png", dpi=110)
    print("  from rest:", [(round(w, 1), round(float(v), 4)) for w, v in rest])


def mistuned_envelope():
    """The 24-blade Coulomb ring through its resonance, 1200 to 1470 rad/s, tuned (on the cyclic reduction) and
    mistuned (2 %, seed 1, the whole ring's map): the largest and smallest of the blades' first harmonics of x
    (docs/orbits_rings.md, *Mistuned rings*), and each blade at the mistuned ring's stable peak, with an integration from
    rest there."""
    from dataclasses import replace

    from blademodel.numeric.kernels import make_integrator
    from blademodel.orbits.branch_states import envelope, state_indices
    tuned_cfg = load_config("models/bladed_disk_24.yaml")
    cfg = apply_overrides(tuned_cfg, {"mistuning_std": "0.02", "mistuning_seed": "1"})
    kw = dict(grazing_tol=float("inf"), max_points=1500, transient=100)   # 20 periods from rest: no tuned orbit found
    t = time.process_time()
    tuned = continuation(tuned_cfg, "omega", 1200.0, 1470.0, cyclic=True, **kw)
    _report("tuned 24-blade ring, cyclic", tuned, t)
    t = time.process_time()
    mis = continuation(cfg, "omega", 1200.0, 1470.0, **kw)
    _report("mistuned 24-blade ring (2 %, seed 1)", mis, t)
    xs = state_indices(mis.state_names, "x*")
    peaks = {}
    for label, b in (("tuned", tuned), ("mistuned", mis)):
        largest, _, which = envelope(b.harmonics, xs)
        k = int(np.argmax(np.where(b.stable, largest, -np.inf)))
        peaks[label] = (b.params[k], largest[k], k)
        print(f"  {label}: largest stable first harmonic {largest[k] * 1e6:.3f} um at {b.params[k]:.4f} rad/s "
              f"(blade {b.state_names[which[k]]})")
    factor = peaks["mistuned"][1] / peaks["tuned"][1]
    print(f"  amplification factor (largest stable peaks): {factor:.4f}")
    w, _, k = peaks["mistuned"]
    blades = np.abs(mis.harmonics[k, xs]) * 1e6
    ig = make_integrator(apply_overrides(cfg, {"omega": repr(float(w))}).build())
    z = np.zeros(ig.n_state)
    _, mode, _ = ig.advance(z, ig.mode_of(z), 0, 400)
    rec = ig.record_buffer(ig.steps_per_period + 1)
    ig.advance(z, mode, 0, 1, n_transient=0, record=rec)
    X = rec[1][:-1][:, xs]
    rest = np.abs(2 * np.fft.rfft(X, axis=0)[1] / X.shape[0]) * 1e6
    print(f"  from rest at {w:.4f} rad/s, 400 periods: largest blade difference from the orbit "
          f"{np.max(np.abs(rest - blades)):.3g} um")
    near = int(np.argmin(np.where(tuned.stable, np.abs(tuned.params - w), np.inf)))   # the nearest stable point
    level = float(np.abs(tuned.harmonics[near, xs]).max()) * 1e6
    fig = Figure(figsize=(11, 4.0))
    ax = fig.add_subplot(1, 2, 1)
    quiet = [replace(b, special=[q for q in b.special if q.kind != "grazing"]) for b in (tuned, mis)]
    branch_figure(quiet, "x*", ax=ax, labels=["tuned (every blade alike)", "mistuned 2 %"])
    ax.set_xlabel("ω (rad/s)")
    ax.set_title(f"largest and smallest blade; amplification factor {factor:.3f}", fontsize=9)
    ax.legend(fontsize=6, loc="lower right")
    ax = fig.add_subplot(1, 2, 2)
    n = np.arange(1, len(xs) + 1)
    ax.bar(n, blades, color="C2", label=f"mistuned orbit at {w:.2f} rad/s (its stable peak)")
    ax.plot(n, rest, "o", color="k", mfc="none", ms=5, label="integration from rest, 400 periods")
    ax.axhline(level, color="C0", lw=1.2, label=f"tuned orbit at {tuned.params[near]:.2f} rad/s")
    ax.set_ylim(0.8 * min(blades.min(), level), 1.05 * max(blades.max(), level))
    ax.set_xlabel("blade")
    ax.set_ylabel("first harmonic of x (µm)")
    ax.set_title("each blade at the mistuned ring's stable peak", fontsize=9)
    ax.legend(fontsize=6, loc="lower right")
    ax.grid(alpha=0.3, axis="y")
    fig.suptitle("24-blade Coulomb ring, EO 3, F0 = 60 N, through its resonance: tuned and mistuned "
                 "(stiffness deviations 2 %, seed 1)", fontsize=9)
    fig.tight_layout()
    fig.savefig(OUT / "mistuned_envelope.png", dpi=110)


FIGURES = ("frf_pair", "period_doubling", "nonsmooth_fold", "frf_bladed_disk", "doublings_bladed_disk",
           "branch_points_twin_blades", "branch_points_ring", "mistuned_envelope")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--only", choices=FIGURES)
    args = ap.parse_args()
    for name in FIGURES:
        if args.only in (None, name):
            globals()[name]()


if __name__ == "__main__":
    main()
