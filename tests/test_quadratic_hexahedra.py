"""Quadratic elements on hexahedra (27-node, Q2 displacements; issue 43, items 1-2): the 9-node
facets' dual mortar (docs/quadratic.md, Sect. 6).

* The facet closure of a Q2 hexahedron lists its nine nodes in the order of basix's quadrilateral
  of degree 2 (:func:`~contactqvi.contact.facets.biquadratic_shapes`).
* The dual basis Φ = A N of a 9-node facet is biorthogonal to its Lagrange functions with the vertex
  quadrilateral's area element, on a distorted and on a warped facet; every N_i has a positive
  integral, so no modified basis is needed.
* One pair whose master is the slave facet: M = diag(D) = S, D = int N_i; random pairs: the rows of M
  and S sum to D, and D sums to the linear facets' overlap.
* The flat non-matching interface of the hexahedral blocks reproduces linear fields; the contact patch
  test holds to 1e-8 (frictionless, Coulomb 0.3, moduli 1 and 3 GPa); the frictional stack rotated by Q
  gives Q u(Q^T x); all ranks equal each rank alone (a path stopped and restarted continues exactly:
  tests/test_quadratic_mortar.py).
* A 27-node block on a rigid plane through the runner, with displacements alone and as the Taylor-Hood
  pair Q2/Q1 at nu = 0.4999: the homogeneous solution at all 27 nodes of every cell of the VTX output;
  under a rigid sphere the contact surface's file shows the body's displacement at every point (facet
  centres included).
* A mesh of 20-node hexahedra is refused by name.
"""

from __future__ import annotations

import pathlib

from mpi4py import MPI

import numpy as np
import pytest
import scipy.spatial

from dolfinx import fem
from dolfinx.mesh import exterior_facet_indices

from contactqvi.case import parse_case
from contactqvi.contact.facets import (
    area_elements,
    biquadratic_shapes,
    dual_coefficients,
    nodal_integrals,
    quadrilateral_shapes,
)
from contactqvi.contact.interface import BodyPair
from contactqvi.contact.mortar import exterior_facet_cells, facet_closures, mortar_coupling
from contactqvi.contact.problem import assemble_contact_problem
from contactqvi.contact.segments import quadratic_segment_integrals, segment_integrals
from contactqvi.elasticity import body_materials
from contactqvi.exact_surfaces import CoaxialCylinders
from contactqvi.laws import Coulomb, Frictionless
from contactqvi.meshes import boundary_facets, read_gmsh
from contactqvi.parameters import ParameterError
from contactqvi.paraview import read_vtx
from contactqvi.runner import run_case
from mortar_checks import frame_invariance_error, linear_field_errors, rotation
from test_hex_mortar import DISTORTED, E, MESH, NU, P, ROLLERS, SPLIT_TETS, _blocks, _gauss, _solve
from test_two_body import on_all_ranks_and_alone

ROOT = pathlib.Path(__file__).resolve().parent.parent
#: A unit cube of 27-node hexahedra resting on the plane z = 0.
BLOCK = ROOT / "tests" / "data" / "hex27_block.geo"
#: basix's nodes of the quadrilateral of degree 2 (reference coordinates), in the closure's order.
NODES = np.array([[0, 0], [1, 0], [0, 1], [1, 1], [0.5, 0], [0, 0.5], [1, 0.5], [0.5, 1], [0.5, 0.5]])


@pytest.fixture(scope="module")
def meshes() -> dict:
    return {}


def _exterior_facets(msh) -> np.ndarray:
    """The owned exterior facets of ``msh``."""
    facets = exterior_facet_indices(msh.topology)
    return facets[facets < msh.topology.index_map(2).size_local]


