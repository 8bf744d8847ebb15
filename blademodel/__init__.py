"""blademodel: rub-impact dynamics of shrouded turbine blades."""

__version__ = "0.1.0"

from .model import Model  # noqa: E402

__all__ = ["Model", "open_result", "__version__"]


def __getattr__(name):
    # open_result on first use: importing blademodel does not load xarray and the sweep machinery
    if name == "open_result":
        from .sweep import open_result
        return open_result
    raise AttributeError(f"module 'blademodel' has no attribute {name!r}")
