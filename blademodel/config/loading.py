"""Read a model config from YAML, with errors that point at the file and line.

The ``model:`` key selects the format: ``components`` (:class:`ComponentsModel`, a
list of components), ``bladed_disk`` (:class:`BladedDisk`, a ring of the paper's
blades) or a kind a plugin registers (:mod:`blademodel.config.kinds`), such as
``blade_pair`` (:class:`blademodel.zheng2022.BladePair`, the paper's pair with
Table 1 defaults). A validation error names the file, the line, the field path and
the value::

    models/x.yaml:7: masses.0.m = -1.0: Input should be greater than 0

The line is found by walking the node tree of ``yaml.compose`` along the
pydantic error location.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping, Optional, Union

import yaml
from pydantic import ValidationError

from ..model import Model
from .bladed_disk import BladedDisk
from .components_format import ComponentsModel
from .errors import ConfigError, FieldError, format_loc, format_value
from .kinds import model_kinds, register_model_kind

Config = Union[ComponentsModel, BladedDisk, Any]   # or a kind a plugin registers (blademodel.config.kinds)

register_model_kind("components", ComponentsModel)
register_model_kind("bladed_disk", BladedDisk)


# --- locating errors -------------------------------------------------------------------
def _clean_loc(data: Any, loc: tuple) -> tuple:
    """Drop the parts of a pydantic ``loc`` that are not in the data (union tags)."""
    out, cur = [], data
    for i, part in enumerate(loc):
        last = i == len(loc) - 1
        if isinstance(cur, dict):
            if part in cur:
                out.append(part)
                cur = cur[part]
            elif last:
                out.append(part)  # a missing or extra field
        elif isinstance(cur, list) and isinstance(part, int) and 0 <= part < len(cur):
            out.append(part)
            cur = cur[part]
        elif last:
            out.append(part)  # inside a value a before-validator expanded
    return tuple(out)


def _line(root: Optional[yaml.Node], loc: tuple) -> Optional[int]:
    """1-based line of the deepest node along ``loc`` (a key's line for a mapping value)."""
    if root is None:
        return None
    node, line = root, root.start_mark.line
    for part in loc:
        if isinstance(node, yaml.MappingNode):
            for key, value in node.value:
                if isinstance(key, yaml.ScalarNode) and key.value == str(part):
                    node, line = value, key.start_mark.line
                    break
            else:
                break
        elif isinstance(node, yaml.SequenceNode) and isinstance(part, int) and 0 <= part < len(node.value):
            node = node.value[part]
            line = node.start_mark.line
        else:
            break
    return line + 1


def _describe(err: dict, data: Any) -> tuple[tuple, str]:
    """``(loc, "path = value: message")`` of one pydantic error."""
    ctx_err = (err.get("ctx") or {}).get("error")
    if isinstance(ctx_err, FieldError):
        loc = _clean_loc(data, tuple(err["loc"]) + ctx_err.loc)
        value, msg, has_value = ctx_err.value, ctx_err.reason, ctx_err.value is not None
    else:
        loc = _clean_loc(data, tuple(err["loc"]))
        value, msg = err.get("input"), err["msg"]
        has_value = err["type"] != "missing"
        if msg.startswith("Value error, "):
            msg = msg[len("Value error, "):]
    path = format_loc(loc)
    if not path:
        return loc, msg
    return loc, f"{path} = {format_value(value)}: {msg}" if has_value else f"{path}: {msg}"


def _validation_error(exc: ValidationError, data: Any, source: str, root=None) -> ConfigError:
    lines, first = [], None
    for err in exc.errors():
        loc, text = _describe(err, data)
        line = _line(root, loc) if loc else None
        first = first or line
        lines.append(f"{source}:{line}: {text}" if line else f"{source}: {text}")
    return ConfigError("\n".join(lines), path=source, line=first)


def _check_duplicate_keys(node, source: str):
    """PyYAML keeps the last of duplicate keys silently; refuse them instead."""
    if isinstance(node, yaml.MappingNode):
        seen = set()
        for key, value in node.value:
            if isinstance(key, yaml.ScalarNode):
                if key.value in seen:
                    line = key.start_mark.line + 1
                    raise ConfigError(f"{source}:{line}: duplicate key {key.value!r}", path=source, line=line)
                seen.add(key.value)
            _check_duplicate_keys(value, source)
    elif isinstance(node, yaml.SequenceNode):
        for item in node.value:
            _check_duplicate_keys(item, source)


# --- public API -------------------------------------------------------------------------
def config_from_data(data: Any, *, source: str = "<config>", root: Optional[yaml.Node] = None) -> Config:
    """Validate already-parsed config data, dispatching on its ``model:`` key.

    Parameters
    ----------
    data : dict
        The parsed YAML.
    source : str
        Name of the origin, used in error messages.
    root : yaml.Node, optional
        The composed node tree of the same text, to give line numbers.

    Raises
    ------
    ConfigError
    """
    if not isinstance(data, dict):
        raise ConfigError(f"{source}: expected a mapping with a 'model:' key, got {format_value(data)}",
                          path=source)
    kind = data.get("model")
    kinds = model_kinds()
    if kind not in kinds:
        line = _line(root, ("model",)) if "model" in data else (1 if root is not None else None)
        where = f"{source}:{line}" if line else source
        what = f"model = {format_value(kind)}" if "model" in data else "model: missing key"
        raise ConfigError(f"{where}: {what}: expected one of {', '.join(map(repr, kinds))} (further kinds come "
                          f"from installed plugins: 'pip install -e .' registers the paper's 'blade_pair')",
                          path=source, line=line)
    try:
        return kinds[kind].model_validate(data)
    except ValidationError as e:
        raise _validation_error(e, data, source, root) from None


def _decode(raw: bytes, source: str) -> str:
    """The text of a config file: UTF-8 without NUL bytes, else a :class:`ConfigError` naming the file."""
    if b"\x00" in raw[:8192]:
        raise ConfigError(f"{source}: not a text file (it holds NUL bytes): a config is YAML text "
                          f"in UTF-8", path=source)
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as e:
        line = raw[:e.start].count(b"\n") + 1
        raise ConfigError(f"{source}:{line}: not UTF-8 text (byte 0x{raw[e.start]:02x} at offset {e.start}: "
                          f"{e.reason}); save the config as UTF-8", path=source, line=line) from None


def read_yaml(path: Union[str, Path]) -> tuple[Any, Optional[yaml.Node]]:
    """Parse a YAML file into ``(data, node tree)``; errors give ``file:line``.

    Raises
    ------
    ConfigError
        On an unreadable file, a YAML syntax error or a duplicate key.
    """
    source = str(path)
    try:
        raw = Path(path).read_bytes()
    except OSError as e:
        raise ConfigError(f"{source}: cannot read: {e.strerror or e}", path=source) from None
    text = _decode(raw, source)
    try:
        root = yaml.compose(text, Loader=yaml.SafeLoader)
        if root is not None:
            _check_duplicate_keys(root, source)
        data = yaml.load(text, Loader=yaml.SafeLoader)
    except yaml.MarkedYAMLError as e:
        mark = e.problem_mark or e.context_mark
        line = mark.line + 1 if mark else None
        context = e.context
        if context and e.context_mark and e.context_mark.line + 1 != line:
            context += f" (from line {e.context_mark.line + 1})"
        what = ": ".join(x for x in (context, e.problem) if x)
        raise ConfigError(f"{source}:{line}: YAML syntax error: {what}", path=source, line=line) from None
    except yaml.YAMLError as e:
        raise ConfigError(f"{source}: YAML error: {e}", path=source) from None
    return data, root


def validate_file(schema: type, path: Union[str, Path]):
    """Read ``path`` and validate it with the pydantic ``schema`` (errors name file:line)."""
    data, root = read_yaml(path)
    try:
        return schema.model_validate(data)
    except ValidationError as e:
        raise _validation_error(e, data, str(path), root) from None


def load_config(path: Union[str, Path]) -> Config:
    """Read and validate a YAML model config.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    BladedDisk, ComponentsModel or a plugin's config (the paper's BladePair)
        Selected by the file's ``model:`` key.

    Raises
    ------
    ConfigError
        On an unreadable file, a YAML syntax error or an invalid value; the
        message gives ``file:line``, the field path and the value.
    """
    data, root = read_yaml(path)
    return config_from_data(data, source=str(path), root=root)


def parse_value(text: str) -> Any:
    """A ``--set`` value as YAML reads it (``5`` -> 5, ``[x, y]`` -> list); else the text."""
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError:
        return text


def _set_path(data: dict, name: str, value: Any, source: str):
    parts = name.split(".")
    if len(parts) == 1 and name not in data and name in (data.get("parameters") or {}):
        parts = ["parameters", name]  # components format: a bare name is a parameter
    cur = data
    for i, part in enumerate(parts):
        last = i == len(parts) - 1
        here = ".".join(parts[:i + 1])
        if isinstance(cur, dict):
            if part not in cur and part.lstrip("-").isdigit() and int(part) in cur:
                part = int(part)  # a mapping keyed by index (a disk's contacts)
            if part not in cur and (cur or not last):
                known = ", ".join(map(str, cur)) or "none"
                raise ConfigError(f"{source} {name}: unknown field {here!r} (known: {known})", path=source)
            if last:
                cur[part] = value
            else:
                if cur[part] is None:
                    cur[part] = {}
                cur = cur[part]
        elif isinstance(cur, list):
            try:
                idx = int(part)
                cur[idx]
            except (ValueError, IndexError):
                raise ConfigError(f"{source} {name}: {here!r} is not an index of a list of {len(cur)}",
                                  path=source) from None
            if last:
                cur[idx] = value
            else:
                cur = cur[idx]
        else:
            raise ConfigError(f"{source} {name}: {'.'.join(parts[:i])!r} has no field {part!r}", path=source)


def apply_overrides(config: Config, overrides: Mapping[str, Any], *, source: str = "--set") -> Config:
    """A copy of ``config`` with fields replaced, revalidated.

    Parameters
    ----------
    config : BladePair, BladedDisk or ComponentsModel
    overrides : mapping of str to object
        Dotted field paths (``gamma``, ``blade1.m``, ``contacts.0.gap``) to values;
        strings are read as YAML scalars (``"5"`` -> 5, ``"1e5"`` is converted by
        validation). In the components format a bare name of a declared
        parameter sets that parameter (``omega`` = ``parameters.omega``).
    source : str
        Label of the overrides in error messages.

    Raises
    ------
    ConfigError
        On an unknown field or an invalid value, naming the field and the value.
    """
    data = config.model_dump()
    for name, value in overrides.items():
        _set_path(data, name, parse_value(value) if isinstance(value, str) else value, source)
    try:
        return type(config).model_validate(data)
    except ValidationError as e:
        raise _validation_error(e, data, source) from None


def load_model(path: Union[str, Path], overrides: Optional[Mapping[str, Any]] = None) -> Model:
    """Read a YAML config and build its :class:`~blademodel.model.Model`.

    Parameters
    ----------
    path : str or Path
    overrides : mapping, optional
        Passed to :func:`apply_overrides` before building.

    Raises
    ------
    ConfigError
    """
    config = load_config(path)
    if overrides:
        config = apply_overrides(config, overrides)
    try:
        return config.build()
    except ValueError as e:
        raise ConfigError(f"{path}: {e}", path=str(path)) from None
