"""The temperature map Phi (E1): its Newton blocks (33)/(63) by finite differences, superlinear inner Newton."""

from __future__ import annotations

import math

from mpi4py import MPI

import numpy as np
import pytest
import ufl

from dolfinx import fem

from contactqvi.linalg import create_ksp, preset
from contactqvi.meshes import create_unit_interval, create_unit_square
from contactqvi.parameters import ParameterError
from contactqvi.problems import thermoforming
from contactqvi.qvi import TemperatureMap


def _map(case: str, prefix: str):
    """Phi for Test 3 (2D, g piecewise linear) or Test 1 (I) (1D, g = alpha1 + arctan(...))."""
    if case == "test3":
        data = thermoforming.test3()
        msh, _ = create_unit_square(MPI.COMM_WORLD, 10)
    else:
        data = thermoforming.test1(1 + 1 / math.pi, 1.01)
        msh, _ = create_unit_interval(MPI.COMM_WORLD, 64)
    V = fem.functionspace(msh, ("Lagrange", 1))
    x = ufl.SpatialCoordinate(msh)
    return V, TemperatureMap(V, data.k, data.g, data.Psi0(x), data.psi(x), data.varphi(x), prefix=prefix)


def _derivative(tm: TemperatureMap, h: fem.Function, out: fem.Function) -> None:
    """out = G_Phi(u) h = I_h(varphi xi_h), xi_h solving (33) with the blocks of (63) at the current (u, T)."""
    tm.linearize(tm.u, tm.T)
    A, C = tm.jacobian_matrix, tm.coupling_matrix
    rhs = A.createVecLeft()
    C.mult(h.x.petsc_vec, rhs)
    rhs.scale(-1.0)
    ksp = create_ksp(A.getComm(), "tphi_derivative_", preset("lu"), A=A)
    ksp.solve(rhs, out.x.petsc_vec)
    out.x.scatter_forward()
    out.x.array[:] *= tm.varphi.x.array
    ksp.destroy()
    rhs.destroy()


def _norm(comm, a: np.ndarray) -> float:
    return math.sqrt(comm.allreduce(float(a @ a), op=MPI.SUM))


# u keeps s = Psi0 + psi T - u on one smooth piece of g in the interior (away from the kinks):
# Test 3: s in (0, 1); Test 1: s < 1 since u = 2 sin(pi x) exceeds varphi T = sin(pi x) T / alpha1.
SMOOTH_POINTS = {
    "test3": lambda x: 0.3 * np.sin(np.pi * x[0]) * np.sin(np.pi * x[1]),
    "test1": lambda x: 2.0 * np.sin(np.pi * x[0]),
}


@pytest.mark.parametrize("case", ["test3", "test1"])
def test_newton_derivative_matches_finite_differences(case):
    V, tm = _map(case, f"tphi_fd_{case}_")
    comm, n = V.mesh.comm, V.dofmap.index_map.size_local
    u, h = fem.Function(V), fem.Function(V)
    u.interpolate(SMOOTH_POINTS[case])
    h.interpolate(lambda x: x[0] * (1 - x[0]) * (1 + x[0]) * (x[1] * (1 - x[1]) if case == "test3" else 1.0))
    base, perturbed, derivative = fem.Function(V), fem.Function(V), fem.Function(V)
    tm.solve(u)
    tm.apply(base)
    _derivative(tm, h, derivative)
    scale = _norm(comm, derivative.x.array[:n])
    assert scale > 1e-3
    remainders = []
    for eps in (1e-2, 1e-3):
        w = fem.Function(V)
        w.x.array[:] = u.x.array + eps * h.x.array
        tm.solve(w)
        tm.apply(perturbed)
        diff = (perturbed.x.array[:n] - base.x.array[:n]) / eps - derivative.x.array[:n]
        remainders.append(_norm(comm, diff) / scale)
    # first-order Taylor remainder: O(eps) (or round-off when Phi is affine there)
    assert remainders[1] < 1e-4, remainders
    assert remainders[1] < 0.2 * remainders[0] or remainders[1] < 1e-8, remainders


def test_semismooth_newton_for_temperature_converges_superlinearly():
    data = thermoforming.test1(1 + 1 / math.pi, 1.01)
    msh, _ = create_unit_interval(MPI.COMM_WORLD, 200)
    V = fem.functionspace(msh, ("Lagrange", 1))
    x = ufl.SpatialCoordinate(msh)
    tm = TemperatureMap(V, data.k, data.g, data.Psi0(x), data.psi(x), data.varphi(x), prefix="tphi1_")
    u = fem.Function(V)
    u.interpolate(lambda x: 0.5 * np.sin(np.pi * x[0]) + 0.3 * np.sin(3 * np.pi * x[0]))
    steps = tm.solve(u)
    r = tm.residual_history
    assert 3 <= steps <= 12, r
    assert r[-1] <= 1e-11 * r[0]
    ratios = [r[i + 1] / r[i] for i in range(len(r) - 1) if r[i] > 1e-9 * r[0]]
    # superlinear: the contraction factor of the residual goes to zero
    assert ratios[-1] < 0.05 and ratios[-1] < ratios[0], ratios


def test_negative_k_is_rejected():
    data = thermoforming.test3()
    msh, _ = create_unit_square(MPI.COMM_WORLD, 2)
    V = fem.functionspace(msh, ("Lagrange", 1))
    x = ufl.SpatialCoordinate(msh)
    with pytest.raises(ParameterError) as info:
        TemperatureMap(V, -1.0, data.g, data.Psi0(x), data.psi(x), data.varphi(x))
    assert info.value.name == "k"
