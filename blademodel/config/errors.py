"""Errors of config validation and loading."""

from __future__ import annotations

from typing import Any, Sequence


def format_loc(loc: Sequence) -> str:
    """Dotted field path of a pydantic ``loc`` (``("masses", 0, "m")`` -> ``masses.0.m``)."""
    return ".".join(str(p) for p in loc)


def format_value(value: Any, limit: int = 60) -> str:
    """Short text of an offending value: ``repr`` for strings, ``str`` otherwise."""
    text = repr(value) if isinstance(value, str) else str(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


class ConfigError(ValueError):
    """A config that cannot be read or validated.

    The message names the file and line where known, the field path and the
    offending value: ``models/x.yaml:7: masses.0.m = -1.0: Input should be greater than 0``.

    Attributes
    ----------
    path : str or None
        The config file, if the config came from one.
    line : int or None
        1-based line of the first error.
    """

    def __init__(self, message: str, *, path: str | None = None, line: int | None = None):
        super().__init__(message)
        self.path = path
        self.line = line


class FieldError(ValueError):
    """A validation error located at a field path, raised inside model validators.

    Pydantic reports errors of a model validator at the model itself; the loader
    reads :attr:`loc` from this exception to point at the offending field.

    Parameters
    ----------
    loc : tuple
        Field path from the root of the config (``("springs", 0, "a")``).
    value : object
        The offending value.
    reason : str
        What is wrong with it.
    """

    def __init__(self, loc: Sequence, value: Any, reason: str):
        self.loc = tuple(loc)
        self.value = value
        self.reason = reason
        where = format_loc(self.loc)
        if where and value is not None:
            where += f" = {format_value(value)}"
        super().__init__(f"{where}: {reason}" if where else reason)
