"""The deformed-body view of ``pv_views.py``: the body warped by the displacement, and the obstacle."""

from __future__ import annotations

import math

import numpy as np

from pv_common import FIELDS, SOURCES, add_array, add_title, colour_bar, field, new_view, plane_basis, producer, save


def obstacle_source(obstacle, centre, extent):
    """A ParaView source of the rigid obstacle (``summary.json``'s case.obstacle) at its initial place."""
    from paraview import simple

    kind = obstacle["type"]
    if kind == "sphere":
        return simple.Sphere(Center=list(obstacle["center"]), Radius=obstacle["radius"],
                             ThetaResolution=96, PhiResolution=48)  # fmt: skip
    if kind == "cylinder":
        axis = np.asarray(obstacle["axis"], dtype=float) / np.linalg.norm(obstacle["axis"])
        point = np.asarray(obstacle["point"], dtype=float)
        middle = point + np.dot(np.asarray(centre) - point, axis) * axis
        line = simple.Line(Point1=list(middle - extent * axis), Point2=list(middle + extent * axis))
        return simple.Tube(Input=line, Radius=obstacle["radius"], NumberofSides=96)
    normal = np.asarray(obstacle["normal"], dtype=float) / np.linalg.norm(obstacle["normal"])
    point = np.asarray(obstacle["point"], dtype=float)
    origin = np.asarray(centre) - np.dot(np.asarray(centre) - point, normal) * normal  # the centre on the plane
    e1, e2 = plane_basis(normal)
    corner = origin - 0.7 * extent * (e1 + e2)
    return simple.Plane(Origin=list(corner), Point1=list(corner + 1.4 * extent * e1),
                        Point2=list(corner + 1.4 * extent * e2))  # fmt: skip


#: The name of the k-th obstacle's Transform filter (k = 1, 2, ...) in the pipeline and in a saved state.
OBSTACLE_NAME = "obstacle {}"


def rotation_matrix(axis, angle):
    """The rotation by ``angle`` degrees about ``axis`` (Rodrigues' formula, as contactqvi's Rotation)."""
    a = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    K = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    theta = math.radians(angle)
    return np.eye(3) + math.sin(theta) * K + (1.0 - math.cos(theta)) * K @ K


def euler_zxy(Q):
    """Angles (degrees about x, y, z) with Q = R_z R_x R_y: ParaView's ``Transform.Rotate``
    (vtkTransform's orientation order); y taken as 0 where x is +-90 degrees (gimbal lock)."""
    x = math.asin(max(-1.0, min(1.0, Q[2, 1])))
    if abs(math.cos(x)) < 1e-9:
        return [math.degrees(x), 0.0, math.degrees(math.atan2(Q[1, 0], Q[0, 0]))]
    return [math.degrees(x), math.degrees(math.atan2(-Q[2, 0], Q[2, 2])), math.degrees(math.atan2(-Q[0, 1], Q[1, 1]))]


def obstacle_transform(step, scale=1.0):
    """ParaView's ``Transform`` (``Translate``, ``Rotate``: x' = t + R_z R_x R_y x) that takes the rigid
    obstacles from their initial place to theirs at the summary's ``step`` (its ``translation`` t
    and ``rotation`` Q about the centre c: x = Q (X - c) + c + t; none when it has neither), the
    motion magnified by ``scale`` as the body's displacement is drawn (t and the angle times it)."""
    translation = scale * np.asarray(step.get("translation") or (0.0, 0.0, 0.0), dtype=float)
    rotation = step.get("rotation")
    if not rotation:
        return [float(t) for t in translation], [0.0, 0.0, 0.0]
    Q, centre = rotation_matrix(rotation["axis"], scale * rotation["angle"]), np.asarray(rotation["centre"], float)
    return [float(t) for t in centre - Q @ centre + translation], euler_zxy(Q)


def move_obstacles(moved, step, scale=1.0):
    """Put the obstacles' Transform filters ``moved`` where the summary's ``step`` has them
    (:func:`obstacle_transform`)."""
    translate, rotate = obstacle_transform(step, scale)
    for obstacle in moved:
        obstacle.Transform.Translate, obstacle.Transform.Rotate = translate, rotate


def show_obstacles(view, obstacles, centre, extent, when):
    """The rigid ``obstacles`` (brown, half transparent) about the body's ``centre``: the Transform
    filters that move them (:func:`move_obstacles`; named :data:`OBSTACLE_NAME`) and a caption line
    for each, ``when`` saying at which time they are drawn."""
    from paraview import simple

    moved, captions = [], []
    for k, obstacle in enumerate(obstacles, 1):
        moved.append(simple.Transform(Input=obstacle_source(obstacle, centre, extent)))
        simple.RenameSource(OBSTACLE_NAME.format(k), moved[-1])
        moved[-1].Transform = "Transform"
        shape = simple.Show(moved[-1], view)
        shape.DiffuseColor = shape.AmbientColor = [0.55, 0.45, 0.35]
        shape.Opacity = 0.5
        captions.append(f"brown: the rigid obstacle ({obstacle['type']}) {when}")
    return moved, captions


