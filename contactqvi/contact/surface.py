"""The contact surface of a solved contact problem: its fields and tributary patches.

:class:`ContactSurface` is built once per problem: a surface mesh of the contact
facets (``dolfinx.mesh.create_submesh`` of dimension 2) with P1 spaces, the
lumped nodal areas, and this rank's *tributary patches* (each owned facet cut
into one quadrilateral per vertex, through the edge midpoints and the facet
centre; the patches of a node tile the area its lumped nodal area stands for).
:meth:`ContactSurface.update` fills the fields of each solved step in place;
:meth:`ContactSurface.dataset` gives this rank's piece of the patches for
``contact_surface.bp`` (see :mod:`contactqvi.contact.postprocess`).

The surface's vertices are the contact nodes of
:class:`~contactqvi.contact.problem.ContactProblem` and the nodes of the contact
boundary that carry a Dirichlet condition; the latter have no contact law and get
state ``NO_CONTACT``, zero forces and slip. Vectors have three global components.
"""

from __future__ import annotations

import dataclasses
import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import ufl

from dolfinx import fem, la
from dolfinx import mesh as dmesh
from dolfinx.cpp.mesh import cell_num_vertices

from contactqvi.contact.mortar import exterior_facet_cells, facet_closures
from contactqvi.contact.nodal import State
from contactqvi.contact.problem import ContactProblem
from contactqvi.contact.scd_newton import SCDNewtonResult
from contactqvi.elasticity import displacement_degree
from contactqvi.load_steps import placed
from contactqvi.paraview import Dataset, MeshPiece

__all__ = [
    "SLIDING_STATES",
    "STATE_NAMES",
    "STICKING_STATES",
    "UNITS",
    "ContactSurface",
    "ContactSurfaceFields",
    "FRICTIONLESS_STATE_NAMES",
    "PRESSURE_DEFINITIONS",
    "TributaryPatches",
    "FENCE",
    "contact_facet_areas",
    "labelled",
    "pressure_kinds",
    "pressure_label",
    "pressure_measure",
    "pressure_range",
    "pressure_summary",
    "robust_range",
    "state_names",
    "vertex_blocks",
]

#: Names of the contact states (seed 000, Table 1) of a law with friction, by :class:`State`
#: value; "grazing": touching with zero normal force. A frictionless law's: :func:`state_names`.
STATE_NAMES = {
    State.NO_CONTACT: "no contact",
    State.SLIDING: "sliding",
    State.STICKING: "sticking",
    State.WEAK_CONTACT_SLIDING: "grazing, sliding",
    State.WEAK_STICKING: "sticking on the cone boundary",
    State.WEAK_CONTACT_STICKING: "grazing, at rest",
    State.SEPARATED_STICKING: "separated, sticking (Tresca)",
}
#: Names of the states a frictionless law gives (slip bound 0: a touching node is in contact,
#: neither sliding nor sticking); the others cannot occur without friction.
FRICTIONLESS_STATE_NAMES = {
    State.NO_CONTACT: "no contact",
    State.SLIDING: "in contact",
    State.WEAK_CONTACT_SLIDING: "grazing, moving",
    State.WEAK_CONTACT_STICKING: "grazing, at rest",
}


def state_names(frictional: bool) -> dict[State, str]:
    """Names of the states a contact law can give, as figures and ``summary.json`` show them:
    :data:`STATE_NAMES` for a law with friction (``law.frictional``), else
    :data:`FRICTIONLESS_STATE_NAMES`."""
    return STATE_NAMES if frictional else FRICTIONLESS_STATE_NAMES


#: What the contact pressure (a node's normal force over its contact area) is, by the area it
#: is divided by: its name in figures, ``summary.json`` and ParaView, and its definition.
PRESSURE_DEFINITIONS = {
    "Cauchy": "normal force per deformed area: the normal Cauchy traction on the deformed surface",
    "nominal": "normal force per reference area: the nominal (first Piola) normal traction",
}


def pressure_kinds(problem: ContactProblem) -> list[str]:
    """The kind (a key of :data:`PRESSURE_DEFINITIONS`) of each contact pair's pressure:
    ``Cauchy`` when its nodal areas are those of the deformed surface, i.e. a hyperelastic
    body (finite strain) and the pair searched in the current configuration each step;
    ``nominal`` at small strain (where the two agree to the strain's order) or for a pair
    searched once (areas of the reference configuration)."""
    finite_strain = problem.hyperelastic is not None
    return ["Cauchy" if finite_strain and i.searched_each_step else "nominal" for i in problem.interfaces]


