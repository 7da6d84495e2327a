"""The runs behind the tables of seed 002, Sect. 6: which example, grid, gamma and method, as data.

Each ``table_*`` function runs the solvers of :mod:`contactqvi.friction` on one
discretisation (``q1``, ``p1`` or ``fd``) with the paper's settings and returns the
measured numbers beside the paper's (:data:`~contactqvi.problems.stadler.PAPER`) as
plain data; ``stadler_tables.py`` writes them as tables. ``quick`` uses small grids
(a smoke test, not the paper's N). Counts are linear solves after the initialisation
(the solution of (3.2) with xi = 0), d_lambda is measured against lambda_bar =
lambda_1e16 on the same grid. All functions are collective.
"""

from __future__ import annotations

import typing

from mpi4py import MPI

import numpy as np

from contactqvi.friction import (
    FrictionActiveSetSolver,
    UzawaSolver,
    augmented_lagrangian,
    create_problem,
    semismooth_newton_sigma,
)
from contactqvi.friction.analysis import iteration_count, mirror_x1, neumann_to_dirichlet_eigenvalue, set_changes
from contactqvi.friction.pdas import ActiveSetResult
from contactqvi.lifetime import PETScOwner
from contactqvi.problems.stadler import PAPER, REFERENCE_GAMMA, stadler_example

__all__ = ["Case", "Cases", "TABLES"]


class Case(PETScOwner):
    """Problem, (PDAS) solver, lambda_bar and y_bar of one (example, N, discretisation, reading)."""

    def __init__(self, example: int, N: int, discretisation: str, reading: str):
        self.key = (example, N, discretisation, reading)
        data = stadler_example(example, example2_reading=reading)
        self.problem = create_problem(MPI.COMM_WORLD, data, N=N, discretisation=discretisation)
        self.pdas = FrictionActiveSetSolver(self.problem)
        self.reference = self.pdas.solve(gamma=REFERENCE_GAMMA, sigma=1.0, max_iterations=100)
        if not self.reference.converged:
            raise RuntimeError(f"lambda_bar of {self.key}: PDAS ended with {self.reference.status}")
        self.y_bar = self.reference.y.x.petsc_vec.copy()

    def petsc_objects(self) -> list[typing.Any]:
        return [self.y_bar, self.pdas, self.problem]

    def solve(self, gamma: float, ss: bool = False, **kwargs: typing.Any) -> ActiveSetResult:
        """(SS) (sigma = 1/gamma) or (PDAS) with sigma = 1."""
        sigma = semismooth_newton_sigma(float(gamma)) if ss else 1.0
        return self.pdas.solve(gamma=float(gamma), sigma=sigma, **kwargs)

    def counts(self, gammas: list, ss: bool) -> list[int | str]:
        return [iteration_count(self.solve(gamma, ss)) for gamma in gammas]


class Cases(PETScOwner):
    """One :class:`Case` alive at a time (the large grids of Table 6.6 do not fit side by side on a laptop).

    Args:
        discretisation: of every case.
        quick: small grids (a smoke test).
    """

    def __init__(self, discretisation: str, quick: bool = False):
        self.discretisation, self.quick = discretisation, quick
        self.current: Case | None = None

    def get(self, example: int, N: int, reading: str = "x1x2") -> Case:
        """The case (example, N, reading), built after destroying the previous one if that differs."""
        key = (example, N, self.discretisation, reading)
        if self.current is None or self.current.key != key:
            self.destroy()
            self.current = Case(*key)
        return self.current

    def petsc_objects(self) -> list[Case | None]:
        return [self.current]

    def destroy(self) -> None:
        super().destroy()
        self.current = None


def table_6_1(cases: Cases) -> dict:
    """Table 6.1: (SS) iterations for Example 1, N = 80 (and (PDAS), and the set changes of (SS))."""
    N, gammas = (20 if cases.quick else 80), PAPER["6.1"]["gamma"]
    case = cases.get(1, N)
    ss = [case.solve(gamma, ss=True) for gamma in gammas]
    return {"N": N, "gamma": gammas, "paper_ss": PAPER["6.1"]["ss"], "ss": [iteration_count(r) for r in ss],
            "pdas": case.counts(gammas, ss=False), "ss_changes_per_iteration": [set_changes(r) for r in ss],
            "ss_switches_between_A_minus_and_A_plus": [sum(h["switches_between_active_sets"] or 0 for h in r.history)
                                                       for r in ss]}  # fmt: skip


def figure_6_1(cases: Cases) -> dict:
    """The table of Fig. 6.1: |||y_gamma - y_bar||| for Example 1, N = 160, and its slope over gamma = 1e2..1e5."""
    N, gammas = (40 if cases.quick else 160), PAPER["fig6.1"]["gamma"]
    case = cases.get(1, N)
    errors = [case.problem.energy_norm(case.solve(gamma).y.x.petsc_vec, case.y_bar) for gamma in gammas]
    fit = [i for i, gamma in enumerate(gammas) if 1e2 <= gamma <= 1e5]
    slope = float(np.polyfit(np.log10(np.array(gammas)[fit]), np.log10(np.array(errors)[fit]), 1)[0])
    return {"N": N, "gamma": gammas, "error": errors, "paper_error": PAPER["fig6.1"]["error"], "slope_1e2_1e5": slope}


