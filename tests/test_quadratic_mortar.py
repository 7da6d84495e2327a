"""Quadratic elements (P2 on 10-node tetrahedra) between meshed bodies: the quadratic dual mortar
coupling (docs/quadratic.md, Sect. 5; issue 43).

* The integrals of one pair of 6-node triangles: over a master facet equal to the slave one,
  sum_j M_ij u_j = D_i ũ_i for every displacement u = S ũ of the facet (biorthogonality of the
  dual basis Φ with the modified basis Ñ), and D_i = int Ñ_i; over random pairs, sum_j M_ij = D_i
  (the master's functions sum to one) and sum_i D_i is the overlap's area (the segments are
  those of the vertex triangles, as for linear elements).
* A flat non-matching interface reproduces linear fields: sum_j C_ij x_j = x̃_i (= x_i on a flat
  surface), rows of C sum to 1, D sums to the interface's area.
* The contact patch test on non-matching P2 meshes (frictionless, with friction, and with
  different moduli, where the interface slips): a uniform pressure at every slave node, vertices
  and edges alike, and the homogeneous solution, to 1e-8.
* The frictional stack rotated by Q gives Q u(Q^T x) to 1e-8; 1, 2 and 3 ranks the same
  displacements to 1e-9; a frictional path stopped and restarted continues as the uninterrupted one.
"""

from __future__ import annotations

import dataclasses
import tomllib

from mpi4py import MPI

import numpy as np
import pytest

from dolfinx import fem

from contactqvi.case import Step, load_case, parse_case
from contactqvi.contact.facets import MODIFIED_AREAS, modified_shapes
from contactqvi.contact.interface import BodyPair
from contactqvi.contact.mortar import mortar_coupling
from contactqvi.contact.problem import assemble_contact_problem
from contactqvi.contact.segments import quadratic_segment_integrals, segment_integrals, slave_moments
from contactqvi.laws import Frictionless
from contactqvi.meshes import boundary_facets
from contactqvi.parameters import ParameterError
from contactqvi.paraview import read_vtx
from contactqvi.problems.uniaxial import stacked_compression
from contactqvi.runner import build_problem, run_case
from mortar_checks import frame_invariance_error, linear_field_errors, rotation
from test_homogeneous_compression import DATA as STACK, HEIGHTS, _blocks as stack_blocks
from test_two_body import (NU, P, ROOT, _homogeneous, _patch_problem, _solve, _stack_problem, blocks,  # noqa: F401
                           on_all_ranks_and_alone)

#: barycentric coordinates of a 6-node triangle's nodes: the vertices, then the midside node of
#: the edge opposite each
NODES = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0.5, 0.5], [0.5, 0, 0.5], [0.5, 0.5, 0]])


@pytest.mark.one_rank(reason="segment integrals of given triangles (numpy), no search")
def test_a_master_equal_to_the_slave_gives_the_dual_weights():
    """Master = slave facet (its vertices listed from vertex 1 on): sum_j M_ij u_j = D_i ũ_i for
    each modified basis function ũ = e_k, whose nodal values are Ñ_k at the nodes, and
    D = area x (2/15, 2/15, 2/15, 1/5, 1/5, 1/5)."""
    slave = np.array([[[0.0, 0.0, 0.0], [2.0, 0.1, 0.0], [0.3, 1.5, 0.0]]])
    area = 0.5 * np.linalg.norm(np.cross(slave[0, 1] - slave[0, 0], slave[0, 2] - slave[0, 0]))
    D, M, S = quadratic_segment_integrals(slave, np.array([[0.0, 0.0, 1.0]]), slave[:, [1, 2, 0]] - [0.0, 0.0, 0.1])
    assert D[0] == pytest.approx(area * MODIFIED_AREAS, rel=1e-14)
    # master node j is slave node permutation[j]
    permutation = np.array([1, 2, 0, 4, 5, 3])
    in_slave_order = np.empty_like(M[0])
    in_slave_order[:, permutation] = M[0]
    nodal = modified_shapes(NODES)  # nodal[j, k]: the value of Ñ_k at node j
    assert in_slave_order @ nodal == pytest.approx(np.diag(D[0]), abs=1e-14 * area)
    assert S[0] == pytest.approx(in_slave_order, abs=1e-14 * area)  # the slave's moments: its own M


