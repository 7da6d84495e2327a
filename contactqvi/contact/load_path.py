"""Quasi-static load paths: a sequence of static contact problems of the seed-000 type.

Seed 000, Sect. 1, treats the static problem as one step of the quasi-static one.
Step k scales tractions and body force by its load factor and moves the obstacles and
the moved groups rigidly to x = Q_k (X - c) + c + t_k (its translation t_k and, optionally,
its rotation Q_k about a centre c fixed for the path, :class:`~contactqvi.load_steps.Rotation`;
a rotated obstacle's pair is searched each step); friction acts on the slip increment since
step k - 1 relative to the obstacle's surface, whose material point at a node's closest
point moved by t_k - t_{k-1} plus the rotation's chord
(:meth:`~contactqvi.contact.problem.ContactProblem.set_step`). Each step is solved
by the SCD semismooth* Newton method from the previous step's solution, with the
nodes that touched the obstacle moved along with it (no slip increment); the
first step starts from the given guess, or a load path continues after the steps
of a checkpoint (:mod:`contactqvi.contact.checkpoint`). All that a step reads from
the steps before is one :class:`~contactqvi.contact.path_state.PathState`, updated
after each converged step and checkpointed whole, so a restarted path is the
uninterrupted one.

Body pairs searched each step are found again before every step after the first,
in the configuration the step before ended in
(:meth:`~contactqvi.contact.problem.ContactProblem.search`): the change of variables
u = T_k w is new, the slip is measured from T_k^-1 of the last displacement, and the
contact states are carried over node by node (a node new to the contact starts as
not in contact). The SCD solver is rebuilt for the new contact nodes; a multigrid
Newton-step solver is set up once per load path and kept, its levels updated for the
searched A (:func:`_path_levels`).

A search before a step uses the configuration of the step before, so the contact
geometry of a step lags by one step. Pairs with ``search = "until_settled"`` remove the
lag (:func:`_settle`): after a step converged, the pairs are searched again in the
configuration it reached and the step is solved again from there, the slip still
measured from the step before, until a solve changes the displacement by at most
``geometry_tol`` times the step's increment (:data:`PATH_PARAMETERS`; Code_Aster's
geometric loop, ``REAC_GEOM = 'AUTOMATIQUE'`` with ``RESI_GEOM``, tested on the
displacement). The loop is the fixed-point iteration c <- u(c) on the configuration c
searched in; where a solve changes the displacement no less than the one before (the
iteration does not contract: nodes at the edge of a master surface flip between facets,
docs/ironing.md), each later search moves only part of the way, c <- c + omega (u(c) - c),
omega halved at every such solve, which has the same fixed point.

A step that does not converge (and was not interrupted) is cut: its first half, from the
last converged state (:class:`~contactqvi.contact.path_state.PathState`), is solved
instead, halved again if that fails too, up to ``max_cuts`` halvings in a row
(:data:`PATH_PARAMETERS`; by default only for hyperelastic bodies); after each part that
converges the next one is twice as large, up to the rest of the step. The step's result
holds all its parts and attempts (history entries marked ``substep``, ``substep_load``,
``substep_translation``, ``substep_status``); the path stops when the cuts are used up.
A path that relaxes past limit points (``limit_points``) relaxes there instead
(:mod:`~contactqvi.contact.relaxation`), and at once where a solve stalls (its residual at a
stationary point of the merit function short of a solution, as at a limit point): cuts that
bracket a limit point fail again and again, each after the whole stall window (the seal strip of
docs/finite_strain.md Sect. 15 spent 130-180 Newton steps in 6-8 failed parts before it relaxed).
"""

from __future__ import annotations

import dataclasses
import logging
import math
import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

from dolfinx import fem

from contactqvi.contact.convection import convected, sliding_translation
from contactqvi.contact.newton_step_solver import NEWTON_STEP_SOLVERS, NewtonStepSolver
from contactqvi.contact.nodal import TOUCHING
from contactqvi.contact.path_state import PathState
from contactqvi.contact.problem import ContactProblem
from contactqvi.contact.relaxation import relax
from contactqvi.contact.scd_newton import (PARAMETERS, SCDNewtonResult, SCDNewtonSolver, checked_parameters,
                                            newton_step_solver)
from contactqvi.lifetime import PETScOwner
from contactqvi.linalg import create_ksp, ksp_converged_reason, preset
from contactqvi.contact.surface import contact_facet_areas
from contactqvi.load_steps import LoadStep, Rotation, check_steps, interpolated
from contactqvi.parameters import Parameter, Parameters, require
from contactqvi.records import warn
from contactqvi.result import Status, Timings

__all__ = ["PATH_PARAMETERS", "SOLVER_PARAMETERS", "LoadStep", "PathState", "Rotation", "check_steps",
           "contact_resultants", "solve_load_path", "step_position"]

logger = logging.getLogger(__name__)

StepCallback = typing.Callable[[int, LoadStep, PETSc.Vec, SCDNewtonResult, PathState], None]

