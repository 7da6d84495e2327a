"""Implicit dynamic contact: contact-stabilised Newmark-family schemes, each step solved by SCD Newton.

A member (α_m, α_f, β, γ) of the generalized-α family (:mod:`contactqvi.time_scheme`:
Newmark's average acceleration rule, HHT-α, Chung-Hulbert's generalized-α) with the
contact-stabilised predictor of Deuflhard, Krause and Ertel (2008); derivation and energy
identity in docs/dynamics.md. With tau the time step, M the mass and K the stiffness in the
solver's variables w (M = T^T M_K T, K = T^T A_K T of :mod:`contactqvi.contact.problem`),
F(t) the load at time t (load factor and translation of the case's time points,
:func:`~contactqvi.load_steps.at_time`), g = F - K w the force without contact, m_n the
inertial force without contact (m_n = g_n for Newmark's rule), a_n Newmark's acceleration and
K the admissible set (the contact conditions at t_{n+1}), a step from (w_n, v_n, a_n, m_n) is

1. predictor   w_pred = w_n + tau v_n,
2. projection  w_bar = argmin_{w in K} 1/2 ||w - w_pred||_M^2, i.e. the GE
               0 in M (w - w_pred) + Q_0(w) (frictionless Q) -- a contact problem with A = M,
3. step        0 in c M (w - w_bar) + K w - F_{n+1} - (alpha_f g_n - c_a m_n) / (1 - alpha_f) + Q(w)
               (docs/dynamics.md (3.3); c, c_a of the scheme) -- a contact problem with
               A_eff = K + c M and a shifted load,
4. update      a_{n+1} = (w_{n+1} - w_bar) / (beta tau^2) - (1/2 - beta) / beta a_n,
               v_{n+1} = v_n + tau ((1 - gamma) a_n + gamma a_{n+1}),
               m_{n+1} = ((1 - alpha_f) g_{n+1} + alpha_f g_n - alpha_m m_n) / (1 - alpha_m)
               (Newmark's rule: v_{n+1} = v_n + (2/tau)(w_{n+1} - w_bar), no a_n).

A step that fails may be retried with a shorter tau (:meth:`StabilisedNewmark.step` takes
any tau; A_eff and the step's solver follow it).

Steps 2 and 3 are the GE 0 in f(u) + Q(u) of seed 000 (6.3) in the shifted variables
u = w + d of :meth:`~contactqvi.contact.problem.ContactProblem.set_step` (slip measured
from w_n: u_t is the slip increment over the step, slip rate times tau), solved by
:class:`~contactqvi.contact.scd_newton.SCDNewtonSolver` unchanged. All that a step reads
from the steps before is one :class:`DynamicState`.

A linear body with no prescribed dof (a free block) has its rigid translation c_b held apart from
w, u = T w + sum_b c_b e_b + offsets (:attr:`DynamicState.translation`), moved before each step to
the predicted one (:meth:`StabilisedNewmark._float`): K e_b = 0, so the stiffness multiplies the
deformation, not the travel (docs/dynamics.md Sect. 5).
"""

from __future__ import annotations

import dataclasses
import logging
import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import ufl

import dolfinx.fem.petsc
from dolfinx import fem

from contactqvi.contact.hyperelastic import HyperelasticSystem
from contactqvi.contact.problem import ContactProblem
from contactqvi.contact.scd_newton import HYPERELASTIC_TOL, SCDNewtonResult, SCDNewtonSolver
from contactqvi.time_scheme import TimeScheme
from contactqvi.elasticity import displacement_degree, lame_parameters
from contactqvi.laws import Frictionless
from contactqvi.lifetime import PETScOwner, VectorSet
from contactqvi.linalg import default_options
from contactqvi.load_steps import LoadStep, at_time
from contactqvi.parameters import require
from contactqvi.postprocess import internal_force_form, load_form

__all__ = ["ENERGY_TERMS", "MASS_RTOL", "STEP_TOL", "BodyMotion", "DynamicState", "InertialSystem", "PhysicalEnergy",
           "StabilisedNewmark", "global_components", "global_mass_matrix", "mass_matrix"]

logger = logging.getLogger(__name__)

#: Relative tolerance of the mass solves M â = m of the schemes that carry â (CG, Jacobi: the
#: consistent mass is spectrally equivalent to its diagonal, some 20 iterations).
MASS_RTOL = 1e-12
#: ``tol`` of a frictional time step's Newton steps and of its projection's (3.2) unless ``[solver]
#: tol`` is given: a hyperelastic step's, for a linear body too. In A_eff = K + c M a body's motion
#: along the contact surface is held by the mass term alone, and Krylov solves to the load path's 0.1
#: left it far off while friction decides between stick and slip (a block carried by a moving belt,
#: GAMG: 30-39 Newton steps per sticking step, 249 in all; to 1e-3: 118; exact solves: 75; the shipped
#: sliding_block 181 -> 114 Newton steps, its solver 0.13 -> 0.09 s). Without friction the load path's
#: tolerance stays: the drop test on benchmarks/dynamics_cost.py's medium mesh took 7.6 Newton steps
#: per time step instead of 9.4 to 1e-3, but 1.25 s instead of 0.83 (docs/dynamics.md Sect. 3.4).
STEP_TOL = HYPERELASTIC_TOL
#: The energy terms of a step (J), as in ``summary.json`` (docs/dynamics.md, Sect. 4).
ENERGY_TERMS = ("kinetic", "elastic", "external_work", "support_work", "friction_dissipation", "contact_work",
                "balance_error")