def pressure_label(problem: ContactProblem) -> str:
    """The contact pressure's name: ``Cauchy contact pressure`` or ``nominal contact pressure``
    (:func:`pressure_kinds`); ``Cauchy / nominal contact pressure`` when the pairs differ."""
    kinds = pressure_kinds(problem)
    return " / ".join(k for k in PRESSURE_DEFINITIONS if k in kinds) + " contact pressure"


#: States counted as sticking and as sliding in areas and indicators; all others are open.
STICKING_STATES = (State.STICKING, State.WEAK_STICKING)
SLIDING_STATES = (State.SLIDING,)

#: SI units of the fields and summary entries.
UNITS = {
    "body": "1",
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
    "max_nodal_contact_pressure": "Pa",
    "max_nodal_contact_pressure_at": "m",
    "min_nodal_contact_pressure": "Pa",
    "contact_pressure_range": "Pa",
    "deformed_contact_area": "m^2",
    "max_von_mises": "Pa",
    "equilibrium_error": "1",
    "displacement_norm": "m",
}


def contact_facet_areas(problem: ContactProblem, states: np.ndarray, displacement: fem.Function | None = None,
                        deformed: bool = False) -> np.ndarray:
    """Sticking and sliding area (m^2) of this rank's owned slave facets: ``[sticking, sliding]``.
    Not collective.

    Each facet f counts its area A_f times the share of its nodes that stick, and that slide, each
    such node j weighted by max(0, -N_f . n_j), N_f the facet's outward unit normal and n_j the
    node's contact normal (from the master into the body): the facet's area projected on the
    plane normal to the contact, so a facet that faces the master counts wholly and a side facet
    touched at a corner node only (its normal across the contact normal) counts nothing. A facet
    all of whose nodes touch squarely counts wholly, one that the edge of the contact zone runs
    through (some nodes open) by the share of its nodes that touch, i.e. the integral of the P1
    interpolant of the nodes' 0/1 indicator over a triangle (which puts the edge half way between
    the last node in contact and the first open one, on average). Supported nodes (all three
    components prescribed; they have no contact law) take no part, so a flat slave surface
    entirely in contact counts its whole area; a slave node that found no master facet counts
    as open, and a facet of supported nodes only counts nothing.

    Args:
        problem: the contact problem.
        states: :class:`State` of each owned contact node (``problem.contact_blk``).
        displacement: N_f is taken on the surface displaced by it (the configuration a finite
            strain step reached); None: the reference one.
        deformed: A_f of the displaced surface (else of the reference one).
    """
    V = problem.V
    code = la.vector(V.dofmap.index_map, bs=1)  # per node: 0 supported, 1 open, 2 sliding, 3 sticking
    supported = np.bincount(problem.dirichlet_dofs_loc // 3, minlength=len(code.array)) == 3
    code.array[:] = np.where(supported, 0.0, 1.0)
    code.array[problem.contact_blk] = np.select([np.isin(states, STICKING_STATES), np.isin(states, SLIDING_STATES)],
                                                [3.0, 2.0], 1.0)
    code.scatter_forward()
    node_blk = _slave_facet_nodes(problem)
    x = V.tabulate_dof_coordinates()
    moved = x if displacement is None else x + displacement.x.array.reshape(-1, 3)
    area, normal = _facet_geometry(problem, node_blk, moved)
    if displacement is not None and not deformed:
        area = _facet_geometry(problem, node_blk, x)[0]
    facing = np.maximum(-np.einsum("fi,fki->fk", normal, _contact_normals(problem)[node_blk]), 0.0)
    node_code = code.array[node_blk]
    share = area / np.maximum(np.count_nonzero(node_code > 0, axis=1), 1)
    sticking, sliding = (np.sum(facing * (node_code == code_of_state), axis=1) for code_of_state in (3, 2))
    return np.array([share @ sticking, share @ sliding])


def _slave_facet_nodes(problem: ContactProblem) -> np.ndarray:
    """(F, k) local blocks of the nodes of this rank's owned slave facets (k = 3 or 4, in the
    facet's vertex order)."""
    msh = problem.V.mesh
    fdim = msh.topology.dim - 1
    msh.topology.create_connectivity(fdim, 0)
    facets = problem.contact_facets[problem.contact_facets < msh.topology.index_map(fdim).size_local]
    k = 4 if msh.topology.cell_type == dmesh.CellType.hexahedron else 3
    return vertex_blocks(problem.V)[msh.topology.connectivity(fdim, 0).array.reshape(-1, k)[facets]]


def _facet_geometry(problem: ContactProblem, node_blk: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Area (F,) and outward unit normal (F, 3) of the facets of nodes ``node_blk`` at the node
    positions ``x`` (local blocks, 3): from the diagonals (tensor-product quadrilaterals: 0-3,
    1-2), oriented away from the centre of the cell the facet bounds."""
    msh = problem.V.mesh
    fdim = msh.topology.dim - 1
    msh.topology.create_connectivity(fdim, fdim + 1)
    facets = problem.contact_facets[problem.contact_facets < msh.topology.index_map(fdim).size_local]
    cells = msh.topology.connectivity(fdim, fdim + 1)
    cell = cells.array[cells.offsets[facets]]  # a boundary facet's one cell
    corners = x[node_blk]
    quadrilateral = node_blk.shape[1] == 4
    diagonals = (corners[:, 3] - corners[:, 0], corners[:, 2] - corners[:, 1]) if quadrilateral else (
        corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    cross = np.cross(*diagonals).reshape(-1, 3)
    area = 0.5 * np.linalg.norm(cross, axis=1)
    outward = corners.mean(axis=1) - x[problem.V.dofmap.list[cell]].mean(axis=1)
    normal = cross * np.sign(np.einsum("fi,fi->f", cross, outward))[:, None] / np.maximum(2.0 * area, 1e-300)[:, None]
    return area, normal


def _contact_normals(problem: ContactProblem) -> np.ndarray:
    """(local nodes incl. ghosts, 3) the contact normal n of each contact node's frame (from the
    master into the body), zero at the other nodes."""
    normals = la.vector(problem.V.dofmap.index_map, bs=3)
    normals.array[:] = 0.0
    normals.array.reshape(-1, 3)[problem.contact_blk] = problem.frames[:, 2]
    normals.scatter_forward()
    return normals.array.reshape(-1, 3)


#: Values beyond the quartiles by more than this many interquartile ranges are outliers (Tukey's fences).
FENCE = 1.5


def robust_range(values: np.ndarray, fenced: bool = True) -> tuple[float, float]:
    """The 1st and 99th percentile of ``values``, ``fenced`` within Tukey's fences (:data:`FENCE`
    interquartile ranges beyond the quartiles): the range a colour scale spans and the summary's
    ``contact_pressure_range``. On a coarse mesh a few corner nodes at a symmetry plane are more
    than 1 % of the pressing nodes (a press fit's 4 of 67, 193-314 MPa where the others carry
    61-131), and the fences keep them from setting the range, while a Hertz distribution lies
    within them. A stress map is not fenced: its contact zone is a few percent of the boundary's
    cells, outside the fences of the rest."""
    first, lower, upper, last = np.percentile(values, [1.0, 25.0, 75.0, 99.0])
    spread = FENCE * (upper - lower) if fenced else np.inf
    return float(max(first, lower - spread)), float(min(last, upper + spread))


def pressure_measure(problem: ContactProblem) -> str:
    """What the nodal pressures lambda_j / A_j of ``problem`` are, in ``summary.json``: ``"cauchy"``
    (force per area of the deformed surface) when every pair's is (:func:`pressure_kinds`: a
    hyperelastic body, the pair searched each step, A_j the nodal areas of the configuration the
    step was searched in: the step before's, this step's with ``search = "until_settled"`` or
    ``"newton"``),
    ``"nominal"`` (per area of the reference surface) when every pair's is, else ``"mixed"``."""
    kinds = set(pressure_kinds(problem))
    return kinds.pop().lower() if len(kinds) == 1 else "mixed"


