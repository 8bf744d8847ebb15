"""Building blocks of a model: masses, springs, dampers, forces, contacts, friction."""

from .contact import Contact
from .damper import Damper
from .force import ConstantForce, Harmonic, HarmonicForce, MultiHarmonicForce
from .friction import Coulomb, FrictionLaw, Iwan, Jenkins, NoFriction
from .mass import Mass, coordinate_name
from .parameter import Param
from .spring import Spring

__all__ = ["Mass", "Spring", "Damper", "ConstantForce", "HarmonicForce", "MultiHarmonicForce", "Harmonic",
           "Contact", "Param", "FrictionLaw", "Coulomb", "Jenkins", "NoFriction", "Iwan", "coordinate_name"]
