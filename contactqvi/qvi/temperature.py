"""The temperature map Phi (E1 of seed 003): Phi(u) = I_h(varphi T), T solving (30)/(58).

    k T - Lap T = g(Psi0 + psi T - u) in Omega,   dT/dn = 0 on the boundary,

with a nonincreasing, piecewise smooth g and its Newton derivative G_g (Assumption
3.8 vi). T is found by semismooth Newton (SNES with the Newton derivative as
Jacobian), warm-started from the previous T. On P1/Q1 the obstacle is nodal, so
Phi(u) is the nodal interpolant of varphi T and its Newton derivative is
G_Phi(u) h = I_h(varphi xi_h), xi_h solving the linearised equation (33).
"""

from __future__ import annotations

import dataclasses
import typing

from petsc4py import PETSc

import ufl

import dolfinx.fem.petsc
from dolfinx import fem

from contactqvi.linalg import create_snes, reassemble_matrix
from contactqvi.parameters import require_positive
from contactqvi.vi.nonlinear import NonlinearFormProblem, snes_converged_reason

__all__ = ["ScalarNonlinearity", "TemperatureMap", "DEFAULT_PHI_OPTIONS"]

UFLMap = typing.Callable[[ufl.core.expr.Expr], ufl.core.expr.Expr]

#: Semismooth Newton defaults for (30); -phi_snes_... overrides them.
DEFAULT_PHI_OPTIONS = {
    "snes_type": "newtonls",
    "snes_linesearch_type": "bt",
    "snes_rtol": 1e-13,
    "snes_atol": 1e-15,
    "snes_stol": 1e-14,
    "snes_max_it": 50,
    "ksp_type": "preonly",
    "pc_type": "lu",
    "pc_factor_mat_solver_type": "mumps",
}


@dataclasses.dataclass(frozen=True)
class ScalarNonlinearity:
    """A (possibly nonsmooth) scalar function g with a Newton derivative G_g, both on UFL expressions."""

    g: UFLMap
    derivative: UFLMap


