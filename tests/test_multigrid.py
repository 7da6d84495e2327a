"""The multigrid set-up of ``contactqvi/multigrid.py``: the memory-lean Galerkin products of
:func:`~contactqvi.multigrid.set_up` give PETSc's default coarse operators (to round-off),
leave the options database as they found it, and the Galerkin updates still work on them.
Serial and on 2 ranks (the "backend" product is the parallel one).
"""

from __future__ import annotations

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import ufl

import dolfinx.fem.petsc
from dolfinx import fem, mesh

from contactqvi import linalg
from contactqvi.linalg import create_ksp, default_options, nonzero_row_indices, nonzero_rows, preset, significant
from contactqvi.multigrid import GalerkinUpdate, set_up


def _coarse_operators(ksp: PETSc.KSP) -> list[PETSc.Mat]:
    pc = ksp.getPC()
    return [pc.getMGSmoother(level).getOperators()[0] for level in range(pc.getMGLevels() - 1)]


def _operator() -> tuple[PETSc.Mat, fem.FunctionSpace]:
    """A scalar P1 operator (Laplacian plus mass) on the unit cube, 8^3 cells, and its space
    (to be kept alive while the matrix is used)."""
    msh = mesh.create_unit_cube(MPI.COMM_WORLD, 8, 8, 8)
    V = fem.functionspace(msh, ("Lagrange", 1))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    J = dolfinx.fem.petsc.assemble_matrix(fem.form(ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx + u * v * ufl.dx))
    J.assemble()
    return J, V


def test_lean_set_up_gives_the_default_coarse_operators_and_restores_the_options():
    J, _space = _operator()
    options = preset("gmres_gamg")
    plain, lean = (create_ksp(MPI.COMM_WORLD, prefix, options, A=J) for prefix in ("mg_plain_", "mg_lean_"))
    with default_options("mg_plain_", options):
        plain.setUp()
    with default_options("mg_lean_", options):
        set_up(lean)
    assert not any(PETSc.Options().hasName(name) for name in ("matptap_via", "mat_product_clear"))
    expected, actual = _coarse_operators(plain), _coarse_operators(lean)
    assert len(expected) == len(actual) >= 1
    for C, D in zip(expected, actual):
        difference = D.copy()
        difference.axpy(-1.0, C)
        assert difference.norm() <= 1e-12 * C.norm()
        difference.destroy()

    change = J.duplicate(copy=False)  # the updates' products run on the lean operators
    start = change.getOwnershipRange()[0]
    change.setValue(start, start, 0.5)
    change.assemble()
    galerkin = GalerkinUpdate(lean.getPC())
    galerkin.update(change)
    coarsest = _coarse_operators(lean)[0]
    assert np.isfinite(coarsest.norm()) and galerkin.updates == 1
    for obj in (galerkin, change, plain, lean, J):
        obj.destroy()


def test_galerkin_update_sets_up_each_smoothers_jacobi_on_its_updated_operator():
    """After an update every level's Jacobi preconditioner is 1 / diag of that level's new
    operator (the fine one changed in place), not of the operator of the set-up."""
    J, _space = _operator()
    options = preset("gmres_gamg")
    ksp = create_ksp(MPI.COMM_WORLD, "mg_jacobi_", options, A=J)
    with default_options("mg_jacobi_", options):
        set_up(ksp)
    pc = ksp.getPC()
    assert pc.getMGLevels() >= 2
    change = J.duplicate(copy=False)
    low, high = change.getOwnershipRange()
    for row in range(low, high, 7):  # a few rows per rank, their diagonal raised tenfold
        change.setValue(row, row, 9.0 * J.getValue(row, row))
    change.assemble()
    J.axpy(1.0, change, PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
    galerkin = GalerkinUpdate(pc)
    galerkin.update(change)
    for level in range(1, pc.getMGLevels()):
        smoother = pc.getMGSmoother(level)
        assert smoother.getPC().getType() == PETSc.PC.Type.JACOBI
        operator = smoother.getOperators()[0]
        ones, applied = operator.createVecRight(), operator.createVecRight()
        ones.set(1.0)
        smoother.getPC().apply(ones, applied)
        diagonal = operator.getDiagonal()
        assert np.allclose(applied.array * diagonal.array, 1.0, rtol=1e-12)
        for vec in (ones, applied, diagonal):
            vec.destroy()
    for obj in (galerkin, change, ksp, J):
        obj.destroy()


def test_nonzero_rows_of_a_change_with_no_zero_row():
    """A change nonzero on every row (as on a coarse level, where few rows mix everything):
    PETSc's MatFindZeroRows then returns no index set at all (NULL), and every owned row is
    reported (lev 9 d3/L2 on 2 ranks crashed there); explicit zeros still do not count."""
    J, _space = _operator()
    low, high = J.getOwnershipRange()
    assert np.array_equal(nonzero_row_indices(J), np.arange(low, high))
    rows, compact = nonzero_rows(J)
    assert np.array_equal(rows.getIndices(), np.arange(low, high)) and compact.getSize() == J.getSize()
    assert np.isclose(compact.norm(PETSc.NormType.FROBENIUS), J.norm(PETSc.NormType.FROBENIUS), rtol=1e-14)
    zeroed = J.copy()
    zeroed.zeroRows(np.arange(low, high, 2, dtype=PETSc.IntType), diag=0.0)  # explicit zeros on every other row
    assert np.array_equal(nonzero_row_indices(zeroed), np.arange(low + 1, high, 2))
    for obj in (rows, compact, zeroed, J):
        obj.destroy()


def test_significant_entries_drop_the_terms_a_difference_cancelled(monkeypatch):
    """J + E - (1 + 1e-14) E with E = 1e4 J^2 (a wider stencil, as B^T D B of the nodal pressure
    against the cell-wise tangent; cancelled to about round-off of E): without its entries below
    1e-9 of their row it is J again, on J's pattern (the rows' columns are J's), in J's layout,
    read 100 rows at a time."""
    monkeypatch.setattr(linalg, "_ROWS_AT_A_TIME", 100)
    J, _space = _operator()
    E = J.matMult(J)
    E.scale(1e4)
    wide = J.duplicate(copy=True)
    wide.axpy(1.0, E, PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
    wide.axpy(-(1.0 + 1e-14), E, PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
    assert wide.getInfo()["nz_used"] > 2 * J.getInfo()["nz_used"]
    narrow = significant(wide, 1e-9)
    assert narrow.getOwnershipRange() == J.getOwnershipRange() and narrow.getSize() == J.getSize()
    for row in range(*J.getOwnershipRange()):
        assert np.array_equal(narrow.getRow(row)[0], J.getRow(row)[0])
    narrow.axpy(-1.0, J, PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
    assert narrow.norm(PETSc.NormType.INFINITY) <= 1e-13 * E.norm(PETSc.NormType.INFINITY)
    for obj in (narrow, wide, E, J):
        obj.destroy()
