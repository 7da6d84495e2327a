"""Residual/Jacobian callbacks for PETSc SNES, and SNES reasons as :class:`~contactqvi.result.Status`.

A problem owns its work vector ``b``, its matrix ``A`` and the callbacks
``F(snes, x, b)`` and ``J(snes, x, A, P)``; SNES owns the Newton loop.

* :class:`NonlinearFormProblem`: compiled forms F(u; v), J (the Jacobian form may
  be a Newton (generalised) derivative of a nonsmooth residual, e.g. built from a
  piecewise derivative ``G_g`` of ``g``) and Dirichlet conditions.
* :class:`AffineProblem`: F(x) = A x - l with an assembled matrix and load.
"""

from __future__ import annotations

import abc

from petsc4py import PETSc

import dolfinx.fem.petsc
from dolfinx import fem

from contactqvi.lifetime import PETScOwner
from contactqvi.linalg import reassemble_matrix
from contactqvi.result import Status

__all__ = ["AffineProblem", "NonlinearFormProblem", "SNESProblem", "snes_converged_reason", "snes_status"]


class SNESProblem(PETScOwner, abc.ABC):
    """Callbacks ``F``, ``J`` with the work vector ``b`` and matrix ``A`` they fill."""

    b: PETSc.Vec
    A: PETSc.Mat

    @abc.abstractmethod
    def F(self, snes: PETSc.SNES, x: PETSc.Vec, b: PETSc.Vec) -> None:
        """Residual at ``x`` into ``b``."""

    @abc.abstractmethod
    def J(self, snes: PETSc.SNES, x: PETSc.Vec, A: PETSc.Mat, P: PETSc.Mat) -> None:
        """Jacobian at ``x`` into ``A`` (= ``P``)."""

    def attach(self, snes: PETSc.SNES) -> None:
        """Register the callbacks and work objects with ``snes``."""
        snes.setFunction(self.F, self.b)
        snes.setJacobian(self.J, self.A, self.A)


class NonlinearFormProblem(SNESProblem):
    """F(u; v) = 0 with Jacobian form J.

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

    def petsc_objects(self) -> list[PETSc.Object]:
        return [self.b, self.A]

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


class AffineProblem(SNESProblem):
    """F(x) = A x - l with the constant Jacobian A (``A`` and ``load`` stay the caller's)."""

    def __init__(self, A: PETSc.Mat, load: PETSc.Vec):
        self.A, self.load = A, load
        self.b = A.createVecLeft()

    def petsc_objects(self) -> list[PETSc.Object]:
        return [self.b]

    def F(self, snes: PETSc.SNES, x: PETSc.Vec, b: PETSc.Vec) -> None:
        self.A.mult(x, b)
        b.axpy(-1.0, self.load)

    def J(self, snes: PETSc.SNES, x: PETSc.Vec, A: PETSc.Mat, P: PETSc.Mat) -> None:
        """A is constant: nothing to assemble."""


def snes_converged_reason(snes: PETSc.SNES) -> str:
    """Name of the SNES converged/diverged reason (e.g. ``CONVERGED_FNORM_ABS``)."""
    reason = snes.getConvergedReason()
    names = {v: k for k, v in PETSc.SNES.ConvergedReason.__dict__.items() if isinstance(v, int)}
    return names.get(reason, str(reason))


_Reason = PETSc.SNES.ConvergedReason
#: SNESConvergedReason -> Status; a failure without its own Status is named by the nearest one
#: (the PETSc name stays in the result's ``reason``).
_SNES_STATUS = {
    _Reason.CONVERGED_FNORM_ABS: Status.CONVERGED_ATOL,
    _Reason.CONVERGED_FNORM_RELATIVE: Status.CONVERGED_RTOL,
    _Reason.CONVERGED_SNORM_RELATIVE: Status.CONVERGED_STEP,
    _Reason.CONVERGED_ITS: Status.CONVERGED_ITERATIONS,
    _Reason.DIVERGED_MAX_IT: Status.DIVERGED_MAX_IT,
    _Reason.DIVERGED_FUNCTION_COUNT: Status.DIVERGED_MAX_IT,
    _Reason.DIVERGED_LINEAR_SOLVE: Status.DIVERGED_LINEAR_SOLVE,
    _Reason.DIVERGED_LINE_SEARCH: Status.DIVERGED_LINE_SEARCH,
    _Reason.DIVERGED_LOCAL_MIN: Status.DIVERGED_LINE_SEARCH,
    _Reason.DIVERGED_TR_DELTA: Status.DIVERGED_LINE_SEARCH,
    _Reason.DIVERGED_INNER: Status.DIVERGED_INNER,
}


def snes_status(snes: PETSc.SNES) -> Status:
    """The :class:`Status` of the last ``snes.solve`` (NaN, domain and dtol failures: ``DIVERGED_DTOL``)."""
    reason = snes.getConvergedReason()
    if reason == 0:
        return Status.ITERATING
    return _SNES_STATUS.get(reason, Status.DIVERGED_DTOL)
