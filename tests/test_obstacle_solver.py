"""The obstacle solver S (E2): exact solution, SNES VI oracle, feasibility, complementarity, bad input."""

from __future__ import annotations

import math

from mpi4py import MPI

import numpy as np
import pytest
import ufl

from dolfinx import fem

from contactqvi.meshes import create_unit_square
from contactqvi.parameters import ParameterError
from contactqvi.problems.obstacle import radial_obstacle
from contactqvi.vi import ObstacleProblem, ObstacleSolver, rho_path

DATA = radial_obstacle()


def _radial(n: int, cell_type: str = "quadrilateral", obstacle_shift: float = 0.0):
    msh, tags = create_unit_square(MPI.COMM_WORLD, n, cell_type)
    V = fem.functionspace(msh, ("Lagrange", 1))
    msh.topology.create_connectivity(1, 2)
    g = fem.Function(V)
    g.interpolate(DATA.exact)
    bc = fem.dirichletbc(g, fem.locate_dofs_topological(V, 1, tags.indices))
    theta = fem.Function(V)
    theta.interpolate(DATA.obstacle)
    theta.x.array[:] += obstacle_shift
    return msh, ObstacleProblem(V, fem.Constant(msh, 0.0), theta, [bc])


def _h1_error(msh, u) -> float:
    e = u - DATA.exact_ufl(ufl.SpatialCoordinate(msh))
    form = fem.form((e**2 + ufl.inner(ufl.grad(e), ufl.grad(e))) * ufl.dx(metadata={"quadrature_degree": 6}))
    return math.sqrt(msh.comm.allreduce(fem.assemble_scalar(form), op=MPI.SUM))


@pytest.mark.parametrize("cell_type", ["quadrilateral", "triangle"])
def test_radial_exact_solution_converges_at_first_order(cell_type):
    errors = []
    for n in (16, 32, 64):
        msh, problem = _radial(n, cell_type)
        result = ObstacleSolver(problem).solve()
        assert result.converged and result.pfmy_iterations > 0 and result.pdas_iterations >= 1
        errors.append(_h1_error(msh, problem.u))
    rates = [math.log2(errors[i] / errors[i + 1]) for i in range(2)]
    assert errors[2] < 0.07, errors
    assert min(rates) > 0.85, (errors, rates)


def test_pfmy_pdas_agrees_with_snes_vi_and_is_exactly_feasible():
    msh, problem = _radial(24)
    ObstacleSolver(problem, {"s_solver": "pfmy-pdas"}, prefix="t_pfmy_").solve()
    u_pdas = problem.u.x.array.copy()
    lam = problem.multiplier.array.copy()
    n = problem.n_owned
    theta = problem.obstacle.x.array[:n]
    # Feasibility exactly at the nodes (the final projection), and an active set.
    assert msh.comm.allreduce(float(np.max(u_pdas[:n] - theta)), op=MPI.MAX) <= 0.0
    active = u_pdas[:n] == theta
    assert msh.comm.allreduce(int(active.sum())) > 20
    # Complementarity of the discrete multiplier: lambda >= 0, lambda = 0 where u < theta.
    scale = msh.comm.allreduce(float(np.max(np.abs(lam))), op=MPI.MAX)
    assert scale > 0
    assert msh.comm.allreduce(float(np.min(lam)), op=MPI.MIN) >= -1e-10 * scale
    assert msh.comm.allreduce(float(np.max(np.abs(lam[~active]))), op=MPI.MAX) == 0.0
    # The independent oracle: PETSc's reduced-space VI Newton.
    problem.u.x.array[:] = 0.0
    vi = ObstacleSolver(problem, {"s_solver": "vinewtonrsls"}, prefix="t_vi_").solve()
    assert vi.converged and vi.vi_iterations > 0
    diff = msh.comm.allreduce(float(np.max(np.abs(problem.u.x.array[:n] - u_pdas[:n]))), op=MPI.MAX)
    assert diff < 1e-8


def test_pdas_refactorisations_agree_with_snes_vi():
    # A short PFMY path leaves PDAS several solves: its one matrix is refilled and MUMPS refactorises.
    msh, problem = _radial(32)
    pdas = ObstacleSolver(problem, {"rho_min": 1e-3}, prefix="t_refac_pdas_").solve()
    assert pdas.converged and pdas.pdas_iterations >= 3
    u_pdas = problem.u.x.array.copy()
    problem.u.x.array[:] = 0.0
    assert ObstacleSolver(problem, {"s_solver": "vinewtonrsls"}, prefix="t_refac_vi_").solve().converged
    n = problem.n_owned
    assert msh.comm.allreduce(float(np.max(np.abs(problem.u.x.array[:n] - u_pdas[:n]))), op=MPI.MAX) < 1e-10


@pytest.mark.one_rank(reason="the rho path's numbers, no mesh")
def test_rho_path_ends_at_rho_min():
    assert rho_path(1.0, 1e-6, 10.0) == pytest.approx([10.0**-k for k in range(7)], rel=1e-12)
    assert rho_path(1.0, 5e-4, 10.0) == pytest.approx([1.0, 0.1, 0.01, 1e-3, 5e-4], rel=1e-12)
    assert rho_path(1e-2, 1e-2, 10.0) == [1e-2]


def test_warm_start_uses_the_shorter_path():
    _, problem = _radial(16)
    solver = ObstacleSolver(problem, {"rho0": 1.0, "rho0_warm": 1e-2, "rho_min": 1e-6})
    cold = solver.solve()
    warm = solver.solve()
    assert warm.pfmy_iterations < cold.pfmy_iterations
    assert warm.active_nodes == cold.active_nodes


@pytest.mark.parametrize(
    "params, name",
    [({"rho_min": 1.0, "rho0": 1.0}, "rho_min"), ({"s_solver": "bogus"}, "s_solver"), ({"rho0": -1.0}, "rho0"), ({"nope": 1}, "nope")],
)
def test_bad_parameters_name_the_parameter(params, name):
    _, problem = _radial(4)
    with pytest.raises(ParameterError) as info:
        ObstacleSolver(problem, params)
    assert info.value.name == name


def test_obstacle_below_boundary_data_means_empty_feasible_set():
    _, problem = _radial(8, obstacle_shift=-5.0)
    with pytest.raises(ParameterError, match="feasible set K is empty") as info:
        ObstacleSolver(problem).solve()
    assert info.value.name == "obstacle"
