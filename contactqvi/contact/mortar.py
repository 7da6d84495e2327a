"""Mortar coupling of two non-matching surfaces with a dual multiplier basis.

The contact conditions between a slave surface Gamma_s and a master surface
Gamma_m are imposed weakly, tested with the dual (biorthogonal) basis psi_i of the
slave nodes (Wohlmuth): on a linear triangle psi_i = 4 phi_i - 1, so that
int_T psi_i phi_k = delta_ik int_T phi_k; on a bilinear quadrilateral (hexahedral
meshes) psi = A phi with A = D_e M_e^{-1} from the facet's mass matrix
(:mod:`contactqvi.contact.facets`). The mortar matrices

    D_ii = int_{Gamma_s} psi_i,        M_ij = int_{Gamma_s} psi_i (phi_j^m o pi),

pi the projection of the slave surface onto the master surface along the slave
normal, give the weighted relative displacement of slave node i,

    w_i = u_i - sum_j C_ij u_j,    C = D^{-1} M,

which vanishes for every linear displacement field continuous across the
interface: sum_j M_ij p(x_j) = int psi_i p = D_ii p(x_i) for linear p (the contact
patch test). D_ii is integrated over the mortar segments, the parts of Gamma_s
that have a master facet, as int psi_i sum_k phi_k; with full coverage this is
int phi_i (the lumped area), and sum_j C_ij = 1 always, so rigid translations
of both bodies never open or close the interface.

Segment-to-segment integration (Puso-Laursen): each slave facet and each master
facet facing it (triangles or quadrilaterals, in any combination) are projected onto
the slave facet's plane (a quadrilateral's mean plane, normal to its diagonals'
cross product), the master polygon is clipped by the slave polygon
(Sutherland-Hodgman, convex clippers), the clipped polygon is split into a fan of
triangles and integrated there. The shape functions at a point of the plane are the
barycentric coordinates of a projected triangle, or the bilinear shape functions at
the reference coordinates of a projected quadrilateral (the inverse of its bilinear
map, Newton's method); a slave quadrilateral's integrals take its true area element
(the ratio of it to the plane's at the point). What is exact on a flat interface:
psi_i phi_j^m is quadratic on a pair of triangles (rule of degree 2) and a polynomial
of degree <= 4 on a pair of parallelograms or of a parallelogram and a triangle
(degree 4), so such interfaces are integrated exactly; on a quadrilateral that is no
parallelogram the inverse bilinear map is no polynomial, and a rule of degree 20
(:data:`QUADRILATERAL_DEGREE`) meets the integrals to about 1e-12 on strongly
distorted facets (a warped facet's area element too).

Parallel search: each rank owns the slave facets of its cells; it receives from
every rank the master facets that lie within ``search_distance`` of the bounding
box of its own slave facets (never a whole surface), pairs them by a k-d tree on
facet centroids, integrates, and sends the rows of ghost slave nodes to their
owners. Small deformations with small sliding per search: the search and the
integration take the geometry of a given configuration (the reference one, or the
deformed one of the last load step, :func:`mortar_coupling`'s ``displacement``); the
unknown stays the total displacement, so the weighted gap is taken between the
reference positions with the C of that configuration.
"""

from __future__ import annotations

import dataclasses

from mpi4py import MPI

import numpy as np
import scipy.spatial

from dolfinx import fem

from contactqvi.contact.facets import (
    POLYGON_ORDER,
    area_elements,
    dual_coefficients,
    nodal_integrals,
    planar_jacobians,
    quadrilateral_shapes,
    reference_coordinates,
    triangle_rule,
)
from contactqvi.parameters import require

__all__ = ["MortarCoupling", "clip_polygons", "mortar_coupling", "segment_integrals", "surface_facets"]

#: Degree-2 rule on a triangle (barycentric points, weights summing to 1): exact for
#: psi_i phi_j^m on a flat pair of linear triangles.
_POINTS = np.array([[2 / 3, 1 / 6, 1 / 6], [1 / 6, 2 / 3, 1 / 6], [1 / 6, 1 / 6, 2 / 3]])
_WEIGHTS = np.full(3, 1.0 / 3.0)
#: Degree of the rule on the triangles of a clipped polygon for a pair of parallelograms or of a
#: parallelogram and a triangle: psi_i phi_j^m is a polynomial of degree 4 on a flat pair (exact).
AFFINE_DEGREE = 4
#: ... and for a pair with a quadrilateral that is no parallelogram (distorted or warped): the
#: inverse bilinear map makes psi_i phi_j^m no polynomial, and the rule's error decays with its
#: degree. A flat interface of quadrilaterals moved by up to 0.3 of their size reproduces linear
#: fields to 8e-8 (degree 6), 9e-13 (12), 4e-16 (16); triangles cut into three quadrilaterals
#: (meshes/hex_on_split_tets.geo, as slave) to 3e-7 (12), 6e-9 (16), 5e-11 (20, 79 points),
#: 3e-14 (30), and the patch test on them as master to 3e-8, 6e-10, 4e-12 (tests/test_hex_mortar.py).
QUADRILATERAL_DEGREE = 20
#: Slave nodes whose mortar segments give D_ii below this fraction of their lumped
#: area are not coupled (they lie at the rim of the master's shadow).
MIN_COVERAGE = 0.5


