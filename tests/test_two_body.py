"""Contact between meshed bodies: mortar geometry, the contact patch test, bad input.

The patch test (Taylor-Papadopoulos, here in 3D): two unit blocks with independent
tetrahedral meshes (h = 0.25 below, 0.16 above: non-matching at z = 1), rollers on
the planes x = 0, y = 0 and z = 0, a uniform pressure p on top. The upper block is
held along z by the contact alone. With one material the exact solution is the
homogeneous stress sigma_zz = -p, so u = (nu p x / E, nu p y / E, -p z / E); with
different moduli and no friction each block is homogeneous on its own and the
interface slips. Both are linear fields, so a discretisation that passes the patch
test reproduces them to round-off.
"""

from __future__ import annotations

import pathlib

from mpi4py import MPI

import numpy as np
import pytest
import scipy.spatial

from dolfinx import fem

from contactqvi.case import load_case
from contactqvi.contact.interface import BodyPair
from contactqvi.contact.mortar import mortar_coupling
from contactqvi.contact.segments import clip_polygons, segment_integrals
from contactqvi.contact.nodal import State
from contactqvi.contact.problem import assemble_contact_problem
from contactqvi.contact.scd_newton import SCDNewtonSolver
from contactqvi.laws import Coulomb
from contactqvi.elasticity import body_materials
from contactqvi.meshes import boundary_facets, read_gmsh, split_by_body
from contactqvi.parameters import ParameterError
from contactqvi.runner import run_case
from mortar_checks import frame_invariance_error, linear_field_errors, rotation

ROOT = pathlib.Path(__file__).resolve().parent.parent
MESH = ROOT / "meshes" / "patch_blocks.geo"
P = 1e6  # pressure on top (Pa)
NU = 0.3
ROLLERS = {"lower.bottom": {2: 0.0}, "lower.symmetry_x": {0: 0.0}, "upper.symmetry_x": {0: 0.0},
           "lower.symmetry_y": {1: 0.0}, "upper.symmetry_y": {1: 0.0}}


@pytest.fixture(scope="module")
def blocks():
    msh, facet_tags, cell_tags = read_gmsh(MESH, MPI.COMM_WORLD)
    return msh, split_by_body(msh, facet_tags, cell_tags), cell_tags


@pytest.mark.one_rank(reason="clipping and segment integrals of given triangles (numpy), no search")
def test_clipping_and_segment_integrals_of_one_pair():
    triangle = np.array([[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]])
    polygon = np.zeros((1, 6, 2))
    polygon[0, :3] = [[0.2, 0.2], [1.2, 0.2], [0.2, 1.2]]
    clipped, count = clip_polygons(polygon, np.array([3]), triangle)
    assert count[0] == 3
    assert np.allclose(clipped[0, :3], [[0.2, 0.2], [0.8, 0.2], [0.2, 0.8]], atol=1e-15)
    # a master triangle equal to the slave one: D = area/3, M = D (biorthogonality)
    slave = np.array([[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]])
    D, M = segment_integrals(slave, np.array([[0.0, 0.0, 1.0]]), slave[:, [1, 2, 0]] - [0.0, 0.0, 0.1])
    assert np.allclose(D, 1.0 / 6.0, atol=1e-15)
    assert np.allclose(M[0][:, [2, 0, 1]], np.eye(3) / 6.0, atol=1e-15)  # master vertex k is slave vertex (k+1) % 3


