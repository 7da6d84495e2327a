"""What the figures of a contact result show, as data, before anything is drawn.

Each figure of :mod:`contactqvi.contact.figures` is first described by a pure function
of small gathered arrays (rank 0): :func:`bodies_figure` (``bodies.png``) and
:func:`states_figure` (``contact_states.png``) return a :class:`BodiesFigure` and a
:class:`StatesFigure`, which hold what is drawn (meshes, polygons, the obstacles clipped
to the view), the colour ranges and every text; the figures module then only renders
them. Tests read these descriptions, never pixels.

Rules the descriptions follow (issue 46):

* the step shown is named with its load factor and translation; after a failed path the
  text says at which step it failed and that the last converged one is shown
  (:class:`ShownStep`);
* a hyperelastic body is drawn at true scale; a linear one is magnified only when the
  contact nodes that touch stay touching in the picture (:func:`displacement_scale`);
* colour ranges span the 1st-99th percentile (:func:`robust_scale`), the largest value
  and where it is stated beside them;
* a contact group is unrolled only when a cylinder or a sphere fits it
  (:mod:`contactqvi.contact.surface_views`), else drawn flat.
"""

from __future__ import annotations

import dataclasses
import math
import typing

import numpy as np

from contactqvi.contact.nodal import State
from contactqvi.contact.surface import FENCE, robust_range, state_names
from contactqvi.contact.surface_views import SurfaceView, contact_limits, number, surface_views
from contactqvi.load_steps import Rotation, placed
from contactqvi.obstacles import Cylinder, Obstacle, Plane, Sphere, tangent_frames
from contactqvi.paraview import Dataset

__all__ = [
    "BodiesFigure",
    "ColourScale",
    "DrawnState",
    "ObstacleDrawing",
    "ShownStep",
    "StatesFigure",
    "StatesPanel",
    "Surface3D",
    "bodies_figure",
    "camera_direction",
    "displacement_scale",
    "length_text",
    "obstacle_drawing",
    "pressing_nodes",
    "robust_scale",
    "state_labels",
    "states_figure",
]

#: One colour per state (colour-blind safe, Okabe-Ito), by :class:`State` value.
STATE_COLOURS = ["#d9d9d9", "#e69f00", "#0072b2", "#f0e442", "#56b4e9", "#cc79a7", "#009e73"]


def length_text(values: typing.Sequence[float]) -> str:
    """A position or translation in mm to 0.1 um: ``(0, 0, -1.5) mm``, never ``-0``."""
    return "(" + ", ".join(number(round(1e3 * float(v), 4) + 0.0, 8) for v in values) + ") mm"


@dataclasses.dataclass(frozen=True)
class ShownStep:
    """The load step a figure shows, and how the load path ended.

    Attributes:
        step: the step's number (1-based), None for a single solve.
        load: its load factor.
        translation: the translation (m) of the obstacles and moved groups at it.
        rotation: their rotation at it, or None.
        total: the number of steps of the path, or None.
        failed: the number of the step the path failed at (None: it did not fail).
        failed_status: the status that step ended with.
    """

    step: int | None
    load: float
    translation: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rotation: Rotation | None = None
    total: int | None = None
    failed: int | None = None
    failed_status: str = ""

    @classmethod
    def from_summary(cls, summary: dict[str, typing.Any]) -> ShownStep:
        """The last converged step of a run's summary (its ``steps``), and the step after it that failed."""
        steps = summary["steps"]
        shown = max(i for i, entry in enumerate(steps) if entry["converged"])
        entry = steps[shown]
        failed = next((e for e in steps[shown + 1:] if not e["converged"]), None)
        rotation = entry.get("rotation")
        total = len(summary.get("case", {}).get("steps", [])) or None
        return cls(step=entry["step"], load=float(entry["load"]), translation=tuple(entry["translation"]),
                   rotation=None if rotation is None else Rotation(**rotation), total=total,
                   failed=None if failed is None else failed["step"],
                   failed_status="" if failed is None else str(failed.get("status", "")))

    def where(self) -> str:
        """``step 3 of 20``, or '' for a single solve."""
        return "" if self.step is None else f"step {self.step}" + ("" if self.total is None else f" of {self.total}")

    def text(self) -> str:
        """``step 3 of 20: load factor 1, translation (0, 0, -0.225) mm``."""
        where = self.where()
        what = [f"load factor {number(self.load, 4)}"]
        if any(t != 0.0 for t in self.translation):
            what.append(f"translation {length_text(self.translation)}")
        if self.rotation is not None:
            what.append(f"rotation {number(self.rotation.angle, 4)} deg")
        return (where + ": " if where else "") + ", ".join(what)

    def status(self) -> str:
        """``path failed at step 13 (diverged_max_it); showing step 12, the last converged``, or ''."""
        if self.failed is None:
            return ""
        why = f" ({self.failed_status})" if self.failed_status else ""
        return f"path failed at step {self.failed}{why}; showing step {self.step}, the last converged"


