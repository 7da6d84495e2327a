"""Monolithic block systems for the Newton step (61), realised as (62)-(64) / (68).

Blocks are PETSc matrices on the same P1/Q1 row layout; they are combined into a
nest, converted to one AIJ matrix and solved with a direct solver (MUMPS by
default, options prefix ``qvi_newton_``). Constraints such as mu = 0 on the
active set A_i are imposed exactly as identity rows of that block (the rows of
(68) "deleted" in Sect. 4.1), never by penalties.

The block matrices are given once and their owners re-assemble the values in
place between Newton steps; :meth:`BlockNewtonSystem.update` then converts the
nest to a new AIJ matrix; the vectors are allocated once. Refilling the previous
AIJ matrix instead (MAT_REUSE_MATRIX, then MUMPS' numerical refactorisation) gave
wrong Newton directions under MPI with PETSc 3.22, also with the zeroed identity
rows kept in the pattern (MAT_KEEP_NONZERO_PATTERN): Test 1 (h = 1/200, Algorithm
2, u0 the Poisson solution) then converged only linearly on 2 ranks until Phi's
Newton failed, while it takes 3 iterations serially and with the rebuilt matrix.
"""

from __future__ import annotations

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

from contactqvi.lifetime import PETScOwner
from contactqvi.linalg import create_ksp, ksp_converged_reason, preset
from contactqvi.result import InnerSolveError

__all__ = ["BlockNewtonSystem", "diagonal_matrix"]


def diagonal_matrix(diagonal: PETSc.Vec) -> PETSc.Mat:
    """Sparse AIJ matrix with the given diagonal (same parallel layout as the vector)."""
    n, N = diagonal.getLocalSize(), diagonal.getSize()
    D = PETSc.Mat().createAIJ(((n, N), (n, N)), nnz=(1, 0), comm=diagonal.getComm())
    D.setDiagonal(diagonal)
    D.assemble()
    return D


class BlockNewtonSystem(PETScOwner):
    """One block linear system with identity rows on chosen (owned) dofs of each block.

    Args:
        comm: communicator.
        blocks: the block matrices (None: zero block), kept by reference; their owners
            re-assemble them in place before each :meth:`update`.
        prefix: PETSc options prefix of the KSP.
        ksp: KSP preset of the monolithic system.
    """

    def __init__(
        self, comm: MPI.Comm, blocks: list[list[PETSc.Mat | None]], prefix: str = "qvi_newton_", ksp: str = "lu"
    ):
        self.comm = comm
        self.nest = PETSc.Mat().createNest(blocks, comm=comm)
        self.K: PETSc.Mat | None = None
        start = self.nest.getOwnershipRange()[0]
        self.indices = [is_.getIndices().copy() for is_ in self.nest.getNestISs()[0]]
        self.positions = [idx - start for idx in self.indices]
        self.fixed = [np.zeros(idx.size, bool) for idx in self.indices]
        self.ksp = create_ksp(comm, prefix, preset(ksp, "ksp"))
        sizes = (self.nest.getLocalSize()[0], self.nest.getSize()[0])
        #: solution and right-hand side in the layout of the monolithic matrix
        self.x, self.b = (PETSc.Vec().createMPI(sizes, comm=comm) for _ in range(2))

    def petsc_objects(self) -> list[PETSc.Object | None]:
        return [self.ksp, self.K, self.x, self.b, self.nest]

    def update(self, fixed: list[np.ndarray]) -> None:
        """Build the matrix from the blocks' current values; row i of block j becomes an identity row if fixed[j][i]."""
        if self.K is not None:
            self.K.destroy()
        self.K = self.nest.convert("aij", out=PETSc.Mat())
        self.fixed = fixed
        rows = np.concatenate([idx[mask] for idx, mask in zip(self.indices, fixed)])
        self.K.zeroRows(rows.astype(PETSc.IntType), 1.0)
        self.ksp.setOperators(self.K)

    def solve(self, rhs: list[np.ndarray | None]) -> list[np.ndarray]:
        """Solve with right-hand side blocks (owned values; None = 0); fixed rows get 0."""
        self.b.set(0.0)
        for pos, values, mask in zip(self.positions, rhs, self.fixed):
            if values is not None:
                self.b.array[pos] = np.where(mask, 0.0, values)
        self.ksp.solve(self.b, self.x)
        if self.ksp.getConvergedReason() <= 0:
            raise InnerSolveError(f"Newton system: linear solve failed ({ksp_converged_reason(self.ksp)})")
        return [self.x.array[pos].copy() for pos in self.positions]
