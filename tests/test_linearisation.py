"""The derivatives of the mortar geometry (issue 45, item 2; :mod:`contactqvi.contact.linearisation`)
against central finite differences.

Pairs of distorted, warped facets (triangles and quadrilaterals in every combination) check
dD and dM of the segment integrals; the sphere pressed into the block of
``meshes/hertz_bodies_coarse.geo`` (tetrahedra) and ``hertz_bodies_hex_coarse.geo``
(hexahedra), both distorted by a smooth displacement field, check the nodal quantities
(L.1)-(L.3): the weighted separation, the nodal normal and the weighted gap of every coupled
slave node, the law's variables (13.1) (gap and objective slip in the node's frame), the
frames' turn of the slave forces and the master nodes' shares (L.4), for coordinates of slave
and master nodes. Central differences of step h have
an error of O(h^2) and of round-off / h; with h = 1e-6 of the facets' size both are near
1e-10 of the derivative, and the bound is the issue's 1e-6.
"""

from __future__ import annotations

import pathlib

from mpi4py import MPI

import numpy as np
import pytest

from dolfinx import fem
from dolfinx import mesh as dmesh

from contactqvi.contact.kinematics import (contact_variables, frame_turn, master_shares, pair_frame_derivatives,
                                          pair_frames, variable_derivatives)
from contactqvi.contact.linearisation import segment_jacobians
from contactqvi.contact.mortar import MortarCoupling, mortar_coupling
from contactqvi.contact.owners import owner_ranges, sum_to_owners
from contactqvi.contact.segments import segment_integrals
from contactqvi.meshes import boundary_facets, read_gmsh, split_by_body

ROOT = pathlib.Path(__file__).resolve().parent.parent
#: The issue's bound on the relative difference between a derivative and its central difference.
BOUND = 1e-6


def _facet(n: int, rng: np.random.Generator, z: float, warp: float) -> np.ndarray:
    """A distorted triangle or quadrilateral (tensor-product order) about the origin near the plane z."""
    corners = {3: [[-1.0, -1.0], [1.2, -0.9], [0.1, 1.1]], 4: [[-1.0, -1.0], [1.1, -0.9], [-0.9, 1.0], [1.0, 1.2]]}[n]
    x = np.column_stack([np.array(corners) + 0.2 * rng.standard_normal((n, 2)), z + warp * rng.standard_normal(n)])
    return x


@pytest.mark.one_rank(reason="segment integrals of given facets (numpy), no mesh")
@pytest.mark.parametrize("ns, nm", [(3, 3), (4, 4), (3, 4), (4, 3)])
def test_segment_integral_derivatives(ns, nm):
    """dD and dM of overlapping pairs of distorted facets (the quadrilaterals warped, the master
    0.3 off the slave's plane and turned) against central differences in each of the pair's
    3 (n_s + n_m) coordinates."""
    rng = np.random.default_rng(7)
    pairs = 6
    slave = np.stack([_facet(ns, rng, 0.0, 0.1 * (ns == 4)) for _ in range(pairs)])
    turn = np.array([[np.cos(0.4), -np.sin(0.4), 0.0], [np.sin(0.4), np.cos(0.4), 0.0], [0.0, 0.0, 1.0]])
    master = np.stack([_facet(nm, rng, -0.3, 0.1) @ turn.T + [0.3, 0.2, 0.0] for _ in range(pairs)])
    normal = np.cross(slave[:, -1] - slave[:, 0], slave[:, 2] - slave[:, 1])
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    D, M, dD, dM = segment_jacobians(slave, normal, master)
    reference = segment_integrals(slave, normal, master)
    assert np.abs(D - reference[0]).max() <= 1e-14 * np.abs(D).max()
    assert np.abs(M - reference[1]).max() <= 1e-14 * np.abs(M).max()
    assert (M.sum(axis=(1, 2)) > 0.1).all()  # every pair overlaps
    x = np.concatenate([slave, master], axis=1)
    h = 1e-6
    for v in range(ns + nm):
        for c in range(3):
            fd = []
            for sign in (1.0, -1.0):
                y = x.copy()
                y[:, v, c] += sign * h
                s = y[:, :ns]
                n = np.cross(s[:, -1] - s[:, 0], s[:, 2] - s[:, 1])
                n /= np.linalg.norm(n, axis=1)[:, None]
                n *= np.sign(np.einsum("ij,ij->i", n, normal))[:, None]
                fd.append(segment_integrals(s, n, y[:, ns:]))
            assert np.abs((fd[0][0] - fd[1][0]) / (2 * h) - dD[..., v, c]).max() <= BOUND * np.abs(dD).max()
            assert np.abs((fd[0][1] - fd[1][1]) / (2 * h) - dM[..., v, c]).max() <= BOUND * np.abs(dM).max()


