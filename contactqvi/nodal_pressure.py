"""The nodally averaged volumetric tetrahedron: a locking-free P1 formulation for nearly
incompressible bodies (Bonet & Burton 1998; Bonet, Marriott & Hassan 2001); with quadratic
displacements the same averaging at the vertices is the Taylor-Hood P2/P1 pair with a lumped
pressure mass, condensed (docs/nearly_incompressible.md, Sect. 6).

Linear tetrahedra lock when the bulk modulus dominates: one volume constraint per cell
against about one free node per five cells. Averaging the volume change at the vertices
leaves one constraint per node instead. With the strain energy split as

    psi(F) = [psi(F) - U(J)] + U(J),   U the material's volumetric energy (lambda-weighted),

the remainder psi - U is integrated cell-wise as before, and U at the vertices a:

    Pi_vol(u) = sum_a V_a U(Jbar_a),   V_a = int chi phi_a dX,   Jbar_a = int chi phi_a J dX / V_a,   (1)

chi the (DG0) indicator of the cells whose body takes this formulation (bodies share no
nodes, so a vertex belongs to one body) and J = det F (finite strain) or 1 + div u (small
strain, U = lambda/2 (J - 1)^2). With the nodal pressure p_h = sum_a U'(Jbar_a) phi_a (P1):

    residual   d Pi_vol[v] = int chi p_h J F^-T : grad v dX,                          (2)
    tangent    d2 Pi_vol[v, w] = int chi p_h d(J F^-T : grad v)[w] dX + (B v)^T D (B w),  (3)
               B_(a,i) = int chi phi_a J F^-T : grad phi_i dX,   D = diag(U''(Jbar_a) / V_a).

On P1 tetrahedra J is constant per cell and p_h linear, so every integral of (1)-(3) is
exact with the materials' quadrature. The first term of (3) is ``ufl.derivative`` of (2)
with p_h held fixed; the second couples every two nodes that share a neighbour, a wider
stencil than the cell-wise stiffness (the problem's A is created with it once,
:class:`VolumetricTangent`). The linear version is (3) at u = 0: the stiffness of
2 mu eps : eps plus lambda B^T M_L^-1 B, B = int chi phi_a div phi_i (U''(1) = lambda for
every material here, the linearisation's lambda). Known weaknesses, measured in
docs/nearly_incompressible.md: the P1/P1 pair of displacement and nodal pressure is not inf-sup
stable, the remainder psi - U keeps the constant-strain tetrahedron's shear stiffness, the
stencil is wider (3.7 times A's nonzeros on the seal strip), and with GAMG the Krylov
iterations grow with lambda.
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
import dolfinx.la
from dolfinx import fem

from contactqvi.elasticity import displacement_degree, strain, stress
from contactqvi.lifetime import PETScOwner
from contactqvi.materials import FORMULATIONS, Material
from contactqvi.parameters import require, require_choice
from contactqvi.records import warn

__all__ = ["NodalPressure", "VolumetricTangent", "averaged_stress", "formulation_indicator", "internal_work",
           "recommend", "remainder_piola", "small_strain_stiffness"]

logger = logging.getLogger(__name__)

#: Poisson's ratio above which a plain P1 body is told about ``"nodal_pressure"`` (:func:`recommend`).
LOCKING_POISSON = 0.49

Formulation = str | dict[str, str]


def formulation_indicator(msh: dolfinx.mesh.Mesh, formulation: Formulation,
                          cell_tags: dolfinx.mesh.MeshTags | None = None,
                          poisson: float | fem.Function | None = None) -> fem.Function | None:
    """chi of (1): 1 in the cells of the bodies with ``"nodal_pressure"``, 0 elsewhere (DG0), or
    None where no body takes it. ``formulation``: one name for all cells, or one per body
    (cell group of ``cell_tags``; bodies not listed: ``"displacement"``). With ``poisson`` (a
    number or DG0) the plain P1 cells are checked by :func:`recommend`. Collective."""
    given = formulation if isinstance(formulation, dict) else {None: formulation}
    for body, name in given.items():
        require_choice("formulation" if body is None else f"bodies.{body}.formulation", name, FORMULATIONS)
    if all(name == "displacement" for name in given.values()):
        if poisson is not None:
            recommend(poisson, None, msh.comm)
        return None
    chi = fem.Function(fem.functionspace(msh, ("DG", 0)), name="nodal_pressure")
    for body, name in given.items():
        if body is None:
            chi.x.array[:] = float(name == "nodal_pressure")
            continue
        require(cell_tags is not None and body in cell_tags.names, f"bodies.{body}.formulation",
                "no cell group of that name in the mesh")
        chi.x.array[cell_tags.find(cell_tags.names[body])] = float(name == "nodal_pressure")
    chi.x.scatter_forward()
    if poisson is not None:
        recommend(poisson, chi, msh.comm)
    return chi


def volumetric_energy(material: Material | None, J: ufl.core.expr.Expr, lmbda: typing.Any) -> ufl.core.expr.Expr:
    """U(J) of (1): the material's (:meth:`~contactqvi.materials.Material.volumetric_energy`), or
    lambda/2 (J - 1)^2 of linear elasticity (``material`` None)."""
    return lmbda / 2 * (J - 1) ** 2 if material is None else material.volumetric_energy(J, lmbda)


def _volume_change(u: ufl.core.expr.Expr, finite: bool) -> tuple[ufl.core.expr.Expr, typing.Callable]:
    """J and its derivative dJ[v]: det F and J F^-T : grad v (finite strain), or 1 + div u and
    div v (small strain)."""
    if not finite:
        return 1 + ufl.div(u), ufl.div
    F = ufl.Identity(len(u)) + ufl.grad(u)
    J = ufl.det(F)
    return J, lambda v: J * ufl.inner(ufl.inv(F).T, ufl.grad(v))


def _nodal_degree(V: fem.FunctionSpace, finite: bool) -> int:
    """The quadrature degree that integrates phi_a J of (1) exactly: 2 on linear elements; on
    quadratic ones 2 (small strain: div u linear) or 4 (det F cubic)."""
    return 4 if finite and displacement_degree(V) == 2 else 2


def remainder_piola(material: Material, u: ufl.core.expr.Expr, mu: typing.Any, lmbda: typing.Any,
                    chi: fem.Function) -> ufl.core.expr.Expr:
    """d (psi - chi U(J)) / dF at F = I + grad u: the cell-wise part of the stress of (1)."""
    F = ufl.variable(ufl.Identity(len(u)) + ufl.grad(u))
    psi = material.strain_energy(F, mu, lmbda) - chi * material.volumetric_energy(ufl.det(F), lmbda)
    return ufl.diff(psi, F)


def internal_work(u: fem.Function, v: ufl.core.expr.Expr, material: Material | None, mu: typing.Any,
                  lmbda: typing.Any, chi: fem.Function) -> tuple[ufl.Form, NodalPressure]:
    """The internal virtual work of (1): the remainder psi - chi U cell-wise plus (2), UFL, with
    the :class:`NodalPressure` whose p_h it holds (update it before each assembly). Small strain
    (``material`` None): 2 mu eps : eps + lambda (1 - chi) tr eps tr eps plus (2)."""
    averaged = NodalPressure(u, chi, lmbda, material, None if material is None else mu)
    if material is None:
        cellwise = ufl.inner(stress(u, mu, lmbda * (1 - chi)), strain(v)) * ufl.dx
    else:
        dx = material.dx(displacement_degree(u.function_space))
        cellwise = ufl.inner(remainder_piola(material, u, mu, lmbda, chi), ufl.grad(v)) * dx
    return cellwise + averaged.term(v), averaged


def averaged_stress(averaged: NodalPressure, mu: typing.Any, lmbda: typing.Any) -> ufl.core.expr.Expr:
    """The Cauchy stress of (1) at ``averaged.u``: the remainder's plus chi p_h I (U'(J) I is the
    Cauchy stress of U; small strain: lambda theta_bar I), UFL."""
    u, chi, material = averaged.u, averaged.chi, averaged.material
    volumetric = chi * averaged.pressure * ufl.Identity(len(u))
    if material is None:
        return stress(u, mu, lmbda * (1 - chi)) + volumetric
    F = ufl.Identity(len(u)) + ufl.grad(u)
    return remainder_piola(material, u, mu, lmbda, chi) * F.T / ufl.det(F) + volumetric


@dataclasses.dataclass
class _Line:
    """A line search of the mixed method (:meth:`NodalPressure.start_line`): u_k (``anchor``),
    theta_k and Jbar_k - theta_k at its nodes, the trial step size, and the form of
    dJbar_k[u - u_k] V_a with its work functions."""

    anchor: fem.Function
    change: fem.Function
    form: fem.Form
    linearised: fem.Function
    missed: fem.Function
    theta: np.ndarray = dataclasses.field(default_factory=lambda: np.empty(0))
    residual: np.ndarray = dataclasses.field(default_factory=lambda: np.empty(0))
    alpha: float = 0.0


class NodalPressure:
    """The nodal fields of (1)-(2) for a displacement ``u``: V_a, lambda_a, Jbar_a, p_a = U'(Jbar_a)
    and U''(Jbar_a), as P1 functions, with the compiled forms that make them (no PETSc
    objects kept). Nodes outside chi's cells have V_a = 0, Jbar_a = 1, p_a = U''_a = 0.

    In a Newton solve of the mixed method (docs/nearly_incompressible.md, Sect. 7) the volume
    ratio theta_a at which p and U'' are evaluated is a variable of its own (:attr:`carried`),
    moved by the linearised constraint Jbar_a(u) = theta_a, and Jbar(u) is its residual.

    Args:
        u: the displacement (vector P1); its values are read at :meth:`update`.
        chi: the indicator of :func:`formulation_indicator`.
        lmbda: Lamé's lambda (number or DG0 expression).
        material: the hyperelastic material (finite strain), or None (small strain).
        mu: the shear modulus (finite strain): the scale of the constraint's residual in the
            mixed method's merit function (:meth:`constraint_norm`), or None.

    Attributes:
        ratio: Jbar_a(u) of the last :meth:`update`.
        mean: theta_a, where p and U'' are evaluated: ``ratio`` unless :attr:`carried`.
        carried: whether theta is the mixed method's variable (:meth:`carry`).
    """

    def __init__(self, u: fem.Function, chi: fem.Function, lmbda: typing.Any, material: Material | None,
                 mu: typing.Any = None):
        self.u, self.chi, self.material = u, chi, material
        msh = u.function_space.mesh
        self.Q = fem.functionspace(msh, ("Lagrange", 1))
        q = ufl.TestFunction(self.Q)
        self.dx = ufl.dx(metadata={"quadrature_degree": _nodal_degree(u.function_space, material is not None)})
        J, self.dJ = _volume_change(u, material is not None)
        self.volume = self._nodal(chi * q * self.dx, None, "nodal_volume")
        self.lame = self._nodal(chi * lmbda * q * self.dx, self.volume, "nodal_lambda")
        self._mean_form = fem.form(chi * J * q * self.dx)
        self.ratio = fem.Function(self.Q, name="nodal_volume_change")
        self.mean = fem.Function(self.Q, name="nodal_volume_ratio")
        self.carried = False
        self._starting = False  # the next update starts a carried theta: at _start, or at Jbar if None
        self._start: np.ndarray | None = None
        self._line: _Line | None = None  # made at the first line search
        self._on_line = False
        self._mu, self._weight = mu, None
        self.pressure = fem.Function(self.Q, name="nodal_pressure")
        self.modulus = fem.Function(self.Q, name="nodal_bulk_modulus")
        mean = ufl.variable(self.mean)
        energy = volumetric_energy(material, mean, self.lame)
        points = self.Q.element.interpolation_points()
        self._derivatives = (fem.Expression(ufl.diff(energy, mean), points),
                             fem.Expression(ufl.diff(ufl.diff(energy, mean), mean), points))
        self.coupling_form = fem.form(chi * q * self.dJ(ufl.TrialFunction(u.function_space)) * self.dx)

    def _nodal(self, integral: ufl.Form, volume: fem.Function | None, name: str) -> fem.Function:
        """The P1 function of the assembled ``integral`` (divided by ``volume`` where it is > 0)."""
        out = fem.Function(self.Q, name=name)
        self._assemble(fem.form(integral), out, volume)
        return out

    def _assemble(self, form: fem.Form, out: fem.Function, volume: fem.Function | None) -> None:
        """``out`` = the vector of ``form`` (summed over the ranks), divided by V_a of ``volume`` if
        given (0 where V_a = 0); ghosts updated."""
        vec = out.x.petsc_vec
        with vec.localForm() as local:
            local.set(0.0)
        dolfinx.fem.petsc.assemble_vector(vec, form)
        vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        if volume is not None:
            v = volume.x.petsc_vec.array_r
            vec.array[:] = np.divide(vec.array_r, v, out=np.zeros_like(v), where=v > 0)
        out.x.scatter_forward()

    def update(self) -> None:
        """Jbar at the nodes for the current ``u``, and p = U'(theta), U''(theta) at theta = Jbar, or,
        while :attr:`carried`, at the mixed method's theta (on a line search: the trial point's,
        :meth:`start_line`) (collective)."""
        self._assemble_ratio()
        if not self.carried or (self._starting and self._start is None):
            self.mean.x.array[:] = self.ratio.x.array
        elif self._starting:
            self.mean.x.array[:] = self._start
        elif self._on_line:
            self._move_along_line()
        self._starting = False
        self.pressure.interpolate(self._derivatives[0])
        self.modulus.interpolate(self._derivatives[1])

    def _assemble_ratio(self) -> None:
        """:attr:`ratio` = Jbar(u) (1 where V_a = 0)."""
        self._assemble(self._mean_form, self.ratio, self.volume)
        self.ratio.x.array[self.volume.x.array <= 0] = 1.0

    # -- the mixed method (docs/nearly_incompressible.md, Sect. 7) ---------------------------
    def _merit_weight(self) -> np.ndarray:
        """w_a = mu_a V_a^(2/3) (N) of the owned nodes: the constraint's residual V_a (Jbar_a - theta_a)
        times the shear stiffness mu / h_a of a node's cells (h_a = V_a^(1/3)), a force."""
        shear = self._nodal(self.chi * self._mu * ufl.TestFunction(self.Q) * self.dx, self.volume, "nodal_mu")
        n = self.Q.dofmap.index_map.size_local
        return shear.x.array[:n] * np.cbrt(self.volume.x.array[:n]) ** 2

    def carry(self, carried: bool, start: fem.Function | None = None) -> None:
        """Begin (``True``; theta = Jbar of the displacement ``start``, or of ``u`` if None, at the next
        :meth:`update`) or end the mixed method's carried theta; ending it makes the next
        :meth:`update` the condensed one again (collective)."""
        self.carried, self._starting, self._start, self._on_line = carried, carried, None, False
        if carried and self._weight is None:
            self._weight = self._merit_weight()
        if carried and start is not None:  # u is overwritten by the solver's next evaluation anyway
            self.u.x.array[:] = start.x.array
            self._assemble_ratio()
            self._start = self.ratio.x.array.copy()

    def constraint(self) -> np.ndarray:
        """Jbar_a(u) - theta_a of the owned nodes at the last :meth:`update` (0 unless :attr:`carried`)."""
        n = self.Q.dofmap.index_map.size_local
        return self.ratio.x.array[:n] - self.mean.x.array[:n]

    def constraint_pressure(self) -> np.ndarray:
        """U''(theta_a) (Jbar_a - theta_a) of the owned nodes at the last :meth:`update`: the pressure
        that the linearised constraint adds to p_h in the Newton step's right-hand side
        (:meth:`condense_constraint`)."""
        n = self.Q.dofmap.index_map.size_local
        return self.modulus.x.array[:n] * self.constraint()

    def constraint_norm(self) -> float:
        """||w (Jbar - theta)|| (N; :meth:`_merit_weight`) over the ranks: the constraint's share of
        the mixed method's merit function (collective)."""
        return float(np.sqrt(self.Q.mesh.comm.allreduce(float(np.sum((self._weight * self.constraint()) ** 2)),
                                                          op=MPI.SUM)))

    def condense_constraint(self) -> None:
        """p += U''(theta) (Jbar - theta) at the nodes (after :meth:`update`): with it the residual (2)
        is r_u + B^T U''(theta) (Jbar - theta), the right-hand side of the Newton step with the
        linearised constraint condensed (Sect. 7, (7.2))."""
        self.pressure.x.array[:] += self.modulus.x.array * (self.ratio.x.array - self.mean.x.array)

    def start_line(self, missed: np.ndarray | None = None) -> None:
        """A line search from the current ``u`` (of the last :meth:`update`, the Newton step's
        linearisation point u_k) begins: theta(alpha) = theta_k + alpha (Jbar_k - theta_k - e) +
        dJbar_k[u - u_k] follows the trial points (:meth:`set_step`). ``missed``: e at the owned nodes,
        the residual of the linearised constraint that an inexact solve of the Newton step left
        (:attr:`~contactqvi.contact.pressure_schur.PressureSchur.missed`), or None (0)."""
        if self._line is None:
            anchor = fem.Function(self.u.function_space)
            change = fem.Function(self.u.function_space)
            form = fem.form(self.chi * ufl.TestFunction(self.Q) * _volume_change(anchor, True)[1](change) * self.dx)
            self._line = _Line(anchor, change, form, fem.Function(self.Q), fem.Function(self.Q))
        line = self._line
        line.anchor.x.array[:] = self.u.x.array
        line.theta = self.mean.x.array.copy()
        line.residual = self.ratio.x.array - self.mean.x.array
        if missed is not None:
            line.missed.x.array[:len(missed)] = missed
            line.missed.x.scatter_forward()
            line.residual -= line.missed.x.array
        line.alpha, self._on_line = 0.0, True

    def set_step(self, alpha: float) -> None:
        """The step size of the next trial point on the line (:meth:`start_line`)."""
        self._line.alpha = alpha

    def end_line(self) -> None:
        """The line search ended: theta stays the accepted trial point's."""
        self._on_line = False

    def _move_along_line(self) -> None:
        """theta = theta_k + alpha (Jbar_k - theta_k) + dJbar_k[u - u_k] at the current ``u``."""
        line = self._line
        line.change.x.array[:] = self.u.x.array - line.anchor.x.array
        self._assemble(line.form, line.linearised, self.volume)
        self.mean.x.array[:] = line.theta + line.alpha * line.residual + line.linearised.x.array

    def term(self, v: ufl.core.expr.Expr) -> ufl.Form:
        """(2): int chi p_h dJ[v] dX, UFL (p_h of the last :meth:`update`)."""
        return self.chi * self.pressure * self.dJ(v) * self.dx