def pressure_summary(problem: ContactProblem, result: SCDNewtonResult) -> dict[str, typing.Any]:
    """The contact pressure of a solved step in ``summary.json`` terms (Pa). Collective.

    ``max_contact_pressure``: the largest facet average, over the owned slave facets, of the P1
    interpolant of the nodal pressures p_j = lambda_j / A_j (0 at supported nodes): the mean of
    the facet's nodal values, so one node (a corner where the nodal areas are cut) moves it by
    a third (a quarter on quadrilaterals) of its excess only; ``max_nodal_contact_pressure``
    and ``max_nodal_contact_pressure_at``: the largest p_j and its node's reference position (m);
    ``min_nodal_contact_pressure``: the smallest p_j > 0, of the nodes that carry a normal force (0
    if none), with the largest the spread of a pressure that should be uniform (every slave node,
    the edge nodes of quadratic elements too);
    ``contact_pressure_range``: the robust range, :func:`pressure_range`; ``contact_pressure_measure``:
    :func:`pressure_measure`.
    """
    comm = problem.comm
    pressure = result.normal_force / problem.contact_area
    nodal = la.vector(problem.V.dofmap.index_map, bs=1)
    nodal.array[:] = 0.0
    nodal.array[problem.contact_blk] = pressure
    nodal.scatter_forward()
    facet_mean = nodal.array[_slave_facet_nodes(problem)].mean(axis=1)
    x = problem.V.tabulate_dof_coordinates()[problem.contact_blk]
    top = int(np.argmax(pressure)) if len(pressure) else -1
    value, at = max(comm.allgather((float(pressure[top]), x[top].tolist()) if top >= 0 else (-np.inf, None)),
                    key=lambda item: item[0])
    gathered = np.concatenate(comm.allgather(pressure))
    loaded = gathered[gathered > 0.0]
    return {"max_contact_pressure": comm.allreduce(float(facet_mean.max(initial=0.0)), op=MPI.MAX),
            "max_nodal_contact_pressure": max(value, 0.0), "max_nodal_contact_pressure_at": at,
            "min_nodal_contact_pressure": float(loaded.min()) if len(loaded) else 0.0,
            "contact_pressure_range": pressure_range(gathered),
            "contact_pressure_measure": pressure_measure(problem)}


