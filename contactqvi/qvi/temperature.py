"""The temperature map Phi (E1 of seed 003): Phi(u) = I_h(varphi T), T solving (30)/(58).

    k T - Lap T = g(Psi0 + psi T - u) in Omega,   dT/dn = 0 on the boundary,

with a nonincreasing, piecewise smooth g and its Newton derivative G_g (Assumption
3.8 vi). T is found by semismooth Newton (SNES with the Newton derivative as
Jacobian), warm-started from the previous T. On P1/Q1 the obstacle is nodal, so
Phi(u) is the nodal interpolant of varphi T and its Newton derivative is
G_Phi(u) h = I_h(varphi xi_h), xi_h solving the linearised equation (33).
"""

from __future__ import annotations

import typing

from petsc4py import PETSc

import ufl

import dolfinx.fem.petsc
from dolfinx import fem

from contactqvi.lifetime import PETScOwner
from contactqvi.linalg import create_snes, preset, reassemble_matrix
from contactqvi.parameters import require_positive
from contactqvi.result import InnerSolveError
from contactqvi.vi.nonlinear import NonlinearFormProblem, snes_converged_reason

__all__ = ["Nonlinearity", "TemperatureMap", "DEFAULT_PHI_OPTIONS"]

UFLMap = typing.Callable[[ufl.core.expr.Expr], ufl.core.expr.Expr]

#: Semismooth Newton defaults for (30); -phi_snes_... overrides them.
DEFAULT_PHI_OPTIONS = {
    "snes_type": "newtonls",
    "snes_linesearch_type": "bt",
    "snes_rtol": 1e-13,
    "snes_atol": 1e-15,
    "snes_stol": 1e-14,
    "snes_max_it": 50,
    **preset("lu"),
}


class Nonlinearity(typing.Protocol):
    """A (possibly nonsmooth) scalar function g with a Newton derivative G_g, both on UFL expressions
    (e.g. :class:`contactqvi.problems.thermoforming.ScalarNonlinearity`)."""

    g: UFLMap
    derivative: UFLMap


class TemperatureMap(PETScOwner):
    """Evaluate Phi(u) = I_h(varphi T) and assemble its Newton derivative, (29)-(33).

    The SNES iterate :attr:`T` (with the input :attr:`u`) is the state of the last
    solve and the initial guess of the next; the Newton blocks of (33)/(63) are
    assembled by :meth:`linearize` at a point given explicitly, on coefficients of
    their own, so assembling them never disturbs that state.

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
        g: Nonlinearity,
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
        #: the point (u, T) of the last :meth:`linearize`
        self.u_lin, self.T_lin = fem.Function(V), fem.Function(V)
        v, dT = ufl.TestFunction(V), ufl.TrialFunction(V)
        dx = ufl.Measure("dx", domain=V.mesh, metadata={"quadrature_degree": quadrature_degree})

        def jacobian(T: fem.Function, u: fem.Function) -> ufl.Form:
            s = Psi0 + psi * T - u
            return k * dT * v * dx + ufl.inner(ufl.grad(dT), ufl.grad(v)) * ufl.dx - g.derivative(s) * psi * dT * v * dx

        s = Psi0 + psi * self.T - self.u
        F = k * self.T * v * dx + ufl.inner(ufl.grad(self.T), ufl.grad(v)) * ufl.dx - g.g(s) * v * dx
        self.nonlinear = NonlinearFormProblem(fem.form(F), fem.form(jacobian(self.T, self.u)), self.T, [])
        self.snes = create_snes(V.mesh.comm, prefix, DEFAULT_PHI_OPTIONS)
        self.snes.setConvergenceHistory(reset=True)
        self.nonlinear.attach(self.snes)
        self.x = self.T.x.petsc_vec.duplicate()
        #: the matrix of (33)/(63) at (u_lin, T_lin)
        self.jacobian_form = fem.form(jacobian(self.T_lin, self.u_lin))
        #: (G_g(s) h, zeta) at (u_lin, T_lin): the u-derivative of the residual, the coupling block of (63)
        s_lin = Psi0 + psi * self.T_lin - self.u_lin
        self.coupling_form = fem.form(g.derivative(s_lin) * ufl.TrialFunction(V) * v * dx)
        self.jacobian_matrix = dolfinx.fem.petsc.assemble_matrix(self.jacobian_form)
        self.jacobian_matrix.assemble()
        self.coupling_matrix = dolfinx.fem.petsc.assemble_matrix(self.coupling_form)
        self.coupling_matrix.assemble()
        self.varphi = fem.Function(V, name="varphi")
        self.varphi.interpolate(fem.Expression(varphi, V.element.interpolation_points(), comm=V.mesh.comm))
        self.residual_history: list[float] = []
        #: residual of the first (cold) solve: the scale for round-off stagnation
        self.reference_norm: float | None = None
        self.roundoff = 1e-10

    def petsc_objects(self) -> list[typing.Any]:
        return [self.snes, self.x, self.jacobian_matrix, self.coupling_matrix, self.nonlinear]

    def solve(self, u: fem.Function) -> int:
        """Solve (30) for T at ``u``, starting from the current :attr:`T`; returns Newton steps."""
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
            reason = snes_converged_reason(self.snes)
            raise InnerSolveError(f"Phi: semismooth Newton for the temperature failed ({reason})")
        return self.snes.getIterationNumber()

    def restart_from(self, T: fem.Function) -> None:
        """Start the next :meth:`solve` from ``T``."""
        self.T.x.array[:] = T.x.array

    def apply(self, out: fem.Function) -> None:
        """out = I_h(varphi T) for the current T."""
        out.x.array[:] = self.varphi.x.array * self.T.x.array

    def linearize(self, u: fem.Function, T: fem.Function, scale: float = 1.0) -> None:
        """Re-assemble the blocks of (33)/(63) in place at (u, T): :attr:`jacobian_matrix`
        and ``scale`` times :attr:`coupling_matrix` (both owned by this map: do not destroy)."""
        self.u_lin.x.array[:] = u.x.array
        self.T_lin.x.array[:] = T.x.array
        reassemble_matrix(self.coupling_matrix, self.coupling_form).scale(scale)
        reassemble_matrix(self.jacobian_matrix, self.jacobian_form)
