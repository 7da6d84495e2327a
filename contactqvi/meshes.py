"""Meshes of the papers' geometries, with named facet tags, and gmsh readers.

Every constructor returns ``(mesh, facet_tags)``; the integer tag of a named
boundary is ``tag_of(facet_tags, name)``, and the names are stored on the tags
object as ``facet_tags.names`` (``dict[str, int]``).

In parallel every mesh is distributed by :func:`cell_partitioner`: the same
partition on every run, and no ghost cells unless asked for.
"""

from __future__ import annotations

import contextlib
import dataclasses
import itertools
import math
import os
import pathlib
import typing

from mpi4py import MPI

import numpy as np

from dolfinx import graph
from dolfinx import mesh as dmesh

from contactqvi.parameters import ParameterError, require

__all__ = [
    "BOX_BOUNDARIES",
    "ELEMENT_KINDS",
    "SQUARE_BOUNDARIES",
    "INTERVAL_BOUNDARIES",
    "contact_body_sizes",
    "create_contact_body",
    "create_unit_square",
    "create_unit_interval",
    "SEPARATE_BODIES",
    "SharedNodes",
    "read_gmsh",
    "split_by_body",
    "tag_of",
    "boundary_facets",
    "cell_partitioner",
]

#: Boundary names of the contact body Omega(d) of seed 000, Sect. 7.
BOX_BOUNDARIES = {"dirichlet": 1, "right": 2, "top": 3, "contact": 4, "front": 5, "back": 6}
#: Boundary names of the unit square.
SQUARE_BOUNDARIES = {"left": 1, "right": 2, "bottom": 3, "top": 4}
#: Boundary names of the unit interval.
INTERVAL_BOUNDARIES = {"left": 1, "right": 2}

GapFunction = typing.Callable[[np.ndarray, np.ndarray], np.ndarray]


@contextlib.contextmanager
def _environment(**variables: str) -> typing.Iterator[None]:
    """Set environment variables for the duration of a ``with`` block."""
    saved = {name: os.environ.get(name) for name in variables}
    os.environ.update(variables)
    try:
        yield
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


def cell_partitioner(
    comm: MPI.Comm, ghost_mode: dmesh.GhostMode = dmesh.GhostMode.none
) -> typing.Callable | None:
    """A cell partitioner that gives the same partition on every run; None in serial.

    DOLFINx partitions with PT-SCOTCH, and SCOTCH 7 runs several threads per
    process whose races change the result: the same 2-rank command got one of two
    partitions at random, and through the GAMG aggregates different Newton and
    Krylov counts. Run with one thread (``SCOTCH_PTHREAD_NUMBER=1``, set only
    while partitioning) and a fixed seed, the partition depends on nothing but the
    mesh and the number of ranks.

    Args:
        comm: communicator the mesh is distributed over.
        ghost_mode: ``GhostMode.none`` (default; nothing in contactqvi integrates
            over interior facets) or ``GhostMode.shared_facet``. Without ghost cells
            each cell lives on one rank only, and files written by the ranks
            together hold every cell once.
    """
    if comm.size == 1:
        return None
    scotch = graph.partitioner_scotch(imbalance=0.025, seed=0)

    def partition(comm, n_parts, local_graph, ghosting):
        with _environment(SCOTCH_PTHREAD_NUMBER="1"):
            return scotch(comm, n_parts, local_graph, ghosting)

    return dmesh.create_cell_partitioner(partition, ghost_mode)


def _tag_facets(msh: dmesh.Mesh, markers: dict[str, typing.Callable], names: dict[str, int]) -> dmesh.MeshTags:
    """Facet tags from boundary markers; a facet takes the first marker that claims all its nodes.

    The markers are evaluated at the nodes of the exterior facets, which needs only
    the facet-cell connectivity (``locate_entities_boundary`` would also build the
    vertex-to-cell and facet-to-facet connectivities, about 20 bytes per dof that the
    mesh then keeps).
    """
    fdim = msh.topology.dim - 1
    msh.topology.create_connectivity(fdim, msh.topology.dim)
    exterior = dmesh.exterior_facet_indices(msh.topology)
    nodes = dmesh.entities_to_geometry(msh, fdim, exterior)
    points = msh.geometry.x[nodes.ravel()].T
    values = np.zeros(len(exterior), dtype=np.int32)
    for name, marker in markers.items():
        claimed = np.asarray(marker(points), dtype=bool).reshape(nodes.shape).all(axis=1)
        values[(values == 0) & claimed] = names[name]
    tagged = values > 0
    tags = dmesh.meshtags(msh, fdim, exterior[tagged], values[tagged])
    tags.names = dict(names)
    return tags


