"""Linear-solver options of the seed-002 solvers belong to the instance, not to the shared PETSc database."""

from __future__ import annotations

from mpi4py import MPI
from petsc4py import PETSc

import pytest

from contactqvi.friction import FrictionActiveSetSolver, create_problem
from contactqvi.linalg import preset
from contactqvi.problems.stadler import stadler_example

from friction_checks import state_residual

ITERATIVE = preset("cg_jacobi", ksp_rtol=1e-2)


@pytest.fixture
def prefix():
    """A prefix no other test uses; whatever a test leaves under it is removed afterwards."""
    name = "friction_options_test_"
    yield name
    opts = PETSc.Options()
    for key in ("ksp_type", "pc_type", "ksp_rtol", "pc_factor_mat_solver_type"):
        opts.delValue(name + key)


def _state_residual(problem, result) -> float:
    residual = state_residual(problem, result.y.x.petsc_vec, result.lam)
    return residual / problem.F.norm(PETSc.NormType.NORM_INFINITY)


def test_two_instances_with_one_prefix_keep_their_own_options(prefix):
    """A loose iterative solver first, then the default direct one under the same prefix."""
    problem = create_problem(MPI.COMM_WORLD, stadler_example(3), N=21)
    with problem, FrictionActiveSetSolver(problem, prefix, ITERATIVE) as iterative:
        with FrictionActiveSetSolver(problem, prefix) as direct:
            assert (iterative.ksp.getType(), iterative.ksp.getPC().getType()) == ("cg", "jacobi")
            assert iterative.ksp.getTolerances()[0] == pytest.approx(1e-2)
            assert (direct.ksp.getType(), direct.ksp.getPC().getType()) == ("preonly", "lu")
            assert not PETSc.Options().hasName(prefix + "ksp_type")
            # (3.2a) holds to round-off only with the direct solver; rtol 1e-2 leaves a visible residual.
            exact = _state_residual(problem, direct.solve(gamma=50.0))
            loose = _state_residual(problem, iterative.solve(gamma=50.0))
    print(f"relative (3.2a) residual: direct {exact:.1e}, cg/jacobi rtol 1e-2 {loose:.1e}")
    assert exact < 1e-10 and loose > 1e-6


def test_user_options_win_and_stay(prefix):
    """A value in the database (e.g. from the command line) overrides ``ksp_options`` and is not removed."""
    opts = PETSc.Options()
    opts[prefix + "ksp_type"] = "gmres"
    problem = create_problem(MPI.COMM_WORLD, stadler_example(3), N=9)
    with problem, FrictionActiveSetSolver(problem, prefix, ITERATIVE) as pdas:
        assert pdas.ksp.getType() == "gmres" and pdas.ksp.getPC().getType() == "jacobi"
    assert opts.getString(prefix + "ksp_type") == "gmres"
    assert not opts.hasName(prefix + "pc_type")
