"""blademodel: rub-impact dynamics of shrouded turbine blades."""

__version__ = "0.1.0"

from .model import Model  # noqa: E402

__all__ = ["Model", "__version__"]
