"""The paper's finite-difference scheme (seed 002, Sect. 6; contactqvi/friction/finite_differences.py).

Matrix properties, consistency on quadratics (exact for the five-point stencil,
first order for the one-sided normal differences), agreement with Q1 under
refinement, the same matrix on 1 and N ranks; on the paper's own grids, what the
paper reports (its Uzawa counts, the rates of Table 6.2, the behaviour of (SS) in
Table 6.1), and a regression guard of our own counts.
"""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest

from contactqvi.friction import FrictionActiveSetSolver, UzawaSolver, create_problem, semismooth_newton_sigma
from contactqvi.friction.analysis import iteration_count, set_changes
from contactqvi.problems.stadler import PAPER, REFERENCE_GAMMA, stadler_example


def _fd(example: int, N: int, comm: MPI.Comm = MPI.COMM_WORLD):
    return create_problem(comm, stadler_example(example), N=N, discretisation="fd")


def _grid_matrix(problem) -> np.ndarray | None:
    """K in grid numbering (row/column i N + j of the node (i h, j h)), dense, gathered on rank 0."""
    index_map, N = problem.V.dofmap.index_map, problem.N
    codes = problem.ij[:, 0] * N + problem.ij[:, 1]
    glob = index_map.local_range[0] + np.arange(index_map.size_local)
    indptr, indices, values = problem.K.getValuesCSR()
    rows = np.repeat(codes, np.diff(indptr))
    parts = problem.comm.gather((glob, codes, rows, indices, values), root=0)
    if problem.comm.rank != 0:
        return None
    code_of = np.empty(index_map.size_global, dtype=np.int64)
    dense = np.zeros((N * N, N * N))
    for glob, codes, *_ in parts:
        code_of[glob] = codes
    for *_, rows, columns, values in parts:
        dense[rows, code_of[columns]] = values
    return dense


def _on_rank0(comm: MPI.Comm, check) -> None:
    """Run ``check()`` on rank 0 and fail on every rank with its message."""
    message = None
    if comm.rank == 0:
        try:
            check()
        except AssertionError as exc:
            message = str(exc) or "assertion failed"
    message = comm.bcast(message, root=0)
    assert message is None, message


@pytest.mark.parametrize("example", [1, 2, 3])
def test_matrix_is_a_nonsingular_m_matrix_symmetric_without_friction_corners(example):
    """Positive diagonal, nonpositive off-diagonal, row sums >= 0; symmetric except at friction corners.

    Example 1 (friction on top/bottom, Dirichlet left/right) has no corner between two
    friction edges: K is symmetric positive definite. Examples 2 and 3 have four; the
    only asymmetric entries couple a corner row (mean of two one-sided differences) with
    its two edge neighbours, whose one-sided rows do not reach back.
    """
    with _fd(example, 9) as problem:
        K, N = _grid_matrix(problem), problem.N

        def check():
            off = K - np.diag(np.diag(K))
            assert np.all(np.diag(K) > 0) and np.all(off <= 0) and np.all(K.sum(axis=1) >= -1e-14)
            unsymmetric = np.flatnonzero(np.abs(K - K.T).max(axis=1) > 0)
            corners = {0, N - 1, N * (N - 1), N * N - 1}
            if example == 1:
                assert unsymmetric.size == 0
                assert np.linalg.eigvalsh(K).min() > 0
            else:
                unsymmetric_rows = set(unsymmetric) - {c + s for c in corners for s in (-N, -1, 1, N)}
                assert unsymmetric_rows <= corners, sorted(unsymmetric_rows)
                assert np.linalg.eigvals(K).real.min() > 0

        _on_rank0(problem.comm, check)