#: ``max_cuts`` of a hyperelastic body when not given (Code_Aster's SUBD_NIVEAU counts alike).
HYPERELASTIC_CUTS = 4
#: Relative residual of the linear solve of the elastic predictor (:func:`_elastic_change`).
PREDICTOR_RTOL = 1e-8
#: A gap at rest of at most this times the largest coordinate touches (:func:`_elastic_change`): a gap
#: is a difference of positions, resolved to a few eps of their size (a block on a plane through its
#: bottom: -6e-17 ... 2.3e-17 m, each rank's last node negative; with ``gap <= 0`` the held nodes were
#: as many as the ranks, and half the block's height in one step took 6 Newton steps on 1 and 2
#: ranks, 9 on 3, 7 on 4).
GAP_ROUNDOFF = 1e-12
#: The step of the central difference of r_K along the change of the prescribed values, relative
#: to it (:func:`_tangent_change`).
FINITE_DIFFERENCE = 1e-6
#: What ``limit_points`` may ask for.
LIMIT_POINTS = ("relax", "stop")
#: ``stall_iterations`` of a path that relaxes past limit points: its failed attempts end there
#: (at a limit point ||y^|| stays within 10 % for the rest of the 100 Newton steps, Sect. 15).
RELAXING_STALL = 20
#: The load path's own parameters, given with the SCD solver's (``[solver]`` of a case file).
PATH_PARAMETERS = Parameters(
    geometry_tol=Parameter(1e-3, "search = until_settled: a step has settled when a solve after a search changes the "
                           "displacement by at most this times the step's increment (max norms)",
                           minimum=0.0, maximum=1.0),
    max_searches=Parameter(10, "search = until_settled: searches in a step's own configuration before the step "
                           "fails (diverged_max_it)", type=int, minimum=1),
    max_cuts=Parameter(None, "a load step that does not converge is cut in half and retried from the last "
                       "converged state, at most this many halvings in a row (the step grows back after each "
                       f"success); None: {HYPERELASTIC_CUTS} for a hyperelastic body, 0 for linear elasticity",
                       type=int, minimum=0, optional=True),
    limit_points=Parameter(None, "a hyperelastic load step that stalls, or fails with its cuts used up (the path's "
                           "end at a limit point, where a part has to snap): 'relax' follows the body's overdamped "
                           "motion at the step's loads to an equilibrium and goes on from there "
                           "(docs/finite_strain.md Sect. 15), 'stop' ends the path; None: 'relax' for a hyperelastic "
                           "body whose pairs are searched once, every step or inside the Newton iteration ('newton'), "
                           "'stop' otherwise", type=str,
                           choices=LIMIT_POINTS, optional=True),
)
#: A step whose displacement increment is below this fraction of the displacement has not
#: moved (round-off): its configuration is the settled one of the step before.
STILL = 1e-9
#: :func:`_turned_on`: the last solution turned on rigidly meets the step's prescribed values to this
#: fraction of the largest of them and of the positions (round-off of the turn), or is not taken.
TURNED_WHOLE = 1e-9
#: Everything the ``[solver]`` table of a case file may hold: the SCD solver's parameters and the path's.
SOLVER_PARAMETERS = Parameters({**PARAMETERS, **PATH_PARAMETERS})


def solve_load_path(
    problem: ContactProblem,
    steps: typing.Sequence[LoadStep],
    u: PETSc.Vec,
    parameters: dict[str, typing.Any] | None = None,
    prefix: str = "coulomb_",
    on_step: StepCallback | None = None,
    from_rest: bool = False,
    state: PathState | None = None,
    stop: typing.Callable[[], bool] | None = None,
) -> list[SCDNewtonResult]:
    """Solve the steps in turn with one SCD Newton solver (one per step when the problem is
    searched each step); a step that does not converge is cut (module docstring); stop at
    the first that fails with its cuts used up.

    Args:
        problem, steps: the contact problem (its step is set here) and the load path.
        u: initial guess of the first step (shifted displacements); holds the last
            step's solution on return.
        parameters, prefix: SCD Newton parameters and the path's (:data:`SOLVER_PARAMETERS`),
            PETSc options prefix of the Newton-step KSP.
        on_step: called after each step with (index, step, u, result, state), e.g. to write
            output and checkpoints (``state``: after the last converged step).
        from_rest: start the first step from the body at rest (u~ = 0) instead of ``u``.
        state: the path's state to continue from, after its ``state.done`` steps (a
            checkpoint's; ``u`` is then ignored), updated in place as steps converge
            (owned by the caller); None: from step 1.
        stop: asked before each Newton step (collective); true ends the step as ``interrupted``.

    Every later step stops at the first step's target ||y^|| (``atol`` of ``solve``) if its
    own test asks for more: a small increment is not solved to ``rtol`` of its own small start.

    Returns the results of the steps solved (after ``state.done``); the last one failed if not converged.
    """
    check_steps(steps)
    parameters, path = _split(parameters)
    results: list[SCDNewtonResult] = []
    own, state = state is None, PathState.at_rest(problem) if state is None else state
    try:
        with _StepSolver(problem, parameters, prefix, path, stop, None if from_rest else u) as solve:
            index, cuts, attempts = state.done, 0, []
            while index < len(steps):
                step = _toward(state, steps[index], cuts)
                result = solve(step, u, state, from_rest)
                attempts.append((step, result, {}))
                cuts = _cuts_after(problem, u, state, index, step, result, cuts, solve)
                if cuts is not None:
                    continue
                result = _relaxed(problem, index, steps[index], u, state, solve, attempts)
                results.append(_cut(attempts, result.status) if len(attempts) > 1 else result)
                attempts, cuts = [], 0
                if on_step is not None:
                    on_step(index, steps[index], u, results[-1], state)
                if not result.converged:
                    break
                index += 1
    finally:
        if own:
            state.destroy()
    return results


def _cuts_after(problem: ContactProblem, u: PETSc.Vec, state: PathState, index: int, step: LoadStep,
                result: SCDNewtonResult, cuts: int, solve: _StepSolver) -> int | None:
    """Record a converged solve of (a part, after ``cuts`` halvings, of) step ``index`` in
    ``state``, and return the halvings of the next part: one fewer after a part that
    converged (0: the rest of the step), one more after a failure while ``solve`` allows
    (``cuts_allowed``); None when the step is done (solved whole, failed with its cuts used up,
    or interrupted), or when it stalled on a path that relaxes past limit points: a limit point is
    relaxed past at once, not bracketed by cuts (module docstring)."""
    if result.converged:
        state.record(problem, u, result, complete=cuts == 0)
        return cuts - 1 if cuts > 0 else None  # a part of the step: grow back toward its end
    if result.status == Status.INTERRUPTED or cuts >= solve.cuts_allowed:
        return None
    if result.status == Status.DIVERGED_STALLED and solve.relaxes:
        return None
    warn(problem.comm, logger, "step_cut", f"step {index + 1}: {result.status} at {step_position(step)}; cut to "
         f"{0.5 ** (cuts + 1):g} of what remains of it", step=index + 1, load=step.load, fraction=0.5 ** (cuts + 1))
    return cuts + 1


