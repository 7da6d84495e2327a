"""Reproduce the numerical results of seed 002 (Stadler 2004, Sect. 6) with contactqvi.friction.

Writes ``benchmarks/results/stadler_<table>.json`` and ``.md`` (the paper's numbers
beside ours) and ``stadler_summary.md`` for

* Table 6.1 (SS iterations, Example 1, N = 80),
* the table of Fig. 6.1 (|||y_gamma - y_bar|||, Example 1, N = 160, y_bar = y_1e16),
* Table 6.2 (rates q_lambda^k of SS, Example 2, gamma = 50, N = 160),
* Table 6.3 (SS and PDAS iterations, Example 2, N = 160; both readings of f),
* Tables 6.4/6.5 (ALM exact/inexact, Example 2, N = 160),
* Table 6.6 (iterations over N and gamma, Example 3),
* Table 6.7 (ALM inexact, Example 3, N = 160) and the exact-ALM system-solve count,
* the Uzawa observations (Example 1, N = 80, gamma = 10, 20, 30; Example 2, gamma = 0.2).

Table 6.6 and the Uzawa observations also run the same solvers on the paper's own
discretisation (:class:`PaperFiniteDifferences`, serial) to separate discretisation
effects from the algorithms.

Discretisation: Q1 finite elements on the unit square with N grid points per
direction (N - 1 cells) and a lumped boundary mass on Gamma_f, where the paper
uses the five-point finite-difference stencil with one-sided normal differences
on N x N grids. Iteration counts are the number of linear solves after the
initialisation (the solution of (3.2) with xi = 0), as in the paper.

Run: ``python benchmarks/stadler_tables.py [--tables 6.1 6.3 ...] [--quick]``.
"""

from __future__ import annotations

import argparse
import json
import logging
import pathlib
import time
import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import scipy.sparse

from dolfinx import fem

from contactqvi.friction import (
    FrictionProblem,
    PrimalDualActiveSet,
    augmented_lagrangian,
    semismooth_newton_sigma,
    uzawa,
)
from contactqvi.meshes import create_unit_square
from contactqvi.problems.stadler import StadlerExample, create_stadler_problem, stadler_example

RESULTS = pathlib.Path(__file__).resolve().parent / "results"
REFERENCE_GAMMA = 1e16

#: The paper's numbers (seed 002, Sect. 6); "div" = (SS) did not find the solution.
PAPER = {
    "6.1": {"gamma": [1e2, 1e4, 1e6, 1e8], "ss": [2, 3, 3, 3]},
    "fig6.1": {"gamma": [1, 10, 1e2, 1e3, 1e4, 1e5, 1e6],
               "error": [4.46e-1, 1.79e-1, 2.30e-2, 2.49e-3, 2.54e-4, 2.54e-5, 2.54e-6]},
    "6.2": {"gamma": 50, "q": [0.58, 0.45, 0.25, 0.18, 0.00]},
    "6.3": {"gamma": [3, 5, 10, 50, 100, 150, 160, 1e3, 1e10],
            "ss": [3, 4, 4, 5, 6, 7, "div", "div", "div"], "pdas": [3, 4, 4, 5, 6, 5, 5, 6, 6]},
    "6.4": {
        "1e2": {"iter": [6, 3, 2, 1, 1, 1, 1],
                "d": [2.55e-2, 8.54e-3, 3.62e-3, 1.62e-3, 7.45e-4, 3.58e-4, 1.77e-4]},
        "1e4": {"iter": [6, 1, 1, 1, 1], "d": [4.00e-4, 3.06e-6, 2.67e-8, 2.62e-10, 2.84e-12]},
    },
    "6.5": {
        "1e2": {"iter": [1, 2, 2, 2, 1, 1, 1],
                "d": [2.96e-1, 5.03e-2, 7.60e-3, 1.89e-3, 9.99e-4, 5.36e-4, 2.91e-4]},
        "1e4": {"iter": [1, 2, 1, 2, 1, 1, 1],
                "d": [3.81e-1, 1.46e-1, 3.79e-2, 1.87e-4, 2.20e-6, 2.67e-8, 3.28e-10]},
        "10^l": {"iter": [1, 3, 2, 1, 1, 1], "d": [1.41e-1, 2.30e-2, 2.16e-3, 1.11e-5, 1.04e-8, 1.14e-12]},
    },
    "6.6": {
        "gamma": [5, 10, 30, 50, 1e2, 1e3, 1e5, 1e10],
        "N": [20, 40, 80, 160, 320],
        "iter": [[3, 3, 3, 3, 3, 3, 3, 3], [3, 3, 4, 5, 4, 4, 4, 4], [3, 4, 4, 5, 5, 6, 6, 6],
                 [3, 3, 5, 5, 6, 8, 7, 7], [3, 4, 5, 6, 7, 7, 8, 8]],
        "pdas_used": [[0, 0, 0, 0, 0, 0, 0, 1], [0, 0, 0, 0, 0, 0, 0, 1], [0, 0, 0, 0, 0, 0, 0, 1],
                      [0, 0, 0, 0, 0, 0, 1, 1], [0, 0, 0, 0, 0, 0, 1, 1]],
    },
    "6.7": {
        "1e2": {"iter": [1, 2, 1, 1, 1, 1, 2],
                "d": [1.62e-1, 1.99e-2, 6.94e-3, 1.40e-3, 4.67e-4, 1.91e-4, 9.20e-5]},
        "1e4": {"iter": [1, 3, 2, 1, 1, 1], "d": [2.14e-1, 1.46e-2, 4.11e-4, 9.06e-7, 8.20e-9, 8.43e-11]},
        "10^l": {"iter": [1, 2, 2, 1, 1, 1], "d": [8.54e-2, 2.62e-2, 2.40e-3, 4.21e-4, 9.08e-8, 8.23e-12]},
    },
    "uzawa": {"example1_N80": {"10": 32, "20": 17, "30": "no convergence"},
              "example2_gamma0.2": "stopped after 400 iterations at d_lambda = 1.03e-2; "
                                   "no convergence for gamma > 0.2"},
}  # fmt: skip

