"""A Newton-step preconditioner for nearly incompressible bodies: one sweep of the block
factorisation of the uncondensed displacement-pressure system (docs/nearly_incompressible.md,
Sect. 5).

With bodies of the averaged volume change (:mod:`contactqvi.nodal_pressure`) the Newton
matrix of (5.4) (seed 000) is, in the solver's variables (T the change of variables),

    J = J_r + L D P,   P = B T,   L = W P^T,   D = diag(U''(Jbar_a) / V_a),

with J_r the Newton matrix of everything but the averaged term B^T D B and W the rows' left
factor of (5.4) (the identity off the contact nodes,
:class:`~contactqvi.contact.newton_matrix.NewtonMatrix`). With rows eliminated by the SCD solver
(identity rows, their columns moved to the right-hand side) P loses their columns and L their
rows, but not their columns: L = K W (B T)^T, K the identity but at the eliminated rows. W couples
a sliding node's tangential rows to its normal row (Coulomb's bound follows the normal force),
which is eliminated; with L = W P^T those rows kept the bulk term in J_r (up to session 42: every
Krylov solve of a frictional Taylor-Hood block failed from nu = 0.49 on). J is the Schur complement
of the uncondensed system

    [ J - L D P   L             ] [du]   [r]
    [ Lambda P    -Lambda D^-1  ] [ p] = [0],

its pressure rows (a volume change) brought to force units by Lambda = diag(mu_a / h_a)
(h_a = V_a^(1/3), V_a = int chi phi_a). The Krylov method (FGMRES) runs on that system
(:meth:`PressureSchur.solve`): where it holds, p = D P du and J du = r. One sweep of its block
factorisation (the block preconditioners of saddle-point systems, Elman, Silvester & Wathen
2014) applied to (r, q),

    y = G r,   p = S~^-1 (P y - Lambda^-1 q),   du = G (r - L p),

preconditions it, with G one BoomerAMG V-cycle on J_r (no term of the bulk modulus) and
S~ = D^-1 + s S_loc the approximation of its Schur complement D^-1 + P J_r^-1 L by the summed
element Schur complements S_loc of the shear stiffness (:mod:`contactqvi.contact.local_schur`;
s = :data:`SCHUR_SCALE`), solved exactly (MUMPS; options prefix the V-cycle's + ``schur_``).
Where the displacement-pressure pair is inf-sup stable (quadratic displacements with the nodal P1
pressure: a Taylor-Hood pair with a lumped pressure mass) the preconditioned system's
eigenvalues are bounded independently of the bulk modulus. Up to session 41 S~ was
D^-1 + c M_L / mu (M_L = diag(V_a)): exact where D^-1 dominates, near nu = 0.5 only spectrally
equivalent, with constants of the cells' shapes (docs/nearly_incompressible.md, Sect. 5).

Krylov iterations on J itself with the same sweep (the Woodbury formula with S~ for S; up to
session 35) are not: J's preconditioned operator is I + L D (S~ - S) S~^-1 P J_r^-1, whose
spectrum spreads with D however well S~ approximates S. A residual of J reduced by tol then
left the shear part of the error, which decides the contact, far off: the two-body Hertz case at
nu = 0.4999 crept to its contact patch a node per Newton step (66, 48, 33, 20 Newton steps per
load step; exact solves 4, 3, 3, 3; the uncondensed system 6, 5, 6, 5). On the uncondensed
system J's residual is e_u + L D e_p, e_p the pressure rows' residual (:meth:`PressureSchur.solve`
goes on until J's residual meets the test). For linear displacements (P1/P1) the pressure modes
the pair does not control are left to the Krylov method, and the counts grow as with GAMG.

Eliminated rows (the SCD solver's identity rows, :meth:`NewtonMatrix.assemble`) have zero
columns in J: P gets them too, and L zero rows, so that J_r keeps J's identity rows and columns
there.

The V-cycle takes J_r without two things of J (docs/nearly_incompressible.md, Sect. 5):

* the nodal pressure's initial stress at finite strain, W T^T K_p T with K_p = int chi p_h
  d(J F^-T : grad v)[w] dX (the first term of (3) of :mod:`contactqvi.nodal_pressure`): it is
  indefinite, of the size of p_h, and an iterate whose volumes are off carries p_h of several
  shear moduli; with it in J_r the V-cycle diverged (the first Newton step of a block at
  nu = 0.4999: 2000 Krylov iterations and no convergence; without it 16);
* the entries B^T D B leaves in J's pattern, cancelled to round-off in J_r (:data:`CANCELLED`):
  a V-cycle on J's 2-ring stencil did 2.8 times the work.
"""