def table_6_2(cases: Cases) -> dict:
    """Table 6.2: q_lambda^k = ||lambda^k - lambda_gamma|| / ||lambda^(k-1) - lambda_gamma|| of (SS), Example 2."""
    N, gamma = (40 if cases.quick else 160), float(PAPER["6.2"]["gamma"])
    case, iterates = cases.get(2, N), []
    result = case.solve(gamma, ss=True, monitor=lambda k, y, lam, xi: iterates.append(lam.copy()))
    distances = [case.problem.boundary_norm(lam - result.lam) for lam in iterates]
    q = [b / a for a, b in zip(distances, distances[1:])]
    return {"N": N, "gamma": gamma, "status": str(result.status), "q": q, "paper_q": PAPER["6.2"]["q"]}


def table_6_3(cases: Cases) -> dict:
    """Table 6.3: (SS) and (PDAS) iterations for Example 2, N = 160, for both readings of f."""
    N, gammas = (40 if cases.quick else 160), PAPER["6.3"]["gamma"]
    data = {"N": N, "gamma": gammas, "paper_ss": PAPER["6.3"]["ss"], "paper_pdas": PAPER["6.3"]["pdas"]}
    for reading in ("x1x2", "x1x1"):
        case = cases.get(2, N, reading)
        data[reading] = {"ss": case.counts(gammas, ss=True), "pdas": case.counts(gammas, ss=False)}
    return data


def _alm(cases: Cases, example: int, inner: str, paper: dict, steps: dict[str, int]) -> dict:
    """(ALM) for each gamma of a paper table (``steps``: gamma label -> ALM steps): inner (PDAS) iterations, d_lambda."""
    N = 40 if cases.quick else 160
    case, data = cases.get(example, N), {"N": N}
    for label, max_outer in steps.items():
        gamma = {"schedule": "power10"} if label == "10^l" else {"gamma": float(label)}
        result = augmented_lagrangian(case.pdas, inner=inner, reference=case.reference.lam, max_outer=max_outer,
                                      **gamma)  # fmt: skip
        d_lambda = [h["d_lambda"] for h in result.history]
        data[label] = {"iter": [h["inner_iterations"] for h in result.history], "d": d_lambda,
                       "paper": paper[label], "linear_solves": result.linear_solves,
                       "monotone": bool(all(b < a for a, b in zip(d_lambda, d_lambda[1:])))}  # fmt: skip
    return data


def table_6_4(cases: Cases) -> dict:
    """Table 6.4: (ALM) with exact inner (PDAS), Example 2."""
    return _alm(cases, 2, "exact", PAPER["6.4"], {"1e2": 7, "1e4": 5})


def table_6_5(cases: Cases) -> dict:
    """Table 6.5: (ALM) with inexact inner (PDAS) (the (3.2c) residual halved), Example 2."""
    return _alm(cases, 2, "inexact", PAPER["6.5"], {"1e2": 7, "1e4": 7, "10^l": 7})


def table_6_7(cases: Cases) -> dict:
    """Table 6.7: inexact (ALM) for Example 3, and the system solves of exact (ALM) until d_lambda < 1e-4."""
    data = _alm(cases, 3, "inexact", PAPER["6.7"], {"1e2": 7, "1e4": 7, "10^l": 7})
    case, exact = cases.get(3, data["N"]), {}
    for gamma in (10.0, 50.0, 1e2, 1e3):
        result = augmented_lagrangian(case.pdas, gamma=gamma, reference=case.reference.lam, atol=1e-4, max_outer=50)
        exact[f"{gamma:g}"] = {"linear_solves": result.linear_solves, "outer": result.iterations,
                               "status": str(result.status)}  # fmt: skip
    return {**data, "exact_alm_solves_to_1e_4": exact}


def table_6_6(cases: Cases) -> dict:
    """Table 6.6: (SS) and (PDAS) iterations for Example 3 over N and gamma, and the tail of its largest count."""
    Ns, gammas = ([20, 40] if cases.quick else PAPER["6.6"]["N"]), PAPER["6.6"]["gamma"]
    data: dict[str, typing.Any] = {"N": Ns, "gamma": gammas, "paper": PAPER["6.6"], "ss": [], "pdas": []}
    for N in Ns:
        data["ss"].append(cases.get(3, N).counts(gammas, ss=True))
        data["pdas"].append(cases.get(3, N).counts(gammas, ss=False))
    data["pdas_at_most_8"] = all(isinstance(c, int) and c <= 8 for row in data["pdas"] for c in row)
    gamma = float(gammas[int(np.argmax([c if isinstance(c, int) else -1 for c in data["pdas"][-1]]))])
    data["tail"] = _tail(cases, Ns[-1], gamma)
    return data