def pressure_range(pressure: np.ndarray) -> list[float]:
    """The robust range [low, high] (Pa) of nodal contact pressures ``pressure`` (all nodes: gathered):
    :func:`robust_range` of the pressures > 0, the range of the pictures' colours; [0, 0] if none is loaded."""
    loaded = pressure[pressure > 0.0]
    return list(robust_range(loaded)) if len(loaded) else [0.0, 0.0]


def labelled(name: str) -> str:
    """Field name with its unit, as written to files: ``contact_pressure [Pa]``."""
    return f"{name} [{UNITS[name]}]"


@dataclasses.dataclass
class ContactSurfaceFields:
    """Named P1 functions on the contact surface mesh (seed 000, Sect. 7 output).

    Attributes:
        state: ``contact_state``, the :class:`~contactqvi.contact.nodal.State` value.
        pair: ``contact_pair``, the index of the node's contact pair in
            ``problem.interfaces`` (the order of ``[[contacts]]``); -1 at nodes without
            a contact law.
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
            normal of the node's frame, g + n . u~ (linearised as in the seed); at a
            slave node without contact law of a body pair, NaN.
        displacement: ``displacement`` (m): u~, for warping the surface.
        nodal_area: ``nodal_area`` (m^2): lumped area of each surface node, so that
            the sum of pressure * nodal_area is the total normal force.
    """

    state: fem.Function
    pair: fem.Function
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


def vertex_blocks(V: fem.FunctionSpace) -> np.ndarray:
    """Local block (node) index of each local vertex, for a Lagrange space of degree 1 or 2.

    The i-th dof of a cell sits at the cell's i-th vertex (a quadratic space's vertex dofs come first).
    """
    msh = V.mesh
    tdim = msh.topology.dim
    msh.topology.create_connectivity(tdim, 0)
    cell_vertices = msh.topology.connectivity(tdim, 0).array.reshape(-1, cell_num_vertices(msh.topology.cell_type))
    index_map = msh.topology.index_map(0)
    blocks = np.empty(index_map.size_local + index_map.num_ghosts, dtype=np.int32)
    blocks[cell_vertices.ravel()] = V.dofmap.list[:, :cell_vertices.shape[1]].ravel()
    return blocks