@pytest.mark.one_rank(reason="segment integrals of given triangles (numpy), no search")
def test_a_partly_covered_facet_takes_the_dual_basis_of_its_covered_part():
    """The slave triangle (0,0), (1,0), (0,1) covered for x >= 1/2 only (the triangle S of area 1/8,
    its centroid (2/3, 1/6)), by two master triangles: the whole facet's dual basis 4 phi_i - 1 gives
    D = 4 int_S phi_i - 1/8 = (-1/24, 5/24, -1/24); the covered part's basis gives D = int_S phi_i =
    (1/48, 1/12, 1/48), the rows of M sum to D, and a linear field p is reproduced,
    sum_j M_ij p(x_j) = D_i p(x_i) (biorthogonality over S: the patch test of a partly covered facet),
    which the whole facet's basis does not. A facet covered whole keeps the whole facet's basis."""
    from contactqvi.contact.covered import covered_basis
    from contactqvi.contact.segments import basis_integrals

    slave_x = np.array([[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]])
    up = np.array([[0.0, 0.0, 1.0]])  # the projection direction (the slave's inward normal)
    below = -0.1
    master_x = np.array([[[0.5, -1.0, below], [3.0, -1.0, below], [0.5, 1.0, below]],
                         [[3.0, -1.0, below], [3.0, 3.0, below], [0.5, 1.0, below]]])
    pairs_s = np.array([0, 0])

    def integrals(facets: np.ndarray, master: np.ndarray) -> tuple[np.ndarray, ...]:
        return basis_integrals(slave_x[facets], up[facets], master)

    D, M = segment_integrals(slave_x[pairs_s], up[pairs_s], master_x)
    assert np.allclose(D.sum(axis=0), [-1.0 / 24.0, 5.0 / 24.0, -1.0 / 24.0], rtol=0.0, atol=1e-15)
    D_c, M_c, covered = covered_basis(slave_x, master_x, pairs_s, D, M, integrals)
    assert covered is not None and covered.pairs.tolist() == [0, 1]
    assert np.allclose(D_c.sum(axis=0), [1.0 / 48.0, 1.0 / 12.0, 1.0 / 48.0], rtol=0.0, atol=1e-15)
    assert np.allclose(M_c.sum(axis=2), D_c, rtol=0.0, atol=1e-15)
    p = master_x[..., :2] + [0.3, -0.7]  # the field p(x) = (x + 0.3, y - 0.7) at the master vertices
    reproduced = np.einsum("paj,pjk->ak", M_c, p)
    assert np.allclose(reproduced, D_c.sum(axis=0)[:, None] * (slave_x[0, :, :2] + [0.3, -0.7]), rtol=0.0,
                       atol=1e-15)
    whole = np.einsum("paj,pjk->ak", M, p)
    assert np.abs(whole - D.sum(axis=0)[:, None] * (slave_x[0, :, :2] + [0.3, -0.7])).max() > 1e-3
    covering = np.array([[[-1.0, -1.0, below], [3.0, -1.0, below], [-1.0, 3.0, below]]])
    D, M = segment_integrals(slave_x, up, covering)
    D_c, M_c, covered = covered_basis(slave_x, covering, np.array([0]), D, M, integrals)
    assert covered is None and D_c is D and M_c is M


@pytest.mark.one_rank(reason="clipping and segment integrals of given triangles (numpy), no search")
def test_segment_integrals_of_random_pairs_sum_to_the_slave_weights():
    """Random slave and master triangles (about a third overlap, some touch at an edge): the
    pairs the separating-axis filter skips have no overlap (their clipped polygon has zero
    area), and sum_j M_ij = D_i (sum_j phi_j = 1 on the overlap) for all of them."""
    rng = np.random.default_rng(7)
    count = 4000
    slave = np.concatenate([rng.uniform(-1.0, 1.0, (count, 3, 2)), np.zeros((count, 3, 1))], axis=2)
    master = np.concatenate([rng.uniform(-1.0, 1.0, (count, 3, 2)) + rng.uniform(-1.5, 1.5, (count, 1, 2)),
                             np.full((count, 3, 1), -0.1)], axis=2)
    master[:50, :2] = slave[:50, [1, 0]]  # sharing the edge v0 v1, on the other side of it
    master[:50, 2, :2] = slave[:50, 0, :2] + slave[:50, 1, :2] - slave[:50, 2, :2]  # v2 mirrored
    normal = np.tile([0.0, 0.0, 1.0], (count, 1))
    D, M = segment_integrals(slave, normal, master)
    assert np.allclose(M.sum(axis=2), D, atol=1e-13)

    def ccw(t: np.ndarray) -> np.ndarray:
        d1, d2 = t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]
        return np.where((d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0] < 0.0)[:, None, None], t[:, [0, 2, 1]], t)

    polygon = np.zeros((count, 6, 2))
    polygon[:, :3] = ccw(master[..., :2])
    clipped, vertices = clip_polygons(polygon, np.full(count, 3), ccw(slave[..., :2]))
    area = np.zeros(count)
    for k in range(1, 5):  # fan areas of the brute-force clipping
        has = vertices >= k + 2
        d1, d2 = clipped[has, k] - clipped[has, 0], clipped[has, k + 1] - clipped[has, 0]
        area[has] += 0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
    skipped = ~np.any(M != 0.0, axis=(1, 2))
    assert np.all(area[skipped] <= 1e-14)
    assert 0.2 * count < np.count_nonzero(~skipped) < 0.8 * count
    assert np.allclose(D.sum(axis=1), area, atol=1e-13)  # sum_i psi_i = 1: D sums to the overlap's area


