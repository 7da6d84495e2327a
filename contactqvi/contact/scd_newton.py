"""SCD semismooth* Newton method for the Coulomb GE 0 in A u - l + Q(u) (seed 000).

Q is the nodal law of the problem's :class:`~contactqvi.contact.nodal.FrictionLaw`
(Coulomb as in the paper; Tresca and frictionless with the same machinery).

One iteration k (Algorithm 1 of Sect. 4 in the form of Sect. 5):
  1. approximation step (6.17): d^ = (gamma I + Q)^{-1}(gamma u - (A u - l)),
     residual y^ = (gamma (u - d^), u - d^);
  2. Newton step (5.4) with an element of S*Q at (d^, gamma u - (A u - l) - gamma d^)
     (Cor. 6.8; nodal bases in :func:`contactqvi.contact.nodal.scd_adjoint_blocks`):
        (W*^T A + U*^T) du = -(W*^T y1^ + U*^T y2^),
     rows of non-contact dofs are those of A (Q^R = 0: rge(I, 0));
  3. non-monotone line search of Sect. 7 on ||y^||.

The Newton matrix is assembled as D A + U with block-diagonal D = W*^T, U = U*^T
(identity/zero on non-contact nodes): it stays within the sparsity of A and is
built in parallel by PETSc (MatMatMult, reused pattern). Rows whose subspace is
rge(0, I) (the normal row of a contact node, all rows of a sticking node) are
pure identity rows; by default they are eliminated exactly before the Krylov
solve (MatZeroRowsColumns, the known values moved to the right-hand side), so the
inexact GMRES solve (tolerance ``tol`` of Sect. 7) only acts on the coupled rows.
"""

from __future__ import annotations

import dataclasses
import logging
import time
import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

from contactqvi.contact.nodal import State, classify, contact_states, resolvent, scd_adjoint_blocks, stick_reversed_slip
from contactqvi.contact.problem import ContactProblem
from contactqvi.elasticity import rigid_motions_nullspace
from contactqvi.linalg import create_ksp, default_options, ksp_converged_reason, power_iteration
from contactqvi.parameters import ParameterTable, merge_parameters, require, require_positive

__all__ = [
    "APPROXIMATION_STEPS",
    "GAMMA_RULES",
    "KSP_PRESETS",
    "PARAMETERS",
    "SCDNewtonResult",
    "SCDNewtonSolver",
    "check_parameters",
    "line_search_steps",
]

logger = logging.getLogger(__name__)

