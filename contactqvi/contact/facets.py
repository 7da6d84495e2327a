"""Reference geometry of contact facets: linear triangles and bilinear quadrilaterals.

The mortar integrals (:mod:`contactqvi.contact.mortar`) need, on a slave or master
facet, the shape functions phi at points given in a plane (the slave facet's plane,
onto which both facets are projected), and on a slave facet the dual basis psi.

* Triangles (facets of tetrahedra, vertices v0 v1 v2): phi are the barycentric
  coordinates, affine in the plane; psi_i = 4 phi_i - 1.
* Quadrilaterals (facets of hexahedra, DOLFINx's tensor-product order: v0 (0, 0),
  v1 (1, 0), v2 (0, 1), v3 (1, 1); round the polygon v0 v1 v3 v2): the bilinear map
  x(xi) = sum_k phi_k(xi) x_k. A point of the plane has reference coordinates xi of
  the projected bilinear map, found by Newton's method (:func:`reference_coordinates`);
  on a parallelogram the map is affine and the first step is exact. The dual basis
  psi = A phi with A = D_e M_e^{-1} (Popp, Gee, Wall 2009, IJNME 79), D_e = diag int phi_k,
  M_e = int phi_j phi_k over the facet with its true area element |x_xi x x_eta|
  (8 x 8 Gauss points: exact on a flat facet, whose area element is bilinear; on a facet
  warped by 0.3 of its size, whose area element is no polynomial, to 1e-15), so that
  int psi_i phi_k = delta_ik int phi_k. On a parallelogram A is the tensor product of the
  1D duals 2 phi_0 - phi_1: psi_0 = 4 phi_0 - 2 phi_1 - 2 phi_2 + phi_3.
* Quadratic triangles (facets of 10-node tetrahedra, vertices v0 v1 v2, then the midside
  node of the edge opposite each): the Lagrange functions N_v = L_v (2 L_v - 1),
  N_(3+k) = 4 L_(k+1) L_(k+2) of the barycentric coordinates L, and on a slave facet the
  modified basis Ñ of Popp, Wohlmuth, Gee and Wall (2012, Sect. 3; docs/quadratic.md (1)),
  Ñ_v = N_v + alpha sum_(k != v) N_(3+k), Ñ_(3+k) = (1 - 2 alpha) N_(3+k), whose dual basis
  Φ = A Ñ, A = D_e M_e^{-1}, is one matrix on every flat facet (:data:`MODIFIED_DUAL`).
* Biquadratic quadrilaterals (facets of 27-node hexahedra, quadratic displacements): the nine
  Lagrange functions of basix's quadrilateral of degree 2, in the order of the facet's closure
  (the vertices in tensor-product order, the midside nodes of the edges v0 v1, v0 v2, v1 v3,
  v2 v3, the centre), of the reference coordinates of the vertices' bilinear map. Each of them
  has a positive integral (on a parallelogram 1/36, 1/9 and 4/9 of the area at a vertex, an edge
  and the centre), so the slave surface needs no modified basis (Popp, Wohlmuth, Gee and Wall
  2012, Sect. 3: it is the 8-node serendipity facet whose vertex functions integrate to a
  negative number): the dual basis is Φ = A N, A = D_e M_e^{-1} with the vertex quadrilateral's
  area element, as on a bilinear facet.
"""

from __future__ import annotations

import basix
import numpy as np

from contactqvi.contact.dual import Dual, primal

__all__ = ["ALPHA", "MODIFIED_AREAS", "MODIFIED_DUAL", "POLYGON_ORDER", "area_elements", "biquadratic_normals",
           "biquadratic_shapes", "dual_coefficients", "facet_areas", "length", "magnitude", "modified_dual",
           "modified_shapes", "nodal_integrals", "planar_jacobians", "quadratic_normals", "quadratic_shapes",
           "quadrilateral_shapes", "reference_coordinates", "triangle_rule", "unit_normals"]

#: The vertices of a facet with n vertices in the order round its polygon.
POLYGON_ORDER = {3: [0, 1, 2], 4: [0, 1, 3, 2]}
#: Newton iterations of :func:`reference_coordinates` stop at this change of xi (reference units).
NEWTON_TOL = 1e-14
#: ... or where the steps stop falling below this (at least halving no more): the map of a
#: thin quadrilateral (a master facet seen nearly edge-on from the slave's plane, whose
#: Jacobian is 3e-4 of its squared size) is ill-conditioned, and round-off holds its steps
#: near 1e-14 (measured: 1.2e-14 after the 10th and every later step).
ROUND_OFF_TOL = 1e-10
NEWTON_MAX_IT = 25