#: Columns of the nodal table :meth:`ContactSurface._fill_table` fills on the contact nodes.
_COLUMNS = {"state": 0, "contact": 1, "pressure": 2, "traction": slice(3, 6), "slip": slice(6, 9),
            "gap": 9, "normal": slice(10, 13), "pair": 13}
_TABLE_BS = 14


class TributaryPatches:
    """Facets cut into one quadrilateral per vertex (through edge midpoints and centre).

    Point values are interpolated to the new points (midpoint: mean of the edge's
    ends; centre: mean of the facet's vertices, the bilinear/linear value there), or, for
    quadratic elements, given there (:meth:`extend`).

    Args:
        points: (N, 3) vertices.
        cells: (C, k) facets, VTK order (the vertices go round each facet).
        duplicate: (N,) True at vertices another piece owns (None: none).
    """

    def __init__(self, points: np.ndarray, cells: np.ndarray, duplicate: np.ndarray | None = None):
        n_points, (n_cells, k) = len(points), cells.shape
        ends = np.stack([cells, np.roll(cells, -1, axis=1)], axis=2).reshape(-1, 2)  # edge j: vertex j to j+1
        self.edges, edge_of = np.unique(np.sort(ends, axis=1), axis=0, return_inverse=True)
        self.edges = self.edges.reshape(-1, 2)
        edge_of = edge_of.reshape(n_cells, k) + n_points
        centre = n_points + len(self.edges) + np.arange(n_cells)
        self._cells = cells
        self.vertex = cells.ravel()  # the node whose patch each patch is
        self.cells = np.stack([cells, edge_of, np.repeat(centre[:, None], k, axis=1), np.roll(edge_of, 1, axis=1)],
                              axis=2).reshape(-1, 4)
        self.points = self.extend(points)
        self.duplicate = np.zeros(len(self.points), dtype=bool)
        if duplicate is not None:
            self.duplicate[:n_points] = duplicate

    @classmethod
    def of_mesh(cls, piece: MeshPiece) -> TributaryPatches:
        """The patches of this rank's owned facets; a midpoint is a duplicate where another rank owns the edge."""
        patches = cls(piece.points, piece.cells, piece.duplicate)
        n_points = len(piece.points)
        patches.duplicate[n_points : n_points + len(patches.edges)] = _edges_owned_elsewhere(piece, patches.edges)
        return patches

    def extend(self, values: np.ndarray, midpoints: np.ndarray | None = None,
               centres: np.ndarray | None = None) -> np.ndarray:
        """Values at the vertices extended to the patches' points; at the edges' midpoints
        ``midpoints`` where given (the midside nodes of quadratic elements), else the mean of the ends;
        at the facets' centres ``centres`` where given (the centre nodes of 9-node quadrilaterals), else
        the mean of the vertices."""
        at_edges = values[self.edges].mean(axis=1) if midpoints is None else midpoints
        at_centres = values[self._cells].mean(axis=1) if centres is None else centres
        return np.concatenate([values, at_edges, at_centres])

    def dataset(self, point_data: dict[str, np.ndarray], state: np.ndarray, pair: np.ndarray,
                midpoints: dict[str, np.ndarray] | None = None, centres: dict[str, np.ndarray] | None = None,
                ) -> Dataset:
        """Point data (at the vertices; ``midpoints``: at the edges' midpoints, ``centres``: at the facets'
        centres) extended; cell data: ``state`` and ``pair`` of each patch's
        vertex and the indicators ``is_open``, ``is_in_contact`` (sticking or sliding: the
        one that names a frictionless pair's contact), ``is_sliding``, ``is_sticking``: 0/1 by the
        vertex's state, and on the patch of a vertex without contact law (``pair`` -1, a
        supported node) the share of its facet's other nodes in that state, as
        :func:`contact_facet_areas` counts them (on facets whose patches have equal areas,
        e.g. triangles and parallelograms, and that face the master squarely, integrating an
        indicator gives that area; the indicators are not weighted by the facets' normals)."""
        state = state[self.vertex].astype(np.int32)
        pair = np.rint(pair[self.vertex]).astype(np.int32)
        law = (pair >= 0).reshape(self._cells.shape)  # (facets, vertices): also for a rank without facets
        indicators = {}
        for name, states in (("is_sliding", SLIDING_STATES), ("is_sticking", STICKING_STATES)):
            on = np.isin(state, states).reshape(law.shape) & law
            share = np.count_nonzero(on, axis=1) / np.maximum(np.count_nonzero(law, axis=1), 1)
            indicators[name] = np.where(law, on, share[:, None]).ravel()
        indicators["is_in_contact"] = indicators["is_sliding"] + indicators["is_sticking"]
        indicators["is_open"] = 1.0 - indicators["is_in_contact"]
        return Dataset(
            points=self.points,
            cells=self.cells,
            cell_type=9,  # VTK_QUAD
            point_data={name: self.extend(values, (midpoints or {}).get(name), (centres or {}).get(name))
                        for name, values in point_data.items()},
            cell_data={"contact_state": state, "contact_pair": pair, **{
                name: indicators[name] for name in ("is_open", "is_in_contact", "is_sliding", "is_sticking")}},
            duplicate=self.duplicate,
        )


