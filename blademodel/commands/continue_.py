"""``blademodel continue MODEL.yaml --param NAME --from A --to B``: a branch of periodic orbits."""

from __future__ import annotations

import argparse
import functools
import json
import os
import sys
from pathlib import Path

import numpy as np

from .. import interrupts
from ..orbits import (ContinuationInterrupted, FlowError, ShootingError, branch_point_branch, continuation,
                      period_doubled_branch)
from ..orbits.branch_states import alike, envelope, state_indices
from ..orbits.cyclic import CyclicError
from ..orbits.least_period import branch_least_periods
from ..progress import Progress
from ..sweep.point import observed
from . import jsonout
from .common import (add_jacobian_arguments, add_model_arguments, add_stepping_arguments, check_at_least_one,
                     config_and_model)
from .output import check_output_file
from .plot import SWITCHED


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``continue`` subcommand."""
    p = subparsers.add_parser("continue", help="follow periodic orbits in a parameter (FRFs, bifurcations)",
                              description="Find a periodic orbit at --from, then follow it by pseudo-arclength "
                                          "continuation in the config field --param toward --to, around folds; "
                                          "report each orbit's stability and the folds, period doublings, "
                                          "Neimark-Sacker bifurcations, border collisions and grazing points "
                                          "found.")
    add_model_arguments(p)
    p.add_argument("--param", required=True, metavar="NAME", help="config field, e.g. omega (an FRF) or gamma")
    p.add_argument("--from", dest="start", type=float, required=True, metavar="A", help="start value")
    p.add_argument("--to", dest="stop", type=float, required=True, metavar="B", help="end value")
    p.add_argument("--period", "--periods", dest="period", type=int, default=1, metavar="N",
                   help="period of the orbits in excitation periods (default 1; --periods as for 'orbit')")
    p.add_argument("--transient", type=int, default=20, metavar="M",
                   help="periods from rest for the first guess (default 20)")
    p.add_argument("--max-points", type=int, default=400, metavar="K", help="points at most (default 400)")
    p.add_argument("--ds-max", type=float, default=0.05, help="largest arclength step (default 0.05)")
    p.add_argument("--tol", type=float, default=1e-10, help="scaled residual of each orbit (default 1e-10)")
    p.add_argument("--grazing-tol", type=float, default=None, metavar="G",
                   help="locate grazing points only to G of the range (default: as the bifurcations, 1e-7); "
                        "inf reports each at the first point past it. Cheaper on mistuned rings, whose contacts "
                        "graze one by one; the branch's points stay the same")
    add_stepping_arguments(p)
    p.add_argument("--cyclic", action="store_true",
                   help="a tuned bladed disk under engine-order excitation: follow its travelling-wave orbits on "
                        "the map over T / d reduced by their symmetry (d = N / gcd(EO, N); 8 times fewer steps on "
                        "24 blades at engine order 3), the whole ring's multipliers from it (docs/orbits_rings.md); "
                        "with --switch, the period-doubled branches (on the reduced map where it has a branch point at "
                        "the doubling, else on the whole ring's map) and the branches crossing at branch points (on "
                        "the map over 2 T / d where the reduced map period-doubles there, else on the whole ring's "
                        "map)")
    p.add_argument("--switch", action="store_true",
                   help="also follow the period-doubled branch born at each period doubling found, and the branch "
                        "that crosses this one at each branch point (on identical blades: orbits that break their "
                        "symmetry, localised; saved beside --out as FILE_pd1.nc, ..., FILE_bp1.nc, ...; drawn on "
                        "the same --plot)")
    p.add_argument("--quantity", choices=("harmonic", "amplitude", "section", "reduction"), default="harmonic",
                   help="what --plot draws: first-harmonic amplitude (an FRF, default), half the peak-to-peak "
                        "excursion, the Poincare samples (a bifurcation diagram), or the vibration reduction P_d "
                        "against the model without contacts (of the first mass's coordinates, in percent)")
    p.add_argument("--overlay", metavar="SWEEP.nc",
                   help="draw the first harmonics (or with --quantity reduction the P_d) of a brute-force sweep of "
                        "the same field (a 'blademodel sweep' result file) on --plot, as dots")
    p.add_argument("--state", default=None,
                   help="state plotted and reported (default: the first coordinate); a pattern such as 'x*' "
                        "(quoted) stands for the largest of the states it matches at each point, and --plot draws "
                        "the smallest too: the envelope of a mistuned ring's blades")
    p.add_argument("--out", metavar="FILE.nc", help="write the branch (NetCDF)")
    p.add_argument("--plot", metavar="FILE.png", help="draw the branch (stable solid, unstable dashed)")
    add_jacobian_arguments(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(run=run)
    return p


#: Seconds between two saves of an unfinished branch to ``--out`` (``$BLADEMODEL_CHECKPOINT_SECONDS``, default 30).
CHECKPOINT_SECONDS = float(os.environ.get("BLADEMODEL_CHECKPOINT_SECONDS", 30.0))

#: The options that shape a branch (``--workers`` does not: the branch is the same to the bit): a file made with
#: the same ones, and the same config, is this command's own.
_RUN_OPTIONS = ("param", "start", "stop", "period", "transient", "max_points", "ds_max", "tol", "steps_per_period",
                "event_tol", "method", "jacobian")


def _reporter(label: str, param: str):
    """``progress(point, value)`` for :func:`continuation`: the point count and the field's value."""
    shown = Progress("points", label=label)

    def progress(point: int, value: float) -> None:
        shown(point, 0, f"{param} = {value:.6g}")

    progress.interrupt = shown.interrupt
    return progress


