"""``blademodel equations MODEL.yaml [--mode NAME | --contact NAME] [--latex]``: equations of motion.

A model with one contact shows every mode (or ``--mode stick``). With several
contacts the modes are the product of every contact's modes (``4**24`` for a
24-blade disk), so nothing is enumerated: ``--mode c12=stick,c23=open`` derives
that one mode (contacts not named are open), ``--contact c12`` shows one
contact's own equations, and without either flag the mode with every contact
open is shown, with a line saying how to ask for others.
"""

from __future__ import annotations

import argparse

from ..symbolic import derive
from ..symbolic.assembly import (
    _combo,
    _mode_name,
    _name_list,
    contact_equations,
    derive_mode,
    mode_count,
    parse_assignment,
)
from ..symbolic.display import latex, latex_contact, pretty, pretty_contact
from .common import add_model_arguments, model_from_args


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``equations`` subcommand."""
    p = subparsers.add_parser("equations", help="print the equations of motion of every mode",
                              description="Derive a model's equations of motion and print them, "
                                          "mode by mode, with N_c and f_c defined per mode. A model "
                                          "with several contacts shows one mode at a time.")
    add_model_arguments(p)
    which = p.add_mutually_exclusive_group()
    which.add_argument("--mode", metavar="NAME",
                       help="only this mode: e.g. stick for one contact, 'c12=stick,c23=slip+' for "
                            "several (contacts not named are open; 'open': every contact open)")
    which.add_argument("--contact", metavar="NAME",
                       help="one contact's own equations: penetration, slip, N and its friction law "
                            "in each of its modes")
    p.add_argument("--latex", action="store_true", help="print LaTeX (amsmath align* blocks)")
    p.add_argument("--ascii", action="store_true", help="plain ASCII instead of Unicode")
    p.set_defaults(run=run)
    return p


def _assignment(model, text: str) -> dict:
    """``--mode`` of a model with several contacts, checked against its contacts and modes."""
    try:
        assignment = parse_assignment(text)
    except ValueError as e:
        raise ValueError(f"--mode {text}: {e}; contacts are {_name_list(c.name for c in model.contacts)}") \
            from None
    try:
        _combo(model.contacts, assignment)
    except KeyError as e:
        raise ValueError(f"--mode {text}: {e.args[0]}") from None
    return assignment


def _hint(model) -> str:
    """How to ask for another mode than all-open."""
    contacts = model.contacts
    example = ",".join(f"{c.name}={c.modes[1] if len(c.modes) > 1 else c.modes[0]}" for c in contacts[:2])
    per = sorted({len(c.modes) for c in contacts})
    sizes = f"{per[0]} per contact" if len(per) == 1 else "per contact: " + ", ".join(map(str, per))
    return (f"Only the mode with every contact open is shown: the {len(contacts)} contacts have "
            f"{mode_count(model)} mode combinations ({sizes}). Ask for one with --mode {example} "
            f"(contacts not named are open), or for one contact's equations with "
            f"--contact {contacts[0].name}.")


def run(args: argparse.Namespace) -> int:
    """Print the equations; return the exit code."""
    model = model_from_args(args)
    unicode = not args.ascii
    if args.contact is not None:
        ce = contact_equations(model, args.contact)
        text = latex_contact(ce) if args.latex else pretty_contact(ce, unicode=unicode)
    elif len(model.contacts) <= 1:
        mode = args.mode
        if mode is not None and "=" in mode:  # 'c=stick' names the one contact's mode
            mode = _mode_name(model.contacts, _combo(model.contacts, _assignment(model, mode)))
        system = derive(model)
        text = latex(system, mode) if args.latex else pretty(system, mode, unicode=unicode)
    else:
        assignment = {} if args.mode is None else _assignment(model, args.mode)
        system = derive_mode(model, assignment, guards=False)
        text = latex(system) if args.latex else pretty(system, unicode=unicode)
        if args.mode is None:
            text += ("% " if args.latex else "\n") + _hint(model) + "\n"
    print(text, end="")
    return 0
