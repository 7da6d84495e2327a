"""Rigid obstacles rotated by the load steps (issue 36, item 6).

A step's ``rotation`` (axis, angle, centre; total) moves the rigid obstacles together with
the groups ``boundary.moved``: x = Q (X - c) + c + t (:func:`~contactqvi.load_steps.placed`),
and friction measures the slip from the displacement of the obstacle's material point at each
node's closest point (:func:`~contactqvi.load_steps.rigid_increment`).

* Objectivity at finite strain: a neo-Hookean block held at its face x = 0 (a moved group),
  pressed onto a plane by a follower pressure on its top, Coulomb friction; then the plane and
  the held face are turned together by 90 degrees about x in five steps. The final contact force
  is Q times the pressed one's, the same nodes touch, and every step of the turn has the same
  contact states node by node.
* The obstacle's surface motion in the friction law, in closed form: a linear block clamped at
  its top, pressed 1 mm into a plane, which then turns about its own normal (e3) through a
  centre c beside the block. The plane's geometry is unchanged: frictionless, the solution does
  not change at all. With Coulomb friction every node slides, and the friction force at each
  node is anti-parallel to the slip relative to the obstacle, du - (I - Q^T)(p - c) with the
  chord (I - Q^T)(p - c) of the arc about the axis that ends at the node's closest point p.
* Named errors of a rotated obstacle (case file and problem).
"""

from __future__ import annotations

import pathlib
import tomllib

from mpi4py import MPI

import numpy as np
import pytest

from contactqvi.case import parse_case
from contactqvi.contact import LoadStep, Rotation, solve_load_path
from contactqvi.contact.load_path import contact_resultants
from contactqvi.contact.nodal import State
from contactqvi.contact.problem import build_contact_problem
from contactqvi.laws import Coulomb, Frictionless
from contactqvi.load_steps import placed, rigid_increment
from contactqvi.materials import NeoHookean
from contactqvi.meshes import create_contact_body
from contactqvi.obstacles import Cylinder, Plane, Sphere
from contactqvi.parameters import ParameterError

ROOT = pathlib.Path(__file__).resolve().parent.parent
YOUNG, POISSON = 10e6, 0.3  # Pa
PRESSURE = 0.5e6  # Pa on the block's top: about 5 % strain
TURNS = 5  # steps of 18 degrees
AXIS_X = (1.0, 0.0, 0.0)
TURN_CENTRE = (1.0, 0.5, 0.0)  # m, the middle of the block's bottom


def _block(law, **options):
    """The box [0, 2] x [0, 1] x [0, 1] of :func:`create_contact_body`, level 2 (8 x 4 x 4 hexahedra),
    its bottom ``contact`` on the plane z = 0."""
    msh, facet_tags = create_contact_body(MPI.COMM_WORLD, 2, lambda x, y: 0.0 * x)
    return build_contact_problem(msh, facet_tags, YOUNG, POISSON, {}, law, obstacle=Plane((0, 0, 0), (0, 0, 1)),
                                 **options)


def _gathered(problem, values: np.ndarray) -> np.ndarray:
    """Per contact node values in the order of the nodes' global indices, on every rank."""
    glob = problem.V.dofmap.index_map.local_to_global(problem.contact_blk)
    pairs = problem.comm.allgather((glob, values))
    glob = np.concatenate([g for g, _ in pairs])
    return np.concatenate([v for _, v in pairs])[np.argsort(glob)]