def sweep_overlay(path, field: str, states, law: str | None = None, quantity: str = "harmonic") -> tuple:
    """``(values, first-harmonic amplitudes)`` from a sweep result file over ``field``: of the state index
    ``states``, or the largest of those of a list of them at each point
    (:func:`~blademodel.orbits.branch_states.envelope`); with ``quantity="reduction"``, ``(values, P_d)``
    (``states`` unused).

    Only the finished, successful points (and for ``P_d`` those where it is defined); with several laws in the
    file, those of ``law``.

    Raises
    ------
    ValueError
        If the file did not sweep ``field`` or holds no first harmonics (written before they were stored), or
        no ``P_d`` (a sweep run without ``vibration_reduction``).
    """
    from ..sweep.runner import open_result
    ds = open_result(path)
    if f"param_{field}" not in ds:
        raise ValueError(f"--overlay {path}: the sweep did not vary {field!r} (it varied "
                         f"{', '.join(ds.attrs['fields'])})")
    if quantity == "reduction" and ("Pd" not in ds or not np.isfinite(ds["Pd"].values).any()):
        raise ValueError(f"--overlay {path}: the sweep holds no P_d (run it with run.vibration_reduction: true)")
    if quantity != "reduction" and "harmonic1" not in ds:
        raise ValueError(f"--overlay {path}: the file holds no first harmonics (written by an older blademodel); "
                         f"run the sweep again")
    ok = (ds["done"].values == 1) & (ds["error"].values == "")
    laws = set(ds["law"].values[ok])
    if law is not None and len(laws) > 1:
        ok &= ds["law"].values == law
    if quantity == "reduction":
        ok &= np.isfinite(ds["Pd"].values)
        return ds[f"param_{field}"].values[ok], ds["Pd"].values[ok]
    columns = [int(k) for k in np.atleast_1d(states)]
    return ds[f"param_{field}"].values[ok], envelope(ds["harmonic1"].values[ok], columns)[0]


def _hint_cyclic(config, period: int) -> None:
    """On a tuned ring under engine-order excitation, say on stderr that ``--cyclic`` may follow its period-1 orbits
    on a fraction of the period."""
    from ..orbits.cyclic import reducible
    if period != 1:
        return
    try:
        N, _, g = reducible(config)
    except CyclicError:
        return
    print(f"hint: this ring is tuned and driven in engine order: --cyclic follows its travelling waves on T / "
          f"{N // g} of the period, the whole ring's multipliers from it (docs/orbits_rings.md)", file=sys.stderr)


