"""Coulomb output: surface fields, the files of ``write_contact_results`` read back, the summary."""

from __future__ import annotations

import json

from mpi4py import MPI

import numpy as np
import pytest

from contactqvi import meshes
from contactqvi.contact import LoadStep, State, build_contact_problem, solve_load_path
from contactqvi.contact.postprocess import STATE_NAMES, UNITS, write_contact_results
from contactqvi.contact.surface import ContactSurface, TributaryPatches
from contactqvi.laws import Coulomb
from contactqvi.paraview import Dataset, write_xdmf
from contactqvi.problems import coulomb as data
from contactqvi.tables import to_builtin
from output_files import read_vtx, read_xdmf_point_data

LEV = 3
FIELDS = {"contact_state", "contact_pair", "contact_pressure", "friction_traction", "slip", "tangential_displacement", "gap",
          "displacement", "nodal_area"}
STICKING = (State.STICKING, State.WEAK_STICKING)


@pytest.fixture(scope="module")
def solution():
    """Converged d1/L1 problem at lev 3 (exact inner solves), u and result."""
    msh, tags = meshes.create_contact_body(MPI.COMM_WORLD, LEV, data.gap_function("d1"))
    problem = build_contact_problem(msh, tags, data.YOUNG, data.POISSON, data.tractions("L1"), Coulomb(data.FRICTION))
    u = problem.A.createVecRight()
    (result,) = solve_load_path(problem, [LoadStep()], u, {"pc": "lu"}, prefix="surface_")
    assert result.converged
    return problem, u, result


def _rows(points: np.ndarray, queries: np.ndarray) -> np.ndarray:
    """Row of ``points`` with the coordinates of each query point (-1 if none)."""
    keys = np.round(np.vstack([points, queries]), 12)
    _, ids = np.unique(keys, axis=0, return_inverse=True)
    ids = ids.ravel()
    lookup = np.full(ids.max() + 1, -1)
    lookup[ids[: len(points)]] = np.arange(len(points))
    return lookup[ids[len(points) :]]


