"""Test 1 of seed 003 (69): 1D QVI with exact solution u = sin(pi x), T = alpha1."""

from __future__ import annotations

import math

from mpi4py import MPI

import pytest

from contactqvi.problems import thermoforming
from contactqvi.qvi import build, create_mesh


def _solve(h: float, method: str = "alg2", parameter_set: str = "I", initial: str = "zero", max_iterations: int = 20):
    data = thermoforming.make_test(1, parameter_set, initial)
    msh, _ = create_mesh(MPI.COMM_WORLD, 1, h)
    setup = build(data, msh, method, {"atol": 1e-12, "max_iterations": max_iterations})
    return setup, setup.solver.solve(setup.initial)


@pytest.mark.parametrize("initial", ["zero", "poisson"])
def test_algorithm2_set_I_converges_superlinearly(initial):
    _, result = _solve(1 / 200, initial=initial)
    assert result.converged
    assert result.residuals[-1] <= 1e-12
    assert result.iterations <= 6
    # Sect. 4.2: in this test Algorithm 2 always takes the Newton candidate.
    assert all(t == "newton" for t in result.taken[1:])
    # Superlinear: EOC (71) of the residual history > 1 at the end.
    assert max(result.residual_eocs) > 1.0, result.residual_eocs
    r = result.residuals
    ratios = [r[i + 1] / r[i] for i in range(len(r) - 1)]
    assert all(ratios[i + 1] < ratios[i] for i in range(len(ratios) - 1)), ratios
    assert ratios[-1] < 1e-3, ratios


def test_h1_error_decreases_like_h():
    errors = []
    for n in (50, 100, 200):
        _, result = _solve(1 / n)
        assert result.converged
        errors.append(result.errors[-1])
    rates = [math.log2(errors[i] / errors[i + 1]) for i in range(2)]
    assert errors[-1] < 0.05
    assert min(rates) > 0.9 and max(rates) < 1.3, (errors, rates)


def test_fixed_point_iteration_is_slower_than_algorithm2():
    _, alg2 = _solve(1 / 100)
    _, c1 = _solve(1 / 100, method="c1", max_iterations=60)
    assert c1.converged
    assert c1.iterations > 2 * alg2.iterations
    diff = abs(c1.errors[-1] - alg2.errors[-1])
    assert diff < 1e-9


def test_set_II_algorithm1_converges_beyond_the_theory():
    _, alg1 = _solve(1 / 100, method="alg1", parameter_set="II")
    # gamma = (1 + pi)/(pi alpha1 alpha2) >> 1 (no contraction), yet Newton converges (Fig. 1(c)).
    assert alg1.converged and alg1.iterations <= 6
    assert alg1.residuals[-1] <= 1e-12