def _hint_grazing(config) -> None:
    """On a ring whose blades or contacts differ, say on stderr that ``--grazing-tol`` may spare most of the run:
    its contacts graze one by one, and each grazing point is located to ``locate_tol``."""
    from ..config import BladedDisk
    from ..orbits.cyclic import what_differs
    if not isinstance(config, BladedDisk) or what_differs(config) is None:
        return
    print("hint: the blades or contacts of this ring differ, so its contacts graze one by one, and locating each "
          "grazing point to 1e-7 may be most of the run: --grazing-tol 1e-3 or inf leaves the branch's points the "
          "same (2.5 and 8.3 times cheaper on a mistuned 24-blade ring; docs/continuation_settings.md)",
          file=sys.stderr)


def run(args: argparse.Namespace) -> int:
    """Continue the branch; return the exit code."""
    check_at_least_one(args, ("period", "max_points", "steps_per_period"))
    for name in ("tol", "ds_max"):
        if not getattr(args, name) > 0:
            raise ValueError(f"--{name.replace('_', '-')} must be > 0, got {getattr(args, name)}")
    if args.start == args.stop:
        raise ValueError(f"--from and --to must differ, got {args.start:g} twice")
    if args.out:
        check_output_file(args.out, ".nc", what="NetCDF file")
    if args.plot:
        check_output_file(args.plot, ".png", option="--plot", what="PNG image")
    if args.overlay:
        if not args.plot:
            raise ValueError("--overlay draws on the plot: give --plot FILE.png too")
        if args.quantity not in ("harmonic", "reduction"):
            raise ValueError("--overlay draws a sweep's first harmonics or its P_d: use it with --quantity harmonic "
                             "or reduction")
        sweep_overlay(args.overlay, args.param, 0, quantity=args.quantity)   # the file's checks, before the run
    config, model = config_and_model(args)
    run_settings = {k: getattr(args, k) for k in _RUN_OPTIONS}
    if args.grazing_tol is not None:   # (files written without it stay this command's own at the default)
        if not args.grazing_tol > 0:
            raise ValueError(f"--grazing-tol must be > 0 (or inf), got {args.grazing_tol}")
        run_settings["grazing_tol"] = args.grazing_tol
    if not args.cyclic and not args.json:
        _hint_cyclic(config, args.period)
    if args.grazing_tol is None and not args.json:
        _hint_grazing(config)
    if args.cyclic:
        run_settings["cyclic"] = True   # (files written without it stay this command's own without it)
    shared = dict(max_points=args.max_points, ds_max=args.ds_max, tol=args.tol, grazing_tol=args.grazing_tol,
                  steps_per_period=args.steps_per_period, event_tol=args.event_tol, method=args.method,
                  jacobian=args.jacobian, workers=args.workers)

    def branch_of(resume, **kw):
        return continuation(config, args.param, args.start, args.stop, periods=args.period,
                            transient=args.transient, resume=resume, cyclic=args.cyclic, **shared, **kw)

    try:
        branch = _continued(args.out, config, run_settings, "branch", args.param, branch_of)
    except (ShootingError, FlowError) as e:
        print(f"error: {e}", file=sys.stderr)
        if getattr(e, "least_tol", None) is not None:
            print(f"hint: --tol {e.least_tol:g}", file=sys.stderr)
        elif getattr(e, "at_start", False):
            print("hint: --transient N (periods from rest before shooting), another --from, or --period 2",
                  file=sys.stderr)
        return 1
    doubled, branched, doubled_files = [], [], []

    def switch_at(points, tag, label, what, follow) -> list:
        """The branch ``follow(point, resume=..., ...)`` from each of ``points``, saved beside ``--out`` as
        FILE_<tag>1.nc, ... (None where the switch failed, with a warning); its run settings name the point under
        the tag's key (:data:`~.plot.SWITCHED`)."""
        key = SWITCHED[tag][0]
        out = []
        for k, p in enumerate(points, 1):
            name = str(Path(args.out).with_name(f"{Path(args.out).stem}_{tag}{k}.nc")) if args.out else None
            try:
                out.append(_continued(name, config, {**run_settings, key: k}, f"{label} {k}", args.param,
                                      functools.partial(follow, p)))
            except (ShootingError, FlowError) as e:
                print(f"warning: no switch at the {what} {k} ({args.param} = {p.param:.6g}): {e}", file=sys.stderr)
                out.append(None)
                continue
            if name:
                doubled_files.append(name)
        return out

    def switched(pd, resume, **kw):
        if resume is not None:   # an unfinished period-doubled branch goes on as any branch
            if args.cyclic:   # on the reduced map where it was followed there (its orbits G's fixed points)
                try:
                    return continuation(config, args.param, args.start, args.stop, periods=2 * args.period,
                                        resume=resume, cyclic=True, **shared, **kw)
                except CyclicError:
                    pass
            return continuation(config, args.param, args.start, args.stop, periods=2 * args.period,
                                resume=resume, **shared, **kw)
        return period_doubled_branch(config, args.param, pd, args.start, args.stop, periods=args.period,
                                     cyclic=args.cyclic, parent=branch, **shared, **kw)

    def crossing(bp, resume, **kw):
        if resume is not None:   # an unfinished crossing branch goes on as any branch, on the whole map
            return continuation(config, args.param, args.start, args.stop, periods=args.period,
                                resume=resume, **shared, **kw)
        return branch_point_branch(config, args.param, bp, args.start, args.stop, periods=args.period,
                                   cyclic=args.cyclic, crossed=branch, **shared, **kw)

    if args.switch:
        doubled = switch_at(branch.points("period-doubling"), "pd", "period-doubled branch", "period doubling",
                            switched)
        branched = switch_at(branch.points("branch-point"), "bp", "branch from branch point", "branch point", crossing)
    state = args.state or branch.state_names[0]
    idx = state_indices(branch.state_names, state, "--state")
    reduction, unreduced = _reduction(branch, config)
    summed = ", ".join(observed(model))   # what P_d sums
    if args.plot:
        from ..plots.branch import branch_figure
        overlay = None
        if args.overlay:
            overlay = sweep_overlay(args.overlay, args.param, idx, getattr(config, "friction", None), args.quantity)
        drawn = [(branch, f"period {branch.periods}")]
        for tag, switched_to in (("pd", doubled), ("bp", branched)):
            drawn += [(b, SWITCHED[tag][1].format(k=k)) for k, b in enumerate(switched_to, 1) if b is not None]
        values = None
        if args.quantity == "reduction":
            if reduction is None:
                raise ValueError(f"--quantity reduction: {unreduced}")
            values = [reduction] + [_reduction(b, config)[0] for b, _ in drawn[1:]]
        branch_figure([b for b, _ in drawn], summed if values is not None else state,
                      quantity=args.quantity, overlay=overlay, values=values,
                      labels=[label for _, label in drawn] if len(drawn) > 1 else None).savefig(args.plot, dpi=120)
    spread = envelope(branch.harmonics, idx)
    largest, smallest, which = spread
    rep = {"field": branch.field, "periods": branch.periods, "points": len(branch.params),
           "message": branch.message, "integrations": branch.integrations, "replays": branch.replays,
           "values": branch.params.tolist(),
           "harmonic1": largest.tolist(), "stable": branch.stable.tolist(),
           "least_periods": branch_least_periods(branch).tolist(),
           "P_d": None if reduction is None else reduction.tolist(),
           "special": [{"kind": p.kind, "value": p.param, "multiplier": [p.multiplier.real, p.multiplier.imag],
                        "bracket": None if p.bracket is None else list(p.bracket)}
                       for p in branch.special], "state": state,
           "doubled": [_summary(b, idx) for b in doubled], "branched": [_summary(b, idx) for b in branched]}
    if len(idx) > 1:   # a pattern: harmonic1 is the largest of its states; which, and the smallest
        rep["largest_state"] = [branch.state_names[k] for k in which]
        rep["smallest1"] = smallest.tolist()
    if args.json:
        print(jsonout.dumps(rep))
        return 0
    print(f"{len(branch.params)} period-{branch.periods} orbits from {args.param} = {branch.params[0]:.6g} to "
          f"{branch.params[-1]:.6g} ({branch.message}); {int(np.sum(~branch.stable))} unstable; "
          f"{branch.integrations} integrations of the period map and {branch.replays} tangent replays"
          f"{_run_again(branch, args.param)}")
    print(_peak(branch, state, idx, spread, args.param))
    if reduction is not None and np.isfinite(reduction).any():
        k = int(np.nanargmax(reduction))
        print(f"  vibration reduction P_d of {summed}: {np.nanmin(reduction):.4g} % to "
              f"{reduction[k]:.4g} % (the largest at {args.param} = {branch.params[k]:.8g}, "
              f"{'stable' if branch.stable[k] else 'unstable'})")
    if len(branch.special) > 1:   # the bifurcations are not lost among many grazing points
        print(f"  special points: {branch.special_counts()}, in their order along the branch:")
    for line in _special_lines(branch, args.param):
        print(line)
    for what, switched_to in (("period doubling", doubled), ("branch point", branched)):
        for k, b in enumerate(switched_to, 1):
            if b is None:
                continue
            print(f"{len(b.params)} period-{b.periods} orbits from the {what} {k}, {args.param} = "
                  f"{b.params.min():.6g} to {b.params.max():.6g} ({b.message}); {int(np.sum(~b.stable))} unstable"
                  f"{_run_again(b, args.param)}")
            for line in _special_lines(b, args.param):
                print(line)
    for what, name in (("saved", args.out), ("saved", ", ".join(doubled_files)), ("plotted", args.plot)):
        if name:
            print(f"{what} {name}")
    return 0


