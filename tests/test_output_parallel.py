"""VTX and XDMF files written in parallel hold the cells and integrals of a serial run.

The box (0,2)x(0,1)x(0,1) in 4 x 2 x 2 hexahedra; serial values by hand: 45
points, 16 cells, volume 2, and for f = x + 2y + 3z the integral 2 + 2 + 3 = 7.
Each rank writes its own cells (one ADIOS2 block); a point shared by two blocks
is written by both and flagged as a duplicate in all but its owner's. DOLFINx
0.9's own VTXWriter repeats ghost cells (the reason for
:func:`contactqvi.paraview.write_vtx`); both ghost modes are written here.
"""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest

from dolfinx import fem
from dolfinx import mesh as dmesh

from contactqvi import meshes
from contactqvi.paraview import MeshPiece, VTXDatasetWriter, write_vtx, write_xdmf
from output_files import read_vtx, read_xdmf_point_data

N_POINTS, N_CELLS, VOLUME, INTEGRAL = 45, 16, 2.0, 7.0


def _box(ghost_mode: dmesh.GhostMode, comm: MPI.Comm = MPI.COMM_WORLD) -> dmesh.Mesh:
    return dmesh.create_box(
        comm, [np.zeros(3), np.array([2.0, 1.0, 1.0])], [4, 2, 2], dmesh.CellType.hexahedron,
        partitioner=meshes.cell_partitioner(comm, ghost_mode),
    )


def _fields(msh: dmesh.Mesh) -> tuple[fem.Function, fem.Function, fem.Function]:
    f = fem.Function(fem.functionspace(msh, ("Lagrange", 1)), name="f")
    f.interpolate(lambda x: x[0] + 2.0 * x[1] + 3.0 * x[2])
    v = fem.Function(fem.functionspace(msh, ("Lagrange", 1, (3,))), name="v [m]")
    v.interpolate(lambda x: x)
    rank = fem.Function(fem.functionspace(msh, ("DG", 0)), name="rank")
    rank.x.array[:] = msh.comm.rank + 1.0  # differs between ranks: each cell's owner
    return f, v, rank


