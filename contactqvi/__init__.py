"""contactqvi: nonsmooth contact and quasi-variational inequalities on FEniCSx.

Semismooth Newton methods for
  * 3D contact with Coulomb friction (SCD semismooth* Newton), :mod:`contactqvi.contact`;
  * Stadler's simplified friction problem, :mod:`contactqvi.friction`;
  * obstacle problems and the thermoforming QVI, :mod:`contactqvi.vi`, :mod:`contactqvi.qvi`.
"""

from contactqvi.elasticity import elasticity_forms, lame_parameters, rigid_motions_nullspace, strain, stress
from contactqvi.meshes import (
    contact_body_sizes,
    create_contact_body,
    create_unit_interval,
    create_unit_square,
    read_gmsh,
    tag_of,
)
from contactqvi.parameters import ParameterError

__version__ = "0.1.0"

__all__ = [
    "ParameterError",
    "contact_body_sizes",
    "create_contact_body",
    "create_unit_interval",
    "create_unit_square",
    "elasticity_forms",
    "lame_parameters",
    "read_gmsh",
    "rigid_motions_nullspace",
    "strain",
    "stress",
    "tag_of",
]
