"""scripts/paraview/pv_views.py reads what contactqvi writes (no ParaView needed).

The script lists its files (``SOURCES``) and fields (``FIELDS``) in one place; this
test checks that list against a fresh demo result, and the parts of the views that
need no ParaView: the step and obstacle read from ``summary.json``, and the frame a
contact surface is seen in (VTK only, as pyvista installs it). For a dynamic result
(``pv_time.py``): its detection, the frames chosen from the contact force (on the shipped
drop test too), the obstacles' motion, the colour range, the errors that name a missing
key, field or file; and, run by ``make paraview-dynamics`` (``-m paraview``, which installs
ParaView), the drop test rendered by ``scripts/paraview/run.sh``.
"""

from __future__ import annotations

import importlib.util
import json
import pathlib
import shutil
import subprocess
import xml.etree.ElementTree as ET

from mpi4py import MPI

import numpy as np
import pytest
from shipped_runs import group

ROOT = pathlib.Path(__file__).resolve().parent.parent
SCRIPT = ROOT / "scripts" / "paraview" / "pv_views.py"
DATA = ROOT / "tests" / "data" / "pictures"


@pytest.fixture(scope="module")
def pv_views():
    spec = importlib.util.spec_from_file_location("pv_views", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)  # imports ParaView only inside its functions
    return module


def field_names(path: pathlib.Path) -> list[str]:
    """Names of the fields in a VTX (.bp) directory."""
    import adios2

    with adios2.FileReader(str(path)) as reader:
        vtk_xml = reader.available_attributes()["vtk.xml"]["Value"].strip('"')
    return [a.get("Name") for a in ET.fromstring(vtk_xml).iter("DataArray") if a.get("Name")]


def test_field_matches(pv_views):
    for found in ("von_mises", "von_mises [Pa]", "von_mises (Pa)", "von_mises_Pa"):
        assert pv_views.field_matches(found, "von_mises")
    for found in ("von_mises_max", "von", "displacement [m]", "von_mises [kg]"):
        assert not pv_views.field_matches(found, "von_mises")


def test_demo_output_has_the_fields(pv_views, load_demo, mpi_tmp_path):
    out = mpi_tmp_path / "coulomb"
    assert load_demo("coulomb3d").main(["--lev", "1", "--output", str(out), "--no-plot"]) == 0
    MPI.COMM_WORLD.Barrier()
    for role, name in pv_views.SOURCES.items():
        assert (out / name).exists(), f"{name} not written"
        names = field_names(out / name)
        for field, (dataset, required, *_) in pv_views.FIELDS.items():
            if dataset == role and required:
                assert any(pv_views.field_matches(n, field) for n in names), (field, names)


def test_state_names(pv_views):
    """The legend uses the contact-state names of the package's own output."""
    from contactqvi.contact.postprocess import STATE_NAMES

    assert {int(state): name for state, name in STATE_NAMES.items()} == {
        state: label for state, (label, _) in pv_views.CONTACT_STATES.items()
    }


def test_step_and_obstacle_from_the_summary(pv_views, mpi_tmp_path):
    """A case result: its obstacle and the translation of the step shown (the last by default)."""
    comm = MPI.COMM_WORLD
    plane = {"type": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0]}
    steps = [{"step": k, "converged": True, "translation": [0.0, 0.0, -0.1 * k]} for k in (1, 2, 3)]
    if comm.rank == 0:
        (mpi_tmp_path / "summary.json").write_text(json.dumps({"case": {"obstacle": plane}, "steps": steps}))
    comm.Barrier()
    last, first = pv_views.describe(mpi_tmp_path, -1), pv_views.describe(mpi_tmp_path, 1)
    assert last["obstacle"] == plane and last["step"]["translation"] == steps[2]["translation"]
    assert "step 3 of 3" in last["label"]
    assert first["step"]["translation"] == steps[0]["translation"] and "step 1 of 3" in first["label"]
    assert pv_views.describe(mpi_tmp_path / "nothing", -1)["obstacle"] is None  # the paper demo: no obstacle


