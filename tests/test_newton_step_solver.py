"""The linear solver of the SCD Newton step (``contact/newton_step_solver.py``): what its
preconditioner keeps from step to step, its Krylov test, its initial guess and its PETSc lifetime.

J is a scalar Poisson-plus-mass matrix changed in place on a few rows before every
solve, as the SCD Newton matrix changes on the contact rows; the preconditioner set-ups
of a solve are counted from PETSc's log (``PCSetUp`` events; a reused preconditioner
logs none). Serial and on 2 ranks.
"""

from __future__ import annotations

import dataclasses

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import pytest
import ufl

import dolfinx.fem.petsc
from dolfinx import fem, mesh

from contactqvi.contact import NewtonStepSolver, SCDNewtonSolver, build_contact_problem
from contactqvi.laws import Coulomb
from contactqvi.lifetime import PETScOwner
from contactqvi.meshes import create_contact_body
from contactqvi.problems import coulomb

from petsc_audit import assert_frees_petsc_objects

_SUBSET = PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN


@dataclasses.dataclass(eq=False)
class _System(PETScOwner):
    """J (changed in place by ``change`` at each :meth:`step`), a right-hand side and a solution."""

    V: fem.FunctionSpace  # kept: a GAMG set-up on J crashes once J's function space is gone
    J: PETSc.Mat
    change: PETSc.Mat
    rhs: PETSc.Vec
    du: PETSc.Vec

    @classmethod
    def create(cls, n: int = 6) -> _System:
        msh = mesh.create_unit_cube(MPI.COMM_WORLD, n, n, n)
        V = fem.functionspace(msh, ("Lagrange", 1))
        u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
        J = dolfinx.fem.petsc.assemble_matrix(fem.form(ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx + u * v * ufl.dx))
        J.assemble()
        change = J.duplicate(copy=False)  # J's pattern, zero but on the first three rows of each rank
        start = change.getOwnershipRange()[0]
        for row in range(start, start + 3):
            change.setValue(row, row, 0.5)
        change.assemble()
        rhs, du = J.createVecs()
        rhs.set(1.0)
        return cls(V, J, change, rhs, du)

    def petsc_objects(self) -> list[PETSc.Object]:
        return [self.J, self.change, self.rhs, self.du]

    def step(self, solver: NewtonStepSolver, kinds: np.ndarray, tol: float = 0.1) -> int:
        """J += change, then one solve from du = 0; returns the PCSetUp events it logged."""
        self.J.axpy(1.0, self.change, _SUBSET)
        self.du.set(0.0)
        before = _set_ups()
        assert solver.solve(self.J, self.change, kinds, self.rhs, self.du, tol) > 0, solver.reason
        return _set_ups() - before

    def relative_residual(self) -> float:
        residual = self.rhs.duplicate()
        self.J.mult(self.du, residual)
        residual.aypx(-1.0, self.rhs)
        value = residual.norm() / self.rhs.norm()
        residual.destroy()
        return value


def _set_ups() -> int:
    return PETSc.Log.Event("PCSetUp").getPerfInfo()["count"]


def _solver(pc: str, prefix: str, multigrid_options: dict | None = None, **options) -> NewtonStepSolver:
    PETSc.Log.begin()
    parameters = {"rtol": 0.1, "reuse_pc": True, "rebuild_iterations": 10, "initial_guess": True, **options}
    return NewtonStepSolver(MPI.COMM_WORLD, prefix, pc, multigrid_options or {}, **parameters)


def test_multigrid_is_set_up_once_and_follows_J_by_galerkin_updates():
    with _System.create() as system, _solver("gamg", "nss_mg_") as solver:
        kinds = np.zeros(4, np.int8)
        system.step(solver, kinds)
        galerkin = solver.galerkin
        assert galerkin is not None and galerkin.updates == 0
        for step in range(1, 4):
            system.step(solver, kinds + step)  # kinds play no part with multigrid
            assert solver.galerkin is galerkin and galerkin.updates == step
            assert system.relative_residual() <= 0.1
        assert solver.ksp.getInitialGuessNonzero()


def test_a_slow_solve_brings_a_new_multigrid_set_up():
    with _System.create() as system, _solver("gamg", "nss_rebuild_", rebuild_iterations=1) as solver:
        kinds = np.zeros(4, np.int8)
        system.step(solver, kinds, tol=1e-8)
        first = solver.galerkin
        assert solver.iterations > 1
        system.step(solver, kinds, tol=1e-8)
        assert solver.galerkin is not first and solver.galerkin.updates == 0
        assert first.updates == 0 and system.relative_residual() <= 1e-8


