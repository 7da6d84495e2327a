"""Standard ParaView views of a Coulomb contact result (``demos/coulomb3d.py --output DIR``).

Run with ParaView's Python (5.13: ``pvbatch`` or ``pvpython``) under a display or
``xvfb-run``; ``scripts/paraview/run.sh`` sets that up and ``make paraview``
installs ParaView from Debian and runs it on a fresh result::

    xvfb-run -a pvbatch scripts/paraview/pv_views.py results/pv --out docs/images

Writes three PNGs to ``--out`` (default: the result directory):

* ``paraview_deformed.png``: the body warped by the displacement (magnified; the
  factor is in the caption) coloured by the von Mises stress (cell-wise); without
  a ``von_mises`` field, by the displacement magnitude, and the title says so.
* ``paraview_contact_traction.png``: the contact surface in plan view, coloured by
  the contact pressure, with friction-traction arrows at the nodes.
* ``paraview_stick_slip.png``: the contact states as categories with their areas.
  A cell-wise state (contactqvi writes one cell per node and facet, the node's
  tributary patch) fills its cell; a nodal state fills the quarter of each
  adjacent face nearest to its node, i.e. its lumped area.

Every file and field the script reads is listed in ``SOURCES`` and ``FIELDS``
below; a missing file or field stops it with a message that names it.

The data are read with ParaView's readers (``Xdmf3ReaderS`` for XDMF at the first
time step, ``ADIOS2VTXReader`` for VTX ``.bp``), fetched, and the fields of one
dataset gathered onto one grid: DOLFINx's XDMF writes one grid per function, and
VTX from several ranks one piece per rank.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys

# ---------------------------------------------------------------------------
# What this script reads: the one place to change when the output changes.
# ---------------------------------------------------------------------------

#: Datasets of a result directory: candidate files, in order of preference. A
#: field is taken from the first existing file of its dataset that holds it.
SOURCES = {
    "volume": ("body.bp", "contact.xdmf", "displacement.bp"),
    "surface": ("contact_surface.bp", "contact_surface.xdmf"),
}

#: ParaView reader for each file type.
READERS = {".xdmf": "Xdmf3ReaderS", ".bp": "ADIOS2VTXReader"}

#: Fields: name -> (dataset, required, label, unit in the files, unit shown, factor
#: from the file's unit to the shown one). A name also matches with a unit suffix
#: ("von_mises [Pa]", "von_mises (Pa)", "von_mises_Pa").
FIELDS = {
    "displacement": ("volume", True, "displacement", "m", "mm", 1e3),
    "von_mises": ("volume", False, "von Mises stress", "Pa", "MPa", 1e-6),
    "contact_pressure": ("surface", True, "contact pressure", "Pa", "MPa", 1e-6),
    "friction_traction": ("surface", True, "friction traction", "Pa", "MPa", 1e-6),
    "contact_state": ("surface", True, "contact state", "", "", 1.0),
}

#: Values of ``contact_state`` (contactqvi.contact.nodal.State) -> (label, RGB): the
#: names of contactqvi.contact.postprocess.STATE_NAMES and the (colour-blind safe,
#: Okabe-Ito) colours of its contact_states.png.
CONTACT_STATES = {
    0: ("no contact", (0.851, 0.851, 0.851)),  # #d9d9d9
    1: ("sliding", (0.902, 0.624, 0.0)),  # #e69f00
    2: ("sticking", (0.0, 0.447, 0.698)),  # #0072b2
    3: ("grazing, sliding", (0.941, 0.894, 0.259)),  # #f0e442
    4: ("sticking on the cone boundary", (0.337, 0.706, 0.914)),  # #56b4e9
    5: ("grazing, at rest", (0.8, 0.475, 0.655)),  # #cc79a7
    6: ("separated, sticking (Tresca)", (0.0, 0.62, 0.451)),  # #009e73
}

#: The states always shown in the legend (others only when they occur).
ALWAYS_IN_LEGEND = (0, 1, 2)

#: A surface with a cell-wise contact_state is cut into tributary patches (one
#: quadrilateral per node and facet: node, edge midpoint, facet centre, edge
#: midpoint); this corner of each cell is the patch's node. Arrows are drawn there.
PATCH_NODE_CORNER = 0

#: The rigid foundation's plane x3 = FOUNDATION_X3 (drawn in the deformed view).
FOUNDATION_X3 = 0.0

IMAGE_SIZE = (1600, 900)
FONT = 22  # titles and colour-bar text, in points at IMAGE_SIZE


class ResultError(Exception):
    """A file or field this script needs is not in the result directory."""


# ---------------------------------------------------------------------------
# Reading: ParaView readers, then the fields of one dataset on one VTK grid.
# ---------------------------------------------------------------------------


def _leaves(data):
    """The non-empty datasets of a (possibly composite) VTK data object."""
    if not data.IsA("vtkCompositeDataSet"):
        return [data] if data.GetNumberOfPoints() else []
    leaves = []
    it = data.NewIterator()
    it.InitTraversal()
    while not it.IsDoneWithTraversal():
        leaf = it.GetCurrentDataObject()
        if leaf is not None and leaf.GetNumberOfPoints():
            leaves.append(leaf)
        it.GoToNextItem()
    return leaves


def _array_names(grid):
    names = []
    for data in (grid.GetPointData(), grid.GetCellData()):
        names += [data.GetArrayName(i) for i in range(data.GetNumberOfArrays())]
    return [n for n in names if n and not n.startswith("vtk")]


def _one_grid(leaves, path):
    """One unstructured grid with every field of ``leaves``.

    Leaves holding the same fields are pieces of one mesh (VTX from several ranks):
    they are appended. Leaves holding different fields are copies of one mesh
    (DOLFINx's XDMF: one grid per function): their arrays are gathered onto the first.
    """
    from vtkmodules.vtkCommonDataModel import vtkUnstructuredGrid
    from vtkmodules.vtkFiltersCore import vtkAppendFilter

    if not leaves:
        raise ResultError(f"{path}: no data (an empty or unfinished file?)")
    if len({tuple(sorted(_array_names(leaf))) for leaf in leaves}) == 1 and len(leaves) > 1:
        append = vtkAppendFilter()
        for leaf in leaves:
            append.AddInputData(leaf)
        append.Update()
        return append.GetOutput()
    grid = vtkUnstructuredGrid()
    grid.DeepCopy(leaves[0])
    for leaf in leaves[1:]:
        if (leaf.GetNumberOfPoints(), leaf.GetNumberOfCells()) != (grid.GetNumberOfPoints(), grid.GetNumberOfCells()):
            print(f"pv_views: {path}: a grid of {leaf.GetNumberOfPoints()} points differs from the first "
                  f"({grid.GetNumberOfPoints()}); its fields {_array_names(leaf)} are not used", file=sys.stderr)
            continue
        for source, target in ((leaf.GetPointData(), grid.GetPointData()), (leaf.GetCellData(), grid.GetCellData())):
            for i in range(source.GetNumberOfArrays()):
                if source.GetArrayName(i) and target.GetArray(source.GetArrayName(i)) is None:
                    target.AddArray(source.GetArray(i))
    return grid


def read_file(path):
    """The file at ``path`` as one VTK unstructured grid, read with ParaView's reader."""
    from paraview import servermanager, simple

    reader_name = READERS.get(os.path.splitext(path)[1])
    if reader_name is None:
        raise ResultError(f"{path}: no reader for this file type (known: {', '.join(READERS)})")
    if reader_name == "ADIOS2VTXReader":
        reader = simple.ADIOS2VTXReader(FileName=path)
    else:
        reader = getattr(simple, reader_name)(FileName=[path])
    times = list(getattr(reader, "TimestepValues", None) or [])
    reader.UpdatePipeline(times[0] if times else 0.0)  # XDMF: the first step, else no data
    fetched = servermanager.Fetch(reader)
    data = fetched.NewInstance()
    data.DeepCopy(fetched)  # the XDMF reader's arrays point into memory it frees with it
    simple.Delete(reader)
    grid = _one_grid(_leaves(data), path)
    return grid


#: Unit suffixes a field name may carry in the files.
UNIT_SUFFIXES = ("m", "Pa", "MPa", "1")


def field_matches(found, name):
    """Whether the array name ``found`` is field ``name``, bare or with a unit suffix
    ("von_mises", "von_mises [Pa]", "von_mises (Pa)", "von_mises_Pa")."""
    if found == name:
        return True
    rest = found[len(name):] if found.startswith(name) else ""
    return rest[:1] in (" ", "[", "(", "_") and rest.strip(" []()_") in UNIT_SUFFIXES


def _find_array(grid, name):
    """(association, array) of field ``name`` in ``grid`` (see :func:`field_matches`)."""
    for association, data in (("POINTS", grid.GetPointData()), ("CELLS", grid.GetCellData())):
        for i in range(data.GetNumberOfArrays()):
            if field_matches(data.GetArrayName(i) or "", name):
                return association, data.GetArray(i)
    return None


class Dataset:
    """The fields of one dataset (``SOURCES``), on the grid of its first file."""

    def __init__(self, result_dir, role):
        self.role = role
        self.candidates = [os.path.join(result_dir, name) for name in SOURCES[role]]
        self.files = [path for path in self.candidates if os.path.exists(path)]
        if not self.files:
            raise ResultError(f"{result_dir}: no {role} file; looked for {', '.join(SOURCES[role])} "
                              f"(SOURCES in {os.path.basename(__file__)})")
        self.grids = {}
        self.grid = None
        self.origin = {}

    def _grid_of(self, path):
        if path not in self.grids:
            self.grids[path] = read_file(path)
        return self.grids[path]

    def field(self, name):
        """(association, numpy array) of ``name`` (``FIELDS``), put on this dataset's grid.

        The grid is that of the first file holding a field. A field of another file
        joins it when that file's mesh has the same number of points and cells.
        Returns None for a missing optional field; raises ResultError for a missing
        required one.
        """
        from vtkmodules.util.numpy_support import vtk_to_numpy

        required = FIELDS[name][1]
        for path in self.files:
            grid = self._grid_of(path)
            found = _find_array(grid, name)
            if found is None:
                continue
            association, array = found
            if self.grid is None:
                self.grid = grid
            elif grid is not self.grid:
                same = (grid.GetNumberOfPoints(), grid.GetNumberOfCells()) == (
                    self.grid.GetNumberOfPoints(), self.grid.GetNumberOfCells())
                if not same:
                    continue
                data = self.grid.GetPointData() if association == "POINTS" else self.grid.GetCellData()
                data.AddArray(array)
            self.origin[name] = os.path.basename(path)
            return association, vtk_to_numpy(array)
        if required:
            raise ResultError(f"field '{name}' ({FIELDS[name][2]}) not found in the {self.role} file(s) "
                              f"{', '.join(os.path.basename(p) for p in self.files)} "
                              f"(FIELDS/SOURCES in {os.path.basename(__file__)})")
        return None


def add_array(grid, association, name, values):
    """Add the numpy array ``values`` to ``grid`` as point or cell data ``name``."""
    from vtkmodules.util.numpy_support import numpy_to_vtk

    import numpy as np

    array = numpy_to_vtk(np.ascontiguousarray(values, dtype=np.float64), deep=True)
    array.SetName(name)
    (grid.GetPointData() if association == "POINTS" else grid.GetCellData()).AddArray(array)


def producer(grid):
    """A ParaView source holding the VTK data object ``grid``."""
    from paraview import simple

    source = simple.PVTrivialProducer()
    source.GetClientSideObject().SetOutput(grid)
    source.UpdatePipeline()
    return source


def node_points(grid, values, name, patches):
    """The nodes of a surface as points carrying ``values`` (point data ``name``):
    all points, or on a tributary-patch surface the PATCH_NODE_CORNER of each cell."""
    from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
    from vtkmodules.vtkCommonCore import vtkPoints
    from vtkmodules.vtkCommonDataModel import vtkPolyData

    import numpy as np

    x = vtk_to_numpy(grid.GetPoints().GetData())
    if patches:
        connectivity = vtk_to_numpy(grid.GetCells().GetConnectivityArray())
        offsets = vtk_to_numpy(grid.GetCells().GetOffsetsArray())
        ids = np.unique(connectivity[offsets[:-1] + PATCH_NODE_CORNER])
    else:
        ids = np.arange(len(x))
    points = vtkPoints()
    points.SetData(numpy_to_vtk(np.ascontiguousarray(x[ids], dtype=np.float64), deep=True))
    poly = vtkPolyData()
    poly.SetPoints(points)
    add_array(poly, "POINTS", name, values[ids])
    return poly


def cell_areas(grid):
    """Area of each (polygonal) cell of ``grid``, as a numpy array."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkFiltersVerdict import vtkCellSizeFilter

    sizes = vtkCellSizeFilter()
    sizes.SetInputData(grid)
    for kind in ("Vertex", "Length", "Volume"):
        getattr(sizes, f"Compute{kind}CountOff" if kind == "Vertex" else f"Compute{kind}Off")()
    sizes.ComputeAreaOn()
    sizes.Update()
    return vtk_to_numpy(sizes.GetOutput().GetCellData().GetArray("Area"))


def nodal_tiles(grid, state):
    """Each polygon of ``grid`` split into one quadrilateral per corner (the corner's
    share of the cell: corner, edge midpoint, centroid, edge midpoint), carrying the
    corner's ``state`` as cell data, so a nodal category is drawn without blending."""
    from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray, vtk_to_numpy
    from vtkmodules.vtkCommonCore import vtkPoints
    from vtkmodules.vtkCommonDataModel import VTK_QUAD, vtkCellArray, vtkUnstructuredGrid

    import numpy as np

    x = vtk_to_numpy(grid.GetPoints().GetData()).astype(np.float64)
    points, quads, values = [], [], []
    for c in range(grid.GetNumberOfCells()):
        ids = grid.GetCell(c).GetPointIds()
        corners = [ids.GetId(i) for i in range(ids.GetNumberOfIds())]
        p = x[corners]
        centroid = p.mean(axis=0)
        n = len(corners)
        for i in range(n):
            base = len(points)
            points += [p[i], 0.5 * (p[i] + p[(i + 1) % n]), centroid, 0.5 * (p[i] + p[(i - 1) % n])]
            quads.append([4, base, base + 1, base + 2, base + 3])
            values.append(state[corners[i]])
    vtk_points = vtkPoints()
    vtk_points.SetData(numpy_to_vtk(np.asarray(points), deep=True))
    cells = vtkCellArray()
    cells.SetCells(len(quads), numpy_to_vtkIdTypeArray(np.asarray(quads, dtype=np.int64).ravel(), deep=True))
    tiles = vtkUnstructuredGrid()
    tiles.SetPoints(vtk_points)
    tiles.SetCells(VTK_QUAD, cells)
    add_array(tiles, "CELLS", "contact_state", np.asarray(values))
    return tiles


# ---------------------------------------------------------------------------
# Rendering
# ---------------------------------------------------------------------------


def new_view(parallel_projection=False):
    from paraview import simple

    view = simple.CreateView("RenderView")
    view.ViewSize = list(IMAGE_SIZE)
    view.OrientationAxesVisibility = 0
    view.UseColorPaletteForBackground = 0
    view.Background = [1.0, 1.0, 1.0]
    view.CameraParallelProjection = int(parallel_projection)
    return view


def add_title(view, title, caption=""):
    """A title at the top of the view and an optional caption (lines) at the bottom left."""
    from paraview import simple

    for text, location, size in ((title, "Upper Center", FONT + 4), (caption, "Lower Left Corner", FONT - 4)):
        if not text:
            continue
        source = simple.Text(Text=text)
        display = simple.Show(source, view)
        display.WindowLocation = location
        display.FontSize = size
        display.Color = [0.0, 0.0, 0.0]
        display.Justification = "Center" if location == "Upper Center" else "Left"


def label_format(largest):
    """A printf format showing values up to ``largest`` with about three digits."""
    largest = abs(largest)
    if largest >= 100 or largest == 0:
        return "%-.0f"
    if largest >= 10:
        return "%-.1f"
    if largest >= 0.01:
        return "%-.2f" if largest >= 1 else "%-.3f"
    return "%-.2e"


def colour_bar(view, lut, title, position=(0.86, 0.18), length=0.6, fmt="%-#.3g"):
    from paraview import simple

    bar = simple.GetScalarBar(lut, view)
    bar.Title = title
    bar.ComponentTitle = ""
    bar.Orientation = "Vertical"
    bar.WindowLocation = "Any Location"
    bar.Position = list(position)
    bar.ScalarBarLength = length
    bar.TitleColor = bar.LabelColor = [0.0, 0.0, 0.0]
    bar.TitleFontSize = FONT
    bar.LabelFontSize = FONT - 2
    bar.TitleBold = 1
    bar.HorizontalTitle = 1  # above the bar: a rotated title can run into long tick labels
    bar.AutomaticLabelFormat = 0
    bar.LabelFormat = fmt
    bar.RangeLabelFormat = fmt
    bar.AddRangeLabels = 1
    bar.DrawTickMarks = 1
    bar.Visibility = 1
    return bar


def plan_axes(view, font=FONT - 2):
    """x1 and x2 axes (m) along the bottom and left of a plan view."""
    grid = view.AxesGrid
    grid.Visibility = 1
    # The y title is centred on the axis next to the tick labels: spaces move it clear of them.
    grid.XTitle, grid.YTitle, grid.ZTitle = "x1 (m)", "x2 (m)" + " " * 7, ""
    grid.AxesToLabel = 1 + 2  # Min-X and Min-Y only
    for axis in "XYZ":
        setattr(grid, f"{axis}TitleFontSize", font)
        setattr(grid, f"{axis}LabelFontSize", font - 2)
        setattr(grid, f"{axis}TitleColor", [0.0, 0.0, 0.0])
        setattr(grid, f"{axis}LabelColor", [0.0, 0.0, 0.0])
    grid.GridColor = [0.3, 0.3, 0.3]
    return grid


def flat(display):
    """Colours exactly as mapped (no shading): for plan views of flat surfaces."""
    display.Ambient = 1.0
    display.Diffuse = 0.0
    display.Specular = 0.0


def nice(value):
    """The number 1, 2 or 5 times a power of ten nearest below ``value`` (> 0)."""
    exponent = math.floor(math.log10(value))
    mantissa = value / 10**exponent
    return next(m for m in (5, 2, 1) if m <= mantissa) * 10**exponent


def save(view, path):
    from paraview import simple

    simple.Render(view)
    simple.SaveScreenshot(path, view, ImageResolution=list(IMAGE_SIZE), TransparentBackground=0)
    print(f"pv_views: wrote {path}")
    for source in list(simple.GetSources().values()):  # the next view starts from nothing
        simple.Delete(source)
    simple.Delete(view)


def case_label(result_dir):
    """'lev 4, d3/L2, F = 0.23' from summary.json, or the directory name."""
    try:
        with open(os.path.join(result_dir, "summary.json")) as f:
            p = json.load(f)["parameters"]
        law = f"F = {p['friction']:g}" if p.get("law", "coulomb") == "coulomb" else f"Tresca, S = {p['slip_bound']:g} Pa"
        return f"lev {p['lev']}, {p['geometry']}/{p['load']}, {law}"
    except (OSError, KeyError, ValueError, TypeError):
        return os.path.basename(os.path.normpath(result_dir))


def deformed_view(volume, case, path):
    """The body warped by the displacement, coloured by von Mises (or |u|)."""
    from paraview import simple

    import numpy as np

    _, u = volume.field("displacement")
    von_mises = volume.field("von_mises")
    grid = volume.grid
    u = u.reshape(len(u), -1)
    u_max = float(np.linalg.norm(u, axis=1).max())
    bounds = grid.GetBounds()
    extent = max(bounds[1] - bounds[0], bounds[3] - bounds[2], bounds[5] - bounds[4])
    scale = nice(0.08 * extent / u_max) if u_max > 0 else 1.0

    if von_mises is not None:
        association, values = von_mises
        name = "vm_shown"
        label, _, unit, factor = FIELDS["von_mises"][2:]
        shown = values * factor
        where = "cell-wise" if association == "CELLS" else "nodal"
        title = f"Deformed body coloured by von Mises stress ({case})"
        what = f"colour: von Mises stress, {where} ({volume.origin['von_mises']})"
    else:
        association, name = "POINTS", "u_magnitude_shown"
        factor = FIELDS["displacement"][5]
        shown = np.linalg.norm(u, axis=1) * factor
        label, unit = "displacement magnitude", FIELDS["displacement"][4]
        title = f"Deformed body coloured by displacement magnitude: no von Mises stress in the files ({case})"
        what = (f"colour: displacement magnitude (no field 'von_mises' in "
                f"{', '.join(os.path.basename(p) for p in volume.files)})")
    add_array(grid, association, name, shown)

    view = new_view()
    body = producer(grid)
    undeformed = simple.Show(simple.Outline(Input=body), view)
    undeformed.DiffuseColor = undeformed.AmbientColor = [0.45, 0.45, 0.45]
    undeformed.LineWidth = 1.5
    warp = simple.WarpByVector(Input=body, Vectors=["POINTS", volume_name(grid, "displacement")], ScaleFactor=scale)
    display = simple.Show(warp, view)
    display.Representation = "Surface With Edges"
    display.EdgeColor = [0.25, 0.25, 0.25]
    simple.ColorBy(display, (association, name))
    lut = simple.GetColorTransferFunction(name)
    lut.ApplyPreset("Turbo" if von_mises is not None else "Viridis (matplotlib)", True)
    lut.RescaleTransferFunction(0.0, float(shown.max()) or 1.0)  # both are magnitudes: from 0
    colour_bar(view, lut, f"{label} ({unit})", position=(0.85, 0.2), fmt=label_format(shown.max()))

    # The foundation x3 = FOUNDATION_X3, a little larger than the body's footprint.
    margin = 0.06 * extent
    plane = simple.Plane(Origin=[bounds[0] - margin, bounds[2] - margin, FOUNDATION_X3],
                         Point1=[bounds[1] + margin, bounds[2] - margin, FOUNDATION_X3],
                         Point2=[bounds[0] - margin, bounds[3] + margin, FOUNDATION_X3])
    floor = simple.Show(plane, view)
    floor.DiffuseColor = floor.AmbientColor = [0.55, 0.45, 0.35]
    floor.Opacity = 0.5

    centre = [(bounds[0] + bounds[1]) / 2, (bounds[2] + bounds[3]) / 2, (bounds[4] + bounds[5]) / 2]
    view.CameraFocalPoint = centre
    view.CameraPosition = [centre[0] - 1.6 * extent, centre[1] - 2.4 * extent, centre[2] + 1.5 * extent]
    view.CameraViewUp = [0.0, 0.0, 1.0]
    simple.ResetCamera(view)
    view.CameraPosition = [c + 0.8 * (p - c) for p, c in zip(view.CameraPosition, centre)]
    # Move the scene up and left a little: room for the caption and the colour bar.
    direction = np.subtract(view.CameraFocalPoint, view.CameraPosition)
    right = np.cross(direction, view.CameraViewUp)
    shift = 0.09 * extent * np.array([0.0, 0.0, -1.0]) + 0.1 * extent * right / np.linalg.norm(right)
    view.CameraFocalPoint = list(np.add(view.CameraFocalPoint, shift))
    view.CameraPosition = list(np.add(view.CameraPosition, shift))
    add_title(view, title, f"displacement magnified \u00d7{scale:g} (largest {u_max * 1e3:.3g} mm); {what}\n"
                           f"grey box: undeformed body; brown plane: rigid foundation x3 = {FOUNDATION_X3:g} m")
    save(view, path)


def volume_name(grid, name):
    """The name under which field ``name`` is stored in ``grid`` (it may carry a unit)."""
    found = _find_array(grid, name)
    return found[1].GetName()


def plan_view_camera(view, grid, box):
    """Plan view of ``grid`` from +x3 (x1 to the right, x2 up), parallel projection,
    scaled so that it fills ``box`` = (left, right, bottom, top), fractions of the image."""
    width, height = IMAGE_SIZE
    b = grid.GetBounds()
    size_x, size_y = max(b[1] - b[0], 1e-12), max(b[3] - b[2], 1e-12)
    pixels_per_m = min((box[1] - box[0]) * width / size_x, (box[3] - box[2]) * height / size_y)
    focal = [(b[0] + b[1]) / 2 + (width / 2 - (box[0] + box[1]) / 2 * width) / pixels_per_m,
             (b[2] + b[3]) / 2 + (height / 2 - (box[2] + box[3]) / 2 * height) / pixels_per_m,
             (b[4] + b[5]) / 2]
    view.CameraFocalPoint = focal
    view.CameraPosition = [focal[0], focal[1], focal[2] + 10.0 * max(size_x, size_y)]
    view.CameraViewUp = [0.0, 1.0, 0.0]
    view.CameraParallelScale = height / 2 / pixels_per_m


def traction_view(surface, case, path):
    """Contact surface coloured by pressure with friction-traction arrows."""
    from paraview import simple

    import numpy as np

    p_assoc, pressure = surface.field("contact_pressure")
    t_assoc, traction = surface.field("friction_traction")
    patches = surface.field("contact_state")[0] == "CELLS"
    grid = surface.grid
    _, _, _, _, p_unit, p_factor = FIELDS["contact_pressure"]
    _, _, _, _, t_unit, t_factor = FIELDS["friction_traction"]
    add_array(grid, p_assoc, "pressure_shown", pressure * p_factor)
    traction = traction.reshape(len(traction), -1)
    if traction.shape[1] == 2:
        traction = np.column_stack([traction, np.zeros(len(traction))])
    add_array(grid, t_assoc, "traction_shown", traction * t_factor)
    t_max = float(np.linalg.norm(traction, axis=1).max()) * t_factor

    view = new_view(parallel_projection=True)
    source = producer(grid)
    display = simple.Show(source, view)
    display.Representation = "Surface With Edges"
    display.EdgeColor = [0.6, 0.6, 0.6]
    flat(display)
    simple.ColorBy(display, (p_assoc, "pressure_shown"))
    lut = simple.GetColorTransferFunction("pressure_shown")
    lut.ApplyPreset("Blues", True)
    lut.InvertTransferFunction()  # white: no pressure
    p_max = float(pressure.max()) * p_factor
    lut.RescaleTransferFunction(0.0, p_max or 1.0)
    colour_bar(view, lut, f"contact pressure ({p_unit})", position=(0.86, 0.2), fmt=label_format(p_max))

    bounds = grid.GetBounds()
    if t_max > 0:
        if t_assoc == "POINTS":
            source_points = producer(node_points(grid, traction * t_factor, "traction_shown", patches))
        else:
            source_points = simple.CellCenters(Input=source)
        n_arrows = source_points.GetDataInformation().GetNumberOfPoints()
        spacing = math.sqrt((bounds[1] - bounds[0]) * (bounds[3] - bounds[2]) / max(n_arrows, 1))
        glyph = simple.Glyph(Input=source_points, GlyphType="Arrow")
        glyph.OrientationArray = ["POINTS", "traction_shown"]
        glyph.ScaleArray = ["POINTS", "traction_shown"]
        glyph.ScaleFactor = 1.6 * spacing / t_max  # the largest arrow: 1.6 node spacings
        glyph.GlyphMode = "All Points"
        glyph.GlyphType.TipLength = 0.3
        glyph.GlyphType.TipRadius = 0.12
        glyph.GlyphType.ShaftRadius = 0.04
        arrows = simple.Show(glyph, view)
        arrows.ColorArrayName = ["POINTS", ""]  # a solid colour
        arrows.DiffuseColor = arrows.AmbientColor = [0.85, 0.1, 0.1]
        # Arrows a little above the surface (towards the camera), so the surface does not hide them.
        arrows.Translation = [0.0, 0.0, 0.02 * max(bounds[1] - bounds[0], bounds[3] - bounds[2])]
    plan_view_camera(view, grid, box=(0.11, 0.80, 0.16, 0.86))
    plan_axes(view)
    add_title(view, f"Contact pressure and friction traction ({case})",
              f"contact surface in plan view (from +x3, through the body); red arrows: friction traction on the body, "
              f"length proportional to its magnitude (largest {t_max:.3g} {t_unit})")
    save(view, path)


def stick_slip_view(surface, case, path):
    """Contact states as categories, with an annotated legend."""
    from paraview import simple

    import numpy as np

    from vtkmodules.util.numpy_support import vtk_to_numpy

    association, state = surface.field("contact_state")
    grid = surface.grid
    codes = np.rint(state).astype(int)
    unknown = sorted(set(codes.tolist()) - set(CONTACT_STATES))
    if unknown:
        raise ResultError(f"contact_state in {surface.origin['contact_state']} has values {unknown} "
                          f"that CONTACT_STATES in {os.path.basename(__file__)} does not name")
    if association == "POINTS":
        shown = nodal_tiles(grid, codes)
        how = "nodal states: each node colours its share of the adjacent faces"
    else:
        shown = grid
        add_array(shown, "CELLS", "contact_state", codes)
        how = "cell-wise states (in contactqvi output each cell is a node's tributary patch)"

    view = new_view(parallel_projection=True)
    source = producer(shown)
    display = simple.Show(source, view)
    display.Representation = "Surface"
    flat(display)
    simple.ColorBy(display, ("CELLS", "contact_state"))
    lut = simple.GetColorTransferFunction("contact_state")
    lut.InterpretValuesAsCategories = 1
    lut.AnnotationsInitialized = 1
    present = sorted(set(codes.tolist()) | set(ALWAYS_IN_LEGEND))
    shown_codes = vtk_to_numpy(shown.GetCellData().GetArray("contact_state"))
    areas = {s: float(cell_areas(shown)[shown_codes == s].sum()) for s in present}
    annotations, colours = [], []
    for s in present:
        label, rgb = CONTACT_STATES[s]
        annotations += [str(s), f"{label} ({areas[s]:.3g} m\u00b2)"]
        colours += list(rgb)
    lut.Annotations = annotations
    lut.IndexedColors = colours
    bar = colour_bar(view, lut, "contact state", position=(0.72, 0.30), length=0.4)
    bar.DrawTickMarks = 0
    bar.AddRangeLabels = 0
    bar.TextPosition = "Ticks left/bottom, annotations right/top"

    edges = simple.Show(producer(grid), view)  # the mesh on top, thin
    edges.Representation = "Wireframe"
    edges.ColorArrayName = ["POINTS", ""]  # a solid colour
    edges.AmbientColor = edges.DiffuseColor = [0.3, 0.3, 0.3]
    edges.Translation = [0.0, 0.0, 1e-3]
    plan_view_camera(view, grid, box=(0.11, 0.64, 0.16, 0.86))
    plan_axes(view)
    add_title(view, f"Stick/slip map ({case})", f"contact surface in plan view (from +x3, through the body); {how}")
    save(view, path)


VIEWS = {
    "paraview_deformed.png": ("volume", deformed_view),
    "paraview_contact_traction.png": ("surface", traction_view),
    "paraview_stick_slip.png": ("surface", stick_slip_view),
}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("result_dir", help="output directory of demos/coulomb3d.py")
    parser.add_argument("--out", help="directory for the PNGs (default: result_dir)")
    args = parser.parse_args(argv)
    out = args.out or args.result_dir
    os.makedirs(out, exist_ok=True)
    from paraview import simple

    simple.LoadPalette("WhiteBackground")
    case = case_label(args.result_dir)
    try:
        datasets = {role: Dataset(args.result_dir, role) for role in SOURCES}
        for name, (role, view) in VIEWS.items():
            view(datasets[role], case, os.path.join(out, name))
    except ResultError as error:
        print(f"pv_views: {error}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
