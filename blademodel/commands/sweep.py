"""``blademodel sweep STUDY.yaml``: run a study into a NetCDF file (resumable)."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..sweep import load_study, run_study
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
    p.add_argument("--out", metavar="FILE", help="result file (default: out/<study name>.nc)")
    p.add_argument("--warm-start", action="store_true", help="start each point from the previous final state")
    add_run_arguments(p)
    p.set_defaults(run=run)
    return p


def execute(study, out: Path, args) -> list[Path]:
    """Run ``study`` into ``out`` and plot it; returns the figure paths."""
    check_output_file(out, ".nc", what="NetCDF file", make_folders=True)  # before any point is computed
    if args.quick:
        study = study.quick_version()
    if getattr(args, "warm_start", False):
        study = study.model_copy(update={"run": study.run.model_copy(update={"warm_start": True})})
    run_study(study, out, workers=args.workers, scheduler=args.scheduler, restart=args.restart)
    if args.no_plot:
        return []
    from ..plots import plot_result
    return plot_result(out, out.parent)


def run(args: argparse.Namespace) -> int:
    """Run the sweep; return the exit code."""
    study = load_study(args.study)
    out = Path(args.out) if args.out else Path("out") / f"{study.name}{'_quick' if args.quick else ''}.nc"
    figures = execute(study, out, args)
    print(f"results: {out}")
    for f in figures:
        print(f"figure:  {f}")
    return 0
