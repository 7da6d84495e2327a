"""Composite maps H = S o Phi of seed 003 with their Newton systems.

Each map evaluates H at a point y (returning an :class:`Evaluation` with H(y)
and the data its Newton derivative needs) and solves the linearised system

    (Id - s G_S(Phi(y)) G_Phi(y)) d = b                                   (61)

for a scalar ``s`` (s = 1 without localisation; s = R/||x - c|| when the
projection P_B of Sect. 2.3 is active, see :mod:`contactqvi.qvi.outer`).

* :class:`ObstacleQVIMap`: obstacle-type QVI (58), S the obstacle solver with
  obstacle Phi0 + Phi(u), Phi the temperature map; Newton system (62)-(64).
* :class:`SemilinearVIMap`: the semilinear VI (48)/(53), S = S0 with source
  Phi(u) = b1(u) b2(u) + f; Newton system from Lemmas 3.16/3.17.
* :class:`RegularisedQVIMap`: comparison method C2, S replaced by the smoothed
  Moreau-Yosida solution map S_rho of (60); Newton system (65)-(67).
"""

from __future__ import annotations

import dataclasses
import typing

from petsc4py import PETSc

import numpy as np
import ufl

import dolfinx.fem.petsc
from dolfinx import fem

from contactqvi.lifetime import PETScOwner
from contactqvi.linalg import reassemble_matrix
from contactqvi.qvi.newton_system import BlockNewtonSystem, diagonal_matrix
from contactqvi.qvi.temperature import TemperatureMap
from contactqvi.result import InnerSolveError
from contactqvi.vi.moreau_yosida import PathFollowingMoreauYosida, huber_derivative
from contactqvi.vi.problem import ObstacleProblem
from contactqvi.vi.solver import ObstacleResult, ObstacleSolver, rho_path

__all__ = ["Evaluation", "CompositeMap", "ObstacleQVIMap", "SemilinearVIMap", "RegularisedQVIMap"]


@dataclasses.dataclass
class Evaluation:
    """H(y) and the state the Newton derivative at y is built from.

    Attributes:
        y: the point H was evaluated at.
        value: H(y).
        temperature: T at y (QVI maps), else None.
        active: owned nodes of the active set {H(y) = obstacle} (Sect. 4.1).
        counts: inner iteration counts of this evaluation.
        obstacle: the obstacle the evaluation of S used (Phi0 + Phi(y) for QVIs).
    """

    y: fem.Function
    value: fem.Function
    temperature: fem.Function | None
    active: np.ndarray
    counts: dict[str, int]
    obstacle: fem.Function


def _counts(phi_newton: int, s: ObstacleResult) -> dict[str, int]:
    """Inner counts of one evaluation; raises :class:`InnerSolveError` if S did not converge."""
    if not s.converged:
        raise InnerSolveError(f"S: the obstacle solver did not converge ({s.status})")
    return {"phi_newton": phi_newton, "pfmy": s.pfmy_iterations, "pdas": s.pdas_iterations, "vi": s.vi_iterations}


