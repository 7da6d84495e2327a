"""Summary entries that say what they are (issue 37, item 3): the contact area of the facets
in contact, the contact force over all pairs, states named for the law, titles in an
engineer's words.

``contact_area`` counts each slave facet by the share of its nodes with a contact law that
touch: exact for a surface entirely in contact (supported nodes included), the P1
interpolant of the nodes' contact indicator where the zone's edge runs through a facet.
"""

from __future__ import annotations

import pathlib

from mpi4py import MPI

import numpy as np
import pytest

from dolfinx import fem

from contactqvi import meshes
from contactqvi.case import load_case, parse_case
from contactqvi.contact import build_contact_problem
from contactqvi.contact.figure_data import ShownStep, state_labels
from contactqvi.contact.figures import _pair_text
from contactqvi.contact.interface import BodyPair, ObstaclePair
from contactqvi.contact.nodal import State
from contactqvi.contact.postprocess import contact_summary
from contactqvi.contact.problem import assemble_contact_problem
from contactqvi.contact.scd_newton import SCDNewtonSolver
from contactqvi.contact.surface import FRICTIONLESS_STATE_NAMES, STATE_NAMES, contact_facet_areas, pressure_range
from contactqvi.elasticity import body_materials
from contactqvi.laws import Coulomb, Frictionless
from contactqvi.meshes import read_gmsh, split_by_body
from contactqvi.obstacles import Plane, Sphere
from contactqvi.problems import coulomb as data
from contactqvi.runner import run_case

ROOT = pathlib.Path(__file__).resolve().parent.parent
P = 1e6  # pressure on the patch test's top (Pa)
ROLLERS = {"lower.bottom": {2: 0.0}, "lower.symmetry_x": {0: 0.0}, "upper.symmetry_x": {0: 0.0},
           "lower.symmetry_y": {1: 0.0}, "upper.symmetry_y": {1: 0.0}}


@pytest.fixture(scope="module")
def box():
    """The paper's body at lev 2 on the plane x3 = 0 (contact surface 2 x 1 m, clamped at x1 = 0,
    so the nodes of that edge have no contact law), not solved."""
    msh, tags = meshes.create_contact_body(MPI.COMM_WORLD, 2, data.gap_function("d1"))
    problem = build_contact_problem(msh, tags, data.YOUNG, data.POISSON, data.tractions("L1"), Coulomb(data.FRICTION))
    yield problem
    problem.destroy()


def _areas(problem, states: np.ndarray) -> np.ndarray:
    return problem.comm.allreduce(contact_facet_areas(problem, states), op=MPI.SUM)


def test_a_surface_entirely_in_contact_counts_its_whole_area(box):
    """All contact nodes sticking, then all sliding: 2 m^2, the facets at the clamped edge
    included (the nodes' lumped areas leave out the clamped nodes' strip)."""
    m = len(box.contact_blk)
    for state, expected in ((State.STICKING, [2.0, 0.0]), (State.SLIDING, [0.0, 2.0])):
        assert np.allclose(_areas(box, np.full(m, state, dtype=np.int8)), expected, rtol=1e-13, atol=0)
    lumped = box.comm.allreduce(float(box.contact_area.sum()), op=MPI.SUM)
    assert lumped == pytest.approx(1.875, rel=1e-13)  # the old definition: the clamped edge's strip left out


def test_a_partly_touching_surface_counts_the_p1_interpolant_of_the_contact_indicator(box):
    """Nodes with x1 <= 1 touch (sticking for x2 <= 0.5, else sliding): the facets of x1 < 1
    count wholly, the row of facets beyond x1 = 1 by half (two of its four nodes touch); so
    does the row above x2 = 0.5 split between sticking and sliding."""
    x = box.V.tabulate_dof_coordinates()[box.contact_blk]
    sizes = meshes.contact_body_sizes(2)
    h1, h2 = 2.0 / sizes["nx1"], 1.0 / sizes["nx2"]
    states = np.where(x[:, 0] <= 1.0 + 1e-12, np.where(x[:, 1] <= 0.5 + 1e-12, State.STICKING, State.SLIDING),
                      State.NO_CONTACT).astype(np.int8)
    sticking, sliding = _areas(box, states)
    assert sticking + sliding == pytest.approx(1.0 + 0.5 * h1, rel=1e-13)
    assert sticking == pytest.approx((0.5 + 0.5 * h2) * (1.0 + 0.5 * h1), rel=1e-13)  # the row x2 = 0.5 sticks


