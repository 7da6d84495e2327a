"""The material interface: a strain-energy density of the deformation gradient, in UFL."""

from __future__ import annotations

import abc
import typing

import ufl

from contactqvi.parameters import ParameterError, require_choice

__all__ = ["FORMULATIONS", "MATERIALS", "Material", "create_material"]

#: Hyperelastic materials by name, registered by defining a subclass of :class:`Material`.
MATERIALS: dict[str, type[Material]] = {}

#: The discretisations of a body's volume change (``formulation`` of a case's material):
#: ``"displacement"`` (plain P1, cell-wise) and ``"nodal_pressure"`` (the nodally averaged
#: volume change of :mod:`contactqvi.nodal_pressure`, for nearly incompressible bodies).
FORMULATIONS = ("displacement", "nodal_pressure")


class Material(abc.ABC):
    """A hyperelastic material: strain energy psi(F) per unit reference volume (J/m^3).

    Its Lamé parameters (mu, lambda) are those of its linearisation at F = I, computed
    from Young's modulus and Poisson's ratio by
    :func:`~contactqvi.elasticity.lame_parameters`.
    """

    name: typing.ClassVar[str]
    #: Quadrature degree of the stress integrals (residual, tangent, reactions, stress
    #: averages) per degree of the displacements: exact for the linear part on P1 tetrahedra
    #: and Q1 hexahedra (2 x 2 x 2 Gauss points); UFL's estimate for ln J and F^-T would be far
    #: higher. Quadratic tetrahedra take twice it: with a rule of degree 2 a neo-Hookean block
    #: of 10-node tetrahedra pressed by 10 % per step took 37-59 exact Newton steps per step
    #: (line-search steps of 1e-4: the under-integrated tangent), with degree 4 9-14.
    quadrature_degree: typing.ClassVar[int] = 2

    def __init_subclass__(cls, **kwargs: typing.Any) -> None:
        super().__init_subclass__(**kwargs)
        MATERIALS[cls.name] = cls

    @abc.abstractmethod
    def strain_energy(self, F: ufl.core.expr.Expr, mu: typing.Any, lmbda: typing.Any) -> ufl.core.expr.Expr:
        """psi(F) for the Lamé parameters ``mu``, ``lmbda`` (numbers or UFL expressions)."""

    def volumetric_energy(self, J: ufl.core.expr.Expr, lmbda: typing.Any) -> ufl.core.expr.Expr:
        """U(J): the part of psi that carries lambda and depends on J = det F alone, with
        U''(1) = lambda (the nodally averaged formulation averages it, :mod:`contactqvi.nodal_pressure`).

        Raises:
            ParameterError: the material has no such part (``material.formulation``).
        """
        raise ParameterError("material.formulation", f"'nodal_pressure' needs a volumetric energy U(J); "
                             f"{self.name} has none (use 'neo_hookean')")

    def first_piola(self, u: ufl.core.expr.Expr, mu: typing.Any, lmbda: typing.Any) -> ufl.core.expr.Expr:
        """P = d psi / d F at F = I + grad u (Pa), by UFL's differentiation of psi."""
        F = ufl.variable(ufl.Identity(u.ufl_shape[0]) + ufl.grad(u))
        return ufl.diff(self.strain_energy(F, mu, lmbda), F)

    def cauchy_stress(self, u: ufl.core.expr.Expr, mu: typing.Any, lmbda: typing.Any) -> ufl.core.expr.Expr:
        """sigma = P F^T / det F at F = I + grad u (Pa): the true stress in the deformed body."""
        F = ufl.Identity(u.ufl_shape[0]) + ufl.grad(u)
        return self.first_piola(u, mu, lmbda) * F.T / ufl.det(F)

    def dx(self, degree: int = 1) -> ufl.Measure:
        """The cell measure of this material's stress integrals for displacements of polynomial
        ``degree`` (:attr:`quadrature_degree` times it)."""
        return ufl.dx(metadata={"quadrature_degree": self.quadrature_degree * degree})

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


def create_material(name: str, path: str = "material.model") -> Material:
    """The material called ``name``; a :class:`~contactqvi.parameters.ParameterError` named
    ``path`` for an unknown one."""
    require_choice(path, name, MATERIALS)
    return MATERIALS[name]()
