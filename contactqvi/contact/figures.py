"""Figure of a solved contact problem: the contact states on the surface (seed 000, Fig. 2).

Drawn with matplotlib (Agg, no display) on rank 0 from the tributary patches of
every rank, gathered there; so only surfaces of at most
:data:`contactqvi.tables.GATHER_MAX_NODES` nodes are drawn.
"""

from __future__ import annotations

import logging
import os
import pathlib

from mpi4py import MPI

import numpy as np

from contactqvi.contact.nodal import State
from contactqvi.contact.surface import STATE_NAMES, ContactSurface
from contactqvi.paraview import Dataset, gather_pieces
from contactqvi.tables import GATHER_MAX_NODES, atomic_path

__all__ = ["plot_contact_states"]

logger = logging.getLogger(__name__)

#: One colour per state (colour-blind safe, Okabe-Ito), by :class:`State` value.
_STATE_COLOURS = ["#d9d9d9", "#e69f00", "#0072b2", "#f0e442", "#56b4e9", "#cc79a7", "#009e73"]


def plot_contact_states(path: str | os.PathLike, surface: ContactSurface) -> bool:
    """PNG of the contact surface coloured by contact state (seed 000, Fig. 2).

    The tributary patch of each node (:class:`~contactqvi.contact.surface.TributaryPatches`)
    gets its state's colour. The surface is seen along its mean normal, with axes
    in m (global x1, x2 ... when the normal is a coordinate axis). Returns whether
    the PNG was written: not for surfaces of more than ``GATHER_MAX_NODES`` nodes,
    nor when matplotlib fails (a figure never ends a run). Collective.
    """
    comm = surface.mesh.comm
    if surface.n_nodes > GATHER_MAX_NODES:
        logger.info("%s is skipped: %d surface nodes > %d (drawn on one rank)", path, surface.n_nodes, GATHER_MAX_NODES)
        return False
    dataset = gather_pieces(comm, surface.dataset())
    ok = False
    if comm.rank == 0:
        try:
            with atomic_path(MPI.COMM_SELF, path) as tmp:
                _draw_states(tmp, dataset)
            ok = True
        except Exception as exc:  # a figure must never end a solve (nor leave the other ranks waiting)
            logger.warning("%s is skipped: %s", path, exc)
    return bool(comm.bcast(ok, root=0))


def _draw_states(path: pathlib.Path, dataset: Dataset) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection
    from matplotlib.colors import BoundaryNorm, ListedColormap

    from contactqvi.obstacles import tangent_frames

    polygons = dataset.points[dataset.cells]  # (patches, 4, 3)
    areas = np.cross(polygons[:, 2] - polygons[:, 0], polygons[:, 3] - polygons[:, 1])
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
    plane = polygons @ frame.T

    state = dataset.cell_data["contact_state"]
    n_states = len(State)
    present = np.isin(np.arange(n_states), state)
    cmap = ListedColormap(_STATE_COLOURS[:n_states])
    norm = BoundaryNorm(np.arange(n_states + 1) - 0.5, n_states)
    extent = np.ptp(plane.reshape(-1, 2), axis=0)
    height = float(np.clip(6.5 * extent[1] / max(extent[0], 1e-300), 2.0, 8.0)) + 1.3  # axes 6.5 in wide
    fig, ax = plt.subplots(figsize=(10.5, height), layout="constrained")
    patches = PolyCollection(plane, array=state, cmap=cmap, norm=norm, edgecolors="face", linewidths=0.3)
    ax.add_collection(patches)
    ax.autoscale_view()
    ax.set_aspect("equal")
    ax.set_xlabel(labels[0])
    ax.set_ylabel(labels[1])
    ax.set_title("Contact states (seed 000, Table 1): one colour per node's tributary area")
    bar = fig.colorbar(patches, ax=ax, ticks=np.arange(n_states), fraction=0.05, pad=0.02)
    bar.ax.set_yticklabels([f"{s.value} {STATE_NAMES[s]}" + ("" if present[s] else " (none)") for s in State])
    bar.ax.tick_params(length=0)
    fig.savefig(path, dpi=150, format="png")
    plt.close(fig)
