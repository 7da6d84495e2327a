"""Test 3 of seed 003 (78): the 2D thermoforming QVI; serial vs parallel; bad input."""

from __future__ import annotations

import dataclasses

from mpi4py import MPI

import numpy as np
import pytest

from contactqvi.tables import gather_vertex_values
from contactqvi.parameters import ParameterError
from contactqvi.problems import thermoforming
from contactqvi.qvi import build, create_mesh


def _solve(comm: MPI.Comm, h: float, method: str = "alg2", **outer):
    data = thermoforming.test3()
    msh, _ = create_mesh(comm, 2, h)
    setup = build(data, msh, method, {"atol": 1e-12, "max_iterations": 40, **outer})
    return setup, setup.solver.solve(setup.initial)


@pytest.mark.parametrize("h", [0.04, 0.02])
def test_algorithm2_mesh_independent_and_feasible(h):
    setup, result = _solve(MPI.COMM_WORLD, h)
    assert result.converged
    assert result.iterations <= 5
    assert result.residuals[-1] <= 1e-12
    totals = result.totals
    assert totals["phi_newton"] > 0 and totals["pfmy"] > 0 and totals["pdas"] > 0
    # u <= mould Phi0 + varphi T at every node, at the returned iterate.
    ev = result.evaluation
    n = setup.fmap.n_owned
    comm = setup.V.mesh.comm
    u = result.solution.x.array[:n]
    excess = comm.allreduce(float(np.max(u - ev.obstacle.x.array[:n])), op=MPI.MAX)
    assert excess <= 1e-12
    # the membrane touches the mould
    assert comm.allreduce(int(np.count_nonzero(ev.active))) > 10


def test_fixed_point_and_newton_reach_the_same_solution():
    _, newton = _solve(MPI.COMM_WORLD, 0.04, "alg1")
    _, fixed = _solve(MPI.COMM_WORLD, 0.04, "c1")
    assert newton.converged and fixed.converged
    assert fixed.iterations > 2 * newton.iterations
    # separately built meshes may number their dofs differently in parallel: compare by coordinates
    _, u_newton = _sorted(*gather_vertex_values(newton.solution))
    _, u_fixed = _sorted(*gather_vertex_values(fixed.solution))
    if MPI.COMM_WORLD.rank == 0:
        assert np.max(np.abs(u_newton - u_fixed)) < 1e-10


def test_regularised_c2_and_linesearch_c3_converge():
    _, c3 = _solve(MPI.COMM_WORLD, 0.04, "c3")
    assert c3.converged and c3.iterations <= 6
    _, c2 = _solve(MPI.COMM_WORLD, 0.04, "c2", atol=1e-10)
    assert c2.converged


def _sorted(x, u):
    """Order by coordinates rounded to 1e-9 (raw coordinates differ by round-off across partitions)."""
    if x is None:
        return None, None
    key = np.round(x, 9)
    order = np.lexsort((key[:, 0], key[:, 1], key[:, 2]))
    return x[order], u[order]


def test_serial_and_parallel_runs_agree():
    """Each rank solves the whole problem on COMM_SELF; compare with the COMM_WORLD solve."""
    _, parallel = _solve(MPI.COMM_WORLD, 0.04)
    _, serial = _solve(MPI.COMM_SELF, 0.04)
    assert parallel.iterations == serial.iterations
    assert parallel.taken == serial.taken
    x_par, u_par = _sorted(*gather_vertex_values(parallel.solution))
    x_ser, u_ser = _sorted(*gather_vertex_values(serial.solution))
    if MPI.COMM_WORLD.rank == 0:
        assert np.allclose(x_par, x_ser)
        assert np.max(np.abs(u_par - u_ser)) < 1e-8, (np.max(np.abs(u_par - u_ser)), parallel.residuals, serial.residuals)
    assert abs(parallel.residuals[0] - serial.residuals[0]) < 1e-10


@pytest.mark.parametrize(
    "kwargs, name",
    [({"h": 0.0}, "h"), ({"h": -0.1}, "h"), ({"method": "newton"}, "method"), ({"rho": -1.0}, "rho")],
)
def test_bad_input_names_the_parameter(kwargs, name):
    with pytest.raises(ParameterError) as info:
        data = thermoforming.test3()
        msh, _ = create_mesh(MPI.COMM_WORLD, 2, kwargs.get("h", 0.25))
        build(data, msh, kwargs.get("method", "alg2"), rho=kwargs.get("rho", 1e-4))
    assert info.value.name == name