@pytest.mark.parametrize("search", ["until_settled", "newton"])
def test_a_block_turned_with_its_plane_is_objective(search):
    """Pressed in two steps (some nodes sliding, some sticking), then turned: the final contact
    force is Q f of the pressed block, the same nodes touch, and the contact states of the turn's
    first and last steps agree node by node (a rigid turn slips nowhere: every node sticks), but
    where a node's friction force lies on the bound in both: with no slip, sticking and sliding
    are one state there, told apart by round-off (2 ranks: 5 and 1 such nodes).

    Searched until settled, or inside the Newton iteration (``"newton"``: the slip's reference
    turned with the plane, docs/finite_strain.md Sect. 18). Measured: 6.6e-12 (force, relative;
    1 and 2 ranks; ``"newton"``: 2.2e-14 and 3.3e-14); asserted 1e-6."""
    rows = []
    steps = [LoadStep(0.5), LoadStep(1.0)] + [
        LoadStep(1.0, rotation=Rotation(AXIS_X, 90.0 * (k + 1) / TURNS, TURN_CENTRE)) for k in range(TURNS)]
    mu = 0.3
    with _block(Coulomb(mu), clamped=(), moved=["dirichlet"], material=NeoHookean(), search=search,
                pressures={"top": PRESSURE}, rotations=True) as problem:

        def record(index, step, u, result, state):
            bound = np.linalg.norm(result.friction_force, axis=1) >= (1.0 - 1e-9) * mu * result.normal_force
            rows.append({"converged": result.converged,
                         "force": np.array(contact_resultants(problem, result)["contact_force"]),
                         "states": _gathered(problem, result.states), "bound": _gathered(problem, bound)})

        u = problem.A.createVecRight()
        solve_load_path(problem, steps, u, {"pc": "lu", "geometry_tol": 1e-9}, on_step=record, from_rest=True)
        u.destroy()
    assert len(rows) == 2 + TURNS and all(row["converged"] for row in rows)
    pressed, first, turned = rows[1], rows[2], rows[-1]
    Q = Rotation(AXIS_X, 90.0).matrix()
    error = np.linalg.norm(turned["force"] - Q @ pressed["force"]) / np.linalg.norm(pressed["force"])
    counts = [np.bincount(row["states"], minlength=4).tolist() for row in (pressed, first, turned)]
    print(f"objectivity: force {error:.2e}, states pressed/first turn/last turn {counts}")
    assert error <= 1e-6, (error, pressed["force"], turned["force"])
    assert counts[0][State.SLIDING] > 0 and counts[0][State.STICKING] > 0, counts
    touching = [row["states"] != State.NO_CONTACT for row in (pressed, turned)]
    alike = (turned["states"] == first["states"]) | (turned["bound"] & first["bound"])
    assert np.array_equal(*touching) and alike.all(), counts


SPIN_CENTRE = (-2.0, 0.5, 0.0)  # m: beside the block, 2 to 4 m from its nodes
SPIN = Rotation((0.0, 0.0, 1.0), 1.0, SPIN_CENTRE)  # degrees about the plane's normal
PRESS = (0.0, 0.0, 1e-3)  # m: the plane pushed 1 mm into the block
FRICTION = 0.3


def _spun(law) -> dict:
    """The block clamped at its top, pressed by the plane (step 1), then the plane turned by
    :data:`SPIN` (step 2): per step u~, forces and states of the contact nodes (owned), the
    nodes' positions where the plane was searched and their frames."""
    rows = []
    steps = [LoadStep(1.0, PRESS), LoadStep(1.0, PRESS, SPIN)]
    with _block(law, clamped=("top",), search="every_step") as problem:

        def record(index, step, u, result, state):
            blk = problem.contact_blk
            searched = problem.interfaces[0].searched_at
            x = problem.V.tabulate_dof_coordinates()[blk] + (0.0 if searched is None else searched)
            rows.append({"converged": result.converged, "u": state.displacement.x.array.reshape(-1, 3)[blk].copy(),
                         "normal": result.normal_force.copy(), "friction": result.friction_force.copy(),
                         "states": result.states.copy(), "frames": problem.frames.copy(), "x": x})

        u = problem.A.createVecRight()
        solve_load_path(problem, steps, u, {"pc": "lu", "rtol": 1e-12}, on_step=record, from_rest=True)
        u.destroy()
    assert len(rows) == 2 and all(row["converged"] for row in rows)
    return rows