from __future__ import annotations

import dataclasses
import typing

from petsc4py import PETSc

import numpy as np
import ufl

import dolfinx.fem.petsc
from dolfinx import fem

from contactqvi.contact.local_schur import local_schur
from contactqvi.contact.newton_matrix import NewtonMatrix
from contactqvi.lifetime import PETScOwner, VectorSet
from contactqvi.linalg import OptionsDict, create_ksp, default_options, preset, significant
from contactqvi.nodal_pressure import VolumetricTangent

__all__ = ["PressureSchur"]

_DIFFERENT = PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN

#: s of S~ = D^-1 + s S_loc (S_loc bounds P J_r^-1 L from above). Measured on the P2 O-ring (h 0.25,
#: the first six steps, exact solves of J_r; Krylov iterations per Newton step at nu = 0.45 / 0.4999):
#: s = 1: 6.3 / 11.8; 0.5: 5.2 / 9.6; 0.25: 6.1 / 10.5; with the V-cycle, 20 steps: 0.5: 10.0 / 14.6,
#: 0.35: 11.3 / 16.1 (docs/nearly_incompressible.md, Sect. 5).
SCHUR_SCALE = 0.5
#: J_r = J - W P^T D P keeps J's entries of B^T D B, which couples every displacement dof with
#: the 2-ring of cells around it, as terms cancelled to round-off (bulk over shear modulus times
#: eps of their row); the V-cycle takes J_r without its entries below this fraction of their row.
CANCELLED = 1e-9
#: :meth:`PressureSchur.converged`: an uncondensed residual this fraction of its right-hand side ends
#: the solve whatever J's residual: round-off, beyond which the Krylov method gains nothing.
ROUND_OFF = 1e-13


