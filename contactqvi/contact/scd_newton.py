"""SCD semismooth* Newton method for the Coulomb GE 0 in A u - l + Q(u) (seed 000).

Q is the nodal law of the problem's contact laws (:class:`~contactqvi.laws.NodalLaw`:
Coulomb as in the paper; Tresca, frictionless and pressure-dependent Coulomb with the
same machinery), acting on each contact node's components in its frame (two
tangential, then normal).

One iteration k (Algorithm 1 of Sect. 4 in the form of Sect. 5), each part a method
named after it:
  1. :meth:`~SCDNewtonSolver.approximation_step` (6.17):
     d^ = (gamma I + Q)^{-1}(gamma u - (A u - l)), residual y^ = (gamma (u - d^), u - d^),
     and :meth:`~SCDNewtonSolver.classify` (the graph point's states, Table 1; with
     ``approximation = stick_reversed`` reversed slips go onto the sticking branch);
  2. :meth:`~SCDNewtonSolver.generalized_derivative`: an element rge(W*, U*) of S*Q at
     (d^, gamma u - (A u - l) - gamma d^) (Cor. 6.8, nodal bases in
     :func:`contactqvi.contact.nodal.scd_adjoint_blocks`);
  3. :meth:`~SCDNewtonSolver.newton_system` (5.4): (W*^T A + U*^T) du = -(W*^T y1^ + U*^T y2^),
     rows of non-contact dofs those of A (Q^R = 0: rge(I, 0)), J = D A + U with
     block-diagonal D = W*^T, U = U*^T, kept as A plus a change on the contact rows
     (:class:`~contactqvi.contact.newton_matrix.NewtonMatrix`); rows whose subspace
     is rge(0, I) (the normal row of a contact node, all rows of a sticking node) are
     pure identity rows and are eliminated exactly (MatZeroRowsColumns);
  4. :meth:`~SCDNewtonSolver.linear_solve`: the inexact Krylov solve to ``tol``
     (Sect. 7; tighter in the local phase, :meth:`~SCDNewtonSolver.forcing_term`) by a
     :class:`~contactqvi.contact.newton_step_solver.NewtonStepSolver`, which owns the KSP
     and the preconditioner's reuse (a multigrid set up once, its coarse operators
     following J by Galerkin products of the contact rows' change);
  5. :meth:`~SCDNewtonSolver.line_search`: the non-monotone line search of Sect. 7 on ||y^||.
"""

from __future__ import annotations

import dataclasses
import logging
import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

from dolfinx import fem

from contactqvi.contact.nodal import State, classify, contact_states, resolvent, scd_adjoint_blocks, stick_reversed_slip
from contactqvi.contact.newton_matrix import NewtonMatrix
from contactqvi.contact.newton_step_solver import NEWTON_STEP_SOLVERS, NewtonStepSolver
from contactqvi.contact.pressure_schur import PressureSchur
from contactqvi.contact.problem import ContactProblem
from contactqvi.elasticity import displacement_degree, lame_parameters
from contactqvi.lifetime import PETScOwner, VectorSet
from contactqvi.linalg import power_iteration
from contactqvi.nodal_pressure import NodalPressure
from contactqvi.parameters import Parameter, Parameters, require
from contactqvi.result import Result, Status

__all__ = [
    "GRADED_RANGE",
    "PARAMETERS",
    "Forcing",
    "GraphPoint",
    "SCDNewtonResult",
    "SCDNewtonSolver",
    "WorkVectors",
    "line_search_steps",
]

logger = logging.getLogger(__name__)

#: ``gamma_rule = auto``: ``nodal_diagonal`` when the largest diagonal entry of the contact
#: nodes spans more than this factor, else ``contact_diagonal``. A uniform structured mesh
#: spans 4 (corner, edge and interior nodes of the contact face: the paper's bodies at
#: lev 3-6 3.96-4.0), anything else more: 9.1 (patch test), 11.9 (cases/arch_block.toml),
#: 29-39 (two-body cases, whose slave diagonals mix both bodies' stiffness through T),
#: 1300-3400 (Hertz, Cattaneo-Mindlin). On every shipped case above 4, ``nodal_diagonal``
#: took as many or fewer Newton steps (make-test variants, 1 rank): patch 5 = 5, arch block
#: 38 -> 35, vice 17 -> 15, two-body Hertz 34 -> 29, two-body Cattaneo-Mindlin 41 -> 24
#: (its first step 25 -> 10); on the paper's meshes it costs 8 % more (``_gamma_rule``).
GRADED_RANGE = 8.0

#: ``tol`` of Sect. 7 (the inner Krylov solves of a linear f), and of a hyperelastic f: its
#: Jacobian changes at every Newton step, and solves to 0.1 let the line search accept
#: steps of 1/32 for tens of iterations with a slowly growing merit (the rubber pad's
#: coarse mesh with GAMG: step 3 took 44 Newton steps on 1 rank, 134 and a cut on 2; in all
#: 205 Newton steps and 710 Krylov iterations on 1 rank; to 1e-2: 157 and 712; to 1e-3: 127
#: and 703, none stagnating; exact solves: 74). The second also where the Newton steps are
#: solved with ``pc = "pressure_schur"`` (nearly incompressible Taylor-Hood bodies, linear or not):
#: near nu = 0.5 J's residual is dominated by the volumetric part of the error, times the bulk
#: modulus, and a residual reduced by 0.1 leaves the shear part, which decides the contact, far off
#: (the linear wavy block at nu = 0.4999: 12 Newton steps and 329 Krylov iterations at 0.1, 6 and
#: 216 at 1e-3; docs/nearly_incompressible.md Sect. 5).
LINEAR_TOL, HYPERELASTIC_TOL = 0.1, 1e-3

#: The V-cycle on J_r of ``pc = "pressure_schur"``: BoomerAMG with HMIS coarsening and extended
#: interpolation (strong threshold 0.5, as for 3D elasticity). Against BoomerAMG's defaults, the
#: same Newton and Krylov counts in 1.5-1.7x less time (P2 O-ring at nu = 0.4999: 506 s against
#: 841 s; the neo-Hookean block, lev 2: 63 s against 95 s); aggressive coarsening was faster still
#: but lost the robustness in nu (benchmarks/results/nearly_incompressible.md Sect. 9).
PRESSURE_CYCLE = {"pc_type": "hypre", "pc_hypre_type": "boomeramg", "pc_hypre_boomeramg_strong_threshold": 0.5,
                  "pc_hypre_boomeramg_coarsen_type": "HMIS", "pc_hypre_boomeramg_interp_type": "ext+i"}

