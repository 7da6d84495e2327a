"""VTX and XDMF files written on N ranks hold the points, cells and integrals of a serial run.

The box (0,2)x(0,1)x(0,1) in 4 x 2 x 2 hexahedra; serial values by hand: 45
points, 16 cells, volume 2, and for f = x + 2y + 3z the integral 2 + 2 + 3 = 7.
DOLFINx 0.9's own VTXWriter repeats ghost points and cells on 2 ranks (the
reason for :func:`contactqvi.io.write_vtx`); both ghost modes are written here.
"""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest

from dolfinx import fem
from dolfinx import mesh as dmesh

from contactqvi import io, meshes

N_POINTS, N_CELLS, VOLUME, INTEGRAL = 45, 16, 2.0, 7.0


def _fields(ghost_mode: dmesh.GhostMode) -> tuple[fem.Function, fem.Function, fem.Function]:
    msh = dmesh.create_box(
        MPI.COMM_WORLD, [np.zeros(3), np.array([2.0, 1.0, 1.0])], [4, 2, 2], dmesh.CellType.hexahedron,
        partitioner=meshes.cell_partitioner(MPI.COMM_WORLD, ghost_mode),
    )
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


def _check(points: np.ndarray, cells: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Counts, volume and the integral of f (trilinear, exact for linear f on boxes)."""
    assert points.shape == (N_POINTS, 3) and cells.shape == (N_CELLS, 8)
    assert len(np.unique(np.round(points, 12), axis=0)) == N_POINTS
    volumes = _hex_volumes(points, cells)
    assert volumes.sum() == pytest.approx(VOLUME, rel=1e-14)
    assert volumes @ f[cells].mean(axis=1) == pytest.approx(INTEGRAL, rel=1e-14)
    return volumes


@pytest.mark.parametrize("ghost_mode", [dmesh.GhostMode.none, dmesh.GhostMode.shared_facet])
def test_vtx_as_serial(ghost_mode, mpi_tmp_path):
    f, v, rank = _fields(ghost_mode)
    io.write_vtx(mpi_tmp_path / "fields.bp", [f, v, rank])
    if MPI.COMM_WORLD.rank == 0:
        data = io.read_vtx(mpi_tmp_path / "fields.bp")
        assert data.cell_type == 72  # VTK_LAGRANGE_HEXAHEDRON of degree 1, as DOLFINx names it
        volumes = _check(data.points, data.cells, data.point_data["f"])
        assert np.allclose(data.point_data["v [m]"], data.points, rtol=0, atol=1e-15)
        counts = np.bincount(data.cell_data["rank"].astype(int))[1:]
        assert len(counts) == MPI.COMM_WORLD.size and counts.sum() == N_CELLS  # every cell once, from its owner
        assert volumes @ data.cell_data["rank"] >= VOLUME


@pytest.mark.parametrize("ghost_mode", [dmesh.GhostMode.none, dmesh.GhostMode.shared_facet])
def test_xdmf_as_serial(ghost_mode, mpi_tmp_path):
    import meshio

    f, v, rank = _fields(ghost_mode)
    io.write_xdmf(mpi_tmp_path / "fields.xdmf", f.function_space.mesh, [f, v, rank])
    if MPI.COMM_WORLD.rank == 0:
        points, fields = io.read_xdmf_point_data(mpi_tmp_path / "fields.xdmf")
        with meshio.xdmf.TimeSeriesReader(str(mpi_tmp_path / "fields.xdmf")) as reader:
            _, blocks = reader.read_points_cells()
        (block,) = blocks
        assert block.type == "hexahedron"  # VTK vertex order, as DOLFINx writes XDMF
        _check(points, block.data, fields["f"])
        assert np.allclose(fields["v [m]"], points, rtol=0, atol=1e-15)


def test_dolfinx_vtx_repeats_ghosts(mpi_tmp_path):
    """Why write_vtx gathers: DOLFINx's VTXWriter on a ghosted mesh writes ghost cells per rank."""
    from dolfinx.io import VTXWriter

    f, _, _ = _fields(dmesh.GhostMode.shared_facet)
    with VTXWriter(MPI.COMM_WORLD, str(mpi_tmp_path / "native.bp"), [f], engine="BP4") as writer:
        writer.write(0.0)
    MPI.COMM_WORLD.Barrier()
    if MPI.COMM_WORLD.rank == 0:
        data = io.read_vtx(mpi_tmp_path / "native.bp")
        if MPI.COMM_WORLD.size == 1:
            assert data.cells.shape == (N_CELLS, 8)
        else:
            assert len(data.cells) > N_CELLS and len(data.points) > N_POINTS


def test_vtx_time_steps(mpi_tmp_path):
    """A VTXDatasetWriter series: one step per write, read back by step."""
    f, _, _ = _fields(dmesh.GhostMode.none)
    msh = f.function_space.mesh
    with io.VTXDatasetWriter(msh.comm, mpi_tmp_path / "series.bp") as writer:
        for step in range(3):
            f.x.array[:] = step
            writer.write(io.gather_dataset(msh, {"f": f}), t=0.5 * step)
    if msh.comm.rank == 0:
        for step in range(3):
            data = io.read_vtx(mpi_tmp_path / "series.bp", step=step)
            assert data.points.shape == (N_POINTS, 3) and np.all(data.point_data["f"] == step)
    assert not list(mpi_tmp_path.glob(".*partial*"))