@pytest.mark.one_rank(reason="segment integrals of given triangles (numpy), no search")
def test_quadratic_segments_are_those_of_the_vertex_triangles():
    """Random pairs of triangles in parallel planes: sum_j M_ij = D_i and sum_k S_ik = D_i (the
    functions sum to one), and sum_i D_i equals the linear elements' (the overlap's area), whose
    slave moments also sum to their D."""
    rng = np.random.default_rng(11)
    count = 2000
    slave = np.concatenate([rng.uniform(-1.0, 1.0, (count, 3, 2)), np.zeros((count, 3, 1))], axis=2)
    master = np.concatenate([rng.uniform(-1.0, 1.0, (count, 3, 2)) + rng.uniform(-1.0, 1.0, (count, 1, 2)),
                             np.full((count, 3, 1), -0.1)], axis=2)
    normal = np.tile([0.0, 0.0, 1.0], (count, 1))
    D, M, S = quadratic_segment_integrals(slave, normal, master)
    linear, _ = segment_integrals(slave, normal, master)
    assert np.count_nonzero(linear.sum(axis=1)) > count // 5
    assert np.allclose(M.sum(axis=2), D, atol=1e-13)
    assert np.allclose(S.sum(axis=2), D, atol=1e-13)
    assert np.allclose(slave_moments(slave, normal, master).sum(axis=2), linear, atol=1e-13)
    assert np.allclose(D.sum(axis=1), linear.sum(axis=1), atol=1e-13)


@pytest.mark.parametrize("slave, master", [("upper", "lower"), ("lower", "upper")])
def test_flat_non_matching_quadratic_interface_is_integrated_exactly(blocks, slave, master):
    """sum_j C_ij x_j = x̃_i = x_i (the slave's modified positions on a flat surface), rows sum to
    1, gap 0, and D sums to the interface's area; every node of the slave surface is coupled."""
    msh, tags, _ = blocks
    V = fem.functionspace(msh, ("Lagrange", 2, (3,)))
    index_map = V.dofmap.index_map
    surface = boundary_facets(tags, f"{slave}.interface")
    coupling = mortar_coupling(V, surface, boundary_facets(tags, f"{master}.interface"), 0.1)
    comm = msh.comm
    assert max(linear_field_errors(V, coupling)) < 1e-14
    assert comm.allreduce(float(coupling.weight.sum()), op=MPI.SUM) == pytest.approx(1.0, rel=1e-13)
    nodes = fem.locate_dofs_topological(V, 2, surface)
    assert comm.allreduce(len(coupling.slave_blk), op=MPI.SUM) == comm.allreduce(
        int(np.count_nonzero(nodes < index_map.size_local)), op=MPI.SUM)


@pytest.mark.parametrize("young_upper, friction", [(1e9, 0.0), (1e9, 0.3), (3e9, 0.0)])
def test_quadratic_contact_patch_test(blocks, young_upper, friction):
    """The patch test with P2 on both blocks: the pressure lambda_i / D_ii is P at every slave node,
    and the displacement is the homogeneous one, to 1e-8 (measured 1e-11 and 5e-13)."""
    with _patch_problem(blocks, young_upper, friction, degree=2) as problem:
        result, displacement = _solve(problem, pc="lu")
        comm = problem.comm
        assert result.converged and problem.n_contact == 265
        pressure = result.normal_force / problem.contact_area
        assert comm.allreduce(float(np.abs(pressure / P - 1.0).max(initial=0.0)), op=MPI.MAX) < 1e-8
        n = problem.V.dofmap.index_map.size_local
        exact = _homogeneous(problem, 1e9, young_upper)[:n]
        error = np.abs(displacement.x.array.reshape(-1, 3)[:n] - exact).max(initial=0.0)
        assert comm.allreduce(float(error), op=MPI.MAX) < 1e-8 * comm.allreduce(float(np.abs(exact).max()),
                                                                                op=MPI.MAX)
        assert comm.allreduce(float(result.normal_force.sum()), op=MPI.SUM) == pytest.approx(P, rel=1e-10)


def test_quadratic_two_body_solution_is_frame_invariant(blocks):
    """The frictional stack of P2 blocks rotated by Q gives Q u(x) at the rotated nodes, to 1e-8."""
    msh, tags, cell_tags = blocks

    def solve(R: np.ndarray) -> np.ndarray:
        with _stack_problem(msh, tags, cell_tags, R, degree=2) as problem:
            result, displacement = _solve(problem, pc="lu")
            assert result.converged
            return displacement.x.array.reshape(-1, 3).copy()

    assert frame_invariance_error(msh, solve, rotation(np.array([1.0, 2.0, 2.0]) / 3.0, 0.7)) < 1e-8


