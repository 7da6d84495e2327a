"""The obstacle solver S (E2 of seed 003, Sect. 4.1): PFMY + PDAS, or SNES VI."""

from __future__ import annotations

import dataclasses
import typing

import numpy as np

from dolfinx import fem

from contactqvi.lifetime import PETScOwner
from contactqvi.parameters import Parameter, Parameters, require
from contactqvi.result import Result, Status
from contactqvi.vi.moreau_yosida import PathFollowingMoreauYosida
from contactqvi.vi.pdas import ObstacleActiveSetSolver
from contactqvi.vi.problem import ObstacleProblem
from contactqvi.vi.snes_vi import ObstacleSNESVI

__all__ = ["OBSTACLE_PARAMETERS", "ObstacleResult", "ObstacleSolver", "check_obstacle_parameters", "rho_path"]

_POSITIVE = {"minimum": 0.0, "exclusive": True}

OBSTACLE_PARAMETERS = Parameters(
    s_solver=Parameter(
        "pfmy-pdas",
        "S-solver: PFMY path + PDAS restoration, or PETSc's SNES VI",
        type=str,
        choices=("pfmy-pdas", "vinewtonrsls"),
    ),
    rho0=Parameter(1.0, "PFMY: first Moreau-Yosida parameter on a cold start", **_POSITIVE),
    rho0_warm=Parameter(1e-2, "PFMY: first Moreau-Yosida parameter on a warm start", **_POSITIVE),
    rho_min=Parameter(1e-6, "PFMY: last Moreau-Yosida parameter", **_POSITIVE),
    rho_factor=Parameter(10.0, "PFMY: rho is divided by this factor along the path", minimum=1.0, exclusive=True),
    pdas_max_iterations=Parameter(100, "PDAS: maximum number of iterations", type=int, minimum=1),
    pdas_c=Parameter(1.0, "PDAS: constant c, in units of the stiffness diagonal", **_POSITIVE),
)


def check_obstacle_parameters(overrides: dict | None) -> dict[str, typing.Any]:
    """:data:`OBSTACLE_PARAMETERS` with ``overrides``, checked; a ParameterError names a bad one."""
    params = OBSTACLE_PARAMETERS.check(overrides)
    rho0, rho0_warm, rho_min = params["rho0"], params["rho0_warm"], params["rho_min"]
    require(rho_min < rho0, "rho_min", f"must be < rho0 = {rho0!r}, got {rho_min!r}")
    require(rho_min <= rho0_warm, "rho_min", f"must be <= rho0_warm = {rho0_warm!r}, got {rho_min!r}")
    return params


def rho_path(rho0: float, rho_min: float, factor: float) -> list[float]:
    """rho0, rho0/factor, ... while above rho_min, then rho_min itself (the path always ends there)."""
    rhos = [rho0]
    while rhos[-1] / factor >= rho_min * (1 - 1e-12):
        rhos.append(rhos[-1] / factor)
    if rhos[-1] > rho_min * (1 + 1e-12):
        rhos.append(rho_min)
    return rhos


@dataclasses.dataclass(kw_only=True)
class ObstacleResult(Result):
    """One evaluation of S; ``iterations`` counts its linear solves (Newton steps plus PDAS solves).

    The status is that of the stage that decides: PDAS (a PFMY path that stopped
    early only costs PDAS iterations) or SNES VI.

    Attributes:
        pfmy_iterations, pdas_iterations, vi_iterations: the counts by stage.
        active: owned nodes of the active set {u = theta}.
        active_nodes: its global size.
    """

    pfmy_iterations: int = 0
    pdas_iterations: int = 0
    vi_iterations: int = 0
    active: np.ndarray | None = None
    active_nodes: int = 0


class ObstacleSolver(PETScOwner):
    """Evaluate S: solve the obstacle problem for a given obstacle and the problem's source.

    Args:
        problem: the obstacle problem (its ``u`` is initial guess and result).
        parameters: overrides of :data:`OBSTACLE_PARAMETERS`.
        prefix: options prefix; stages use ``<prefix>pfmy_``, ``<prefix>pdas_``, ``<prefix>vi_``.
    """

    def __init__(self, problem: ObstacleProblem, parameters: dict | None = None, prefix: str = "obstacle_"):
        self.params = check_obstacle_parameters(parameters)
        self.problem = problem
        self.warm = False
        self.pfmy: PathFollowingMoreauYosida | None = None
        self.pdas: ObstacleActiveSetSolver | None = None
        self.vi: ObstacleSNESVI | None = None
        if self.params["s_solver"] == "pfmy-pdas":
            self.pfmy = PathFollowingMoreauYosida(problem, prefix + "pfmy_")
            max_it, c = self.params["pdas_max_iterations"], self.params["pdas_c"]
            self.pdas = ObstacleActiveSetSolver(problem, max_it, c, prefix + "pdas_")
        else:
            self.vi = ObstacleSNESVI(problem, prefix + "vi_")

    def petsc_objects(self) -> list[PETScOwner | None]:
        return [self.pfmy, self.pdas, self.vi]

    def solve(self, obstacle: fem.Function | None = None, warm_start: bool | None = None) -> ObstacleResult:
        """Solve for ``obstacle`` (None: the problem's current one) from ``problem.u``.

        ``warm_start`` (the default after the first solve) starts from ``problem.u``, else from
        the boundary values extended by 0.
        """
        p, prm = self.problem, self.params
        if obstacle is not None:
            p.set_obstacle(obstacle)
        p.check_feasible_set()
        warm = self.warm if warm_start is None else warm_start
        if not warm:
            p.u.x.array[:] = p.boundary_values.x.array
        result = ObstacleResult(status=Status.ITERATING, iterations=0)
        if prm["s_solver"] == "pfmy-pdas":
            rhos = rho_path(prm["rho0_warm"] if warm else prm["rho0"], prm["rho_min"], prm["rho_factor"])
            pfmy, pdas = self.pfmy.solve(rhos), self.pdas.solve()
            result.pfmy_iterations, result.pdas_iterations, result.status = pfmy.iterations, pdas.iterations, pdas.status
            result.timings.update({"pfmy": sum(pfmy.timings.values()), "pdas": sum(pdas.timings.values())})
        else:
            vi = self.vi.solve()
            result.vi_iterations, result.status, result.timings = vi.iterations, vi.status, vi.timings
        result.iterations = result.pfmy_iterations + result.pdas_iterations + result.vi_iterations
        result.active = p.active_set(p.u)
        result.active_nodes = p.comm.allreduce(int(result.active.sum()))
        self.warm = True
        return result