def global_mass_matrix(problem: ContactProblem, density: float | fem.Function) -> tuple[PETSc.Mat, np.ndarray]:
    """M_K = (rho u, v), the consistent mass matrix in global components, with zero rows and
    columns at the prescribed dofs (so that A + c M keeps A's identity rows), and each owned
    node's diagonal entry before that (kg; its three components' alike)."""
    V = problem.V
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    M_K = dolfinx.fem.petsc.assemble_matrix(fem.form(density * ufl.inner(u, v) * ufl.dx))
    M_K.assemble()
    diagonal = M_K.getDiagonal()
    nodal = diagonal.array.reshape(-1, 3)[:, 0].copy()
    diagonal.destroy()
    n_owned = 3 * V.dofmap.index_map.size_local
    owned = problem.dirichlet_dofs_loc[problem.dirichlet_dofs_loc < n_owned]
    M_K.zeroRowsColumns((owned + 3 * V.dofmap.index_map.local_range[0]).astype(PETSc.IntType), diag=0.0)
    return M_K, nodal


def mass_matrix(problem: ContactProblem, M_K: PETSc.Mat) -> PETSc.Mat:
    """M = T^T M_K T in the solver's variables of :func:`global_mass_matrix` (a new matrix; M_K
    itself without a change of variables)."""
    T = problem.to_global
    if T is None:
        return M_K.duplicate(copy=True)
    with default_options("", {"mat_product_clear": True}):
        return M_K.PtAP(T)


@dataclasses.dataclass
class InertialSystem(HyperelasticSystem):
    """f of the step (3.3) for a hyperelastic body (docs/dynamics.md, Sect. 3.1): in global
    components, with r_K(u) = int P(F) : grad v dX - lambda_{n+1} l(v) of
    :class:`~contactqvi.contact.hyperelastic.HyperelasticSystem` (zero on the prescribed rows),

        r(u) = r_K(u) + c M_K u + b,   b = -c M_K u_bar + (alpha_f r_K(u_n) + c_a m_n) / (1 - alpha_f),
        dr/du = K_T(u) + c M_K,        (lambda_n in r_K(u_n); c, c_a of the time scheme)

    m_n the inertial force without contact (-r_K(u_n) for Newmark's rule; (3.6) of docs/dynamics.md):
    the linear step's c M (w - w_bar) + K w - F_{n+1} - (alpha_f g_n - c_a m_n) / (1 - alpha_f) with the
    internal force P(F) in place of K w. The problem maps r and dr/du to its variables
    (:meth:`~contactqvi.contact.problem.ContactProblem.residual`, ``tangent``) as for a static
    step; :class:`StabilisedNewmark` sets ``coefficient`` and ``inertia`` per step.

    Attributes:
        mass: M_K (global components, zero rows and columns at the prescribed dofs; not owned).
        coefficient: c of the scheme and the current time step (:meth:`TimeScheme.inertia_coefficient`).
        inertia: b (global components, ghosted; not owned).
        work: a vector for M_K u (not owned).
        density: rho of M_K = (rho u, v) (number or DG0 function).
    """

    mass: PETSc.Mat | None = None
    coefficient: float = 0.0
    inertia: PETSc.Vec | None = None
    work: PETSc.Vec | None = None
    density: typing.Any = None

    def mass_term(self) -> tuple[float, typing.Any] | None:
        """(c, rho) of the term c M_K u while c > 0 and rho is known, else None."""
        return (self.coefficient, self.density) if self.coefficient > 0.0 and self.density is not None else None

    def assemble_residual(self, load_factor: float, condensed: bool = False) -> PETSc.Vec:
        r = super().assemble_residual(load_factor, condensed)
        self.mass.mult(self.displacement.x.petsc_vec, self.work)
        r.axpy(self.coefficient, self.work)
        r.axpy(1.0, self.inertia)
        return r

    def assemble_tangent(self, out: PETSc.Mat) -> PETSc.Mat:
        super().assemble_tangent(out)
        out.axpy(self.coefficient, self.mass, PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
        return out


@dataclasses.dataclass
class DynamicState(PETScOwner):
    """A time integration after its first ``done`` steps: all that the next step reads.

    Attributes:
        done: number of converged time steps.
        time: t_done (s).
        displacement: w_n in the solver's variables (without the shift).
        physical: u_n, the physical displacement in global components (owned dofs of the
            displacement space; the energies' variable).
        velocity: v_n in the solver's variables (m/s).
        acceleration: (v_n - v_{n-1}) / tau, the last step's mean acceleration (m/s^2), zero at
            time 0; output only, no step reads it.
        newmark_acceleration: Newmark's a_n in the solver's variables (m/s^2), and
        inertial_force: m_n, the inertial force without the contact forces (N; in the variables
            of f: the solver's for a linear body, global components for a hyperelastic one; zero
            at the prescribed dofs), both for the schemes that carry them
            (:attr:`TimeScheme.carries_acceleration`), zero for Newmark's rule.
        contact_forces: the last step's mean contact force per owned contact node, normal (N,
            >= 0) and tangential ((N, 2), nodal frames) as the solver reports them (docs/dynamics.md
            Sect. 3.2); empty at time 0; output only.
        energy: the step's energy terms (:data:`ENERGY_TERMS`), the works and the dissipation
            summed from time 0 (J).
        initial_energy: kinetic + elastic energy at time 0 (J).
        translation: (bodies, 3) rigid translation c_b of each body held apart from w_n (m, global
            axes; :meth:`StabilisedNewmark.step`): u_n = T w_n + sum_b c_b e_b + offsets.
    """

    done: int
    time: float
    displacement: PETSc.Vec
    physical: PETSc.Vec
    velocity: PETSc.Vec
    acceleration: PETSc.Vec
    newmark_acceleration: PETSc.Vec
    inertial_force: PETSc.Vec
    energy: dict[str, float]
    initial_energy: float
    contact_forces: tuple[np.ndarray, np.ndarray] = (np.empty(0), np.empty((0, 2)))
    translation: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 3)))

    def petsc_objects(self) -> list[typing.Any]:
        return [self.displacement, self.physical, self.velocity, self.acceleration, self.newmark_acceleration,
                self.inertial_force]


