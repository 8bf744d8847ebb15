"""Validated configs: the paper's blade pair and the generic component format."""

from .blade_pair import BladePair, BladeValues
from .components_format import ComponentsModel
from .errors import ConfigError
from .loading import apply_overrides, config_from_data, load_config, load_model

__all__ = ["BladePair", "BladeValues", "ComponentsModel", "ConfigError", "load_config", "load_model",
           "apply_overrides", "config_from_data"]
