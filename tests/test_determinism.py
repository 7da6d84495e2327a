"""The same command on the same number of ranks gives the same partition, counts and numbers.

Run-to-run variation entered through the mesh partition: PT-SCOTCH 7 partitions
with several threads per process, and their races gave one of two partitions of
the same mesh at random (then, through the GAMG aggregates, 13 or 12 Newton steps
for lev 3 d1/L1 on 2 ranks). :func:`contactqvi.meshes.cell_partitioner` runs it
with one thread. Everything else (assembly, GAMG set-up, reductions) is
deterministic for a fixed partition; these tests repeat a case in one process.
"""

from __future__ import annotations

import os

from mpi4py import MPI

import numpy as np

from dolfinx import fem, graph
from dolfinx import mesh as dmesh

from contactqvi import meshes, tables
from contactqvi.contact import LoadStep, build_contact_problem, solve_load_path
from contactqvi.laws import Coulomb
from contactqvi.problems import coulomb as data


def _owned_cells(msh: dmesh.Mesh) -> list[np.ndarray]:
    """Original (input) indices of the cells each rank owns, gathered on every rank."""
    n_cells = msh.topology.index_map(3).size_local
    return MPI.COMM_WORLD.allgather(np.sort(np.asarray(msh.topology.original_cell_index[:n_cells])))


def test_same_partition_every_time():
    environment = os.environ.get("SCOTCH_PTHREAD_NUMBER")
    first = _owned_cells(meshes.create_contact_body(MPI.COMM_WORLD, 3, data.gap_function("d1"))[0])
    for _ in range(5):
        again = _owned_cells(meshes.create_contact_body(MPI.COMM_WORLD, 3, data.gap_function("d1"))[0])
        assert all(np.array_equal(a, b) for a, b in zip(first, again))
    assert os.environ.get("SCOTCH_PTHREAD_NUMBER") == environment  # set only while partitioning

    # The partition of a single-threaded PT-SCOTCH, run with the variable set around the call.
    sizes = meshes.contact_body_sizes(3)
    partitioner = None
    if MPI.COMM_WORLD.size > 1:
        partitioner = dmesh.create_cell_partitioner(graph.partitioner_scotch(0.025, 0), dmesh.GhostMode.none)
    os.environ["SCOTCH_PTHREAD_NUMBER"] = "1"
    try:
        box = dmesh.create_box(MPI.COMM_WORLD, [np.zeros(3), np.array([2.0, 1.0, 1.0])],
                               [sizes["nx1"], sizes["nx2"], sizes["nx3"]], dmesh.CellType.hexahedron,
                               partitioner=partitioner)
    finally:
        if environment is None:
            del os.environ["SCOTCH_PTHREAD_NUMBER"]
        else:
            os.environ["SCOTCH_PTHREAD_NUMBER"] = environment
    assert all(np.array_equal(a, b) for a, b in zip(first, _owned_cells(box)))


def test_ghost_mode_none_by_default():
    msh, _ = meshes.create_contact_body(MPI.COMM_WORLD, 1, data.gap_function("d1"))
    assert msh.topology.index_map(3).num_ghosts == 0


def _solve(lev: int, case: str) -> tuple[int, int, list[float], np.ndarray | None]:
    geometry, load = case.split("/")
    msh, tags = meshes.create_contact_body(MPI.COMM_WORLD, lev, data.gap_function(geometry))
    with build_contact_problem(msh, tags, data.YOUNG, data.POISSON, data.tractions(load), Coulomb(data.FRICTION)) as problem:
        u = problem.A.createVecRight()
        (result,) = solve_load_path(problem, [LoadStep()], u, prefix="determinism_")  # default: GMRES + GAMG
        assert result.converged
        displacement = problem.physical_displacement(u, fem.Function(problem.V))
        _, values = tables.gather_vertex_values(displacement)
        u.destroy()
    return result.iterations, result.inner_iterations, [h["residual"] for h in result.history], values


def test_same_counts_and_solution_twice():
    """lev 3 d1/L1 (the case that varied) twice in one process: identical to the last bit."""
    first = _solve(3, "d1/L1")
    second = _solve(3, "d1/L1")
    assert first[:3] == second[:3]
    if MPI.COMM_WORLD.rank == 0:
        assert np.array_equal(first[3], second[3])
