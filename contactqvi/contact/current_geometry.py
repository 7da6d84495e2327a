"""The contact geometry of body pairs in the current configuration, inside the Newton iteration.

A pair with ``search = "newton"`` (docs/finite_strain.md, Sects. 13-14) has its mortar D, M,
C = D^-1 M, nodal normals and frames taken at the current positions x = X + u~ of every Newton
iterate and of every trial point of the line search: on the facet pairs and slave nodes of the
pair's last search (:func:`~contactqvi.contact.mortar.coupling_on_layout`; the load path
searches again when a converged iterate's projections have left them). The law's variables
at its slave nodes are (13.1),

    v_i,n = n_i . s_i   (the weighted gap),   v_i,a = t_a,i . (p_i - p_i^start),

the slip objective, measured from the master material point p_i^start = sum_j C_ij^start x_j
the node projected onto at the start of the load step. With the change of variables
u~ = T(x) w of :mod:`contactqvi.contact.problem` re-formed at each iterate, the solver's
variable at a contact node is v itself: its shift is d = v - w (:func:`following_shift`).
The Newton step (13.3) needs two more Jacobians than the frozen geometry's J = D A + U:

    J = D (A + Gamma T) + U (dv/du~) T,

Gamma u~' the change of T(x)^T r_K at fixed r_K (the slave frames turning, the slave force
passed to other master nodes), and dv/du~ the derivative of (13.1), identity-like in its own
motion. :func:`geometric_rows` assembles both as PETSc matrices, right-multiplied by T, from
the entries of :mod:`contactqvi.contact.kinematics`. An obstacle pair searched ``"newton"`` takes
(18.1)-(18.2) of :mod:`contactqvi.contact.obstacle_geometry` instead (Sect. 18).
"""

from __future__ import annotations

import dataclasses
import typing

from petsc4py import PETSc

import numpy as np

from dolfinx import fem
from dolfinx import mesh as dmesh

from contactqvi.contact.kinematics import (aligned_previous, contact_variables, frame_turn, master_shares,
                                           pair_frame_derivatives, variable_derivatives)
from contactqvi.contact.interface import Interface, assembled_area, lumped_area_form
from contactqvi.contact.mortar import MortarCoupling
from contactqvi.contact.obstacle_geometry import ObstacleGeometry
from contactqvi.load_steps import Rotation

__all__ = ["CurrentGeometry", "following_shift", "geometric_rows"]


@dataclasses.dataclass
class CurrentGeometry:
    """Where the geometry of the pairs searched ``"newton"`` was taken, and the slip's reference.

    Attributes:
        displacement: u~ of the configuration the interfaces were integrated at.
        start: per interface, its coupling at the start of the load step (C^start of (13.1)), for an
            obstacle pair its nodes' pi^start in the obstacle's initial position ((18.1),
            :func:`~contactqvi.contact.obstacle_geometry.start_points`), or None for a pair not
            searched ``"newton"``.
        base, direction: the line of the line search, u~_k and T_k du
            (:meth:`~contactqvi.contact.problem.ContactProblem.set_search_line`).
        trial: its trial point u~_k + alpha T_k du.
        area_forms: per obstacle surface the form of its nodal areas deformed by ``displacement``
            (:meth:`deformed_areas`), compiled once for this geometry.
    """

    displacement: fem.Function
    start: tuple[MortarCoupling | np.ndarray | None, ...]
    base: fem.Function
    direction: fem.Function
    trial: fem.Function
    area_forms: dict[str, fem.Form] = dataclasses.field(default_factory=dict)

    def deformed_areas(self, facet_tags: dmesh.MeshTags, surface: str) -> np.ndarray:
        """The nodal areas of ``surface`` deformed by :attr:`displacement` (local nodes; m^2;
        :func:`~contactqvi.contact.interface.lumped_area_form`). Collective."""
        if surface not in self.area_forms:
            self.area_forms[surface] = lumped_area_form(self.displacement.function_space, facet_tags, surface,
                                                        self.displacement)
        return assembled_area(self.area_forms[surface])

    @classmethod
    def at(cls, displacement: fem.Function,
           starts: typing.Sequence[MortarCoupling | np.ndarray | None]) -> CurrentGeometry:
        """The geometry at ``displacement`` (copied), the load step starting there with ``starts``."""
        copy = fem.Function(displacement.function_space)
        copy.x.array[:] = displacement.x.array
        V = displacement.function_space
        return cls(copy, tuple(starts), fem.Function(V), fem.Function(V), fem.Function(V))