#: Newton-step solvers selectable by the parameter ``pc`` (PETSc options under the
#: solver's prefix; anything given on the command line wins). Measured in
#: docs/coulomb.md and benchmarks/results/coulomb_*.md.
#:
#: * ``gamg`` (default): GMRES stopped at the *unpreconditioned* relative residual
#:   ||b - J du|| <= tol ||b|| (the paper's test, Sect. 7), right-preconditioned by
#:   one W-cycle of smoothed-aggregation AMG with the rigid-body near-nullspace. AMG
#:   reduces all error components alike, so a residual reduced by tol is a direction
#:   accurate to about tol, and the local phase converges linearly with rate about
#:   tol, as the paper predicts. Against the V-cycle, the W-cycle lowers the relative
#:   residual a step actually reaches (lev 6 d3/L2, geometric mean 0.046 vs 0.055):
#:   lev 5-8, all six cases, 369 instead of 416 Newton steps and 9-14 % less solve
#:   time (docs/coulomb.md). GAMG reads the cycle type when it builds its levels.
#: * ``paper``: GMRES + block-Jacobi/ILU(0) as in Sect. 7, stopped at the
#:   left-preconditioned residual ||M^{-1}(b - J du)|| <= tol ||M^{-1} b|| (MATLAB's
#:   gmres tests it when given a preconditioner). With ILU a 10 % residual
#:   reduction is met by directions that miss the smooth part of the solution, which
#:   costs Newton steps from lev 6 on (lev 7 d1/L1 does not converge).
#: * ``hypre``: as ``gamg`` with BoomerAMG (scalar coarsening; its nodal/vector
#:   interpolation variants broke down on the eliminated rows here).
#: * ``lu``: exact inner solves (MUMPS); the reference for the Newton counts.
KSP_PRESETS: dict[str, dict[str, typing.Any]] = {
    "gamg": {
        "ksp_type": "gmres",
        "ksp_pc_side": "right",
        "ksp_norm_type": "unpreconditioned",
        "ksp_gmres_restart": 200,
        "ksp_max_it": 2000,
        "pc_type": "gamg",
        "pc_gamg_type": "agg",
        "pc_mg_cycle_type": "w",
        "pc_gamg_reuse_interpolation": True,
    },
    "paper": {
        "ksp_type": "gmres",
        "ksp_pc_side": "left",
        "ksp_norm_type": "preconditioned",
        "ksp_gmres_restart": 200,
        "ksp_max_it": 5000,
        "pc_type": "bjacobi",
        "sub_pc_type": "ilu",
    },
    "hypre": {
        "ksp_type": "gmres",
        "ksp_pc_side": "right",
        "ksp_norm_type": "unpreconditioned",
        "ksp_gmres_restart": 200,
        "ksp_max_it": 2000,
        "pc_type": "hypre",
        "pc_hypre_type": "boomeramg",
        "pc_hypre_boomeramg_strong_threshold": 0.5,
    },
    "lu": {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"},
}


#: Solver parameters: name -> (default, description).
PARAMETERS: ParameterTable = {
    "rtol": (1e-12, "stop when ||y^(k)|| <= rtol ||y^(0)||"),
    "atol": (0.0, "... or when ||y^(k)|| <= atol (units of gamma u)"),
    "max_iterations": (100, "Newton iterations before giving up (status 'diverged')"),
    "tol": (0.1, "relative residual reduction of the inner GMRES solve (tol, Sect. 7)"),
    "gamma": (None, "gamma of the approximation step (6.17) (N/m); None: set by gamma_rule"),
    "gamma_rule": (
        "contact_diagonal",
        "gamma when not given: 'contact_diagonal' = largest diagonal entry of A at the contact dofs; "
        "'power' = power-iteration estimate of lambda_max(A) (Sect. 7)",
    ),
    "approximation": (
        "stick_reversed",
        "approximation step: 'forward_backward' = (6.17); 'stick_reversed' = (6.17), then nodes whose slip "
        "reversed since the last iterate are moved to the sticking branch (APPROXIMATION_STEPS)",
    ),
    "power_iterations": (5, "power iterations for the estimate of lambda_max(A) (gamma_rule 'power', Sect. 7)"),
    "state_tol": (1e-10, "weak-state tolerance relative to max |gamma u - (A u - l)| over contact nodes"),
    "eliminate_fixed_rows": (True, "solve the identity rows (sticking, normal contact rows) exactly"),
    "max_line_search": (20, "step sizes tried by the line search before it fails"),
    "pc": ("gamg", "Newton-step solver: " + ", ".join(KSP_PRESETS)),
    "reuse_pc": (True, "keep the preconditioner while no contact node changes its kind (Krylov solvers only)"),
}


#: Rules for gamma of (6.17) when it is not given.
#:
#: * ``power`` (Sect. 7): five power iterations on A, a lower bound of lambda_max(A)
#:   (about 0.8 lambda_max(A) here), i.e. the step 1/L of a forward-backward method.
#: * ``contact_diagonal``: max_i A_ii over the dofs of the contact nodes, the stiffness
#:   of one contact node with its neighbours held, about lambda_max(A)/4.5 for the Q1
#:   meshes of Sect. 7 (both scale like E h). gamma only acts at the contact nodes: the
#:   Newton rows of the other dofs are those of A whatever gamma is ((5.4), Q^R = 0).
#:   There it is the stiffness of the trial force w = gamma u - (A u - l) of the
#:   resolvent (6.8)/(6.7), i.e. the augmentation parameter of an augmented-Lagrangian
#:   (Alart-Curnier type) contact formulation. After a Newton step that drives a sliding
#:   node's slip through zero by s (the sliding linearisation prescribes the friction
#:   force F lambda t in the old direction t, and with the wrong t the whole body
#:   overshoots), the next approximation step classifies the node as sticking only if
#:   gamma s < 2 F lambda; with gamma = lambda_max(A) almost every reversed node is
#:   classified as sliding backwards and the slip direction ping-pongs for several
#:   damped steps before sticking nodes appear. Measured (exact solves, lev 3-5, all six
#:   cases): 14.7 -> 9.3 Newton steps on average; GAMG tol 0.1: 19.8 -> 14.3.
GAMMA_RULES = ("contact_diagonal", "power")


#: Approximation steps (step 3 of Algorithm 1).
#:
#: * ``forward_backward``: the point (6.17) of the paper, d^ = (gamma I + Q)^{-1}(gamma u - (A u - l)).
#: * ``stick_reversed`` (default): (6.17), then every sliding node with a slip bound
#:   b > 0 whose slip v12 points against the previous iterate's is moved to the point of gph Q~ with
#:   v12 = 0 and the same force (:func:`~contactqvi.contact.nodal.stick_reversed_slip`),
#:   so its Newton rows are the sticking ones. Algorithm 1 admits any graph point that
#:   satisfies (4.2), and this one does near the solution, so the local convergence
#:   theory (Theorem 4.4) is unchanged; the line search still measures the residual
#:   of (6.17). Why: the Newton step of a sliding node prescribes the friction force
#:   in the current slip direction t and lets the node move freely along t. Where the
#:   solution sticks, the step drives the slip through zero, the next step slides
#:   the other way, and the line search damps this for several steps while no node
#:   sticks (lev 5 d3/L2, exact solves: 4 damped steps in a row, the tangential part
#:   of ||y^|| stays at ~6e7 N). Measured with the default gamma, all six cases
#:   (docs/coulomb.md): GAMG, tol 0.1, lev 3-7: 433 -> 382 Newton steps, lev 5 d3/L2
#:   20 -> 13; exact solves, lev 3-5: d3 10-13 -> 7-9 steps, d1 and d2 +-1.
APPROXIMATION_STEPS = ("forward_backward", "stick_reversed")


def line_search_steps(count: int) -> np.ndarray:
    """Step sizes 1, 1/2, 1/4, 1/8, 1/32, 1/128, 0.1/128, 0.01/128, ... of Sect. 7."""
    head = np.array([1.0, 0.5, 0.25, 0.125, 1.0 / 32, 1.0 / 128])
    tail = (1.0 / 128) * 10.0 ** -np.arange(1, max(count - len(head), 0) + 1)
    return np.concatenate([head, tail])[:count]


@dataclasses.dataclass
class SCDNewtonResult:
    """Outcome of :meth:`SCDNewtonSolver.solve`."""

    status: str  # "converged", "diverged", "line_search_failed" or "linear_solver_failed"
    iterations: int
    krylov_iterations: int
    gamma: float
    history: list[dict]
    timings: dict[str, float]
    states: np.ndarray  # state of each owned contact node at the last approximation step
    normal_force: np.ndarray  # lambda = -theta >= 0 per owned contact node (N)
    friction_force: np.ndarray  # (m, 2) tangential force of the foundation on the body (N)

    @property
    def converged(self) -> bool:
        return self.status == "converged"


def check_parameters(parameters: dict | None) -> dict:
    """:data:`PARAMETERS` merged with ``parameters`` and validated (cheap: call before assembly)."""
    p = merge_parameters(PARAMETERS, parameters)
    require(0.0 < p["rtol"] < 1.0, "rtol", f"must lie in (0, 1), got {p['rtol']!r}")
    require_positive("atol", p["atol"], allow_zero=True)
    require(0.0 < p["tol"] < 1.0, "tol", f"must lie in (0, 1), got {p['tol']!r}")
    for name in ("max_iterations", "power_iterations", "max_line_search"):
        require(int(p[name]) >= 1, name, f"must be >= 1, got {p[name]!r}")
    require_positive("state_tol", p["state_tol"], allow_zero=True)
    if p["gamma"] is not None:
        require_positive("gamma", p["gamma"])
    require(
        p["approximation"] in APPROXIMATION_STEPS,
        "approximation",
        f"must be one of {', '.join(APPROXIMATION_STEPS)}, got {p['approximation']!r}",
    )
    require(p["gamma_rule"] in GAMMA_RULES, "gamma_rule", f"must be one of {', '.join(GAMMA_RULES)}, got {p['gamma_rule']!r}")
    require(p["pc"] in KSP_PRESETS, "pc", f"must be one of {', '.join(KSP_PRESETS)}, got {p['pc']!r}")
    return p


class SCDNewtonSolver:
    """SCD semismooth* Newton solver for :class:`ContactProblem` (seed 000, Sects. 4-7).

    Args:
        problem: the assembled GE.
        parameters: overrides of :data:`PARAMETERS`.
        prefix: PETSc options prefix of the Newton-step KSP; any ``-{prefix}ksp_*``
            or ``-{prefix}pc_*`` option on the command line overrides the preset
            :data:`KSP_PRESETS` selected by the parameter ``pc``.
    """

    def __init__(self, problem: ContactProblem, parameters: dict | None = None, prefix: str = "coulomb_"):
        self.problem = problem
        self.parameters = p = check_parameters(parameters)
        comm = problem.comm
        A = problem.A
        self._D = _block_diagonal_like(A, np.eye(3))  # W*^T = I off the contact nodes
        self._U = _block_diagonal_like(A, np.zeros((3, 3)))  # U*^T = 0 off the contact nodes
        self._J: PETSc.Mat | None = None
        self._near_nullspace = rigid_motions_nullspace(problem.V)  # for AMG; the rows of J off the contact are A's
        self.ksp = create_ksp(comm, prefix, KSP_PRESETS[p["pc"]], rtol=p["tol"])
        self._steps = line_search_steps(int(p["max_line_search"]))
        self._gamma = None if p["gamma"] is None else float(p["gamma"])
        self._pc_kinds: np.ndarray | None = None  # node kinds when the preconditioner was last built

    def destroy(self) -> None:
        """Free the solver's PETSc objects (collective)."""
        for obj in (self.ksp, self._D, self._U, self._J, self._near_nullspace):
            if obj is not None:
                obj.destroy()

    # -- pieces of one iteration -------------------------------------------------
    @property
    def gamma(self) -> float:
        """gamma of (6.17): given, or by the rule ``gamma_rule`` (:data:`GAMMA_RULES`)."""
        if self._gamma is None:
            if self.parameters["gamma_rule"] == "power":
                x0 = _coordinate_noise(self.problem)
                self._gamma = power_iteration(self.problem.A, x0, int(self.parameters["power_iterations"]))
                x0.destroy()
            else:
                diagonal = self.problem.A.getDiagonal()
                local = diagonal.array.reshape(-1, 3)[self.problem.contact_blk]
                self._gamma = self.problem.comm.allreduce(float(local.max(initial=0.0)), op=MPI.MAX)
                diagonal.destroy()
        return self._gamma

    def residual(self, r: PETSc.Vec, u: PETSc.Vec, dhat: PETSc.Vec) -> tuple[float, np.ndarray, np.ndarray]:
        """Approximation step (6.17) at u, given r = A u - l.

        Writes d^ into ``dhat`` and returns ``(||y^||, v, z)`` with (v, z) the graph
        points of Q~ at the owned contact nodes. ||y^|| = sqrt(gamma^2 + 1) ||u - d^||.
        """
        gamma, blk = self.gamma, self.problem.contact_blk
        dhat.waxpy(-1.0 / gamma, r, u)  # non-contact dofs: (gamma I)^{-1}(gamma u - r)
        w = gamma * u.array.reshape(-1, 3)[blk] - r.array.reshape(-1, 3)[blk]
        v, z = resolvent(w, gamma, self.problem.law)
        dhat.array.reshape(-1, 3)[blk] = v
        diff = u.copy()
        diff.axpy(-1.0, dhat)
        norm = np.sqrt(gamma**2 + 1.0) * diff.norm()
        diff.destroy()
        return norm, v, z

    def approximation_step(self, u: PETSc.Vec) -> tuple[float, np.ndarray, np.ndarray]:
        """``(||y^||, v, z)`` of (6.17) at u alone (see :meth:`residual`); ||y^|| is the
        accuracy measure shared by every contact solver here."""
        r, dhat = self.problem.A.createVecRight(), self.problem.A.createVecRight()
        self.problem.A.mult(u, r)
        r.axpy(-1.0, self.problem.load)
        step = self.residual(r, u, dhat)
        r.destroy()
        dhat.destroy()
        return step

    def newton_matrix(self, Wt: np.ndarray, Ut: np.ndarray) -> PETSc.Mat:
        """J = D A + U with D = W*^T, U = U*^T on contact nodes, (I, 0) elsewhere."""
        blk = self.problem.contact_blk
        _set_diagonal_blocks(self._D, blk, Wt)
        _set_diagonal_blocks(self._U, blk, Ut)
        self._J = self._D.matMult(self.problem.A, result=self._J)
        self._J.axpy(1.0, self._U, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
        self._J.setNearNullSpace(self._near_nullspace)
        return self._J

    def _reuse_preconditioner(self, kinds: np.ndarray) -> bool:
        """Whether the Newton-step KSP may keep its preconditioner (parameter ``reuse_pc``).

        Between steps in which no contact node changes its kind, J changes only in
        the sliding rows' coefficients (a few per cent of the rows), so the
        preconditioner built for an earlier J stays good while GMRES still solves
        the current system to ``tol``. Direct solves (``preonly``) always refactor.
        """
        same = self._pc_kinds is not None and np.array_equal(self._pc_kinds, kinds)
        reuse = self.problem.comm.allreduce(same, op=MPI.LAND)
        reuse = reuse and bool(self.parameters["reuse_pc"]) and self.ksp.getType() != "preonly"
        if not reuse:
            self._pc_kinds = kinds
        return reuse

    # -- the method ----------------------------------------------------------------
    def solve(self, u: PETSc.Vec) -> SCDNewtonResult:
        """Run the method from the initial guess ``u`` (shifted displacements), in place."""
        p, problem = self.parameters, self.problem
        comm, A, blk = problem.comm, problem.A, problem.contact_blk
        timings = {"gamma": 0.0, "residual": 0.0, "newton_matrix": 0.0, "linear_solve": 0.0, "line_search": 0.0}
        t0 = time.perf_counter()
        gamma = self.gamma
        timings["gamma"] = time.perf_counter() - t0

        work = [A.createVecRight() for _ in range(8)]
        r, dhat, y2, rhs, du, Adu, u_trial, r_trial = work
        d_trial = dhat.duplicate()
        work.append(d_trial)
        rstart = A.getOwnershipRange()[0]

        t0 = time.perf_counter()
        A.mult(u, r)
        r.axpy(-1.0, problem.load)
        norm, v, z = self.residual(r, u, dhat)
        timings["residual"] += time.perf_counter() - t0
        norm0 = norm
        history: list[dict] = []
        krylov_total = 0
        status = "diverged"
        v_previous = v  # v of (6.17) at the previous iterate
        for k in range(int(p["max_iterations"]) + 1):
            w_scale = comm.allreduce(float(np.abs(gamma * v + z).max(initial=0.0)), op=MPI.MAX)
            state_tol = p["state_tol"] * w_scale
            normal, tangential = classify(v, z, gamma, problem.law, state_tol)
            v_forward_backward, n_reversed = v, 0
            if p["approximation"] == "stick_reversed" and k > 0:
                v, tangential, reversed_ = stick_reversed_slip(v, z, tangential, v_previous, problem.law, state_tol)
                # y2^ = u - d^ changes at the moved nodes; the right-hand side below takes y1^ = gamma y2^, which
                # is then wrong only in their tangential components, where the columns of W*^T vanish.
                dhat.array.reshape(-1, 3)[blk] = v
                n_reversed = comm.allreduce(int(reversed_.sum()), op=MPI.SUM)
            v_previous = v_forward_backward
            states = contact_states(normal, tangential)
            counts = _state_counts(comm, states)
            entry = {
                "k": k, "residual": norm, "relative_residual": norm / norm0, "states": counts, "reversed": n_reversed
            }
            history.append(entry)
            if norm <= p["rtol"] * norm0 or norm <= p["atol"]:
                status = "converged"
                _log_iteration(entry, None, None)
                break
            if k == int(p["max_iterations"]):
                _log_iteration(entry, None, None)
                break

            # Newton step (5.4): (W*^T A + U*^T) du = -(W*^T y1^ + U*^T y2^), y1^ = gamma y2^ = gamma (u - d^)
            t0 = time.perf_counter()
            Wt, Ut = scd_adjoint_blocks(v, z, normal, tangential, gamma, problem.law)
            J = self.newton_matrix(Wt, Ut)
            y2.waxpy(-1.0, dhat, u)
            self._D.mult(y2, rhs)
            rhs.scale(gamma)
            self._U.multAdd(y2, rhs, rhs)
            rhs.scale(-1.0)
            du.set(0.0)
            if p["eliminate_fixed_rows"]:
                fixed_loc = _fixed_rows(Wt, blk)
                du.array[fixed_loc] = rhs.array[fixed_loc] / gamma
                J.zeroRowsColumns((fixed_loc + rstart).astype(PETSc.IntType), diag=gamma, x=du, b=rhs)
            timings["newton_matrix"] += time.perf_counter() - t0

            t0 = time.perf_counter()
            self.ksp.setOperators(J)
            self.ksp.getPC().setReusePreconditioner(self._reuse_preconditioner(np.concatenate([normal, tangential])))
            # The eliminated rows carry their exact values in the initial guess (direct solvers need none).
            self.ksp.setInitialGuessNonzero(bool(p["eliminate_fixed_rows"]) and self.ksp.getType() != "preonly")
            # GAMG reads its multigrid options again when it builds its levels, inside the solve.
            with default_options(self.ksp.getOptionsPrefix(), KSP_PRESETS[p["pc"]]):
                self.ksp.solve(rhs, du)
            timings["linear_solve"] += time.perf_counter() - t0
            krylov = self.ksp.getIterationNumber()
            krylov_total += krylov
            entry.update(krylov_iterations=krylov, ksp_reason=ksp_converged_reason(self.ksp))
            if self.ksp.getConvergedReason() < 0:
                status = "linear_solver_failed"
                _log_iteration(entry, None, krylov)
                break

            # Non-monotone line search of Sect. 7: r(u + a du) = r + a A du.
            t0 = time.perf_counter()
            A.mult(du, Adu)
            bound = 1.0 + 0.1 / (k + 1)
            accepted = None
            for alpha in self._steps:
                u_trial.waxpy(alpha, du, u)
                r_trial.waxpy(alpha, Adu, r)
                trial_norm, v_trial, z_trial = self.residual(r_trial, u_trial, d_trial)
                if trial_norm <= (bound - 0.1 * alpha) * norm:
                    accepted = alpha
                    break
            timings["line_search"] += time.perf_counter() - t0
            entry["alpha"] = accepted
            _log_iteration(entry, accepted, krylov)
            if accepted is None:
                status = "line_search_failed"
                break
            u_trial.copy(u)
            r_trial.copy(r)
            d_trial.copy(dhat)
            norm, v, z = trial_norm, v_trial, z_trial

        for vec in work:
            vec.destroy()
        return SCDNewtonResult(
            status=status,
            iterations=len(history) - 1,
            krylov_iterations=krylov_total,
            gamma=gamma,
            history=history,
            timings=timings,
            states=states,
            normal_force=-z[:, 2].copy(),
            friction_force=-z[:, :2].copy(),
        )


def _block_diagonal_like(A: PETSc.Mat, block: np.ndarray) -> PETSc.Mat:
    """Block-diagonal AIJ matrix with A's layout and every 3x3 diagonal block = ``block``.

    All nine entries of every diagonal block are stored (zeros included), so the
    pattern of D A equals that of A and U fits into it.
    """
    M = PETSc.Mat().createAIJ(size=A.getSizes(), bsize=3, nnz=(3, 0), comm=A.getComm())
    M.setOption(PETSc.Mat.Option.IGNORE_ZERO_ENTRIES, False)
    n_blk = A.getLocalSize()[0] // 3
    _set_diagonal_blocks(M, np.arange(n_blk), np.broadcast_to(block, (n_blk, 3, 3)))
    return M


def _set_diagonal_blocks(M: PETSc.Mat, blk: np.ndarray, blocks: np.ndarray) -> None:
    """Overwrite the diagonal 3x3 blocks of the owned local nodes ``blk``."""
    rows = (np.asarray(blk) + M.getOwnershipRange()[0] // 3).astype(PETSc.IntType)[:, None]
    M.setValuesBlockedRCV(rows, rows, np.ascontiguousarray(blocks).reshape(len(rows), 1, 9))
    M.assemble()


def _fixed_rows(Wt: np.ndarray, blk: np.ndarray) -> np.ndarray:
    """Owned local rows whose W*^T row vanishes: pure (gamma-scaled) identity rows."""
    zero_rows = ~np.any(Wt, axis=2)  # (m, 3)
    return (3 * np.asarray(blk, dtype=np.int64)[:, None] + np.arange(3))[zero_rows].astype(np.int32)


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


def _log_iteration(entry: dict, alpha: float | None, krylov: int | None) -> None:
    c = entry["states"]
    weak = c["weak_contact_sliding"] + c["weak_sticking"] + c["weak_contact_sticking"]
    stick = c["sticking"] + c["separated_sticking"]
    logger.info(
        "  %3d  |y^| %.3e  rel %.2e  alpha %-9s  krylov %-5s  free %5d  slide %5d  stick %5d  weak %d  reversed %d",
        entry["k"],
        entry["residual"],
        entry["relative_residual"],
        "-" if alpha is None else f"{alpha:.3g}",
        "-" if krylov is None else krylov,
        c["no_contact"],
        c["sliding"],
        stick,
        weak,
        entry["reversed"],
    )
