"""The predictor of a slide step (contactqvi/contact/convection.py): the last solution convected with
what slides, found on the rank that owns each point and in the node's own body."""

from __future__ import annotations

import dataclasses
import pathlib
import tomllib

import numpy as np
import pytest

from mpi4py import MPI

from dolfinx import fem

from contactqvi.case import parse_case
from contactqvi.contact import convection, load_path
from contactqvi.runner import build_problem, run_case

ROOT = pathlib.Path(__file__).resolve().parent.parent
CASE = ROOT / "cases" / "sliding_blocks.toml"
DATA = ROOT / "tests" / "data"
#: Per body (lower, upper): u = G X + c, a different linear field in each.
FIELDS = ((np.array([[1e-3, 2e-3, 0.0], [0.0, -1e-3, 3e-3], [2e-3, 0.0, 1e-3]]), np.array([1e-3, 0.0, -2e-3])),
          (np.array([[-2e-3, 0.0, 1e-3], [1e-3, 1e-3, 0.0], [0.0, 2e-3, -1e-3]]), np.array([0.0, 5e-3, 1e-3])))


def sliding_blocks(friction: float = 0.0) -> dict:
    """cases/sliding_blocks.toml with neo-Hookean blocks searched ``"newton"``, frictionless or with
    Coulomb ``friction``: the upper block (its top moved) pressed 1 mm, slid 0.1 m and 0.2 m along x,
    then pressed 0.5 mm more."""
    data = tomllib.loads(CASE.read_text())
    for body in data["bodies"]:
        body["material"]["model"] = "neo_hookean"
    data["contacts"][0].update(law="coulomb", friction=friction, search="newton")
    if friction == 0.0:
        data["contacts"][0]["law"] = "frictionless"
        del data["contacts"][0]["friction"]
    data["steps"] = [{"translation": t} for t in ([0.0, 0.0, -1e-3], [0.1, 0.0, -1e-3], [0.2, 0.0, -1e-3],
                                                   [0.2, 0.0, -1.5e-3])]
    return data


def test_convected_follows_each_body_linear_field():
    """u~_n a linear field per block (exact in P1): the predictor moves the upper block (its top a group
    ``boundary.moved``) by t and gives the lower block u~_n(X - t), its own field also on its top face z =
    0.5, which the upper block's bottom touches, and u~_n where X - t lies outside it (to 1e-13), on any
    number of ranks."""
    comm = MPI.COMM_WORLD
    data = sliding_blocks()
    data["mesh"]["file"] = str(CASE.parent / data["mesh"]["file"])
    with build_problem(parse_case(data), comm) as problem:
        V = problem.V
        X = V.tabulate_dof_coordinates()
        body = problem.node_body
        last = fem.Function(V)
        values = last.x.array.reshape(-1, 3)
        for k, (G, c) in enumerate(FIELDS):
            values[body == k] = X[body == k] @ G.T + c
        t = np.array([0.3, -0.05, 0.0])
        predicted = convection.convected(problem, last, t)
        n = V.dofmap.index_map.size_local
        got = predicted.x.array.reshape(-1, 3)[:n]
        lower = body[:n] == 0
        shifted = X[:n] - t
        inside = lower & (shifted[:, 0] >= -1.0 - 1e-12) & (shifted[:, 1] <= 1.0 + 1e-12)
        expected = values[:n].copy()
        expected[~lower] += t
        expected[inside] = shifted[inside] @ FIELDS[0][0].T + FIELDS[0][1]
        assert np.abs(got - expected).max(initial=0.0) <= 1e-13
        top = inside & np.isclose(X[:n, 2], 0.5)
        assert comm.allreduce(int(top.sum()), op=MPI.SUM) > 0
        ghosts = predicted.x.array.copy()
        predicted.x.scatter_forward()
        assert np.array_equal(ghosts, predicted.x.array)


@pytest.mark.parametrize("friction", [0.0, 0.2])
def test_slide_steps_start_convected_and_reach_the_same_solution(mpi_tmp_path, monkeypatch, friction):
    """The sliding blocks searched ``"newton"``: the two slide steps start from the convected predictor,
    the press steps do not (a translation into the contact), and the path's solution is the one without
    that predictor (neo-Hookean, frictionless or Coulomb 0.2 with the slip of each step measured from
    its start: the same equilibria; pair forces to 1e-8 of the normal force). Measured Newton steps of
    the two slide steps: frictionless 3 and 3 convected, 3 and 2 without (on these flat blocks both
    predictors start near the solution); Coulomb 3 and 3 against 6 and 6 (the die of the shipped
    ironing, which presses a trough, 3-8 against 15-28: docs/finite_strain.md Sect. 21). Regression
    guard: at most 4 each."""
    comm = MPI.COMM_WORLD
    slid = []
    original = load_path.convected

    def counted(problem, last, change):
        slid.append(change.copy())
        return original(problem, last, change)

    monkeypatch.setattr(load_path, "convected", counted)
    runs = {}
    summary, code = run_case(parse_case(sliding_blocks(friction), CASE.parent), mpi_tmp_path / "convected", comm,
                             plot=False)
    assert code == 0, summary["status"]
    runs["convected"] = summary
    assert [list(t) for t in slid] == [[0.1, 0.0, 0.0], [0.1, 0.0, 0.0]]
    monkeypatch.setattr(convection, "SLIDING_COSINE", 0.0)  # no step slides
    summary, code = run_case(parse_case(sliding_blocks(friction), CASE.parent), mpi_tmp_path / "tangent", comm,
                             plot=False)
    assert code == 0, summary["status"]
    runs["tangent"] = summary
    assert len(slid) == 2
    for a, b in zip(runs["convected"]["steps"], runs["tangent"]["steps"]):
        force = np.asarray(a["contact_force"])
        assert np.abs(force - b["contact_force"]).max() <= 1e-8 * abs(force[2])
    newton = {name: [s["iterations"] for s in run["steps"]] for name, run in runs.items()}
    assert max(newton["convected"][1:3]) <= 4, newton


