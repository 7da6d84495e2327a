"""The summed element Schur complements of the displacement-pressure pair: an approximation of
the pressure Schur complement P J_r^-1 P^T of :mod:`contactqvi.contact.pressure_schur` that sees
the cells' shapes and moduli (docs/nearly_incompressible.md, Sect. 5).

For each cell e of the bodies with the nodal pressure, with A_e the cell's shear stiffness
int 2 mu eps(u) : eps(v) and B_e its block of B = int chi phi_a div v (reference configuration),

    S_e = B_e A_e^+ B_e^T,   S_loc = sum_e S_e                                              (1)

(A_e^+ the pseudo-inverse: A_e vanishes on the cell's rigid motions, which B_e does not see, as
div vanishes on them; computed as (A_e + a R R^T)^-1 with R their orthonormal basis). S_loc
bounds the true S = B A^-1 B^T from above, because p^T S p = sup_v 2 p^T B v - v^T A v and giving
every cell its own v only enlarges the sup; where
the pair is inf-sup stable cell by cell (P2 displacements, P1 pressure: div maps a P2 tetrahedron's
fields onto the P1 functions) each S_e is definite, and S_loc is spectrally equivalent to S with
constants of the cells' shapes, not of their aspect ratios and moduli alone as the lumped mass
M_L / mu is.

With a mass term c M in the displacement block (the viscous relaxation past a limit point,
:mod:`contactqvi.contact.relaxation`: M = (rho u, v), rho each body's Young's modulus) the true
complement is S(c) = B (A + c M)^-1 B^T, and the cells take A_e + c M_e, regular for c > 0:

    S_loc(c) = sum_e B_e (A_e + c M_e)^-1 B_e^T,                                            (2)

an upper bound of S(c) by the same argument. S_loc of (1) alone is S_loc(0), which sees the
smooth pressure modes through A_e only: it overestimates S(c) where c M dominates A (the first
relaxation steps), and the pressure block's preconditioner with it (the
0.125 mm P2 O-ring with Coulomb friction at nu = 0.4999, its first relaxation step: 169-484 Krylov
iterations per Newton step with S_loc(0), 52-113 with S_loc(c); docs/nearly_incompressible.md Sect. 5).
"""

from __future__ import annotations

import typing

from petsc4py import PETSc

import basix.ufl
import numpy as np
import ufl

import dolfinx.fem.petsc
from dolfinx import fem

from contactqvi.elasticity import rigid_motions, strain

__all__ = ["local_schur"]

#: Preallocated entries per row of S_loc, on and off the rank (a vertex and its neighbours).
_NEIGHBOURS = 64


def _cell_blocks(form: ufl.Form, rows: fem.FunctionSpace, columns: fem.FunctionSpace, cells: np.ndarray,
                 ) -> np.ndarray:
    """(cells, m, n) the cell matrices of a bilinear ``form`` on broken (discontinuous) spaces, read
    from its assembled block-diagonal matrix (owned cells ``cells``; cell dof order)."""
    M = dolfinx.fem.petsc.assemble_matrix(fem.form(form))
    M.assemble()
    values = M.getValuesCSR()[2]
    M.destroy()
    row_dofs = _unrolled(rows, cells)
    col_dofs = _unrolled(columns, cells)
    n = col_dofs.shape[1]
    local = values.reshape(-1, n)[row_dofs]  # (cells, m, n): each row holds its cell's columns, ascending
    position = np.argsort(np.argsort(col_dofs, axis=1), axis=1)  # where each cell column sits in a row
    return np.take_along_axis(local, position[:, None, :], axis=2)


def _unrolled(V: fem.FunctionSpace, cells: np.ndarray) -> np.ndarray:
    """(cells, n) the scalar local dofs of ``cells`` in a (blocked) space, in cell order."""
    bs = V.dofmap.index_map_bs
    blocks = V.dofmap.list[cells]
    return (bs * blocks[:, :, None] + np.arange(bs)).reshape(len(cells), -1)


def _rigid_projector(V: fem.FunctionSpace, cells: np.ndarray, A: np.ndarray) -> np.ndarray:
    """(cells, n, n) a R R^T, R an orthonormal basis of the rigid motions at the nodes of each cell of
    the broken vector space ``V`` and a the mean of the diagonal of its cell matrix ``A``: A + a R R^T
    is regular, and B_e (A + a R R^T)^-1 B_e^T = B_e A^+ B_e^T, because B_e vanishes on R."""
    x = V.tabulate_dof_coordinates()[V.dofmap.list[cells]]  # (cells, nodes, 3)
    modes = rigid_motions(x - x.mean(axis=1, keepdims=True))  # (cells, nodes, component, mode)
    R = np.linalg.qr(modes.reshape(len(cells), -1, modes.shape[-1]))[0]
    scale = np.trace(A, axis1=1, axis2=2) / A.shape[1]
    return scale[:, None, None] * R @ np.swapaxes(R, 1, 2)


def local_schur(V: fem.FunctionSpace, Q: fem.FunctionSpace, mu: typing.Any, chi: fem.Function,
                mass: tuple[float, typing.Any] | None = None) -> PETSc.Mat:
    """S_loc of (1) on the scalar P1 space ``Q`` for the displacement space ``V`` (its degree), the
    shear modulus ``mu`` and the cells ``chi`` marks, or S_loc(c) of (2) for ``mass`` = (c, rho) with
    c > 0 (collective)."""
    msh = V.mesh
    cell = msh.basix_cell()
    degree = V.ufl_element().embedded_superdegree
    broken_u = fem.functionspace(msh, basix.ufl.element("Lagrange", cell, degree, shape=(3,), discontinuous=True))
    broken_p = fem.functionspace(msh, basix.ufl.element("Lagrange", cell, 1, discontinuous=True))
    u, v, q = ufl.TrialFunction(broken_u), ufl.TestFunction(broken_u), ufl.TestFunction(broken_p)
    n_cells = msh.topology.index_map(msh.topology.dim).size_local
    inside = np.flatnonzero(chi.x.array[:n_cells] > 0.5).astype(np.int32)
    A = _cell_blocks(2 * mu * ufl.inner(strain(u), strain(v)) * ufl.dx, broken_u, broken_u, inside)
    B = _cell_blocks(chi * q * ufl.div(u) * ufl.dx, broken_p, broken_u, inside)
    if mass is not None and mass[0] > 0.0:
        coefficient, density = mass
        regular = A + coefficient * _cell_blocks(density * ufl.inner(u, v) * ufl.dx, broken_u, broken_u, inside)
    else:
        regular = A + _rigid_projector(broken_u, inside, A)
    S = B @ np.linalg.solve(regular, np.swapaxes(B, 1, 2))
    index_map = Q.dofmap.index_map
    vertices = index_map.local_to_global(Q.dofmap.list[inside].ravel()).reshape(len(inside), -1)
    sizes = (index_map.size_local, index_map.size_global)
    out = PETSc.Mat().createAIJ(size=(sizes, sizes), nnz=(_NEIGHBOURS, _NEIGHBOURS), comm=msh.comm)
    out.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
    zero = out.createVecLeft()
    out.setDiagonal(zero, addv=PETSc.InsertMode.ADD_VALUES)  # every row, outside chi's cells too
    zero.destroy()
    out.setValuesRCV(vertices.astype(PETSc.IntType), vertices.astype(PETSc.IntType), S,
                     addv=PETSc.InsertMode.ADD_VALUES)
    out.assemble()
    return out
