"""Volume results of small-strain linear elasticity: stress, von Mises stress, reactions.

Units are SI as everywhere in contactqvi: stresses in Pa, forces in N.

* :class:`StressFields`, :func:`stress_fields`: the Cauchy stress tensor and the
  von Mises stress as cell-wise constant (DG0) fields, the cell averages of sigma(u).
* :func:`reaction_forces`: the force each supported boundary exerts on the body,
  from the residual r(v) = a(u, v) - l(v) assembled without boundary conditions
  (independent of any assembled, constrained or rotated matrix): at the dofs of a
  support r is the support's reaction, so its sum over them is the resultant.
* :func:`applied_force`: the resultant of tractions and body force.

Global equilibrium: reactions + contact force + applied force = 0, up to the
residual left at free dofs by the solver.
"""

from __future__ import annotations

import dataclasses

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import ufl

from dolfinx import fem, la
from dolfinx import mesh as dmesh

from contactqvi.elasticity import lame_parameters, strain, stress
from contactqvi.meshes import boundary_facets, tag_of
from contactqvi.parameters import require

__all__ = ["ElasticBody", "StressFields", "applied_force", "reaction_forces", "stress_fields", "von_mises"]

Vector3 = tuple[float, float, float]


@dataclasses.dataclass(frozen=True)
class ElasticBody:
    """What the volume results need besides the displacement: material, boundaries, loads.

    Attributes:
        young, poisson: E (Pa) and nu.
        facet_tags: facet tags with boundary names (:mod:`contactqvi.meshes`).
        supports: boundaries with a Dirichlet condition (clamped or prescribed
            components), whose reaction forces are reported, in this order.
        tractions: surface traction (Pa) per boundary name, at load factor 1.
        body_force: volume force density (N/m^3) at load factor 1, or None.
    """

    young: float
    poisson: float
    facet_tags: dmesh.MeshTags
    supports: tuple[str, ...] = ("dirichlet",)
    tractions: dict[str, Vector3] = dataclasses.field(default_factory=dict)
    body_force: Vector3 | None = None


def von_mises(sigma: np.ndarray) -> np.ndarray:
    """sqrt(3/2 s : s), s = sigma - tr(sigma)/3 I, of stress tensors ``sigma`` (..., 3, 3)."""
    s = sigma - np.trace(sigma, axis1=-2, axis2=-1)[..., None, None] / 3.0 * np.eye(3)
    return np.sqrt(1.5 * np.einsum("...ij,...ij->...", s, s))


class StressFields:
    """Cell averages of the Cauchy stress and the von Mises stress of ``u`` (3D, DG0).

    The tensor is the L2 projection of sigma(u) onto cell-wise constants (the
    average over each cell, exact where the stress is constant); von Mises is taken
    of that average. Spaces, forms and cell volumes are made once; :meth:`update`
    recomputes both fields from the current values of ``u``. Collective.

    Attributes:
        stress: DG0 function named ``stress`` (3 x 3, Pa).
        von_mises: DG0 function named ``von_mises`` (Pa).
    """

    def __init__(self, u: fem.Function, young: float, poisson: float):
        msh = u.function_space.mesh
        require(msh.geometry.dim == 3, "mesh", "stress_fields: three-dimensional bodies only")
        mu, lmbda = lame_parameters(young, poisson)
        W = fem.functionspace(msh, ("DG", 0, (3, 3)))
        Q = fem.functionspace(msh, ("DG", 0))
        self._n_cells = msh.topology.index_map(msh.topology.dim).size_local
        self._volume = fem.assemble_vector(fem.form(ufl.TestFunction(Q) * ufl.dx)).array[: self._n_cells]
        self._integral = fem.form(ufl.inner(stress(u, mu, lmbda), ufl.TestFunction(W)) * ufl.dx)
        self.stress = fem.Function(W, name="stress")
        self.von_mises = fem.Function(Q, name="von_mises")

    def update(self) -> tuple[fem.Function, fem.Function]:
        """Both fields of the current ``u``: ``(stress, von_mises)``."""
        n_cells = self._n_cells
        integral = fem.assemble_vector(self._integral)
        owned = integral.array[: 9 * n_cells].reshape(n_cells, 9) / self._volume[:, None]
        self.stress.x.array[: 9 * n_cells] = owned.ravel()
        self.stress.x.scatter_forward()
        self.von_mises.x.array[:n_cells] = von_mises(owned.reshape(n_cells, 3, 3))
        self.von_mises.x.scatter_forward()
        return self.stress, self.von_mises