@pytest.mark.parametrize("normal", [(0.0, 0.0, 1.0), (np.sin(0.35), 0.0, np.cos(0.35)), (0.0, -1.0, 0.0)])
def test_a_surface_is_seen_along_its_normal_from_its_body(pv_views, normal):
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonCore import vtkPoints
    from vtkmodules.vtkCommonDataModel import vtkPolyData

    import pv_common

    n = np.asarray(normal)
    e1, e2 = pv_common.plane_basis(n)
    s, t = np.meshgrid(np.linspace(0, 2, 5), np.linspace(0, 1, 3))
    x = np.outer(s.ravel(), e1) + np.outer(t.ravel(), e2) + [0.3, 0.2, 0.1]
    surface = vtkPolyData()
    surface.SetPoints(vtkPoints())
    surface.GetPoints().SetData(numpy_to_vtk(x, deep=True))
    centre, f1, f2, f3 = pv_common.surface_frame(surface, x.mean(axis=0) + 0.5 * n)  # the body on the +n side
    assert np.allclose(f3, n) and np.allclose(np.cross(f1, f2), f3) and np.isclose(np.dot(f1, f2), 0.0)
    assert np.allclose(centre, x.mean(axis=0))
    if normal == (0.0, 0.0, 1.0):  # seen from +x3: x1 to the right, x2 up
        assert np.allclose(f1, [1, 0, 0]) and np.allclose(f2, [0, 1, 0])


@pytest.mark.one_rank(reason="the deformed view's scale rule, serial arithmetic")
def test_the_deformed_view_is_true_to_scale_at_finite_strain_and_where_bodies_touch(pv_views):
    """The rubber pad (finite strain, 4 mm on a 40 mm pad) is drawn at true scale, not
    "magnified x0.2"; a linear body is magnified only when nothing touches, never shrunk."""
    import pv_body

    assert pv_body.drawing_scale(4e-3, 0.04, finite=True, touching=True) == (1.0, "true scale (finite strain)")
    assert pv_body.drawing_scale(1e-6, 0.04, finite=False, touching=True)[0] == 1.0
    scale, words = pv_body.drawing_scale(1e-6, 0.04, finite=False, touching=False)
    assert scale == 2000.0 and words == "displacement magnified \u00d72000 (nothing touches)"
    assert pv_body.drawing_scale(4e-3, 0.04, finite=False, touching=False) == (1.0, "true scale")


@pytest.mark.one_rank(reason="colour bar geometry, serial arithmetic")
def test_colour_bar_titles_fit_in_the_image(pv_views):
    import pv_common

    titles = ("nominal contact pressure (MPa)", "Cauchy / nominal contact pressure (MPa)", "von Mises stress (MPa)")
    for title in titles:
        left = pv_common.bar_left(title, 0.86)
        assert left * pv_common.IMAGE_SIZE[0] + 0.55 * pv_common.FONT * len(title) < pv_common.IMAGE_SIZE[0]
    assert pv_common.bar_left("contact state", 0.72) == 0.72


@pytest.mark.parametrize("name", ["rubber_pad", "hertz_bodies", "seal"])
def test_paraview_names_the_pressure_as_contactqvi_does(pv_views, name):
    """ParaView's name of the contact pressure, read from the summary's case, is the one the
    problem gives (contactqvi.contact.surface.pressure_label): Cauchy for the rubber pad
    (neo-Hookean, searched until settled), nominal for linear Hertz and for the seal (neo-Hookean,
    searched once: reference areas)."""
    from contactqvi.case import load_case
    from contactqvi.contact.surface import pressure_label
    from contactqvi.runner import build_problem
    from shipped_runs import shipped_case

    import pv_common

    case = load_case(DATA / "seal_half_nu0.45.toml") if name == "seal" else shipped_case(name)
    with build_problem(case, MPI.COMM_WORLD) as problem:
        label = pressure_label(problem)
    assert label == pv_common.pressure_name(case.to_dict())
    assert label == {"rubber_pad": "Cauchy", "hertz_bodies": "nominal", "seal": "nominal"}[name] + " contact pressure"
    described = pv_views.describe(ROOT / "nothing", -1)
    assert described["pressure"] == "nominal contact pressure" and described["finite_strain"] is False