def curved_die(law: str) -> dict:
    """The line contact of ``tests/data/line_contact.geo`` as a die on a rubber block: the half-cylinder
    (R = 50 mm, neo-Hookean, E = 200 MPa, its flat face a group ``boundary.moved``) pressed 1 mm into
    the block (neo-Hookean, E = 10 MPa, clamped at its bottom) in two steps and slid 4 mm along x in
    four, both on y-rollers at their ends, the die's curved face the slave searched ``"newton"``,
    frictionless or with Coulomb friction 0.3."""
    friction = {"friction": 0.3} if law == "coulomb" else {}
    return {
        "mesh": {"file": "line_contact.geo"},
        "bodies": [
            {"name": "block", "material": {"young": 10e6, "poisson": 0.3, "model": "neo_hookean"},
             "boundary": {"clamped": ["bottom"], "displacement": {"ends": {"y": 0.0}}}},
            {"name": "cyl", "material": {"young": 200e6, "poisson": 0.3, "model": "neo_hookean"},
             "boundary": {"moved": ["load"], "displacement": {"ends": {"y": 0.0}}}},
        ],
        "contacts": [{"slave": "cyl.curved", "master": "block.top", "law": law, "search": "newton", **friction}],
        "steps": [{"translation": [0.0, 0.0, -5e-4]}, {"translation": [0.0, 0.0, -1e-3]}]
        + [{"translation": [k * 1e-3, 0.0, -1e-3]} for k in range(1, 5)],
    }


@pytest.mark.parametrize("law", ["frictionless", "coulomb"])
def test_a_curved_die_slides_in_fewer_newton_steps(mpi_tmp_path, monkeypatch, law):
    """A die that presses a trough and slides (the ironing's situation on a small mesh): its four slide
    steps take at most half the Newton steps from the convected predictor that they take from the
    tangent's (measured 15 against 47 frictionless, 19 against 57 with Coulomb 0.3), to the same pair
    forces (1e-8 of the normal force, friction history included). Regression guard: at most 8 a step
    (measured 3-7)."""
    comm = MPI.COMM_WORLD
    runs = {}
    for predictor in ("convected", "tangent"):
        if predictor == "tangent":
            monkeypatch.setattr(convection, "SLIDING_COSINE", 0.0)  # no step slides
        summary, code = run_case(parse_case(curved_die(law), DATA), mpi_tmp_path / predictor, comm, plot=False)
        assert code == 0, summary["status"]
        runs[predictor] = summary["steps"]
    for a, b in zip(runs["convected"], runs["tangent"], strict=True):
        force = np.asarray(a["contact_force"])
        assert np.abs(force - b["contact_force"]).max() <= 1e-8 * abs(force[2])
    slides = {name: [s["iterations"] for s in steps[2:]] for name, steps in runs.items()}
    assert 2 * sum(slides["convected"]) <= sum(slides["tangent"]), slides
    assert max(slides["convected"]) <= 8, slides


@pytest.mark.parametrize("translation, slides", [((0.1, 0.0, -1e-3), True), ((0.0, 0.0, -1.5e-3), False)])
def test_a_step_slides_along_the_contact_not_into_it(mpi_tmp_path, translation, slides):
    """After the press step, a step that moves the upper block along x slides (its nodes' normals are
    z), one that presses it further does not."""
    comm = MPI.COMM_WORLD
    data = sliding_blocks()
    data["steps"] = data["steps"][:1]
    data["mesh"]["file"] = str(CASE.parent / data["mesh"]["file"])
    case = parse_case(data)
    with build_problem(case, comm) as problem:
        u = problem.A.createVecRight()
        states = []
        results = load_path.solve_load_path(problem, case.steps, u, dict(case.solver), "slide_",
                                            lambda i, step, u, result, state: states.append(state), from_rest=True)
        u.destroy()
        assert results[-1].converged
        step = dataclasses.replace(case.steps[0], translation=tuple(translation))
        found = convection.sliding_translation(problem, states[-1], step)
    assert (found is not None) == slides