def _distortion(x: np.ndarray, size: float) -> np.ndarray:
    """A smooth displacement (local nodes, 3): the upper body (z > 0) pushed 0.03 of ``size``
    down into the lower, and every node moved by 0.01 of ``size`` along waves."""
    k = 2.0 * np.pi / size
    u = 0.01 * size * np.column_stack([np.sin(k * x[:, 1] + 0.3), np.cos(k * x[:, 0]), np.sin(k * (x[:, 0] + x[:, 1]))])
    u[:, 2] -= 0.03 * size * (x[:, 2] > 1e-9 * size)
    return u


@pytest.mark.parametrize("edge", [False, True])
@pytest.mark.parametrize("projecting", [False, True])
@pytest.mark.parametrize("mesh", ["hertz_bodies_coarse.geo", "hertz_bodies_hex_coarse.geo"])
def test_nodal_geometry_derivatives(mesh, projecting, edge):
    """(L.1)-(L.3) of every coupled slave node (the block's top against the sphere, deformed by
    :func:`_distortion`) against central differences in coordinates of slave and master nodes
    that its rows depend on. ``edge``: as on a symmetry plane through the contact, the slave
    surface ends a quarter across the contact patch (nodes whose averaged normal and covered facets
    are one-sided) and three of four slave nodes carry rollers (x, y or both prescribed: the normal
    without those components, the frames aligned with them)."""
    comm = MPI.COMM_WORLD
    msh, facet_tags, cell_tags = read_gmsh(ROOT / "meshes" / mesh, comm)
    tags = split_by_body(msh, facet_tags, cell_tags)
    V = fem.functionspace(msh, ("Lagrange", 1, (3,)))
    index_map = V.dofmap.index_map
    x = V.tabulate_dof_coordinates()
    size = comm.allreduce(float(np.ptp(x[:, 0])) if len(x) else 0.0, op=MPI.MAX)
    u = _distortion(x, size)
    slave, master = boundary_facets(tags, "block.top"), boundary_facets(tags, "ball.sphere")

    def coupling_at(displacement: np.ndarray, linearised: bool = False) -> MortarCoupling:
        return mortar_coupling(V, slave, master, search_distance=0.02 * size, displacement=displacement,
                               linearised=linearised, projecting=projecting)

    if edge:
        reach = comm.allreduce(float(x[coupling_at(u).slave_blk, 0].max(initial=0.0)), op=MPI.MAX)
        slave = slave[dmesh.compute_midpoints(msh, 2, slave)[:, 0] > 0.25 * reach]

    base = coupling_at(u, linearised=True)
    # the step's start: the configuration half-way, restricted to the slave nodes coupled in both
    start = coupling_at(0.5 * u)
    common = np.intersect1d(base.slave_blk, start.slave_blk)
    base, start = base.restricted(np.isin(base.slave_blk, common)), start.restricted(np.isin(start.slave_blk, common))
    derivatives = base.derivatives
    rows_glob = index_map.local_to_global(base.slave_blk)
    n_rows = comm.allreduce(len(rows_glob))
    assert n_rows >= (10 if edge else 20)
    # columns: dofs that rows depend on geometrically, slave and master nodes, chosen on rank 0
    dofs_everywhere = comm.gather(derivatives.dofs)
    candidates = np.unique(np.concatenate(dofs_everywhere)) if comm.rank == 0 else None
    rng = np.random.default_rng(3)
    dofs = comm.bcast(rng.choice(candidates, size=min(12, len(candidates)), replace=False) if comm.rank == 0 else None)
    h = 1e-6 * size / 10
    errors = np.zeros(6)
    scales = np.zeros(6)
    owners = owner_ranges(comm, index_map)
    weights = np.cos(x[base.slave_blk])  # any slave values v_i held fixed
    transfer = master_shares(comm, index_map, base, weights)
    prescribed = np.zeros((len(base.slave_blk), 3), dtype=bool)  # the rollers' components
    if edge:
        kind = rows_glob % 4
        prescribed[kind == 1, 0] = True
        prescribed[kind == 2, 1] = True
        prescribed[kind == 3, :2] = True
    frames = pair_frames(base.normal, prescribed)[1]
    dframes = pair_frame_derivatives(base, prescribed)
    _, s_base, slip_base = contact_variables(comm, index_map, base, start, x + u, frames)
    variables = variable_derivatives(index_map, base, start, s_base, slip_base, frames, dframes)
    turn = frame_turn(base, dframes, weights)
    for dof in dofs:
        node, component = divmod(int(dof), 3)
        local = index_map.global_to_local(np.array([node], dtype=np.int64))[0]  # -1: not on this rank
        results = []
        for sign in (1.0, -1.0):
            v = u.copy()
            if local >= 0:
                v[local, component] += sign * h
            c = coupling_at(v)
            c = c.restricted(np.isin(c.slave_blk, common))
            assert np.array_equal(c.slave_blk, base.slave_blk)
            variables_at, s, _ = contact_variables(comm, index_map, c, start, x + v, pair_frames(c.normal, prescribed)[1])
            results.append((s, c.normal, np.einsum("ij,ij->i", c.normal, s), variables_at,
                            np.einsum("iaj,ij->ia", pair_frames(c.normal, prescribed)[1], weights), _master_shares(V, c, weights)))
        fd = [(a - b) / (2 * h) for a, b in zip(results[0][:5], results[1][:5])]
        # predicted: the nodes' own motion (e_i - C_iJ e_c) plus the geometric part
        explicit = np.zeros((len(rows_glob), 3))
        explicit[rows_glob == node, component] += 1.0
        entry_rows = np.repeat(np.arange(len(rows_glob)), np.diff(base.C_indptr))
        hit = base.C_master_glob == node
        np.add.at(explicit[:, component], entry_rows[hit], -base.C_values[hit])
        geometric_s, geometric_n = np.zeros((len(rows_glob), 3)), np.zeros((len(rows_glob), 3))
        at = derivatives.dofs == dof
        geometric_s[derivatives.rows[at]] = derivatives.separation[at]
        geometric_n[derivatives.rows[at]] = derivatives.normal[at]
        ds = explicit + geometric_s
        dgap = np.einsum("ij,ij->i", base.normal, ds) + np.einsum("ij,ij->i", geometric_n, s_base)
        at = variables[1] == dof
        dv = np.zeros((len(rows_glob), 3))
        np.add.at(dv, variables[0][at], variables[2][at])
        at = turn[1] == dof
        dturn = np.zeros((len(rows_glob), 3))
        np.add.at(dturn, turn[0][at], turn[2][at])
        for k, (predicted, difference) in enumerate(zip((ds, geometric_n, dgap, dv, dturn), fd)):
            errors[k] = max(errors[k], np.abs(predicted - difference).max(initial=0.0))
            scales[k] = max(scales[k], np.abs(predicted).max(initial=0.0))
        # (L.4): the master nodes' shares sum_i C_ij v_i, summed on the masters' owners
        shares = [results[0][5], results[1][5]]
        at = transfer[1] == dof
        got = sum_to_owners(comm, owners, transfer[0][at], np.zeros(at.sum()), transfer[2][at])
        masters = np.union1d(np.union1d(shares[0][0], shares[1][0]), got[0])
        difference = (_on(masters, *shares[0]) - _on(masters, *shares[1])) / (2 * h)
        predicted = _on(masters, got[0], got[2])
        errors[5] = max(errors[5], np.abs(predicted - difference).max(initial=0.0))
        scales[5] = max(scales[5], np.abs(predicted).max(initial=0.0))
    comm.Allreduce(MPI.IN_PLACE, errors, op=MPI.MAX)
    comm.Allreduce(MPI.IN_PLACE, scales, op=MPI.MAX)
    assert (scales > 0.0).all(), scales
    assert (errors <= BOUND * scales).all(), (errors / scales)


def _master_shares(V: fem.FunctionSpace, coupling: MortarCoupling,
                   values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """sum_i C_ij v_i of each master node j, on the owners of j: (global indices, (k, 3) sums)."""
    comm, index_map = V.mesh.comm, V.dofmap.index_map
    rows = np.repeat(np.arange(len(coupling.slave_blk)), np.diff(coupling.C_indptr))
    summed = sum_to_owners(comm, owner_ranges(comm, index_map), coupling.C_master_glob,
                           np.zeros(len(rows)), coupling.C_values[:, None] * values[rows])
    return summed[0], summed[2]


def _on(nodes: np.ndarray, glob: np.ndarray, values: np.ndarray) -> np.ndarray:
    """(len(nodes), 3) ``values`` of the global nodes ``glob`` at ``nodes`` (zero elsewhere)."""
    out = np.zeros((len(nodes), 3))
    out[np.searchsorted(nodes, glob)] = values
    return out
