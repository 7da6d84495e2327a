"""Hyperelastic materials: a strain-energy density psi(F) in UFL, one small module each.

A body's material is linear elasticity (small strain, the default: no module, the
stiffness is one constant matrix) or one of :data:`MATERIALS`, whose first
Piola-Kirchhoff stress P = d psi / d F and tangent follow from ``ufl.derivative``
(:mod:`contactqvi.contact.hyperelastic`). Each material is parametrised by Young's
modulus and Poisson's ratio of its linearisation at F = I, so that a hyperelastic body
and a linear one agree at small strain. A new model is a module here (a
:class:`Material` subclass with ``name`` and ``strain_energy``) and an import below.
"""

from contactqvi.materials.base import FORMULATIONS, MATERIALS, Material, create_material

# Imported in this order, the materials are listed in this order (MATERIALS, error messages).
from contactqvi.materials.neo_hookean import NeoHookean
from contactqvi.materials.saint_venant_kirchhoff import SaintVenantKirchhoff

__all__ = ["FORMULATIONS", "MATERIALS", "Material", "NeoHookean", "SaintVenantKirchhoff", "create_material"]
