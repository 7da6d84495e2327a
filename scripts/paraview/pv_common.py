"""Shared pieces of the ParaView views (``pv_views.py``): what a result holds, reading it, drawing.

Imports of ParaView and VTK are inside the functions: the tables and
:func:`field_matches` load in any Python (``tests/test_paraview_script.py``).
"""

from __future__ import annotations

import json
import os

import numpy as np

#: The file of each dataset of a result directory.
SOURCES = {"volume": "body.bp", "surface": "contact_surface.bp"}
#: The run's description: its case, its steps (their times and contact forces in a dynamic result).
SUMMARY = "summary.json"

#: Fields: name -> (dataset, required, label, unit in the files, unit shown, factor from the
#: file's unit to the shown one). A name also matches with a unit suffix ("von_mises [Pa]").
FIELDS = {
    "displacement": ("volume", True, "displacement", "m", "mm", 1e3),
    "velocity": ("volume", False, "velocity", "m/s", "m/s", 1.0),  # a dynamic result's (pv_time.py)
    "von_mises": ("volume", False, "von Mises stress", "Pa", "MPa", 1e-6),
    "contact_pressure": ("surface", True, "contact pressure", "Pa", "MPa", 1e-6),
    "friction_traction": ("surface", True, "friction traction", "Pa", "MPa", 1e-6),
    "contact_state": ("surface", True, "contact state", "", "", 1.0),
}

#: Values of ``contact_state`` -> (label, RGB): the names of contactqvi.contact.postprocess.STATE_NAMES
#: and the (colour-blind safe, Okabe-Ito) colours of its contact_states.png.
CONTACT_STATES = {
    0: ("no contact", (0.851, 0.851, 0.851)),
    1: ("sliding", (0.902, 0.624, 0.0)),
    2: ("sticking", (0.0, 0.447, 0.698)),
    3: ("grazing, sliding", (0.941, 0.894, 0.259)),
    4: ("sticking on the cone boundary", (0.337, 0.706, 0.914)),
    5: ("grazing, at rest", (0.8, 0.475, 0.655)),
    6: ("separated, sticking (Tresca)", (0.0, 0.62, 0.451)),
}
ALWAYS_IN_LEGEND = (0, 1, 2)
#: Corner of each tributary patch (node, edge midpoint, facet centre, edge midpoint) that is its node.
PATCH_NODE_CORNER = 0
UNIT_SUFFIXES = ("m", "Pa", "MPa", "1", "m/s")
IMAGE_SIZE = (1600, 900)
FONT = 22


#: The contact pressure's kinds, as contactqvi.contact.surface.PRESSURE_DEFINITIONS names them.
PRESSURE_KINDS = ("Cauchy", "nominal")
#: Searches in the current configuration each step (contactqvi.load_steps.SEARCHES).
SEARCHED_EACH_STEP = ("every_step", "until_settled", "newton")


def finite_strain(case):
    """Whether the summary's ``case`` has a hyperelastic body (a ``model`` in a material)."""
    materials = [case.get("material") or {}] + [body.get("material") or {} for body in case.get("bodies") or []]
    return any(material.get("model") for material in materials)


def obstacles_of(case):
    """The rigid obstacles of the summary's ``case``: its ``obstacle`` and those of its ``contacts``."""
    obstacles = [case["obstacle"]] if case.get("obstacle") else []
    return obstacles + [pair["obstacle"] for pair in case.get("contacts") or [] if pair.get("obstacle")]


def read_summary(result_dir, required=False):
    """The result's ``summary.json``; {} when it is missing or unreadable, unless ``required``."""
    path = os.path.join(result_dir, SUMMARY)
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError) as error:
        if required:
            raise ResultError(f"{path}: {error} (SUMMARY in {os.path.basename(__file__)})") from error
        return {}


def pressure_name(case):
    """The contact pressure's name, as contactqvi.contact.surface.pressure_label gives it:
    Cauchy for a pair searched each step of a hyperelastic body, nominal otherwise (small
    strain, or searched once); both joined when the pairs differ. A result without a case
    (the paper's demo) is linear: nominal."""
    pairs = list(case.get("contacts") or []) + ([case["contact"]] if case.get("contact") else [])
    kinds = {"Cauchy" if finite_strain(case) and pair.get("search", "every_step" if "master" in pair else "once")
             in SEARCHED_EACH_STEP else "nominal" for pair in pairs} or {"nominal"}
    return " / ".join(kind for kind in PRESSURE_KINDS if kind in kinds) + " contact pressure"


#: Tukey's fence of the pressure's colours, as contactqvi.contact.figure_data.FENCE.
FENCE = 1.5