def test_unknown_test_and_bad_obstacle_parameters():
    with pytest.raises(ParameterError) as info:
        thermoforming.make_test(7)
    assert info.value.name == "test"
    data = thermoforming.test3()
    msh, _ = create_mesh(MPI.COMM_WORLD, 2, 0.25)
    with pytest.raises(ParameterError) as info:
        build(data, msh, "alg2", obstacle_parameters={"rho0": 1e-6, "rho_min": 1e-6})
    assert info.value.name == "rho_min"
    # C2 checks the same parameters, and has no S-solver to choose.
    for params, name in (({"bogus": 1}, "bogus"), ({"s_solver": "vinewtonrsls"}, "s_solver"), ({"rho_factor": 1}, "rho_factor")):
        with pytest.raises(ParameterError) as info:
            build(data, msh, "c2", obstacle_parameters=params)
        assert info.value.name == name


def _linearisation_defect(setup, steps: int, eps: float) -> float:
    """||R(x + eps d) - R(x) + eps R(x)|| / (eps ||R(x)||) for the Newton direction d at the iterate after ``steps`` steps."""
    solver, n = setup.solver, setup.fmap.n_owned
    x = setup.initial.x.array[:n].copy()
    for _ in range(steps):
        ev, _ = solver.evaluate(x)
        x = x + solver.newton_direction(x, ev)
    ev, _ = solver.evaluate(x)
    d = solver.newton_direction(x, ev)
    r = x - ev.value.x.array[:n]
    ev_t, _ = solver.evaluate(x + eps * d)
    r_t = x + eps * d - ev_t.value.x.array[:n]
    return solver.norm(r_t - r + eps * r) / (eps * solver.norm(r))


@pytest.mark.parametrize("test, method, h", [(3, "alg1", 0.1), (3, "c2", 0.1), (4, "alg1", 0.05)])
def test_newton_system_is_the_linearisation_after_reassembly(test, method, h):
    # G_R(x) d = -R(x) checked by finite differences of R at the second iterate, i.e. with the block
    # matrices of (62)-(64), (65)-(67) or Test 4 re-assembled in place once. R is piecewise linear
    # along d there (active set and kinks of g unchanged), so the defect is round-off.
    data = thermoforming.make_test(test)
    msh, _ = create_mesh(MPI.COMM_WORLD, data.dim, h)
    setup = build(data, msh, method, {"atol": 1e-10})
    assert _linearisation_defect(setup, steps=1, eps=1e-4) < 1e-6


def test_newton_system_with_varphi_nonzero_on_the_boundary():
    # Test 1 with varphi + 1/2, which violates the paper's varphi = 0 on the boundary: the Newton system
    # must still be the linearisation (delta u = 0 there, whatever eta = varphi xi is).
    data = thermoforming.make_test(1)
    varphi = data.varphi
    shifted = dataclasses.replace(data, varphi=lambda x: varphi(x) + 0.5)
    msh, _ = create_mesh(MPI.COMM_WORLD, 1, 0.02)
    setup = build(shifted, msh, "alg1", {"atol": 1e-10})
    assert _linearisation_defect(setup, steps=1, eps=1e-4) < 1e-6


def test_projection_derivative_by_finite_differences():
    # Test 2 at u0 (outside B_R(0)): with the exact G_PB of Lemma 2.9 the defect is a first-order Taylor
    # remainder; the scaled variant R/||x|| Id is not a derivative of P_B (O(1) defect, radial direction).
    data = thermoforming.test2()
    defects = {}
    for variant in ("exact", "scaled"):
        msh, _ = create_mesh(MPI.COMM_WORLD, 1, 0.02)
        setup = build(data, msh, "alg1", {"atol": 1e-10, "radius": 4.944, "projection_derivative": variant})
        defects[variant] = [_linearisation_defect(setup, 0, eps) for eps in (1e-3, 1e-4)]
    exact, scaled = defects["exact"], defects["scaled"]
    assert exact[1] < 1e-6 and exact[1] < 0.2 * exact[0], exact
    assert min(scaled) > 1e-2, scaled