#: The round-off of the law's variables in the current configuration (``search = "newton"``) in units
#: of ``floor`` gamma max |x| (:meth:`SCDNewtonSolver.stopping_target`): they are differences of
#: positions of size |x| taken through the clipped segments' integrals and the averaged normals. The
#: pressed blocks of tests/test_rotation.py (Coulomb friction, held by it alone) stalled at 4.0-4.7e-7 N,
#: 4.3-5 times floor gamma max |x| = 9.4e-8 N, for 500 Newton steps of their first load step (7 with
#: this factor; docs/finite_strain.md Sect. 14).
POSITION_ROUNDOFF = 10.0
#: Parameters of :class:`SCDNewtonSolver` (also the ``[solver]`` table of a case file).
PARAMETERS = Parameters(
    rtol=Parameter(1e-12, "stop when ||y^(k)|| <= rtol ||y^(0)|| (Sect. 7)", minimum=0.0, maximum=1.0, exclusive=True),
    floor=Parameter(1e-14, "... or when ||y^(k)|| <= floor ||l||, l the load in the shifted variables (A u - l is "
                    "evaluated to about eps ||l||; a hyperelastic f to about eps times its stress terms, "
                    "ContactProblem.force_scale), or <= floor gamma max|u| over the contact rows of the start "
                    "(gamma u to eps of it; 0: off)", minimum=0.0, maximum=1.0),
    atol=Parameter(0.0, "... or when ||y^(k)|| <= atol (N)", minimum=0.0),
    max_iterations=Parameter(100, "Newton iterations before giving up", type=int, minimum=1),
    stall_iterations=Parameter(None, "a solve whose ||y^|| has not fallen to stall_factor of its value this many "
                               "Newton steps before has stalled (diverged_stalled); None: never (a load path that "
                               "relaxes past limit points takes 20)", type=int, minimum=1, optional=True),
    stall_factor=Parameter(0.5, "the fraction in stall_iterations' test (0.5: ||y^|| has not halved)", minimum=0.0,
                           maximum=1.0, exclusive=True),
    tol=Parameter(None, "relative residual reduction of the inner Krylov solve (tol, Sect. 7); None: "
                  f"{LINEAR_TOL:g} (Sect. 7) for linear elasticity, {HYPERELASTIC_TOL:g} for a hyperelastic body "
                  "or pc = 'pressure_schur'",
                  minimum=0.0, maximum=1.0, exclusive=True, optional=True),
    tol_rule=Parameter("local", "Krylov tolerance per step: tol in every step (Sect. 7), or tol until no contact "
                       "node changes its kind, then Eisenstat-Walker (choice 2)", type=str,
                       choices=("constant", "local")),
    gamma=Parameter(None, "gamma of the approximation step (6.17) (N/m); None: set by gamma_rule",
                    minimum=0.0, exclusive=True, optional=True),
    gamma_rule=Parameter("auto", "gamma when not given: largest diagonal entry of A at the contact dofs, each "
                         "contact node's own largest diagonal entry, the first unless the contact nodes' diagonals "
                         f"span more than {GRADED_RANGE:g}x (auto), or the power-iteration estimate of lambda_max(A) "
                         "of Sect. 7", type=str, choices=("auto", "contact_diagonal", "nodal_diagonal", "power")),
    approximation=Parameter("stick_reversed", "approximation step: (6.17), or (6.17) with the nodes whose slip "
                            "reversed moved to the sticking branch", type=str,
                            choices=("forward_backward", "stick_reversed")),
    power_iterations=Parameter(5, "power iterations for lambda_max(A) (gamma_rule 'power')", type=int, minimum=1),
    state_tol=Parameter(0.0, "weak-state tolerance relative to max |gamma u - (A u - l)| at the contact nodes "
                        "(0: weak states only at exact zeros)", minimum=0.0),
    eliminate_fixed_rows=Parameter(True, "solve the identity rows (sticking, normal contact rows) exactly", type=bool),
    max_line_search=Parameter(20, "step sizes tried by the line search before it fails", type=int, minimum=1),
    pc=Parameter(None, "Newton-step solver; None: 'pressure_schur' where a quadratic body has the nodal pressure "
                 "(the Taylor-Hood pair, whose Newton steps GAMG does not solve at nu near 0.5), else 'gamg'",
                 type=str, choices=tuple(NEWTON_STEP_SOLVERS), optional=True),
    mixed=Parameter(True, "hyperelastic bodies with the nodal pressure: Newton's method on the displacements and "
                    "the nodal volume ratios, their constraint linearised (docs/nearly_incompressible.md, Sect. 7); "
                    "false: on the displacements with the volume ratios condensed", type=bool),
    reuse_pc=Parameter(True, "multigrid: coarse operators updated by the contact rows' change instead of a new "
                       "set-up; other preconditioners: kept while no contact node changes its kind", type=bool),
    pc_rebuild_iterations=Parameter(10, "multigrid with reuse_pc and smoothed aggregation: a new set-up (new "
                                    "interpolation) after a Krylov solve that took more iterations than this",
                                    type=int, minimum=1),
)


def line_search_steps(count: int) -> np.ndarray:
    """Step sizes 1, 1/2, 1/4, 1/8, 1/32, 1/128, 0.1/128, 0.01/128, ... of Sect. 7."""
    head = np.array([1.0, 0.5, 0.25, 0.125, 1.0 / 32, 1.0 / 128])
    tail = (1.0 / 128) * 10.0 ** -np.arange(1, max(count - len(head), 0) + 1)
    return np.concatenate([head, tail])[:count]


@dataclasses.dataclass
class GraphPoint:
    """The approximation step's point (v, z) of gph Q~ at the owned contact nodes.

    Attributes:
        norm: ||y^|| = sqrt(gamma^2 + 1) ||u - d^|| (N), the accuracy measure of every
            contact solver here.
        v, z: (m, 3) graph points in the nodes' frames; z = (g, theta), theta <= 0.
    """

    norm: float
    v: np.ndarray
    z: np.ndarray


@dataclasses.dataclass(kw_only=True)
class SCDNewtonResult(Result):
    """Outcome of :meth:`SCDNewtonSolver.solve`; ``inner_iterations`` are Krylov iterations.

    Attributes:
        gamma: gamma of (6.17) used (N/m).
        target: ||y^|| at which it stops (N): max(rtol ||y^(0)||, floor ||l||, atol) or
            the caller's ``atol`` of :meth:`SCDNewtonSolver.solve`.
        states: :class:`~contactqvi.contact.nodal.State` of each owned contact node
            at the last approximation step.
        normal_force: lambda = -theta >= 0 per owned contact node (N).
        friction_force: (m, 2) tangential force of the obstacle on the body in the
            nodes' frames (N).
        switches: how often each owned contact node changed its state from one Newton
            iterate to the next in this solve.
        switched_from: each node's state before its last change (its state where it never changed).
    """

    gamma: float
    target: float
    states: np.ndarray
    normal_force: np.ndarray
    friction_force: np.ndarray
    forcing: Forcing | None = None
    switches: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0, np.int32))
    switched_from: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0, np.int8))

    def record_states(self, states: np.ndarray) -> None:
        """Take the Newton iterate's contact ``states`` (Table 1), counting each node's changes."""
        if len(self.states) != len(states):  # the first iterate (or new contact nodes)
            self.switches, self.switched_from = np.zeros(len(states), np.int32), states.copy()
        else:
            changed = states != self.states
            self.switches[changed] += 1
            self.switched_from[changed] = self.states[changed]
        self.states = states


