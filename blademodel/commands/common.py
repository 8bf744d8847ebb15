"""Arguments and helpers shared by subcommands."""

from __future__ import annotations

import argparse

from ..config import ConfigError, load_model
from ..model import Model


def add_model_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the ``MODEL.yaml`` positional argument and repeatable ``--set NAME=VALUE``."""
    parser.add_argument("model", metavar="MODEL.yaml",
                        help="model config (blade_pair, bladed_disk or components format)")
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="NAME=VALUE",
                        help="override a config field, e.g. --set gamma=5 or --set contacts.0.gap=1e-5 "
                             "(repeatable)")


def add_stepping_arguments(parser: argparse.ArgumentParser) -> None:
    """Add ``--steps-per-period``, ``--method`` and ``--event-tol`` (the integrator's settings)."""
    parser.add_argument("--steps-per-period", type=int, default=1000, metavar="S",
                        help="steps per excitation period (default 1000)")
    parser.add_argument("--method", choices=("rk4", "rk8"), default="rk4",
                        help="stepping method: classical RK4 (default) or an eighth-order Runge-Kutta method")
    parser.add_argument("--event-tol", type=float, default=1e-10, metavar="E",
                        help="event bracket, as a fraction of the step (default 1e-10)")


def add_jacobian_arguments(parser: argparse.ArgumentParser) -> None:
    """Add ``--jacobian`` and ``--workers`` (how the period map is differentiated, and in how many threads)."""
    from ..orbits.period_map import JACOBIAN_METHODS
    parser.add_argument("--jacobian", choices=JACOBIAN_METHODS, default="auto",
                        help="how the period map is differentiated: auto (the tangent of the flow, or central "
                             "differences where it fails), tangent, differences (central), forward (half the "
                             "integrations of central differences, multipliers to about 1e-6)")
    parser.add_argument("--workers", type=int, default=None, metavar="N",
                        help="threads for Jacobians by differences, and (continue, N >= 2) a thread that locates "
                             "grazing points beside the continuation (default: all cores; the result is the same "
                             "whatever N; give 1 where several runs share the machine)")


def check_at_least_one(args: argparse.Namespace, names) -> None:
    """``ValueError`` naming the first option of ``names`` (attribute names) below 1."""
    for name in names:
        if getattr(args, name) < 1:
            raise ValueError(f"--{name.replace('_', '-')} must be at least 1, got {getattr(args, name)}")


def config_and_model(args: argparse.Namespace):
    """The config of ``args.model`` with ``--set`` applied, and its built model.

    Raises
    ------
    ConfigError
        Naming the file, where the config is valid field by field but cannot be built.
    """
    from ..config import apply_overrides, load_config
    config = apply_overrides(load_config(args.model), parse_overrides(args.overrides))
    try:
        return config, config.build()
    except ValueError as e:
        raise ConfigError(f"{args.model}: {e}", path=str(args.model)) from None


def parse_overrides(items: list[str]) -> dict[str, str]:
    """``["gamma=5"]`` -> ``{"gamma": "5"}``.

    Raises
    ------
    ConfigError
        For an item without ``=``.
    """
    out = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise ConfigError(f"--set {item!r}: expected NAME=VALUE")
        out[name.strip()] = value.strip()
    return out


def model_from_args(args: argparse.Namespace) -> Model:
    """The model of ``args.model`` with ``args.overrides`` applied."""
    return load_model(args.model, parse_overrides(getattr(args, "overrides", [])))
