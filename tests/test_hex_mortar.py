"""Mortar contact on hexahedral meshes (issue 37, part 2): quadrilateral facets.

Unit checks of the facets' geometry (the dual basis of a bilinear quadrilateral, the
inverse of its bilinear map), of the segment integrals of quadrilaterals against
quadrilaterals and triangles (flat non-matching interfaces: linear fields reproduced),
and the contact patch test on two non-matching hexahedral blocks (``meshes/hex_blocks.geo``:
4^3 hexahedra below, 5^3 above; rollers on x = 0, y = 0, z = 0, a pressure p on top;
exact u = (nu p x / E, nu p y / E, -p z / E), contact pressure p), frictionless and with
Coulomb friction, and rotated.

A hexahedral body against a tetrahedral one cannot be one DOLFINx 0.9 mesh (one cell type
per mesh, and all bodies share one function space); mixed pairs of facets are checked in
the segment integrals (quadrilaterals against triangles both ways), and the patch test runs
on a block of tetrahedra split into hexahedra (``meshes/hex_on_split_tets.geo``), whose
interface facets are the triangles cut into three quadrilaterals: no parallelograms.
"""

from __future__ import annotations

import pathlib

from mpi4py import MPI

import numpy as np
import pytest

from dolfinx import fem

from contactqvi.case import load_case
from contactqvi.contact.facets import (
    area_elements,
    dual_coefficients,
    nodal_integrals,
    quadrilateral_shapes,
    reference_coordinates,
)
from contactqvi.contact.interface import BodyPair
from contactqvi.contact.mortar import mortar_coupling
from contactqvi.contact.segments import segment_integrals
from contactqvi.contact.problem import assemble_contact_problem
from contactqvi.contact.scd_newton import SCDNewtonSolver
from contactqvi.elasticity import body_materials
from contactqvi.laws import Coulomb
from contactqvi.meshes import boundary_facets, read_gmsh, split_by_body
from contactqvi.runner import run_case
from mortar_checks import frame_invariance_error, linear_field_errors, rotation

ROOT = pathlib.Path(__file__).resolve().parent.parent
MESH = ROOT / "meshes" / "hex_blocks.geo"
#: The lower block's tetrahedra split into hexahedra: flat interface facets that are no parallelograms.
SPLIT_TETS = ROOT / "meshes" / "hex_on_split_tets.geo"
P = 1e6  # pressure on top (Pa)
E = 1e9
NU = 0.3
ROLLERS = {"lower.bottom": {2: 0.0}, "lower.symmetry_x": {0: 0.0}, "upper.symmetry_x": {0: 0.0},
           "lower.symmetry_y": {1: 0.0}, "upper.symmetry_y": {1: 0.0}}
#: A distorted (no parallelogram) flat quadrilateral, tensor-product order, in the plane z = 0.2.
DISTORTED = np.array([[0.0, 0.0, 0.2], [1.3, 0.1, 0.2], [-0.2, 0.9, 0.2], [1.0, 1.4, 0.2]])


def _gauss(n: int) -> tuple[np.ndarray, np.ndarray]:
    """n x n Gauss-Legendre points on the unit square and weights summing to 1 (numpy's rule,
    an oracle independent of basix's)."""
    t, w = np.polynomial.legendre.leggauss(n)
    t, w = 0.5 * (t + 1.0), 0.5 * w
    return np.array([[a, b] for a in t for b in t]), np.outer(w, w).ravel()


@pytest.mark.one_rank(reason="the dual basis of given quadrilaterals (numpy), no mesh")
def test_dual_basis_of_a_parallelogram_is_the_tensor_product():
    """psi_0 = 4 phi_0 - 2 phi_1 - 2 phi_2 + phi_3 and its permutations; on a triangle 4 phi - 1."""
    parallelogram = np.array([[[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.5, 1.0, 0.0], [2.5, 1.0, 0.0]]])
    one_d = np.array([[2.0, -1.0], [-1.0, 2.0]])
    assert np.allclose(dual_coefficients(parallelogram)[0], np.kron(one_d, one_d), atol=1e-13)
    triangle = parallelogram[:, :3]
    assert np.array_equal(dual_coefficients(triangle)[0], 4.0 * np.eye(3) - 1.0)
    assert np.allclose(nodal_integrals(parallelogram), 0.5, atol=1e-15)  # area 2, a quarter each