@dataclasses.dataclass(frozen=True)
class Forcing:
    """What :meth:`SCDNewtonSolver.forcing_term` needs of the Newton iterate before the present one:
    its ||y^||, whether the step from it was a full one (``settled`` if also the present kinds equal
    ``kinds``), and ``kinds``. Kept across a search inside the Newton iteration: a solve that ended
    for one (``search_again``) hands it to the solve that goes on from the same iterate on the new
    facet pairs (:meth:`SCDNewtonSolver.solve`'s ``forcing``), the step before the search included."""

    norm: float
    full: bool
    kinds: np.ndarray


@dataclasses.dataclass(eq=False)
class GammaVectors(PETScOwner):
    """gamma of (6.17) per dof (gamma_i at contact node i, the largest elsewhere), as vectors.

    Attributes:
        gamma: gamma per dof (the scaling of y1^ = Gamma y2^ in the Newton system).
        inverse: 1/gamma per dof (the approximation step's u - r/gamma).
        weight: sqrt(gamma^2 + 1)/sqrt(gamma_max^2 + 1) per dof (the norm of y^).
    """

    gamma: PETSc.Vec
    inverse: PETSc.Vec
    weight: PETSc.Vec

    def petsc_objects(self) -> list[PETSc.Vec]:
        return [self.gamma, self.inverse, self.weight]


@dataclasses.dataclass(eq=False)
class WorkVectors(VectorSet):
    """Vectors of A's layout that carry one Newton iteration from step to step.

    Created once per :class:`SCDNewtonSolver` and reused by every iteration of every
    solve; freed by the solver's :meth:`~SCDNewtonSolver.destroy`.

    Attributes:
        r: r = A u - l at the iterate u: from the start of a solve (and ``r_trial`` of
            each accepted step) to the line search, which moves along r + alpha A du.
        dhat: d^ of (6.17) at the iterate: from the approximation step through
            :meth:`~SCDNewtonSolver.classify` (reversed slips moved) to the Newton system.
        y2: y2^ = u - d^: scratch of the approximation step (the norm of y^) and of the
            Newton system (its right-hand side).
        rhs: right-hand side of (5.4), fixed rows eliminated: Newton system -> linear solve.
        du: the Newton direction: exact on the eliminated rows (Newton system), the
            Krylov solution elsewhere (linear solve) -> line search.
        Adu: A du, within the line search.
        u_trial: the line search's trial point u + alpha du -> u when accepted.
        r_trial: its residual r + alpha A du -> r when accepted; scratch of
            :meth:`~SCDNewtonSolver.residual`.
        d_trial: its d^ -> ``dhat`` when accepted; scratch of :meth:`~SCDNewtonSolver.residual`.
        displacement: u - d of a linear f's iterate: scratch of :meth:`~SCDNewtonSolver.smooth_part`.
    """

    r: PETSc.Vec
    dhat: PETSc.Vec
    y2: PETSc.Vec
    rhs: PETSc.Vec
    du: PETSc.Vec
    Adu: PETSc.Vec
    u_trial: PETSc.Vec
    r_trial: PETSc.Vec
    d_trial: PETSc.Vec
    displacement: PETSc.Vec