@dataclasses.dataclass
class _Work(VectorSet):
    """The vectors of one time step (solver variables), reused by every step: ``scratch`` for
    products, the predictor w_pred (3.1) (then delta = w_bar - w_pred), the projected w_bar (3.2),
    the next displacement w_{n+1}, its increment Delta w, the velocity change (3.4), the
    load F_n of the step's start (then any load), the force without contact g_n there (in
    the variables of :attr:`DynamicState.inertial_force`) and the contact force of the step
    (solver's variables)."""

    scratch: PETSc.Vec
    predicted: PETSc.Vec
    projected: PETSc.Vec
    next_displacement: PETSc.Vec
    increment: PETSc.Vec
    velocity_change: PETSc.Vec
    previous_load: PETSc.Vec
    previous_force: PETSc.Vec
    contact_force: PETSc.Vec


class PhysicalEnergy(PETScOwner):
    """The elastic energy and the works of the loads and of the supports in the physical
    displacement u (global components; docs/dynamics.md (4.2)), from the internal force K u
    assembled without boundary conditions (:func:`~contactqvi.postprocess.internal_force_form`)
    and the loads f at load factor 1 (tractions, pressures, body force; unlifted), so that
    prescribed motions do work and the elastic energy is the body's whatever its supports.
    Over a step from u_n to u_{n+1}, with Delta u = u_{n+1} - u_n and the load factors l_n, l_{n+1}:

        Delta E_el = 1/2 Delta u . K (u_n + u_{n+1})                    (exact: K symmetric, constant)
        W_ext     += 1/2 (l_n + l_{n+1}) Delta u . f
        W_support += 1/2 Delta u_p . (K (u_n + u_{n+1}) - (l_n + l_{n+1}) f)_p   (prescribed dofs p)

    Attributes:
        field: a displacement Function, the forms' argument (:meth:`step` sets it).
    """

    def __init__(self, problem: ContactProblem):
        V, body = problem.V, problem.body
        v = ufl.TestFunction(V)
        self.field = fem.Function(V)
        internal, self._update = internal_force_form(self.field, v, body)
        self._internal = fem.form(internal)
        self._stored = None
        if body.material is not None:  # psi(F) of a hyperelastic body (the linear one: 1/2 u . K u)
            mu, lmbda = lame_parameters(body.young, body.poisson)
            F = ufl.Identity(3) + ufl.grad(self.field)
            dx = body.material.dx(displacement_degree(V))
            self._stored = fem.form(body.material.strain_energy(F, mu, lmbda) * dx)
        self.internal_force = dolfinx.fem.petsc.create_vector(self._internal)
        self.load = dolfinx.fem.petsc.assemble_vector(fem.form(load_form(V.mesh, v, body, 1.0)))
        self.load.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        n_owned = 3 * V.dofmap.index_map.size_local
        self.prescribed = problem.dirichlet_dofs_loc[problem.dirichlet_dofs_loc < n_owned]
        self._increment, self._before = self.load.duplicate(), self.load.duplicate()

    def petsc_objects(self) -> list[typing.Any]:
        return [self.internal_force, self.load, self._increment, self._before]

    def step(self, before: PETSc.Vec, after: PETSc.Vec, loads: tuple[float, float]) -> dict[str, float]:
        """The increments of ``elastic``, ``external_work`` and ``support_work`` from the physical
        displacement ``before`` to ``after`` (owned dofs) at the load factors ``loads``: (4.2) of
        docs/dynamics.md; for a hyperelastic body Delta E_el = Psi(u_{n+1}) - Psi(u_n), Psi = int
        psi(F) dX, and K (u_n + u_{n+1}) the sum of the internal forces at u_n and u_{n+1}. Collective."""
        increment, comm = self._increment, self.load.comm.tompi4py()
        increment.waxpy(-1.0, before, after)
        if self._stored is None:
            self._internal_force_at(before, after)  # K (u_n + u_{n+1})
            elastic = 0.5 * increment.dot(self.internal_force)
        else:
            stored_before = self._internal_force_at(before)
            self.internal_force.copy(self._before)
            elastic = self._internal_force_at(after) - stored_before
            self.internal_force.axpy(1.0, self._before)
        factor = loads[0] + loads[1]
        self.internal_force.axpy(-factor, self.load)  # K (u_n + u_{n+1}) - (l_n + l_{n+1}) f
        p = self.prescribed
        support = 0.5 * float(np.dot(increment.array[p], self.internal_force.array[p]))
        return {"elastic": elastic, "external_work": 0.5 * factor * increment.dot(self.load),
                "support_work": comm.allreduce(support, op=MPI.SUM)}

    def _internal_force_at(self, x: PETSc.Vec, y: PETSc.Vec | None = None) -> float:
        """The internal force at the displacement x (+ y) into :attr:`internal_force`; returns
        Psi there for a hyperelastic body (else 0). Collective."""
        field = self.field.x.petsc_vec
        x.copy(field)
        if y is not None:
            field.axpy(1.0, y)
        self.field.x.scatter_forward()
        self._update()
        with self.internal_force.localForm() as local:
            local.set(0.0)
        dolfinx.fem.petsc.assemble_vector(self.internal_force, self._internal)
        self.internal_force.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        if self._stored is None:
            return 0.0
        return self.field.function_space.mesh.comm.allreduce(fem.assemble_scalar(self._stored), op=MPI.SUM)


