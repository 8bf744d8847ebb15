"""Friction laws, the interface they share, and the registry of laws by name."""

from .base import STICK, Candidate, ContactContext, FrictionLaw, Guard, StickConstraint
from .coulomb import Coulomb
from .iwan import Iwan
from .jenkins import Jenkins
from .none import NoFriction
from .registry import ENTRY_POINT_GROUP, known_names, law_class, make_law, registered_laws

__all__ = ["FrictionLaw", "ContactContext", "Candidate", "Guard", "StickConstraint", "STICK",
           "Coulomb", "Jenkins", "NoFriction", "Iwan", "ENTRY_POINT_GROUP", "known_names", "law_class",
           "make_law", "registered_laws"]
