"""The discrete contact problem of seed 000, Sect. 6, as PETSc objects: rigid obstacles and bodies.

Generalized equation (6.3): 0 in A u - l + Q(u) in the shifted displacements
u = u~ + d, written in *nodal frames*: at each contact node the three dofs are the
components along (t1, t2, n) of :mod:`contactqvi.obstacles` (n the obstacle's
normal pointing into the body), elsewhere the global ones. With the block-diagonal
rotation T (frame to global), A = T^T A_global T and l~ = T^T l~_global, so the
nodal law Q acts on (two tangential, normal) components exactly as in the seed,
where T = I (plane x3 = 0, frames e1, e2, e3; then no rotation is applied at all).

Several bodies (seed 000, Remark 6.2: a two-body problem is a one-body problem after
an algebraic transformation). At the slave nodes of a body pair the unknown is the
mortar relative displacement w_i = u_i - sum_j C_ij u_j (:mod:`contactqvi.contact.mortar`)
in the node's frame, elsewhere the displacement itself:
    u = T w,   T = (I + N) R,
R the block-diagonal rotation to nodal frames and N the mortar rows
N_(i,j) = C_ij P_i (slave node i, master node j; P_i drops the components
prescribed at i, a roller on a symmetry plane through the interface, where both
bodies' displacement in that direction is prescribed). N maps master to slave dofs
and no node is both, so N^2 = 0 and T^-1 = R^T (I - N). Master dofs with prescribed
values g are left out of T and enter as the offset c = N g: u = T w + lambda c.
With A_K, l~_K the assembled stiffness and load (identity rows and lifting at
prescribed dofs), the problem in w is again (6.3) with
    A = T^T A_K T,   l~ = T^T (l~_K - A_K c),
the prescribed rows of A still identity rows, so the SCD solver sees the seed's
nodal structure unchanged whatever the master side is.

The shift d (zero off the contact nodes) makes the non-penetration condition
u3 >= 0 and, for load steps, measures slip from the previous step:
    d_n = g_k,   d_t = -(u~_t of the previous step + tangential obstacle motion since it),
where g_k is the gap to the obstacle at step k (:meth:`ContactProblem.set_step`), so
u_t is the slip increment relative to the obstacle (the obstacle motion: the displacement
since the step before of the obstacle's material point at the node's closest point, the
translation's increment plus the rotation's chord, :meth:`ContactProblem.set_step`; the
time-discrete quasi-static Coulomb problem; a single step from rest is the static problem
of the seed).

Shift of the load, derived (the seed prints l := l~ - A d, which is a sign slip):
u~ = u - d minimises 1/2 u~^T A u~ - l~^T u~ subject to the contact conditions, and
    1/2 (u - d)^T A (u - d) - l~^T (u - d) = 1/2 u^T A u - (l~ + A d)^T u + const,
using A = A^T. Hence l = l~ + A d.
"""

from __future__ import annotations

import dataclasses
import time
import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import dolfinx.fem.petsc
import dolfinx.la
from dolfinx import fem
from dolfinx import mesh as dmesh

from contactqvi.contact.hyperelastic import HyperelasticSystem, create_hyperelastic_system, prescribed_rows
from contactqvi.contact.current_geometry import CurrentGeometry, following_shift, geometric_rows
from contactqvi.contact.interface import (BodyPair, Interface, ObstaclePair, Pair, build_interfaces, error_key,
                                          followed, search_again)
from contactqvi.contact.kinematics import roller_aligned
from contactqvi.contact.mortar import MortarCoupling
from contactqvi.contact.obstacle_geometry import start_points
from contactqvi.contact.quadratic import ModifiedBasis, modified_basis
from contactqvi.elasticity import (BodyForce, displacement_degree, elasticity_forms, lame_parameters,
                                   orthonormalize, rigid_motions_nullspace)
from contactqvi.laws import ContactLaw, Frictionless, NodalLaw, StackedLaw
from contactqvi.lifetime import PETScOwner
from contactqvi.materials import Material
from contactqvi.linalg import assemble_system, default_options, nonzero_rows
from contactqvi.load_steps import Rotation
from contactqvi.meshes import boundary_facets
from contactqvi.nodal_pressure import Formulation, VolumetricTangent, formulation_indicator, small_strain_stiffness
from contactqvi.obstacles import Obstacle, Plane
from contactqvi.parameters import require
from contactqvi.postprocess import ElasticBody

__all__ = ["ContactProblem", "ElasticSystem", "assemble_contact_problem", "build_contact_problem"]

_DIFFERENT = PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN
_SAME = PETSc.Mat.Structure.SAME_NONZERO_PATTERN
_SUBSET = PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN

Vector3 = tuple[float, float, float]


@dataclasses.dataclass
class ElasticSystem(PETScOwner):
    """The assembled elastic system before the change of variables, kept to search the
    contact again (:meth:`ContactProblem.search`).

    Attributes:
        stiffness: A_K (identity rows and columns at the prescribed dofs).
        loads: the lifted loads l~_K at load factor 1 and of the unit translations.
        constrained: (local nodes, 3) mask of the prescribed components.
        owned_dirichlet: owned local indices of the prescribed dofs.
    """

    stiffness: PETSc.Mat
    loads: list[PETSc.Vec]
    constrained: np.ndarray
    owned_dirichlet: np.ndarray

    def petsc_objects(self) -> list[typing.Any]:
        return [self.stiffness, *self.loads]