def _special_lines(branch, param: str) -> list[str]:
    """The report's line for each special point of ``branch``, in their order along it."""
    lines = []
    for p in branch.special:
        if p.kind == "gap":
            lo, hi = _distinct(*p.bracket)
            lines.append(f"  gap: no orbit found between {param} = {lo} and {hi}; the branch goes on from the orbit "
                         f"at {p.param:.8g}, which may lie on another branch (more steps a period, "
                         f"--steps-per-period, may close the gap)")
            continue
        within = "" if p.bracket is None else ", somewhere in [{}, {}]".format(*_distinct(*p.bracket))
        lines.append(f"  {p.kind} at {param} = {p.param:.8g}{within} ({_MULTIPLIER_IS.get(p.kind, 'multiplier')} "
                     f"{p.multiplier.real:.6g}{p.multiplier.imag:+.6g}i)")
    return lines


def _distinct(lo: float, hi: float) -> tuple[str, str]:
    """A bracket's ends printed to eight significant digits, or to as many more as tell them apart (up to 17)."""
    for digits in range(8, 18):
        a, b = f"{lo:.{digits}g}", f"{hi:.{digits}g}"
        if a != b:
            break
    return a, b


#: What a special point's multiplier is, where it is not the one on the unit circle (``SpecialPoint.multiplier``).
_MULTIPLIER_IS = {"grazing": "largest multiplier at the branch's point before it:",
                  "border-collision": "multiplier that jumps across the circle, past it:",
                  "nonsmooth-fold": "multiplier beside it, none crossing the circle:"}