class TemperatureMap:
    """Evaluate Phi(u) = I_h(varphi T) and its Newton derivative, (29)-(33).

    Args:
        V: scalar P1/Q1 space of u and T.
        k: the constant k > 0.
        g: the nonlinearity and its Newton derivative.
        Psi0, psi, varphi: the data of (58) as UFL expressions (or Functions).
        quadrature_degree: quadrature of the nonsmooth terms (shared by residual
            and Jacobian so that the Newton derivative is consistent).
        prefix: PETSc options prefix of the SNES.
    """

    def __init__(
        self,
        V: fem.FunctionSpace,
        k: float,
        g: ScalarNonlinearity,
        Psi0: ufl.core.expr.Expr,
        psi: ufl.core.expr.Expr,
        varphi: ufl.core.expr.Expr,
        quadrature_degree: int = 2,
        prefix: str = "phi_",
    ):
        require_positive("k", k)
        self.V = V
        self.u = fem.Function(V, name="membrane_input")
        self.T = fem.Function(V, name="temperature")
        T, u = self.T, self.u
        v, dT = ufl.TestFunction(V), ufl.TrialFunction(V)
        dx = ufl.Measure("dx", domain=V.mesh, metadata={"quadrature_degree": quadrature_degree})
        s = Psi0 + psi * T - u
        F = k * T * v * dx + ufl.inner(ufl.grad(T), ufl.grad(v)) * ufl.dx - g.g(s) * v * dx
        J = k * dT * v * dx + ufl.inner(ufl.grad(dT), ufl.grad(v)) * ufl.dx - g.derivative(s) * psi * dT * v * dx
        self.jacobian_form = fem.form(J)
        #: (G_g(s) h, zeta): the u-derivative of the residual, the coupling block of (63).
        self.coupling_form = fem.form(g.derivative(s) * ufl.TrialFunction(V) * v * dx)
        #: the matrices of (33)/(63), allocated here and re-assembled in place
        self.jacobian_matrix = dolfinx.fem.petsc.assemble_matrix(self.jacobian_form)
        self.jacobian_matrix.assemble()
        self.coupling_matrix = dolfinx.fem.petsc.assemble_matrix(self.coupling_form)
        self.coupling_matrix.assemble()
        self.nonlinear = NonlinearFormProblem(fem.form(F), self.jacobian_form, T, [])
        self.snes = create_snes(V.mesh.comm, prefix, DEFAULT_PHI_OPTIONS)
        self.snes.setConvergenceHistory(reset=True)
        self.nonlinear.attach(self.snes)
        self.varphi = fem.Function(V, name="varphi")
        self.varphi.interpolate(fem.Expression(varphi, V.element.interpolation_points(), comm=V.mesh.comm))
        self.x = T.x.petsc_vec.duplicate()
        self.residual_history: list[float] = []
        #: residual of the first (cold) solve: the scale for round-off stagnation
        self.reference_norm: float | None = None
        self.roundoff = 1e-10

    def solve(self, u: fem.Function) -> int:
        """Solve (30) for T at ``u`` (warm start from the current T); returns Newton steps."""
        u.x.petsc_vec.copy(self.u.x.petsc_vec)
        self.u.x.scatter_forward()
        self.T.x.petsc_vec.copy(self.x)
        self.snes.solve(None, self.x)
        self.x.copy(self.T.x.petsc_vec)
        self.T.x.scatter_forward()
        self.residual_history = [float(r) for r in self.snes.getConvergenceHistory()[0]]
        if self.reference_norm is None:
            self.reference_norm = self.residual_history[0]
        reason = self.snes.getConvergedReason()
        # A line search that cannot decrease a residual at round-off level is convergence.
        stagnated = reason == PETSc.SNES.ConvergedReason.DIVERGED_LINE_SEARCH and (
            self.residual_history[-1] <= self.roundoff * self.reference_norm
        )
        if reason <= 0 and not stagnated:
            raise RuntimeError(f"Phi: semismooth Newton for the temperature failed ({snes_converged_reason(self.snes)})")
        return self.snes.getIterationNumber()

    def apply(self, out: fem.Function) -> None:
        """out = I_h(varphi T) for the current T."""
        out.x.array[:] = self.varphi.x.array * self.T.x.array

    def assemble_jacobian(self) -> PETSc.Mat:
        """Newton derivative of (30) in T at the current (u, T): the matrix of (33)/(63).

        Re-assembled in place into :attr:`jacobian_matrix` (owned by this map: do not destroy).
        """
        return reassemble_matrix(self.jacobian_matrix, self.jacobian_form)

    def assemble_coupling(self) -> PETSc.Mat:
        """Matrix of (G_g(Psi0 + psi T - u) h, zeta), the h-term of (63).

        Re-assembled in place into :attr:`coupling_matrix` (owned by this map: do not destroy).
        """
        return reassemble_matrix(self.coupling_matrix, self.coupling_form)

    def derivative(self, h: fem.Function, out: fem.Function) -> None:
        """out = G_Phi(u) h = I_h(varphi xi_h), xi_h from (33) at the current (u, T)."""
        A, C = self.assemble_jacobian(), self.assemble_coupling()
        rhs = A.createVecLeft()
        C.mult(h.x.petsc_vec, rhs)
        rhs.scale(-1.0)
        ksp = PETSc.KSP().create(self.V.mesh.comm)
        ksp.setOperators(A)
        ksp.setType("preonly")
        ksp.getPC().setType("lu")
        ksp.getPC().setFactorSolverType("mumps")
        ksp.solve(rhs, out.x.petsc_vec)
        out.x.scatter_forward()
        out.x.array[:] *= self.varphi.x.array
        rhs.destroy()
        ksp.destroy()

    def destroy(self) -> None:
        for obj in (self.snes, self.nonlinear, self.x, self.jacobian_matrix, self.coupling_matrix):
            obj.destroy()
