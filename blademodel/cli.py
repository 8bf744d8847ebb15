"""The ``blademodel`` command line: ``blademodel <command> ...``.

Subcommands live in :mod:`blademodel.commands`, one module each, exposing
``register(subparsers)`` and ``run(args) -> int``. To add one, write the module
and add its name to :data:`COMMANDS`; a listed module that does not exist yet is
skipped. A plugin adds its own commands (modules of the same shape) under the
entry point group ``blademodel.commands``, as the paper wing adds ``reproduce``.
"""

from __future__ import annotations

import argparse
import importlib
import re
import sys
from importlib.metadata import entry_points
from typing import Optional, Sequence

from . import __version__

#: Subcommand modules of :mod:`blademodel.commands`, in help order.
COMMANDS = ["equations", "simulate", "orbit", "continue_", "sweep", "plot"]
#: Entry point group of plugin commands (each a module with ``register`` and ``run``).
ENTRY_POINT_GROUP = "blademodel.commands"

#: Exit code of a usage or config error (as argparse uses).
EXIT_USAGE = 2
#: Exit code after Ctrl-C (128 + SIGINT, as shells report it).
EXIT_INTERRUPTED = 130


def _load_commands() -> list:
    modules = []
    for name in COMMANDS:
        full = f"{__package__}.commands.{name}"
        try:
            modules.append(importlib.import_module(full))
        except ModuleNotFoundError as e:
            if e.name != full:
                raise  # the command exists but one of its imports is missing
    return modules + [ep.load() for ep in entry_points(group=ENTRY_POINT_GROUP)]


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every available subcommand registered."""
    parser = argparse.ArgumentParser(prog="blademodel",
                                     description="Rub-impact dynamics of shrouded turbine blades.")
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for module in _load_commands():
        module.register(sub)
    return parser


#: A negative number in any float notation (argparse before Python 3.12 takes ``-1e-5`` for an option).
_NEGATIVE_NUMBER = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$")


def _negative_values_attached(argv: Sequence[str]) -> list:
    """``argv`` with each negative number that follows a long option attached to it (``--to -1e-5`` as
    ``--to=-1e-5``), which argparse reads as that option's value in every notation."""
    out: list = []
    for token in argv:
        if out and _NEGATIVE_NUMBER.match(token) and out[-1].startswith("--") and out[-1] != "--" \
                and "=" not in out[-1]:
            out[-1] = f"{out[-1]}={token}"
        else:
            out.append(token)
    return out


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
        The exit code: 0 on success, 2 on a usage, config or value error or a
        damaged result file, 1 on another failure (a result file locked by
        another sweep, a lost worker, an unreachable scheduler, a sweep whose
        every point failed), 130 after Ctrl-C. Messages are printed to stderr
        as ``error: ...``, without a traceback.
    """
    from . import interrupts
    try:
        args = build_parser().parse_args(_negative_values_attached(sys.argv[1:] if argv is None else argv))
        with interrupts.handled():   # Ctrl-C and SIGTERM raise KeyboardInterrupt, never lost
            return int(args.run(args) or 0)
    except KeyboardInterrupt as e:  # Ctrl-C: one line (a sweep's says how to resume), no traceback
        print(("\n" if sys.stderr.isatty() else "") + (str(e) or "interrupted"), file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:  # the reader went away (``blademodel ... | head``)
        sys.stderr.close()
        return 0
    except Exception as e:
        from .sweep.errors import SweepError  # imported here: Ctrl-C is caught from the first line of main
        if isinstance(e, SweepError):  # a damaged or locked result file, a lost worker, no scheduler
            print(f"error: {e}", file=sys.stderr)
            return e.exit_code
        if isinstance(e, (ValueError, KeyError)):  # ConfigError is a ValueError
            print(f"error: {_message(e)}", file=sys.stderr)
            return EXIT_USAGE
        raise


if __name__ == "__main__":
    sys.exit(main())