def robust_top(values):
    """The top of a contact pressure's colours as contactqvi's bodies.png takes it: the 99th
    percentile of the positive (pressing) ``values``, at most FENCE interquartile ranges above
    the upper quartile, so that a few corner nodes at symmetry planes do not set it; 0 for none.
    The same for the speeds of a dynamic result (pv_time.py): a few ringing nodes do not set it."""
    pressing = np.asarray(values)[np.asarray(values) > 0.0]
    if len(pressing) == 0:
        return 0.0
    lower, upper, last = np.percentile(pressing, [25.0, 75.0, 99.0])
    return float(min(last, upper + FENCE * (upper - lower)))


def bar_left(title, position):
    """The left edge (fraction of the image) of a vertical colour bar at ``position`` moved left
    as far as its horizontal ``title`` (FONT, bold) needs to fit in the image."""
    width = 0.62 * FONT * len(title) + 24  # pixels: a generous average glyph width
    return min(position, 1.0 - width / IMAGE_SIZE[0])


class ResultError(Exception):
    """A file, field or step this script needs is not in the result directory."""


def field_matches(found, name):
    """Whether the array name ``found`` is field ``name``, bare or with a unit suffix
    ("von_mises", "von_mises [Pa]", "von_mises (Pa)", "von_mises_Pa")."""
    rest = found[len(name):] if found.startswith(name) else None
    return rest == "" or (rest is not None and rest[:1] in " [(_" and rest.strip(" []()_") in UNIT_SUFFIXES)


def open_vtx(path):
    """An ``ADIOS2VTXReader`` of the VTX file ``path`` and its times (a list, [0.0] for none)."""
    from paraview import simple

    if not os.path.exists(path):
        raise ResultError(f"{path}: not found (SOURCES in {os.path.basename(__file__)})")
    reader = simple.ADIOS2VTXReader(FileName=os.path.abspath(path))
    times = getattr(reader, "TimestepValues", None) or [0.0]
    return reader, [times] if isinstance(times, float) else list(times)  # one step: ParaView gives a number


def grid_at(reader, time, where):
    """The data of ``reader`` at ``time`` as one unstructured grid: the pieces of the ranks that
    wrote the file appended; ``where`` names the file and step in an error."""
    from paraview import servermanager
    from vtkmodules.vtkFiltersCore import vtkAppendFilter

    reader.UpdatePipeline(time)
    data = servermanager.Fetch(reader)
    append = vtkAppendFilter()
    leaves = [data]
    if data.IsA("vtkCompositeDataSet"):
        leaves, it = [], data.NewIterator()
        it.InitTraversal()
        while not it.IsDoneWithTraversal():
            leaves.append(it.GetCurrentDataObject())
            it.GoToNextItem()
    for leaf in leaves:
        if leaf is not None and leaf.GetNumberOfPoints():
            append.AddInputData(leaf)
    if not append.GetNumberOfInputConnections(0):
        raise ResultError(f"{where}: no data (an empty or unfinished file?)")
    append.Update()
    return append.GetOutput()


def read_grid(path, step):
    """Step ``step`` (1-based, negative from the end) of the VTX file ``path`` as one unstructured grid."""
    from paraview import simple

    reader, times = open_vtx(path)
    index = step - 1 if step > 0 else step
    if step == 0 or not -len(times) <= index < len(times):
        raise ResultError(f"{path}: no step {step}; it holds {len(times)} (--step 1 ... {len(times)})")
    grid = grid_at(reader, times[index], f"{path} at step {step}")
    simple.Delete(reader)
    return grid


def field_name(names, name, where, required=None):
    """The one of ``names`` (a dataset's arrays) that is field ``name`` (:func:`field_matches`); None
    when it is missing and optional, a ResultError naming it when it is required (``required``, or
    as ``FIELDS`` says)."""
    found = next((found for found in names if field_matches(found or "", name)), None)
    if found is None and (FIELDS[name][1] if required is None else required):
        raise ResultError(f"field '{name}' ({FIELDS[name][2]}) not in {where} (FIELDS in {os.path.basename(__file__)})")
    return found


def field(grid, name, where, required=None):
    """(association, numpy array, its name) of field ``name`` (``FIELDS``); None for a missing
    optional one (``required`` overrides ``FIELDS``)."""
    from vtkmodules.util.numpy_support import vtk_to_numpy

    for association, data in (("POINTS", grid.GetPointData()), ("CELLS", grid.GetCellData())):
        found = field_name([data.GetArrayName(i) for i in range(data.GetNumberOfArrays())], name, where, False)
        if found is not None:
            return association, vtk_to_numpy(data.GetArray(found)), found
    return field_name([], name, where, required)  # raises for a required field


def add_array(grid, association, name, values):
    from vtkmodules.util.numpy_support import numpy_to_vtk

    array = numpy_to_vtk(np.ascontiguousarray(values, dtype=np.float64), deep=True)
    array.SetName(name)
    (grid.GetPointData() if association == "POINTS" else grid.GetCellData()).AddArray(array)


