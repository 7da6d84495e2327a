"""Galerkin coarse operators of a multigrid preconditioner kept exact under a sparse change.

A set-up of PETSc's GAMG builds interpolations P_l (level l-1 to l) and the coarse
operators by Galerkin products, C_{l-1} = P_l^T C_l P_l from C_{L-1} = J. Most of a
set-up is these products (the finest one dominates). When J changes by a matrix
Delta_{L-1} on a few rows only (in the Newton steps of a contact problem: the rows of
the contact nodes and their neighbours, :mod:`contactqvi.contact.newton_matrix`),
the coarse operators change by

    Delta_{l-1} = P_l^T Delta_l P_l,    C_{l-1} <- C_{l-1} + Delta_{l-1},

products whose cost scales with the changed rows, while the interpolations are kept.
With S the rows on which Delta_l has nonzero entries, P_l^T Delta_l P_l =
(P_l)_S^T ((Delta_l)_S P_l): only the rows S of P_l enter, never its transpose (a
PtAP of the whole change transposes the local P_l each time: lev 9 d3/L2, 2 ranks,
0.27 s against 0.08 s per update, 12 % of the solve against 3 %). Only the rows whose
values changed count: the change matrix keeps a fixed pattern (all rows J may
change, with explicit zeros on the rows that did not), and on a mortar interface
those rows are dense (two-body Hertz medium mesh: 1.0 M entries in the pattern
against 2.2 M in J; when the mortar rows still stored their zero entries, 1.8 M
against 2.9 M, a product over the pattern cost nearly as much as a new set-up, over
the changed rows an eighth of that), with the same operators (docs/bodies.md). The
updated operators are exactly the Galerkin operators of the new J with the old
interpolations, i.e. what ``-pc_gamg_reuse_interpolation`` gives after a full
set-up, at the cost of the change only. The coarse solver is factorised again and
each level's smoother preconditioner (Jacobi) set up again on its updated operator;
the Chebyshev smoothers keep the eigenvalue bounds estimated at the set-up (a new
estimate is ten GMRES iterations per level: two-body Hertz medium mesh, 0.67 of a
6.75 s load path, the same Krylov counts without it, 125 and 124; docs/bodies.md).

Memory of the set-up's products (PETSc 3.22, MPIAIJ on several processes;
docs/coulomb.md, Memory). PETSc's default parallel PtAP ("nonscalable") forms A P on
each process, a local copy of P and P^T, and keeps them on the coarse operator for a
later product of the same pattern, which nothing here makes (GAMG's set-up forms each
coarse operator once, the updates form new products): about 1.7 KB/dof held after the
set-up. :func:`set_up` frees them as each product is done and forms the products by
the "backend" algorithm (a sequential P^T A P of the diagonal blocks, which forms no
A P, plus the off-process part), which peaks lower (lev 9 d3/L2, 2 ranks: peak 5526
-> 4259 B/dof; lev 11 fits 2 ranks in 16.2 GiB); "allatonce" peaks lower still but
took 4-6x longer on the finest level. The updates' products (Delta_l)_S P_l are
formed by the "backend" algorithm on several processes too: the default one merges
all local rows of P_l first (lev 9: 0.06 against 0.02 s per update).
"""

from __future__ import annotations

import typing

from petsc4py import PETSc

from contactqvi.lifetime import PETScOwner
from contactqvi.linalg import default_options, nonzero_rows

__all__ = ["GalerkinUpdate", "is_multigrid", "set_up"]

_SUBSET = PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN
#: Options without a prefix (a product's matrix has none) in force during a multigrid
#: set-up: each Galerkin product's intermediates are freed when it is formed ...
_SET_UP_OPTIONS = {"mat_product_clear": True}
#: ... and on several processes formed by the "backend" algorithm (an MPIAIJ product
#: only: a sequential PtAP rejects the name, and forms no A P anyway).
_PARALLEL_SET_UP_OPTIONS = {**_SET_UP_OPTIONS, "matptap_via": "backend"}