class CompositeMap(PETScOwner):
    """Shared parts: the obstacle problem, lumped mass, stiffness without BCs, the Newton system.

    Subclasses allocate their blocks once, create :attr:`system` from them, and
    re-assemble the state-dependent ones in place in ``linearize``, from the
    :class:`Evaluation` they are given only. A map owns the problem and the
    solvers it is given (``parts``): :meth:`destroy` frees them too; subclasses add
    their own blocks to :meth:`petsc_objects`.
    """

    def __init__(self, problem: ObstacleProblem, parts: list[PETScOwner]):
        self.problem, self.parts = problem, parts
        self.V, self.comm, self.n_owned = problem.V, problem.comm, problem.n_owned
        v, w = ufl.TestFunction(self.V), ufl.TrialFunction(self.V)
        self.lumped_mass = dolfinx.fem.petsc.assemble_vector(fem.form(v * ufl.dx))
        self.lumped_mass.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        stiffness_form = fem.form(ufl.inner(ufl.grad(w), ufl.grad(v)) * ufl.dx)
        self.stiffness = dolfinx.fem.petsc.assemble_matrix(stiffness_form)
        self.stiffness.assemble()
        m = self.lumped_mass.array
        #: lumped mass M_L and -M_L: the identity terms of (62)/(65) in the basis of (68)
        self.mass, self.negative_mass = self._diag(m), self._diag(-m)
        self.boundary = ~problem.free
        self.system: BlockNewtonSystem | None = None

    def petsc_objects(self) -> list[typing.Any]:
        return [self.system, self.mass, self.negative_mass, self.stiffness, self.lumped_mass, *self.parts, self.problem]

    def _diag(self, values: np.ndarray) -> PETSc.Mat:
        """A diagonal matrix with the layout of V."""
        vec = self.lumped_mass.duplicate()
        vec.array[:] = values
        D = diagonal_matrix(vec)
        vec.destroy()
        return D

    @staticmethod
    def _assembled(form: fem.Form) -> PETSc.Mat:
        """The matrix of ``form`` (re-assembled in place later)."""
        A = dolfinx.fem.petsc.assemble_matrix(form)
        A.assemble()
        return A

    def _copy(self, f: fem.Function, name: str) -> fem.Function:
        g = fem.Function(self.V, name=name)
        g.x.array[:] = f.x.array
        return g

    def solve_linearized(self, b: np.ndarray) -> np.ndarray:
        """d with (Id - s G_S G_Phi) d = b (owned values) for the last ``linearize``."""
        m = self.lumped_mass.array
        rhs = [m * b] + [None] * (len(self.system.positions) - 1)
        return self.system.solve(rhs)[0]


class _TemperatureCoupledMap(CompositeMap):
    """Maps through Phi (E1): S sees the mould Phi0 + Phi(y) as its obstacle."""

    def __init__(self, problem: ObstacleProblem, temperature: TemperatureMap, Phi0: fem.Function, parts: list):
        super().__init__(problem, [temperature, *parts])
        self.temperature, self.Phi0 = temperature, Phi0

    def _mould(self, y: fem.Function) -> tuple[int, fem.Function]:
        """E1: T at y (Newton steps) and the obstacle Phi0 + Phi(y) of (58)."""
        newton_steps = self.temperature.solve(y)
        mould = fem.Function(self.V, name="mould")
        self.temperature.apply(mould)
        mould.x.array[:] += self.Phi0.x.array
        return newton_steps, mould

    def _linearize_temperature(self, ev: Evaluation, scale: float) -> None:
        """The blocks of (63) at (y, T(y)); Phi's next solve starts from T(y), near the next iterate."""
        self.temperature.linearize(ev.y, ev.temperature, scale)
        self.temperature.restart_from(ev.temperature)


