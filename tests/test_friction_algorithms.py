"""PDAS/SS/ALM/Uzawa for Stadler's simplified friction problem (seed 002)."""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest

from contactqvi.friction import (
    FrictionActiveSetSolver,
    UzawaSolver,
    augmented_lagrangian,
    complementarity_residual,
    create_problem,
    semismooth_newton_sigma,
)
from contactqvi.friction.analysis import mirror_x1
from contactqvi.problems.stadler import stadler_example
from contactqvi.result import Status

from friction_checks import state_residual

ROUND_OFF = 1e-10


def _problem(example: int, N: int, discretisation: str = "q1"):
    return create_problem(MPI.COMM_WORLD, stadler_example(example), N=N, discretisation=discretisation)


def _shift(problem) -> np.ndarray:
    """A nonzero lambda_hat (a smooth function of the node coordinates, |lambda_hat| < 2g)."""
    x = problem.V.tabulate_dof_coordinates()[problem.boundary_dofs]
    return 1.5 * problem.g * np.sin(7.0 * x[:, 0] + 3.0 * x[:, 1])


@pytest.mark.parametrize("example", [1, 2, 3])
@pytest.mark.parametrize("discretisation", ["q1", "p1", "fd"])
@pytest.mark.parametrize("shifted", [False, True])
def test_pdas_termination_solves_optimality_system(example, discretisation, shifted):
    """Lemma 4.1: when the sets repeat, (3.2a)-(3.2c) hold to round-off at every node."""
    gamma, sigma = 50.0, 1.0
    with _problem(example, 17, discretisation) as problem, FrictionActiveSetSolver(problem) as pdas:
        lam_hat = _shift(problem) if shifted else problem.boundary_zeros()
        result = pdas.solve(gamma=gamma, sigma=sigma, lam_hat=lam_hat)
        assert result.status == Status.CONVERGED_ACTIVE_SET and result.converged
        assert 1 <= result.iterations <= 10
        lam, xi = result.lam, result.xi
        scale = problem.max_abs(problem.F.array_r)
        res_a = state_residual(problem, result.y.x.petsc_vec, lam) / scale
        res_b = problem.max_abs(problem.trace(result.y.x.petsc_vec) + (lam_hat - lam) / gamma - xi)
        res_c = problem.max_abs(complementarity_residual(xi, lam, problem.g, sigma))
        # (3.2c) for another sigma too: the solution does not depend on sigma.
        res_c_ss = problem.max_abs(complementarity_residual(xi, lam, problem.g, 1.0 / gamma))
        print(f"example {example} {discretisation}: residuals (3.2a) {res_a:.1e} (3.2b) {res_b:.1e} (3.2c) {res_c:.1e}")
        assert res_a < ROUND_OFF and res_b < ROUND_OFF and res_c < ROUND_OFF and res_c_ss < ROUND_OFF
        assert problem.max_abs(lam) <= problem.g * (1 + 1e-14)
        # the history reports the same residual, and the sets of the last solve are nontrivial
        assert result.history[-1]["residual_32c"] < ROUND_OFF
        assert 0 < problem.count(result.states != 0) < problem.n_boundary


@pytest.mark.parametrize("example", [2, 3])
def test_pdas_ss_and_alm_agree(example):
    """For fixed gamma, PDAS (sigma = 1), SS (sigma = 1/gamma) and step 1 of exact ALM give one solution."""
    gamma = 30.0
    with _problem(example, 17) as problem, FrictionActiveSetSolver(problem) as pdas:
        by_pdas = pdas.solve(gamma=gamma, sigma=1.0)
        y_pdas = by_pdas.y.x.array.copy()  # the solver's y is overwritten by its next solve
        by_ss = pdas.solve(gamma=gamma, sigma=semismooth_newton_sigma(gamma))
        y_ss = by_ss.y.x.array.copy()
        by_alm = augmented_lagrangian(pdas, gamma=gamma, inner="exact", max_outer=1)
        assert by_pdas.status == by_ss.status == Status.CONVERGED_ACTIVE_SET
        assert by_alm.status == Status.CONVERGED_ITERATIONS and by_alm.iterations == 1
        assert by_alm.inner_iterations == by_pdas.iterations and by_alm.linear_solves == by_pdas.iterations + 1
        for y, lam in ((y_ss, by_ss.lam), (by_alm.y.x.array, by_alm.lam)):
            assert problem.max_abs(y - y_pdas) < 1e-10
            assert problem.max_abs(lam - by_pdas.lam) < 1e-10
        for result in (by_pdas, by_ss, by_alm):
            assert problem.max_abs(result.lam) <= problem.g * (1 + 1e-14)


