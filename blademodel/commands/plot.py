"""``blademodel plot RESULT.nc [--out DIR]``: write the figures of a sweep result as PNG files."""

from __future__ import annotations

import argparse


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``plot`` subcommand."""
    p = subparsers.add_parser("plot", help="write the figures of a sweep result (PNG)",
                              description="Draw the figures a result's study asks for (bifurcation "
                                          "diagram and P_d curves, periodicity map or case panels) and "
                                          "print the paths of the PNG files.")
    p.add_argument("result", metavar="RESULT.nc", help="result file of a study run")
    p.add_argument("--out", metavar="DIR", help="directory of the figures (default: next to the result)")
    p.set_defaults(run=run)
    return p


def run(args: argparse.Namespace) -> int:
    """Write the figures and print their paths; return the exit code."""
    from ..plots import plot_result
    for path in plot_result(args.result, args.out):
        print(path)
    return 0
