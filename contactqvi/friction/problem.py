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
no multiplier: y = 0 there.
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

from contactqvi.meshes import tag_of
from contactqvi.parameters import require, require_positive

__all__ = [
    "ACTIVE_MINUS",
    "ACTIVE_PLUS",
    "INACTIVE",
    "FrictionProblem",
    "boundary_states",
    "complementarity_residual",
]

LoadFunction = typing.Callable[[ufl.SpatialCoordinate], ufl.core.expr.Expr]

#: Nodal state codes of the sets of (3.3)/(PDAS step 2).
INACTIVE, ACTIVE_MINUS, ACTIVE_PLUS = 0, -1, 1


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


class FrictionProblem:
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
        require_positive("g", g)
        require(isinstance(mu, (int, float)) and np.isfinite(mu), "mu", f"must be a finite number, got {mu!r}")
        if dirichlet_boundaries:
            require(mu >= 0, "mu", f"must be >= 0 (coercivity of a), got {mu!r}")
        else:
            require(
                mu > 0, "mu", f"must be > 0 when Gamma_0 is empty, else a(y, y) is not coercive on H^1; got {mu!r}"
            )
        require(len(friction_boundaries) > 0, "friction_boundaries", "Gamma_f must not be empty")
        overlap = set(friction_boundaries) & set(dirichlet_boundaries)
        require(not overlap, "friction_boundaries", f"boundaries {sorted(overlap)} are both Gamma_f and Gamma_0")

        self.mesh, self.facet_tags = msh, facet_tags
        self.mu, self.g = float(mu), float(g)
        self.comm: MPI.Comm = msh.comm
        self.V = fem.functionspace(msh, ("Lagrange", 1))
        V = self.V
        fdim = msh.topology.dim - 1
        msh.topology.create_connectivity(fdim, msh.topology.dim)

        u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
        x = ufl.SpatialCoordinate(msh)
        self.load_expression = load(x)
        dx_load = ufl.dx(metadata={"quadrature_degree": quadrature_degree})
        friction_ids = tuple(tag_of(facet_tags, name) for name in friction_boundaries)
        ds = ufl.Measure("ds", domain=msh, subdomain_data=facet_tags)
        mu_c = fem.Constant(msh, PETSc.ScalarType(self.mu))
        self.a_form = fem.form(ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx + mu_c * u * v * ufl.dx)
        self.L_form = fem.form(self.load_expression * v * dx_load)
        self.boundary_mass_form = fem.form(v * ds(friction_ids))

        dirichlet_facets = np.unique(
            np.concatenate(
                [facet_tags.find(tag_of(facet_tags, name)) for name in dirichlet_boundaries]
                + [np.zeros(0, dtype=np.int32)]
            )
        ).astype(np.int32)
        dirichlet_dofs = fem.locate_dofs_topological(V, fdim, dirichlet_facets)
        self.bcs = [fem.dirichletbc(PETSc.ScalarType(0.0), dirichlet_dofs, V)] if dirichlet_boundaries else []
        n_owned = V.dofmap.index_map.size_local
        self._dirichlet_owned = dirichlet_dofs[dirichlet_dofs < n_owned]

        # K with identity rows/columns on Gamma_0, F with zero entries there.
        self.K = dolfinx.fem.petsc.assemble_matrix(self.a_form, bcs=self.bcs)
        self.K.assemble()
        self.F = dolfinx.fem.petsc.assemble_vector(self.L_form)
        dolfinx.fem.petsc.apply_lifting(self.F, [self.a_form], bcs=[self.bcs])
        self.F.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        dolfinx.fem.petsc.set_bc(self.F, self.bcs)

        # Lumped boundary mass: row sums of the Gamma_f mass matrix, m_i = int phi_i ds.
        mass = dolfinx.fem.petsc.assemble_vector(self.boundary_mass_form)
        mass.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        friction_facets = np.unique(
            np.concatenate([facet_tags.find(i) for i in friction_ids] + [np.zeros(0, dtype=np.int32)])
        ).astype(np.int32)
        candidates = fem.locate_dofs_topological(V, fdim, friction_facets)
        candidates = candidates[candidates < n_owned]
        candidates = np.setdiff1d(candidates, dirichlet_dofs)
        m = mass.array_r[candidates]
        #: Owned friction nodes (local dof indices, sorted), the node set of Gamma_f.
        self.boundary_dofs: np.ndarray = candidates[m > 0.0].astype(np.int32)
        #: Lumped boundary mass m_i at the owned friction nodes.
        self.boundary_mass: np.ndarray = mass.array_r[self.boundary_dofs].copy()
        mass.destroy()
        self.n_boundary = self.comm.allreduce(len(self.boundary_dofs), op=MPI.SUM)
        require(self.n_boundary > 0, "friction_boundaries", "Gamma_f contains no free node")

    # --- nodal boundary vectors -------------------------------------------------
    def create_boundary_vector(self) -> PETSc.Vec:
        """A zero PETSc Vec with one entry per owned friction node (lambda, xi, ...)."""
        vec = PETSc.Vec().createMPI((len(self.boundary_dofs), PETSc.DECIDE), comm=self.comm)
        vec.set(0.0)
        return vec

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

    # --- equations ---------------------------------------------------------------
    def multiplier_from_state(self, y: PETSc.Vec, work: PETSc.Vec) -> np.ndarray:
        """lambda = (F - K y)_i / m_i at the friction nodes, i.e. (3.2a) solved for lambda.

        This is the discrete -dy/dn on Gamma_f; it is evaluated from the
        residual instead of lambda_hat + gamma tau y so that it stays accurate
        for gamma up to 1e16 (no cancellation of gamma * O(1/gamma)).
        """
        self.K.mult(y, work)
        return (self.F.array_r[self.boundary_dofs] - work.array_r[self.boundary_dofs]) / self.boundary_mass

    def state_residual(self, y: PETSc.Vec, lam: np.ndarray, work: PETSc.Vec) -> float:
        """Max-norm of K y + M lambda - F over all free dofs, (3.2a) (global)."""
        self.K.mult(y, work)
        work.axpy(-1.0, self.F)
        values = work.array
        values[self.boundary_dofs] += self.boundary_mass * lam
        values[self._dirichlet_owned] = 0.0
        return float(work.norm(PETSc.NormType.NORM_INFINITY))

    def energy_norm(self, y: PETSc.Vec) -> float:
        """|||y||| = a(y, y)^(1/2) for y vanishing on Gamma_0 (Sect. 6.1)."""
        work = self.K.createVecLeft()
        self.K.mult(y, work)
        value = y.dot(work)
        work.destroy()
        return float(np.sqrt(max(value, 0.0)))
