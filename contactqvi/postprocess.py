"""Volume results of small-strain linear elasticity: stress, von Mises stress, reactions.

Units are SI as everywhere in contactqvi: stresses in Pa, forces in N.

* :class:`StressFields`, :func:`stress_fields`: the Cauchy stress tensor and the
  von Mises stress as cell-wise constant (DG0) fields, the cell averages of sigma(u).
* :func:`reaction_forces`: the force each supported boundary exerts on the body,
  from the residual r(v) = a(u, v) - l(v) assembled without boundary conditions
  (independent of any assembled, constrained or rotated matrix): at a constrained
  dof r is the reaction there; each prescribed component's reaction belongs to the
  supports that prescribe that component at that node, shared equally when several
  do, so the reactions do not depend on the order of the supports.
* :func:`applied_force`: the resultant of tractions and body force (with a force per
  body: of each body's own, :attr:`ElasticBody.body_force`).

Global equilibrium: reactions + contact force + applied force = 0, up to the
residual left at free dofs by the solver.
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

from contactqvi.elasticity import (BodyForce, body_force_form, displacement_degree, lame_parameters, pressure_form,
                                   strain, stress)
from contactqvi.materials import Material
from contactqvi.meshes import boundary_facets, tag_of
from contactqvi.nodal_pressure import averaged_stress, internal_work
from contactqvi.parameters import require

__all__ = ["ElasticBody", "StressFields", "applied_force", "internal_force_form", "load_form", "reaction_forces",
           "stress_fields", "von_mises"]

Vector3 = tuple[float, float, float]


@dataclasses.dataclass(frozen=True)
class ElasticBody:
    """What the volume results need besides the displacement: material, boundaries, loads.

    Attributes:
        young, poisson: E (Pa) and nu.
        facet_tags: facet tags with boundary names (:mod:`contactqvi.meshes`).
        supports: boundaries with a Dirichlet condition (clamped or prescribed
            components), whose reaction forces are reported (in this order; the
            values do not depend on it).
        tractions: surface traction (Pa) per boundary name, at load factor 1.
        body_force: volume force density (N/m^3) at load factor 1: one vector, or one
            per body ``{body: f}`` (cell group names of ``cell_tags``), or None.
        prescribed: the components (0, 1, 2 for x, y, z) each support prescribes,
            ``{name: (1,)}`` for a roller holding y. A support not listed prescribes
            the components constrained at every one of its nodes (:func:`reaction_forces`;
            what the case gives unless all its nodes also lie on supports that
            prescribe more).
        cell_tags: named cell groups, one per body (for a body force per body), or None.
        material: a hyperelastic material (finite strain: the residual of P(F), the Cauchy
            stress P F^T / det F), or None for linear elasticity.
        pressures: pressure (Pa, > 0 into the body) per boundary name, at load factor 1
            (on the deformed surface for a hyperelastic body).
        nodal: the indicator of the cells whose volume change is averaged at the nodes
            (:mod:`contactqvi.nodal_pressure`), or None.
    """

    young: float
    poisson: float
    facet_tags: dmesh.MeshTags
    supports: tuple[str, ...] = ("dirichlet",)
    tractions: dict[str, Vector3] = dataclasses.field(default_factory=dict)
    body_force: BodyForce | None = None
    prescribed: dict[str, tuple[int, ...]] = dataclasses.field(default_factory=dict)
    cell_tags: dmesh.MeshTags | None = None
    material: Material | None = None
    pressures: dict[str, float] = dataclasses.field(default_factory=dict)
    nodal: fem.Function | None = None


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

    def __init__(self, u: fem.Function, young: float, poisson: float, material: Material | None = None,
                 nodal: fem.Function | None = None):
        msh = u.function_space.mesh
        require(msh.geometry.dim == 3, "mesh", "stress_fields: three-dimensional bodies only")
        mu, lmbda = lame_parameters(young, poisson)
        W = fem.functionspace(msh, ("DG", 0, (3, 3)))
        Q = fem.functionspace(msh, ("DG", 0))
        self._n_cells = msh.topology.index_map(msh.topology.dim).size_local
        self._volume = fem.assemble_vector(fem.form(ufl.TestFunction(Q) * ufl.dx)).array[: self._n_cells]
        self._averaged = None
        if nodal is not None:  # the nodally averaged volume change (contactqvi.nodal_pressure)
            self._averaged = internal_work(u, ufl.TestFunction(u.function_space), material, mu, lmbda, nodal)[1]
            integral = ufl.inner(averaged_stress(self._averaged, mu, lmbda), ufl.TestFunction(W)) * ufl.dx
        elif material is None:
            integral = ufl.inner(stress(u, mu, lmbda), ufl.TestFunction(W)) * ufl.dx
        else:
            integral = (ufl.inner(material.cauchy_stress(u, mu, lmbda), ufl.TestFunction(W))
                        * material.dx(displacement_degree(u.function_space)))
        self._integral = fem.form(integral)
        self.stress = fem.Function(W, name="stress")
        self.von_mises = fem.Function(Q, name="von_mises")

    def update(self) -> tuple[fem.Function, fem.Function]:
        """Both fields of the current ``u``: ``(stress, von_mises)``."""
        n_cells = self._n_cells
        if self._averaged is not None:
            self._averaged.update()
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


def load_form(msh: dmesh.Mesh, v: ufl.core.expr.Expr, body: ElasticBody, load_factor: float,
               u: fem.Function | None = None) -> ufl.Form:
    """l(v) = lambda ((f, v) + sum of (t, v) over the traction boundaries - the pressures'
    load), the pressures on the surface deformed by ``u`` for a hyperelastic body
    (:func:`~contactqvi.elasticity.pressure_form`)."""
    ds = ufl.Measure("ds", domain=msh, subdomain_data=body.facet_tags)
    factor = fem.Constant(msh, PETSc.ScalarType(load_factor))
    zero = fem.Constant(msh, np.zeros(3, dtype=PETSc.ScalarType))
    form = ufl.inner(zero, v) * ufl.dx
    if body.body_force is not None:
        form += factor * body_force_form(msh, v, body.body_force, body.cell_tags)
    for name, traction in body.tractions.items():
        t = fem.Constant(msh, np.asarray(traction, dtype=PETSc.ScalarType))
        form += factor * ufl.inner(t, v) * ds(tag_of(body.facet_tags, name))
    if body.pressures:
        follower = u if body.material is not None else None
        form += factor * pressure_form(msh, v, body.facet_tags, body.pressures, follower)
    return form


def reaction_forces(
    u: fem.Function, body: ElasticBody, load_factor: float = 1.0, dirichlet_dofs_loc: np.ndarray | None = None,
    nodal_forces: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """Reaction force (N, global components) of each support of ``body`` on it.

    The residual r(v) = a(u, v) - l(v) is assembled without boundary conditions; at a
    constrained dof it is the reaction there. Each prescribed component's reaction at
    a node belongs to the supports that prescribe that component there (a node on a
    y-roller and a face with prescribed x and z gives r_y to the roller and r_x, r_z
    to the face); where several supports prescribe the same component at a node (a
    clamped face and a roller meeting at an edge, two clamped faces at a corner) its
    reaction is split equally among them: no support is preferred, so no tie needs
    breaking (a rule by the number of components held would still need one between
    two clamped faces), and mirror-image supports get mirror-image reactions. The
    reactions therefore do not depend on the order of ``body.supports``, and they add
    up to r summed over all constrained dofs of the supports' nodes, whatever the
    split. What a support prescribes: ``body.prescribed``, else the components
    constrained at every one of its nodes. Collective.

    Args:
        u: displacement (global components; for a contact problem the physical
            displacement u~).
        body: material, boundaries and loads.
        load_factor: factor on tractions and body force.
        dirichlet_dofs_loc: local unrolled indices of the constrained dofs (global
            components, e.g. ``ContactProblem.dirichlet_dofs_loc``); the free
            components of a support node (a roller) carry other forces, such as
            contact. None: the components the supports prescribe at their nodes
            (all three for a support not in ``body.prescribed``).
        nodal_forces: (owned nodes, 3) other forces on the nodes (N, global components),
            taken off the residual: what of them acts on a constrained component goes
            straight into the support (a contact force on a prescribed component of a
            master node, which the discrete problem does not see).

    Raises:
        ParameterError: a constrained component of a support node that no support
            prescribes (``body.prescribed`` disagrees with ``dirichlet_dofs_loc``).
    """
    V = u.function_space
    comm = V.mesh.comm
    values = _nodal_residual(u, body, load_factor)
    if nodal_forces is not None:
        values = values - nodal_forces
    on_support = _support_nodes(V, body)
    constrained = None if dirichlet_dofs_loc is None else _owned_components(dirichlet_dofs_loc, len(on_support))
    prescribes = _prescribed_components(body, on_support, constrained, comm)
    if constrained is None:  # what the supports prescribe at their nodes
        constrained = on_support.astype(np.int64) @ prescribes.astype(np.int64) > 0
    rows = np.flatnonzero(on_support.any(axis=1))
    shares = _shares(on_support[rows], prescribes, constrained[rows], comm)
    totals = comm.allreduce(np.einsum("nkc,nc->kc", shares, values[rows]), op=MPI.SUM)
    return {name: totals[k] for k, name in enumerate(body.supports)}


def _nodal_residual(u: fem.Function, body: ElasticBody, load_factor: float) -> np.ndarray:
    """r = a(u, .) - l(.) assembled without boundary conditions at the owned nodes (owned nodes, 3; N)."""
    V = u.function_space
    v = ufl.TestFunction(V)
    internal, update = internal_force_form(u, v, body)
    update()
    residual_form = internal - load_form(V.mesh, v, body, load_factor, u)
    residual = fem.assemble_vector(fem.form(residual_form))
    residual.scatter_reverse(la.InsertMode.add)
    n_owned = V.dofmap.index_map.size_local
    return residual.array[: 3 * n_owned].reshape(n_owned, 3).copy()


def internal_force_form(u: fem.Function, v: ufl.core.expr.Expr, body: ElasticBody
                        ) -> tuple[ufl.Form, typing.Callable[[], None]]:
    """The internal virtual work a(u, v) of ``body`` (small strain, hyperelastic, or with the
    nodal pressure of :mod:`contactqvi.nodal_pressure`) and what to call before each assembly
    (the nodal pressure's update; nothing otherwise)."""
    mu, lmbda = lame_parameters(body.young, body.poisson)
    if body.nodal is not None:
        internal, averaged = internal_work(u, v, body.material, mu, lmbda, body.nodal)
        return internal, averaged.update
    if body.material is None:
        return ufl.inner(stress(u, mu, lmbda), strain(v)) * ufl.dx, lambda: None
    dx = body.material.dx(displacement_degree(u.function_space))
    return ufl.inner(body.material.first_piola(u, mu, lmbda), ufl.grad(v)) * dx, lambda: None


def _support_nodes(V: fem.FunctionSpace, body: ElasticBody) -> np.ndarray:
    """(owned nodes, supports) mask: the owned nodes of each of ``body.supports``. Collective."""
    msh = V.mesh
    fdim = msh.topology.dim - 1
    msh.topology.create_connectivity(fdim, msh.topology.dim)
    n_owned = V.dofmap.index_map.size_local
    on_support = np.zeros((n_owned, len(body.supports)), dtype=bool)
    for k, name in enumerate(body.supports):
        blk = fem.locate_dofs_topological(V, fdim, boundary_facets(body.facet_tags, name))
        on_support[blk[blk < n_owned], k] = True
    return on_support


def _owned_components(dofs_loc: np.ndarray, n_owned: int) -> np.ndarray:
    """(owned nodes, 3) mask of the components among ``dofs_loc`` (local unrolled indices)."""
    constrained = np.zeros(3 * n_owned, dtype=bool)
    constrained[dofs_loc[dofs_loc < 3 * n_owned]] = True
    return constrained.reshape(n_owned, 3)


def _prescribed_components(body: ElasticBody, on_support: np.ndarray, constrained: np.ndarray | None,
                           comm: MPI.Comm) -> np.ndarray:
    """(supports, 3) mask of the components each support prescribes: ``body.prescribed``, else
    those ``constrained`` at every one of its nodes (on all ranks; all three if None). Collective."""
    prescribes = np.ones((len(body.supports), 3), dtype=bool)
    if constrained is not None:
        free_nodes = comm.allreduce(on_support.T.astype(np.int64) @ (~constrained).astype(np.int64), op=MPI.SUM)
        sizes = comm.allreduce(on_support.sum(axis=0), op=MPI.SUM)
        prescribes = (free_nodes == 0) & (sizes > 0)[:, None]
    for k, name in enumerate(body.supports):
        if name in body.prescribed:
            components = list(body.prescribed[name])
            require(set(components) <= {0, 1, 2}, f"prescribed.{name}",
                    f"components must be 0, 1 or 2, got {components!r}")
            prescribes[k] = np.isin(np.arange(3), components)
    return prescribes


def _shares(on_support: np.ndarray, prescribes: np.ndarray, constrained: np.ndarray, comm: MPI.Comm) -> np.ndarray:
    """(nodes, supports, 3): each support's share of each constrained component of the
    nodes, 1 / (number of the node's supports that prescribe it) or 0. Collective."""
    claims = on_support[:, :, None] & prescribes[None] & constrained[:, None, :]
    claimants = claims.sum(axis=1)
    unclaimed = comm.allreduce(int(np.count_nonzero(constrained & (claimants == 0))), op=MPI.SUM)
    require(unclaimed == 0, "prescribed", f"{unclaimed} constrained components of support nodes are prescribed "
            "by no support")
    return claims / np.maximum(claimants, 1)[:, None, :]


def applied_force(msh: dmesh.Mesh, body: ElasticBody, load_factor: float = 1.0,
                  u: fem.Function | None = None) -> np.ndarray:
    """Resultant (N) of the tractions, pressures and the body force at ``load_factor`` (a
    hyperelastic body's pressures on the surface deformed by ``u``). Collective."""
    total = np.zeros(3)
    for i in range(3):
        direction = fem.Constant(msh, np.eye(3)[i].astype(PETSc.ScalarType))
        value = fem.assemble_scalar(fem.form(load_form(msh, direction, body, load_factor, u)))
        total[i] = msh.comm.allreduce(value, op=MPI.SUM)
    return total
