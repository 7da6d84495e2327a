"""Assemble the solver stack for problem data: spaces, Phi, S, the composite map and the outer method.

``method`` is one of ``alg1``, ``alg2``, ``c1``, ``c2``, ``c3`` (Sect. 4.1 of
seed 003); C2 swaps S for the Moreau-Yosida map S_rho and runs Algorithm 1.

The data are read by their fields (e.g. the containers of
:mod:`contactqvi.problems.thermoforming`), each a function of the spatial coordinate
returning a UFL expression, except ``dim``, ``k`` and ``atol``:

* the QVI (58): ``dim``, ``k``, ``g`` (a :class:`~contactqvi.qvi.temperature.Nonlinearity`),
  ``Phi0``, ``f``, ``varphi``, ``Psi0``, ``psi``, ``initial`` (None: u0 = (-Lap)^{-1} f),
  ``atol`` (the stopping tolerance of ||R(u)||_H1 when the caller gives none) and
  optionally ``exact``;
* the semilinear VI (48): ``dim``, ``b1``, ``b2`` (Nonlinearities), ``f``, ``Phi0``,
  ``initial``, ``atol``.
"""

from __future__ import annotations

import dataclasses
import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import ufl

from dolfinx import fem, la
from dolfinx import mesh as dmesh

from contactqvi.lifetime import PETScOwner
from contactqvi.linalg import assemble_system, create_ksp, preset
from contactqvi.meshes import create_unit_interval, create_unit_square
from contactqvi.parameters import Parameter, Parameters, require
from contactqvi.qvi.maps import CompositeMap, ObstacleQVIMap, RegularisedQVIMap, SemilinearVIMap
from contactqvi.qvi.outer import FIXED_POINT_PARAMETERS, FixedPointSolver
from contactqvi.qvi.temperature import TemperatureMap
from contactqvi.vi.moreau_yosida import PathFollowingMoreauYosida
from contactqvi.vi.problem import ObstacleProblem
from contactqvi.vi.solver import ObstacleSolver, check_obstacle_parameters

__all__ = ["BUILD_PARAMETERS", "OUTER_METHODS", "QVISetup", "create_mesh", "build", "exterior_facets"]

OUTER_METHODS = ("alg1", "alg2", "c1", "c2", "c3")

BUILD_PARAMETERS = Parameters(
    method=Parameter("alg2", "outer method: Algorithms 1, 2, or C1, C2, C3 (Sect. 4.1)", type=str, choices=OUTER_METHODS),
    rho=Parameter(1e-4, "C2: Moreau-Yosida parameter of S_rho", minimum=0.0, exclusive=True),
    quadrature_degree=Parameter(2, "quadrature degree of the nonsmooth terms", type=int, minimum=1),
)


def create_mesh(comm: MPI.Comm, dim: int, h: float, cell_type: str = "quadrilateral") -> tuple[dmesh.Mesh, dmesh.MeshTags]:
    """Uniform mesh of (0,1) or (0,1)^2 with cell edge length h (n = round(1/h) cells per side)."""
    require(isinstance(h, (int, float)) and h > 0, "h", f"must be > 0, got {h!r}")
    require(h <= 1, "h", f"must be <= 1 (the domain is the unit interval/square), got {h!r}")
    n = max(1, int(round(1.0 / h)))
    return create_unit_interval(comm, n) if dim == 1 else create_unit_square(comm, n, cell_type)


@dataclasses.dataclass
class QVISetup(PETScOwner):
    """Everything a run needs: the space, the composite map, the outer solver and u0; owns the map and solver."""

    V: fem.FunctionSpace
    fmap: CompositeMap
    solver: FixedPointSolver
    initial: fem.Function
    Phi0: fem.Function

    def petsc_objects(self) -> list[PETScOwner]:
        return [self.solver, self.fmap]


def exterior_facets(msh: dmesh.Mesh) -> np.ndarray:
    """Local indices of the facets that belong to exactly one cell of the whole mesh.

    Counts each facet's owned cells on every rank and sums the counts over the
    ranks sharing the facet. Needed because on a 1D mesh distributed without
    ghost cells (:func:`contactqvi.meshes.cell_partitioner`), DOLFINx 0.9's
    ``exterior_facet_indices`` also returns the vertices on the partition interface.
    """
    tdim = msh.topology.dim
    msh.topology.create_entities(tdim - 1)
    msh.topology.create_connectivity(tdim - 1, tdim)
    facet_map, n_cells_owned = msh.topology.index_map(tdim - 1), msh.topology.index_map(tdim).size_local
    f2c = msh.topology.connectivity(tdim - 1, tdim)
    n_facets = facet_map.size_local + facet_map.num_ghosts
    counts = la.vector(facet_map)
    owned_cells = (f2c.array < n_cells_owned).astype(float)
    counts.array[:] = np.add.reduceat(owned_cells, f2c.offsets[:n_facets])  # every facet has a cell here
    counts.scatter_reverse(la.InsertMode.add)
    counts.scatter_forward()
    return np.flatnonzero(counts.array == 1).astype(np.int32)


def _interpolate(V: fem.FunctionSpace, expr: ufl.core.expr.Expr, name: str) -> fem.Function:
    f = fem.Function(V, name=name)
    f.interpolate(fem.Expression(expr, V.element.interpolation_points(), comm=V.mesh.comm))
    return f


