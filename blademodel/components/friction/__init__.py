"""Friction laws and the interface they share."""

from .base import STICK, Candidate, ContactContext, FrictionLaw, Guard, StickConstraint
from .coulomb import Coulomb
from .jenkins import Jenkins
from .none import NoFriction

__all__ = ["FrictionLaw", "ContactContext", "Candidate", "Guard", "StickConstraint", "STICK",
           "Coulomb", "Jenkins", "NoFriction"]
