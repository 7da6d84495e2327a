"""The contact-surface views of ``pv_views.py``: pressure with friction tractions, and the stick/slip map."""

from __future__ import annotations

import math

import numpy as np

from pv_common import (
    ALWAYS_IN_LEGEND,
    CONTACT_STATES,
    FENCE,
    FIELDS,
    FONT,
    IMAGE_SIZE,
    SOURCES,
    ResultError,
    add_array,
    add_title,
    bar_left,
    cell_areas,
    colour_bar,
    field,
    flat,
    new_view,
    patch_nodes,
    points_of,
    producer,
    robust_top,
    save,
)


def plan_view(view, surface, frame, box):
    """Look at ``surface`` along -n from its body's side (parallel projection), filling ``box`` =
    (left, right, bottom, top) as fractions of the image; with axes when n is a coordinate axis."""
    centre, e1, e2, n = frame
    local = (points_of(surface) - centre) @ np.column_stack([e1, e2])
    low, high = local.min(axis=0), np.maximum(local.max(axis=0), local.min(axis=0) + 1e-12)
    width, height = IMAGE_SIZE
    size = high - low
    pixels_per_m = min((box[1] - box[0]) * width / size[0], (box[3] - box[2]) * height / size[1])
    shift = (high + low) / 2 + np.array([width / 2 - (box[0] + box[1]) / 2 * width,
                                         height / 2 - (box[2] + box[3]) / 2 * height]) / pixels_per_m  # fmt: skip
    focal = centre + shift[0] * e1 + shift[1] * e2
    view.CameraParallelProjection = 1
    view.CameraFocalPoint = list(focal)
    view.CameraPosition = list(focal + 10.0 * max(size) * n)
    view.CameraViewUp = list(e2)
    view.CameraParallelScale = height / 2 / pixels_per_m
    if abs(n[2]) < 0.999:
        return f"along -n, n = ({n[0]:.2f}, {n[1]:.2f}, {n[2]:.2f})"
    axes = view.AxesGrid  # a plan view from +-x3: x1 and x2 axes (m)
    axes.Visibility, axes.AxesToLabel = 1, 1 + 2
    axes.XTitle, axes.YTitle, axes.ZTitle = "x1 (m)", "x2 (m)" + " " * 7, ""  # spaces: clear of the tick labels
    for axis in "XYZ":
        setattr(axes, f"{axis}TitleFontSize", FONT - 2)
        setattr(axes, f"{axis}LabelFontSize", FONT - 4)
        setattr(axes, f"{axis}TitleColor", [0.0, 0.0, 0.0])
        setattr(axes, f"{axis}LabelColor", [0.0, 0.0, 0.0])
    return "from +x3" if n[2] > 0 else "from -x3"


