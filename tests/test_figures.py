"""What ``bodies.png`` and ``contact_states.png`` show, read from their descriptions
(:mod:`contactqvi.contact.figure_data`), never from pixels (issue 46).

The geometry and the words are checked on small numpy arrays (one rank); the cases of
issue 46 are solved for a step or two on coarse meshes and their figures described on
any number of ranks: a neo-Hookean seal pressed by a plate (an L-shaped contact group,
``tests/data/pictures``, from ``../shared/repro/turn5``), a press fit (a quarter bore;
corner nodes at the symmetry planes), two-body Hertz, a hexahedral stack and the shipped
rubber pad (Cauchy pressure, a cylinder).
"""

from __future__ import annotations

import dataclasses
import pathlib

from mpi4py import MPI

import numpy as np
import pytest

from contactqvi.case import load_case
from contactqvi.contact.figure_data import (
    ShownStep,
    displacement_scale,
    length_text,
    obstacle_drawing,
    robust_scale,
)
from contactqvi.contact.figures import describe_bodies, describe_contact_states
from contactqvi.contact.load_path import solve_load_path
from contactqvi.contact.path_state import PathState
from contactqvi.contact.postprocess import ContactResultsWriter
from contactqvi.contact.surface_views import contact_limits, surface_views
from contactqvi.obstacles import Cylinder, Plane, Sphere
from contactqvi.runner import PREFIX, build_problem
from shipped_runs import shipped_case

DATA = pathlib.Path(__file__).resolve().parent / "data" / "pictures"


def _no_negative_zero(texts: list[str]) -> None:
    for text in texts:
        assert "-0 " not in text and "-0," not in text and "-0)" not in text and "-0.00" not in text, text


def _rectangle_patches(corner: np.ndarray, e1: np.ndarray, e2: np.ndarray, n1: int, n2: int) -> np.ndarray:
    """(n1 * n2, 4, 3) unit quadrilaterals of a grid in the plane spanned by ``e1``, ``e2``."""
    cells = [[corner + (i + a) * e1 + (j + b) * e2 for a, b in ((0, 0), (1, 0), (1, 1), (0, 1))]
             for i in range(n1) for j in range(n2)]
    return np.array(cells, dtype=float)


def _arc_patches(radius: float, start: float, stop: float, cells: int, length: float,
                 centre: tuple[float, float] = (0.0, 0.0)) -> np.ndarray:
    """Quadrilaterals of a cylinder's arc (axis x3) from angle ``start`` to ``stop``."""
    theta = np.linspace(start, stop, cells + 1)
    x = centre[0] + radius * np.cos(theta)
    y = centre[1] + radius * np.sin(theta)
    return np.array([[[x[i], y[i], 0.0], [x[i + 1], y[i + 1], 0.0], [x[i + 1], y[i + 1], length],
                      [x[i], y[i], length]] for i in range(cells)])


@pytest.mark.one_rank(reason="figure texts from a summary dict, serial arithmetic")
def test_the_step_shown_and_a_failed_path_are_named():
    """After a failed path the figures say where it failed and show the last converged step."""
    summary = {"case": {"steps": [{}] * 20}, "steps": [
        {"step": 1, "load": 1.0, "translation": [0.0, 0.0, -7.5e-5], "converged": True},
        {"step": 2, "load": 1.0, "translation": [-1e-20, 0.0, -1.5e-4], "converged": True},
        {"step": 3, "load": 1.0, "translation": [0.0, 0.0, -2.25e-4], "converged": False,
         "status": "diverged_max_it"}]}
    shown = ShownStep.from_summary(summary)
    assert shown.step == 2 and shown.failed == 3
    assert shown.text() == "step 2 of 20: load factor 1, translation (0, 0, -0.15) mm"
    assert shown.status() == "path failed at step 3 (diverged_max_it); showing step 2, the last converged"
    assert ShownStep.from_summary({"steps": summary["steps"][:2]}).status() == ""
    assert length_text([2e-5, -1.2e-18, 0.0]) == "(0.02, 0, 0) mm"