@pytest.mark.parametrize("example", [2, 3])
def test_consistency_on_a_quadratic(example):
    """q = x1^2 + 2 x2^2 + x1 x2 + 3 x1: interior rows give h^2 (-Laplace q + mu q) exactly; a friction row divided
    by m_P gives the mean over its one-sided directions of dq/dn - (h/2) d2q/dn2 (Taylor, exact for quadratics)."""
    with _fd(example, 11) as problem:
        h, n_owned = problem.h, problem.V.dofmap.index_map.size_local
        x = problem.V.tabulate_dof_coordinates()[:n_owned, :2]
        q = problem.K.createVecRight()
        q.array[:] = x[:, 0] ** 2 + 2 * x[:, 1] ** 2 + x[:, 0] * x[:, 1] + 3 * x[:, 0]
        Kq = problem.K.createVecLeft()
        problem.K.mult(q, Kq)
        interior = problem.interior
        expected = h**2 * (-6.0 + problem.mu * q.array[interior])
        assert problem.max_abs(Kq.array[interior] - expected) < 1e-13
        b = problem.boundary_dofs
        inward = np.where(problem.ij[b] == 0, 1, np.where(problem.ij[b] == problem.N - 1, -1, 0))
        gradient = np.column_stack([2 * x[b, 0] + x[b, 1] + 3, 4 * x[b, 1] + x[b, 0]])
        second = np.array([2.0, 4.0])  # d2q/dx1^2, d2q/dx2^2
        taylor = (-inward * gradient - (h / 2) * second * (inward != 0)).sum(axis=1) / (inward != 0).sum(axis=1)
        assert problem.max_abs(Kq.array[b] / problem.boundary_mass - taylor) < 1e-12
        ones = problem.K.createVecRight()
        ones.set(1.0)
        problem.K.mult(ones, Kq)  # row sums: mu h^2 inside, 0 on Gamma_f
        assert problem.max_abs(Kq.array[interior] - problem.mu * h**2) < 1e-15
        assert problem.max_abs(Kq.array[b]) < 1e-15
        for vec in (q, Kq, ones):
            vec.destroy()


def test_load_is_sampled_at_interior_nodes():
    """F = h^2 f(P) at interior nodes (Example 2's smooth f), 0 on the boundary."""
    with _fd(2, 13) as problem:
        n_owned = problem.V.dofmap.index_map.size_local
        x = problem.V.tabulate_dof_coordinates()[:n_owned]
        f = 10.0 * (np.sin(4 * np.pi * x[:, 0]) + np.cos(4 * np.pi * x[:, 1]))
        expected = np.where(problem.interior, problem.h**2 * f, 0.0)
        assert problem.max_abs(problem.F.array_r - expected) < 1e-14


def test_same_matrix_on_one_and_all_ranks():
    comm = MPI.COMM_WORLD
    with _fd(3, 9, MPI.COMM_SELF) as serial, _fd(3, 9, comm) as parallel:
        K_serial, K_parallel = _grid_matrix(serial), _grid_matrix(parallel)
        _on_rank0(comm, lambda: np.testing.assert_array_equal(K_serial, K_parallel))


@pytest.mark.parametrize("example", [2, 3])
def test_agrees_with_q1_under_refinement(example):
    """y_bar of FD and Q1 on the same grid points differ by O(h): the difference halves with h."""
    differences = []
    for N in (11, 21, 41, 81):
        y = {}
        for discretisation in ("q1", "fd"):
            problem = create_problem(MPI.COMM_WORLD, stadler_example(example), N=N, discretisation=discretisation)
            with problem, FrictionActiveSetSolver(problem) as pdas:
                result = pdas.solve(gamma=REFERENCE_GAMMA)
                assert result.converged
                y[discretisation] = result.y.x.array[: problem.V.dofmap.index_map.size_local].copy()
        differences.append(problem.max_abs(y["q1"] - y["fd"]))  # same mesh, same dof numbering
    print(f"example {example}: max |y_Q1 - y_FD| =", " ".join(f"{d:.2e}" for d in differences))
    assert all(b < 0.65 * a for a, b in zip(differences, differences[1:]))
    assert differences[-1] < 0.03


@pytest.fixture(scope="module")
def example1_n80():
    """Example 1 on the paper's grid N = 80 with its (PDAS) solver and lambda_bar = lambda_1e16."""
    problem = create_problem(MPI.COMM_WORLD, stadler_example(1), N=80, discretisation="fd")
    pdas = FrictionActiveSetSolver(problem)
    reference = pdas.solve(gamma=REFERENCE_GAMMA, max_iterations=100)
    assert reference.converged
    yield problem, pdas, reference.lam
    pdas.destroy()
    problem.destroy()