def length(v: np.ndarray, axis: int = -1) -> np.ndarray:
    """Euclidean length along ``axis``, sqrt(sum v_k^2): the arithmetic of ``np.linalg.norm``,
    written with the operations a :class:`~contactqvi.contact.dual.Dual` differentiates."""
    return np.sqrt(np.sum(v * v, axis=axis))


def magnitude(a: np.ndarray) -> np.ndarray:
    """|a|, ``np.abs`` written as a branch on the value's sign (a :class:`~contactqvi.contact.dual.Dual`
    then carries the derivative of the side taken)."""
    return np.where(a < 0.0, -a, a)


def unit_normals(x: np.ndarray) -> np.ndarray:
    """(P, 3) unit normals of facets (P, n, 3), not oriented: a triangle's (v1 - v0) x (v2 - v0),
    a quadrilateral's mean plane, the cross product of its diagonals v0 v3 and v1 v2."""
    if x.shape[1] == 3:
        normal = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    else:
        normal = np.cross(x[:, 3] - x[:, 0], x[:, 2] - x[:, 1])
    return normal / length(normal)[:, None]


def triangle_rule(degree: int) -> tuple[np.ndarray, np.ndarray]:
    """Barycentric points (Q, 3) and weights (Q,) summing to 1 of basix's rule of ``degree``
    on a triangle (exact for polynomials of that degree)."""
    points, weights = basix.make_quadrature(basix.CellType.triangle, degree)
    return np.column_stack([1.0 - points.sum(axis=1), points]), weights / weights.sum()


def quadrilateral_shapes(xi: np.ndarray) -> np.ndarray:
    """(..., 4) bilinear shape functions at reference points (..., 2), tensor-product order."""
    s, t = xi[..., 0], xi[..., 1]
    return np.stack([(1.0 - s) * (1.0 - t), s * (1.0 - t), (1.0 - s) * t, s * t], axis=-1)