def tag_of(facet_tags: dmesh.MeshTags, name: str) -> int:
    """Integer tag of the boundary called ``name``; unknown names raise."""
    names = getattr(facet_tags, "names", {})
    require(name in names, "boundary", f"unknown boundary {name!r}; known: {', '.join(sorted(names))}")
    return names[name]


def boundary_facets(facet_tags: dmesh.MeshTags, name: str) -> np.ndarray:
    """Local indices of the facets of boundary ``name``."""
    return facet_tags.find(tag_of(facet_tags, name))


def contact_body_sizes(lev: int) -> dict[str, int]:
    """Cell counts, contact nodes p and free dofs n of Omega(d) at level ``lev``.

    Seed 000, Sect. 7: nx1 = ceil(4 2^(lev/2)), nx2 = nx3 = ceil(2 2^(lev/2)),
    p = nx1 (nx2 + 1) and n = 3 nx1 (nx2 + 1)(nx3 + 1) (Table 2).
    """
    require(isinstance(lev, (int, np.integer)) and lev >= 0, "lev", f"must be an integer >= 0, got {lev!r}")
    scale = 2.0 ** (lev / 2)
    nx1 = math.ceil(4 * scale - 1e-12)
    nx2 = nx3 = math.ceil(2 * scale - 1e-12)
    return {"nx1": nx1, "nx2": nx2, "nx3": nx3, "p": nx1 * (nx2 + 1), "n": 3 * nx1 * (nx2 + 1) * (nx3 + 1)}


def create_contact_body(
    comm: MPI.Comm, lev: int, gap: GapFunction, length: float = 2.0, width: float = 1.0, height: float = 1.0,
    cell_type: str = "hexahedron",
) -> tuple[dmesh.Mesh, dmesh.MeshTags]:
    """Hexahedral (or, ``cell_type="tetrahedron"``, tetrahedral: six per hexahedron) mesh of Omega(d) = {(x1, x2) in (0,L)x(0,W), d(x1,x2) < x3 < H}.

    Seed 000, Sect. 7: the box is cut into nx1 nx2 nx3 hexahedra (see
    :func:`contact_body_sizes`) and the vertices are moved vertically to
    x3 = d + s (H - d) for s uniform in [0, 1]. Facet tags: ``dirichlet``
    (x1 = 0), ``right`` (x1 = L), ``top`` (x3 = H), ``contact`` (bottom),
    ``front`` (x2 = 0), ``back`` (x2 = W).

    Args:
        comm: communicator the mesh is distributed over.
        lev: discretisation level (>= 0).
        gap: the initial gap d(x1, x2) >= 0, vectorised over numpy arrays.
        length, width, height: box dimensions (m).
    """
    sizes = contact_body_sizes(lev)
    for name, value in (("length", length), ("width", width), ("height", height)):
        require(value > 0, name, f"must be > 0, got {value!r}")
    kinds = {"hexahedron": dmesh.CellType.hexahedron, "tetrahedron": dmesh.CellType.tetrahedron}
    require(cell_type in kinds, "cell_type", f"must be one of {sorted(kinds)}, got {cell_type!r}")
    msh = dmesh.create_box(
        comm,
        [np.zeros(3), np.array([length, width, height])],
        [sizes["nx1"], sizes["nx2"], sizes["nx3"]],
        kinds[cell_type],
        partitioner=cell_partitioner(comm),
    )
    x = msh.geometry.x
    d = np.asarray(gap(x[:, 0], x[:, 1]), dtype=float)
    d = np.broadcast_to(d, x[:, 0].shape)
    lowest = msh.comm.allreduce(float(d.min()), op=MPI.MIN)
    highest = msh.comm.allreduce(float(d.max()), op=MPI.MAX)
    require(lowest >= 0, "gap", f"initial gap must be >= 0 everywhere (no initial penetration), min = {lowest:g}")
    require(highest < height, "gap", f"gap must stay below the height {height:g}, max = {highest:g}")
    tol = 1e-10 * max(length, width, height)
    markers = {
        "dirichlet": lambda p: np.isclose(p[0], 0.0, atol=tol),
        "right": lambda p: np.isclose(p[0], length, atol=tol),
        "top": lambda p: np.isclose(p[2], height, atol=tol),
        "contact": lambda p: np.isclose(p[2], 0.0, atol=tol),
        "front": lambda p: np.isclose(p[1], 0.0, atol=tol),
        "back": lambda p: np.isclose(p[1], width, atol=tol),
    }
    tags = _tag_facets(msh, markers, BOX_BOUNDARIES)
    x[:, 2] = d + x[:, 2] / height * (height - d)
    return msh, tags