@dataclasses.dataclass(frozen=True)
class SurfaceFacets:
    """Facets of a boundary surface, owned by this rank: linear triangles (tetrahedral
    meshes) or bilinear quadrilaterals (hexahedral meshes, vertices in tensor-product order).

    Attributes:
        blk: (f, n) local node (block) indices of the vertices (ghosts included), n = 3 or 4.
        x: (f, n, 3) vertex coordinates.
        normal: (f, 3) outward unit normals (away from the body; of a quadrilateral's mean
            plane, the cross product of its diagonals).
    """

    blk: np.ndarray
    x: np.ndarray
    normal: np.ndarray

    @property
    def area(self) -> np.ndarray:
        if self.x.shape[1] == 3:
            return 0.5 * np.linalg.norm(np.cross(self.x[:, 1] - self.x[:, 0], self.x[:, 2] - self.x[:, 0]), axis=1)
        return self.lumped.sum(axis=1)

    @property
    def lumped(self) -> np.ndarray:
        """(f, n) int phi_k: each vertex's lumped area."""
        return nodal_integrals(self.x)


#: Facets of a cell of DOLFINx's cell types with mortar contact, and how many vertices each has.
_CELL_FACETS = {"tetrahedron": (4, 3), "hexahedron": (6, 4)}


def surface_facets(V: fem.FunctionSpace, facets: np.ndarray, coords: np.ndarray | None = None) -> SurfaceFacets:
    """The owned exterior facets ``facets`` (local indices) of a P1 space on tetrahedra or a Q1
    space on hexahedra, with the node positions ``coords`` (local nodes, ghosts included;
    default the mesh's)."""
    msh = V.mesh
    tdim = msh.topology.dim
    cell_name = msh.topology.cell_name()
    require(cell_name in _CELL_FACETS, "mesh",
            f"mortar contact needs tetrahedral or hexahedral meshes, got {cell_name} cells")
    per_cell, n = _CELL_FACETS[cell_name]
    msh.topology.create_connectivity(tdim - 1, tdim)
    msh.topology.create_connectivity(tdim, tdim - 1)
    facets = np.asarray(facets, dtype=np.int32)
    facets = facets[facets < msh.topology.index_map(tdim - 1).size_local]
    f2c, c2f = msh.topology.connectivity(tdim - 1, tdim), msh.topology.connectivity(tdim, tdim - 1)
    cells = f2c.array[f2c.offsets[facets]]
    local = np.argmax(c2f.array.reshape(-1, per_cell)[cells] == facets[:, None], axis=1)
    closure = np.array([V.dofmap.dof_layout.entity_closure_dofs(tdim - 1, i) for i in range(per_cell)])
    cell_blk = V.dofmap.list[cells]
    blk = np.take_along_axis(cell_blk, closure[local], axis=1)
    coords = V.tabulate_dof_coordinates() if coords is None else coords
    x = coords[blk]
    if n == 3:
        normal = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    else:  # the diagonals v0 v3 and v1 v2
        normal = np.cross(x[:, 3] - x[:, 0], x[:, 2] - x[:, 1])
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    outward = np.einsum("ij,ij->i", normal, x.mean(axis=1) - coords[cell_blk].mean(axis=1)) > 0.0
    normal[~outward] *= -1.0
    return SurfaceFacets(blk.astype(np.int32), x, normal)