def following_shift(V: fem.FunctionSpace, current: CurrentGeometry, interfaces: typing.Sequence[Interface],
                    contact_blk: np.ndarray, interface_of_node: np.ndarray, fit: float, solver_variables: np.ndarray,
                    constrained: np.ndarray, translation: np.ndarray,
                    rotation: Rotation | None) -> tuple[np.ndarray, np.ndarray]:
    """The shift d = v - w of the contact nodes (``contact_blk``, each one's interface
    ``interface_of_node``) of the pairs searched ``"newton"`` at the ``current`` geometry: v of
    (13.1) (of (18.1) for an obstacle placed by ``translation`` and ``rotation``; ``constrained``:
    (local nodes, 3) prescribed components), w = T^-1 u~ the solver's variables of the displacement
    there (``solver_variables``, owned local dofs), the interference not yet resolved (1 - ``fit``)
    delta(x) added to the normal one. Returns ``(positions in contact_blk, (k, 3) shift)``. Collective."""
    positions = V.tabulate_dof_coordinates() + current.displacement.x.array.reshape(-1, 3)
    x = V.tabulate_dof_coordinates()[contact_blk]
    at, shifts = [np.empty(0, dtype=np.int64)], [np.empty((0, 3))]
    for k, interface in enumerate(interfaces):
        if not interface.follows:
            continue
        nodes = np.flatnonzero(interface_of_node == k)
        coupling = interface.coupling
        if coupling is None:
            v = ObstacleGeometry(interface.obstacle, positions[interface.blk], constrained[interface.blk],
                                 current.start[k], translation, rotation).variables()
        else:
            previous = aligned_previous(current.start[k], coupling)
            v = contact_variables(V.mesh.comm, V.dofmap.index_map, coupling, previous, positions, interface.frames)[0]
        d = v - solver_variables.reshape(-1, 3)[contact_blk[nodes]]
        if coupling is not None:
            d[:, 2] += interface.gap(x[nodes], np.zeros(3), fit=fit) - interface.initial_gap
        at.append(nodes)
        shifts.append(d)
    return np.concatenate(at), np.concatenate(shifts)


