"""The law's variables of a body pair in the current configuration and their derivatives (issue 45).

docs/finite_strain.md, Sect. 13, (13.1): at a slave node i with the mortar coupling C of the
current positions x, its nodal normal n_i and frame (t_1, t_2, n)_i of
:func:`~contactqvi.obstacles.tangent_frames`,

    v_i,n = n_i . s_i,   s_i = x_i - p_i,   p_i = sum_j C_ij x_j           (the weighted gap),
    v_i,a = t_a,i . (p_i - p_i^prev),   p_i^prev = sum_j C_ij^prev x_j      (the slip, a = 1, 2),

C^prev the coupling of the configuration the load step started from (the master material
point slave node i projected onto then, at its current position): objective, since a rigid
motion of both bodies changes neither C nor C^prev. Their derivatives with respect to x
combine the nodes' own motion (C fixed) with the geometric parts (L.1)-(L.2) of
:mod:`contactqvi.contact.linearisation`:

    dv_n = n . (dx_i - sum_j C_ij dx_j + ds^geo) + dn . s,
    dv_a = t_a . (sum_j (C_ij - C_ij^prev) dx_j - ds^geo) + dt_a . (p - p^prev),

and the frame's, from dn through the construction of t_1 (:func:`frame_derivatives`). The
same turn of the frames changes the slave rows R_i^T r_i of the forces (12.2) at fixed r
(:func:`frame_turn`), and the change of C moves the master rows sum_i C_ij P_i r_i
(:func:`master_shares`).
"""

from __future__ import annotations

from mpi4py import MPI

import dataclasses

import numpy as np

from contactqvi.contact.linearisation import PairDerivatives
from contactqvi.contact.mortar import MortarCoupling
from contactqvi.contact.owners import fetch_rows
from contactqvi.obstacles import frame_axes, tangent_frames

__all__ = ["aligned_previous", "contact_variables", "frame_derivatives", "frame_turn", "master_shares",
           "pair_frame_derivatives", "pair_frames", "roller_aligned", "variable_derivatives"]


def roller_aligned(frames: np.ndarray, constrained: np.ndarray) -> np.ndarray:
    """``frames`` (m, 3, 3) with t_1 along the first prescribed global axis and t_2 = n x t_1 at
    the nodes with a prescribed component (``constrained``, (m, 3) bool; a roller on a symmetry
    plane through the contact, whose axis lies in the tangent plane): a prescribed component is
    then a frame component (:mod:`contactqvi.contact.problem`)."""
    partly = np.flatnonzero(constrained.any(axis=1))
    frames = frames.copy()
    axis = np.eye(3)[np.argmax(constrained[partly], axis=1)]
    frames[partly, 0] = axis
    frames[partly, 1] = np.cross(frames[partly, 2], axis)
    return frames


