"""``blademodel equations MODEL.yaml [--mode NAME] [--latex]``: print the equations of motion."""

from __future__ import annotations

import argparse

from ..symbolic import derive
from ..symbolic.display import latex, pretty
from .common import add_model_arguments, model_from_args


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``equations`` subcommand."""
    p = subparsers.add_parser("equations", help="print the equations of motion of every mode",
                              description="Derive a model's equations of motion and print them, "
                                          "mode by mode, with N_c and f_c defined per mode.")
    add_model_arguments(p)
    p.add_argument("--mode", metavar="NAME", help="only this mode (e.g. stick, 'c12=stick,c23=open')")
    p.add_argument("--latex", action="store_true", help="print LaTeX (amsmath align* blocks)")
    p.add_argument("--ascii", action="store_true", help="plain ASCII instead of Unicode")
    p.set_defaults(run=run)
    return p


def run(args: argparse.Namespace) -> int:
    """Print the equations; return the exit code."""
    system = derive(model_from_args(args))
    if args.latex:
        text = latex(system, args.mode)
    else:
        text = pretty(system, args.mode, unicode=not args.ascii)
    print(text, end="")
    return 0