def create_unit_square(
    comm: MPI.Comm, n: int, cell_type: str = "quadrilateral"
) -> tuple[dmesh.Mesh, dmesh.MeshTags]:
    """Unit square with n x n cells (Q1 quadrilaterals or P1 triangles).

    Facet tags ``left`` (x = 0), ``right`` (x = 1), ``bottom`` (y = 0), ``top`` (y = 1).
    """
    require(isinstance(n, (int, np.integer)) and n >= 1, "n", f"must be an integer >= 1, got {n!r}")
    kinds = {"quadrilateral": dmesh.CellType.quadrilateral, "triangle": dmesh.CellType.triangle}
    require(cell_type in kinds, "cell_type", f"must be one of {sorted(kinds)}, got {cell_type!r}")
    msh = dmesh.create_unit_square(comm, n, n, kinds[cell_type], partitioner=cell_partitioner(comm))
    markers = {
        "left": lambda p: np.isclose(p[0], 0.0),
        "right": lambda p: np.isclose(p[0], 1.0),
        "bottom": lambda p: np.isclose(p[1], 0.0),
        "top": lambda p: np.isclose(p[1], 1.0),
    }
    return msh, _tag_facets(msh, markers, SQUARE_BOUNDARIES)


def create_unit_interval(comm: MPI.Comm, n: int) -> tuple[dmesh.Mesh, dmesh.MeshTags]:
    """Unit interval with n cells; facet tags ``left`` and ``right``."""
    require(isinstance(n, (int, np.integer)) and n >= 1, "n", f"must be an integer >= 1, got {n!r}")
    msh = dmesh.create_unit_interval(comm, n, partitioner=cell_partitioner(comm))
    markers = {"left": lambda p: np.isclose(p[0], 0.0), "right": lambda p: np.isclose(p[0], 1.0)}
    return msh, _tag_facets(msh, markers, INTERVAL_BOUNDARIES)