@dataclasses.dataclass
class VolumetricTangent(PETScOwner):
    """The second term B^T D B of (3) as PETSc matrices, for the Jacobian and the linear stiffness.

    Attributes:
        nodal: the nodal fields (:class:`NodalPressure`).
        bcs: the Dirichlet conditions: B's columns at prescribed dofs are zero, so B^T D B has
            zero rows and columns there (the identity rows of the stiffness stay).
        B: the coupling of (3) (P1 scalar rows, displacement columns).
        D: diag(U''(Jbar_a) / V_a).
        product: B^T D B of the last :meth:`add_to` (its symbolic part kept), or None.
        initial_stress: the first term of (3) alone, int chi p_h d(J F^-T : grad v)[w] dX (zero rows
            and columns at prescribed dofs), at the nodal fields of the last :meth:`add_to`, kept
            there once :meth:`keep_initial_stress` asked for it (finite strain), else None.
    """

    nodal: NodalPressure
    bcs: list[fem.DirichletBC]
    B: PETSc.Mat
    D: PETSc.Mat
    product: PETSc.Mat | None = None
    initial_stress: PETSc.Mat | None = None
    _initial_stress_form: fem.Form | None = None

    def petsc_objects(self) -> list[typing.Any]:
        return [self.product, self.D, self.B, self.initial_stress]

    def keep_initial_stress(self) -> None:
        """From the next :meth:`add_to` on, keep :attr:`initial_stress` (a finite-strain body's; the
        pressure's share of (3) that a preconditioner may leave out, :mod:`contactqvi.contact.pressure_schur`)."""
        if self.nodal.material is None or self._initial_stress_form is not None:
            return
        V = self.nodal.u.function_space
        self._initial_stress_form = fem.form(ufl.derivative(self.nodal.term(ufl.TestFunction(V)), self.nodal.u,
                                                            ufl.TrialFunction(V)))
        self.initial_stress = dolfinx.fem.petsc.create_matrix(self._initial_stress_form)

    @classmethod
    def create(cls, nodal: NodalPressure, bcs: list[fem.DirichletBC]) -> VolumetricTangent:
        """B of ``nodal``'s coupling form and an empty diagonal D (assembled at :meth:`add_to`)."""
        B = dolfinx.fem.petsc.create_matrix(nodal.coupling_form)
        index_map = nodal.Q.dofmap.index_map
        sizes = (index_map.size_local, index_map.size_global)
        D = PETSc.Mat().createAIJ(size=(sizes, sizes), nnz=(1, 0), comm=B.getComm())
        D.setUp()
        return cls(nodal, list(bcs), B, D)

    def assemble(self) -> PETSc.Mat:
        """B^T D B at the nodal fields' current state (call ``nodal.update()`` first), kept in
        :attr:`product` and returned."""
        B = self.B
        B.zeroEntries()
        dolfinx.fem.petsc.assemble_matrix(B, self.nodal.coupling_form, bcs=self.bcs)
        B.assemble()
        nodal = self.nodal
        diagonal = nodal.modulus.x.petsc_vec.copy()
        volume = nodal.volume.x.petsc_vec.array_r
        diagonal.array[:] = np.divide(diagonal.array_r, volume, out=np.zeros_like(volume), where=volume > 0)
        self.D.setDiagonal(diagonal)
        self.D.assemble()
        diagonal.destroy()
        if self.product is None:
            self.product = self.D.PtAP(B)
        else:
            self.D.PtAP(B, result=self.product)
        return self.product

    def add_to(self, K: PETSc.Mat, structure: PETSc.Mat.Structure = PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN,
               ) -> None:
        """K += B^T D B (the second term of (3)); ``structure`` DIFFERENT the first time K gets it. The
        first term of (3) goes into :attr:`initial_stress` if it is kept (at the same nodal fields)."""
        K.axpy(1.0, self.assemble(), structure)
        if self.initial_stress is not None:
            self.initial_stress.zeroEntries()
            dolfinx.fem.petsc.assemble_matrix(self.initial_stress, self._initial_stress_form, bcs=self.bcs,
                                              diagonal=0.0)
            self.initial_stress.assemble()

    def lift(self, b: PETSc.Vec, bcs: list[fem.DirichletBC]) -> None:
        """b -= (B^T D B) g at the free rows for the prescribed values g of ``bcs``: the lifting
        of (3)'s second term (:meth:`assemble` done; dolfinx's ``apply_lifting`` lifts the
        cell-wise part)."""
        g = dolfinx.la.create_petsc_vector(self.nodal.u.function_space.dofmap.index_map, 3)
        g.set(0.0)
        dolfinx.fem.petsc.set_bc(g, bcs)
        full = dolfinx.fem.petsc.assemble_matrix(self.nodal.coupling_form)
        full.assemble()
        pressure, lifted = full.createVecLeft(), g.duplicate()
        full.mult(g, pressure)
        scaled = pressure.duplicate()
        self.D.mult(pressure, scaled)
        self.B.multTranspose(scaled, lifted)
        b.axpy(-1.0, lifted)
        for obj in (g, full, pressure, scaled, lifted):
            obj.destroy()


