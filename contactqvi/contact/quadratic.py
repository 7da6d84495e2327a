"""The modified quadratic basis of the slave surfaces of 10-node tetrahedra (quadratic displacements).

On a 6-node triangle the quadratic Lagrange functions of the vertices integrate to zero,
N_v = L_v (2 L_v - 1), int N_v = 0, so a vertex has no area to carry a contact pressure and no
dual (biorthogonal) multiplier basis with positive weights exists. Following Popp, Wohlmuth, Gee
and Wall (SIAM J. Sci. Comput. 34, 2012, Sect. 3: the basis transformation for quadratic
triangles, after Wohlmuth, Popp, Gee and Wall 2012), the displacement of the slave surface is
written in the modified basis

    Ñ_v = N_v + alpha (N_e + N_e'),   Ñ_e = (1 - 2 alpha) N_e,   alpha = 1/5,          (1)

e, e' the two edges of the facet at vertex v. It spans the same space, keeps the partition of
unity and gives every node a positive integral (int Ñ_v = 2A/15, int Ñ_e = A/5 on a flat facet
of area A). The coefficients ũ of a slave-surface displacement in (1) and its nodal values u are
related node by node,

    u_v = ũ_v,   u_e = (1 - 2 alpha) ũ_e + alpha (ũ_a + ũ_b),                            (2)

a, b the ends of edge e: u = S ũ with S the identity off the slave surfaces' edge nodes. The
contact conditions take ũ (the change of variables of the contact problem becomes u = S (I + N) R w,
:mod:`contactqvi.contact.problem`); the weighted quantities of a node follow from (1):

* its contact area, int Ñ_i = (S^T w)_i, w_j = int N_j the lumped quadratic areas;
* its position x̃ = S^-1 x, with x̃_e = (x_e - alpha (x_a + x_b)) / (1 - 2 alpha) off the
  surface (2/3 of the edge's sagitta beyond it): the weighted gap to a plane,
  int Φ_i g(x) / int Ñ_i with the dual basis Φ of (1), is the gap at x̃_i exactly, g being linear
  in x and x = sum_k x̃_k Ñ_k.

A nodal contact law on the nodes of the slave surface with these areas and positions is the dual
mortar discretisation of the contact with a rigid obstacle (exact for a plane, a nodal quadrature
of the weighted gap for a curved obstacle).
"""

from __future__ import annotations

import dataclasses
import typing

from petsc4py import PETSc

import numpy as np

import dolfinx.la
from dolfinx import fem

from contactqvi.contact.facets import ALPHA
from contactqvi.contact.mortar import exterior_facet_cells, facet_closures
from contactqvi.contact.owners import owner_ranges, sum_to_owners
from contactqvi.elasticity import displacement_degree
from contactqvi.lifetime import PETScOwner

__all__ = ["ALPHA", "ModifiedBasis", "modified_basis"]

@dataclasses.dataclass(eq=False)
class ModifiedBasis(PETScOwner):
    """S of (2) and its inverse on a quadratic vector space (block size 3, S = s ⊗ I).

    Attributes:
        V: the displacement space (vector P2).
        S: u = S ũ, of the geometry: positions and areas.
        inverse: ũ = S^-1 u.
        S_free, inverse_free: S and its inverse for the change of variables of the contact
            problem: without the entries of a prescribed component of an edge's end, and the
            identity in a prescribed component of an edge node. A prescribed component on a slave
            surface is zero (a roller), so S ũ is the same displacement, but a prescribed unknown
            then moves no free displacement and its row stays the identity of a prescribed row,
            as the residual's rows u_i - l_i of a hyperelastic body take it (as N of the mortar
            rows drops the columns of prescribed dofs,
            :func:`~contactqvi.contact.problem._change_of_variables`).
        edges: owned local blocks of the slave surfaces' edge nodes, sorted.
    """

    V: fem.FunctionSpace
    S: PETSc.Mat
    inverse: PETSc.Mat
    S_free: PETSc.Mat
    inverse_free: PETSc.Mat
    edges: np.ndarray

    def petsc_objects(self) -> list[typing.Any]:
        return [self.S, self.inverse, self.S_free, self.inverse_free]

    def positions(self, x: np.ndarray) -> np.ndarray:
        """x̃ = S^-1 x of local nodal vectors ``x`` (local nodes with ghosts, 3): positions or
        displacements in the modified basis (ghosts updated). Collective."""
        return self._apply(self.inverse, x, transpose=False)

    def areas(self, w: np.ndarray) -> np.ndarray:
        """int Ñ_i = (S^T w)_i of the lumped quadratic areas ``w`` (local nodes with ghosts, the
        owned ones complete): the contact area of each node (ghosts updated). Collective."""
        return self._apply(self.S, np.repeat(np.asarray(w)[:, None], 3, axis=1), transpose=True)[:, 0]

    def _apply(self, M: PETSc.Mat, values: np.ndarray, transpose: bool) -> np.ndarray:
        index_map = self.V.dofmap.index_map
        x, y = (dolfinx.la.create_petsc_vector(index_map, 3) for _ in range(2))
        n_owned = 3 * index_map.size_local
        x.array[:n_owned] = np.asarray(values, dtype=float).reshape(-1)[:n_owned]
        (M.multTranspose if transpose else M.mult)(x, y)
        y.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        with y.localForm() as local:
            out = local.array_r.reshape(-1, 3).copy()
        for vec in (x, y):
            vec.destroy()
        return out


