"""Segment-to-segment integration of a slave and a master facet: the mortar integrals of one pair.

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

Every function here takes plain arrays or :class:`~contactqvi.contact.dual.Dual` arrays
(forward-mode automatic differentiation): given the vertex coordinates as duals it returns
the integrals and their derivatives in one evaluation
(:mod:`contactqvi.contact.linearisation`). The integrals are differentiable in the
coordinates away from their branch decisions (which vertices a clipping edge keeps, a
polygon's orientation, the rule a pair takes); those are taken on the values, so the
derivatives are those of the branch the values take.
"""

from __future__ import annotations

import typing

import numpy as np

from contactqvi.contact.dual import primal
from contactqvi.contact.facets import (
    POLYGON_ORDER,
    area_elements,
    biquadratic_normals,
    biquadratic_shapes,
    dual_coefficients,
    length,
    magnitude,
    modified_dual,
    planar_jacobians,
    quadratic_normals,
    quadratic_shapes,
    quadrilateral_shapes,
    reference_coordinates,
    triangle_rule,
)

__all__ = ["AFFINE_DEGREE", "BIQUADRATIC_DEGREE", "QUADRILATERAL_DEGREE", "Surface", "basis_integrals",
           "clip_polygons", "curvature_integrals", "diameters", "edge_ties", "exact_surface_integrals",
           "normal_separation_integrals", "planar_basis_integrals", "planar_integrals", "plane_coordinates",
           "quadratic_segment_integrals", "segment_integrals", "slave_moments"]

class Surface(typing.Protocol):
    """An exact surface: the signed distance of points (n, 3) and the unit direction away from it
    (as :meth:`contactqvi.obstacles.Obstacle.distance`)."""

    def distance(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]: ...


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
#: :func:`clip_polygons`: a clipping edge with the whole polygon on its inner side up to this fraction
#: of its length does not clip it. Where a slave's and a master's facets meet edge on edge on a symmetry
#: plane through a flat interface (both ends held on the plane, the facets' tilt across it and the gap
#: vanishing at the solution), the master's edge lies off the slave's by their product, round-off and
#: below: cut by the sign of that, the segment was bounded by the master's edge or by the slave's, the
#: same polygon with other derivatives, a kink every iterate sat on with its side picked by round-off
#: (the 50 % compression's last step: a linear tail, 7 / 14 / 10 Newton steps on 1 / 2 / 3 ranks, now
#: 9 / 7 / 9, and 7 / 8 / 8 with covered.covered_basis taken at any sliver; docs/finite_strain.md
#: Sect. 22). The sliver a polygon left whole can reach past the edge is 1e-10 of it: an overlap of
#: that much changes D and M by that share of a facet.
CLIP_BAND = 1e-10
#: Degree of the rule for a pair of biquadratic (9-node) parallelograms: Φ_i N_j^m is of degree 4 in
#: each facet's reference coordinates, affine in the plane's, so of degree 8 on a flat pair (exact).
BIQUADRATIC_DEGREE = 8

