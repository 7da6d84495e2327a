"""Figures of a solved contact problem, drawn on rank 0 from small gathered surfaces.

* :func:`plot_contact_states`: the contact states on each pair's surface (seed 000,
  Fig. 2), with matplotlib (Agg, no display) from the tributary patches of every rank;
* :func:`plot_deformed_bodies`: a 3D view of the deformed bodies coloured by von Mises
  stress, with the rigid obstacles, and the contact surfaces coloured by the contact
  pressure, with pyvista (off screen, on a virtual X display made for the drawing when
  there is none), from the owned boundary facets of every rank;
* :func:`plot_forces`: the contact forces and support reactions along the load path
  (:mod:`contactqvi.contact.force_history`), from the summary.

Each of the first two is described first (:func:`describe_contact_states`,
:func:`describe_bodies`: the data of :mod:`contactqvi.contact.figure_data`), then
rendered; tests read the descriptions. Only surfaces of at most
:data:`contactqvi.tables.GATHER_MAX_NODES` nodes are drawn. A figure never ends a run: a
failure is logged and the figure skipped.
"""

from __future__ import annotations

import contextlib
import logging
import os
import pathlib
import subprocess
import textwrap
import typing

from mpi4py import MPI

import numpy as np

from dolfinx import fem
from dolfinx import mesh as dmesh

from contactqvi.contact.figure_data import (
    BodiesFigure,
    DrawnState,
    ShownStep,
    StatesFigure,
    Surface3D,
    bodies_figure,
    states_figure,
)
from contactqvi.contact.force_history import plot_force_history
from contactqvi.contact.interface import BodyPair, Pair
from contactqvi.contact.nodal import State
from contactqvi.contact.problem import ContactProblem
from contactqvi.contact.surface import ContactSurface, pressure_label, vertex_blocks
from contactqvi.contact.surface_views import number
from contactqvi.paraview import Dataset, gather_pieces
from contactqvi.tables import GATHER_MAX_NODES, atomic_path

__all__ = ["describe_bodies", "describe_contact_states", "draw_on_rank_0", "plot_contact_states", "plot_deformed_bodies",
           "plot_forces"]

logger = logging.getLogger(__name__)

Builder = typing.Callable[[], typing.Any]


def _shown(problem: ContactProblem, shown: ShownStep | None) -> ShownStep:
    """``shown``, or the problem's current load factor, translation and rotation (a single solve)."""
    if shown is not None:
        return shown
    return ShownStep(None, problem.load_factor, tuple(float(t) for t in problem.translation), problem.step_rotation)


def _states_builder(surface: ContactSurface, shown: ShownStep | None) -> Builder | None:
    """Gather the tributary patches on rank 0 and return what builds the states figure there
    (None above ``GATHER_MAX_NODES`` nodes). Collective."""
    if surface.n_nodes > GATHER_MAX_NODES:
        logger.info("contact_states.png is skipped: %d surface nodes > %d (drawn on one rank)", surface.n_nodes,
                    GATHER_MAX_NODES)
        return None
    dataset = gather_pieces(surface.mesh.comm, surface.dataset())
    pairs = [interface.pair for interface in surface.problem.interfaces]
    vertices = 4 if surface.mesh.topology.cell_type == dmesh.CellType.quadrilateral else 3
    step = _shown(surface.problem, shown)
    return lambda: states_figure(dataset, _facet_pair(dataset.cell_data["contact_pair"], vertices),
                                 [_pair_text(p) for p in pairs], [p.law.frictional for p in pairs], step)


def describe_contact_states(surface: ContactSurface, shown: ShownStep | None = None) -> StatesFigure | None:
    """What ``contact_states.png`` shows (:func:`~contactqvi.contact.figure_data.states_figure`),
    on rank 0; None on the other ranks and for surfaces above ``GATHER_MAX_NODES`` nodes. Collective."""
    build = _states_builder(surface, shown)
    return build() if build is not None and surface.mesh.comm.rank == 0 else None