@dataclasses.dataclass
class ContactProblem(PETScOwner):
    """Stiffness, loads and contact nodes of the GE (6.3) in nodal frames.

    Attributes:
        V: vector P1/Q1 space of the displacement (all bodies).
        A: stiffness matrix in the solver's variables w (T^T A_K T); prescribed rows
            and columns are identity rows/columns, so A restricted to the free dofs is
            the paper's A.
        applied: load l~ at load factor 1 in the solver's variables (tractions, body
            force and the lifting of prescribed displacements; their values on
            prescribed dofs).
        load: shifted load l = lambda l~ + A d of the current step.
        unshifted: the current step's load without the shift, lambda l~ + sum_k s_k l~_k and
            what a time step adds (:meth:`shift_load`): a linear f is evaluated as A (u - d) -
            this, so that A multiplies the displacement u~ = u - d and not u and d apart, whose
            products are round-off of A |d| where d carries a travelled slip (docs/dynamics.md
            Sect. 5).
        shift: the shift d of the current step (nodal frames).
        contact_blk: owned local node (block) indices of the contact (slave) nodes, sorted.
        contact_facets: local facet indices of the slave surfaces (for output on them).
        contact_area: contact area of each owned contact node (m^2).
        law: the pairs' contact laws lumped to the contact nodes (the slip bound b(lambda)
            of each node, :class:`~contactqvi.laws.NodalLaw`).
        frames: (m, 3, 3) frame of each owned contact node; rows t1, t2, n in global
            coordinates, fixed in the reference configuration.
        interfaces: the contact pairs' nodal data (:mod:`contactqvi.contact.interface`).
        interface_of_node: (m,) index into ``interfaces`` of each contact node.
        body: materials, supports and loads at load factor 1 (for stresses and reactions).
        rotation: R (frame components to global), or None where every frame is (e1, e2, e3)
            and there is no body pair.
        coupling: N of the mortar rows (global components), or None without body pairs.
        transform: T = (I + N) R, or None (then T = R); on quadratic elements T = S_free (I + N) R
            (:attr:`modified`).
        offset: c = N g, the slave displacement due to prescribed master dofs at load
            factor 1, or None.
        translated: loads l~_c of a unit translation e_c (c = x, y, z) of the moved
            groups (empty without them), and for a problem built for rotations the nine
            loads l~_ab of the fields e_a X_b on them (a, b = x, y, z; row-major): a step
            adds sum_c s_c l~_c + sum_ab (Q - I)_ab l~_ab, s = t - (Q - I) c
            (:meth:`rigid_motion`).
        translated_offset: their offsets c_c (None without body pairs).
        rollers: (m,) mask of contact nodes whose t1 component is prescribed (zero).
        dirichlet_dofs_loc: local unrolled indices of Dirichlet dofs (incl. ghosts).
        node_body: body index of each local node (ghosts included), or None for one body.
        n_contact: global number p of contact nodes.
        n_free: global number n of free dofs.
        load_factor, translation, step_rotation, fit: the current step (:meth:`set_step`).
        setup_seconds: wall seconds (largest rank) of the last contact search with the
            nodal frames and mortar integration (``contact_search``) and of A = T^T A_K T
            with the loads (``change_of_variables``).
        elastic: A_K and the loads before the change of variables when a pair is searched
            again before every load step (:meth:`search`), else None.
        hyperelastic: the nonlinear f and its Jacobian of a hyperelastic body (finite strain,
            :mod:`contactqvi.contact.hyperelastic`): A is then the Jacobian at the last
            iterate, not a constant; None for linear elasticity (f(u) = A u - l).
        current: where the geometry of the pairs searched ``"newton"`` was taken and their
            slip's reference (:mod:`contactqvi.contact.current_geometry`); None without such pairs
            until the first search.
        modified: S of the slave surfaces' modified basis on quadratic elements
            (:mod:`contactqvi.contact.quadratic`: the contact variables are the coefficients ũ of
            u = S ũ), or None on linear ones.
        volumetric: lambda B^T M_L^-1 B of the small-strain stiffness of the bodies with the nodally
            averaged volume change (:mod:`contactqvi.nodal_pressure`), or None.
    """

    V: fem.FunctionSpace
    A: PETSc.Mat
    applied: PETSc.Vec
    load: PETSc.Vec
    unshifted: PETSc.Vec
    shift: PETSc.Vec
    contact_blk: np.ndarray
    contact_facets: np.ndarray
    contact_area: np.ndarray
    law: NodalLaw
    frames: np.ndarray
    interfaces: tuple[Interface, ...]
    interface_of_node: np.ndarray
    body: ElasticBody
    rotation: PETSc.Mat | None
    coupling: PETSc.Mat | None
    transform: PETSc.Mat | None
    offset: PETSc.Vec | None
    translated: tuple[PETSc.Vec, ...]
    translated_offset: tuple[PETSc.Vec | None, ...]
    rollers: np.ndarray
    dirichlet_dofs_loc: np.ndarray
    node_body: np.ndarray | None
    n_contact: int
    n_free: int
    load_factor: float = 1.0
    translation: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))
    step_rotation: Rotation | None = None
    fit: float = 1.0
    setup_seconds: dict[str, float] = dataclasses.field(default_factory=dict)
    elastic: ElasticSystem | None = None
    hyperelastic: HyperelasticSystem | None = None
    current: CurrentGeometry | None = None
    modified: ModifiedBasis | None = None
    volumetric: VolumetricTangent | None = None

    @property
    def comm(self) -> MPI.Comm:
        return self.V.mesh.comm

    @property
    def obstacle(self) -> Obstacle | None:
        """The rigid obstacle, when the only pair is one against an obstacle."""
        return self.interfaces[0].obstacle if len(self.interfaces) == 1 else None

    def petsc_objects(self) -> list[typing.Any]:
        """A, the load vectors, S, R, N, T and c (copies by ``dataclasses.replace`` share them)."""
        objects = (self.A, self.applied, self.load, self.unshifted, self.shift, self.elastic, self.hyperelastic,
                   self.modified, self.volumetric, *self._variables_objects())
        return [obj for obj in objects if obj is not None]

    def _variables_objects(self) -> list[typing.Any]:
        """The PETSc objects of the change of variables, which a new search replaces."""
        objects = (self.rotation, self.coupling, self.transform, self.offset, *self.translated,
                   *self.translated_offset)
        return [obj for obj in objects if obj is not None]

    @property
    def to_global(self) -> PETSc.Mat | None:
        """The map of the change of variables to global components: T with body pairs, R with
        nodal frames only, None without a change (the identity)."""
        return self.transform if self.transform is not None else self.rotation

    @property
    def averaged_volume(self) -> VolumetricTangent | None:
        """The term B^T D B of the nodally averaged volume change at the last tangent (finite strain)
        or of the stiffness (small strain), or None without such bodies."""
        return self.volumetric if self.hyperelastic is None else self.hyperelastic.volumetric

    @property
    def searched_each_step(self) -> bool:
        """Whether a pair is searched again before every load step (:meth:`search`)."""
        return self.elastic is not None

    @property
    def follows_geometry(self) -> bool:
        """Whether a pair's geometry follows the Newton iterate (``search = "newton"``)."""
        return any(i.follows for i in self.interfaces)

    @property
    def settles_geometry(self) -> bool:
        """Whether a load step is searched and solved again in the configuration it reached
        until that configuration settles (a pair with ``search = "until_settled"``)."""
        return any(i.settles for i in self.interfaces)

    def search(self, displacement: fem.Function, *, change: bool = False, start: bool = True) -> PETSc.Mat | None:
        """Search the pairs searched each step again in the configuration x + ``displacement``
        (global components), and rebuild the nodal data and the change of variables from it:
        the contact nodes, frames, areas and laws, T, A = T^T A_K T and the loads.

        A keeps its identity: the new T^T A_K T is written into the object ``A``, whose
        pattern grows by the new slave-master couplings (old ones stay as explicit
        zeros), so a preconditioner set up on A can be updated instead of set up again
        (:meth:`~contactqvi.contact.newton_step_solver.NewtonStepSolver.update_operator`).
        The step (load factor, translation) is kept, but its load and shift belong to the
        old variables: set a step (:meth:`set_step`) before solving. A solver built on the
        old problem (its contact nodes) must be rebuilt. Collective.

        Pairs searched ``"newton"`` are found with their derivatives, and ``displacement`` becomes
        their current geometry (:attr:`current`); with ``start`` it starts a load step (the
        slip's reference C^start of (13.1)), else the step's reference is kept.

        Returns, with ``change``, the new A minus the old one (a new matrix, nonzero only
        on the rows near the interfaces), else None.
        """
        require(self.elastic is not None, "search", "no contact pair of this problem is searched each step")
        interfaces, search_seconds = _timed(self.comm, search_again, self.V, self.body.facet_tags, self.interfaces,
                                            self.elastic.constrained, displacement, self.translation,
                                            self.hyperelastic is not None, self.step_rotation, True, self.modified)
        for obj in (self.applied, *self._variables_objects()):
            if all(obj is not b for b in self.elastic.loads):  # without frames (T = I) the loads are l~_K themselves
                obj.destroy()
        fields, variables_seconds = _timed(self.comm, _contact_fields, self.elastic, interfaces, True, self.modified)
        searched = fields.pop("A")
        # PETSc 3.22's MatAXPY with a different pattern drops A's near-nullspace without
        # releasing it (a leak of one null space per search): release it first
        self.A.setNearNullSpace(PETSc.NullSpace())
        self.A.axpy(-1.0, searched, _DIFFERENT)  # old - new, on the union of both patterns
        difference = _nonzeros(self.A, -1.0) if change else None
        self.A.zeroEntries()
        self.A.axpy(1.0, searched, _SUBSET)
        searched.destroy()
        for name, value in fields.items():
            setattr(self, name, value)
        if self.hyperelastic is not None:  # the rows of the prescribed dofs in the new frames
            h = self.hyperelastic
            h.prescribed = prescribed_rows(h.external, h.dirichlet_owned, self.rotation)
            h.forget_transform()
        self.setup_seconds = {"contact_search": search_seconds, "change_of_variables": variables_seconds}
        if self.follows_geometry:
            starts = [self._start_of(i, displacement) if i.follows else None for i in self.interfaces]
            if not start and self.current is not None:
                starts = list(self.current.start)
            self.current = CurrentGeometry.at(displacement, starts)
        return difference

    def _start_of(self, interface: Interface, displacement: fem.Function) -> MortarCoupling | np.ndarray:
        """The slip's reference of a pair searched ``"newton"`` at a load step's start in x +
        ``displacement``: a body pair's coupling (C^start of (13.1)), an obstacle pair's closest
        points in the obstacle's initial position (pi^start of (18.1), the obstacle where the step
        before put it)."""
        if interface.coupling is not None:
            return interface.coupling
        x = interface.position + displacement.x.array.reshape(-1, 3)[interface.blk]
        return start_points(interface.obstacle, x, self.translation, self.step_rotation)

    def follow(self, displacement: fem.Function, linearised: bool = False) -> None:
        """Take the geometry of the pairs searched ``"newton"`` at x + ``displacement`` on the
        facet pairs and slave nodes of their last search (:func:`~contactqvi.contact.interface.followed`;
        with its derivatives if ``linearised``, which only a Newton step needs, not a trial point):
        their frames, areas and laws, R, N, T and the offsets c (new values in the same
        objects, of the same patterns), and the shift d = v - w of their nodes
        (:func:`~contactqvi.contact.current_geometry.following_shift`) with the load of the
        current step. A and the Newton solver's nodes stay. Collective."""
        elastic, current = self.elastic, self.current
        if displacement is not current.displacement:
            current.displacement.x.array[:] = displacement.x.array
        interfaces = followed(self.V, self.interfaces, elastic.constrained, current.displacement, self.translation,
                              self.step_rotation, self._deformed_areas, linearised)
        contact_blk, _, frames, contact_area = _merged(interfaces)
        frames = roller_aligned(frames, elastic.constrained[contact_blk])
        rotation = _nodal_rotation(self.A, contact_blk, frames, always=True)
        new_objects = [rotation]
        if self.coupling is not None:  # body pairs: N, T and the offsets c too
            coupling = _mortar_rows(self.A, interfaces, elastic.constrained)
            offsets = [_prescribed_offset(coupling, b, elastic.owned_dirichlet) for b in elastic.loads]
            new_objects += [coupling, _change_of_variables(coupling, rotation, elastic.owned_dirichlet)]
            for new, old in zip(offsets, (self.offset, *self.translated_offset)):
                new.copy(old)
                new.destroy()
        for new, old in zip(new_objects, (self.rotation, self.coupling, self.transform)):
            new.copy(old, _SAME)
            new.destroy()
        self.interfaces, self.frames, self.contact_area = tuple(interfaces), frames, contact_area
        self.law = _nodal_law(interfaces, self.interface_of_node, contact_area)
        self._shift_following()
        self._shifted_load()

    def _deformed_areas(self, surface: str) -> np.ndarray:
        """The nodal areas of ``surface`` at the current geometry (:meth:`CurrentGeometry.deformed_areas`)."""
        return self.current.deformed_areas(self.body.facet_tags, surface)

    def layout_changed(self, displacement: fem.Function) -> bool:
        """Whether a search of the body pairs searched ``"newton"`` in x + ``displacement`` finds other
        facet pairs or slave nodes than their current geometry's (collective; an obstacle pair's slave
        nodes are those of its surface, whatever the configuration)."""
        following = [i for i in self.interfaces if i.follows and i.coupling is not None]
        found = search_again(self.V, self.body.facet_tags, following, self.elastic.constrained, displacement,
                             self.translation, True, self.step_rotation, linearised=False)
        return not all(old.coupling.layout.covers(new.coupling.layout, self.comm) for new, old in zip(found, following))

    def set_search_line(self, u: PETSc.Vec, du: PETSc.Vec) -> None:
        """The line of a line search from u along du in the physical displacement: u~(u) and
        u~(u + du) - u~(u) = T du (zero at the prescribed dofs) into :attr:`current`."""
        current = self.current
        self.physical_displacement(u, current.base)
        end = u.copy()
        end.axpy(1.0, du)
        self.physical_displacement(end, current.direction)
        end.destroy()
        current.direction.x.array[:] -= current.base.x.array

    def follow_line(self, alpha: float, out: PETSc.Vec) -> None:
        """The geometry at u~ + alpha T du on the line of :meth:`set_search_line` (:meth:`follow`),
        and the solver's variables there into ``out``: w + d, v at the contact nodes."""
        current = self.current
        current.trial.x.array[:] = current.base.x.array + alpha * current.direction.x.array
        self.follow(current.trial)
        self.solver_variables(current.trial, out)
        out.axpy(1.0, self.shift)

    def geometric_rows(self, u: PETSc.Vec) -> tuple[PETSc.Mat, PETSc.Mat]:
        """Gamma T and (dv/du~) T of the Newton matrix at u, the iterate the geometry was last
        taken at (new matrices; :func:`~contactqvi.contact.current_geometry.geometric_rows`)."""
        if any(i.follows and i.coupling is not None and i.coupling.derivatives is None  # a trial's: the same
               for i in self.interfaces):  # values, with their derivatives
            self.interfaces = tuple(followed(self.V, self.interfaces, self.elastic.constrained,
                                             self.current.displacement, self.translation, self.step_rotation,
                                             self._deformed_areas, linearised=True))
        h = self.hyperelastic
        self.physical_displacement(u, h.displacement)
        return geometric_rows(self.V, self.current, self.interfaces, self.elastic.constrained, self.contact_blk,
                              self.to_global, h.prescribed, h.assemble_residual(self.load_factor), self.translation,
                              self.step_rotation)

    def _shift_following(self) -> None:
        """The shift of the nodes of the pairs searched ``"newton"``: d = v - w at :attr:`current`,
        zero on a prescribed (roller) component, whose variable stays w (zero) as for the frozen
        geometry (:func:`_align_frames`; v vanishes there too, the projection lying in the plane)."""
        w = self.A.createVecRight()
        self.solver_variables(self.current.displacement, w)
        nodes, d = following_shift(self.V, self.current, self.interfaces, self.contact_blk, self.interface_of_node,
                                   self.fit, w.array_r, self.elastic.constrained, self.translation, self.step_rotation)
        w.destroy()
        self.shift.array.reshape(-1, 3)[self.contact_blk[nodes]] = d
        dofs = (3 * self.contact_blk[nodes, None] + np.arange(3)).ravel()
        self.shift.array[np.intersect1d(dofs, self.hyperelastic.prescribed)] = 0.0

    def rigid_motion(self) -> np.ndarray:
        """The coefficients of the loads :attr:`translated` at the current step: the moved
        groups' displacement u = (Q - I)(X - c) + t is sum_c s_c e_c + sum_ab (Q - I)_ab e_a X_b
        with s = t - (Q - I) c; without a rotation t itself."""
        return _rigid_coefficients(self.translation, self.step_rotation)

    def step_load(self, load_factor: float, translation: np.ndarray, rotation: Rotation | None,
                  out: PETSc.Vec) -> PETSc.Vec:
        """lambda l~ + sum_k s_k l~_k of a step (:meth:`set_step`'s arguments) into ``out``: the
        small-strain loads and lifted prescribed values in the solver's variables, without the shift."""
        self.applied.copy(out)
        out.scale(load_factor)
        for t, b in zip(_rigid_coefficients(np.asarray(translation, dtype=float), rotation), self.translated):
            out.axpy(t, b)
        return out

    def solver_variables(self, displacement: fem.Function, out: PETSc.Vec) -> PETSc.Vec:
        """The solver's variables u~ = T^-1 (u - lambda c - sum_k s_k c_k) of a physical
        displacement u (global components) at the current step's load factor and rigid
        motion (:meth:`rigid_motion`), with T^-1 = R^T (I - N): the inverse of
        :meth:`physical_displacement` (without the shift); written into ``out``."""
        local = displacement.x.petsc_vec.copy()
        if self.offset is not None:
            local.axpy(-self.load_factor, self.offset)
        for t, c in zip(self.rigid_motion(), self.translated_offset):
            if c is not None:
                local.axpy(-t, c)
        self.from_global(local, out)
        local.destroy()
        return out

    def from_global(self, x: PETSc.Vec, out: PETSc.Vec) -> PETSc.Vec:
        """T^-1 x = R^T (I - N) S^-1 x of a vector x in global components (a velocity, an
        acceleration: no offsets; S = I on linear elements), written into ``out``."""
        local = x.copy()
        if self.modified is not None:
            self.modified.inverse_free.mult(x, local)
        if self.coupling is not None:
            coupled = local.duplicate()
            self.coupling.mult(local, coupled)
            local.axpy(-1.0, coupled)
            coupled.destroy()
        if self.rotation is None:
            local.copy(out)
        else:
            self.rotation.multTranspose(local, out)
        local.destroy()
        return out

    def into_global(self, x: PETSc.Vec, out: PETSc.Vec) -> PETSc.Vec:
        """T x of a vector x in the solver's variables (a velocity, a displacement without the
        shift and the offsets): in global components, written into ``out`` (ghosts not updated)."""
        transform = self.to_global
        if transform is None:
            x.copy(out)
        else:
            transform.mult(x, out)
        return out

    def force_from_global(self, f: PETSc.Vec, out: PETSc.Vec) -> PETSc.Vec:
        """T^T f of a force f in global components (ghosted or not): the force in the solver's
        variables, written into ``out``."""
        transform = self.to_global
        if transform is None:
            out.array[:] = f.array_r[: out.getLocalSize()]
        else:
            transform.multTranspose(f, out)
        return out

    def force_to_global(self, x: PETSc.Vec, out: PETSc.Vec) -> PETSc.Vec:
        """T^-T x = S^-T (I - N)^T R x of a force x in the solver's variables (T^T f = x): the force
        in global components, written into ``out``."""
        local = out if self.rotation is None else x.duplicate()
        if self.rotation is None:
            x.copy(local)
        else:
            self.rotation.mult(x, local)
        if self.coupling is not None:
            coupled = local.duplicate()
            self.coupling.multTranspose(local, coupled)
            local.axpy(-1.0, coupled)
            coupled.destroy()
        if local is not out:
            local.copy(out)
            local.destroy()
        if self.modified is not None:
            modified = out.copy()
            self.modified.inverse_free.multTranspose(modified, out)
            modified.destroy()
        return out

    def force_scale(self) -> float:
        """The size (N) of the terms whose difference f(u) is, to which floating point resolves f:
        ||l|| for a linear f (A u - l, l = lambda l~ + A d), and at least the stress terms'
        size for a hyperelastic one (:attr:`HyperelasticSystem.force_scale`). Collective."""
        scale = self.load.norm()
        return scale if self.hyperelastic is None else max(scale, self.hyperelastic.force_scale)

    def position_scale(self) -> float:
        """The size (m) of the positions whose differences the law's variables v of pairs searched
        ``"newton"`` are (13.1): the largest coordinate of the current configuration; 0 without
        such pairs. Collective."""
        if self.current is None:
            return 0.0
        x = self.V.tabulate_dof_coordinates() + self.current.displacement.x.array.reshape(-1, 3)
        return self.comm.allreduce(float(np.abs(x).max(initial=0.0)), op=MPI.MAX)

    def residual(self, u: PETSc.Vec, out: PETSc.Vec, condensed: bool = False) -> None:
        """f(u) of a hyperelastic problem into ``out``: T^T r_K(u~) at the current step (T = R
        without body pairs), the prescribed rows u_i - l_i as in the linear problem
        (:mod:`contactqvi.contact.hyperelastic`; ``condensed``: its
        :meth:`~contactqvi.contact.hyperelastic.HyperelasticSystem.assemble_residual`)."""
        system = self.hyperelastic
        self.physical_displacement(u, system.displacement)
        self.force_from_global(system.assemble_residual(self.load_factor, condensed), out)
        prescribed = system.prescribed
        out.array[prescribed] = u.array_r[prescribed] - self.load.array_r[prescribed]

    def tangent(self, u: PETSc.Vec) -> None:
        """The Jacobian of a hyperelastic problem's f at u, T^T K_T(u~) T, into the storage of A."""
        self.tangent_at(self.physical_displacement(u, self.hyperelastic.displacement))

    def tangent_at(self, displacement: fem.Function, out: PETSc.Mat | None = None) -> PETSc.Mat:
        """T^T K_T(u~) T at the physical displacement u~ = ``displacement`` (global components)
        into ``out`` (of A's pattern; default: the storage of A, :meth:`tangent`), which is returned."""
        out = self.A if out is None else out
        system = self.hyperelastic
        if displacement is not system.displacement:
            system.displacement.x.array[:] = displacement.x.array
        system.load_factor.value = self.load_factor
        transform = self.to_global
        if transform is None:
            return system.assemble_tangent(out)
        out.zeroEntries()
        out.axpy(1.0, system.transformed_tangent(transform), _SUBSET)
        return out

    def gap(self, translation: typing.Sequence[float] = (0.0, 0.0, 0.0), rotation: Rotation | None = None,
            fit: float = 1.0) -> np.ndarray:
        """Gap of each owned contact node (m), obstacles rotated by ``rotation`` about its centre
        and translated by ``translation`` (:func:`~contactqvi.load_steps.placed`), the fraction
        ``fit`` of the declared interferences resolved (:meth:`Interface.gap`)."""
        return self._per_node(lambda i, nodes: i.gap(i.position, np.asarray(translation, dtype=float), rotation, fit),
                              1)

    def _per_node(self, value: typing.Callable[[Interface, np.ndarray], np.ndarray], width: int) -> np.ndarray:
        """An interface-wise quantity spread over the contact nodes ((m,) or (m, width))."""
        out = np.zeros((len(self.contact_blk), width))
        for k, interface in enumerate(self.interfaces):
            nodes = np.flatnonzero(self.interface_of_node == k)
            out[nodes] = np.asarray(value(interface, nodes)).reshape(len(nodes), width)
        return out[:, 0] if width == 1 else out

    def set_step(
        self, load_factor: float = 1.0, translation: typing.Sequence[float] = (0.0, 0.0, 0.0),
        previous: PETSc.Vec | None = None, previous_translation: typing.Sequence[float] = (0.0, 0.0, 0.0),
        rotation: Rotation | None = None, previous_rotation: Rotation | None = None, fit: float = 1.0,
        held: PETSc.Vec | None = None,
    ) -> None:
        """Shift and load of a load step: tractions, body force and prescribed displacements
        times ``load_factor``, the obstacles and moved groups rotated by ``rotation`` (total,
        about its centre; None: not) and translated by ``translation`` (total, m),
        x = Q (X - c) + c + t (the moved groups need a problem built with ``rotations``, rotated
        obstacles a search each step: their normals turn), the fraction ``fit`` of the body
        pairs' declared interferences resolved (the gap g + (1 - fit) δ(x), :meth:`gap`); slip
        measured from the step before: from its displacement ``previous`` (u~ in the solver's
        variables; None: from rest) and from the obstacles' position ``previous_translation``,
        ``previous_rotation``: the tangential part of the displacement since then of the
        obstacle's material point at each node's closest point
        (:meth:`~contactqvi.contact.interface.Interface.obstacle_increment`; a master body moves
        with the solution, its slip is in w itself). Both come from the load path's
        :class:`~contactqvi.contact.path_state.PathState`; nothing of the step before is
        read from the problem itself. ``held``: a displacement held apart from the solver's
        variables (solver's variables; a time step's translations of free bodies,
        :meth:`~contactqvi.contact.dynamics.StabilisedNewmark.step`), whose normal components
        at the contact nodes the gaps take.
        """
        translation = np.asarray(translation, dtype=float)
        if rotation is not None or previous_rotation is not None:
            self._check_rotatable()
        moved = self._obstacle_motion(translation, rotation, np.asarray(previous_translation, dtype=float),
                                      previous_rotation)
        nodal = np.zeros((len(self.contact_blk), 3))
        if previous is not None:
            nodal[:, :2] = previous.array.reshape(-1, 3)[self.contact_blk, :2]
        nodal[:, :2] = -(nodal[:, :2] + moved)
        nodal[:, 2] = self.gap(translation, rotation, fit)
        if held is not None:
            nodal[:, 2] += held.array.reshape(-1, 3)[self.contact_blk, 2]
        self.shift.set(0.0)
        self.shift.array.reshape(-1, 3)[self.contact_blk] = nodal
        self.load_factor, self.translation, self.step_rotation = float(load_factor), translation, rotation
        self.fit = float(fit)
        if self.current is not None:
            self._shift_following()
        self._shifted_load()

    def _shifted_load(self) -> None:
        """The loads of the current step and shift: :attr:`unshifted` = lambda l~ + sum_k s_k l~_k and
        l (:meth:`shift_load`)."""
        self.step_load(self.load_factor, self.translation, self.step_rotation, self.unshifted)
        self.shift_load()

    def shift_load(self) -> None:
        """l = :attr:`unshifted` + A d (a hyperelastic f is evaluated at u - d itself: d only on its
        identity rows, as A d there); after a change of either."""
        self.unshifted.copy(self.load)
        if self.hyperelastic is None:
            self.A.multAdd(self.shift, self.load, self.load)
        else:
            self.load.axpy(1.0, self.shift)

    def _check_rotatable(self) -> None:
        """Raise unless a step may rotate: moved groups built with their rotation loads (or none),
        something to rotate, and every obstacle pair searched each step (its frames turn)."""
        require(len(self.translated) in (0, 12), "steps.rotation", "the problem was built without rotations of "
                "moved groups (build it with rotations=True and boundary.moved groups)")
        obstacles = [i for i in self.interfaces if i.obstacle is not None]
        require(len(self.translated) == 12 or bool(obstacles), "steps.rotation", "rotates the groups boundary.moved "
                "and the rigid obstacles; this problem has neither")
        for interface in obstacles:
            require(interface.searched_each_step, error_key(interface.pair, "search"), "a rotated obstacle's normals "
                    "turn: its pair must be searched each step ('every_step' or 'until_settled'), got 'once'")

    def _obstacle_motion(self, translation: np.ndarray, rotation: Rotation | None, previous_translation: np.ndarray,
                         previous_rotation: Rotation | None) -> np.ndarray:
        """(m, 2) tangential components (t1, t2) of each contact node's obstacle surface displacement
        since the step before (:meth:`~contactqvi.contact.interface.Interface.obstacle_increment`;
        zero on body pairs), checked to vanish along components prescribed on contact nodes."""
        increment = self._per_node(lambda i, nodes: i.obstacle_increment(
            i.position, translation, rotation, previous_translation, previous_rotation), 3)
        moved = np.einsum("nij,nj->ni", self.frames[:, :2, :], increment)
        along = self.comm.allreduce(float(np.abs(moved[self.rollers, 0]).max(initial=0.0)), op=MPI.MAX)
        size = self.comm.allreduce(float(np.abs(increment).max(initial=0.0)), op=MPI.MAX)
        require(along <= 1e-12 * max(size, 1e-300), "steps.translation",
                "the obstacle must not move along a component prescribed on contact nodes")
        return moved

    def physical_displacement(self, u: PETSc.Vec, out: fem.Function) -> fem.Function:
        """u~ = T (u - d) + lambda c + sum_k s_k c_k (:meth:`rigid_motion`) in global components, written into
        ``out`` (ghosts updated).

        At the prescribed dofs off the contact nodes u takes its exact value, the load there (A
        is the identity on their rows and columns, so no other row depends on it): the inexact Newton-step
        solves leave an error of relative size 1e-7 in a prescribed nonzero value, far below
        the stopping test in those unscaled identity rows but a force of K_ii times it in the
        reactions (two-body Hertz: 7 N of 81 kN, a force balance of 6e-5 instead of 1e-9).
        """
        local = u.copy()
        local.axpy(-1.0, self.shift)
        prescribed = self.dirichlet_dofs_loc[self.dirichlet_dofs_loc < local.getLocalSize()]
        prescribed = prescribed[~np.isin(prescribed // 3, self.contact_blk)]  # rollers there: in nodal frames
        local.array[prescribed] = self.load.array[prescribed] - self.shift.array[prescribed]
        self.into_global(local, out.x.petsc_vec)
        local.destroy()
        if self.offset is not None:
            out.x.petsc_vec.axpy(self.load_factor, self.offset)
        for t, c in zip(self.rigid_motion(), self.translated_offset):
            if c is not None:
                out.x.petsc_vec.axpy(t, c)
        out.x.scatter_forward()
        return out

    def nodal_contact_forces(self, normal_force: np.ndarray, friction_force: np.ndarray) -> np.ndarray:
        """Force of the contact on each owned node (owned nodes, 3; N, global components).

        At the contact nodes the law's force, normal and friction force in the node's frame;
        for body pairs its opposite spread to the master nodes by C^T (Newton's third law,
        every row of C sums to 1), also onto their prescribed components. Collective.
        """
        forces = self.A.createVecRight()
        forces.set(0.0)
        nodal = np.einsum("ij,ijk->ik", np.column_stack([friction_force, normal_force]), self.frames)
        index_map = self.V.dofmap.index_map
        forces.setValuesBlocked(index_map.local_to_global(self.contact_blk).astype(PETSc.IntType), nodal,
                                addv=PETSc.InsertMode.ADD_VALUES)
        for k, interface in enumerate(self.interfaces):
            c = interface.coupling
            if c is None:
                continue
            slave = nodal[np.searchsorted(self.contact_blk, c.slave_blk)]
            spread = -np.repeat(slave, np.diff(c.C_indptr), axis=0) * c.C_values[:, None]
            forces.setValuesBlocked(c.C_master_glob.astype(PETSc.IntType), spread, addv=PETSc.InsertMode.ADD_VALUES)
        forces.assemble()
        values = forces.array.reshape(-1, 3).copy()
        forces.destroy()
        return values

    @property
    def multigrid_options(self) -> dict[str, typing.Any]:
        """GAMG options for this problem's near-nullspace (PETSc option names without prefix).

        With several bodies the near-nullspace has six modes per body, and GAMG gives every
        aggregate as many coarse unknowns as there are modes: 12 for two bodies. With smoothed
        aggregation the first coarse operator of the two-body Hertz medium mesh then had 5124
        rows and 2.6 M nonzeros, as many as the fine one, and a set-up took 4.8 s (1.2 s with
        six modes). Unsmoothed aggregation (plain aggregates as interpolation) keeps the
        coarse operators to neighbouring aggregates: set-up 0.8 s, the load path 117 -> 25 s,
        Newton steps 9/21/13/17 -> 8/8/9/8. Larger aggregates (a distance-3 maximal
        independent set) did as well on small meshes but fail at a million dofs on 2 ranks:
        PETSc 3.22 preallocates local rows times the largest aggregate (160189 x 17994,
        beyond 32-bit indices; the mortar rows, then with their zero entries stored, made aggregates of
        thousands of nodes).

        Below about a thousand unknowns the 12-unknown aggregates hardly coarsen (medium
        mesh: 31425 -> 5256 -> 1020 -> 348 -> 180 -> 132 -> 96 -> 72 -> 60 -> 48 rows), and
        those six Chebyshev-smoothed levels cost Krylov iterations: the coarsest level is
        the first one below 3000 unknowns, solved exactly on one process (GAMG's default
        coarse solver). Two-body Hertz, Newton rtol 1e-8: medium 287 -> 200 Krylov
        iterations; fine (113 k dofs) 235 -> 168, Newton steps 29 -> 27, solve 31.2 -> 25 s
        on 1 rank, 25.5 -> 18.7 s on 2 (docs/bodies.md).
        One body: none (PETSc's defaults; the paper's tables).
        """
        bodies = 0 if self.node_body is None else self.comm.allreduce(int(self.node_body.max(initial=-1)) + 1,
                                                                      op=MPI.MAX)
        return {"pc_gamg_agg_nsmooths": 0, "pc_gamg_coarse_eq_limit": 3000} if bodies > 1 else {}

    def near_nullspace(self) -> PETSc.NullSpace:
        """Rigid-body modes of each body in the solver's variables, T^-1 of the global ones
        (:meth:`from_global`), for AMG (six per body)."""
        modes = rigid_motions_nullspace(self.V, self.node_body)
        if self.rotation is None:
            return modes
        global_modes = modes.getVecs()
        vectors = [self.A.createVecRight() for _ in global_modes]
        for mode, vector in zip(global_modes, vectors):
            self.from_global(mode, vector)
        if self.coupling is not None or self.modified is not None:
            orthonormalize(vectors)
        rotated = PETSc.NullSpace().create(vectors=vectors, comm=self.comm)
        for vector in [*global_modes, *vectors]:  # the null spaces hold their own references
            vector.destroy()
        modes.destroy()
        return rotated


def build_contact_problem(
    msh: dmesh.Mesh,
    facet_tags: dmesh.MeshTags,
    young: float,
    poisson: float,
    tractions: dict[str, Vector3],
    law: ContactLaw = Frictionless(),
    clamped: typing.Sequence[str] = ("dirichlet",),
    contact: str = "contact",
    obstacle: Obstacle | None = None,
    body_force: Vector3 | None = None,
    displacements: dict[str, dict[int, float]] | None = None,
    moved: typing.Sequence[str] = (),
    material: Material | None = None,
    search: str = "once",
    pressures: dict[str, float] | None = None,
    rotations: bool = False,
    formulation: Formulation = "displacement", degree: int = 1,
) -> ContactProblem:
    """Assemble the GE (6.3) for a body against a rigid obstacle, at load factor 1.

    The contact nodes are the nodes of the ``contact`` boundary that are not clamped
    (their number is p of Table 2); a node with some prescribed components (a roller
    on a symmetry plane) stays a contact node if those components are tangential.

    Args:
        msh, facet_tags: mesh with named boundaries.
        young, poisson: E (Pa) and nu.
        tractions: surface traction (Pa) per boundary name.
        law: the contact law (:mod:`contactqvi.laws`), e.g. ``Coulomb(friction=0.23)``;
            tractions in it (a Tresca bound) are lumped to nodal forces with each
            node's area.
        clamped: boundaries with u = 0.
        contact: boundary that may touch the obstacle.
        obstacle: the rigid obstacle; default the foundation {x3 <= 0} of seed 000.
        body_force: volume force density (N/m^3).
        displacements: prescribed components per boundary name, ``{name: {component: value (m)}}``.
        moved: boundaries moved rigidly with the obstacle's translation.
        material: a hyperelastic material (finite strain), or None: linear elasticity.
        search: when the contact is searched (:class:`~contactqvi.contact.interface.ObstaclePair`).
        pressures: pressure (Pa, > 0 into the body) per boundary name, scaled by the load
            factor; on the deformed surface for a hyperelastic ``material``.
        rotations: build the loads of rotations of the ``moved`` groups (nine more lifted loads),
            for steps with a ``rotation`` (:class:`~contactqvi.load_steps.LoadStep`).
        formulation: ``"displacement"`` (plain P1) or ``"nodal_pressure"`` (the volume change
            averaged at the nodes, :mod:`contactqvi.nodal_pressure`), or one per body (several
            bodies, ``{body: name}``).
        degree: of the displacements, 1 or 2 (10-node tetrahedra, :mod:`contactqvi.contact.quadratic`).

    Raises:
        ParameterError: bad values, unknown boundary names, or a contact node inside
            the obstacle (initial penetration).
    """
    require(isinstance(law, ContactLaw), "law", f"must be a contact law of contactqvi.laws, got {law!r}")
    law = law.checked()  # before assembly; errors named by the parameter ("friction")
    obstacle = Plane((0.0, 0.0, 0.0), (0.0, 0.0, 1.0)) if obstacle is None else obstacle
    pair = ObstaclePair(contact, obstacle, law, search)
    return assemble_contact_problem(msh, facet_tags, young, poisson, tractions, [pair], clamped, body_force,
                                    displacements, moved=moved, material=material,
                                    pressures=pressures, rotations=rotations, formulation=formulation, degree=degree)


def assemble_contact_problem(
    msh: dmesh.Mesh,
    facet_tags: dmesh.MeshTags,
    young: float | fem.Function,
    poisson: float | fem.Function,
    tractions: dict[str, Vector3],
    pairs: typing.Sequence[Pair],
    clamped: typing.Sequence[str] = (),
    body_force: BodyForce | None = None,
    displacements: dict[str, dict[int, float]] | None = None,
    cell_tags: dmesh.MeshTags | None = None,
    moved: typing.Sequence[str] = (), formulation: Formulation = "displacement",
    material: Material | None = None, pressures: dict[str, float] | None = None, rotations: bool = False,
    inertia: bool = False, degree: int = 1,
) -> ContactProblem:
    """Assemble the GE (6.3) of one or several bodies with contact pairs, at load factor 1.

    Args as in :func:`build_contact_problem`, and: ``young``, ``poisson`` numbers or DG0
    functions; ``pairs`` the contact pairs (:mod:`contactqvi.contact.interface`);
    ``cell_tags`` one named cell group per body (each gets its own rigid-body modes);
    ``body_force`` one vector (N/m^3) for all bodies or one per body, ``{body: f}``
    (:func:`~contactqvi.elasticity.body_forces`; each body's weight enters its balance);
    ``moved``, ``material``, ``pressures``, ``rotations``, ``formulation``, ``degree`` as in
    :func:`build_contact_problem`;
    ``inertia``: the bodies have mass (a time step, :mod:`contactqvi.contact.dynamics`): none need be held.

    Raises ``ParameterError`` as :func:`~contactqvi.contact.interface.build_interfaces`,
    and for nonzero prescribed components on contact nodes or a body nothing holds.
    """
    V = _displacement_space(msh, degree, pairs, material)
    # the locking warning is about linear tetrahedra; quadratic ones keep their contact area (docs/quadratic.md)
    nodal = formulation_indicator(msh, formulation, cell_tags, poisson if degree == 1 else None)
    a, L = elasticity_forms(V, young, poisson, facet_tags, tractions, body_force, cell_tags, pressures, nodal)
    msh.topology.create_connectivity(msh.topology.dim - 1, msh.topology.dim)  # for the facet dofs
    bcs, moved_bc = _dirichlet_conditions(V, facet_tags, clamped, displacements or {}, moved)
    dirichlet_dofs_loc = np.unique(np.concatenate([bc.dof_indices()[0] for bc in bcs] + [np.empty(0, np.int32)]))
    A, loads, volumetric = _stiffness(V, a, L, bcs, moved_bc, dirichlet_dofs_loc, rotations, young, poisson, nodal)
    constrained, owned_dirichlet = _prescribed(V, dirichlet_dofs_loc)
    modified = _slave_basis(V, facet_tags, pairs, constrained)
    interfaces, search_seconds = _timed(msh.comm, build_interfaces, V, facet_tags, pairs, constrained, modified)
    elastic = ElasticSystem(A, loads, constrained, owned_dirichlet)
    searched = any(i.searched_each_step for i in interfaces)
    fields, variables_seconds = _timed(msh.comm, _contact_fields, elastic, interfaces, searched, modified)
    node_body = _bodies(V, facet_tags, cell_tags, constrained, interfaces, held=not inertia)
    supports, comm = tuple(dict.fromkeys([*clamped, *(displacements or {}), *moved])), msh.comm
    problem = ContactProblem(
        V=V, **{vector: fields["applied"].duplicate() for vector in ("load", "unshifted", "shift")},
        contact_facets=np.unique(np.concatenate(
            [boundary_facets(facet_tags, i.slave_surface) for i in interfaces])).astype(np.int32),
        body=ElasticBody(young, poisson, facet_tags, supports, dict(tractions), body_force,
                         _prescribed_components(clamped, displacements or {}, moved), cell_tags,
                         pressures=dict(pressures or {}), nodal=nodal),
        dirichlet_dofs_loc=dirichlet_dofs_loc.astype(np.int32), node_body=node_body,
        n_free=comm.allreduce(3 * V.dofmap.index_map.size_local - len(owned_dirichlet), op=MPI.SUM),
        setup_seconds={"contact_search": search_seconds, "change_of_variables": variables_seconds},
        elastic=elastic if searched else None, modified=modified, volumetric=volumetric, **fields,
    )
    problem.set_step()
    _make_hyperelastic(problem, material, young, poisson, L, bcs, facet_tags, nodal)
    return problem


def _displacement_space(msh: dmesh.Mesh, degree: int, pairs: typing.Sequence[Pair],
                        material: Material | None) -> fem.FunctionSpace:
    """The vector Lagrange space of the displacements of ``degree`` (:func:`_check_degree`)."""
    require(msh.geometry.dim == 3, "mesh", "the contact problem is three-dimensional")
    _check_degree(msh, degree, pairs, material)
    return fem.functionspace(msh, ("Lagrange", degree, (3,)))


def _prescribed(V: fem.FunctionSpace, dirichlet_dofs_loc: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The (local nodes, 3) mask of the prescribed components, and the owned prescribed dofs."""
    index_map = V.dofmap.index_map
    constrained = np.isin(np.arange(3 * (index_map.size_local + index_map.num_ghosts)), dirichlet_dofs_loc)
    return constrained.reshape(-1, 3), dirichlet_dofs_loc[dirichlet_dofs_loc < 3 * index_map.size_local]


def _slave_basis(V: fem.FunctionSpace, facet_tags: dmesh.MeshTags, pairs: typing.Sequence[Pair],
                 constrained: np.ndarray) -> ModifiedBasis | None:
    """The modified basis of the pairs' slave surfaces on quadratic tetrahedra, else None (linear
    elements, and the 9-node facets of 27-node hexahedra, whose Lagrange functions all have positive
    integrals: :mod:`contactqvi.contact.facets`)."""
    if displacement_degree(V) == 1 or V.mesh.topology.cell_name() == "hexahedron":
        return None
    return modified_basis(V, np.unique(np.concatenate([boundary_facets(facet_tags, pair.slave_surface)
                                                       for pair in pairs])), constrained)


def _check_degree(msh: dmesh.Mesh, degree: int, pairs: typing.Sequence[Pair], material: Material | None) -> None:
    """Quadratic displacements take tetrahedra or hexahedra, pairs searched once or each step (a
    hyperelastic body's pairs of bodies: once; exact cylinders on tetrahedra); linear ones on a
    second-order (curved) mesh take tetrahedra and linear-elastic bodies, their displacements
    staying linear on the curved cells (docs/press_fit.md, "Curved contact surfaces")."""
    require(degree in (1, 2), "mesh.order", f"must be 1 (linear elements) or 2 (quadratic), got {degree!r}")
    cells, geometry = msh.topology.cell_name(), msh.geometry.cmap.degree
    if degree == 1:
        require(geometry == 1 or (cells == "tetrahedron" and geometry == 2), "mesh.file",
                f"curved contact surfaces are read from second-order tetrahedra (10 nodes); got {cells} cells of "
                f"degree {geometry}")
        require(geometry == 1 or material is None, "mesh.file",
                "a second-order (curved) mesh with linear elements takes linear-elastic bodies: their "
                "displacements stay linear on the curved cells, and the contact geometry of a hyperelastic body, "
                "which follows the deformed surfaces, needs quadratic ones: give mesh.order = 2 (bodies against "
                "rigid obstacles), or mesh with Mesh.ElementOrder = 1")
        return
    for pair in pairs:
        require(cells == "tetrahedron" or not isinstance(pair, BodyPair) or pair.cylinder is None,
                error_key(pair, "cylinder"),
                "exact cylinders take tetrahedra with quadratic elements (10-node); the mesh has hexahedra")
        require(pair.search != "newton", error_key(pair, "search"), "quadratic elements take pairs searched once "
                "or each step ('once', 'every_step', 'until_settled'); the geometry inside the Newton iteration "
                "('newton') is built for linear elements")
        require(material is None or not isinstance(pair, BodyPair) or pair.search == "once", error_key(pair, "search"),
                "quadratic elements with a hyperelastic body take pairs of meshed bodies searched 'once' (the "
                "reference configuration's coupling); searched again at finite strain they do not converge yet "
                "(docs/quadratic.md, Sect. 4)")


def _rigid_coefficients(translation: np.ndarray, rotation: Rotation | None) -> np.ndarray:
    """:meth:`ContactProblem.rigid_motion` of a translation and a rotation (or None)."""
    if rotation is None:
        return translation
    turn = rotation.matrix() - np.eye(3)
    return np.concatenate([translation - turn @ np.asarray(rotation.centre), turn.ravel()])


def _check_linear_pairs(problem: ContactProblem) -> None:
    """Raise if a pair of bodies of linear elasticity is searched ``"newton"``."""
    for interface in problem.interfaces:
        require(not interface.follows, error_key(interface.pair, "search"),
                "'newton' takes the geometry of finite deformations into the Newton iteration and needs "
                "hyperelastic bodies (a material model); for linear elasticity use 'every_step' or 'until_settled'")


def _stiffness(V: fem.FunctionSpace, a: fem.Form, L: fem.Form, bcs: list[fem.DirichletBC],
               moved_bc: fem.DirichletBC | None, dirichlet_dofs_loc: np.ndarray, rotations: bool,
               young: float | fem.Function, poisson: float | fem.Function,
               nodal: fem.Function | None) -> tuple[PETSc.Mat, list[PETSc.Vec], VolumetricTangent | None]:
    """A_K and the lifted loads of ``L`` and of the moved groups (:func:`_unit_translations`);
    with ``nodal`` (the cells of averaged bodies) A_K gains lambda B^T M_L^-1 B and every load
    its lifting (:func:`~contactqvi.nodal_pressure.small_strain_stiffness`, returned, else None)."""
    A, applied = assemble_system(a, L, bcs)
    volumetric = small_strain_stiffness(V, lame_parameters(young, poisson)[1], nodal, bcs)
    if volumetric is not None:
        volumetric.add_to(A, _DIFFERENT)
        volumetric.lift(applied, bcs)
    return A, [applied, *_unit_translations(V, a, moved_bc, dirichlet_dofs_loc, rotations, volumetric)], volumetric


def _make_hyperelastic(problem: ContactProblem, material: Material | None, young: float | fem.Function,
                       poisson: float | fem.Function, load: fem.Form, bcs: list[fem.DirichletBC],
                       facet_tags: dmesh.MeshTags, nodal: fem.Function | None = None) -> None:
    """Give ``problem`` the finite-strain f of a hyperelastic ``material`` (its ``hyperelastic``
    system, :mod:`contactqvi.contact.hyperelastic`, and the material of its volume results).
    Nothing for a linear material (None), whose pairs cannot be searched ``"newton"``."""
    if material is None:
        _check_linear_pairs(problem)
        return
    if problem.volumetric is not None:  # the tangent's own averaged term replaces the small-strain one
        problem.volumetric.destroy()
        problem.volumetric = None
    problem.hyperelastic = create_hyperelastic_system(problem.V, material, young, poisson, load, bcs,
                                                      problem.dirichlet_dofs_loc, problem.rotation,
                                                      problem.body.pressures, facet_tags, nodal)
    problem.body = dataclasses.replace(problem.body, material=material)


def _nonzeros(M: PETSc.Mat, scale: float) -> PETSc.Mat:
    """``scale`` times the nonzero entries of ``M`` (a new matrix of M's layout), read through
    its nonzero rows only: after a search M is zero but near the interfaces, and a copy of
    all of it would be one more matrix of A's size at the peak of the search."""
    rows, compact = nonzero_rows(M)
    indptr, indices, values = compact.getValuesCSR()
    low, high = M.getOwnershipRange()
    lengths = np.zeros(high - low, dtype=np.int64)
    lengths[rows.getIndices() - low] = np.diff(indptr)
    out = PETSc.Mat().createAIJ(size=M.getSizes(), comm=M.getComm(), csr=(
        np.concatenate([[0], np.cumsum(lengths)]).astype(PETSc.IntType), indices, scale * values))
    out.assemble()
    for obj in (rows, compact):
        obj.destroy()
    return out


def _timed(comm: MPI.Comm, function: typing.Callable[..., typing.Any], *args: typing.Any) -> tuple[typing.Any, float]:
    """``function(*args)`` and its wall seconds (largest rank). Collective."""
    start = time.perf_counter()
    value = function(*args)
    return value, comm.allreduce(time.perf_counter() - start, op=MPI.MAX)


def _merged(interfaces: typing.Sequence[Interface]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The interfaces' slave nodes sorted, with their interface index, frames and areas."""
    contact_blk = np.concatenate([i.blk for i in interfaces]).astype(np.int32)
    order = np.argsort(contact_blk, kind="stable")
    interface_of_node = np.repeat(np.arange(len(interfaces)), [len(i.blk) for i in interfaces])[order]
    frames = np.concatenate([i.frames for i in interfaces])[order]
    return contact_blk[order], interface_of_node, frames, np.concatenate([i.area for i in interfaces])[order]


def _nodal_law(interfaces: typing.Sequence[Interface], interface_of_node: np.ndarray,
               contact_area: np.ndarray) -> NodalLaw:
    """Each pair's law lumped to its slave nodes with their areas (m^2), as one nodal law."""
    laws = tuple(i.pair.law.lumped(contact_area[interface_of_node == k]) for k, i in enumerate(interfaces))
    return laws[0] if len(laws) == 1 else StackedLaw(laws, interface_of_node)


def _contact_fields(elastic: ElasticSystem, interfaces: typing.Sequence[Interface],
                    keep: bool, modified: ModifiedBasis | None = None) -> dict[str, typing.Any]:
    """The :class:`ContactProblem` fields that follow from the interfaces: the merged contact
    nodes with their frames, areas and laws, and the change of variables with A and the
    loads in the solver's variables (:func:`_solver_variables`). ``keep``: leave ``elastic``'s
    matrix and loads alive (they are freed or reused as the new A otherwise); ``modified``: the
    slave surfaces' modified basis of quadratic elements."""
    comm = elastic.stiffness.getComm().tompi4py()
    contact_blk, interface_of_node, frames, contact_area = _merged(interfaces)
    constrained = elastic.constrained[contact_blk]
    _check_prescribed_on_contact(elastic.loads, contact_blk, constrained, comm)
    frames = _align_frames(frames, constrained, comm)
    A, loads, rotation, coupling, transform, offsets = _solver_variables(elastic, interfaces, contact_blk, frames,
                                                                         keep, modified)
    return {"A": A, "applied": loads[0], "translated": tuple(loads[1:]), "offset": offsets[0],
            "translated_offset": tuple(offsets[1:]), "contact_blk": contact_blk, "contact_area": contact_area,
            "law": _nodal_law(interfaces, interface_of_node, contact_area), "frames": frames,
            "interfaces": tuple(interfaces), "interface_of_node": interface_of_node, "rotation": rotation,
            "coupling": coupling, "transform": transform, "rollers": constrained.any(axis=1),
            "n_contact": comm.allreduce(len(contact_blk), op=MPI.SUM)}


def _solver_variables(
    elastic: ElasticSystem, interfaces: typing.Sequence[Interface], contact_blk: np.ndarray, frames: np.ndarray,
    keep: bool, modified: ModifiedBasis | None = None,
) -> tuple[PETSc.Mat, list[PETSc.Vec], PETSc.Mat | None, PETSc.Mat | None, PETSc.Mat | None, list[PETSc.Vec | None]]:
    """A = T^T A_K T and l~ = T^T (l~_K - A_K c) for each load, with R, N, T and the offsets c
    of the change of variables (T = S (I + N) R with the ``modified`` basis S of quadratic slave
    surfaces). Without a change (T = I) the loads themselves and A_K (a copy if ``keep``);
    otherwise new objects, and A_K and the loads are freed unless ``keep``."""
    A_K, loads = elastic.stiffness, elastic.loads
    mortar = any(i.coupling is not None for i in interfaces)
    follows = any(i.follows for i in interfaces)  # R's values change inside the Newton iteration
    rotation = _nodal_rotation(A_K, contact_blk, frames, always=mortar or follows or modified is not None)
    coupling = transform = None
    offsets: list[PETSc.Vec | None] = [None] * len(loads)
    if mortar:
        coupling = _mortar_rows(A_K, interfaces, elastic.constrained)
        offsets = [_prescribed_offset(coupling, b, elastic.owned_dirichlet) for b in loads]
        transform = _change_of_variables(coupling, rotation, elastic.owned_dirichlet)
    if modified is not None:
        unmodified = transform if transform is not None else rotation
        transform = modified.S_free.matMult(unmodified)
        if unmodified is not rotation:
            unmodified.destroy()
    if rotation is None:  # T = I: A_K itself, a copy of it when A_K is kept (the searches change A, not A_K)
        return A_K.duplicate(copy=True) if keep else A_K, loads, rotation, coupling, transform, offsets
    T = transform if transform is not None else rotation
    transformed = [_in_solver_variables(A_K, T, b, c) for b, c in zip(loads, offsets)]
    with default_options("", {"mat_product_clear": True}):  # A keeps no copies of A_K T and T (same values)
        A = A_K.PtAP(T)
    if not keep:
        for obj in (A_K, *loads):
            obj.destroy()
    return A, transformed, rotation, coupling, transform, offsets


def _unit_translations(V: fem.FunctionSpace, a: fem.Form, moved_bc: fem.DirichletBC | None,
                       dirichlet_dofs_loc: np.ndarray, rotations: bool = False,
                       volumetric: VolumetricTangent | None = None) -> list[PETSc.Vec]:
    """The lifted loads of a unit translation e_c (c = x, y, z) of the moved groups, all
    other prescribed values zero: -A_K e_c at free dofs, e_c at the moved ones; with
    ``rotations`` then those of the nine fields e_a X_b (a, b = x, y, z, row-major) on the
    moved groups, of which a rotation's (Q - I) X is made (:meth:`ContactProblem.rigid_motion`);
    ``volumetric``: the averaged part of A_K, lifted too."""
    if moved_bc is None:
        return []
    value = moved_bc.g
    loads = []
    for c in range(3):
        value.value[:] = np.eye(3)[c]
        loads.append(_lifted(a, moved_bc, dirichlet_dofs_loc, volumetric))
    value.value[:] = 0.0
    if rotations:
        field = fem.Function(V)
        rotated_bc = fem.dirichletbc(field, np.unique(moved_bc.dof_indices()[0] // 3).astype(np.int32))
        x = V.tabulate_dof_coordinates()
        for c in range(9):
            field.x.array[:] = 0.0
            field.x.array.reshape(-1, 3)[:, c // 3] = x[:, c % 3]
            loads.append(_lifted(a, rotated_bc, dirichlet_dofs_loc, volumetric))
    return loads


def _lifted(a: fem.Form, bc: fem.DirichletBC, dirichlet_dofs_loc: np.ndarray,
            volumetric: VolumetricTangent | None = None) -> PETSc.Vec:
    """The lifted load of ``bc``'s values alone: -A_K g at free dofs, g at ``bc``'s dofs, zero at
    the other prescribed dofs ``dirichlet_dofs_loc`` (A_K: ``a`` and the averaged ``volumetric``)."""
    V = a.function_spaces[0]
    b = dolfinx.la.create_petsc_vector(V.dofmap.index_map, V.dofmap.index_map_bs)  # ghosted, for the lifting
    b.set(0.0)
    dolfinx.fem.petsc.apply_lifting(b, [a], bcs=[[bc]])
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    if volumetric is not None:
        volumetric.lift(b, [bc])
    b.array[dirichlet_dofs_loc[dirichlet_dofs_loc < b.getLocalSize()]] = 0.0
    dolfinx.fem.petsc.set_bc(b, [bc])
    return b


def _check_prescribed_on_contact(loads: list[PETSc.Vec], contact_blk: np.ndarray, constrained: np.ndarray,
                                 comm: MPI.Comm) -> None:
    """Only zero (roller) components may be prescribed on contact nodes."""
    nonzero = sum(comm.allreduce(int(np.count_nonzero(b.array.reshape(-1, 3)[contact_blk][constrained])))
                  for b in loads)
    require(nonzero == 0, "boundary.displacement", f"{nonzero} components prescribed on contact nodes are not "
            "zero (or move with the steps); on the contact surface only rollers (zero tangential components) "
            "are supported")


def _in_solver_variables(A_K: PETSc.Mat, T: PETSc.Mat, b: PETSc.Vec, offset: PETSc.Vec | None) -> PETSc.Vec:
    """T^T (b - A_K c) for a lifted load b (a new vector)."""
    out = b.duplicate()
    if offset is None:
        T.multTranspose(b, out)
        return out
    lifted = b.duplicate()
    A_K.mult(offset, lifted)
    lifted.aypx(-1.0, b)
    T.multTranspose(lifted, out)
    lifted.destroy()
    return out


def _mortar_rows(A: PETSc.Mat, interfaces: typing.Sequence[Interface], constrained: np.ndarray) -> PETSc.Mat:
    """N: N_(3i+a, 3j+a) = C_ij at slave node i, master node j, for the components a not
    prescribed at i (global components; owned rows)."""
    rows, cols, values = [], [], []
    for interface in interfaces:
        c = interface.coupling
        if c is None:
            continue
        node = np.repeat(c.slave_blk, np.diff(c.C_indptr))
        for a in range(3):
            free = ~constrained[node, a]
            rows.append(3 * node[free] + a)
            cols.append(3 * c.C_master_glob[free] + a)
            values.append(c.C_values[free])
    rows, cols, values = np.concatenate(rows), np.concatenate(cols), np.concatenate(values)
    order = np.lexsort((cols, rows))
    n_local = A.getLocalSize()[0]
    indptr = np.zeros(n_local + 1, dtype=PETSc.IntType)
    np.add.at(indptr, rows + 1, 1)
    N = PETSc.Mat().createAIJ(size=A.getSizes(), bsize=3, comm=A.getComm(), csr=(
        np.cumsum(indptr).astype(PETSc.IntType), cols[order].astype(PETSc.IntType), values[order]))
    N.assemble()
    return N


def _prescribed_offset(N: PETSc.Mat, b: PETSc.Vec, owned_dirichlet: np.ndarray) -> PETSc.Vec:
    """c = N g: the slave displacement of the prescribed values g of a lifted load ``b``
    (its entries at the prescribed dofs ``owned_dirichlet``)."""
    prescribed = b.duplicate()
    prescribed.set(0.0)
    prescribed.array[owned_dirichlet] = b.array[owned_dirichlet]
    offset = b.duplicate()
    N.mult(prescribed, offset)
    prescribed.destroy()
    return offset


def _change_of_variables(N: PETSc.Mat, rotation: PETSc.Mat, owned_dirichlet: np.ndarray) -> PETSc.Mat:
    """T = (I + N_f) R, N_f without the columns of prescribed dofs (``N`` becomes N_f)."""
    free = N.createVecRight()
    free.set(1.0)
    free.array[owned_dirichlet] = 0.0
    N.diagonalScale(None, free)
    NR = N.matMult(rotation)
    transform = rotation.copy()
    transform.axpy(1.0, NR, structure=_DIFFERENT)
    for obj in (free, NR):
        obj.destroy()
    return transform


def _prescribed_components(clamped: typing.Sequence[str], displacements: dict[str, dict[int, float]],
                           moved: typing.Sequence[str]) -> dict[str, tuple[int, ...]]:
    """The components (0, 1, 2) each support prescribes: all three on clamped and moved
    groups, the given ones on a group with prescribed displacements (several entries of
    one group: the union)."""
    prescribed = {name: {0, 1, 2} for name in [*clamped, *moved]}
    for name, components in displacements.items():
        prescribed.setdefault(name, set()).update(components)
    return {name: tuple(sorted(components)) for name, components in prescribed.items()}


def _bodies(V: fem.FunctionSpace, facet_tags: dmesh.MeshTags, cell_tags: dmesh.MeshTags | None,
            constrained: np.ndarray, interfaces: typing.Sequence[Interface], held: bool) -> np.ndarray | None:
    """Each local node's body (:func:`_node_body`), None without cell tags; with ``held``, every
    body checked to be held (:func:`_check_held`)."""
    if cell_tags is None:
        return None
    node_body = _node_body(V, cell_tags)
    if held:
        _check_held(V, facet_tags, cell_tags, node_body, constrained, interfaces)
    return node_body


def _check_held(V: fem.FunctionSpace, facet_tags: dmesh.MeshTags, cell_tags: dmesh.MeshTags,
                node_body: np.ndarray, constrained: np.ndarray, interfaces: typing.Sequence[Interface]) -> None:
    """Raise if a body can translate freely: along no direction may a body lack both a
    prescribed displacement component and a contact surface that resists it.

    A contact pair whose law has friction (:attr:`~contactqvi.laws.ContactLaw.frictional`) resists every direction;
    a frictionless one the directions of its normals, on both its bodies. Rotations
    are not checked.
    """
    comm = V.mesh.comm
    n_owned = V.dofmap.index_map.size_local
    names = list(cell_tags.names)
    held = np.zeros((len(names), 3, 3))
    for k in range(len(names)):
        prescribed = constrained[:n_owned][node_body[:n_owned] == k].any(axis=0)
        held[k] += np.diag(comm.allreduce(prescribed.astype(float), op=MPI.SUM) > 0).astype(float)
    for interface in interfaces:
        pair = interface.pair
        frictional = pair.law.frictional
        normals = interface.frames[:, 2]
        spread = comm.allreduce(np.einsum("ij,ik->jk", normals, normals), op=MPI.SUM)
        spread = np.eye(3) if frictional else spread / max(np.trace(spread), 1e-300)
        surfaces = [interface.slave_surface] + ([pair.master] if isinstance(pair, BodyPair) else [])
        for surface in surfaces:
            nodes = fem.locate_dofs_topological(V, V.mesh.topology.dim - 1, boundary_facets(facet_tags, surface))
            bodies = set().union(*comm.allgather(set(np.unique(node_body[nodes]).tolist())))
            for k in bodies - {-1}:
                held[k] += spread
    for k, name in enumerate(names):
        values, vectors = np.linalg.eigh(held[k])
        if values[0] < 1e-6:
            direction = np.array2string(vectors[:, 0], precision=3)
            require(False, f"bodies.{name}", f"nothing holds the body along {direction}: no prescribed "
                    "displacement component and no contact surface resists a translation that way "
                    "(add a support, or friction)")


def _node_body(V: fem.FunctionSpace, cell_tags: dmesh.MeshTags) -> np.ndarray:
    """Index (0, 1, ...) in ``cell_tags.names`` of the body of each local node (ghosts included)."""
    index_map = V.dofmap.index_map
    node_body = np.full(index_map.size_local + index_map.num_ghosts, -1, dtype=np.int32)
    for k, tag in enumerate(cell_tags.names.values()):
        cells = cell_tags.find(tag)
        node_body[V.dofmap.list[cells].ravel()] = k
    return node_body


def _dirichlet_conditions(
    V: fem.FunctionSpace, facet_tags: dmesh.MeshTags, clamped: typing.Sequence[str],
    displacements: dict[str, dict[int, float]], moved: typing.Sequence[str],
) -> tuple[list[fem.DirichletBC], fem.DirichletBC | None]:
    """Boundary conditions u = 0 on ``clamped``, u_i = value on ``displacements`` and
    u = (a translation, zero here) on ``moved``; the last also returned on its own."""
    fdim = V.mesh.topology.dim - 1
    bcs = []
    for name in clamped:
        blk = fem.locate_dofs_topological(V, fdim, boundary_facets(facet_tags, name))
        bcs.append(fem.dirichletbc(np.zeros(3, dtype=PETSc.ScalarType), blk, V))
    for name, components in displacements.items():
        facets = boundary_facets(facet_tags, name)
        for component, value in components.items():
            require(component in (0, 1, 2), f"boundary.displacement.{name}", f"component must be 0, 1 or 2, got {component!r}")
            dofs = fem.locate_dofs_topological(V.sub(component), fdim, facets)
            bcs.append(fem.dirichletbc(PETSc.ScalarType(value), dofs, V.sub(component)))
    moved_bc = None
    if moved:
        facets = np.unique(np.concatenate([boundary_facets(facet_tags, name) for name in moved]))
        blk = fem.locate_dofs_topological(V, fdim, facets)
        moved_bc = fem.dirichletbc(fem.Constant(V.mesh, np.zeros(3, dtype=PETSc.ScalarType)), blk, V)
        bcs.append(moved_bc)
    return bcs, moved_bc


def _align_frames(frames: np.ndarray, constrained: np.ndarray, comm: MPI.Comm) -> np.ndarray:
    """Frames whose t1 is the first prescribed global axis at partly constrained contact nodes.

    A prescribed displacement component on a contact node (a roller on a symmetry
    plane through the contact) must lie in the tangent plane; with t1 = e_c,
    t2 = n x e_c it is a frame component, so its Dirichlet row stays an identity row
    in nodal frames. The nodal law still sees all components; with u_t1 = 0, no
    obstacle motion along t1 (both checked) and r_t1 = 0 on the Dirichlet row, its
    argument has w_t1 = 0, so the law leaves u_t1 = 0 and puts no force on it.
    """
    partly = np.flatnonzero(constrained.any(axis=1))
    normals = frames[partly, 2]
    tangential = np.abs(normals[constrained[partly]] if len(partly) else np.empty(0)) <= 1e-10
    bad = comm.allreduce(int(np.count_nonzero(~tangential)), op=MPI.SUM)
    require(bad == 0, "boundary.displacement", f"{bad} contact nodes have a prescribed displacement component "
            "along the obstacle's normal; only tangential components can be prescribed on the contact surface")
    return roller_aligned(frames, constrained)


def _nodal_rotation(A: PETSc.Mat, contact_blk: np.ndarray, frames: np.ndarray, always: bool) -> PETSc.Mat | None:
    """Block-diagonal R with R_ii = frame_i^T at the contact nodes, I elsewhere; None if R = I
    and not ``always``."""
    comm = A.getComm().tompi4py()
    if not always and not comm.allreduce(bool(np.any(frames != np.eye(3))), op=MPI.LOR):
        return None
    T = PETSc.Mat().createAIJ(size=A.getSizes(), bsize=3, nnz=(3, 0), comm=A.getComm())
    n_blk = A.getLocalSize()[0] // 3
    blocks = np.broadcast_to(np.eye(3), (n_blk, 3, 3)).copy()
    blocks[contact_blk] = np.transpose(frames, (0, 2, 1))
    rows = (np.arange(n_blk) + A.getOwnershipRange()[0] // 3).astype(PETSc.IntType)[:, None]
    T.setValuesBlockedRCV(rows, rows, blocks.reshape(n_blk, 1, 9))
    T.assemble()
    return T
