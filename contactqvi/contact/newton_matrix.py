"""The Newton matrix J = D A + U of (5.4) (seed 000) in the storage of A, changed on the contact rows only.

Off the contact nodes D = W*^T = I and U = U*^T = 0 (Q^R = 0: rge(I, 0)), so J and A
differ only in

* the rows of the contact dofs: (D - I) A + U with 3x3 diagonal blocks D, U per node, and
* after the exact elimination of the identity rows (MatZeroRowsColumns), the
  columns of the eliminated dofs, i.e. the rows of the contact nodes' neighbours.

:class:`NewtonMatrix` computes J on exactly these rows (a surface-sized matrix with
A's row pattern there) and writes them into A's own storage: the body-sized matrix
exists once, and the cost of a Newton step's matrix scales with the contact
surface. A's values on these rows are kept, so products with A stay exact while the
storage holds J (:meth:`NewtonMatrix.mult_stiffness`) and A is restored exactly
afterwards (:meth:`NewtonMatrix.restore`). The step-to-step change of those rows is
what a multigrid preconditioner needs to keep its Galerkin coarse operators exact
(:class:`contactqvi.multigrid.GalerkinUpdate`).
"""

from __future__ import annotations

import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

from contactqvi.lifetime import PETScOwner
from contactqvi.linalg import nonzero_row_indices

__all__ = ["NewtonMatrix"]

_SAME = PETSc.Mat.Structure.SAME_NONZERO_PATTERN
_SUBSET = PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN


class NewtonMatrix(PETScOwner):
    """J = D A + U of (5.4) for the contact nodes ``contact_blk``, written into A's storage.

    Args:
        A: the stiffness matrix (block size 3, nodes in their frames). From
            :meth:`assemble` to :meth:`restore` (or :meth:`destroy`) it holds J;
            A's values on the rows J changes are kept meanwhile.
        contact_blk: owned local node indices of the contact nodes.

    Attributes:
        J: the Newton matrix: the object ``A`` itself, whatever it holds now.
        contact_dofs: owned local dofs (rows) of the contact nodes, node by node.
        rows: J on the rows it shares with no other matrix (the contact dofs and their
            neighbours; A's layout, zero rows elsewhere), as of the last :meth:`assemble`.
        change: J of this :meth:`assemble` minus J of the previous one (A before the
            first), on the pattern of ``rows``.
    """

    def __init__(self, A: PETSc.Mat, contact_blk: np.ndarray):
        self.J = A
        self._contact_blk = np.asarray(contact_blk, dtype=np.int64)
        self.contact_dofs = _contact_dofs_loc(self._contact_blk)
        self._coupled = _coupled_rows(A, self._contact_blk)
        self._rows_of_A = _rows_of(A, self._coupled)
        self.rows = self._rows_of_A.duplicate(copy=True)  # J = A before the first assemble
        self.change = self._rows_of_A.duplicate(copy=False)
        self._D_minus_I = _contact_blocks(A, self._contact_blk)
        self._U = _contact_blocks(A, self._contact_blk)
        self._fixed_diagonal = _contact_blocks(A, self._contact_blk)
        self._DA = self._D_minus_I.matMult(self._rows_of_A)
        self._product = A.createVecLeft()  # A x on the rows of ``rows``
        self._geometric: tuple[PETSc.Mat, PETSc.Mat] | None = None
        self._holds_J = False
        for M in (self.rows, self.change):  # every row is set by its owner
            M.setOption(PETSc.Mat.Option.NO_OFF_PROC_ENTRIES, True)

    def petsc_objects(self) -> list[typing.Any]:
        return [self._product, self._DA, self._fixed_diagonal, self._U, self._D_minus_I, self.change, self.rows,
                self._rows_of_A, *(self._geometric or ())]

    def set_geometric(self, forces: PETSc.Mat, variables: PETSc.Mat) -> None:
        """The geometric rows of a geometry that follows the iterate (taken over; the previous
        ones are freed): J = D (A + ``forces``) + U ``variables`` instead of D A + U, ``forces``
        Gamma T and ``variables`` (dv/du~) T of :mod:`contactqvi.contact.current_geometry`, their
        patterns within A's."""
        for M in self._geometric or ():
            M.destroy()
        self._geometric = (forces, variables)

    def destroy(self) -> None:
        """Restore A (:meth:`restore`) and free everything but A (collective)."""
        self.restore()
        super().destroy()

    def set_blocks(self, Wt: np.ndarray, Ut: np.ndarray) -> None:
        """D = I + blockdiag(Wt - I) and U = blockdiag(Ut) on the contact nodes ((m, 3, 3) each)."""
        _set_blocks(self._D_minus_I, self._contact_blk, Wt - np.eye(3))
        _set_blocks(self._U, self._contact_blk, Ut)

    def assemble(
        self, fixed: np.ndarray | None = None, gamma: float = 1.0, x: PETSc.Vec | None = None,
        b: PETSc.Vec | None = None,
    ) -> PETSc.Mat:
        """J = D A + U for the blocks of :meth:`set_blocks`, in A's storage; returns J.

        ``fixed`` ((m, 3) bool, per contact node and component) marks the dofs whose
        rows and columns are eliminated as by ``J.zeroRowsColumns(rows, gamma, x, b)``:
        their rows become gamma times identity rows, b takes the eliminated columns
        times x, and b = gamma x on them.
        """
        rows = self.rows
        rows.copy(self.change, _SAME)
        self.change.scale(-1.0)  # minus J of the previous assemble
        self._rows_of_A.copy(rows, _SAME)
        self._D_minus_I.matMult(self._rows_of_A, result=self._DA)
        rows.axpy(1.0, self._DA, _SUBSET)
        if self._geometric is None:
            rows.axpy(1.0, self._U, _SUBSET)
        else:
            forces, variables = self._geometric
            rows.axpy(1.0, forces, _SUBSET)
            for product in (self._D_minus_I.matMult(forces), self._U.matMult(variables)):
                rows.axpy(1.0, product, _SUBSET)
                product.destroy()
        if fixed is not None:
            self._eliminate(fixed, gamma, x, b)
        self.change.axpy(1.0, rows, _SAME)
        # the storage holds the previous J: only the rows that changed are written
        _insert_rows(self.J, rows, self.change if self._holds_J else None)
        self._holds_J = True
        return self.J

    def fixed_dofs(self, fixed: np.ndarray) -> np.ndarray:
        """Owned local dofs of the contact components marked in ``fixed`` ((m, 3) bool)."""
        return self.contact_dofs[fixed.ravel()]

    def restore(self) -> None:
        """Write A's kept values back into its storage: the object holds A again, bit for bit."""
        if self._holds_J:
            _insert_rows(self.J, self._rows_of_A)
            self._holds_J = False

    def refresh(self, lagged: bool = False) -> None:
        """A's storage was overwritten by a new stiffness of the same pattern (the Jacobian of a
        nonlinear f at a new iterate): keep its values on the rows J changes, as at construction.

        ``lagged``: a preconditioner keeps levels made for the last J, so the next :attr:`change`
        is taken from that J (its rows kept in ``rows``) instead of from the new stiffness."""
        self._holds_J = False
        fresh = _rows_of(self.J, self._coupled)
        fresh.copy(self._rows_of_A, _SAME)
        if not lagged:
            fresh.copy(self.rows, _SAME)
        fresh.destroy()

    def undone(self) -> PETSc.Mat:
        """A minus the J of the last :meth:`assemble` (zero before the first), on the pattern
        of ``rows``: the storage's change from that J back to A (:meth:`restore`; a new matrix)."""
        undone = self._rows_of_A.copy()
        undone.axpy(-1.0, self.rows, _SAME)
        return undone

    def mult_stiffness(self, x: PETSc.Vec, y: PETSc.Vec) -> None:
        """y = A x, also while the storage holds J: J's rows off ``rows`` are A's, and
        A's own values are kept for the others."""
        self.J.mult(x, y)
        if self._holds_J:
            self._rows_of_A.mult(x, self._product)
            y.array[self._coupled] = self._product.array[self._coupled]

    def _eliminate(self, fixed: np.ndarray, gamma: float, x: PETSc.Vec, b: PETSc.Vec) -> None:
        """Rows and columns of the ``fixed`` contact dofs of J (held by ``rows``) become gamma I.

        MatZeroRowsColumns with a nonzero diagonal wants a diagonal entry in every row,
        which ``rows`` lacks off its rows: it zeroes the diagonal too, gamma is added by a
        contact-block matrix, and b = gamma x is set on the fixed rows.
        """
        fixed_loc = self.fixed_dofs(fixed)
        start = self.J.getOwnershipRange()[0]
        self.rows.zeroRowsColumns((start + fixed_loc).astype(PETSc.IntType), diag=0.0, x=x, b=b)
        b.array[fixed_loc] = gamma * x.array[fixed_loc]
        _set_blocks(self._fixed_diagonal, self._contact_blk, gamma * fixed[:, :, None] * np.eye(3))
        self.rows.axpy(1.0, self._fixed_diagonal, _SUBSET)

    def left_scaled(self, M: PETSc.Mat) -> PETSc.Mat:
        """D M for the blocks of :meth:`set_blocks` (a new matrix; M of A's row layout)."""
        out = self._D_minus_I.matMult(M)
        out.axpy(1.0, M, PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
        return out

    def left_scale(self, x: PETSc.Vec, y: PETSc.Vec) -> None:
        """y = D x for the blocks of :meth:`set_blocks`."""
        self._D_minus_I.multAdd(x, x, y)

    def mult_blocks(self, x: PETSc.Vec, y: PETSc.Vec, gamma: PETSc.Vec) -> None:
        """y = Gamma D x + U x for the blocks of :meth:`set_blocks`: the right-hand side operator of (5.4)
        with y1^ = Gamma x."""
        self._D_minus_I.multAdd(x, x, y)
        y.pointwiseMult(y, gamma)  # D Gamma = Gamma D: gamma is constant on each node
        self._U.multAdd(x, y, y)

    def mult_add_D(self, x: PETSc.Vec, y: PETSc.Vec) -> None:
        """y += D x for the blocks of :meth:`set_blocks` (x is left unchanged)."""
        self._D_minus_I.multAdd(x, y, y)
        y.axpy(1.0, x)


def _insert_rows(M: PETSc.Mat, rows: PETSc.Mat, changed: PETSc.Mat | None = None) -> None:
    """Overwrite M's values on the nonempty owned rows of ``rows`` (same layout, pattern within M's),
    or only on those where ``changed`` (same pattern as ``rows``) has a nonzero entry.

    Most Newton steps change few of the rows (two-body Hertz medium mesh: 0-23 k of the 1.0 M
    entries of ``rows``), and the cost of writing a row is a search for each entry."""
    indptr, indices, values = rows.getValuesCSR()
    if changed is not None:
        lengths = np.diff(indptr)
        kept = np.zeros(len(lengths), dtype=bool)
        kept[nonzero_row_indices(changed) - changed.getOwnershipRange()[0]] = True
        entries = np.repeat(kept, lengths)
        indptr = np.concatenate([[0], np.cumsum(np.where(kept, lengths, 0))]).astype(PETSc.IntType)
        indices, values = indices[entries], values[entries]
    M.setOption(PETSc.Mat.Option.NO_OFF_PROC_ENTRIES, True)  # for this assembly only: M may be assembled again
    M.setValuesCSR(indptr, indices, values)
    M.assemble()
    M.setOption(PETSc.Mat.Option.NO_OFF_PROC_ENTRIES, False)


def _contact_dofs_loc(contact_blk: np.ndarray) -> np.ndarray:
    """Owned local dofs of the contact nodes, node by node (sorted for sorted ``contact_blk``)."""
    return (3 * contact_blk[:, None] + np.arange(3)).ravel()


def _coupled_rows(A: PETSc.Mat, contact_blk: np.ndarray) -> np.ndarray:
    """Owned local rows of A that hold a contact dof's row or column (A is structurally symmetric)."""
    start, end = A.getOwnershipRange()
    contact_glob = (start + _contact_dofs_loc(contact_blk)).astype(PETSc.IntType)
    rows = PETSc.IS().createGeneral(contact_glob, comm=A.getComm())
    columns = PETSc.IS().createStride(end - start, first=start, step=1, comm=A.getComm())
    contact_rows = A.createSubMatrix(rows, columns)
    neighbours_glob = np.unique(contact_rows.getValuesCSR()[1]).astype(PETSc.IntType)
    for obj in (contact_rows, columns, rows):
        obj.destroy()
    marker = A.createVecLeft()
    marker.setValues(neighbours_glob, np.ones(len(neighbours_glob)), addv=PETSc.InsertMode.INSERT_VALUES)
    marker.assemble()
    coupled = np.flatnonzero(marker.array).astype(np.int64)
    marker.destroy()
    return coupled


def _rows_of(A: PETSc.Mat, rows_loc: np.ndarray) -> PETSc.Mat:
    """A matrix of A's layout holding A's values on the owned local rows ``rows_loc`` only."""
    start, end = A.getOwnershipRange()
    comm = A.getComm()
    rows = PETSc.IS().createGeneral((start + rows_loc).astype(PETSc.IntType), comm=comm)
    columns = PETSc.IS().createStride(end - start, first=start, step=1, comm=comm)
    sub = A.createSubMatrix(rows, columns)
    indptr, indices, values = sub.getValuesCSR()
    lengths = np.zeros(end - start, dtype=np.int64)
    lengths[rows_loc] = np.diff(indptr)
    full_indptr = np.concatenate([[0], np.cumsum(lengths)]).astype(PETSc.IntType)
    M = PETSc.Mat().createAIJ(size=A.getSizes(), csr=(full_indptr, indices, values), comm=comm)
    for obj in (sub, columns, rows):
        obj.destroy()
    return M


def _contact_blocks(A: PETSc.Mat, contact_blk: np.ndarray) -> PETSc.Mat:
    """Zero matrix of A's layout with room for a 3x3 block on the diagonal of each contact node.

    All nine entries of each block are stored, zeros included, so products with it
    keep one pattern from step to step.
    """
    n_local = A.getLocalSize()[0]
    nnz = np.zeros(n_local, dtype=PETSc.IntType)
    nnz.reshape(-1, 3)[contact_blk] = 3
    M = PETSc.Mat().createAIJ(size=A.getSizes(), bsize=3, nnz=(nnz, np.zeros_like(nnz)), comm=A.getComm())
    M.setOption(PETSc.Mat.Option.IGNORE_ZERO_ENTRIES, False)
    M.setOption(PETSc.Mat.Option.NO_OFF_PROC_ENTRIES, True)
    _set_blocks(M, contact_blk, np.zeros((len(contact_blk), 3, 3)))
    return M


def _set_blocks(M: PETSc.Mat, blk: np.ndarray, blocks: np.ndarray) -> None:
    """Overwrite the diagonal 3x3 blocks of the owned local nodes ``blk``."""
    rows = (np.asarray(blk) + M.getOwnershipRange()[0] // 3).astype(PETSc.IntType)[:, None]
    values = np.ascontiguousarray(np.broadcast_to(blocks, (len(rows), 3, 3))).reshape(len(rows), 1, 9)
    M.setValuesBlockedRCV(rows, rows, values)
    M.assemble()
