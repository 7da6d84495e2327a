"""PDAS/SS/ALM/Uzawa for Stadler's simplified friction problem (seed 002)."""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest

from contactqvi.friction import (
    PrimalDualActiveSet,
    augmented_lagrangian,
    complementarity_residual,
    semismooth_newton_sigma,
    uzawa,
)
from contactqvi.problems.stadler import create_stadler_problem, stadler_example

ROUND_OFF = 1e-10


def _problem(example: int, N: int, cell_type: str = "quadrilateral"):
    return create_stadler_problem(MPI.COMM_WORLD, stadler_example(example), N, cell_type)


def _shift(problem):
    """A nonzero lambda_hat (a smooth function of the node coordinates, |lambda_hat| < 2g)."""
    lam_hat = problem.create_boundary_vector()
    x = problem.V.tabulate_dof_coordinates()[problem.boundary_dofs]
    lam_hat.array[:] = 1.5 * problem.g * np.sin(7.0 * x[:, 0] + 3.0 * x[:, 1])
    return lam_hat


def _max(problem, values: np.ndarray) -> float:
    return problem.comm.allreduce(float(np.abs(values).max(initial=0.0)), op=MPI.MAX)


@pytest.mark.parametrize("example", [1, 2, 3])
@pytest.mark.parametrize("cell_type", ["quadrilateral", "triangle"])
@pytest.mark.parametrize("shifted", [False, True])
def test_pdas_termination_solves_optimality_system(example, cell_type, shifted):
    """Lemma 4.1: when the sets repeat, (3.2a)-(3.2c) hold to round-off at every node."""
    problem = _problem(example, 17, cell_type)
    pdas = PrimalDualActiveSet(problem)
    gamma, sigma = 50.0, 1.0
    lam_hat = _shift(problem) if shifted else problem.create_boundary_vector()
    result = pdas.solve(gamma, sigma, lam_hat=lam_hat)
    assert result.status == "converged"
    assert 1 <= result.iterations <= 10
    work = problem.K.createVecLeft()
    lam, xi = result.lam.array_r, result.xi.array_r
    scale = _max(problem, problem.F.array_r)
    res_a = problem.state_residual(result.y.x.petsc_vec, lam, work) / scale
    res_b = _max(problem, problem.trace(result.y.x.petsc_vec) + (lam_hat.array_r - lam) / gamma - xi)
    res_c = _max(problem, complementarity_residual(xi, lam, problem.g, sigma))
    # (3.2c) for another sigma too: the solution does not depend on sigma.
    res_c_ss = _max(problem, complementarity_residual(xi, lam, problem.g, 1.0 / gamma))
    print(f"example {example} {cell_type}: residuals (3.2a) {res_a:.1e} (3.2b) {res_b:.1e} (3.2c) {res_c:.1e}")
    assert res_a < ROUND_OFF and res_b < ROUND_OFF and res_c < ROUND_OFF and res_c_ss < ROUND_OFF
    assert _max(problem, lam) <= problem.g * (1 + 1e-14)
    # the history reports the same residual, and the sets of the last solve are nontrivial
    assert result.history[-1]["residual_32c"] < ROUND_OFF
    n_active = problem.count(result.states != 0)
    assert 0 < n_active < problem.n_boundary


@pytest.mark.parametrize("example", [2, 3])
def test_pdas_ss_and_alm_agree(example):
    """For fixed gamma, PDAS (sigma = 1), SS (sigma = 1/gamma) and step 1 of exact ALM give one solution."""
    problem = _problem(example, 17)
    pdas = PrimalDualActiveSet(problem)
    gamma = 30.0
    by_pdas = pdas.solve(gamma, 1.0)
    by_ss = pdas.solve(gamma, semismooth_newton_sigma(gamma))
    by_alm = augmented_lagrangian(pdas, gamma, inner="exact", max_outer=1)
    assert by_pdas.status == by_ss.status == "converged" and by_alm.status == "completed"
    for other in (by_ss, by_alm):
        dy = other.y.x.petsc_vec - by_pdas.y.x.petsc_vec
        assert dy.norm(0) < 1e-10  # NORM_INFINITY on the owned part, global
        assert _max(problem, other.lam.array_r - by_pdas.lam.array_r) < 1e-10
    for result in (by_pdas, by_ss, by_alm):
        assert _max(problem, result.lam.array_r) <= problem.g * (1 + 1e-14)


