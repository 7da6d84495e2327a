"""Stadler's simplified (scalar Tresca) friction problem (seed 002): PDAS, SS, ALM, Uzawa."""

from contactqvi.friction.pdas import ActiveSetResult, PrimalDualActiveSet, semismooth_newton_sigma
from contactqvi.friction.problem import FrictionProblem, boundary_states, complementarity_residual

__all__ = [
    "ActiveSetResult",
    "FrictionProblem",
    "PrimalDualActiveSet",
    "boundary_states",
    "complementarity_residual",
    "semismooth_newton_sigma",
]
