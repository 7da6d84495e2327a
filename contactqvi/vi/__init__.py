"""Obstacle problems: PFMY path following, PDAS feasibility restoration, SNES VI (seed 003, E2)."""

from contactqvi.vi.moreau_yosida import PathFollowingMoreauYosida, PFMYResult, huber, huber_derivative
from contactqvi.vi.nonlinear import AffineProblem, NonlinearFormProblem, snes_converged_reason, snes_status
from contactqvi.vi.pdas import ObstacleActiveSetSolver, PDASResult
from contactqvi.vi.problem import ObstacleProblem
from contactqvi.vi.snes_vi import ObstacleSNESVI, SNESVariationalInequality, SNESVIResult
from contactqvi.vi.solver import OBSTACLE_PARAMETERS, ObstacleResult, ObstacleSolver, rho_path

__all__ = [
    "OBSTACLE_PARAMETERS",
    "AffineProblem",
    "NonlinearFormProblem",
    "ObstacleActiveSetSolver",
    "ObstacleProblem",
    "ObstacleResult",
    "ObstacleSNESVI",
    "ObstacleSolver",
    "PDASResult",
    "PFMYResult",
    "PathFollowingMoreauYosida",
    "SNESVIResult",
    "SNESVariationalInequality",
    "huber",
    "huber_derivative",
    "rho_path",
    "snes_converged_reason",
    "snes_status",
]
