"""``blademodel sweep STUDY.yaml``: run a study into a NetCDF file (resumable)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..sweep import load_study, run_study, storage
from .output import check_output_file


def add_run_arguments(p: argparse.ArgumentParser) -> None:
    """Options shared by ``sweep`` and ``reproduce``."""
    p.add_argument("--quick", action="store_true", help="coarse version (few points and periods)")
    p.add_argument("--workers", type=int, default=None, metavar="N", help="processes (default: all cores)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="run on this Dask distributed scheduler")
    p.add_argument("--restart", action="store_true", help="discard an existing result file and start again")
    p.add_argument("--no-plot", action="store_true", help="do not write figures")


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``sweep`` subcommand."""
    p = subparsers.add_parser("sweep", help="run a parameter study",
                              description="Run every point of a study into one NetCDF file, written point by "
                                          "point: a killed sweep resumes where it stopped.")
    p.add_argument("study", metavar="STUDY.yaml")
    p.add_argument("--out", metavar="FILE", help="result file (default: out/<study name>/<study name>.nc; "
                                                 "the figures go beside it)")
    p.add_argument("--warm-start", action="store_true", help="start each point from the previous final state")
    add_run_arguments(p)
    p.set_defaults(run=run)
    return p


def failure_summary(out: Path, limit: int = 5) -> tuple[list[str], bool]:
    """Lines summing up the failed points of ``out`` by error, and whether every point failed.

    Returns
    -------
    lines : list of str
        Empty when no point failed.
    all_failed : bool
    """
    failed = storage.failures(out)
    total = storage.check(out).n_points
    if not failed:
        return [], False
    by_kind: dict[str, list[int]] = {}   # by exception name; the first message as an example
    for i, error in failed.items():
        by_kind.setdefault(error.split(":", 1)[0], []).append(i)
    lines = [f"{out}: {len(failed)} of {total} points failed:"]
    for kind, idx in sorted(by_kind.items(), key=lambda kv: -len(kv[1]))[:limit]:
        shown = ", ".join(map(str, idx[:8])) + (", ..." if len(idx) > 8 else "")
        lines.append(f"  {len(idx)} x {kind} (points {shown}), e.g. {failed[idx[0]].splitlines()[0]}")
    if len(by_kind) > limit:
        lines.append(f"  ... and {len(by_kind) - limit} other kinds of error")
    return lines, len(failed) == total


def execute(study, out: Path, args) -> tuple[list[Path], bool]:
    """Run ``study`` into ``out`` and plot it.

    Returns
    -------
    figures : list of Path
    ok : bool
        False if every point failed (the failures are summed up on stderr, nothing is plotted).
    """
    check_output_file(out, ".nc", what="NetCDF file", make_folders=True)  # before any point is computed
    if args.quick:
        study = study.quick_version()
    if getattr(args, "warm_start", False):
        study = study.model_copy(update={"run": study.run.model_copy(update={"warm_start": True})})
    run_study(study, out, workers=args.workers, scheduler=args.scheduler, restart=args.restart)
    lines, all_failed = failure_summary(out)
    for line in lines:
        print(line, file=sys.stderr)
    if all_failed:
        print(f"error: every point of {out} failed; nothing to plot", file=sys.stderr)
        return [], False
    if args.no_plot:
        return [], True
    from ..plots import plot_result
    return plot_result(out, out.parent), True


def default_out(folder: Path, name: str, quick: bool = False) -> Path:
    """``folder/name/name.nc`` (``name_quick.nc`` for ``--quick``): the one layout of ``sweep`` and ``reproduce``.

    The study's folder holds its data and its figures. Refused if it would not lie
    inside ``folder``.
    """
    out = folder / name / f"{name}{'_quick' if quick else ''}.nc"
    if out.resolve().parent.parent != folder.resolve():
        raise ValueError(f"study name {name!r} would write outside {folder}/; use a plain name")
    return out


def run(args: argparse.Namespace) -> int:
    """Run the sweep; return the exit code (1 if every point failed)."""
    study = load_study(args.study)
    out = Path(args.out) if args.out else default_out(Path("out"), study.name, args.quick)
    figures, ok = execute(study, out, args)
    print(f"results: {out}")
    for f in figures:
        print(f"figure:  {f}")
    return 0 if ok else 1
