"""Contact of an elastic body with a rigid foundation: Coulomb friction by the SCD
semismooth* Newton method (seed 000)."""

from contactqvi.contact.nodal import State, classify, lipschitz_constant, resolvent, scd_adjoint_blocks
from contactqvi.contact.problem import ContactProblem, build_contact_problem
from contactqvi.contact.scd_newton import KSP_PRESETS, PARAMETERS, SCDNewtonResult, SCDNewtonSolver

__all__ = [
    "KSP_PRESETS",
    "PARAMETERS",
    "ContactProblem",
    "SCDNewtonResult",
    "SCDNewtonSolver",
    "State",
    "build_contact_problem",
    "classify",
    "lipschitz_constant",
    "resolvent",
    "scd_adjoint_blocks",
]