def _relaxed(problem: ContactProblem, index: int, step: LoadStep, u: PETSc.Vec, state: PathState,
             solve: _StepSolver, attempts: list) -> SCDNewtonResult:
    """The result of step ``index`` (``step``) after its ``attempts``: the last attempt's, unless it
    stalled or failed with the step's cuts used up and ``solve`` relaxes (``limit_points``); then the step is
    relaxed to an equilibrium after ``state`` (:func:`~contactqvi.contact.relaxation.relax`), its
    solves added to ``attempts`` and the equilibrium that ends it recorded in ``state``, and the
    result is the last solve's, ``diverged_max_it`` when the relaxation ended without one."""
    result = attempts[-1][1]
    if result.converged or result.status == Status.INTERRUPTED or not solve.relaxes:
        return result
    warn(problem.comm, logger, "relaxed", f"step {index + 1}: no equilibrium near the last one at "
         f"{step_position(step)} (the quasi-static path's end at a limit point, where a part has "
         "to snap): the body relaxes there by overdamped motion (docs/finite_strain.md Sect. 15)", step=index + 1)
    solves = relax(problem, step, u, state, solve)
    attempts.extend(solves)
    step, result, mark = solves[-1]
    if result.converged and mark["viscosity"] == 0.0:
        state.record(problem, u, result, complete=True)
        logger.info("step %d: relaxed in %d steps to an equilibrium", index + 1, mark["relaxation"])
        return result
    if result.status == Status.INTERRUPTED:
        return result
    warn(problem.comm, logger, "not_relaxed", f"step {index + 1}: the relaxation reached no equilibrium in "
         f"{mark['relaxation']} steps", step=index + 1, steps=mark["relaxation"])
    return dataclasses.replace(result, status=Status.DIVERGED_MAX_IT)


class _StepSolver(PETScOwner):
    """Solves the load steps of one path: the SCD solver (one per step when the problem is
    searched each step) and the multigrid levels it carries, the first step's initial
    guess for a retry (``initial``, copied; None: from rest), and the halvings a failed
    step may take (``cuts_allowed``, ``max_cuts`` of ``path`` or its default)."""

    def __init__(self, problem: ContactProblem, parameters: dict[str, typing.Any], prefix: str,
                 path: dict[str, typing.Any], stop: typing.Callable[[], bool] | None, initial: PETSc.Vec | None):
        self.problem, self.parameters, self.prefix, self.path, self.stop = problem, parameters, prefix, path, stop
        self.initial = None if initial is None else initial.copy()
        self.solver: SCDNewtonSolver | None = None
        self.carried = _path_levels(problem, parameters, prefix) if problem.searched_each_step else None
        default_cuts = HYPERELASTIC_CUTS if problem.hyperelastic is not None else 0
        self.cuts_allowed = path["max_cuts"] if path["max_cuts"] is not None else default_cuts
        relaxable = problem.hyperelastic is not None and not problem.settles_geometry
        limit_points = path["limit_points"] or ("relax" if relaxable else "stop")
        require(limit_points == "stop" or relaxable, "solver.limit_points",
                "'relax' takes a hyperelastic body whose pairs are searched once, every step or inside the Newton "
                "iteration ('newton'), not 'until_settled'")
        self.relaxes = limit_points == "relax"
        if self.relaxes and parameters.get("stall_iterations") is None:  # a failed attempt ends when it stalls
            self.parameters = {**parameters, "stall_iterations": RELAXING_STALL}

    def petsc_objects(self) -> list[typing.Any]:
        return [self.solver, self.carried, self.initial]

    def __call__(self, step: LoadStep, u: PETSc.Vec, state: PathState, from_rest: bool,
                 extrapolate: float = 0.0, overrides: dict[str, typing.Any] | None = None) -> SCDNewtonResult:
        """Solve ``step`` after ``state``'s (the predictor of :func:`_start`; a problem searched
        each step searched first, and settled after); its solution in ``u``. ``extrapolate`` > 0:
        the predictor is the last solve's increment extrapolated by that factor (a relaxation step
        after one that converged). ``overrides``: SCD parameters of this solve alone (a relaxation
        step's, :data:`~contactqvi.contact.relaxation.STEP_PARAMETERS`)."""
        if not overrides:
            return self._solve(step, u, state, from_rest, extrapolate)
        saved = self.parameters
        self.parameters = {**saved, **overrides}
        if self.solver is not None:
            self.solver.parameters.update(overrides)
        try:
            return self._solve(step, u, state, from_rest, extrapolate)
        finally:
            self.parameters = saved
            if self.solver is not None:  # the one the solve ended with (a search makes a new one)
                own = checked_parameters(self.problem, saved)
                self.solver.parameters.update({name: own[name] for name in overrides})

    def _solve(self, step: LoadStep, u: PETSc.Vec, state: PathState, from_rest: bool,
               extrapolate: float) -> SCDNewtonResult:
        """:meth:`__call__` with the path's own parameters."""
        problem = self.problem
        if problem.searched_each_step and self.solver is not None:
            self.carried, self.solver = _released(self.solver), None
        if state.solved == 0 and self.initial is not None:
            self.initial.copy(u)  # the given guess, also for a retry of the first step
        extrapolated = _start(problem, step, u, state, from_rest, self.carried, extrapolate)
        pc = checked_parameters(problem, self.parameters)["pc"]
        if problem.follows_geometry and (state.solved > 0 or from_rest):
            _predict(problem, step, u, state, self.carried, pc, self.prefix)
        elif from_rest and state.solved == 0 and problem.hyperelastic is not None:
            _add_elastic_change(problem, u, state, pc, self.prefix)
        if self.solver is None:
            self.solver = SCDNewtonSolver(problem, self.parameters, prefix=self.prefix, step_solver=self.carried)
            self.carried = None
        if problem.follows_geometry:
            self.solver, result = _follow(problem, step, u, state, self.solver, self.stop)
            return result
        result = self.solver.solve(u, atol=state.target, stop=self.stop, volume_start=_volume_start(state))
        if result.status == Status.DIVERGED_FUNCTION_DOMAIN and state.solved > 0 and problem.hyperelastic is not None:
            _carried(problem, u, state)
            if _add_elastic_change(problem, u, state, pc, self.prefix) or extrapolated:
                logger.info("the predictor inverts elements: the step starts again from the last solution%s",
                            "" if extrapolated else " and the tangent's response to the step's change there")
                result = self.solver.solve(u, atol=state.target, stop=self.stop, volume_start=_volume_start(state))
        self.solver, result = _settle(problem, step, u, state, self.solver, result, self.stop, self.path)
        return result


