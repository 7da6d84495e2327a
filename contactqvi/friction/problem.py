"""Discrete simplified friction problem (P) of seed 002 with a lumped boundary mass.

Seed 002 (Stadler, SIAM J. Optim. 15 (2004)) minimises

    J(y) = 1/2 a(y, y) - (f, y) + g int_{Gamma_f} |tau y|,   y = 0 on Gamma_0,

with a(y, z) = (grad y, grad z) + mu (y, z). We discretise y with continuous
Q1 (or P1) finite elements and the multiplier lambda (and xi) of (2.4)/(3.2) by
their *nodal values* on the friction boundary, with the lumped boundary mass
m_i = int_{Gamma_f} phi_i ds. The discrete optimality system is

    K y + M lambda = F,                         (3.2a)
    y_i + (lambda_hat_i - lambda_i) / gamma = xi_i,   (3.2b)
    xi_i = max(0, xi_i + sigma (lambda_i - g)) + min(0, xi_i + sigma (lambda_i + g)),  (3.2c)

at every friction node i, with M = diag(m). Because M is diagonal, (3.2c) and the
sets A-, A+, I of (3.3) are nodewise, and ||v||_{L2(Gamma_f)} is evaluated
exactly as sqrt(sum_i m_i v_i^2) for nodal boundary vectors.

Nodes on Gamma_f that are also Dirichlet nodes (the corners of Example 1) carry
no multiplier: y = 0 there. The paper's finite-difference scheme has the same form
(:class:`contactqvi.friction.finite_differences.PaperFiniteDifferences` replaces K, F
and m), so every solver runs on both.
"""

from __future__ import annotations

import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import ufl

import dolfinx.fem.petsc
from dolfinx import fem
from dolfinx import mesh as dmesh

from contactqvi.lifetime import PETScOwner
from contactqvi.meshes import tag_of
from contactqvi.parameters import require, require_positive

__all__ = [
    "ACTIVE_MINUS",
    "ACTIVE_PLUS",
    "INACTIVE",
    "FrictionData",
    "FrictionProblem",
    "boundary_states",
    "complementarity_residual",
]

LoadFunction = typing.Callable[[ufl.SpatialCoordinate], ufl.core.expr.Expr]

#: Nodal state codes of the sets of (3.3)/(PDAS step 2).
INACTIVE, ACTIVE_MINUS, ACTIVE_PLUS = 0, -1, 1


class FrictionData(typing.Protocol):
    """The data of (P) on a mesh with named boundaries, as :func:`contactqvi.friction.build.create_problem`
    reads them (e.g. :func:`contactqvi.problems.stadler.stadler_example`).

    Attributes:
        friction_boundaries, dirichlet_boundaries: the boundaries forming Gamma_f and Gamma_0.
        load: f as a function of the spatial coordinate.
        g, mu: the friction bound and the coefficient of (y, z) in a(y, z).
        quadrature_degree: of the rule for (f, v).
    """

    friction_boundaries: typing.Sequence[str]
    dirichlet_boundaries: typing.Sequence[str]
    load: LoadFunction
    g: float
    mu: float
    quadrature_degree: int


def boundary_states(xi: np.ndarray, lam: np.ndarray, g: float, sigma: float) -> np.ndarray:
    """Active/inactive prediction of (PDAS) step 2 at every (owned) friction node.

    Returns an int8 array with -1 on A- = {xi + sigma (lambda + g) < 0}, +1 on
    A+ = {xi + sigma (lambda - g) > 0} and 0 on I (the rest).
    """
    states = np.zeros(xi.shape, dtype=np.int8)
    states[xi + sigma * (lam + g) < 0.0] = ACTIVE_MINUS
    states[xi + sigma * (lam - g) > 0.0] = ACTIVE_PLUS
    return states


def complementarity_residual(xi: np.ndarray, lam: np.ndarray, g: float, sigma: float) -> np.ndarray:
    """Nodal residual of (3.2c): xi - max(0, xi + sigma(lambda - g)) - min(0, xi + sigma(lambda + g))."""
    return xi - np.maximum(0.0, xi + sigma * (lam - g)) - np.minimum(0.0, xi + sigma * (lam + g))