logger = logging.getLogger("stadler_tables")

DISCRETISATION_NOTE = """# Seed 002 (Stadler 2004): paper vs contactqvi

## Discretisation and why numbers differ

* Paper: five-point finite differences on an N x N grid, one-sided differences for the normal
  derivative, multiplier and sets at the boundary grid points.
* Here: continuous Q1 finite elements on the unit square with N grid points per direction (N - 1
  cells, so the vertices are the paper's grid points), load integrated with a degree-4 rule (3 x
  3 Gauss points; 2 x 2 for Example 1, see below), and the multiplier lambda (and xi) as *nodal*
  values on Gamma_f with the lumped boundary mass m_i = int_{Gamma_f} phi_i ds. Then (3.2a)
  reads K y + M lambda = F with M diagonal, the complementarity (3.2c)/(3.3) and the sets A-,
  A+, I are nodewise, and ||v||_{L2(Gamma_f)} = (sum_i m_i v_i^2)^(1/2) is exact for nodal
  vectors. Nodes on Gamma_f that are Dirichlet nodes (the corners of Example 1) carry no
  multiplier.
* Both schemes approximate the same continuous problem, but the discrete Neumann-to-Dirichlet
  maps C_h differ (the FE boundary row contains half a cell of tangential stiffness and load;
  the FD row is a one-sided difference). On smooth boundary functions they agree (largest
  eigenvalue on Gamma_f in the Uzawa table), on grid-scale ones the FE map is about half the
  FD map (smallest eigenvalue on the inactive set). Everything that depends on the spectrum of
  C_h restricted to the inactive set therefore differs by O(1) factors: the contraction of
  (ALM) per step for fixed gamma, the speed and admissible steps of Uzawa, the constants of
  |||y_gamma - y_bar|||. Iteration counts of the active-set methods depend on how the discrete
  sets approach their limit, which is a property of the grid; the counts agree closely but
  not exactly.
* Cross-check: `PaperFiniteDifferences` is the paper's scheme written as K y + M lambda = F, so
  that the same PDAS/SS/Uzawa code runs on it (Table 6.6 and the Uzawa table). It reproduces the
  paper's Uzawa counts for Example 1 exactly, Table 6.6 within one iteration, and the chattering
  of (SS) for N >= 160, gamma >= 1e5.
* Example 1's load is integrated with the 2 x 2 Gauss rule: the 3 x 3 rule samples the jump of f
  on x1 = 1/2 (the centre line of the middle cell column for even N) and broke the antisymmetry
  of (f, v) and lambda_bar that the paper's grid has.
* Iteration counts are numbers of linear solves after the initialisation (the solution of
  (3.2) with xi = 0), d_lambda^l = ||lambda_bar - lambda^l||_{L2(Gamma_f)} with
  lambda_bar = lambda_{1e16} on the same grid.

"""