def modified_basis(V: fem.FunctionSpace, facets: np.ndarray, constrained: np.ndarray) -> ModifiedBasis | None:
    """:class:`ModifiedBasis` of the slave surfaces made of the local exterior ``facets`` of a
    vector P2 space on tetrahedra; None for a space of degree 1. ``constrained``: (local nodes, 3)
    mask of the prescribed components. Each edge node's ends go to the rank that owns it (a rank
    that owns an edge node need not hold a surface facet with it). Collective."""
    if displacement_degree(V) == 1:
        return None
    msh = V.mesh
    cells, local = exterior_facet_cells(msh, np.asarray(facets, dtype=np.int32))
    blk = np.take_along_axis(V.dofmap.list[cells], facet_closures(V.dofmap.dof_layout, msh)[local], axis=1)
    index_map = V.dofmap.index_map
    edge = np.repeat(blk[:, 3:].ravel(), 2)
    ends = np.stack([blk[:, [1, 2, 0]].ravel(), blk[:, [2, 0, 1]].ravel()], axis=1).ravel()
    glob = index_map.local_to_global(np.concatenate([edge, ends]).astype(np.int32)).reshape(2, -1)
    rows, cols, held = sum_to_owners(msh.comm, owner_ranges(msh.comm, index_map), glob[0], glob[1],
                                     constrained[ends].astype(float))
    edges = np.unique(rows) - index_map.local_range[0]
    ends, held = cols.reshape(-1, 2), held.reshape(-1, 2, 3) > 0.0  # two ends per edge row, sorted by row
    end, diagonal = np.full(held.shape, ALPHA), np.full((len(edges), 3), 1.0 - 2.0 * ALPHA)
    geometric = (_matrix(V, edges, ends, diagonal, end),
                 _matrix(V, edges, ends, 1.0 / diagonal, -end / diagonal[:, None]))
    # a prescribed component of an edge node is one of its ends' too (the edge lies in the plane
    # of a roller): the identity there, and no prescribed end in a free component's row
    diagonal = np.where(constrained[edges], 1.0, diagonal)
    end = np.where(held | constrained[edges][:, None, :], 0.0, end)
    variables = (_matrix(V, edges, ends, diagonal, end),
                 _matrix(V, edges, ends, 1.0 / diagonal, -end / diagonal[:, None]))
    return ModifiedBasis(V, *geometric, *variables, edges.astype(np.int32))


def _matrix(V: fem.FunctionSpace, edges: np.ndarray, ends: np.ndarray, diagonal: np.ndarray,
            end: np.ndarray) -> PETSc.Mat:
    """The block matrix with rows s_ee = ``diagonal`` (edges, 3) and s_ea, s_eb = ``end`` (edges, 2, 3),
    per component, at the owned edge blocks ``edges`` (local) with their ends (global blocks), the
    identity elsewhere."""
    index_map = V.dofmap.index_map
    n_blocks, start = index_map.size_local, index_map.local_range[0]
    width = np.ones(n_blocks, dtype=np.int64)
    width[edges] = 3
    block = np.repeat(np.arange(n_blocks), width)  # the block entries, row by row
    column = start + block
    value = np.ones((len(block), 3))
    first = np.concatenate([[0], np.cumsum(width)[:-1]])[edges]
    value[first] = diagonal
    column[first + 1], column[first + 2] = ends[:, 0], ends[:, 1]
    value[first + 1], value[first + 2] = end[:, 0], end[:, 1]
    order = np.lexsort((column, block))
    block, column, value = block[order], column[order], value[order]
    # scalar row 3 b + c holds the entries of block row b at the columns' components c
    entry = np.tile(np.arange(len(block)), 3)
    component = np.repeat(np.arange(3), len(block))
    order = np.lexsort((entry, component, block[entry]))
    entry, component = entry[order], component[order]
    indptr = np.concatenate([[0], np.cumsum(np.repeat(width, 3))]).astype(PETSc.IntType)
    M = PETSc.Mat().createAIJ(size=((3 * n_blocks, PETSc.DETERMINE), (3 * n_blocks, PETSc.DETERMINE)), bsize=3,
                              csr=(indptr, (3 * column[entry] + component).astype(PETSc.IntType),
                                   value[entry, component]), comm=V.mesh.comm)
    M.assemble()
    return M