def test_a_frictionless_block_does_not_feel_its_plane_turn_about_the_normal():
    """The plane turned about its own normal is the same plane: u~ of the two steps agree
    (measured 2.5e-13 relative to the 1 mm press; asserted 1e-12) and the friction force is
    round-off (measured 4e-14 of the largest normal force; asserted 1e-12)."""
    comm = MPI.COMM_WORLD
    pressed, spun = _spun(Frictionless())
    change = comm.allreduce(float(np.abs(spun["u"] - pressed["u"]).max(initial=0.0)), op=MPI.MAX) / PRESS[2]
    normal = comm.allreduce(float(spun["normal"].max(initial=0.0)), op=MPI.MAX)
    tangential = comm.allreduce(float(np.abs(spun["friction"]).max(initial=0.0)), op=MPI.MAX) / normal
    print(f"frictionless: change {change:.2e}, friction / normal {tangential:.2e}")
    assert change <= 1e-12 and tangential <= 1e-12, (change, tangential)


def test_friction_opposes_the_slip_on_a_plane_turning_about_its_normal():
    """Every pressed node slides, with |f_t| = mu lambda, and f_t is anti-parallel to the slip
    du - d_obs relative to the obstacle, d_obs = (I - Q^T)(p - c) the chord of the arc about the
    axis that ends at the node's closest point p (closed form): measured 1.4e-13 (direction, the norm of the
    difference of the unit vectors), asserted 1e-8. The chord makes half the angle increment with
    the circle's tangent e3 x (p - c); f_t makes at most that plus asin(|du_t| / |d_obs|) with it
    (the block's own deflection, closed-form bound; measured below it)."""
    comm = MPI.COMM_WORLD
    pressed, spun = _spun(Coulomb(FRICTION))
    touching = spun["normal"] > 0.0
    n_touching = comm.allreduce(int(np.count_nonzero(touching)), op=MPI.SUM)
    n_nodes = comm.allreduce(len(touching), op=MPI.SUM)
    sliding = comm.allreduce(int(np.count_nonzero(spun["states"][touching] == State.SLIDING)), op=MPI.SUM)
    assert n_touching == n_nodes and sliding == n_touching, (n_touching, sliding, n_nodes)
    ratio = np.linalg.norm(spun["friction"], axis=1) / (FRICTION * spun["normal"])
    bound = comm.allreduce(float(np.abs(ratio - 1.0).max(initial=0.0)), op=MPI.MAX)
    frames = spun["frames"]
    friction = np.einsum("ni,nij->nj", spun["friction"], frames[:, :2])  # global components
    p = spun["x"].copy()  # searched in step 1's configuration: the closest points on the plane z = 1 mm
    p[:, 2] = PRESS[2]
    obstacle = (p - SPIN_CENTRE) @ (np.eye(3) - SPIN.matrix().T).T  # (I - Q^T)(p - c)
    assert np.allclose(obstacle, rigid_increment(spun["x"], PRESS, SPIN, PRESS, None), rtol=0.0, atol=1e-15)
    du = spun["u"] - pressed["u"]
    slip = du - obstacle
    slip -= np.einsum("ni,ni->n", slip, frames[:, 2])[:, None] * frames[:, 2]
    unit = friction / np.linalg.norm(friction, axis=1)[:, None]
    direction = comm.allreduce(float(np.abs(unit + slip / np.linalg.norm(slip, axis=1)[:, None]).max(initial=0.0)),
                               op=MPI.MAX)
    tangent = np.cross([0.0, 0.0, 1.0], p - SPIN_CENTRE)
    angle = np.arccos(np.clip(np.einsum("ni,ni->n", unit, tangent / np.linalg.norm(tangent, axis=1)[:, None]),
                              -1.0, 1.0))
    du_t = np.linalg.norm(du - np.einsum("ni,ni->n", du, frames[:, 2])[:, None] * frames[:, 2], axis=1)
    allowed = np.radians(SPIN.angle) / 2.0 + np.arcsin(du_t / np.linalg.norm(obstacle, axis=1))
    excess = comm.allreduce(float((angle - allowed).max(initial=-np.inf)), op=MPI.MAX)
    largest = comm.allreduce(float(angle.max(initial=0.0)), op=MPI.MAX)
    print(f"friction: |f|/(mu N) - 1 {bound:.2e}, direction {direction:.2e}, angle to tangent {largest:.4e} "
          f"(half increment {np.radians(SPIN.angle) / 2:.4e}), excess {excess:.2e}")
    assert bound <= 1e-10, bound
    assert direction <= 1e-8, direction
    assert excess <= 0.0, excess


