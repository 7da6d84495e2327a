"""Test helpers of the mortar tests: linear fields across a flat interface, frame invariance."""

from __future__ import annotations

import typing

from mpi4py import MPI

import numpy as np

from dolfinx import fem

from contactqvi.contact.mortar import MortarCoupling

__all__ = ["frame_invariance_error", "linear_field_errors", "rotation"]


def linear_field_errors(V: fem.FunctionSpace, coupling: MortarCoupling) -> tuple[float, float, float]:
    """Max over the slave nodes of all ranks of |x_i - sum_j C_ij x_j| (the positions, a linear
    field), of |sum_j C_ij - 1| and of the weighted gap |g_i| (collective; the master positions
    are gathered by global index, so only for small surfaces)."""
    comm = V.mesh.comm
    x = V.tabulate_dof_coordinates()
    index_map = V.dofmap.index_map
    owned_glob = index_map.local_to_global(np.arange(index_map.size_local, dtype=np.int32))
    table = dict(zip(np.concatenate(comm.allgather(owned_glob)).tolist(),
                     np.concatenate(comm.allgather(x[: index_map.size_local]))))
    rows = np.repeat(np.arange(len(coupling.slave_blk)), np.diff(coupling.C_indptr))
    projected = np.zeros((len(coupling.slave_blk), 3))
    master_x = np.array([table[j] for j in coupling.C_master_glob]).reshape(-1, 3)
    np.add.at(projected, rows, coupling.C_values[:, None] * master_x)
    row_sums = np.bincount(rows, weights=coupling.C_values, minlength=len(coupling.slave_blk))
    local = (np.abs(projected - x[coupling.slave_blk]).max(initial=0.0), np.abs(row_sums - 1.0).max(initial=0.0),
             np.abs(coupling.gap).max(initial=0.0))
    return tuple(comm.allreduce(float(value), op=MPI.MAX) for value in local)


def rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """The rotation matrix about the unit vector ``axis`` by ``angle`` (Rodrigues)."""
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def frame_invariance_error(msh, solve: typing.Callable[[np.ndarray], np.ndarray], Q: np.ndarray) -> float:
    """max |u_Q(Q x) - Q u(x)| / max |u| over all ranks, u = ``solve(I)`` and u_Q = ``solve(Q)``
    the displacements (local nodes, 3) with the mesh's nodes moved to Q x (restored after)."""
    original = msh.geometry.x.copy()
    displacements = []
    try:
        for R in (np.eye(3), Q):
            msh.geometry.x[:] = original @ R.T
            displacements.append(solve(R))
    finally:
        msh.geometry.x[:] = original
    scale = msh.comm.allreduce(float(np.abs(displacements[0]).max()), op=MPI.MAX)
    error = np.abs(displacements[1] - displacements[0] @ Q.T).max()
    return msh.comm.allreduce(float(error), op=MPI.MAX) / scale
