"""Results of a solved contact problem: surface fields, force balance, files, figure.

Surface fields (:func:`contact_fields`) live on a surface mesh of the contact
facets (``dolfinx.mesh.create_submesh`` of dimension 2), as P1 functions; vectors
have three global components. Its vertices are the contact nodes of
:class:`~contactqvi.contact.problem.ContactProblem` and the nodes of the contact
boundary that carry a Dirichlet condition; the latter have no contact law and get
state ``NO_CONTACT``, zero forces and slip.

Files (:class:`ContactResultsWriter`, :func:`write_contact_results`), one dataset
each, the same on any number of ranks (:func:`contactqvi.io.gather_dataset`):

* ``body.bp`` (VTX): point data ``displacement [m]``; cell data ``stress [Pa]``
  (cell average of the Cauchy stress, 3 x 3) and ``von_mises [Pa]`` (of it).
* ``contact_surface.bp`` (VTX): the contact surface cut into the *tributary
  patches* of its nodes (each facet into one quadrilateral per vertex, through
  the edge midpoints and the facet centre; the patches of a node tile the area
  that its lumped nodal area stands for). Point data, the P1 fields interpolated
  (exactly for bilinear/linear facets): ``displacement [m]``, ``contact_pressure
  [Pa]``, ``friction_traction [Pa]``, ``slip [m]``, ``tangential_displacement
  [m]``, ``gap [m]``. Cell data, the value of the patch's node, so ParaView draws
  categories without blending them: ``contact_state`` (:class:`State` value) and
  the 0/1 indicators ``is_open``, ``is_sliding``, ``is_sticking``; integrating
  an indicator over the surface gives that area.

Summary entries (:func:`contact_summary`), SI units listed under ``units``: total
contact force of the obstacle on the body (N, global components), reaction force
of each support (N), applied force (N) and the relative equilibrium error of
their sum, contact/sticking/sliding areas (m^2, lumped nodal areas by state),
node counts per state, the largest contact pressure and von Mises stress (Pa),
the global l2 norm of u~ (m; the number demos print to compare runs).
"""

from __future__ import annotations

import dataclasses
import logging
import os
import pathlib
import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import ufl

from dolfinx import fem, la
from dolfinx import mesh as dmesh

from contactqvi import io
from contactqvi.contact.load_path import contact_resultants
from contactqvi.contact.nodal import State
from contactqvi.contact.problem import ContactProblem
from contactqvi.contact.scd_newton import SCDNewtonResult
from contactqvi.postprocess import applied_force, reaction_forces, stress_fields

__all__ = [
    "STATE_NAMES",
    "UNITS",
    "ContactResultsWriter",
    "ContactSurfaceFields",
    "contact_fields",
    "contact_summary",
    "contact_surface_dataset",
    "plot_contact_states",
    "write_contact_results",
]

logger = logging.getLogger(__name__)

#: Names of the contact states (seed 000, Table 1), by :class:`State` value; "grazing":
#: touching with zero normal force.
STATE_NAMES = {
    State.NO_CONTACT: "no contact",
    State.SLIDING: "sliding",
    State.STICKING: "sticking",
    State.WEAK_CONTACT_SLIDING: "grazing, sliding",
    State.WEAK_STICKING: "sticking on the cone boundary",
    State.WEAK_CONTACT_STICKING: "grazing, at rest",
    State.SEPARATED_STICKING: "separated, sticking (Tresca)",
}
#: States counted as sticking and as sliding in areas and indicators; all others are open.
STICKING_STATES = (State.STICKING, State.WEAK_STICKING)
SLIDING_STATES = (State.SLIDING,)

#: SI units of the fields and summary entries.
UNITS = {
    "displacement": "m",
    "stress": "Pa",
    "von_mises": "Pa",
    "contact_pressure": "Pa",
    "friction_traction": "Pa",
    "slip": "m",
    "tangential_displacement": "m",
    "gap": "m",
    "nodal_area": "m^2",
    "contact_force": "N",
    "reaction_forces": "N",
    "applied_force": "N",
    "contact_area": "m^2",
    "sticking_area": "m^2",
    "sliding_area": "m^2",
    "max_contact_pressure": "Pa",
    "max_von_mises": "Pa",
    "equilibrium_error": "1",
    "displacement_norm": "m",
}


