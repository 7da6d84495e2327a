"""Obstacle problems: PFMY path following, PDAS feasibility restoration, SNES VI (seed 003, E2)."""

from contactqvi.vi.moreau_yosida import PathFollowingMoreauYosida, PFMYResult, huber, huber_derivative
from contactqvi.vi.nonlinear import NonlinearFormProblem, snes_converged_reason
from contactqvi.vi.pdas import PDASResult, PrimalDualActiveSet
from contactqvi.vi.problem import ObstacleProblem
from contactqvi.vi.snes_vi import SNESVariationalInequality, SNESVIResult
from contactqvi.vi.solver import OBSTACLE_PARAMETERS, ObstacleResult, ObstacleSolver, rho_path

__all__ = [
    "OBSTACLE_PARAMETERS",
    "NonlinearFormProblem",
    "ObstacleProblem",
    "ObstacleResult",
    "ObstacleSolver",
    "PDASResult",
    "PFMYResult",
    "PathFollowingMoreauYosida",
    "PrimalDualActiveSet",
    "SNESVIResult",
    "SNESVariationalInequality",
    "huber",
    "huber_derivative",
    "rho_path",
    "snes_converged_reason",
]
