"""The paper's own discretisation of (P) (seed 002, Sect. 6): finite differences on the N x N grid.

Sect. 6 uses "the usual five-point stencil approximation to the Laplace operator"
and "one-sided differences" for the normal derivative. Scaled by h^2, (2.4)/(3.2a)
keeps the form K y + M lambda = F of :class:`~contactqvi.friction.FrictionProblem`,
so the same solvers run on it:

* interior node P: 4 y_P - sum_{Q ~ P} y_Q + mu h^2 y_P = h^2 f(P) (f sampled at P);
* Gamma_f node P: -dy/dn = lambda with the one-sided difference to the inward
  neighbour, y_P - y_in + h lambda_P = 0 (m_P = h); at a corner between two
  friction edges the mean of both one-sided differences, times h/2 (m_P = h/2);
* Gamma_0 node: y_P = 0 (identity row; its column is dropped from the other rows).

Then lambda = (F - K y)_P / m_P is the one-sided -dy/dn at P, the lambda^0 :=
-dy^0/dn of (PDAS) step 1, and ||.||_{L2(Gamma_f)} is the trapezoidal rule on each
edge, except that a corner between two friction edges has the weight h/2 of its
row, not h (the perimeter of Examples 2 and 3 is measured as 4 - 2h). K is
symmetric except in the rows of corners between two friction edges (Examples 2
and 3); it is a nonsingular M-matrix. The grid points are the vertices of the Q1
mesh of :func:`contactqvi.meshes.create_unit_square`, so vectors, index maps and
the parallel layout are those of the Q1 problem; K is assembled row-wise in parallel.
"""

from __future__ import annotations

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import scipy.sparse

from dolfinx import fem

from contactqvi.friction.problem import FrictionData, FrictionProblem
from contactqvi.meshes import SQUARE_BOUNDARIES, create_unit_square
from contactqvi.parameters import require

__all__ = ["PaperFiniteDifferences"]

#: Grid steps to the four neighbours of the five-point stencil.
NEIGHBOURS = ((1, 0), (-1, 0), (0, 1), (0, -1))


class PaperFiniteDifferences(FrictionProblem):
    """A problem on the unit square in the paper's finite-difference scheme (module docstring).

    Args:
        comm: communicator.
        data: the problem's data (:class:`~contactqvi.friction.problem.FrictionData`); Gamma_f
            and Gamma_0 must cover the boundary.
        N: grid points per direction (h = 1/(N - 1)).
    """

    def __init__(self, comm: MPI.Comm, data: FrictionData, N: int):
        boundaries = set(data.friction_boundaries) | set(data.dirichlet_boundaries)
        require(boundaries == set(SQUARE_BOUNDARIES), "data", "Gamma_f and Gamma_0 must cover the boundary")
        msh, facet_tags = create_unit_square(comm, N - 1)
        super().__init__(msh, facet_tags, data.friction_boundaries, data.dirichlet_boundaries, data.load, data.mu,
                         data.g)  # fmt: skip
        self.N, self.h = N, 1.0 / (N - 1)
        n_owned = self.V.dofmap.index_map.size_local
        #: Grid indices (i, j) of the owned nodes: x = (i h, j h).
        self.ij = np.rint(self.V.tabulate_dof_coordinates()[:n_owned, :2] / self.h).astype(np.int64)
        self.interior = ((self.ij > 0) & (self.ij < N - 1)).all(axis=1)
        rows, cols, vals, directions = self._stencil()
        self.K.destroy()
        self.K = self._matrix(rows, cols, vals)
        self._sample_load()
        self.boundary_mass = self.h / directions

    def _global_numbering(self, dirichlet: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Global index of every grid point (by i N + j) and the Gamma_0 flag of every global index."""
        index_map = self.V.dofmap.index_map
        glob = index_map.local_range[0] + np.arange(index_map.size_local, dtype=np.int64)
        codes = np.concatenate(self.comm.allgather(self.ij[:, 0] * self.N + self.ij[:, 1]))
        globs = np.concatenate(self.comm.allgather(glob))
        node_glob = np.empty(self.N * self.N, dtype=np.int64)
        node_glob[codes] = globs
        dirichlet_glob = np.zeros(index_map.size_global, dtype=bool)
        dirichlet_glob[globs] = np.concatenate(self.comm.allgather(dirichlet))
        return node_glob, dirichlet_glob

    def _stencil(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Owned rows (local), columns (global) and values of K; the stencil directions per friction node."""
        N, ij = self.N, self.ij
        dirichlet = ~self.interior
        dirichlet[self.boundary_dofs] = False
        node_glob, dirichlet_glob = self._global_numbering(dirichlet)
        first = self.V.dofmap.index_map.local_range[0]
        p = np.flatnonzero(self.interior)
        rows, cols, vals = [p], [first + p], [np.full(p.size, 4.0 + self.mu * self.h**2)]
        for step in NEIGHBOURS:
            rows.append(p)
            cols.append(node_glob[(ij[p, 0] + step[0]) * N + ij[p, 1] + step[1]])
            vals.append(np.full(p.size, -1.0))
        b = self.boundary_dofs
        inward = np.where(ij[b] == 0, 1, np.where(ij[b] == N - 1, -1, 0))
        directions = np.count_nonzero(inward, axis=1)  # 1 on an edge, 2 at a corner
        rows.append(b)
        cols.append(first + b)
        vals.append(1.0 / directions)
        for axis in (0, 1):
            along = inward[:, axis] != 0
            neighbour = ij[b[along]].copy()
            neighbour[:, axis] += inward[along, axis]
            rows.append(b[along])
            cols.append(node_glob[neighbour[:, 0] * N + neighbour[:, 1]])
            vals.append(-1.0 / directions[along] ** 2)
        d = np.flatnonzero(dirichlet)
        rows, cols, vals = [*rows, d], [*cols, first + d], [*vals, np.ones(d.size)]
        rows, cols, vals = (np.concatenate(a) for a in (rows, cols, vals))
        keep = (cols == first + rows) | ~dirichlet_glob[cols]  # y = 0 on Gamma_0
        return rows[keep], cols[keep], vals[keep], directions

    def _matrix(self, rows: np.ndarray, cols: np.ndarray, vals: np.ndarray) -> PETSc.Mat:
        """The AIJ matrix of the owned rows (the layout of the Q1 dofs)."""
        n_owned, n_global = self.V.dofmap.index_map.size_local, self.V.dofmap.index_map.size_global
        csr = scipy.sparse.csr_matrix((vals, (rows, cols)), shape=(n_owned, n_global))
        csr.sort_indices()
        return PETSc.Mat().createAIJ(
            ((n_owned, n_global), (n_owned, n_global)),
            csr=(csr.indptr.astype(PETSc.IntType), csr.indices.astype(PETSc.IntType), csr.data), comm=self.comm,
        )  # fmt: skip

    def _sample_load(self) -> None:
        """F = h^2 f(P) at interior nodes, 0 on the boundary."""
        f = fem.Function(self.V)
        f.interpolate(fem.Expression(self.load_expression, self.V.element.interpolation_points(), comm=self.comm))
        n_owned = self.V.dofmap.index_map.size_local
        self.F.array[:] = np.where(self.interior, self.h**2 * f.x.array[:n_owned], 0.0)