def traction_view(result, path):
    """Contact surface coloured by pressure with friction-traction arrows at the nodes."""
    from paraview import simple

    grid, frame = result["surface"], result["frame"]
    p_assoc, pressure, _ = field(grid, "contact_pressure", SOURCES["surface"])
    t_assoc, traction, _ = field(grid, "friction_traction", SOURCES["surface"])
    p_unit, p_factor = FIELDS["contact_pressure"][4:]
    t_unit, t_factor = FIELDS["friction_traction"][4:]
    add_array(grid, p_assoc, "pressure_shown", pressure * p_factor)
    traction = traction.reshape(len(traction), -1) * t_factor
    traction = np.column_stack([traction, np.zeros((len(traction), 3 - traction.shape[1]))])
    t_max = float(np.linalg.norm(traction, axis=1).max())
    ids = patch_nodes(grid) if p_assoc == "POINTS" else np.arange(len(pressure))
    largest = int(ids[np.argmax(pressure[ids])])
    p_top = robust_top(pressure[ids]) * p_factor
    where = points_of(grid)[largest] if p_assoc == "POINTS" else None
    view = new_view()
    display = simple.Show(producer(grid), view)
    display.Representation, display.EdgeColor = "Surface With Edges", [0.6, 0.6, 0.6]
    flat(display)
    simple.ColorBy(display, (p_assoc, "pressure_shown"))
    lut = simple.GetColorTransferFunction("pressure_shown")
    lut.ApplyPreset("Blues", True)
    lut.InvertTransferFunction()  # white: no pressure
    lut.RescaleTransferFunction(0.0, p_top or 1.0)
    title = f"{result['case']['pressure']} ({p_unit})"
    colour_bar(view, lut, title, p_top)
    side = plan_view(view, grid, frame, box=(0.11, bar_left(title, 0.86) - 0.04, 0.16, 0.86))
    if t_max > 1e-9 * (p_top or 1.0) and t_assoc == "POINTS":  # not a frictionless pair's round-off
        from vtkmodules.vtkCommonCore import vtkPoints
        from vtkmodules.vtkCommonDataModel import vtkPolyData
        from vtkmodules.util.numpy_support import numpy_to_vtk

        nodes = vtkPolyData()
        nodes.SetPoints(vtkPoints())
        nodes.GetPoints().SetData(numpy_to_vtk(np.ascontiguousarray(points_of(grid)[ids]), deep=True))
        add_array(nodes, "POINTS", "traction_shown", traction[ids])
        glyph = simple.Glyph(Input=producer(nodes), GlyphType="Arrow", GlyphMode="All Points")
        glyph.OrientationArray = glyph.ScaleArray = ["POINTS", "traction_shown"]
        spacing = math.sqrt(cell_areas(grid).sum() / max(len(ids), 1))
        glyph.ScaleFactor = 1.6 * spacing / t_max  # the largest arrow: 1.6 node spacings
        arrows = simple.Show(glyph, view)
        arrows.ColorArrayName, arrows.DiffuseColor = ["POINTS", ""], [0.85, 0.1, 0.1]
        arrows.AmbientColor = arrows.DiffuseColor
        arrows.Translation = list(0.5 * spacing * frame[3])  # towards the camera, above the surface
    add_title(view, f"{result['case']['pressure'].capitalize()} and friction traction ({result['case']['label']})",
              f"contact surface seen {side}, through the body; red arrows: friction traction on the body, "
              f"length proportional to its magnitude (largest {t_max:.3g} {t_unit})\n"
              f"colours up to the 99th percentile of the pressing nodes' pressure within {FENCE:g} interquartile "
              f"ranges ({p_top:.3g} {p_unit}); largest {pressure[largest] * p_factor:.3g} {p_unit}"
              + ("" if where is None else " at (" + ", ".join(f"{round(1e3 * c, 4) + 0.0:g}" for c in where) + ") mm"))
    save(view, path)


def stick_slip_view(result, path):
    """Contact states as categories, with their areas in the legend."""
    from paraview import simple

    grid = result["surface"]
    association, state, _ = field(grid, "contact_state", SOURCES["surface"])
    if association != "CELLS":
        raise ResultError(f"contact_state in {SOURCES['surface']}: nodal, expected one value per tributary patch")
    codes = np.rint(state).astype(int)
    unknown = sorted(set(codes.tolist()) - set(CONTACT_STATES))
    if unknown:
        raise ResultError(f"contact_state has values {unknown} that CONTACT_STATES does not name")
    add_array(grid, "CELLS", "state_shown", codes)
    areas = cell_areas(grid)
    view = new_view()
    display = simple.Show(producer(grid), view)
    flat(display)
    simple.ColorBy(display, ("CELLS", "state_shown"))
    lut = simple.GetColorTransferFunction("state_shown")
    lut.InterpretValuesAsCategories = lut.AnnotationsInitialized = 1
    present = sorted(set(codes.tolist()) | set(ALWAYS_IN_LEGEND))
    legend = {s: f"{CONTACT_STATES[s][0]} ({areas[codes == s].sum():.3g} m\u00b2)" for s in present}
    lut.Annotations = [text for s in present for text in (str(s), legend[s])]
    lut.IndexedColors = [c for s in present for c in CONTACT_STATES[s][1]]
    bar = colour_bar(view, lut, "contact state", position=(0.72, 0.30), length=0.4)
    bar.DrawTickMarks = bar.AddRangeLabels = 0
    bar.TextPosition = "Ticks left/bottom, annotations right/top"
    edges = simple.Show(producer(grid), view)  # the patches' edges on top, thin
    edges.Representation, edges.ColorArrayName = "Wireframe", ["POINTS", ""]
    edges.AmbientColor = edges.DiffuseColor = [0.3, 0.3, 0.3]
    edges.Translation = list(1e-3 * math.sqrt(areas.sum()) * result["frame"][3])
    side = plan_view(view, grid, result["frame"], box=(0.11, 0.64, 0.16, 0.86))
    add_title(view, f"Stick/slip map ({result['case']['label']})",
              f"contact surface seen {side}, through the body; each cell is a node's tributary patch")
    save(view, path)