def _volume_start(state: PathState) -> fem.Function | None:
    """The displacement whose nodal volume ratios start a step's mixed Newton method: the last
    converged step's (in the checkpoint, so a restart starts alike), None before the first."""
    return state.displacement if state.solved > 0 else None


def _toward(state: PathState, step: LoadStep, cuts: int) -> LoadStep:
    """``step`` itself, or after ``cuts`` halvings the part 2^-cuts of the way to it from
    ``state`` (load factor, translation, rotation and fit interpolated)."""
    if cuts == 0:
        return step
    fraction = 0.5**cuts
    load = state.load + fraction * (step.load - state.load)
    translation = state.translation + fraction * (np.asarray(step.translation) - state.translation)
    fit = state.fit + fraction * (step.fit_fraction - state.fit)
    return LoadStep(load, tuple(float(t) for t in translation), interpolated(state.rotation, step.rotation, fraction),
                    fit)


def step_position(step: LoadStep) -> str:
    """A (part of a) load step in the log: load factor, translation and rotation to 7 significant
    digits, so that the parts of a step cut again and again stay apart."""
    text = (f"load factor {step.load:.7g}, translation of the obstacles and moved groups ("
            + ", ".join(f"{t:.7g}" for t in step.translation) + ") m")
    if step.rotation is not None:
        text += f", rotation {step.rotation.angle:.7g} degrees about {step.rotation.axis}"
    return text


def _cut(attempts: list[tuple[LoadStep, SCDNewtonResult, dict[str, typing.Any]]], status: Status) -> SCDNewtonResult:
    """One step's result of its parts and failed attempts (:func:`_merged`), each history entry
    marked with its ``substep``, that part's load factor, translation and its status (so a failed
    step tells how far its converged parts went), and a relaxation's marks."""
    marks = [{"substep": j, "substep_load": step.load, "substep_translation": list(step.translation),
              "substep_status": str(result.status), **mark} for j, (step, result, mark) in enumerate(attempts)]
    return _merged([result for _, result, _ in attempts], status, marks)


def _split(parameters: dict[str, typing.Any] | None) -> tuple[dict[str, typing.Any], dict[str, typing.Any]]:
    """The SCD solver's parameters and the path's (:data:`PATH_PARAMETERS`, checked) of ``parameters``."""
    given = dict(parameters or {})
    return given, PATH_PARAMETERS.check({name: given.pop(name) for name in PATH_PARAMETERS if name in given})


def _released(solver: SCDNewtonSolver) -> NewtonStepSolver | None:
    """Destroy ``solver`` before a search (which replaces the contact nodes and changes A) and
    return its Newton-step solver if that keeps multigrid levels (updated to A), else None."""
    step_solver = solver.release_step_solver()
    solver.destroy()
    return step_solver


def _path_levels(problem: ContactProblem, parameters: dict | None, prefix: str) -> NewtonStepSolver | None:
    """The Newton-step solver of a load path searched each step, if it keeps multigrid levels
    (:attr:`~contactqvi.contact.newton_step_solver.NewtonStepSolver.keeps_levels`), else None.

    Its levels are set up once, on A of the reference configuration, and then follow
    every Newton matrix and every search by Galerkin updates: a search changes A near
    the interfaces only, and a new set-up per step cost more than the updates
    (two-body Hertz, docs/bodies.md). A restart sets up on the same A, so it continues
    with the levels of the uninterrupted run (up to the round-off of the updates).
    """
    step_solver = newton_step_solver(problem, checked_parameters(problem, parameters), prefix)
    near_nullspace = problem.near_nullspace()
    problem.A.setNearNullSpace(near_nullspace)
    kept = step_solver.set_up_levels(problem.A)
    near_nullspace.destroy()
    if kept:
        return step_solver
    step_solver.destroy()
    return None


def _start(problem: ContactProblem, step: LoadStep, u: PETSc.Vec, state: PathState, from_rest: bool,
           step_solver: NewtonStepSolver | None, extrapolate: float = 0.0) -> bool:
    """Set ``step``, the one after ``state``'s, and put its initial guess in ``u``: the guess
    given (or rest) for the first step, else the predictor of :func:`_continue` (``extrapolate``
    its factor where given); a problem
    searched each step is searched first in the configuration of the step before, which
    updates the levels of ``step_solver`` (if any) for the new A. Whether the guess extrapolates
    the last solve."""
    logger.info("step %d: %s", state.done + 1, step_position(step))
    if state.solved == 0:
        if problem.follows_geometry:  # the geometry and the slip's reference of the start (a retry's too)
            _set_previous(problem, state)  # the obstacles where the start has them
            _search_in(problem, state.displacement, step_solver)
        problem.set_step(step.load, step.translation, rotation=step.rotation, fit=step.fit_fraction)
        if from_rest:
            problem.shift.copy(u)  # u~ = 0
        return False
    if problem.searched_each_step:
        _set_previous(problem, state)
        _search_in(problem, state.displacement, step_solver)
        problem.solver_variables(state.displacement, state.variables)
    return _continue(problem, step, u, state, extrapolate)


