"""Compressible neo-Hookean material (Ciarlet's form, as in the FEniCS hyperelasticity demos)."""

from __future__ import annotations

import typing

import ufl

from contactqvi.materials.base import Material

__all__ = ["NeoHookean"]


class NeoHookean(Material):
    """psi = mu/2 (I_C - 3) - mu ln J + lambda/2 (ln J)^2, I_C = tr(F^T F), J = det F.

    P = mu (F - F^-T) + lambda ln J F^-T; rubber-like, polyconvex, psi -> infinity as J -> 0.
    """

    name = "neo_hookean"

    def strain_energy(self, F: ufl.core.expr.Expr, mu: typing.Any, lmbda: typing.Any) -> ufl.core.expr.Expr:
        J = ufl.det(F)
        return mu / 2 * (ufl.tr(F.T * F) - 3) - mu * ufl.ln(J) + self.volumetric_energy(J, lmbda)

    def volumetric_energy(self, J: ufl.core.expr.Expr, lmbda: typing.Any) -> ufl.core.expr.Expr:
        """U(J) = lambda/2 (ln J)^2 (U''(1) = lambda); the remainder mu/2 (I_C - 3) - mu ln J has
        the bulk modulus 2 mu / 3 only."""
        return lmbda / 2 * ufl.ln(J) ** 2