def clip_polygons(polygon: np.ndarray, count: np.ndarray, clip: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sutherland-Hodgman: convex polygons clipped by convex counter-clockwise polygons, vectorised.

    Args:
        polygon: (P, K, 2) vertices, counter-clockwise, the first ``count`` valid; K must
            leave room for one more vertex per edge of ``clip``.
        count: (P,) vertex counts.
        clip: (P, L, 2) counter-clockwise convex polygons (triangles, quadrilaterals), all
            of L vertices.

    Returns:
        ``(polygon, count)``: the intersections, (P, K', 2) and (P,); count < 3 means empty.
        K' > K only where round-off made a polygon degenerate (nearly coincident vertices on
        either side of a clipping edge: a half-plane then cuts it more than twice; seen on
        rotated surfaces, where coordinates carry 1e-17 noise).
    """
    P = polygon.shape[0]
    rows = np.arange(P)
    L = clip.shape[1]
    for e in range(L):
        K = polygon.shape[1]
        a, b = clip[:, e], clip[:, (e + 1) % L]
        edge = b - a

        def side(p: np.ndarray) -> np.ndarray:
            return edge[:, None, 0] * (p[..., 1] - a[:, None, 1]) - edge[:, None, 1] * (p[..., 0] - a[:, None, 0])

        nxt_index = (np.arange(K)[None, :] + 1) % np.maximum(count, 1)[:, None]
        nxt = polygon[rows[:, None], nxt_index]
        s_cur, s_nxt = side(polygon), side(nxt)
        valid = np.arange(K)[None, :] < count[:, None]
        in_cur, in_nxt = s_cur >= 0.0, s_nxt >= 0.0
        denom = np.where(s_cur - s_nxt == 0.0, 1.0, s_cur - s_nxt)
        crossing = polygon + (s_cur / denom)[..., None] * (nxt - polygon)
        # emitted per input vertex i: [crossing if the edge i -> i+1 crosses] then [nxt if nxt inside]
        emit_cross = valid & (in_cur != in_nxt)
        emit_next = valid & in_nxt
        slots = np.cumsum(np.stack([emit_cross, emit_next], axis=2).reshape(P, 2 * K), axis=1) - 1
        values = np.stack([crossing, nxt], axis=2).reshape(P, 2 * K, 2)
        emitted = np.stack([emit_cross, emit_next], axis=2).reshape(P, 2 * K)
        out = np.zeros((P, max(K, int(emitted.sum(axis=1).max(initial=0))), 2))
        p_idx, k_idx = np.nonzero(emitted)
        out[p_idx, slots[p_idx, k_idx]] = values[p_idx, k_idx]
        polygon, count = out, emitted.sum(axis=1)
    return polygon, count


def _plane_coordinates(origin: np.ndarray, e1: np.ndarray, e2: np.ndarray, x: np.ndarray) -> np.ndarray:
    d = x - origin[:, None, :]
    return np.stack([np.einsum("pj,pkj->pk", e1, d), np.einsum("pj,pkj->pk", e2, d)], axis=2)


def _barycentric(triangle: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(P, Q, 3) barycentric coordinates of (P, Q, 2) points in (P, 3, 2) triangles."""
    t = np.stack([triangle[:, 1] - triangle[:, 0], triangle[:, 2] - triangle[:, 0]], axis=2)  # (P, 2, 2)
    lam = np.linalg.solve(t[:, None], (points - triangle[:, None, 0])[..., None])[..., 0]
    return np.concatenate([1.0 - lam.sum(axis=2, keepdims=True), lam], axis=2)


def _signed_area(triangle: np.ndarray) -> np.ndarray:
    d1, d2 = triangle[:, 1] - triangle[:, 0], triangle[:, 2] - triangle[:, 0]
    return 0.5 * (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])