@pytest.mark.parametrize("slave, master", [("upper", "lower"), ("lower", "upper")])
def test_flat_non_matching_interface_is_integrated_exactly(blocks, slave, master):
    """sum_j C_ij x_j = x_i (linear fields are reproduced), rows sum to 1, gap 0, and the
    weights D_ii add up to the interface area."""
    msh, tags, _ = blocks
    V = fem.functionspace(msh, ("Lagrange", 1, (3,)))
    coupling = mortar_coupling(V, boundary_facets(tags, f"{slave}.interface"),
                               boundary_facets(tags, f"{master}.interface"), 0.1)
    comm = msh.comm
    assert max(linear_field_errors(V, coupling)) < 1e-14
    assert comm.allreduce(float(coupling.weight.sum()), op=MPI.SUM) == pytest.approx(1.0, rel=1e-13)
    assert np.allclose(coupling.normal, [0.0, 0.0, 1.0 if slave == "upper" else -1.0], atol=1e-14)


def _patch_problem(blocks, young_upper: float, friction: float, degree: int = 1):
    """The patch test's blocks with displacements of ``degree`` (P1 or P2)."""
    msh, tags, cell_tags = blocks
    young, poisson = body_materials(msh, cell_tags, {"lower": (1e9, NU), "upper": (young_upper, NU)})
    return assemble_contact_problem(msh, tags, young, poisson, {"upper.top": (0.0, 0.0, -P)},
                                    [BodyPair("upper.interface", "lower.interface", Coulomb(friction))],
                                    displacements=ROLLERS, cell_tags=cell_tags, degree=degree)


def _solve(problem, pc: str = "gamg"):
    u = problem.A.createVecRight()
    problem.shift.copy(u)  # from rest
    with SCDNewtonSolver(problem, {"pc": pc}, prefix="patch_") as solver:
        result = solver.solve(u)
    displacement = problem.physical_displacement(u, fem.Function(problem.V))
    u.destroy()
    return result, displacement


def _homogeneous(problem, young_lower: float, young_upper: float) -> np.ndarray:
    """Each block under sigma_zz = -P, free to expand laterally."""
    x = problem.V.tabulate_dof_coordinates()
    lower = problem.node_body == 0
    young = np.where(lower, young_lower, young_upper)
    uz = np.where(lower, -P * x[:, 2] / young_lower, -P / young_lower - P * (x[:, 2] - 1.0) / young_upper)
    return np.column_stack([NU * P * x[:, 0] / young, NU * P * x[:, 1] / young, uz])


@pytest.mark.parametrize("young_upper, friction", [(1e9, 0.0), (1e9, 0.3), (3e9, 0.0)])
def test_contact_patch_test(blocks, young_upper, friction):
    """Uniform pressure across the non-matching interface and the homogeneous solution,
    to 1e-8 relative (with the default GAMG Newton-step solver)."""
    with _patch_problem(blocks, young_upper, friction) as problem:
        result, displacement = _solve(problem)
        comm = problem.comm
        assert result.converged
        assert problem.n_contact > 0
        pressure = result.normal_force / problem.contact_area
        assert comm.allreduce(float(np.abs(pressure / P - 1.0).max(initial=0.0)), op=MPI.MAX) < 1e-8
        n = problem.V.dofmap.index_map.size_local
        exact = _homogeneous(problem, 1e9, young_upper)[:n]
        error = np.abs(displacement.x.array.reshape(-1, 3)[:n] - exact).max(initial=0.0)
        assert comm.allreduce(float(error), op=MPI.MAX) < 1e-8 * np.abs(exact).max()
        total = comm.allreduce(float(result.normal_force.sum()), op=MPI.SUM)
        assert total == pytest.approx(P * 1.0, rel=1e-10)  # the load, through the interface


