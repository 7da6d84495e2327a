"""Quadratic elements (10-node tetrahedra, P2 displacements; 27-node hexahedra, Q2) against rigid
obstacles (issue 43; between meshed bodies: tests/test_quadratic_mortar.py,
tests/test_quadratic_hexahedra.py).

The slave surface's displacement is taken in the modified basis of
:mod:`contactqvi.contact.quadratic` (u = S ũ, Ñ_v = N_v + alpha (N_e + N_e'), Ñ_e = (1 - 2 alpha) N_e):

* the change of variables u = S ũ: S^-1 inverts it, the weighted positions of a flat surface
  are its nodes', and every node has a positive contact area, int Ñ_i, summing to the surface's;
* a block on a frictionless plane with rollers on two sides, its top pressed down (linear
  elasticity: Hooke; neo-Hookean: the uniaxial closed form of docs/finite_strain.md, Sect. 6),
  is homogeneous: P2 holds it exactly, u to round-off, and the nodal contact pressure
  lambda_i / int Ñ_i is uniform (a lumped quadratic basis, int N_v = 0, cannot carry it: its
  vertices would take no force); so is Q2 on hexahedra, whose facets need no modified basis
  (int N_i > 0 at every node of a 9-node quadrilateral). On any number of ranks;
* the tangent of the transformed problem is the derivative of its residual, also in the rows
  of the rollers on the slave surface;
* bad input: an order other than 1 or 2, named ``mesh.order``.
"""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest
import ufl

from dolfinx import fem, la

from contactqvi.case import parse_case
from contactqvi.contact import LoadStep, build_contact_problem, solve_load_path
from contactqvi.contact.quadratic import ALPHA, modified_basis
from contactqvi.laws import Frictionless
from contactqvi.materials import NeoHookean
from contactqvi.meshes import boundary_facets, create_contact_body
from contactqvi.parameters import ParameterError
from contactqvi.records import Recorder
from contactqvi.problems.uniaxial import uniaxial_stress

YOUNG, POISSON = 10e6, 0.3  # Pa, -
#: The block's supports: rollers on x = 0 and y = 0, the top pressed down (m) at load 1.
ROLLERS = {"dirichlet": {0: 0.0}, "front": {1: 0.0}}


def _block(cell_type: str = "tetrahedron"):
    return create_contact_body(MPI.COMM_WORLD, 1, lambda x, y: np.zeros_like(x), length=1.0, width=1.0, height=1.0,
                               cell_type=cell_type)


def _largest(values: np.ndarray) -> float:
    return MPI.COMM_WORLD.allreduce(float(np.abs(values).max(initial=0.0)), op=MPI.MAX)


def _sum(values: np.ndarray) -> float:
    return MPI.COMM_WORLD.allreduce(float(np.sum(values)), op=MPI.SUM)


def test_the_modified_basis_is_inverted_and_has_positive_areas():
    """S^-1 x = x̃ with S x̃ = x to round-off; on the flat bottom of the block x̃ = x (no sagitta);
    int Ñ_i > 0 at every node, vertices and edges, summing to the area 1 m^2 (the lumped quadratic
    int N_v is 0 at the vertices)."""
    msh, tags = _block()
    V = fem.functionspace(msh, ("Lagrange", 2, (3,)))
    facets = boundary_facets(tags, "contact")
    constrained = np.zeros((V.dofmap.index_map.size_local + V.dofmap.index_map.num_ghosts, 3), dtype=bool)
    with modified_basis(V, facets, constrained) as basis:
        x = V.tabulate_dof_coordinates()
        moved = x + np.sin(3.0 * x)  # any vector field
        tilde = basis.positions(moved)
        owned = 3 * V.dofmap.index_map.size_local
        back, there = basis.S.createVecRight(), basis.S.createVecLeft()
        back.array[:] = tilde.ravel()[:owned]
        basis.S.mult(back, there)
        assert _largest(there.array_r - moved.ravel()[:owned]) <= 1e-14
        for vec in (back, there):
            vec.destroy()
        nodes = fem.locate_dofs_topological(V, 2, facets)
        assert _largest(basis.positions(x)[nodes] - x[nodes]) <= 1e-15
        Q = fem.functionspace(msh, ("Lagrange", 2))
        ds = ufl.ds(subdomain_data=tags, subdomain_id=tags.names["contact"])
        w = fem.assemble_vector(fem.form(ufl.TestFunction(Q) * ds))
        w.scatter_reverse(la.InsertMode.add)
        area = basis.areas(w.array)
        owned_nodes = nodes[nodes < V.dofmap.index_map.size_local]
        assert MPI.COMM_WORLD.allreduce(float(area[owned_nodes].min(initial=np.inf)), op=MPI.MIN) > 0.0
        assert _sum(area[owned_nodes]) == pytest.approx(1.0, rel=1e-13)
        assert _sum(basis.edges.size) > 0
        assert ALPHA == 0.2


def _compressed(material, compression: float, steps: int, cell_type: str = "tetrahedron") -> list[dict]:
    """The quadratic block of ``cell_type`` pressed by ``compression`` of its height in ``steps`` steps: per
    step the nodes, u, the nodal contact pressures and the result (exact Newton steps)."""
    msh, tags = _block(cell_type)
    rows = []
    with build_contact_problem(msh, tags, YOUNG, POISSON, {}, Frictionless(), clamped=(), contact="contact",
                               displacements={**ROLLERS, "top": {2: -compression}}, material=material,
                               degree=2) as problem:
        def record(index, step, u, result, state):
            x = problem.V.tabulate_dof_coordinates()[: problem.V.dofmap.index_map.size_local]
            rows.append({"load": step.load, "x": x, "u": state.displacement.x.array.reshape(-1, 3)[: len(x)].copy(),
                         "pressure": result.normal_force / problem.contact_area, "result": result,
                         "area": _sum(problem.contact_area)})

        u = problem.A.createVecRight()
        solve_load_path(problem, [LoadStep((k + 1) / steps) for k in range(steps)], u, {"pc": "lu"}, on_step=record,
                        from_rest=True)
        u.destroy()
    return rows


