"""contactqvi: nonsmooth contact and quasi-variational inequalities on FEniCSx.

Semismooth Newton methods for
  * 3D contact with Coulomb friction against rigid obstacles (SCD semismooth* Newton),
    static or along quasi-static load paths, :mod:`contactqvi.contact`, with the contact
    laws of :mod:`contactqvi.laws` (Coulomb, Tresca, frictionless, pressure-dependent); a user's
    problem as a case file, :mod:`contactqvi.case` and :mod:`contactqvi.runner`;
  * Stadler's simplified friction problem, :mod:`contactqvi.friction`;
  * obstacle problems and the thermoforming QVI, :mod:`contactqvi.vi`, :mod:`contactqvi.qvi`.

The shared core: :class:`Status` and :class:`Result` (:mod:`contactqvi.result`),
:class:`Parameters` (:mod:`contactqvi.parameters`), the KSP presets of
:mod:`contactqvi.linalg`, output in :mod:`contactqvi.tables`, :mod:`contactqvi.paraview` (docs/architecture.md).
"""

from contactqvi.case import ContactCase, load_case
from contactqvi.elasticity import elasticity_forms, lame_parameters, rigid_motions_nullspace, strain, stress
from contactqvi.laws import LAWS, ContactLaw, Coulomb, Frictionless, PressureDependentCoulomb, Tresca
from contactqvi.linalg import KSP_PRESETS, preset
from contactqvi.meshes import (
    cell_partitioner,
    contact_body_sizes,
    create_contact_body,
    create_unit_interval,
    create_unit_square,
    read_gmsh,
    tag_of,
)
from contactqvi.obstacles import Cylinder, Plane, Sphere
from contactqvi.parameters import Parameter, ParameterError, Parameters
from contactqvi.postprocess import ElasticBody, applied_force, reaction_forces, stress_fields
from contactqvi.result import Result, Status
from contactqvi.runner import run_case

__version__ = "0.1.0"

__all__ = [
    "KSP_PRESETS",
    "LAWS",
    "ContactCase",
    "ContactLaw",
    "Coulomb",
    "Cylinder",
    "ElasticBody",
    "Frictionless",
    "Parameter",
    "ParameterError",
    "Parameters",
    "Plane",
    "PressureDependentCoulomb",
    "Result",
    "Sphere",
    "Status",
    "Tresca",
    "applied_force",
    "cell_partitioner",
    "contact_body_sizes",
    "create_contact_body",
    "create_unit_interval",
    "create_unit_square",
    "elasticity_forms",
    "lame_parameters",
    "load_case",
    "preset",
    "reaction_forces",
    "read_gmsh",
    "rigid_motions_nullspace",
    "run_case",
    "strain",
    "stress",
    "stress_fields",
    "tag_of",
]