def producer(grid):
    from paraview import simple

    source = simple.PVTrivialProducer()
    source.GetClientSideObject().SetOutput(grid)
    source.UpdatePipeline()
    return source


def points_of(grid):
    from vtkmodules.util.numpy_support import vtk_to_numpy

    return vtk_to_numpy(grid.GetPoints().GetData()).astype(float)


def patch_nodes(grid):
    """Point ids of the nodes of a tributary-patch surface (corner PATCH_NODE_CORNER of each cell)."""
    from vtkmodules.util.numpy_support import vtk_to_numpy

    connectivity = vtk_to_numpy(grid.GetCells().GetConnectivityArray())
    offsets = vtk_to_numpy(grid.GetCells().GetOffsetsArray())
    return np.unique(connectivity[offsets[:-1] + PATCH_NODE_CORNER])


def plane_basis(n):
    """Unit vectors e1, e2 with (e1, e2, n) right-handed; e1 = x1 and e2 = x2 for n = x3."""
    axis = np.eye(3)[int(np.argmin(np.abs(n)))]
    e1 = axis - np.dot(axis, n) * n
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(n, e1)


def surface_frame(surface, body_centre):
    """(centre, e1, e2, n): the surface's plane of least variance, n towards the body (the camera's side)."""
    x = points_of(surface)
    centre = x.mean(axis=0)
    n = np.linalg.svd(x - centre, full_matrices=False)[2][-1]
    n = n if np.dot(np.asarray(body_centre) - centre, n) >= 0 else -n
    return (centre, *plane_basis(n), n)


def cell_areas(grid):
    """Area of each (polygonal) cell of ``grid``."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkFiltersVerdict import vtkCellSizeFilter

    sizes = vtkCellSizeFilter()
    sizes.SetInputData(grid)
    sizes.Update()
    return vtk_to_numpy(sizes.GetOutput().GetCellData().GetArray("Area"))


def new_view():
    from paraview import simple

    view = simple.CreateView("RenderView")
    view.ViewSize = list(IMAGE_SIZE)
    view.OrientationAxesVisibility = 0
    view.UseColorPaletteForBackground = 0
    view.Background = [1.0, 1.0, 1.0]
    return view


def show_text(view, source, location="Upper Center", size=FONT + 4):
    """Show a text ``source`` (a Text, an AnnotateTimeFilter) in black at ``location``."""
    from paraview import simple

    display = simple.Show(source, view)
    display.WindowLocation, display.FontSize, display.Color = location, size, [0.0, 0.0, 0.0]
    display.Justification = "Center" if location == "Upper Center" else "Left"
    return display


def add_title(view, title, caption=""):
    """The ``title`` at the top and the ``caption`` at the lower left; their Text sources (those given)."""
    from paraview import simple

    sources = []
    for text, location, size in ((title, "Upper Center", FONT + 4), (caption, "Lower Left Corner", FONT - 4)):
        if text:
            sources.append(simple.Text(Text=text))
            show_text(view, sources[-1], location, size)
    return sources


def colour_bar(view, lut, title, largest=None, position=(0.86, 0.2), length=0.6):
    from paraview import simple

    bar = simple.GetScalarBar(lut, view)
    bar.Title, bar.ComponentTitle, bar.Orientation = title, "", "Vertical"
    bar.WindowLocation, bar.ScalarBarLength = "Any Location", length
    bar.Position = [bar_left(title, position[0]), position[1]]  # the title never cut off at the right
    bar.TitleColor = bar.LabelColor = [0.0, 0.0, 0.0]
    bar.TitleFontSize, bar.LabelFontSize, bar.TitleBold, bar.HorizontalTitle = FONT, FONT - 2, 1, 1
    if largest is not None:  # about three digits
        big = abs(largest)
        fmt = "%-.0f" if big >= 100 or big == 0 else "%-.1f" if big >= 10 else "%-.2f" if big >= 1 else "%-.3f"
        bar.AutomaticLabelFormat, bar.LabelFormat, bar.RangeLabelFormat = 0, fmt, fmt
        bar.AddRangeLabels = bar.DrawTickMarks = 1
    bar.Visibility = 1
    return bar


def flat(display):
    """Colours exactly as mapped (no shading): for views of flat surfaces."""
    display.Ambient, display.Diffuse, display.Specular = 1.0, 0.0, 0.0


def screenshot(view, path):
    from paraview import simple

    simple.Render(view)
    simple.SaveScreenshot(path, view, ImageResolution=list(IMAGE_SIZE), TransparentBackground=0)
    print(f"pv_views: wrote {path}")


def clear(view):
    """Delete every source and ``view``: the next view starts from nothing."""
    from paraview import simple

    for source in list(simple.GetSources().values()):
        simple.Delete(source)
    simple.Delete(view)


def save(view, path):
    screenshot(view, path)
    clear(view)
