"""Foundation: meshes, elasticity, parallel agreement, output, input validation."""

from __future__ import annotations

import json
import pathlib

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import pytest

import dolfinx.fem.petsc
from dolfinx import fem

from contactqvi import meshes, paraview, tables
from contactqvi.elasticity import elasticity_forms, lame_parameters, rigid_motions_nullspace
from contactqvi.laws import Coulomb
from contactqvi.linalg import create_ksp, power_iteration
from contactqvi.parameters import ParameterError
from contactqvi.problems.coulomb import PAPER_TABLE2, gap_function

MESHES = pathlib.Path(__file__).resolve().parent.parent / "meshes"

# Seed 000, Table 2: lev -> (p, n)
TABLE2_SIZES = {3: (84, 1764), 4: (144, 3888), 5: (299, 11661), 6: (544, 27744), 7: (1104, 79488),
                8: (2112, 209088), 9: (4277, 603057), 10: (8320, 1622400)}


@pytest.mark.one_rank(reason="a closed formula of the mesh sizes")
@pytest.mark.parametrize("lev", sorted(TABLE2_SIZES))
def test_table2_sizes_formula(lev):
    sizes = meshes.contact_body_sizes(lev)
    assert (sizes["p"], sizes["n"]) == TABLE2_SIZES[lev]
    assert set(PAPER_TABLE2) <= set(TABLE2_SIZES)


@pytest.mark.parametrize("lev", [3, 4, 5])
@pytest.mark.parametrize("geometry", ["d1", "d3"])
def test_contact_body_mesh_counts(lev, geometry):
    """Built meshes have p contact nodes and n free dofs of Table 2, and the bottom at x3 = d."""
    from contactqvi.contact import build_contact_problem

    comm = MPI.COMM_WORLD
    msh, tags = meshes.create_contact_body(comm, lev, gap_function(geometry))
    problem = build_contact_problem(msh, tags, 70e9, 0.3, {"top": (0, 0, -1e9)}, Coulomb(0.2))
    assert (problem.n_contact, problem.n_free) == TABLE2_SIZES[lev]
    x = problem.V.tabulate_dof_coordinates()[problem.contact_blk]
    assert np.allclose(x[:, 2], gap_function(geometry)(x[:, 0], x[:, 1]), atol=1e-14)
    assert np.all(x[:, 0] > 0)
    area = comm.allreduce(problem.contact_area.sum(), op=MPI.SUM)
    assert 1.9 < area < 2.0  # 2 m^2 minus the half-row of nodes on x1 = 0


@pytest.mark.parametrize("geometry", ["d1", "d2"])
def test_contact_body_facet_tags(geometry):
    """Each face of the box is tagged whole (global facet counts), on the curved bottom too,
    without the vertex-to-cell connectivity that locate_entities_boundary would leave behind."""
    comm = MPI.COMM_WORLD
    sizes = meshes.contact_body_sizes(4)
    nx1, nx2, nx3 = sizes["nx1"], sizes["nx2"], sizes["nx3"]
    msh, tags = meshes.create_contact_body(comm, 4, gap_function(geometry))
    expected = {"dirichlet": nx2 * nx3, "right": nx2 * nx3, "top": nx1 * nx2, "contact": nx1 * nx2,
                "front": nx1 * nx3, "back": nx1 * nx3}
    counts = {name: comm.allreduce(len(meshes.boundary_facets(tags, name)), op=MPI.SUM) for name in expected}
    assert counts == expected
    with pytest.raises(RuntimeError):
        msh.topology.connectivity(0, 3)


