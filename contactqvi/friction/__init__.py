"""Stadler's simplified (scalar Tresca) friction problem (seed 002): PDAS, SS, ALM, Uzawa."""

from contactqvi.friction.alm import INNER_SOLVES, SCHEDULES, ALMResult, augmented_lagrangian
from contactqvi.friction.pdas import ActiveSetResult, FrictionActiveSetSolver, semismooth_newton_sigma
from contactqvi.friction.problem import FrictionProblem, boundary_states, complementarity_residual
from contactqvi.friction.uzawa import UzawaResult, UzawaSolver

__all__ = [
    "INNER_SOLVES",
    "SCHEDULES",
    "ALMResult",
    "ActiveSetResult",
    "FrictionActiveSetSolver",
    "FrictionProblem",
    "UzawaResult",
    "UzawaSolver",
    "augmented_lagrangian",
    "boundary_states",
    "complementarity_residual",
    "semismooth_newton_sigma",
]
