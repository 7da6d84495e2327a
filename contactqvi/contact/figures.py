"""Figures of a solved contact problem, drawn on rank 0 from small gathered surfaces.

* :func:`plot_contact_states`: the contact states on each pair's surface (seed 000,
  Fig. 2), with matplotlib (Agg, no display) from the tributary patches of every rank;
* :func:`plot_deformed_bodies`: a 3D view of the deformed bodies coloured by von Mises
  stress, with pyvista (off screen, on a virtual X display made for the drawing when
  there is none), from the owned boundary facets of every rank;
* :func:`plot_forces`: the contact forces and support reactions along the load path
  (:mod:`contactqvi.contact.force_history`), from the summary.

Only surfaces of at most :data:`contactqvi.tables.GATHER_MAX_NODES` nodes are drawn.
A figure never ends a run: a failure is logged and the figure skipped.
"""

from __future__ import annotations

import contextlib
import logging
import os
import pathlib
import subprocess
import typing

from mpi4py import MPI

import numpy as np

from dolfinx import fem
from dolfinx import mesh as dmesh

from contactqvi.contact.force_history import plot_force_history
from contactqvi.contact.interface import BodyPair, Pair
from contactqvi.contact.nodal import State
from contactqvi.contact.problem import ContactProblem
from contactqvi.contact.surface import ContactSurface, state_names, vertex_blocks
from contactqvi.paraview import Dataset, gather_pieces
from contactqvi.tables import GATHER_MAX_NODES, atomic_path

__all__ = ["plot_contact_states", "plot_deformed_bodies", "plot_forces"]

logger = logging.getLogger(__name__)

#: One colour per state (colour-blind safe, Okabe-Ito), by :class:`State` value.
_STATE_COLOURS = ["#d9d9d9", "#e69f00", "#0072b2", "#f0e442", "#56b4e9", "#cc79a7", "#009e73"]


def plot_contact_states(path: str | os.PathLike, surface: ContactSurface, step: int | None = None) -> bool:
    """PNG of the contact surfaces coloured by contact state (seed 000, Fig. 2), one panel per pair.

    The tributary patch of each node (:class:`~contactqvi.contact.surface.TributaryPatches`)
    gets its state's colour, the states named for the pair's law
    (:func:`~contactqvi.contact.surface.state_names`: frictionless contact is "in contact").
    Each contact pair's slave surface is seen along its mean normal, with axes in m (global
    x1, x2 ... when the normal is a coordinate axis). The title names the load step (``step``,
    else the problem's load factor and obstacle translation) and the pair(s), slave on master.
    Returns whether the PNG was written: not for surfaces of more than
    ``GATHER_MAX_NODES`` nodes, nor when matplotlib fails (a figure never ends a run).
    Collective.
    """
    comm = surface.mesh.comm
    if surface.n_nodes > GATHER_MAX_NODES:
        logger.info("%s is skipped: %d surface nodes > %d (drawn on one rank)", path, surface.n_nodes, GATHER_MAX_NODES)
        return False
    dataset = gather_pieces(comm, surface.dataset())
    pairs = [interface.pair for interface in surface.problem.interfaces]
    vertices = 4 if surface.mesh.topology.cell_type == dmesh.CellType.quadrilateral else 3
    title = f"Contact states, {_step_text(surface.problem, step)}"
    return _draw_on_rank_0(comm, path, lambda tmp: _draw_states(
        tmp, dataset, _facet_pair(dataset.cell_data["contact_pair"], vertices), pairs, title))


