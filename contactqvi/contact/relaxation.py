"""Viscous relaxation past a limit point of a quasi-static load path (docs/finite_strain.md Sect. 15).

A frictional quasi-static path can end at a limit point: beyond it no equilibrium lies near the
last one, a part of the body has to snap, and neither a Newton globalisation nor smaller steps get
past it (the seal strip of docs/finite_strain.md Sect. 11 ends at 25.99 % squeeze; a dynamic run of
it snaps at 26.0 %). The physical path goes on through motion. Where a hyperelastic step has stalled,
or failed with its cuts used up, :func:`relax` follows the overdamped (gradient-flow) motion of the body
instead, at the step's loads and obstacle positions: the implicit Euler steps

    0 in r(u_{k+1}) + c_k M (u_{k+1} - u_k) + Q(u_{k+1}),                                       (15.1)

M = (E u, v) the mass matrix of a density equal to each body's Young's modulus (so that c M is in
proportion to each body's stiffness, a steel base's as a rubber strip's; zero at the prescribed
dofs), friction on the slip increment from u_k (each step a part of the load step at its full
load, recorded in the path's state as a cut step's part is). This is the proximal-point iteration
of the step's incremental problem (Rockafellar, SIAM J. Control Optim. 14 (1976) 877): for a large
c_k each step is a small move that Newton's method follows, and its fixed points (u_{k+1} = u_k)
are the equilibria of the step.
c_0 is the ratio of the diagonals of the small-strain stiffness and of M, so that the first step
is a strongly damped one; after each step that converges c_k is halved, after each that fails it
is multiplied by 4 (the switched evolution relaxation of pseudo-transient continuation, Kelley
and Keyes, SIAM J. Numer. Anal. 35 (1998) 508). A relaxation step is a point of the flow, not an
equilibrium: it is solved to 1e-6 of its start, and given up (c too small) when ||y^|| has not fallen by
a quarter over 8 Newton steps (:data:`STEP_PARAMETERS`). A step after one that converged starts from the
extrapolation u_k + (u_k - u_{k-1}) of the flow, any other from u_k (pairs searched ``"newton"``:
each step from u_k, by their own predictor; docs/finite_strain.md
Sect. 15: the seal strips on the 1.0 and 0.5 mm meshes took 1 898 and 2 570 Newton steps in all,
1 953 and 2 954 from u_k). Once a step changes the displacement by at most :data:`SETTLED` of the
largest change of the relaxation, the step is solved again without the viscous term (c = 0) from there: its
solution, an equilibrium of the quasi-static problem with the slip measured from the relaxed
configuration, ends the load step; if that solve fails, the relaxation goes on until the change
has fallen by another factor :data:`SETTLED`. The viscous forces do work on the relaxation path
only: the equilibrium that ends the step carries none of them.
"""

from __future__ import annotations

import dataclasses
import logging
import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

from contactqvi.contact.dynamics import InertialSystem, global_mass_matrix
from contactqvi.contact.path_state import PathState
from contactqvi.contact.problem import ContactProblem
from contactqvi.contact.scd_newton import SCDNewtonResult
from contactqvi.load_steps import LoadStep
from contactqvi.result import Status

__all__ = ["MAX_STEPS", "SETTLED", "STEP_PARAMETERS", "relax"]

logger = logging.getLogger(__name__)

#: Relaxation steps (15.1), converged or not, before the load step fails (60 before the steps took
#: :data:`STEP_PARAMETERS`; the 0.25 mm seal at nu 0.45, mu 0.3 then took all 60, now 69: Sect. 15).
MAX_STEPS = 100
#: A relaxation step that changes the displacement by at most this fraction of the relaxation's
#: largest change (max norms; after a plain solve that failed, of that step's change) has settled:
#: the step is solved again without the viscous term.
SETTLED = 0.1
#: c_k after a converged relaxation step is c_{k-1} / GROWTH; after a failed one, c_{k-1} * 4.
GROWTH = 2.0
#: The SCD parameters of a relaxation step (the last, plain solve takes the path's): a step of the
#: flow is no equilibrium, so it is solved to 1e-6 of its start, and it has failed (c too small: the
#: damped step's problem lost its definiteness at the snap) once ||y^|| has not fallen by a quarter
#: over 8 Newton steps (docs/finite_strain.md Sect. 15, session 48).
STEP_PARAMETERS = {"rtol": 1e-6, "stall_iterations": 8, "stall_factor": 0.75}


