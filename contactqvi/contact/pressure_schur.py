"""A Newton-step preconditioner for nearly incompressible bodies: one sweep of the block
factorisation of the uncondensed displacement-pressure system (docs/nearly_incompressible.md,
Sect. 5).

With bodies of the averaged volume change (:mod:`contactqvi.nodal_pressure`) the Newton
matrix of (5.4) (seed 000) is, in the solver's variables (T the change of variables),

    J = J_r + L D P,   P = B T,   L = W P^T,   D = diag(U''(Jbar_a) / V_a),

with J_r the Newton matrix of everything but the averaged term B^T D B and W the rows' left
factor of (5.4) (the identity off the contact nodes,
:class:`~contactqvi.contact.newton_matrix.NewtonMatrix`). J is the Schur complement of the
uncondensed system

    [ J_r   L    ] [du]   [r]
    [ P    -D^-1 ] [ p] = [0],

whose pressure block is what the bulk modulus makes large. One sweep of its block
factorisation (the block preconditioners of saddle-point systems, Elman, Silvester & Wathen
2014) applied to (r, 0),

    y = G r,   p = S~^-1 P y,   du = G (r - L p),

with G one BoomerAMG V-cycle on J_r (no term of the bulk modulus) and S~ = D^-1 + c M_L / mu
the lumped approximation of the Schur complement D^-1 + P J_r^-1 L (M_L = diag(V_a), mu the
nodal shear modulus, c = :data:`SHEAR_FACTOR`), preconditions J. Where the
displacement-pressure pair is inf-sup stable (quadratic displacements with the nodal P1
pressure: a Taylor-Hood pair with a lumped pressure mass) its Krylov counts grow little with
lambda (2.2x from nu = 0.45 to 0.4999 on the wavy block, plain GAMG 7.3x); for linear
displacements (P1/P1) the pressure modes the pair does not control are left to the Krylov
method, and the counts grow as with GAMG.

Eliminated rows (the SCD solver's identity rows, :meth:`NewtonMatrix.assemble`) have zero
columns in J: P gets them too, so that J_r keeps J's identity rows and columns there.

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

import typing

from petsc4py import PETSc

import numpy as np
import ufl

import dolfinx.fem.petsc
from dolfinx import fem

from contactqvi.contact.newton_matrix import NewtonMatrix
from contactqvi.lifetime import PETScOwner
from contactqvi.linalg import OptionsDict, create_ksp, default_options, significant
from contactqvi.nodal_pressure import VolumetricTangent

__all__ = ["PressureSchur"]

_DIFFERENT = PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN

#: c of S~ = D^-1 + c M_L / mu. Measured on the wavy block with quadratic displacements (linear
#: elasticity, exact solves with J_r; Krylov iterations per Newton step at nu = 0.45 / 0.4999):
#: c = 0.5: 17.3 / 27.4; 1: 9.4 / 14.1; 2: 4.8 / 10.7; 3: 5.7 / 12.3; 5: 6.5 / 14.2.
SHEAR_FACTOR = 2.0
#: J_r = J - W P^T D P keeps J's entries of B^T D B, which couples every displacement dof with
#: the 2-ring of cells around it, as terms cancelled to round-off (bulk over shear modulus times
#: eps of their row); the V-cycle takes J_r without its entries below this fraction of their row.
CANCELLED = 1e-9


class PressureSchur(PETScOwner):
    """The block preconditioner of this module (:meth:`context`: as a petsc4py ``python`` PC).

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
        vec = self._shear_volume
        self.P: PETSc.Mat | None = None
        self.reduced: PETSc.Mat | None = None  # J_r
        self._newton: NewtonMatrix | None = None
        self._schur_inverse = vec.duplicate()
        self._p = vec.duplicate()
        self._y: PETSc.Vec | None = None
        self._t: PETSc.Vec | None = None

    def petsc_objects(self) -> list[typing.Any]:
        return [self.cycle, self.P, self.reduced, self._shear_volume, self._schur_inverse, self._p, self._y,
                self._t]

    def update(self, J: PETSc.Mat, newton: NewtonMatrix, transform: PETSc.Mat | None, eliminated: np.ndarray) -> None:
        """J_r, P and S~^-1 for the Newton matrix J of ``newton`` (the averaged term at J's tangent),
        the change of variables ``transform`` (None: the identity) and the owned local rows
        ``eliminated`` by the SCD solver (collective)."""
        self._newton = newton
        B = self.volumetric.B
        if self.P is not None:
            self.P.destroy()
        self.P = B.matMult(transform) if transform is not None else B.copy()
        kept = J.createVecRight()
        kept.set(1.0)
        kept.array[eliminated] = 0.0
        self.P.diagonalScale(R=kept)
        averaged = self.volumetric.D.PtAP(self.P)  # P^T D P
        stress = self.volumetric.initial_stress
        if stress is not None:  # + T^T K_p T
            moved = stress.PtAP(transform) if transform is not None else stress.copy()
            moved.diagonalScale(L=kept, R=kept)
            averaged.axpy(1.0, moved, _DIFFERENT)
            moved.destroy()
        scaled = newton.left_scaled(averaged)  # W (P^T D P + T^T K_p T)
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
        self._set_schur_inverse()
        if self._y is None:
            self._y, self._t = J.createVecRight(), J.createVecRight()
        kept.destroy()

    def _set_schur_inverse(self) -> None:
        """1 / (V_a / U''_a + c V_a^2 / int chi mu phi_a) at the nodes of averaged cells, 0 elsewhere
        (c = :data:`SHEAR_FACTOR`)."""
        modulus = self.volumetric.D.getDiagonal()  # U''_a / V_a
        volume = self.volumetric.nodal.volume.x.petsc_vec.array_r
        shear = self._shear_volume.array_r
        inside = (volume > 0) & (modulus.array_r > 0)
        schur = np.divide(1.0, modulus.array_r, out=np.zeros_like(volume), where=inside)
        schur += SHEAR_FACTOR * np.divide(volume**2, shear, out=np.zeros_like(volume), where=inside)
        self._schur_inverse.array[:] = np.divide(1.0, schur, out=np.zeros_like(volume), where=inside)
        modulus.destroy()

    def context(self) -> _Context:
        """The context of a petsc4py ``python`` PC that applies :meth:`apply`."""
        return _Context(self.apply)

    def apply(self, r: PETSc.Vec, du: PETSc.Vec) -> None:
        """du = G (r - L S~^-1 P G r)."""
        y, t, p = self._y, self._t, self._p
        self.cycle.solve(r, y)
        self.P.mult(y, p)
        p.pointwiseMult(p, self._schur_inverse)
        self.P.multTranspose(p, y)
        self._newton.left_scale(y, t)  # L p = W P^T p
        t.aypx(-1.0, r)
        self.cycle.solve(t, du)


class _Context:
    """A petsc4py ``python`` PC context: PCApply only (the PC's destruction leaves the owner alone)."""

    def __init__(self, apply: typing.Callable[[PETSc.Vec, PETSc.Vec], None]):
        self._apply = apply

    def apply(self, pc: PETSc.PC, r: PETSc.Vec, du: PETSc.Vec) -> None:
        self._apply(r, du)