def test_alm_converges_to_lambda_bar():
    """(ALM) solves (P*) without gamma -> infinity: exact ALM with gamma = 1e3 reaches lambda_{1e16}."""
    with _problem(3, 17) as problem, FrictionActiveSetSolver(problem) as pdas:
        reference = pdas.solve(gamma=1e16)
        y_bar = reference.y.x.array.copy()
        result = augmented_lagrangian(pdas, gamma=1e3, reference=reference.lam, atol=1e-10, max_outer=10)
        d = [h["d_lambda"] for h in result.history]
        print("exact ALM d_lambda:", " ".join(f"{v:.2e}" for v in d))
        assert result.status == Status.CONVERGED_ATOL
        assert all(b < a for a, b in zip(d, d[1:]))  # monotone decrease, Theorem 5.5
        assert problem.max_abs(result.y.x.array - y_bar) < 1e-10
        assert problem.max_abs(result.lam) <= problem.g * (1 + 1e-14)
        # without a reference the test is on the change of lambda: another status
        unreferenced = augmented_lagrangian(pdas, gamma=1e3, atol=1e-10, max_outer=10)
        assert unreferenced.status == Status.CONVERGED_STEP
        assert unreferenced.history[-1]["lambda_change"] < 1e-10


def test_inexact_alm_halves_the_residual_and_accelerates_with_gamma_schedule():
    """Inexact ALM (Sect. 6.2): each inner solve halves the (3.2c) residual; gamma_l = 10^l converges fast."""
    with _problem(2, 21) as problem, FrictionActiveSetSolver(problem) as pdas:
        reference = pdas.solve(gamma=1e16).lam
        fixed = augmented_lagrangian(pdas, gamma=1e2, inner="inexact", reference=reference, max_outer=6)
        growing = augmented_lagrangian(pdas, schedule="power10", inner="inexact", reference=reference, max_outer=6)
    for result in (fixed, growing):
        assert result.status == Status.CONVERGED_ITERATIONS
        assert all(h["inner_status"] in ("converged_inexact", "converged_active_set") for h in result.history)
    assert [h["gamma"] for h in growing.history] == [10.0**k for k in range(1, 7)]
    d_fixed = [h["d_lambda"] for h in fixed.history]
    d_growing = [h["d_lambda"] for h in growing.history]
    print("inexact ALM gamma=1e2:", " ".join(f"{v:.1e}" for v in d_fixed))
    print("inexact ALM gamma=10^l:", " ".join(f"{v:.1e}" for v in d_growing))
    assert d_growing[-1] < 1e-9 and d_growing[-1] < 1e-3 * d_fixed[-1]
    assert all(b < a for a, b in zip(d_growing[1:], d_growing[2:]))


def test_alm_reports_a_failed_inner_solve():
    """An inner (PDAS) that cycles (sigma = 1e-3, Example 2) ends (ALM) with DIVERGED_INNER, not a silent result."""
    with _problem(2, 17) as problem, FrictionActiveSetSolver(problem) as pdas:
        parameters = {"gamma": 1e2, "sigma": 1e-3, "inner": "inexact"}
        first = augmented_lagrangian(pdas, max_outer=1, **parameters)
        y_first = first.y.x.array.copy()
        result = augmented_lagrangian(pdas, max_outer=3, **parameters)
        assert result.status == Status.DIVERGED_INNER and not result.converged and result.iterations == 2
        assert result.history[-1]["inner_status"] == "diverged_cycling"
        # y and lambda are the last accepted iterate, that of step 1 (a separate run: MUMPS on 2 ranks is
        # reproducible to round-off only), not the rejected one, which is O(1) away
        scale = problem.max_abs(first.lam)
        assert problem.max_abs(result.lam - first.lam) <= 1e-12 * scale
        assert np.allclose(result.y.x.array, y_first, rtol=0, atol=1e-12 * np.abs(y_first).max())
        assert result.history[-1]["lambda_change"] > 0.1 * scale


def test_pdas_inexact_stop_reduces_residual():
    """The inexact stopping rule: residual(3.2c) <= 1/2 initial residual at the end."""
    with _problem(3, 17) as problem, FrictionActiveSetSolver(problem) as pdas:
        result = pdas.solve(gamma=1e4, sigma=1.0, lam_hat=_shift(problem), residual_reduction=0.5)
    assert result.status in (Status.CONVERGED_INEXACT, Status.CONVERGED_ACTIVE_SET)
    assert result.history[-1]["residual_32c"] <= 0.5 * result.initial_residual
    assert all(h["residual_32c"] > 0.5 * result.initial_residual for h in result.history[:-1])


def test_pdas_reports_the_iteration_limit_and_a_failed_linear_solve():
    """DIVERGED_MAX_IT when the sets still change at the limit; DIVERGED_LINEAR_SOLVE when the KSP fails."""
    with _problem(3, 17) as problem:
        with FrictionActiveSetSolver(problem) as pdas:
            limited = pdas.solve(gamma=1e4, max_iterations=1)
        assert limited.status == Status.DIVERGED_MAX_IT and limited.iterations == 1
        options = {"ksp_type": "cg", "pc_type": "none", "ksp_max_it": 1, "ksp_rtol": 1e-12}
        with FrictionActiveSetSolver(problem, "friction_failing_", options) as pdas:
            failed = pdas.solve(gamma=1e4)
        assert failed.status == Status.DIVERGED_LINEAR_SOLVE and failed.iterations == 0


