"""Small-strain isotropic linear elasticity in UFL.

Units are the caller's; the demos use SI (Pa, m, N).
"""

from __future__ import annotations

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import ufl

from dolfinx import fem, la
from dolfinx import mesh as dmesh

from contactqvi.meshes import tag_of
from contactqvi.parameters import require, require_positive

__all__ = [
    "body_force_form",
    "body_forces",
    "body_materials",
    "cellwise",
    "displacement_degree",
    "lame_parameters",
    "orthonormalize",
    "strain",
    "stress",
    "elasticity_forms",
    "pressure_form",
    "rigid_motions",
    "rigid_motions_nullspace",
]


Modulus = float | fem.Function

#: A volume force density (N/m^3): one vector for all cells, or one per body (cell group name).
BodyForce = tuple[float, ...] | dict[str, tuple[float, ...]]


def lame_parameters(young: Modulus, poisson: Modulus) -> tuple[Modulus, Modulus]:
    """Lamé parameters (mu, lambda) from Young's modulus E and Poisson's ratio nu.

    Numbers give numbers; cell-wise functions (:func:`body_materials`, checked there)
    give UFL expressions.

    Raises:
        ParameterError: if E <= 0 or nu is outside (-1, 0.5).
    """
    if not isinstance(young, fem.Function):
        require_positive("young", young)
    if not isinstance(poisson, fem.Function):
        require(-1.0 < poisson < 0.5, "poisson", f"must lie in (-1, 0.5), got {poisson!r}")
    mu = young / (2.0 * (1.0 + poisson))
    lmbda = young * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson))
    return mu, lmbda


def body_materials(
    msh: dmesh.Mesh, cell_tags: dmesh.MeshTags, materials: dict[str, tuple[float, float]]
) -> tuple[fem.Function, fem.Function]:
    """Young's modulus and Poisson's ratio of several bodies as cell-wise (DG0) functions.

    Args:
        msh: mesh of all bodies.
        cell_tags: named cell groups (``cell_tags.names``), one per body.
        materials: body name -> (E (Pa), nu); every body of the mesh needs one.

    Returns:
        ``(young, poisson)``, named ``young`` and ``poisson``.
    """
    W = fem.functionspace(msh, ("DG", 0))
    young, poisson = fem.Function(W, name="young"), fem.Function(W, name="poisson")
    young.x.array[:] = np.nan
    for name, (E, nu) in materials.items():
        require(name in cell_tags.names, f"bodies.{name}",
                f"no cell group {name!r} in the mesh; it has: {', '.join(sorted(cell_tags.names))}")
        lame_parameters(E, nu)  # checks E and nu
        cells = cell_tags.find(cell_tags.names[name])
        young.x.array[cells], poisson.x.array[cells] = E, nu
    young.x.scatter_forward()
    poisson.x.scatter_forward()
    n_cells = msh.topology.index_map(msh.topology.dim).size_local
    missing = msh.comm.allreduce(int(np.count_nonzero(np.isnan(young.x.array[:n_cells]))))
    require(missing == 0, "bodies", f"{missing} cells belong to no body (every cell needs a material)")
    return young, poisson


def cellwise(msh: dmesh.Mesh, cell_tags: dmesh.MeshTags, values: dict[str, float], name: str) -> fem.Function:
    """A DG0 function with the value ``values[body]`` on each body's cells (a density, kg/m^3)."""
    field = fem.Function(fem.functionspace(msh, ("DG", 0)), name=name)
    for body, value in values.items():
        require(body in cell_tags.names, f"bodies.{body}", f"no cell group {body!r} in the mesh")
        field.x.array[cell_tags.find(cell_tags.names[body])] = value
    field.x.scatter_forward()
    return field


