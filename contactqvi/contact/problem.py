"""The discrete contact problem of seed 000, Sect. 6, as PETSc objects, for any rigid obstacle.

Generalized equation (6.3): 0 in A u - l + Q(u) in the shifted displacements
u = u~ + d, written in *nodal frames*: at each contact node the three dofs are the
components along (t1, t2, n) of :mod:`contactqvi.obstacles` (n the obstacle's
normal pointing into the body), elsewhere the global ones. With the block-diagonal
rotation T (frame to global), A = T^T A_global T and l~ = T^T l~_global, so the
nodal law Q acts on (two tangential, normal) components exactly as in the seed,
where T = I (plane x3 = 0, frames e1, e2, e3; then no rotation is applied at all).

The shift d (zero off the contact nodes) makes the non-penetration condition
u3 >= 0 and, for load steps, measures slip from the previous step:
    d_n = g_k,   d_t = -(u~_t of the previous step + tangential obstacle translation since it),
where g_k is the gap to the obstacle at step k (:meth:`ContactProblem.set_step`), so
u_t is the slip increment relative to the obstacle (the time-discrete quasi-static
Coulomb problem; a single step from rest is the static problem of the seed).

Shift of the load, derived (the seed prints l := l~ - A d, which is a sign slip):
u~ = u - d minimises 1/2 u~^T A u~ - l~^T u~ subject to the contact conditions, and
    1/2 (u - d)^T A (u - d) - l~^T (u - d) = 1/2 u^T A u - (l~ + A d)^T u + const,
using A = A^T. Hence l = l~ + A d.
"""

from __future__ import annotations

import dataclasses
import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import ufl

from dolfinx import fem, la
from dolfinx import mesh as dmesh

from contactqvi.contact.nodal import FrictionLaw
from contactqvi.elasticity import elasticity_forms, rigid_motions_nullspace
from contactqvi.lifetime import PETScOwner
from contactqvi.linalg import assemble_system
from contactqvi.meshes import boundary_facets
from contactqvi.obstacles import Obstacle, Plane
from contactqvi.parameters import require, require_positive
from contactqvi.postprocess import ElasticBody

__all__ = ["ContactProblem", "build_contact_problem"]

Vector3 = tuple[float, float, float]