def plot_deformed_bodies(path: str | os.PathLike, displacement: fem.Function, von_mises: fem.Function,
                         touching: bool = False, surface: ContactSurface | None = None) -> bool:
    """PNG of the bodies' boundary, deformed and coloured by the von Mises stress, and beside it
    the contact surfaces of ``surface`` (updated to the same step) deformed alike and coloured
    by the contact pressure.

    ``displacement``: P1 displacement (m); ``von_mises``: DG0 von Mises stress (Pa), each
    boundary facet coloured by its cell's value. Drawn at true scale when bodies touch each
    other (``touching``: a magnified displacement would draw them overlapping or apart where
    they touch) or when the displacement is large (:func:`_displacement_scale`), else
    magnified so that the largest displacement is a tenth of the bodies' size; the title
    says which. Returns whether the PNG was written (not above ``GATHER_MAX_NODES``
    boundary points). Collective.
    """
    comm = displacement.function_space.mesh.comm
    piece = _boundary_piece(displacement, von_mises)
    points = comm.allreduce(len(piece.points), op=MPI.SUM)
    if points > GATHER_MAX_NODES:
        logger.info("%s is skipped: %d boundary points > %d (drawn on one rank)", path, points, GATHER_MAX_NODES)
        return False
    dataset = gather_pieces(comm, piece)
    contact = None if surface is None or surface.n_nodes > GATHER_MAX_NODES else gather_pieces(comm, surface.dataset())
    return _draw_on_rank_0(comm, path, lambda tmp: _draw_bodies(tmp, dataset, touching, contact))


def plot_forces(path: str | os.PathLike, steps: typing.Sequence[dict[str, typing.Any]], comm: MPI.Comm) -> bool:
    """PNG of the pairs' contact forces and the supports' reactions along the load path (the
    summary's ``steps``; :func:`~contactqvi.contact.force_history.plot_force_history`). Returns
    whether it was written. Collective."""
    return _draw_on_rank_0(comm, path, lambda tmp: plot_force_history(tmp, steps))


def _draw_on_rank_0(comm: MPI.Comm, path: str | os.PathLike, draw: typing.Callable[[pathlib.Path], None]) -> bool:
    """Call ``draw`` with a temporary file on rank 0, moved to ``path`` when it succeeded."""
    ok = False
    if comm.rank == 0:
        try:
            with atomic_path(MPI.COMM_SELF, path) as tmp:
                draw(tmp)
            ok = True
        except Exception as exc:  # a figure must never end a solve (nor leave the other ranks waiting)
            logger.warning("%s is skipped: %s", path, exc)
    return bool(comm.bcast(ok, root=0))


def _boundary_piece(displacement: fem.Function, von_mises: fem.Function) -> Dataset:
    """This rank's owned boundary facets with the displacement at their nodes and von Mises per facet."""
    V = displacement.function_space
    msh = V.mesh
    fdim = msh.topology.dim - 1
    msh.topology.create_connectivity(fdim, msh.topology.dim)
    msh.topology.create_connectivity(fdim, 0)
    facets = dmesh.exterior_facet_indices(msh.topology)
    facets = facets[facets < msh.topology.index_map(fdim).size_local]
    quadrilateral = msh.topology.cell_type == dmesh.CellType.hexahedron
    facet_vertices = msh.topology.connectivity(fdim, 0).array.reshape(-1, 4 if quadrilateral else 3)[facets]
    if quadrilateral:  # DOLFINx's tensor-product order to VTK's order round the quadrilateral
        facet_vertices = facet_vertices[:, [0, 1, 3, 2]]
    nodes, cells = np.unique(vertex_blocks(V)[facet_vertices], return_inverse=True)
    facet_cells = msh.topology.connectivity(fdim, msh.topology.dim)
    cell = facet_cells.array[facet_cells.offsets[facets]]  # a boundary facet has one cell
    return Dataset(
        points=V.tabulate_dof_coordinates()[nodes], cells=cells.reshape(len(facets), -1), cell_type=9 if quadrilateral else 5,
        point_data={"displacement": displacement.x.array.reshape(-1, 3)[nodes]},
        cell_data={"von_mises": von_mises.x.array[von_mises.function_space.dofmap.list[cell, 0]]},
    )


