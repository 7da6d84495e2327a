"""Assemble the solver stack for problem data: spaces, Phi, S, the composite map and the outer method.

``method`` is one of ``alg1``, ``alg2``, ``c1``, ``c2``, ``c3`` (Sect. 4.1 of
seed 003); C2 swaps S for the Moreau-Yosida map S_rho and runs Algorithm 1.
"""

from __future__ import annotations

import dataclasses

from mpi4py import MPI
from petsc4py import PETSc

import ufl

import dolfinx.fem.petsc
from dolfinx import fem
from dolfinx import mesh as dmesh

from contactqvi.meshes import create_unit_interval, create_unit_square
from contactqvi.parameters import require, require_positive
from contactqvi.qvi.data import ObstacleQVIData, SemilinearVIData
from contactqvi.qvi.maps import CompositeMap, ObstacleQVIMap, RegularisedQVIMap, SemilinearVIMap
from contactqvi.qvi.outer import FixedPointSolver
from contactqvi.qvi.temperature import TemperatureMap
from contactqvi.vi.moreau_yosida import PathFollowingMoreauYosida
from contactqvi.vi.problem import ObstacleProblem
from contactqvi.vi.solver import ObstacleSolver, check_obstacle_parameters

__all__ = ["OUTER_METHODS", "QVISetup", "create_mesh", "build"]

OUTER_METHODS = ("alg1", "alg2", "c1", "c2", "c3")


def create_mesh(comm: MPI.Comm, dim: int, h: float, cell_type: str = "quadrilateral") -> tuple[dmesh.Mesh, dmesh.MeshTags]:
    """Uniform mesh of (0,1) or (0,1)^2 with cell edge length h (n = round(1/h) cells per side)."""
    require(isinstance(h, (int, float)) and h > 0, "h", f"must be > 0, got {h!r}")
    require(h <= 1, "h", f"must be <= 1 (the domain is the unit interval/square), got {h!r}")
    n = max(1, int(round(1.0 / h)))
    return create_unit_interval(comm, n) if dim == 1 else create_unit_square(comm, n, cell_type)


@dataclasses.dataclass
class QVISetup:
    """Everything a run needs: the space, the composite map, the outer solver and u0."""

    V: fem.FunctionSpace
    fmap: CompositeMap
    solver: FixedPointSolver
    initial: fem.Function
    Phi0: fem.Function

    def destroy(self) -> None:
        """Free the PETSc objects of the whole stack (collective)."""
        self.solver.destroy()
        self.fmap.destroy()
        PETSc.garbage_cleanup(self.V.mesh.comm)


def _interpolate(V: fem.FunctionSpace, expr: ufl.core.expr.Expr, name: str) -> fem.Function:
    f = fem.Function(V, name=name)
    f.interpolate(fem.Expression(expr, V.element.interpolation_points(), comm=V.mesh.comm))
    return f


def _poisson(V: fem.FunctionSpace, f: ufl.core.expr.Expr, bcs: list[fem.DirichletBC]) -> fem.Function:
    """(-Lap)^{-1} f with homogeneous Dirichlet data."""
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    problem = dolfinx.fem.petsc.LinearProblem(
        ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx,
        f * v * ufl.dx(metadata={"quadrature_degree": 4}),
        bcs=bcs,
        petsc_options={"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"},
    )
    w = problem.solve()
    w.name = "initial"
    return w


def build(
    data: ObstacleQVIData | SemilinearVIData,
    msh: dmesh.Mesh,
    method: str = "alg2",
    outer_parameters: dict | None = None,
    obstacle_parameters: dict | None = None,
    rho: float = 1e-4,
    quadrature_degree: int = 2,
) -> QVISetup:
    """Build Phi, S, H = S o Phi and the outer solver for ``data`` on ``msh`` (P1/Q1).

    Args:
        data: QVI (58) or semilinear VI (48) data.
        msh: the mesh; the whole boundary carries u = 0.
        method: ``alg1``, ``alg2``, ``c1``, ``c2`` or ``c3``.
        outer_parameters: overrides of :data:`~contactqvi.qvi.outer.FIXED_POINT_PARAMETERS` (not ``method``).
        obstacle_parameters: overrides of :data:`~contactqvi.vi.solver.OBSTACLE_PARAMETERS`.
        rho: Moreau-Yosida parameter of C2.
        quadrature_degree: quadrature of the nonsmooth terms.
    """
    require(method in OUTER_METHODS, "method", f"unknown method {method!r}; known: {', '.join(OUTER_METHODS)}")
    require(msh.topology.dim == data.dim, "mesh", f"Test data are {data.dim}D, the mesh is {msh.topology.dim}D")
    require_positive("rho", rho)
    if isinstance(data, ObstacleQVIData):
        require_positive("k", data.k)
    V = fem.functionspace(msh, ("Lagrange", 1))
    x = ufl.SpatialCoordinate(msh)
    fdim = msh.topology.dim - 1
    msh.topology.create_connectivity(fdim, msh.topology.dim)
    boundary = dmesh.exterior_facet_indices(msh.topology)
    bcs = [fem.dirichletbc(PETSc.ScalarType(0.0), fem.locate_dofs_topological(V, fdim, boundary), V)]
    Phi0 = _interpolate(V, data.Phi0(x), "Phi0")
    obstacle = fem.Function(V, name="obstacle")
    obstacle.x.array[:] = Phi0.x.array
    params = dict(outer_parameters or {})
    params["method"] = "alg1" if method == "c2" else method
    params.setdefault("label", method)

    if isinstance(data, SemilinearVIData):
        y = fem.Function(V, name="y")
        source = data.b1.g(y) * data.b2.g(y) + data.f(x)
        problem = ObstacleProblem(V, source, obstacle, bcs, quadrature_degree)
        solver_s = ObstacleSolver(problem, obstacle_parameters)
        du, q = ufl.TrialFunction(V), ufl.TestFunction(V)
        dx = ufl.Measure("dx", domain=msh, metadata={"quadrature_degree": quadrature_degree})
        derivative = data.b1.g(y) * data.b2.derivative(y) + data.b2.g(y) * data.b1.derivative(y)
        fmap: CompositeMap = SemilinearVIMap(solver_s, y, derivative * du * q * dx)
    else:
        temperature = TemperatureMap(
            V, data.k, data.g, data.Psi0(x), data.psi(x), data.varphi(x), quadrature_degree
        )
        problem = ObstacleProblem(V, data.f(x), obstacle, bcs, quadrature_degree)
        if method == "c2":
            prm = check_obstacle_parameters(obstacle_parameters)
            require(
                prm["method"] == "pfmy-pdas",
                "method",
                f"C2 replaces S by the Moreau-Yosida map S_rho of (65)-(67); S-solver {prm['method']!r} does not apply",
            )
            pfmy = PathFollowingMoreauYosida(problem)
            fmap = RegularisedQVIMap(temperature, pfmy, Phi0, rho, prm["rho0"], prm["rho_factor"])
        else:
            fmap = ObstacleQVIMap(temperature, ObstacleSolver(problem, obstacle_parameters), Phi0)

    if data.initial is None:
        u0 = _poisson(V, data.f(x), bcs)
    else:
        u0 = _interpolate(V, data.initial(x), "initial")
    for bc in bcs:
        bc.set(u0.x.array)
    exact = None if getattr(data, "exact", None) is None else data.exact(x)
    solver = FixedPointSolver(fmap, params, exact=exact)
    return QVISetup(V, fmap, solver, u0, Phi0)