@dataclasses.dataclass
class ContactProblem(PETScOwner):
    """Stiffness, loads and contact nodes of the GE (6.3) in nodal frames.

    Attributes:
        V: vector P1/Q1 space of the displacement.
        A: stiffness matrix in nodal frames; Dirichlet rows and columns are identity
            rows/columns, so A restricted to the free dofs is the paper's A.
        applied: load l~ at load factor 1 in nodal frames (tractions, body force and
            the lifting of prescribed displacements; their values on Dirichlet dofs).
        load: shifted load l = lambda l~ + A d of the current step.
        shift: the shift d of the current step (nodal frames).
        contact_blk: owned local node (block) indices of the contact nodes.
        contact_facets: local facet indices of the contact boundary (for output on it).
        contact_area: lumped contact-surface area of each owned contact node (m^2).
        law: slip bound of the nodal friction law (Coulomb, Tresca or none).
        frames: (m, 3, 3) frame of each owned contact node; rows t1, t2, n in global
            coordinates, fixed in the reference configuration.
        obstacle: the rigid obstacle in its initial position.
        body: material, supports and loads at load factor 1 (for stresses and reactions).
        rotation: T (frame components to global), or None where every frame is (e1, e2, e3).
        rollers: (m,) mask of contact nodes whose t1 component is prescribed (zero).
        dirichlet_dofs_loc: local unrolled indices of Dirichlet dofs (incl. ghosts).
        n_contact: global number p of contact nodes.
        n_free: global number n of free dofs.
        load_factor, translation: the current step (:meth:`set_step`).
    """

    V: fem.FunctionSpace
    A: PETSc.Mat
    applied: PETSc.Vec
    load: PETSc.Vec
    shift: PETSc.Vec
    contact_blk: np.ndarray
    contact_facets: np.ndarray
    contact_area: np.ndarray
    law: FrictionLaw
    frames: np.ndarray
    obstacle: Obstacle
    body: ElasticBody
    rotation: PETSc.Mat | None
    rollers: np.ndarray
    dirichlet_dofs_loc: np.ndarray
    n_contact: int
    n_free: int
    load_factor: float = 1.0
    translation: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))

    @property
    def comm(self) -> MPI.Comm:
        return self.V.mesh.comm

    def petsc_objects(self) -> list[typing.Any]:
        """A, the load vectors and T (copies by ``dataclasses.replace`` share them)."""
        return [obj for obj in (self.A, self.applied, self.load, self.shift, self.rotation) if obj is not None]

    def gap(self, translation: typing.Sequence[float] = (0.0, 0.0, 0.0)) -> np.ndarray:
        """Gap of each owned contact node to the obstacle translated by ``translation`` (m)."""
        x = self.V.tabulate_dof_coordinates()[self.contact_blk]
        return self.obstacle.translated(translation).distance(x)[0]

    def set_step(
        self, load_factor: float = 1.0, translation: typing.Sequence[float] = (0.0, 0.0, 0.0),
        previous: PETSc.Vec | None = None,
    ) -> None:
        """Shift and load of a load step: tractions, body force and prescribed displacements
        times ``load_factor``,
        the obstacle translated by ``translation`` (total, m), slip measured from the
        physical displacement ``previous`` (nodal frames; None: from rest) and from the
        obstacle's position of the step before.
        """
        translation = np.asarray(translation, dtype=float)
        moved = self.frames[:, :2, :] @ (translation - self.translation)  # tangential obstacle motion per node
        along = self.comm.allreduce(float(np.abs(moved[self.rollers, 0]).max(initial=0.0)), op=MPI.MAX)
        require(along <= 1e-12 * max(float(np.linalg.norm(translation - self.translation)), 1e-300),
                "steps.translation", "the obstacle must not move along a component prescribed on contact nodes")
        nodal = np.zeros((len(self.contact_blk), 3))
        if previous is not None:
            nodal[:, :2] = previous.array.reshape(-1, 3)[self.contact_blk, :2]
        nodal[:, :2] = -(nodal[:, :2] + moved)
        nodal[:, 2] = self.gap(translation)
        self.shift.set(0.0)
        self.shift.array.reshape(-1, 3)[self.contact_blk] = nodal
        self.applied.copy(self.load)
        self.load.scale(load_factor)
        self.A.multAdd(self.shift, self.load, self.load)  # l = lambda l~ + A d
        self.load_factor, self.translation = float(load_factor), translation

    def physical_displacement(self, u: PETSc.Vec, out: fem.Function) -> fem.Function:
        """u~ = T (u - d) in global components, written into ``out`` (ghosts updated)."""
        if self.rotation is None:
            out.x.petsc_vec.waxpy(-1.0, self.shift, u)
        else:
            local = u.copy()
            local.axpy(-1.0, self.shift)
            self.rotation.mult(local, out.x.petsc_vec)
            local.destroy()
        out.x.scatter_forward()
        return out

    def near_nullspace(self) -> PETSc.NullSpace:
        """Rigid-body modes in nodal frames (T^T of the global ones), for AMG."""
        modes = rigid_motions_nullspace(self.V)
        if self.rotation is None:
            return modes
        global_modes = modes.getVecs()
        vectors = [self.A.createVecRight() for _ in global_modes]
        for mode, vector in zip(global_modes, vectors):
            self.rotation.multTranspose(mode, vector)
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
    friction: float = 0.0,
    slip_bound: float = 0.0,
    clamped: typing.Sequence[str] = ("dirichlet",),
    contact: str = "contact",
    obstacle: Obstacle | None = None,
    body_force: Vector3 | None = None,
    displacements: dict[str, dict[int, float]] | None = None,
) -> ContactProblem:
    """Assemble the GE (6.3) for a body against a rigid obstacle, at load factor 1.

    The contact nodes are the nodes of the ``contact`` boundary that are not clamped
    (their number is p of Table 2); a node with some prescribed components (a roller
    on a symmetry plane) stays a contact node if those components are tangential.

    Args:
        msh, facet_tags: mesh with named boundaries.
        young, poisson: E (Pa) and nu.
        tractions: surface traction (Pa) per boundary name.
        friction: Coulomb friction coefficient F >= 0.
        slip_bound: Tresca slip bound (Pa) >= 0: a friction traction bound, lumped
            to the nodal bound s_i = slip_bound * (area of node i) (N).
        clamped: boundaries with u = 0.
        contact: boundary that may touch the obstacle.
        obstacle: the rigid obstacle; default the foundation {x3 <= 0} of seed 000.
        body_force: volume force density (N/m^3).
        displacements: prescribed components per boundary name, ``{name: {component: value (m)}}``.

    Raises:
        ParameterError: bad values, unknown boundary names, or a contact node inside
            the obstacle (initial penetration).
    """
    require_positive("friction", friction, allow_zero=True)
    require_positive("slip_bound", slip_bound, allow_zero=True)
    require(msh.geometry.dim == 3, "mesh", "the contact problem is three-dimensional")
    obstacle = Plane((0.0, 0.0, 0.0), (0.0, 0.0, 1.0)) if obstacle is None else obstacle
    V = fem.functionspace(msh, ("Lagrange", 1, (3,)))
    a, L = elasticity_forms(V, young, poisson, facet_tags, tractions, body_force)
    msh.topology.create_connectivity(msh.topology.dim - 1, msh.topology.dim)
    bcs = _dirichlet_conditions(V, facet_tags, clamped, displacements or {})
    dirichlet_dofs_loc = np.unique(np.concatenate([bc.dof_indices()[0] for bc in bcs] + [np.empty(0, np.int32)]))
    A, applied = assemble_system(a, L, bcs)
    n_owned = V.dofmap.index_map.size_local
    contact_facets = boundary_facets(facet_tags, contact)
    contact_blk, constrained = _contact_nodes(V, contact_facets, dirichlet_dofs_loc)
    nonzero = msh.comm.allreduce(int(np.count_nonzero(applied.array.reshape(-1, 3)[contact_blk][constrained])))
    require(nonzero == 0, "boundary.displacement", f"{nonzero} components prescribed on contact nodes are not "
            "zero; on the contact surface only rollers (zero tangential components) are supported")
    x = V.tabulate_dof_coordinates()[contact_blk]
    _check_penetration(msh, obstacle, x)
    frames = _align_frames(obstacle.frames(x), constrained, msh.comm)
    rotation = _nodal_rotation(A, contact_blk, frames)
    if rotation is not None:  # nodal frames: A = T^T A T, l~ = T^T l~
        A_global, A = A, A.PtAP(rotation)
        A_global.destroy()
        applied_global, applied = applied, applied.duplicate()
        rotation.multTranspose(applied_global, applied)
        applied_global.destroy()

    comm = msh.comm
    n_fixed_owned = int(np.count_nonzero(dirichlet_dofs_loc < 3 * n_owned))
    contact_area = _lumped_area(msh, facet_tags, contact, contact_blk)
    problem = ContactProblem(
        V=V, A=A, applied=applied, load=applied.duplicate(), shift=applied.duplicate(),
        contact_blk=contact_blk, contact_facets=contact_facets, contact_area=contact_area,
        law=FrictionLaw(float(friction), float(slip_bound) * contact_area), frames=frames, obstacle=obstacle,
        body=ElasticBody(young, poisson, facet_tags, tuple(dict.fromkeys([*clamped, *(displacements or {})])),
                         dict(tractions), body_force),
        rotation=rotation, rollers=constrained.any(axis=1), dirichlet_dofs_loc=dirichlet_dofs_loc.astype(np.int32),
        n_contact=comm.allreduce(len(contact_blk), op=MPI.SUM),
        n_free=comm.allreduce(3 * n_owned - n_fixed_owned, op=MPI.SUM),
    )
    problem.set_step()
    return problem