def _reduction(b, config) -> tuple:
    """``(P_d at each point of b, None)``, or ``(None, why)`` where the model without contacts has no closed-form
    steady state (:func:`~blademodel.orbits.branch_reduction.branch_vibration_reduction`)."""
    from ..orbits.branch_reduction import branch_vibration_reduction
    if b is None:
        return None, "no branch"
    try:
        return branch_vibration_reduction(b, config), None
    except ValueError as e:
        return None, str(e)


def _run_again(b, param: str) -> str:
    """What the summary line of a branch adds where some of its orbits have a shorter least period than the
    branch's (:func:`~blademodel.orbits.least_period.branch_least_periods`): how many, over which values."""
    least = branch_least_periods(b)
    parts = []
    for k in sorted(set(least[least < b.periods].tolist())):
        on = b.params[least == k]
        where = f"{on[0]:.6g}" if on.size == 1 else f"{on.min():.6g} to {on.max():.6g}"
        parts.append(f"{on.size} of them the period-{k} orbit run {b.periods // k} times ({param} = {where})")
    return "; " + "; ".join(parts) if parts else ""


def _summary(b, idx: list) -> dict | None:
    """A switched branch for the JSON report (None where the switch failed); ``idx``: the states reported (the
    largest of their first harmonics at each point)."""
    if b is None:
        return None
    return {"periods": b.periods, "points": len(b.params), "message": b.message, "values": b.params.tolist(),
            "harmonic1": envelope(b.harmonics, idx)[0].tolist(), "stable": b.stable.tolist(),
            "least_periods": branch_least_periods(b).tolist(),
            "special": [{"kind": p.kind, "value": p.param} for p in b.special]}