@contextlib.contextmanager
def _display() -> typing.Iterator[None]:
    """An X display for VTK: the user's, or a virtual one (Xvfb) for the duration of the block."""
    if os.environ.get("DISPLAY"):
        yield
        return
    read, write = os.pipe()
    server = subprocess.Popen(["Xvfb", "-displayfd", str(write), "-screen", "0", "1600x1200x24", "-nolisten", "tcp"],
                              pass_fds=(write,), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    os.close(write)
    with os.fdopen(read) as pipe:
        number = pipe.readline().strip()
    os.environ["DISPLAY"] = f":{number}"
    try:
        yield
    finally:
        del os.environ["DISPLAY"]
        server.terminate()
        server.wait(10)


def _draw_bodies(path: pathlib.Path, dataset: Dataset, touching: bool, contact: Dataset | None) -> None:
    import pyvista

    points, u = dataset.points, dataset.point_data["displacement"]
    stress = dataset.cell_data["von_mises"]
    scale = 1.0 if touching else _displacement_scale(points, u)
    drawn = "true scale" if scale == 1.0 else f"displacement x {scale:.3g}"
    grid = pyvista.UnstructuredGrid({dataset.cell_type: dataset.cells}, points + scale * u)
    name = "von Mises stress [Pa]"
    grid.cell_data[name] = stress
    limits, log_scale = _stress_colour_range(stress)
    camera = [tuple(_camera_direction(grid.cell_centers().points, stress)), (0.0, 0.0, 0.0), (0.0, 0.0, 1.0)]
    with _display():
        plotter = pyvista.Plotter(off_screen=True, window_size=(1600 if contact is None else 2800, 1200),
                                  shape=(1, 1 if contact is None else 2))
        try:
            plotter.add_mesh(grid, scalars=name, cmap="viridis", clim=limits, log_scale=log_scale, show_edges=True,
                             edge_color="#404040", line_width=0.3, scalar_bar_args={"vertical": True, "fmt": "%.3g"})
            plotter.add_text(f"deformed bodies ({drawn}); von Mises stress per cell"
                             + (" (log scale)" if log_scale else ""), font_size=12)
            # looking along -direction at the bodies (reset_camera keeps the direction and fits them in)
            plotter.camera_position = camera
            plotter.reset_camera()
            plotter.show_axes()
            if contact is not None:
                plotter.subplot(0, 1)
                _add_contact_pressure(plotter, contact, scale, camera)
            image = plotter.screenshot(None, return_img=True)
        finally:
            plotter.close()
    import matplotlib.image

    matplotlib.image.imsave(path, image, format="png")


def _add_contact_pressure(plotter: typing.Any, contact: Dataset, scale: float, camera: list) -> None:
    """The contact surfaces (tributary patches) deformed by ``scale`` times their displacement,
    coloured by the contact pressure, seen from the bodies' camera direction; only the patches
    near the contact zone when it spans less than :data:`ZOOM_FRACTION` of the surfaces (a
    Hertz zone on a large block)."""
    import pyvista

    pressure = contact.point_data["contact_pressure [Pa]"]
    cells = contact.cells
    centres = contact.points[cells].mean(axis=1)
    touching = centres[pressure[cells].max(axis=1) > 0.0]
    keep = np.ones(len(cells), dtype=bool)
    zoomed = len(touching) > 0 and np.all(np.ptp(touching, axis=0) < ZOOM_FRACTION * np.ptp(centres, axis=0) + 1e-300)
    if zoomed:
        margin = 0.5 * float(np.ptp(touching, axis=0).max())
        keep = np.all((centres >= touching.min(axis=0) - margin) & (centres <= touching.max(axis=0) + margin), axis=1)
    used, kept = np.unique(cells[keep], return_inverse=True)  # only the points drawn (the camera fits them)
    grid = pyvista.UnstructuredGrid({contact.cell_type: kept.reshape(-1, cells.shape[1])},
                                    (contact.points + scale * contact.point_data["displacement [m]"])[used])
    name = "contact pressure [Pa]"
    grid.point_data[name] = pressure[used]
    plotter.add_mesh(grid, scalars=name, cmap="inferno", clim=(0.0, max(float(pressure.max(initial=0.0)), 1.0)),
                     lighting=False, scalar_bar_args={"vertical": True, "fmt": "%.3g"})
    plotter.add_text("contact pressure on the deformed contact surfaces (slave side)"
                     + (", zoomed on the contact zone" if zoomed else ""), font_size=12)
    plotter.camera_position = camera
    plotter.reset_camera()
    plotter.show_axes()


#: Displacements above this fraction of the bodies' size are drawn at true scale (finite
#: strain, large sliding: a magnified picture would be a different shape).
TRUE_SCALE_FRACTION = 0.01


def _displacement_scale(points: np.ndarray, u: np.ndarray) -> float:
    """Factor on the displacement drawn: 1 when the largest displacement is above
    :data:`TRUE_SCALE_FRACTION` of the bodies' size, else the factor that magnifies it to a
    tenth of that size."""
    largest = float(np.linalg.norm(u, axis=1).max(initial=0.0))
    size = float(np.ptp(points, axis=0).max())
    return 0.1 * size / largest if 0.0 < largest < TRUE_SCALE_FRACTION * size else 1.0


#: Stresses spanning more than this factor are coloured on a log scale (contact stresses are
#: concentrated: on a linear scale all but the contact zone has the colour of zero).
LOG_SCALE_RANGE = 100.0


def _stress_colour_range(stress: np.ndarray) -> tuple[tuple[float, float], bool]:
    """Colour limits of the von Mises stress and whether to use a log scale: linear from 0 when
    the stresses span less than :data:`LOG_SCALE_RANGE`, else logarithmic over the top four
    decades (lower values take the lowest colour)."""
    top = float(stress.max(initial=0.0))
    positive = stress[stress > 0.0]
    if top <= 0.0 or positive.min() * LOG_SCALE_RANGE > top:
        return (0.0, max(top, 1.0)), False
    return (max(float(positive.min()), 1e-4 * top), top), True


def _camera_direction(centres: np.ndarray, stress: np.ndarray) -> np.ndarray:
    """Unit vector from the bodies towards the camera: the diagonal of the octant of the
    bounding box that holds the largest stress, 35 degrees above (or below) the horizontal, so
    that the region that matters faces the camera (e.g. the symmetry planes through the
    contact of a quarter model, which an isometric view from the positive octant hides)."""
    side = np.sign(centres[np.argmax(stress)] - 0.5 * (centres.min(axis=0) + centres.max(axis=0)))
    side[side == 0.0] = 1.0
    direction = np.array([side[0], side[1], side[2] * np.tan(np.radians(35.0)) * np.sqrt(2.0)])
    return direction / np.linalg.norm(direction)


def _step_text(problem: ContactProblem, step: int | None) -> str:
    """``step 6``, or without a step number the load factor and, if moved, the obstacles' translation."""
    if step is not None:
        return f"step {step}"
    moved = np.any(problem.translation != 0.0)
    return f"load factor {problem.load_factor:g}" + (
        f", obstacles moved by ({', '.join(f'{t:.3g}' for t in problem.translation)}) m" if moved else "")


def _pair_text(pair: Pair) -> str:
    """A contact pair in an engineer's words: ``upper.interface on lower.interface``,
    ``contact on the sphere`` (the obstacle's kind)."""
    if isinstance(pair, BodyPair):
        return f"{pair.slave} on {pair.master}"
    return f"{pair.surface} on the {type(pair.obstacle).__name__.lower()}"


def _state_labels(frictional: set[bool]) -> dict[State, str]:
    """Legend text of the states the laws of the pairs drawn can give (``frictional``: their
    ``law.frictional``), a state named differently by the two kinds named both ways."""
    labels: dict[State, list[str]] = {}
    for kind in sorted(frictional, reverse=True):
        for state, name in state_names(kind).items():
            labels.setdefault(state, [])
            if name not in labels[state]:
                labels[state].append(name + (" (frictionless pairs)" if len(frictional) > 1 and not kind else ""))
    return {state: " / ".join(names) for state, names in sorted(labels.items())}


def _facet_pair(pair: np.ndarray, vertices: int) -> np.ndarray:
    """The pair of each patch's facet: patches come in runs of ``vertices`` per facet, and a
    node without a contact law (-1, a supported node) takes the pair of its facet's other nodes."""
    return np.repeat(pair.reshape(-1, vertices).max(axis=1), vertices)


#: A surface whose facet normals lie in one plane within this (the smallest eigenvalue of their
#: area-weighted scatter, relative to the largest), but not in one direction, is drawn unrolled
#: about the axis normal to that plane (a cylinder's arc by its length).
CURVED = 1e-2


def _plan_view(polygons: np.ndarray) -> tuple[np.ndarray, list[str]]:
    """In-plane coordinates of ``polygons`` (n, 4, 3) and axis labels: a flat surface (or a
    doubly curved one, a Hertz zone) seen along its mean normal; a singly curved one (a bore, a
    shaft, a roller's track: normals perpendicular to one axis) unrolled, along the axis and
    by arc length on the circle fitted to it, so that a 90 degree arc of radius b is pi b / 2
    long in the picture, not its chord."""
    from contactqvi.obstacles import tangent_frames

    areas = np.cross(polygons[:, 2] - polygons[:, 0], polygons[:, 3] - polygons[:, 1])
    scatter = np.einsum("ni,nj->ij", areas, areas / np.maximum(np.linalg.norm(areas, axis=1), 1e-300)[:, None])
    values, vectors = np.linalg.eigh(scatter)
    if values[0] <= CURVED * values[2] < values[1]:  # normals spread in one plane only
        return _unrolled(polygons, vectors[:, 0])
    mean_normal = areas.sum(axis=0)
    mean_normal /= np.linalg.norm(mean_normal)
    axis = np.argmax(np.abs(mean_normal))
    if np.isclose(abs(mean_normal[axis]), 1.0, atol=1e-8):  # a coordinate plane: global axes
        a, b = [i for i in range(3) if i != axis]
        frame = np.eye(3)[[a, b]]
        labels = [f"x{a + 1} [m]", f"x{b + 1} [m]"]
    else:
        frame = tangent_frames(mean_normal[None])[0, :2]
        labels = [f"t{i + 1} = ({', '.join(f'{c:.2f}' for c in t)}) [m]" for i, t in enumerate(frame)]
    return polygons @ frame.T, labels


def _unrolled(polygons: np.ndarray, axis: np.ndarray) -> tuple[np.ndarray, list[str]]:
    """``polygons`` of a surface curved about ``axis`` unrolled: the arc length on the circle
    fitted (least squares) to the points projected on the plane normal to it, from the mean
    direction of the points, and the coordinate along the axis; the longer one first."""
    from contactqvi.obstacles import tangent_frames

    axis = axis / np.linalg.norm(axis)
    e1, e2 = tangent_frames(axis[None])[0, :2]
    points = polygons.reshape(-1, 3)
    p, q = points @ e1, points @ e2
    # x^2 + y^2 = 2 a x + 2 b y + c: centre (a, b), radius^2 = c + a^2 + b^2 (Kasa's fit)
    (a, b, c), *_ = np.linalg.lstsq(np.column_stack([2 * p, 2 * q, np.ones_like(p)]), p**2 + q**2, rcond=None)
    radius = float(np.sqrt(c + a * a + b * b))
    angle = np.arctan2(q - b, p - a)
    middle = np.arctan2(np.sin(angle).mean(), np.cos(angle).mean())
    arc = radius * np.angle(np.exp(1j * (angle - middle)))
    along = points @ axis
    direction = ", ".join(f"{v + 0.0:.2f}" for v in axis)
    labels = [f"arc length on radius {radius:.4g} m [m]", f"along the axis ({direction}) [m]"]
    coordinates = [arc, along]
    if np.ptp(along) > np.ptp(arc):  # the longer extent across the picture
        coordinates, labels = coordinates[::-1], labels[::-1]
    return np.stack(coordinates, axis=-1).reshape(*polygons.shape[:2], 2), labels


#: Zoom a panel onto the contact zone when the zone spans less than this fraction of the surface.
ZOOM_FRACTION = 0.25


def _zoom_to_contact(ax: typing.Any, plane: np.ndarray, state: np.ndarray) -> bool:
    """Limit the panel's axes to the patches in contact with a margin of half their extent,
    when they cover less than :data:`ZOOM_FRACTION` of the surface's extent (a Hertz contact
    zone on a large block is otherwise a dot in a corner); whether it zoomed."""
    touching = plane[state != State.NO_CONTACT].reshape(-1, 2)
    if len(touching) == 0:
        return False
    points = plane.reshape(-1, 2)
    low, high, full_low, full_high = touching.min(0), touching.max(0), points.min(0), points.max(0)
    if np.any(high - low >= ZOOM_FRACTION * (full_high - full_low)):
        return False
    margin = 0.5 * float((high - low).max())
    ax.set_xlim(max(low[0] - margin, full_low[0]), min(high[0] + margin, full_high[0]))
    ax.set_ylim(max(low[1] - margin, full_low[1]), min(high[1] + margin, full_high[1]))
    return True


def _draw_states(path: pathlib.Path, dataset: Dataset, pair: np.ndarray, pairs: list[Pair], title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection
    from matplotlib.colors import BoundaryNorm, ListedColormap

    shown = [k for k in range(len(pairs)) if np.any(pair == k)]
    labels = _state_labels({pairs[k].law.frictional for k in shown})
    listed = np.array(list(labels), dtype=int)  # the states the laws can give, coloured in this order
    colour_of = np.zeros(len(State), dtype=int)
    colour_of[listed] = np.arange(len(listed))
    state = dataset.cell_data["contact_state"]
    cmap = ListedColormap([_STATE_COLOURS[s] for s in listed])
    norm = BoundaryNorm(np.arange(len(listed) + 1) - 0.5, len(listed))
    columns = 1 if len(shown) == 1 else 2
    rows = -(-len(shown) // columns)
    fig, axes = plt.subplots(rows, columns, figsize=(10.5 if columns == 1 else 14.0, 1.3 + 5.0 * rows),
                             layout="constrained", squeeze=False)
    for ax, k in zip(axes.ravel(), shown):
        plane, axis_labels = _plan_view(dataset.points[dataset.cells[pair == k]])
        patches = PolyCollection(plane, array=colour_of[state[pair == k]], cmap=cmap, norm=norm, edgecolors="face",
                                 linewidths=0.3)
        ax.add_collection(patches)
        ax.autoscale_view()
        ax.set_aspect("equal")
        ax.set_xlabel(axis_labels[0])
        ax.set_ylabel(axis_labels[1])
        panel = _pair_text(pairs[k]) if len(shown) > 1 else "one colour per node's tributary area"
        zoomed = _zoom_to_contact(ax, plane, state[pair == k])
        ax.set_title(panel + (", zoomed on the contact zone" if zoomed else ""))
    for ax in axes.ravel()[len(shown):]:
        ax.set_axis_off()
    fig.suptitle(f"{title}: {_pair_text(pairs[shown[0]])}" if len(shown) == 1 else title)
    bar = fig.colorbar(patches, ax=axes.ravel().tolist(), ticks=np.arange(len(listed)), fraction=0.05, pad=0.02)
    bar.ax.set_yticklabels([text + ("" if np.any(state == s) else " (none)") for s, text in labels.items()])
    bar.ax.tick_params(length=0)
    fig.savefig(path, dpi=150, format="png")
    plt.close(fig)