def small_strain_stiffness(V: fem.FunctionSpace, lmbda: typing.Any, chi: fem.Function | None,
                           bcs: list[fem.DirichletBC]) -> VolumetricTangent | None:
    """The small-strain lambda B^T M_L^-1 B of the cells ``chi`` marks ((3) at u = 0; call
    :meth:`VolumetricTangent.add_to` and :meth:`~VolumetricTangent.lift`), or None without ``chi``."""
    if chi is None:
        return None
    averaged = NodalPressure(fem.Function(V), chi, lmbda, None)
    averaged.update()
    return VolumetricTangent.create(averaged, bcs)


def recommend(poisson: float | fem.Function, chi: fem.Function | None, comm: MPI.Comm) -> float:
    """Warn (:func:`contactqvi.records.warn`, key ``volumetric_locking``: logged once and kept for
    ``summary.json``) when a cell on plain P1 (chi = 0) has nu > :data:`LOCKING_POISSON`: linear
    tetrahedra lock there (docs/nearly_incompressible.md). Returns that largest nu (collective)."""
    if isinstance(poisson, fem.Function):
        n_cells = poisson.function_space.mesh.topology.index_map(3).size_local
        plain = np.ones(n_cells, dtype=bool) if chi is None else chi.x.array[:n_cells] < 0.5
        largest = comm.allreduce(float(poisson.x.array[:n_cells][plain].max(initial=-1.0)), op=MPI.MAX)
    else:
        largest = float(poisson) if chi is None else -1.0
    if largest > LOCKING_POISSON:
        warn(comm, logger, "volumetric_locking", f"Poisson's ratio {largest:.4g} on linear elements with the "
             "displacement formulation: they lock volumetrically (too stiff, a shrunken contact area, speckled "
             "pressures); give the material formulation = \"nodal_pressure\"", poisson=largest)
    return largest