class FrictionProblem(PETScOwner):
    """Forms, matrices and nodal boundary data of the discrete problem (P).

    The problem owns the stiffness matrix K of a(., .) (Dirichlet rows and
    columns on Gamma_0 replaced by the identity), the load vector F of (f, .),
    the lumped boundary mass of Gamma_f and the owned friction nodes. Solvers
    take a problem and never know which paper example it describes.

    Args:
        msh: the mesh (unit square in the paper).
        facet_tags: facet tags with ``names`` (see :mod:`contactqvi.meshes`).
        friction_boundaries: names of the boundaries forming Gamma_f.
        dirichlet_boundaries: names of the boundaries forming Gamma_0 (may be
            empty). Boundaries in neither list carry the natural condition
            grad y . n = 0.
        load: f as a function of the spatial coordinate (UFL expression).
        mu: the coefficient of (y, z) in a(., .), >= 0, and > 0 if Gamma_0 is empty.
        g: the friction bound, > 0.
        quadrature_degree: quadrature for the load (f may be discontinuous).
    """

    def __init__(
        self,
        msh: dmesh.Mesh,
        facet_tags: dmesh.MeshTags,
        friction_boundaries: typing.Sequence[str],
        dirichlet_boundaries: typing.Sequence[str],
        load: LoadFunction,
        mu: float,
        g: float,
        quadrature_degree: int = 4,
    ):
        _check_data(friction_boundaries, dirichlet_boundaries, mu, g)
        self.mesh, self.facet_tags = msh, facet_tags
        self.mu, self.g = float(mu), float(g)
        self.comm: MPI.Comm = msh.comm
        self.V = fem.functionspace(msh, ("Lagrange", 1))
        msh.topology.create_connectivity(msh.topology.dim - 1, msh.topology.dim)
        self.load_expression = load(ufl.SpatialCoordinate(msh))
        friction_ids = tuple(tag_of(facet_tags, name) for name in friction_boundaries)
        self._compile_forms(friction_ids, quadrature_degree)
        dirichlet_dofs = self._locate_dofs([tag_of(facet_tags, name) for name in dirichlet_boundaries])
        self.bcs = [fem.dirichletbc(PETSc.ScalarType(0.0), dirichlet_dofs, self.V)] if dirichlet_boundaries else []
        self._assemble_system()
        self._lump_boundary_mass(friction_ids, dirichlet_dofs)
        self._work = self.K.createVecLeft()

    def _compile_forms(self, friction_ids: tuple[int, ...], quadrature_degree: int) -> None:
        """a(y, z) = (grad y, grad z) + mu (y, z), (f, z) and the boundary mass int_{Gamma_f} z ds."""
        msh, V = self.mesh, self.V
        u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
        dx_load = ufl.dx(metadata={"quadrature_degree": quadrature_degree})
        ds = ufl.Measure("ds", domain=msh, subdomain_data=self.facet_tags)
        mu = fem.Constant(msh, PETSc.ScalarType(self.mu))
        self.a_form = fem.form(ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx + mu * u * v * ufl.dx)
        self.L_form = fem.form(self.load_expression * v * dx_load)
        self.boundary_mass_form = fem.form(v * ds(friction_ids))

    def _locate_dofs(self, tags: list[int]) -> np.ndarray:
        """Local dofs (owned and ghost) on the facets with the given tags."""
        facets = [self.facet_tags.find(tag) for tag in tags] + [np.zeros(0, dtype=np.int32)]
        facets_sorted = np.unique(np.concatenate(facets)).astype(np.int32)
        return fem.locate_dofs_topological(self.V, self.mesh.topology.dim - 1, facets_sorted)

    def _assemble_system(self) -> None:
        """K with identity rows/columns on Gamma_0, F with zero entries there."""
        self.K = dolfinx.fem.petsc.assemble_matrix(self.a_form, bcs=self.bcs)
        self.K.assemble()
        self.F = dolfinx.fem.petsc.assemble_vector(self.L_form)
        dolfinx.fem.petsc.apply_lifting(self.F, [self.a_form], bcs=[self.bcs])
        self.F.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        dolfinx.fem.petsc.set_bc(self.F, self.bcs)

    def _lump_boundary_mass(self, friction_ids: tuple[int, ...], dirichlet_dofs: np.ndarray) -> None:
        """Owned friction nodes and their lumped mass m_i = int_{Gamma_f} phi_i ds (row sums of the mass matrix)."""
        mass = dolfinx.fem.petsc.assemble_vector(self.boundary_mass_form)
        mass.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        candidates = self._locate_dofs(list(friction_ids))
        candidates = candidates[candidates < self.V.dofmap.index_map.size_local]
        candidates = np.setdiff1d(candidates, dirichlet_dofs)
        m = mass.array_r[candidates]
        #: Owned friction nodes (local dof indices, sorted), the node set of Gamma_f.
        self.boundary_dofs: np.ndarray = candidates[m > 0.0].astype(np.int32)
        #: Lumped boundary mass m_i at the owned friction nodes.
        self.boundary_mass: np.ndarray = mass.array_r[self.boundary_dofs].copy()
        mass.destroy()
        self.n_boundary = self.comm.allreduce(len(self.boundary_dofs), op=MPI.SUM)
        require(self.n_boundary > 0, "friction_boundaries", "Gamma_f contains no free node")

    def petsc_objects(self) -> list[typing.Any]:
        return [self.K, self.F, self._work]

    # --- nodal boundary vectors -------------------------------------------------
    def boundary_zeros(self) -> np.ndarray:
        """A zero nodal boundary vector: one entry per owned friction node (lambda, xi, ...)."""
        return np.zeros(len(self.boundary_dofs))

    def trace(self, y: PETSc.Vec) -> np.ndarray:
        """Nodal trace tau_f y at the owned friction nodes (a copy)."""
        return y.array_r[self.boundary_dofs].copy()

    def boundary_norm(self, values: np.ndarray) -> float:
        """||v||_{L2(Gamma_f)} of a nodal boundary vector with the lumped mass (global)."""
        local = float(np.dot(self.boundary_mass, values * values))
        return float(np.sqrt(self.comm.allreduce(local, op=MPI.SUM)))

    def count(self, mask: np.ndarray) -> int:
        """Global number of friction nodes where ``mask`` holds."""
        return int(self.comm.allreduce(int(np.count_nonzero(mask)), op=MPI.SUM))

    def max_abs(self, values: np.ndarray) -> float:
        """max |v| over all ranks of a nodal (or owned) vector, 0 if empty."""
        return float(self.comm.allreduce(float(np.abs(values).max(initial=0.0)), op=MPI.MAX))

    # --- equations ---------------------------------------------------------------
    def multiplier_from_state(self, y: PETSc.Vec) -> np.ndarray:
        """lambda = (F - K y)_i / m_i at the friction nodes, i.e. (3.2a) solved for lambda.

        This is the discrete -dy/dn on Gamma_f; it is evaluated from the
        residual instead of lambda_hat + gamma tau y so that it stays accurate
        for gamma up to 1e16 (no cancellation of gamma * O(1/gamma)).
        """
        self.K.mult(y, self._work)
        return (self.F.array_r[self.boundary_dofs] - self._work.array_r[self.boundary_dofs]) / self.boundary_mass

    def energy_norm(self, y: PETSc.Vec, reference: PETSc.Vec | None = None) -> float:
        """|||y - reference||| = a(y - reference, y - reference)^(1/2) for y vanishing on Gamma_0 (Sect. 6.1)."""
        difference = y.copy()
        if reference is not None:
            difference.axpy(-1.0, reference)
        self.K.mult(difference, self._work)
        value = difference.dot(self._work)
        difference.destroy()
        return float(np.sqrt(max(value, 0.0)))


def _check_data(
    friction_boundaries: typing.Sequence[str], dirichlet_boundaries: typing.Sequence[str], mu: float, g: float
) -> None:
    """The data of (P): g > 0, a(., .) coercive, Gamma_f not empty and disjoint from Gamma_0."""
    require_positive("g", g)
    require(isinstance(mu, (int, float)) and np.isfinite(mu), "mu", f"must be a finite number, got {mu!r}")
    if dirichlet_boundaries:
        require(mu >= 0, "mu", f"must be >= 0 (coercivity of a), got {mu!r}")
    else:
        require(mu > 0, "mu", f"must be > 0 when Gamma_0 is empty, else a(y, y) is not coercive on H^1; got {mu!r}")
    require(len(friction_boundaries) > 0, "friction_boundaries", "Gamma_f must not be empty")
    overlap = set(friction_boundaries) & set(dirichlet_boundaries)
    require(not overlap, "friction_boundaries", f"boundaries {sorted(overlap)} are both Gamma_f and Gamma_0")