def test_patch_test_with_slip_meets_the_coulomb_conditions(blocks):
    """Different moduli and F = 0.3: the blocks want to expand differently, so the rim
    slips. At every slave node: lambda >= 0, ||g|| <= F lambda, and sliding nodes carry
    ||g|| = F lambda against their slip (the resolvent's fixed point, checked by state)."""
    friction = 0.3
    with _patch_problem(blocks, 3e9, friction) as problem:
        result, _ = _solve(problem)
        comm = problem.comm
        assert result.converged
        lam, g = result.normal_force, result.friction_force
        scale = comm.allreduce(float(lam.max(initial=0.0)), op=MPI.MAX)
        assert comm.allreduce(float(lam.min(initial=0.0)), op=MPI.MIN) >= -1e-10 * scale
        excess = np.linalg.norm(g, axis=1) - friction * lam
        assert comm.allreduce(float(excess.max(initial=-np.inf)), op=MPI.MAX) <= 1e-8 * scale
        sliding = result.states == State.SLIDING
        assert comm.allreduce(int(np.count_nonzero(sliding)), op=MPI.SUM) > 0  # the interface slips somewhere
        assert np.allclose(np.linalg.norm(g[sliding], axis=1), friction * lam[sliding], rtol=1e-8, atol=1e-10 * scale)
        # equilibrium of the upper block along z: the contact carries the whole load
        assert comm.allreduce(float(lam.sum()), op=MPI.SUM) == pytest.approx(P, rel=1e-8)


def _shifted_blocks(blocks, dz: float):
    """The blocks with the upper one moved by dz along z (a new mesh geometry)."""
    msh, tags, cell_tags = blocks
    upper = cell_tags.find(cell_tags.names["upper"])
    nodes = np.unique(msh.geometry.dofmap[upper])
    original = msh.geometry.x[nodes, 2].copy()
    msh.geometry.x[nodes, 2] += dz
    return msh, nodes, original


@pytest.mark.parametrize("dz, message", [(-0.01, "initial penetration"), (5.0, "nowhere near")])
def test_bad_placement_is_reported_by_pair(blocks, dz, message):
    msh, nodes, original = _shifted_blocks(blocks, dz)
    try:
        with pytest.raises(ParameterError, match=message) as error:
            _patch_problem(blocks, 1e9, 0.0)
        assert "upper.interface/lower.interface" in str(error.value)
    finally:
        msh.geometry.x[nodes, 2] = original


def test_a_node_on_a_slave_and_a_master_surface_is_rejected(blocks):
    msh, tags, cell_tags = blocks
    young, poisson = body_materials(msh, cell_tags, {"lower": (1e9, NU), "upper": (1e9, NU)})
    pairs = [BodyPair("upper.interface", "lower.interface"), BodyPair("lower.interface", "upper.interface")]
    with pytest.raises(ParameterError, match="slave"):
        assemble_contact_problem(msh, tags, young, poisson, {}, pairs, displacements=ROLLERS, cell_tags=cell_tags)


def test_a_body_nothing_holds_is_named(blocks):
    """Without the upper block's rollers and without friction nothing holds it along x, y;
    the lower block is held by its own rollers."""
    msh, tags, cell_tags = blocks
    young, poisson = body_materials(msh, cell_tags, {"lower": (1e9, NU), "upper": (1e9, NU)})
    rollers = {name: value for name, value in ROLLERS.items() if not name.startswith("upper")}
    with pytest.raises(ParameterError, match="bodies.upper: nothing holds the body"):
        assemble_contact_problem(msh, tags, young, poisson, {"upper.top": (0.0, 0.0, -P)},
                                 [BodyPair("upper.interface", "lower.interface")], displacements=rollers,
                                 cell_tags=cell_tags)


def _stack_problem(msh, tags, cell_tags, rotation: np.ndarray, degree: int = 1):
    """The blocks without rollers: the lower one clamped at the bottom, the upper one held
    by friction (F = 0.5) under a pressure with a small shear, all rotated by ``rotation``;
    displacements of ``degree``."""
    young, poisson = body_materials(msh, cell_tags, {"lower": (1e9, NU), "upper": (3e9, 0.2)})
    traction = rotation @ np.array([0.1 * P, 0.05 * P, -P])
    return assemble_contact_problem(msh, tags, young, poisson, {"upper.top": tuple(traction)},
                                    [BodyPair("upper.interface", "lower.interface", Coulomb(0.5))],
                                    clamped=["lower.bottom"], cell_tags=cell_tags, degree=degree)