class PaperFiniteDifferences(FrictionProblem):
    """An example in the paper's own discretisation (Sect. 6), on the nodes of the Q1 grid (serial).

    Sect. 6 uses the five-point stencil on the N x N grid and one-sided differences
    for the normal derivative. Scaled by h^2, (2.4)/(3.2a) keeps the form
    K y + M lambda = F of :class:`FrictionProblem`, so the same solvers run on it:

    * interior node P: 4 y_P - sum_{Q ~ P} y_Q + mu h^2 y_P = h^2 f(P) (f sampled at P);
    * Gamma_f node: -dy/dn = lambda with the one-sided difference to the inward
      neighbour, y_P - y_in + h lambda_P = 0 (m_P = h); at a corner between two
      friction edges the mean of both one-sided differences, times h/2 (m_P = h/2);
    * Gamma_0 node: y_P = 0.

    Then lambda = (F - K y)_P / m_P is the one-sided -dy/dn at P, the lambda^0 :=
    -dy^0/dn of (PDAS) step 1, and ||.||_{L2(Gamma_f)} is the trapezoidal rule.
    """

    def __init__(self, example: StadlerExample, N: int):
        msh, facet_tags = create_unit_square(MPI.COMM_SELF, N - 1)
        super().__init__(
            msh, facet_tags, example.friction_boundaries, example.dirichlet_boundaries, example.load, example.mu,
            example.g,
        )  # fmt: skip
        h = 1.0 / (N - 1)
        n = self.V.dofmap.index_map.size_local
        ij = np.rint(self.V.tabulate_dof_coordinates()[:n, :2] / h).astype(np.int64)
        node = np.empty((N, N), dtype=np.int64)
        node[ij[:, 0], ij[:, 1]] = np.arange(n)
        interior = ((ij > 0) & (ij < N - 1)).all(axis=1)
        dirichlet = ~interior
        dirichlet[self.boundary_dofs] = False
        p = np.flatnonzero(interior)
        rows, cols = [p], [p]
        vals = [np.full(p.size, 4.0 + self.mu * h**2)]
        for step in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            rows.append(p)
            cols.append(node[ij[p, 0] + step[0], ij[p, 1] + step[1]])
            vals.append(np.full(p.size, -1.0))
        b = self.boundary_dofs
        inward = np.where(ij[b] == 0, 1, np.where(ij[b] == N - 1, -1, 0))
        directions = np.count_nonzero(inward, axis=1)  # 1 on an edge, 2 at a corner
        rows.append(b)
        cols.append(b)
        vals.append(1.0 / directions)
        for axis in (0, 1):
            along = inward[:, axis] != 0
            neighbour = ij[b[along]].copy()
            neighbour[:, axis] += inward[along, axis]
            rows.append(b[along])
            cols.append(node[neighbour[:, 0], neighbour[:, 1]])
            vals.append(-1.0 / directions[along] ** 2)
        d = np.flatnonzero(dirichlet)
        rows.append(d)
        cols.append(d)
        vals.append(np.ones(d.size))
        rows, cols, vals = (np.concatenate(a) for a in (rows, cols, vals))
        keep = (rows == cols) | ~dirichlet[cols]  # y = 0 on Gamma_0
        csr = scipy.sparse.csr_matrix((vals[keep], (rows[keep], cols[keep])), shape=(n, n))
        csr.sort_indices()
        self.K.destroy()
        self.K = PETSc.Mat().createAIJ(
            (n, n), csr=(csr.indptr.astype(PETSc.IntType), csr.indices.astype(PETSc.IntType), csr.data),
            comm=MPI.COMM_SELF,
        )  # fmt: skip
        f = fem.Function(self.V)
        f.interpolate(fem.Expression(self.load_expression, self.V.element.interpolation_points(), comm=MPI.COMM_SELF))
        self.F.array[:] = np.where(interior, h**2 * f.x.array[:n], 0.0)
        self.boundary_mass = h / directions


#: The ``cell_type`` value of :class:`Setup` that selects :class:`PaperFiniteDifferences`, and its table label.
FINITE_DIFFERENCES, FD_LABEL = "paper-fd", "paper's FD"


class Setup:
    """Problem, PDAS solver and reference lambda_bar = lambda_1e16 of one (example, N), built once.

    ``cell_type`` is ``quadrilateral``/``triangle`` (our Q1/P1 problem) or
    :data:`FINITE_DIFFERENCES` (the paper's scheme, serial).
    """

    _cache: typing.ClassVar[dict] = {}

    def __init__(self, example: int, N: int, cell_type: str, reading: str = "x1x2"):
        data = stadler_example(example, reading)
        if cell_type == FINITE_DIFFERENCES:
            self.problem: FrictionProblem = PaperFiniteDifferences(data, N)
        else:
            self.problem = create_stadler_problem(MPI.COMM_WORLD, data, N, cell_type)
        self.pdas = PrimalDualActiveSet(self.problem)
        self.reference = self.pdas.solve(REFERENCE_GAMMA, 1.0, max_iterations=100)
        assert self.reference.converged, "reference solve failed"

    @classmethod
    def get(cls, example: int, N: int, cell_type: str, reading: str = "x1x2") -> Setup:
        key = (example, N, cell_type, reading)
        if key not in cls._cache:
            cls._cache.clear()  # keep one large problem in memory at a time
            cls._cache[key] = cls(example, N, cell_type, reading)
        return cls._cache[key]


def _count(result) -> int | str:
    """Iteration count, or the reason the active-set method did not find the solution."""
    return result.iterations if result.status == "converged" else f"div ({result.status} after {result.iterations})"


def _fmt(value: typing.Any) -> str:
    if isinstance(value, float):
        return f"{value:.2e}"
    return "" if value is None else str(value)