def is_multigrid(pc: PETSc.PC) -> bool:
    """True for preconditioners with Galerkin levels this module can update (GAMG, MG)."""
    return pc.getType() in (PETSc.PC.Type.GAMG, PETSc.PC.Type.MG)


def set_up(ksp: PETSc.KSP) -> None:
    """Set up ``ksp`` and its multigrid preconditioner with the memory-lean Galerkin products above.

    The same coarse operators as PETSc's default products up to round-off (on 1 rank
    bit for bit: only the clearing applies); the user's own ``-matptap_via`` or
    ``-mat_product_clear`` wins.
    """
    options = _SET_UP_OPTIONS if ksp.getComm().getSize() == 1 else _PARALLEL_SET_UP_OPTIONS
    with default_options("", options):
        ksp.setUp()


class GalerkinUpdate(PETScOwner):
    """Updates the levels of the set-up multigrid preconditioner ``pc`` for changes of its fine operator.

    Args:
        pc: a GAMG or MG preconditioner after its set-up; its fine operator must
            keep its identity (changes are made in place).

    Attributes:
        updates: number of :meth:`update` calls since the set-up.
    """

    def __init__(self, pc: PETSc.PC):
        self._pc = pc
        levels = pc.getMGLevels()
        self._interpolations = [pc.getMGInterpolation(level) for level in range(1, levels)]
        self._operators = [pc.getMGSmoother(level).getOperators()[0] for level in range(levels)]
        for operator in self._operators[:-1]:  # the coarse ones, changed here row by row by their owners
            operator.setOption(PETSc.Mat.Option.NO_OFF_PROC_ENTRIES, True)
        self.updates = 0  # updates since the set-up

    def petsc_objects(self) -> list[typing.Any]:
        return [*self._interpolations, *self._operators, self._pc]

    def update(self, change: PETSc.Mat, structure: PETSc.Mat.Structure = _SUBSET) -> None:
        """Add ``change`` (already added to the fine operator) to every coarse level and
        set up the smoothers' preconditioners again; the preconditioner is then to be reused.

        ``structure``: the coarse changes' patterns lie within the levels' own
        (``SUBSET_NONZERO_PATTERN``: J changed on its own pattern), or may add entries
        (``DIFFERENT_NONZERO_PATTERN``: J's pattern grew, e.g. by a contact search).
        """
        coarse = change
        for level in reversed(range(len(self._interpolations))):
            finer, coarse = coarse, _galerkin_product(coarse, self._interpolations[level])
            self._operators[level].axpy(1.0, coarse, structure)
            if finer is not change:  # a coarse change made here, not the caller's
                finer.destroy()
        if coarse is not change:
            coarse.destroy()
        if structure != _SUBSET:  # a grown pattern is a new matrix in the same object
            for operator in self._operators[:-1]:
                operator.setOption(PETSc.Mat.Option.NO_OFF_PROC_ENTRIES, True)
        for level, operator in enumerate(self._operators):
            smoother = self._pc.getMGSmoother(level)
            if level == 0:  # the coarse solver: factorised again
                smoother.setOperators(operator, operator)
            else:  # the smoother's preconditioner follows its operator; Chebyshev keeps its bounds
                smoother.getPC().setUp()
        self._pc.setReusePreconditioner(True)
        self.updates += 1


def _galerkin_product(change: PETSc.Mat, P: PETSc.Mat) -> PETSc.Mat:
    """P^T ``change`` P as P_S^T (change_S P), S the rows of ``change`` with nonzero entries
    (a new matrix in the layout of P's columns)."""
    rows, change_rows = nonzero_rows(change)
    low, high = P.getOwnershipRangeColumn()
    columns = PETSc.IS().createStride(high - low, low, 1, comm=P.getComm())  # all of P's columns
    P_rows = P.createSubMatrix(rows, columns)
    # "backend" on several processes (a sequential product rejects the name)
    options = {} if P.getComm().getSize() == 1 else {"matmatmult_via": "backend"}
    with default_options("", options):
        product = change_rows.matMult(P)
    coarse = P_rows.transposeMatMult(product)
    for obj in (rows, columns, change_rows, P_rows, product):
        obj.destroy()
    return coarse