class PressureSchur(PETScOwner):
    """The block preconditioner of this module (:meth:`context`: as a petsc4py ``python`` PC) and the
    uncondensed system it preconditions (:attr:`augmented`, solved by :meth:`solve`).

    Args:
        volumetric: the averaged term's B and D, assembled at the tangent the Newton matrix
            was built from (:class:`~contactqvi.nodal_pressure.VolumetricTangent`; not owned).
        mu: the shear modulus (number or DG0 expression) of S~.
        prefix: options prefix of the V-cycle on J_r (``{prefix}ksp_*``, ``{prefix}pc_*``).
        options: its default PC options; its KSP is ``preonly``.
    """

    def __init__(self, volumetric: VolumetricTangent, mu: typing.Any, prefix: str, options: OptionsDict):
        self.volumetric = volumetric
        volumetric.keep_initial_stress()
        self._options = {**options, "ksp_type": "preonly"}
        self.cycle = create_ksp(volumetric.B.getComm(), prefix, self._options)
        nodal = volumetric.nodal
        # int chi mu phi_a
        self._shear_volume = dolfinx.fem.petsc.assemble_vector(
            fem.form(nodal.chi * mu * ufl.TestFunction(nodal.Q) * nodal.dx))
        self._shear_volume.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        self.P: PETSc.Mat | None = None  # B T without the eliminated columns
        self._full: PETSc.Mat | None = None  # B T
        self._kept = volumetric.B.createVecRight()  # 0 at the eliminated rows, else 1
        self.reduced: PETSc.Mat | None = None  # J_r
        self._J: PETSc.Mat | None = None  # the Newton matrix of the last update (not owned)
        self._newton: NewtonMatrix | None = None
        self._scales = _Scales.create(self._shear_volume)
        self._mu = mu
        self._static = self._summed(None)  # s S_loc
        self._local = self._static  # s S_loc(c) of the mass term of :meth:`set_mass`, S_loc(0) without one
        self._mass: tuple[float, typing.Any] | None = None
        self._schur = self._local.duplicate(copy=True)  # S~
        self._schur_solver = create_ksp(volumetric.B.getComm(), f"{prefix}schur_", preset("lu"), self._schur)
        self._pressure = _Pressure.create(self._shear_volume)
        self._displacement: _Displacement | None = None
        self.augmented: PETSc.Mat | None = None  # the uncondensed system's operator
        self._rhs: PETSc.Vec | None = None  # its right-hand side and solution
        self._solution: PETSc.Vec | None = None
        self._condensed: PETSc.KSP | None = None  # J's own solver (:meth:`solve`)
        self._padded: tuple[PETSc.Vec, PETSc.Vec] = ()
        self._constrained = False
        self._trial: PETSc.Vec | None = None  # the iterate :meth:`converged` builds
        # :meth:`converged`'s tests, set by :meth:`solve`: the uncondensed residual's and J's
        self._tests = _Tests()
        #: the Krylov iteration of the last :meth:`solve` at which the uncondensed residual met rtol
        #: (None: never)
        self.uncondensed_iterations: int | None = None
        #: after a constrained :meth:`solve`: the linearised constraint's residual e_p / V_a that the
        #: solve left at the owned nodes (the Newton step's volume ratios take it, Sect. 7)
        self.missed = np.empty(0)

    def petsc_objects(self) -> list[typing.Any]:
        viscous = [] if self._local is self._static else [self._local]
        return [self.cycle, self.P, self._full, self._kept, self.reduced, self._shear_volume, self._scales,
                self._static, *viscous, self._schur, self._schur_solver, self._pressure, self._displacement,
                self.augmented, self._rhs, self._solution, self._trial, self._condensed, *self._padded]

    def _summed(self, mass: tuple[float, typing.Any] | None) -> PETSc.Mat:
        """s S_loc(c) of :func:`~contactqvi.contact.local_schur.local_schur` for the mass term ``mass``."""
        nodal = self.volumetric.nodal
        summed = local_schur(nodal.u.function_space, nodal.Q, self._mu, nodal.chi, mass)
        summed.scale(SCHUR_SCALE)
        return summed

    def set_mass(self, mass: tuple[float, typing.Any] | None) -> None:
        """The mass term (c, rho) of the displacement block for the next :meth:`update` (None: none):
        S~ takes the summed element Schur complements of A_e + c M_e (local_schur (2)), assembled again
        when c changes (a relaxation step's viscosity; collective)."""
        if mass == self._mass:
            return
        if self._local is not self._static:
            self._local.destroy()
        self._local = self._static if mass is None else self._summed(mass)
        self._mass = mass

    def update(self, J: PETSc.Mat, newton: NewtonMatrix, transform: PETSc.Mat | None, eliminated: np.ndarray) -> None:
        """J_r, P and Sigma^-1 for the Newton matrix J of ``newton`` (the averaged term at J's tangent),
        the change of variables ``transform`` (None: the identity) and the owned local rows
        ``eliminated`` by the SCD solver (collective)."""
        self._newton = newton
        B = self.volumetric.B
        for matrix in (self.P, self._full):
            if matrix is not None:
                matrix.destroy()
        self._full = B.matMult(transform) if transform is not None else B.copy()  # B T
        self._kept.set(1.0)
        self._kept.array[eliminated] = 0.0
        self.P = self._full.copy()
        self.P.diagonalScale(R=self._kept)
        product = self.volumetric.D.matMult(self.P)
        averaged = self._full.transposeMatMult(product)  # (B T)^T D P
        product.destroy()
        stress = self.volumetric.initial_stress
        if stress is not None:  # + T^T K_p T
            moved = stress.PtAP(transform) if transform is not None else stress.copy()
            moved.diagonalScale(R=self._kept)
            averaged.axpy(1.0, moved, _DIFFERENT)
            moved.destroy()
        scaled = newton.left_scaled(averaged)  # W ((B T)^T D P + T^T K_p T)
        scaled.diagonalScale(L=self._kept)
        averaged.destroy()
        wide = J.duplicate(copy=True)  # the matrices of J's 2-ring pattern go as soon as done with
        wide.axpy(-1.0, scaled, _DIFFERENT)
        scaled.destroy()
        if self.reduced is not None:
            self.reduced.destroy()
        self.reduced = significant(wide, CANCELLED)
        wide.destroy()
        self.reduced.setNearNullSpace(J.getNearNullSpace())
        self.cycle.setOperators(self.reduced)
        with default_options(self.cycle.getOptionsPrefix(), self._options):
            self.cycle.setUp()
        self._J = J
        self._set_pressure_scales()
        if self.augmented is None:
            self._create_augmented(J)

    def _set_pressure_scales(self) -> None:
        """D's diagonal d_a = U''_a / V_a, 1 / d_a, Lambda_a = mu_a / h_a = int chi mu phi_a / V_a^(4/3)
        (at the nodes of no averaged cell, P's zero rows with d_a = 0: 0, 1 and 1; there the system reads
        -Lambda p = q) and S~ = diag(1 / d_a) + s S_loc, factorised."""
        modulus = self.volumetric.D.getDiagonal()
        d = modulus.array_r
        volume = self.volumetric.nodal.volume.x.petsc_vec.array_r
        shear = self._shear_volume.array_r
        inside = (volume > 0) & (d > 0) & (shear > 0)
        s = self._scales
        s.modulus.array[:] = np.where(inside, d, 0.0)
        s.compliance.array[:] = np.divide(1.0, d, out=np.ones_like(d), where=inside)
        s.force.array[:] = np.divide(shear, np.cbrt(volume) * volume, out=np.ones_like(d), where=inside)
        modulus.destroy()
        self._local.copy(self._schur, PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
        self._schur.setDiagonal(s.compliance, addv=PETSc.InsertMode.ADD_VALUES)
        self._schur_solver.setUp()

    def _create_augmented(self, J: PETSc.Mat) -> None:
        """The uncondensed system's operator (a ``python`` Mat, :meth:`_mult`) and vectors: the
        displacement rows of J's layout followed by the pressure rows, on each rank."""
        self._displacement = _Displacement.create(J)
        size = J.getLocalSize()[0] + self._pressure.x.getLocalSize()
        self.augmented = PETSc.Mat().createPython(((size, PETSc.DECIDE), (size, PETSc.DECIDE)),
                                                  _Operator(self._mult), comm=J.getComm())
        self.augmented.setUp()
        self._rhs, self._solution = self.augmented.createVecs()
        self._trial = self._rhs.duplicate()

    def set_constraint(self, pressure: np.ndarray | None) -> None:
        """The mixed Newton method's linearised constraint for the next :meth:`solve`: ``pressure`` =
        U''(theta_a) (Jbar_a - theta_a) at the owned nodes, the pressure that its force g = L ``pressure``
        in the right-hand side stands for (docs/nearly_incompressible.md, Sect. 7), or None (the
        condensed method, linear bodies)."""
        self._constrained = pressure is not None
        if self._constrained:
            self._pressure.c.array[:] = pressure

    def solve(self, ksp: PETSc.KSP, rhs: PETSc.Vec, du: PETSc.Vec) -> tuple[PETSc.KSP, int]:
        """du of J du = rhs (after :meth:`update`) by ``ksp`` (whose PC :meth:`context` is) on the
        uncondensed system, to ``ksp``'s rtol. Returns the KSP whose converged reason is the solve's
        and the Krylov iterations.

        *The mixed method* (:meth:`set_constraint`): the constraint's rows are the pressure rows,
        rhs = (rhs + L c_p, -Lambda D^-1 c_p) with c_p = U''(theta) (Jbar - theta), so the uncondensed
        residual is that of the (u, theta) Newton system with the constraint's rows in the merit
        function's weights (Lambda D^-1 c_p = w (Jbar - theta), w_a = mu_a V_a^(2/3), (7.3)), and rtol
        is the inexact Newton test in the merit's own norm, from (du, D P du + c_p); J's residual must
        meet it as well at the contact rows (below), whose laws take their forces from it.

        *Otherwise* the test is ||rhs - J du|| <= rtol ||rhs|| on the condensed residual, from (du, D P du).

        The uncondensed residual (e_u, Lambda e_p) leaves J's residual e_u + L D e_p: the pressure rows'
        residual e_p comes back multiplied by the bulk modulus. So the Krylov method goes on past its own
        test until J's residual meets rtol as well (:meth:`converged`): over every row, or in the mixed
        method over the contact rows (docs/nearly_incompressible.md, Sect. 7).

        If the uncondensed solve fails, J itself is solved with the same sweep (:meth:`apply` to (r, 0),
        the Woodbury formula with S~), from ``du`` as given: an iterate far from equilibrium can carry a
        nodal pressure of several shear moduli, whose initial stress makes J - L D P indefinite, and the
        uncondensed system's preconditioner, built on J_r without it, then fails (the first Newton step
        of the Taylor-Hood block at nu = 0.4999 from the tangent's response: 8000 iterations without
        convergence, where J's own solve converges in 300).
        """
        q, d = self._pressure, self._displacement
        self._set_start(rhs, du)
        ksp.setOperators(self.augmented)
        rtol, atol = ksp.getTolerances()[:2]
        rhs_norm = self._rhs.norm()
        self._tests = _Tests(max(rtol * rhs_norm, atol), rtol * rhs.norm(), ROUND_OFF * rhs_norm, rhs)
        self.uncondensed_iterations = None
        ksp.solve(self._rhs, self._solution)
        self._split(self._solution, du, q.x)
        converged = ksp.getConvergedReason() >= 0
        if self._constrained:
            self._set_missed(du, q.x, converged)
        iterations = ksp.getIterationNumber()
        if converged:
            return ksp, iterations
        condensed = self._condensed_solver(ksp)
        condensed.setOperators(self._J)
        condensed.setTolerances(rtol=rtol)
        condensed.setInitialGuessNonzero(True)
        d.start.copy(du)
        condensed.solve(rhs, du)
        return condensed, iterations + condensed.getIterationNumber()

    def converged(self, ksp: PETSc.KSP, its: int, rnorm: float) -> int:
        """The convergence test of :meth:`solve`'s Krylov method (a petsc4py KSP convergence test; its
        iteration ``its``, ``rnorm`` the uncondensed residual's norm): converged once rnorm meets rtol and
        J's residual of the iterate (built only then) does too, or once rnorm is down to
        :data:`ROUND_OFF`. Returns the KSP's converged reason (0: go on)."""
        reasons = PETSc.KSP.ConvergedReason
        tests = self._tests
        if not np.isfinite(rnorm):
            return reasons.DIVERGED_NANORINF
        if rnorm > tests.uncondensed:
            return reasons.ITERATING
        if self.uncondensed_iterations is None:
            self.uncondensed_iterations = its
        if rnorm <= tests.round_off:
            return reasons.CONVERGED_ATOL
        ksp.buildSolution(self._trial)
        self._split(self._trial, self._displacement.x, self._pressure.y)
        return reasons.CONVERGED_RTOL if self._condensed_norm(self._displacement.x) <= tests.condensed else reasons.ITERATING

    def _condensed_norm(self, du: PETSc.Vec) -> float:
        """The norm of J's residual of ``du`` over the rows of J's test: the contact nodes' in the mixed
        method, else every row (collective)."""
        residual = self._displacement.y
        self._J.mult(du, residual)
        residual.aypx(-1.0, self._tests.rhs)
        if not self._constrained:
            return residual.norm()
        local = float(np.sum(residual.array_r[self._newton.contact_dofs] ** 2))
        return float(np.sqrt(residual.getComm().tompi4py().allreduce(local)))

    def _set_start(self, rhs: PETSc.Vec, du: PETSc.Vec) -> None:
        """The uncondensed right-hand side and start of :meth:`solve` (``du`` kept in the work vector
        ``start``): (rhs + L c_p, -Lambda D^-1 c_p) and (du, D P du + c_p) in the mixed method, else
        (rhs, 0) and (du, D P du)."""
        q, d = self._pressure, self._displacement
        du.copy(d.start)
        self.P.mult(du, q.x)
        q.x.pointwiseMult(q.x, self._scales.modulus)
        if not self._constrained:
            self._merge(rhs, q.zero(), self._rhs)
            self._merge(du, q.x, self._solution)
            return
        q.x.axpy(1.0, q.c)
        rhs.copy(d.y)
        q.c.copy(q.t)
        q.t.scale(-1.0)
        self._subtract_L(q.t, d.y)  # rhs + L c_p
        q.t.pointwiseMult(q.t, self._scales.compliance)
        q.t.pointwiseMult(q.t, self._scales.force)  # -Lambda D^-1 c_p
        self._merge(d.y, q.t, self._rhs)
        self._merge(du, q.x, self._solution)

    def _set_missed(self, du: PETSc.Vec, p: PETSc.Vec, converged: bool) -> None:
        """:attr:`missed` of the constrained solve that gave (du, p): the pressure rows' residual
        e_p = P du - D^-1 (p - c_p) over V_a, or zero if the solve failed (J is then solved, and the
        constraint's linearisation holds exactly)."""
        q = self._pressure
        if not converged:
            self.missed = np.zeros(q.x.getLocalSize())
            return
        self.P.mult(du, q.y)
        q.t.waxpy(-1.0, q.c, p)
        q.t.pointwiseMult(q.t, self._scales.compliance)
        q.y.axpy(-1.0, q.t)
        volume = self.volumetric.nodal.volume.x.petsc_vec.array_r
        self.missed = np.divide(q.y.array_r, volume, out=np.zeros_like(volume), where=volume > 0)

    def _condensed_solver(self, ksp: PETSc.KSP) -> PETSc.KSP:
        """The KSP of :meth:`solve`'s solves of J (made at the first; options prefix ``ksp``'s and
        ``condensed_``)."""
        if self._condensed is None:
            self._condensed = create_ksp(ksp.getComm(), f"{ksp.getOptionsPrefix()}condensed_",
                                         preset("gmres_pressure_schur"))
            self._condensed.getPC().setPythonContext(_Context(self._apply_condensed))
            self._padded = self.augmented.createVecs()
        return self._condensed

    def _apply_condensed(self, r: PETSc.Vec, z: PETSc.Vec) -> None:
        """z = the displacement rows of :meth:`apply` to (r, 0)."""
        into, out = self._padded
        self._merge(r, self._pressure.zero(), into)
        self.apply(into, out)
        self._split(out, z, self._pressure.t)

    def _mult(self, x: PETSc.Vec, y: PETSc.Vec) -> None:
        """(y_u, y_p) = ((J - L D P) x_u + L x_p, Lambda (P x_u - D^-1 x_p)) = (J x_u - L (D P x_u - x_p),
        Lambda (P x_u - D^-1 x_p)), with D^-1 x_p = x_p at P's zero rows (:meth:`_set_pressure_scales`)."""
        d, q, s = self._displacement, self._pressure, self._scales
        self._split(x, d.x, q.x)
        self.P.mult(d.x, q.y)  # P x_u
        self._J.mult(d.x, d.y)
        q.t.pointwiseMult(q.y, s.modulus)
        q.t.axpy(-1.0, q.x)  # D P x_u - x_p
        self._subtract_L(q.t, d.y)
        q.t.pointwiseMult(q.x, s.compliance)
        q.y.axpy(-1.0, q.t)
        q.y.pointwiseMult(q.y, s.force)
        self._merge(d.y, q.y, y)

    def apply(self, r: PETSc.Vec, z: PETSc.Vec) -> None:
        """(z_u, z_p) = (G (r_u - L z_p), S~^-1 (P G r_u - Lambda^-1 r_p)): one sweep of the block
        factorisation."""
        d, q, s = self._displacement, self._pressure, self._scales
        self._split(r, d.x, q.x)
        self.cycle.solve(d.x, d.y)
        self.P.mult(d.y, q.y)
        q.x.pointwiseDivide(q.x, s.force)
        q.y.axpy(-1.0, q.x)
        self._schur_solver.solve(q.y, q.t)
        self._subtract_L(q.t, d.x)
        self.cycle.solve(d.x, d.y)
        self._merge(d.y, q.t, z)

    def _subtract_L(self, p: PETSc.Vec, u: PETSc.Vec) -> None:
        """u -= L p = K W (B T)^T p (K the identity but at the eliminated rows)."""
        t = self._displacement
        self._full.multTranspose(p, t.t)
        self._newton.left_scale(t.t, t.w)
        t.w.pointwiseMult(t.w, self._kept)
        u.axpy(-1.0, t.w)

    def _split(self, x: PETSc.Vec, u: PETSc.Vec, p: PETSc.Vec) -> None:
        """u, p = the displacement and pressure rows of the uncondensed vector x."""
        n = u.getLocalSize()
        with x.getBuffer(readonly=True) as values:
            u.array[:] = values[:n]
            p.array[:] = values[n:]

    def _merge(self, u: PETSc.Vec, p: PETSc.Vec, x: PETSc.Vec) -> None:
        """x = the uncondensed vector of rows u, p."""
        n = u.getLocalSize()
        with x.getBuffer() as values:
            values[:n] = u.array_r
            values[n:] = p.array_r

    def attach(self, ksp: PETSc.KSP) -> None:
        """Make ``ksp`` (FGMRES with a ``python`` PC) :meth:`solve`'s Krylov method: its PC applies
        :meth:`apply`, its convergence test is :meth:`converged`."""
        ksp.getPC().setPythonContext(_Context(self.apply))
        ksp.setConvergenceTest(self.converged)


@dataclasses.dataclass
class _Displacement(VectorSet):
    """Work vectors of J's layout."""

    x: PETSc.Vec
    y: PETSc.Vec
    t: PETSc.Vec
    w: PETSc.Vec
    start: PETSc.Vec


@dataclasses.dataclass
class _Pressure(VectorSet):
    """Work vectors of the nodal pressure's layout; ``c`` the constraint's pressure
    (:meth:`PressureSchur.set_constraint`)."""

    x: PETSc.Vec
    y: PETSc.Vec
    t: PETSc.Vec
    c: PETSc.Vec

    def zero(self) -> PETSc.Vec:
        """y set to zero."""
        self.y.zeroEntries()
        return self.y


@dataclasses.dataclass
class _Scales(VectorSet):
    """The diagonals of the pressure rows (:meth:`PressureSchur._set_pressure_scales`)."""

    modulus: PETSc.Vec
    compliance: PETSc.Vec
    force: PETSc.Vec


class _Tests(typing.NamedTuple):
    """:meth:`PressureSchur.converged`'s tests in one :meth:`PressureSchur.solve`: the uncondensed
    residual's norm at most ``uncondensed`` and J's residual of J du = ``rhs`` at most ``condensed``, or
    the uncondensed residual's at most ``round_off``."""

    uncondensed: float = 0.0
    condensed: float = 0.0
    round_off: float = 0.0
    rhs: PETSc.Vec | None = None


class _Operator:
    """A petsc4py ``python`` Mat context: MatMult only."""

    def __init__(self, mult: typing.Callable[[PETSc.Vec, PETSc.Vec], None]):
        self._mult = mult

    def mult(self, mat: PETSc.Mat, x: PETSc.Vec, y: PETSc.Vec) -> None:
        self._mult(x, y)


class _Context:
    """A petsc4py ``python`` PC context: PCApply only (the PC's destruction leaves the owner alone)."""

    def __init__(self, apply: typing.Callable[[PETSc.Vec, PETSc.Vec], None]):
        self._apply = apply

    def apply(self, pc: PETSc.PC, r: PETSc.Vec, du: PETSc.Vec) -> None:
        self._apply(r, du)
