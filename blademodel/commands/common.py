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