def test_unsmoothed_aggregation_is_not_set_up_again_after_a_slow_solve():
    """Its interpolation depends on J's pattern and the near-nullspace only (several bodies)."""
    unsmoothed = {"pc_gamg_agg_nsmooths": 0}
    with _System.create() as system, _solver("gamg", "nss_unsmoothed_", unsmoothed, rebuild_iterations=1) as solver:
        kinds = np.zeros(4, np.int8)
        system.step(solver, kinds, tol=1e-8)
        first = solver.galerkin
        assert solver.iterations > 1
        system.step(solver, kinds, tol=1e-8)
        assert solver.galerkin is first and first.updates == 1
        assert system.relative_residual() <= 1e-8


def test_levels_set_up_before_the_first_solve_follow_a_grown_pattern():
    """A contact search (several bodies) changes J where the mortar couplings move, outside
    its pattern: after :meth:`update_operator` every level is again the Galerkin product of
    the finer one with the kept interpolation, and the solves go on without a new set-up."""
    with _System.create() as system, _solver("gamg", "nss_grown_", {"pc_gamg_agg_nsmooths": 0}) as solver:
        J = system.J
        assert solver.set_up_levels(J)
        galerkin = solver.galerkin
        n, start = J.getSize()[0], J.getOwnershipRange()[0]
        grown = PETSc.Mat().createAIJ(size=J.getSizes(), nnz=(2, 2), comm=J.getComm())
        far = (start + n // 2) % n  # not a neighbour of row ``start`` on the cube
        grown.setValues([start, far], [far, start], [[0.0, 0.05], [0.05, 0.0]], addv=PETSc.InsertMode.ADD_VALUES)
        grown.assemble()
        J.axpy(1.0, grown, PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
        solver.update_operator(grown, grown=True)
        pc = solver.ksp.getPC()
        operators = [pc.getMGSmoother(level).getOperators()[0] for level in range(pc.getMGLevels())]
        assert operators[-1].handle == J.handle
        for level in range(1, len(operators)):
            expected = operators[level].PtAP(pc.getMGInterpolation(level))
            scale = expected.norm()
            expected.axpy(-1.0, operators[level - 1], PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
            assert expected.norm() <= 1e-13 * scale, level
            expected.destroy()
        system.step(solver, np.zeros(4, np.int8))
        assert solver.galerkin is galerkin and galerkin.updates == 2
        assert system.relative_residual() <= 0.1
        grown.destroy()


@pytest.mark.parametrize("reuse_pc", [True, False])
def test_other_preconditioners_are_kept_while_no_contact_node_changes_its_kind(reuse_pc):
    with _System.create() as system, _solver("paper", f"nss_ilu_{reuse_pc}_", reuse_pc=reuse_pc) as solver:
        kinds = np.zeros(4, np.int8)
        assert system.step(solver, kinds) > 0
        assert (system.step(solver, kinds.copy()) > 0) is not reuse_pc
        assert system.relative_residual() <= 1.0  # GMRES + ILU: 0.1 on the preconditioned residual
        changed = kinds.copy()
        if MPI.COMM_WORLD.rank == 0:  # a change on one rank is a change everywhere
            changed[0] = 1
        assert system.step(solver, changed) > 0
        assert solver.galerkin is None


def test_direct_solves_refactor_at_every_step():
    with _System.create() as system, _solver("lu", "nss_lu_") as solver:
        kinds = np.zeros(4, np.int8)
        for _ in range(3):
            assert system.step(solver, kinds) > 0
            assert system.relative_residual() <= 1e-12
        assert not solver.ksp.getInitialGuessNonzero() and solver.galerkin is None


def test_the_initial_guess_is_used_only_when_asked_for():
    with _System.create() as system, _solver("gamg", "nss_zero_guess_", initial_guess=False) as solver:
        system.du.set(1.0)
        solver.solve(system.J, system.change, np.zeros(0, np.int8), system.rhs, system.du, 0.1)
        assert not solver.ksp.getInitialGuessNonzero() and system.relative_residual() <= 0.1


def test_the_krylov_test_is_relative_to_the_rhs_of_5_4():
    """rtol is tol ||rhs of (5.4)|| / ||assembled rhs||, unless the test is relative to the initial residual."""
    with _System.create() as system, _solver("gamg", "nss_rtol_") as solver:
        assert solver.krylov_rtol(0.1, 0.25) == pytest.approx(0.025)
        solver.solve(system.J, system.change, np.zeros(0, np.int8), system.rhs, system.du, 0.1, rhs_ratio=0.25)
        assert solver.ksp.getTolerances()[0] == pytest.approx(0.025)
        options = PETSc.Options()
        options["nss_rtol_ksp_converged_use_initial_residual_norm"] = True
        try:
            assert solver.krylov_rtol(0.1, 0.25) == 0.1
        finally:
            options.delValue("nss_rtol_ksp_converged_use_initial_residual_norm")


def test_a_start_that_meets_the_test_alone_still_solves_the_free_rows():
    """An eliminated row (here every rank's first: an identity row) whose exact value dominates
    ||rhs|| lets the start du_0 (that value, zero elsewhere) meet tol ||rhs||: the free rows are then
    solved to tol of their own residual ||rhs - J du_0||, not left at zero (0 Krylov iterations);
    with a start that does not meet the test, or whose free rows are round-off, the rtol is the paper's."""
    with _System.create() as system, _solver("gamg", "nss_free_rows_") as solver:
        J, rhs, du = system.J, system.rhs, system.du
        first = J.getOwnershipRange()[0]
        J.zeroRowsColumns([first], diag=1.0)  # the eliminated row: identity, its column moved to the rhs
        rhs.setValue(first, 1e6)
        rhs.assemble()
        free = rhs.copy()
        free.setValue(first, 0.0)  # the free rows' part of the rhs, whose size the start leaves
        free.assemble()
        start = free.norm()
        for exact, paper in ((1e6, False), (1.0, True)):
            rhs.setValue(first, exact)
            rhs.assemble()
            du.set(0.0)
            du.setValue(first, exact)
            du.assemble()
            assert solver.solve(J, system.change, np.zeros(0, np.int8), rhs, du, 0.1) > 0
            assert solver.ksp.getTolerances()[0] == pytest.approx(0.1 if paper else 0.1 * start / rhs.norm())
            assert solver.iterations > 0 and system.relative_residual() * rhs.norm() <= 0.1 * (rhs.norm() if paper
                                                                                                 else start)
        rhs.scale(1e-20)  # free rows at round-off of the eliminated row's 1e6: solved already, the paper's test
        rhs.setValue(first, 1e6)
        rhs.assemble()
        du.set(0.0)
        du.setValue(first, 1e6)
        du.assemble()
        assert solver.solve(J, system.change, np.zeros(0, np.int8), rhs, du, 0.1) > 0
        assert solver.ksp.getTolerances()[0] == 0.1 and solver.iterations == 0
        free.destroy()


@pytest.mark.parametrize("pc", ["gamg", "paper", "lu"])
def test_the_newton_step_solver_frees_its_petsc_objects(pc, mpi_tmp_path):
    """Every policy (a multigrid set-up replaced after a slow solve included) leaves nothing alive."""

    def run():
        system = _System.create()
        solver = _solver(pc, f"nss_life_{pc}_", rebuild_iterations=1)
        for step in range(3):
            system.step(solver, np.full(4, step // 2, np.int8), tol=1e-6)
        return [solver, system]

    assert_frees_petsc_objects(run, mpi_tmp_path)


def test_the_scd_solver_frees_its_step_solver_and_work_vectors(mpi_tmp_path):
    """The SCD solver with a new multigrid set-up after every Newton step, over two solves."""

    def run():
        msh, tags = create_contact_body(MPI.COMM_WORLD, 2, coulomb.gap_function("d3"))
        problem = build_contact_problem(msh, tags, coulomb.YOUNG, coulomb.POISSON, coulomb.tractions("L2"),
                                        Coulomb(coulomb.FRICTION))  # fmt: skip
        solver = SCDNewtonSolver(problem, {"pc_rebuild_iterations": 1}, prefix="nss_life_scd_")
        u = problem.A.createVecRight()
        assert solver.solve(u).converged and solver.solve(u).converged  # cold, then warm
        return [solver, u, problem]

    assert_frees_petsc_objects(run, mpi_tmp_path)