@pytest.mark.one_rank(reason="colour ranges of numpy arrays, serial arithmetic")
def test_paraview_colours_the_pressure_as_the_pictures_do(pv_views):
    """The traction view's colours end where bodies.png's do: corner nodes do not set them."""
    from contactqvi.contact.figure_data import robust_scale

    import pv_common

    rng = np.random.default_rng(5)
    pressure = np.concatenate([np.zeros(20), rng.uniform(62e6, 123e6, 61), [193e6, 215e6, 300e6, 314e6]])
    top = pv_common.robust_top(pressure)
    assert top < 193e6
    assert top == pytest.approx(robust_scale("p", pressure[pressure > 0], np.zeros((65, 3)), "nodes").high, rel=1e-14)
    assert pv_common.robust_top(np.zeros(4)) == 0.0


def timed_steps(forces, dt=1e-5):
    """Summary entries of a dynamic run with these contact forces (N, along x3)."""
    return [{"step": k + 1, "converged": True, "time": (k + 1) * dt, "contact_force": [0.0, 0.0, f]}
            for k, f in enumerate(forces)]  # fmt: skip


@pytest.mark.one_rank(reason="the choice of frames from a summary, serial arithmetic")
def test_the_frames_over_time_follow_the_contact_force(pv_views):
    """Before contact, first contact, the peak force, separation and the end, each on its step;
    events on one step share a frame; a run without contact is filled up to MIN_FRAMES."""
    import pv_time

    forces = [0.0, 0.0, 1e-9, 5.0, 9.0, 4.0, 1e-7, 0.0, 0.0, 0.0]  # 1e-9, 1e-7: round-off, no contact
    assert pv_views.chosen_frames(timed_steps(forces)) == [
        (0, "first step"), (2, "before contact"), (3, "first contact"), (4, "peak contact force"),
        (6, "separation"), (9, "end")]  # fmt: skip
    assert pv_views.chosen_frames(timed_steps([3.0, 2.0, 1.0, 0.0, 0.0, 0.0])) == [
        (0, "first step, first contact, peak contact force"), (1, ""), (3, "separation"), (5, "end")]
    assert pv_views.chosen_frames(timed_steps([0.0] * 9)) == [(0, "first step"), (2, ""), (4, ""), (8, "end")]
    assert pv_views.chosen_frames(timed_steps([1.0])) == [(0, "first step, first contact, peak contact force, end")]
    assert pv_time.time_unit(679.4e-6) == ("\u00b5s", 1e6) and pv_time.time_unit(0.374)[0] == "ms"
    assert pv_time.time_unit(2.0) == ("s", 1.0)


@pytest.mark.one_rank(reason="the detection of a dynamic summary, serial arithmetic")
def test_a_dynamic_result_is_told_by_its_summary(pv_views):
    """A scheme and timed steps make the views over time; a quasi-static summary, or none, does not.
    A step without a key the frames are chosen from, a missing velocity field or a missing
    summary.json (``--time``) stop the script with their names."""
    import pv_common
    import pv_time

    dynamic = {"scheme": {"name": "newmark"}, "steps": timed_steps([0.0, 1.0])}
    assert pv_views.is_dynamic(dynamic)
    assert not pv_views.is_dynamic({"steps": [{"step": 1, "converged": True, "translation": [0, 0, 0]}]})
    assert not pv_views.is_dynamic(pv_common.read_summary(ROOT / "nothing"))
    with pytest.raises(pv_common.ResultError, match=r"summary.json: step 2 has no 'contact_force'"):
        del dynamic["steps"][1]["contact_force"]
        pv_time.written_steps(dynamic, "summary.json")
    with pytest.raises(pv_common.ResultError, match=r"field 'velocity' \(velocity\) not in .*body.bp"):
        pv_common.field_name(["displacement [m]", "acceleration [m/s^2]"], "velocity", "out/body.bp", required=True)
    assert pv_common.field_name(["velocity [m/s]"], "velocity", "out/body.bp", required=True) == "velocity [m/s]"
    with pytest.raises(pv_common.ResultError, match=r"nothing/summary.json"):
        pv_common.read_summary(ROOT / "nothing", required=True)