def _poisson(V: fem.FunctionSpace, f: ufl.core.expr.Expr, bcs: list[fem.DirichletBC]) -> fem.Function:
    """(-Lap)^{-1} f with homogeneous Dirichlet data (options prefix ``qvi_initial_``)."""
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    a = fem.form(ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx)
    L = fem.form(f * v * ufl.dx(metadata={"quadrature_degree": 4}))
    A, b = assemble_system(a, L, bcs)
    w = fem.Function(V, name="initial")
    ksp = create_ksp(V.mesh.comm, "qvi_initial_", preset("lu"), A=A)
    ksp.solve(b, w.x.petsc_vec)
    w.x.scatter_forward()
    for obj in (ksp, A, b):
        obj.destroy()
    return w


def _semilinear_map(data: typing.Any, problem_args: tuple, obstacle_parameters: dict | None, degree: int):
    """Test 4: S0 with the source Phi(y) = b1(y) b2(y) + f and the coupling (50)."""
    V, x, obstacle, bcs = problem_args
    y = fem.Function(V, name="y")
    source = data.b1.g(y) * data.b2.g(y) + data.f(x)
    solver = ObstacleSolver(ObstacleProblem(V, source, obstacle, bcs, degree), obstacle_parameters)
    du, q = ufl.TrialFunction(V), ufl.TestFunction(V)
    dx = ufl.Measure("dx", domain=V.mesh, metadata={"quadrature_degree": degree})
    derivative = data.b1.g(y) * data.b2.derivative(y) + data.b2.g(y) * data.b1.derivative(y)
    return SemilinearVIMap(solver, y, derivative * du * q * dx)


def _qvi_map(data: typing.Any, problem_args: tuple, obstacle_parameters: dict | None, Phi0, method, rho, degree):
    """(58): Phi (temperature) then S, or S_rho for C2."""
    V, x, obstacle, bcs = problem_args
    temperature = TemperatureMap(V, data.k, data.g, data.Psi0(x), data.psi(x), data.varphi(x), degree)
    problem = ObstacleProblem(V, data.f(x), obstacle, bcs, degree)
    if method != "c2":
        return ObstacleQVIMap(temperature, ObstacleSolver(problem, obstacle_parameters), Phi0)
    prm = check_obstacle_parameters(obstacle_parameters)
    require(
        prm["s_solver"] == "pfmy-pdas",
        "s_solver",
        f"C2 replaces S by the Moreau-Yosida map S_rho of (65)-(67); S-solver {prm['s_solver']!r} does not apply",
    )
    return RegularisedQVIMap(temperature, PathFollowingMoreauYosida(problem), Phi0, rho, prm["rho0"], prm["rho_factor"])


def build(
    data: typing.Any,
    msh: dmesh.Mesh,
    method: str = "alg2",
    outer_parameters: dict | None = None,
    obstacle_parameters: dict | None = None,
    rho: float = 1e-4,
    quadrature_degree: int = 2,
) -> QVISetup:
    """Build Phi, S, H = S o Phi and the outer solver for ``data`` on ``msh`` (P1/Q1).

    Args:
        data: QVI (58) or semilinear VI (48) data (module docstring).
        msh: the mesh; the whole boundary carries u = 0.
        method, rho, quadrature_degree: see :data:`BUILD_PARAMETERS`.
        outer_parameters: overrides of :data:`~contactqvi.qvi.outer.FIXED_POINT_PARAMETERS` (not ``method``);
            ``atol`` None or absent: the data's.
        obstacle_parameters: overrides of :data:`~contactqvi.vi.solver.OBSTACLE_PARAMETERS`.
    """
    prm = BUILD_PARAMETERS.check({"method": method, "rho": rho, "quadrature_degree": quadrature_degree})
    require(msh.topology.dim == data.dim, "mesh", f"Test data are {data.dim}D, the mesh is {msh.topology.dim}D")
    params = dict(outer_parameters or {})
    params["method"] = "alg1" if method == "c2" else method
    params.setdefault("label", method)
    if params.get("atol") is None:
        params["atol"] = data.atol
    FIXED_POINT_PARAMETERS.check(params)
    check_obstacle_parameters(obstacle_parameters)
    V = fem.functionspace(msh, ("Lagrange", 1))
    x = ufl.SpatialCoordinate(msh)
    fdim = msh.topology.dim - 1
    boundary_dofs = fem.locate_dofs_topological(V, fdim, exterior_facets(msh))
    bcs = [fem.dirichletbc(PETSc.ScalarType(0.0), boundary_dofs, V)]
    Phi0 = _interpolate(V, data.Phi0(x), "Phi0")
    obstacle = fem.Function(V, name="obstacle")
    obstacle.x.array[:] = Phi0.x.array
    args = (V, x, obstacle, bcs)
    if hasattr(data, "b1"):  # the semilinear VI (48)
        fmap: CompositeMap = _semilinear_map(data, args, obstacle_parameters, prm["quadrature_degree"])
    else:
        fmap = _qvi_map(data, args, obstacle_parameters, Phi0, method, prm["rho"], prm["quadrature_degree"])
    u0 = _poisson(V, data.f(x), bcs) if data.initial is None else _interpolate(V, data.initial(x), "initial")
    for bc in bcs:
        bc.set(u0.x.array)
    exact = None if getattr(data, "exact", None) is None else data.exact(x)
    return QVISetup(V, fmap, FixedPointSolver(fmap, params, exact=exact), u0, Phi0)
