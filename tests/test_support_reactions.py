"""Reactions per support do not depend on the order of the supports (issue 35, part 2).

Each prescribed component's reaction at a node belongs to the supports that prescribe that
component there, split equally where several do (:func:`contactqvi.postprocess.reaction_forces`).
Checked at the level of the rule, on a box with a smooth displacement field against node sums
picked by coordinates from the residual A u (the matrix without boundary conditions), and on
the line contact of issue 35 (a half-cylinder on a block, rollers on both end faces, a loaded
top), whose supports must report the same reactions whichever order a case lists them in, each
body in force balance. Every test runs serially and under ``mpirun -n 2``.
"""

from __future__ import annotations

import pathlib

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import pytest

import dolfinx.fem.petsc
from dolfinx import fem

from contactqvi import meshes
from contactqvi.case import parse_case
from contactqvi.elasticity import elasticity_forms
from contactqvi.parameters import ParameterError
from contactqvi.postprocess import ElasticBody, reaction_forces
from contactqvi.runner import run_case

DATA = pathlib.Path(__file__).resolve().parent / "data"
YOUNG, POISSON = 70e9, 0.3
#: The box's faces (meshes.create_contact_body): the plane each lies in, (axis, value).
FACES = {"dirichlet": (0, 0.0), "front": (1, 0.0), "contact": (2, 0.0)}


@pytest.fixture(scope="module")
def box() -> tuple[fem.Function, dolfinx.mesh.MeshTags, np.ndarray, np.ndarray]:
    """A 6 x 3 x 3 hexahedral box (0,2)x(0,1)x(0,1), a smooth displacement u (not in
    equilibrium, so that every node carries a residual), the residual A u at the owned nodes
    (owned nodes, 3; A assembled without boundary conditions) and the nodes' coordinates."""
    msh, tags = meshes.create_contact_body(MPI.COMM_WORLD, 1, lambda x, y: np.zeros_like(x))
    V = fem.functionspace(msh, ("Lagrange", 1, (3,)))
    u = fem.Function(V)
    u.interpolate(lambda x: 1e-3 * np.stack([x[0] * x[1] + x[2], x[1] * x[2] - x[0] ** 2, x[0] * x[2] + x[1]]))
    a, _ = elasticity_forms(V, YOUNG, POISSON, tags, {})
    A = dolfinx.fem.petsc.assemble_matrix(a)
    A.assemble()
    r = A.createVecLeft()
    A.mult(u.x.petsc_vec, r)
    n_owned = V.dofmap.index_map.size_local
    residual = r.array.reshape(n_owned, 3).copy()
    for obj in (A, r):
        obj.destroy()
    return u, tags, residual, V.tabulate_dof_coordinates()[:n_owned]


def _on(x: np.ndarray, face: str) -> np.ndarray:
    """Mask of the nodes ``x`` on ``face`` (:data:`FACES`)."""
    axis, value = FACES[face]
    return np.isclose(x[:, axis], value, rtol=0, atol=1e-12)


def _dirichlet_dofs(V: fem.FunctionSpace, tags: dolfinx.mesh.MeshTags,
                    prescribed: dict[str, tuple[int, ...]]) -> np.ndarray:
    """Local unrolled indices of the components ``prescribed`` per face, as the contact problem
    makes them (one DirichletBC per face and component)."""
    fdim = V.mesh.topology.dim - 1
    V.mesh.topology.create_connectivity(fdim, fdim + 1)
    dofs = [fem.dirichletbc(PETSc.ScalarType(0.0), fem.locate_dofs_topological(
        V.sub(c), fdim, meshes.boundary_facets(tags, name)), V.sub(c)).dof_indices()[0]
        for name, components in prescribed.items() for c in components]
    return np.unique(np.concatenate(dofs))


