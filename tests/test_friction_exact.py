"""A closed-form, one-dimensional case of (P): slip on one edge, stick on the other.

Omega = (0, 1)^2, Gamma_f = {x1 = 0} u {x1 = 1}, Gamma_0 empty, homogeneous
Neumann on x2 = 0, 1, mu = 1, g = 1 and f = c1 + c2 x1 depend on x1 only, so
y = y(x1) solves -y'' + y = f with lambda = -dy/dn: lambda(0) = y'(0),
lambda(1) = -y'(1). For c1 = 5, c2 = -6 the left edge slips (lambda = g, y > 0)
and the right edge sticks (y = 0, |lambda| < g):

    y = c1 + c2 x + A cosh x + B sinh x,  B = g - c2,  A = -(c1 + c2 + B sinh 1) / cosh 1.
"""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest

from contactqvi.friction import FrictionActiveSetSolver, FrictionProblem
from contactqvi.meshes import create_unit_square
from contactqvi.result import Status

G, C1, C2 = 1.0, 5.0, -6.0
B = G - C2
A = -(C1 + C2 + B * np.sinh(1.0)) / np.cosh(1.0)


def exact_y(x: np.ndarray) -> np.ndarray:
    return C1 + C2 * x + A * np.cosh(x) + B * np.sinh(x)


def exact_lambda(x: np.ndarray) -> np.ndarray:
    """lambda = y'(0) on x1 = 0 and -y'(1) on x1 = 1."""
    dy = C2 + A * np.sinh(x) + B * np.cosh(x)
    return np.where(x < 0.5, dy, -dy)


@pytest.mark.one_rank(reason="the exact solution's formulas, no mesh")
def test_exact_solution_is_consistent():
    """The formula satisfies the complementarity conditions (2.5) of the assumed stick/slip case."""
    assert exact_y(np.array([0.0]))[0] > 0.3 and abs(exact_y(np.array([1.0]))[0]) < 1e-14
    assert exact_lambda(np.array([0.0]))[0] == pytest.approx(G)
    assert 0.0 < exact_lambda(np.array([1.0]))[0] < 0.8 * G


@pytest.mark.parametrize("cell_type", ["quadrilateral", "triangle"])
def test_errors_decrease_under_refinement(cell_type):
    comm = MPI.COMM_WORLD
    errors = []
    for N in (5, 9, 17, 33):
        msh, tags = create_unit_square(comm, N - 1, cell_type)
        problem = FrictionProblem(msh, tags, ("left", "right"), (), lambda x: C1 + C2 * x[0], mu=1.0, g=G)
        with problem, FrictionActiveSetSolver(problem) as pdas:
            result = pdas.solve(gamma=1e16)
            n_owned = problem.V.dofmap.index_map.size_local
            x = problem.V.tabulate_dof_coordinates()[:n_owned, 0]
            y_error = problem.max_abs(result.y.x.array[:n_owned] - exact_y(x))
        assert result.status == Status.CONVERGED_ACTIVE_SET
        xb = problem.V.tabulate_dof_coordinates()[problem.boundary_dofs, 0]
        lam_error = problem.boundary_norm(result.lam - exact_lambda(xb))
        slip = problem.count((result.states == 1) & (xb < 0.5))
        stick = problem.count((result.states == 0) & (xb > 0.5))
        assert slip + stick == problem.n_boundary  # left edge in A+, right edge in I, nothing else
        errors.append((N, y_error, lam_error))
        if comm.rank == 0:
            print(f"{cell_type} N={N:3d}: max|y_h - y| = {y_error:.3e}, ||lambda_h - lambda||_L2 = {lam_error:.3e}")
    # Q1: the discrete problem reduces exactly to 1D P1 (second order at the nodes); P1 on
    # right-diagonal triangles does not (its mass term couples x2), the order is lower.
    factor = 3.5 if cell_type == "quadrilateral" else 1.4
    for (_, ey0, el0), (_, ey1, el1) in zip(errors, errors[1:]):
        assert ey1 < ey0 / factor
        assert el1 < el0 / factor
    assert errors[-1][1] < 2e-3 and errors[-1][2] < 5e-3