@pytest.mark.one_rank(reason="colour ranges of numpy arrays, serial arithmetic")
def test_colour_ranges_are_robust_and_state_the_largest_value():
    """A press fit's pressures on a coarse mesh: 61 nodes between 62 and 123 MPa and four
    corner nodes at the symmetry planes up to 314 MPa. The colours stop below the corners;
    the largest value and its place are stated."""
    rng = np.random.default_rng(3)
    pressure = np.concatenate([rng.uniform(62e6, 123e6, 61), [193e6, 215e6, 300e6, 314e6]])
    at = np.zeros((len(pressure), 3))
    at[-1] = [0.02, 0.0, 0.002]
    scale = robust_scale("nominal contact pressure", pressure, at, "the pressing nodes' values")
    assert 60e6 < scale.low < 70e6 and 110e6 < scale.high < 193e6
    assert scale.largest == 314e6 and scale.largest_at == (0.02, 0.0, 0.002)
    assert scale.title == "nominal contact pressure [MPa]"
    assert "largest 314 MPa at (20, 0, 2) mm" in scale.note
    # a Hertz distribution p0 sqrt(1 - r^2/a^2) over a disc of nodes: nothing clipped but the top percent
    hertz = 1e9 * np.sqrt(1.0 - rng.uniform(0.0, 1.0, 2000))
    assert robust_scale("p", hertz, np.zeros((2000, 3)), "nodes").high > 0.98e9
    stresses = robust_scale("von Mises stress", np.geomspace(1e3, 1e9, 500), np.zeros((500, 3)), "cells", True)
    assert stresses.log and stresses.title == "von Mises stress [MPa]"


@pytest.mark.one_rank(reason="the drawing scale rule, serial arithmetic")
def test_only_a_linear_body_whose_touching_nodes_stay_touching_is_magnified():
    size = 0.1
    assert displacement_scale(size, 1e-5, 0.0, finite_strain=True) == (1.0, "true scale (finite strain)")
    scale, text = displacement_scale(size, 1e-5, 0.0, finite_strain=False)  # a flat stack: zero gaps
    assert scale == 1000.0 and text == "displacement magnified x1000 (touching bodies stay touching)"
    assert displacement_scale(size, 1e-5, 2e-4, False)[0] == 1.0  # a Hertz gap of 0.2 mm at the zone's edge
    assert displacement_scale(size, 1e-5, 2e-6, False, zone=0.01)[0] == 10.0  # 2e-5 m off in a 10 mm zone
    assert displacement_scale(size, 1e-5, 0.0, False, rotated=True)[0] == 1.0
    assert displacement_scale(size, 2e-3, 0.0, False)[0] == 1.0  # 2 % of the size: true scale


@pytest.mark.one_rank(reason="obstacle geometry on numpy arrays, serial arithmetic")
def test_obstacles_are_clipped_to_the_view():
    """A plane is the polygon it cuts from the view's box, a sphere or cylinder its surface
    within the box; an obstacle outside the view is not drawn."""
    low, high = np.array([0.0, 0.0, 0.0]), np.array([2.0, 1.0, 1.0])
    plane = obstacle_drawing(Plane((0.0, 0.0, 0.5), (0.0, 0.0, -1.0)), low, high, "the plane")
    assert plane.faces.shape == (1, 4) and np.allclose(plane.points[:, 2], 0.5)
    assert np.allclose(np.ptp(plane.points, axis=0), [2.0, 1.0, 0.0])
    tilted = obstacle_drawing(Plane((0.5, 0.5, 0.5), (1.0, 1.0, 1.0)), low, np.ones(3), "tilted")  # a unit cube
    assert len(tilted.points) == 6 and np.allclose((tilted.points - 0.5) @ [1, 1, 1], 0.0)  # a hexagon
    angles = np.unwrap(np.arctan2(*(tilted.points - 0.5)[:, :2].T))
    assert np.all(np.diff(angles) > 0) or np.all(np.diff(angles) < 0)  # its corners in order round it
    assert obstacle_drawing(Plane((0.0, 0.0, 3.0), (0.0, 0.0, 1.0)), low, high, "far") is None
    for obstacle in (Sphere((1.0, 0.5, 3.0), 2.8), Cylinder((1.0, 0.5, 3.0), (0.0, 1.0, 0.0), 2.8)):
        drawing = obstacle_drawing(obstacle, low, high, "curved")
        assert np.all((drawing.points >= low - 1e-12) & (drawing.points <= high + 1e-12))
        assert np.allclose(obstacle.distance(drawing.points)[0], 0.0, atol=1e-12)
        assert drawing.points[:, 2].min() == pytest.approx(0.2, abs=1e-9)  # the lowest point of its surface
    assert obstacle_drawing(Sphere((1.0, 0.5, 5.0), 1.0), low, high, "far") is None