def pair_frames(normal: np.ndarray, constrained: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The unit normals of a body pair's slave nodes and their frames: the nodal normals
    ``normal`` (m, 3) with the components prescribed at the node (``constrained``, (m, 3)) taken
    out (on a symmetry plane the normal lies in the plane), and the frames of
    :func:`~contactqvi.obstacles.tangent_frames` aligned with the rollers (:func:`roller_aligned`)."""
    projected = normal * ~constrained
    projected /= np.linalg.norm(projected, axis=1)[:, None]
    return projected, roller_aligned(tangent_frames(projected), constrained)


def frame_derivatives(normal: np.ndarray, dn: np.ndarray, constrained: np.ndarray | None = None) -> np.ndarray:
    """(E, 3, 3) derivatives (rows dt_1, dt_2, dn) of the frames of unit normals ``normal`` (E, 3)
    along their derivatives ``dn`` (E, 3), for :func:`~contactqvi.obstacles.tangent_frames`:
    t_1 = (a - (a . n) n) / |a - (a . n) n| with the fixed axis a that function picks for n,
    t_2 = n x t_1; where a component is prescribed (``constrained``, (E, 3)) t_1 is that axis
    and t_2 = n x t_1 (:func:`roller_aligned`)."""
    frames = tangent_frames(normal)
    t1 = frames[:, 0]
    axis = frame_axes(normal)
    raw = axis - np.einsum("ij,ij->i", axis, normal)[:, None] * normal
    draw = -np.einsum("ij,ij->i", axis, dn)[:, None] * normal - np.einsum("ij,ij->i", axis, normal)[:, None] * dn
    dt1 = (draw - np.einsum("ij,ij->i", t1, draw)[:, None] * t1) / np.linalg.norm(raw, axis=1)[:, None]
    dt2 = np.cross(dn, t1) + np.cross(normal, dt1)
    if constrained is not None:
        partly = constrained.any(axis=1)
        roller = np.eye(3)[np.argmax(constrained[partly], axis=1)]
        dt1[partly] = 0.0
        dt2[partly] = np.cross(dn[partly], roller)
    return np.stack([dt1, dt2, dn], axis=1)


def pair_frame_derivatives(coupling: MortarCoupling, constrained: np.ndarray) -> np.ndarray:
    """(E, 3, 3) derivatives of the frames of :func:`pair_frames` (``constrained``: (m, 3) of the
    coupling's rows) for the entries of ``coupling.derivatives``. With m the normal taken out of
    the prescribed components, n' = m n / |m n| and dn' = (I - n' n'^T) m dn / |m n|."""
    d = coupling.derivatives
    free = ~constrained[d.rows]
    kept = coupling.normal[d.rows] * free
    size = np.linalg.norm(kept, axis=1)[:, None]
    normal = kept / size
    dn = d.normal * free
    dn = (dn - np.einsum("ij,ij->i", normal, dn)[:, None] * normal) / size
    return frame_derivatives(normal, dn, constrained[d.rows])


def aligned_previous(previous: MortarCoupling, coupling: MortarCoupling) -> MortarCoupling:
    """The rows of ``previous`` (a coupling of the step's start) for the slave nodes of
    ``coupling``, in its order; a node ``previous`` does not couple takes its row of
    ``coupling`` (its slip is measured from where it is now)."""
    found = np.isin(coupling.slave_blk, previous.slave_blk)
    kept = previous.restricted(np.isin(previous.slave_blk, coupling.slave_blk))
    new = coupling.restricted(~found)
    lengths = np.zeros(len(coupling.slave_blk), dtype=np.int64)
    lengths[found] = np.diff(kept.C_indptr)
    lengths[~found] = np.diff(new.C_indptr)
    entries_of = np.repeat(found, lengths)
    masters = np.empty(lengths.sum(), dtype=np.int64)
    values = np.empty(lengths.sum())
    masters[entries_of], values[entries_of] = kept.C_master_glob, kept.C_values
    masters[~entries_of], values[~entries_of] = new.C_master_glob, new.C_values
    return dataclasses.replace(coupling, C_indptr=np.concatenate([[0], np.cumsum(lengths)]), C_master_glob=masters,
                               C_values=values, derivatives=None, layout=None)


def _projection(comm: MPI.Comm, index_map, coupling: MortarCoupling, current: np.ndarray) -> np.ndarray:
    """(m, 3) sum_j C_ij x_j of the current positions ``current`` (local nodes), masters fetched."""
    rows = np.repeat(np.arange(len(coupling.slave_blk)), np.diff(coupling.C_indptr))
    masters = fetch_rows(comm, index_map, current[:index_map.size_local], coupling.C_master_glob)
    projected = np.zeros((len(coupling.slave_blk), 3))
    np.add.at(projected, rows, coupling.C_values[:, None] * masters)
    return projected


def contact_variables(comm: MPI.Comm, index_map, coupling: MortarCoupling, previous: MortarCoupling,
                      current: np.ndarray, frames: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(13.1) of the coupling's rows at the current positions ``current`` (local nodes, 3) in
    their ``frames`` (m, 3, 3; :func:`pair_frames`).

    ``previous`` has the rows of the same slave nodes (:func:`aligned_previous`). Returns
    ``(v, s, slip)``: (m, 3) the variables (t_1, t_2, n components), (m, 3) s_i and (m, 3)
    p_i - p_i^prev. Collective."""
    projected = _projection(comm, index_map, coupling, current)
    slip = projected - _projection(comm, index_map, previous, current)
    s = current[coupling.slave_blk] - projected
    v = np.column_stack([np.einsum("ij,ij->i", frames[:, 0], slip), np.einsum("ij,ij->i", frames[:, 1], slip),
                         np.einsum("ij,ij->i", frames[:, 2], s)])
    return v, s, slip


def variable_derivatives(index_map, coupling: MortarCoupling, previous: MortarCoupling, s: np.ndarray,
                         slip: np.ndarray, frames: np.ndarray,
                         dframes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The derivatives of (13.1) with respect to the current positions, entries
    ``(rows, dofs, values)``: (E,) coupling row, (E,) global coordinate index 3 J + c, (E, 3)
    (t_1, t_2, n) components; duplicates to be added. ``s``, ``slip`` from :func:`contact_variables`,
    ``frames`` and ``dframes`` from :func:`pair_frames` and :func:`pair_frame_derivatives`;
    ``coupling`` must carry its derivatives (``mortar_coupling(..., linearised=True)``)."""
    d = coupling.derivatives
    m = len(coupling.slave_blk)
    # geometric parts: ds^geo and the frames' turn
    geometric = np.column_stack([
        -np.einsum("ij,ij->i", frames[d.rows, 0], d.separation) + np.einsum("ij,ij->i", dframes[:, 0], slip[d.rows]),
        -np.einsum("ij,ij->i", frames[d.rows, 1], d.separation) + np.einsum("ij,ij->i", dframes[:, 1], slip[d.rows]),
        np.einsum("ij,ij->i", frames[d.rows, 2], d.separation) + np.einsum("ij,ij->i", dframes[:, 2], s[d.rows])])
    # the nodes' own motion: the slave node itself (normal), sum_j C_ij dx_j (normal, with -),
    # sum_j (C_ij - C_ij^prev) dx_j (tangential)
    own = index_map.local_to_global(coupling.slave_blk)
    own_rows = np.repeat(np.arange(m), 3)
    own_dofs = 3 * np.repeat(own, 3) + np.tile(np.arange(3), m)
    own_values = np.zeros((3 * m, 3))
    own_values[:, 2] = frames[:, 2].ravel()
    rows_c, dofs_c, values_c = _weighted_motion(coupling, frames, sign_tangential=1.0)
    rows_p, dofs_p, values_p = _weighted_motion(previous, frames, sign_tangential=-1.0, tangential_only=True)
    return (np.concatenate([d.rows, own_rows, rows_c, rows_p]), np.concatenate([d.dofs, own_dofs, dofs_c, dofs_p]),
            np.concatenate([geometric, own_values, values_c, values_p]))


def _weighted_motion(coupling: MortarCoupling, frames: np.ndarray, sign_tangential: float,
                     tangential_only: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Entries of sum_j C_ij dx_j in (t_1, t_2, n) components: +- t_a . (C_ij e_c) tangential,
    -n . (C_ij e_c) normal (none with ``tangential_only``), for every C entry and c."""
    lengths = np.diff(coupling.C_indptr)
    row = np.repeat(np.arange(len(lengths)), lengths)
    rows = np.repeat(row, 3)
    dofs = 3 * np.repeat(coupling.C_master_glob, 3) + np.tile(np.arange(3), len(row))
    components = frames[rows, :, np.tile(np.arange(3), len(row))]  # (E, 3): (t_1, t_2, n) . e_c
    weights = np.repeat(coupling.C_values, 3)[:, None]
    values = weights * components * np.array([sign_tangential, sign_tangential, 0.0 if tangential_only else -1.0])
    return rows, dofs, values


def frame_turn(coupling: MortarCoupling, dframes: np.ndarray,
               forces: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The derivative of R_i^T r_i (the (t_1, t_2, n) components of slave forces ``forces``
    (m, 3) held fixed) with respect to the current positions, through the frames' turn
    ``dframes`` (:func:`pair_frame_derivatives`): entries ``(rows, dofs, values)`` as
    :func:`variable_derivatives`' (the slave rows of the term Gamma of docs/finite_strain.md,
    Sect. 13)."""
    d = coupling.derivatives
    return d.rows, d.dofs, np.einsum("eaj,ej->ea", dframes, forces[d.rows])


def master_shares(comm: MPI.Comm, index_map, coupling: MortarCoupling,
                  values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The derivative of the master nodes' share sum_i C_ij v_i of slave values v (held
    fixed): the force a slave node passes to the master nodes under T^T (v_i = P_i r_i,
    :mod:`contactqvi.contact.problem`). With C_ij = M_ij / D_i,

        d(sum_i C_ij v_i) = sum_i dM_ij v_i / D_i - sum_i C_ij (v_i / D_i) dD_i,     (L.4)

    the first term summed over the rank's pairs (v / D fetched from the rows' owners),
    the second over its rows. Collective; ``coupling`` must carry its derivatives.

    Args:
        coupling: the :class:`~contactqvi.contact.mortar.MortarCoupling` these are of.
        values: (m, 3) v_i of its rows.

    Returns:
        ``(rows, dofs, values)``: entries of the (global node j of the master, global
        coordinate index 3 J + c) derivative, (E,), (E,), (E, 3), on the rank that made
        them (sum them into a matrix, duplicates added).
    """
    d = coupling.derivatives
    scaled = values / coupling.weight[:, None]
    # sum_i C_ij (v_i / D_i) dD_i over the owned rows: every (C entry, dD entry) of a row
    lengths = np.diff(coupling.C_indptr)
    per_row = np.bincount(d.rows, minlength=len(lengths))
    starts = np.concatenate([[0], np.cumsum(per_row)])
    c_entry = np.repeat(np.arange(len(coupling.C_values)), np.repeat(per_row, lengths))
    row = np.repeat(np.repeat(np.arange(len(lengths)), lengths), np.repeat(per_row, lengths))
    d_entry = starts[row] + _ranges(np.repeat(per_row, lengths))
    node_values = -(coupling.C_values[c_entry] * d.weight[d_entry])[:, None] * scaled[row]
    node_rows, node_dofs = coupling.C_master_glob[c_entry], d.dofs[d_entry]
    # sum_i dM_ij v_i / D_i over the rank's pairs
    owned = np.zeros((index_map.size_local, 3))
    owned[coupling.slave_blk] = scaled
    p = d.pairs
    at_slaves = fetch_rows(comm, index_map, owned, p.slave_glob.ravel()).reshape(*p.slave_glob.shape, 3)
    pair_values = np.einsum("pabvc,pak->pbvck", p.dM, at_slaves)  # (P, n_m, N, 3, 3)
    shape = pair_values.shape[:-1]
    pair_rows = np.broadcast_to(p.master_glob[:, :, None, None], shape).ravel()
    pair_dofs = np.broadcast_to(p.dofs[:, None], shape).ravel()
    cross = _covered_shares(p, at_slaves)
    return (np.concatenate([node_rows, pair_rows, cross[0]]), np.concatenate([node_dofs, pair_dofs, cross[1]]),
            np.concatenate([node_values, pair_values.reshape(-1, 3), cross[2]]))


def _covered_shares(pairs: PairDerivatives, at_slaves: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """What the derivative of a partly covered facet's A, (L.5) of :mod:`contactqvi.contact.covered`,
    adds to the first term of (L.4):
    sum_i (v_i / D_i) dA_ia G_p,aj for the master node j of each pair p and the vertices of each pair
    q of the same facet, whose dF_q and dH_q make dA's term (``at_slaves``: v / D at the pairs' slave
    nodes); the entries of :func:`master_shares`."""
    c = pairs.covered
    if c is None or len(c.pairs) == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros((0, 3))
    s = at_slaves[c.pairs]  # (Q, n_s, 3)
    As = np.einsum("pab,pak->pbk", c.A, s)
    r = s[:, :, None, None, :] * c.dF[..., None] - np.einsum("pbk,pbdvc->pdvck", As, c.dH)  # s^T dA_q H
    w = np.einsum("pdvck,pde->pevck", r, c.Hinv)
    # every ordered pair (p, q) of pairs of one facet
    order = np.argsort(c.facet, kind="stable")
    sizes = np.bincount(c.facet)[c.facet[order]]
    starts = np.concatenate([[0], np.cumsum(np.bincount(c.facet))])[c.facet[order]]
    p_of, q_of = np.repeat(order, sizes), order[np.repeat(starts, sizes) + _ranges(sizes)]
    values = np.einsum("xevck,xej->xjvck", w[q_of], c.G[p_of])  # (X, n_m, N, 3, 3)
    shape = values.shape[:-1]
    rows = np.broadcast_to(pairs.master_glob[c.pairs[p_of]][:, :, None, None], shape).ravel()
    dofs = np.broadcast_to(pairs.dofs[c.pairs[q_of]][:, None], shape).ravel()
    return rows, dofs, values.reshape(-1, 3)


def _ranges(lengths: np.ndarray) -> np.ndarray:
    """0, 1, ..., n - 1 for each n of ``lengths``, concatenated."""
    ends = np.cumsum(lengths)
    return np.arange(ends[-1] if len(ends) else 0) - np.repeat(ends - lengths, lengths)