def _sums(comm: MPI.Comm, residual: np.ndarray, weights: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Per support, the sum over the owned nodes of residual * weight (nodes, 3), over all ranks."""
    return {name: comm.allreduce((w * residual).sum(axis=0), op=MPI.SUM) for name, w in weights.items()}


def _expected(x: np.ndarray, case: str) -> dict[str, np.ndarray]:
    """Hand-written shares (owned nodes, 3) of each support in ``case`` of :data:`CASES`."""
    left, front, bottom = _on(x, "dirichlet"), _on(x, "front"), _on(x, "contact")
    one = np.ones(3)
    if case == "different components":  # x-roller on x = 0, (y, z) held on z = 0: edge split by component
        return {"dirichlet": left[:, None] * [1.0, 0.0, 0.0], "contact": bottom[:, None] * [0.0, 1.0, 1.0]}
    edge = (left & front)[:, None]
    if case == "same component":  # clamped x = 0 and y-roller y = 0: the edge's r_y halved
        return {"dirichlet": left[:, None] * (one - 0.5 * edge * [0.0, 1.0, 0.0]),
                "front": front[:, None] * [0.0, 1.0, 0.0] * np.where(edge, 0.5, 1.0)}
    # every component of the supports' nodes (no constrained dofs given): the edge's r halved
    return {"dirichlet": left[:, None] * np.where(edge, 0.5, 1.0) * one,
            "front": front[:, None] * np.where(edge, 0.5, 1.0) * one}


#: What each support prescribes in the cases of the rule (None: every component, no dofs given).
CASES = {
    "different components": {"dirichlet": (0,), "contact": (1, 2)},
    "same component": {"dirichlet": (0, 1, 2), "front": (1,)},
    "every component": None,
}


@pytest.mark.parametrize("case", sorted(CASES))
@pytest.mark.parametrize("explicit", [False, True], ids=["inferred", "explicit"])
@pytest.mark.parametrize("reverse", [False, True], ids=["listed", "reversed"])
def test_rule_at_an_edge(box, case, explicit, reverse):
    """At an edge node each support gets the components it prescribes; a component prescribed
    by two supports is split equally; the order of the supports and whether the components are
    given (``ElasticBody.prescribed``) or read off the constrained dofs change nothing."""
    u, tags, residual, x = box
    comm = MPI.COMM_WORLD
    prescribed = CASES[case] or {"dirichlet": (0, 1, 2), "front": (0, 1, 2)}
    supports = tuple(reversed(prescribed)) if reverse else tuple(prescribed)
    body = ElasticBody(YOUNG, POISSON, tags, supports, prescribed=prescribed if explicit else {})
    dofs = None if CASES[case] is None else _dirichlet_dofs(u.function_space, tags, prescribed)
    reactions = reaction_forces(u, body, dirichlet_dofs_loc=dofs)
    expected = _sums(comm, residual, _expected(x, case))
    scale = max(np.linalg.norm(r) for r in expected.values())
    assert list(reactions) == list(supports)
    for name in supports:
        assert np.allclose(reactions[name], expected[name], rtol=0, atol=1e-12 * scale), name
    # whatever the split, the supports' reactions add up to r over the constrained dofs of their nodes
    constrained = np.ones(residual.shape, dtype=bool) if dofs is None else np.isin(
        np.arange(residual.size), dofs).reshape(-1, 3)
    on_supports = np.logical_or.reduce([_on(x, name) for name in supports])
    total = comm.allreduce((residual * (constrained & on_supports[:, None])).sum(axis=0), op=MPI.SUM)
    assert np.allclose(sum(reactions.values()), total, rtol=0, atol=1e-12 * scale)


def test_rule_rejects_components_that_disagree_with_the_constraints(box):
    """A support said to prescribe x while its nodes are held in y: the y reactions would be
    nobody's, so the call raises (on every rank)."""
    u, tags, _, _ = box
    prescribed = {"dirichlet": (0, 1, 2), "front": (1,)}
    dofs = _dirichlet_dofs(u.function_space, tags, prescribed)
    body = ElasticBody(YOUNG, POISSON, tags, tuple(prescribed), prescribed={"front": (0,)})
    with pytest.raises(ParameterError, match="prescribed by no support"):
        reaction_forces(u, body, dirichlet_dofs_loc=dofs)


def _line_contact(cylinder_groups: list[str]) -> dict:
    """The line contact of issue 35 (``tests/data/line_contact.geo``): the block clamped at
    its bottom, both bodies on y-rollers at their end faces, the cylinder's top moved down by
    0.151 mm with x held; the cylinder's displacement groups listed in ``cylinder_groups``' order."""
    groups = {"ends": {"y": 0.0}, "load": {"x": 0.0, "z": -1.51e-4}}
    return {
        "mesh": {"file": "line_contact.geo"},
        "bodies": [
            {"name": "block", "material": {"young": 70e9, "poisson": 0.33},
             "boundary": {"clamped": ["bottom"], "displacement": {"ends": {"y": 0.0}}}},
            {"name": "cyl", "material": {"young": 210e9, "poisson": 0.3},
             "boundary": {"displacement": {name: groups[name] for name in cylinder_groups}}},
        ],
        "contacts": [{"slave": "block.top", "master": "cyl.curved", "law": "frictionless"}],
        "steps": [{"load": 0.5}, {"load": 1.0}],
    }


@pytest.fixture(scope="module")
def line_contact(tmp_path_factory) -> dict[str, list[dict]]:
    """Step summaries of the line contact with the cylinder's groups in both orders."""
    comm = MPI.COMM_WORLD
    base = pathlib.Path(comm.bcast(str(tmp_path_factory.mktemp("lines")) if comm.rank == 0 else None, root=0))
    runs = {}
    for order in (["ends", "load"], ["load", "ends"]):
        summary, code = run_case(parse_case(_line_contact(order), DATA), base / "_".join(order), comm, plot=False)
        assert code == 0
        runs[" before ".join(order)] = summary["steps"]
    return runs


def test_line_contact_reactions_do_not_depend_on_the_order(line_contact):
    """Every support's reaction, at every step, is the same whichever order the cylinder's
    groups are listed in (to 1e-10 of the largest); a roller carries only its own component,
    the load face none along y."""
    first, second = line_contact.values()
    for a, b in zip(first, second, strict=True):
        assert set(a["reaction_forces"]) == set(b["reaction_forces"])
        scale = max(np.linalg.norm(r) for r in a["reaction_forces"].values())
        for name, reaction in a["reaction_forces"].items():
            assert np.allclose(reaction, b["reaction_forces"][name], rtol=0, atol=1e-10 * scale), name
        for step in (a, b):
            reactions = step["reaction_forces"]
            for roller in ("block.ends", "cyl.ends"):
                assert reactions[roller][0] == 0.0 and reactions[roller][2] == 0.0, roller
            assert reactions["cyl.load"][1] == 0.0


@pytest.mark.parametrize("order", ["ends before load", "load before ends"])
def test_line_contact_bodies_in_balance(line_contact, order):
    """Each body's reactions and the contact force on it (on the block, the slave, the pair's
    force; on the cylinder its opposite) add up to zero, to 1e-10 of the largest, at every
    step; the load face alone holds the cylinder down (the end rollers hold no z)."""
    for step in line_contact[order]:
        reactions = {name: np.asarray(r) for name, r in step["reaction_forces"].items()}
        (force,) = (np.asarray(f) for f in step["pair_forces"].values())
        assert np.allclose(step["applied_force"], 0.0)
        for body, contact in (("block", force), ("cyl", -force)):
            forces = [r for name, r in reactions.items() if name.startswith(f"{body}.")] + [contact]
            scale = max(np.linalg.norm(f) for f in forces)
            assert np.linalg.norm(np.sum(forces, axis=0)) <= 1e-10 * scale, body
            assert step["body_equilibrium_errors"][body] <= 1e-10
        assert reactions["cyl.load"][2] == pytest.approx(force[2], rel=1e-10)