@pytest.mark.one_rank(reason="the dual basis of given quadrilaterals (numpy), no mesh")
@pytest.mark.parametrize("warp", [0.0, 0.3])
def test_dual_basis_of_a_distorted_quadrilateral_is_biorthogonal(warp):
    """int psi_i phi_k dA = delta_ik int phi_k dA with the true area element, by a 20 x 20 Gauss
    rule: to round-off on a flat distorted quadrilateral (the area element is bilinear, the
    8 x 8 rule of the construction exact) and on one warped by 0.3 of its size (vertex 3
    lifted), whose area element is no polynomial (measured 1.4e-15; 7.6e-6 with 3 x 3 points)."""
    x = DISTORTED.copy()
    x[3, 2] += warp
    A = dual_coefficients(x[None])[0]
    points, weights = _gauss(20)
    dA = weights * area_elements(x[None], points[None])[0]
    phi = quadrilateral_shapes(points)
    psi = phi @ A.T
    products = np.einsum("q,qi,qk->ik", dA, psi, phi)
    lumped = dA @ phi
    assert np.abs(products - np.diag(lumped)).max() < 1e-13 * lumped.max()
    assert np.abs(np.diag(products) - nodal_integrals(x[None])[0]).max() < 1e-13 * lumped.max()


@pytest.mark.one_rank(reason="segment integrals of given facets (numpy), no search")
@pytest.mark.parametrize("master", [np.array([[-3.0, -3.0], [3.0, -3.0], [-3.0, 3.0], [3.0, 3.0]]),
                                    np.array([[-9.0, -9.0], [9.0, -9.0], [0.0, 9.0]])])
def test_warped_slave_facet_is_integrated_with_its_true_area(master):
    """A slave quadrilateral warped by 0.3 of its size over a larger flat master facet (a
    quadrilateral, a triangle) in z = -1: sum_i D_i = int sum_i psi_i dA is the warped facet's
    true area (20 x 20 Gauss points of its area element) to 1e-12 (measured 7e-16), and
    sum_j M_ij = D_i (sum_j phi_j^m = 1)."""
    x = DISTORTED.copy()
    x[3, 2] += 0.3
    normal = np.cross(x[3] - x[0], x[2] - x[1])
    normal /= np.linalg.norm(normal)
    master = np.column_stack([master, np.full(len(master), -1.0)])
    D, M = segment_integrals(x[None], normal[None], master[None])
    points, weights = _gauss(20)
    area = float(weights @ area_elements(x[None], points[None])[0])
    assert abs(D.sum() - area) < 1e-12 * area
    assert np.abs(M.sum(axis=2) - D).max() < 1e-14 * area


@pytest.mark.one_rank(reason="the inverse bilinear map of given quadrilaterals (numpy), no mesh")
def test_reference_coordinates_invert_the_bilinear_map():
    rng = np.random.default_rng(3)
    xi = rng.uniform(0.0, 1.0, (1, 50, 2))
    x2 = DISTORTED[None, :, :2]
    points = np.einsum("pqk,pkj->pqj", quadrilateral_shapes(xi), x2)
    assert np.abs(reference_coordinates(x2, points) - xi).max() < 1e-14
    collapsed = np.zeros((1, 4, 2))  # all four vertices at one point: no map to invert
    assert np.isnan(reference_coordinates(collapsed, points)).all()
    folded = DISTORTED[None, [0, 1, 3, 2], :2]  # the vertices out of order: a bow tie
    inverse = reference_coordinates(folded, points)
    assert np.isnan(inverse).any(axis=-1).any()  # NaN where Newton's method did not converge ...
    mapped = np.einsum("pqk,pkj->pqj", quadrilateral_shapes(inverse), folded)
    converged = ~np.isnan(inverse).any(axis=-1)
    assert np.abs(mapped[converged] - points[converged]).max(initial=0.0) < 1e-12  # ... else a solution


#: A thin quadrilateral: a facet of the sphere of meshes/hertz_bodies_hex_coarse.geo seen nearly
#: edge-on from the block's top (projected onto it; Jacobian 3e-4 of its squared size).
THIN = np.array([[0.20715166900772064, 0.09070028206112517], [0.17457534350025722, 0.07874769993360507],
                 [0.103946448144821, 0.04683386438022775], [0.11668585837526793, 0.05299506184005029]])


