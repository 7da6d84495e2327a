"""Derivatives of the mortar geometry with respect to the current node positions (issue 45, item 2).

At finite deformation the weighted separation, gap and slip of a slave node i are functions
of the current positions x = X + u through everything the mortar coupling is built from
(:mod:`contactqvi.contact.mortar`):

    s_i(x) = x_i - sum_j C_ij(x) x_j,   C_ij = M_ij / D_i,   g~_i = n_i(x) . s_i(x),
    n_i = a_i / |a_i|,   a_i = sum over the slave facets f at i of (-A_f N_f),

A_f N_f a facet's area times its outward unit normal and D_i, M_ij the integrals over the
mortar segments, the clipped polygons of :mod:`contactqvi.contact.segments`. A variation
dx splits into the part the change of variables u = T w of
:mod:`contactqvi.contact.problem` already holds (the nodes move, C stays: dx_i - sum_j
C_ij dx_j) and the *geometric* part, the coupling and the normals moving with the facets:

    ds_i^geo = -sum_j dC_ij x_j = -(sum_j dM_ij x_j - dD_i p_i) / D_i,  p_i = sum_j C_ij x_j,  (L.1)
    dn_i = (I - n_i n_i^T) da_i / |a_i|,                                                     (L.2)
    dg~_i = n_i . (dx_i - sum_j C_ij dx_j) + n_i . ds_i^geo + dn_i . s_i.                      (L.3)

Popp, Gee and Wall (IJNME 79 (2009) 1354, Sect. 4; 3D: Popp, Gitterle, Gee, Wall, IJNME 83
(2010) 1428) derive dD, dM and da by hand, through the clip polygon's vertices and the
projections. Here they are taken by forward-mode automatic differentiation (Griewank and
Walther, "Evaluating Derivatives", 2nd ed., SIAM 2008): the segment integration
(:mod:`contactqvi.contact.segments`) runs once on dual numbers
(:class:`~contactqvi.contact.dual.Dual`), values and a trailing axis of derivatives, its branch
decisions (clipping pattern, orientation, rule) taken on the values: exact to round-off on the
branch of x, with no difference of two values. Each pair of facets depends on its 3 (n_s + n_m)
coordinates; the integration in the slave facet's plane depends on fewer, the plane coordinates
that vary (and a quadrilateral's warp), so it is differentiated there and chained with the
projection's Jacobian (:func:`_integral_jacobians`). On the owners of the slave nodes the pairs'
derivatives are summed as the values are (:mod:`contactqvi.contact.owners`) and combined into
(L.1)-(L.2).
"""

from __future__ import annotations

import dataclasses
import typing

from mpi4py import MPI

import numpy as np

from contactqvi.contact.covered import CoveredBasis, CoveredDerivatives, covered_entries
from contactqvi.contact.dual import Dual, primal
from contactqvi.contact.facets import facet_areas, unit_normals
from contactqvi.contact.owners import owner_ranges, sum_to_owners
from contactqvi.contact.segments import (diameters, edge_ties, planar_basis_integrals, planar_integrals,
                                         plane_coordinates)

__all__ = ["KINK", "KINK_OFFSET", "CouplingDerivatives", "PairDerivatives", "basis_jacobians", "coupling_derivatives",
           "segment_jacobians"]


#: A pair whose dD or dM exceed this times its slave facet's diameter (they are of
#: the order of it: D is an area) is at a kink (:func:`segment_jacobians`).
KINK = 10.0
#: ... and is differentiated with its master facet moved by this fraction of that diameter
#: along one direction for all pairs (:data:`_KINK_DIRECTION`).
KINK_OFFSET = 1e-6
#: The direction of that move, a unit vector along no mesh line or common normal: a master node
#: moves alike in every pair it belongs to, so the pairs at a node take the same side of its kink.
_KINK_DIRECTION = np.sin(np.arange(1.0, 4.0)) / np.linalg.norm(np.sin(np.arange(1.0, 4.0)))
#: Facet pairs differentiated at a time (each value with its derivatives in all directions):
#: bounds the work arrays as :data:`~contactqvi.contact.mortar` bounds its own.
_CHUNK = 1 << 12
_QUADRILATERAL_CHUNK = 1 << 7


