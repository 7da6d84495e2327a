"""The linear solver of the SCD Newton step: J du = rhs of (5.4), inexactly (seed 000, Sect. 7).

:class:`NewtonStepSolver` owns the Krylov solver of the Newton steps, its
preconditioner's reuse from step to step (multigrid levels kept Galerkin-exact by
:class:`~contactqvi.multigrid.GalerkinUpdate`) and the paper's Krylov test.
"""

from __future__ import annotations

import logging
import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

from contactqvi.contact.pressure_schur import PressureSchur
from contactqvi.lifetime import PETScOwner
from contactqvi.linalg import OptionsDict, create_ksp, default_options, ksp_converged_reason, preset
from contactqvi.multigrid import GalerkinUpdate, is_multigrid, set_up
from contactqvi.records import warn

__all__ = ["FALLBACK", "NEWTON_STEP_SOLVERS", "NewtonStepSolver"]

logger = logging.getLogger(__name__)

#: The preset of the direct solve a Newton step falls back to, once, when its Krylov solve
#: fails (:data:`contactqvi.linalg.KSP_PRESETS`; options prefix ``{prefix}fallback_``).
FALLBACK = "lu"

#: A start whose residual is below this fraction of the right-hand side's norm has its free rows
#: solved to round-off (:meth:`NewtonStepSolver._free_rows_rtol`).
RESOLVED = 1e-12

#: Newton-step solvers selectable by the SCD parameter ``pc``, each a preset of
#: :data:`contactqvi.linalg.KSP_PRESETS` applied under the solver's options prefix
#: (``-{prefix}ksp_*``/``-{prefix}pc_*`` on the command line win). ``gamg``
#: (default): FGMRES + one GAMG V-cycle with the rigid-body near-nullspace, stopped
#: at the unpreconditioned relative residual (the paper's test, Sect. 7); ``paper``:
#: GMRES + block-Jacobi/ILU(0) as in Sect. 7; ``hypre``: FGMRES + BoomerAMG; ``lu``:
#: exact (MUMPS), the reference for the Newton counts. Measured in docs/coulomb.md.
#: ``jacobi``: GMRES + point Jacobi for a mass-like problem (a dynamic step's projection).
#: ``pressure_schur``: FGMRES + the block preconditioner of bodies with the nodally averaged
#: volume change on the uncondensed displacement-pressure system, robust in the bulk modulus
#: (:mod:`contactqvi.contact.pressure_schur`).
NEWTON_STEP_SOLVERS = {"gamg": "gmres_gamg", "paper": "gmres_ilu", "hypre": "gmres_hypre", "lu": "lu",
                       "jacobi": "gmres_jacobi", "pressure_schur": "gmres_pressure_schur"}