def test_contact_surface_fields(solution, mpi_tmp_path):
    """The surface fields (XDMF, read with meshio) hold each node's state, forces, slip and gap."""
    problem, u, result = solution
    comm = problem.comm
    surface = ContactSurface(problem).update(u, result)
    write_xdmf(mpi_tmp_path / "contact_surface.xdmf", surface.mesh, surface.functions)
    points, fields = read_xdmf_point_data(mpi_tmp_path / "contact_surface.xdmf")
    assert set(fields) == FIELDS
    state, pressure, area = fields["contact_state"], fields["contact_pressure"], fields["nodal_area"]
    traction, slip, gap = fields["friction_traction"], fields["slip"], fields["gap"]
    tangential, displacement = fields["tangential_displacement"], fields["displacement"]

    # Vertices: the p contact nodes and the nx2 + 1 nodes of the clamped edge x1 = 0.
    sizes = meshes.contact_body_sizes(LEV)
    assert problem.n_contact == sizes["p"]
    assert len(points) == problem.n_contact + sizes["nx2"] + 1
    edge = np.isclose(points[:, 0], 0.0)
    assert np.count_nonzero(edge) == sizes["nx2"] + 1
    assert np.all(state[edge] == State.NO_CONTACT) and np.all(pressure[edge] == 0.0)
    assert np.all(traction[edge] == 0.0) and np.all(slip[edge] == 0.0) and np.all(displacement[edge] == 0.0)
    assert np.allclose(gap[edge], points[edge, 2], rtol=0, atol=1e-14)  # clamped: the initial gap

    # Total normal force; states as counted by the solver.
    total = comm.allreduce(float(result.normal_force.sum()), op=MPI.SUM)
    assert abs(np.sum(pressure * area) - total) <= 1e-10 * total
    assert set(np.unique(state)) <= {float(s) for s in State}
    counts = comm.allreduce(np.bincount(result.states.astype(np.int64), minlength=len(State)), op=MPI.SUM)
    assert np.array_equal(np.bincount(state[~edge].astype(np.int64), minlength=len(State)), counts)

    # Slip: zero where not touching, the tangential displacement where touching (one step from rest).
    open_ = state == State.NO_CONTACT
    assert np.any(open_) and np.all(slip[open_] == 0.0)
    assert np.any(np.abs(tangential[open_]).max(axis=1) > 1e-6)  # free nodes move tangentially
    assert np.allclose(slip[~open_], tangential[~open_], rtol=0, atol=1e-14)
    stick = np.isin(state, STICKING)
    assert np.any(stick) and np.all(np.linalg.norm(slip[stick], axis=1) <= 1e-10 * np.abs(slip).max())
    assert np.allclose(tangential[:, :2], displacement[:, :2], rtol=0, atol=1e-14) and np.all(tangential[:, 2] == 0.0)
    assert np.all(traction[:, 2] == 0.0)
    cone = np.linalg.norm(traction, axis=1) - problem.law.friction * pressure
    assert np.all(cone <= 1e-8 * np.abs(pressure).max())
    sliding = state == State.SLIDING
    assert np.all(np.einsum("ij,ij->i", traction[sliding], slip[sliding]) < 0.0)  # friction opposes slip

    # Node by node: the owned contact nodes of every rank, found by coordinates.
    x = problem.V.tabulate_dof_coordinates()[problem.contact_blk]
    rows = _rows(points, x)
    assert np.all(rows >= 0)
    assert np.array_equal(state[rows], result.states)
    assert np.allclose(pressure[rows], result.normal_force / problem.contact_area, rtol=1e-12, atol=0)
    assert np.allclose(traction[rows, :2], result.friction_force / problem.contact_area[:, None], rtol=1e-12, atol=0)
    shifted = u.array.reshape(-1, 3)[problem.contact_blk]  # frames e1, e2, e3: (slip, gap after deformation)
    assert np.allclose(gap[rows], shifted[:, 2], rtol=0, atol=1e-14)
    assert np.all(gap >= -1e-12)

    # In memory, ghost entries (under mpirun) hold their owner's values.
    for f in surface.functions:
        local = f.x.array.reshape(len(f.function_space.tabulate_dof_coordinates()), f.function_space.dofmap.index_map_bs)
        rows = _rows(points, f.function_space.tabulate_dof_coordinates())
        assert np.all(rows >= 0) and np.array_equal(local, fields[f.name][rows].reshape(local.shape))


def _patch_areas(dataset: Dataset) -> np.ndarray:
    """Areas of planar quadrilaterals (half the cross product of the diagonals)."""
    p = dataset.points[dataset.cells]
    return 0.5 * np.linalg.norm(np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 1]), axis=1)


def _box_volumes(dataset: Dataset) -> np.ndarray:
    """Volumes of box-shaped hexahedra in VTK order."""
    p = dataset.points[dataset.cells]
    return np.abs(np.linalg.det(np.stack([p[:, 1] - p[:, 0], p[:, 3] - p[:, 0], p[:, 4] - p[:, 0]], axis=1)))


def _assert_points(dataset: Dataset, n_points: int) -> None:
    """Every point once outside the duplicates (the copies of the ranks' shared points), copies equal."""
    assert np.count_nonzero(~dataset.duplicate) == n_points
    keys = np.round(dataset.points, 12)
    assert len(np.unique(keys[~dataset.duplicate], axis=0)) == len(np.unique(keys, axis=0)) == n_points
    first = _rows(dataset.points[~dataset.duplicate], dataset.points)
    for name, values in dataset.point_data.items():
        assert np.array_equal(values, values[~dataset.duplicate][first]), name