@pytest.mark.parametrize("path", [MESH, BLOCK])
def test_the_facet_closure_is_in_the_order_of_the_biquadratic_shapes(meshes, path):
    """Each exterior facet's closure in a Q2 space, on 8-node and on 27-node hexahedra: its nodes are the
    vertex quadrilateral's bilinear map at basix's nodes of degree 2, and the biquadratic functions are
    1 at their own node and 0 at the others."""
    msh = _blocks(meshes, path)[0] if path == MESH else read_gmsh(path, MPI.COMM_WORLD)[0]
    V = fem.functionspace(msh, ("Lagrange", 2, (3,)))
    msh.topology.create_connectivity(2, 3)
    facets = _exterior_facets(msh)
    cells, local = exterior_facet_cells(msh, facets)
    blk = np.take_along_axis(V.dofmap.list[cells], facet_closures(V.dofmap.dof_layout, msh)[local], axis=1)
    x = V.tabulate_dof_coordinates()[blk]
    mapped = np.einsum("kv,fvd->fkd", quadrilateral_shapes(NODES), x[:, :4])
    assert blk.shape[1] == 9 and len(facets) > 0
    assert np.abs(x - mapped).max() < 1e-14
    assert np.abs(biquadratic_shapes(NODES) - np.eye(9)).max() < 1e-14


@pytest.mark.one_rank(reason="the dual basis of given quadrilaterals (numpy), no mesh")
@pytest.mark.parametrize("warp", [0.0, 0.3])
def test_the_biquadratic_dual_basis_is_biorthogonal(warp):
    """int Φ_i N_k dA = delta_ik int N_k dA (20 x 20 Gauss points of the vertex quadrilateral's area
    element) to round-off on a flat distorted facet and on one warped by 0.3 of its size; int N_k > 0 at
    every node, summing to the area; on a parallelogram 1/36, 1/9 and 4/9 of it."""
    x = DISTORTED.copy()
    x[3, 2] += warp
    A = dual_coefficients(x[None], 9)[0]
    points, weights = _gauss(20)
    dA = weights * area_elements(x[None], points[None])[0]
    N = biquadratic_shapes(points)
    products = np.einsum("q,qi,qk->ik", dA, N @ A.T, N)
    lumped = dA @ N
    assert np.abs(products - np.diag(lumped)).max() < 1e-13 * lumped.max()
    assert np.abs(nodal_integrals(x[None], 9)[0] - lumped).max() < 1e-13 * lumped.max()
    assert lumped.min() > 0.0 and lumped.sum() == pytest.approx(dA.sum(), rel=1e-14)
    square = np.array([[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]]])
    assert nodal_integrals(square, 9)[0] == pytest.approx([1 / 36] * 4 + [1 / 9] * 4 + [4 / 9], rel=1e-13)


@pytest.mark.one_rank(reason="segment integrals of given quadrilaterals (numpy), no search")
def test_a_biquadratic_master_equal_to_the_slave_gives_the_dual_weights():
    """Master = slave facet (a parallelogram, its vertices listed from another corner): M = diag(D) in the
    slave's node order (biorthogonality), S = M, D = int N_i."""
    slave = np.array([[[0.0, 0.0, 0.0], [2.0, 0.1, 0.0], [0.3, 1.5, 0.0], [2.3, 1.6, 0.0]]])
    master = slave[:, [1, 3, 0, 2]] - [0.0, 0.0, 0.1]  # the facet turned: master node j is slave node order[j]
    order = np.array([1, 3, 0, 2, 6, 4, 7, 5, 8])
    D, M, S = quadratic_segment_integrals(slave, np.array([[0.0, 0.0, 1.0]]), master)
    assert D[0] == pytest.approx(nodal_integrals(slave, 9)[0], rel=1e-13)
    in_slave_order = np.empty_like(M[0])
    in_slave_order[:, order] = M[0]
    assert in_slave_order == pytest.approx(np.diag(D[0]), abs=1e-13 * D.max())
    assert S[0] == pytest.approx(np.diag(D[0]), abs=1e-13 * D.max())