def _predict(problem: ContactProblem, step: LoadStep, u: PETSc.Vec, state: PathState,
             step_solver: NewtonStepSolver | None, pc: str, prefix: str) -> None:
    """The predictor of ``step`` (set in ``problem`` after ``state``) with pairs searched
    ``"newton"`` into ``u``, the pairs searched there (``step_solver``'s levels updated). Where the
    prescribed values alone move (the predictor of the other modes), a step that moves a boundary
    by more than an element's height (a compression, a die slid sideways) turns elements inside
    out, and is cut. A step that continues the last solve (along its change of load,
    translation and rotation), which continued the one before, extrapolates its increment
    (:meth:`PathState.extrapolation`; Abaqus' default, Code_Aster's ``PREDICTION = 'EXTRAPOLE'``);
    one that begins to turn bodies that turn whole turns the last solution on (:func:`_turned_on`);
    any other, the first from rest too, adds the response of the stiffness to the change of its
    loads and prescribed values (:func:`_elastic_change`: at rest, or the tangent at the last
    solution; Code_Aster's ``'TANGENTE'``), but a step that slides along the contact starts from
    the last solution convected with what slides (:mod:`~contactqvi.contact.convection`: the
    shipped ironing's slide steps 3-8 Newton steps instead of 15-28).
    ``pc``: the Newton-step solver's preset."""
    factor = state.extrapolation(step.load, step.translation, step.rotation, turns_only=True)
    if factor > 0.0:
        predicted = _extrapolated(problem, step, state, factor)
    elif (turned := _turned_on(problem, step, state, u)) is not None:
        predicted = turned
    else:
        predicted = fem.Function(problem.V)
        slide = sliding_translation(problem, state, step)
        if slide is not None:
            change = problem.solver_variables(convected(problem, state.displacement, slide),
                                              problem.A.createVecRight())
        else:
            change = _elastic_change(problem, state, pc, prefix)
            if state.solved > 0:
                change.axpy(1.0, state.variables)
        change.axpy(1.0, problem.shift)
        prescribed = problem.hyperelastic.prescribed  # exact, not the Krylov solve's: a contact node's
        change.array[prescribed] = problem.load.array_r[prescribed]  # roller keeps it in its plane
        problem.physical_displacement(change, predicted)
        change.destroy()
    _search_at(problem, step, u, state, predicted, step_solver, start=False)


def _turned_on(problem: ContactProblem, step: LoadStep, state: PathState, u: PETSc.Vec) -> fem.Function | None:
    """The last solution turned on rigidly with the moved groups (:meth:`PathState.turned`) as the
    predictor of a step that begins to turn them (u~, and ``u`` in the solver's variables), if that
    meets every prescribed value of the step (no support stays behind: the bodies turn whole), else
    None (``u`` then holds nothing of use). A rigid turn of the whole is predicted exactly; the
    tangent's response (:func:`_elastic_change`) turns by the chord and strains the bodies by about
    half the angle squared (the pressed blocks of tests/test_rotation.py searched ``"newton"``: 104
    Newton steps for their first 9-degree turn, 0 now; docs/finite_strain.md Sect. 14)."""
    if not state.turns_to(step.rotation):
        return None
    turned = fem.Function(problem.V)
    turned.x.array[:] = state.turned(step.translation, step.rotation, problem.V.tabulate_dof_coordinates()).ravel()
    problem.solver_variables(turned, u)
    u.axpy(1.0, problem.shift)
    rows = problem.hyperelastic.prescribed
    prescribed = problem.load.array_r[rows]
    off = problem.comm.allreduce(float(np.abs(u.array_r[rows] - prescribed).max(initial=0.0)), op=MPI.MAX)
    size = problem.comm.allreduce(float(np.abs(prescribed).max(initial=0.0)), op=MPI.MAX)
    return turned if off <= TURNED_WHOLE * max(size, problem.position_scale()) else None


def _add_elastic_change(problem: ContactProblem, u: PETSc.Vec, state: PathState, pc: str, prefix: str) -> bool:
    """Add to the predictor ``u`` of a hyperelastic body searched once or every step the response of
    the stiffness to the step's change of loads and prescribed values (:func:`_elastic_change`: the
    stiffness at rest at the path's start, the tangent at the last solution later); whether it
    changed ``u`` (False where only obstacles move, or where that solve failed). Used where the
    predictor is not enough (docs/finite_strain.md Sect. 17):

    * The first step from rest (u~ = 0): there the stiffness is the tangent, and this is Code_Aster's
      ``PREDICTION = 'TANGENTE'``. With the prescribed values moved alone, the layer under a moved
      face took the whole step: at nu = 0.499 the first Newton steps undid a pressure of the bulk
      modulus times that layer's strain (a block compressed by 3.3 % with the nodal pressure, exact
      Newton steps: 30 on a flat foundation, 38 on a wavy one; 3 and 4 from here), and half the
      height in one step inverted it.
    * A later step whose predictor (:func:`_continue`) inverts elements, which was cut: every step
      of the stacked blocks' 30 % compression took two halves, 12-14 Newton steps (5-7 from here).
      Before the tangent's response (the small-strain stiffness's, lifted by it), the stacked
      blocks' 50 % took 5-8 Newton steps to 60 % and then 19, 14, 48, 24, each step cut; from the
      tangent's, 5 in every step, uncut. A predictor that does not invert elements is kept."""
    change = _elastic_change(problem, state, pc, prefix)
    changed = change.norm(PETSc.NormType.NORM_INFINITY) > 0.0
    u.axpy(1.0, change)
    change.destroy()
    return changed