class StabilisedNewmark(PETScOwner):
    """A contact-stabilised scheme of the Newmark family (module docstring) on a linear or
    hyperelastic ``problem``.

    For a linear body turns ``problem.A`` into A_eff = K + c M in place (K is kept as a copy for
    the step's load); a hyperelastic body's f and Jacobian, which the solver assembles at every
    Newton step into A, get the inertia from an :class:`InertialSystem` that takes the place of
    ``problem.hyperelastic`` while the integrator lives (put back by :meth:`destroy`). Owns the
    two SCD solvers, the M-projection of the predictor and the implicit step. The problem's
    contact is searched once (M and T of the reference configuration) or, for pairs searched
    ``"every_step"``, again after every step (:meth:`search`, which the runner calls).
    ``parameters`` and ``prefix`` are the SCD solver's; the projection's Krylov solver reads its
    options under ``prefix + "predictor_"``. The loads, prescribed displacements and the
    obstacles' and moved groups' translation and rotation follow the time points ``path``
    (:func:`~contactqvi.load_steps.at_time`; the default: constant loads).

    Attributes:
        scheme: the time scheme (α_m, α_f, β, γ).
        prescribed: owned local indices of the prescribed dofs in the solver's variables.
        tau: the time step A_eff and the step's solver are made for (s).
        motion: each body's mass-weighted mean motion and rigid translations (:class:`BodyMotion`).
        floating: (bodies,) whether a body's translation is held apart from w (:meth:`_float`).
    """

    def __init__(self, problem: ContactProblem, density: float | fem.Function, dt: float,
                 parameters: dict | None = None, prefix: str = "dynamics_",
                 path: typing.Sequence[LoadStep] = (LoadStep(),), scheme: TimeScheme = TimeScheme.newmark()):
        require(not (problem.settles_geometry or problem.follows_geometry), "dynamics",
                "a time step searches its contact once or before each step, not until it settles or at each Newton "
                "step (docs/dynamics.md)")
        require(problem.hyperelastic is None or problem.body.nodal is None, "material.formulation",
                "[dynamics] takes a hyperelastic body in the displacement formulation")
        require(dt > 0.0, "dynamics.dt", f"the time step must be > 0 (s), got {dt!r}")
        self.problem, self.tau, self.path, self.scheme = problem, float(dt), tuple(path), scheme
        frictional = any(interface.pair.law.frictional for interface in problem.interfaces)
        self._parameters = {**({"tol": STEP_TOL} if frictional else {}), **(parameters or {})}
        self._prefix = prefix
        self.global_mass, self._nodal_mass = global_mass_matrix(problem, density)
        self.static = problem.hyperelastic
        if self.static is not None:
            inertia = self.static.internal.duplicate()
            problem.hyperelastic = InertialSystem(
                **{f.name: getattr(self.static, f.name) for f in dataclasses.fields(self.static)},
                mass=self.global_mass, coefficient=scheme.inertia_coefficient(self.tau), inertia=inertia,
                work=inertia.duplicate(), density=density)
        self._assemble()
        self.energy = PhysicalEnergy(problem)
        self._work = _Work.create(problem.A)
        self.motion = BodyMotion(problem, self.global_mass)
        self.floating = self._floating_bodies()

    def _assemble(self) -> None:
        """What depends on the problem's last search (its T): M = T^T M_K T, a linear body's K
        (a copy of A) and A_eff = K + c M in A, the projection's M_p and problem, the
        prescribed rows and the two SCD solvers."""
        problem = self.problem
        self.mass = mass_matrix(problem, self.global_mass)
        self.stiffness = None
        if self.static is None:
            self.stiffness = problem.A.duplicate(copy=True)
            problem.A.axpy(self.scheme.inertia_coefficient(self.tau), self.mass,
                           PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
        self.projection_matrix = self.mass.duplicate(copy=True)
        diagonal = self.mass.getDiagonal()
        self.prescribed = _zero_rows(diagonal)
        diagonal.set(0.0)
        diagonal.array[self.prescribed] = self._nodal_mass[self.prescribed // 3]  # the node's mass: gamma, scaling
        self.projection_matrix.setDiagonal(diagonal, addv=PETSc.InsertMode.ADD_VALUES)
        diagonal.destroy()
        self.projection = dataclasses.replace(problem, A=self.projection_matrix, load=problem.load.duplicate(),
                                              unshifted=problem.load.duplicate(),
                                              law=Frictionless().lumped(problem.contact_area), hyperelastic=None)
        self.predictor_solver = SCDNewtonSolver(self.projection, self._projection_parameters(),
                                                prefix=self._prefix + "predictor_")
        self.solver = SCDNewtonSolver(problem, self._parameters, prefix=self._prefix)

    def _projection_parameters(self) -> dict:
        """The SCD parameters of the projection (3.2): the step's, with GMRES + point Jacobi for its
        Newton steps unless they are exact (``pc = "lu"``; docs/dynamics.md Sect. 3.2): M_p is
        spectrally equivalent to its diagonal, and on a graded mesh its rows span the nodes'
        masses (6e-7 to 1e3 kg on the Hertz block), where a residual in force units is the
        heavy rows' round-off."""
        parameters = dict(self._parameters or {})
        if parameters.get("pc", "gamg") != "lu":
            parameters["pc"] = "jacobi"
        return parameters

    def _assembled(self) -> list[typing.Any]:
        """The PETSc objects of :meth:`_assemble`."""
        return [self.predictor_solver, self.solver, self.mass, self.stiffness, self.projection_matrix,
                self.projection.load, self.projection.unshifted]

    def petsc_objects(self) -> list[typing.Any]:
        """The solvers, M, M_K, K, the projection's matrix and load, the energies' vectors, the work
        vectors and a hyperelastic step's inertia vectors (not the problem's)."""
        system = self.problem.hyperelastic
        inertial = [system.inertia, system.work] if isinstance(system, InertialSystem) else []
        return [*self._assembled(), self.global_mass, self.energy, self._work, self.motion, *inertial]

    def _floating_bodies(self) -> np.ndarray:
        """Whether each body (:attr:`BodyMotion.translations`' order) has its translation held apart
        from w (:meth:`_float`): the linear bodies none of whose dofs is prescribed (their
        stiffness has the rigid translations in its kernel). Collective."""
        problem = self.problem
        held = np.zeros(len(self.motion.translations), dtype=np.int32)
        if self.static is not None:
            return np.zeros(len(held), dtype=bool)
        nodes = problem.dirichlet_dofs_loc // 3
        held[np.zeros(len(nodes), dtype=np.int32) if problem.node_body is None else problem.node_body[nodes]] = 1
        problem.comm.Allreduce(MPI.IN_PLACE, held, op=MPI.MAX)
        return held == 0

    def search(self, state: DynamicState, carry: bool = True) -> None:
        """Search the problem's pairs again in the configuration ``state`` ended in (its physical
        displacement u_n; docs/dynamics.md Sect. 3.3) and rebuild what depends on T
        (:meth:`_assemble`). With ``carry`` the state's vectors in the solver's variables are
        carried over to the new ones: w_n = T^-1 (u_n - offsets), the velocity and the
        accelerations by T_new^-1 T_old, m_n of a linear body by T_new^T T_old^-T (a hyperelastic
        body's m_n is in global components); without, they are left as they are (a restart reads
        them in the new variables). Collective."""
        problem, scheme = self.problem, self.scheme
        carried = [state.velocity, state.acceleration, state.newmark_acceleration] if carry else []
        forces = [state.inertial_force] if carry and self.static is None and scheme.carries_acceleration else []
        moved = [x.copy() for x in carried + forces]
        field = fem.Function(problem.V)
        for x, y in zip(carried, moved):
            global_components(problem, x, field).x.petsc_vec.copy(y)
        for x, y in zip(forces, moved[len(carried):]):
            problem.force_to_global(x, y)
        state.physical.copy(field.x.petsc_vec)
        field.x.scatter_forward()
        problem.search(field)
        for obj in self._assembled():
            if obj is not None:
                obj.destroy()
        self._assemble()
        if carry:
            field.x.petsc_vec.axpy(-1.0, self.motion.translate(state.translation))
            problem.solver_variables(field, state.displacement)
            for x, y in zip(carried, moved):
                problem.from_global(y, x)
            for x, y in zip(forces, moved[len(carried):]):
                problem.force_from_global(y, x)
        for y in moved:
            y.destroy()

    def resume(self, state: DynamicState) -> None:
        """Put the problem where ``state``, read from a checkpoint, left it: its loads, obstacles
        and moved groups at ``state.time`` and, for pairs searched every step, the search there
        (:meth:`search` without carrying: the checkpoint holds the vectors in those variables).
        Nothing to do at time 0. Collective."""
        if state.done == 0:
            return
        at = at_time(self.path, state.time)
        self.problem.set_step(at.load, at.translation, rotation=at.rotation)
        if self.problem.searched_each_step:
            self.search(state, carry=False)

    def destroy(self) -> None:
        """Free the PETSc objects (collective) and give the problem back its static hyperelastic system."""
        super().destroy()
        if self.static is not None:
            self.problem.hyperelastic = self.static

    def initial_state(self, velocity: PETSc.Vec | None = None) -> DynamicState:
        """The state at time 0: at rest in the reference configuration with the initial velocity
        ``velocity`` (solver variables; None: zero), zero at the prescribed dofs, and for a scheme
        that carries them the loads' force m_0 = g_0 of time 0 and the acceleration a_0 = M^-1 g_0
        (the bodies start free of contact forces)."""
        w, v, a, newmark, force = (self.problem.A.createVecRight() for _ in range(5))
        physical = self.energy.load.copy()
        for vector in (w, v, a, newmark, force, physical):
            vector.set(0.0)
        if velocity is not None:
            velocity.copy(v)
            v.array[self.prescribed] = 0.0
        if self.scheme.carries_acceleration:
            self._free_force(at_time(self.path, 0.0), w, None, force)
            self._initial_acceleration(force, newmark)
        energy = {name: 0.0 for name in ENERGY_TERMS}
        energy["kinetic"] = 0.5 * _energy_norm(self.mass, v, self._work.scratch)
        return DynamicState(0, 0.0, w, physical, v, a, newmark, force, energy, energy["kinetic"],
                            translation=np.zeros((len(self.floating), 3)))

    def step(self, state: DynamicState, u: PETSc.Vec, tau: float | None = None,
             stop: typing.Callable[[], bool] | None = None) -> tuple[SCDNewtonResult, SCDNewtonResult]:
        """One time step of length ``tau`` (None: the last one's) from ``state``: the projected
        predictor (3.1)-(3.2) and the step (3.3) of docs/dynamics.md, each solved by SCD Newton,
        the loads and obstacles at t_{n+1} = ``state.time`` + tau; ``u`` holds the step's solution
        (shifted). The state is advanced (:meth:`_record`; its time, not ``done``) only when both
        converged. Returns both results."""
        self._use_time_step(self.tau if tau is None else tau)
        problem, tau = self.problem, self.tau
        predicted, projected = self._work.predicted, self._work.projected
        before, after = at_time(self.path, state.time), at_time(self.path, state.time + tau)
        problem.step_load(before.load, before.translation, before.rotation, self._work.previous_load)
        if self.static is None:  # g_n = F_n - K w_n before the translation moves (K e_b = 0)
            force = self._work.previous_force
            self.stiffness.mult(state.displacement, force)
            force.aypx(-1.0, self._work.previous_load)
            force.array[self.prescribed] = 0.0
        held = self._float(state, tau)
        problem.set_step(after.load, after.translation, previous=state.displacement, rotation=after.rotation,
                         previous_translation=before.translation, previous_rotation=before.rotation, held=held)
        # d: gaps at t_{n+1}, slip measured from w_n and the obstacles' motion over the step
        predicted.waxpy(tau, state.velocity, state.displacement)
        self.projection_matrix.mult(predicted, self.projection.unshifted)
        self.projection.shift_load()
        u.waxpy(1.0, predicted, problem.shift)
        projection = self.predictor_solver.solve(u, stop=stop)
        if not projection.converged:
            return projection, projection
        projected.waxpy(-1.0, problem.shift, u)
        if self.static is None:
            self._add_inertia(state, projected)
        else:
            self._set_inertia(state, u, before.load)
        result = self.solver.solve(u, stop=stop)
        if result.converged:
            self._record(state, u, result, (before, after))
        return projection, result

    def _float(self, state: DynamicState, tau: float) -> PETSc.Vec | None:
        """Hold the predicted translation of each floating body (:attr:`floating`) apart from w:
        c_b += the mass-weighted mean over body b of w_n + tau v_n + tau^2/2 a (a the last step's
        mean acceleration), w_n -= T^-1 e_b times it. Returns T^-1 sum_b c_b e_b (the work vector
        ``increment``; None without floating bodies), whose normal components at the contact nodes
        the gaps take (:meth:`~contactqvi.contact.problem.ContactProblem.set_step`). An exact change
        of variables, K T^-1 e_b = 0: the stiffness then multiplies the deformation and the step's
        departure from the predicted translation, where the travel made its products round-off of
        K |u| (docs/dynamics.md Sect. 5)."""
        if not self.floating.any():
            return None
        x, held = self._work.scratch, self._work.increment
        x.waxpy(tau, state.velocity, state.displacement)
        x.axpy(0.5 * tau**2, state.acceleration)
        change = np.array(list(self.motion.velocities(x).values())) * self.floating[:, None]
        state.translation += change
        self.problem.from_global(self.motion.translate(change), x)
        state.displacement.axpy(-1.0, x)
        return self.problem.from_global(self.motion.translate(state.translation), held)

    def mean_displacements(self, state: DynamicState) -> dict[str, list[float]]:
        """Each body's mass-weighted mean displacement (m, global axes) at ``state``: of w_n and the
        translation held apart. Collective."""
        means = self.motion.velocities(state.displacement).items()
        return {name: [m + c for m, c in zip(mean, held)] for (name, mean), held in zip(means, state.translation)}

    def _use_time_step(self, tau: float) -> None:
        """Make A_eff = K + c M and the step's solver (its gamma and preconditioner are A_eff's)
        for ``tau``, unless they are made for it (to round-off)."""
        require(tau > 0.0, "dynamics.dt", f"the time step must be > 0 (s), got {tau!r}")
        if abs(tau - self.tau) <= 1e-12 * self.tau:
            return
        scheme = self.scheme
        if self.static is None:
            self.problem.A.axpy(scheme.inertia_coefficient(tau) - scheme.inertia_coefficient(self.tau), self.mass,
                                PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
        else:
            self.problem.hyperelastic.coefficient = scheme.inertia_coefficient(tau)
        self.tau = float(tau)
        self.solver.destroy()
        self.solver = SCDNewtonSolver(self.problem, self._parameters, prefix=self._prefix)

    def _add_inertia(self, state: DynamicState, projected: PETSc.Vec) -> None:
        """The step's load of (3.3): l = F_{n+1} + A_eff d (set_step) + c M w_bar + (alpha_f g_n -
        c_a m_n) / (1 - alpha_f), g_n = F_n - K w_n zero at the prescribed rows, m_n = g_n for
        Newmark's rule (c_a = -1, alpha_f = 0: the last term is g_n)."""
        problem, work, scheme = self.problem, self._work.scratch, self.scheme
        self.mass.mult(projected, work)
        load = problem.unshifted
        load.axpy(scheme.inertia_coefficient(self.tau), work)
        force = self._work.previous_force
        history = state.inertial_force if scheme.carries_acceleration else force
        load.axpy(-scheme.history_factor / (1.0 - scheme.alpha_f), history)
        if scheme.alpha_f != 0.0:
            load.axpy(scheme.alpha_f / (1.0 - scheme.alpha_f), force)
        problem.shift_load()

    def _set_inertia(self, state: DynamicState, u: PETSc.Vec, load: float) -> None:
        """The hyperelastic step's b = -c M_K u_bar + (alpha_f r_K(u_n) + c_a m_n) / (1 - alpha_f) at
        the load factor ``load`` of t_n (:class:`InertialSystem`; u_bar the physical displacement
        of the projected ``u``), m_n = -r_K(u_n) for Newmark's rule; g_n = -r_K(u_n) kept for
        the update of m (global components)."""
        system, problem, scheme = self.problem.hyperelastic, self.problem, self.scheme
        problem.physical_displacement(u, system.displacement)
        self.global_mass.mult(system.displacement.x.petsc_vec, system.inertia)
        system.inertia.scale(-system.coefficient)
        state.physical.copy(system.displacement.x.petsc_vec)
        system.displacement.x.scatter_forward()
        residual = HyperelasticSystem.assemble_residual(system, load)
        if not scheme.carries_acceleration:
            system.inertia.axpy(-scheme.history_factor / (1.0 - scheme.alpha_f), residual)
            return
        system.inertia.axpy(scheme.alpha_f / (1.0 - scheme.alpha_f), residual)
        system.inertia.axpy(scheme.history_factor / (1.0 - scheme.alpha_f), state.inertial_force)
        force = self._work.previous_force
        force.array[:] = residual.array_r[: force.getLocalSize()]
        force.scale(-1.0)

    def _free_force(self, step: LoadStep, w: PETSc.Vec, u: PETSc.Vec | None, out: PETSc.Vec) -> None:
        """g = F - K w without contact, zero at the prescribed rows, at the load factor and
        translation of ``step``: of a linear body from w (solver's variables), of a hyperelastic
        one -r_K at the physical displacement of the shifted ``u`` (None: zero; global
        components). Uses the work vector ``previous_load``."""
        problem = self.problem
        if self.static is None:
            self.stiffness.mult(w, out)
            problem.step_load(step.load, step.translation, step.rotation, self._work.previous_load)
            out.aypx(-1.0, self._work.previous_load)
        else:
            system = problem.hyperelastic
            if u is None:
                system.displacement.x.array[:] = 0.0
            else:
                problem.physical_displacement(u, system.displacement)
            out.array[:] = HyperelasticSystem.assemble_residual(system, step.load).array_r[: out.getLocalSize()]
            out.scale(-1.0)
            return
        out.array[self.prescribed] = 0.0

    def _initial_acceleration(self, force: PETSc.Vec, out: PETSc.Vec) -> None:
        """a_0 = M^-1 g_0 (solver's variables; zero at the prescribed rows, where M_p has identity
        rows) of the force ``force`` of :meth:`_free_force`: CG with Jacobi to :data:`MASS_RTOL`
        (options under the integrator's prefix + ``"mass_"``)."""
        rhs = self._work.scratch
        if self.static is None:
            force.copy(rhs)
        else:
            self.problem.force_from_global(force, rhs)
            rhs.array[self.prescribed] = 0.0
        ksp = PETSc.KSP().create(self.mass.getComm())
        try:
            ksp.setOperators(self.projection_matrix)
            ksp.setType(PETSc.KSP.Type.CG)
            ksp.getPC().setType(PETSc.PC.Type.JACOBI)
            ksp.setTolerances(rtol=MASS_RTOL, atol=0.0, max_it=1000)
            ksp.setOptionsPrefix(self._prefix + "mass_")
            ksp.setFromOptions()
            ksp.solve(rhs, out)
            if ksp.getConvergedReason() <= 0:
                raise RuntimeError(f"the mass solve M a_0 = g_0 of the initial acceleration did not converge (KSP "
                                   f"reason {ksp.getConvergedReason()}, {ksp.getIterationNumber()} iterations)")
        finally:
            ksp.destroy()

    def _contact_part(self, state: DynamicState, out: PETSc.Vec) -> None:
        """d = m - M a of ``state`` in the solver's variables (T^T m for a hyperelastic body): the
        contact forces that Newmark's acceleration holds and the inertial force without contact
        does not (3.7), zero at the prescribed rows. Uses the work vector ``previous_load``."""
        if self.static is None:
            state.inertial_force.copy(out)
        else:
            self.problem.force_from_global(state.inertial_force, out)
        self.mass.mult(state.newmark_acceleration, self._work.previous_load)
        out.axpy(-1.0, self._work.previous_load)
        out.array[self.prescribed] = 0.0

    def _record(self, state: DynamicState, u: PETSc.Vec, result: SCDNewtonResult,
                steps: tuple[LoadStep, LoadStep]) -> None:
        """Advance ``state`` over the step just solved: w_{n+1} = u - d, u_{n+1}, v_{n+1} (3.4), a_{n+1}
        and m_{n+1} (3.6) of a scheme that carries them, the step's mean acceleration, the time
        and the energy terms (4.1)-(4.2) of docs/dynamics.md."""
        problem, tau, work, scheme = self.problem, self.tau, self._work, self.scheme
        w_next, increment, velocity_change = work.next_displacement, work.increment, work.velocity_change
        w_next.waxpy(-1.0, problem.shift, u)
        increment.waxpy(-1.0, state.displacement, w_next)
        work.predicted.aypx(-1.0, work.projected)  # delta = w_bar - w_pred
        velocity_change.waxpy(-1.0, work.projected, w_next)
        if scheme.carries_acceleration:
            # velocity_change: w_{n+1} - w_bar in, v_{n+1} - v_n out
            self._advance_acceleration(state, steps[1], w_next, u)
            mean = work.contact_force.array.reshape(-1, 3)[problem.contact_blk]
            state.contact_forces = (mean[:, 2].copy(), mean[:, :2].copy())
        else:
            velocity_change.scale(2.0 / tau)  # v_{n+1} - v_n
            state.contact_forces = (0.5 * result.normal_force, 0.5 * result.friction_force)
        self.mass.mult(velocity_change, work.scratch)
        projection_work = -work.predicted.dot(work.scratch) / tau
        state.velocity.axpy(1.0, velocity_change)
        velocity_change.copy(state.acceleration)
        state.acceleration.scale(1.0 / tau)
        w_next.copy(state.displacement)
        physical = problem.physical_displacement(u, self.energy.field).x.petsc_vec.copy()
        physical.axpy(1.0, self.motion.translate(state.translation))
        changes = self.energy.step(state.physical, physical, (steps[0].load, steps[1].load))
        physical.copy(state.physical)
        physical.destroy()
        normal, tangential, friction = _contact_work(problem, state.contact_forces, increment, u)
        energy = state.energy
        for name, change in changes.items():
            energy[name] += change
        energy["friction_dissipation"] -= friction
        energy["contact_work"] += normal + tangential + projection_work
        energy["kinetic"] = 0.5 * _energy_norm(self.mass, state.velocity, work.scratch)
        stored = energy["kinetic"] + energy["elastic"] - state.initial_energy
        energy["balance_error"] = (stored - energy["external_work"] - energy["support_work"] - energy["contact_work"]
                                   + energy["friction_dissipation"])
        state.time += tau

    def _advance_acceleration(self, state: DynamicState, step: LoadStep, w_next: PETSc.Vec, u: PETSc.Vec) -> None:
        """Newmark's a_{n+1} = (w_{n+1} - w_bar)/(beta tau^2) - (1/2 - beta)/beta a_n, the velocity change
        tau ((1 - gamma) a_n + gamma a_{n+1}) into the work vector ``velocity_change`` (which holds
        w_{n+1} - w_bar), and m_{n+1} = ((1 - alpha_f) g_{n+1} + alpha_f g_n - alpha_m m_n)/(1 - alpha_m),
        the balance of the step without its contact forces (g_n of the step's start, g_{n+1} at
        ``step``), into ``state`` (3.6); the step's mean contact force -((1 - gamma) d_n + gamma d_{n+1}),
        d = m - M a (3.7), into the work vector ``contact_force``."""
        scheme, tau, change = self.scheme, self.tau, self._work.velocity_change
        a, d = state.newmark_acceleration, self._work.contact_force
        self._contact_part(state, d)  # d_n
        change.scale(1.0 / (scheme.beta * tau**2))
        change.axpy(-(0.5 - scheme.beta) / scheme.beta, a)  # a_{n+1}
        a.scale(tau * (1.0 - scheme.gamma))
        a.axpy(tau * scheme.gamma, change)  # v_{n+1} - v_n
        a.swap(change)
        m, g = state.inertial_force, self._work.scratch
        self._free_force(step, w_next, u, g)
        m.scale(-scheme.alpha_m)
        m.axpy(1.0 - scheme.alpha_f, g)
        m.axpy(scheme.alpha_f, self._work.previous_force)
        m.scale(1.0 / (1.0 - scheme.alpha_m))
        self._contact_part(state, g)  # d_{n+1}
        d.scale(-(1.0 - scheme.gamma))
        d.axpy(-scheme.gamma, g)


class BodyMotion(PETScOwner):
    """Each body's mean velocity, the mass-weighted v_b = e_b^T M_K T v / e_b^T M_K e_b per axis,
    with e_b the rigid translation of body b in global components (the momentum of the free
    dofs over their mass; a component prescribed on all of a body has no mass: 0). In global
    components, so that a new search (a new T) leaves it as it is.

    Args:
        problem: the contact problem (``node_body`` names the bodies; None: one body ``"body"``).
        mass: M_K of :func:`global_mass_matrix`.
    """

    def __init__(self, problem: ContactProblem, mass: PETSc.Mat):
        self.problem, self.mass = problem, mass
        names = list(problem.body.cell_tags.names) if problem.node_body is not None else ["body"]
        n = problem.V.dofmap.index_map.size_local
        node_body = problem.node_body[:n] if problem.node_body is not None else np.zeros(n, dtype=np.int32)
        self.translations: dict[str, list[PETSc.Vec]] = {}
        for k, name in enumerate(names):
            self.translations[name] = []
            for axis in range(3):
                z = mass.createVecRight()
                z.set(0.0)
                z.array.reshape(-1, 3)[node_body == k, axis] = 1.0
                self.translations[name].append(z)
        self._work, self._global = mass.createVecRight(), mass.createVecRight()
        self.masses = {name: [_energy_norm(mass, z, self._work) for z in zs] for name, zs in self.translations.items()}

    def petsc_objects(self) -> list[typing.Any]:
        """The translations and the work vectors (not M_K)."""
        return [*(z for zs in self.translations.values() for z in zs), self._work, self._global]

    def translate(self, translation: np.ndarray) -> PETSc.Vec:
        """sum_b t_b e_b of the (bodies, 3) translations ``translation`` (m; global components), in a
        work vector of this object."""
        self._global.set(0.0)
        for zs, t in zip(self.translations.values(), translation):
            for z, component in zip(zs, t):
                if component != 0.0:
                    self._global.axpy(component, z)
        return self._global

    def velocities(self, velocity: PETSc.Vec) -> dict[str, list[float]]:
        """Each body's mean velocity (m/s, global axes) of ``velocity`` (solver variables); of a
        displacement, its mean displacement (m). Collective."""
        self.mass.mult(self.problem.into_global(velocity, self._global), self._work)
        return {name: [z.dot(self._work) / m if m > 0.0 else 0.0 for z, m in zip(zs, self.masses[name])]
                for name, zs in self.translations.items()}


def _zero_rows(diagonal: PETSc.Vec) -> np.ndarray:
    """Owned local rows of M whose diagonal vanishes (to round-off of the largest): the prescribed
    dofs in the solver's variables (in nodal frames at a contact node with a roller), where M_K
    has zero rows and columns and A has identity rows."""
    largest = diagonal.norm(PETSc.NormType.NORM_INFINITY)
    return np.flatnonzero(np.abs(diagonal.array) <= 1e-12 * largest)


def _energy_norm(A: PETSc.Mat, x: PETSc.Vec, work: PETSc.Vec) -> float:
    """x^T A x (collective)."""
    A.mult(x, work)
    return x.dot(work)


def _contact_work(problem: ContactProblem, forces: tuple[np.ndarray, np.ndarray], increment: PETSc.Vec,
                  u: PETSc.Vec) -> tuple[float, float, float]:
    """The work of the step's mean contact forces ``forces`` = (lambda_n, R_t) (docs/dynamics.md
    (4.1)), summed over the contact nodes (nodal frames; the relative displacement at a body
    pair's slave nodes): on the body, lambda_n . Delta w_n (normal) and R_t . Delta w_t
    (tangential), and the friction's, R_t . u_t (<= 0) over the slip increment u_t relative to
    the obstacle (the shifted solution's tangential part; Delta w_t where the obstacle does not
    move). Collective."""
    nodal = increment.array.reshape(-1, 3)[problem.contact_blk]
    slip = u.array.reshape(-1, 3)[problem.contact_blk, :2]
    normal, friction = forces
    works = np.array([np.dot(normal, nodal[:, 2]), np.sum(friction * nodal[:, :2]), np.sum(friction * slip)])
    normal, tangential, friction = problem.comm.allreduce(works, op=MPI.SUM)
    return float(normal), float(tangential - friction), float(friction)


def global_components(problem: ContactProblem, x: PETSc.Vec, out: fem.Function) -> fem.Function:
    """T x: a velocity or acceleration in the solver's variables in global components (no shift,
    no offsets), written into ``out`` (ghosts updated)."""
    problem.into_global(x, out.x.petsc_vec)
    out.x.scatter_forward()
    return out