def _separated(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(P,) whether the polygons ``b`` (P, K, 2) lie strictly outside an edge of the convex
    counter-clockwise polygons ``a`` (P, L, 2): one half of a separating axis test."""
    separated = np.zeros(len(a), dtype=bool)
    L = a.shape[1]
    for e in range(L):
        p, edge = a[:, e], a[:, (e + 1) % L] - a[:, e]
        side = edge[:, None, 0] * (b[..., 1] - p[:, None, 1]) - edge[:, None, 1] * (b[..., 0] - p[:, None, 0])
        separated |= (side < 0.0).all(axis=1)
    return separated


def _counter_clockwise(x2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Facets projected to the plane (P, n, 2), as counter-clockwise polygons, and their signed areas."""
    if x2.shape[1] == 3:
        area = _signed_area(x2)
        return np.where((area < 0.0)[:, None, None], x2[:, [0, 2, 1]], x2), area
    polygon = x2[:, POLYGON_ORDER[x2.shape[1]]]
    area = 0.5 * np.sum(polygon[..., 0] * np.roll(polygon[..., 1], -1, axis=1)
                        - np.roll(polygon[..., 0], -1, axis=1) * polygon[..., 1], axis=1)
    return np.where((area < 0.0)[:, None, None], polygon[:, ::-1], polygon), area


def _projected_pairs(slave: np.ndarray, normal: np.ndarray, master: np.ndarray) -> tuple:
    """Slave and master facets in coordinates of the slave facet's plane (through its vertex 0,
    normal ``normal``), their counter-clockwise polygons, and the pairs that may overlap there."""
    origin = slave[:, 0]
    e1 = slave[:, 1] - origin
    if slave.shape[1] == 4:  # the edge of a warped quadrilateral leaves its mean plane
        e1 -= np.einsum("ij,ij->i", e1, normal)[:, None] * normal
    e1 /= np.linalg.norm(e1, axis=1)[:, None]
    e2 = np.cross(normal, e1)
    s2 = _plane_coordinates(origin, e1, e2, slave)
    m2 = _plane_coordinates(origin, e1, e2, master)
    s_ccw, s_area = _counter_clockwise(s2)
    m_ccw, m_area = _counter_clockwise(m2)
    # a master facet seen edge-on has no shadow; most candidate pairs of a search are disjoint
    # (separating axis test, a tenth of the clipping's cost)
    shadow = np.abs(m_area) > 1e-12 * np.abs(s_area)
    pairs = np.flatnonzero(shadow & ~_separated(s_ccw, m_ccw) & ~_separated(m_ccw, s_ccw))
    return s2, m2, s_ccw, m_ccw, pairs


def _shape_values(x2: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(P, Q, n) shape functions of facets projected to the plane (P, n, 2) at points (P, Q, 2)."""
    if x2.shape[1] == 3:
        return _barycentric(x2, points)
    return quadrilateral_shapes(reference_coordinates(x2, points))


def _slave_values(slave: np.ndarray, s2: np.ndarray, dual: np.ndarray | None,
                  points: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """(P, Q, n) dual basis psi of slave facets at points (P, Q, 2) of their plane, and the
    ratio of the facet's area element to the plane's there (None: 1, a flat triangle)."""
    if slave.shape[1] == 3:
        return 4.0 * _barycentric(s2, points) - 1.0, None
    xi = reference_coordinates(s2, points)
    ratio = area_elements(slave, xi) / planar_jacobians(s2, xi)
    return np.einsum("pik,pqk->pqi", dual, quadrilateral_shapes(xi)), ratio


def _affine(x: np.ndarray) -> np.ndarray:
    """(P,) whether facets (P, n, 3) have an affine map: triangles, and parallelograms to round-off."""
    if x.shape[1] == 3:
        return np.ones(len(x), dtype=bool)
    return np.linalg.norm(x[:, 3] - x[:, 2] - x[:, 1] + x[:, 0], axis=1) <= 1e-12 * _diameters(x)


def _rules(slave: np.ndarray, master: np.ndarray, degree: int | None) -> list[tuple[np.ndarray, tuple]]:
    """The pairs (a mask) integrated with each rule (barycentric points, weights): ``degree``
    if given; else degree 2 for two triangles and :data:`AFFINE_DEGREE` for other pairs of
    affine facets (exact on a flat pair), :data:`QUADRILATERAL_DEGREE` for the rest."""
    if degree is not None:
        return [(np.ones(len(slave), dtype=bool), triangle_rule(degree))]
    if slave.shape[1] == master.shape[1] == 3:
        return [(np.ones(len(slave), dtype=bool), (_POINTS, _WEIGHTS))]
    affine = _affine(slave) & _affine(master)
    return [(affine, triangle_rule(AFFINE_DEGREE)), (~affine, triangle_rule(QUADRILATERAL_DEGREE))]


def segment_integrals(slave: np.ndarray, normal: np.ndarray, master: np.ndarray,
                      degree: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Mortar integrals of pairs of a slave and a master facet (triangles or quadrilaterals).

    Args:
        slave: (P, n, 3) slave vertices (n = 3 or 4, quadrilaterals in tensor-product
            order); normal: (P, 3) unit normal of the slave facet (of its mean plane).
        master: (P, m, 3) master vertices.
        degree: of the rule on each triangle of the clipped polygons; None: exact where
            the pair's facets are triangles or parallelograms (:func:`_rules`), else
            :data:`QUADRILATERAL_DEGREE`.

    Returns:
        ``(D, M)``: (P, n) int psi_i and (P, n, m) int psi_i phi_j^m over the part of the
        slave facet that the master facet, projected onto the slave facet's plane along
        ``normal``, covers (zero where they do not overlap); quadrilaterals with their
        true area element.
    """
    P, ns, nm = len(slave), slave.shape[1], master.shape[1]
    s2, m2, s_ccw, m_ccw, pairs = _projected_pairs(slave, normal, master)
    polygon = np.zeros((len(pairs), ns + nm, 2))  # clipping adds at most one vertex per clipping edge
    polygon[:, :nm] = m_ccw[pairs]
    polygon, count = clip_polygons(polygon, np.full(len(pairs), nm), s_ccw[pairs])
    dual = dual_coefficients(slave[pairs]) if ns == 4 else None
    D, M = np.zeros((P, ns)), np.zeros((P, ns, nm))
    for group, rule in _rules(slave[pairs], master[pairs], degree):
        for k in range(1, polygon.shape[1] - 1):  # fan (v0, v_k, v_k+1)
            has = group & (count >= k + 2)
            if not has.any():
                continue
            tri = np.stack([polygon[has, 0], polygon[has, k], polygon[has, k + 1]], axis=1)
            area = np.abs(_signed_area(tri))
            points = np.einsum("qi,pij->pqj", rule[0], tri)
            psi, ratio = _slave_values(slave[pairs[has]], s2[pairs[has]], None if dual is None else dual[has], points)
            phi_m = _shape_values(m2[pairs[has]], points)
            weights = area[:, None] * rule[1][None, :]
            if ratio is not None:
                weights = weights * ratio
            D[pairs[has]] += np.einsum("pq,pqi->pi", weights, psi)
            M[pairs[has]] += np.einsum("pq,pqi,pqj->pij", weights, psi, phi_m)
    return D, M


@dataclasses.dataclass(frozen=True)
class MortarCoupling:
    """The mortar rows of the owned slave nodes of one contact pair.

    Attributes:
        slave_blk: (m,) owned local node indices of the coupled slave nodes, sorted.
        weight: (m,) D_ii (m^2), the lumped area of the node's mortar segments.
        C_indptr, C_master_glob, C_values: CSR rows of C = D^{-1} M for ``slave_blk``,
            columns the global node indices of master nodes; every row sums to 1.
        normal: (m, 3) unit nodal normals pointing from the master into the slave body
            (area-weighted averages of the slave facets' normals).
        separation: (m, 3) weighted separation of the reference positions
            x_i - sum_j C_ij x_j (m); the gap is its normal component.
    """

    slave_blk: np.ndarray
    weight: np.ndarray
    C_indptr: np.ndarray
    C_master_glob: np.ndarray
    C_values: np.ndarray
    normal: np.ndarray
    separation: np.ndarray

    @property
    def gap(self) -> np.ndarray:
        """(m,) weighted gap n_i . (x_i - sum_j C_ij x_j) of the reference positions (m)."""
        return np.einsum("ij,ij->i", self.normal, self.separation)


def _exchange_master(comm: MPI.Comm, slave: SurfaceFacets, master: SurfaceFacets,
                     master_glob: np.ndarray, padding: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Master facets (coordinates, global node indices, normals) within ``padding`` of
    this rank's slave facets' bounding box, gathered from the ranks that own them."""
    if len(slave.x):
        box = np.concatenate([slave.x.min(axis=(0, 1)) - padding, slave.x.max(axis=(0, 1)) + padding])
    else:
        box = np.array([np.inf] * 3 + [-np.inf] * 3)
    boxes = np.asarray(comm.allgather(box))  # one box per rank
    lo, hi = master.x.min(axis=1), master.x.max(axis=1)
    send = []
    for r in range(comm.size):
        near = np.all((hi >= boxes[r, :3]) & (lo <= boxes[r, 3:]), axis=1)
        send.append((master.x[near], master_glob[near], master.normal[near]))
    received = comm.alltoall(send)
    return tuple(np.concatenate([part[i] for part in received]) for i in range(3))


def mortar_coupling(V: fem.FunctionSpace, slave_facets: np.ndarray, master_facets: np.ndarray,
                    search_distance: float | None = None, excluded_blk: np.ndarray | None = None,
                    displacement: np.ndarray | None = None) -> MortarCoupling:
    """C = D^{-1} M, nodal normals and weighted gaps of a slave and a master surface.

    Args:
        V: vector P1 (tetrahedra) or Q1 (hexahedra) space on the mesh holding both bodies.
        slave_facets, master_facets: local facet indices of the two surfaces.
        search_distance: master facets farther than this from a slave facet
            (between bounding boxes, m) are not paired with it; None: the slave
            facet's longest edge.
        excluded_blk: local node indices never coupled (e.g. clamped slave nodes).
        displacement: (local nodes, 3) displacement of the configuration searched
            (ghosts included); None: the reference configuration.

    Collective. Slave nodes with less than :data:`MIN_COVERAGE` of their lumped area
    in the master's shadow are left out, and so are nodes whose weighted gap in the
    searched configuration exceeds ``search_distance`` (default: the node's own size
    sqrt(2 x lumped area)).
    """
    comm, index_map, x = V.mesh.comm, V.dofmap.index_map, V.tabulate_dof_coordinates()
    current = x if displacement is None else x + displacement
    slave, master = surface_facets(V, slave_facets, current), surface_facets(V, master_facets, current)
    master_glob = index_map.local_to_global(master.blk.ravel()).reshape(master.blk.shape)
    diameter = max(_max_edge(slave.x, comm), _max_edge(master.x, comm))
    reach = 2.0 * diameter + (diameter if search_distance is None else search_distance)
    mx, mglob, mnormal = _exchange_master(comm, slave, master, master_glob, reach)

    # candidate pairs: centroids within reach, bounding boxes within search_distance, facing normals
    pairs_s, pairs_m = _candidate_pairs(slave.x, slave.normal, mx, search_distance)
    facing = np.einsum("ij,ij->i", slave.normal[pairs_s], mnormal[pairs_m]) < 0.0
    pairs_s, pairs_m, D_pair, M_pair = _overlapping(slave, mx, pairs_s[facing], pairs_m[facing])

    weight, lumped_area, normal, M = _owned_sums(comm, index_map, slave, pairs_s, mglob[pairs_m], D_pair, M_pair)
    coupled = (lumped_area > 0.0) & (weight >= MIN_COVERAGE * lumped_area)
    if excluded_blk is not None:
        coupled[excluded_blk[excluded_blk < index_map.size_local]] = False
    slave_blk = np.flatnonzero(coupled).astype(np.int32)

    rows_loc = M[0] - index_map.local_range[0]
    keep = coupled[rows_loc]
    order = np.lexsort((M[1][keep], rows_loc[keep]))
    rows_loc, cols, values = rows_loc[keep][order], M[1][keep][order], M[2][keep][order]
    values = values / weight[rows_loc]
    position = np.searchsorted(slave_blk, rows_loc)
    indptr = np.concatenate([[0], np.cumsum(np.bincount(position, minlength=len(slave_blk)))]).astype(np.int64)

    n = normal[slave_blk]
    n /= np.linalg.norm(n, axis=1)[:, None]
    positions = x if displacement is None else np.hstack([x, current])  # reference, searched: fetched together
    projected = np.zeros((len(slave_blk), positions.shape[1]))
    np.add.at(projected, position, values[:, None] * _master_coordinates(comm, index_map, positions, cols))
    separation = positions[slave_blk] - projected
    coupling = MortarCoupling(slave_blk, weight[slave_blk], indptr, cols.astype(np.int64), values, n,
                              separation[:, :3])
    # a node farther than the search distance (default: its own size) cannot touch in this step
    reach = np.sqrt(2.0 * lumped_area[slave_blk]) if search_distance is None else search_distance
    return _restricted(coupling, np.einsum("ij,ij->i", n, separation[:, -3:]) <= reach)


#: Candidate pairs integrated at a time by :func:`_overlapping` (bounds its work arrays to about 100 MB)
#: for two triangles (3 points per triangle of a clipped polygon); with a quadrilateral, whose
#: rules have up to 79 points and up to 6 triangles per polygon, a 32nd of it.
_CHUNK = 1 << 16
_QUADRILATERAL_CHUNK = 1 << 11


def _overlapping(slave: SurfaceFacets, master_x: np.ndarray, pairs_s: np.ndarray,
                 pairs_m: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The candidate pairs whose facets overlap, with their :func:`segment_integrals`.

    The candidates are the pairs within the search distance; most do not overlap
    (two-body Hertz medium mesh, search distance 5 mm: 20 000 of the 26 448 entries of
    C were zeros), and their zero entries made A = T^T A_K T twice as large as its
    nonzeros (4.1 M entries, 2.0 M nonzero): dense mortar rows of zeros that GAMG
    aggregated across and every product carried. Integrated in chunks, the work
    arrays stay bounded (all at once they took 390 MB on the fine mesh).
    """
    kept = []
    chunk = _CHUNK if slave.x.shape[1] == master_x.shape[1] == 3 else _QUADRILATERAL_CHUNK
    for start in range(0, len(pairs_s), chunk):
        s, m = pairs_s[start:start + chunk], pairs_m[start:start + chunk]
        D, M = segment_integrals(slave.x[s], -slave.normal[s], master_x[m])
        overlap = np.any(M != 0.0, axis=(1, 2))
        kept.append((s[overlap], m[overlap], D[overlap], M[overlap]))
    if not kept:
        ns, nm = slave.x.shape[1], master_x.shape[1]
        return np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64), np.empty((0, ns)), np.empty((0, ns, nm))
    return tuple(np.concatenate(parts) for parts in zip(*kept))


def _owned_sums(comm: MPI.Comm, index_map, slave: SurfaceFacets, pairs_s: np.ndarray, master_glob: np.ndarray,
                D_pair: np.ndarray, M_pair: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple]:
    """Sum the pairs' contributions on the owners of the slave nodes.

    Returns, over the owned nodes: D_ii, the lumped slave area, the area-weighted
    normal sum (pointing into the slave body), and the owned entries (rows, cols,
    values) of M with global node indices.
    """
    slave_glob = index_map.local_to_global(slave.blk.ravel()).reshape(slave.blk.shape)
    ns, nm = slave_glob.shape[1], master_glob.shape[1]
    owners = _owners(comm, index_map)
    rows = slave_glob[pairs_s].ravel()
    D = _sum_to_owners(comm, owners, rows, np.zeros_like(rows), D_pair.ravel())
    M = _sum_to_owners(comm, owners, np.repeat(slave_glob[pairs_s], nm, axis=1).ravel(),
                       np.tile(master_glob, (1, ns)).ravel(), M_pair.ravel())
    nodes = slave_glob.ravel()
    area = _sum_to_owners(comm, owners, nodes, np.zeros_like(nodes), slave.lumped.ravel())
    normal_values = np.repeat(slave.area[:, None] * -slave.normal, ns, axis=0)
    start, n_owned = index_map.local_range[0], index_map.size_local
    weight, lumped_area, normal = np.zeros(n_owned), np.zeros(n_owned), np.zeros((n_owned, 3))
    weight[D[0] - start] = D[2]
    lumped_area[area[0] - start] = area[2]
    for k in range(3):
        summed = _sum_to_owners(comm, owners, nodes, np.zeros_like(nodes), normal_values[:, k])
        normal[summed[0] - start, k] = summed[2]
    return weight, lumped_area, normal, M


def _restricted(coupling: MortarCoupling, keep: np.ndarray) -> MortarCoupling:
    """The rows ``keep`` of ``coupling``."""
    lengths = np.diff(coupling.C_indptr)
    entries = np.repeat(keep, lengths)
    indptr = np.concatenate([[0], np.cumsum(lengths[keep])]).astype(np.int64)
    return MortarCoupling(coupling.slave_blk[keep], coupling.weight[keep], indptr, coupling.C_master_glob[entries],
                          coupling.C_values[entries], coupling.normal[keep], coupling.separation[keep])


def _diameters(x: np.ndarray) -> np.ndarray:
    """(f,) the largest distance between two vertices of each facet (f, n, 3): its longest edge
    (a triangle) or the longest of edges and diagonals (a quadrilateral)."""
    a, b = np.triu_indices(x.shape[1], k=1)
    return np.linalg.norm(x[:, a] - x[:, b], axis=2).max(axis=1, initial=0.0)


def _max_edge(x: np.ndarray, comm: MPI.Comm) -> float:
    return comm.allreduce(float(_diameters(x).max(initial=0.0)), op=MPI.MAX)


def _candidate_pairs(slave_x: np.ndarray, slave_normal: np.ndarray, master_x: np.ndarray,
                     search_distance: float | None) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs (slave, master) whose bounding boxes are within the search distance
    (``None``: each slave facet's own diameter, so graded meshes pair locally) and whose
    centroids lie closer along the slave facet's plane than the sum of their diameters
    (:func:`_diameters`): every point of a facet lies within its diameter of its vertices'
    mean, so other pairs cannot overlap in projection (two-body Hertz fine mesh,
    search distance 5 mm: 77 k of 266 k candidates kept, 13 k overlap)."""
    if len(slave_x) == 0 or len(master_x) == 0:
        return np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64)
    slave_edge, master_edge = _diameters(slave_x), _diameters(master_x)
    pad = slave_edge if search_distance is None else np.full(len(slave_x), search_distance)
    slave_c, master_c = slave_x.mean(axis=1), master_x.mean(axis=1)
    pairs_s, pairs_m = _near_centroids(slave_c, slave_edge + pad, master_c, master_edge)
    d, n = master_c[pairs_m] - slave_c[pairs_s], slave_normal[pairs_s]
    along = d - np.einsum("ij,ij->i", d, n)[:, None] * n
    near = np.einsum("ij,ij->i", along, along) <= (slave_edge[pairs_s] + master_edge[pairs_m]) ** 2
    pairs_s, pairs_m = pairs_s[near], pairs_m[near]
    lo_s, hi_s = slave_x.min(axis=1)[pairs_s], slave_x.max(axis=1)[pairs_s]
    lo_m, hi_m = master_x.min(axis=1)[pairs_m], master_x.max(axis=1)[pairs_m]
    padding = pad[pairs_s, None]
    near = np.all((hi_m >= lo_s - padding) & (lo_m <= hi_s + padding), axis=1)
    return pairs_s[near], pairs_m[near]


def _near_centroids(slave_c: np.ndarray, slave_r: np.ndarray, master_c: np.ndarray,
                    master_r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs (i, j) with |slave_c[i] - master_c[j]| <= slave_r[i] + master_r[j].

    Facets are binned by size (powers of two) and each pair of bins queried with its
    largest radius, so a graded mesh's large facets do not widen the small ones' search.
    """
    def bins(r: np.ndarray) -> np.ndarray:
        return np.floor(np.log2(np.maximum(r, 1e-300))).astype(np.int64)

    slave_bin, master_bin = bins(slave_r), bins(master_r)
    master_sets = []
    for b in np.unique(master_bin):
        idx = np.flatnonzero(master_bin == b)
        master_sets.append((idx, scipy.spatial.cKDTree(master_c[idx]), master_r[idx].max()))
    found_s, found_m = [np.empty(0, dtype=np.int64)], [np.empty(0, dtype=np.int64)]
    for b in np.unique(slave_bin):
        s_idx = np.flatnonzero(slave_bin == b)
        tree = scipy.spatial.cKDTree(slave_c[s_idx])
        for m_idx, master_tree, m_reach in master_sets:
            near = tree.sparse_distance_matrix(master_tree, float(slave_r[s_idx].max() + m_reach), output_type="ndarray")
            i, j = s_idx[near["i"]], m_idx[near["j"]]
            keep = near["v"] <= slave_r[i] + master_r[j]
            found_s.append(i[keep])
            found_m.append(j[keep])
    return np.concatenate(found_s), np.concatenate(found_m)


def _owners(comm: MPI.Comm, index_map) -> np.ndarray:
    """Start of each rank's range of global node indices, and the total, (size + 1,)."""
    starts = comm.allgather(index_map.local_range[0])
    return np.array([*starts, index_map.size_global], dtype=np.int64)


def _sum_to_owners(comm: MPI.Comm, owners: np.ndarray, rows: np.ndarray, cols: np.ndarray,
                   values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Send entries (row, col, value) to the owner of ``row`` and sum duplicates there.

    Returns the owned entries ``(rows, cols, values)``, unique (row, col) pairs.
    """
    rows, cols = np.asarray(rows, dtype=np.int64), np.asarray(cols, dtype=np.int64)
    rank = np.searchsorted(owners, rows, side="right") - 1
    order = np.argsort(rank, kind="stable")
    bounds = np.searchsorted(rank[order], np.arange(comm.size + 1))
    send = [(rows[order[a:b]], cols[order[a:b]], values[order[a:b]]) for a, b in zip(bounds[:-1], bounds[1:])]
    received = comm.alltoall(send)
    rows = np.concatenate([part[0] for part in received])
    cols = np.concatenate([part[1] for part in received])
    values = np.concatenate([part[2] for part in received])
    width = owners[-1] + 1  # global node indices are < width: one int64 key per (row, col)
    keys, inverse = np.unique(rows * width + cols, return_inverse=True)
    summed = np.bincount(inverse.ravel(), weights=values, minlength=len(keys))
    return keys // width, keys % width, summed


def _master_coordinates(comm: MPI.Comm, index_map, x: np.ndarray, glob: np.ndarray) -> np.ndarray:
    """Rows of ``x`` (owned nodes first, any width) of the nodes with global indices ``glob``,
    fetched from their owners."""
    owners = _owners(comm, index_map)
    rank = np.searchsorted(owners, glob, side="right") - 1
    order = np.argsort(rank, kind="stable")
    bounds = np.searchsorted(rank[order], np.arange(comm.size + 1))
    requests = comm.alltoall([glob[order[a:b]] for a, b in zip(bounds[:-1], bounds[1:])])
    start = index_map.local_range[0]
    replies = comm.alltoall([x[r - start] for r in requests])
    result = np.empty((len(glob), x.shape[1]))
    result[order] = np.concatenate(replies) if replies else np.empty((0, x.shape[1]))
    return result