@dataclasses.dataclass(frozen=True)
class ColourScale:
    """A colour range and what it stands for.

    Attributes:
        title: the colour bar's title, with the unit shown.
        low, high: the range coloured (in the field's SI unit; values beyond take the end colours).
        log: a logarithmic scale.
        unit, factor: the unit shown and the factor from the SI unit to it.
        largest: the largest value (SI) and ``largest_at`` its reference position (m).
        note: what the range is and where the largest value is, as the picture states it.
    """

    title: str
    low: float
    high: float
    log: bool
    unit: str
    factor: float
    largest: float
    largest_at: tuple[float, float, float]
    note: str


def stress_unit(value: float) -> tuple[str, float]:
    """The unit a stress of size ``value`` (Pa) is shown in, and the factor to it."""
    for unit, factor in (("GPa", 1e-9), ("MPa", 1e-6), ("kPa", 1e-3)):
        if abs(value) * factor >= 1.0:
            return unit, factor
    return "Pa", 1.0


#: Values spanning more than this factor within their 1st-99th percentile get a log colour scale.
LOG_SCALE_RANGE = 100.0


def robust_scale(name: str, values: np.ndarray, at: np.ndarray, what: str, stress_map: bool = False) -> ColourScale:
    """The colour scale of ``values`` (Pa) at positions ``at`` (m): the robust range of the
    positive values (:func:`~contactqvi.contact.surface.robust_range`, fenced unless a ``stress_map``), so that a few
    singular values (corner nodes at a symmetry plane) do not set it; the largest value and
    its position stated in ``note``. A ``stress_map`` starts at zero, or is logarithmic when
    the percentiles span more than :data:`LOG_SCALE_RANGE`.
    ``what`` names the values the percentiles are of."""
    positive = values[values > 0.0]
    low, high = robust_range(positive, not stress_map) if len(positive) else (0.0, 1.0)
    log = bool(stress_map and low * LOG_SCALE_RANGE < high)
    if log:
        low = max(low, 1e-4 * high)
    elif stress_map or high - low <= 1e-6 * high:  # a uniform pressure: from zero
        low = 0.0
    high = max(high, 1e-300)
    top = int(np.argmax(values)) if len(values) else -1
    largest, largest_at = (float(values[top]), at[top]) if top >= 0 else (0.0, np.zeros(3))
    unit, factor = stress_unit(high)
    fence = "" if stress_map else f", within {number(FENCE)} interquartile ranges of the quartiles"
    shown = f"{number(low * factor, 3)} to {number(high * factor, 3)} {unit}" + (", log scale" if log else "")
    note = (f"colours: 1st-99th percentile of {what}{fence} ({shown}); "
            f"largest {number(largest * factor, 3)} {unit} at {length_text(largest_at)}")
    return ColourScale(f"{name} [{unit}]", low, high, log, unit, factor, largest,
                       tuple(float(c) for c in largest_at), note)


#: Displacements above this fraction of the bodies' size are drawn at true scale.
TRUE_SCALE_FRACTION = 0.01
#: A magnified picture may move touching nodes apart or into each other by at most this
#: fraction of the bodies' size (about two pixels of the picture).
TOUCH_TOLERANCE = 2e-3
#: A smaller magnification than this is not worth it: drawn at true scale.
MIN_MAGNIFICATION = 10.0


def _nice_floor(value: float) -> float:
    """The largest 1, 2 or 5 times a power of ten not above ``value``."""
    exponent = math.floor(math.log10(value))
    return next(m for m in (5, 2, 1) if m * 10.0**exponent <= value * (1 + 1e-12)) * 10.0**exponent