def test_regularisation_error_decreases_like_inverse_gamma():
    """|||y_gamma - y_bar||| ~ gamma^-1 (table in Fig. 6.1), slope fitted over gamma = 1e2 ... 1e5."""
    gammas = np.array([1e2, 1e3, 1e4, 1e5])
    with _problem(1, 21) as problem, FrictionActiveSetSolver(problem) as pdas:
        y_bar = pdas.solve(gamma=1e16).y.x.petsc_vec.copy()  # the solver's y is overwritten by its next solve
        errors = np.array([problem.energy_norm(pdas.solve(gamma=g).y.x.petsc_vec, y_bar) for g in gammas])
        y_bar.destroy()
    slope = np.polyfit(np.log10(gammas), np.log10(errors), 1)[0]
    print("|||y_gamma - y_bar|||:", " ".join(f"{e:.2e}" for e in errors), f"slope {slope:.3f}")
    assert -1.2 <= slope <= -0.8


def test_uzawa_converges_for_small_gamma_to_pdas_solution():
    """Uzawa (lambda^0 = 0, stop at d_lambda < tol) reaches the PDAS reference for a small step."""
    with _problem(1, 17) as problem, FrictionActiveSetSolver(problem) as pdas, UzawaSolver(problem) as solver:
        reference = pdas.solve(gamma=1e16).lam
        seen = []
        result = solver.solve(
            gamma=5.0, reference=reference, atol=1e-8, max_iterations=500,
            monitor=lambda l, y, lam: seen.append((l, problem.boundary_norm(reference - lam))),
        )  # fmt: skip
        print("Uzawa iterations:", result.iterations)
        assert result.status == Status.CONVERGED_ATOL and result.iterations > 5
        assert seen == [(h["l"], h["d_lambda"]) for h in result.history]
        assert problem.max_abs(result.lam) <= problem.g
        stalled = solver.solve(gamma=5.0, reference=reference, atol=1e-8, max_iterations=3)
        assert stalled.status == Status.DIVERGED_MAX_IT and stalled.iterations == 3
        unreferenced = solver.solve(gamma=5.0, atol=1e-6)
        assert unreferenced.status == Status.CONVERGED_STEP and unreferenced.history[-1]["lambda_change"] < 1e-6


def test_ss_chatters_for_large_gamma_where_pdas_converges():
    """Sect. 6.2/6.3: for large gamma (SS) moves nodes between A- and A+ and cycles; (PDAS, sigma = 1) does not."""
    gamma = 1e10
    with _problem(3, 41) as problem, FrictionActiveSetSolver(problem) as pdas:
        by_ss = pdas.solve(gamma=gamma, sigma=semismooth_newton_sigma(gamma))
        by_pdas = pdas.solve(gamma=gamma, sigma=1.0)
    switches_ss = [h["switches_between_active_sets"] for h in by_ss.history[1:]]
    switches_pdas = [h["switches_between_active_sets"] for h in by_pdas.history[1:]]
    print("SS A-/A+ switches per iteration:", switches_ss)
    assert by_ss.status == Status.DIVERGED_CYCLING and not by_ss.converged and sum(switches_ss) > 0
    assert by_pdas.status == Status.CONVERGED_ACTIVE_SET and by_pdas.iterations <= 8 and sum(switches_pdas) == 0


def test_ss_converges_superlinearly():
    """Table 6.2: q_lambda^k = ||lambda^k - lambda_gamma|| / ||lambda^(k-1) - lambda_gamma|| decreases to 0."""
    gamma, iterates = 50.0, []
    with _problem(2, 41) as problem, FrictionActiveSetSolver(problem) as pdas:
        result = pdas.solve(gamma=gamma, sigma=1.0 / gamma, monitor=lambda k, y, lam, xi: iterates.append((k, lam.copy())))
        assert [k for k, _ in iterates] == list(range(result.iterations + 1))
        distances = [problem.boundary_norm(lam - result.lam) for _, lam in iterates]
    q = [b / a for a, b in zip(distances, distances[1:])]
    print("q_lambda^k:", " ".join(f"{v:.2f}" for v in q))
    assert result.status == Status.CONVERGED_ACTIVE_SET and len(q) >= 3
    assert q[-1] == 0.0 and all(b < a for a, b in zip(q[:-1], q[1:])) and q[0] < 1.0


@pytest.mark.parametrize("N", [20, 40, 80])
def test_example1_load_and_multiplier_are_odd_about_the_middle(N):
    """Example 1's f is odd about x1 = 1/2, so are (f, v) and lambda_bar, as on the paper's grids (even N)."""
    with _problem(1, N) as problem, FrictionActiveSetSolver(problem) as pdas:
        n_owned = problem.V.dofmap.index_map.size_local
        x = problem.V.tabulate_dof_coordinates()
        load = problem.F.array_r
        load_defect = problem.max_abs(load + mirror_x1(problem.comm, x[:n_owned], load))
        lam = pdas.solve(gamma=1e16).lam
        lam_defect = problem.max_abs(lam + mirror_x1(problem.comm, x[problem.boundary_dofs], lam))
        scale = problem.max_abs(load)
    print(f"N = {N}: odd-part defects of (f, v) {load_defect:.1e}, of lambda_bar {lam_defect:.1e}")
    assert load_defect < 1e-13 * scale and lam_defect < 1e-10