def read_gmsh(
    source: str | pathlib.Path, comm: MPI.Comm, gdim: int = 3
) -> tuple[dmesh.Mesh, dmesh.MeshTags, dmesh.MeshTags]:
    """Read a gmsh ``.msh`` file (or a ``.geo`` script) on rank 0 and distribute it.

    Physical groups of dimension gdim-1 become facet tags and those of dimension
    gdim cell tags; their gmsh names become ``facet_tags.names`` and
    ``cell_tags.names`` (``dict[str, int]``). The nodes that cells of two physical
    volumes share become ``cell_tags.shared_nodes`` (a list of :class:`SharedNodes`;
    legal in one body of several volumes, an error for bodies: :func:`split_by_body`).

    Returns:
        ``(mesh, facet_tags, cell_tags)``.

    Raises:
        ParameterError: (``mesh``) on every rank when the file is missing or gmsh cannot
            read it, and before the mesh is distributed when DOLFINx cannot take the
            model (a gmsh volume in two physical volumes, facets of a group with a node
            in no cell, cells of several kinds: they ended in an MPI abort or a heap
            corruption), naming the groups, the counts and where.
    """
    import gmsh

    from dolfinx.io import gmshio

    path = pathlib.Path(source)
    exists = comm.bcast(path.is_file() if comm.rank == 0 else None, root=0)
    require(exists, "mesh", f"mesh file {str(path)!r} not found")
    require(path.suffix in (".msh", ".geo"), "mesh", f"expected a .msh or .geo file, got {path.suffix!r}")
    initialised = gmsh.isInitialized()
    if not initialised:
        gmsh.initialize(interruptible=False)
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        model, error = None, None
        if comm.rank == 0:
            try:  # gmsh's errors (a bad script, a missing Include) happen on rank 0 only: shared below
                model = _read_model(path, gdim)
            except Exception as exc:
                error = f"gmsh cannot read {str(path)!r}: {exc}"
        model, error = comm.bcast((model, error), root=0)
        require(error is None, "mesh", error or "")
        require(model.fault is None, "mesh", model.fault or "")
        # Facet tags are distributed with the cells; with GhostMode.none DOLFINx 0.9 lost a whole
        # group now and then on 2 ranks (inclined_block.geo), so gmsh meshes keep shared-facet ghosts.
        partitioner = cell_partitioner(comm, dmesh.GhostMode.shared_facet)
        msh, cell_tags, facet_tags = gmshio.model_to_mesh(gmsh.model, comm, 0, gdim=gdim, partitioner=partitioner)
    finally:
        if not initialised:
            gmsh.finalize()
    facet_tags.names, cell_tags.names = model.facet_groups, model.volumes
    cell_tags.shared_nodes = model.shared
    n_owned_facets = msh.topology.index_map(gdim - 1).size_local
    for name, tag in model.facet_groups.items():
        found = comm.allreduce(int(np.count_nonzero(facet_tags.find(tag) < n_owned_facets)), op=MPI.SUM)
        require(found == model.facet_counts[name], "mesh", f"physical group {name!r}: {found} of its "
                f"{model.facet_counts[name]} facets arrived after distributing the mesh")
    return msh, facet_tags, cell_tags


@dataclasses.dataclass(frozen=True)
class _GmshModel:
    """What rank 0 reads from a gmsh model before DOLFINx distributes it.

    Attributes:
        facet_groups, volumes: physical groups of dimension gdim-1 and gdim, name -> tag.
        facet_counts: number of facets of each facet group.
        shared: the nodes that cells of two physical volumes share.
        fault: why DOLFINx cannot take the model (error text), or None.
    """

    facet_groups: dict[str, int]
    volumes: dict[str, int]
    facet_counts: dict[str, int]
    shared: list[SharedNodes]
    fault: str | None


def _read_model(path: pathlib.Path, gdim: int) -> _GmshModel:
    """Open ``path`` in gmsh (rank 0 only; a ``.geo`` script is meshed) and check its mesh."""
    import gmsh

    gmsh.open(str(path))
    if path.suffix == ".geo":
        gmsh.model.mesh.generate(gdim)
    groups = {dim: {gmsh.model.getPhysicalName(dim, tag) or str(tag): tag
                    for _, tag in gmsh.model.getPhysicalGroups(dim)} for dim in (gdim - 1, gdim)}
    facets = {name: _element_rows(gdim - 1, tag) for name, tag in groups[gdim - 1].items()}
    cells = {name: _element_rows(gdim, tag) for name, tag in groups[gdim].items()}
    kinds = {name: _element_kinds(gdim, tag) for name, tag in groups[gdim].items()}
    entities = {name: np.asarray(gmsh.model.getEntitiesForPhysicalGroup(gdim, tag), dtype=np.int64)
                for name, tag in groups[gdim].items()}
    node_tags, node_x, _ = gmsh.model.mesh.getNodes()
    nodes = _Nodes(np.asarray(node_tags, dtype=np.int64), np.asarray(node_x, dtype=float).reshape(-1, 3))
    shared, fault = _mesh_faults(facets, cells, entities, nodes)
    fault = _facets_in_two_groups(gdim - 1, groups[gdim - 1]) or _mixed_cells(kinds) or _unread_cells(kinds) or fault
    counts = {name: sum(len(rows) for rows in facets[name]) for name in facets}
    return _GmshModel(groups[gdim - 1], groups[gdim], counts, shared, fault)


