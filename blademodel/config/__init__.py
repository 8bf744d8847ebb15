"""Validated configs: the paper's blade pair, a bladed disk and the generic component format."""

from .blade_pair import BladePair, BladeValues
from .bladed_disk import BladedDisk, ContactValues
from .components_format import ComponentsModel
from .errors import ConfigError
from .loading import apply_overrides, config_from_data, load_config, load_model

__all__ = ["BladePair", "BladeValues", "BladedDisk", "ContactValues", "ComponentsModel", "ConfigError",
           "load_config", "load_model", "apply_overrides", "config_from_data"]