@pytest.mark.one_rank(reason="surface geometry on numpy arrays, serial arithmetic")
def test_contact_groups_are_drawn_flat_per_plane_or_unrolled_on_a_fitted_surface():
    """An L-shaped flat group (a top and a side) is drawn per plane in global axes, a quarter
    bore unrolled from its symmetry plane, a half-cylinder from its crown, a spherical cap from
    its crown; the fits' errors are stated; no label says ``-0``."""
    top = _rectangle_patches(np.array([0.0, 0.0, 5e-3]), np.array([1e-3, 0, 0]), np.array([0, 1e-3, 0]), 10, 2)
    side = _rectangle_patches(np.array([10e-3, 0.0, 2.5e-3]), np.array([0, 1e-3, 0]), np.array([0, 0, 0.5e-3]), 2, 5)
    views = surface_views(np.concatenate([top, side]), np.ones(30))
    assert [view.kind for view, _ in views] == ["plane", "plane"]
    assert [view.labels for view, _ in views] == [("x1 [mm]", "x2 [mm]"), ("x2 [mm]", "x3 [mm]")]
    assert [view.title for view, _ in views] == ["plane 1 of 2, x3 = 5 mm", "plane 2 of 2, x1 = 10 mm"]
    assert np.ptp(views[0][0].coordinates[..., 0]) == pytest.approx(10.0)
    bore = _arc_patches(0.02, 0.0, np.pi / 2, 8, 2e-3)
    (view, shown), = surface_views(bore, np.ones(len(bore)))
    assert view.kind == "cylinder" and view.labels[0] == "arc length from the plane x2 = 0 [mm]"
    assert view.coordinates[..., 0].min() == pytest.approx(0.0, abs=1e-9)
    assert view.coordinates[..., 0].max() == pytest.approx(10 * np.pi, rel=1e-9)
    assert view.fit_error < 1e-12 and "radius 20 mm" in view.title and "rms error 0 %" in view.title
    cord = _arc_patches(2.5e-3, 0.1, np.pi - 0.1, 12, 1e-3, centre=(0.01, 0.03))
    pressure = np.exp(-((cord[:, 0, 0] - 0.01) / 1e-3) ** 2)  # pressed at the top, x = 10 mm
    (view, _), = surface_views(cord, pressure)
    assert view.labels[0] == "arc length from the crown [mm]"
    crown = view.coordinates[np.argmax(pressure), 0, 0]
    assert abs(crown) < 2.5 * np.pi / 12  # within a cell of the origin
    theta, phi = np.meshgrid(np.linspace(0.0, 0.4, 6), np.linspace(0.0, 2 * np.pi, 13), indexing="ij")
    cap = 0.01 * np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), -np.cos(theta)], axis=-1)
    quads = np.array([[cap[i, j], cap[i + 1, j], cap[i + 1, j + 1], cap[i, j + 1]]
                      for i in range(5) for j in range(12)])
    (view, _), = surface_views(quads, 1.0 - quads[:, 0, 2] ** 2)
    assert view.kind == "sphere" and "radius 10 mm" in view.title
    for view, _ in views:
        _no_negative_zero([view.title, *view.labels])


@pytest.mark.one_rank(reason="zoom limits on numpy arrays, serial arithmetic")
def test_a_small_contact_zone_is_zoomed_on():
    corners = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    plane = np.array([corners + [i, j] for i in range(10) for j in range(10)])
    state = np.zeros(len(plane), dtype=int)
    state[0] = 1
    assert contact_limits(plane, state, 0.25) == ((0.0, 1.5), (0.0, 1.5))
    assert contact_limits(plane, np.ones(len(plane), dtype=int), 0.25) is None