def _tangents(x: np.ndarray, xi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """dx/dxi and dx/deta of the bilinear map of vertices x (P, 4, d) at points xi (P, Q, 2): (P, Q, d) each."""
    s, t = xi[..., 0, None], xi[..., 1, None]
    b, c = x[:, None, 1] - x[:, None, 0], x[:, None, 2] - x[:, None, 0]
    d = x[:, None, 3] - x[:, None, 2] - x[:, None, 1] + x[:, None, 0]
    return b + d * t, c + d * s


def area_elements(x: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """(P, Q) area element |x_xi x x_eta| of quadrilaterals (P, 4, 3) at points xi (P, Q, 2)."""
    x_s, x_t = _tangents(x, xi)
    return length(np.cross(x_s, x_t))


def planar_jacobians(x2: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """(P, Q) |det| of the bilinear maps of planar quadrilaterals (P, 4, 2) at points xi (P, Q, 2)."""
    x_s, x_t = _tangents(x2, xi)
    return magnitude(x_s[..., 0] * x_t[..., 1] - x_s[..., 1] * x_t[..., 0])


def _bilinear_map(x2: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """x(xi) = a + b s + c t + d s t of planar quadrilaterals (P, 4, 2): (b, c, d, points - a), (P, 1, 2)
    and (P, Q, 2)."""
    a, b, c = x2[:, None, 0], x2[:, None, 1] - x2[:, None, 0], x2[:, None, 2] - x2[:, None, 0]
    d = x2[:, None, 3] - x2[:, None, 2] - x2[:, None, 1] + x2[:, None, 0]
    return b, c, d, points - a


def _newton_step(b: np.ndarray, c: np.ndarray, d: np.ndarray, target: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """The step J^{-1} (x(xi) - point) of :func:`reference_coordinates` at xi (P, Q, 2)."""
    s, t = xi[..., 0, None], xi[..., 1, None]
    x_s, x_t = b + d * t, c + d * s
    residual = s * x_s + c * t - target  # a + b s + c t + d s t - point
    det = x_s[..., 0] * x_t[..., 1] - x_s[..., 1] * x_t[..., 0]
    return np.stack([x_t[..., 1] * residual[..., 0] - x_t[..., 0] * residual[..., 1],
                     x_s[..., 0] * residual[..., 1] - x_s[..., 1] * residual[..., 0]], axis=-1) / det[..., None]


def reference_coordinates(x2: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Reference coordinates (P, Q, 2) of points (P, Q, 2) of the plane in the bilinear maps
    of planar quadrilaterals (P, 4, 2): Newton's method, all points at once, started from
    the centre (the first step is exact on a parallelogram; on the distorted facets of
    meshes/hertz_bodies_hex_coarse.geo 6 iterations, 7 from the vertex v0), until the
    steps are below :data:`NEWTON_TOL` or stall at round-off (:data:`ROUND_OFF_TOL`).
    On :class:`~contactqvi.contact.dual.Dual` arguments the iteration runs on the values, and
    the derivatives are those of its solution, -(J^{-1} r)' at the residual r(xi) = 0
    (implicit differentiation; Griewank and Walther, "Evaluating Derivatives", SIAM 2008, Ch. 15).

    Points where Newton's method does not converge (a degenerate or non-convex quadrilateral: a
    deformed facet seen edge-on) get NaN, which the mortar integrals carry to the caller
    (:func:`~contactqvi.contact.mortar.mortar_coupling`: a mesh error in the reference
    configuration, an undefined contact geometry in a deformed one).
    """
    if isinstance(x2, Dual) or isinstance(points, Dual):
        xi = reference_coordinates(primal(x2), primal(points))
        return Dual(xi, -_newton_step(*_bilinear_map(x2, points), xi).tangent)
    b, c, d, target = _bilinear_map(x2, points)
    xi = np.full(points.shape, 0.5)
    previous = np.inf
    with np.errstate(divide="ignore", invalid="ignore"):
        for _ in range(NEWTON_MAX_IT):
            step = _newton_step(b, c, d, target, xi)
            xi -= step
            largest = np.abs(step).max(initial=0.0)
            if largest <= NEWTON_TOL or (largest <= ROUND_OFF_TOL and largest >= 0.5 * previous):
                return xi
            previous = largest
    xi[~(np.abs(step).max(axis=-1) <= ROUND_OFF_TOL)] = np.nan
    return xi


#: 8 x 8 Gauss points on the unit square and weights summing to 1: exact for bilinear x bilinear
#: x the (bilinear) area element of a flat quadrilateral; the mass matrix of one warped by 0.3 of
#: its size to 1.4e-15 (3 x 3 points: 7.6e-6, 6 x 6: 3.3e-12), a few operations per facet.
_GAUSS_POINTS, _GAUSS_WEIGHTS = basix.make_quadrature(basix.CellType.quadrilateral, 15)
_GAUSS_WEIGHTS = _GAUSS_WEIGHTS / _GAUSS_WEIGHTS.sum()


def _facet_mass(x: np.ndarray, nodes: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """Lumped masses D_e (P, n) = int phi_k and mass matrices M_e (P, n, n) of quadrilaterals (P, 4, 3)
    with the area element of their bilinear map: of the bilinear functions (``nodes`` 4) or the
    biquadratic ones (9; the rule is exact for them too on a flat facet)."""
    xi = np.broadcast_to(_GAUSS_POINTS, (len(x), *_GAUSS_POINTS.shape))
    weights = area_elements(x, xi) * _GAUSS_WEIGHTS
    phi = (quadrilateral_shapes if nodes == 4 else biquadratic_shapes)(_GAUSS_POINTS)
    return np.einsum("pq,qk->pk", weights, phi), np.einsum("pq,qj,qk->pjk", weights, phi, phi)


def nodal_integrals(x: np.ndarray, nodes: int | None = None) -> np.ndarray:
    """(P, n) int phi_k of facets (P, n, 3): the lumped area of each vertex (area / 3 on a triangle);
    with ``nodes`` = 9 of each node of the biquadratic functions on quadrilaterals."""
    if x.shape[1] == 3:
        area = 0.5 * length(np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]))
        return np.repeat(area[:, None] / 3.0, 3, axis=1)
    return _facet_mass(x, nodes or 4)[0]


def facet_areas(x: np.ndarray) -> np.ndarray:
    """(P,) areas of facets (P, n, 3): a triangle's half cross product, a quadrilateral's
    sum of its lumped areas (its true area)."""
    if x.shape[1] == 3:
        return 0.5 * length(np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]))
    return nodal_integrals(x).sum(axis=1)


def dual_coefficients(x: np.ndarray, nodes: int | None = None) -> np.ndarray:
    """(P, n, n) A with psi_i = sum_k A_ik phi_k, the dual basis of facets (P, n, 3):
    int psi_i phi_k = delta_ik int phi_k. Triangles: A = 4 I - 1; quadrilaterals:
    A = D_e M_e^{-1} (M_e is symmetric, so A = (M_e^{-1} D_e)^T), of the bilinear functions, or
    with ``nodes`` = 9 of the biquadratic ones (P, 9, 9)."""
    if x.shape[1] == 3:
        return np.broadcast_to(4.0 * np.eye(3) - 1.0, (len(x), 3, 3))
    nodes = nodes or 4
    lumped, mass = _facet_mass(x, nodes)
    return np.swapaxes(np.linalg.solve(mass, lumped[:, :, None] * np.eye(nodes)), 1, 2)


#: basix's quadrilateral of degree 2: its nodes in the order of a 27-node hexahedron's facet closure
#: in DOLFINx (module docstring; ``tests/test_quadratic_hexahedra.py`` checks the order).
_BIQUADRATIC = basix.create_element(basix.ElementFamily.P, basix.CellType.quadrilateral, 2,
                                    basix.LagrangeVariant.equispaced)


def _biquadratic_table(xi: np.ndarray, derivatives: int) -> np.ndarray:
    """(1 + 2 derivatives, ..., 9) the biquadratic functions (and their xi-derivatives) at points xi (..., 2)."""
    table = _BIQUADRATIC.tabulate(derivatives, np.ascontiguousarray(xi, dtype=float).reshape(-1, 2))[..., 0]
    return table.reshape(len(table), *xi.shape[:-1], 9)


def biquadratic_shapes(xi: np.ndarray) -> np.ndarray:
    """(..., 9) the Lagrange functions of a 9-node quadrilateral at reference points xi (..., 2)."""
    return _biquadratic_table(xi, 0)[0]


def biquadratic_normals(xi: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """(p, Q, 3) unit normals of 9-node quadrilaterals ``nodes`` (p, 9, 3), ordered as
    :func:`biquadratic_shapes`, at reference points xi (p, Q, 2): dx/dxi x dx/deta, not oriented."""
    gradient = _biquadratic_table(xi, 1)[1:]
    dx = np.einsum("jpqa,pad->jpqd", gradient, nodes)
    normal = np.cross(dx[0], dx[1])
    return normal / length(normal)[..., None]


#: alpha of the modified basis of 6-node triangles (Popp, Wohlmuth, Gee and Wall 2012).
ALPHA = 0.2


def quadratic_shapes(L: np.ndarray) -> np.ndarray:
    """(..., 6) the Lagrange functions of a 6-node triangle at barycentric coordinates L (..., 3):
    the vertices' L_v (2 L_v - 1), then the edges' 4 L_(k+1) L_(k+2) (edge k opposite vertex k)."""
    return np.concatenate([L * (2.0 * L - 1.0), 4.0 * L[..., [1, 2, 0]] * L[..., [2, 0, 1]]], axis=-1)


def quadratic_normals(L: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """(p, Q, 3) unit normals of 6-node triangles ``nodes`` (p, 6, 3), ordered as
    :func:`quadratic_shapes`, at barycentric coordinates L (p, Q, 3): of the tangents
    dx/dL_1 - dx/dL_0 and dx/dL_2 - dx/dL_0, not oriented."""
    G = np.zeros((*L.shape[:-1], 6, 3))  # dN_a / dL_j
    for k in range(3):
        G[..., k, k] = 4.0 * L[..., k] - 1.0
        G[..., 3 + k, (k + 1) % 3] = 4.0 * L[..., (k + 2) % 3]
        G[..., 3 + k, (k + 2) % 3] = 4.0 * L[..., (k + 1) % 3]
    dx = np.einsum("pqaj,pad->pqjd", G, nodes)
    normal = np.cross(dx[..., 1, :] - dx[..., 0, :], dx[..., 2, :] - dx[..., 0, :])
    return normal / length(normal)[..., None]


#: Ñ = B N of the modified basis: the vertices' rows take alpha of the two edges at the vertex.
_MODIFIED = np.block([[np.eye(3), ALPHA * (1.0 - np.eye(3))], [np.zeros((3, 3)), (1.0 - 2.0 * ALPHA) * np.eye(3)]])


def modified_shapes(L: np.ndarray) -> np.ndarray:
    """(..., 6) the modified basis Ñ of a 6-node slave triangle at barycentric coordinates L (..., 3)."""
    return np.einsum("ij,...j->...i", _MODIFIED, quadratic_shapes(L))


def _modified_dual() -> tuple[np.ndarray, np.ndarray]:
    """A = D_e M_e^{-1} of the modified basis on a flat triangle, and int Ñ_k / area (a rule of
    degree 4 is exact for Ñ_j Ñ_k)."""
    points, weights = triangle_rule(4)
    shapes = modified_shapes(points)
    mass = np.einsum("q,qj,qk->jk", weights, shapes, shapes)
    lumped = mass.sum(axis=1)
    return np.linalg.solve(mass, np.diag(lumped)).T, lumped


#: (6, 6) Φ_i = sum_k A_ik Ñ_k: the dual basis of the modified basis on a flat triangle,
#: int Φ_i Ñ_k = delta_ik int Ñ_k; and the areas int Ñ_k over the facet's area, 2/15 at the
#: vertices and 1/5 at the edges.
MODIFIED_DUAL, MODIFIED_AREAS = _modified_dual()


def modified_dual(L: np.ndarray) -> np.ndarray:
    """(..., 6) the dual basis Φ of the modified basis of a flat 6-node triangle at barycentric
    coordinates L (..., 3)."""
    return np.einsum("ik,...k->...i", MODIFIED_DUAL, modified_shapes(L))