def _tail(cases: Cases, N: int, gamma: float) -> dict:
    """How the last (PDAS) iterations change the sets at (N, gamma), and the counts of the grids N - 4 ... N + 4."""
    case = cases.get(3, N)
    result = case.solve(gamma)
    margin = case.problem.g - np.abs(result.lam[result.states == 0])
    tail = {"N": N, "gamma": gamma, "iterations": result.iterations, "changes": set_changes(result),
            "min_g_minus_abs_lambda_on_I": case.problem.comm.allreduce(float(margin.min(initial=np.inf)), op=MPI.MIN)}
    tail["neighbour_grids"] = {M: cases.get(3, M).solve(gamma).iterations for M in range(N - 4, N + 5)}
    return tail


def _uzawa_runs(case: Case, steps: tuple[float, ...], max_iterations: int) -> dict:
    """Uzawa from lambda^0 = 0 until d_lambda < 1e-4 for each step gamma, and the spectra of C_h (4.2)."""
    runs = {}
    with UzawaSolver(case.problem) as solver:
        for gamma in steps:
            r = solver.solve(gamma=gamma, reference=case.reference.lam, max_iterations=max_iterations)
            runs[f"{gamma:g}"] = {"iterations": r.iterations, "status": str(r.status),
                                  "final_d_lambda": r.history[-1]["d_lambda"]}  # fmt: skip
    problem, inactive = case.problem, case.reference.states == 0
    top = neumann_to_dirichlet_eigenvalue(problem, inactive)
    spectra = {"inactive_nodes": problem.count(inactive),
               "lambda_max_C_on_Gamma_f": neumann_to_dirichlet_eigenvalue(problem, np.ones_like(inactive)),
               "lambda_max_C_on_inactive_set": top,
               "lambda_min_C_on_inactive_set": neumann_to_dirichlet_eigenvalue(problem, inactive, shift=top)}
    return {"runs": runs, "spectra": spectra}


def _uzawa_long_run(case: Case, gamma: float, iterations: int) -> dict:
    """Uzawa continued past the stopping test, with the symmetry breaking ||lambda + lambda(1 - x1, .)|| / 2.

    Example 1's data are odd about x1 = 1/2, and so are lambda_bar and every Uzawa
    iterate in exact arithmetic: an unstable mode of gamma is seeded by round-off only.
    """
    problem = case.problem
    x = problem.V.tabulate_dof_coordinates()[problem.boundary_dofs]

    def breaking(lam: np.ndarray) -> float:
        return 0.5 * problem.boundary_norm(lam + mirror_x1(problem.comm, x, lam))

    seen: list[float] = []
    with UzawaSolver(problem) as solver:
        run = solver.solve(gamma=gamma, reference=case.reference.lam, atol=np.finfo(float).tiny,
                           max_iterations=iterations, monitor=lambda l, y, lam: seen.append(breaking(lam)))  # fmt: skip
    d_lambda = [h["d_lambda"] for h in run.history]
    best = int(np.argmin(d_lambda))
    return {"gamma": gamma, "iterations": iterations,
            "first_below_1e-4": next((i + 1 for i, v in enumerate(d_lambda) if v < 1e-4), None),
            "min_d_lambda": d_lambda[best], "min_at": best + 1, "symmetry_breaking_at_min": seen[best],
            "d_lambda_last": d_lambda[-1], "symmetry_breaking_last": seen[-1],
            "symmetry_breaking_of_lambda_bar": breaking(case.reference.lam)}  # fmt: skip


def uzawa(cases: Cases) -> dict:
    """Uzawa (Sect. 6.1/6.2): Example 1, N = 80, gamma = 5 ... 30 (+ a long run at 20); Example 2, N = 160."""
    N1, N2 = (20, 40) if cases.quick else (80, 160)
    example1 = _uzawa_runs(cases.get(1, N1), (5.0, 10.0, 15.0, 20.0, 25.0, 30.0), 1000)
    example1["long_run"] = _uzawa_long_run(cases.get(1, N1), 20.0, 60)
    example2 = _uzawa_runs(cases.get(2, N2), (0.1, 0.2, 0.3), 400)
    return {"example1_N": N1, "example1": example1, "example2_N": N2, "example2": example2, "paper": PAPER["uzawa"]}


#: The tables of Sect. 6 in the paper's order.
TABLES: dict[str, typing.Callable[[Cases], dict]] = {
    "6.1": table_6_1,
    "fig6.1": figure_6_1,
    "6.2": table_6_2,
    "6.3": table_6_3,
    "6.4": table_6_4,
    "6.5": table_6_5,
    "6.6": table_6_6,
    "6.7": table_6_7,
    "uzawa": uzawa,
}
