"""scripts/paraview/pv_views.py reads what contactqvi writes (no ParaView needed).

The script lists its files (``SOURCES``) and fields (``FIELDS``) in one place; this
test checks that list against a fresh demo result, and the parts of the views that
need no ParaView: the step and obstacle read from ``summary.json``, and the frame a
contact surface is seen in (VTK only, as pyvista installs it).
"""

from __future__ import annotations

import importlib.util
import json
import pathlib
import xml.etree.ElementTree as ET

from mpi4py import MPI

import numpy as np
import pytest

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
    assert last["obstacle"] == plane and last["translation"] == steps[2]["translation"]
    assert "step 3 of 3" in last["label"]
    assert first["translation"] == steps[0]["translation"] and "step 1 of 3" in first["label"]
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