def _hex_volumes(points: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Volumes of box-shaped hexahedra in VTK order."""
    p = points[cells]
    return np.abs(np.linalg.det(np.stack([p[:, 1] - p[:, 0], p[:, 3] - p[:, 0], p[:, 4] - p[:, 0]], axis=1)))


def _check(points: np.ndarray, cells: np.ndarray, f: np.ndarray, duplicate: np.ndarray | None = None) -> np.ndarray:
    """Counts, volume and the integral of f (trilinear, exact for linear f on boxes)."""
    assert cells.shape == (N_CELLS, 8)
    assert len(np.unique(np.round(points, 12), axis=0)) == N_POINTS
    if duplicate is not None:  # every point once outside the duplicates
        assert np.count_nonzero(~duplicate) == N_POINTS
        assert len(np.unique(np.round(points[~duplicate], 12), axis=0)) == N_POINTS
    volumes = _hex_volumes(points, cells)
    assert volumes.sum() == pytest.approx(VOLUME, rel=1e-14)
    assert volumes @ f[cells].mean(axis=1) == pytest.approx(INTEGRAL, rel=1e-14)
    return volumes


@pytest.mark.parametrize("ghost_mode", [dmesh.GhostMode.none, dmesh.GhostMode.shared_facet])
def test_vtx_parallel_as_serial(ghost_mode, mpi_tmp_path):
    comm = MPI.COMM_WORLD
    f, v, rank = _fields(_box(ghost_mode))
    write_vtx(mpi_tmp_path / "fields.bp", [f, v, rank])
    if comm.rank == 0:
        data = read_vtx(mpi_tmp_path / "fields.bp")
        assert data.cell_type == 72  # VTK_LAGRANGE_HEXAHEDRON of degree 1, as DOLFINx names it
        volumes = _check(data.points, data.cells, data.point_data["f"], data.duplicate)
        assert np.allclose(data.point_data["v [m]"], data.points, rtol=0, atol=1e-15)  # copies agree too
        counts = np.bincount(data.cell_data["rank"].astype(int))[1:]
        assert len(counts) == comm.size and counts.sum() == N_CELLS  # every cell once, from its owner
        assert volumes @ data.cell_data["rank"] >= VOLUME
        assert (len(data.points) > N_POINTS) == (comm.size > 1)  # interface points in both pieces


@pytest.mark.parametrize("ghost_mode", [dmesh.GhostMode.none, dmesh.GhostMode.shared_facet])
def test_xdmf_as_serial(ghost_mode, mpi_tmp_path):
    import meshio

    f, v, rank = _fields(_box(ghost_mode))
    write_xdmf(mpi_tmp_path / "fields.xdmf", f.function_space.mesh, [f, v, rank])
    if MPI.COMM_WORLD.rank == 0:
        points, fields = read_xdmf_point_data(mpi_tmp_path / "fields.xdmf")
        with meshio.xdmf.TimeSeriesReader(str(mpi_tmp_path / "fields.xdmf")) as reader:
            _, blocks = reader.read_points_cells()
        (block,) = blocks
        assert block.type == "hexahedron"  # VTK vertex order, as DOLFINx writes XDMF
        assert points.shape == (N_POINTS, 3)
        _check(points, block.data, fields["f"])
        assert np.allclose(fields["v [m]"], points, rtol=0, atol=1e-15)


def test_ranks_without_cells(mpi_tmp_path):
    """A mesh whose cells all live on the last rank: the other ranks write no block, the file is whole."""
    comm = MPI.COMM_WORLD
    msh = _box(dmesh.GhostMode.none)
    n_cells = msh.topology.index_map(3).size_local
    mine = np.arange(n_cells if comm.rank == comm.size - 1 else 0, dtype=np.int32)
    part = dmesh.create_submesh(msh, 3, mine)[0]
    n_owned = comm.allgather(part.topology.index_map(3).size_local)
    assert n_owned[-1] > 0 and sum(n_owned[:-1]) == 0
    piece = MeshPiece(part)
    assert piece.cells.shape == (n_owned[comm.rank], 8)
    f, v, rank = _fields(part)
    write_vtx(mpi_tmp_path / "part.bp", [f, v, rank])
    write_xdmf(mpi_tmp_path / "part.xdmf", part, [f])
    if comm.rank == 0:
        data = read_vtx(mpi_tmp_path / "part.bp")
        assert len(data.cells) == n_owned[-1] and np.all(data.cell_data["rank"] == comm.size)
        assert not np.any(data.duplicate)  # one block: every point its own
        assert np.allclose(data.point_data["v [m]"], data.points, rtol=0, atol=1e-15)
        volumes = _hex_volumes(data.points, data.cells)
        assert volumes.sum() == pytest.approx(VOLUME * n_owned[-1] / N_CELLS, rel=1e-14)
        points, fields = read_xdmf_point_data(mpi_tmp_path / "part.xdmf")
        assert np.allclose(fields["f"], points @ [1.0, 2.0, 3.0], rtol=1e-14)


def test_dolfinx_vtx_repeats_ghosts(mpi_tmp_path):
    """Why write_vtx writes its own blocks: DOLFINx's VTXWriter on a ghosted mesh writes ghost cells per rank."""
    from dolfinx.io import VTXWriter

    f, _, _ = _fields(_box(dmesh.GhostMode.shared_facet))
    with VTXWriter(MPI.COMM_WORLD, str(mpi_tmp_path / "native.bp"), [f], engine="BP4") as writer:
        writer.write(0.0)
    MPI.COMM_WORLD.Barrier()
    if MPI.COMM_WORLD.rank == 0:
        data = read_vtx(mpi_tmp_path / "native.bp")
        if MPI.COMM_WORLD.size == 1:
            assert data.cells.shape == (N_CELLS, 8)
        else:
            assert len(data.cells) > N_CELLS


def test_vtx_time_steps(mpi_tmp_path):
    """A VTXDatasetWriter series: one step per write, read back by step."""
    f, _, _ = _fields(_box(dmesh.GhostMode.none))
    piece = MeshPiece(f.function_space.mesh)
    comm = MPI.COMM_WORLD
    with VTXDatasetWriter(comm, mpi_tmp_path / "series.bp") as writer:
        for step in range(3):
            f.x.array[:] = step
            writer.write(piece.dataset({"f": f}), t=0.5 * step)
    if comm.rank == 0:
        for step in range(3):
            data = read_vtx(mpi_tmp_path / "series.bp", step=step)
            assert np.count_nonzero(~data.duplicate) == N_POINTS and np.all(data.point_data["f"] == step)
    assert not list(mpi_tmp_path.glob(".*partial*"))


def test_vtx_arrays_must_agree(mpi_tmp_path):
    """A step whose arrays differ (on one rank of several: on rank 0 they do not) fails on every rank, no file."""
    comm = MPI.COMM_WORLD
    f, _, _ = _fields(_box(dmesh.GhostMode.none))
    piece = MeshPiece(f.function_space.mesh)
    name = "f" if comm.rank == 0 and comm.size > 1 else "g"
    with pytest.raises(ValueError, match="arrays"):
        with VTXDatasetWriter(comm, mpi_tmp_path / "bad.bp") as writer:
            writer.write(piece.dataset({"f": f}), t=0.0)
            writer.write(piece.dataset({name: f}), t=1.0)
    assert not (mpi_tmp_path / "bad.bp").exists() and not list(mpi_tmp_path.glob(".*partial*"))


def test_solution_npz_only_below_the_size_limit(mpi_tmp_path, monkeypatch):
    """solution.npz gathers the field on rank 0: skipped above GATHER_MAX_NODES unless forced."""
    from contactqvi import tables

    f, _, _ = _fields(_box(dmesh.GhostMode.none))
    monkeypatch.setattr(tables, "GATHER_MAX_NODES", N_POINTS - 1)
    assert not tables.write_solution_npz(mpi_tmp_path / "skipped.npz", f)
    assert tables.write_solution_npz(mpi_tmp_path / "forced.npz", f, force=True)
    monkeypatch.setattr(tables, "GATHER_MAX_NODES", N_POINTS)
    assert tables.write_solution_npz(mpi_tmp_path / "small.npz", f)
    if MPI.COMM_WORLD.rank == 0:
        assert not (mpi_tmp_path / "skipped.npz").exists()
        for name in ("forced.npz", "small.npz"):
            data = np.load(mpi_tmp_path / name)
            assert data["x"].shape == (N_POINTS, 3) and np.allclose(data["u"], data["x"] @ [1.0, 2.0, 3.0])