def _element_rows(dim: int, tag: int) -> list[np.ndarray]:
    """Node tags of the elements of physical group ``(dim, tag)``: one array per gmsh entity
    and element type, one row per element."""
    import gmsh

    rows = []
    for entity in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
        types, _, nodes = gmsh.model.mesh.getElements(dim, entity)
        rows += [np.asarray(tags, dtype=np.int64).reshape(-1, gmsh.model.mesh.getElementProperties(kind)[3])
                 for kind, tags in zip(types, nodes)]
    return rows


def _facets_in_two_groups(dim: int, groups: dict[str, int]) -> str | None:
    """The error text when gmsh surfaces (facets) are in two facet groups, else None.

    DOLFINx 0.9 gives each facet one tag, so a facet in two physical groups is kept in
    one of them only (which one depends on the tags): the other group loses it.
    """
    import gmsh

    entities = {name: set(gmsh.model.getEntitiesForPhysicalGroup(dim, tag)) for name, tag in groups.items()}
    shared = []
    for first, second in itertools.combinations(sorted(groups), 2):
        common = sorted(entities[first] & entities[second])
        if common:
            count = sum(len(tags) for entity in common for tags in gmsh.model.mesh.getElements(dim, entity)[1])
            kind = "surface" if dim == 2 else "curve"
            listed = ", ".join(str(int(entity)) for entity in common)
            shared.append(f"{first!r} and {second!r} share {count} facets (gmsh {kind}{'s' * (len(common) > 1)} "
                          f"{listed})")
    if not shared:
        return None
    return (f"the physical groups {'; '.join(shared)}: a facet may be in one physical group only (DOLFINx keeps "
            "one group per facet, and the other group loses those facets). Remove the shared surfaces from one "
            "of the two groups (a group the case does not name can go), or split them into surfaces of their own")


def _element_kinds(dim: int, tag: int) -> set[str]:
    """gmsh's names of the kinds of element of physical group ``(dim, tag)`` ("Hexahedron 8")."""
    import gmsh

    return {gmsh.model.mesh.getElementProperties(kind)[0]
            for entity in gmsh.model.getEntitiesForPhysicalGroup(dim, tag)
            for kind in gmsh.model.mesh.getElementTypes(dim, entity)}


def _mixed_cells(kinds: dict[str, set[str]]) -> str | None:
    """The error text when the physical volumes hold cells of several kinds, else None.

    DOLFINx 0.9 builds a mesh of one cell type (gmshio: an ``MPI_ERR_RANK`` abort otherwise),
    and the bodies of a case share one mesh, so a hexahedral body cannot touch a tetrahedral one.
    """
    if len(set().union(*kinds.values())) <= 1:
        return None
    listed = "; ".join(f"{name!r}: {', '.join(sorted(kind))}" for name, kind in kinds.items())
    return (f"the physical volumes hold cells of several kinds ({listed}): the bodies of a case share one mesh, "
            "and DOLFINx 0.9 takes one kind of cell per mesh; mesh every body with the same kind (all "
            "hexahedra: Transfinite and Recombine on every volume, or all tetrahedra)")


#: gmsh's kinds of volume element that the bodies take: first-order and complete second-order
#: tetrahedra and hexahedra (DOLFINx 0.9 reads no serendipity cell, and the elements are of degree 1 or 2).
ELEMENT_KINDS = ("Tetrahedron 4", "Tetrahedron 10", "Hexahedron 8", "Hexahedron 27")


def _unread_cells(kinds: dict[str, set[str]]) -> str | None:
    """The error text when a physical volume holds cells of a kind not in :data:`ELEMENT_KINDS`, else None
    (gmshio stopped with a KeyError of gmsh's element type)."""
    other = {name: sorted(kind - set(ELEMENT_KINDS)) for name, kind in kinds.items() if kind - set(ELEMENT_KINDS)}
    if not other:
        return None
    listed = "; ".join(f"{name!r}: {', '.join(kind)}" for name, kind in other.items())
    return (f"the physical volumes hold cells of kinds that cannot be read ({listed}); the bodies take "
            f"{', '.join(ELEMENT_KINDS)}: mesh in tetrahedra or hexahedra (no prisms or pyramids) with "
            "Mesh.ElementOrder = 1 or 2 and, for hexahedra of second order, Mesh.SecondOrderIncomplete = 0 "
            "(27 nodes, not the 20-node serendipity hexahedron)")