def test_two_body_solution_is_frame_invariant(blocks):
    """The stack rotated by a rotation Q gives the rotated solution Q u(x) at the rotated
    nodes Q x, to 1e-8 (exact inner solves; the tangential frames differ, the law is isotropic)."""
    msh, tags, cell_tags = blocks

    def solve(R: np.ndarray) -> np.ndarray:
        with _stack_problem(msh, tags, cell_tags, R) as problem:
            result, displacement = _solve(problem, pc="lu")
            assert result.converged
            return displacement.x.array.reshape(-1, 3).copy()

    assert frame_invariance_error(msh, solve, rotation(np.array([1.0, 2.0, 2.0]) / 3.0, 0.7)) < 1e-8


@pytest.mark.ranks(2)  # compares a parallel run with a serial one
@pytest.mark.parametrize("pc", ["lu", "gamg"])
def test_two_body_parallel_equals_serial(pc):
    """The patch blocks with slip (F = 0.3, different moduli) on all ranks and on each rank
    alone: the same displacement at every node to 1e-10 and Newton counts within 1, with
    exact and with GAMG Newton-step solves (the inexact ones depend on the partition through
    the aggregates: 6 and 7 on 1 and 2 ranks, measured)."""
    (parallel, serial), error = on_all_ranks_and_alone(pc)
    assert abs(parallel - serial) <= 1
    assert error < 1e-10


def on_all_ranks_and_alone(pc: str, degree: int = 1, mesh: pathlib.Path = MESH) -> tuple[tuple[int, int], float]:
    """The patch blocks of ``mesh`` with slip (F = 0.3, moduli 1 and 3 GPa), displacements of ``degree``,
    solved on all ranks and on each rank alone: the Newton counts (all, alone) and the largest difference
    of the displacements at a node over the largest displacement. Collective."""
    runs = {}
    for name, comm in (("parallel", MPI.COMM_WORLD), ("serial", MPI.COMM_SELF)):
        msh, facet_tags, cell_tags = read_gmsh(mesh, comm)
        problem = _patch_problem((msh, split_by_body(msh, facet_tags, cell_tags), cell_tags), 3e9, 0.3, degree)
        with problem:
            result, displacement = _solve(problem, pc)
            assert result.converged
            n = problem.V.dofmap.index_map.size_local
            # a node is its position and its body (the blocks' corners coincide at z = 1)
            x = np.column_stack([problem.V.tabulate_dof_coordinates()[:n], problem.node_body[:n]])
            runs[name] = (result.iterations, x, displacement.x.array.reshape(-1, 3)[:n].copy())
    iterations, x, u = runs["serial"]
    x_par, u_par = runs["parallel"][1:]
    distance, position = scipy.spatial.cKDTree(x).query(x_par)  # a quadratic space's midside nodes carry round-off
    assert distance.max(initial=0.0) < 1e-12
    error = MPI.COMM_WORLD.allreduce(float(np.abs(u_par - u[position]).max(initial=0.0)), op=MPI.MAX)
    return (runs["parallel"][0], iterations), error / np.abs(u).max()


def test_patch_case_file_reports_each_body_in_balance(mpi_tmp_path):
    """cases/patch_test.toml through the runner: the pair carries the load, every body and
    the whole are in balance, and the results are written."""
    summary, code = run_case(load_case(ROOT / "cases" / "patch_test.toml"), mpi_tmp_path / "patch", plot=False)
    assert code == 0
    step = summary["steps"][-1]
    assert step["pair_forces"]["upper.interface/lower.interface"] == pytest.approx([0.0, 0.0, P], abs=1e-6 * P)
    assert step["equilibrium_error"] < 1e-10
    assert set(step["body_equilibrium_errors"]) == {"lower", "upper"}
    assert max(step["body_equilibrium_errors"].values()) < 1e-10
    assert (mpi_tmp_path / "patch" / "body.bp").is_dir() and (mpi_tmp_path / "patch" / "contact_surface.bp").is_dir()