def displacement_scale(size: float, largest: float, reference_gap: float, finite_strain: bool,
                       rotated: bool = False, zone: float = 0.0) -> tuple[float, str]:
    """Factor on the displacement drawn and the words that say it.

    A hyperelastic body (``finite_strain``) is drawn at true scale, and so is one whose
    largest displacement is above :data:`TRUE_SCALE_FRACTION` of the bodies' ``size``. A
    linear one is magnified towards a tenth of the size, but only as far as the contact
    nodes that touch stay touching in the picture: magnified s times (the obstacles moved s
    times their translation), a node whose gap at rest was g is drawn (s - 1) |g| off its
    partner, kept below :data:`TOUCH_TOLERANCE` of the size of the touching ``zone`` (of the
    bodies when 0; ``reference_gap``: the largest |g| of the touching nodes; a flat stack's
    zero lets it magnify, a Hertz contact's or a press fit's gap keeps it true). A
    magnification below :data:`MIN_MAGNIFICATION` and rotated obstacles are drawn at true scale."""
    if finite_strain:
        return 1.0, "true scale (finite strain)"
    if largest <= 0.0 or largest >= TRUE_SCALE_FRACTION * size:
        return 1.0, "true scale"
    wanted = 0.1 * size / largest
    touching = 1.0 if rotated else 1.0 + TOUCH_TOLERANCE * (zone or size) / max(reference_gap, 1e-300)
    scale = _nice_floor(min(wanted, touching))
    if scale < MIN_MAGNIFICATION:
        return 1.0, "true scale (bodies touch: magnified they would part or overlap)"
    return scale, f"displacement magnified x{scale:.0f} (touching bodies stay touching)"


@dataclasses.dataclass(frozen=True)
class ObstacleDrawing:
    """A rigid obstacle's surface clipped to the view: polygons (``faces`` into ``points``, m)."""

    label: str
    points: np.ndarray
    faces: np.ndarray