def stress_fields(u: fem.Function, young: float, poisson: float) -> tuple[fem.Function, fem.Function]:
    """The :class:`StressFields` of ``u`` once: ``(stress, von_mises)``. Collective."""
    return StressFields(u, young, poisson).update()


def _load_form(msh: dmesh.Mesh, v: ufl.core.expr.Expr, body: ElasticBody, load_factor: float) -> ufl.Form:
    """l(v) = lambda ((f, v) + sum of (t, v) over the traction boundaries)."""
    ds = ufl.Measure("ds", domain=msh, subdomain_data=body.facet_tags)
    factor = fem.Constant(msh, PETSc.ScalarType(load_factor))
    zero = fem.Constant(msh, np.zeros(3, dtype=PETSc.ScalarType))
    form = ufl.inner(zero, v) * ufl.dx
    if body.body_force is not None:
        form += factor * ufl.inner(fem.Constant(msh, np.asarray(body.body_force, dtype=PETSc.ScalarType)), v) * ufl.dx
    for name, traction in body.tractions.items():
        t = fem.Constant(msh, np.asarray(traction, dtype=PETSc.ScalarType))
        form += factor * ufl.inner(t, v) * ds(tag_of(body.facet_tags, name))
    return form


def reaction_forces(
    u: fem.Function, body: ElasticBody, load_factor: float = 1.0, dirichlet_dofs_loc: np.ndarray | None = None,
    nodal_forces: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """Reaction force (N, global components) of each support of ``body`` on it.

    The residual r(v) = a(u, v) - l(v) is assembled without boundary conditions
    and summed over the constrained dofs of each support's nodes; a node on two
    supports counts for the first in ``body.supports``. Collective.

    Args:
        u: displacement (global components; for a contact problem the physical
            displacement u~).
        body: material, boundaries and loads.
        load_factor: factor on tractions and body force.
        dirichlet_dofs_loc: local unrolled indices of the constrained dofs (global
            components, e.g. ``ContactProblem.dirichlet_dofs_loc``); the free
            components of a support node (a roller) carry other forces, such as
            contact. None: every component of the supports' nodes.
        nodal_forces: (owned nodes, 3) other forces on the nodes (N, global components),
            taken off the residual: what of them acts on a constrained component goes
            straight into the support (a contact force on a prescribed component of a
            master node, which the discrete problem does not see).
    """
    V = u.function_space
    msh = V.mesh
    mu, lmbda = lame_parameters(body.young, body.poisson)
    v = ufl.TestFunction(V)
    residual_form = fem.form(ufl.inner(stress(u, mu, lmbda), strain(v)) * ufl.dx - _load_form(msh, v, body, load_factor))
    residual = fem.assemble_vector(residual_form)
    residual.scatter_reverse(la.InsertMode.add)
    n_owned = V.dofmap.index_map.size_local
    values = residual.array[: 3 * n_owned].reshape(n_owned, 3)
    if nodal_forces is not None:
        values = values - nodal_forces
    if dirichlet_dofs_loc is not None:
        constrained = np.zeros(residual.array.size, dtype=bool)
        constrained[dirichlet_dofs_loc] = True
        values = values * constrained[: 3 * n_owned].reshape(n_owned, 3)
    fdim = msh.topology.dim - 1
    msh.topology.create_connectivity(fdim, msh.topology.dim)
    counted = np.zeros(n_owned, dtype=bool)
    reactions = {}
    for name in body.supports:
        blk = fem.locate_dofs_topological(V, fdim, boundary_facets(body.facet_tags, name))
        blk = blk[blk < n_owned]
        blk = blk[~counted[blk]]
        counted[blk] = True
        reactions[name] = msh.comm.allreduce(values[blk].sum(axis=0), op=MPI.SUM)
    return reactions


def applied_force(msh: dmesh.Mesh, body: ElasticBody, load_factor: float = 1.0) -> np.ndarray:
    """Resultant (N) of the tractions and the body force at ``load_factor``. Collective."""
    total = np.zeros(3)
    for i in range(3):
        direction = fem.Constant(msh, np.eye(3)[i].astype(PETSc.ScalarType))
        value = fem.assemble_scalar(fem.form(_load_form(msh, direction, body, load_factor)))
        total[i] = msh.comm.allreduce(value, op=MPI.SUM)
    return total