@pytest.mark.parametrize("cell_type", ["tetrahedron", "hexahedron"])
def test_linear_quadratic_block_is_hookes_law(cell_type):
    """Linear elasticity, 0.1 % compression: eps11 = eps22 = -nu eps33 at every node (edges, and the
    hexahedra's face centres, included) to 1e-10 of the strain, the nodal pressure E eps33 at every
    slave node to 1e-8, the contact areas summing to 1 m^2."""
    strain = 1e-3
    (row,) = _compressed(None, strain, 1, cell_type)
    assert row["result"].converged
    exact = row["x"] * np.array([POISSON * strain, POISSON * strain, -strain])
    assert _largest(row["u"] - exact) <= 1e-10 * strain
    assert _largest(row["pressure"] - YOUNG * strain) <= 1e-8 * YOUNG * strain
    assert row["area"] == pytest.approx(1.0, rel=1e-13)


@pytest.mark.parametrize("cell_type", ["tetrahedron", "hexahedron"])
def test_neo_hookean_quadratic_block_is_the_uniaxial_closed_form(cell_type):
    """Neo-Hookean, 30 % in ten steps: u to 1e-8 of the top's motion and the nodal pressure -P33
    to 1e-8 at every step; at most 8 Newton steps per step (measured 3 on tetrahedra, 2-3 on
    hexahedra; 10 % steps took 9-15: docs/quadratic.md)."""
    compression = 0.3
    for row in _compressed(NeoHookean(), compression, 10, cell_type):
        assert row["result"].converged, row["result"].status
        assert row["result"].iterations <= 8
        s = 1.0 - compression * row["load"]
        a, P33 = uniaxial_stress(s, YOUNG, POISSON)
        assert _largest(row["u"] - row["x"] * np.array([a - 1.0, a - 1.0, s - 1.0])) <= 1e-8 * (1.0 - s)
        assert _largest(row["pressure"] + P33) <= 1e-8 * abs(P33), row["load"]


def test_quadratic_tangent_is_the_derivative_of_the_residual():
    """T^T K_T T against central differences of T^T r_K(T w) (the residual's prescribed rows u_i - l_i
    included) at a displacement of 5 mm of the metre block: 1e-9 of the product. The rollers' rows
    on the slave surface must stay identities of the transformed problem (S_free); with the plain S
    they were 0.36 there and the Newton steps crept at alpha = 0.5."""
    msh, tags = _block()
    with build_contact_problem(msh, tags, YOUNG, POISSON, {}, Frictionless(), clamped=(), contact="contact",
                               displacements={**ROLLERS, "top": {2: -0.1}}, material=NeoHookean(),
                               degree=2) as problem:
        problem.set_step(0.5)
        prescribed = problem.hyperelastic.prescribed
        u = problem.A.createVecRight()
        u.array[:] = 5e-3 * np.sin(np.arange(u.getLocalSize()))
        u.array[prescribed] = problem.load.array_r[prescribed]
        direction = u.duplicate()
        direction.array[:] = np.cos(3.0 * np.arange(u.getLocalSize()))
        direction.array[prescribed] = 0.0
        product, difference, residual, trial = u.duplicate(), u.duplicate(), u.duplicate(), u.duplicate()
        problem.tangent(u)
        problem.A.mult(direction, product)
        difference.set(0.0)
        eps = 1e-6
        for sign in (1.0, -1.0):
            trial.waxpy(sign * eps, direction, u)
            problem.residual(trial, residual)
            difference.axpy(sign / (2.0 * eps), residual)
        difference.axpy(-1.0, product)
        assert difference.norm() <= 1e-9 * product.norm()
        for vec in (u, direction, product, difference, residual, trial):
            vec.destroy()


def test_an_order_other_than_one_or_two_is_refused():
    """An order other than 1 or 2 in a case file is a ParameterError named mesh.order."""
    case = {"mesh": {"box": {"lev": 1}, "order": 3}, "material": {"young": YOUNG, "poisson": POISSON},
            "boundary": {"clamped": ["dirichlet"]}, "contact": {"surface": "contact", "law": "frictionless"},
            "obstacle": {"type": "plane", "point": [0, 0, 0], "normal": [0, 0, 1]}}
    with pytest.raises(ParameterError, match=r"^mesh\.order: must be 1 \(linear elements\) or 2 \(quadratic\), "
                       r"got 3"):
        parse_case(case)


@pytest.mark.parametrize("degree, warned", [(1, ["volumetric_locking"]), (2, [])])
def test_the_locking_warning_is_for_linear_elements(degree, warned):
    """nu = 0.499 with the displacement formulation: linear tetrahedra are warned of volumetric locking,
    quadratic ones are not (they keep their contact area: docs/quadratic.md, Sect. 3)."""
    msh, tags = _block()
    with Recorder() as recorder, build_contact_problem(msh, tags, YOUNG, 0.499, {}, Frictionless(), clamped=(),
                                                       contact="contact", displacements=ROLLERS, degree=degree):
        pass
    assert [r["key"] for r in recorder.records] == warned