class SCDNewtonSolver(PETScOwner):
    """SCD semismooth* Newton solver for :class:`ContactProblem` (seed 000, Sects. 4-7).

    Owns the Newton matrix, the Newton-step linear solver and the work vectors;
    ``solve`` can be called repeatedly (load steps) and the object must be freed with
    :meth:`destroy` (or used in a ``with`` block).

    Args:
        problem: the assembled GE.
        parameters: overrides of :data:`PARAMETERS`.
        prefix: PETSc options prefix of the Newton-step KSP; any ``-{prefix}ksp_*``
            or ``-{prefix}pc_*`` option overrides the preset chosen by ``pc``.
        step_solver: a Newton-step solver to take over (and own) instead of a new one:
            one released by the solver of this problem before a search
            (:meth:`release_step_solver`), its levels updated for the searched A.

    Attributes:
        parameters, prefix: the checked parameters and the options prefix.
        step_solver: the linear solver of the Newton steps (KSP and preconditioner reuse).
    """

    def __init__(self, problem: ContactProblem, parameters: dict | None = None, prefix: str = "coulomb_",
                 step_solver: NewtonStepSolver | None = None):
        self.problem = problem
        self.parameters = p = checked_parameters(problem, parameters)
        self.prefix = prefix
        A = problem.A
        self._newton = NewtonMatrix(A, problem.contact_blk)
        self._near_nullspace = problem.near_nullspace()  # for AMG; the rows of J off the contact are A's
        self._newton.J.setNearNullSpace(self._near_nullspace)
        self.step_solver = newton_step_solver(problem, p, prefix) if step_solver is None else step_solver
        self._steps = line_search_steps(p["max_line_search"])
        self._gamma = p["gamma"]
        self._gamma_nodes: np.ndarray | None = None  # gamma_i per owned contact node
        self._gamma_dofs: GammaVectors | None = None  # made at the first use of gamma
        self._rhs_ratio = 1.0  # of the last Newton system: ||rhs of (5.4)|| / ||rhs with the rows eliminated||
        self._eliminated = np.empty(0, dtype=np.int32)  # of the last Newton system: owned local rows
        self._exact: tuple[np.ndarray, np.ndarray] | None = None  # ... and its rows with known du, du there
        self._work = WorkVectors.create(A)
        self._carried: NodalPressure | None = None  # the mixed method's nodal volume, during a solve
        self._constraint: np.ndarray | None = None  # its U''(theta) (Jbar - theta) at the Newton step's iterate
        self._missed: np.ndarray | None = None  # and the linearised constraint's residual the step's solve left

    def petsc_objects(self) -> list[typing.Any]:
        objects = [self.step_solver, self._newton, self._near_nullspace, self._work, self._gamma_dofs]
        return [obj for obj in objects if obj is not None]

    def release_step_solver(self) -> NewtonStepSolver | None:
        """Restore A and hand the Newton-step solver over to the caller (who then owns it),
        if it keeps multigrid levels (:attr:`NewtonStepSolver.keeps_levels`), updated to A;
        else None (it stays with this solver). This solver can then only be destroyed.

        Before a contact search (:func:`~contactqvi.contact.load_path.solve_load_path`):
        the searched A changes near the interfaces only, and updating the levels costs
        a fraction of a new set-up (two-body Hertz, docs/bodies.md).
        """
        if not self.step_solver.keeps_levels:
            return None
        undone = self._newton.undone()
        self._newton.restore()
        self.step_solver.update_operator(undone, grown=False)
        undone.destroy()
        step_solver, self.step_solver = self.step_solver, None
        return step_solver

    @property
    def ksp(self) -> PETSc.KSP:
        """The Krylov solver of the Newton steps (:attr:`step_solver`'s)."""
        return self.step_solver.ksp

    @property
    def gamma(self) -> float:
        """gamma of (6.17) (the largest gamma_i when each node has its own)."""
        if self._gamma_dofs is None:
            self._set_gamma()
        return self._gamma

    @property
    def gamma_nodes(self) -> np.ndarray:
        """gamma_i of each owned contact node (all equal unless the rule is ``nodal_diagonal``)."""
        if self._gamma_dofs is None:
            self._set_gamma()
        return self._gamma_nodes

    def _set_gamma(self) -> None:
        """gamma given or by ``gamma_rule`` (:meth:`_gamma_rule`), and its per-dof vectors: gamma,
        1/gamma and the norm weight sqrt(gamma^2 + 1)/sqrt(gamma_max^2 + 1).

        * ``power`` (Sect. 7): five power iterations on A, a lower bound of lambda_max(A)
          (about 0.8 lambda_max(A) here), i.e. the step 1/L of a forward-backward method.
        * ``contact_diagonal``: max_i A_ii over the dofs of the contact nodes, the
          stiffness of one contact node with its neighbours held, about lambda_max(A)/4.5
          on the Q1 meshes of Sect. 7 (both scale like E h). gamma only acts at the contact
          nodes (the Newton rows of the other dofs are those of A whatever gamma is: (5.4),
          Q^R = 0); there it is the stiffness of the trial force w = gamma u - (A u - l) of
          the resolvent (6.8)/(6.7), the augmentation parameter of an augmented-Lagrangian
          (Alart-Curnier type) formulation. A node whose slip a Newton step drove through
          zero by s (the sliding rows prescribe the friction force in the old slip
          direction) is classified as sticking by the next approximation step only if
          gamma s < 2 F lambda: with gamma = lambda_max(A)
          almost every reversed node slides backwards and the slip direction ping-pongs
          for several damped steps (docs/coulomb.md, "Why the localisation phase was
          long"). Exact solves, lev 3-5, six cases: 14.7 -> 9.3 Newton steps on average;
          GAMG, tol 0.1: 19.8 -> 14.3.
        * ``nodal_diagonal``: gamma_i = the largest diagonal entry of A at contact node i,
          Gamma = diag(gamma_i) instead of gamma I in (6.17):
          d^ = (Gamma + Q)^{-1}(Gamma u - (A u - l)), y^ = (Gamma (u - d^), u - d^). Q is
          nodal, so the resolvent, the states and the SCD bases stay nodal with
          gamma -> gamma_i. On a graded mesh one gamma fitted to the coarsest contact node
          is far too stiff for the refined ones. Off the contact nodes gamma is the
          contact maximum (it does not enter their Newton rows).
        """
        A, comm, blk = self.problem.A, self.problem.comm, self.problem.contact_blk
        diagonal = A.getDiagonal()
        nodal = diagonal.array.reshape(-1, 3)[blk].max(axis=1, initial=0.0)
        rule = self._gamma_rule(nodal)
        if self._gamma is None and rule == "power":
            x0 = _coordinate_noise(self.problem)
            self._gamma = power_iteration(A, x0, self.parameters["power_iterations"])
            x0.destroy()
        elif self._gamma is None:
            self._gamma = comm.allreduce(float(nodal.max(initial=0.0)), op=MPI.MAX)
        per_node = self.parameters["gamma"] is None and rule == "nodal_diagonal"
        self._gamma_nodes = nodal if per_node else np.full(len(blk), self._gamma)
        gamma = diagonal  # reused: gamma per dof
        gamma.set(self._gamma)
        gamma.array.reshape(-1, 3)[blk] = self._gamma_nodes[:, None]
        inverse, weight = gamma.duplicate(), gamma.duplicate()
        inverse.array[:] = 1.0 / gamma.array
        weight.array[:] = np.sqrt(gamma.array**2 + 1.0) / np.sqrt(self._gamma**2 + 1.0)
        self._gamma_dofs = GammaVectors(gamma, inverse, weight)

    def _gamma_rule(self, nodal: np.ndarray) -> str:
        """The parameter ``gamma_rule``, with ``auto`` resolved from the contact nodes' diagonals ``nodal``.

        ``auto``: ``nodal_diagonal`` on a graded contact surface (diagonals spanning
        more than :data:`GRADED_RANGE`), else ``contact_diagonal``. On the paper's
        uniform meshes ``nodal_diagonal`` costs 246 instead of 228 Newton steps (exact
        solves, lev 3-5, six cases; the edge and corner nodes get a quarter of the
        gamma); on the graded Hertz mesh (medium, GAMG) it takes 8/8/8/8 Newton steps
        against 10/12/11/12.
        """
        rule, comm = self.parameters["gamma_rule"], self.problem.comm
        if rule != "auto":
            return rule
        low = comm.allreduce(float(nodal.min(initial=np.inf)), op=MPI.MIN)
        high = comm.allreduce(float(nodal.max(initial=0.0)), op=MPI.MAX)
        rule = "nodal_diagonal" if high > GRADED_RANGE * low else "contact_diagonal"
        logger.info("gamma_rule auto: contact diagonals span %.3g x: %s", high / low, rule)
        return rule

    # -- step 1: approximation step -------------------------------------------------
    def approximation_step(self, r: PETSc.Vec, u: PETSc.Vec, dhat: PETSc.Vec) -> GraphPoint:
        """Approximation step (6.17) at u, given r = A u - l; writes d^ into ``dhat``.

        The forward-backward point d^ = (Gamma + Q)^{-1}(Gamma u - (A u - l)) (Gamma = gamma I
        unless ``nodal_diagonal``); ||y^|| = ||(Gamma^2 + I)^{1/2} (u - d^)||, i.e.
        sqrt(gamma^2 + 1) ||u - d^|| for one gamma.
        """
        gamma, blk = self.gamma_nodes[:, None], self.problem.contact_blk
        w = gamma * u.array.reshape(-1, 3)[blk] - r.array.reshape(-1, 3)[blk]
        v, z = resolvent(w, gamma[:, 0], self.problem.law)
        diff = self._work.y2
        self._difference(r, u, GraphPoint(0.0, v, z), diff)
        dhat.waxpy(-1.0, diff, u)  # non-contact dofs: (gamma I)^{-1}(gamma u - r) = u - r/gamma
        dhat.array.reshape(-1, 3)[blk] = v
        diff.pointwiseMult(diff, self._gamma_dofs.weight)
        norm = diff.norm()
        if self._carried is not None:  # the mixed method's constraint rows, as r's off the contact
            norm = float(np.hypot(norm, self._carried.constraint_norm() / self.gamma))
        return GraphPoint(float(np.sqrt(self.gamma**2 + 1.0) * norm), v, z)

    def _difference(self, r: PETSc.Vec, u: PETSc.Vec, point: GraphPoint, out: PETSc.Vec) -> None:
        """y2^ = u - d^ of the graph point ``point`` at u (r = f(u)) into ``out``, without subtracting
        u and d^: where gamma |u| is far above the forces (a stiff body's slip increment, a travel)
        their difference is round-off of |u|, which y1^ = Gamma y2^ multiplies by gamma. Off the
        contact nodes y2^ = r / gamma; at them, from gamma u - r = gamma v + z, y2^ = (r + z) / gamma
        where v does not vanish and u itself where it does (the sticking and touching components,
        and those the approximation step moved to v_12 = 0)."""
        blk = self.problem.contact_blk
        out.pointwiseMult(self._gamma_dofs.inverse, r)
        nodal = (r.array_r.reshape(-1, 3)[blk] + point.z) / self.gamma_nodes[:, None]
        out.array.reshape(-1, 3)[blk] = np.where(point.v == 0.0, u.array_r.reshape(-1, 3)[blk], nodal)

    def _graph_point(self, u: PETSc.Vec, r: PETSc.Vec, dhat: PETSc.Vec) -> GraphPoint:
        """r = f(u) into ``r``, then the approximation step at u (d^ into ``dhat``)."""
        self.smooth_part(u, r)
        return self.approximation_step(r, u, dhat)

    def smooth_part(self, u: PETSc.Vec, r: PETSc.Vec) -> None:
        """f(u) of 0 in f(u) + Q(u) into ``r``: A u - l (6.3), evaluated as A (u - d) - (l - A d)
        (:attr:`~contactqvi.contact.problem.ContactProblem.unshifted`), or the residual of a
        hyperelastic body (:mod:`contactqvi.contact.hyperelastic`; Sect. 5 takes any smooth f)."""
        problem = self.problem
        if problem.hyperelastic is not None:
            problem.residual(u, r)
            return
        x = self._work.displacement
        x.waxpy(-1.0, problem.shift, u)
        self._newton.mult_stiffness(x, r)
        r.axpy(-1.0, problem.unshifted)

    def linearise(self, u: PETSc.Vec, k: int) -> None:
        """grad f at u of (5.4) into A's storage when f is nonlinear (a hyperelastic body):
        the tangent at the iterate of Newton step ``k``, whose rows the Newton matrix then
        changes. A linear f has grad f = A: nothing to do.

        The preconditioner is set up on the first J of each solve (k = 0) and lagged within
        it (PETSc's ``-snes_lag_preconditioner -2``): a multigrid keeps its interpolations and
        coarse operators, updated only by the change of J's rows at the contact (the fine
        level and its smoother take each J whole), and the Krylov method solves each J to
        ``tol``. Within a load step the tangent changes by the step's increment. A new set-up
        at every Newton step took 38 % of the two-body Hertz fine mesh's neo-Hookean path
        (benchmarks/results/finite_strain_performance.md)."""
        if self.problem.hyperelastic is None:
            return
        self.problem.tangent(u)
        self._newton.refresh(lagged=k > 0)
        if self.problem.follows_geometry:  # J = D (A + Gamma T) + U (dv/du~) T (docs/finite_strain.md, Sect. 13)
            self._newton.set_geometric(*self.problem.geometric_rows(u))
        if k == 0:
            self.step_solver.operator_replaced()

    def residual(self, u: PETSc.Vec) -> GraphPoint:
        """The graph point of (6.17) at u alone: ||y^|| is the accuracy measure."""
        return self._graph_point(u, self._work.r_trial, self._work.d_trial)

    def _carried_volume(self) -> NodalPressure | None:
        """The nodal volume ratios of the mixed method (parameter ``mixed``), or None."""
        system = self.problem.hyperelastic
        if not self.parameters["mixed"] or system is None or system.volumetric is None:
            return None
        return system.volumetric.nodal

    def _constraint_force(self, u: PETSc.Vec) -> PETSc.Vec:
        """The mixed method's g = B^T U''(theta) (Jbar - theta) at the iterate u, in the solver's
        variables (the condensed residual's excess over r; into the scratch ``r_trial``): the
        linearised constraint's share of the Newton step's right-hand side
        (docs/nearly_incompressible.md, Sect. 7)."""
        w = self._work
        self.problem.residual(u, w.r_trial, condensed=True)
        w.r_trial.axpy(-1.0, w.r)
        return w.r_trial

    def classify(self, point: GraphPoint, v_previous: np.ndarray | None) -> tuple[np.ndarray, np.ndarray, int]:
        """Normal and tangential kinds of the graph point (Table 1), in place on ``point``.

        Weak states: a quantity counts as zero below ``state_tol`` times the largest trial
        force max |w|; the default 0 means exact zeros only. A relative 1e-10 (before) is
        relative to gamma times the largest gap on a large contact surface (1.5e12 N on
        the Hertz meshes): the nodes at the edge of the contact area, with forces below
        150 N, became weak and the Hertz steps stalled (medium mesh, GAMG: 100 Newton
        steps at step 3). On the paper's bodies no node was ever weak with 1e-10.

        With ``approximation = stick_reversed`` (default) and a previous slip
        ``v_previous``, every sliding node with a slip bound b > 0 whose slip v12 points
        against the previous iterate's is moved to the point of gph Q~ with v12 = 0 and
        the same force (:func:`~contactqvi.contact.nodal.stick_reversed_slip`), so its
        Newton rows are the sticking ones, and d^ follows. Algorithm 1 admits any graph
        point that satisfies (4.2), and this one does near the solution, so Theorem 4.4
        holds; the line search still measures the residual of (6.17). The Newton step of
        a sliding node prescribes the friction force in the current slip direction; where
        the solution sticks it drives the slip through zero, the next step slides the
        other way, and the line search damps this for several steps (lev 5 d3/L2, exact
        solves: 4 damped steps in a row). Six cases (docs/coulomb.md, "Reversed slips"):
        GAMG, tol 0.1, lev 3-7: 433 -> 382 Newton steps; exact solves, lev 3-5: d3
        10-13 -> 7-9 steps, d1 and d2 +-1. ``forward_backward``: (6.17) alone.

        Returns ``(normal, tangential, number of moved nodes)``.
        """
        comm, law = self.problem.comm, self.problem.law
        gamma = self.gamma_nodes
        w_scale = comm.allreduce(float(np.abs(gamma[:, None] * point.v + point.z).max(initial=0.0)), op=MPI.MAX)
        tol = self.parameters["state_tol"] * w_scale
        normal, tangential = classify(point.v, point.z, gamma, law, tol)
        if self.parameters["approximation"] != "stick_reversed" or v_previous is None:
            return normal, tangential, 0
        point.v, tangential, moved = stick_reversed_slip(point.v, point.z, tangential, v_previous, law, tol)
        # y2^ = u - d^ changes at the moved nodes; the right-hand side takes y1^ = gamma y2^, which is then
        # wrong only in their tangential components, where the columns of W*^T vanish.
        self._work.dhat.array.reshape(-1, 3)[self.problem.contact_blk] = point.v
        return normal, tangential, comm.allreduce(int(moved.sum()), op=MPI.SUM)

    # -- step 2: generalized derivative ----------------------------------------------
    def generalized_derivative(
        self, point: GraphPoint, normal: np.ndarray, tangential: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Blocks (W*^T, U*^T) of an element of S*Q~ at the graph point (Cor. 6.8)."""
        return scd_adjoint_blocks(point.v, point.z, normal, tangential, self.gamma_nodes, self.problem.law)

    # -- step 3: reduced Newton system -----------------------------------------------
    def newton_system(self, Wt: np.ndarray, Ut: np.ndarray, u: PETSc.Vec, y2: PETSc.Vec) -> PETSc.Mat:
        """Matrix J = D A + U and right-hand side -(D y1^ + U y2^) of (5.4), fixed rows eliminated;
        -(D (y1^ + g) + U y2^) in the mixed method, g its linearised constraint's force
        (:meth:`_constraint_force`; docs/nearly_incompressible.md, Sect. 7). ``y2`` is y2^ = u - d^ at
        the iterate u (:meth:`_difference`), y1^ = Gamma y2^.

        The right-hand side goes to the work vector ``rhs`` and the eliminated rows'
        exact values to ``du``; returns J. The prescribed rows of a hyperelastic f are identity
        rows, du = l - u there, and those exact values replace the Krylov solve's
        (:meth:`linear_solve`; docs/finite_strain.md, Sect. 18: a roller on a contact node, whose
        value the physical displacement does not reset, solved to the Krylov tolerance of the
        force rows held the rubber pad's Newton steps to a linear rate of 0.2). Keeps ||rhs of (5.4)|| / ||rhs|| for the
        Krylov test (:meth:`~contactqvi.contact.newton_step_solver.NewtonStepSolver.krylov_rtol`).
        """
        w = self._work
        self._newton.set_blocks(Wt, Ut)
        self._newton.mult_blocks(y2, w.rhs, self._gamma_dofs.gamma)  # y1^ = Gamma y2^
        self._constraint = None
        if self._carried is not None:
            self._newton.mult_add_D(self._constraint_force(u), w.rhs)
            self._constraint = self._carried.constraint_pressure()
        w.rhs.scale(-1.0)
        w.du.set(0.0)
        self._rhs_ratio = 1.0
        self._eliminated = np.empty(0, dtype=np.int32)
        self._exact = None
        if self.problem.hyperelastic is not None:  # its prescribed rows are identity rows: du = l - u there
            rows = self.problem.hyperelastic.prescribed
            self._exact = rows, self.problem.load.array_r[rows] - u.array_r[rows]
        if not self.parameters["eliminate_fixed_rows"]:
            return self._newton.assemble()
        fixed = ~np.any(Wt, axis=2)  # (m, 3): W*^T rows that vanish, pure (gamma-scaled) identity rows
        self._eliminated = fixed_loc = self._newton.fixed_dofs(fixed)
        gamma_fixed = self._gamma_dofs.gamma.array[fixed_loc]
        w.du.array[fixed_loc] = w.rhs.array[fixed_loc] / gamma_fixed
        J = self._newton.assemble(fixed, self.gamma, w.du, w.rhs)
        # The eliminated rows are gamma I with the largest gamma, so rhs holds gamma du there, not gamma_i du.
        excess = float(np.sum((self.gamma**2 - gamma_fixed**2) * w.du.array[fixed_loc] ** 2))
        excess = self.problem.comm.allreduce(excess, op=MPI.SUM)
        if excess > 0.0:
            norm = w.rhs.norm()
            self._rhs_ratio = float(np.sqrt(max(norm**2 - excess, 0.0)) / norm)
        return J

    # -- step 4: linear solve ----------------------------------------------------------
    def forcing_term(self, norm: float, previous_norm: float | None, settled: bool, target: float) -> float:
        """Relative tolerance of this step's Krylov solve.

        ``tol`` of Sect. 7 while the contact nodes still change their kinds (the
        localisation phase, where tighter solves buy little: Table 4). With
        ``tol_rule = local``, once a full step left every kind unchanged (``settled``),
        the method is in the local phase of Theorem 4.4 and Eisenstat and Walker's
        choice 2 (gamma = 0.9, alpha = 2) keeps it superlinear:
        eta = min(tol, max(0.9 (||y^k|| / ||y^(k-1)||)^2, 0.5 target / ||y^k||)),
        never tighter than what the last step needs to reach the solver's own stopping
        target (the parameters' test; a caller's looser ``atol`` does not loosen it). Measured
        (docs/coulomb.md): lev 5-7, Newton steps 14 -> 11, 13 -> 10, 13 -> 9 at equal
        or fewer Krylov iterations.
        """
        p = self.parameters
        if p["tol_rule"] == "constant" or not settled or previous_norm is None:
            return p["tol"]
        return min(p["tol"], max(0.9 * (norm / previous_norm) ** 2, 0.5 * target / norm))

    def linear_solve(self, J: PETSc.Mat, kinds: np.ndarray, tol: float) -> int:
        """Inexact solve J du = rhs of the last :meth:`newton_system` to ``tol`` (Sect. 7) by
        :attr:`step_solver`, from and into the work vector ``du``; returns the KSP's converged reason."""
        w = self._work
        if self.step_solver.pressure is not None:
            system = self.problem.hyperelastic
            self.step_solver.pressure.set_mass(None if system is None else system.mass_term())
            self.step_solver.pressure.update(J, self._newton, self.problem.to_global, self._eliminated)
            self.step_solver.pressure.set_constraint(self._constraint)
        reason = self.step_solver.solve(J, self._newton.change, kinds, w.rhs, w.du, tol, self._rhs_ratio)
        pressure = self.step_solver.pressure
        self._missed = None if pressure is None or self._constraint is None or self.step_solver.fallback else \
            pressure.missed
        if self._exact is not None:
            rows, values = self._exact
            w.du.array[rows] = values
        return reason

    # -- step 5: globalisation -----------------------------------------------------------
    def line_search(self, u: PETSc.Vec, norm: float, k: int) -> tuple[float | None, GraphPoint | None]:
        """Non-monotone line search of Sect. 7 along du from u, with r(u + a du) = r + a A du
        for a linear f, else f evaluated at the trial point (a trial where f is undefined, an
        inverted element, gives NaN and is rejected like any other).

        Accepts the first step size alpha with ||y^(u + alpha du)|| <= (1 + 0.1/(k+1) - 0.1 alpha) ||y^(u)||
        and leaves the trial point in the work vectors ``u_trial``, ``r_trial``, ``d_trial``.
        Returns ``(alpha, graph point)``, or ``(None, None)`` when no step size is accepted.
        """
        w, linear, follows = self._work, self.problem.hyperelastic is None, self.problem.follows_geometry
        if linear:
            self._newton.mult_stiffness(w.du, w.Adu)
        if follows:
            self.problem.set_search_line(u, w.du)
        bound = 1.0 + 0.1 / (k + 1)
        if self._carried is not None:
            self._carried.start_line(self._missed)
        for alpha in self._steps:
            if self._carried is not None:
                self._carried.set_step(float(alpha))
            if follows:  # the geometry at the trial point, the solver's variables there (v at the contact)
                self.problem.follow_line(float(alpha), w.u_trial)
            else:
                w.u_trial.waxpy(alpha, w.du, u)
            if linear:
                w.r_trial.waxpy(alpha, w.Adu, w.r)
            else:
                self.smooth_part(w.u_trial, w.r_trial)
            point = self.approximation_step(w.r_trial, w.u_trial, w.d_trial)
            if point.norm <= (bound - 0.1 * alpha) * norm:
                if self._carried is not None:
                    self._carried.end_line()
                return float(alpha), point
        return None, None

    def _accept_trial(self, u: PETSc.Vec) -> None:
        """The line search's trial point becomes the iterate: u, r and d^ from the trial vectors."""
        w = self._work
        w.u_trial.copy(u)
        w.r_trial.copy(w.r)
        w.d_trial.copy(w.dhat)

    # -- the method ----------------------------------------------------------------------
    def stopping_target(self, norm0: float, variables: float = 0.0) -> float:
        """The solver's own stopping target max(rtol ||y^(0)||, floor ||l||, atol, floor gamma s) (N),
        s the larger of ``variables`` (the largest |u| at the contact rows of the start) and the
        positions' size of pairs searched ``"newton"``.

        Seed 000, Sect. 7, stops at ||y^(k)|| <= 1e-12 ||y^(0)|| from u0 = 0; that test is
        kept (``rtol``), so Tables 2-4 keep their counts. It is relative to the start,
        and some starts put it below what floating point resolves: off the contact nodes
        y^ is the residual A u - l, a difference of terms of size ||A d|| (l = lambda l~ + A d
        is the load in the shifted variables), so ||y^|| cannot be driven much below
        eps ||l||. ``floor`` = 1e-14 (45 eps) keeps every start above round-off and
        stays 100 times below the paper's target from u0 = 0 (where ||y^(0)|| is about
        ||l||), so it never acts there. Without it the first step of cases/hertz.toml
        (gaps of metres: ||l|| = 1.0e12 N, ||y^(0)|| = 5.1e5 N) stalled on round-off for
        up to 30 Newton steps with exact solves and took 53, 31 and 100 (failed) steps
        with GAMG on the medium mesh (now 7-8), and a step in which nothing touches and
        nothing is loaded never converged (now at k = 0): docs/coulomb.md, "The stopping test".
        A hyperelastic f is a difference of stress terms of size mu |F| that cancel to
        mu |grad u|, so its floor is relative to their size
        (:meth:`~contactqvi.contact.problem.ContactProblem.force_scale`, docs/finite_strain.md).
        With the geometry in the current configuration (``search = "newton"``) the law's
        variables are differences of positions, resolved to a few hundred eps times their size,
        which y1^ multiplies by gamma: the floor is also :data:`POSITION_ROUNDOFF` ``floor`` gamma
        max |x| (the shipped ironing stalled at 1.4e-5 N, 1e-11 of its start, against a target of
        9e-6 N; docs/finite_strain.md, Sect. 14). The same holds for the contact variables u
        themselves wherever gamma u is far larger than the forces, as with a large slip increment
        of a stiff body: a dynamic time step of steel blocks sliding 6 cm under gravity alone
        stalled at 1.4e-7 N, 6e-12 of its start, against a target of 2.3e-8 N (docs/dynamics.md,
        Sect. 5).
        """
        p = self.parameters
        geometric = p["floor"] * self.gamma * max(POSITION_ROUNDOFF * self.problem.position_scale(), variables)
        return max(p["rtol"] * norm0, p["floor"] * self.problem.force_scale(), p["atol"], geometric)

    def _stopping_status(self, norm: float, norm0: float, target: float, k: int,
                         stop: typing.Callable[[], bool] | None, history: list[dict]) -> Status | None:  # fmt: skip
        """Why the iteration ends before Newton step k (converged, out of iterations, stalled over
        ``stall_iterations`` steps of ``history``, f undefined at the iterate, or ``stop()``), or
        None. The line search accepts finite residuals only, so an undefined f (an inverted
        element of a hyperelastic body) is the initial guess's."""
        if not np.isfinite(norm):
            return Status.DIVERGED_FUNCTION_DOMAIN
        if norm <= target:
            return Status.CONVERGED_RTOL if norm <= self.parameters["rtol"] * norm0 else Status.CONVERGED_ATOL
        if k == self.parameters["max_iterations"]:
            return Status.DIVERGED_MAX_IT
        window, factor = self.parameters["stall_iterations"], self.parameters["stall_factor"]
        if window is not None and k >= window and norm > factor * history[k - window]["residual"]:
            return Status.DIVERGED_STALLED
        if stop is not None and stop():
            return Status.INTERRUPTED
        return None

    def solve(self, u: PETSc.Vec, atol: float = 0.0, stop: typing.Callable[[], bool] | None = None,
              search: typing.Callable[[PETSc.Vec], bool] | None = None,
              volume_start: fem.Function | None = None, forcing: Forcing | None = None) -> SCDNewtonResult:
        """Run Algorithm 1 from the initial guess ``u`` (shifted displacements), in place.

        Stops at ||y^|| <= max(rtol ||y^(0)||, floor ||l||, atol) (:meth:`stopping_target`),
        or at the caller's ``atol`` (N) of this solve if larger: the accuracy of an earlier
        load step, or of an outer iteration (the Tresca fixed point). The Newton matrices are
        written into the storage of ``problem.A``
        (:class:`~contactqvi.contact.newton_matrix.NewtonMatrix`); it holds A again on return.
        ``stop()`` (collective, the same answer on every rank) is asked before each Newton
        step; when it is true the solve ends with status ``interrupted``. ``search(u)``
        (collective) is asked before each Newton step after the first: whether the contact must
        be searched again at the iterate u (a geometry that follows the iterate,
        :mod:`contactqvi.contact.current_geometry`); then the solve ends with status ``search_again``.
        With the mixed method (``mixed``) the nodal volume ratios start at those of the displacement
        ``volume_start`` (global components: a load path's last converged step), or at u's.
        ``forcing``: the :class:`Forcing` of a solve that ended for a search at the iterate ``u``; its
        Krylov tolerance goes on from there (:meth:`forcing_term`) instead of starting at ``tol``.
        """
        self._carried = self._carried_volume()
        try:
            if self._carried is not None:
                self._carried.carry(True, volume_start)
            return self._algorithm_1(u, atol, stop, search, forcing)
        finally:
            if self._carried is not None:
                self._carried.carry(False)
                self._carried = None
            self._newton.restore()

    def _algorithm_1(self, u: PETSc.Vec, atol: float, stop: typing.Callable[[], bool] | None,
                     search: typing.Callable[[PETSc.Vec], bool] | None, forcing: Forcing | None) -> SCDNewtonResult:
        """Algorithm 1 of Sect. 4 (the loop of :meth:`solve`), A's storage left holding J."""
        comm, w = self.problem.comm, self._work
        result = SCDNewtonResult(status=Status.DIVERGED_MAX_IT, iterations=0, gamma=0.0, target=0.0,
                                 states=np.empty(0, np.int8), normal_force=np.empty(0), friction_force=np.empty((0, 2)))
        with result.timings.phase("gamma"):
            result.gamma = self.gamma
        with result.timings.phase("residual"):
            point = self._graph_point(u, w.r, w.dhat)
        norm0 = point.norm
        contact = u.array_r.reshape(-1, 3)[self.problem.contact_blk]
        own_target = self.stopping_target(norm0, comm.allreduce(float(np.abs(contact).max(initial=0.0)), op=MPI.MAX))
        result.target = max(own_target, atol)
        v_previous, last = None, forcing  # of the previous iteration (a solve before a search: its last)
        for k in range(self.parameters["max_iterations"] + 1):
            v_forward_backward = point.v
            normal, tangential, moved = self.classify(point, v_previous)
            v_previous = v_forward_backward
            result.record_states(contact_states(normal, tangential))
            entry = {"k": k, "residual": point.norm, "relative_residual": point.norm / norm0 if norm0 else 0.0,
                     "states": _state_counts(comm, result.states), "reversed": moved}
            result.history.append(entry)
            status = self._stopping_status(point.norm, norm0, result.target, k, stop, result.history)
            if status is None and k > 0 and search is not None and search(u):
                status = Status.SEARCH_AGAIN
            kinds = np.concatenate([normal, tangential])
            settled = last is not None and last.full and comm.allreduce(np.array_equal(kinds, last.kinds), op=MPI.LAND)
            if status is not None:
                result.status = status
                if status == Status.SEARCH_AGAIN:
                    result.forcing = Forcing(last.norm, settled, kinds)
                _log_iteration(entry)
                break
            with result.timings.phase("newton_matrix"):
                self.linearise(u, k)
                self._difference(w.r, u, point, w.y2)
                J = self.newton_system(*self.generalized_derivative(point, normal, tangential), u, w.y2)
            entry["tol"] = self.forcing_term(point.norm, None if last is None else last.norm, settled, own_target)
            with result.timings.phase("linear_solve"):
                reason = self.linear_solve(J, kinds, entry["tol"])
            entry.update(self.step_solver.record())
            result.inner_iterations += entry["krylov_iterations"]
            if reason < 0:
                result.status = Status.DIVERGED_LINEAR_SOLVE
                _log_iteration(entry)
                break
            with result.timings.phase("line_search"):
                alpha, trial = self.line_search(u, point.norm, k)
            entry["alpha"] = alpha
            _log_iteration(entry)
            if trial is None:
                result.status = Status.DIVERGED_LINE_SEARCH
                break
            self._accept_trial(u)
            last, point = Forcing(point.norm, alpha == 1.0, kinds), trial
        result.iterations = len(result.history) - 1
        result.normal_force, result.friction_force = -point.z[:, 2].copy(), -point.z[:, :2].copy()
        return result


def checked_parameters(problem: ContactProblem, parameters: dict | None) -> dict:
    """:data:`PARAMETERS` checked, with the defaults that depend on the problem filled in
    (``tol``: :data:`LINEAR_TOL`, or :data:`HYPERELASTIC_TOL` for hyperelastic bodies and ``pressure_schur``;
    ``pc``: the block preconditioner for the Taylor-Hood pair, docs/nearly_incompressible.md Sect. 5,
    else GAMG)."""
    p = PARAMETERS.check(parameters)
    if p["pc"] is None:
        taylor_hood = problem.averaged_volume is not None and displacement_degree(problem.V) == 2
        p["pc"] = "pressure_schur" if taylor_hood else "gamg"
    if p["tol"] is None:
        loose = problem.hyperelastic is None and p["pc"] != "pressure_schur"
        p["tol"] = LINEAR_TOL if loose else HYPERELASTIC_TOL
    if problem.follows_geometry:  # the rows U (dv/du~) T are no identity rows
        p["eliminate_fixed_rows"] = False
    return p


def newton_step_solver(problem: ContactProblem, parameters: dict, prefix: str) -> NewtonStepSolver:
    """The Newton-step solver of the checked SCD ``parameters`` (``pc``, ``tol``, ``reuse_pc``, ...)
    for ``problem``, with options prefix ``prefix``."""
    p = parameters
    pressure = None
    if p["pc"] == "pressure_schur":
        require(problem.averaged_volume is not None, "pc", "'pressure_schur' preconditions the averaged volume "
                "change: give the nearly incompressible bodies formulation = \"nodal_pressure\"")
        mu = lame_parameters(problem.body.young, problem.body.poisson)[0]
        pressure = PressureSchur(problem.averaged_volume, mu, f"{prefix}pressure_", PRESSURE_CYCLE)
    return NewtonStepSolver(problem.comm, prefix, p["pc"], problem.multigrid_options, rtol=p["tol"],
                            reuse_pc=p["reuse_pc"], rebuild_iterations=p["pc_rebuild_iterations"],
                            initial_guess=p["eliminate_fixed_rows"], pressure=pressure)


def _coordinate_noise(problem: ContactProblem) -> PETSc.Vec:
    """Deterministic pseudo-random start vector built from dof coordinates.

    It is the same function of position on any number of ranks, so the power
    iteration (hence gamma) does not depend on the partition.
    """
    V = problem.V
    n_owned = V.dofmap.index_map.size_local
    x = V.tabulate_dof_coordinates()[:n_owned]
    phase = x @ np.array([12.9898, 78.233, 37.719])
    values = np.sin(phase[:, None] * np.array([1.0, 1.7, 2.3]) + np.array([0.0, 1.1, 2.2])) * 43758.5453
    vec = problem.A.createVecRight()
    vec.array[:] = (values - np.floor(values) - 0.5).ravel()
    return vec


def _state_counts(comm: MPI.Comm, states: np.ndarray) -> dict[str, int]:
    """Global number of contact nodes per :class:`State`."""
    local = np.bincount(states.astype(np.int64), minlength=len(State))
    total = comm.allreduce(local, op=MPI.SUM)
    return {state.name.lower(): int(total[state]) for state in State}


def _log_iteration(entry: dict[str, typing.Any]) -> None:
    c = entry["states"]
    weak = c["weak_contact_sliding"] + c["weak_sticking"] + c["weak_contact_sticking"]
    stick = c["sticking"] + c["separated_sticking"]
    alpha, krylov = entry.get("alpha"), entry.get("krylov_iterations")
    logger.info(
        "  %3d  |y^| %.3e  rel %.2e  alpha %-9s  krylov %-5s  free %5d  slide %5d  stick %5d  weak %d  reversed %d",
        entry["k"], entry["residual"], entry["relative_residual"], "-" if alpha is None else f"{alpha:.3g}",
        "-" if krylov is None else krylov, c["no_contact"], c["sliding"], stick, weak, entry["reversed"],
    )  # fmt: skip
