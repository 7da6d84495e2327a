"""Coulomb output on the contact surface (``contact_surface.xdmf``), read back with meshio."""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest

from contactqvi import io, meshes
from contactqvi.contact import SCDNewtonSolver, State, build_contact_problem
from contactqvi.contact.postprocess import contact_fields
from contactqvi.problems import coulomb as data

LEV = 3
FIELDS = {"contact_state", "contact_pressure", "friction_traction", "slip", "gap", "nodal_area"}


@pytest.fixture(scope="module")
def solution():
    """Converged d1/L1 problem at lev 3 (exact inner solves), u and result."""
    msh, tags = meshes.create_contact_body(MPI.COMM_WORLD, LEV, data.gap_function("d1"))
    problem = build_contact_problem(msh, tags, data.YOUNG, data.POISSON, data.tractions("L1"), data.FRICTION)
    u = problem.A.createVecRight()
    result = SCDNewtonSolver(problem, {"pc": "lu"}, prefix="surface_").solve(u)
    assert result.converged
    return problem, u, result


def _rows(points: np.ndarray, queries: np.ndarray) -> np.ndarray:
    """Row of ``points`` with the coordinates of each query point (-1 if none)."""
    keys = np.round(np.vstack([points, queries]), 12)
    _, ids = np.unique(keys, axis=0, return_inverse=True)
    ids = ids.ravel()
    lookup = np.full(ids.max() + 1, -1)
    lookup[ids[: len(points)]] = np.arange(len(points))
    return lookup[ids[len(points) :]]


def test_contact_surface_file(solution, mpi_tmp_path):
    """The surface fields read back with meshio hold each node's state, forces and slip."""
    problem, u, result = solution
    comm = problem.comm
    surface = contact_fields(problem, u, result)
    io.write_xdmf(mpi_tmp_path / "contact_surface.xdmf", surface.mesh, surface.functions)
    points, fields = io.read_xdmf_point_data(mpi_tmp_path / "contact_surface.xdmf")
    assert set(fields) == FIELDS
    state, pressure, area = fields["contact_state"], fields["contact_pressure"], fields["nodal_area"]
    traction, slip, gap = fields["friction_traction"], fields["slip"], fields["gap"]

    # Vertices: the p contact nodes and the nx2 + 1 nodes of the clamped edge x1 = 0.
    sizes = meshes.contact_body_sizes(LEV)
    assert problem.n_contact == sizes["p"]
    assert len(points) == problem.n_contact + sizes["nx2"] + 1
    edge = np.isclose(points[:, 0], 0.0)
    assert np.count_nonzero(edge) == sizes["nx2"] + 1
    assert np.all(state[edge] == State.NO_CONTACT) and np.all(pressure[edge] == 0.0)
    assert np.all(traction[edge] == 0.0) and np.all(slip[edge] == 0.0)
    assert np.allclose(gap[edge], points[edge, 2], rtol=0, atol=1e-14)  # clamped: the initial gap

    # Total normal force.
    total = comm.allreduce(float(result.normal_force.sum()), op=MPI.SUM)
    assert abs(np.sum(pressure * area) - total) <= 1e-10 * total

    # States: values of the State enum, as many per state as the solver counted.
    assert set(np.unique(state)) <= {float(s) for s in State}
    counts = comm.allreduce(np.bincount(result.states.astype(np.int64), minlength=len(State)), op=MPI.SUM)
    assert np.array_equal(np.bincount(state[~edge].astype(np.int64), minlength=len(State)), counts)
    stick = np.isin(state, (State.STICKING, State.WEAK_STICKING))
    assert np.any(stick) and np.all(np.linalg.norm(slip[stick], axis=1) <= 1e-10 * np.abs(slip).max())
    assert np.all(traction[:, 2] == 0.0) and np.all(slip[:, 2] == 0.0)  # tangential vectors
    cone = np.linalg.norm(traction, axis=1) - problem.law.friction * pressure
    assert np.all(cone <= 1e-8 * np.abs(pressure).max())

    # Node by node: the owned contact nodes of every rank, found by coordinates.
    x = problem.V.tabulate_dof_coordinates()[problem.contact_blk]
    rows = _rows(points, x)
    assert np.all(rows >= 0)
    assert np.array_equal(state[rows], result.states)
    assert np.allclose(pressure[rows], result.normal_force / problem.contact_area, rtol=1e-12, atol=0)
    assert np.allclose(traction[rows, :2], result.friction_force / problem.contact_area[:, None], rtol=1e-12, atol=0)
    u_contact = u.array.reshape(-1, 3)[problem.contact_blk]  # slip u~12 = u12, gap = u3 (shifted)
    assert np.allclose(slip[rows, :2], u_contact[:, :2], rtol=0, atol=1e-14)
    assert np.allclose(gap[rows], u_contact[:, 2], rtol=0, atol=1e-14)

    # In memory, ghost entries (under mpirun) hold their owner's values.
    for f in surface.functions:
        local = f.x.array.reshape(len(f.function_space.tabulate_dof_coordinates()), -1)
        rows = _rows(points, f.function_space.tabulate_dof_coordinates())
        assert np.all(rows >= 0) and np.array_equal(local, fields[f.name][rows].reshape(local.shape))


def test_demo_writes_contact_surface(mpi_tmp_path, load_demo):
    out = mpi_tmp_path / "run"
    assert load_demo("coulomb3d").main(["--lev", "1", "--output", str(out), "--no-plot"]) == 0
    points, fields = io.read_xdmf_point_data(out / "contact_surface.xdmf")
    sizes = meshes.contact_body_sizes(1)
    assert set(fields) == FIELDS and len(points) == sizes["p"] + sizes["nx2"] + 1
    _, volume = io.read_xdmf_point_data(out / "contact.xdmf")
    assert set(volume) == {"displacement"}
    assert not (out / "contact_states.png").exists()