def test_alm_converges_to_lambda_bar():
    """(ALM) solves (P*) without gamma -> infinity: exact ALM with gamma = 1e3 reaches lambda_{1e16}."""
    problem = _problem(3, 17)
    pdas = PrimalDualActiveSet(problem)
    reference = pdas.solve(1e16)
    result = augmented_lagrangian(pdas, 1e3, inner="exact", reference=reference.lam, tol=1e-10, max_outer=10)
    d = [h["d_lambda"] for h in result.history]
    print("exact ALM d_lambda:", " ".join(f"{v:.2e}" for v in d))
    assert result.status == "converged"
    assert all(b < a for a, b in zip(d, d[1:]))  # monotone decrease, Theorem 5.5
    y_error = (result.y.x.petsc_vec - reference.y.x.petsc_vec).norm(0)
    assert y_error < 1e-10
    assert _max(problem, result.lam.array_r) <= problem.g * (1 + 1e-14)


def test_inexact_alm_halves_the_residual_and_accelerates_with_gamma_schedule():
    """Inexact ALM (Sect. 6.2): each inner solve halves the (3.2c) residual; gamma_l = 10^l converges fast."""
    problem = _problem(2, 21)
    pdas = PrimalDualActiveSet(problem)
    reference = pdas.solve(1e16).lam
    fixed = augmented_lagrangian(pdas, 1e2, inner="inexact", reference=reference, max_outer=6)
    growing = augmented_lagrangian(pdas, lambda step: 10.0**step, inner="inexact", reference=reference, max_outer=6)
    for result in (fixed, growing):
        assert all(h["inner_status"] in ("inexact", "converged") for h in result.history)
    d_fixed = [h["d_lambda"] for h in fixed.history]
    d_growing = [h["d_lambda"] for h in growing.history]
    print("inexact ALM gamma=1e2:", " ".join(f"{v:.1e}" for v in d_fixed))
    print("inexact ALM gamma=10^l:", " ".join(f"{v:.1e}" for v in d_growing))
    assert d_growing[-1] < 1e-9 and d_growing[-1] < 1e-3 * d_fixed[-1]
    assert all(b < a for a, b in zip(d_growing[1:], d_growing[2:]))


def test_pdas_inexact_stop_reduces_residual():
    """The inexact stopping rule: residual(3.2c) <= 1/2 initial residual at the end."""
    problem = _problem(3, 17)
    pdas = PrimalDualActiveSet(problem)
    result = pdas.solve(1e4, 1.0, lam_hat=_shift(problem), residual_reduction=0.5)
    assert result.status in ("inexact", "converged")
    assert result.history[-1]["residual_32c"] <= 0.5 * result.initial_residual
    assert all(h["residual_32c"] > 0.5 * result.initial_residual for h in result.history[:-1])


def test_regularisation_error_decreases_like_inverse_gamma():
    """|||y_gamma - y_bar||| ~ gamma^-1 (table in Fig. 6.1), slope fitted over gamma = 1e2 ... 1e5."""
    problem = _problem(1, 21)
    pdas = PrimalDualActiveSet(problem)
    y_bar = pdas.solve(1e16).y  # keep the Function alive: its petsc_vec wraps the Function's memory
    gammas = np.array([1e2, 1e3, 1e4, 1e5])
    errors = []
    for gamma in gammas:
        y_gamma = pdas.solve(gamma, 1.0).y
        errors.append(problem.energy_norm(y_gamma.x.petsc_vec - y_bar.x.petsc_vec))
    errors = np.array(errors)
    slope = np.polyfit(np.log10(gammas), np.log10(errors), 1)[0]
    print("|||y_gamma - y_bar|||:", " ".join(f"{e:.2e}" for e in errors), f"slope {slope:.3f}")
    assert -1.2 <= slope <= -0.8