def _labelled(name: str) -> str:
    """Field name with its unit, as written to files: ``contact_pressure [Pa]``."""
    return f"{name} [{UNITS[name]}]"


@dataclasses.dataclass
class ContactSurfaceFields:
    """Named P1 functions on the contact surface mesh (seed 000, Sect. 7 output).

    Attributes:
        state: ``contact_state``, the :class:`~contactqvi.contact.nodal.State` value.
        pressure: ``contact_pressure`` (Pa): normal force over the lumped nodal area.
        traction: ``friction_traction`` (Pa, tangential vector): friction force of the
            obstacle on the body over the lumped nodal area; opposite to the slip
            when sliding.
        slip: ``slip`` (m, tangential vector): slip relative to the obstacle in this
            step (the tangential part of the shifted displacement, seed 000 (6.3))
            where the node touches the obstacle; zero where it does not (state
            ``NO_CONTACT``).
        tangential_displacement: ``tangential_displacement`` (m): the displacement
            u~ minus its component along the obstacle normal, at every node.
        gap: ``gap`` (m): distance to the obstacle after deformation along the
            normal of the node's frame, g + n . u~ (linearised as in the seed).
        displacement: ``displacement`` (m): u~, for warping the surface.
        nodal_area: ``nodal_area`` (m^2): lumped area of each surface node, so that
            the sum of pressure * nodal_area is the total normal force.
    """

    state: fem.Function
    pressure: fem.Function
    traction: fem.Function
    slip: fem.Function
    tangential_displacement: fem.Function
    gap: fem.Function
    displacement: fem.Function
    nodal_area: fem.Function

    @property
    def mesh(self) -> dmesh.Mesh:
        """The surface mesh of the contact facets."""
        return self.state.function_space.mesh

    @property
    def functions(self) -> list[fem.Function]:
        """All fields, for writing to one file."""
        return [getattr(self, field.name) for field in dataclasses.fields(self)]


def _vertex_blocks(V: fem.FunctionSpace) -> np.ndarray:
    """Local block (node) index of each local vertex, for a degree-1 Lagrange space.

    The i-th dof of a cell of a degree-1 Lagrange space sits at the cell's i-th vertex.
    """
    msh = V.mesh
    tdim = msh.topology.dim
    msh.topology.create_connectivity(tdim, 0)
    cell_vertices = msh.topology.connectivity(tdim, 0).array
    index_map = msh.topology.index_map(0)
    blocks = np.empty(index_map.size_local + index_map.num_ghosts, dtype=np.int32)
    blocks[cell_vertices] = V.dofmap.list.ravel()
    return blocks


#: Columns of the nodal table :func:`_nodal_table` fills on the contact nodes.
_COLUMNS = {"state": 0, "contact": 1, "pressure": 2, "traction": slice(3, 6), "slip": slice(6, 9),
            "gap": 9, "normal": slice(10, 13)}


def _nodal_table(problem: ContactProblem, u: PETSc.Vec, result: SCDNewtonResult) -> la.Vector:
    """Per node of V (owned and ghost): state, contact flag, pressure, friction traction,
    slip, gap and frame normal at the contact nodes, global components; zero elsewhere.

    Filled on the owned contact nodes and scattered, so every rank sees the owner's
    values at its ghost nodes.
    """
    V = problem.V
    table = la.vector(V.dofmap.index_map, bs=13)
    values = table.array.reshape(-1, 13)
    values[:] = 0.0
    values[:, _COLUMNS["state"]] = State.NO_CONTACT
    blk, frames, area = problem.contact_blk, problem.frames, problem.contact_area
    shifted = u.array.reshape(-1, 3)[blk]  # nodal frames: (slip increment, gap after deformation)
    touching = result.states != State.NO_CONTACT
    values[blk, _COLUMNS["state"]] = result.states
    values[blk, _COLUMNS["contact"]] = 1.0
    values[blk, _COLUMNS["pressure"]] = result.normal_force / area
    values[blk, _COLUMNS["traction"]] = np.einsum("ij,ijk->ik", result.friction_force, frames[:, :2]) / area[:, None]
    values[blk, _COLUMNS["slip"]] = np.einsum("ij,ijk->ik", shifted[:, :2], frames[:, :2]) * touching[:, None]
    values[blk, _COLUMNS["gap"]] = shifted[:, 2]
    values[blk, _COLUMNS["normal"]] = frames[:, 2]
    table.scatter_forward()
    return table