def test_write_contact_results(solution, mpi_tmp_path):
    """Files and summary: the same counts on any number of ranks; integrals match the summary."""
    problem, u, result = solution
    comm = problem.comm
    summary = write_contact_results(mpi_tmp_path / "run", problem, u, result, plot=True)
    assert summary["files"] == ["body.bp", "contact_surface.bp", "solution.npz", "contact_states.png", "bodies.png"]
    assert summary["equilibrium_error"] < 1e-8
    assert set(summary["units"]) <= set(UNITS) and summary["units"]["contact_force"] == "N"
    assert summary["contact_area"] == pytest.approx(summary["sticking_area"] + summary["sliding_area"])
    assert sum(summary["state_counts"].values()) == problem.n_contact
    assert set(summary["state_counts"]) == set(STATE_NAMES.values())
    assert json.loads(json.dumps(to_builtin(summary))) is not None  # JSON-ready
    if comm.rank != 0:
        return
    sizes = meshes.contact_body_sizes(LEV)
    nx1, nx2, nx3 = sizes["nx1"], sizes["nx2"], sizes["nx3"]

    volume = read_vtx(mpi_tmp_path / "run" / "body.bp")
    _assert_points(volume, (nx1 + 1) * (nx2 + 1) * (nx3 + 1))
    assert volume.cells.shape == (nx1 * nx2 * nx3, 8)
    assert set(volume.point_data) == {"displacement [m]"}
    assert set(volume.cell_data) == {"stress [Pa]", "von_mises [Pa]"}
    assert volume.cell_data["stress [Pa]"].shape == (nx1 * nx2 * nx3, 9)
    assert _box_volumes(volume).sum() == pytest.approx(2.0 * 1.0 * (1.0 - 0.01), rel=1e-12)
    assert volume.cell_data["von_mises [Pa]"].max() == pytest.approx(summary["max_von_mises"], rel=1e-14)

    surface = read_vtx(mpi_tmp_path / "run" / "contact_surface.bp")
    n_nodes, n_edges, n_facets = (nx1 + 1) * (nx2 + 1), nx1 * (nx2 + 1) + (nx1 + 1) * nx2, nx1 * nx2
    _assert_points(surface, n_nodes + n_edges + n_facets)
    assert surface.cells.shape == (4 * n_facets, 4)
    assert set(surface.point_data) == {f"{name} [{UNITS[name]}]"
                                       for name in FIELDS - {"contact_state", "contact_pair", "nodal_area"}}
    assert set(surface.cell_data) == {"contact_state", "contact_pair", "is_open", "is_in_contact", "is_sliding",
                                      "is_sticking"}
    area = _patch_areas(surface)
    assert area.sum() == pytest.approx(2.0, rel=1e-12)
    cells = surface.cell_data
    assert np.array_equal(cells["is_open"] + cells["is_sliding"] + cells["is_sticking"], np.ones(len(area)))
    assert area @ cells["is_sticking"] == pytest.approx(summary["sticking_area"], rel=1e-12)
    assert area @ cells["is_sliding"] == pytest.approx(summary["sliding_area"], rel=1e-12)
    assert area @ cells["is_in_contact"] == pytest.approx(summary["contact_area"], rel=1e-12)
    # Bilinear pressure on rectangles: its integral is the total normal force (lumped areas).
    pressure = surface.point_data["contact_pressure [Pa]"][surface.cells].mean(axis=1)
    assert area @ pressure == pytest.approx(summary["contact_force"][2], rel=1e-12)
    traction = surface.point_data["friction_traction [Pa]"][surface.cells].mean(axis=1)
    assert area @ traction[:, 0] == pytest.approx(summary["contact_force"][0], rel=1e-12)


def test_demo_writes_contact_surface(mpi_tmp_path, load_demo):
    out = mpi_tmp_path / "run"
    assert load_demo("coulomb3d").main(["--lev", "1", "--output", str(out), "--no-plot"]) == 0
    sizes = meshes.contact_body_sizes(1)
    if MPI.COMM_WORLD.rank == 0:
        surface = read_vtx(out / "contact_surface.bp")
        assert surface.cells.shape == (4 * sizes["nx1"] * sizes["nx2"], 4)
        assert "contact_state" in surface.cell_data
        summary = json.loads((out / "summary.json").read_text())
        assert summary["equilibrium_error"] < 1e-8 and summary["units"]["contact_force"] == "N"
    assert not (out / "contact_states.png").exists()


def test_bodies_picture(solution, mpi_tmp_path):
    """The 3D picture of the deformed body and its contact surface: a 2800 x 1200 PNG, the left
    1600 columns the body coloured by von Mises stress, the right ones the contact surface by
    contact pressure (each many colours, not a blank or single-colour image)."""
    import matplotlib.image

    problem, u, result = solution
    write_contact_results(mpi_tmp_path / "picture", problem, u, result, plot=True, solution_npz=False)
    if problem.comm.rank == 0:
        image = matplotlib.image.imread(mpi_tmp_path / "picture" / "bodies.png")
        assert image.shape[:2] == (1200, 2800)
        background = image[0, -1, :3]
        for panel, size in ((image[:, :1400, :3], 1400 * 1200), (image[:, 1400:, :3], 1400 * 1200)):
            drawn = panel[np.any(np.abs(panel - background) > 0.05, axis=-1)]
            assert len(drawn) > 0.05 * size  # the body (the surface) fills a good part of its panel
            assert len(np.unique(np.round(drawn * 32), axis=0)) > 20  # a colour map, not one colour


