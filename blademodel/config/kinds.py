"""Config kinds by the value of a config's ``model:`` key: the framework's own and those plugins add.

The framework knows ``components`` and ``bladed_disk``. Another package adds a kind
by registering its pydantic config class (which must have a ``model`` literal field
and a ``build()`` method) under the entry point group ``blademodel.models`` in its
``pyproject.toml``, or by calling :func:`register_model_kind` when imported. The
paper's pair (``blade_pair``) comes this way from :mod:`blademodel.zheng2022`, so
the framework never imports it. Like the friction laws, kinds come from the
installed package metadata: a checkout used without ``pip install -e .`` knows only
the framework's kinds until the plugin is imported.
"""

from __future__ import annotations

from importlib.metadata import entry_points

#: Entry point group of config kinds (name: the ``model:`` value, object: the config class).
ENTRY_POINT_GROUP = "blademodel.models"
_KINDS: dict[str, type] = {}
_LOADED = False


def register_model_kind(name: str, cls: type) -> None:
    """Make ``model: <name>`` configs validate as ``cls``."""
    _KINDS[name] = cls


def _load_plugins() -> None:
    global _LOADED
    if _LOADED:
        return
    _LOADED = True
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        _KINDS.setdefault(ep.name, ep.load())


def model_kinds() -> dict[str, type]:
    """Every known kind: ``{name: config class}``, plugins loaded."""
    _load_plugins()
    return dict(_KINDS)