def contact_fields(
    problem: ContactProblem, u: PETSc.Vec, result: SCDNewtonResult, displacement: fem.Function | None = None
) -> ContactSurfaceFields:
    """Contact state, pressure, friction traction, slip, gap and displacement on the contact surface.

    Forces and states are those of the last approximation step's graph point
    (``result``), divided by the problem's lumped nodal area; slip and gap come from
    the solution ``u`` (shifted displacements in nodal frames, seed 000 (6.3)).
    Collective.

    Args:
        problem: the contact problem that was solved (at its current load step).
        u: its solution (shifted displacements).
        result: the solver's result for ``u``.
        displacement: the physical displacement of ``u`` if computed already.
    """
    V = problem.V
    msh = V.mesh
    surface, _, vertex_map, _ = dmesh.create_submesh(msh, msh.topology.dim - 1, problem.contact_facets)
    scalars = fem.functionspace(surface, ("Lagrange", 1))
    vectors = fem.functionspace(surface, ("Lagrange", 1, (3,)))
    parent_blk = _vertex_blocks(V)[vertex_map]  # every local surface vertex, owned or ghost

    table = _nodal_table(problem, u, result)
    nodal = table.array.reshape(-1, 13)[parent_blk]
    if displacement is None:
        displacement = problem.physical_displacement(u, fem.Function(V))
    u_tilde = displacement.x.array.reshape(-1, 3)[parent_blk]
    contact = nodal[:, _COLUMNS["contact"]] > 0
    scalar_blk, vector_blk = _vertex_blocks(scalars), _vertex_blocks(vectors)
    x = scalars.tabulate_dof_coordinates()[scalar_blk]
    obstacle = problem.obstacle.translated(problem.translation)
    initial_gap, normal = obstacle.distance(x)
    normal[contact] = nodal[contact, _COLUMNS["normal"]]  # the nodes' (reference) frames
    gap = np.where(contact, nodal[:, _COLUMNS["gap"]], initial_gap + np.einsum("ij,ij->i", normal, u_tilde))
    tangential = u_tilde - np.einsum("ij,ij->i", normal, u_tilde)[:, None] * normal

    def field(name: str, values: np.ndarray) -> fem.Function:
        space, blk = (vectors, vector_blk) if values.ndim == 2 else (scalars, scalar_blk)
        f = fem.Function(space, name=name)
        bs = space.dofmap.index_map_bs
        f.x.array.reshape(-1, bs)[blk] = values.reshape(-1, bs)
        return f

    nodal_area = fem.Function(scalars, name="nodal_area")
    fem.assemble_vector(nodal_area.x.array, fem.form(ufl.TestFunction(scalars) * ufl.dx))
    nodal_area.x.scatter_reverse(la.InsertMode.add)
    nodal_area.x.scatter_forward()
    return ContactSurfaceFields(
        state=field("contact_state", nodal[:, _COLUMNS["state"]]),
        pressure=field("contact_pressure", nodal[:, _COLUMNS["pressure"]]),
        traction=field("friction_traction", nodal[:, _COLUMNS["traction"]]),
        slip=field("slip", nodal[:, _COLUMNS["slip"]]),
        tangential_displacement=field("tangential_displacement", tangential),
        gap=field("gap", gap),
        displacement=field("displacement", u_tilde),
        nodal_area=nodal_area,
    )


