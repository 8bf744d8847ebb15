"""Validated configs: a bladed disk and the generic component format (the paper's pair: :mod:`blademodel.zheng2022`)."""

from .blade_values import BladeValues
from .bladed_disk import BladedDisk, ContactValues
from .components_format import ComponentsModel
from .errors import ConfigError
from .loading import apply_overrides, config_from_data, load_config, load_model

__all__ = ["BladeValues", "BladedDisk", "ContactValues", "ComponentsModel", "ConfigError",
           "load_config", "load_model", "apply_overrides", "config_from_data"]