def test_uzawa_converges_for_small_gamma_to_pdas_solution():
    """Uzawa (lambda^0 = 0, stop at d_lambda < tol) reaches the PDAS reference for a small step."""
    problem = _problem(1, 17)
    pdas = PrimalDualActiveSet(problem)
    reference = pdas.solve(1e16).lam
    seen = []
    result = uzawa(
        problem, 5.0, reference=reference, tol=1e-8, max_iterations=500,
        monitor=lambda l, y, lam: seen.append((l, problem.boundary_norm(reference.array_r - lam.array_r))),
    )  # fmt: skip
    print("Uzawa iterations:", result.iterations)
    assert result.converged and result.iterations > 5
    assert seen == [(h["l"], h["d_lambda"]) for h in result.history]
    assert _max(problem, result.lam.array_r) <= problem.g
    stalled = uzawa(problem, 5.0, reference=reference, tol=1e-8, max_iterations=3)
    assert stalled.status == "max_iterations" and stalled.iterations == 3


def test_ss_chatters_for_large_gamma_where_pdas_converges():
    """Sect. 6.2/6.3: for large gamma (SS) moves nodes between A- and A+ and cycles; (PDAS, sigma = 1) does not."""
    problem = _problem(3, 41)
    pdas = PrimalDualActiveSet(problem)
    gamma = 1e10
    by_ss = pdas.solve(gamma, semismooth_newton_sigma(gamma))
    by_pdas = pdas.solve(gamma, 1.0)
    switches_ss = [h["switches_between_active_sets"] for h in by_ss.history[1:]]
    switches_pdas = [h["switches_between_active_sets"] for h in by_pdas.history[1:]]
    print("SS A-/A+ switches per iteration:", switches_ss)
    assert by_ss.status == "cycling" and sum(switches_ss) > 0
    assert by_pdas.status == "converged" and by_pdas.iterations <= 8 and sum(switches_pdas) == 0


def test_ss_converges_superlinearly():
    """Table 6.2: q_lambda^k = ||lambda^k - lambda_gamma|| / ||lambda^(k-1) - lambda_gamma|| decreases to 0."""
    problem = _problem(2, 41)
    pdas = PrimalDualActiveSet(problem)
    gamma = 50.0
    iterates = []
    result = pdas.solve(gamma, 1.0 / gamma, monitor=lambda k, y, lam, xi: iterates.append((k, lam.array_r.copy())))
    assert [k for k, _ in iterates] == list(range(result.iterations + 1))
    distances = [problem.boundary_norm(lam - result.lam.array_r) for _, lam in iterates]
    q = [b / a for a, b in zip(distances, distances[1:])]
    print("q_lambda^k:", " ".join(f"{v:.2f}" for v in q))
    assert result.status == "converged" and len(q) >= 3
    assert q[-1] == 0.0 and all(b < a for a, b in zip(q[:-1], q[1:])) and q[0] < 1.0


def _odd_part_defect(problem, N: int, dofs: np.ndarray, values: np.ndarray) -> float:
    """max |v(x1, x2) + v(1 - x1, x2)| over the nodes ``dofs`` (owned, local) of the N x N grid, all ranks."""
    ij = np.rint(problem.V.tabulate_dof_coordinates()[dofs, :2] * (N - 1)).astype(np.int64)
    ijs, vs = problem.comm.gather(ij, root=0), problem.comm.gather(values.copy(), root=0)
    defect = None
    if problem.comm.rank == 0:
        ij, values = np.vstack(ijs), np.concatenate(vs)
        code = ij[:, 0] * N + ij[:, 1]
        order = np.argsort(code)
        mirror = order[np.searchsorted(code[order], (N - 1 - ij[:, 0]) * N + ij[:, 1])]
        defect = float(np.abs(values + values[mirror]).max())
    return problem.comm.bcast(defect, root=0)


@pytest.mark.parametrize("N", [20, 40, 80])
def test_example1_load_and_multiplier_are_odd_about_the_middle(N):
    """Example 1's f is odd about x1 = 1/2, so are (f, v) and lambda_bar, as on the paper's grids (even N)."""
    problem = _problem(1, N)
    n_owned = problem.V.dofmap.index_map.size_local
    load_defect = _odd_part_defect(problem, N, np.arange(n_owned), problem.F.array_r)
    lam = PrimalDualActiveSet(problem).solve(1e16).lam.array_r
    lam_defect = _odd_part_defect(problem, N, problem.boundary_dofs, lam)
    print(f"N = {N}: odd-part defects of (f, v) {load_defect:.1e}, of lambda_bar {lam_defect:.1e}")
    scale = problem.F.norm(0)  # NORM_INFINITY on the owned part, global
    assert load_defect < 1e-13 * scale and lam_defect < 1e-10