def _elastic_change(problem: ContactProblem, state: PathState, pc: str, prefix: str) -> PETSc.Vec:
    """The change of the solver's variables (a new vector) under the change of the loads and
    prescribed values from ``state`` to the step set in ``problem``: at the path's start by the
    stiffness A of the last search (at rest the tangent of every hyperelastic model), after a
    converged solve of a hyperelastic body by its tangent there (:func:`_tangent_change`,
    Code_Aster's ``PREDICTION = 'TANGENTE'``), with the variables of the contact
    nodes in contact held: all three at a node of a frictional pair (with the tangential ones free,
    a body held by friction alone was free to move, and the predictor was A's null space), the
    normal one at a node of a frictionless pair, whose tangential variables carry no force (held,
    they sheared an ironing die by its whole slide step; :func:`_predict`). After a converged solve
    every contact node is held; at the path's start (``state`` at rest) those whose gap at the step
    is not positive (to round-off, :data:`GAP_ROUNDOFF`), the others are free (held, a block on a
    wavy foundation was pressed against it at every node, and at nu = 0.4999 its first step stalled
    after 38 Newton steps where it now takes 6; docs/finite_strain.md Sect. 17). Zero where nothing
    changes, and where the solve fails (logged; with the open nodes free, a body that only contact
    holds has no unique response)."""
    change, before = problem.A.createVecRight(), problem.A.createVecRight()
    problem.step_load(problem.load_factor, problem.translation, problem.step_rotation, change)
    problem.step_load(state.load, state.translation, state.rotation, before)
    change.axpy(-1.0, before)
    before.destroy()
    if change.norm(PETSc.NormType.NORM_INFINITY) == 0.0:
        return change
    frictional = np.array([i.pair.law.frictional for i in problem.interfaces], dtype=bool)[problem.interface_of_node]
    rows = np.where(frictional[:, None], [[True, True, True]], [[False, False, True]])
    if state.solved == 0:
        size = float(np.abs(problem.V.tabulate_dof_coordinates()).max(initial=0.0))
        touching = GAP_ROUNDOFF * problem.comm.allreduce(size, op=MPI.MAX)
        rows &= (problem.gap(problem.translation, problem.step_rotation, problem.fit) <= touching)[:, None]
    held = (3 * problem.contact_blk[:, None] + np.arange(3))[rows]
    A = problem.A.copy() if state.solved == 0 or problem.hyperelastic is None else _tangent_change(problem, state,
                                                                                                   change)
    A.zeroRows((A.getOwnershipRange()[0] + held).astype(PETSc.IntType), diag=1.0)
    change.array[held] = 0.0
    # The block preconditioner belongs to a Newton-step solver's matrix. Where it is asked for, AMG
    # does not solve A's bulk term (P2 block at nu = 0.4999: GAMG out of iterations, or a start
    # whose first step stalled; factorised: 4 Newton steps, docs/finite_strain.md Sect. 17).
    solver = NEWTON_STEP_SOLVERS["lu" if pc == "pressure_schur" else pc]
    ksp = create_ksp(problem.comm, f"{prefix}predictor_", preset(solver), A, rtol=PREDICTOR_RTOL)
    solution = change.duplicate()
    ksp.solve(change, solution)
    if ksp.getConvergedReason() < 0:
        logger.info("the elastic predictor was not solved (%s): the step starts without it", ksp_converged_reason(ksp))
        solution.zeroEntries()
    for obj in (ksp, A, change):
        obj.destroy()
    return solution


def _tangent_change(problem: ContactProblem, state: PathState, change: PETSc.Vec) -> PETSc.Mat:
    """The tangent K_T at the last converged solution u_n of a hyperelastic body (a new matrix in
    the solver's variables), and the free rows of ``change`` replaced by the tangent's: the change
    of the loads less K_T times the change of the prescribed values g, the lifting of the
    linearised step f(u_n + g + delta) = f(u_n) + K_T (g + delta) - Delta l (``change`` keeps g on
    the prescribed rows). K_T g is the central difference of r_K along g at 1e-6 of it (its error
    of order 1e-12 of K_T g, its round-off eps ||r_K's terms|| / 1e-6): the tangent's matrix has
    identity rows and columns at the prescribed dofs, so it cannot lift them itself, and r_K at
    u_n + g turns the cells under a moved face inside out. A itself is left as it was."""
    system = problem.hyperelastic
    prescribed = system.prescribed
    tangent = problem.tangent_at(state.displacement, problem.A.duplicate(copy=False))
    step = change.duplicate()
    step.zeroEntries()
    step.array[prescribed] = change.array_r[prescribed]
    direction = problem.into_global(step, system.internal.duplicate())  # g in global components
    base = state.displacement.x.petsc_vec
    epsilon = FINITE_DIFFERENCE
    rhs = system.internal.duplicate()
    rhs.zeroEntries()
    for sign in (1.0, -1.0):  # -K_T g
        base.copy(system.displacement.x.petsc_vec)
        system.displacement.x.petsc_vec.axpy(sign * epsilon, direction)
        system.displacement.x.scatter_forward()
        rhs.axpy(-sign / (2.0 * epsilon), system.assemble_residual(problem.load_factor))
    base.copy(system.displacement.x.petsc_vec)
    system.displacement.x.scatter_forward()
    rhs.axpy(1.0, system.assemble_residual(state.load))  # + Delta l = r_K(lambda_n) - r_K(lambda_n+1)
    rhs.axpy(-1.0, system.assemble_residual(problem.load_factor))
    free = change.duplicate()
    problem.force_from_global(rhs, free)
    free.array[prescribed] = change.array_r[prescribed]
    free.copy(change)
    for obj in (step, direction, rhs, free):
        obj.destroy()
    return tangent


def _set_previous(problem: ContactProblem, state: PathState) -> None:
    """Set the step of ``state`` again: its prescribed parts and fit (before a search in its configuration)."""
    problem.set_step(state.load, state.translation, rotation=state.rotation, fit=state.fit)


def _search_in(problem: ContactProblem, configuration: fem.Function, step_solver: NewtonStepSolver | None,
               start: bool = True) -> None:
    """Search the problem again in x + ``configuration`` and update ``step_solver``'s levels (if
    any); ``start``: the search starts a load step (the slip's reference of pairs searched
    ``"newton"``, :meth:`~contactqvi.contact.problem.ContactProblem.search`)."""
    change = problem.search(configuration, change=step_solver is not None, start=start)
    if change is not None:
        step_solver.update_operator(change, grown=True)
        change.destroy()
    logger.info("contact search in the deformed configuration: %d contact nodes, %.2f s (search) + %.2f s "
                "(change of variables)", problem.n_contact, problem.setup_seconds["contact_search"],
                problem.setup_seconds["change_of_variables"])


