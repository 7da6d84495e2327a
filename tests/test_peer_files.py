"""The files the peer benchmarks share (``benchmarks/peers/common.py``, ``export.py``): the
reader of cases and meshes that GetFEM and Kratos use sees the bodies, groups and node order
that contactqvi sees, so that their results compare row by row with ours.

Neither peer is needed: ``common`` imports neither, and the exported files are read here by
both ``common`` and contactqvi.
"""

from __future__ import annotations

import pathlib
import sys

from mpi4py import MPI

import numpy as np
import pytest

from dolfinx import fem

from contactqvi import tables
from contactqvi.case import load_case
from contactqvi.meshes import read_gmsh

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks" / "peers"))
import common  # noqa: E402
import export  # noqa: E402


@pytest.fixture(scope="module")
def patch(tmp_path_factory) -> pathlib.Path:
    """cases/patch_test.toml with its mesh exported as gmsh 2.2 ASCII (the peers' input)."""
    out = tmp_path_factory.mktemp("peers") if MPI.COMM_WORLD.rank == 0 else None
    out = MPI.COMM_WORLD.bcast(out, root=0)
    if MPI.COMM_WORLD.rank == 0:
        export.export_case(out, ROOT / "cases" / "patch_test.toml", "patch")
    MPI.COMM_WORLD.Barrier()
    return out / "patch.toml"


def test_bodies_case_reads_as_contactqvi_reads_it(patch):
    ours = load_case(patch)
    peers = common.load_bodies_case(patch)
    assert [b.name for b in peers.bodies] == [b.name for b in ours.bodies]
    for theirs, mine in zip(peers.bodies, ours.bodies):
        assert (theirs.young, theirs.poisson) == (mine.material.young, mine.material.poisson)
        assert theirs.displacement == {k: d.components() for k, d in mine.boundary.displacement.items()}
        assert {k: tuple(v) for k, v in theirs.traction.items()} == dict(mine.boundary.traction)
    (pair,) = peers.pairs
    assert ".".join(pair.slave) == ours.contacts[0].slave and ".".join(pair.master) == ours.contacts[0].master
    assert pair.friction == pytest.approx(0.3)
    with pytest.raises(ValueError, match="load_bodies_case"):
        common.load_case(patch)


def test_mesh_splits_into_bodies_with_their_own_nodes(patch):
    mesh = common.read_msh(common.load_bodies_case(patch).mesh)
    lower, lower_nodes = mesh.body("lower")
    upper, upper_nodes = mesh.body("upper")
    assert len(np.intersect1d(lower_nodes, upper_nodes)) == 0
    assert len(lower_nodes) + len(upper_nodes) == len(mesh.points)
    assert len(lower.cells) + len(upper.cells) == len(mesh.cells)
    # The interface group spans both blocks; each body keeps its own faces of it, at z = 1,
    # and the two meshes meet there at some points only (non-matching).
    for body in (lower, upper):
        assert np.allclose(body.points[body.faces["interface"], 2], 1.0)
    assert len(lower.faces["interface"]) + len(upper.faces["interface"]) == len(mesh.faces["interface"])
    assert "top" in upper.faces and "top" not in lower.faces and "bottom" not in upper.faces
    lower_points = set(map(tuple, lower.points[np.unique(lower.faces["interface"])]))
    upper_points = set(map(tuple, upper.points[np.unique(upper.faces["interface"])]))
    assert 0 < len(lower_points & upper_points) < len(upper_points)
    with pytest.raises(KeyError, match="physical volume 'middle'"):
        mesh.body("middle")


def test_peer_node_order_is_ours(patch):
    """common.sort_nodes orders the file's nodes as contactqvi.tables.gather_vertex_values orders
    the dofs of a P1 field, nodes at one point of two bodies included (by file order)."""
    comm = MPI.COMM_WORLD
    mesh = common.read_msh(common.load_bodies_case(patch).mesh)
    msh, _, _ = read_gmsh(patch.parent / "patch_blocks.msh", comm)
    V = fem.functionspace(msh, ("Lagrange", 1, (3,)))
    u = fem.Function(V)
    # u = (index of the node in the file, x, y) at each node: the file index through the
    # geometry's input indices, which read_gmsh takes from the file's node order.
    node = np.empty(V.dofmap.index_map.size_local + V.dofmap.index_map.num_ghosts, dtype=np.int64)
    node[V.dofmap.list.ravel()] = msh.geometry.dofmap.ravel()
    index = np.asarray(msh.geometry.input_global_indices, dtype=np.int64)[node]
    x = V.tabulate_dof_coordinates()
    values = u.x.array.reshape(-1, 3)
    values[:, 0], values[:, 1:] = index, x[:, :2]
    x_ours, u_ours = tables.gather_vertex_values(u)
    if comm.rank == 0:
        order = common.sort_nodes(mesh.points)
        assert np.allclose(x_ours, mesh.points[order], rtol=0, atol=1e-14)
        assert np.array_equal(u_ours[:, 0], order)  # ties (37 shared interface points) in file order
        assert np.allclose(u_ours[:, 1:], mesh.points[order, :2], rtol=0, atol=1e-14)
