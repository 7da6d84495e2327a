"""Saint Venant-Kirchhoff material: linear elasticity in the Green-Lagrange strain."""

from __future__ import annotations

import typing

import ufl

from contactqvi.materials.base import Material

__all__ = ["SaintVenantKirchhoff"]


class SaintVenantKirchhoff(Material):
    """psi = lambda/2 (tr E)^2 + mu tr(E^2), E = (F^T F - I)/2.

    S = lambda tr E I + 2 mu E; large rotations, moderate strains (it softens and loses
    stability in strong compression).
    """

    name = "saint_venant_kirchhoff"

    def strain_energy(self, F: ufl.core.expr.Expr, mu: typing.Any, lmbda: typing.Any) -> ufl.core.expr.Expr:
        E = (F.T * F - ufl.Identity(F.ufl_shape[0])) / 2
        return lmbda / 2 * ufl.tr(E) ** 2 + mu * ufl.tr(E * E)
