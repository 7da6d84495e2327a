"""Every solver object of the obstacle, QVI and SNES-VI families frees its PETSc objects.

Two independent checks around build + solve + ``destroy()``:

* a reference audit: every PETSc object created meanwhile that Python still
  references (the stack is kept alive on purpose) must be destroyed, except the
  vectors DOLFINx wraps around its own Function arrays;
* PETSc's own count of created minus destroyed objects per type (``-log_view``'s
  object table) must be back where it was once Python has dropped the stack. In
  parallel, petsc4py hands an object that was never destroyed to PETSc's garbage
  list instead of freeing it, so under ``mpirun`` this also catches objects that
  were dropped without ``destroy()`` (serially those are freed on the spot).
"""

from __future__ import annotations

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import pytest

from dolfinx import fem

from contactqvi.contact import build_contact_problem
from contactqvi.contact.signorini_vi import solve_signorini_vi
from contactqvi.laws import Frictionless
from contactqvi.meshes import create_contact_body, create_unit_square
from contactqvi.problems import coulomb, thermoforming
from contactqvi.problems.obstacle import radial_obstacle
from contactqvi.qvi import build, create_mesh
from contactqvi.vi import ObstacleProblem, ObstacleSolver

from petsc_audit import assert_frees_petsc_objects


def _radial_problem(n: int) -> ObstacleProblem:
    data = radial_obstacle()
    msh, tags = create_unit_square(MPI.COMM_WORLD, n)
    V = fem.functionspace(msh, ("Lagrange", 1))
    msh.topology.create_connectivity(1, 2)
    g, theta = fem.Function(V), fem.Function(V)
    g.interpolate(data.exact)
    theta.interpolate(data.obstacle)
    bc = fem.dirichletbc(g, fem.locate_dofs_topological(V, 1, tags.indices))
    return ObstacleProblem(V, fem.Constant(msh, 0.0), theta, [bc])


@pytest.mark.parametrize("s_solver", ["pfmy-pdas", "vinewtonrsls"])
def test_obstacle_solver_frees_its_petsc_objects(s_solver, mpi_tmp_path):
    def run():
        problem = _radial_problem(8)
        solver = ObstacleSolver(problem, {"s_solver": s_solver}, prefix=f"tlife_{s_solver}_")
        assert solver.solve().converged and solver.solve().converged  # cold, then warm
        return [solver, problem]

    assert_frees_petsc_objects(run, mpi_tmp_path)


@pytest.mark.parametrize("test, method", [(3, "alg2"), (3, "c2"), (3, "c3"), (4, "alg1"), (2, "alg2")])
def test_qvi_stack_frees_its_petsc_objects(test, method, mpi_tmp_path):
    def run():
        data = thermoforming.make_test(test)
        msh, _ = create_mesh(MPI.COMM_WORLD, data.dim, 0.1 if data.dim == 2 else 0.05)
        outer = {"atol": 1e-10, "radius": 0.01} if test == 2 else {"atol": 1e-10}
        setup = build(data, msh, method, outer)
        assert setup.solver.solve(setup.initial).converged
        return [setup]

    assert_frees_petsc_objects(run, mpi_tmp_path)


@pytest.mark.parametrize("ksp, near_nullspace", [("lu", False), ("cg_gamg", True)])
def test_signorini_snes_vi_frees_its_petsc_objects(ksp, near_nullspace, mpi_tmp_path):
    def run():
        msh, tags = create_contact_body(MPI.COMM_WORLD, 1, coulomb.gap_function("d3"))
        problem = build_contact_problem(msh, tags, coulomb.YOUNG, coulomb.POISSON, coulomb.tractions("L2"), Frictionless())
        u = problem.A.createVecRight()
        result = solve_signorini_vi(problem, u, {"snes_rtol": 1e-12}, prefix=f"tlife_signorini_{ksp}_", ksp=ksp,
                                    near_nullspace=near_nullspace)
        assert result.converged
        assert np.all(u.array.reshape(-1, 3)[problem.contact_blk, 2] >= 0.0)
        # the caller's objects: PETSc caches a vector on A in the first SNES solve with it
        return [u, problem]

    assert_frees_petsc_objects(run, mpi_tmp_path)


class _LeakyOwner:
    """Forgets one of its two vectors in destroy()."""

    def __init__(self):
        self.kept, self.forgotten = PETSc.Vec().createMPI(4), PETSc.Vec().createMPI(4)

    def destroy(self):
        self.kept.destroy()


def test_the_audit_catches_an_object_left_alive(mpi_tmp_path):
    made = []

    def run():
        made.append(_LeakyOwner())
        return list(made)

    with pytest.raises(AssertionError, match="mpi|seq"):
        assert_frees_petsc_objects(run, mpi_tmp_path)
    made[0].forgotten.destroy()
