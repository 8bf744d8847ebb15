"""Subcommands of the ``blademodel`` command line.

Each module here exposes ``register(subparsers)``, which adds its parser and sets
``run`` as the parser's default, and ``run(args) -> int``. :mod:`blademodel.cli`
lists the modules it loads in ``COMMANDS``.
"""