def _zxy(angles):
    """R_z R_x R_y of ParaView's ``Transform.Rotate`` (degrees about x, y, z; checked against
    pvbatch: a point of a PointSource under Translate = (1, 2, 3), Rotate = (20, 35, 50))."""
    a, b, c = np.radians(angles)
    Rx = np.array([[1.0, 0.0, 0.0], [0.0, np.cos(a), -np.sin(a)], [0.0, np.sin(a), np.cos(a)]])
    Ry = np.array([[np.cos(b), 0.0, np.sin(b)], [0.0, 1.0, 0.0], [-np.sin(b), 0.0, np.cos(b)]])
    Rz = np.array([[np.cos(c), -np.sin(c), 0.0], [np.sin(c), np.cos(c), 0.0], [0.0, 0.0, 1.0]])
    return Rz @ Rx @ Ry


@pytest.mark.one_rank(reason="3 x 3 matrices")
@pytest.mark.parametrize("axis, angle", [((0.0, 1.0, 0.0), 10.0), ((1.0, -2.0, 0.5), 73.0), ((1.0, 0.0, 0.0), 90.0),
                                         ((0.0, 0.0, 1.0), -135.0), ((0.3, 0.4, -0.2), 0.0)])
def test_the_obstacles_are_drawn_where_the_step_has_them(pv_views, axis, angle):
    """ParaView's Transform of a step's obstacle motion (translation t, rotation Q about c) maps every
    point X to Q (X - c) + c + t (contactqvi.load_steps.Rotation's Q), also where the x angle is
    90 degrees (gimbal lock); magnified, the angle and t scale alike; a step without a motion
    stays in place."""
    from contactqvi.load_steps import Rotation

    import pv_body

    centre, t = (0.2, -0.1, 0.05), (0.01, 0.02, -0.3)
    X = np.random.default_rng(3).standard_normal((6, 3))
    for scale in (1.0, 20.0):
        step = {"translation": list(t), "rotation": {"axis": list(axis), "angle": angle, "centre": list(centre)}}
        translate, rotate = pv_body.obstacle_transform(step, scale)
        Q = Rotation(axis, scale * angle, centre).matrix()
        expected = (X - centre) @ Q.T + centre + scale * np.asarray(t)
        assert X @ _zxy(rotate).T + translate == pytest.approx(expected, abs=1e-12)
    assert pv_body.obstacle_transform({"translation": [0.0, 0.0, -0.1]}, 2.0) == ([0.0, 0.0, -0.2], [0.0, 0.0, 0.0])
    assert pv_body.obstacle_transform({}) == ([0.0, 0.0, 0.0], [0.0, 0.0, 0.0])


def test_the_state_file_moves_the_obstacles_with_the_time(pv_views, monkeypatch):
    """The animation cue of ``paraview_time.pvsm`` puts each obstacle's Transform where the written
    step at or before the animation's time has it (here with a stand-in for paraview.simple)."""
    import sys
    import types

    import pv_body
    import pv_time

    turn = {"axis": [0, 0, 1], "centre": [0, 0, 0]}
    steps = [{"translation": [0.1 * k, 0.0, 0.0], "rotation": {**turn, "angle": 5.0 * k}} for k in range(4)]
    times = [0.0, 0.1, 0.2, 0.3]
    transforms = {f"obstacle {k}": types.SimpleNamespace(Transform=types.SimpleNamespace()) for k in (1, 2)}
    scene = types.SimpleNamespace(AnimationTime=0.0)
    simple = types.SimpleNamespace(FindSource=transforms.__getitem__, GetAnimationScene=lambda: scene)
    monkeypatch.setitem(sys.modules, "paraview", types.SimpleNamespace(simple=simple))
    monkeypatch.setitem(sys.modules, "paraview.simple", simple)
    cue = {}
    exec(pv_time.obstacle_cue_script(steps, times, 2.0, 2), cue)
    for time, index in ((0.0, 0), (0.15, 1), (0.2, 2), (0.29, 2), (1.0, 3)):
        scene.AnimationTime = time
        cue["tick"](None)
        translate, rotate = pv_body.obstacle_transform(steps[index], 2.0)
        for obstacle in transforms.values():
            assert obstacle.Transform.Translate == pytest.approx(translate, abs=1e-15)
            assert obstacle.Transform.Rotate == pytest.approx(rotate, abs=1e-12)