@pytest.mark.ranks(2, 3)  # compares a parallel run with a serial one
def test_quadratic_two_body_parallel_equals_serial():
    """The patch blocks with slip (F = 0.3, different moduli), P2, on all ranks and on each rank
    alone (exact Newton-step solves): Newton counts within 1 (2 on 1 and 2 ranks, 3 on 3: the last step
    meets the stopping test on one partition only) and the same displacement at every node to 1e-9."""
    (parallel, serial), error = on_all_ranks_and_alone("lu", degree=2)
    assert abs(parallel - serial) <= 1
    assert error < 1e-9


def test_quadratic_pairs_refuse_the_geometry_inside_newton(blocks):
    """A pair searched "newton" with quadratic elements is a ParameterError named by the pair's search."""
    msh, tags, cell_tags = blocks
    pair = BodyPair("upper.interface", "lower.interface", Frictionless(), search="newton")
    with pytest.raises(ParameterError, match=r"search: quadratic elements take pairs searched once or each step"):
        assemble_contact_problem(msh, tags, 1e9, NU, {}, [pair], cell_tags=cell_tags, degree=2)


def _patch_case(case_file: str = "patch_test.toml", order: int = 2):
    """``cases/{case_file}`` (the patch blocks of tetrahedra, or ``hex_patch.toml`` of hexahedra) with
    elements of ``order``, the upper block three times stiffer (the interface slips) and the pressure
    in two steps."""
    case = load_case(ROOT / "cases" / case_file)
    upper = case.bodies[1]
    stiffer = dataclasses.replace(upper, material=dataclasses.replace(upper.material, young=3e9))
    return dataclasses.replace(case, mesh=dataclasses.replace(case.mesh, order=order),
                               bodies=(case.bodies[0], stiffer), steps=(Step(load=0.5), Step(load=1.0)))


@pytest.mark.parametrize("case_file", ["patch_test.toml", "hex_patch.toml"])
def test_a_quadratic_pair_restarts_exactly(mpi_tmp_path, case_file):
    """The frictional patch case with quadratic elements (P2 on tetrahedra, Q2 on hexahedra; searched
    before each step), stopped after step 1 and restarted: step 2 equals the uninterrupted run's, pair
    force and Newton count, to 1e-12."""
    case = _patch_case(case_file)
    whole, code = run_case(case, mpi_tmp_path / "whole", plot=False)
    assert code == 0
    _, code = run_case(case, mpi_tmp_path / "cut", plot=False, stop_after=1)
    assert code == 3
    resumed, code = run_case(case, mpi_tmp_path / "cut", plot=False, restart=True)
    assert code == 0
    a, b = whole["steps"][1], resumed["steps"][1]
    assert b["iterations"] == a["iterations"]
    (force,), (again,) = a["pair_forces"].values(), b["pair_forces"].values()
    assert again == pytest.approx(force, rel=1e-12, abs=1e-12 * np.abs(force).max())
    assert abs(force[2]) == pytest.approx(P, rel=1e-10)  # the whole load through the interface


def test_a_hyperelastic_quadratic_stack_searched_once_is_the_closed_form(mpi_tmp_path):
    """The neo-Hookean stack of tests/data/stacked_30.toml (two blocks of different moduli on non-matching
    meshes, expanding alike) with P2, the pair searched once, pressed 3 % and 6 %: the homogeneous closed
    form to 1e-8 of the travel (measured 5e-13) and no tangential pair force (1e-10 of the normal;
    measured 1e-16). Searched before each step it is refused (it did not converge: docs/quadratic.md
    Sect. 4)."""
    comm = MPI.COMM_WORLD
    data = tomllib.loads((STACK / "stacked_30.toml").read_text())
    data["mesh"]["order"] = 2
    data["contacts"][0]["search"] = "once"
    data["steps"] = [{"load": 0.1}, {"load": 0.2}]
    summary, code = run_case(parse_case(data, STACK), mpi_tmp_path, comm, plot=False)
    assert code == 0, summary["status"]
    blocks, travel = stack_blocks("stacked_30.toml")
    for k, step in enumerate(summary["steps"]):
        stack = stacked_compression(blocks, HEIGHTS, step["load"] * travel)
        if comm.rank == 0:
            dataset = read_vtx(mpi_tmp_path / "body.bp", k)
            body = dataset.cell_data_at_points("body [1]").astype(np.int64)
            error = np.abs(dataset.point_data["displacement [m]"] - stack.displacement(dataset.points, body)).max()
            assert error <= 1e-8 * stack.travel
        (force,) = step["pair_forces"].values()
        assert np.hypot(force[0], force[1]) <= 1e-10 * abs(force[2])
    data["contacts"][0]["search"] = "every_step"
    with pytest.raises(ParameterError, match=r"search: quadratic elements with a hyperelastic body take pairs of "
                       r"meshed bodies searched 'once'"):
        build_problem(parse_case(data, STACK), comm)