def geometric_rows(V: fem.FunctionSpace, current: CurrentGeometry, interfaces: typing.Sequence[Interface],
                   constrained: np.ndarray, contact_blk: np.ndarray, transform: PETSc.Mat, prescribed: np.ndarray,
                   residual: PETSc.Vec, translation: np.ndarray,
                   rotation: Rotation | None) -> tuple[PETSc.Mat, PETSc.Mat]:
    """Gamma T and (dv/du~) T of the Newton matrix (module docstring) at the ``current`` geometry
    of ``interfaces`` (``constrained``: (local nodes, 3) prescribed components; ``contact_blk``
    the contact nodes; the obstacles placed by ``translation`` and ``rotation``), T = ``transform``,
    ``residual`` r_K there (global components, zero on
    prescribed rows): two new matrices of T's layout, their rows and columns of the solver's
    prescribed dofs (``prescribed``, owned local) dropped (those rows of f are u - l, and u~
    there is the prescribed value whatever the solver's variable is), the rows of a contact
    node's prescribed (roller) component and all rows of the nodes of pairs that do not follow
    the iterate identity rows of (dv/du~) T. Collective."""
    comm, index_map = V.mesh.comm, V.dofmap.index_map
    forces, variables = _Entries(), _Entries()
    positions = V.tabulate_dof_coordinates() + current.displacement.x.array.reshape(-1, 3)
    for k, interface in enumerate(interfaces):
        if not interface.follows:
            continue
        coupling = interface.coupling
        if coupling is None:
            _obstacle_rows(index_map, interface, positions, constrained, current.start[k], translation, rotation,
                           residual, forces, variables)
            continue
        slave_glob = index_map.local_to_global(coupling.slave_blk)
        fixed = constrained[coupling.slave_blk]
        dframes = pair_frame_derivatives(coupling, fixed)
        previous = aligned_previous(current.start[k], coupling)
        _, s, slip = contact_variables(comm, index_map, coupling, previous, positions, interface.frames)
        rows, dofs, values = variable_derivatives(index_map, coupling, previous, s, slip, interface.frames, dframes)
        variables.add_frame_rows(slave_glob[rows], dofs, values)
        r = residual.array_r.reshape(-1, 3)[coupling.slave_blk] * ~fixed  # P_i r_i
        rows, dofs, values = frame_turn(coupling, dframes, r)
        forces.add_frame_rows(slave_glob[rows], dofs, values)
        rows, dofs, values = master_shares(comm, index_map, coupling, r)
        forces.add_frame_rows(rows, dofs, values)
    free = transform.createVecRight()
    free.set(1.0)
    free.array[prescribed] = 0.0
    matrices = []
    for entries in (forces, variables):
        G = entries.matrix(transform)
        product = G.matMult(transform)
        product.diagonalScale(free, free)
        G.destroy()
        matrices.append(product)
    identity = _identity_rows(interfaces, contact_blk, free, transform)
    matrices[1].axpy(1.0, identity, PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
    for obj in (free, identity):
        obj.destroy()
    return matrices[0], matrices[1]


def _identity_rows(interfaces: typing.Sequence[Interface], contact_blk: np.ndarray, free: PETSc.Vec,
                   transform: PETSc.Mat) -> PETSc.Mat:
    """The identity rows of (dv/du~) T (a new matrix of ``transform``'s layout): a prescribed
    (roller) component of a contact node (``free`` zero there), and every component of a node of a
    pair that does not follow the iterate (an obstacle searched once beside a pair searched
    ``"newton"``). Their variable is w + d, d the shift, as for the frozen geometry
    (:func:`~contactqvi.contact.problem._align_frames`)."""
    contact_dofs = (3 * contact_blk[:, None] + np.arange(3)).ravel()
    frozen = np.concatenate([np.empty(0, dtype=np.int64), *(i.blk for i in interfaces if not i.follows)])
    rows = np.union1d(contact_dofs[free.array_r[contact_dofs] == 0.0],
                      (3 * frozen[:, None] + np.arange(3)).ravel()).astype(np.int64)
    marked = np.zeros(transform.getLocalSize()[0], dtype=PETSc.IntType)
    marked[rows] = 1
    identity = PETSc.Mat().createAIJ(size=transform.getSizes(), comm=transform.getComm(), csr=(
        np.concatenate([[0], np.cumsum(marked)]).astype(PETSc.IntType),
        (transform.getOwnershipRange()[0] + rows).astype(PETSc.IntType), np.ones(len(rows))))
    identity.assemble()
    return identity


def _obstacle_rows(index_map, interface: Interface, positions: np.ndarray, constrained: np.ndarray,
                   start: np.ndarray, translation: np.ndarray, rotation: Rotation | None, residual: PETSc.Vec,
                   forces: _Entries, variables: _Entries) -> None:
    """The entries of an obstacle pair's nodes (18.2) and frames' turn into ``variables`` and
    ``forces`` (``positions`` the current ones of the local nodes, ``start`` pi^start of (18.1))."""
    blk = interface.blk
    fixed = constrained[blk]
    geometry = ObstacleGeometry(interface.obstacle, positions[blk], fixed, start, translation, rotation)
    r = residual.array_r.reshape(-1, 3)[blk] * ~fixed  # P_i r_i
    nodes, components, dv, turn = geometry.derivatives(r)
    glob = index_map.local_to_global(blk)[nodes]
    variables.add_frame_rows(glob, 3 * np.asarray(glob, dtype=np.int64) + components, dv)
    forces.add_frame_rows(glob, 3 * np.asarray(glob, dtype=np.int64) + components, turn)


class _Entries:
    """COO entries (row, column, value) of a matrix of A's layout, nonzeros only."""

    def __init__(self) -> None:
        self.rows: list[np.ndarray] = []
        self.cols: list[np.ndarray] = []
        self.values: list[np.ndarray] = []

    def add_frame_rows(self, nodes: np.ndarray, dofs: np.ndarray, values: np.ndarray) -> None:
        """Entries of global nodes ``nodes`` (E,), columns ``dofs`` (E,), values (E, 3) for the
        node's three rows 3 J + a."""
        rows = (3 * np.asarray(nodes, dtype=np.int64)[:, None] + np.arange(3)).ravel()
        cols = np.repeat(np.asarray(dofs, dtype=np.int64), 3)
        values = np.asarray(values).ravel()
        nonzero = values != 0.0
        self.rows.append(rows[nonzero])
        self.cols.append(cols[nonzero])
        self.values.append(values[nonzero])

    def matrix(self, like: PETSc.Mat) -> PETSc.Mat:
        """The assembled matrix (duplicates added; rows on any rank)."""
        rows = np.concatenate([np.empty(0, dtype=np.int64), *self.rows]).astype(PETSc.IntType)
        cols = np.concatenate([np.empty(0, dtype=np.int64), *self.cols]).astype(PETSc.IntType)
        values = np.concatenate([np.empty(0), *self.values])
        width = np.int64(like.getSize()[1])  # one int64 key per (row, column)
        keys, inverse = np.unique(rows.astype(np.int64) * width + cols, return_inverse=True)
        summed = np.bincount(inverse.ravel(), weights=values, minlength=len(keys))
        nodes, starts = np.unique(keys // width, return_index=True)
        indptr = np.append(starts, len(keys)).astype(PETSc.IntType)
        M = PETSc.Mat().createAIJ(size=like.getSizes(), comm=like.getComm())
        M.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
        M.setUp()
        M.setValuesIJV(indptr, (keys % width).astype(PETSc.IntType), summed, addv=PETSc.InsertMode.ADD_VALUES,
                       rowmap=nodes.astype(PETSc.IntType))
        M.assemble()
        return M