@pytest.mark.one_rank(reason="figure and patch geometry on small numpy arrays, drawn without a mesh")
def test_bodies_picture_looks_at_the_largest_stress_and_spans_its_decades():
    """The camera of ``bodies.png`` is on the side of the largest stress (a quarter model's
    contact lies at its symmetry planes, x = y = 0 here, which a view from the positive
    octant would hide), and stresses spanning decades get a log colour scale."""
    from contactqvi.contact.figure_data import camera_direction, robust_scale

    centres = np.random.default_rng(1).uniform([0.0, 0.0, -1.0], [1.0, 1.0, 0.0], size=(500, 3))
    stress = 1e4 + 1e9 * np.exp(-50.0 * np.sum(centres**2, axis=1))  # peaks at the contact, (0, 0, 0)
    direction = camera_direction(centres, stress)
    assert np.allclose(np.linalg.norm(direction), 1.0) and np.all(np.sign(direction) == [-1.0, -1.0, 1.0])
    assert np.isclose(np.degrees(np.arcsin(direction[2])), 35.0)
    scale = robust_scale("von Mises stress", stress, centres, "cells", stress_map=True)
    assert scale.log and scale.high <= stress.max() and scale.largest == stress.max()
    linear = robust_scale("von Mises stress", np.array([2.0, 3.0, 5.0]), np.zeros((3, 3)), "cells", stress_map=True)
    assert not linear.log and linear.low == 0.0  # within two decades: linear from zero


@pytest.mark.one_rank(reason="figure and patch geometry on small numpy arrays, drawn without a mesh")
def test_tributary_patches_of_triangles():
    """Triangles are cut into three quadrilaterals of a third of their area each (the lumped P1 area)."""
    points = np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 1.0, 0.0], [2.0, 1.0, 0.0]])
    cells = np.array([[0, 1, 2], [1, 3, 2]])
    state = np.array([State.STICKING, State.SLIDING, State.NO_CONTACT, State.SLIDING], dtype=float)
    pair = np.array([0, 1, -1, 1], dtype=float)
    patches = TributaryPatches(points, cells).dataset({"f [m]": points[:, 0] + points[:, 1]}, state, pair)
    assert patches.cells.shape == (6, 4) and len(patches.points) == 4 + 5 + 2 and not np.any(patches.duplicate)
    area = _patch_areas(patches)
    assert np.allclose(area, 1.0 / 3.0, rtol=1e-14)  # each triangle has area 1
    assert np.allclose(patches.point_data["f [m]"], patches.points[:, 0] + patches.points[:, 1], rtol=1e-14)
    owner = patches.cells[:, 0]
    assert np.array_equal(patches.cell_data["contact_state"], state[owner])
    assert np.array_equal(patches.cell_data["contact_pair"], pair[owner])
    # node 1: 2/3, node 3: 1/3; node 2 has no contact law: its patches take the shares of
    # their facet's other nodes (first facet: 1/2 sliding, 1/2 sticking; second: sliding)
    assert area @ patches.cell_data["is_sliding"] == pytest.approx(1.5)
    assert area @ patches.cell_data["is_sticking"] == pytest.approx(0.5)
    normals = np.cross(*np.moveaxis(patches.points[patches.cells[:, [1, 3]]] - patches.points[owner][:, None], 1, 0))
    assert np.all(normals[:, 2] > 0)  # oriented as the facets
    # a rank without contact facets (two-body cases on 2 ranks) writes an empty piece; its
    # indicators raised there once, and the other rank waited in the collective write
    empty = TributaryPatches(points, np.zeros((0, 3), dtype=cells.dtype)).dataset({}, state, pair)
    assert empty.cells.shape == (0, 4) and len(empty.cell_data["is_in_contact"]) == 0