@pytest.mark.one_rank(reason="colour ranges of numpy arrays, serial arithmetic")
def test_a_few_ringing_nodes_do_not_set_the_colours_over_time(pv_views):
    """The speeds' colours end at the largest speed of the run unless a few nodes ring far above
    the rest (the drop test's contact tip after separation: 7.6 m/s, the ball 1 m/s)."""
    import pv_time

    rng = np.random.default_rng(3)
    speeds = rng.uniform(0.0, 1.0, 5000)
    assert pv_time.speed_top(speeds) == speeds.max()
    ringing = np.concatenate([speeds, rng.uniform(2.0, 7.6, 20)])
    assert pv_time.speed_top(ringing) == pytest.approx(np.percentile(speeds, 99), rel=0.01)


@group("drop_test")
def test_the_drop_test_frames(pv_views, shipped_runs):
    """The shipped drop test is told dynamic by its summary.json, its body.bp holds the fields of
    the frames, and they fall where Hertz's impact has its events: contact from the first step,
    the peak force at t_c / 2, separation at t_c = 522.7 us (cases/drop_test.toml)."""
    import pv_common

    shipped_runs.steps("drop_test")
    out = shipped_runs["drop_test"]["output"]
    summary = pv_common.read_summary(out, required=True)
    assert pv_views.is_dynamic(summary)
    names = field_names(out / pv_common.SOURCES["volume"])
    assert all(pv_common.field_name(names, name, "body.bp", required=True) for name in ("displacement", "velocity"))
    frames = pv_views.chosen_frames([step for step in summary["steps"] if step["converged"]])
    assert [what for _, what in frames] == ["first step, first contact", "peak contact force", "separation", "end"]
    t_c, dt = 522.7e-6, summary["case"]["dynamics"]["dt"]
    times = [summary["steps"][index]["time"] for index, _ in frames]
    assert abs(times[1] - t_c / 2) < dt and abs(times[2] - t_c) < dt and times[3] == summary["steps"][-1]["time"]


@pytest.mark.serial
@pytest.mark.paraview
@group("drop_test")
def test_paraview_renders_the_drop_test_over_time(pv_views, shipped_runs, mpi_tmp_path):
    """scripts/paraview/run.sh on the drop test: the frames and the state file; without its
    summary.json, ``--time`` stops with exit code 2 and names it."""
    import pv_common
    import pv_time

    shipped_runs.steps("drop_test")
    shipped, result = shipped_runs["drop_test"]["output"], mpi_tmp_path / "drop_test"
    result.mkdir()
    shutil.copytree(shipped / pv_common.SOURCES["volume"], result / pv_common.SOURCES["volume"])
    shutil.copy(shipped / pv_common.SUMMARY, result)
    run = subprocess.run(["bash", str(SCRIPT.parent / "run.sh"), str(result), str(mpi_tmp_path / "images")],
                         capture_output=True, text=True, timeout=300)  # fmt: skip
    assert run.returncode == 0, run.stdout + run.stderr
    frames = sorted((mpi_tmp_path / "images").glob("paraview_time_*.png"))
    assert [frame.name for frame in frames] == [pv_time.FRAME_NAME.format(k) for k in (1, 2, 3, 4)]
    assert all(frame.read_bytes()[16:24] == bytes([0, 0, 6, 64, 0, 0, 3, 132]) for frame in frames)  # 1600 x 900
    state = (result / pv_time.STATE).read_text()
    assert str(result / "body.bp") in state and "TRANSFORMS = " in state  # the obstacles' cue
    (result / pv_common.SUMMARY).unlink()
    run = subprocess.run(["bash", str(SCRIPT.parent / "run.sh"), str(result), str(mpi_tmp_path / "images"), "--time"],
                         capture_output=True, text=True, timeout=300)  # fmt: skip
    assert run.returncode == 2 and f"{result / 'summary.json'}: " in run.stderr, run.stdout + run.stderr