def _uniaxial_bar(comm, lev):
    """Box (2 x 1 x 1) pulled by a traction s on x1 = 2, exact u on x1 = 0: uniaxial stress."""
    young, poisson, s = 70e9, 0.3, 1e8
    msh, tags = meshes.create_contact_body(comm, lev, lambda x1, x2: 0.0 * x1)
    V = fem.functionspace(msh, ("Lagrange", 1, (3,)))
    a, L = elasticity_forms(V, young, poisson, tags, {"right": (s, 0.0, 0.0)})
    exact = fem.Function(V)
    exact.interpolate(lambda x: np.vstack([s / young * x[0], -poisson * s / young * x[1], -poisson * s / young * x[2]]))
    fdim = msh.topology.dim - 1
    dofs = fem.locate_dofs_topological(V, fdim, meshes.boundary_facets(tags, "dirichlet"))
    bc = fem.dirichletbc(exact, dofs)
    A = dolfinx.fem.petsc.assemble_matrix(a, bcs=[bc])
    A.assemble()
    A.setNearNullSpace(rigid_motions_nullspace(V))
    b = dolfinx.fem.petsc.assemble_vector(L)
    dolfinx.fem.petsc.apply_lifting(b, [a], bcs=[[bc]])
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    dolfinx.fem.petsc.set_bc(b, [bc])
    ksp = create_ksp(comm, "test_bar_", {"ksp_type": "cg", "pc_type": "gamg", "ksp_rtol": 1e-13}, A)
    uh = fem.Function(V, name="displacement")
    ksp.solve(b, uh.x.petsc_vec)
    uh.x.scatter_forward()
    assert ksp.getConvergedReason() > 0
    error = uh.x.petsc_vec.copy()
    error.axpy(-1.0, exact.x.petsc_vec)
    return uh, error.norm() / exact.x.petsc_vec.norm(), ksp.getIterationNumber()


def test_uniaxial_bar_exact():
    """Q1 reproduces the linear uniaxial-stress field; GAMG with rigid modes converges quickly."""
    uh, rel_error, iterations = _uniaxial_bar(MPI.COMM_WORLD, 3)
    print(f"uniaxial bar: relative error {rel_error:.2e}, {iterations} CG+GAMG iterations")
    assert rel_error < 1e-10
    assert iterations < 40


def test_elasticity_serial_equals_parallel():
    """The same solve on COMM_WORLD and on each rank alone agree to 1e-10."""
    u_world, _, _ = _uniaxial_bar(MPI.COMM_WORLD, 2)
    u_self, _, _ = _uniaxial_bar(MPI.COMM_SELF, 2)
    x_w, v_w = tables.gather_vertex_values(u_world)
    if MPI.COMM_WORLD.rank == 0:
        x_s, v_s = tables.gather_vertex_values(u_self)
        assert np.allclose(x_w, x_s, atol=1e-14)
        assert np.abs(v_w - v_s).max() <= 1e-10 * np.abs(v_s).max()


def test_power_iteration_bounds():
    """Power iteration approaches lambda_max from below on a diagonal operator."""
    comm = MPI.COMM_WORLD
    A = PETSc.Mat().createAIJ(((10, None), (10, None)), nnz=(1, 0), comm=comm)
    start, end = A.getOwnershipRange()
    for i in range(start, end):
        A.setValue(i, i, float(i + 1))
    A.assemble()
    x = A.createVecRight()
    x.set(1.0)
    estimates = [power_iteration(A, x, k) for k in (1, 5, 200)]
    total = comm.allreduce(end - start)
    assert estimates[0] < estimates[1] < estimates[2] <= total + 1e-12
    assert estimates[2] == pytest.approx(total, rel=1e-3)


def test_gmsh_arch_block():
    """The shipped non-cuboid body reads with its physical groups as named facet tags."""
    msh, tags, _ = meshes.read_gmsh(MESHES / "arch_block.geo", MPI.COMM_WORLD)
    assert set(tags.names) == {"dirichlet", "right", "top", "contact"}
    comm = msh.comm
    for name in tags.names:
        assert comm.allreduce(len(meshes.boundary_facets(tags, name)), op=MPI.SUM) > 0
    z_min = comm.allreduce(msh.geometry.x[:, 2].min(), op=MPI.MIN)
    assert z_min == pytest.approx(0.0, abs=1e-12)