def _plane_polygon(plane: Plane, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """The polygon where ``plane`` cuts the box [low, high] (its corners in order), (k, 3)."""
    corners = np.array([[(low, high)[(i >> k) & 1][k] for k in range(3)] for i in range(8)])
    side = (corners - plane.point) @ plane.normal
    cuts = []
    for i in range(8):
        for k in range(3):
            j = i | (1 << k)
            if j != i and side[i] * side[j] <= 0.0 and side[i] != side[j]:
                cuts.append(corners[i] + side[i] / (side[i] - side[j]) * (corners[j] - corners[i]))
    if len(cuts) < 3:
        return np.zeros((0, 3))
    cuts = np.unique(np.round(np.array(cuts), 15), axis=0)
    e1, e2 = tangent_frames(plane.normal[None])[0, :2]
    centred = cuts - cuts.mean(axis=0)
    return cuts[np.argsort(np.arctan2(centred @ e2, centred @ e1))]


def _grid_faces(rows: int, columns: int) -> np.ndarray:
    """Quadrilaterals of a rows x columns grid of points (row-major)."""
    i, j = np.meshgrid(np.arange(rows - 1), np.arange(columns - 1), indexing="ij")
    first = (i * columns + j).ravel()
    return np.stack([first, first + 1, first + columns + 1, first + columns], axis=1)


def _curved_grid(obstacle: Sphere | Cylinder, low: np.ndarray, high: np.ndarray) -> tuple[np.ndarray, int, int]:
    """Points of a sphere's cap or a cylinder's part facing the box [low, high] (rows, columns)."""
    centre = obstacle.center if isinstance(obstacle, Sphere) else obstacle.point
    axis = obstacle.axis if isinstance(obstacle, Cylinder) else None
    corners = np.array([[(low, high)[(i >> k) & 1][k] for k in range(3)] for i in range(8)]) - centre
    if axis is not None:
        along = corners @ axis
        corners = corners - np.outer(along, axis)
    towards = 0.5 * (low + high) - centre
    towards = towards - (0.0 if axis is None else (towards @ axis) * axis)
    towards = towards / np.linalg.norm(towards) if np.linalg.norm(towards) > 0 else tangent_frames(
        np.array([[0.0, 0.0, 1.0]] if axis is None else axis[None]))[0, 0]
    cosines = corners @ towards / np.maximum(np.linalg.norm(corners, axis=1), 1e-300)
    inside = bool(np.all((centre >= low) & (centre <= high)))
    spread = math.pi if inside else min(math.pi, float(np.arccos(np.clip(cosines.min(), -1.0, 1.0))) + 0.1)
    e1 = np.cross(towards, axis) if axis is not None else tangent_frames(towards[None])[0, 0]
    if axis is not None:
        s, phi = np.meshgrid(np.linspace(along.min(), along.max(), 24), np.linspace(-spread, spread, 97), indexing="ij")
        points = centre + s[..., None] * axis + obstacle.radius * (
            np.cos(phi)[..., None] * towards + np.sin(phi)[..., None] * e1)
        return points.reshape(-1, 3), *s.shape
    e2 = np.cross(towards, e1)
    theta, phi = np.meshgrid(np.linspace(0.0, spread, 49), np.linspace(0.0, 2 * math.pi, 97), indexing="ij")
    direction = (np.cos(theta)[..., None] * towards
                 + np.sin(theta)[..., None] * (np.cos(phi)[..., None] * e1 + np.sin(phi)[..., None] * e2))
    return (centre + obstacle.radius * direction).reshape(-1, 3), *theta.shape


def obstacle_drawing(obstacle: Obstacle, low: np.ndarray, high: np.ndarray, label: str) -> ObstacleDrawing | None:
    """The part of ``obstacle`` (at the step shown) inside the box [low, high]: a plane as the
    polygon it cuts from the box, a sphere or a cylinder as its surface's quadrilaterals whose
    corners all lie in the box; None when none does (the obstacle outside the view)."""
    if isinstance(obstacle, Plane):
        polygon = _plane_polygon(obstacle, low, high)
        return ObstacleDrawing(label, polygon, np.arange(len(polygon))[None]) if len(polygon) else None
    if not isinstance(obstacle, Sphere | Cylinder):
        return None
    points, rows, columns = _curved_grid(obstacle, low, high)
    faces = _grid_faces(rows, columns)
    inside = np.all((points >= low - 1e-12) & (points <= high + 1e-12), axis=1)
    faces = faces[inside[faces].all(axis=1)]
    if len(faces) == 0:
        return None
    used, compact = np.unique(faces, return_inverse=True)
    return ObstacleDrawing(label, points[used], compact.reshape(faces.shape))


@dataclasses.dataclass(frozen=True)
class Surface3D:
    """A surface drawn in 3D: ``points`` where drawn (m), ``cells`` (VTK ``cell_type``), the
    colour ``values`` per cell (``on_cells``) or per point; NaN: drawn grey."""

    points: np.ndarray
    cells: np.ndarray
    cell_type: int
    values: np.ndarray
    on_cells: bool


@dataclasses.dataclass(frozen=True)
class BodiesFigure:
    """``bodies.png``: the deformed bodies coloured by von Mises stress with the rigid
    obstacles, and the contact surfaces coloured by the contact pressure.

    Attributes:
        title: what and which step (``Deformed bodies, step 3 of 4: load factor 0.75``).
        status: how the path ended, when it failed (:meth:`ShownStep.status`), else ''.
        scale, scale_text: the factor on the displacement drawn and its words.
        bodies: the bodies' boundary as drawn, von Mises per cell; ``stress`` its scale.
        obstacles: the rigid obstacles clipped to the view.
        camera: unit vector from the bodies towards the camera.
        contact: the contact surfaces as drawn, pressure per point (NaN where none), or None;
            ``pressure`` its scale, ``contact_title`` its panel's title.
    """

    title: str
    status: str
    scale: float
    scale_text: str
    bodies: Surface3D
    stress: ColourScale
    obstacles: list[ObstacleDrawing]
    camera: np.ndarray
    contact: Surface3D | None = None
    pressure: ColourScale | None = None
    contact_title: str = ""


def camera_direction(centres: np.ndarray, stress: np.ndarray) -> np.ndarray:
    """Unit vector from the bodies towards the camera: the diagonal of the octant of the
    bounding box that holds the largest stress, 35 degrees above (or below) the horizontal, so
    that the region that matters faces the camera (e.g. the symmetry planes through the
    contact of a quarter model, which an isometric view from the positive octant hides)."""
    side = np.sign(centres[np.argmax(stress)] - 0.5 * (centres.min(axis=0) + centres.max(axis=0)))
    side[side == 0.0] = 1.0
    direction = np.array([side[0], side[1], side[2] * np.tan(np.radians(35.0)) * np.sqrt(2.0)])
    return direction / np.linalg.norm(direction)


#: The view of ``bodies.png``: the deformed bodies' bounding box grown by this fraction of its
#: largest side on every side; the obstacles are clipped to it.
VIEW_MARGIN = 0.15


@dataclasses.dataclass(frozen=True)
class DrawnState:
    """What a run tells ``bodies.png`` besides the gathered surfaces.

    Attributes:
        shown: the step shown.
        obstacles: the rigid obstacles in their initial position, with their labels.
        finite_strain: a hyperelastic body.
        reference_gap: the largest gap at rest of the touching contact nodes (m,
            :func:`displacement_scale`).
        pressure_name: the contact pressure's name (:func:`~contactqvi.contact.surface.pressure_label`).
    """

    shown: ShownStep
    obstacles: list[tuple[Obstacle, str]]
    finite_strain: bool
    reference_gap: float
    pressure_name: str


def bodies_figure(bodies: Dataset, contact: Dataset | None, drawn: DrawnState) -> BodiesFigure:
    """The description of ``bodies.png`` from the gathered boundary of the bodies (point data
    ``displacement``, cell data ``von_mises``) and contact surfaces (tributary patches)."""
    points, u = bodies.points, bodies.point_data["displacement"]
    size = float(np.ptp(points, axis=0).max()) if len(points) else 1.0
    largest = float(np.linalg.norm(u, axis=1).max(initial=0.0))
    zone = 0.0
    if contact is not None:
        pressed = contact.points[pressing_nodes(contact)[1]]
        zone = float(np.ptp(pressed, axis=0).max()) if len(pressed) else 0.0
    scale, scale_text = displacement_scale(size, largest, drawn.reference_gap, drawn.finite_strain,
                                           drawn.shown.rotation is not None, zone)
    stress = bodies.cell_data["von_mises"]
    centres = points[bodies.cells].mean(axis=1)
    deformed = points + scale * u
    low, high = deformed.min(axis=0), deformed.max(axis=0)
    margin = VIEW_MARGIN * float((high - low).max())
    translation = scale * np.asarray(drawn.shown.translation)
    obstacles = [obstacle_drawing(placed(obstacle, translation, drawn.shown.rotation), low - margin,
                                  high + margin, f"{label} at {drawn.shown.where() or 'this load'}")
                 for obstacle, label in drawn.obstacles]
    figure = BodiesFigure(
        title=f"Deformed bodies, {drawn.shown.text()}", status=drawn.shown.status(), scale=scale,
        scale_text=scale_text, bodies=Surface3D(deformed, bodies.cells, bodies.cell_type, stress, True),
        stress=robust_scale("von Mises stress", stress, centres, "the boundary cells' values", stress_map=True),
        obstacles=[o for o in obstacles if o is not None], camera=camera_direction(centres, stress))
    if contact is None:
        return figure
    surface, pressure_scale, title = _pressure_panel(contact, scale, drawn.pressure_name)
    return dataclasses.replace(figure, contact=surface, pressure=pressure_scale, contact_title=title)


#: Zoom a panel onto the contact zone when the zone spans less than this fraction of the surface.
ZOOM_FRACTION = 0.25


def pressing_nodes(contact: Dataset) -> tuple[np.ndarray, np.ndarray]:
    """Point indices of the contact surface's nodes (each once, the corner of their patches),
    and of those among them that press (pressure > 0)."""
    nodes = np.unique(contact.cells[:, 0])
    if contact.duplicate is not None:
        nodes = nodes[~contact.duplicate[nodes]]
    pressure = contact.point_data["contact_pressure [Pa]"]
    return nodes, nodes[pressure[nodes] > 0.0]


def _pressure_panel(contact: Dataset, scale: float, name: str) -> tuple[Surface3D, ColourScale, str]:
    """The contact surfaces drawn deformed alike, pressure per point (NaN where none presses),
    zoomed on the pressed zone when it is small (:data:`ZOOM_FRACTION` of the surfaces)."""
    pressure = contact.point_data["contact_pressure [Pa]"]
    _, pressing = pressing_nodes(contact)
    cells = contact.cells
    centres = contact.points[cells].mean(axis=1)
    touching = centres[pressure[cells].max(axis=1) > 0.0]
    keep = np.ones(len(cells), dtype=bool)
    zoomed = len(touching) > 0 and np.all(np.ptp(touching, axis=0) < ZOOM_FRACTION * np.ptp(centres, axis=0) + 1e-300)
    if zoomed:
        margin = 0.5 * float(np.ptp(touching, axis=0).max())
        keep = np.all((centres >= touching.min(axis=0) - margin) & (centres <= touching.max(axis=0) + margin), axis=1)
    used, kept = np.unique(cells[keep], return_inverse=True)
    drawn = (contact.points + scale * contact.point_data["displacement [m]"])[used]
    values = np.where(pressure[used] > 0.0, pressure[used], np.nan)
    colours = robust_scale(name, pressure[pressing], contact.points[pressing], "the pressing nodes' values")
    title = f"{name} on the contact surfaces (slave side; grey: none)" + (
        ", zoomed on the contact zone" if zoomed else "")
    return Surface3D(drawn, kept.reshape(-1, cells.shape[1]), contact.cell_type, values, False), colours, title


@dataclasses.dataclass(frozen=True)
class StatesPanel:
    """One panel of ``contact_states.png``: a contact group's tributary patches in 2D (mm).

    Attributes:
        title: the pair and the view (a plane, an unrolled cylinder ...).
        polygons: (n, 4, 2) patches in the panel's coordinates (mm).
        colours: (n,) index of each patch's state in the figure's ``legend``.
        view: :class:`~contactqvi.contact.surface_views.SurfaceView` (labels, the fit).
        limits: ((x0, x1), (y0, y1)) when zoomed on the contact zone, else None.
    """

    title: str
    polygons: np.ndarray
    colours: np.ndarray
    view: SurfaceView
    limits: tuple[tuple[float, float], tuple[float, float]] | None


@dataclasses.dataclass(frozen=True)
class StatesFigure:
    """``contact_states.png``: ``panels``; ``legend`` (colour, label) of each state listed."""

    title: str
    status: str
    panels: list[StatesPanel]
    legend: list[tuple[str, str]]


def states_figure(contact: Dataset, pair_of_patch: np.ndarray, pair_names: list[str], frictional: list[bool],
                  shown: ShownStep) -> StatesFigure:
    """The description of ``contact_states.png`` from the gathered tributary patches: each
    pair's patches drawn as :func:`~contactqvi.contact.surface_views.surface_views` sees them
    (flat, per plane, or unrolled on a fitted cylinder or sphere)."""
    shown_pairs = [k for k in range(len(pair_names)) if np.any(pair_of_patch == k)]
    labels = state_labels({frictional[k] for k in shown_pairs})
    listed = np.array(list(labels), dtype=int)
    colour_of = np.zeros(len(State), dtype=int)
    colour_of[listed] = np.arange(len(listed))
    state = contact.cell_data["contact_state"]
    pressure = contact.point_data["contact_pressure [Pa]"]
    panels = []
    for k in shown_pairs:
        mine = pair_of_patch == k
        polygons = contact.points[contact.cells[mine]]
        for view, where in surface_views(polygons, pressure[contact.cells[mine, 0]]):
            title = (pair_names[k] + ": " if len(shown_pairs) > 1 else "") + view.title
            plane = view.coordinates
            panels.append(StatesPanel(title, plane, colour_of[state[mine][where]], view,
                                      contact_limits(plane, state[mine][where], ZOOM_FRACTION)))
    legend = [(STATE_COLOURS[s], text + ("" if np.any(state == s) else " (none)")) for s, text in labels.items()]
    names = pair_names[shown_pairs[0]] if len(shown_pairs) == 1 else ", ".join(pair_names[k] for k in shown_pairs)
    return StatesFigure(f"Contact states, {shown.text()}; {names}", shown.status(), panels, legend)


def state_labels(frictional: set[bool]) -> dict[State, str]:
    """Legend text of the states the laws of the pairs drawn can give (``frictional``: their
    ``law.frictional``), a state named differently by the two kinds named both ways."""
    labels: dict[State, list[str]] = {}
    for kind in sorted(frictional, reverse=True):
        for state, name in state_names(kind).items():
            labels.setdefault(state, [])
            if name not in labels[state]:
                labels[state].append(name + (" (frictionless pairs)" if len(frictional) > 1 and not kind else ""))
    return {state: " / ".join(names) for state, names in sorted(labels.items())}