def _vertex_of_node(msh: dmesh.Mesh) -> np.ndarray:
    """The topological vertex of each local geometry node of ``msh`` at a cell's vertex (the
    vertices come first in a cell's geometry nodes, in the same order)."""
    tdim = msh.topology.dim
    msh.topology.create_connectivity(tdim, 0)
    vertex_of_node = np.empty(msh.geometry.x.shape[0], dtype=np.int64)
    cell_vertices = msh.topology.connectivity(tdim, 0).array.reshape(len(msh.geometry.dofmap),
                                                                     cell_num_vertices(msh.topology.cell_type))
    vertex_of_node[msh.geometry.dofmap[:, :cell_vertices.shape[1]].ravel()] = cell_vertices.ravel()
    return vertex_of_node


def _edges_of(msh: dmesh.Mesh, vertices: np.ndarray) -> np.ndarray:
    """The local edge of ``msh`` between each pair of local vertices ``vertices`` (E, 2)."""
    msh.topology.create_entities(1)
    msh.topology.create_connectivity(1, 0)
    n_vertices = msh.topology.index_map(0).size_local + msh.topology.index_map(0).num_ghosts

    def key(pairs: np.ndarray) -> np.ndarray:
        pairs = np.sort(pairs, axis=1)
        return pairs[:, 0] * n_vertices + pairs[:, 1]

    edge_keys = key(msh.topology.connectivity(1, 0).array.reshape(-1, 2).astype(np.int64))
    order = np.argsort(edge_keys)
    return order[np.searchsorted(edge_keys, key(np.asarray(vertices, dtype=np.int64)), sorter=order)]


def _edges_owned_elsewhere(piece: MeshPiece, edges: np.ndarray) -> np.ndarray:
    """For edges given by point index pairs of ``piece``, True where another rank owns the edge."""
    msh = piece.mesh
    edge = _edges_of(msh, _vertex_of_node(msh)[piece.nodes[edges]])
    return edge >= msh.topology.index_map(1).size_local


def _midside_blocks(V: fem.FunctionSpace, piece: MeshPiece, edges: np.ndarray, vertex_map: np.ndarray) -> np.ndarray:
    """The block of the quadratic space ``V`` at the midside node of each edge of ``piece`` (point
    index pairs; ``piece`` a submesh of V's mesh whose vertices are ``vertex_map`` of V's mesh)."""
    msh = V.mesh
    tdim = msh.topology.dim
    edge = _edges_of(msh, vertex_map[_vertex_of_node(piece.mesh)[piece.nodes[edges]]])
    msh.topology.create_connectivity(1, tdim)
    msh.topology.create_connectivity(tdim, 1)
    e2c, c2e = msh.topology.connectivity(1, tdim), msh.topology.connectivity(tdim, 1)
    cells = e2c.array[e2c.offsets[edge]]
    per_cell = c2e.offsets[1] - c2e.offsets[0]
    local = np.argmax(c2e.array.reshape(-1, per_cell)[cells] == edge[:, None], axis=1)
    edge_dof = np.array([V.dofmap.dof_layout.entity_dofs(1, i)[0] for i in range(per_cell)])
    return V.dofmap.list[cells, edge_dof[local]]


def _centre_blocks(V: fem.FunctionSpace, facets: np.ndarray) -> np.ndarray:
    """The block of the quadratic space ``V`` on hexahedra at the centre node of each exterior facet
    ``facets`` of V's mesh (the last node of its closure)."""
    cells, local = exterior_facet_cells(V.mesh, np.asarray(facets, dtype=np.int32))
    return V.dofmap.list[cells, facet_closures(V.dofmap.dof_layout, V.mesh)[local, -1]]


