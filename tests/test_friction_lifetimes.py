"""Every PETSc object the seed-002 code creates is destroyed by its owner's collective ``destroy()``.

The audit counts live PETSc objects by class from PETSc's own log (creations minus
destructions, as ``-log_view`` prints them), so it sees objects that Python no
longer references too: left to the garbage collector, a parallel object only goes
to petsc4py's garbage list and stays alive. The counts are taken while the Python
objects (problem, solvers, results) are still referenced, so only ``destroy()``
can bring them back.
"""

from __future__ import annotations

import os
import re
import tempfile

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import pytest

from contactqvi.friction.analysis import neumann_to_dirichlet_eigenvalue
from contactqvi.friction.methods import FrictionSolvers
from contactqvi.problems.stadler import create_stadler_problem

if not PETSc.Log.isActive():
    PETSc.Log.begin()


def live_objects(comm: MPI.Comm) -> dict[str, int]:
    """PETSc objects alive on rank 0 by class (creations - destructions since logging began), on every rank."""
    path = comm.bcast(tempfile.mkstemp(suffix=".log")[1] if comm.rank == 0 else None, root=0)
    viewer = PETSc.Viewer().createASCII(path, comm=comm)
    PETSc.Log.view(viewer)
    viewer.destroy()
    counts: dict[str, int] | None = None
    if comm.rank == 0:
        with open(path) as fh:
            text = fh.read()
        os.unlink(path)
        block = text.split("Object Type", 1)[1].split("=====", 1)[0]
        counts = {}
        for name, created, destroyed in re.findall(r"^\s*(\S.*?)\s+(\d+)\s+(\d+)\s*$", block, re.MULTILINE):
            counts[name] = counts.get(name, 0) + int(created) - int(destroyed)
        counts.pop("Viewer", None)  # the audit's own viewers
    return comm.bcast(counts, root=0)


def leaked(before: dict[str, int], after: dict[str, int]) -> dict[str, int]:
    return {name: n - before.get(name, 0) for name, n in after.items() if n != before.get(name, 0)}


def test_the_audit_sees_an_object_that_is_not_destroyed():
    comm = MPI.COMM_WORLD
    before = live_objects(comm)
    vec = PETSc.Vec().createMPI((3, PETSc.DECIDE), comm=comm)
    assert leaked(before, live_objects(comm)) == {"Vector": 1}
    vec.destroy()
    assert leaked(before, live_objects(comm)) == {}


@pytest.mark.parametrize("discretisation", ["q1", "fd"])
def test_problem_solvers_and_results_free_their_petsc_objects(discretisation):
    """Build + every method + destroy leaves no PETSc object alive, with the results still referenced."""
    comm = MPI.COMM_WORLD
    before = live_objects(comm)
    problem = create_stadler_problem(comm, example=2, N=9, discretisation=discretisation)
    runs = {
        "pdas": {"gamma": 1e3, "max_iterations": 20},
        "ss": {"gamma": 50.0, "sigma": 1.0 / 50.0},
        "alm": {"schedule": "power10", "inner": "inexact", "max_outer": 3},
        "uzawa": {"gamma": 0.2, "max_iterations": 5},
    }
    with problem, FrictionSolvers(problem) as solvers:
        reference = solvers.reference()
        results = {method: solvers.solve(method, parameters, reference.lam) for method, parameters in runs.items()}
        assert all(result.iterations > 0 for result in results.values())
        problem.energy_norm(results["alm"].y.x.petsc_vec, results["uzawa"].y.x.petsc_vec)
        neumann_to_dirichlet_eigenvalue(problem, np.ones(len(problem.boundary_dofs), dtype=bool), iterations=3)
        assert leaked(before, live_objects(comm)), "the audit must see the live problem and solvers"
    assert leaked(before, live_objects(comm)) == {}


def test_demo_frees_its_petsc_objects(mpi_tmp_path, load_demo):
    comm = MPI.COMM_WORLD
    demo = load_demo("simplified_friction")
    before = live_objects(comm)
    argv = ["--example", "3", "--method", "alm", "--N", "9", "--alm-max-outer", "2", "--output", str(mpi_tmp_path)]
    assert demo.main([*argv, "--no-png", "--log-level", "WARNING"]) == 0
    assert leaked(before, live_objects(comm)) == {}