@pytest.mark.one_rank(reason="segment integrals of given quadrilaterals (numpy), no search")
def test_biquadratic_segments_are_those_of_the_vertex_quadrilaterals():
    """Random parallelograms in parallel planes: sum_i D_i is the bilinear facets' (the overlap's area);
    and for a quadratic field f of the plane, which the biquadratic functions of a parallelogram hold
    exactly, sum_j M_ij f(x_j^m) = sum_k S_ik f(x_k) = int Φ_i f over the overlap, whatever part of the
    slave facet the master covers (a wrong projection, reference coordinate or master order breaks it;
    the rows of M and S summing to D follow from f = 1)."""
    rng = np.random.default_rng(5)
    count = 500

    def parallelograms(shift: float, z: float) -> np.ndarray:
        origin = rng.uniform(-1.0, 1.0, (count, 1, 2)) + rng.uniform(-shift, shift, (count, 1, 2))
        a, b = rng.uniform(0.3, 1.0, (count, 1, 2)) * [1.0, 0.2], rng.uniform(0.3, 1.0, (count, 1, 2)) * [0.2, 1.0]
        corners = np.concatenate([origin, origin + a, origin + b, origin + a + b], axis=1)
        return np.concatenate([corners, np.full((count, 4, 1), z)], axis=2)

    def field(x: np.ndarray) -> np.ndarray:
        return 1.0 + 0.3 * x[..., 0] - 0.7 * x[..., 1] + 0.5 * x[..., 0] ** 2 - 0.2 * x[..., 0] * x[..., 1]

    slave, master = parallelograms(0.0, 0.0), parallelograms(0.5, -0.1)
    normal = np.tile([0.0, 0.0, 1.0], (count, 1))
    D, M, S = quadratic_segment_integrals(slave, normal, master)
    linear, _ = segment_integrals(slave, normal, master)
    nodes = quadrilateral_shapes(NODES)  # (9, 4): the nine nodes of a facet from its vertices
    slave_f, master_f = (field(np.einsum("kv,pvd->pkd", nodes, x)) for x in (slave, master))
    assert np.count_nonzero(linear.sum(axis=1)) > count // 5
    assert np.allclose(np.einsum("pij,pj->pi", M, master_f), np.einsum("pik,pk->pi", S, slave_f), atol=1e-13)
    assert np.allclose(M.sum(axis=2), D, atol=1e-13)
    assert np.allclose(D.sum(axis=1), linear.sum(axis=1), atol=1e-13)


@pytest.mark.parametrize("mesh, slave, master, tolerance", [
    (MESH, "upper", "lower", 1e-14), (MESH, "lower", "upper", 1e-14), (SPLIT_TETS, "lower", "upper", 1e-8)])
def test_flat_non_matching_biquadratic_interface(meshes, mesh, slave, master, tolerance):
    """sum_j C_ij x_j = x_i, rows sum to 1, gap 0, D sums to the interface's area, every node of the slave
    surface coupled; exact where the facets are parallelograms, to the degree-20 rule's accuracy on the
    split tetrahedra's quadrilaterals (measured 1.9e-9; bilinear facets 5e-11: the biquadratic functions
    of the inverse bilinear map are further from a polynomial)."""
    msh, tags, _ = _blocks(meshes, mesh)
    V = fem.functionspace(msh, ("Lagrange", 2, (3,)))
    surface = boundary_facets(tags, f"{slave}.interface")
    coupling = mortar_coupling(V, surface, boundary_facets(tags, f"{master}.interface"), 0.1)
    comm = msh.comm
    assert max(linear_field_errors(V, coupling)) < tolerance
    assert comm.allreduce(float(coupling.weight.sum()), op=MPI.SUM) == pytest.approx(1.0, rel=1e-12)
    nodes = fem.locate_dofs_topological(V, 2, surface)
    assert comm.allreduce(len(coupling.slave_blk), op=MPI.SUM) == comm.allreduce(
        int(np.count_nonzero(nodes < V.dofmap.index_map.size_local)), op=MPI.SUM)