def test_output_round_trip(mpi_tmp_path):
    comm = MPI.COMM_WORLD
    uh, _, _ = _uniaxial_bar(comm, 1)
    tables.write_summary(comm, mpi_tmp_path / "summary.json", {"status": "converged", "x": np.arange(3)})
    tables.write_solution_npz(mpi_tmp_path / "solution.npz", uh)
    paraview.write_xdmf(mpi_tmp_path / "u.xdmf", uh.function_space.mesh, [uh])
    paraview.write_vtx(mpi_tmp_path / "u.bp", [uh])
    n_nodes = uh.function_space.dofmap.index_map.size_global
    _, u_ref = tables.gather_vertex_values(uh)
    if comm.rank == 0:
        assert json.loads((mpi_tmp_path / "summary.json").read_text()) == {"status": "converged", "x": [0, 1, 2]}
        data = np.load(mpi_tmp_path / "solution.npz")
        assert data["x"].shape == (n_nodes, 3) and data["u"].shape == (n_nodes, 3)
        assert np.array_equal(data["u"], u_ref)
        assert (mpi_tmp_path / "u.h5").is_file() and (mpi_tmp_path / "u.bp").is_dir()
        assert not list(mpi_tmp_path.glob(".*partial*"))


@pytest.mark.serial
def test_paraview_files_readable(mpi_tmp_path):
    """XDMF (meshio) and VTX/BP4 (ADIOS2) files open with third-party readers.

    Serial only: on N ranks a VTX variable has one block per rank (tests/test_output_parallel.py).
    """
    import adios2
    import meshio

    uh, _, _ = _uniaxial_bar(MPI.COMM_WORLD, 1)
    paraview.write_xdmf(mpi_tmp_path / "u.xdmf", uh.function_space.mesh, [uh])
    paraview.write_vtx(mpi_tmp_path / "u.bp", [uh])
    n_nodes = uh.function_space.dofmap.index_map.size_global
    reader = meshio.xdmf.TimeSeriesReader(str(mpi_tmp_path / "u.xdmf"))
    points, _ = reader.read_points_cells()
    _, point_data, _ = reader.read_data(0)
    assert points.shape == (n_nodes, 3) and point_data["displacement"].shape == (n_nodes, 3)
    with adios2.FileReader(str(mpi_tmp_path / "u.bp")) as bp:
        assert bp.read("displacement").shape == (n_nodes, 3)


def test_atomic_path_removes_partial_file_on_error(mpi_tmp_path):
    comm = MPI.COMM_WORLD
    with pytest.raises(RuntimeError):
        with tables.atomic_path(comm, mpi_tmp_path / "result.json") as tmp:
            if comm.rank == 0:
                tmp.write_text("{")
            raise RuntimeError("solver failed")
    assert not (mpi_tmp_path / "result.json").exists()
    assert not list(mpi_tmp_path.iterdir())


def test_write_table_makes_its_directory(mpi_tmp_path):
    """A benchmark's ``--output`` that does not exist yet is made, not a failure after the run."""
    stem = mpi_tmp_path / "new" / "deeper" / "table"
    tables.write_table(MPI.COMM_WORLD, stem, {"rows": [1, 2]}, "| a |\n", echo=False)
    assert json.loads(stem.with_suffix(".json").read_text()) == {"rows": [1, 2]}
    assert stem.with_suffix(".md").read_text() == "| a |\n"


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: lame_parameters(-1.0, 0.3), "young"),
        (lambda: lame_parameters(70e9, 0.5), "poisson"),
        (lambda: meshes.contact_body_sizes(-1), "lev"),
        (lambda: meshes.create_contact_body(MPI.COMM_WORLD, 1, lambda x1, x2: x1 - 1.0), "gap"),
        (lambda: meshes.tag_of(meshes.create_unit_square(MPI.COMM_WORLD, 2)[1], "contact"), "boundary"),
        (lambda: meshes.read_gmsh(MESHES / "no_such_mesh.msh", MPI.COMM_WORLD), "mesh"),
        (lambda: meshes.create_unit_square(MPI.COMM_WORLD, 2, "hexagon"), "cell_type"),
    ],
)
def test_bad_input_names_parameter(call, name):
    with pytest.raises(ParameterError) as info:
        call()
    assert info.value.name == name
    assert str(info.value).startswith(f"{name}: ")