class ContactSurface:
    """The contact facets of ``problem`` as a surface mesh with its fields; built once, updated per step.

    Collective. The fields (:attr:`fields`) are P1 functions allocated once;
    :meth:`update` overwrites them with a solved step's values.
    """

    def __init__(self, problem: ContactProblem):
        V = problem.V
        msh = V.mesh
        self.problem = problem
        self.mesh, facet_of_cell, vertex_map, _ = dmesh.create_submesh(msh, msh.topology.dim - 1,
                                                                       problem.contact_facets)
        scalars = fem.functionspace(self.mesh, ("Lagrange", 1))
        vectors = fem.functionspace(self.mesh, ("Lagrange", 1, (3,)))
        self._parent_blk = vertex_blocks(V)[vertex_map]  # every local surface vertex, owned or ghost
        self._scalar_blk, self._vector_blk = vertex_blocks(scalars), vertex_blocks(vectors)
        self._x = scalars.tabulate_dof_coordinates()[self._scalar_blk]
        self._table = la.vector(V.dofmap.index_map, bs=_TABLE_BS)
        nodal_area = fem.Function(scalars, name="nodal_area")
        fem.assemble_vector(nodal_area.x.array, fem.form(ufl.TestFunction(scalars) * ufl.dx))
        nodal_area.x.scatter_reverse(la.InsertMode.add)
        nodal_area.x.scatter_forward()
        self.fields = ContactSurfaceFields(
            **{key: fem.Function(vectors if vector else scalars, name=name) for key, name, vector in (
                ("state", "contact_state", False), ("pair", "contact_pair", False),
                ("pressure", "contact_pressure", False),
                ("traction", "friction_traction", True), ("slip", "slip", True),
                ("tangential_displacement", "tangential_displacement", True), ("gap", "gap", False),
                ("displacement", "displacement", True))},
            nodal_area=nodal_area,
        )
        self._piece = MeshPiece(self.mesh, linear=True)
        self._patches = TributaryPatches.of_mesh(self._piece)
        # quadratic elements: the values at the midside nodes go to the patches' edge midpoints
        self._midside_blk = (None if displacement_degree(V) == 1 else
                             _midside_blocks(V, self._piece, self._patches.edges, vertex_map))
        self._midside_x = None if self._midside_blk is None else V.tabulate_dof_coordinates()[self._midside_blk]
        # ... and on hexahedra the values at the facets' centre nodes to the patches' centres
        quadratic_hexahedra = self._midside_blk is not None and msh.topology.cell_name() == "hexahedron"
        self._centre_blk = (_centre_blocks(V, facet_of_cell[:self.mesh.topology.index_map(2).size_local])
                            if quadratic_hexahedra else None)
        self._centre_x = None if self._centre_blk is None else V.tabulate_dof_coordinates()[self._centre_blk]
        self._midside_values: dict[str, np.ndarray] = {}
        self._centre_values: dict[str, np.ndarray] = {}

    @property
    def n_nodes(self) -> int:
        """Global number of surface nodes."""
        return self.mesh.geometry.index_map().size_global

    @property
    def node_states(self) -> np.ndarray:
        """:class:`State` of each owned contact node (``problem.contact_blk``) at the last :meth:`update`."""
        return self._table.array.reshape(-1, _TABLE_BS)[self.problem.contact_blk, _COLUMNS["state"]].astype(np.int32)

    def _fill_table(self, u: PETSc.Vec, result: SCDNewtonResult) -> np.ndarray:
        """Per node of V (owned and ghost): state, contact flag, pressure, friction traction,
        slip, gap and frame normal at the contact nodes, global components; zero elsewhere.

        Filled on the owned contact nodes and scattered, so every rank sees the owner's
        values at its ghost nodes.
        """
        problem = self.problem
        values = self._table.array.reshape(-1, _TABLE_BS)
        values[:] = 0.0
        values[:, _COLUMNS["state"]] = State.NO_CONTACT
        values[:, _COLUMNS["pair"]] = -1
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
        values[blk, _COLUMNS["pair"]] = problem.interface_of_node
        self._table.scatter_forward()
        return values

    def update(
        self, u: PETSc.Vec, result: SCDNewtonResult, displacement: fem.Function | None = None
    ) -> ContactSurfaceFields:
        """Contact state, pressure, friction traction, slip, gap and displacement of a solved step.

        Forces and states are those of the last approximation step's graph point
        (``result``), divided by the problem's lumped nodal area; slip and gap come
        from the solution ``u`` (shifted displacements in nodal frames, seed 000
        (6.3)). Collective.

        Args:
            u: the solution (shifted displacements) of the problem at its current step.
            result: the solver's result for ``u``.
            displacement: the physical displacement of ``u`` if computed already.

        Returns:
            :attr:`fields`, holding this step's values.
        """
        problem = self.problem
        table = self._fill_table(u, result)
        if displacement is None:
            displacement = problem.physical_displacement(u, fem.Function(problem.V))
        u_all = displacement.x.array.reshape(-1, 3)
        fields = self.fields
        for name, values in self._values_at(table, u_all, self._parent_blk, self._x).items():
            f = getattr(fields, name)
            blk = self._vector_blk if values.ndim == 2 else self._scalar_blk
            bs = f.function_space.dofmap.index_map_bs
            f.x.array.reshape(-1, bs)[blk] = values.reshape(-1, bs)
        if self._midside_blk is not None:
            self._midside_values = self._point_values_at(table, u_all, self._midside_blk, self._midside_x)
        if self._centre_blk is not None:
            self._centre_values = self._point_values_at(table, u_all, self._centre_blk, self._centre_x)
        return fields

    def _point_values_at(self, table: np.ndarray, displacement: np.ndarray, blocks: np.ndarray,
                         x: np.ndarray) -> dict[str, np.ndarray]:
        """The point fields' values (by file name) at the nodes ``blocks`` of V at reference positions
        ``x`` (:meth:`_values_at`; the state and pair are cell data, those of the patches' vertices)."""
        return {labelled(getattr(self.fields, name).name): values for name, values in
                self._values_at(table, displacement, blocks, x).items() if name not in ("state", "pair")}

    def _values_at(self, table: np.ndarray, displacement: np.ndarray, blocks: np.ndarray,
                   x: np.ndarray) -> dict[str, np.ndarray]:
        """The fields' values (by :class:`ContactSurfaceFields` name) at the nodes ``blocks`` of V at
        reference positions ``x``, from the nodal ``table`` (:meth:`_fill_table`) and the physical
        ``displacement`` (local nodes, 3)."""
        problem = self.problem
        nodal, u_tilde = table[blocks], displacement[blocks]
        contact = nodal[:, _COLUMNS["contact"]] > 0
        if problem.obstacle is not None:  # the surface's other nodes: gap and normal to the obstacle
            initial_gap, normal = placed(problem.obstacle, problem.translation, problem.step_rotation).distance(x)
        else:  # a body pair: no gap where there is no contact law
            initial_gap, normal = np.full(len(x), np.nan), np.zeros_like(x)
        normal[contact] = nodal[contact, _COLUMNS["normal"]]  # the nodes' (reference) frames
        gap = np.where(contact, nodal[:, _COLUMNS["gap"]], initial_gap + np.einsum("ij,ij->i", normal, u_tilde))
        tangential = u_tilde - np.einsum("ij,ij->i", normal, u_tilde)[:, None] * normal
        return {**{name: nodal[:, _COLUMNS[name]] for name in ("state", "pair", "pressure", "traction", "slip")},
                "tangential_displacement": tangential, "gap": gap, "displacement": u_tilde}

    def dataset(self) -> Dataset:
        """This rank's piece of the tributary patches with the current fields. Not collective.

        Point data: every field but ``contact_state``, ``contact_pair`` and ``nodal_area``,
        named with units (``contact_pressure [Pa]``); cell data: ``contact_state`` and
        ``contact_pair`` of the patch's node and the 0/1 indicators ``is_open``,
        ``is_sliding``, ``is_sticking`` (integrating one over the surface gives that area).
        """
        piece = self._piece
        point_data = {labelled(f.name): piece.point_values(f) for f in self.fields.functions
                      if f.name not in ("contact_state", "contact_pair", "nodal_area")}
        return self._patches.dataset(point_data, piece.point_values(self.fields.state),
                                     piece.point_values(self.fields.pair), self._midside_values, self._centre_values)