@pytest.mark.parametrize("young_upper, friction", [(E, 0.0), (E, 0.3), (3 * E, 0.0)])
def test_biquadratic_contact_patch_test(meshes, young_upper, friction):
    """Q2 on both hexahedral blocks: the pressure lambda_i / D_ii is P at every one of the 121 slave nodes
    (vertices, edges and face centres), the displacement the homogeneous one, to 1e-8 (GAMG Newton-step
    solves; measured 3e-11 and 6e-13), the whole load through the interface."""
    msh, tags, cell_tags = _blocks(meshes, MESH)
    young, poisson = body_materials(msh, cell_tags, {"lower": (E, NU), "upper": (young_upper, NU)})
    with assemble_contact_problem(msh, tags, young, poisson, {"upper.top": (0.0, 0.0, -P)},
                                  [BodyPair("upper.interface", "lower.interface", Coulomb(friction))],
                                  displacements=ROLLERS, cell_tags=cell_tags, degree=2) as problem:
        result, displacement = _solve(problem)
        comm = problem.comm
        assert result.converged and problem.n_contact == 121
        pressure = result.normal_force / problem.contact_area
        assert comm.allreduce(float(np.abs(pressure / P - 1.0).max(initial=0.0)), op=MPI.MAX) < 1e-8
        n = problem.V.dofmap.index_map.size_local
        x = problem.V.tabulate_dof_coordinates()[:n]
        lower = problem.node_body[:n] == 0
        stiffness = np.where(lower, E, young_upper)
        uz = np.where(lower, -P * x[:, 2] / E, -P / E - P * (x[:, 2] - 1.0) / young_upper)
        exact = np.column_stack([NU * P * x[:, 0] / stiffness, NU * P * x[:, 1] / stiffness, uz])
        error = np.abs(displacement.x.array.reshape(-1, 3)[:n] - exact).max(initial=0.0)
        assert comm.allreduce(float(error), op=MPI.MAX) < 1e-8 * 2.0 * P / E
        assert comm.allreduce(float(result.normal_force.sum()), op=MPI.SUM) == pytest.approx(P, rel=1e-10)


def test_biquadratic_two_body_solution_is_frame_invariant(meshes):
    """The Q2 hexahedral stack (lower block clamped, upper held by friction 0.5 under a pressure with a
    small shear, moduli 1 and 3 GPa) rotated by Q about (1, 2, 2)/3 by 0.7 rad gives Q u(x) at the nodes
    Q x, to 1e-8 (exact Newton-step solves)."""
    msh, tags, cell_tags = _blocks(meshes, MESH)
    young, poisson = body_materials(msh, cell_tags, {"lower": (E, NU), "upper": (3 * E, 0.2)})

    def solve(R: np.ndarray) -> np.ndarray:
        traction = tuple(R @ np.array([0.1 * P, 0.05 * P, -P]))
        with assemble_contact_problem(msh, tags, young, poisson, {"upper.top": traction},
                                      [BodyPair("upper.interface", "lower.interface", Coulomb(0.5))],
                                      clamped=["lower.bottom"], cell_tags=cell_tags, degree=2) as problem:
            result, displacement = _solve(problem, pc="lu")
            assert result.converged
            return displacement.x.array.reshape(-1, 3).copy()

    assert frame_invariance_error(msh, solve, rotation(np.array([1.0, 2.0, 2.0]) / 3.0, 0.7)) < 1e-8


@pytest.mark.ranks(2, 3)  # compares a parallel run with a serial one
def test_biquadratic_two_body_parallel_equals_serial():
    """The hexahedral blocks with slip (Coulomb 0.3, moduli 1 and 3 GPa), Q2, on all ranks and on each
    rank alone (exact Newton-step solves): Newton counts within 1 and the same displacement at every node
    to 1e-9."""
    (parallel, serial), error = on_all_ranks_and_alone("lu", degree=2, mesh=MESH)
    assert abs(parallel - serial) <= 1
    assert error < 1e-9


def test_exact_cylinders_on_hexahedra_are_refused(meshes):
    """A pair declared coaxial cylinders with quadratic hexahedra is a ParameterError named by the pair's
    cylinder key (the exact surfaces' integrals are those of 6-node triangles)."""
    msh, tags, cell_tags = _blocks(meshes, MESH)
    pair = BodyPair("upper.interface", "lower.interface", Frictionless(),
                    cylinder=CoaxialCylinders())
    with pytest.raises(ParameterError, match=r"cylinder: exact cylinders take tetrahedra with quadratic elements"):
        assemble_contact_problem(msh, tags, E, NU, {}, [pair], cell_tags=cell_tags, degree=2)