def _settle(problem: ContactProblem, step: LoadStep, u: PETSc.Vec, state: PathState, solver: SCDNewtonSolver,
            result: SCDNewtonResult, stop: typing.Callable[[], bool] | None,
            path: dict[str, typing.Any]) -> tuple[SCDNewtonSolver, SCDNewtonResult]:
    """Search ``step``, the one after ``state``'s, again in the configuration its solution ``u``
    reached and solve it again from there, until a solve changes the displacement by at most
    ``geometry_tol`` times the step's increment from ``state.displacement`` (the step before's;
    zero before the first step), at most ``max_searches`` times (``path``:
    :data:`PATH_PARAMETERS`); nothing when the step did not move (:data:`STILL`) or no pair
    of the problem is searched ``"until_settled"``.

    The slip stays measured from the step before (its u~ in the new variables goes to
    ``state.variables``); each solve starts from the configuration searched in and stops at
    the first one's target ||y^||; after a solve that changed the displacement no less than
    the one before, the next configuration is under-relaxed (module docstring). Returns the
    solver of the last solve (``solver`` is destroyed) and the step's result: the last
    solve's, with the iterations, timings and history of all of them, ``diverged_max_it``
    if the configuration did not settle.
    """
    if not problem.settles_geometry:
        return solver, result
    solves, change, status, target = [result], math.inf, result.status, result.target
    index, before = state.done, state.displacement
    reached = problem.physical_displacement(u, fem.Function(problem.V))  # the configuration searched in
    work = reached.x.petsc_vec.duplicate()
    relaxation = 1.0
    try:
        while result.converged:
            work.waxpy(-1.0, before.x.petsc_vec, reached.x.petsc_vec)
            increment = work.norm(PETSc.NormType.NORM_INFINITY)
            still = increment <= STILL * reached.x.petsc_vec.norm(PETSc.NormType.NORM_INFINITY)
            if still or change <= path["geometry_tol"] * increment:
                break
            if len(solves) > path["max_searches"]:
                warn(problem.comm, logger, "not_settled", f"step {index + 1}: the configuration did not settle in "
                     f"{path['max_searches']} searches (last change {change:.3g} m of an increment of {increment:.3g} m)",
                     step=index + 1, searches=path["max_searches"], change=change, increment=increment)
                status = Status.DIVERGED_MAX_IT
                break
            solver = _search_reached(problem, step, u, state, reached, solver)
            result = solver.solve(u, atol=target, stop=stop)
            solves.append(result)
            status = result.status
            reached.x.petsc_vec.copy(work)
            problem.physical_displacement(u, reached)
            work.axpy(-1.0, reached.x.petsc_vec)
            change, last = work.norm(PETSc.NormType.NORM_INFINITY), change
            if change >= last:  # not contracting: move only part of the way to the next configuration
                relaxation *= 0.5
            if relaxation < 1.0:
                reached.x.petsc_vec.axpy(1.0 - relaxation, work)
                reached.x.scatter_forward()
            logger.info("step %d, search %d in the configuration it reached: the displacement changed by %.3g m "
                        "(%.3g of the step's increment)", index + 1, len(solves) - 1, change,
                        change / increment if increment > 0.0 else math.inf)
    finally:
        work.destroy()
    return solver, _merged(solves, status)


def _follow(problem: ContactProblem, step: LoadStep, u: PETSc.Vec, state: PathState, solver: SCDNewtonSolver,
            stop: typing.Callable[[], bool] | None) -> tuple[SCDNewtonSolver, SCDNewtonResult]:
    """Solve ``step`` with pairs searched ``"newton"``: the geometry follows the iterate on the facet
    pairs of the last search, and where an iterate's projections leave them (or a converged
    solution's) the pairs are searched again there and the step is solved on from it (the slip
    still from the step's start); the searches are part of the Newton iteration, whose
    ``max_iterations`` bound all its steps. Returns the last solve's solver (``solver`` is
    destroyed otherwise) and the step's result, all its solves merged (:func:`_merged`)."""
    reached = fem.Function(problem.V)
    budget = solver.parameters["max_iterations"]

    def moved(iterate: PETSc.Vec) -> bool:
        problem.physical_displacement(iterate, reached)
        return problem.layout_changed(reached)

    result = solver.solve(u, atol=state.target, stop=stop, search=moved, volume_start=_volume_start(state))
    solves, target = [result], result.target
    while result.status == Status.SEARCH_AGAIN or (result.converged and moved(u)):
        if sum(r.iterations for r in solves) >= budget:
            return solver, _merged(solves, Status.DIVERGED_MAX_IT)
        logger.info("step %d, search %d: the projections left the facets of the last search", state.done + 1,
                    len(solves))
        problem.physical_displacement(u, reached)
        solver = _search_reached(problem, step, u, state, reached, solver, start=False)
        result = solver.solve(u, atol=target, stop=stop, search=moved, forcing=result.forcing)
        solves.append(result)
    return solver, _merged(solves, result.status)


def _search_reached(problem: ContactProblem, step: LoadStep, u: PETSc.Vec, state: PathState, reached: fem.Function,
                    solver: SCDNewtonSolver, start: bool = True) -> SCDNewtonSolver:
    """:func:`_search_at` ``reached`` and return a new solver for it, which takes over ``solver``'s
    multigrid levels (``solver`` is destroyed)."""
    parameters, prefix, step_solver = solver.parameters, solver.prefix, _released(solver)
    _search_at(problem, step, u, state, reached, step_solver, start)
    return SCDNewtonSolver(problem, parameters, prefix=prefix, step_solver=step_solver)


def _search_at(problem: ContactProblem, step: LoadStep, u: PETSc.Vec, state: PathState, reached: fem.Function,
               step_solver: NewtonStepSolver | None, start: bool = True) -> None:
    """Search ``step`` again in x + ``reached`` (``step_solver``'s levels updated, if any), set it
    with the slip from the step before (``state``, whose u~ in the new variables goes to
    ``state.variables``) and put ``reached`` into ``u`` (new variables); ``start`` as for
    :func:`_search_in`."""
    _search_in(problem, reached, step_solver, start)
    _set_previous(problem, state)
    problem.solver_variables(state.displacement, state.variables)
    problem.set_step(step.load, step.translation, state.variables, state.translation, step.rotation, state.rotation,
                     step.fit_fraction)
    problem.solver_variables(reached, u)
    u.axpy(1.0, problem.shift)


