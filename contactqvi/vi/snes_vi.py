"""PETSc's reduced-space active-set Newton for variational inequalities (``vinewtonrsls``).

:class:`SNESVariationalInequality` is the one SNES-VI wrapper of contactqvi: it
takes a problem with residual/Jacobian callbacks (:mod:`contactqvi.vi.nonlinear`)
and the bounds lower <= x <= upper, and solves under an options prefix with a
named KSP preset (:data:`contactqvi.linalg.KSP_PRESETS`) for the inactive-set
systems; given the Jacobian's near-nullspace, the preset's preconditioner works on
the full space with the active rows eliminated (:class:`EmbeddedInactivePC`). Its
users: :class:`ObstacleSNESVI`, the alternative S-solver and the independent oracle
for PFMY+PDAS, and the Signorini peer (:mod:`contactqvi.contact.signorini_vi`).
"""

from __future__ import annotations

import dataclasses

from mpi4py import MPI
from petsc4py import PETSc

import ufl

from dolfinx import fem

from contactqvi.lifetime import PETScOwner
from contactqvi.linalg import OptionsDict, create_snes, default_options, preset
from contactqvi.result import Result, Status
from contactqvi.vi.nonlinear import NonlinearFormProblem, SNESProblem, snes_converged_reason, snes_status
from contactqvi.vi.problem import ObstacleProblem

__all__ = [
    "VI_OPTIONS",
    "OBSTACLE_VI_OPTIONS",
    "EmbeddedInactivePC",
    "SNESVIResult",
    "SNESVariationalInequality",
    "ObstacleSNESVI",
]

#: Options of every SNES VI: the method, and the line search it converged with on these machines
#: (PETSc 3.22; ``snes_linesearch_type basic``).
VI_OPTIONS: OptionsDict = {"snes_type": "vinewtonrsls", "snes_linesearch_type": "basic"}

#: Tolerances of the obstacle VI (tight: it is the oracle PFMY+PDAS is compared with).
OBSTACLE_VI_OPTIONS: OptionsDict = {"snes_rtol": 1e-14, "snes_atol": 1e-13, "snes_stol": 0.0, "snes_max_it": 200}


@dataclasses.dataclass(kw_only=True)
class SNESVIResult(Result):
    """A SNES VI solve; ``iterations`` are Newton steps, ``inner_iterations`` Krylov iterations.

    Attributes:
        reason: PETSc's name of the converged/diverged reason (e.g. ``CONVERGED_FNORM_RELATIVE``).
    """

    reason: str = ""