@pytest.mark.one_rank(reason="obstacle geometry, no mesh")
@pytest.mark.parametrize("obstacle", [Plane((0.1, 0.2, 0.3), (0.0, 0.6, 0.8)), Sphere((1.0, 0.0, 2.0), 0.5),
                                      Cylinder((0.0, 1.0, 0.0), (1.0, 0.0, 0.0), 0.5)])
def test_a_rotated_obstacle_has_the_rotated_gap_and_normal(obstacle):
    """g_rotated(Q (x - c) + c + t) = g(x) and n_rotated = Q n (the placed obstacle of a step), to 1e-14."""
    rotation = Rotation((1.0, 2.0, 3.0) / np.linalg.norm((1.0, 2.0, 3.0)), 37.0, (0.3, -0.2, 0.5))
    t = np.array([0.1, -0.3, 0.2])
    x = np.random.default_rng(3).uniform(-2.0, 2.0, (20, 3))
    Q = rotation.matrix()
    gap, normal = obstacle.distance(x)
    moved = (x - rotation.centre) @ Q.T + rotation.centre + t
    gap_moved, normal_moved = placed(obstacle, t, rotation).distance(moved)
    assert np.abs(gap_moved - gap).max() <= 1e-14 and np.abs(normal_moved - normal @ Q.T).max() <= 1e-14


@pytest.mark.one_rank(reason="rigid motion arithmetic, no mesh")
def test_the_obstacle_surface_increment_is_the_chord_of_each_points_arc():
    """Between rotations by 10 and 25 degrees about an oblique axis through c (and translations
    t_0, t_1): p - d is where p's material point was, i.e. phi_0(phi_1^-1(p)); without the
    translations d is a chord of length 2 r sin(15 / 2 degrees), r the distance from the axis, and
    perpendicular to the axis; without rotations d = t_1 - t_0 exactly. To 1e-14."""
    axis = np.array([1.0, -2.0, 2.0]) / 3.0
    centre = (0.5, -0.2, 1.0)
    r0, r1 = Rotation(tuple(axis), 10.0, centre), Rotation(tuple(axis), 25.0, centre)
    t0, t1 = np.array([0.1, 0.0, -0.2]), np.array([0.3, 0.4, 0.0])
    p = np.random.default_rng(5).uniform(-2.0, 2.0, (50, 3))
    d = rigid_increment(p, t1, r1, t0, r0)
    X = (p - centre - t1) @ r1.matrix() + centre  # the material points' initial positions
    assert np.abs(p - d - ((X - centre) @ r0.matrix().T + centre + t0)).max() <= 1e-14
    chord = rigid_increment(p, (0, 0, 0), r1, (0, 0, 0), r0)
    offset = p - centre
    radius = np.linalg.norm(offset - (offset @ axis)[:, None] * axis, axis=1)
    assert np.abs(np.linalg.norm(chord, axis=1) - 2.0 * radius * np.sin(np.radians(7.5))).max() <= 1e-14
    assert np.abs(chord @ axis).max() <= 1e-14
    assert np.array_equal(rigid_increment(p, t1, None, t0, None), np.broadcast_to(t1 - t0, p.shape))


