"""The obstacle solver S (E2 of seed 003, Sect. 4.1): PFMY + PDAS, or SNES VI."""

from __future__ import annotations

import dataclasses
import typing

from contactqvi.parameters import ParameterTable, merge_parameters, require, require_positive
from contactqvi.vi.moreau_yosida import PathFollowingMoreauYosida
from contactqvi.vi.pdas import PrimalDualActiveSet
from contactqvi.vi.problem import ObstacleProblem
from contactqvi.vi.snes_vi import SNESVariationalInequality

__all__ = ["OBSTACLE_PARAMETERS", "ObstacleResult", "ObstacleSolver", "check_obstacle_parameters", "rho_path"]

OBSTACLE_PARAMETERS: ParameterTable = {
    "method": ("pfmy-pdas", "S-solver: 'pfmy-pdas' (PFMY path + PDAS restoration) or 'vinewtonrsls' (PETSc SNES VI)"),
    "rho0": (1.0, "first Moreau-Yosida parameter on a cold start"),
    "rho0_warm": (1e-2, "first Moreau-Yosida parameter on a warm start"),
    "rho_min": (1e-6, "last Moreau-Yosida parameter"),
    "rho_factor": (10.0, "rho is divided by this factor along the path"),
    "pdas_max_iterations": (100, "maximum number of PDAS iterations"),
    "pdas_c": (1.0, "PDAS constant, in units of the stiffness diagonal"),
}

METHODS = ("pfmy-pdas", "vinewtonrsls")


def rho_path(rho0: float, rho_min: float, factor: float) -> list[float]:
    """rho0, rho0/factor, ... while above rho_min, then rho_min itself (the path always ends there)."""
    rhos = [rho0]
    while rhos[-1] / factor >= rho_min * (1 - 1e-12):
        rhos.append(rhos[-1] / factor)
    if rhos[-1] > rho_min * (1 + 1e-12):
        rhos.append(rho_min)
    return rhos


@dataclasses.dataclass
class ObstacleResult:
    """Iteration counts of one evaluation of S, by stage."""

    pfmy_iterations: int = 0
    pdas_iterations: int = 0
    vi_iterations: int = 0
    active_nodes: int = 0
    converged: bool = True


def _check(params: dict[str, typing.Any]) -> None:
    require(params["method"] in METHODS, "method", f"unknown S-solver {params['method']!r}; known: {', '.join(METHODS)}")
    for name in ("rho0", "rho0_warm", "rho_min"):
        require_positive(name, params[name])
    require(params["rho_factor"] > 1, "rho_factor", f"must be > 1, got {params['rho_factor']!r}")
    require(params["rho_min"] < params["rho0"], "rho_min", f"must be < rho0 = {params['rho0']!r}, got {params['rho_min']!r}")
    require(
        params["rho_min"] <= params["rho0_warm"],
        "rho_min",
        f"must be <= rho0_warm = {params['rho0_warm']!r}, got {params['rho_min']!r}",
    )
    require(params["pdas_max_iterations"] >= 1, "pdas_max_iterations", "must be >= 1")


def check_obstacle_parameters(overrides: dict | None) -> dict[str, typing.Any]:
    """:data:`OBSTACLE_PARAMETERS` with ``overrides``, checked; a ParameterError names a bad one."""
    params = merge_parameters(OBSTACLE_PARAMETERS, overrides)
    _check(params)
    return params


class ObstacleSolver:
    """Evaluate S: solve the obstacle problem for the current obstacle/source of ``problem``.

    Args:
        problem: the obstacle problem (its ``u`` is initial guess and result).
        parameters: overrides of :data:`OBSTACLE_PARAMETERS`.
        prefix: options prefix; stages use ``<prefix>pfmy_``, ``<prefix>pdas_``, ``<prefix>vi_``.
    """

    def __init__(self, problem: ObstacleProblem, parameters: dict | None = None, prefix: str = "obstacle_"):
        self.params = check_obstacle_parameters(parameters)
        self.problem = problem
        self.warm = False
        if self.params["method"] == "pfmy-pdas":
            self.pfmy = PathFollowingMoreauYosida(problem, prefix + "pfmy_")
            self.pdas = PrimalDualActiveSet(problem, self.params["pdas_max_iterations"], self.params["pdas_c"], prefix + "pdas_")
        else:
            self.vi = SNESVariationalInequality(problem, prefix + "vi_")

    def solve(self, warm_start: bool | None = None) -> ObstacleResult:
        """Solve from ``problem.u`` (warm start, the default after the first solve) or from 0."""
        p, prm = self.problem, self.params
        p.check_feasible_set()
        warm = self.warm if warm_start is None else warm_start
        if not warm:
            p.u.x.array[:] = p.boundary_values.x.array
        result = ObstacleResult()
        if prm["method"] == "pfmy-pdas":
            rhos = rho_path(prm["rho0_warm"] if warm else prm["rho0"], prm["rho_min"], prm["rho_factor"])
            pfmy = self.pfmy.solve(rhos)
            pdas = self.pdas.solve()
            result.pfmy_iterations, result.pdas_iterations = pfmy.iterations, pdas.iterations
            # PDAS decides: a PFMY path that stopped early only costs PDAS iterations.
            result.converged = pdas.converged
        else:
            vi = self.vi.solve()
            result.vi_iterations, result.converged = vi.iterations, vi.converged
        n = p.n_owned
        active = p.free & (p.u.x.array[:n] >= p.obstacle.x.array[:n])
        result.active_nodes = p.comm.allreduce(int(active.sum()))
        self.warm = True
        return result

    def destroy(self) -> None:
        for stage in ("pfmy", "pdas", "vi"):
            if hasattr(self, stage):
                getattr(self, stage).destroy()