@dataclasses.dataclass(frozen=True)
class _Nodes:
    """The nodes of a gmsh model: tags and coordinates (one row each)."""

    tags: np.ndarray
    x: np.ndarray

    def box(self, tags: np.ndarray) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """Corners of the bounding box of the nodes ``tags``; round-off around 0 printed as 0."""
        order = np.argsort(self.tags)
        x = self.x[order[np.searchsorted(self.tags, tags, sorter=order)]]
        x = np.where(np.abs(x) < 1e-12 * max(float(np.abs(self.x).max()), 1e-300), 0.0, x)
        return tuple(map(float, x.min(axis=0))), tuple(map(float, x.max(axis=0)))


@dataclasses.dataclass(frozen=True)
class SharedNodes:
    """Nodes that cells of two physical volumes share: two bodies that are not separate meshes.

    Attributes:
        first, second: names of the physical volumes.
        count: number of shared nodes.
        lower, upper: corners of their bounding box (x, y, z).
    """

    first: str
    second: str
    count: int
    lower: tuple[float, ...]
    upper: tuple[float, ...]

    def __str__(self) -> str:
        return (f"physical volumes {self.first!r} and {self.second!r} share {self.count} nodes "
                f"({_box_text(self.lower, self.upper)})")


#: What the errors about bodies that share nodes advise (a gmsh script's fixes).
SEPARATE_BODIES = (
    "each body must be a mesh of its own, touching the others without common nodes. gmsh merges coincident "
    "nodes of volumes extruded with Layers{} (a structured extrusion) where they touch, and joins volumes "
    "by Coherence or BooleanFragments: start the bodies a small gap apart (e.g. 1e-6 m: the contact closes "
    "it), or extrude without Layers{}, and do not use Coherence or BooleanFragments across bodies"
)


def _box_text(lower: typing.Sequence[float], upper: typing.Sequence[float]) -> str:
    """``x = 0, y in [0, 0.2], z = 0``: where a set of nodes lies."""
    return ", ".join(f"{axis} = {low:.4g}" if low == high else f"{axis} in [{low:.4g}, {high:.4g}]"
                     for axis, low, high in zip("xyz", lower, upper))


def _mesh_faults(facets: dict[str, list[np.ndarray]], cells: dict[str, list[np.ndarray]],
                 entities: dict[str, np.ndarray], nodes: _Nodes) -> tuple[list[SharedNodes], str | None]:
    """The nodes shared by physical volumes, and the error text of a model DOLFINx cannot take.

    gmshio gives DOLFINx the cells of every physical volume, so a gmsh volume in two of them
    gives each of its cells twice (a heap corruption in 0.9), and the facets of every facet
    group: one with a node in no cell has no rank to go to (``MPI_ERR_RANK``, an abort).
    Shared nodes alone are legal (one body of several volumes); with loose facets they are
    the likely cause (an extrusion with Layers{} merged one body's nodes into another's).
    """
    for first, second in itertools.combinations(entities, 2):
        common = np.intersect1d(entities[first], entities[second])
        if len(common):
            return [], (f"gmsh volume {int(common[0])} is in the physical volumes {first!r} and {second!r}: "
                        "each cell must be in one physical volume")
    used = {name: np.unique(np.concatenate([np.empty(0, np.int64)] + [r.ravel() for r in rows]))
            for name, rows in cells.items()}
    shared = _shared_nodes(used, nodes)
    loose = _loose_facets(facets, np.unique(np.concatenate([np.empty(0, np.int64), *used.values()])), nodes)
    if loose is None:
        return shared, None
    if shared:
        return shared, f"{'; '.join(map(str, shared))}, and {loose}: {SEPARATE_BODIES}"
    return shared, (f"{loose}: each facet of a physical group must be a face of a cell of a physical volume "
                    "(is the group on a volume that is in no Physical Volume?)")