def _tributary_patches(dataset: io.Dataset) -> io.Dataset:
    """Cut every facet into one quadrilateral per vertex (through edge midpoints and centre).

    Point data are interpolated to the new points (midpoint: mean of the edge's
    ends; centre: mean of the facet's vertices, the bilinear/linear value there);
    cell data of the result take point data ``contact_state`` of each patch's vertex.
    """
    cells = dataset.cells  # VTK order: the vertices of a facet go round it
    n_points, (n_cells, k) = len(dataset.points), cells.shape
    ends = np.stack([cells, np.roll(cells, -1, axis=1)], axis=2).reshape(-1, 2)  # edge j: vertex j to j+1
    edges, edge_of = np.unique(np.sort(ends, axis=1), axis=0, return_inverse=True)
    edge_of = edge_of.reshape(n_cells, k) + n_points
    centre = n_points + len(edges) + np.arange(n_cells)

    def extend(values: np.ndarray) -> np.ndarray:
        return np.concatenate([values, values[edges].mean(axis=1), values[cells].mean(axis=1)])

    patches = np.stack([cells, edge_of, np.repeat(centre[:, None], k, axis=1), np.roll(edge_of, 1, axis=1)], axis=2)
    owner = cells.ravel()
    state = dataset.point_data["contact_state"][owner].astype(np.int32)
    return io.Dataset(
        points=extend(dataset.points),
        cells=patches.reshape(-1, 4),
        cell_type=9,  # VTK_QUAD
        point_data={name: extend(values) for name, values in dataset.point_data.items() if name != "contact_state"},
        cell_data={
            "contact_state": state,
            "is_open": (~np.isin(state, STICKING_STATES + SLIDING_STATES)).astype(np.int32),
            "is_sliding": np.isin(state, SLIDING_STATES).astype(np.int32),
            "is_sticking": np.isin(state, STICKING_STATES).astype(np.int32),
        },
    )


def contact_surface_dataset(fields: ContactSurfaceFields) -> io.Dataset | None:
    """The surface fields as one dataset of tributary patches, on rank 0 (None elsewhere).

    See the module docstring for its arrays. Collective.
    """
    point_data = {"contact_state": fields.state}
    point_data |= {_labelled(f.name): f for f in fields.functions if f.name not in ("contact_state", "nodal_area")}
    dataset = io.gather_dataset(fields.mesh, point_data)
    return None if dataset is None else _tributary_patches(dataset)


def contact_summary(
    problem: ContactProblem,
    u: PETSc.Vec,
    result: SCDNewtonResult,
    von_mises: fem.Function | None = None,
    displacement: fem.Function | None = None,
) -> dict[str, typing.Any]:
    """Force balance, areas and extreme values of a solved step, with ``units``. Collective.

    Args:
        problem, u, result: the solved problem at its current step, its solution
            (shifted displacements) and the solver's result.
        von_mises: the von Mises field (DG0) if computed, for its maximum.
        displacement: the physical displacement of ``u`` if computed already.
    """
    comm = problem.comm
    if displacement is None:
        displacement = problem.physical_displacement(u, fem.Function(problem.V))
    reactions = reaction_forces(displacement, problem.body, problem.load_factor, problem.dirichlet_dofs_loc)
    applied = applied_force(problem.V.mesh, problem.body, problem.load_factor)
    resultants = contact_resultants(problem, result)
    contact_force = np.asarray(resultants["contact_force"])
    total = sum(reactions.values(), np.zeros(3)) + contact_force + applied
    scale = max([np.linalg.norm(applied), np.linalg.norm(contact_force)] + [np.linalg.norm(r) for r in reactions.values()])
    counts = comm.allreduce(np.bincount(result.states.astype(np.int64), minlength=len(State)), op=MPI.SUM)
    pressure = result.normal_force / problem.contact_area
    summary = {
        "contact_force": contact_force.tolist(),
        "reaction_forces": {name: r.tolist() for name, r in reactions.items()},
        "applied_force": applied.tolist(),
        "equilibrium_error": float(np.linalg.norm(total) / scale) if scale > 0 else 0.0,
        "contact_area": resultants["contact_area"],
        "sticking_area": resultants["sticking_area"],
        "sliding_area": resultants["sliding_area"],
        "state_counts": {STATE_NAMES[s]: int(counts[s]) for s in State},
        "max_contact_pressure": comm.allreduce(float(pressure.max(initial=0.0)), op=MPI.MAX),
        "displacement_norm": displacement.x.petsc_vec.norm(),
    }
    if von_mises is not None:
        n_cells = von_mises.function_space.mesh.topology.index_map(3).size_local
        summary["max_von_mises"] = comm.allreduce(float(von_mises.x.array[:n_cells].max(initial=0.0)), op=MPI.MAX)
    summary["units"] = {name: UNITS[name] for name in summary if name in UNITS}
    return summary


