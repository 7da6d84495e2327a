"""The discrete obstacle problem (21)/(54) of seed 003 on a P1/Q1 space.

Find u in V_h with u = g_D on the Dirichlet boundary, u <= theta at every node
and (grad u, grad(v - u)) >= (f, v - u) for all such v. The obstacle ``theta``
is a nodal Function (phi + Phi0 in (21)), the source ``f`` any UFL expression
(it may depend on Functions the caller updates, as in (53)).
"""

from __future__ import annotations

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import ufl

import dolfinx.fem.petsc
from dolfinx import fem

from contactqvi.lifetime import PETScOwner
from contactqvi.parameters import require

__all__ = ["ObstacleProblem"]


class ObstacleProblem(PETScOwner):
    """Forms, boundary conditions and nodal data of an obstacle problem.

    Args:
        V: scalar P1 (interval/triangle) or Q1 (quadrilateral) space.
        source: the load f (UFL expression; may depend on Functions).
        obstacle: nodal upper obstacle theta in V; the solvers' forms use this
            Function, and :meth:`set_obstacle` changes its values.
        bcs: Dirichlet conditions of u (homogeneous for H^1_0).
        quadrature_degree: quadrature degree of the load and the (nonsmooth)
            Moreau-Yosida term (60).
    """

    def __init__(
        self,
        V: fem.FunctionSpace,
        source: ufl.core.expr.Expr,
        obstacle: fem.Function,
        bcs: list[fem.DirichletBC],
        quadrature_degree: int = 2,
    ):
        require(V.dofmap.index_map_bs == 1, "V", "the obstacle problem needs a scalar space")
        require(V.element.basix_element.degree == 1, "V", "nodal active sets need P1/Q1 elements (Sect. 4.1)")
        self.V, self.source, self.obstacle, self.bcs = V, source, obstacle, bcs
        self.comm: MPI.Comm = V.mesh.comm
        self.u = fem.Function(V, name="membrane")
        self.n_owned = V.dofmap.index_map.size_local
        u_trial, v = ufl.TrialFunction(V), ufl.TestFunction(V)
        dx = ufl.Measure("dx", domain=V.mesh, metadata={"quadrature_degree": quadrature_degree})
        self.stiffness_form = fem.form(ufl.inner(ufl.grad(u_trial), ufl.grad(v)) * ufl.dx)
        self.load_form = fem.form(source * v * dx)
        self.A = dolfinx.fem.petsc.assemble_matrix(self.stiffness_form, bcs=bcs)
        self.A.assemble()
        self.load = dolfinx.fem.petsc.create_vector(self.load_form)
        self.multiplier = self.load.duplicate()
        self.multiplier.set(0.0)
        bc_loc = np.concatenate([bc.dof_indices()[0] for bc in bcs]) if bcs else np.zeros(0, np.int32)
        self.free = np.ones(self.n_owned, dtype=bool)
        self.free[bc_loc[bc_loc < self.n_owned]] = False
        self.boundary_values = fem.Function(V)
        for bc in bcs:
            bc.set(self.boundary_values.x.array)
        self.dx = dx

    def petsc_objects(self) -> list[PETSc.Object]:
        return [self.A, self.load, self.multiplier]

    def set_obstacle(self, theta: fem.Function) -> None:
        """Copy the nodal values of ``theta`` (same space) into the problem's obstacle."""
        self.obstacle.x.array[:] = theta.x.array

    def active_set(self, u: fem.Function) -> np.ndarray:
        """Owned free nodes where ``u`` touches the obstacle, {u = theta} (Sect. 4.1)."""
        n = self.n_owned
        return self.free & (u.x.array[:n] >= self.obstacle.x.array[:n])

    def assemble_load(self) -> PETSc.Vec:
        """Load vector (f, v) with the Dirichlet values lifted and set (current f)."""
        b = self.load
        with b.localForm() as b_loc:
            b_loc.set(0.0)
        dolfinx.fem.petsc.assemble_vector(b, self.load_form)
        dolfinx.fem.petsc.apply_lifting(b, [self.stiffness_form], bcs=[self.bcs])
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        dolfinx.fem.petsc.set_bc(b, self.bcs)
        return b

    def check_feasible_set(self) -> None:
        """K is empty if the obstacle lies below the Dirichlet data somewhere on the boundary."""
        theta = self.obstacle.x.array[: self.n_owned]
        g = self.boundary_values.x.array[: self.n_owned]
        gap = np.min(theta[~self.free] - g[~self.free], initial=np.inf)
        gap = self.comm.allreduce(gap, op=MPI.MIN)
        require(
            gap >= -1e-12,
            "obstacle",
            f"lies below the boundary data by {-gap:.3g}; the feasible set K is empty",
        )

    def residual(self, u: fem.Function, out: PETSc.Vec) -> PETSc.Vec:
        """Discrete multiplier lambda = (f, v) - (grad u, grad v) on the free dofs, 0 on Dirichlet dofs."""
        b = self.assemble_load()
        self.A.mult(u.x.petsc_vec, out)
        out.aypx(-1.0, b)
        out.array[~self.free] = 0.0
        return out