def clip_polygons(polygon: np.ndarray, count: np.ndarray, clip: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sutherland-Hodgman: convex polygons clipped by convex counter-clockwise polygons, vectorised;
    an edge of ``clip`` with the whole polygon within :data:`CLIP_BAND` of its inner side leaves it
    whole (its vertices, not crossings, whichever side of the edge round-off puts them).

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
        nxt_index = (np.arange(K)[None, :] + 1) % np.maximum(count, 1)[:, None]
        s_cur = _side(primal(a)[:, None], primal(edge)[:, None], primal(polygon))  # the decisions: on values
        s_nxt = s_cur[rows[:, None], nxt_index]
        valid = np.arange(K)[None, :] < count[:, None]
        band = CLIP_BAND * np.sum(primal(edge) ** 2, axis=1)  # _side is |edge| times the distance
        inner = np.all((s_cur >= -band[:, None]) | ~valid, axis=1)[:, None]  # not clipped
        in_cur, in_nxt = (s_cur >= 0.0) | inner, (s_nxt >= 0.0) | inner
        # emitted per input vertex i: [crossing if the edge i -> i+1 crosses] then [nxt if nxt inside]
        emit_cross = valid & (in_cur != in_nxt)
        emit_next = valid & in_nxt
        emitted = np.stack([emit_cross, emit_next], axis=2).reshape(P, 2 * K)
        slots = np.cumsum(emitted, axis=1) - 1
        out = np.zeros((P, max(K, int(emitted.sum(axis=1).max(initial=0))), 2), like=polygon)
        p_idx, k_idx = np.nonzero(emit_cross)  # the crossings, of edges whose ends lie on either side
        current, nxt = polygon[p_idx, k_idx], polygon[p_idx, nxt_index[p_idx, k_idx]]
        a_cross, edge_cross = a[p_idx], edge[p_idx]
        side_cur, side_nxt = _side(a_cross, edge_cross, current), _side(a_cross, edge_cross, nxt)
        out[p_idx, slots[p_idx, 2 * k_idx]] = current + (side_cur / (side_cur - side_nxt))[:, None] * (nxt - current)
        p_idx, k_idx = np.nonzero(emit_next)
        out[p_idx, slots[p_idx, 2 * k_idx + 1]] = polygon[p_idx, nxt_index[p_idx, k_idx]]
        polygon, count = out, emitted.sum(axis=1)
    return polygon, count


def _side(a: np.ndarray, edge: np.ndarray, p: np.ndarray) -> np.ndarray:
    """edge x (p - a): positive where the points p lie left of the lines through a along edge."""
    return edge[..., 0] * (p[..., 1] - a[..., 1]) - edge[..., 1] * (p[..., 0] - a[..., 0])


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


def _edge_sides(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(P, L, K) :func:`_side` of the vertices of polygons ``b`` (P, K, 2) with respect to the edges
    of the counter-clockwise polygons ``a`` (P, L, 2)."""
    edges = np.roll(a, -1, axis=1) - a
    return _side(a[:, :, None], edges[:, :, None], b[:, None])


def _separated(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(P,) whether the polygons ``b`` (P, K, 2) lie strictly outside an edge of the convex
    counter-clockwise polygons ``a`` (P, L, 2): one half of a separating axis test."""
    return (_edge_sides(a, b) < 0.0).all(axis=2).any(axis=1)


def edge_ties(s2: np.ndarray, m2: np.ndarray) -> np.ndarray:
    """(P,) whether a vertex of a slave or master facet in the plane (:func:`plane_coordinates`)
    lies exactly on the line of an edge of the other: a tie of the clipping's decisions, where
    D and M have kinks (facets of conforming meshes, which share vertices)."""
    s_ccw, m_ccw = _counter_clockwise(s2)[0], _counter_clockwise(m2)[0]
    return (_edge_sides(s_ccw, m_ccw) == 0.0).any(axis=(1, 2)) | (_edge_sides(m_ccw, s_ccw) == 0.0).any(axis=(1, 2))


def _counter_clockwise(x2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Facets projected to the plane (P, n, 2), as counter-clockwise polygons, and their signed areas."""
    if x2.shape[1] == 3:
        area = _signed_area(x2)
        return np.where((area < 0.0)[:, None, None], x2[:, [0, 2, 1]], x2), area
    polygon = x2[:, POLYGON_ORDER[x2.shape[1]]]
    area = 0.5 * np.sum(polygon[..., 0] * np.roll(polygon[..., 1], -1, axis=1)
                        - np.roll(polygon[..., 0], -1, axis=1) * polygon[..., 1], axis=1)
    return np.where((area < 0.0)[:, None, None], polygon[:, ::-1], polygon), area


def plane_coordinates(slave: np.ndarray, normal: np.ndarray,
                      master: np.ndarray) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, np.ndarray]]:
    """Slave and master facets (P, n, 3), (P, m, 3) in coordinates of the slave facet's plane
    (normal ``normal``): the origin its vertex 0, the axes e1 along its first edge (projected
    onto a warped quadrilateral's mean plane) and e2 = normal x e1.

    Returns:
        ``(s2, m2, (e1, e2))``: (P, n, 2), (P, m, 2) and the axes (P, 3) each. s2[:, 0] and
        s2[:, 1, 1] are zero whatever the positions.
    """
    origin = slave[:, 0]
    e1 = slave[:, 1] - origin
    if slave.shape[1] == 4:  # the edge of a warped quadrilateral leaves its mean plane
        e1 -= np.einsum("ij,ij->i", e1, normal)[:, None] * normal
    e1 /= length(e1)[:, None]
    e2 = np.cross(normal, e1)
    return _plane_coordinates(origin, e1, e2, slave), _plane_coordinates(origin, e1, e2, master), (e1, e2)


def _overlapping_shadows(s2: np.ndarray, m2: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The facets in the plane (P, n, 2), (P, m, 2) as counter-clockwise polygons, and the pairs
    that may overlap there."""
    s_ccw, s_area = _counter_clockwise(s2)
    m_ccw, m_area = _counter_clockwise(m2)
    # a master facet seen edge-on has no shadow; most candidate pairs of a search are disjoint
    # (separating axis test, a tenth of the clipping's cost)
    shadow = np.abs(primal(m_area)) > 1e-12 * np.abs(primal(s_area))
    s_value, m_value = primal(s_ccw), primal(m_ccw)
    pairs = np.flatnonzero(shadow & ~_separated(s_value, m_value) & ~_separated(m_value, s_value))
    return s_ccw, m_ccw, pairs


def _shape_values(x2: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(P, Q, n) shape functions of facets projected to the plane (P, n, 2) at points (P, Q, 2)."""
    if x2.shape[1] == 3:
        return _barycentric(x2, points)
    return quadrilateral_shapes(reference_coordinates(x2, points))


def _slave_values(slave: np.ndarray, s2: np.ndarray, dual: np.ndarray | None,
                  points: np.ndarray) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """(P, Q, n) dual basis psi of slave facets at points (P, Q, 2) of their plane (of the bilinear
    or, with ``dual`` (P, 9, 9), the biquadratic functions of a quadrilateral), the ratio of the
    facet's area element to the plane's there and the points' reference coordinates (None, None:
    a flat triangle)."""
    if slave.shape[1] == 3:
        return 4.0 * _barycentric(s2, points) - 1.0, None, None
    xi = reference_coordinates(s2, points)
    ratio = area_elements(slave, xi) / planar_jacobians(s2, xi)
    shapes = quadrilateral_shapes(xi) if dual.shape[-1] == 4 else biquadratic_shapes(xi)
    return np.einsum("pik,pqk->pqi", dual, shapes), ratio, xi


def _affine(x: np.ndarray) -> np.ndarray:
    """(P,) whether facets (P, n, 3) have an affine map: triangles, and parallelograms to round-off."""
    if x.shape[1] == 3:
        return np.ones(len(x), dtype=bool)
    x = primal(x)
    return np.linalg.norm(x[:, 3] - x[:, 2] - x[:, 1] + x[:, 0], axis=1) <= 1e-12 * diameters(x)


def _rules(slave: np.ndarray, master: np.ndarray, degree: int | None,
           affine_degree: int = AFFINE_DEGREE) -> list[tuple[np.ndarray, tuple]]:
    """The pairs (a mask) integrated with each rule (barycentric points, weights): ``degree``
    if given; else degree 2 for two triangles and ``affine_degree`` for other pairs of
    affine facets (exact on a flat pair), :data:`QUADRILATERAL_DEGREE` for the rest."""
    if degree is not None:
        return [(np.ones(len(slave), dtype=bool), triangle_rule(degree))]
    if slave.shape[1] == master.shape[1] == 3:
        return [(np.ones(len(slave), dtype=bool), (_POINTS, _WEIGHTS))]
    affine = _affine(slave) & _affine(master)
    return [(affine, triangle_rule(affine_degree)), (~affine, triangle_rule(QUADRILATERAL_DEGREE))]


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
    s2, m2, _ = plane_coordinates(slave, normal, master)
    return planar_integrals(slave, s2, master, m2, degree)


def planar_integrals(slave: np.ndarray, s2: np.ndarray, master: np.ndarray, m2: np.ndarray,
                     degree: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """:func:`segment_integrals` of facet pairs from their :func:`plane_coordinates` s2 (P, n, 2)
    and m2 (P, m, 2). The facets' vertices serve a slave quadrilateral's area element and dual
    basis (unchanged by a rigid motion of the facet) and the choice of the rule."""
    P, ns, nm = len(slave), slave.shape[1], master.shape[1]
    D, M = np.zeros((P, ns), like=m2), np.zeros((P, ns, nm), like=m2)
    for rows, weights, psi, points, _ in _segment_points(slave, s2, master, m2, degree):
        phi_m = _shape_values(m2[rows], points)
        D[rows] += np.einsum("pq,pqi->pi", weights, psi)
        M[rows] += np.einsum("pq,pqi,pqj->pij", weights, psi, phi_m)
    return D, M


def basis_integrals(slave: np.ndarray, normal: np.ndarray, master: np.ndarray,
                    degree: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The integrals of the slave facet's own (Lagrange) basis phi over the segments of facet pairs,
    from which the dual basis of the covered part of a facet is built (:mod:`contactqvi.contact.mortar`,
    ``projecting``): the arguments of :func:`segment_integrals`.

    Returns:
        ``(F, G, H)``: (P, n) int phi_a, (P, n, m) int phi_a phi_j^m, (P, n, n) int phi_a phi_b over the
        part of the slave facet that the master facet covers; the rules of :func:`segment_integrals`,
        exact on flat pairs of triangles or parallelograms.
    """
    s2, m2, _ = plane_coordinates(slave, normal, master)
    return planar_basis_integrals(slave, s2, master, m2, degree)


def planar_basis_integrals(slave: np.ndarray, s2: np.ndarray, master: np.ndarray, m2: np.ndarray,
                           degree: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`basis_integrals` of facet pairs from their :func:`plane_coordinates` (as
    :func:`planar_integrals`)."""
    P, ns, nm = len(slave), slave.shape[1], master.shape[1]
    F, G, H = np.zeros((P, ns), like=m2), np.zeros((P, ns, nm), like=m2), np.zeros((P, ns, ns), like=m2)
    for rows, weights, _, points, xi in _segment_points(slave, s2, master, m2, degree):
        phi = _barycentric(s2[rows], points) if xi is None else quadrilateral_shapes(xi)
        phi_m = _shape_values(m2[rows], points)
        F[rows] += np.einsum("pq,pqi->pi", weights, phi)
        G[rows] += np.einsum("pq,pqi,pqj->pij", weights, phi, phi_m)
        H[rows] += np.einsum("pq,pqi,pqj->pij", weights, phi, phi)
    return F, G, H


def curvature_integrals(slave: np.ndarray, normal: np.ndarray, master: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The integrals that carry the curvature of quadratic (6-node) triangles into the mortar gap.

    A 6-node triangle is its vertices' flat triangle plus an edge bubble per edge,
    x(L) = sum_i x_i L_i + sum_k b_k(L) s_k with b_k = 4 L_(k+1) L_(k+2) and s_k the sagitta of
    edge k (its midside node less its ends' mean; edge k opposite vertex k). Over the segments
    of :func:`segment_integrals` (the flat triangles' clipped shadows), these are

        B_s[i, k] = int psi_i b_k,    B_m[i, k] = int psi_i (b_k^m o pi),

    pi the projection along ``normal`` onto the master's flat triangle. psi_i b_k is cubic on a
    flat pair; the rule is exact to degree 4. Triangles only: (P, 3, 3) vertices each.
    """
    s2, m2, _ = plane_coordinates(slave, normal, master)
    Bs, Bm = np.zeros((len(slave), 3, 3)), np.zeros((len(slave), 3, 3))
    for rows, weights, psi, points, _ in _segment_points(slave, s2, master, m2, 4):
        Bs[rows] += np.einsum("pq,pqi,pqk->pik", weights, psi, _edge_bubbles(_barycentric(s2[rows], points)))
        Bm[rows] += np.einsum("pq,pqi,pqk->pik", weights, psi, _edge_bubbles(_barycentric(m2[rows], points)))
    return Bs, Bm


def slave_moments(slave: np.ndarray, normal: np.ndarray, master: np.ndarray) -> np.ndarray:
    """(P, 3, 3) S[i, k] = int psi_i phi_k over the segments of pairs of linear triangles (as
    :func:`segment_integrals`): the slave part of the weighted separation, int psi_i x = sum_k S_ik x_k,
    over the part of the slave facet the master covers (D_ii delta_ik where it covers it all). Exact
    (a rule of degree 2)."""
    s2, m2, _ = plane_coordinates(slave, normal, master)
    S = np.zeros((len(slave), 3, 3))
    for rows, weights, psi, points, _ in _segment_points(slave, s2, master, m2, None):
        S[rows] += np.einsum("pq,pqi,pqk->pik", weights, psi, _barycentric(s2[rows], points))
    return S


def quadratic_segment_integrals(slave: np.ndarray, normal: np.ndarray,
                                master: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The mortar integrals of pairs of quadratic facets (quadratic displacements): 6-node triangles
    (``slave``, ``master``: (P, 3, 3) vertices) or 9-node quadrilaterals ((P, 4, 3)),

        D[i] = int Φ_i,    M[i, j] = int Φ_i (N_j^m o pi),    S[i, k] = int Φ_i N_k,

    Φ the slave's dual basis (of the modified basis of a triangle,
    :data:`~contactqvi.contact.facets.MODIFIED_DUAL`; of the biquadratic functions of a
    quadrilateral, with its vertices' area element), N^m the master's quadratic Lagrange
    functions (:func:`~contactqvi.contact.facets.quadratic_shapes`,
    :func:`~contactqvi.contact.facets.biquadratic_shapes`), over the segments of the facets'
    vertex polygons, pi the projection along ``normal`` (the slave's) onto the master's. Φ_i N_j^m
    is of degree 4 on a flat pair of triangles and of degree 8 on a pair of parallelograms: the
    rules are exact there. Curved facets enter through the positions of their nodes, which the
    weighted gap takes: S x (N the slave's own quadratic Lagrange functions) is its slave part,
    int Φ_i x_s, over the segments only; it is D_ii x̃_i where the master covers the slave facet
    (biorthogonality), and where it does not (a sliver at the rim of a surface, where the
    projection along a facet's tilted normal reaches a little past the master's edge), it stays
    the integral of the positions that are there, while x̃_i lies 2/3 of the edges' sagittas off
    the surface (docs/quadratic.md, Sect. 5)."""
    s2, m2, _ = plane_coordinates(slave, normal, master)
    n = 6 if slave.shape[1] == 3 else 9
    D, M, S = np.zeros((len(slave), n)), np.zeros((len(slave), n, n)), np.zeros((len(slave), n, n))
    for rows, weights, values in _quadratic_points(slave, s2, master, m2):
        D[rows] += np.einsum("pq,pqi->pi", weights, values.dual)
        M[rows] += np.einsum("pq,pqi,pqj->pij", weights, values.dual, values.master)
        S[rows] += np.einsum("pq,pqi,pqk->pik", weights, values.dual, values.slave)
    return D, M, S


class _QuadraticValues(typing.NamedTuple):
    """The functions of a pair of quadratic facets at the points of their segments (p, Q, n) each:
    the slave's dual basis Φ, its Lagrange functions N and the master's N^m at the projections,
    with the slave's reference (or barycentric) coordinates of the points."""

    dual: np.ndarray
    slave: np.ndarray
    master: np.ndarray
    coordinates: np.ndarray

    def slave_normals(self, nodes: np.ndarray) -> np.ndarray:
        """(p, Q, 3) unit normals of the slave facets of ``nodes`` (p, n, 3) at the points, not oriented."""
        if nodes.shape[1] == 6:
            return quadratic_normals(self.coordinates, nodes)
        return biquadratic_normals(self.coordinates, nodes)


def _quadratic_points(slave: np.ndarray, s2: np.ndarray, master: np.ndarray,
                      m2: np.ndarray) -> typing.Iterator[tuple[np.ndarray, np.ndarray, _QuadraticValues]]:
    """The quadrature of the segments of pairs of quadratic facets (their vertex polygons ``slave``,
    ``master`` and their :func:`plane_coordinates` ``s2``, ``m2``): per triangle of the clipped
    polygons' fans, the pairs (indices), the weights (p, Q) and the :class:`_QuadraticValues`. Pairs of
    triangles take the rule of degree 4; of quadrilaterals :data:`BIQUADRATIC_DEGREE` where both are
    parallelograms, else :data:`QUADRILATERAL_DEGREE`."""
    if slave.shape[1] == 3:
        for rows, weights, _, points, _ in _segment_points(slave, s2, master, m2, 4):
            Ls = _barycentric(s2[rows], points)
            yield rows, weights, _QuadraticValues(modified_dual(Ls), quadratic_shapes(Ls),
                                                  quadratic_shapes(_barycentric(m2[rows], points)), Ls)
        return
    for rows, weights, dual, points, xi in _segment_points(slave, s2, master, m2, None, BIQUADRATIC_DEGREE, 9):
        yield rows, weights, _QuadraticValues(dual, biquadratic_shapes(xi),
                                              biquadratic_shapes(reference_coordinates(m2[rows], points)), xi)


def exact_surface_integrals(slave: np.ndarray, normal: np.ndarray, master: np.ndarray,
                            slave_sagitta: np.ndarray | None, master_sagitta: np.ndarray | None,
                            surfaces: tuple[Surface, Surface], quadratic: bool) -> np.ndarray:
    """What the exact surfaces add to D_ii times the separation of slave node i, per facet pair:

        E[i] = int psi_i (nu (nu . (P_s x_s - P_m x_m)) - (x_s - x_m)),

    x_s and x_m the points of the slave facet and of its projection pi on the master facet as the
    discretisation has them (the vertex triangles, plus their edge bubbles b_k s_k where the
    sagittas s_k are given: curved facets), P_s and P_m the closest points of the exact slave and
    master surfaces ``surfaces`` (shapes with :meth:`~contactqvi.obstacles.Obstacle.distance`), nu
    the exact slave surface's unit normal at P_s x_s, psi the dual basis (the modified quadratic
    one's, Φ, if ``quadratic``). Added to the weighted separation of the discrete surfaces, it
    gives that of the exact ones along their normal: the two projections lie apart along the
    surfaces too, by about the facets' tilt times their sagittas (about 0.5 µm on the press fit's
    1.5 mm facets), which a nodal normal would take a part of (docs/press_fit.md, "Exact cylindrical
    surfaces"). Triangles (P, 3, 3); a rule of degree 4.
    """
    s2, m2, _ = plane_coordinates(slave, normal, master)
    E = np.zeros((len(slave), 6 if quadratic else 3, 3))
    for rows, weights, psi, points, _ in _segment_points(slave, s2, master, m2, 4):
        Ls, Lm = _barycentric(s2[rows], points), _barycentric(m2[rows], points)
        discrete, exact = [], []
        sides = ((Ls, slave, slave_sagitta, surfaces[0]), (Lm, master, master_sagitta, surfaces[1]))
        for L, x, sagitta, surface in sides:
            point = np.einsum("pqk,pkd->pqd", L, x[rows])
            if sagitta is not None:
                point += np.einsum("pqk,pkd->pqd", _edge_bubbles(L), sagitta[rows])
            distance, direction = surface.distance(point.reshape(-1, 3))
            discrete.append(point)
            exact.append((point.reshape(-1, 3) - distance[:, None] * direction, direction))
        nu = exact[0][1]
        along = np.einsum("qd,qd->q", nu, exact[0][0] - exact[1][0])[:, None] * nu
        if quadratic:
            psi = modified_dual(Ls)
        integrand = along.reshape(discrete[0].shape) - (discrete[0] - discrete[1])
        E[rows] += np.einsum("pq,pqi,pqd->pid", weights, psi, integrand)
    return E


def normal_separation_integrals(slave: np.ndarray, normal: np.ndarray, master: np.ndarray,
                                slave_nodes: np.ndarray, master_nodes: np.ndarray) -> np.ndarray:
    """(P, n, 3) what taking the separation along the curved slave surface's normal adds to D_ii
    times the separation of slave node i, per pair of quadratic facets (6-node triangles or 9-node
    quadrilaterals, quadratic displacements):

        E[i] = int Φ_i (nu (nu . (x_s - x_m)) - (x_s - x_m)),

    x_s = sum_k N_k x_k the slave facet's point (``slave_nodes`` (P, n, 3), in the order of
    :func:`quadratic_segment_integrals`' functions), x_m the master facet's (``master_nodes``) at
    its projection pi, nu the slave facet's unit normal at x_s, Φ the slave's dual basis; the
    segments are those of the vertex polygons ``slave``, ``master`` projected along ``normal``, as
    in :func:`quadratic_segment_integrals`. pi pairs the two curved surfaces through their vertex
    polygons, so x_m lies beside the foot of x_s's normal by about the facets' tilt times their
    sagittas (0.5 µm on the press fit's 1.5 mm facets), and a nodal normal takes a part of that
    tangential offset into the gap (docs/quadratic.md Sect. 5).
    """
    s2, m2, _ = plane_coordinates(slave, normal, master)
    E = np.zeros((len(slave), slave_nodes.shape[1], 3))
    for rows, weights, values in _quadratic_points(slave, s2, master, m2):
        x_s = np.einsum("pqk,pkd->pqd", values.slave, slave_nodes[rows])
        delta = x_s - np.einsum("pqk,pkd->pqd", values.master, master_nodes[rows])
        nu = values.slave_normals(slave_nodes[rows])
        integrand = np.einsum("pqd,pqd->pq", nu, delta)[..., None] * nu - delta
        E[rows] += np.einsum("pq,pqi,pqd->pid", weights, values.dual, integrand)
    return E


def _edge_bubbles(L: np.ndarray) -> np.ndarray:
    """(..., 3) b_k = 4 L_(k+1) L_(k+2) at barycentric coordinates L (..., 3)."""
    return 4.0 * L[..., [1, 2, 0]] * L[..., [2, 0, 1]]


def _segment_points(slave: np.ndarray, s2: np.ndarray, master: np.ndarray, m2: np.ndarray, degree: int | None,
                    affine_degree: int = AFFINE_DEGREE, nodes: int | None = None,
                    ) -> typing.Iterator[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]]:
    """The quadrature of the segments of facet pairs in the slave's plane (:func:`planar_integrals`):
    per triangle of the clipped polygons' fans, the pairs that have one (indices), the weights
    (p, Q) (a slave quadrilateral's true area element included), the slave's dual basis psi
    (p, Q, n; of a quadrilateral's biquadratic functions with ``nodes`` = 9), the points (p, Q, 2) and
    their reference coordinates in a slave quadrilateral (None for a triangle); the rules of
    :func:`_rules`."""
    ns, nm = slave.shape[1], master.shape[1]
    s_ccw, m_ccw, pairs = _overlapping_shadows(s2, m2)
    polygon = np.zeros((len(pairs), ns + nm, 2), like=m_ccw)  # clipping adds at most one vertex per clipping edge
    polygon[:, :nm] = m_ccw[pairs]
    polygon, count = clip_polygons(polygon, np.full(len(pairs), nm), s_ccw[pairs])
    dual = dual_coefficients(slave[pairs], nodes) if ns == 4 else None
    for group, rule in _rules(slave[pairs], master[pairs], degree, affine_degree):
        for k in range(1, polygon.shape[1] - 1):  # fan (v0, v_k, v_k+1)
            has = group & (count >= k + 2)
            if not has.any():
                continue
            tri = np.stack([polygon[has, 0], polygon[has, k], polygon[has, k + 1]], axis=1)
            area = magnitude(_signed_area(tri))
            points = np.einsum("qi,pij->pqj", rule[0], tri)
            psi, ratio, xi = _slave_values(slave[pairs[has]], s2[pairs[has]], None if dual is None else dual[has],
                                           points)
            weights = area[:, None] * rule[1][None, :]
            if ratio is not None:
                weights = weights * ratio
            yield pairs[has], weights, psi, points, xi


def diameters(x: np.ndarray) -> np.ndarray:
    """(f,) the largest distance between two vertices of each facet (f, n, 3): its longest edge
    (a triangle) or the longest of edges and diagonals (a quadrilateral)."""
    a, b = np.triu_indices(x.shape[1], k=1)
    return np.linalg.norm(x[:, a] - x[:, b], axis=2).max(axis=1, initial=0.0)