def plot_contact_states(path: str | os.PathLike, surface: ContactSurface, shown: ShownStep | None = None) -> bool:
    """PNG of the contact surfaces coloured by contact state (seed 000, Fig. 2).

    The tributary patch of each node (:class:`~contactqvi.contact.surface.TributaryPatches`)
    gets its state's colour, the states named for the pair's law
    (:func:`~contactqvi.contact.surface.state_names`); each group is drawn flat or unrolled
    (:mod:`contactqvi.contact.surface_views`). The title names the step ``shown`` (else the
    problem's load factor and translation), and a failed path. Returns whether the PNG was
    written: not for surfaces of more than ``GATHER_MAX_NODES`` nodes, nor when drawing
    fails (a figure never ends a run). Collective.
    """
    build = _states_builder(surface, shown)
    if build is None:
        return False
    return draw_on_rank_0(surface.mesh.comm, path, lambda tmp: _render_states(tmp, build()))


def _touching_reference_gap(surface: ContactSurface) -> float:
    """The largest |gap| at rest of the contact nodes that touch at the last update: to an
    obstacle in its initial position, or a body pair's weighted gap as meshed
    (:func:`~contactqvi.contact.figure_data.displacement_scale`). Collective."""
    problem = surface.problem
    states = surface.node_states
    x = problem.V.tabulate_dof_coordinates()
    largest = 0.0
    for interface in problem.interfaces:
        gap = interface.initial_gap if interface.obstacle is None else interface.obstacle.distance(x[interface.blk])[0]
        touching = states[np.searchsorted(problem.contact_blk, interface.blk)] != State.NO_CONTACT
        largest = max(largest, float(np.abs(gap[touching]).max(initial=0.0)))
    return problem.comm.allreduce(largest, op=MPI.MAX)


def _bodies_builder(displacement: fem.Function, von_mises: fem.Function, surface: ContactSurface,
                    shown: ShownStep | None) -> Builder | None:
    """Gather the bodies' boundary and the contact surfaces on rank 0 and return what builds
    the bodies figure there (None above ``GATHER_MAX_NODES`` boundary points). Collective."""
    comm = displacement.function_space.mesh.comm
    piece = _boundary_piece(displacement, von_mises)
    points = comm.allreduce(len(piece.points), op=MPI.SUM)
    if points > GATHER_MAX_NODES:
        logger.info("bodies.png is skipped: %d boundary points > %d (drawn on one rank)", points, GATHER_MAX_NODES)
        return None
    problem = surface.problem
    dataset = gather_pieces(comm, piece)
    contact = None if surface.n_nodes > GATHER_MAX_NODES else gather_pieces(comm, surface.dataset())
    obstacles = [(i.obstacle, f"the {type(i.obstacle).__name__.lower()} (rigid)") for i in problem.interfaces
                 if i.obstacle is not None]
    drawn = DrawnState(_shown(problem, shown), obstacles, problem.hyperelastic is not None,
                       _touching_reference_gap(surface), pressure_label(problem))
    return lambda: bodies_figure(dataset, contact, drawn)


def describe_bodies(displacement: fem.Function, von_mises: fem.Function, surface: ContactSurface,
                    shown: ShownStep | None = None) -> BodiesFigure | None:
    """What ``bodies.png`` shows (:func:`~contactqvi.contact.figure_data.bodies_figure`), on
    rank 0; None on the other ranks and above ``GATHER_MAX_NODES`` boundary points. Collective."""
    build = _bodies_builder(displacement, von_mises, surface, shown)
    return build() if build is not None and displacement.function_space.mesh.comm.rank == 0 else None