@pytest.mark.one_rank(reason="the inverse bilinear map of a given quadrilateral (numpy), no mesh")
def test_reference_coordinates_of_a_thin_quadrilateral():
    """Round-off holds Newton's steps on the thin facet at about 1e-14 (they stalled at 1.2e-14,
    just above the tolerance, and the search raised "did not converge"): the stall is accepted
    as convergence, and the grid's points come back to 1e-12 (measured 3.0e-14)."""
    t = np.linspace(0.01, 0.99, 15)
    xi = np.array([[a, b] for a in t for b in t])[None]
    points = np.einsum("pqk,pkj->pqj", quadrilateral_shapes(xi), THIN[None])
    assert np.abs(reference_coordinates(THIN[None], points) - xi).max() < 1e-12


#: A shear of the plane z = 0: it maps the rectangles of a grid onto parallelograms (area kept).
SHEAR = np.array([[1.0, 0.4, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])


def _grid(n: int, jiggle: float = 0.0, seed: int = 0, grading: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Quadrilaterals (f, 4) of an n x n grid of the unit square in z = 0 (tensor-product vertex
    order), its lines graded by t -> t^grading (rectangles), its interior nodes then moved by up
    to ``jiggle`` cells (distorted quadrilaterals); and its nodes (N, 3)."""
    t = np.linspace(0.0, 1.0, n + 1) ** grading
    X, Y = np.meshgrid(t, t, indexing="ij")
    rng = np.random.default_rng(seed)
    interior = (X > 0) & (X < 1) & (Y > 0) & (Y < 1)
    X = X + interior * rng.uniform(-jiggle, jiggle, X.shape) / n
    Y = Y + interior * rng.uniform(-jiggle, jiggle, Y.shape) / n
    nodes = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    v0 = (i * (n + 1) + j).ravel()
    return np.stack([v0, v0 + n + 1, v0 + 1, v0 + n + 2], axis=1), nodes


def _triangles(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Triangles of an n x n grid of the unit square in z = 0 (each square cut by a diagonal)."""
    quads, nodes = _grid(n)
    return np.concatenate([quads[:, [0, 1, 3]], quads[:, [0, 3, 2]]]), nodes


def _reproduction_error(slave: tuple, master: tuple, degree: int | None = None) -> tuple[float, float]:
    """Max over slave nodes of |x_i - sum_j C_ij x_j| for the flat interface of two meshes of
    one domain of area 1, all pairs integrated (no search); and |sum_i D_ii - 1| (the area)."""
    (s_cells, s_nodes), (m_cells, m_nodes) = slave, master
    s_pair, m_pair = (a.ravel() for a in np.meshgrid(np.arange(len(s_cells)), np.arange(len(m_cells)), indexing="ij"))
    slave_x = s_nodes[s_cells[s_pair]]
    master_x = m_nodes[m_cells[m_pair]] - [0.0, 0.0, 1e-3]  # a small gap: projected along the normal
    D_pair, M_pair = segment_integrals(slave_x, np.tile([0.0, 0.0, -1.0], (len(s_pair), 1)), master_x, degree)
    D = np.zeros(len(s_nodes))
    M = np.zeros((len(s_nodes), len(m_nodes)))
    np.add.at(D, s_cells[s_pair], D_pair)
    np.add.at(M, (s_cells[s_pair][:, :, None], m_cells[m_pair][:, None, :]), M_pair)
    C = M / D[:, None]
    return float(np.abs(C @ m_nodes[:, :2] - s_nodes[:, :2]).max()), abs(D.sum() - 1.0)


@pytest.mark.one_rank(reason="segment integrals of given facets (numpy), no search")
@pytest.mark.parametrize("slave, master", [("graded quads", "quads"), ("quads", "graded quads"),
                                           ("quads", "triangles"), ("triangles", "graded quads")])
def test_flat_interface_of_parallelograms_and_triangles_is_integrated_exactly(slave, master):
    """Non-matching parallelograms (a 3 x 3 graded grid, a 4 x 4 uniform one, sheared by
    :data:`SHEAR`) and triangles (5 x 5 x 2), also mixed pairs both ways: psi_i phi_j^m is a
    polynomial of degree <= 4 in the plane there, so sum_j C_ij x_j = x_i and sum D_ii = area
    to round-off."""
    meshes = {"graded quads": _grid(3, grading=1.4), "quads": _grid(4), "triangles": _triangles(5)}
    meshes = {name: (cells, nodes @ SHEAR.T) for name, (cells, nodes) in meshes.items()}
    error, area = _reproduction_error(meshes[slave], meshes[master])
    assert error < 1e-14
    assert area < 1e-14


@pytest.mark.one_rank(reason="segment integrals of given facets (numpy), no search")
def test_flat_interface_of_distorted_quadrilaterals_converges_with_the_rule():
    """Distorted (no parallelogram) quadrilaterals both sides: the inverse bilinear maps make
    psi_i phi_j^m no polynomial on the clipped triangles, so linear fields are reproduced to
    the rule's accuracy, converging with its degree (measured 2.6e-3, 8.4e-8, 9.2e-13 at
    degrees 2, 6, 12; the default, 20, to round-off)."""
    slave, master = _grid(3, 0.3, 1), _grid(4, 0.3, 2)
    errors = {degree: _reproduction_error(slave, master, degree)[0] for degree in (2, 6, 12, None)}
    assert errors[12] < errors[6] < errors[2]
    assert errors[6] < 1e-6 and errors[12] < 1e-11 and errors[None] < 1e-14
    assert _reproduction_error(slave, master, 2)[1] < 1e-13  # sum_i psi_i = 1: the area exact at any degree


@pytest.fixture(scope="module")
def meshes() -> dict:
    """The meshes read so far, by file (each read once for the module)."""
    return {}


def _blocks(meshes: dict, path: pathlib.Path) -> tuple:
    if path not in meshes:
        msh, facet_tags, cell_tags = read_gmsh(path, MPI.COMM_WORLD)
        meshes[path] = (msh, split_by_body(msh, facet_tags, cell_tags), cell_tags)
    return meshes[path]


@pytest.fixture
def hex_blocks(meshes):
    return _blocks(meshes, MESH)


@pytest.mark.parametrize("mesh, slave, master, nodes, tolerance", [
    (MESH, "upper", "lower", 36, 1e-14), (MESH, "lower", "upper", 25, 1e-14),
    (SPLIT_TETS, "upper", "lower", 49, 1e-14), (SPLIT_TETS, "lower", "upper", None, 1e-9)])
def test_flat_non_matching_hexahedral_interface(meshes, mesh, slave, master, nodes, tolerance):
    """sum_j C_ij x_j = x_i, rows sum to 1, gap 0, sum D_ii = the interface's area. Exact where
    the slave facets are parallelograms (squares; sum_j phi_j^m x_j = x holds pointwise on any
    master facet); the split tetrahedra's quadrilaterals as slave to the degree-20 rule's
    accuracy (measured 5e-11). ``nodes``: the slave's interface nodes, (n + 1)^2 on a
    structured face of n x n cells (None: unstructured)."""
    msh, tags, _ = _blocks(meshes, mesh)
    V = fem.functionspace(msh, ("Lagrange", 1, (3,)))
    coupling = mortar_coupling(V, boundary_facets(tags, f"{slave}.interface"),
                               boundary_facets(tags, f"{master}.interface"), 0.1)
    comm = msh.comm
    found = comm.allreduce(len(coupling.slave_blk), op=MPI.SUM)
    assert (found == nodes) if nodes is not None else (found > 0)
    assert max(linear_field_errors(V, coupling)) < tolerance
    assert comm.allreduce(float(coupling.weight.sum()), op=MPI.SUM) == pytest.approx(1.0, rel=1e-13)


def _solve(problem, pc: str = "gamg"):
    u = problem.A.createVecRight()
    problem.shift.copy(u)
    with SCDNewtonSolver(problem, {"pc": pc}, prefix="hex_") as solver:
        result = solver.solve(u)
    displacement = problem.physical_displacement(u, fem.Function(problem.V))
    u.destroy()
    return result, displacement


@pytest.mark.parametrize("mesh, slave, master, friction", [
    (MESH, "upper", "lower", 0.0), (MESH, "upper", "lower", 0.3),
    (SPLIT_TETS, "upper", "lower", 0.0), (SPLIT_TETS, "upper", "lower", 0.3), (SPLIT_TETS, "lower", "upper", 0.3)])
def test_hexahedral_contact_patch_test(meshes, mesh, slave, master, friction):
    """Uniform pressure p across the non-matching hexahedral interface and the homogeneous
    solution, both to 1e-8 relative (GAMG Newton-step solves). Measured: squares on squares
    (hex_blocks.geo) 1.7e-12 in pressure, 3.2e-13 in displacement; squares on the split
    tetrahedra's quadrilaterals 4e-12 / 3e-12, those as slave 4.6e-10 / 1.2e-11 (degree-20
    rule on facets that are no parallelograms)."""
    msh, tags, cell_tags = _blocks(meshes, mesh)
    young, poisson = body_materials(msh, cell_tags, {"lower": (E, NU), "upper": (E, NU)})
    with assemble_contact_problem(msh, tags, young, poisson, {"upper.top": (0.0, 0.0, -P)},
                                  [BodyPair(f"{slave}.interface", f"{master}.interface", Coulomb(friction))],
                                  displacements=ROLLERS, cell_tags=cell_tags) as problem:
        result, displacement = _solve(problem)
        comm = problem.comm
        assert result.converged
        if mesh == MESH:
            assert problem.n_contact == (36 if slave == "upper" else 25)  # (global) the slave's interface nodes
        pressure = result.normal_force / problem.contact_area
        assert comm.allreduce(float(np.abs(pressure / P - 1.0).max(initial=0.0)), op=MPI.MAX) < 1e-8
        n = problem.V.dofmap.index_map.size_local
        x = problem.V.tabulate_dof_coordinates()[:n]
        exact = np.column_stack([NU * P * x[:, 0] / E, NU * P * x[:, 1] / E, -P * x[:, 2] / E])
        error = np.abs(displacement.x.array.reshape(-1, 3)[:n] - exact).max(initial=0.0)
        assert comm.allreduce(float(error), op=MPI.MAX) < 1e-8 * P * 2.0 / E
        assert comm.allreduce(float(result.normal_force.sum()), op=MPI.SUM) == pytest.approx(P, rel=1e-10)


def test_hexahedral_two_body_solution_is_frame_invariant(hex_blocks):
    """The hexahedral stack without rollers (lower block clamped, upper held by friction F = 0.5
    under a pressure with a small shear, moduli 1 and 3 GPa) rotated by Q about (1, 2, 2)/3 by
    0.7 rad gives Q u(x) at the nodes Q x, to 1e-8 (exact Newton-step solves; measured 1.6e-12,
    3 of the 36 slave nodes sliding)."""
    msh, tags, cell_tags = hex_blocks
    young, poisson = body_materials(msh, cell_tags, {"lower": (E, NU), "upper": (3 * E, 0.2)})

    def solve(R: np.ndarray) -> np.ndarray:
        traction = tuple(R @ np.array([0.1 * P, 0.05 * P, -P]))
        with assemble_contact_problem(msh, tags, young, poisson, {"upper.top": traction},
                                      [BodyPair("upper.interface", "lower.interface", Coulomb(0.5))],
                                      clamped=["lower.bottom"], cell_tags=cell_tags) as problem:
            result, displacement = _solve(problem, pc="lu")
            assert result.converged
            return displacement.x.array.reshape(-1, 3).copy()

    assert frame_invariance_error(msh, solve, rotation(np.array([1.0, 2.0, 2.0]) / 3.0, 0.7)) < 1e-8


def test_hex_patch_case_file(mpi_tmp_path):
    """cases/hex_patch.toml (the user's repro) through the runner: the pair carries the load
    p x 1 m^2, every body is in balance."""
    summary, code = run_case(load_case(ROOT / "cases" / "hex_patch.toml"), mpi_tmp_path / "hex_patch", plot=False)
    assert code == 0
    step = summary["steps"][-1]
    assert step["pair_forces"]["upper.interface/lower.interface"] == pytest.approx([0.0, 0.0, P], abs=1e-6 * P)
    assert max(step["body_equilibrium_errors"].values()) < 1e-10
