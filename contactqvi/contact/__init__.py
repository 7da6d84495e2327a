"""Contact of an elastic body with a rigid obstacle: Coulomb friction by the SCD
semismooth* Newton method (seed 000), its Tresca variant, and quasi-static load paths."""

from contactqvi.contact.load_path import LoadStep, contact_resultants, solve_load_path
from contactqvi.contact.nodal import (
    FrictionLaw,
    Normal,
    State,
    Tangential,
    classify,
    contact_states,
    lipschitz_constant,
    resolvent,
    scd_adjoint_blocks,
)
from contactqvi.contact.problem import ContactProblem, build_contact_problem
from contactqvi.contact.scd_newton import NEWTON_STEP_SOLVERS, PARAMETERS, SCDNewtonResult, SCDNewtonSolver

__all__ = [
    "NEWTON_STEP_SOLVERS",
    "PARAMETERS",
    "ContactProblem",
    "FrictionLaw",
    "LoadStep",
    "Normal",
    "SCDNewtonResult",
    "SCDNewtonSolver",
    "State",
    "Tangential",
    "build_contact_problem",
    "classify",
    "contact_resultants",
    "contact_states",
    "lipschitz_constant",
    "resolvent",
    "scd_adjoint_blocks",
    "solve_load_path",
]