def _md_table(header: list[str], rows: list[list[typing.Any]]) -> str:
    lines = ["| " + " | ".join(str(h) for h in header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(_fmt(v) for v in row) + " |" for row in rows]
    return "\n".join(lines)


def table_6_1(cell_type: str, quick: bool) -> tuple[dict, str]:
    N = 20 if quick else 80
    s = Setup.get(1, N, cell_type)
    gammas = PAPER["6.1"]["gamma"]
    ss = [s.pdas.solve(g, semismooth_newton_sigma(g)) for g in gammas]
    pd = [s.pdas.solve(g, 1.0) for g in gammas]
    data = {"N": N, "gamma": gammas, "ss": [_count(r) for r in ss], "pdas": [_count(r) for r in pd],
            "paper_ss": PAPER["6.1"]["ss"],
            "switches_between_A_minus_and_A_plus_ss": [sum(h["switches_between_active_sets"] or 0 for h in r.history)
                                                      for r in ss],
            "ss_changes_per_iteration": [[h["changes"] for h in r.history] for r in ss]}  # fmt: skip
    fd = Setup.get(1, N, FINITE_DIFFERENCES)
    fd_ss = [fd.pdas.solve(g, semismooth_newton_sigma(g)) for g in gammas]
    data["paper_fd_ss"] = [_count(r) for r in fd_ss]
    data["paper_fd_ss_changes_per_iteration"] = [[h["changes"] for h in r.history] for r in fd_ss]
    md = _md_table(
        ["gamma", *[f"{g:.0e}" for g in gammas]],
        [["paper SS", *data["paper_ss"]], ["ours SS", *data["ss"]], ["ours PDAS (sigma=1)", *data["pdas"]],
         [f"{FD_LABEL} SS", *data["paper_fd_ss"]]],
    )  # fmt: skip
    changes = _md_table(
        ["gamma", "ours SS", f"{FD_LABEL} SS"],
        [[f"{g:.0e}", " ".join(str(c) for c in a[1:]), " ".join(str(c) for c in b[1:])]
         for g, a, b in zip(gammas, data["ss_changes_per_iteration"], data["paper_fd_ss_changes_per_iteration"])],
    )  # fmt: skip
    ok = all(isinstance(c, int) and c <= 3 for c in data["ss"])
    data["done_when_ss_at_most_3"] = ok
    return data, (
        f"Example 1, N = {N}: iterations of (SS); 'paper's FD': the same code on the paper's scheme.\n\n{md}\n\n"
        f"SS <= 3 iterations for all gamma: {ok}\n\nNodes changing set in iteration 2, 3, ...:\n\n{changes}\n"
    )


def figure_6_1(cell_type: str, quick: bool) -> tuple[dict, str]:
    N = 40 if quick else 160
    s = Setup.get(1, N, cell_type)
    y_bar = s.reference.y
    gammas = PAPER["fig6.1"]["gamma"]
    errors = []
    for g in gammas:
        result = s.pdas.solve(float(g), 1.0)
        errors.append(s.problem.energy_norm(result.y.x.petsc_vec - y_bar.x.petsc_vec))
    fit = [i for i, g in enumerate(gammas) if 1e2 <= g <= 1e5]
    slope = float(np.polyfit(np.log10(np.array(gammas)[fit]), np.log10(np.array(errors)[fit]), 1)[0])
    data = {"N": N, "gamma": gammas, "error": errors, "paper_error": PAPER["fig6.1"]["error"],
            "slope_1e2_1e5": slope}  # fmt: skip
    rows = [[f"{g:.0e}", p, e] for g, p, e in zip(gammas, data["paper_error"], errors)]
    md = _md_table(["gamma", "paper", "ours"], rows)
    return data, (
        f"Example 1, N = {N}: |||y_gamma - y_bar|||, y_bar = y_1e16.\n\n{md}\n\n"
        f"fitted slope (gamma = 1e2..1e5): {slope:.3f}\n"
    )


def table_6_2(cell_type: str, quick: bool) -> tuple[dict, str]:
    N = 40 if quick else 160
    s = Setup.get(2, N, cell_type)
    gamma = float(PAPER["6.2"]["gamma"])
    iterates: list[np.ndarray] = []
    result = s.pdas.solve(
        gamma, semismooth_newton_sigma(gamma), monitor=lambda k, y, lam, xi: iterates.append(lam.array_r.copy())
    )
    distances = [s.problem.boundary_norm(lam - result.lam.array_r) for lam in iterates]
    q = [b / a for a, b in zip(distances, distances[1:])]
    data = {"N": N, "gamma": gamma, "status": result.status, "q": q, "paper_q": PAPER["6.2"]["q"]}
    pad = [None] * max(0, len(q) - len(PAPER["6.2"]["q"]))
    md = _md_table(["k", *range(1, len(q) + 1)], [["paper q_lambda^k", *PAPER["6.2"]["q"], *pad], ["ours", *q]])
    return data, (
        f"Example 2, N = {N}, (SS) with gamma = {gamma:g}: q_lambda^k = ||lambda^k - lambda_gamma|| / "
        f"||lambda^(k-1) - lambda_gamma|| (lambda^0: the initialisation).\n\n{md}\n"
    )


def table_6_3(cell_type: str, quick: bool) -> tuple[dict, str]:
    N = 40 if quick else 160
    gammas = PAPER["6.3"]["gamma"]
    data: dict[str, typing.Any] = {
        "N": N, "gamma": gammas, "paper_ss": PAPER["6.3"]["ss"], "paper_pdas": PAPER["6.3"]["pdas"]
    }
    rows = [["paper SS", *PAPER["6.3"]["ss"]], ["paper PDAS", *PAPER["6.3"]["pdas"]]]
    for reading in ("x1x2", "x1x1"):
        s = Setup.get(2, N, cell_type, reading)
        ss = [s.pdas.solve(float(g), semismooth_newton_sigma(float(g))) for g in gammas]
        pd = [s.pdas.solve(float(g), 1.0) for g in gammas]
        data[reading] = {"ss": [_count(r) for r in ss], "pdas": [_count(r) for r in pd]}
        rows += [[f"ours SS, f reading {reading}", *data[reading]["ss"]],
                 [f"ours PDAS, f reading {reading}", *data[reading]["pdas"]]]  # fmt: skip
    ours = data["x1x2"]["pdas"]
    ok = all(isinstance(o, int) and o <= p + 2 for o, p in zip(ours, PAPER["6.3"]["pdas"]))
    data["done_when_pdas_within_plus_2"] = ok
    md = _md_table(["gamma", *[f"{g:g}" for g in gammas]], rows)
    return data, (
        f"Example 2, N = {N}: iterations of (SS) and (PDAS, sigma = 1); 'div' = the sets cycle.\n"
        "Reading x1x2: f = 10(sin 4 pi x1 + cos 4 pi x2) (our default); x1x1: f = 10(sin 4 pi x1 + cos 4 pi x1).\n\n"
        f"{md}\n\nPDAS (x1x2) within +2 of the paper for every gamma: {ok}\n"
    )


def _alm_rows(s: Setup, inner: str, runs: dict[str, int], paper: dict) -> tuple[dict, str]:
    data, parts = {}, []
    for label, steps in runs.items():
        gamma = (lambda step: 10.0**step) if label == "10^l" else float(label)
        result = augmented_lagrangian(s.pdas, gamma, inner=inner, reference=s.reference.lam, max_outer=steps)
        iters = [h["inner_iterations"] for h in result.history]
        d = [h["d_lambda"] for h in result.history]
        data[label] = {"iter": iters, "d": d, "paper": paper[label], "linear_solves": result.linear_solves,
                       "monotone": bool(all(b < a for a, b in zip(d, d[1:]))),
                       "steps_to_1e_11": next((i + 1 for i, v in enumerate(d) if v < 1e-11), None)}  # fmt: skip
        header = ["l", *range(1, steps + 1)]
        pad = [None] * (steps - len(paper[label]["iter"]))
        rows = [["paper #iter_PD", *paper[label]["iter"], *pad], ["ours #iter_PD", *iters],
                ["paper d_lambda", *paper[label]["d"], *pad], ["ours d_lambda", *d]]  # fmt: skip
        parts.append(f"gamma = {label}:\n\n{_md_table(header, rows)}\n")
    return data, "\n".join(parts)


def table_6_4(cell_type: str, quick: bool) -> tuple[dict, str]:
    N = 40 if quick else 160
    data, md = _alm_rows(Setup.get(2, N, cell_type), "exact", {"1e2": 7, "1e4": 5}, PAPER["6.4"])
    data["N"] = N
    return data, f"Example 2, N = {N}: (ALM) with exact inner solve by (PDAS).\n\n{md}"


def table_6_5(cell_type: str, quick: bool) -> tuple[dict, str]:
    N = 40 if quick else 160
    data, md = _alm_rows(Setup.get(2, N, cell_type), "inexact", {"1e2": 7, "1e4": 7, "10^l": 7}, PAPER["6.5"])
    data["N"] = N
    return data, f"Example 2, N = {N}: (ALM), inner (PDAS) stopped when the (3.2c) residual halved.\n\n{md}"


def table_6_7(cell_type: str, quick: bool) -> tuple[dict, str]:
    N = 40 if quick else 160
    s = Setup.get(3, N, cell_type)
    data, md = _alm_rows(s, "inexact", {"1e2": 7, "1e4": 7, "10^l": 7}, PAPER["6.7"])
    exact = {}
    for gamma in (10.0, 50.0, 1e2, 1e3):
        result = augmented_lagrangian(s.pdas, gamma, inner="exact", reference=s.reference.lam, tol=1e-4, max_outer=50)
        exact[f"{gamma:g}"] = {"linear_solves": result.linear_solves, "outer": result.outer_iterations,
                               "status": result.status}  # fmt: skip
    data.update(N=N, exact_alm_solves_to_1e_4=exact)
    rows = [[g, v["outer"], v["linear_solves"], v["status"]] for g, v in exact.items()]
    extra = _md_table(["gamma", "ALM steps", "linear solves incl. initialisation", "status (max 50 steps)"], rows)
    return data, (
        f"Example 3, N = {N}: (ALM), inner (PDAS) stopped when the (3.2c) residual halved.\n\n{md}\n"
        f"Exact (ALM) until d_lambda < 1e-4 (paper: 16 system solves for gamma = 50, 10-20 otherwise):\n\n{extra}\n"
    )


def table_6_6(cell_type: str, quick: bool) -> tuple[dict, str]:
    Ns = [20, 40] if quick else PAPER["6.6"]["N"]
    gammas = PAPER["6.6"]["gamma"]
    schemes = {"ours": cell_type, FD_LABEL: FINITE_DIFFERENCES}
    counts: dict[str, dict[str, list]] = {label: {"ss": [], "pdas": []} for label in schemes}
    rows = []
    for i, N in enumerate(Ns):
        paper = [f"{c}{'*' if star else ''}" for c, star in zip(PAPER["6.6"]["iter"][i], PAPER["6.6"]["pdas_used"][i])]
        rows.append([N, "paper", *paper])
        for label, scheme in schemes.items():
            s = Setup.get(3, N, scheme)
            ss = [_count(s.pdas.solve(float(g), semismooth_newton_sigma(float(g)))) for g in gammas]
            pd = [_count(s.pdas.solve(float(g), 1.0)) for g in gammas]
            counts[label]["ss"].append(ss)
            counts[label]["pdas"].append(pd)
            rows += [[N, f"{label} SS", *ss], [N, f"{label} PDAS", *pd]]
        logger.info("Table 6.6 N=%d done", N)
    at_most_8 = {label: all(isinstance(c, int) and c <= 8 for row in c_["pdas"] for c in row)
                 for label, c_ in counts.items()}  # fmt: skip
    # The largest count of our finest grid: how the last iterations change the sets, and its grid neighbours.
    N = Ns[-1]
    last = counts["ours"]["pdas"][-1]
    gamma = float(gammas[int(np.argmax([c if isinstance(c, int) else -1 for c in last]))])
    changes = {}
    for label, scheme in schemes.items():
        s = Setup.get(3, N, scheme)
        result = s.pdas.solve(gamma, 1.0)
        margin = s.problem.g - np.abs(result.lam.array_r[result.states == 0])
        changes[label] = {
            "iterations": result.iterations,
            "changes": [h["changes"] for h in result.history],
            "min_g_minus_abs_lambda_on_I": s.problem.comm.allreduce(float(margin.min(initial=np.inf)), op=MPI.MIN),
        }
    neighbours = {}
    for M in range(N - 4, N + 5):
        problem = create_stadler_problem(MPI.COMM_WORLD, stadler_example(3), M, cell_type)
        neighbours[M] = PrimalDualActiveSet(problem).solve(gamma, 1.0).iterations
    data = {"N": Ns, "gamma": gammas, "paper": PAPER["6.6"],
            "ss": counts["ours"]["ss"], "pdas": counts["ours"]["pdas"],
            "paper_fd_ss": counts[FD_LABEL]["ss"], "paper_fd_pdas": counts[FD_LABEL]["pdas"],
            "done_when_pdas_at_most_8": at_most_8["ours"], "paper_fd_pdas_at_most_8": at_most_8[FD_LABEL],
            "tail": {"N": N, "gamma": gamma, **changes},
            "neighbour_grids": {"gamma": gamma, "pdas": neighbours}}  # fmt: skip
    md = _md_table(["N", "", *[f"{g:g}" for g in gammas]], rows)
    tail = _md_table(
        ["", "PDAS iterations", "nodes changing set in iteration 2, 3, ...", "min (g - |lambda|) on I"],
        [[label, v["iterations"], " ".join(str(c) for c in v["changes"][1:]), v["min_g_minus_abs_lambda_on_I"]]
         for label, v in changes.items()],
    )  # fmt: skip
    sweep = _md_table(["N", *neighbours], [[f"ours PDAS, gamma = {gamma:g}", *neighbours.values()]])
    return data, (
        "Example 3: iterations for N grid points per direction and gamma\n"
        "('*' in the paper: PDAS used because SS chatters). 'paper's FD' runs the same solver code on the\n"
        "paper's discretisation (five-point stencil, one-sided normal differences; `PaperFiniteDifferences`).\n\n"
        f"{md}\n\nPDAS <= 8 iterations everywhere: ours {at_most_8['ours']}, "
        f"paper's FD {at_most_8[FD_LABEL]}\n\n"
        f"N = {N}, gamma = {gamma:g}: the sets of the last iterations.\n\n{tail}\n\n"
        f"Our Q1 grids around N = {N}:\n\n{sweep}\n"
    )


def neumann_to_dirichlet_eigenvalue(
    s: Setup, mask: np.ndarray, shift: float = 0.0, iterations: int = 400
) -> float:
    """Eigenvalue of C_h = tau K^-1 tau^* M restricted to ``mask`` farthest from ``shift`` (power iteration).

    C_h is the discrete Neumann-to-Dirichlet map (4.2), self-adjoint and positive
    definite in the lumped L2(Gamma_f) product. Power iteration on C_h - shift I
    gives lambda_max for shift = 0 and lambda_min for shift = lambda_max. Uzawa with
    frozen sets is Richardson's iteration for C_h on the inactive set: the error
    contracts by max |1 - gamma lambda| over its spectrum, which is < 1 iff
    gamma < 2 / lambda_max, and is 1 - gamma lambda_min at best for small gamma.
    """
    problem = s.problem
    rhs, y = problem.K.createVecLeft(), problem.K.createVecLeft()
    ksp = s.pdas.ksp
    ksp.setOperators(problem.K)
    v = np.where(mask, np.random.default_rng(seed=2004).uniform(0.5, 1.5, mask.size), 0.0)
    estimate = 0.0
    for _ in range(iterations):
        v /= problem.boundary_norm(v)
        rhs.set(0.0)
        rhs.array[problem.boundary_dofs] = problem.boundary_mass * v
        ksp.solve(rhs, y)
        w = np.where(mask, problem.trace(y) - shift * v, 0.0)
        estimate = shift + problem.comm.allreduce(float(np.dot(problem.boundary_mass * w, v)), op=MPI.SUM)
        v = w
    rhs.destroy()
    y.destroy()
    return estimate


def _mirror_x1(problem: FrictionProblem, N: int) -> np.ndarray:
    """For every friction node (x1, x2) the index of the friction node (1 - x1, x2) (serial)."""
    ij = np.rint(problem.V.tabulate_dof_coordinates()[problem.boundary_dofs, :2] * (N - 1)).astype(np.int64)
    code = ij[:, 0] * N + ij[:, 1]
    order = np.argsort(code)
    return order[np.searchsorted(code[order], (N - 1 - ij[:, 0]) * N + ij[:, 1])]


def _uzawa_example1(s: Setup, N: int, steps: tuple[float, ...], long_step: float, long_run: int) -> dict:
    """Uzawa runs of Example 1 for ``steps``, one run of ``long_run`` iterations past the stopping test, spectra.

    Example 1's data are odd about x1 = 1/2, and so are lambda_bar and every Uzawa
    iterate in exact arithmetic; ``symmetry_breaking`` = ||lambda + lambda(1 - x1, .)|| / 2.
    """
    problem, reference = s.problem, s.reference.lam
    mirror = _mirror_x1(problem, N)
    runs = {}
    for gamma in steps:
        result = uzawa(problem, gamma, reference=reference, tol=1e-4, max_iterations=1000)
        runs[f"{gamma:g}"] = {"iterations": result.iterations, "status": result.status,
                              "final_d_lambda": result.history[-1]["d_lambda"]}  # fmt: skip
    breaking: list[float] = []
    run = uzawa(
        problem, long_step, reference=reference, tol=np.finfo(float).tiny, max_iterations=long_run,  # run them all
        monitor=lambda l, y, lam: breaking.append(0.5 * problem.boundary_norm(lam.array_r + lam.array_r[mirror])),
    )  # fmt: skip
    d = [h["d_lambda"] for h in run.history]
    first = next((i + 1 for i, v in enumerate(d) if v < 1e-4), None)
    best = int(np.argmin(d))
    inactive = s.reference.states == 0
    everywhere = np.ones_like(inactive)
    top_inactive = neumann_to_dirichlet_eigenvalue(s, inactive)
    return {
        "runs": runs,
        "symmetry_breaking_of_lambda_bar": 0.5 * problem.boundary_norm(reference.array_r + reference.array_r[mirror]),
        "inactive_nodes": problem.count(inactive),
        "long_run": {"gamma": long_step, "iterations": long_run, "first_below_1e-4": first,
                     "min_d_lambda": d[best], "min_at": best + 1, "symmetry_breaking_at_min": breaking[best],
                     "d_lambda_last": d[-1], "symmetry_breaking_last": breaking[-1]},
        "lambda_max_C_on_Gamma_f": neumann_to_dirichlet_eigenvalue(s, everywhere),
        "lambda_max_C_on_inactive_set": top_inactive,
        "lambda_min_C_on_inactive_set": neumann_to_dirichlet_eigenvalue(s, inactive, shift=top_inactive),
    }  # fmt: skip


def uzawa_observations(cell_type: str, quick: bool) -> tuple[dict, str]:
    if MPI.COMM_WORLD.size > 1:
        raise RuntimeError("the Uzawa table runs serially (node mirror map, paper's FD scheme)")
    N1, N2 = (20, 40) if quick else (80, 160)
    steps = (5.0, 10.0, 15.0, 20.0, 25.0, 30.0)
    long_step, long_run = 20.0, 60
    ex1 = {label: _uzawa_example1(Setup.get(1, N1, scheme), N1, steps, long_step, long_run)
           for label, scheme in (("ours", cell_type), (FD_LABEL, FINITE_DIFFERENCES))}  # fmt: skip
    s2 = Setup.get(2, N2, cell_type)
    ex2 = {}
    for gamma in (0.1, 0.2, 0.3):
        result = uzawa(s2.problem, gamma, reference=s2.reference.lam, tol=1e-4, max_iterations=400)
        ex2[f"{gamma:g}"] = {"iterations": result.iterations, "status": result.status,
                             "final_d_lambda": result.history[-1]["d_lambda"]}  # fmt: skip
    ex2_spectra = {
        "lambda_max_C_on_Gamma_f": neumann_to_dirichlet_eigenvalue(s2, np.ones(len(s2.problem.boundary_dofs), bool)),
        "lambda_max_C_on_inactive_set": neumann_to_dirichlet_eigenvalue(s2, s2.reference.states == 0),
    }
    data = {"example1_N": N1, "example1": ex1, "example2_N": N2, "example2": ex2, "example2_spectra": ex2_spectra,
            "paper": PAPER["uzawa"]}  # fmt: skip
    paper = PAPER["uzawa"]["example1_N80"]
    rows = []
    for gamma in (f"{g:g}" for g in steps):
        ours = [v["runs"][gamma] for v in ex1.values()]
        rows.append([gamma, paper.get(gamma, ""), *[f"{r['iterations']} ({r['status']})" for r in ours]])
    md1 = _md_table(["gamma", "paper", *[f"{label} (N = {N1})" for label in ex1]], rows)
    rows = [[label, v["inactive_nodes"], v["lambda_max_C_on_Gamma_f"], v["lambda_max_C_on_inactive_set"],
             2 / v["lambda_max_C_on_inactive_set"], v["lambda_min_C_on_inactive_set"],
             v["symmetry_breaking_of_lambda_bar"]] for label, v in ex1.items()]  # fmt: skip
    spec = _md_table(["", "|I| (nodes)", "lambda_max(C_h), Gamma_f", "lambda_max(C_h), I", "2/lambda_max(I)",
                      "lambda_min(C_h), I", "symmetry breaking of lambda_bar"], rows)  # fmt: skip
    rows = []
    for label, v in ex1.items():
        r = v["long_run"]
        rows.append([label, r["first_below_1e-4"], f"{r['min_d_lambda']:.2e} (l = {r['min_at']})",
                     r["symmetry_breaking_at_min"], r["d_lambda_last"], r["symmetry_breaking_last"]])  # fmt: skip
    md_long = _md_table(["", "first l with d < 1e-4", "min d_lambda", "symmetry breaking there",
                         f"d_lambda at l = {long_run}", f"symmetry breaking at l = {long_run}"], rows)  # fmt: skip
    rows = [[g, "400 its, d=1.03e-2" if g == "0.2" else "", v["iterations"], v["status"], v["final_d_lambda"]]
            for g, v in ex2.items()]  # fmt: skip
    md2 = _md_table(["gamma", "paper", "ours iterations", "ours status", "final d_lambda"], rows)
    spec2 = _md_table(
        ["", "lambda_max(C_h), Gamma_f", "2/lambda_max(Gamma_f)", "lambda_max(C_h), I", "2/lambda_max(I)"],
        [["ours", ex2_spectra["lambda_max_C_on_Gamma_f"], 2 / ex2_spectra["lambda_max_C_on_Gamma_f"],
          ex2_spectra["lambda_max_C_on_inactive_set"], 2 / ex2_spectra["lambda_max_C_on_inactive_set"]]],
    )  # fmt: skip
    return data, (
        f"Example 1, N = {N1}: Uzawa iterations, lambda^0 = 0, stopped when d_lambda < 1e-4 (max 1000).\n"
        "'paper's FD' runs the same Uzawa code on the paper's discretisation (`PaperFiniteDifferences`).\n\n"
        f"{md1}\n\n"
        "Discrete Neumann-to-Dirichlet maps C_h (4.2) on Gamma_f and on the inactive set I of lambda_bar\n"
        "(power iteration). Uzawa with frozen sets is Richardson's iteration for C_h on I: stable iff\n"
        "gamma < 2/lambda_max(I), contraction 1 - gamma lambda_min(I) for small gamma. (Continuous:\n"
        "lambda_max(C) on Gamma_f = coth(pi/2)/pi = 0.3471.)\n\n"
        f"{spec}\n\n"
        f"gamma = {long_step:g} continued past the stopping test (the data, lambda_bar and the iterates are odd\n"
        "about x1 = 1/2 in exact arithmetic; 'symmetry breaking' = ||lambda + lambda(1 - x1, .)||/2):\n\n"
        f"{md_long}\n\n"
        f"Example 2, N = {N2} (ours), max 400 iterations:\n\n{md2}\n\n"
        f"Example 2, N = {N2}: C_h on Gamma_f and on the inactive set I of lambda_bar.\n\n"
        f"{spec2}\n"
    )


TABLES: dict[str, typing.Callable[[str, bool], tuple[dict, str]]] = {
    "6.1": table_6_1,
    "fig6.1": figure_6_1,
    "6.2": table_6_2,
    "6.3": table_6_3,
    "6.4": table_6_4,
    "6.5": table_6_5,
    "6.6": table_6_6,
    "6.7": table_6_7,
    "uzawa": uzawa_observations,
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--tables", nargs="*", default=list(TABLES), choices=list(TABLES))
    parser.add_argument("--quick", action="store_true", help="small grids (smoke test, not the paper's N)")
    parser.add_argument("--cell-type", default="quadrilateral", choices=["quadrilateral", "triangle"])
    parser.add_argument("--output", default=str(RESULTS))
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO if MPI.COMM_WORLD.rank == 0 else logging.WARNING, format="%(message)s")
    logging.getLogger("contactqvi").setLevel(logging.WARNING)
    out = pathlib.Path(args.output)
    for name in args.tables:
        start = time.perf_counter()
        data, md = TABLES[name](args.cell_type, args.quick)
        seconds = time.perf_counter() - start
        data.update(cell_type=args.cell_type, quick=args.quick, seconds=seconds, mpi_ranks=MPI.COMM_WORLD.size)
        title = f"Seed 002 {'Table ' + name if name[0].isdigit() else name}" + (" (quick)" if args.quick else "")
        text = f"## {title}\n\n{md}\n"
        if MPI.COMM_WORLD.rank == 0:
            out.mkdir(parents=True, exist_ok=True)
            stem = name.replace(".", "_")
            (out / f"stadler_{stem}.json").write_text(json.dumps(data, indent=1, default=float) + "\n")
            (out / f"stadler_{stem}.md").write_text(text)
        logger.info("%s\n(%.1f s)", text, seconds)
    if MPI.COMM_WORLD.rank == 0:  # the summary collects every table written so far, in the paper's order
        parts = [out / f"stadler_{name.replace('.', '_')}.md" for name in TABLES]
        (out / "stadler_summary.md").write_text(
            DISCRETISATION_NOTE + "\n".join(part.read_text() for part in parts if part.is_file())
        )


if __name__ == "__main__":
    main()