def _patch_problem(friction: float):
    msh, facet_tags, cell_tags = read_gmsh(ROOT / "meshes" / "patch_blocks.geo", MPI.COMM_WORLD)
    tags = split_by_body(msh, facet_tags, cell_tags)
    young, poisson = body_materials(msh, cell_tags, {"lower": (1e9, 0.3), "upper": (1e9, 0.3)})
    law = Coulomb(friction) if friction > 0 else Frictionless()
    return assemble_contact_problem(msh, tags, young, poisson, {"upper.top": (0.0, 0.0, -P)},
                                    [BodyPair("upper.interface", "lower.interface", law)],
                                    displacements=ROLLERS, cell_tags=cell_tags)


@pytest.mark.parametrize("friction", [0.0, 0.3])
def test_patch_test_summary(friction):
    """The contact patch test between two bodies: the contact force is the pair's (P on the
    slave body, before (0, 0, 0): no rigid obstacle), the area the interface's 1 m^2, the
    forces in balance, the states named for the law."""
    with _patch_problem(friction) as problem:
        u = problem.A.createVecRight()
        problem.shift.copy(u)
        with SCDNewtonSolver(problem, {"pc": "lu"}, prefix="summary_") as solver:
            result = solver.solve(u)
        assert result.converged
        summary = contact_summary(problem, u, result, displacement=problem.physical_displacement(
            u, fem.Function(problem.V)))
        u.destroy()
        n_contact = problem.n_contact
    assert summary["contact_force"] == pytest.approx([0.0, 0.0, P], abs=1e-8 * P)
    assert np.allclose(summary["contact_force"], np.sum(list(summary["pair_forces"].values()), axis=0),
                       rtol=1e-14, atol=1e-14 * P)
    assert summary["contact_area"] == pytest.approx(1.0, rel=1e-12)
    assert summary["sticking_area"] + summary["sliding_area"] == pytest.approx(summary["contact_area"], rel=1e-14)
    assert summary["equilibrium_error"] < 1e-10
    names = STATE_NAMES if friction > 0 else FRICTIONLESS_STATE_NAMES
    assert set(summary["state_counts"]) == set(names.values())
    assert sum(summary["state_counts"].values()) == n_contact
    if friction == 0.0:
        assert summary["state_counts"]["in contact"] == n_contact and "sliding" not in summary["state_counts"]


def test_case_with_bodies_only_reports_the_total_contact_force(mpi_tmp_path):
    """cases/patch_test.toml through the runner: ``contact_force`` = the sum of ``pair_forces``; the
    summary names the Newton-step solver (its default for linear elements); the step's wall time
    ``solve_seconds`` holds its solver phases (``timings``)."""
    summary, code = run_case(load_case(ROOT / "cases" / "patch_test.toml"), mpi_tmp_path / "patch", plot=False)
    assert code == 0
    assert summary["newton_step_solver"] == "gamg"
    step = summary["steps"][-1]
    assert step["contact_force"] == pytest.approx([0.0, 0.0, P], abs=1e-6 * P)
    assert step["contact_force"] == pytest.approx(step["pair_forces"]["upper.interface/lower.interface"], abs=1e-9 * P)
    assert step["contact_area"] == pytest.approx(1.0, rel=1e-12)
    assert sum(step["timings"].values()) <= step["solve_seconds"]


DATA = ROOT / "tests" / "data"
#: A neo-Hookean block, quarter model 10 x 10 x 10 mm on rollers (issue 46's ``uniaxial_h2.msh``),
#: pressed by a frictionless plate 0.3 mm down (3 %): a homogeneous uniaxial compression.
UNIAXIAL = {"mesh": {"file": str(DATA / "uniaxial_h2.msh")},
            "material": {"young": 5e6, "poisson": 0.45, "model": "neo_hookean"},
            "boundary": {"displacement": {"symmetry_x": {"x": 0.0}, "symmetry_y": {"y": 0.0}, "bottom": {"z": 0.0}}},
            "contact": {"surface": "top", "law": "frictionless"},
            "obstacle": {"type": "plane", "point": [0.0, 0.0, 0.01], "normal": [0.0, 0.0, -1.0]},
            "steps": [{"translation": [0.0, 0.0, -3e-4]}]}