class Solve(typing.Protocol):
    """Solves a step after ``state`` into ``u`` (the load path's step solver), its predictor the
    last solve's increment extrapolated by ``extrapolate`` where that is > 0, with the SCD
    parameters ``overrides`` for this solve alone."""

    def __call__(self, step: LoadStep, u: PETSc.Vec, state: PathState, from_rest: bool,
                 extrapolate: float = 0.0, overrides: dict[str, typing.Any] | None = None) -> SCDNewtonResult: ...


def relax(problem: ContactProblem, step: LoadStep, u: PETSc.Vec, state: PathState,
          solve: Solve) -> list[tuple[LoadStep, SCDNewtonResult, dict[str, typing.Any]]]:
    """Relax ``problem`` (a hyperelastic body) at ``step`` from ``state`` (the last converged solve,
    advanced in place by each converged relaxation step) and solve the step there
    (module docstring) by ``solve``.
    Returns each solve with its step and a mark (``relaxation``: the step k, ``viscosity``: c_k in
    1/m^2, 0 for the last, plain solve); the last one's solution is in ``u``, and ``state`` is not
    advanced by it. Collective."""
    static, density = problem.hyperelastic, problem.body.young  # M's density: each body's Young's modulus
    mass, _ = global_mass_matrix(problem, density)
    inertia = static.internal.duplicate()
    viscous = InertialSystem(**{f.name: getattr(static, f.name) for f in dataclasses.fields(static)}, mass=mass,
                             coefficient=_initial_coefficient(problem, mass), inertia=inertia,
                             work=inertia.duplicate(), density=density)
    solves, largest, settled, before = [], 0.0, np.inf, state.displacement.x.array.copy()
    moving = False  # whether the last relaxation step converged: the next starts from its extrapolation
    try:
        for k in range(MAX_STEPS):
            problem.hyperelastic = viscous
            mass.mult(state.displacement.x.petsc_vec, inertia)
            inertia.scale(-viscous.coefficient)
            result = solve(step, u, state, False, extrapolate=1.0 if moving else 0.0, overrides=STEP_PARAMETERS)
            solves.append((step, result, {"relaxation": k + 1, "viscosity": viscous.coefficient}))
            if result.status == Status.INTERRUPTED:
                break
            moving = result.converged
            if not result.converged:
                viscous.coefficient *= 4.0
                continue
            state.record(problem, u, result, complete=False)
            change = _largest(problem.comm, state.displacement.x.array - before)
            before[:] = state.displacement.x.array
            largest = max(largest, change)
            logger.info("relaxation step %d (c = %.3g 1/m^2): %d Newton steps, the displacement changed by %.3g m",
                        k + 1, viscous.coefficient, result.iterations, change)
            viscous.coefficient /= GROWTH
            if change <= SETTLED * min(largest, settled):
                problem.hyperelastic = static
                result = solve(step, u, state, False)
                solves.append((step, result, {"relaxation": k + 1, "viscosity": 0.0}))
                if result.converged or result.status == Status.INTERRUPTED:
                    break
                settled = change
    finally:
        problem.hyperelastic = static
        for obj in (mass, viscous.inertia, viscous.work):
            obj.destroy()
    return solves


def _initial_coefficient(problem: ContactProblem, mass: PETSc.Mat) -> float:
    """c_0 of (15.1): the mean diagonal of the small-strain stiffness A over that of ``mass``, on
    the dofs that have mass (1/m^2). Collective."""
    stiffness, inertia = problem.A.getDiagonal(), mass.getDiagonal()
    free = inertia.array > 0.0
    sums = problem.comm.allreduce(np.array([stiffness.array[free].sum(), inertia.array[free].sum()]), op=MPI.SUM)
    for vector in (stiffness, inertia):
        vector.destroy()
    return float(sums[0] / sums[1])


def _largest(comm: MPI.Comm, values: np.ndarray) -> float:
    """max |values| over all ranks."""
    return comm.allreduce(float(np.abs(values).max(initial=0.0)), op=MPI.MAX)
