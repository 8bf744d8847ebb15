"""The paper wing: what exists only for Zheng et al. (2022), built on the generic framework.

Zheng, Liu, He & Han, *Lubricants* 2022, 10, 31 (the model statement:
``docs/MODEL.md``). This package holds the paper's pair of blades as a config
(:class:`BladePair`, ``model: blade_pair``, Table 1 defaults, the literal Eq. 11
variant), the paper's figures as studies (:mod:`.studies`, the data in
``models/studies/``), the printed Eq. 11 beside the derived one (:mod:`.eq11`) and
the ``blademodel reproduce`` command (:mod:`.reproduce`). It depends on the
framework only; the framework finds it as a plugin (entry point groups
``blademodel.models`` and ``blademodel.commands``, see
:mod:`blademodel.config.kinds`), never by importing it.
"""

from ..config.kinds import register_model_kind
from .blade_pair import BladePair

register_model_kind("blade_pair", BladePair)

__all__ = ["BladePair"]