class NewtonStepSolver(PETScOwner):
    """Inexact solver of the Newton systems (5.4) of one SCD Newton solver, with preconditioner reuse.

    What the preconditioner keeps from step to step:

    * multigrid (GAMG, MG) with ``reuse_pc``: it is set up at the first step (or
      before it, on A: :meth:`set_up_levels`); then its coarse operators are updated by
      the Galerkin products of J's change, which lives on the contact rows
      (:class:`~contactqvi.multigrid.GalerkinUpdate`), and of A's change at a contact
      search (:meth:`update_operator`), so every step is preconditioned for its own J
      at the cost of the contact surface;
      a new set-up follows a slow solve (:meth:`_discard_set_up`) when the
      interpolation depends on J's values (smoothed aggregation);
    * other preconditioners with ``reuse_pc``: kept between steps in which no
      contact node changes its kind (:meth:`_set_operator`);
    * direct solvers (``preonly``): a new factorisation at every step.

    The Krylov test is the paper's, ||rhs - J du|| <= tol ||rhs of (5.4)|| (:meth:`krylov_rtol`), and
    at least tol of the start's own residual where the start meets the paper's (:meth:`_free_rows_rtol`).

    Args:
        comm: the problem's communicator.
        prefix: PETSc options prefix of the KSP; any ``-{prefix}ksp_*`` or
            ``-{prefix}pc_*`` option overrides the preset.
        pc: key of :data:`NEWTON_STEP_SOLVERS`.
        multigrid_options: GAMG options of the problem (aggregation for several
            bodies), added to a GAMG preset.
        rtol: default relative tolerance of the Krylov solve (the SCD parameter ``tol``).
        reuse_pc: multigrid: Galerkin updates of one set-up; other preconditioners:
            kept while no contact node changes its kind.
        rebuild_iterations: multigrid with ``reuse_pc`` and smoothed aggregation: a
            new set-up after a solve of more Krylov iterations than this.
        initial_guess: start the Krylov solve from ``du`` as given (it holds the
            exact values of the eliminated rows); direct solvers need none.
        pressure: the block preconditioner of ``pc = "pressure_schur"`` (taken over, its
            :meth:`~contactqvi.contact.pressure_schur.PressureSchur.update` the caller's before
            each solve), else None.

    A Krylov solve that fails (a negative converged reason: out of iterations, a breakdown)
    is done again by a direct solve (:data:`FALLBACK`, MUMPS LU) for that Newton step alone:
    a large load step can leave a preconditioner built for another J far behind (issue 46: an
    80 % step with cuts off ended in ``diverged_linear_solve`` after 2 005 Krylov iterations,
    where exact Newton steps converge in 6).
    It is a warning (``direct_fallback``, :func:`~contactqvi.records.warn`: in ``summary.json`` of a
    case run) and in the step's history (:attr:`fallback`); the next step tries the Krylov solver again.

    Attributes:
        ksp: the Krylov solver.
        galerkin: the Galerkin updates of the current multigrid set-up (None before
            it, and for other preconditioners).
        fallback: the history record of the last solve's fall-back to the direct solve
            (``direct_fallback``: the Krylov solve's reason; ``direct_reason``: the direct
            solve's), empty if it did not fall back.
    """

    def __init__(self, comm: MPI.Comm, prefix: str, pc: str, multigrid_options: OptionsDict, *, rtol: float,
                 reuse_pc: bool, rebuild_iterations: int, initial_guess: bool,
                 pressure: PressureSchur | None = None):  # fmt: skip
        self.comm = comm
        self._options = preset(NEWTON_STEP_SOLVERS[pc])
        if self._options.get("pc_type") == "gamg":
            self._options.update(multigrid_options)
        self.ksp = create_ksp(comm, prefix, self._options, rtol=rtol)
        self.pressure = pressure
        if pressure is not None:
            pressure.attach(self.ksp)
        self.reuse_pc, self.rebuild_iterations, self.initial_guess = reuse_pc, rebuild_iterations, initial_guess
        self._rebuilds = _smoothed_aggregation(prefix, self._options)
        self.galerkin: GalerkinUpdate | None = None
        self._pc_kinds: np.ndarray | None = None  # contact node kinds when the preconditioner was last built
        self._direct: PETSc.KSP | None = None  # made at the first fall-back
        self.fallback: dict[str, str] = {}
        self._solved_by, self._iterations = self.ksp, 0  # the KSP of the last solve and its iterations

    def petsc_objects(self) -> list[typing.Any]:
        return [self.galerkin, self.ksp, self._direct, self.pressure]

    @property
    def iterations(self) -> int:
        """Krylov iterations of the last solve."""
        return self._iterations

    @property
    def reason(self) -> str:
        """Name of the last solve's converged reason (e.g. ``CONVERGED_RTOL``)."""
        return ksp_converged_reason(self._solved_by)

    def record(self) -> dict[str, typing.Any]:
        """The last solve's part of a Newton step's history: ``krylov_iterations``, ``ksp_reason``,
        :attr:`fallback`'s entries and, where :attr:`pressure`'s Krylov method went on past the
        uncondensed system's own test, ``krylov_uncondensed`` (the iterations to that test)."""
        record = {"krylov_iterations": self.iterations, "ksp_reason": self.reason, **self.fallback}
        first = None if self.pressure is None else self.pressure.uncondensed_iterations
        if first is not None and first < self.iterations:
            record["krylov_uncondensed"] = first
        return record

    def solve(self, J: PETSc.Mat, change: PETSc.Mat, kinds: np.ndarray, rhs: PETSc.Vec, du: PETSc.Vec, tol: float,
              rhs_ratio: float = 1.0) -> int:  # fmt: skip
        """Solve J du = rhs to ``tol`` (Sect. 7); returns the KSP's converged reason.

        Args:
            J: the Newton matrix (the same object at every step, changed in place).
            change: J minus the J of the previous call, nonzero on few rows (the
                contact rows): what the multigrid levels are updated by.
            kinds: the contact nodes' normal and tangential kinds J was built for.
            rhs: right-hand side, the fixed rows eliminated.
            du: solution; on entry the exact values of the eliminated rows.
            tol: relative tolerance of the Krylov test (the forcing term).
            rhs_ratio: ||rhs of (5.4)|| / ||rhs|| (:meth:`krylov_rtol`).
        """
        multigrid = self.reuse_pc and is_multigrid(self.ksp.getPC())
        if self.galerkin is not None and self._rebuilds and self.iterations > self.rebuild_iterations:
            self._discard_set_up()
        if multigrid and self.galerkin is not None:
            self.galerkin.update(change)
        elif self.pressure is None:  # the block preconditioner's KSP takes the uncondensed system
            self._set_operator(J, kinds, multigrid)
        from_guess = self.initial_guess and self.ksp.getType() != "preonly"
        rtol = self.krylov_rtol(tol, rhs_ratio)
        if from_guess and self.pressure is None and not self._relative_to_start():
            rtol = self._free_rows_rtol(J, rhs, du, tol, rtol)
        self.ksp.setTolerances(rtol=rtol)
        self.ksp.setInitialGuessNonzero(from_guess)
        # Options read at set-up (GAMG: multigrid options; block Jacobi: sub_*) come from the preset.
        with default_options(self.ksp.getOptionsPrefix(), self._options):
            if multigrid and self.galerkin is None:
                set_up(self.ksp)
                self.galerkin = GalerkinUpdate(self.ksp.getPC())
            if self.pressure is not None:
                self._solved_by, self._iterations = self.pressure.solve(self.ksp, rhs, du)
            else:
                self.ksp.solve(rhs, du)
                self._solved_by, self._iterations = self.ksp, self.ksp.getIterationNumber()
        self.fallback = {}
        if self._solved_by.getConvergedReason() < 0 and self.ksp.getType() != "preonly":
            return self._solve_directly(J, rhs, du)
        return self._solved_by.getConvergedReason()

    def _solve_directly(self, J: PETSc.Mat, rhs: PETSc.Vec, du: PETSc.Vec) -> int:
        """Solve J du = rhs by the direct :data:`FALLBACK` after the Krylov solve failed; log it and
        keep it in :attr:`fallback`. Returns the direct solve's converged reason."""
        if self._direct is None:
            self._direct = create_ksp(self.comm, f"{self.ksp.getOptionsPrefix()}fallback_", preset(FALLBACK))
        self._direct.setOperators(J)
        self._direct.solve(rhs, du)
        reason = self._direct.getConvergedReason()
        self.fallback = {"direct_fallback": self.reason, "direct_reason": ksp_converged_reason(self._direct)}
        warn(self.comm, logger, "direct_fallback", f"the Krylov solve of a Newton step failed ({self.reason} after "
             f"{self.iterations} iterations): solved by {FALLBACK} (MUMPS) instead, {self.fallback['direct_reason']}",
             krylov_iterations=self.iterations)
        if reason < 0:  # a factorisation that failed (a singular J) fails every later solve with a PETSc error
            self._direct.destroy()
            self._direct = None
        return reason

    def set_up_levels(self, A: PETSc.Mat) -> bool:
        """Set the multigrid levels up on ``A`` (with its near-nullspace) before the first
        solve, so that every later operator is reached by Galerkin updates (each solve's
        change, :meth:`update_operator`). Returns whether this solver keeps levels
        (multigrid with ``reuse_pc``); if not, nothing is done."""
        if not (self.reuse_pc and is_multigrid(self.ksp.getPC())):
            return False
        self.ksp.setOperators(A)
        with default_options(self.ksp.getOptionsPrefix(), self._options):
            set_up(self.ksp)
        self.galerkin = GalerkinUpdate(self.ksp.getPC())
        return True

    @property
    def keeps_levels(self) -> bool:
        """Whether a multigrid set-up is kept up to date by Galerkin updates (``reuse_pc``,
        after the first solve or :meth:`set_up_levels`)."""
        return self.galerkin is not None

    def update_operator(self, change: PETSc.Mat, grown: bool) -> None:
        """The operator of the last solve changed in place by ``change``, outside the solves:
        the kept multigrid levels follow it (:attr:`keeps_levels`; else nothing is kept to
        update). ``grown``: the operator's pattern grew (a contact search,
        :meth:`~contactqvi.contact.problem.ContactProblem.search`), and the levels' may.

        The interpolations stay those of the set-up. With unsmoothed aggregation
        (several bodies) they are the aggregates of the graph of the operator set up on
        (:meth:`set_up_levels`: A of the reference configuration) and its near-nullspace;
        a search moves the mortar couplings along the interfaces only, so the new
        operator keeps those aggregates instead of a new set-up.
        """
        if self.galerkin is not None:
            structure = PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN if grown else PETSc.Mat.Structure.SUBSET
            self.galerkin.update(change, structure)

    def operator_replaced(self) -> None:
        """The operator changed everywhere (the Jacobian of a nonlinear f at a new iterate):
        the preconditioner keeps nothing, the next solve sets it up on its J."""
        if self.galerkin is not None:
            self._discard_set_up()
        self._pc_kinds = None

    def _discard_set_up(self) -> None:
        """Drop the multigrid set-up after a solve of more than ``rebuild_iterations`` Krylov iterations.

        The interpolation of a set-up is kept by the Galerkin updates; the first one is
        made from J at u = 0, before the contact zone forms, and fits the later J less
        well (lev 7 d3/L2, 2 ranks: 46 Krylov iterations with the first interpolation
        throughout, 30 with a new set-up at step 3; lev 8 d1/L1, 2 ranks: 58 -> 39 with
        a threshold of 4). At lev 7-8 a set-up costs more than the iterations it saves
        (``benchmarks/coulomb_profile.py``, docs/coulomb.md), so the default threshold
        10 only catches a hierarchy that has really degraded.

        With unsmoothed aggregation (several bodies) the interpolation is made of the
        aggregates of J's graph (its pattern, fixed in a load step) and the
        near-nullspace alone, so a new set-up would build the same hierarchy: no
        rebuilds (two-body Hertz fine mesh: the same Krylov counts with and without
        them, 6 s more with, in a 25 s load path).
        """
        self.galerkin.destroy()
        self.galerkin = None
        self.ksp.getPC().reset()  # a new set-up from scratch (GAMG keeps eigenvalue estimates across a plain one)

    def _set_operator(self, J: PETSc.Mat, kinds: np.ndarray, multigrid: bool) -> None:
        """J for the preconditioner: a new set-up, or (a non-multigrid one with ``reuse_pc``, not
        ``preonly``) the one built while no contact node has changed its kind since.

        J then changes only in the sliding rows' coefficients, and the Krylov method
        still solves the current system to ``tol``.
        """
        same = self._pc_kinds is not None and np.array_equal(self._pc_kinds, kinds)
        reuse = self.comm.allreduce(same, op=MPI.LAND)
        reuse = reuse and self.reuse_pc and not multigrid and self.ksp.getType() != "preonly"
        if not reuse:
            self._pc_kinds = kinds
        self.ksp.setOperators(J)
        self.ksp.getPC().setReusePreconditioner(reuse)

    def krylov_rtol(self, tol: float, rhs_ratio: float) -> float:
        """The KSP's rtol for the paper's test ||rhs - J du|| <= tol ||rhs of (5.4)||: ``tol * rhs_ratio``.

        The eliminated rows are gamma I with one gamma (the largest), so the
        assembled rhs holds gamma du_i there instead of gamma_i du_i; with
        ``nodal_diagonal`` (gamma_i down to 1/3000 of the largest on the Hertz meshes)
        that inflated ||rhs||, the initial guess (exact on the eliminated rows, zero
        elsewhere) met the test and GMRES returned after 0 iterations: the
        Cattaneo-Mindlin steps then stalled (coarse mesh: 23, 43, 42, 35, 39, 7 Newton
        steps, step 7 failed after 100). ``rhs_ratio`` = ||rhs of (5.4)|| / ||assembled
        rhs|| (:meth:`~contactqvi.contact.scd_newton.SCDNewtonSolver.newton_system`; 1
        with one gamma, so the paper's tables are unchanged) gives 4-9 Newton steps per
        load step. Relative to the initial residual
        (``-{prefix}ksp_converged_use_initial_residual_norm``, or the preset's, then not
        scaled) the Mindlin steps converge alike, but Table 2 at lev 3-6 needs 2 Newton and 8
        Krylov iterations more.
        """
        return tol if self._relative_to_start() else tol * rhs_ratio

    def _relative_to_start(self) -> bool:
        """Whether the KSP's test is relative to the initial residual (the preset's or the command line's
        ``-{prefix}ksp_converged_use_initial_residual_norm``)."""
        name = "ksp_converged_use_initial_residual_norm"
        return self._options.get(name, False) or PETSc.Options().getBool(self.ksp.getOptionsPrefix() + name, False)

    @staticmethod
    def _free_rows_rtol(J: PETSc.Mat, rhs: PETSc.Vec, du: PETSc.Vec, tol: float, rtol: float) -> float:
        """The KSP's rtol when the solve starts from ``du`` (exact on the eliminated rows, zero
        elsewhere) and its test is the paper's: ``rtol``, unless that start meets it already. Then the
        eliminated rows' share of ||rhs|| alone passed the test and the step would move them
        alone (zero Krylov iterations, zero on every free row): the free rows are solved to
        ``tol`` of their own residual, ||rhs - J du|| <= tol ||rhs - J du_0||, unless that residual is
        round-off already (below :data:`RESOLVED` ||rhs||, which a Krylov method could not reduce).

        Measured (cases/push_out.toml on 3 ranks, step 1, the fit of a Coulomb pair): the
        nodes whose slip reversed stick (:meth:`SCDNewtonSolver.classify`), their tangential
        rows are eliminated with the slips they undo, and every other Newton step was such a
        zero-iteration step, damped to 1/4 ... 1/1280; the step ran out of its 100 Newton steps
        at 3e-4 of its start, where 1 and 2 ranks took 9 (one Krylov iteration in the same
        place on 1 rank)."""
        residual = rhs.duplicate()
        J.mult(du, residual)
        residual.aypx(-1.0, rhs)
        start, norm = residual.norm(), rhs.norm()
        residual.destroy()
        return tol * start / norm if RESOLVED * norm < start <= rtol * norm else rtol


def _smoothed_aggregation(prefix: str, options: OptionsDict) -> bool:
    """Whether a GAMG preconditioner smooths its aggregates (PETSc's default: one step),
    so that its interpolation depends on J's values; the command line wins over ``options``."""
    if options.get("pc_type") != "gamg":
        return True
    default = int(options.get("pc_gamg_agg_nsmooths", 1))
    return PETSc.Options().getInt(f"{prefix}pc_gamg_agg_nsmooths", default) > 0