class ObstacleQVIMap(_TemperatureCoupledMap):
    """H(u) = S(Phi(u)) for the obstacle-type QVI (58) (E1 then E2 of Sect. 4.1).

    Args:
        temperature: the map Phi.
        solver: the obstacle solver S, called with the obstacle Phi0 + Phi(u).
        Phi0: the nodal obstacle Phi0.
        prefix: options prefix of the Newton system's KSP.
    """

    def __init__(self, temperature: TemperatureMap, solver: ObstacleSolver, Phi0: fem.Function, prefix: str = "qvi_newton_"):
        super().__init__(solver.problem, temperature, Phi0, [solver])
        self.solver = solver
        tm = temperature
        phi = tm.varphi.x.array[: self.n_owned]
        # constant blocks of (68): -M_L diag(varphi) in (62), A diag(varphi) = (grad I_h(varphi .), grad q) in (64).
        # The columns of boundary nodes are zero: delta u = mu + eta vanishes there, so the harmonic extension
        # (64) sees eta = 0 on the boundary. This matters only if varphi != 0 on the boundary, which the paper
        # excludes (Assumption 3.8 ii)).
        self.varphi_mass = self._diag(-self.lumped_mass.array * phi)
        self.varphi_stiffness = self.stiffness.duplicate(copy=True)
        interior_varphi = tm.varphi.x.petsc_vec.copy()
        interior_varphi.array[self.boundary] = 0.0
        self.varphi_stiffness.diagonalScale(R=interior_varphi)
        interior_varphi.destroy()
        blocks = [
            [self.mass, self.varphi_mass, self.negative_mass],
            [tm.coupling_matrix, tm.jacobian_matrix, None],
            [None, self.varphi_stiffness, self.stiffness],
        ]
        self.system = BlockNewtonSystem(self.comm, blocks, prefix)

    def petsc_objects(self) -> list[typing.Any]:
        return [*super().petsc_objects(), self.varphi_mass, self.varphi_stiffness]

    def evaluate(self, y: fem.Function) -> Evaluation:
        """E1: T and Phi(y); E2: u_B = S(Phi0 + Phi(y))."""
        phi_its, mould = self._mould(y)
        s = self.solver.solve(mould)
        counts = _counts(phi_its, s)
        u, T = self._copy(self.problem.u, "membrane"), self._copy(self.temperature.T, "temperature")
        return Evaluation(self._copy(y, "y"), u, T, s.active, counts, mould)

    def linearize(self, ev: Evaluation, scale: float = 1.0) -> None:
        """Block system (68) for (delta u, xi, mu) with mu = 0 on A_i and the boundary; (63) at (y, T(y))."""
        self._linearize_temperature(ev, scale)
        self.system.update([self.boundary, np.zeros(self.n_owned, bool), self.boundary | ev.active])


class SemilinearVIMap(CompositeMap):
    """H(u) = S0(Phi(u)), Phi(u) = b1(u) b2(u) + f, for the semilinear VI (48)/(53).

    Args:
        solver: obstacle solver whose problem's source is Phi(y) written in terms of ``y``.
        y: the Function the source (and ``coupling``) are expressed in.
        coupling: UFL form (G_Phi(y) du, q), (50), bilinear in (trial, test) on V.
        prefix: options prefix of the Newton system's KSP.
    """

    def __init__(self, solver: ObstacleSolver, y: fem.Function, coupling: ufl.Form, prefix: str = "qvi_newton_"):
        super().__init__(solver.problem, [solver])
        self.solver, self.y = solver, y
        self.coupling_form = fem.form(coupling)
        self.coupling = self._assembled(self.coupling_form)
        blocks = [[self.mass, self.negative_mass], [self.coupling, self.stiffness]]
        self.system = BlockNewtonSystem(self.comm, blocks, prefix)

    def petsc_objects(self) -> list[typing.Any]:
        return [*super().petsc_objects(), self.coupling]

    def evaluate(self, y: fem.Function) -> Evaluation:
        self.y.x.array[:] = y.x.array
        s = self.solver.solve()
        counts = _counts(0, s)
        u, obstacle = self._copy(self.problem.u, "membrane"), self._copy(self.problem.obstacle, "obstacle")
        return Evaluation(self._copy(y, "y"), u, None, s.active, counts, obstacle)

    def linearize(self, ev: Evaluation, scale: float = 1.0) -> None:
        """(delta u, z): delta u - z = b, (grad z, grad q) = s (G_Phi delta u, q) on I_i, z = 0 on A_i."""
        self.y.x.array[:] = ev.y.x.array
        reassemble_matrix(self.coupling, self.coupling_form).scale(-scale)
        self.system.update([self.boundary, self.boundary | ev.active])