def _described(case, steps: int, out: pathlib.Path):
    """Solve the first ``steps`` steps of ``case`` (results in ``out``) and describe both
    figures of the last one (on rank 0; None elsewhere), with the summary's step."""
    case = dataclasses.replace(case, steps=case.steps[:steps])
    with build_problem(case, MPI.COMM_WORLD) as problem, ContactResultsWriter(out, problem.comm) as writer:
        u, state = problem.A.createVecRight(), PathState.at_rest(problem)
        entries = []

        def record(index, step, u, result, state):
            entries.append({"step": index + 1, "load": step.load, "translation": list(step.translation),
                            "converged": result.converged, "status": str(result.status)})
            if result.converged:
                writer.write(problem, u, result, t=index + 1)

        solve_load_path(problem, case.steps, u, {}, PREFIX, record, True, state)
        shown = ShownStep.from_summary({"case": {"steps": case.steps}, "steps": entries})
        last = writer.last
        figures = (describe_bodies(last.displacement, last.von_mises, last.surface, shown),
                   describe_contact_states(last.surface, shown))
        for owner in (u, state):
            owner.destroy()
    return figures


@pytest.fixture(scope="module")
def described(tmp_path_factory):
    """The figures of each case, described once per module (made on first use)."""
    comm = MPI.COMM_WORLD
    base = pathlib.Path(comm.bcast(str(tmp_path_factory.mktemp("figures")) if comm.rank == 0 else None, root=0))
    cases = {"seal": (lambda: load_case(DATA / "seal_half_nu0.45.toml"), 2),
             "press_fit": (lambda: load_case(DATA / "fit_h1.0_1.5.toml"), 1),
             "hertz_bodies": (lambda: shipped_case("hertz_bodies"), 1),
             "hex_patch": (lambda: shipped_case("hex_patch"), 1),
             "rubber_pad": (lambda: shipped_case("rubber_pad"), 1)}
    made = {}

    def figures(name: str):
        if name not in made:
            case, steps = cases[name]
            made[name] = _described(case(), steps, base / name)
        return made[name]

    return figures


def _all_texts(bodies, states) -> list[str]:
    texts = [bodies.title, bodies.status, bodies.scale_text, bodies.stress.note, bodies.stress.title,
             bodies.contact_title, bodies.pressure.note, bodies.pressure.title, states.title, states.status]
    texts += [o.label for o in bodies.obstacles]
    for panel in states.panels:
        texts += [panel.title, *panel.view.labels]
    return texts


def test_seal_pictures(described):
    """The neo-Hookean seal after two steps: true scale, the plate drawn where it is, the
    pressure named nominal (searched once: reference areas), its L-shaped group per plane."""
    bodies, states = described("seal")
    if MPI.COMM_WORLD.rank != 0:
        return
    assert bodies.scale == 1.0 and bodies.scale_text == "true scale (finite strain)"
    assert bodies.title == "Deformed bodies, step 2 of 2: load factor 1, translation (0, 0, -0.15) mm"
    assert bodies.status == "" and states.status == ""
    (plate,) = bodies.obstacles
    assert plate.label == "the plane (rigid) at step 2 of 2" and len(plate.faces) == 1
    assert np.allclose(plate.points[:, 2], 5e-3 - 1.5e-4)  # the plate at the step's translation
    drawn = bodies.bodies.points
    assert np.all(plate.points[:, :2].min(axis=0) < drawn[:, :2].min(axis=0))  # over the whole strip
    assert np.all(plate.points[:, :2].max(axis=0) > drawn[:, :2].max(axis=0))
    assert bodies.pressure.title == "nominal contact pressure [kPa]"
    assert bodies.contact_title.startswith("nominal contact pressure on the contact surfaces")
    assert 0.0 < bodies.pressure.low < bodies.pressure.high <= bodies.pressure.largest
    assert [p.view.kind for p in states.panels] == ["plane", "plane"]
    assert [p.title for p in states.panels] == ["plane 1 of 2, x3 = 5 mm", "plane 2 of 2, x1 = 10 mm"]
    assert states.title == ("Contact states, step 2 of 2: load factor 1, translation (0, 0, -0.15) mm; "
                            "contact on the plane")
    _no_negative_zero(_all_texts(bodies, states))


