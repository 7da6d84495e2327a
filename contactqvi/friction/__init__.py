"""Stadler's simplified (scalar Tresca) friction problem (seed 002): PDAS, SS, ALM, Uzawa."""

from contactqvi.friction.alm import INNER_SOLVES, ALMResult, augmented_lagrangian
from contactqvi.friction.pdas import ActiveSetResult, PrimalDualActiveSet, semismooth_newton_sigma
from contactqvi.friction.problem import FrictionProblem, boundary_states, complementarity_residual
from contactqvi.friction.uzawa import UzawaResult, uzawa

__all__ = [
    "INNER_SOLVES",
    "ALMResult",
    "ActiveSetResult",
    "FrictionProblem",
    "PrimalDualActiveSet",
    "UzawaResult",
    "augmented_lagrangian",
    "boundary_states",
    "complementarity_residual",
    "semismooth_newton_sigma",
    "uzawa",
]
