"""Point mass with named translational degrees of freedom."""

from __future__ import annotations

from dataclasses import dataclass, field

from .parameter import Number, Param, as_param


def coordinate_name(dof: str, mass: str) -> str:
    """Name of the coordinate of DOF ``dof`` of mass ``mass``.

    ``x`` of mass ``1`` is ``x1``; ``x`` of mass ``tip`` is ``x_tip``.
    """
    return f"{dof}{mass}" if mass.isdigit() else f"{dof}_{mass}"


@dataclass(frozen=True)
class Mass:
    """A lumped point mass moving along some of the axes ``x`` and ``y``.

    Each DOF is a displacement from the static rest position, positive along its
    axis. The mass contributes ``m`` to the diagonal of the mass matrix for each
    of its DOFs and ``m u^2 / 2`` per DOF to the kinetic energy.

    Parameters
    ----------
    name : str
        Identifier of the mass (``"1"``, ``"tip"``); coordinates are named from it.
    m : float or Param
        Mass in kg, > 0. Default symbol ``m_<name>``.
    dofs : tuple of str
        Axes the mass moves along, a subset of ``("x", "y")``.
    my : float or Param, optional
        A different (modal) mass for the ``y`` DOF, > 0; default ``m``. Lumped
        blade models often have different modal masses per direction.
    """

    name: str
    m: Number
    dofs: tuple[str, ...] = ("x", "y")
    my: Number | None = None
    _m: Param = field(init=False, repr=False, compare=False)
    _my: Param | None = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        if not str(self.name).isidentifier() and not str(self.name).isdigit():
            raise ValueError(f"mass name {self.name!r} must be an identifier or a number")
        object.__setattr__(self, "name", str(self.name))
        dofs = tuple(self.dofs)
        if not dofs or any(d not in ("x", "y") for d in dofs) or len(set(dofs)) != len(dofs):
            raise ValueError(f"mass {self.name}: dofs = {list(dofs)!r} must be distinct axes among 'x', 'y'")
        object.__setattr__(self, "dofs", dofs)
        object.__setattr__(self, "_m", as_param(self.m, f"m_{self.name}", field=f"mass {self.name}: m",
                                                minimum=0.0, strict=True))
        my = None if self.my is None else as_param(self.my, f"my_{self.name}", field=f"mass {self.name}: my",
                                                   minimum=0.0, strict=True)
        object.__setattr__(self, "_my", my)

    @property
    def coordinates(self) -> tuple[str, ...]:
        """Coordinate names of this mass, in DOF order."""
        return tuple(coordinate_name(d, self.name) for d in self.dofs)

    def coordinate(self, dof: str) -> str | None:
        """Coordinate name of ``dof``, or ``None`` if the mass does not move along it."""
        return coordinate_name(dof, self.name) if dof in self.dofs else None

    def parameters(self) -> dict[str, Param]:
        """Numeric parameters, by field name."""
        return {"m": self._m} if self._my is None else {"m": self._m, "my": self._my}

    def inertia(self, dof: str) -> Param:
        """The mass that multiplies the acceleration of ``dof``."""
        return self._my if dof == "y" and self._my is not None else self._m