def test_press_fit_pictures(described):
    """The press fit (hub slave, 1.0/1.5 mm): true scale (the 15 um interference would be drawn
    as an overlap magnified), no corner node at a symmetry plane setting the pressure's colours,
    the bore unrolled from its symmetry plane on a fitted cylinder."""
    bodies, states = described("press_fit")
    if MPI.COMM_WORLD.rank != 0:
        return
    assert bodies.scale == 1.0 and bodies.obstacles == []
    pressure = bodies.pressure
    assert pressure.title == "nominal contact pressure [MPa]"
    assert 40e6 < pressure.low < 70e6 and 90e6 < pressure.high < 140e6  # Lame: 65 MPa (+26 % on this mesh)
    assert pressure.largest > 2.5e8  # a corner node: stated, not the scale
    corner = np.asarray(pressure.largest_at)
    assert np.hypot(corner[0], corner[1]) == pytest.approx(0.02, rel=1e-3) and min(abs(corner[:2])) < 1e-9
    assert f"largest {pressure.largest * 1e-6:.3g} MPa at" in pressure.note
    (panel,) = states.panels
    assert panel.view.kind == "cylinder" and panel.view.fit_error < 1e-3
    assert panel.view.labels[0] in ("arc length from the plane x1 = 0 [mm]", "arc length from the plane x2 = 0 [mm]")
    assert panel.polygons[..., 0].min() == pytest.approx(0.0, abs=1e-6)
    assert panel.polygons[..., 0].max() == pytest.approx(10 * np.pi, rel=2e-3)  # a quarter of 20 mm radius
    _no_negative_zero(_all_texts(bodies, states))


def test_hertz_bodies_pictures(described):
    """Two-body Hertz (coarse): true scale (the ball's gap at the zone's edge would open up
    magnified), the block's flat top drawn in global axes, nominal pressure at small strain."""
    bodies, states = described("hertz_bodies")
    if MPI.COMM_WORLD.rank != 0:
        return
    assert bodies.scale == 1.0 and bodies.scale_text.startswith("true scale (bodies touch: magnified they would")
    assert bodies.title == "Deformed bodies, step 1 of 1: load factor 0.25"
    assert bodies.pressure.title.startswith("nominal contact pressure [")
    assert bodies.pressure.high <= bodies.pressure.largest
    (panel,) = states.panels
    assert panel.view.kind == "flat" and panel.view.labels == ("x1 [mm]", "x2 [mm]")
    assert states.title.endswith("block.top on ball.sphere")
    _no_negative_zero(_all_texts(bodies, states))


def test_hexahedral_stack_pictures(described):
    """The hexahedral stack under a uniform 1 MPa: its flat, matching interface stays touching
    when magnified, so the picture magnifies and says so; the pressure is uniform."""
    bodies, states = described("hex_patch")
    if MPI.COMM_WORLD.rank != 0:
        return
    assert bodies.scale > 10.0 and bodies.scale_text.endswith("(touching bodies stay touching)")
    assert f"x{bodies.scale:g}" in bodies.scale_text
    assert bodies.pressure.title == "nominal contact pressure [MPa]"
    assert bodies.pressure.high == pytest.approx(1e6, rel=1e-6) and bodies.pressure.low == 0.0
    assert np.all(bodies.contact.values[np.isfinite(bodies.contact.values)] == pytest.approx(1e6, rel=1e-6))
    (panel,) = states.panels
    assert panel.view.kind == "flat" and panel.view.labels == ("x1 [mm]", "x2 [mm]")
    _no_negative_zero(_all_texts(bodies, states))


def test_rubber_pad_pictures(described):
    """The shipped rubber pad (neo-Hookean, searched until settled) after its first step: true
    scale, the cylinder drawn where it is within the view, the pressure named Cauchy."""
    bodies, states = described("rubber_pad")
    if MPI.COMM_WORLD.rank != 0:
        return
    assert bodies.scale == 1.0 and bodies.scale_text == "true scale (finite strain)"
    (roller,) = bodies.obstacles
    moved = Cylinder((0.0, 0.0, 0.015 - 0.5e-3), (0.0, 1.0, 0.0), 0.015)
    assert np.allclose(moved.distance(roller.points)[0], 0.0, atol=1e-12)
    drawn = bodies.bodies.points
    margin = 0.15 * np.ptp(drawn, axis=0).max() + 1e-12
    assert np.all(roller.points >= drawn.min(axis=0) - margin) and np.all(roller.points <= drawn.max(axis=0) + margin)
    assert bodies.pressure.title == "Cauchy contact pressure [MPa]"
    assert bodies.contact_title.startswith("Cauchy contact pressure")
    (panel,) = states.panels
    assert panel.view.kind == "flat" and states.title.endswith("top on the cylinder")
    _no_negative_zero(_all_texts(bodies, states))