def _obstacle_case(search: str | None = None, **step: dict) -> dict:
    """cases/hertz.toml as read (a sphere against a block), one step with ``step``'s keys."""
    data = tomllib.loads((ROOT / "cases" / "hertz.toml").read_text())
    data["steps"] = [{"translation": [0.0, 0.0, -1e-4], **step}]
    if search is not None:
        data["contact"]["search"] = search
    return data


@pytest.mark.one_rank(reason="case-file parsing, no mesh")
@pytest.mark.parametrize("search, rotation, message", [
    (None, {"axis": [0.0, 1.0, 0.0], "angle": 1.0}, r"^contact\.search: steps\[0\] rotates the obstacle, whose "
     r"normals then turn: search it each step \('every_step', 'until_settled' or 'newton'\), got 'once'"),
    ("once", {"axis": [0.0, 1.0, 0.0], "angle": 1.0}, r"^contact\.search: .*got 'once'"),
    ("every_step", {"axis": [0.0, 0.0, 0.0], "angle": 1.0}, r"^steps\[0\]\.rotation\.axis: must have nonzero length"),
    ("every_step", {"axis": [0.0, 1.0, 0.0], "angle": "1"}, r"^steps\[0\]\.rotation\.angle: must be a finite number"),
    ("every_step", {"axis": [0.0, 1.0], "angle": 1.0}, r"^steps\[0\]\.rotation\.axis: must be 3 finite numbers"),
    ("every_step", {"axis": [0.0, 1.0, 0.0], "angel": 1.0}, r"^steps\[0\]\.rotation\.angel: unknown key"),
])
def test_a_bad_obstacle_rotation_is_named(search, rotation, message):
    with pytest.raises(ParameterError, match=message):
        parse_case(_obstacle_case(search, rotation=rotation), ROOT / "cases")


@pytest.mark.one_rank(reason="case-file parsing, no mesh")
def test_an_obstacle_rotation_is_read_and_its_centre_kept():
    """A rotated obstacle searched each step is read (axis normalised); a centre that changes
    between steps is named; the contacts of a case with bodies are named by their index."""
    case = parse_case(_obstacle_case("every_step", rotation={"axis": [0.0, 2.0, 0.0], "angle": 1.0,
                                                             "centre": [0.0, 0.0, 1.0]}), ROOT / "cases")
    assert case.steps[0].rotation == Rotation((0.0, 1.0, 0.0), 1.0, (0.0, 0.0, 1.0))
    data = _obstacle_case("every_step")
    data["steps"] = [{"rotation": {"angle": 1.0, "centre": [0.0, 0.0, 1.0]}}, {"rotation": {"angle": 2.0}}]
    with pytest.raises(ParameterError, match=r"^steps\[1\]\.rotation\.centre: must be the centre of the steps "
                       r"before, \[0\.0, 0\.0, 1\.0\]"):
        parse_case(data, ROOT / "cases")
    data = tomllib.loads((ROOT / "cases" / "sliding_blocks.toml").read_text())
    data["contacts"].append({"slave": "lower.bottom", "law": "frictionless",
                             "obstacle": {"type": "plane", "point": [0.0, 0.0, -0.1], "normal": [0.0, 0.0, 1.0]}})
    data["steps"] = [{"rotation": {"angle": 1.0}}]
    with pytest.raises(ParameterError, match=r"^contacts\[1\]\.search: steps\[0\] rotates the obstacle"):
        parse_case(data, ROOT / "cases")


def test_a_problem_refuses_to_rotate_an_obstacle_searched_once():
    """The API names the pair's search (the case file's check, for problems built directly)."""
    with _block(Frictionless(), clamped=("top",)) as problem:
        with pytest.raises(ParameterError, match=r"^contact/obstacle: search: a rotated obstacle's normals turn"):
            problem.set_step(rotation=SPIN)