def strain(u: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    """Small-strain tensor sym(grad u)."""
    return ufl.sym(ufl.grad(u))


def stress(u: ufl.core.expr.Expr, mu: float, lmbda: float) -> ufl.core.expr.Expr:
    """Cauchy stress 2 mu eps(u) + lambda tr(eps(u)) I of isotropic Hooke's law."""
    eps = strain(u)
    return 2.0 * mu * eps + lmbda * ufl.tr(eps) * ufl.Identity(len(u))


def elasticity_forms(
    V: fem.FunctionSpace,
    young: Modulus,
    poisson: Modulus,
    facet_tags: dmesh.MeshTags,
    tractions: dict[str, tuple[float, ...]],
    body_force: BodyForce | None = None,
    cell_tags: dmesh.MeshTags | None = None,
    pressures: dict[str, float] | None = None,
    nodal: fem.Function | None = None,
) -> tuple[fem.Form, fem.Form]:
    """Compiled bilinear form a(u, v) = (sigma(u), eps(v)) and load l(v).

    l(v) = (f, v) + sum over named boundaries of (t, v)_boundary - (p N, v)_boundary.

    Args:
        V: vector Lagrange space.
        young, poisson: E and nu (numbers or DG0 functions, :func:`body_materials`).
        facet_tags: facet tags with boundary names (see :mod:`contactqvi.meshes`).
        tractions: surface traction vector per boundary name.
        body_force: volume force density f (N/m^3), one vector or one per body
            ``{body: f}`` (:func:`body_forces`), or None.
        cell_tags: named cell groups, one per body (needed for a force per body).
        pressures: pressure p (Pa, > 0 pushes into the body) per boundary name: the traction
            -p N of the reference normal here (:func:`pressure_form`).
        nodal: the indicator chi of the cells whose volume change is averaged at the nodes
            (:mod:`contactqvi.nodal_pressure`): a then holds lambda (1 - chi) only, the rest is
            lambda B^T M_L^-1 B. None: every cell takes lambda.
    """
    mu, lmbda = lame_parameters(young, poisson)
    if nodal is not None:
        lmbda = lmbda * (1 - nodal)
    msh = V.mesh
    gdim = msh.geometry.dim
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    a = ufl.inner(stress(u, mu, lmbda), strain(v)) * ufl.dx
    ds = ufl.Measure("ds", domain=msh, subdomain_data=facet_tags)
    zero = fem.Constant(msh, np.zeros(gdim, dtype=PETSc.ScalarType))
    L = ufl.inner(zero, v) * ufl.dx
    if body_force is not None:
        L += body_force_form(msh, v, body_force, cell_tags)
    for name, traction in tractions.items():
        L += ufl.inner(_vector_constant(msh, traction, f"traction[{name}]"), v) * ds(tag_of(facet_tags, name))
    if pressures:
        L += pressure_form(msh, v, facet_tags, pressures)
    return fem.form(a), fem.form(L)


def pressure_form(msh: dmesh.Mesh, v: ufl.core.expr.Expr, facet_tags: dmesh.MeshTags, pressures: dict[str, float],
                  u: ufl.core.expr.Expr | None = None) -> ufl.Form:
    """The load of pressures p (Pa) on named boundaries, UFL (not compiled): on the reference
    surface -(p N, v) (small strain), or with the displacement ``u`` the follower load
    -(p J F^-T N, v) of the pressure on the deformed surface (Nanson's formula: n da =
    J F^-T N dA), F = I + grad u."""
    ds = ufl.Measure("ds", domain=msh, subdomain_data=facet_tags)
    N = ufl.FacetNormal(msh)
    if u is not None:
        F = ufl.Identity(len(N)) + ufl.grad(u)
        N = ufl.det(F) * ufl.inv(F).T * N
    form = None
    for name, value in pressures.items():
        p = fem.Constant(msh, PETSc.ScalarType(value))
        term = -p * ufl.inner(N, v) * ds(tag_of(facet_tags, name))
        form = term if form is None else form + term
    return form


def body_force_form(
    msh: dmesh.Mesh, v: ufl.core.expr.Expr, body_force: BodyForce, cell_tags: dmesh.MeshTags | None = None,
) -> ufl.Form:
    """The body-force term (f, v) of the load over the mesh, UFL (not compiled).

    One vector f (N/m^3) is a constant; a dict ``{body: f}`` becomes the cell-wise (DG0)
    field of :func:`body_forces`, so the term is one integral over all cells whatever the
    number of bodies (DOLFINx 0.9 compiles a form only if all its cell integrals share
    their subdomain data, which integrals ``dx(tag)`` beside the plain ``dx`` of the
    stiffness and tractions would not).
    """
    if not isinstance(body_force, dict):
        return ufl.inner(_vector_constant(msh, body_force, "body_force"), v) * ufl.dx
    require(cell_tags is not None, "body_force", "a force per body needs the bodies' cell groups (cell_tags)")
    return ufl.inner(body_forces(msh, cell_tags, body_force), v) * ufl.dx


def body_forces(msh: dmesh.Mesh, cell_tags: dmesh.MeshTags, forces: dict[str, tuple[float, ...]]) -> fem.Function:
    """Volume force densities of several bodies as one cell-wise (DG0) vector function.

    Args:
        msh: mesh of all bodies.
        cell_tags: named cell groups (``cell_tags.names``), one per body.
        forces: body name -> f (N/m^3); bodies not listed carry none.

    Returns:
        The field named ``body_force``: f of its body in each cell, 0 in the others.

    Raises:
        ParameterError: a body not in ``cell_tags`` or a force of the wrong length or not
            finite (``body_force[name]``).
    """
    gdim = msh.geometry.dim
    f = fem.Function(fem.functionspace(msh, ("DG", 0, (gdim,))), name="body_force")
    names = getattr(cell_tags, "names", {})
    values = f.x.array.reshape(-1, gdim)
    for name, force in forces.items():
        require(name in names, f"body_force[{name}]",
                f"no cell group {name!r} in the mesh; it has: {', '.join(sorted(names)) or 'none'}")
        values[cell_tags.find(names[name])] = _checked_vector(msh, force, f"body_force[{name}]")
    f.x.scatter_forward()
    return f


def _checked_vector(msh: dmesh.Mesh, value: tuple[float, ...], name: str) -> np.ndarray:
    """``value`` as an array of the mesh's dimension; wrong lengths and non-finite entries raise."""
    array = np.asarray(value, dtype=PETSc.ScalarType)
    require(array.shape == (msh.geometry.dim,), name, f"must have {msh.geometry.dim} components, got {value!r}")
    require(bool(np.all(np.isfinite(array))), name, f"must be finite, got {value!r}")
    return array


def _vector_constant(msh: dmesh.Mesh, value: tuple[float, ...], name: str) -> fem.Constant:
    return fem.Constant(msh, _checked_vector(msh, value, name))


def displacement_degree(V: fem.FunctionSpace) -> int:
    """The polynomial degree of the displacements of a Lagrange space V: 1 (linear) or 2 (quadratic)."""
    return V.ufl_element().basix_element.degree


def rigid_motions(x: np.ndarray) -> np.ndarray:
    """(..., gdim, modes) the rigid motions at points x (..., gdim): the gdim translations, then the
    rotations (three in 3D, one in 2D), by component."""
    gdim = x.shape[-1]
    modes = np.zeros((*x.shape, gdim + (3 if gdim == 3 else 1)))
    for i in range(gdim):
        modes[..., i, i] = 1.0
    if gdim == 3:
        modes[..., 0, 3], modes[..., 1, 3] = -x[..., 1], x[..., 0]
        modes[..., 0, 4], modes[..., 2, 4] = x[..., 2], -x[..., 0]
        modes[..., 2, 5], modes[..., 1, 5] = x[..., 1], -x[..., 2]
    else:
        modes[..., 0, 2], modes[..., 1, 2] = -x[..., 1], x[..., 0]
    return modes


def rigid_motions_nullspace(V: fem.FunctionSpace, node_body: np.ndarray | None = None) -> PETSc.NullSpace:
    """Orthonormal rigid-body modes (3 translations, 3 rotations in 3D; 2 + 1 in 2D).

    The near-nullspace for smoothed-aggregation AMG on elasticity operators. With
    ``node_body`` (body index of each local node, bodies sharing no nodes) each body
    moves on its own: six modes per body.
    """
    msh = V.mesh
    gdim = msh.geometry.dim
    index_map, bs = V.dofmap.index_map, V.dofmap.index_map_bs
    n_owned = index_map.size_local
    modes = rigid_motions(V.tabulate_dof_coordinates()[:n_owned, :gdim])
    basis = [la.vector(index_map, bs=bs, dtype=PETSc.ScalarType) for _ in range(modes.shape[-1])]
    values = [b.array[: n_owned * bs].reshape(-1, bs) for b in basis]
    for i, b in enumerate(values):
        b[:] = modes[..., i]
    if node_body is not None:
        owned_body = node_body[:n_owned]
        bodies = V.mesh.comm.allreduce(int(owned_body.max(initial=-1)), op=MPI.MAX) + 1
        split = [la.vector(index_map, bs=bs, dtype=PETSc.ScalarType) for _ in range(bodies * len(basis))]
        for k in range(bodies):
            for i, b in enumerate(values):
                split[k * len(basis) + i].array[: n_owned * bs].reshape(-1, bs)[owned_body == k] = b[owned_body == k]
        basis = split
    la.orthonormalize(basis)
    vectors = []
    for b in basis:  # PETSc-owned copies: the null space keeps references to them
        vec = la.create_petsc_vector(index_map, bs)
        vec.array[:] = b.array[: n_owned * bs]
        vectors.append(vec)
    nullspace = PETSc.NullSpace().create(vectors=vectors, comm=msh.comm)
    for vec in vectors:  # our handles; left to the garbage collector they outlive the null space in parallel
        vec.destroy()
    return nullspace


def orthonormalize(vectors: list[PETSc.Vec]) -> None:
    """Orthonormalise PETSc vectors in place (modified Gram-Schmidt, twice; collective)."""
    for _ in range(2):
        for i, v in enumerate(vectors):
            for w in vectors[:i]:
                v.axpy(-v.dot(w), w)
            v.normalize()
