"""Contact laws: each one object that the case reader, the problem builder and the solver ask.

:class:`ContactLaw` is a law as a case file gives it (``law = "coulomb"``,
``friction = 0.3``); :meth:`ContactLaw.lumped` turns it into the :class:`NodalLaw` of
the slave nodes, the slip bound b(lambda) and its slope that the nodal algebra of
:mod:`contactqvi.contact.nodal` (resolvent, states, SCD bases) is written in. The
laws, one module each, registered in :data:`LAWS` by defining them:

* :class:`Coulomb` (``coulomb``): b = F lambda, seed 000;
* :class:`Tresca` (``tresca``): b = tau times the node's area;
* :class:`Frictionless` (``frictionless``): b = 0;
* :class:`PressureDependentCoulomb` (``pressure_coulomb``): b = F(p) lambda with a
  coefficient that moves from F0 to F_inf as the pressure p = lambda / area grows.

A new law is a module here (a :class:`ContactLaw` subclass and the :class:`NodalLaw`
its ``lumped`` returns) and an import below. This package imports no solver.
"""

from contactqvi.laws.base import (
    DEFAULT_LAW,
    LAWS,
    ContactLaw,
    LawParameter,
    LinearSlipBound,
    NodalLaw,
    StackedLaw,
    create_law,
    parameter_names,
)

# Imported in this order, the laws are listed in this order (LAWS, error messages, --help).
from contactqvi.laws.coulomb import Coulomb
from contactqvi.laws.tresca import Tresca
from contactqvi.laws.frictionless import Frictionless
from contactqvi.laws.pressure_coulomb import PressureCoulombBound, PressureDependentCoulomb

__all__ = [
    "DEFAULT_LAW",
    "LAWS",
    "ContactLaw",
    "Coulomb",
    "Frictionless",
    "LawParameter",
    "LinearSlipBound",
    "NodalLaw",
    "PressureCoulombBound",
    "PressureDependentCoulomb",
    "StackedLaw",
    "Tresca",
    "create_law",
    "parameter_names",
]