def _contact_nodes(
    V: fem.FunctionSpace, contact_facets: np.ndarray, dirichlet_dofs_loc: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Owned nodes of the contact facets that are not clamped, and their (m, 3) mask of
    prescribed components."""
    index_map = V.dofmap.index_map
    constrained = np.zeros((index_map.size_local + index_map.num_ghosts) * 3, dtype=bool)
    constrained[dirichlet_dofs_loc] = True
    constrained = constrained.reshape(-1, 3)
    blk = fem.locate_dofs_topological(V, V.mesh.topology.dim - 1, contact_facets)
    blk = blk[(blk < index_map.size_local) & ~constrained[blk].all(axis=1)].astype(np.int32)
    return blk, constrained[blk]


def _dirichlet_conditions(
    V: fem.FunctionSpace, facet_tags: dmesh.MeshTags, clamped: typing.Sequence[str],
    displacements: dict[str, dict[int, float]],
) -> list[fem.DirichletBC]:
    """Boundary conditions u = 0 on ``clamped`` and u_i = value on ``displacements``."""
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
    return bcs


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
    frames = frames.copy()
    axis = np.eye(3)[np.argmax(constrained[partly], axis=1)]
    frames[partly, 0] = axis
    frames[partly, 1] = np.cross(normals, axis)
    return frames


def _check_penetration(msh: dmesh.Mesh, obstacle: Obstacle, x: np.ndarray) -> None:
    """Raise if a contact node lies inside the obstacle (beyond round-off of the mesh size)."""
    gap, normal = obstacle.distance(x)
    undefined = msh.comm.allreduce(int(np.count_nonzero(~np.isfinite(normal).all(axis=1))), op=MPI.SUM)
    require(undefined == 0, "obstacle", f"{undefined} contact nodes lie where the obstacle has no normal "
            "(a sphere's centre or a cylinder's axis)")
    extent = np.ptp(msh.geometry.x, axis=0).max() if len(msh.geometry.x) else 0.0
    tol = 1e-10 * msh.comm.allreduce(float(extent), op=MPI.MAX)
    count = msh.comm.allreduce(int(np.count_nonzero(gap < -tol)), op=MPI.SUM)
    worst = msh.comm.allreduce(float(gap.min(initial=np.inf)), op=MPI.MIN)
    require(count == 0, "obstacle", f"initial penetration: {count} contact nodes lie inside the obstacle, "
            f"the deepest by {-worst:.3e} m")


def _nodal_rotation(A: PETSc.Mat, contact_blk: np.ndarray, frames: np.ndarray) -> PETSc.Mat | None:
    """Block-diagonal T with T_ii = frame_i^T at the contact nodes, I elsewhere; None if T = I."""
    comm = A.getComm().tompi4py()
    if not comm.allreduce(bool(np.any(frames != np.eye(3))), op=MPI.LOR):
        return None
    T = PETSc.Mat().createAIJ(size=A.getSizes(), bsize=3, nnz=(3, 0), comm=A.getComm())
    n_blk = A.getLocalSize()[0] // 3
    blocks = np.broadcast_to(np.eye(3), (n_blk, 3, 3)).copy()
    blocks[contact_blk] = np.transpose(frames, (0, 2, 1))
    rows = (np.arange(n_blk) + A.getOwnershipRange()[0] // 3).astype(PETSc.IntType)[:, None]
    T.setValuesBlockedRCV(rows, rows, blocks.reshape(n_blk, 1, 9))
    T.assemble()
    return T


def _lumped_area(msh: dmesh.Mesh, facet_tags: dmesh.MeshTags, contact: str, contact_blk: np.ndarray) -> np.ndarray:
    """Lumped area of the contact surface at each owned contact node (m^2)."""
    Q = fem.functionspace(msh, ("Lagrange", 1))
    ds = ufl.Measure("ds", domain=msh, subdomain_data=facet_tags)
    area = la.vector(Q.dofmap.index_map)
    fem.assemble_vector(area.array, fem.form(ufl.TestFunction(Q) * ds(facet_tags.names[contact])))
    area.scatter_reverse(la.InsertMode.add)
    return area.array[contact_blk].copy()