class ContactResultsWriter:
    """Writes the steps of a contact solve to ``body.bp`` and ``contact_surface.bp``.

    One call of :meth:`write` per (load) step, each a time step of both files
    (time = step number unless given). Collective; use in a ``with`` block or call
    :meth:`close`.

    Args:
        out: output directory (created if needed).
    """

    def __init__(self, out: str | os.PathLike, comm: MPI.Comm = MPI.COMM_WORLD):
        self.out = io.prepare_output_dir(comm, out)
        self.comm = comm
        self._body_file = io.VTXDatasetWriter(comm, self.out / "body.bp")
        self._surface_file = io.VTXDatasetWriter(comm, self.out / "contact_surface.bp")
        self._steps = 0
        self.last: tuple[fem.Function, ContactSurfaceFields] | None = None  # displacement, surface fields

    def write(
        self, problem: ContactProblem, u: PETSc.Vec, result: SCDNewtonResult, t: float | None = None
    ) -> dict[str, typing.Any]:
        """Write one step; returns its :func:`contact_summary` entries."""
        t = float(self._steps if t is None else t)
        displacement = problem.physical_displacement(u, fem.Function(problem.V, name="displacement"))
        stress, von_mises = stress_fields(displacement, problem.body.young, problem.body.poisson)
        msh = problem.V.mesh
        volume = io.gather_dataset(
            msh, {_labelled("displacement"): displacement},
            {_labelled("stress"): stress, _labelled("von_mises"): von_mises},
        )
        self._body_file.write(volume, t)
        surface = contact_fields(problem, u, result, displacement)
        self._surface_file.write(contact_surface_dataset(surface), t)
        self._steps += 1
        self.last = (displacement, surface)
        return contact_summary(problem, u, result, von_mises, displacement)

    def close(self, ok: bool = True) -> None:
        """Finish both files (collective); ``ok=False`` discards them."""
        self._body_file.close(ok)
        self._surface_file.close(ok)

    def __enter__(self) -> ContactResultsWriter:
        return self

    def __exit__(self, exc_type, *exc: object) -> None:
        self.close(ok=exc_type is None)


def write_contact_results(
    out: str | os.PathLike,
    problem: ContactProblem,
    u: PETSc.Vec,
    result: SCDNewtonResult,
    plot: bool = True,
) -> dict[str, typing.Any]:
    """Write ``body.bp``, ``contact_surface.bp``, ``solution.npz`` and ``contact_states.png``.

    ``solution.npz`` holds ``x`` (N, 3) and ``u`` (N, 3), the displacement u~
    gathered on rank 0 (:func:`contactqvi.io.write_solution_npz`). Collective.

    Returns:
        The :func:`contact_summary` entries, with ``files`` (names written) and
        ``plot`` (whether the PNG was made) added.
    """
    with ContactResultsWriter(out, problem.comm) as writer:
        summary = writer.write(problem, u, result)
    displacement, surface = writer.last
    io.write_solution_npz(writer.out / "solution.npz", displacement)
    files = ["body.bp", "contact_surface.bp", "solution.npz"]
    if plot:
        summary["plot"] = plot_contact_states(writer.out / "contact_states.png", surface)
        if summary["plot"]:
            files.append("contact_states.png")
    summary["files"] = files
    return summary


#: One colour per state (colour-blind safe, Okabe-Ito), by :class:`State` value.
_STATE_COLOURS = ["#d9d9d9", "#e69f00", "#0072b2", "#f0e442", "#56b4e9", "#cc79a7", "#009e73"]


def plot_contact_states(path: str | os.PathLike, fields: ContactSurfaceFields) -> bool:
    """PNG of the contact surface coloured by contact state (seed 000, Fig. 2).

    The tributary patch of each node (see the module docstring) gets its state's
    colour. The surface is seen along its mean normal,
    with axes in m (global x1, x2 ... when the normal is a coordinate axis). Drawn
    with matplotlib on rank 0 (no display needed). Returns whether the PNG was
    written. Collective.
    """
    dataset = contact_surface_dataset(fields)
    comm = fields.mesh.comm
    ok = False
    if comm.rank == 0:
        try:
            _draw_states(pathlib.Path(path), dataset)
            ok = True
        except Exception as exc:  # a figure must never end a solve (nor leave the other ranks waiting)
            logger.warning("%s is skipped: %s", path, exc)
    return bool(comm.bcast(ok, root=0))


def _draw_states(path: pathlib.Path, dataset: io.Dataset) -> None:
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
    fig.savefig(path, dpi=150)
    plt.close(fig)
