"""The nonlinear f of the GE 0 in f(u) + Q(u) for a hyperelastic body (finite strain).

Seed 000 states the SCD semismooth* Newton method for 0 in f(x) + Q(x) with f smooth
(Sect. 5: the approximation step (5.2)-(5.3), the Newton system (5.4) with the
Jacobian of f); the contact problem (6.3) takes f(u) = A u - l. For a hyperelastic
body (:mod:`contactqvi.materials`) f is the residual of the nonlinear equilibrium in
the problem's variables u (shifted, nodal frames; :mod:`contactqvi.contact.problem`):

    f(u) = R^T r_K(u~),   u~ = R (u - d) (+ the prescribed values),
    r_K(u~)(v) = int P(F) : grad v dX - lambda l(v),   F = I + grad u~,

P = d psi / d F the first Piola-Kirchhoff stress of the material's strain energy and l
the dead load of tractions and body force at load factor 1 (the same form as the linear
problem's); on a prescribed dof f has the linear problem's identity row u_i - l_i. Its
Jacobian is R^T K_T(u~) R with K_T = d r_K / d u~ (``ufl.derivative``, identity rows
and columns at prescribed dofs), written into the storage of the problem's A, whose
pattern it shares. This module assembles r_K and K_T; the problem maps them to its
variables (:meth:`~contactqvi.contact.problem.ContactProblem.residual`,
:meth:`~contactqvi.contact.problem.ContactProblem.tangent`). At u~ = 0 the tangent is the linear stiffness: a hyperelastic body
and a linear one of the same E and nu agree at small strain. The derivation of the
Newton step, gamma and the line search for a nonlinear f: docs/finite_strain.md.

Contact is measured as in the linear problem, in nodal frames with the gap g + n . u
linearised about the configuration of the last search: the reference one (exact for a
plane obstacle, whatever the strain), or the current one for a pair searched each step
(:class:`~contactqvi.contact.interface.ObstaclePair`,
:class:`~contactqvi.contact.interface.BodyPair`: the mortar coupling of the deformed
surfaces). With body pairs the problem's variables are u = T w (T = (I + N) R), and f and
its Jacobian are T^T r_K and T^T K_T T (docs/finite_strain.md, Sect. 5).
"""

from __future__ import annotations

import dataclasses
import typing

from petsc4py import PETSc

import numpy as np
import ufl

import dolfinx.fem.petsc
import dolfinx.la
from dolfinx import fem
from dolfinx import mesh as dmesh

from contactqvi.elasticity import Modulus, displacement_degree, lame_parameters, pressure_form
from contactqvi.lifetime import PETScOwner
from contactqvi.linalg import reassemble_matrix
from contactqvi.materials import Material
from contactqvi.nodal_pressure import VolumetricTangent, internal_work

__all__ = ["HyperelasticSystem", "create_hyperelastic_system", "prescribed_rows"]



