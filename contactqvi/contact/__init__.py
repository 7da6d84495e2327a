"""Contact of elastic bodies with rigid obstacles and with each other: Coulomb friction
by the SCD semismooth* Newton method (seed 000), for any contact law of
:mod:`contactqvi.laws`, mortar coupling of non-matching surfaces, and quasi-static load paths."""

from contactqvi.contact.interface import BodyPair, Interface, ObstaclePair
from contactqvi.contact.load_path import LoadStep, Rotation, contact_resultants, solve_load_path
from contactqvi.contact.mortar import MortarCoupling, mortar_coupling
from contactqvi.contact.newton_step_solver import NEWTON_STEP_SOLVERS, NewtonStepSolver
from contactqvi.contact.path_state import PathState
from contactqvi.contact.nodal import (
    Normal,
    State,
    Tangential,
    classify,
    contact_states,
    lipschitz_constant,
    resolvent,
    scd_adjoint_blocks,
)
from contactqvi.contact.problem import ContactProblem, assemble_contact_problem, build_contact_problem
from contactqvi.contact.scd_newton import PARAMETERS, SCDNewtonResult, SCDNewtonSolver

__all__ = [
    "NEWTON_STEP_SOLVERS",
    "PARAMETERS",
    "BodyPair",
    "ContactProblem",
    "Interface",
    "LoadStep",
    "MortarCoupling",
    "NewtonStepSolver",
    "Normal",
    "ObstaclePair",
    "PathState",
    "Rotation",
    "SCDNewtonResult",
    "SCDNewtonSolver",
    "State",
    "Tangential",
    "assemble_contact_problem",
    "build_contact_problem",
    "classify",
    "contact_resultants",
    "contact_states",
    "lipschitz_constant",
    "mortar_coupling",
    "resolvent",
    "scd_adjoint_blocks",
    "solve_load_path",
]