@pytest.mark.parametrize("poisson, formulation", [(NU, "displacement"), (0.4999, "nodal_pressure")])
def test_a_27_node_block_on_a_plane_writes_its_quadratic_field(mpi_tmp_path, poisson, formulation):
    """tests/data/hex27_block.geo (3^3 hexahedra of 27 nodes) pressed by p onto a frictionless rigid plane,
    rollers on two sides, through the runner, with displacements alone and as the Taylor-Hood pair Q2/Q1
    at nu = 0.4999 (docs/nearly_incompressible.md, Sect. 6): the VTX body file holds 27-point cells, the
    displacement at every point is the homogeneous one (nu p x / E, nu p y / E, -p z / E) to 1e-10 of
    p / E, and the plane carries p x 1 m^2."""
    young, pressure = 1e9, 1e6
    data = {"mesh": {"file": str(BLOCK), "order": 2},
            "material": {"young": young, "poisson": poisson, "formulation": formulation},
            "boundary": {"displacement": {"symmetry_x": {"x": 0.0}, "symmetry_y": {"y": 0.0}},
                         "traction": {"top": [0.0, 0.0, -pressure]}},
            "contact": {"surface": "bottom", "law": "frictionless"},
            "obstacle": {"type": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0]},
            "steps": [{"load": 1.0}]}
    summary, code = run_case(parse_case(data, ROOT), mpi_tmp_path, plot=False)
    assert code == 0, summary["status"]
    assert summary["steps"][-1]["pair_forces"]["bottom/obstacle"] == pytest.approx([0.0, 0.0, pressure],
                                                                                   abs=1e-8 * pressure)
    if MPI.COMM_WORLD.rank == 0:
        dataset = read_vtx(mpi_tmp_path / "body.bp", -1)
        x = dataset.points
        exact = np.column_stack([poisson * x[:, 0], poisson * x[:, 1], -x[:, 2]]) * pressure / young
        (name,) = [key for key in dataset.point_data if key.startswith("displacement")]
        assert dataset.cells.shape[1] == 27
        assert np.abs(dataset.point_data[name] - exact).max() < 1e-10 * pressure / young


def test_the_contact_surface_file_shows_the_quadratic_field_at_every_node(mpi_tmp_path):
    """The 27-node block, clamped on top, pressed 2 mm by a rigid sphere (R = 2 m) at its corner: every
    point of the contact surface's VTX file (the facets' vertices, edge midpoints and centres) shows the
    displacement of the body's file at that point, to 1e-12 of the travel. With the centre nodes' values
    replaced by the mean of the facet's vertices (the linear facets' patches), the centres were off by
    0.22 of the travel."""
    travel = 2e-3
    data = {"mesh": {"file": str(BLOCK), "order": 2}, "material": {"young": 1e9, "poisson": NU},
            "boundary": {"clamped": ["top"], "displacement": {"symmetry_x": {"x": 0.0}, "symmetry_y": {"y": 0.0}}},
            "contact": {"surface": "bottom", "law": "frictionless"},
            "obstacle": {"type": "sphere", "center": [0.0, 0.0, -2.0], "radius": 2.0},
            "steps": [{"translation": [0.0, 0.0, travel]}]}
    summary, code = run_case(parse_case(data, ROOT), mpi_tmp_path, plot=False)
    assert code == 0, summary["status"]
    if MPI.COMM_WORLD.rank == 0:
        body, surface = read_vtx(mpi_tmp_path / "body.bp", -1), read_vtx(mpi_tmp_path / "contact_surface.bp", -1)
        distance, point = scipy.spatial.cKDTree(body.points).query(surface.points)
        (name,) = [key for key in surface.point_data if key.startswith("displacement")]
        (body_name,) = [key for key in body.point_data if key.startswith("displacement")]
        assert len(surface.points) >= 49 and distance.max() < 1e-14  # 4^2 vertices, 24 midpoints, 9 centres
        assert np.abs(surface.point_data[name] - body.point_data[body_name][point]).max() < 1e-12 * travel


def test_serendipity_hexahedra_are_refused_by_name(mpi_tmp_path):
    """The block meshed with 20-node (incomplete second-order) hexahedra, which DOLFINx 0.9 does not read
    (gmshio stopped with a KeyError of gmsh's type 17): a ParameterError named mesh that says how to mesh
    instead, before the mesh is distributed."""
    geo = mpi_tmp_path / "hex20_block.geo"
    if MPI.COMM_WORLD.rank == 0:
        geo.write_text(BLOCK.read_text().replace("Mesh.SecondOrderIncomplete = 0;", "Mesh.SecondOrderIncomplete = 1;"))
    MPI.COMM_WORLD.Barrier()
    with pytest.raises(ParameterError, match=r"^mesh: .*'block': Hexahedron 20.*Mesh\.SecondOrderIncomplete = 0"):
        read_gmsh(geo, MPI.COMM_WORLD)
