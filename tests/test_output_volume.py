"""Volume results: stress and von Mises against a hand computation, reactions, global equilibrium."""

from __future__ import annotations

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import pytest

from dolfinx import fem

from contactqvi import meshes
from contactqvi.contact import build_contact_problem
from contactqvi.contact.load_path import LoadStep, contact_resultants, solve_load_path
from contactqvi.elasticity import elasticity_forms
from contactqvi.laws import Coulomb
from contactqvi.linalg import assemble_system, create_ksp, preset
from contactqvi.postprocess import ElasticBody, applied_force, reaction_forces, stress_fields, von_mises
from contactqvi.problems import coulomb as data

YOUNG, POISSON, SIGMA = 70e9, 0.334, -2.5e8  # compression: von Mises = |sigma_xx|
ROLLERS = {"dirichlet": 0, "front": 1, "contact": 2}  # boundary -> the component held


@pytest.mark.one_rank(reason="the von Mises formula on numpy arrays")
def test_von_mises_formula():
    assert von_mises(np.diag([3.0, 0.0, 0.0])) == pytest.approx(3.0)
    assert von_mises(5.0 * np.eye(3)) == pytest.approx(0.0, abs=1e-12)  # hydrostatic
    shear = np.zeros((3, 3))
    shear[0, 1] = shear[1, 0] = 2.0
    assert von_mises(shear) == pytest.approx(2.0 * np.sqrt(3.0))


def test_uniaxial_stress_and_reactions():
    """Box (0,2)x(0,1)x(0,1) on rollers, traction (sigma, 0, 0) on x1 = 2.

    By hand: sigma = sigma e1 e1 everywhere (u linear, exact in Q1), von Mises =
    |sigma|, the roller x1 = 0 pushes with -sigma * 1 m^2 in x1 and the other
    rollers carry nothing.
    """
    comm = MPI.COMM_WORLD
    msh, tags = meshes.create_contact_body(comm, 1, lambda x, y: np.zeros_like(x))
    V = fem.functionspace(msh, ("Lagrange", 1, (3,)))
    tractions = {"right": (SIGMA, 0.0, 0.0)}
    a, L = elasticity_forms(V, YOUNG, POISSON, tags, tractions)
    fdim = msh.topology.dim - 1
    msh.topology.create_connectivity(fdim, fdim + 1)
    bcs = [
        fem.dirichletbc(PETSc.ScalarType(0.0), fem.locate_dofs_topological(V.sub(i), fdim, meshes.boundary_facets(tags, name)), V.sub(i))
        for name, i in ROLLERS.items()
    ]
    u = _solve(V, a, L, bcs)

    stress, equivalent = stress_fields(u, YOUNG, POISSON)
    n_cells = msh.topology.index_map(3).size_local
    expected = np.zeros((3, 3))
    expected[0, 0] = SIGMA
    sigma = stress.x.array.reshape(-1, 3, 3)[:n_cells]
    assert np.allclose(sigma, expected, rtol=0, atol=1e-8 * abs(SIGMA))
    assert np.allclose(equivalent.x.array[:n_cells], abs(SIGMA), rtol=1e-10)
    assert np.allclose(stress.x.array.reshape(-1, 3, 3), expected, rtol=0, atol=1e-8 * abs(SIGMA))  # ghosts too
    assert stress.name == "stress" and equivalent.name == "von_mises"

    # each roller holds its own component (without it every support would hold all three, and
    # the edges' reactions would be shared among the faces meeting there)
    body = ElasticBody(YOUNG, POISSON, tags, supports=tuple(ROLLERS), tractions=tractions,
                       prescribed={name: (i,) for name, i in ROLLERS.items()})
    reactions = reaction_forces(u, body)
    assert list(reactions) == list(ROLLERS)
    assert np.allclose(reactions["dirichlet"], [-SIGMA, 0.0, 0.0], rtol=0, atol=1e-8 * abs(SIGMA))
    for name in ("front", "contact"):
        assert np.allclose(reactions[name], 0.0, rtol=0, atol=1e-8 * abs(SIGMA))
    dofs = np.concatenate([bc.dof_indices()[0] for bc in bcs])  # only the held components
    for name, reaction in reaction_forces(u, body, dirichlet_dofs_loc=dofs).items():
        assert np.allclose(reaction, reactions[name], rtol=0, atol=1e-8 * abs(SIGMA))
    assert np.allclose(applied_force(msh, body), [SIGMA, 0.0, 0.0], rtol=1e-12, atol=0)
    assert np.allclose(applied_force(msh, body, load_factor=0.5), [0.5 * SIGMA, 0.0, 0.0], rtol=1e-12, atol=0)


def _solve(V: fem.FunctionSpace, a: fem.Form, L: fem.Form, bcs: list[fem.DirichletBC]) -> fem.Function:
    """Linear solve by LU (MUMPS)."""
    A, b = assemble_system(a, L, bcs)
    ksp = create_ksp(A.getComm(), "test_volume_", preset("lu"), A=A)
    u = fem.Function(V)
    ksp.solve(b, u.x.petsc_vec)
    u.x.scatter_forward()
    for obj in (ksp, A, b):
        obj.destroy()
    return u


@pytest.mark.parametrize("lev, case", [(2, "d1/L1"), (3, "d3/L2")])
def test_global_equilibrium(lev, case):
    """Reactions + contact force + applied loads = 0 (relative 1e-8) on a converged Coulomb solve."""
    geometry, load = case.split("/")
    msh, tags = meshes.create_contact_body(MPI.COMM_WORLD, lev, data.gap_function(geometry))
    problem = build_contact_problem(msh, tags, data.YOUNG, data.POISSON, data.tractions(load), Coulomb(data.FRICTION))
    u = problem.A.createVecRight()
    (result,) = solve_load_path(problem, [LoadStep()], u, {"pc": "lu"}, prefix="equilibrium_")
    assert result.converged
    displacement = problem.physical_displacement(u, fem.Function(problem.V))
    body = ElasticBody(data.YOUNG, data.POISSON, tags, supports=("dirichlet",), tractions=data.tractions(load))
    reaction = reaction_forces(displacement, body)["dirichlet"]
    contact = np.asarray(contact_resultants(problem, result)["contact_force"])
    applied = applied_force(msh, body)
    scale = max(np.linalg.norm(applied), np.linalg.norm(contact), np.linalg.norm(reaction))
    assert np.linalg.norm(contact) > 0.1 * scale and np.linalg.norm(reaction) > 0.1 * scale
    assert np.linalg.norm(reaction + contact + applied) <= 1e-8 * scale
    problem.destroy()
    u.destroy()