def _table_6_1(pdas: FrictionActiveSetSolver) -> dict[str, list]:
    ss = [pdas.solve(gamma=gamma, sigma=semismooth_newton_sigma(gamma)) for gamma in PAPER["6.1"]["gamma"]]
    return {
        "ss": [iteration_count(r) for r in ss],
        "pdas": [iteration_count(pdas.solve(gamma=gamma, sigma=1.0)) for gamma in PAPER["6.1"]["gamma"]],
        "changes": [set_changes(r) for r in ss],
        "switches": [sum(h["switches_between_active_sets"] or 0 for h in r.history) for r in ss],
    }


def test_table_6_1_as_the_paper_reports_it(example1_n80):
    """Sect. 6.1: (SS) needs very few iterations, as many for gamma = 1e8 as for 1e2; no node moves between A-
    and A+ within an iteration, so (PDAS) with sigma = 1 >= 1/gamma takes the same iterates (the same counts)."""
    _, pdas, _ = example1_n80
    table = _table_6_1(pdas)
    assert len(set(table["ss"])) == 1 and table["pdas"] == table["ss"] and table["switches"] == [0, 0, 0, 0]
    assert all(abs(ours - paper) <= 1 for ours, paper in zip(table["ss"], PAPER["6.1"]["ss"]))


def test_regression_guard_table_6_1_counts(example1_n80):
    """Regression guard, our own numbers (not the paper's: 2 3 3 3 for (SS)): the counts and set changes of
    benchmarks/results/stadler_6_1_fd.md."""
    _, pdas, _ = example1_n80
    table = _table_6_1(pdas)
    assert table["ss"] == [3, 3, 3, 3] and table["pdas"] == [3, 3, 3, 3]
    assert table["changes"] == [[12, 4], [16, 4], [16, 4], [16, 4]]


def test_uzawa_as_the_paper_reports_it(example1_n80):
    """Sect. 6.1, N = 80: Uzawa from lambda^0 = 0 stops (d_lambda < 1e-4) after 32 iterations for gamma = 10
    and 17 for gamma = 20, and does not converge for gamma = 30 (here: d_lambda grows)."""
    problem, _, lam_bar = example1_n80
    paper = PAPER["uzawa"]["example1_N80"]
    with UzawaSolver(problem) as uzawa:
        counts = {f"{g:g}": uzawa.solve(gamma=g, reference=lam_bar).iterations for g in (10.0, 20.0)}
        unstable = uzawa.solve(gamma=30.0, reference=lam_bar, max_iterations=100)
    assert counts == {"10": paper["10"], "20": paper["20"]} == {"10": 32, "20": 17}
    d_lambda = [h["d_lambda"] for h in unstable.history]
    assert paper["30"] == "no convergence" and not unstable.converged and d_lambda[-1] > 10 * min(d_lambda)


def test_table_6_2_rates_as_the_paper_reports_them():
    """Table 6.2, Example 2, N = 160, (SS) with gamma = 50: q_lambda^k decreases to 0 (superlinear convergence,
    Theorem 5.1), and its first two values are the paper's (0.58, 0.45) to 0.01."""
    problem = create_problem(MPI.COMM_WORLD, stadler_example(2), N=160, discretisation="fd")
    iterates = []
    with problem, FrictionActiveSetSolver(problem) as pdas:
        gamma = float(PAPER["6.2"]["gamma"])
        result = pdas.solve(gamma=gamma, sigma=semismooth_newton_sigma(gamma),
                            monitor=lambda k, y, lam, xi: iterates.append(lam.copy()))  # fmt: skip
        distances = [problem.boundary_norm(lam - result.lam) for lam in iterates]
    q = [b / a for a, b in zip(distances, distances[1:])]
    print("q_lambda^k:", " ".join(f"{v:.3f}" for v in q), "paper:", PAPER["6.2"]["q"])
    assert result.converged and all(b < a for a, b in zip(q, q[1:])) and q[-1] < 1e-12
    assert np.allclose(q[:2], PAPER["6.2"]["q"][:2], atol=0.01)