def plot_deformed_bodies(path: str | os.PathLike, displacement: fem.Function, von_mises: fem.Function,
                         surface: ContactSurface, shown: ShownStep | None = None) -> bool:
    """PNG of the bodies' boundary, deformed and coloured by the von Mises stress, with the
    rigid obstacles at the step ``shown``, and beside it the contact surfaces of ``surface``
    (updated to the same step) deformed alike and coloured by the contact pressure
    (:class:`~contactqvi.contact.figure_data.BodiesFigure`: the scale, ranges and texts).

    ``displacement``: P1 displacement (m); ``von_mises``: DG0 von Mises stress (Pa), each
    boundary facet coloured by its cell's value. Returns whether the PNG was written (not
    above ``GATHER_MAX_NODES`` boundary points). Collective.
    """
    build = _bodies_builder(displacement, von_mises, surface, shown)
    if build is None:
        return False
    return draw_on_rank_0(displacement.function_space.mesh.comm, path, lambda tmp: _render_bodies(tmp, build()))


def plot_forces(path: str | os.PathLike, steps: typing.Sequence[dict[str, typing.Any]], comm: MPI.Comm) -> bool:
    """PNG of the pairs' contact forces and the supports' reactions along the load path (the
    summary's ``steps``; :func:`~contactqvi.contact.force_history.plot_force_history`). Returns
    whether it was written. Collective."""
    return draw_on_rank_0(comm, path, lambda tmp: plot_force_history(tmp, steps))


def draw_on_rank_0(comm: MPI.Comm, path: str | os.PathLike, draw: typing.Callable[[pathlib.Path], None]) -> bool:
    """Call ``draw`` with a temporary file on rank 0, moved to ``path`` when it succeeded; whether it
    did, on every rank (a figure never ends a run)."""
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


def _grid(surface: Surface3D, name: str) -> typing.Any:
    """A pyvista grid of ``surface`` with its values named ``name``."""
    import pyvista

    grid = pyvista.UnstructuredGrid({surface.cell_type: surface.cells}, surface.points)
    (grid.cell_data if surface.on_cells else grid.point_data)[name] = surface.values
    return grid


def _bar(title: str) -> dict[str, typing.Any]:
    """A horizontal colour bar under the panel, wide enough for its title."""
    return {"title": title, "vertical": False, "position_x": 0.15, "position_y": 0.05, "width": 0.7, "height": 0.06,
            "fmt": "%.3g", "title_font_size": 20, "label_font_size": 16, "n_labels": 5}


def _add_panel(plotter: typing.Any, surface: Surface3D, scale: typing.Any, cmap: str, texts: list[str],
               camera: list, lit: bool = True) -> None:
    """One panel: ``surface`` coloured on ``scale`` (a ColourScale), its texts, the camera;
    without ``lit`` the colours as mapped (a surface seen from either side)."""
    name = scale.title
    grid = _grid(surface, name)
    grid[name] = grid[name] * scale.factor
    plotter.add_mesh(grid, scalars=name, cmap=cmap, clim=(scale.low * scale.factor, scale.high * scale.factor),
                     log_scale=scale.log, nan_color="#bdbdbd", show_edges=True, edge_color="#404040",
                     line_width=0.3, lighting=lit, scalar_bar_args=_bar(name))
    plotter.add_text("\n".join(textwrap.fill(t, 100) for t in [*texts, scale.note]), position="upper_left",
                     font_size=11)
    plotter.camera_position = camera
    plotter.reset_camera()
    plotter.show_axes()


