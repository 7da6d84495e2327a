"""Build-and-solve on the body Omega(d) at one level, optionally nested (Table 3)."""

from __future__ import annotations

import dataclasses
import logging
import time
import typing

from mpi4py import MPI
from petsc4py import PETSc

from dolfinx import fem

from contactqvi.contact.load_path import LoadStep, solve_load_path
from contactqvi.contact.problem import ContactProblem, build_contact_problem
from contactqvi.contact.scd_newton import SCDNewtonResult
from contactqvi.laws import ContactLaw
from contactqvi.lifetime import PETScOwner
from contactqvi.meshes import GapFunction, create_contact_body
from contactqvi.transfer import interpolate_nonmatching

__all__ = ["LevelSolution", "solve_level", "solve_nested"]

logger = logging.getLogger(__name__)


@dataclasses.dataclass
class LevelSolution(PETScOwner):
    """Problem, shifted solution u = u~ + d and solver result of one level."""

    lev: int
    problem: ContactProblem
    u: PETSc.Vec
    result: SCDNewtonResult

    def physical_displacement(self) -> fem.Function:
        return self.problem.physical_displacement(self.u, fem.Function(self.problem.V, name="displacement"))

    def petsc_objects(self) -> list[typing.Any]:
        """The problem and u."""
        return [self.problem, self.u]


def solve_level(
    comm: MPI.Comm,
    lev: int,
    gap: GapFunction,
    tractions: dict[str, tuple[float, float, float]],
    young: float,
    poisson: float,
    law: ContactLaw,
    parameters: dict[str, typing.Any] | None = None,
    initial: fem.Function | None = None,
    prefix: str = "coulomb_",
) -> LevelSolution:
    """Mesh Omega(d) at ``lev``, assemble the GE (6.3) and solve it by SCD Newton.

    Args:
        law: the contact law on the bottom surface, e.g. ``Coulomb(friction=0.23)``.
        initial: physical displacement on another mesh of the body to start from
            (interpolated; Table 3); None starts from u0 = 0.
        parameters: :data:`~contactqvi.contact.scd_newton.PARAMETERS` overrides.
    """
    t0 = time.perf_counter()
    msh, facet_tags = create_contact_body(comm, lev, gap)
    problem = build_contact_problem(msh, facet_tags, young, poisson, tractions, law)
    u = problem.A.createVecRight()
    if initial is not None:
        # Bottom nodes of a curved d lie up to O(h^2) outside the coarse mesh: nearest cell within 5 cm.
        start = interpolate_nonmatching(initial, problem.V, padding=0.05)  # keep alive: its petsc_vec wraps its memory
        problem.shift.copy(u)
        u.axpy(1.0, start.x.petsc_vec)
    assembly = time.perf_counter() - t0
    logger.info("lev %d: p = %d contact nodes, n = %d free dofs, %d ranks", lev, problem.n_contact, problem.n_free, comm.size)
    (result,) = solve_load_path(problem, [LoadStep()], u, parameters, prefix=prefix)
    result.timings["assembly"] = assembly
    logger.info(
        "lev %d: %s after %d Newton steps, %d Krylov iterations, gamma = %.4e",
        lev, result.status, result.iterations, result.inner_iterations, result.gamma,
    )
    return LevelSolution(lev, problem, u, result)


def solve_nested(comm: MPI.Comm, levels: typing.Iterable[int], **kwargs) -> list[LevelSolution]:
    """Solve on each level in turn, starting each from the previous level's solution.

    The first level starts from u0 = 0. Stops at the first level that does not
    converge (its solution is the last in the list).
    """
    solutions: list[LevelSolution] = []
    for lev in levels:
        initial = solutions[-1].physical_displacement() if solutions else None
        solutions.append(solve_level(comm, lev, initial=initial, **kwargs))
        if not solutions[-1].result.converged:
            break
    return solutions