def _orientation(x: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """(P,) +1 or -1: the sign that turns :func:`unit_normals` of facets x into ``normal``."""
    return np.where(np.einsum("ij,ij->i", unit_normals(x), normal) < 0.0, -1.0, 1.0)


def segment_jacobians(slave: np.ndarray, normal: np.ndarray,
                      master: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`~contactqvi.contact.segments.segment_integrals` of facet pairs and their derivatives.

    Args:
        slave: (P, n_s, 3); normal: (P, 3) the slave facets' unit normals, either orientation
            (the projection direction; it turns with the facet); master: (P, n_m, 3).

    Returns:
        ``(D, M, dD, dM)``: (P, n_s), (P, n_s, n_m), and their derivatives (P, n_s, N, 3),
        (P, n_s, n_m, N, 3) with respect to the pair's N = n_s + n_m vertices, slave first.
    """
    (D, M), (dD, dM) = _jacobians(slave, normal, master, planar_integrals)
    return D, M, dD, dM


def basis_jacobians(slave: np.ndarray, normal: np.ndarray, master: np.ndarray) -> tuple[tuple, tuple]:
    """:func:`~contactqvi.contact.segments.basis_integrals` (F, G, H) of facet pairs and their
    derivatives with respect to the pair's vertices (the arguments and the derivatives' trailing
    axes of :func:`segment_jacobians`): ``((F, G, H), (dF, dG, dH))``."""
    return _jacobians(slave, normal, master, planar_basis_integrals)


def _jacobians(slave: np.ndarray, normal: np.ndarray, master: np.ndarray,
               integrals: typing.Callable) -> tuple[tuple, tuple]:
    """The values of the planar ``integrals`` of facet pairs and their derivatives with respect to the
    pair's vertices (:func:`segment_jacobians`)."""
    orientation = _orientation(slave, normal)
    values, derivatives, kinked = _integral_jacobians(slave, master, orientation, integrals)
    # At a kink of the integrals (facets that coincide: conforming parts of two meshes, whose clipped
    # polygons have vertices on two edges at once) the clipping ties (a vertex exactly on an edge's
    # line, where each pair would take the side its own values take) or its crossings are near 0/0
    # forms (derivatives far beyond the facet's size); there the one-sided derivative of the master
    # facet moved by KINK_OFFSET of its size along _KINK_DIRECTION serves, an element of the
    # generalized derivative of the semismooth Newton step (docs/finite_strain.md, Sect. 14).
    size = diameters(slave)
    for d in derivatives:
        axes = tuple(range(1, d.ndim))
        kinked |= ~np.isfinite(d).all(axis=axes) | (np.abs(d).max(axis=axes, initial=0.0) > KINK * size)
    if kinked.any():
        moved = master[kinked] + KINK_OFFSET * size[kinked, None, None] * _KINK_DIRECTION
        for d, one_sided in zip(derivatives, _integral_jacobians(slave[kinked], moved, orientation[kinked],
                                                                integrals)[1]):
            d[kinked] = one_sided
    return values, derivatives


def _integral_jacobians(slave: np.ndarray, master: np.ndarray, orientation: np.ndarray,
                        integrals: typing.Callable) -> tuple[tuple, tuple, np.ndarray]:
    """The planar ``integrals`` of facet pairs (:func:`~contactqvi.contact.segments.planar_integrals`
    or :func:`~contactqvi.contact.segments.planar_basis_integrals`), their derivatives with respect to
    the pair's N vertices (each (P, ..., N, 3)), the projection direction the slave facets'
    :func:`unit_normals` times ``orientation`` (P,), and (P,) whether the pair's clipping ties
    (:func:`~contactqvi.contact.segments.edge_ties`).

    Two forward sweeps, the Jacobian of the first accumulated and multiplied onto the second's
    (preaccumulation; Griewank and Walther 2008, Ch. 10): the projection onto the slave facet's
    plane, on the slave facet's coordinates (the master facet's enter it linearly); the
    integration in the plane, on the plane coordinates that vary (:func:`_planar_directions`):
    9 directions instead of 18 for two triangles, 14 instead of 24 for two quadrilaterals.
    """
    ns, N = slave.shape[1], slave.shape[1] + master.shape[1]
    s = Dual.seed(slave)
    normal = orientation[:, None] * unit_normals(s)
    s2, m2, axes = plane_coordinates(s, normal, master)
    planar, jacobian = _planar_directions(s2, m2, axes, s, normal)
    if ns == 4:  # the area element and dual basis: of the facet moved as its plane coordinates and warp
        frame = np.stack([primal(e) for e in (*axes, normal)], axis=1)  # (P, 3, 3): rows e1, e2, normal
        heights = np.broadcast_to(_warp_seed(jacobian.shape[1]), (len(slave), 4, 1, jacobian.shape[1]))
        local = np.concatenate([planar.tangent[:, :ns], heights], axis=2)
        slave = Dual(slave, np.einsum("pvaj,pac->pvcj", local, frame))
    outputs = integrals(slave, planar[:, :ns], master, planar[:, ns:])
    chained = tuple(np.matmul(out.tangent.reshape(len(slave), np.prod(out.shape[1:]), jacobian.shape[1]),
                              jacobian).reshape(*out.shape, N, 3) for out in outputs)
    return tuple(out.value for out in outputs), chained, edge_ties(s2.value, m2.value)


#: The plane coordinates of a slave facet that are zero whatever its position (vertex 0 at the
#: origin, vertex 1 on the first axis: :func:`~contactqvi.contact.segments.plane_coordinates`).
_FIXED = ([0, 0, 1], [0, 1, 1])


def _planar_directions(s2: Dual, m2: Dual, axes: tuple[Dual, Dual], slave: Dual,
                       normal: Dual) -> tuple[Dual, np.ndarray]:
    """The plane coordinates s2 (P, n_s, 2), m2 (P, n_m, 2) of pairs, differentiated with respect
    to the slave facets' coordinates, seeded anew as one dual (P, N, 2), and the Jacobian
    (P, k, 3 N) of its k directions with respect to the pairs' coordinates (slave first): the
    coordinates that vary, then, for a slave quadrilateral, its warp w = n . (x_1 - x_0) (its
    vertices lie at heights (0, w, w, 0) over its mean plane). m2 = E (x - x_0) with E the rows
    ``axes``: E is its derivative with respect to a master vertex x."""
    P, ns, nm = len(s2), s2.shape[1], m2.shape[1]
    free = np.ones((ns + nm, 2), dtype=bool)
    free[_FIXED] = False
    by_slave = [s2.tangent[:, free[:ns]], m2.tangent.reshape(P, 2 * nm, 3 * ns)]
    if ns == 4:
        by_slave.append(np.einsum("pc,pc->p", normal, slave[:, 1] - slave[:, 0]).tangent[:, None])
    by_slave = np.concatenate(by_slave, axis=1)
    k, first = by_slave.shape[1], free[:ns].sum()
    by_master = np.zeros((P, k, 3 * nm))
    E = np.stack([primal(a) for a in axes], axis=1)  # (P, 2, 3)
    by_master[:, first:first + 2 * nm] = np.einsum("vw,pac->pvawc", np.eye(nm), E).reshape(P, 2 * nm, 3 * nm)
    seeds = np.zeros((ns + nm, 2, k))
    seeds[free] = np.eye(free.sum(), k)
    planar = np.concatenate([s2.value, m2.value], axis=1)
    return Dual(planar, np.broadcast_to(seeds, (*planar.shape, k))), np.concatenate([by_slave, by_master], axis=2)


def _warp_seed(k: int) -> np.ndarray:
    """(4, 1, k) the heights of a quadrilateral's vertices over its mean plane along the warp,
    the last of k directions."""
    seed = np.zeros((4, 1, k))
    seed[[1, 2], 0, -1] = 1.0
    return seed


def _area_normal_jacobians(x: np.ndarray, outward: np.ndarray) -> np.ndarray:
    """(f, 3, n, 3) derivatives of -A_f N_f (area times unit normal, into the body) of facets
    (f, n, 3) with outward normals ``outward``, with respect to their vertices."""
    z = Dual.seed(x)
    area_normals = -_orientation(x, outward)[:, None] * facet_areas(z)[:, None] * unit_normals(z)
    return area_normals.tangent.reshape(len(x), 3, *x.shape[1:])


@dataclasses.dataclass(frozen=True)
class PairDerivatives:
    """dM of the facet pairs a rank integrated (its own slave facets), for the derivative of
    the force the slave nodes pass to the master nodes (:func:`~contactqvi.contact.kinematics.master_shares`).

    Attributes:
        slave_glob: (P, n_s), master_glob: (P, n_m) global node indices of the pairs' facets.
        dM: (P, n_s, n_m, N, 3) derivatives of the pairs' M with respect to their N = n_s + n_m
            vertices (slave first); for the pairs of a partly covered facet (``covered``) the part
            at fixed A, A dG_p.
        covered: the pairs of partly covered facets and what the derivative (L.5) of their facet's
            A needs (:class:`~contactqvi.contact.covered.CoveredDerivatives`); None if there are none.
    """

    slave_glob: np.ndarray
    master_glob: np.ndarray
    dM: np.ndarray
    covered: CoveredDerivatives | None = None

    @property
    def dofs(self) -> np.ndarray:
        """(P, N, 3) global indices 3 J + c of the pairs' vertex coordinates."""
        nodes = np.concatenate([self.slave_glob, self.master_glob], axis=1)
        return 3 * nodes[:, :, None] + np.arange(3)


@dataclasses.dataclass(frozen=True)
class CouplingDerivatives:
    """Geometric derivatives (L.1)-(L.2) of the rows of a :class:`~contactqvi.contact.mortar.MortarCoupling`,
    one entry per (row, coordinate it depends on), sorted by row.

    Attributes:
        rows: (E,) index of the coupling's row (its slave node).
        dofs: (E,) global index 3 J + c of the coordinate c of global node J differentiated.
        separation: (E, 3) ds_i^geo: the derivative of the weighted separation s_i with the
            nodes' own motion left out (that part is e_i - C_ij e_j).
        normal: (E, 3) dn_i of the nodal unit normal.
        weight: (E,) dD_i.
        pairs: the rank's pairs' dM (for :func:`~contactqvi.contact.kinematics.master_shares`).
    """

    rows: np.ndarray
    dofs: np.ndarray
    separation: np.ndarray
    normal: np.ndarray
    weight: np.ndarray
    pairs: PairDerivatives

    def restricted(self, keep: np.ndarray) -> CouplingDerivatives:
        """The entries of the rows ``keep`` (a mask over the coupling's rows), rows renumbered."""
        entries = keep[self.rows]
        renumbered = np.cumsum(keep) - 1
        return CouplingDerivatives(renumbered[self.rows[entries]], self.dofs[entries], self.separation[entries],
                                   self.normal[entries], self.weight[entries], self.pairs)


def coupling_derivatives(comm: MPI.Comm, index_map, slave_glob: np.ndarray, slave_x: np.ndarray,
                         slave_normal: np.ndarray, pairs_s: np.ndarray, master_x: np.ndarray,
                         master_glob: np.ndarray, coupled_glob: np.ndarray, weight: np.ndarray,
                         normal_sum: np.ndarray, projected: np.ndarray,
                         covered: CoveredBasis | None = None) -> CouplingDerivatives:
    """(L.1)-(L.2) of the coupled slave nodes a rank owns. Collective.

    The pairs of partly covered facets (``covered``) take the entries (L.6) of
    :mod:`contactqvi.contact.covered`, each of its own pair's vertices.

    Args:
        slave_glob, slave_x, slave_normal: the rank's slave facets: (f, n_s) global node
            indices, (f, n_s, 3) current positions, (f, 3) outward unit normals.
        pairs_s: (P,) slave facet of each overlapping pair; master_x (P, n_m, 3), master_glob
            (P, n_m): its master facet.
        coupled_glob: (m,) sorted global indices of the owned coupled slave nodes, the rows;
            weight (m,) their D_i, normal_sum (m, 3) their a_i, projected (m, 3) their p_i.
        covered: the dual basis of the partly covered facets' covered parts, or None.
    """
    ns = slave_x.shape[1]
    rows, cols, values, pairs = _pair_entries(slave_glob, slave_x, slave_normal, pairs_s, master_x, master_glob,
                                              covered)
    # ... and da (3) of every slave facet at the row, paired or not
    da = np.moveaxis(_area_normal_jacobians(slave_x, slave_normal), 1, -1)  # (f, n_s, 3, 3)
    shape = (len(slave_x), ns, ns)
    facet_entries = (np.broadcast_to(slave_glob[:, :, None], shape).ravel(),
                     np.broadcast_to(slave_glob[:, None, :], shape).ravel(),
                     np.broadcast_to(da[:, None], (*shape, 3, 3)).reshape(-1, 9))
    owned_rows, nodes, summed = _summed_on_owners(comm, index_map, (rows, cols, values), facet_entries)
    owned_rows, summed = np.repeat(owned_rows, 3), summed.reshape(-1, 7)
    dofs = (3 * nodes[:, None] + np.arange(3)).ravel()
    position = np.searchsorted(coupled_glob, owned_rows)
    coupled = position < len(coupled_glob)
    coupled[coupled] = coupled_glob[position[coupled]] == owned_rows[coupled]
    row, dofs, summed = position[coupled], dofs[coupled], summed[coupled]
    separation = -(summed[:, 1:4] - summed[:, :1] * projected[row]) / weight[row, None]
    size = np.linalg.norm(normal_sum, axis=1)
    n = normal_sum / size[:, None]
    da = summed[:, 4:]
    normal = (da - np.einsum("ij,ij->i", n[row], da)[:, None] * n[row]) / size[row, None]
    return CouplingDerivatives(row, dofs, separation, normal, summed[:, 0], pairs)


def _pair_entries(slave_glob: np.ndarray, slave_x: np.ndarray, slave_normal: np.ndarray, pairs_s: np.ndarray,
                  master_x: np.ndarray, master_glob: np.ndarray,
                  covered: CoveredBasis | None) -> tuple[np.ndarray, np.ndarray, np.ndarray, PairDerivatives]:
    """The pairs' entries of :func:`coupling_derivatives` (its arguments): (row node, column node) and,
    per coordinate of the column node, dD and dM x (E, 3, 4), in chunks of :data:`_CHUNK` pairs; and the
    pairs' dM (:class:`PairDerivatives`)."""
    ns, nm = slave_x.shape[1], master_x.shape[1]
    chunk = _CHUNK if ns == nm == 3 else _QUADRILATERAL_CHUNK
    rows, cols = [np.zeros(0, dtype=np.int64)], [np.zeros(0, dtype=np.int64)]  # a rank may have no pairs
    values, pair_dM = [np.zeros((0, 12))], [np.zeros((0, ns, nm, ns + nm, 3))]
    of_covered = np.full(len(pairs_s), -1)
    if covered is not None:
        of_covered[covered.pairs] = np.arange(len(covered.pairs))
    covered_dF, covered_dH = [np.zeros((0, ns, ns + nm, 3))], [np.zeros((0, ns, ns, ns + nm, 3))]
    for start in range(0, len(pairs_s), chunk):
        s = pairs_s[start:start + chunk]
        m_x, m_glob = master_x[start:start + chunk], master_glob[start:start + chunk]
        dD, dM = np.empty((len(s), ns, ns + nm, 3)), np.empty((len(s), ns, nm, ns + nm, 3))
        dMx = np.empty((len(s), ns, ns + nm, 3, 3))
        here = of_covered[start:start + chunk] >= 0  # the pairs of partly covered facets: (L.6)
        whole = ~here
        if whole.any():
            _, _, dD[whole], dM[whole] = segment_jacobians(slave_x[s[whole]], -slave_normal[s[whole]], m_x[whole])
            # dM x: sum_b dM_ab x_b, (P, n_s, N, 3, 3) (a batched product, einsum is slow here)
            product = np.matmul(np.swapaxes(m_x[whole], 1, 2)[:, None], dM[whole].reshape(-1, ns, nm, 3 * (ns + nm)))
            dMx[whole] = product.reshape(-1, ns, 3, ns + nm, 3).transpose(0, 1, 3, 4, 2)
        if here.any():
            _, (dF, dG, dH) = basis_jacobians(slave_x[s[here]], -slave_normal[s[here]], m_x[here])
            dD[here], dM[here], dMx[here] = covered_entries(covered, of_covered[start:start + chunk][here], m_x[here],
                                                            (dF, dG, dH))
            covered_dF.append(dF)
            covered_dH.append(dH)
        pair_dM.append(dM)
        nodes = np.concatenate([slave_glob[s], m_glob], axis=1)  # (P, N): the pair's vertices
        rows.append(np.broadcast_to(slave_glob[s][:, :, None], dD.shape[:3]).ravel())
        cols.append(np.broadcast_to(nodes[:, None, :], dD.shape[:3]).ravel())
        values.append(np.concatenate([dD[..., None], dMx], axis=-1).reshape(-1, 12))
    cross = None if covered is None else CoveredDerivatives(covered.pairs, covered.facet, np.concatenate(covered_dF),
                                                            np.concatenate(covered_dH), covered.A, covered.Hinv,
                                                            covered.G)
    pairs = PairDerivatives(slave_glob[pairs_s], master_glob, np.concatenate(pair_dM), cross)
    return np.concatenate(rows), np.concatenate(cols), np.concatenate(values), pairs


def _summed_on_owners(comm: MPI.Comm, index_map, pair_entries: tuple, facet_entries: tuple) -> tuple:
    """The entries (row node, column node, values) of the pairs (values (E, 3, 4): dD, dM x per
    coordinate of the column node) and of the slave facets (E', 3, 3): da) summed on the owners
    of the rows: (rows, columns, (K, 3, 7)) over the union of their sorted (row, column) keys."""
    owners = owner_ranges(comm, index_map)
    pairs, facets = sum_to_owners(comm, owners, *pair_entries), sum_to_owners(comm, owners, *facet_entries)
    width = np.int64(index_map.size_global + 1)
    pair_keys, facet_keys = pairs[0] * width + pairs[1], facets[0] * width + facets[1]
    keys = np.union1d(pair_keys, facet_keys)
    summed = np.zeros((len(keys), 3, 7))
    summed[np.searchsorted(keys, pair_keys), :, :4] = pairs[2].reshape(-1, 3, 4)
    summed[np.searchsorted(keys, facet_keys), :, 4:] = facets[2].reshape(-1, 3, 3)
    return keys // width, keys % width, summed