def _peak(branch, state: str, idx: list, spread: tuple, param: str) -> str:
    """The line that says where the branch's first harmonic of ``state`` (the largest of ``idx``; ``spread``: their
    :func:`~blademodel.orbits.branch_states.envelope`) is largest, and where it is largest on the stable orbits if
    not there."""
    largest, smallest, which = spread
    same = alike(largest, smallest)

    def at(k):
        whose = ""
        if len(idx) > 1:   # which state is largest, unless they agree (a travelling wave: rounding's choice)
            whose = f" (all {len(idx)} alike)" if same[k] else f" ({branch.state_names[which[k]]})"
        return f"{largest[k]:.6g}{whose} at {param} = {branch.params[k]:.8g}"
    k = int(np.argmax(largest))
    line = f"  largest first harmonic of {state}: {at(k)} ({'stable' if branch.stable[k] else 'unstable'})"
    if not branch.stable[k] and branch.stable.any():
        line += f"; on the stable orbits {at(int(np.argmax(np.where(branch.stable, largest, -np.inf))))}"
    return line


def _continued(path, config, run_settings: dict, label: str, param: str, follow):
    """The branch ``follow(resume=..., checkpoint=..., checkpoint_every=..., progress=...)`` continues, saved to
    ``path`` (if given) every :data:`CHECKPOINT_SECONDS` and at the end (a signal meanwhile is raised once the
    file is complete: :func:`~blademodel.interrupts.deferred`).

    If ``path`` holds this branch (the same ``run_settings`` and config) unfinished, it is resumed; finished, it is
    read back instead of computed again. On Ctrl-C (or SIGTERM) the points found are saved, and a
    :class:`KeyboardInterrupt` says where and how to resume.
    """
    from ..orbits.branch_file import save_branch
    stored = _own_branch(path, config, run_settings)
    if stored is not None and stored.complete:
        print(f"{path} holds this {label}, finished ({len(stored.params)} points): read back, not computed again "
              f"(remove the file to compute it again)", file=sys.stderr)
        return stored
    if stored is not None:
        print(f"resuming the {label} saved in {path}: {len(stored.params)} points, the last at {param} = "
              f"{stored.params[-1]:.6g}", file=sys.stderr)
    progress = _reporter(label, param)

    def save(branch):
        with interrupts.deferred():
            save_branch(branch, path, config, run_settings)

    try:
        branch = follow(resume=stored, checkpoint=save if path else None, checkpoint_every=CHECKPOINT_SECONDS,
                        progress=progress)
    except ContinuationInterrupted as e:   # continuation() acknowledged the signal; the finally ends the bar
        if path is None:
            raise KeyboardInterrupt(f"interrupted: the {len(e.branch.params)} points of the {label} are lost (give "
                                    f"--out FILE.nc to keep them and resume)") from None
        save(e.branch)
        raise KeyboardInterrupt(f"interrupted: {len(e.branch.params)} points of the {label} are saved in {path}; "
                                f"run the same command again to resume") from None
    finally:
        progress.interrupt()
    if path is not None:
        save(branch)
    return branch


def _own_branch(path, config, run_settings: dict):
    """The branch in ``path`` if that file holds a branch made by the same options and config, else None."""
    from ..orbits.branch_file import branch_origin, load_branch
    if path is None:
        return None
    run, stored_config = branch_origin(path)
    if run != json.loads(json.dumps(run_settings)) or stored_config != config.model_dump(mode="json"):
        return None
    return load_branch(path)