def test_the_uniaxial_blocks_contact_area_is_its_top_face(mpi_tmp_path):
    """Issue 46's uniaxial block: ``contact_area`` is the top face, 1e-4 m^2, to 1e-12;
    ``deformed_contact_area`` the deformed top face (1 + u_x)(1 + u_y) at the corner (x, y) =
    (A, B), the deformation being homogeneous; the pressure (nominal: searched once) is uniform,
    so its facet maximum, nodal maximum and robust range agree, and times the face it is the force."""
    summary, code = run_case(parse_case(UNIAXIAL), mpi_tmp_path / "uniaxial", plot=False)
    assert code == 0
    step = summary["steps"][-1]
    assert abs(step["contact_area"] - 1e-4) <= 1e-12 * 1e-4
    solution = np.load(mpi_tmp_path / "uniaxial" / "solution.npz")
    corner = np.flatnonzero(np.isclose(solution["x"], [0.01, 0.01, 0.01], rtol=0.0, atol=1e-9).all(axis=1))
    stretched = np.prod(0.01 + solution["u"][corner[0], :2])
    assert stretched > 1.02e-4 and step["deformed_contact_area"] == pytest.approx(stretched, rel=1e-10)
    assert step["contact_pressure_measure"] == "nominal"
    p = step["max_contact_pressure"]
    assert step["max_nodal_contact_pressure"] == pytest.approx(p, rel=1e-8)
    assert step["contact_pressure_range"] == pytest.approx([p, p], rel=1e-8)
    assert p * 1e-4 == pytest.approx(-step["contact_force"][2], rel=1e-8)


def test_side_facets_touched_at_a_corner_add_no_contact_area(mpi_tmp_path):
    """Issue 46's rubber seal strip (``seal_half_h1.0.msh``): its contact group is the top face,
    10 x 2 mm, and the upper half of the free side. After the first step (0.075 mm) the top is in
    contact and the side's upper nodes touch at the edge only: ``contact_area`` is the top face
    to 0.2 % (2.0021e-5 m^2; the side facets counted by their touching nodes, 2.066e-5 before
    issue 46; the remaining 0.1 % are top and side facets tilted by the bulge, projected)."""
    case = {**UNIAXIAL, "mesh": {"file": str(DATA / "seal_half_h1.0.msh")},
            "material": {"young": 5e6, "poisson": 0.45, "model": "neo_hookean"},
            "boundary": {"displacement": {"symmetry_x": {"x": 0.0}, "symmetry_y": {"y": 0.0}, "back": {"y": 0.0},
                                          "bottom": {"z": 0.0}}},
            "contact": {"surface": "contact", "law": "coulomb", "friction": 0.4},
            "obstacle": {"type": "plane", "point": [0.0, 0.0, 0.005], "normal": [0.0, 0.0, -1.0]},
            "steps": [{"translation": [0.0, 0.0, -7.5e-5]}]}
    summary, code = run_case(parse_case(case), mpi_tmp_path / "seal", plot=False)
    assert code == 0
    step = summary["steps"][-1]
    assert step["state_counts"]["no contact"] > 0  # the side's lower nodes
    assert 2e-5 <= step["contact_area"] <= 2e-5 * 1.002


def test_figure_words():
    """Titles and legends of ``contact_states.png``: the step, the pairs slave on master, and
    states named for the laws drawn (frictionless contact is "in contact")."""
    bodies = BodyPair("upper.interface", "lower.interface", Frictionless())
    sphere = ObstaclePair("contact", Sphere((0.0, 0.0, 1.0), 1.0), Coulomb(0.3))
    plane = ObstaclePair("bottom", Plane((0.0, 0.0, 0.0), (0.0, 0.0, 1.0)), Frictionless())
    assert _pair_text(bodies) == "upper.interface on lower.interface"
    assert _pair_text(sphere) == "contact on the sphere" and _pair_text(plane) == "bottom on the plane"
    assert ShownStep(6, 1.0).text() == "step 6: load factor 1"
    frictionless = state_labels({False})
    assert frictionless[State.SLIDING] == "in contact" and State.STICKING not in frictionless
    assert state_labels({True}) == STATE_NAMES
    both = state_labels({True, False})
    assert both[State.SLIDING] == "sliding / in contact (frictionless pairs)" and both[State.STICKING] == "sticking"
    assert "seed" not in " ".join(both.values())


@pytest.mark.one_rank(reason="a function of one array")
def test_the_robust_pressure_range_leaves_out_corner_nodes():
    """The fenced 1st-99th percentile of the loaded nodes (the pictures' colour range): four corner
    nodes far above the rest (a press fit's symmetry-plane corners) and the unloaded nodes do not
    move it; a uniform pressure is its own range."""
    pressure = np.concatenate([np.zeros(5), np.linspace(75.0, 90.0, 63), [200.0, 250.0, 300.0, 314.0]])
    low, high = pressure_range(pressure)
    assert 75.0 < low < 76.0 and 90.0 < high < 100.0
    assert pressure_range(np.full(3, 7.0)) == [7.0, 7.0]
    assert pressure_range(np.zeros(2)) == [0.0, 0.0]
