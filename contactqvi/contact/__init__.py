"""Contact of an elastic body with a rigid foundation: Coulomb friction by the SCD
semismooth* Newton method (seed 000), and its Tresca variant."""

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
from contactqvi.contact.scd_newton import KSP_PRESETS, PARAMETERS, SCDNewtonResult, SCDNewtonSolver

__all__ = [
    "KSP_PRESETS",
    "PARAMETERS",
    "ContactProblem",
    "FrictionLaw",
    "Normal",
    "SCDNewtonResult",
    "SCDNewtonSolver",
    "State",
    "Tangential",
    "build_contact_problem",
    "classify",
    "contact_states",
    "lipschitz_constant",
    "resolvent",
    "scd_adjoint_blocks",
]