@dataclasses.dataclass
class HyperelasticSystem(PETScOwner):
    """The residual f(u) and its Jacobian of a hyperelastic body, compiled once.

    Attributes:
        material: the strain-energy density.
        displacement: u~ (global components) of the last evaluation.
        residual_form, tangent_form: r_K(u~)(v) without the load, and d r_K / d u~.
        bcs: the problem's Dirichlet conditions (their rows are the prescribed values').
        external: the dead load l at load factor 1 (not lifted; zero at prescribed dofs).
        internal: work vector of r_K (ghosted).
        stiffness: K_T in global components when the problem has nodal frames (A = R^T K_T R;
            made at the first need, :meth:`global_stiffness`), else None (K_T is assembled
            into A itself).
        transformed: T^T K_T T of the last :meth:`transformed_tangent` with its product's
            symbolic data, reused while T stays the same (:meth:`forget_transform`), or None.
        dirichlet_owned: owned local dofs (global components) with prescribed values.
        prescribed: owned local rows of A (solver variables) that are prescribed rows (of the
            nodal frames of the last search, :func:`prescribed_rows`).
        load_factor: the step's load factor in the forms (follower pressures).
        force_scale: ||int mu div v dX|| (N): the size of the stress terms of r_K (mu F and
            mu F^-T of a neo-Hookean body, mu times a node's share of the surface) whose
            difference r_K is, so that floating point resolves r_K to about eps times it
            whatever the strain: at 1e-6 strain the terms cancel to 1e-6 of their size and r_K
            cannot be driven below about 1e-10 of the first residual. Measured: Newton stalls
            at 0.5 eps (two-body Hertz at 1 um) and 1.2 eps (patch blocks at 1e-6 strain) of
            it. The solver's ``floor`` (45 eps) is relative to this scale. With the nodally
            averaged volume change mu + chi lambda replaces mu (:func:`_force_scale`).
        volumetric: the nodally averaged volume change of the bodies that take it
            (:mod:`contactqvi.nodal_pressure`: its nodal pressure is updated before each
            assembly, and its B^T D B added to K_T, whose pattern then holds it), or None.
    """

    material: Material
    displacement: fem.Function
    residual_form: fem.Form
    tangent_form: fem.Form
    bcs: list[fem.DirichletBC]
    external: PETSc.Vec
    internal: PETSc.Vec
    stiffness: PETSc.Mat | None
    dirichlet_owned: np.ndarray
    prescribed: np.ndarray
    load_factor: fem.Constant
    force_scale: float
    transformed: PETSc.Mat | None = None
    volumetric: VolumetricTangent | None = None

    def petsc_objects(self) -> list[typing.Any]:
        return [self.transformed, self.stiffness, self.internal, self.external, self.volumetric]

    def mass_term(self) -> tuple[float, typing.Any] | None:
        """(c, rho) of a term c M u of r with M = (rho u, v), or None: a static body has none
        (:class:`~contactqvi.contact.dynamics.InertialSystem` has)."""
        return None

    def assemble_residual(self, load_factor: float, condensed: bool = False) -> PETSc.Vec:
        """r_K at :attr:`displacement` (global components, zero on the prescribed rows) into
        :attr:`internal`, which is returned. ``condensed``: in the mixed method's Newton solve (the
        nodal volume ratio carried, :class:`~contactqvi.nodal_pressure.NodalPressure`), the residual
        with the linearised constraint condensed, the Newton step's right-hand side."""
        r = self.internal
        self.load_factor.value = load_factor
        with r.localForm() as local:
            local.set(0.0)
        if self.volumetric is not None:
            self.volumetric.nodal.update()
            if condensed and self.volumetric.nodal.carried:
                self.volumetric.nodal.condense_constraint()
        dolfinx.fem.petsc.assemble_vector(r, self.residual_form)
        r.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        r.axpy(-load_factor, self.external)
        r.array[self.dirichlet_owned] = 0.0
        return r

    def global_stiffness(self) -> PETSc.Mat:
        """K_T's matrix in global components (of the linear stiffness' pattern), made once."""
        if self.stiffness is None:
            self.stiffness = dolfinx.fem.petsc.create_matrix(self.tangent_form)
            if self.volumetric is not None:  # the wider stencil of B^T D B, added once
                reassemble_matrix(self.stiffness, self.tangent_form, self.bcs)
                self.volumetric.nodal.update()
                self.volumetric.add_to(self.stiffness, PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
        return self.stiffness

    def assemble_tangent(self, out: PETSc.Mat) -> PETSc.Mat:
        """K_T at :attr:`displacement` (identity rows and columns at prescribed dofs) into ``out``
        (of the linear stiffness' pattern), which is returned; with :attr:`volumetric` (3) of
        :mod:`contactqvi.nodal_pressure`: the cell-wise part with p_h fixed plus B^T D B."""
        if self.volumetric is None:
            return reassemble_matrix(out, self.tangent_form, self.bcs)
        self.volumetric.nodal.update()
        reassemble_matrix(out, self.tangent_form, self.bcs)
        self.volumetric.add_to(out)
        return out

    def transformed_tangent(self, transform: PETSc.Mat) -> PETSc.Mat:
        """T^T K_T T at :attr:`displacement` for the change of variables T = ``transform``, in
        :attr:`transformed` (returned; owned here). The product's symbolic part is formed at the
        first call after a new T and kept: later calls redo the numeric part only (the symbolic
        part took 0.57 of 0.93 s of the product on the two-body Hertz fine mesh, 1 rank)."""
        stiffness = self.assemble_tangent(self.global_stiffness())
        if self.transformed is None:
            self.transformed = stiffness.PtAP(transform)
        else:
            stiffness.PtAP(transform, result=self.transformed)
        return self.transformed

    def forget_transform(self) -> None:
        """The change of variables T was replaced (a contact search): free :attr:`transformed`."""
        if self.transformed is not None:
            self.transformed.destroy()
            self.transformed = None


def create_hyperelastic_system(
    V: fem.FunctionSpace, material: Material, young: Modulus, poisson: Modulus, load: fem.Form,
    bcs: list[fem.DirichletBC], dirichlet_dofs_loc: np.ndarray, rotation: PETSc.Mat | None,
    pressures: dict[str, float] | None = None, facet_tags: dmesh.MeshTags | None = None,
    nodal: fem.Function | None = None,
) -> HyperelasticSystem:
    """The hyperelastic residual and tangent of ``material`` on V (compiled here, once).

    Args:
        V: the displacement space; young, poisson: E (Pa) and nu of the linearisation.
        load: the compiled dead load l(v) (tractions, body force) at load factor 1.
        bcs, dirichlet_dofs_loc: the problem's Dirichlet conditions and their local dofs.
        rotation: R of the problem's nodal frames, or None.
        pressures, facet_tags: pressures (Pa) on named boundaries, which ``load`` holds on the
            reference surface: they follow the deformed surface here (the difference of
            :func:`~contactqvi.elasticity.pressure_form` with and without u, times the load
            factor :attr:`HyperelasticSystem.load_factor`).
        nodal: the indicator chi of the cells whose volume change is averaged at the nodes
            (:func:`~contactqvi.nodal_pressure.formulation_indicator`), or None.
    """
    mu, lmbda = lame_parameters(young, poisson)
    u, v = fem.Function(V, name="displacement"), ufl.TestFunction(V)
    volumetric = None
    if nodal is None:
        residual = ufl.inner(material.first_piola(u, mu, lmbda), ufl.grad(v)) * material.dx(displacement_degree(V))
    else:  # (1)-(2) of contactqvi.nodal_pressure
        residual, averaged = internal_work(u, v, material, mu, lmbda, nodal)
    load_factor = fem.Constant(V.mesh, PETSc.ScalarType(1.0))
    if pressures:
        msh = V.mesh
        residual -= load_factor * (pressure_form(msh, v, facet_tags, pressures, u)
                                   - pressure_form(msh, v, facet_tags, pressures))
    tangent = ufl.derivative(residual, u, ufl.TrialFunction(V))
    residual_form, tangent_form = fem.form(residual), fem.form(tangent)
    if nodal is not None:
        volumetric = VolumetricTangent.create(averaged, bcs)
    index_map, bs = V.dofmap.index_map, V.dofmap.index_map_bs
    n_owned = index_map.size_local * bs
    dirichlet_owned = dirichlet_dofs_loc[dirichlet_dofs_loc < n_owned].astype(np.int32)
    external = dolfinx.la.create_petsc_vector(index_map, bs)
    with external.localForm() as local:
        local.set(0.0)
    dolfinx.fem.petsc.assemble_vector(external, load)
    external.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    external.array[dirichlet_owned] = 0.0
    return HyperelasticSystem(material, u, residual_form, tangent_form, list(bcs), external, external.duplicate(),
                              None, dirichlet_owned, prescribed_rows(external, dirichlet_owned, rotation),
                              load_factor, _force_scale(V, mu if nodal is None else mu + nodal * lmbda, material),
                              volumetric=volumetric)


def _force_scale(V: fem.FunctionSpace, mu: typing.Any, material: Material) -> float:
    """||int mu div v dX|| (N) over the owned dofs (:attr:`HyperelasticSystem.force_scale`). With the
    nodally averaged volume change ``mu`` is mu + chi lambda: its pressure U'(Jbar_a) is resolved to
    eps U''(Jbar_a), about eps lambda (a quadratic O-ring at nu = 0.499 stalled at 1.6e-11 of its
    start on a floor relative to mu alone)."""
    dx = material.dx(displacement_degree(V))
    scale = dolfinx.fem.petsc.assemble_vector(fem.form(mu * ufl.div(ufl.TestFunction(V)) * dx))
    scale.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    norm = scale.norm()
    scale.destroy()
    return norm


def prescribed_rows(like: PETSc.Vec, dirichlet_owned: np.ndarray, rotation: PETSc.Mat | None) -> np.ndarray:
    """Owned local rows of the solver's variables that hold a prescribed dof (the nodal
    frames are aligned with the prescribed components, so R^T maps one onto one)."""
    if rotation is None:
        return dirichlet_owned
    marker, rotated = like.duplicate(), rotation.createVecRight()
    marker.set(0.0)
    marker.array[dirichlet_owned] = 1.0
    rotation.multTranspose(marker, rotated)
    rows = np.flatnonzero(np.abs(rotated.array_r) > 0.5).astype(np.int32)
    for vec in (marker, rotated):
        vec.destroy()
    return rows
