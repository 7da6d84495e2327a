"""Every PETSc object the seed-002 code creates is destroyed by its owner's collective ``destroy()``.

The audit (``tests/petsc_audit.py``, shared with the obstacle, QVI and SNES-VI families)
checks build + every method + ``destroy()`` with the results still referenced: Python
must hold no live PETSc object and PETSc's own count of objects per type must be back
where it was (under ``mpirun`` that also catches objects merely dropped, which sit alive
in petsc4py's garbage list).
"""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest

from contactqvi.friction import create_problem
from contactqvi.friction.analysis import neumann_to_dirichlet_eigenvalue
from contactqvi.friction.methods import FrictionSolvers
from contactqvi.problems.stadler import REFERENCE_GAMMA, stadler_example

from petsc_audit import assert_frees_petsc_objects

RUNS = {
    "pdas": {"gamma": 1e3, "max_iterations": 20},
    "ss": {"gamma": 50.0, "sigma": 1.0 / 50.0},
    "alm": {"schedule": "power10", "inner": "inexact", "max_outer": 3},
    "uzawa": {"gamma": 0.2, "max_iterations": 5},
}


@pytest.mark.parametrize("discretisation", ["q1", "fd"])
def test_problem_solvers_and_results_free_their_petsc_objects(discretisation, mpi_tmp_path):
    results = []

    def run():
        problem = create_problem(MPI.COMM_WORLD, stadler_example(2), N=9, discretisation=discretisation)
        solvers = FrictionSolvers(problem)
        reference = solvers.reference(REFERENCE_GAMMA)
        results.extend(solvers.solve(method, parameters, reference.lam) for method, parameters in RUNS.items())
        assert all(result.iterations > 0 for result in results)
        problem.energy_norm(results[2].y.x.petsc_vec, results[3].y.x.petsc_vec)
        neumann_to_dirichlet_eigenvalue(problem, np.ones(len(problem.boundary_dofs), dtype=bool), iterations=3)
        return [solvers, problem]

    assert_frees_petsc_objects(run, mpi_tmp_path)


def test_demo_frees_its_petsc_objects(mpi_tmp_path, load_demo):
    demo = load_demo("simplified_friction")
    argv = ["--example", "3", "--method", "alm", "--N", "9", "--max-outer", "2", "--output", str(mpi_tmp_path)]

    def run():
        assert demo.main([*argv, "--no-png", "--log-level", "WARNING"]) == 0
        return []

    assert_frees_petsc_objects(run, mpi_tmp_path)