def drawing_scale(u_max, extent, finite, touching):
    """Factor on the displacement in the deformed view, and its words. True scale for a
    hyperelastic body (``finite`` strain) and wherever bodies touch: magnified, touching bodies
    would be drawn apart or overlapping (contactqvi's bodies.png magnifies a linear body as
    far as they stay touching, which needs the gaps at rest that the files do not hold);
    else the largest displacement ``u_max`` magnified to about 8 % of the body's ``extent``
    (1, 2 or 5 times a power of ten), never shrunk."""
    if finite:
        return 1.0, "true scale (finite strain)"
    if touching:
        return 1.0, "true scale (bodies touch: magnified they would part or overlap)"
    raw = 0.08 * extent / u_max if u_max > 0 else 0.0
    if raw < 2.0:
        return 1.0, "true scale"
    exponent = math.floor(math.log10(raw))
    scale = next(m for m in (5, 2, 1) if m <= raw / 10**exponent) * 10**exponent
    return float(scale), f"displacement magnified \u00d7{scale:g} (nothing touches)"


def _colour(grid, u):
    """(association, label, unit, values shown, caption) of the body's colour: von Mises or |u|."""
    von_mises = field(grid, "von_mises", SOURCES["volume"])
    if von_mises is not None:
        association, values, _ = von_mises
        label, _, unit, factor = FIELDS["von_mises"][2:]
        where = "cell-wise" if association == "CELLS" else "nodal"
        return association, label, unit, values * factor, f"colour: von Mises stress ({where})"
    shown = np.linalg.norm(u, axis=1) * FIELDS["displacement"][5]
    return "POINTS", "displacement magnitude", FIELDS["displacement"][4], shown, "colour: |u| (no von Mises stress)"


def show_body(view, source, u_name, scale):
    """The outline of ``source`` (grey, undeformed) and ``source`` warped by ``u_name`` times
    ``scale``, surface with edges: the warp's display."""
    from paraview import simple

    outline = simple.Show(simple.Outline(Input=source), view)
    outline.DiffuseColor = outline.AmbientColor = [0.45, 0.45, 0.45]
    display = simple.Show(simple.WarpByVector(Input=source, Vectors=["POINTS", u_name], ScaleFactor=scale), view)
    display.Representation, display.EdgeColor = "Surface With Edges", [0.25, 0.25, 0.25]
    return display


def oblique_camera(view, centre, extent, bounds=None):
    """Look at ``centre`` from the front left, above, x3 up; all that is shown in the picture (or
    ``bounds``), clear of the colour bar."""
    from paraview import simple

    view.CameraFocalPoint = centre
    view.CameraPosition = [centre[0] - 1.6 * extent, centre[1] - 2.4 * extent, centre[2] + 1.5 * extent]
    view.CameraViewUp = [0.0, 0.0, 1.0]
    if bounds is None:
        simple.ResetCamera(view)
    else:
        view.ResetCamera(list(bounds))
    view.CameraPosition = [c + 0.95 * (p - c) for p, c in zip(view.CameraPosition, centre)]


def deformed_view(result, path):
    """The body warped by the displacement (true scale at finite strain or where bodies
    touch, :func:`drawing_scale`), coloured by von Mises (or |u|), with the obstacles if described."""
    from paraview import simple

    grid, case = result["volume"], result["case"]
    _, u, u_name = field(grid, "displacement", SOURCES["volume"])
    u = u.reshape(len(u), -1)
    u_max = float(np.linalg.norm(u, axis=1).max())
    b = grid.GetBounds()
    extent = max(b[1] - b[0], b[3] - b[2], b[5] - b[4])
    centre = [(b[0] + b[1]) / 2, (b[2] + b[3]) / 2, (b[4] + b[5]) / 2]
    _, state, _ = field(result["surface"], "contact_state", SOURCES["surface"])
    scale, drawn = drawing_scale(u_max, extent, case["finite_strain"], bool(np.any(np.rint(state) != 0)))
    association, label, unit, shown, what = _colour(grid, u)
    add_array(grid, association, "shown", shown)
    view = new_view()
    display = show_body(view, producer(grid), u_name, scale)
    simple.ColorBy(display, (association, "shown"))
    lut = simple.GetColorTransferFunction("shown")
    lut.ApplyPreset("Turbo" if "von Mises" in label else "Viridis (matplotlib)", True)
    lut.RescaleTransferFunction(0.0, float(shown.max()) or 1.0)
    colour_bar(view, lut, f"{label} ({unit})", shown.max(), position=(0.85, 0.2))
    moved, captions = show_obstacles(view, case.get("obstacles") or [], centre, extent, "at this step")
    move_obstacles(moved, case["step"], scale)
    captions.insert(0, f"{drawn} (largest displacement {u_max * 1e3:.3g} mm); {what}; grey box: undeformed")
    oblique_camera(view, centre, extent)
    add_title(view, f"Deformed body ({case['label']})", "\n".join(captions))
    save(view, path)
