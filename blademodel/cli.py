"""The ``blademodel`` command line: ``blademodel <command> ...``.

Subcommands live in :mod:`blademodel.commands`, one module each, exposing
``register(subparsers)`` and ``run(args) -> int``. To add one, write the module
and add its name to :data:`COMMANDS`; a listed module that does not exist yet is
skipped.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from typing import Optional, Sequence

from . import __version__

#: Subcommand modules of :mod:`blademodel.commands`, in help order.
COMMANDS = ["equations", "simulate", "sweep", "reproduce", "plot"]

#: Exit code of a usage or config error (as argparse uses).
EXIT_USAGE = 2


def _load_commands() -> list:
    modules = []
    for name in COMMANDS:
        full = f"{__package__}.commands.{name}"
        try:
            modules.append(importlib.import_module(full))
        except ModuleNotFoundError as e:
            if e.name != full:
                raise  # the command exists but one of its imports is missing
    return modules


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every available subcommand registered."""
    parser = argparse.ArgumentParser(prog="blademodel",
                                     description="Rub-impact dynamics of shrouded turbine blades.")
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for module in _load_commands():
        module.register(sub)
    return parser


def _message(exc: BaseException) -> str:
    if isinstance(exc, KeyError) and exc.args:
        return str(exc.args[0])  # str(KeyError) would quote the message
    return str(exc)


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the command line.

    Parameters
    ----------
    argv : sequence of str, optional
        Arguments without the program name; ``sys.argv[1:]`` by default.

    Returns
    -------
    int
        The exit code: 0 on success, 2 on a usage, config or value error (the
        message is printed to stderr as ``error: ...``, without a traceback).
    """
    args = build_parser().parse_args(argv)
    try:
        return int(args.run(args) or 0)
    except BrokenPipeError:  # the reader went away (``blademodel ... | head``)
        sys.stderr.close()
        return 0
    except (ValueError, KeyError) as e:  # ConfigError is a ValueError
        print(f"error: {_message(e)}", file=sys.stderr)
        return EXIT_USAGE


if __name__ == "__main__":
    sys.exit(main())
