"""Residual/Jacobian callbacks of a nonlinear variational problem for PETSc SNES.

The problem owns the compiled forms and boundary conditions; SNES owns the
Newton loop. The Jacobian form may be a Newton (generalised) derivative of a
nonsmooth residual, e.g. built from a piecewise derivative ``G_g`` of ``g``.
"""

from __future__ import annotations

from petsc4py import PETSc

import dolfinx.fem.petsc
from dolfinx import fem

from contactqvi.linalg import reassemble_matrix

__all__ = ["NonlinearFormProblem", "snes_converged_reason"]

class NonlinearFormProblem:
    """F(u; v) = 0 with Jacobian form J, for ``PETSc.SNES`` callbacks.

    Args:
        F: compiled residual form (linear in the test function).
        J: compiled (generalised) Jacobian form.
        u: the Function both forms depend on; SNES iterates are copied into it.
        bcs: Dirichlet conditions on ``u``'s space (values are imposed on the iterate).
    """

    def __init__(self, F: fem.Form, J: fem.Form, u: fem.Function, bcs: list[fem.DirichletBC]):
        self.F_form, self.J_form, self.u, self.bcs = F, J, u, bcs
        self.b = dolfinx.fem.petsc.create_vector(F)
        self.A = dolfinx.fem.petsc.create_matrix(J)

    def _update(self, x: PETSc.Vec) -> None:
        # the lifting below reads x's ghost entries: SNES does not update them
        x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        x.copy(self.u.x.petsc_vec)
        self.u.x.scatter_forward()

    def F(self, snes: PETSc.SNES, x: PETSc.Vec, b: PETSc.Vec) -> None:
        """Residual at ``x``; Dirichlet rows hold ``x - g``."""
        self._update(x)
        with b.localForm() as b_loc:
            b_loc.set(0.0)
        dolfinx.fem.petsc.assemble_vector(b, self.F_form)
        dolfinx.fem.petsc.apply_lifting(b, [self.J_form], bcs=[self.bcs], x0=[x], alpha=-1.0)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        dolfinx.fem.petsc.set_bc(b, self.bcs, x, -1.0)

    def J(self, snes: PETSc.SNES, x: PETSc.Vec, A: PETSc.Mat, P: PETSc.Mat) -> None:
        """Generalised Jacobian at ``x`` (identity rows on Dirichlet dofs)."""
        reassemble_matrix(A, self.J_form, self.bcs)

    def attach(self, snes: PETSc.SNES) -> None:
        """Register the callbacks and work objects with ``snes``."""
        snes.setFunction(self.F, self.b)
        snes.setJacobian(self.J, self.A, self.A)

    def destroy(self) -> None:
        self.b.destroy()
        self.A.destroy()


def snes_converged_reason(snes: PETSc.SNES) -> str:
    """Name of the SNES converged/diverged reason (e.g. ``CONVERGED_FNORM_ABS``)."""
    reason = snes.getConvergedReason()
    names = {v: k for k, v in PETSc.SNES.ConvergedReason.__dict__.items() if isinstance(v, int)}
    return names.get(reason, str(reason))