def _shared_nodes(used: dict[str, np.ndarray], nodes: _Nodes) -> list[SharedNodes]:
    """The nodes of the cells of two physical volumes, for each pair of volumes that has some."""
    every = np.concatenate([np.empty(0, np.int64), *used.values()])
    tags, counts = np.unique(every, return_counts=True)
    several = tags[counts > 1]
    shared = []
    for first, second in itertools.combinations(used, 2) if len(several) else ():
        common = np.intersect1d(np.intersect1d(used[first], several, assume_unique=True), used[second],
                                assume_unique=True)
        if len(common):
            shared.append(SharedNodes(first, second, len(common), *nodes.box(common)))
    return shared


def _loose_facets(facets: dict[str, list[np.ndarray]], used: np.ndarray, nodes: _Nodes) -> str | None:
    """Text naming the facets of each group that have a node in no cell, and where; None if none has."""
    loose = {name: [r[~np.isin(r, used).all(axis=1)] for r in rows] for name, rows in facets.items()}
    counts = {name: sum(len(r) for r in rows) for name, rows in loose.items()}
    totals = {name: sum(len(r) for r in rows) for name, rows in facets.items()}
    named = [f"{name!r} ({counts[name]} of {totals[name]})" for name in sorted(counts) if counts[name]]
    if not named:
        return None
    orphans = np.setdiff1d(np.concatenate([r.ravel() for rows in loose.values() for r in rows]), used)
    return (f"{sum(counts.values())} facets of the physical groups {', '.join(named)} have nodes in no cell "
            f"({len(orphans)} nodes, {_box_text(*nodes.box(orphans))})")


def split_by_body(msh: dmesh.Mesh, facet_tags: dmesh.MeshTags, cell_tags: dmesh.MeshTags) -> dmesh.MeshTags:
    """Facet tags named ``"body.group"``: each facet group split by the body its facets bound.

    A body is a named cell group (a gmsh physical volume); a facet of group ``g`` on
    the boundary of body ``b`` gets the name ``"b.g"``, so one gmsh group (e.g.
    ``"top"``) can span several bodies and each body's part is addressed on its own.
    Groups with no facets on a body get no name for it.

    Raises:
        ParameterError: (``mesh``) if two bodies share nodes (``cell_tags.shared_nodes``
            of :func:`read_gmsh`): naming them, how many nodes and where, on every rank.
    """
    shared = getattr(cell_tags, "shared_nodes", [])
    if shared:
        raise ParameterError("mesh", f"{'; '.join(map(str, shared))}: {SEPARATE_BODIES}")
    tdim = msh.topology.dim
    msh.topology.create_connectivity(tdim - 1, tdim)
    f2c = msh.topology.connectivity(tdim - 1, tdim)
    n_cells = msh.topology.index_map(tdim).size_local + msh.topology.index_map(tdim).num_ghosts
    body_of_cell = np.full(n_cells, -1, dtype=np.int64)
    body_of_cell[cell_tags.indices] = cell_tags.values
    facet_body = body_of_cell[f2c.array[f2c.offsets[facet_tags.indices]]]
    bodies = {tag: name for name, tag in cell_tags.names.items()}
    groups = {tag: name for name, tag in facet_tags.names.items()}
    pairs = np.stack([facet_body, facet_tags.values.astype(np.int64)], axis=1)
    local_pairs = {(int(b), int(g)) for b, g in np.unique(pairs, axis=0)} if len(pairs) else set()
    all_pairs = sorted(set().union(*msh.comm.allgather(local_pairs)))
    names = {f"{bodies[b]}.{groups[g]}": i + 1 for i, (b, g) in enumerate(all_pairs) if b in bodies}
    width = max([g for _, g in all_pairs], default=0) + 1
    codes = np.array([b * width + g for b, g in all_pairs], dtype=np.int64)
    values = (np.searchsorted(codes, pairs[:, 0] * width + pairs[:, 1]) + 1).astype(np.int32)
    keep = np.isin(facet_body, list(bodies))
    tags = dmesh.meshtags(msh, tdim - 1, facet_tags.indices[keep], values[keep])
    tags.names = names
    return tags
