"""Stadler's simplified (scalar Tresca) friction problem (seed 002): PDAS, SS, ALM, Uzawa."""

from contactqvi.friction.alm import INNER_SOLVES, SCHEDULES, ALMResult, augmented_lagrangian
from contactqvi.friction.build import DISCRETISATIONS, GRID_PARAMETERS, create_problem
from contactqvi.friction.finite_differences import PaperFiniteDifferences
from contactqvi.friction.pdas import ActiveSetResult, FrictionActiveSetSolver, semismooth_newton_sigma
from contactqvi.friction.problem import FrictionData, FrictionProblem, boundary_states, complementarity_residual
from contactqvi.friction.uzawa import UzawaResult, UzawaSolver

__all__ = [
    "DISCRETISATIONS",
    "GRID_PARAMETERS",
    "INNER_SOLVES",
    "SCHEDULES",
    "ALMResult",
    "ActiveSetResult",
    "FrictionActiveSetSolver",
    "FrictionData",
    "FrictionProblem",
    "PaperFiniteDifferences",
    "UzawaResult",
    "UzawaSolver",
    "augmented_lagrangian",
    "boundary_states",
    "complementarity_residual",
    "create_problem",
    "semismooth_newton_sigma",
]
