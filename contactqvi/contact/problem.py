"""The discrete contact problem of seed 000, Sect. 6, as PETSc objects.

Generalized equation (6.3): 0 in A u - l + Q(u), in the shifted displacements
u = u~ + d (d3 = gap alpha_i at contact node i, zero elsewhere), so that the
non-penetration condition reads u3 >= 0 at every contact node.

Shift of the load, derived (the seed prints l := l~ - A d, which is a sign slip):
u~ = u - d minimises 1/2 u~^T A u~ - l~^T u~ subject to the contact conditions, and
    1/2 (u - d)^T A (u - d) - l~^T (u - d) = 1/2 u^T A u - (l~ + A d)^T u + const,
using A = A^T. Hence l = l~ + A d.
"""

from __future__ import annotations

import dataclasses

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import ufl

import dolfinx.fem.petsc
from dolfinx import fem
from dolfinx import mesh as dmesh

from contactqvi.contact.nodal import FrictionLaw
from contactqvi.elasticity import elasticity_forms
from contactqvi.meshes import boundary_facets
from contactqvi.parameters import require

__all__ = ["ContactProblem", "build_contact_problem"]


@dataclasses.dataclass
class ContactProblem:
    """Stiffness, shifted load and contact nodes of the GE (6.3).

    Attributes:
        V: vector Q1/P1 space of the displacement.
        A: stiffness matrix; Dirichlet rows and columns are identity rows/columns,
            so A restricted to the free dofs is the paper's A.
        load: shifted load l = l~ + A d (zero on Dirichlet dofs).
        shift: the shift d (gap in the normal component of contact nodes).
        contact_blk: owned local node (block) indices of the contact nodes.
        contact_facets: local facet indices of the contact boundary (for output on it).
        contact_area: lumped contact-surface area of each owned contact node (m^2).
        law: slip bound of the nodal friction law (Coulomb, Tresca or none).
        frames: (m, 3, 3) orthonormal frame of each owned contact node; rows t1, t2, n
            in global coordinates, n the obstacle's normal pointing into the body. The
            nodal components (two tangential, then normal) of u, the forces and the
            law are taken in this frame.
        dirichlet_dofs_loc: local unrolled indices of Dirichlet dofs (incl. ghosts).
        n_contact: global number p of contact nodes.
        n_free: global number n of free dofs.
    """

    V: fem.FunctionSpace
    A: PETSc.Mat
    load: PETSc.Vec
    shift: PETSc.Vec
    contact_blk: np.ndarray
    contact_facets: np.ndarray
    contact_area: np.ndarray
    law: FrictionLaw
    frames: np.ndarray
    dirichlet_dofs_loc: np.ndarray
    n_contact: int
    n_free: int

    @property
    def comm(self) -> MPI.Comm:
        return self.V.mesh.comm

    def destroy(self) -> None:
        """Free A, load and shift (collective); copies by ``dataclasses.replace`` share them."""
        for obj in (self.A, self.load, self.shift):
            obj.destroy()

    def physical_displacement(self, u: PETSc.Vec, out: fem.Function) -> fem.Function:
        """u~ = u - d written into the Function ``out`` (ghosts updated)."""
        out.x.petsc_vec.waxpy(-1.0, self.shift, u)
        out.x.scatter_forward()
        return out


def build_contact_problem(
    msh: dmesh.Mesh,
    facet_tags: dmesh.MeshTags,
    young: float,
    poisson: float,
    tractions: dict[str, tuple[float, float, float]],
    friction: float = 0.0,
    slip_bound: float = 0.0,
    dirichlet: str = "dirichlet",
    contact: str = "contact",
) -> ContactProblem:
    """Assemble the GE (6.3) for a body on the rigid foundation {x3 <= 0}.

    The contact nodes are the nodes of the ``contact`` boundary not on the
    ``dirichlet`` boundary (their number is p of Table 2); the gap alpha_i is the
    node's height x3 above the foundation; normal e3, tangent plane (e1, e2).

    Args:
        msh, facet_tags: mesh with named boundaries.
        young, poisson: E (Pa) and nu.
        tractions: surface traction (Pa) per boundary name.
        friction: Coulomb friction coefficient F >= 0.
        slip_bound: Tresca slip bound (Pa) >= 0: a friction traction bound, lumped
            to the nodal bound s_i = slip_bound * (area of node i) (N).
        dirichlet, contact: boundary names of Gamma_u and Gamma_c.
    """
    require(np.isfinite(friction) and friction >= 0, "friction", f"must be >= 0, got {friction!r}")
    require(np.isfinite(slip_bound) and slip_bound >= 0, "slip_bound", f"must be >= 0, got {slip_bound!r}")
    require(msh.geometry.dim == 3, "mesh", "the contact problem is three-dimensional")
    V = fem.functionspace(msh, ("Lagrange", 1, (3,)))
    a, L = elasticity_forms(V, young, poisson, facet_tags, tractions)
    fdim = msh.topology.dim - 1
    msh.topology.create_connectivity(fdim, msh.topology.dim)

    dirichlet_blk = fem.locate_dofs_topological(V, fdim, boundary_facets(facet_tags, dirichlet))
    bc = fem.dirichletbc(np.zeros(3, dtype=PETSc.ScalarType), dirichlet_blk, V)
    A = dolfinx.fem.petsc.assemble_matrix(a, bcs=[bc])
    A.assemble()
    load = dolfinx.fem.petsc.assemble_vector(L)
    dolfinx.fem.petsc.apply_lifting(load, [a], bcs=[[bc]])
    load.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    dolfinx.fem.petsc.set_bc(load, [bc])

    n_owned = V.dofmap.index_map.size_local
    contact_facets = boundary_facets(facet_tags, contact)
    contact_blk = fem.locate_dofs_topological(V, fdim, contact_facets)
    contact_blk = np.setdiff1d(contact_blk, dirichlet_blk)
    contact_blk = contact_blk[contact_blk < n_owned].astype(np.int32)
    gap = V.tabulate_dof_coordinates()[contact_blk, 2]
    comm = msh.comm
    require(comm.allreduce(int(np.any(gap < 0)), op=MPI.SUM) == 0, "gap", "initial penetration: a contact node lies below x3 = 0")

    shift = A.createVecRight()
    shift.array.reshape(-1, 3)[contact_blk, 2] = gap
    A.multAdd(shift, load, load)  # l = l~ + A d

    # Lumped nodal area of the contact surface, for pressures and tractions.
    Q = fem.functionspace(msh, ("Lagrange", 1))
    ds = ufl.Measure("ds", domain=msh, subdomain_data=facet_tags)
    area_form = fem.form(ufl.TestFunction(Q) * ds(facet_tags.names[contact]))
    area = dolfinx.fem.petsc.assemble_vector(area_form)
    area.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    contact_area = area.array[contact_blk].copy()
    area.destroy()

    n_dirichlet_owned = int(np.count_nonzero(dirichlet_blk < n_owned)) * 3
    return ContactProblem(
        V=V,
        A=A,
        load=load,
        shift=shift,
        contact_blk=contact_blk,
        contact_facets=contact_facets,
        contact_area=contact_area,
        law=FrictionLaw(float(friction), float(slip_bound) * contact_area),
        frames=np.broadcast_to(np.eye(3), (len(contact_blk), 3, 3)).copy(),
        dirichlet_dofs_loc=(3 * dirichlet_blk[:, None] + np.arange(3)).ravel().astype(np.int32),
        n_contact=comm.allreduce(len(contact_blk), op=MPI.SUM),
        n_free=comm.allreduce(3 * n_owned - n_dirichlet_owned, op=MPI.SUM),
    )
