"""How a contact group is laid flat for ``contact_states.png``: pure geometry on its patches.

A group (one pair's slave patches, reference positions) is drawn

* flat, in its plane's own coordinates (global axes when the plane is a coordinate plane),
  when all its points lie in one plane (:data:`FLAT_TOLERANCE`);
* unrolled, when a cylinder or a sphere fitted by least squares matches it (relative rms
  error at most :data:`FIT_TOLERANCE`, stated in the panel): a cylinder by arc length and
  position along its axis, the arc measured from a symmetry plane the arc ends on (a
  coordinate plane through its end) or else from the crown (the centre of the pressed
  zone); a sphere by geodesic distance from the crown (azimuthal equidistant);
* flat per plane when it is made of a few planes (an L-shaped group: a top face and a
  side), one view each;
* else projected along its mean normal, which the panel says.

Coordinates are in mm; no text shows ``-0``.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from contactqvi.obstacles import tangent_frames

__all__ = ["FIT_TOLERANCE", "FLAT_TOLERANCE", "SurfaceView", "contact_limits", "number", "surface_views"]

#: A group is flat when no point is farther from its best plane than this fraction of its extent.
FLAT_TOLERANCE = 1e-3
#: A fitted cylinder or sphere is accepted when the rms distance of the points from it is at
#: most this fraction of its radius.
FIT_TOLERANCE = 1e-2
#: Facet normals within this angle (degrees) belong to one plane of a piecewise flat group.
PLANE_ANGLE = 5.0
#: At most this many planes are drawn one by one; a group of more is projected.
MAX_PLANES = 4


def number(value: float, digits: int = 3) -> str:
    """``value`` to ``digits`` significant digits, never ``-0`` (a rounded -1e-17 is ``0``)."""
    text = f"{value:.{digits}g}"
    return "0" if float(text) == 0.0 else text


def _vector_text(vector: np.ndarray) -> str:
    return "(" + ", ".join(number(round(float(c), 2) + 0.0, 2) for c in vector) + ")"


@dataclasses.dataclass(frozen=True)
class SurfaceView:
    """A group's patches in 2D.

    Attributes:
        kind: ``flat``, ``plane`` (one plane of several), ``cylinder``, ``sphere`` or ``projected``.
        title: the view in words (``plane x3 = 5 mm``, ``cylinder of radius 20 mm unrolled``).
        labels: the axis labels (mm).
        coordinates: (n, 4, 2) the patches the view shows, in its coordinates (mm).
        fit_error: the fitted cylinder's or sphere's rms error relative to its radius, or None.
    """

    kind: str
    title: str
    labels: tuple[str, str]
    coordinates: np.ndarray
    fit_error: float | None = None


def _area_vectors(polygons: np.ndarray) -> np.ndarray:
    """Twice the area times the unit normal of each (planar) quadrilateral patch."""
    return np.cross(polygons[:, 2] - polygons[:, 0], polygons[:, 3] - polygons[:, 1])


def _plane_view(polygons: np.ndarray, normal: np.ndarray, kind: str, title: str) -> SurfaceView:
    """``polygons`` seen along ``normal``: global axes when it is a coordinate axis."""
    axis = int(np.argmax(np.abs(normal)))
    points = polygons.reshape(-1, 3)
    if np.isclose(abs(normal[axis]), 1.0, atol=1e-8):
        a, b = [i for i in range(3) if i != axis]
        frame = np.eye(3)[[a, b]]
        labels = (f"x{a + 1} [mm]", f"x{b + 1} [mm]")
        where = f"x{axis + 1} = {number(1e3 * float(np.median(points[:, axis])), 4)} mm"
    else:
        frame = tangent_frames(normal[None])[0, :2]
        labels = tuple(f"along t{i + 1} = {_vector_text(t)} [mm]" for i, t in enumerate(frame))
        where = f"normal {_vector_text(normal)}"
    return SurfaceView(kind, title.format(where=where), labels, 1e3 * polygons @ frame.T)


def _plane_fit(points: np.ndarray) -> tuple[np.ndarray, float]:
    """Unit normal of the best plane through ``points`` and their largest distance from it
    relative to their extent."""
    centred = points - points.mean(axis=0)
    normal = np.linalg.svd(centred, full_matrices=False)[2][-1]
    extent = float(np.ptp(points, axis=0).max()) or 1.0
    return normal, float(np.abs(centred @ normal).max(initial=0.0)) / extent


def _fit_cylinder(points: np.ndarray, areas: np.ndarray) -> tuple[np.ndarray, np.ndarray, float, float]:
    """Axis (the direction the normals are perpendicular to), a point on it, radius and rms
    radial error relative to the radius of the cylinder fitted to ``points`` (Kasa's circle,
    least squares, in the plane normal to the axis)."""
    scatter = np.einsum("ni,nj->ij", areas, areas / np.maximum(np.linalg.norm(areas, axis=1), 1e-300)[:, None])
    axis = np.linalg.eigh(scatter)[1][:, 0]
    e1, e2 = tangent_frames(axis[None])[0, :2]
    p, q = points @ e1, points @ e2
    (a, b, c), *_ = np.linalg.lstsq(np.column_stack([2 * p, 2 * q, np.ones_like(p)]), p**2 + q**2, rcond=None)
    radius = float(np.sqrt(max(c + a * a + b * b, 0.0))) or 1e-300
    error = float(np.sqrt(np.mean((np.hypot(p - a, q - b) - radius) ** 2))) / radius
    return axis, a * e1 + b * e2, radius, error


def _fit_sphere(points: np.ndarray) -> tuple[np.ndarray, float, float]:
    """Centre, radius and rms error relative to the radius of the sphere fitted to ``points``
    (|x|^2 = 2 c . x + k, least squares)."""
    (cx, cy, cz, k), *_ = np.linalg.lstsq(np.column_stack([2 * points, np.ones(len(points))]),
                                          np.sum(points**2, axis=1), rcond=None)
    centre = np.array([cx, cy, cz])
    radius = float(np.sqrt(max(k + centre @ centre, 0.0))) or 1e-300
    error = float(np.sqrt(np.mean((np.linalg.norm(points - centre, axis=1) - radius) ** 2))) / radius
    return centre, radius, error


def _wrapped(angle: np.ndarray) -> np.ndarray:
    return np.angle(np.exp(1j * angle))


def _crown(directions: np.ndarray, pressure: np.ndarray) -> tuple[np.ndarray, str]:
    """The mean of unit ``directions`` weighted by ``pressure`` (the centre of the pressed
    zone), or unweighted when nothing presses; and its name."""
    pressed = pressure > 0.0
    weights = pressure if np.any(pressed) else np.ones(len(directions))
    mean = weights @ directions
    return mean / (np.linalg.norm(mean) or 1.0), "the crown" if np.any(pressed) else "the middle"


def _symmetry_end(points: np.ndarray, relative: np.ndarray, extent: float) -> tuple[float, int] | None:
    """The end angle of an arc whose points all lie on a coordinate plane x_k = 0 (a symmetry
    plane of a partial model), with k; None when neither end does."""
    for end in (relative.min(), relative.max()):
        at_end = points[np.abs(relative - end) < 1e-6]
        for k in range(3):
            if np.all(np.abs(at_end[:, k]) <= 1e-6 * extent):
                return float(end), k
    return None


def _unrolled_cylinder(polygons: np.ndarray, pressure: np.ndarray, areas: np.ndarray) -> SurfaceView | None:
    """The group unrolled on its fitted cylinder (None when the fit is off): arc length from
    a symmetry plane its arc ends on, else from the crown, and the position along the axis."""
    points = polygons.reshape(-1, 3)
    axis, centre, radius, error = _fit_cylinder(points, areas)
    if error > FIT_TOLERANCE:
        return None
    e1, e2 = tangent_frames(axis[None])[0, :2]
    radial = points - centre - np.outer(points @ axis, axis)
    angle = np.arctan2(radial @ e2, radial @ e1)
    direction, _ = _crown(np.column_stack([np.cos(angle), np.sin(angle)]), np.ones(len(angle)))
    relative = _wrapped(angle - np.arctan2(direction[1], direction[0]))
    end = _symmetry_end(points, relative, float(np.ptp(points, axis=0).max()))
    if end is not None:
        origin, sign = end[0], (1.0 if end[0] == relative.min() else -1.0)
        start = f"the plane x{end[1] + 1} = 0"
    else:
        node_angle = relative.reshape(polygons.shape[:2])[:, 0]
        crown, start = _crown(np.column_stack([np.cos(node_angle), np.sin(node_angle)]), pressure)
        origin, sign = float(np.arctan2(crown[1], crown[0])), 1.0
    arc = 1e3 * radius * sign * _wrapped(relative - origin)
    along = 1e3 * points @ axis
    coordinates = np.stack([arc, along], axis=-1).reshape(*polygons.shape[:2], 2)
    title = (f"unrolled on the fitted cylinder: radius {number(1e3 * radius, 4)} mm, "
             f"axis {_vector_text(axis)}, rms error {number(round(100 * error, 3) + 0.0, 2)} % of the radius")
    labels = (f"arc length from {start} [mm]", f"along the axis {_vector_text(axis)} [mm]")
    return SurfaceView("cylinder", title, labels, coordinates, error)


def _unrolled_sphere(polygons: np.ndarray, pressure: np.ndarray) -> SurfaceView | None:
    """The group mapped from its fitted sphere (None when the fit is off), azimuthal
    equidistant about the crown: distances from the crown along the sphere kept."""
    points = polygons.reshape(-1, 3)
    centre, radius, error = _fit_sphere(points)
    if error > FIT_TOLERANCE:
        return None
    radial = points - centre
    radial /= np.maximum(np.linalg.norm(radial, axis=1), 1e-300)[:, None]
    crown, start = _crown(radial.reshape(*polygons.shape)[:, 0], pressure)
    e1, e2 = tangent_frames(crown[None])[0, :2]
    polar = np.arccos(np.clip(radial @ crown, -1.0, 1.0))
    azimuth = np.arctan2(radial @ e2, radial @ e1)
    coordinates = 1e3 * radius * polar[:, None] * np.column_stack([np.cos(azimuth), np.sin(azimuth)])
    title = (f"mapped from the fitted sphere (distances from {start} kept): radius {number(1e3 * radius, 4)} mm, "
             f"rms error {number(round(100 * error, 3) + 0.0, 2)} % of the radius")
    labels = tuple(f"geodesic distance from {start} towards t{i + 1} = {_vector_text(t)} [mm]"
                   for i, t in enumerate((e1, e2)))
    return SurfaceView("sphere", title, labels, coordinates.reshape(*polygons.shape[:2], 2), error)


def _planes(polygons: np.ndarray, areas: np.ndarray) -> list[np.ndarray] | None:
    """The group's patches split into planes (normals within :data:`PLANE_ANGLE`, each flat),
    or None when it is not made of at most :data:`MAX_PLANES` planes."""
    normals = areas / np.maximum(np.linalg.norm(areas, axis=1), 1e-300)[:, None]
    label = np.full(len(normals), -1)
    for k in range(MAX_PLANES + 1):
        free = np.flatnonzero(label < 0)
        if len(free) == 0:
            break
        label[free[np.abs(normals[free] @ normals[free[0]]) >= np.cos(np.radians(PLANE_ANGLE))]] = k
    if np.any(label < 0) or label.max() >= MAX_PLANES:
        return None
    masks = [label == k for k in range(label.max() + 1)]
    flat = all(_plane_fit(polygons[m].reshape(-1, 3))[1] <= FLAT_TOLERANCE for m in masks)
    return masks if flat else None


def surface_views(polygons: np.ndarray, pressure: np.ndarray) -> list[tuple[SurfaceView, np.ndarray]]:
    """The views of a group's patches ``polygons`` (n, 4, 3; m), with the pressure at each
    patch's node (n,): one view of all (flat, unrolled on a fitted cylinder or sphere,
    projected), or one per plane; each with the mask of the patches it shows."""
    everything = np.ones(len(polygons), dtype=bool)
    normal, deviation = _plane_fit(polygons.reshape(-1, 3))
    if deviation <= FLAT_TOLERANCE:
        return [(_plane_view(polygons, normal, "flat", "plane {where}"), everything)]
    areas = _area_vectors(polygons)
    fitted = _unrolled_cylinder(polygons, pressure, areas) or _unrolled_sphere(polygons, pressure)
    if fitted is not None:  # a cylinder first: a short strip of one also lies on a sphere
        return [(fitted, everything)]
    planes = _planes(polygons, areas)
    if planes is not None:
        return [(_plane_view(polygons[m], _plane_fit(polygons[m].reshape(-1, 3))[0], "plane",
                             f"plane {k + 1} of {len(planes)}, {{where}}"), m) for k, m in enumerate(planes)]
    mean = areas.sum(axis=0)
    mean = mean / np.linalg.norm(mean) if np.linalg.norm(mean) > 0 else normal
    return [(_plane_view(polygons, mean, "projected", "projected along the mean {where}"), everything)]


def contact_limits(plane: np.ndarray, state: np.ndarray, fraction: float
                   ) -> tuple[tuple[float, float], tuple[float, float]] | None:
    """Axis limits on the patches ``plane`` (n, 4, 2) in contact (``state`` not 0) with a margin
    of half their extent, when they span less than ``fraction`` of the patches' extent (a
    Hertz zone on a large block is otherwise a dot in a corner); None: no zoom."""
    touching = plane[state != 0].reshape(-1, 2)
    if len(touching) == 0:
        return None
    points = plane.reshape(-1, 2)
    low, high, full_low, full_high = touching.min(0), touching.max(0), points.min(0), points.max(0)
    if np.any(high - low >= fraction * (full_high - full_low)):
        return None
    margin = 0.5 * float((high - low).max())
    return ((float(max(low[0] - margin, full_low[0])), float(min(high[0] + margin, full_high[0]))),
            (float(max(low[1] - margin, full_low[1])), float(min(high[1] + margin, full_high[1]))))