def _render_bodies(path: pathlib.Path, figure: BodiesFigure) -> None:
    """Draw ``figure`` (pyvista, off screen) into the PNG ``path``."""
    import pyvista

    camera = [tuple(figure.camera), (0.0, 0.0, 0.0), (0.0, 0.0, 1.0)]
    texts = [figure.title, figure.scale_text + "; von Mises stress per cell"
             + "".join(f"; {o.label} in brown" for o in figure.obstacles)]
    with _display():
        plotter = pyvista.Plotter(off_screen=True, window_size=(1600 if figure.contact is None else 2800, 1200),
                                  shape=(1, 1 if figure.contact is None else 2))
        try:
            for obstacle in figure.obstacles:
                faces = np.concatenate([[len(f), *f] for f in obstacle.faces])
                plotter.add_mesh(pyvista.PolyData(obstacle.points, faces), color="#a0785a", opacity=0.45)
            _add_panel(plotter, figure.bodies, figure.stress, "viridis", texts, camera)
            if figure.status:  # a failed path, in red under the header
                plotter.add_text(figure.status, position=(8, 1080), font_size=14, color="#b00000")
            if figure.contact is not None:
                plotter.subplot(0, 1)
                _add_panel(plotter, figure.contact, figure.pressure, "plasma", [figure.contact_title], camera,
                           lit=False)
            image = plotter.screenshot(None, return_img=True)
        finally:
            plotter.close()
    import matplotlib.image

    matplotlib.image.imsave(path, image, format="png")


def _pair_text(pair: Pair) -> str:
    """A contact pair in an engineer's words: ``upper.interface on lower.interface``,
    ``contact on the sphere`` (the obstacle's kind)."""
    if isinstance(pair, BodyPair):
        return f"{pair.slave} on {pair.master}"
    return f"{pair.surface} on the {type(pair.obstacle).__name__.lower()}"


def _facet_pair(pair: np.ndarray, vertices: int) -> np.ndarray:
    """The pair of each patch's facet: patches come in runs of ``vertices`` per facet, and a
    node without a contact law (-1, a supported node) takes the pair of its facet's other nodes."""
    return np.repeat(pair.reshape(-1, vertices).max(axis=1), vertices)


def _render_states(path: pathlib.Path, figure: StatesFigure) -> None:
    """Draw ``figure`` (matplotlib, Agg) into the PNG ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection
    from matplotlib.colors import BoundaryNorm, ListedColormap
    from matplotlib.ticker import FuncFormatter

    cmap = ListedColormap([colour for colour, _ in figure.legend])
    norm = BoundaryNorm(np.arange(len(figure.legend) + 1) - 0.5, len(figure.legend))
    columns = 1 if len(figure.panels) == 1 else 2
    rows = -(-len(figure.panels) // columns)
    fig, axes = plt.subplots(rows, columns, figsize=(10.5 if columns == 1 else 14.0, 1.6 + 5.0 * rows),
                             layout="constrained", squeeze=False)
    ticks = FuncFormatter(lambda value, _: number(value, 4))
    for ax, panel in zip(axes.ravel(), figure.panels):
        patches = PolyCollection(panel.polygons, array=panel.colours, cmap=cmap, norm=norm, edgecolors="face",
                                 linewidths=0.3)
        ax.add_collection(patches)
        ax.autoscale_view()
        ax.set_aspect("equal")
        if panel.limits is not None:
            ax.set_xlim(*panel.limits[0])
            ax.set_ylim(*panel.limits[1])
        ax.xaxis.set_major_formatter(ticks)
        ax.yaxis.set_major_formatter(ticks)
        ax.set_xlabel(panel.view.labels[0])
        ax.set_ylabel(panel.view.labels[1])
        ax.set_title(textwrap.fill(panel.title + (", zoomed on the contact zone" if panel.limits else ""), 70),
                     fontsize=9)
    for ax in axes.ravel()[len(figure.panels):]:
        ax.set_axis_off()
    fig.suptitle(textwrap.fill(figure.title, 100) + (f"\n{figure.status}" if figure.status else ""),
                 color="#b00000" if figure.status else "black")
    bar = fig.colorbar(patches, ax=axes.ravel().tolist(), ticks=np.arange(len(figure.legend)), fraction=0.05, pad=0.02)
    bar.ax.set_yticklabels([text for _, text in figure.legend])
    bar.ax.tick_params(length=0)
    fig.savefig(path, dpi=150, format="png")
    plt.close(fig)