def _merged(solves: list[SCDNewtonResult], status: Status,
            marks: list[dict[str, typing.Any]] | None = None) -> SCDNewtonResult:
    """One step's result of several solves: the last one's solution and ``status``, the first
    one's target, the iterations and timings added, the history entries marked with their
    solve's ``marks`` (default: the ``search`` they followed)."""
    marks = [{"search": j} for j in range(len(solves))] if marks is None else marks
    timings = Timings()
    for solve in solves:
        for phase, seconds in solve.timings.items():
            timings[phase] = timings.get(phase, 0.0) + seconds
    return dataclasses.replace(
        solves[-1], status=status, target=solves[0].target, iterations=sum(r.iterations for r in solves),
        inner_iterations=sum(r.inner_iterations for r in solves), timings=timings,
        history=[{**entry, **mark} for mark, solve in zip(marks, solves) for entry in solve.history])


def _continue(problem: ContactProblem, step: LoadStep, u: PETSc.Vec, state: PathState,
              extrapolate: float = 0.0) -> bool:
    """Set ``step`` after ``state``'s step, the slip measured from it; ``u`` gets the predictor.
    A hyperelastic body's step that continues the last solve (along its change of load,
    translation and rotation) extrapolates it, slip increments included, a turning node turned on
    (:meth:`PathState.extrapolated`; Abaqus' default, Code_Aster's ``PREDICTION = 'EXTRAPOLE'``); one
    that begins to turn bodies that turn whole turns the last solution on (:func:`_turned_on`).
    The pressed blocks of tests/test_rotation.py take 3 Newton steps per turn instead of 7 with
    ``until_settled``, 0-1 instead of 6 with ``every_step``; the seal strip of docs/finite_strain.md
    Sect. 15 (nu 0.499, Coulomb 0.3) 5.1 a step instead of 12.8. Any other step starts from u~ of
    the last, its touching nodes moved along with their master surface (no slip increment); pairs
    searched ``"newton"`` predict otherwise (:func:`_predict`). ``extrapolate`` > 0: the factor of
    the extrapolation whether the step continues the last or not (a relaxation step, which stays at
    the step's loads). Whether it extrapolates."""
    problem.set_step(step.load, step.translation, state.variables, state.translation, step.rotation, state.rotation,
                     step.fit_fraction)
    factor = extrapolate or state.extrapolation(step.load, step.translation, step.rotation, turns_only=False)
    if problem.hyperelastic is not None and not problem.follows_geometry:
        if factor > 0.0:
            problem.solver_variables(_extrapolated(problem, step, state, factor), u)
            u.axpy(1.0, problem.shift)
            return True
        if _turned_on(problem, step, state, u) is not None:
            return True
    _carried(problem, u, state)
    return False


def _carried(problem: ContactProblem, u: PETSc.Vec, state: PathState) -> None:
    """The predictor ``u`` of a step after ``state`` set in ``problem`` that is not extrapolated: u~
    of the last step, its touching nodes moved along with their master surface (no slip increment)."""
    u.waxpy(1.0, problem.shift, state.variables)
    touching = np.isin(state.contact_states(problem), TOUCHING)
    u.array.reshape(-1, 3)[problem.contact_blk[touching], :2] = 0.0


def _extrapolated(problem: ContactProblem, step: LoadStep, state: PathState, factor: float) -> fem.Function:
    """u~ of ``state`` extrapolated to ``step`` by ``factor`` of its stride, a turning node turned on
    (:meth:`PathState.extrapolated`)."""
    predicted = fem.Function(problem.V)
    points = problem.V.tabulate_dof_coordinates()
    predicted.x.array[:] = state.extrapolated(factor, step.translation, step.rotation, points).ravel()
    return predicted


def contact_resultants(problem: ContactProblem, result: SCDNewtonResult,
                       displacement: fem.Function | None = None) -> dict[str, typing.Any]:
    """Contact forces (N, global components) and contact, sticking and sliding areas (m^2) of a solved step.

    ``pair_forces``: per contact pair, the force of the master side (obstacle or body) on
    the slave body; ``contact_force``: their sum over all pairs, the total force of the
    master sides on the slave bodies; ``obstacle_force``: the part of it from rigid
    obstacles (forces between bodies cancel in the global balance, so this is the one the
    equilibrium of all bodies together has). ``contact_area``: the area of the slave
    facets in contact (:func:`~contactqvi.contact.surface.contact_facet_areas`, the facets'
    normals those of the surface displaced by ``displacement`` if given: at finite strain);
    ``sticking_area`` and ``sliding_area`` split it by the states of the facets' nodes and
    add up to it.
    """
    forces = np.column_stack([result.friction_force, result.normal_force])  # nodal frames
    nodal = np.einsum("ij,ijk->ik", forces, problem.frames) if len(forces) else np.zeros((0, 3))
    pair_forces = {}
    total, obstacles = np.zeros(3), np.zeros(3)
    for k, interface in enumerate(problem.interfaces):
        force = problem.comm.allreduce(nodal[problem.interface_of_node == k].sum(axis=0), op=MPI.SUM)
        pair_forces[interface.pair.name] = force.tolist()
        total += force
        if interface.obstacle is not None:
            obstacles += force
    sticking, sliding = problem.comm.allreduce(contact_facet_areas(problem, result.states, displacement), op=MPI.SUM)
    return {
        "contact_force": total.tolist(),
        "obstacle_force": obstacles.tolist(),
        "pair_forces": pair_forces,
        "contact_area": float(sticking + sliding),
        "sticking_area": float(sticking),
        "sliding_area": float(sliding),
        "units": {"contact_force": "N", "obstacle_force": "N", "pair_forces": "N", "contact_area": "m^2",
                  "sticking_area": "m^2", "sliding_area": "m^2"},
    }
