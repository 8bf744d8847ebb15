"""Per-blade values of a 2-DOF blade (mass, stiffnesses, dampings): the overrides of one blade.

Shared by the configs that assemble such blades (the bladed disk, and the paper's
pair in :mod:`blademodel.zheng2022`); unset values fall back to the config's own.
"""

from __future__ import annotations

from typing import Optional

from pydantic import Field

from .strict import StrictConfig


class BladeValues(StrictConfig):
    """Values of one blade (unset values fall back to the config's)."""

    m: Optional[float] = Field(None, gt=0, description="mass, kg")
    kx: Optional[float] = Field(None, ge=0, description="tangential stiffness, N/m")
    ky: Optional[float] = Field(None, ge=0, description="axial stiffness, N/m")
    cx: Optional[float] = Field(None, ge=0, description="tangential damping, N s/m")
    cy: Optional[float] = Field(None, ge=0, description="axial damping, N s/m")