class EmbeddedInactivePC:
    """Preconditioner of the inactive-set systems of ``vinewtonrsls`` that keeps the
    Jacobian's block size and near-nullspace (a petsc4py Python-PC context).

    ``vinewtonrsls`` solves J_II dx_I = -F_I on the inactive set I with the
    submatrix J_II (MatCreateSubMatrix), which keeps neither J's block size nor
    its near-nullspace: a contact bound removes single components of a node, so
    GAMG would aggregate scalar dofs without rigid-body modes. This PC applies an
    inner PC (e.g. GAMG) to J_II embedded in the full space, J with the active rows
    and columns replaced by identity rows: x_I -> (inner PC applied to (x_I, 0))_I.
    For an exact inner solve that is J_II^{-1}. PETSc sets the PC up at every Newton
    step (a new J_II each time); the inner PC is rebuilt only when the inactive set
    or J changed.

    Args:
        snes: the ``vinewtonrsls`` SNES whose KSP this PC belongs to.
        J: the SNES's Jacobian (assembled in place by the problem's callback).
        near_nullspace: near-nullspace of J (e.g. rigid-body modes), for the inner PC.
        prefix: options prefix of the inner PC.
        options: defaults of the inner PC under ``prefix`` (``pc_type`` etc.).
    """

    def __init__(self, snes: PETSc.SNES, J: PETSc.Mat, near_nullspace: PETSc.NullSpace, prefix: str,
                 options: OptionsDict):
        self.snes, self.J = snes, J
        self.embedded = J.duplicate()
        self.embedded.setNearNullSpace(near_nullspace)
        self.inner = PETSc.PC().create(J.getComm())
        self.inner.setOptionsPrefix(prefix)
        with default_options(prefix, options):
            self.inner.setFromOptions()
        self.x, self.y = J.createVecs()
        self.scatter: PETSc.Scatter | None = None  # full space -> inactive set
        self.inactive: PETSc.IS | None = None  # the set the inner PC was built for
        self.J_state = -1

    def setUp(self, pc: PETSc.PC) -> None:
        inactive = self.snes.getVIInactiveSet()
        J_same = self.J.getComm().tompi4py().allreduce(self.J.stateGet() == self.J_state, op=MPI.LAND)
        if self.inactive is not None and J_same and inactive.equal(self.inactive):
            inactive.destroy()  # our handle; PETSc keeps the set
            return
        self.J.copy(self.embedded, PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
        active = inactive.complement(*self.J.getOwnershipRange())
        self.embedded.zeroRowsColumns(active, diag=1.0)
        active.destroy()
        reduced = pc.getOperators()[1].createVecRight()
        for old in (self.scatter, self.inactive):
            if old is not None:
                old.destroy()
        self.scatter = PETSc.Scatter().create(self.x, inactive, reduced, None)
        reduced.destroy()
        self.inactive, self.J_state = inactive, self.J.stateGet()
        self.inner.setOperators(self.embedded)
        self.inner.setUp()

    def apply(self, pc: PETSc.PC, x: PETSc.Vec, y: PETSc.Vec) -> None:
        self.x.set(0.0)
        self.scatter.scatter(x, self.x, PETSc.InsertMode.INSERT, PETSc.ScatterMode.REVERSE)
        self.inner.apply(self.x, self.y)
        self.scatter.scatter(self.y, y, PETSc.InsertMode.INSERT, PETSc.ScatterMode.FORWARD)

    def view(self, pc: PETSc.PC, viewer: PETSc.Viewer) -> None:
        self.inner.view(viewer)

    def destroy(self, pc: PETSc.PC) -> None:
        """Called by PETSc when the PC is destroyed (collective)."""
        for obj in (self.inner, self.embedded, self.x, self.y, self.scatter, self.inactive):
            if obj is not None:
                obj.destroy()


class SNESVariationalInequality(PETScOwner):
    """Solve F(x) = 0 subject to lower <= x <= upper (complementarity form) by ``vinewtonrsls``.

    Args:
        problem: callbacks ``F``/``J`` with their work vector ``b`` and matrix ``A``
            (:class:`~contactqvi.vi.nonlinear.NonlinearFormProblem`,
            :class:`~contactqvi.vi.nonlinear.AffineProblem`); stays the caller's.
        prefix: PETSc options prefix (``-{prefix}snes_monitor`` etc. on the command line).
        ksp: KSP preset of the inactive-set Newton systems.
        options: further defaults under ``prefix`` (tolerances; they override the preset).
        near_nullspace: near-nullspace of the Jacobian (stays the caller's). Given, the
            preset's preconditioner (``pc_*`` options, under ``{prefix}embedded_``) works
            on the full space (:class:`EmbeddedInactivePC`); the KSP keeps ``ksp_*``.

    Attributes:
        lower, upper: the bounds, -inf and +inf until the caller writes them.
    """

    def __init__(self, problem: SNESProblem, prefix: str, ksp: str = "lu", options: OptionsDict | None = None,
                 near_nullspace: PETSc.NullSpace | None = None):
        self.problem = problem
        comm = problem.A.getComm()
        defaults = {**VI_OPTIONS, **preset(ksp, "ksp"), **(options or {})}
        pc_options = {k: v for k, v in defaults.items() if not k.startswith(("snes_", "ksp_"))}
        if near_nullspace is None:
            self._pc_options = (prefix, pc_options)
            self.snes = create_snes(comm, prefix, defaults)
        else:
            self._pc_options = (f"{prefix}embedded_", pc_options)
            self.snes = create_snes(comm, prefix, {k: v for k, v in defaults.items() if k not in pc_options})
            context = EmbeddedInactivePC(self.snes, problem.A, near_nullspace, *self._pc_options)
            pc = self.snes.getKSP().getPC()
            pc.setType(PETSc.PC.Type.PYTHON)
            pc.setPythonContext(context)  # PETSc calls context.destroy with the SNES's
        problem.attach(self.snes)
        self.lower = problem.b.duplicate()
        self.lower.set(PETSc.NINFINITY)
        self.upper = problem.b.duplicate()
        self.upper.set(PETSc.INFINITY)
        #: the SNES iterate: never a Vec the callbacks assemble from
        self.x = problem.b.duplicate()

    def petsc_objects(self) -> list[PETSc.Object]:
        return [self.snes, self.lower, self.upper, self.x]

    def solve(self, x: PETSc.Vec) -> SNESVIResult:
        """Solve from ``x`` (projected onto the bounds first); the solution overwrites ``x``."""
        result = SNESVIResult(status=Status.ITERATING, iterations=0)
        with result.timings.phase("solve"):
            self.snes.setVariableBounds(self.lower, self.upper)
            x.copy(self.x)
            self.x.pointwiseMax(self.x, self.lower)
            self.x.pointwiseMin(self.x, self.upper)
            # a preconditioner reads some options (GAMG's multigrid ones) when it is set up, inside the solve
            with default_options(*self._pc_options):
                self.snes.solve(None, self.x)
            self.x.copy(x)
        result.status, result.reason = snes_status(self.snes), snes_converged_reason(self.snes)
        result.iterations = self.snes.getIterationNumber()
        result.inner_iterations = self.snes.getLinearSolveIterations()
        return result


class ObstacleSNESVI(PETScOwner):
    """The obstacle problem by SNES VI: residual (grad u, grad v) - (f, v), bound u <= theta at every node.

    The iterate is ``problem.u``; after a solve ``problem.multiplier`` holds the discrete multiplier.
    """

    def __init__(self, problem: ObstacleProblem, prefix: str = "obstacle_vi_"):
        self.problem = problem
        V, u = problem.V, problem.u
        v, du = ufl.TestFunction(V), ufl.TrialFunction(V)
        F = ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx - problem.source * v * problem.dx
        J = ufl.inner(ufl.grad(du), ufl.grad(v)) * ufl.dx
        self.nonlinear = NonlinearFormProblem(fem.form(F), fem.form(J), u, problem.bcs)
        self.vi = SNESVariationalInequality(self.nonlinear, prefix, "lu", OBSTACLE_VI_OPTIONS)

    def petsc_objects(self) -> list[PETScOwner]:
        return [self.vi, self.nonlinear]

    def solve(self) -> SNESVIResult:
        """Solve from ``problem.u`` for the problem's current obstacle."""
        p = self.problem
        p.obstacle.x.petsc_vec.copy(self.vi.upper)
        result = self.vi.solve(p.u.x.petsc_vec)
        p.u.x.scatter_forward()
        p.residual(p.u, p.multiplier)
        return result
