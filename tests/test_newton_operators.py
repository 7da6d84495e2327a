"""The Newton matrix kept as A + (contact rows) and the Galerkin-updated multigrid levels.

Both are checked against direct constructions: J and the eliminated right-hand side
against D A + U followed by MatZeroRowsColumns on the whole matrix, the coarse
operators after several Newton steps against Galerkin products P^T J P computed
afresh with the preconditioner's interpolations. Serial and on 2 ranks.
"""

from __future__ import annotations

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import pytest

from contactqvi import meshes
from contactqvi.contact import SCDNewtonSolver, build_contact_problem
from contactqvi.contact.nodal import classify, resolvent, scd_adjoint_blocks
from contactqvi.laws import Coulomb
from contactqvi.problems import coulomb as data


def _problem(lev: int):
    msh, tags = meshes.create_contact_body(MPI.COMM_WORLD, lev, data.gap_function("d3"))
    return build_contact_problem(msh, tags, data.YOUNG, data.POISSON, data.tractions("L2"), Coulomb(data.FRICTION))


def _block_diagonal(A: PETSc.Mat, blk: np.ndarray, blocks: np.ndarray, default: np.ndarray) -> PETSc.Mat:
    """Block-diagonal matrix of A's layout: ``blocks`` at the nodes ``blk``, ``default`` elsewhere."""
    n_blk = A.getLocalSize()[0] // 3
    values = np.broadcast_to(default, (n_blk, 3, 3)).copy()
    values[blk] = blocks
    M = PETSc.Mat().createAIJ(size=A.getSizes(), bsize=3, nnz=(3, 0), comm=A.getComm())
    rows = (np.arange(n_blk) + A.getOwnershipRange()[0] // 3).astype(PETSc.IntType)[:, None]
    M.setValuesBlockedRCV(rows, rows, values.reshape(n_blk, 1, 9))
    M.assemble()
    return M


@pytest.mark.parametrize("eliminate", [True, False])
def test_newton_matrix_is_DA_plus_U(eliminate):
    """J, the right-hand side and the eliminated values equal those of D A + U built on the whole matrix."""
    problem = _problem(3)
    A, blk = problem.A.duplicate(copy=True), problem.contact_blk  # problem.A holds J after newton_system
    with SCDNewtonSolver(problem, {"eliminate_fixed_rows": eliminate}) as solver:
        rng = np.random.default_rng(7)
        u, w = A.createVecRight(), solver._work
        for _ in range(3):  # several steps: the blocks of one step must not leak into the next
            trial = rng.normal(size=(len(blk), 3)) * np.array([1.0, 1.0, 10.0]) * 1e-6 * solver.gamma
            v, z = resolvent(trial, solver.gamma, problem.law)
            Wt, Ut = scd_adjoint_blocks(v, z, *classify(v, z, solver.gamma, problem.law, 0.0), solver.gamma,
                                        problem.law)
            u.array[:] = rng.normal(size=len(u.array))
            w.dhat.array[:] = rng.normal(size=len(u.array))
            y2 = u.copy()
            y2.axpy(-1.0, w.dhat)
            J = solver.newton_system(Wt, Ut, u, y2)

            D = _block_diagonal(A, blk, Wt, np.eye(3))
            U = _block_diagonal(A, blk, Ut, np.zeros((3, 3)))
            reference = D.matMult(A)
            reference.axpy(1.0, U, PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
            rhs = A.createVecLeft()
            D.mult(y2, rhs)
            rhs.pointwiseMult(rhs, solver._gamma_dofs.gamma)
            U.multAdd(y2, rhs, rhs)
            rhs.scale(-1.0)
            du = rhs.duplicate()
            du.set(0.0)
            fixed = ~np.any(Wt, axis=2)
            fixed_loc = (3 * blk[:, None] + np.arange(3))[fixed] if eliminate else np.empty(0, dtype=np.int64)
            assert MPI.COMM_WORLD.allreduce(len(fixed_loc), op=MPI.SUM) > 0 or not eliminate
            du.array[fixed_loc] = rhs.array[fixed_loc] / solver._gamma_dofs.gamma.array[fixed_loc]
            start = A.getOwnershipRange()[0]
            reference.zeroRowsColumns((start + fixed_loc).astype(PETSc.IntType), diag=solver.gamma, x=du, b=rhs)
            scale = reference.norm()
            reference.axpy(-1.0, J, PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
            assert reference.norm() <= 1e-14 * scale
            for mine, theirs in ((w.rhs, rhs), (w.du, du)):
                theirs.axpy(-1.0, mine)
                assert theirs.norm() <= 1e-14 * max(mine.norm(), 1.0)
            stiffness, exact = A.createVecLeft(), A.createVecLeft()
            solver._newton.mult_stiffness(u, stiffness)  # A u while problem.A holds J
            A.mult(u, exact)
            assert np.array_equal(stiffness.array, exact.array)
            for obj in (D, U, reference, y2, rhs, du, stiffness, exact):
                obj.destroy()
        u.destroy()
    restored = problem.A.copy()
    restored.axpy(-1.0, A, PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
    assert restored.norm(PETSc.NormType.INFINITY) == 0.0  # A again, bit for bit
    for obj in (restored, A):
        obj.destroy()


def test_galerkin_update_keeps_coarse_operators_exact():
    """After Newton steps with Galerkin updates the coarse operators are P^T J P of the current J."""
    problem = _problem(5)
    A = problem.A.duplicate(copy=True)
    with SCDNewtonSolver(problem, {"max_iterations": 5}) as solver:
        u = problem.A.createVecRight()
        solver.solve(u)
        A.axpy(-1.0, problem.A, PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
        assert A.norm(PETSc.NormType.INFINITY) == 0.0  # the solve returns with A in its storage, bit for bit
        pc = solver.ksp.getPC()
        levels = pc.getMGLevels()
        assert levels >= 3 and solver.step_solver.galerkin is not None and solver.step_solver.galerkin.updates >= 2
        last_J = fine = problem.A.copy()  # A (restored by the solve) with the rows of the last step's J
        last_J.setValuesCSR(*solver._newton.rows.getValuesCSR())
        last_J.assemble()
        for level in reversed(range(1, levels)):
            coarse = pc.getMGSmoother(level - 1).getOperators()[0]
            galerkin = fine.PtAP(pc.getMGInterpolation(level))
            scale = galerkin.norm()
            galerkin.axpy(-1.0, coarse, PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
            assert galerkin.norm() <= 1e-12 * scale, level
            galerkin.destroy()
            fine = coarse
        for obj in (last_J, u, A):
            obj.destroy()