class RegularisedQVIMap(_TemperatureCoupledMap):
    """C2: H_rho(u) = S_rho(Phi(u)) with S_rho the smoothed Moreau-Yosida map (60), fixed rho.

    S_rho is evaluated by Newton's method (warm-started; on the first call along
    the path rho0, rho0/rho_factor, ..., rho). The Newton system (65)-(67) is assembled
    consistently at the computed u_B = S_rho(Phi(u)), i.e. with
    G_sigma(u_B - Phi0 - Phi(u)), from the evaluation's u_B and mould.

    Args:
        temperature: the map Phi.
        pfmy: Moreau-Yosida solver on the obstacle problem, called with the obstacle Phi0 + Phi(u).
        Phi0: nodal Phi0.
        rho: the fixed regularisation parameter.
        rho0: start of the path on the first evaluation.
        rho_factor: rho is divided by this factor along that path.
        prefix: options prefix of the Newton system's KSP.
    """

    def __init__(
        self,
        temperature: TemperatureMap,
        pfmy: PathFollowingMoreauYosida,
        Phi0: fem.Function,
        rho: float,
        rho0: float = 1.0,
        rho_factor: float = 10.0,
        prefix: str = "qvi_newton_",
    ):
        super().__init__(pfmy.problem, temperature, Phi0, [pfmy])
        self.pfmy, self.rho = pfmy, rho
        self.path = rho_path(rho0, rho, rho_factor) if rho < rho0 else [rho]
        #: u_B and the mould of the evaluation the penalty blocks are linearised at
        self.u_B, self.mould = fem.Function(self.V), fem.Function(self.V)
        w, q = ufl.TrialFunction(self.V), ufl.TestFunction(self.V)
        rho_c = fem.Constant(self.V.mesh, PETSc.ScalarType(rho))
        penalty = huber_derivative(self.u_B - self.mould, rho_c) / rho_c * w * q * self.problem.dx
        #: rho^-1 (G_sigma w, q) of (67) and the whole (w, q) block (grad w, grad q) + rho^-1 (G_sigma w, q)
        self.penalty_form = fem.form(penalty)
        self.w_block_form = fem.form(ufl.inner(ufl.grad(w), ufl.grad(q)) * ufl.dx + penalty)
        self.penalty = self._assembled(self.penalty_form)
        self.w_block = self._assembled(self.w_block_form)
        #: -rho^-1 (G_sigma I_h(varphi xi), q) of (67): the penalty times diag(varphi), negated
        self.penalty_varphi = self.penalty.duplicate(copy=True)
        tm = temperature
        blocks = [
            [self.mass, None, self.negative_mass],
            [tm.coupling_matrix, tm.jacobian_matrix, None],
            [None, self.penalty_varphi, self.w_block],
        ]
        self.system = BlockNewtonSystem(self.comm, blocks, prefix)
        self.warm = False

    def petsc_objects(self) -> list[typing.Any]:
        return [*super().petsc_objects(), self.penalty, self.w_block, self.penalty_varphi]

    def evaluate(self, y: fem.Function) -> Evaluation:
        phi_its, mould = self._mould(y)
        res = self.pfmy.solve([self.rho] if self.warm else self.path, mould)
        if not res.converged:
            raise InnerSolveError(f"C2: Newton for S_rho failed at rho = {self.rho:g} ({res.status})")
        self.warm = True
        counts = {"phi_newton": phi_its, "pfmy": res.iterations, "pdas": 0, "vi": 0}
        u, T = self._copy(self.problem.u, "membrane"), self._copy(self.temperature.T, "temperature")
        return Evaluation(self._copy(y, "y"), u, T, np.zeros(self.n_owned, bool), counts, mould)

    def linearize(self, ev: Evaluation, scale: float = 1.0) -> None:
        """(delta u, xi, w): delta u - w = b; (63); (grad w, grad q) + rho^-1 (G_sigma (w - I_h(varphi xi)), q) = 0."""
        self._linearize_temperature(ev, scale)
        self.u_B.x.array[:] = ev.value.x.array
        self.mould.x.array[:] = ev.obstacle.x.array
        reassemble_matrix(self.penalty, self.penalty_form)
        reassemble_matrix(self.w_block, self.w_block_form)
        self.penalty.copy(self.penalty_varphi, structure=PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
        self.penalty_varphi.diagonalScale(R=self.temperature.varphi.x.petsc_vec)
        self.penalty_varphi.scale(-1.0)
        self.system.update([self.boundary, np.zeros(self.n_owned, bool), self.boundary])
