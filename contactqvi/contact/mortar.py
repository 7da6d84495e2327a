"""Mortar coupling of two non-matching surfaces with a dual multiplier basis.

The contact conditions between a slave surface Gamma_s and a master surface
Gamma_m are imposed weakly, tested with the dual (biorthogonal) basis psi_i of the
slave nodes (Wohlmuth): on a linear triangle psi_i = 4 phi_i - 1, so that
int_T psi_i phi_k = delta_ik int_T phi_k; on a bilinear quadrilateral (hexahedral
meshes) psi = A phi with A = D_e M_e^{-1} from the facet's mass matrix
(:mod:`contactqvi.contact.facets`); on the 6-node triangles of quadratic displacements, the dual
basis Φ of the slave's modified basis Ñ (:mod:`contactqvi.contact.quadratic`), whose
coefficients ũ = S^-1 u are the slave's unknowns, and on the 9-node quadrilaterals of 27-node
hexahedra the dual basis of their Lagrange functions, the slave's part of the weighted separation
being int Φ_i x over the segments (docs/quadratic.md, Sects. 5-6). The mortar matrices

    D_ii = int_{Gamma_s} psi_i,        M_ij = int_{Gamma_s} psi_i (phi_j^m o pi),

pi the projection of the slave surface onto the master surface along the slave
normal, give the weighted relative displacement of slave node i,

    w_i = u_i - sum_j C_ij u_j,    C = D^{-1} M,

which vanishes for every linear displacement field continuous across the
interface: sum_j M_ij p(x_j) = int psi_i p = D_ii p(x_i) for linear p (the contact
patch test). D_ii is integrated over the mortar segments, the parts of Gamma_s
that have a master facet, as int psi_i sum_k phi_k; with full coverage this is
int phi_i (the lumped area), and sum_j C_ij = 1 always, so rigid translations
of both bodies never open or close the interface. With ``projecting`` (the pairs searched in
the current configuration) a slave facet covered in part takes the dual basis of its covered
part instead (:mod:`contactqvi.contact.covered`), and D_ii = int phi_i over that part.

The integrals of one pair of facets (segment-to-segment, Puso-Laursen) are those of
:mod:`contactqvi.contact.segments`; with ``linearised`` their derivatives with respect to
the searched positions come along (:mod:`contactqvi.contact.linearisation`).

Parallel search: each rank owns the slave facets of its cells; it receives from
every rank the master facets that lie within ``search_distance`` of the bounding
box of its own slave facets (never a whole surface), pairs them by a k-d tree on
facet centroids, integrates, and sends the rows of ghost slave nodes to their
owners. Small deformations with small sliding per search: the search and the
integration take the geometry of a given configuration (the reference one, or the
deformed one of the last load step, :func:`mortar_coupling`'s ``displacement``); the
unknown stays the total displacement, so the weighted gap is taken between the
reference positions with the C of that configuration.
"""

from __future__ import annotations

import dataclasses
import logging

from mpi4py import MPI

import numpy as np
import scipy.spatial

from dolfinx import fem
from dolfinx import mesh as dmesh

from contactqvi.contact.covered import covered_basis
from contactqvi.contact.facets import MODIFIED_AREAS, facet_areas, nodal_integrals, unit_normals
from contactqvi.contact.linearisation import CouplingDerivatives, coupling_derivatives
from contactqvi.contact.owners import fetch_rows, owner_ranges, sum_to_owners
from contactqvi.contact.segments import (Surface, basis_integrals, curvature_integrals, diameters,
                                         exact_surface_integrals, normal_separation_integrals,
                                         quadratic_segment_integrals, segment_integrals, slave_moments)
from contactqvi.parameters import require

logger = logging.getLogger(__name__)

__all__ = ["MortarCoupling", "MortarLayout", "coupling_on_layout", "exterior_facet_cells",
           "facet_closures", "mortar_coupling", "surface_facets"]

#: A facet pair a search finds that overlaps by no more than this fraction of its slave facet's
#: area is no reason to search again (:meth:`MortarLayout.covers`).
NEGLIGIBLE_OVERLAP = 1e-9
#: ... and a node coupled by the last search of a geometry that follows the iterate stays
#: coupled down to this fraction (:func:`mortar_coupling`'s ``kept_blk``).
KEPT_COVERAGE = 0.1
#: Slave nodes whose mortar segments give D_ii below this fraction of their lumped
#: area are not coupled (they lie at the rim of the master's shadow).
MIN_COVERAGE = 0.5


@dataclasses.dataclass(frozen=True)
class SurfaceFacets:
    """Facets of a boundary surface, owned by this rank: linear triangles (tetrahedral
    meshes), bilinear quadrilaterals (hexahedral meshes, vertices in tensor-product order), or
    the 6-node triangles and 9-node quadrilaterals of quadratic displacements.

    Attributes:
        blk: (f, n) local node (block) indices (ghosts included) of the vertices, n = 3 or 4, or
            of a 6-node triangle's vertices and then the midside node of the edge opposite each,
            or of a 9-node quadrilateral's nodes (:func:`~contactqvi.contact.facets.biquadratic_shapes`).
        x: (f, 3 or 4, 3) vertex coordinates.
        normal: (f, 3) outward unit normals (away from the body; of a quadrilateral's mean
            plane, the cross product of its diagonals).
        sagitta: (f, 3, 3) on a curved (second-order) tetrahedral mesh, each edge's midside node
            less the mean of its ends (edge k opposite vertex k), in the reference configuration;
            None on a mesh of degree 1.
    """

    blk: np.ndarray
    x: np.ndarray
    normal: np.ndarray
    sagitta: np.ndarray | None = None

    @property
    def area(self) -> np.ndarray:
        return facet_areas(self.x)

    @property
    def quadratic(self) -> bool:
        """Whether these are 6-node triangles or 9-node quadrilaterals (quadratic displacements)."""
        return self.blk.shape[1] in _VERTICES

    @property
    def lumped(self) -> np.ndarray:
        """(f, n) each node's lumped area: int phi_k, int Ñ_k of the modified basis of 6-node
        triangles (over their vertex triangles), or int N_k of 9-node quadrilaterals (with their
        vertices' area element)."""
        if self.blk.shape[1] == 6:
            return self.area[:, None] * MODIFIED_AREAS
        return nodal_integrals(self.x, self.blk.shape[1])


#: Facets per cell of DOLFINx's cell types with mortar contact.
_CELL_FACETS = {"tetrahedron": 4, "hexahedron": 6}
#: The vertices of a quadratic facet of n nodes (its first ones).
_VERTICES = {6: 3, 9: 4}


def surface_facets(V: fem.FunctionSpace, facets: np.ndarray, coords: np.ndarray | None = None) -> SurfaceFacets:
    """The owned exterior facets ``facets`` (local indices) of a P1 or P2 space on tetrahedra or a
    Q1 or Q2 space on hexahedra, with the node positions ``coords`` (local nodes, ghosts included;
    default the mesh's)."""
    msh = V.mesh
    tdim = msh.topology.dim
    cell_name = msh.topology.cell_name()
    require(cell_name in _CELL_FACETS, "mesh",
            f"mortar contact needs tetrahedral or hexahedral meshes, got {cell_name} cells")
    degree = msh.geometry.cmap.degree  # 2: second-order cells (the problem's builder checks them)
    facets = np.asarray(facets, dtype=np.int32)
    cells, local = exterior_facet_cells(msh, facets[facets < msh.topology.index_map(tdim - 1).size_local])
    cell_blk = V.dofmap.list[cells]
    blk = np.take_along_axis(cell_blk, facet_closures(V.dofmap.dof_layout, msh)[local], axis=1)
    coords = V.tabulate_dof_coordinates() if coords is None else coords
    quadratic = blk.shape[1] in _VERTICES
    x = coords[blk[:, :_VERTICES[blk.shape[1]]] if quadratic else blk]
    normal = unit_normals(x)
    outward = np.einsum("ij,ij->i", normal, x.mean(axis=1) - coords[cell_blk].mean(axis=1)) > 0.0
    normal[~outward] *= -1.0
    curved = degree == 2 and not quadratic  # P2 displacements carry the curved positions themselves
    return SurfaceFacets(blk.astype(np.int32), x, normal, _sagittas(msh, cells, local) if curved else None)


def exterior_facet_cells(msh: dmesh.Mesh, facets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The cell of each exterior facet ``facets`` (local indices) and the facet's index in it."""
    tdim = msh.topology.dim
    msh.topology.create_connectivity(tdim - 1, tdim)
    msh.topology.create_connectivity(tdim, tdim - 1)
    f2c, c2f = msh.topology.connectivity(tdim - 1, tdim), msh.topology.connectivity(tdim, tdim - 1)
    cells = f2c.array[f2c.offsets[facets]]
    per_cell = _CELL_FACETS[msh.topology.cell_name()]
    return cells, np.argmax(c2f.array.reshape(-1, per_cell)[cells] == facets[:, None], axis=1)


def facet_closures(layout, msh: dmesh.Mesh) -> np.ndarray:
    """(facets per cell, k) the dofs of each facet's closure in a cell of the element ``layout``
    (a dof layout of ``msh``'s cells): its vertices first, then on quadratic triangles the
    midside nodes of the edges opposite each, on biquadratic quadrilaterals the midside nodes and
    the centre in the order of :func:`~contactqvi.contact.facets.biquadratic_shapes`."""
    facets = range(_CELL_FACETS[msh.topology.cell_name()])
    return np.array([layout.entity_closure_dofs(msh.topology.dim - 1, i) for i in facets])


def _sagittas(msh: dmesh.Mesh, cells: np.ndarray, local: np.ndarray) -> np.ndarray:
    """(f, 3, 3) :attr:`SurfaceFacets.sagitta` of the facets ``local`` (local index in the cell) of
    ``cells`` of a second-order tetrahedral mesh. A facet's closure in the coordinate element lists
    its vertices as the P1 space does, then the midside node of the edge opposite each."""
    closure = facet_closures(msh.geometry.cmap.create_dof_layout(), msh)
    return _midside_offsets(msh.geometry.x[np.take_along_axis(msh.geometry.dofmap[cells], closure[local], axis=1)])


@dataclasses.dataclass(frozen=True)
class MortarLayout:
    """What a search found, to be integrated again at other positions (:func:`coupling_on_layout`):
    the facet pairs whose projections overlapped and the slave nodes coupled then.

    Attributes:
        slave_facets: local facet indices of the slave surface (as given to :func:`mortar_coupling`).
        pairs_s: (P,) index of each pair's slave facet among the rank's owned ones.
        master_glob: (P, n_m) global node indices of each pair's master facet.
        overlap: (P,) each pair's mortar segment area over its slave facet's area, at the search.
        rows: (m,) owned local node indices of the coupled slave nodes, sorted.
        projecting: partly covered slave facets take the dual basis of their covered part
            (:mod:`contactqvi.contact.covered`).
    """

    slave_facets: np.ndarray
    pairs_s: np.ndarray
    master_glob: np.ndarray
    overlap: np.ndarray
    rows: np.ndarray
    projecting: bool = False

    def covers(self, found: MortarLayout, comm: MPI.Comm) -> bool:
        """Whether this layout has the coupled nodes of ``found`` (a search of the same surfaces)
        and every facet pair of it that overlaps by more than :data:`NEGLIGIBLE_OVERLAP` of its
        slave facet (pairs that touch along an edge or a corner only come and go with round-off
        where facet edges of both surfaces coincide). Collective."""
        def keys(layout: MortarLayout, pairs: np.ndarray) -> np.ndarray:
            return np.column_stack([layout.pairs_s[pairs], np.sort(layout.master_glob[pairs], axis=1)])

        needed = np.flatnonzero(found.overlap > NEGLIGIBLE_OVERLAP)
        _, key = np.unique(np.concatenate([keys(self, np.arange(len(self.pairs_s))), keys(found, needed)]), axis=0,
                           return_inverse=True)
        key = key.ravel()
        local = np.array_equal(self.rows, found.rows) and bool(np.isin(key[len(self.pairs_s):],
                                                                       key[:len(self.pairs_s)]).all())
        return comm.allreduce(local, op=MPI.LAND)


@dataclasses.dataclass(frozen=True)
class MortarCoupling:
    """The mortar rows of the owned slave nodes of one contact pair.

    Attributes:
        slave_blk: (m,) owned local node indices of the coupled slave nodes, sorted.
        weight: (m,) D_ii (m^2), the lumped area of the node's mortar segments.
        C_indptr, C_master_glob, C_values: CSR rows of C = D^{-1} M for ``slave_blk``,
            columns the global node indices of master nodes; every row sums to 1.
        normal: (m, 3) unit nodal normals pointing from the master into the slave body
            (area-weighted averages of the slave facets' normals).
        separation: (m, 3) weighted separation of the reference positions
            x_i - sum_j C_ij x_j (m); the gap is its normal component.
        derivatives: the derivatives of C and n with the searched positions
            (:mod:`contactqvi.contact.linearisation`), if asked for; else None.
        layout: the search's facet pairs and these rows (:class:`MortarLayout`).
    """

    slave_blk: np.ndarray
    weight: np.ndarray
    C_indptr: np.ndarray
    C_master_glob: np.ndarray
    C_values: np.ndarray
    normal: np.ndarray
    separation: np.ndarray
    derivatives: CouplingDerivatives | None = None
    layout: MortarLayout | None = None

    @property
    def gap(self) -> np.ndarray:
        """(m,) weighted gap n_i . (x_i - sum_j C_ij x_j) of the reference positions (m)."""
        return np.einsum("ij,ij->i", self.normal, self.separation)

    def restricted(self, keep: np.ndarray) -> MortarCoupling:
        """The rows ``keep`` (a mask over the rows)."""
        lengths = np.diff(self.C_indptr)
        entries = np.repeat(keep, lengths)
        indptr = np.concatenate([[0], np.cumsum(lengths[keep])]).astype(np.int64)
        derivatives = None if self.derivatives is None else self.derivatives.restricted(keep)
        layout = None if self.layout is None else dataclasses.replace(self.layout, rows=self.slave_blk[keep])
        return MortarCoupling(self.slave_blk[keep], self.weight[keep], indptr, self.C_master_glob[entries],
                              self.C_values[entries], self.normal[keep], self.separation[keep], derivatives, layout)


def _exchange_master(comm: MPI.Comm, slave: SurfaceFacets, master: SurfaceFacets,
                     master_glob: np.ndarray, padding: float) -> tuple[np.ndarray, ...]:
    """Master facets (coordinates, global node indices, normals and, on a curved mesh, sagittas)
    within ``padding`` of this rank's slave facets' bounding box, gathered from the ranks that own
    them."""
    if len(slave.x):
        box = np.concatenate([slave.x.min(axis=(0, 1)) - padding, slave.x.max(axis=(0, 1)) + padding])
    else:
        box = np.array([np.inf] * 3 + [-np.inf] * 3)
    boxes = np.asarray(comm.allgather(box))  # one box per rank
    lo, hi = master.x.min(axis=1), master.x.max(axis=1)
    fields = (master.x, master_glob, master.normal) + (() if master.sagitta is None else (master.sagitta,))
    send = []
    for r in range(comm.size):
        near = np.all((hi >= boxes[r, :3]) & (lo <= boxes[r, 3:]), axis=1)
        send.append(tuple(field[near] for field in fields))
    received = comm.alltoall(send)
    return tuple(np.concatenate([part[i] for part in received]) for i in range(len(fields)))


def mortar_coupling(V: fem.FunctionSpace, slave_facets: np.ndarray, master_facets: np.ndarray,
                    search_distance: float | None = None, excluded_blk: np.ndarray | None = None,
                    displacement: np.ndarray | None = None, linearised: bool = False,
                    kept_blk: np.ndarray | None = None, exact: tuple[Surface, Surface] | None = None,
                    projecting: bool = False) -> MortarCoupling:
    """C = D^{-1} M, nodal normals and weighted gaps of a slave and a master surface.

    Args:
        V: vector P1 or P2 (tetrahedra) or Q1 (hexahedra) space on the mesh holding both bodies.
        slave_facets, master_facets: local facet indices of the two surfaces.
        search_distance: master facets farther than this from a slave facet (between bounding boxes, m)
            are not paired with it; None: the slave facet's longest edge.
        excluded_blk: local node indices never coupled (e.g. clamped slave nodes).
        displacement: (local nodes, 3) displacement of the configuration searched
            (ghosts included); None: the reference configuration.
        linearised: also the derivatives of the rows with respect to the searched positions
            (:func:`~contactqvi.contact.linearisation.coupling_derivatives`).
        kept_blk: owned local nodes coupled by the last search, which stay coupled down to :data:`KEPT_COVERAGE`
            (a geometry that follows the Newton iterate: a node at the master's rim does not come and go).
        exact: the exact slave and master surfaces of the reference configuration (e.g. the
            cylinders of a press fit), between which the weighted gap is then measured
            (:func:`_exact_correction`); None: between the discrete ones.
        projecting: slave facets covered in part take the dual basis of their covered part
            (:mod:`~contactqvi.contact.covered`; flat facets of linear elements, no ``exact``).

    Collective. Slave nodes with less than :data:`MIN_COVERAGE` of their lumped area
    in the master's shadow (:data:`KEPT_COVERAGE` for ``kept_blk``) are left out, and so are
    nodes whose weighted gap in the searched configuration exceeds ``search_distance``
    (default: the node's own size sqrt(2 x lumped area)).
    """
    comm, index_map, x = V.mesh.comm, V.dofmap.index_map, V.tabulate_dof_coordinates()
    current = x if displacement is None else x + displacement
    slave, master = surface_facets(V, slave_facets, current), surface_facets(V, master_facets, current)
    require(not (slave.quadratic and linearised), "mesh.order", "quadratic elements take body pairs searched "
            "once or every step; the linearised geometry (search = \"newton\") is built for linear ones")
    master_glob = index_map.local_to_global(master.blk.ravel()).reshape(master.blk.shape)
    diameter = max(_max_edge(slave.x, comm), _max_edge(master.x, comm))
    reach = 2.0 * diameter + (diameter if search_distance is None else search_distance)
    mx, mglob, mnormal, *msagitta = _exchange_master(comm, slave, master, master_glob, reach)

    # candidate pairs: centroids within reach, bounding boxes within search_distance, facing normals
    pairs_s, pairs_m = _candidate_pairs(slave.x, slave.normal, mx, search_distance)
    facing = np.einsum("ij,ij->i", slave.normal[pairs_s], mnormal[pairs_m]) < 0.0
    pairs_s, pairs_m, integrals = _overlapping(slave, mx, pairs_s[facing], pairs_m[facing], exact is not None)
    _check_defined(comm, integrals, reference=displacement is None)
    layout = MortarLayout(np.asarray(slave_facets), pairs_s, mglob[pairs_m],
                          integrals[0].sum(axis=1) / slave.area[pairs_s], np.empty(0, dtype=np.int32),
                          projecting and exact is None and slave.sagitta is None and not slave.quadratic)
    added = None if slave.sagitta is None else _bulge(slave, pairs_s, mx[pairs_m], msagitta[0][pairs_m])
    if exact is not None:
        correction = _exact_correction(V, slave_facets, pairs_s, mglob[pairs_m],
                                       None if slave.sagitta is None else msagitta[0][pairs_m], exact)
        added = correction if added is None else added + correction
    elif slave.quadratic:
        added = _normal_correction(V, slave, pairs_s, mglob[pairs_m], current)
    coupling, lumped_area, gap = _integrated(V, layout, slave, mx[pairs_m], current, None, excluded_blk,
                                             integrals, linearised, kept_blk, added)
    # a node farther than the search distance (default: its own size) cannot touch in this step
    reach = np.sqrt(2.0 * lumped_area[coupling.slave_blk]) if search_distance is None else search_distance
    return coupling.restricted(gap <= reach)


def coupling_on_layout(V: fem.FunctionSpace, layout: MortarLayout, displacement: np.ndarray,
                       linearised: bool = False) -> MortarCoupling:
    """The coupling of the rows and facet pairs of ``layout`` (an earlier search) at the positions
    x + ``displacement`` (local nodes, 3): D, M, C and the normals integrated again, with the same
    rows and the same pattern of C (entries of pairs that no longer overlap are zero). A row
    that no pair covers any more has D_ii = 0 and C of NaN. Collective."""
    comm, index_map = V.mesh.comm, V.dofmap.index_map
    current = V.tabulate_dof_coordinates() + displacement
    slave = surface_facets(V, layout.slave_facets, current)
    nm = layout.master_glob.shape[1]
    master_x = fetch_rows(comm, index_map, current[:index_map.size_local],
                          layout.master_glob.ravel()).reshape(-1, nm, 3)
    integrals = _pair_integrals(slave, master_x, layout.pairs_s)
    _check_defined(comm, integrals, reference=False)
    with np.errstate(divide="ignore", invalid="ignore"):  # a row no pair covers: NaN, a trial the line search rejects
        return _integrated(V, layout, slave, master_x, current, layout.rows, None, integrals, linearised)[0]


def _check_defined(comm: MPI.Comm, integrals: tuple[np.ndarray, ...], reference: bool) -> None:
    """Raise (``mesh``: in the reference configuration), or log (in a deformed one), where a facet
    pair's integrals are not finite: a quadrilateral facet whose bilinear map has no inverse over
    the pair's points (:func:`~contactqvi.contact.facets.reference_coordinates`). Deformed, the NaN
    goes on into the coupling: a trial point that the line search rejects, or an iterate whose step
    fails (``diverged_function_domain``) and is cut. Collective."""
    undefined = comm.allreduce(int(np.count_nonzero(~np.isfinite(integrals[1]).all(axis=(1, 2)))), op=MPI.SUM)
    if undefined == 0:
        return
    message = (f"the bilinear map of {undefined} contact facet pair(s) has no inverse over their segments' "
               "points: a degenerate or non-convex quadrilateral")
    require(not reference, "mesh", message)
    logger.info("the contact geometry is not defined in this configuration: %s after the deformation", message)


def _integrated(V: fem.FunctionSpace, layout: MortarLayout, slave: SurfaceFacets, master_x: np.ndarray,
                current: np.ndarray, rows: np.ndarray | None, excluded_blk: np.ndarray | None,
                integrals: tuple[np.ndarray, ...] | None, linearised: bool,
                kept_blk: np.ndarray | None = None,
                added: np.ndarray | None = None) -> tuple[MortarCoupling, np.ndarray, np.ndarray]:
    """The coupling of the owned slave nodes ``rows`` by the facet pairs of ``layout`` (their
    master facets at ``master_x``, their :func:`segment_integrals` ``integrals`` if known), the
    lumped slave areas of the owned nodes and the rows' weighted gaps at the positions
    ``current``. ``rows`` None: the nodes the pairs cover for at least :data:`MIN_COVERAGE` of
    their lumped area (:data:`KEPT_COVERAGE` for ``kept_blk``), less ``excluded_blk``. ``added``:
    per pair, what the curvature of a second-order mesh with linear displacements (:func:`_bulge`)
    and exact surfaces (:func:`_exact_correction`) add to D_ii times the separation. Quadratic facets
    take the slave's part of the separation from their integrals' third array,
    int Φ_i x = sum_k S_ik x_k (:func:`~contactqvi.contact.segments.quadratic_segment_integrals`). A
    ``projecting`` layout's partly covered facets take the basis of :mod:`contactqvi.contact.covered`."""
    comm, index_map, x = V.mesh.comm, V.dofmap.index_map, V.tabulate_dof_coordinates()
    pairs_s = layout.pairs_s
    if integrals is None:
        integrals = _pair_integrals(slave, master_x, pairs_s)
    covered = None
    if layout.projecting:
        *integrals, covered = covered_basis(slave.x, master_x, pairs_s, *integrals,
                                            lambda s, m: basis_integrals(slave.x[s], -slave.normal[s], m))
    weight, lumped_area, normal, M = _owned_sums(comm, index_map, slave, pairs_s, layout.master_glob, *integrals[:2])
    coupled = np.zeros(index_map.size_local, dtype=bool)
    if rows is None:
        coverage = np.full(index_map.size_local, MIN_COVERAGE)
        if kept_blk is not None:
            coverage[kept_blk] = KEPT_COVERAGE
        coupled = (lumped_area > 0.0) & (weight >= coverage * lumped_area)
        if excluded_blk is not None:
            coupled[excluded_blk[excluded_blk < index_map.size_local]] = False
    else:
        coupled[rows] = True
    slave_blk = np.flatnonzero(coupled).astype(np.int32)

    position, indptr, cols, values = _rows_of_C(M, index_map.local_range[0], coupled, slave_blk, weight)
    n = normal[slave_blk] / np.linalg.norm(normal[slave_blk], axis=1)[:, None]
    positions = np.hstack([x, current])  # reference and current positions, fetched together
    projected = np.zeros((len(slave_blk), 6))
    np.add.at(projected, position, values[:, None] * fetch_rows(comm, index_map, positions, cols))
    if len(integrals) == 3:  # int psi_i x over the segments, of the reference and the current positions
        moments = np.einsum("pik,pkc->pic", integrals[2], positions[slave.blk[pairs_s]])
        separation = _owned_vectors(comm, index_map, slave, pairs_s, moments)[slave_blk] / weight[slave_blk, None]
        separation -= projected
    else:
        separation = positions[slave_blk] - projected
    if added is not None:
        separation += np.tile(_owned_vectors(comm, index_map, slave, pairs_s, added)[slave_blk]
                              / weight[slave_blk, None], 2)
    derivatives = None
    if linearised:
        slave_glob = index_map.local_to_global(slave.blk.ravel()).reshape(slave.blk.shape)
        derivatives = coupling_derivatives(comm, index_map, slave_glob, slave.x, slave.normal, pairs_s, master_x,
                                           layout.master_glob, index_map.local_to_global(slave_blk),
                                           weight[slave_blk], normal[slave_blk], projected[:, 3:], covered)
    layout = dataclasses.replace(layout, rows=slave_blk)
    coupling = MortarCoupling(slave_blk, weight[slave_blk], indptr, cols.astype(np.int64), values, n,
                              separation[:, :3], derivatives, layout)
    return coupling, lumped_area, np.einsum("ij,ij->i", n, separation[:, 3:])


def _bulge(slave: SurfaceFacets, pairs_s: np.ndarray, master_x: np.ndarray, master_sagitta: np.ndarray) -> np.ndarray:
    """(P, 3, 3) what the curvature of second-order facets adds to D_ii times the separation of
    slave node i, per facet pair (slave facets ``pairs_s``, master facets at ``master_x`` with
    their sagittas): int psi_i (sum_k b_k s_k - sum_k (b_k^m o pi) s_k^m)
    (:func:`~contactqvi.contact.segments.curvature_integrals`). The separation of the flat facets,
    x_i - sum_j C_ij x_j, plus this over D_ii is the weighted separation of the curved surfaces:
    the mesh's chords lie inside a cylinder of radius R by up to h^2 / (8 R), which this restores
    (docs/press_fit.md)."""
    Bs, Bm = curvature_integrals(slave.x[pairs_s], -slave.normal[pairs_s], master_x)
    return (np.einsum("pik,pkd->pid", Bs, slave.sagitta[pairs_s])
            - np.einsum("pik,pkd->pid", Bm, master_sagitta))


def _exact_correction(V: fem.FunctionSpace, slave_facets: np.ndarray, pairs_s: np.ndarray, master_glob: np.ndarray,
                      master_sagitta: np.ndarray | None, exact: tuple[Surface, Surface]) -> np.ndarray:
    """(P, n, 3) what the exact surfaces ``exact`` add to D_ii times the separation of slave node i
    (:func:`~contactqvi.contact.segments.exact_surface_integrals`), per facet pair (the slave
    facets ``pairs_s``, the master facets' global nodes ``master_glob`` and, on a curved mesh with
    linear displacements, their sagittas), in the reference configuration: a small-strain gap is
    taken between reference positions, whichever configuration the pairs were found in. The
    points of the discrete surfaces are those of the vertex triangles, curved by the sagittas of
    a second-order mesh or the midside nodes of quadratic elements. Collective."""
    reference = V.tabulate_dof_coordinates()
    slave = surface_facets(V, slave_facets)
    master = _master_nodes(V, master_glob, reference)
    slave_x, slave_sagitta = slave.x[pairs_s], None if slave.sagitta is None else slave.sagitta[pairs_s]
    if slave.quadratic:  # the curved facets of quadratic displacements: their midside nodes
        slave_sagitta = _midside_offsets(reference[slave.blk[pairs_s]])
        master_sagitta = _midside_offsets(master)
    return exact_surface_integrals(slave_x, -slave.normal[pairs_s], master[:, :3], slave_sagitta, master_sagitta,
                                   exact, slave.quadratic)


def _normal_correction(V: fem.FunctionSpace, slave: SurfaceFacets, pairs_s: np.ndarray, master_glob: np.ndarray,
                       current: np.ndarray) -> np.ndarray:
    """(P, n, 3) what taking the separation of quadratic facets along the slave surface's own normal
    adds to D_ii times the separation of slave node i, per facet pair (the slave facets
    ``pairs_s``, the master facets' global nodes ``master_glob``), at the positions ``current``
    (:func:`~contactqvi.contact.segments.normal_separation_integrals`). Collective."""
    master = _master_nodes(V, master_glob, current)
    return normal_separation_integrals(slave.x[pairs_s], -slave.normal[pairs_s], master[:, :slave.x.shape[1]],
                                       current[slave.blk[pairs_s]], master)


def _master_nodes(V: fem.FunctionSpace, master_glob: np.ndarray, positions: np.ndarray) -> np.ndarray:
    """(P, n, 3) the ``positions`` (local nodes, 3) of the master facets' global nodes ``master_glob``
    (P, n), fetched from their owners. Collective."""
    index_map = V.dofmap.index_map
    master = fetch_rows(V.mesh.comm, index_map, positions[:index_map.size_local], master_glob.ravel())
    return master.reshape(*master_glob.shape, 3)


def _midside_offsets(nodes: np.ndarray) -> np.ndarray:
    """(f, 3, 3) each edge's midside node less the mean of its ends, of 6-node triangles (f, 6, 3)."""
    return nodes[:, 3:] - 0.5 * (nodes[:, [1, 2, 0]] + nodes[:, [2, 0, 1]])


def _owned_vectors(comm: MPI.Comm, index_map, slave: SurfaceFacets, pairs_s: np.ndarray,
                   values: np.ndarray) -> np.ndarray:
    """(owned nodes, w) the pairs' vectors ``values`` (P, n, w) of their slave facets' nodes, summed on
    the owners of the nodes."""
    slave_glob = index_map.local_to_global(slave.blk.ravel()).reshape(slave.blk.shape)
    rows = slave_glob[pairs_s].ravel()
    width = values.shape[2]
    summed = sum_to_owners(comm, owner_ranges(comm, index_map), rows, np.zeros_like(rows), values.reshape(-1, width))
    owned = np.zeros((index_map.size_local, width))
    owned[summed[0] - index_map.local_range[0]] = summed[2]
    return owned


def _rows_of_C(M: tuple, start: int, coupled: np.ndarray, slave_blk: np.ndarray,
               weight: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """CSR rows of C = D^{-1} M of the coupled slave nodes ``slave_blk`` from the owned entries
    ``M`` (global rows, global columns, values; owned range from ``start``): each entry's row
    position, indptr, master columns and values."""
    rows_loc = M[0] - start
    keep = coupled[rows_loc]
    order = np.lexsort((M[1][keep], rows_loc[keep]))
    rows_loc, cols, values = rows_loc[keep][order], M[1][keep][order], M[2][keep][order]
    values = values / weight[rows_loc]
    position = np.searchsorted(slave_blk, rows_loc)
    indptr = np.concatenate([[0], np.cumsum(np.bincount(position, minlength=len(slave_blk)))]).astype(np.int64)
    return position, indptr, cols, values


#: Candidate pairs integrated at a time by :func:`_overlapping` (bounds its work arrays to about 100 MB)
#: for two triangles (3 points per triangle of a clipped polygon); with a quadrilateral, whose
#: rules have up to 79 points and up to 6 triangles per polygon, a 32nd of it.
_CHUNK = 1 << 16
_QUADRILATERAL_CHUNK = 1 << 11


def _overlapping(slave: SurfaceFacets, master_x: np.ndarray, pairs_s: np.ndarray, pairs_m: np.ndarray,
                 moments: bool = False) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, ...]]:
    """The candidate pairs whose facets overlap, with their integrals (:func:`_pair_integrals`).

    The candidates are the pairs within the search distance; most do not overlap
    (two-body Hertz medium mesh, search distance 5 mm: 20 000 of the 26 448 entries of
    C were zeros), and their zero entries made A = T^T A_K T twice as large as its
    nonzeros (4.1 M entries, 2.0 M nonzero): dense mortar rows of zeros that GAMG
    aggregated across and every product carried.
    """
    integrals = _pair_integrals(slave, master_x[pairs_m], pairs_s, moments)
    overlap = np.any(integrals[1] != 0.0, axis=(1, 2))
    return pairs_s[overlap], pairs_m[overlap], tuple(values[overlap] for values in integrals)


def _chunk(slave: SurfaceFacets, master_x: np.ndarray) -> int:
    """Pairs integrated at a time (:data:`_CHUNK`, :data:`_QUADRILATERAL_CHUNK`)."""
    return _CHUNK if slave.blk.shape[1] == master_x.shape[1] == 3 else _QUADRILATERAL_CHUNK


def _pair_integrals(slave: SurfaceFacets, master_x: np.ndarray, pairs_s: np.ndarray,
                    moments: bool = False) -> tuple[np.ndarray, ...]:
    """:func:`segment_integrals` (D, M) of the pairs of slave facets ``pairs_s`` with the master
    facets ``master_x`` (P, n_m, 3), in chunks, so the work arrays stay bounded (all at once
    they took 390 MB on the two-body Hertz fine mesh); :func:`quadratic_segment_integrals` of
    quadratic facets, which bring the slave's moments S (its part of the separation, int psi_i x
    over the segments); with ``moments`` linear triangles bring theirs too (:func:`slave_moments`)."""
    ns = slave.blk.shape[1]
    nm = ns if slave.quadratic else master_x.shape[1]
    moments = moments or slave.quadratic
    parts = [(np.empty((0, ns)), np.empty((0, ns, nm))) + ((np.empty((0, ns, ns)),) if moments else ())]
    chunk = _chunk(slave, master_x)
    for start in range(0, len(pairs_s), chunk):
        s, m = pairs_s[start:start + chunk], master_x[start:start + chunk]
        if slave.quadratic:
            parts.append(quadratic_segment_integrals(slave.x[s], -slave.normal[s], m))
        else:
            parts.append(segment_integrals(slave.x[s], -slave.normal[s], m)
                         + ((slave_moments(slave.x[s], -slave.normal[s], m),) if moments else ()))
    return tuple(np.concatenate(part) for part in zip(*parts))


def _owned_sums(comm: MPI.Comm, index_map, slave: SurfaceFacets, pairs_s: np.ndarray, master_glob: np.ndarray,
                D_pair: np.ndarray, M_pair: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple]:
    """Sum the pairs' contributions on the owners of the slave nodes.

    Returns, over the owned nodes: D_ii, the lumped slave area, the area-weighted
    normal sum (pointing into the slave body), and the owned entries (rows, cols,
    values) of M with global node indices.
    """
    slave_glob = index_map.local_to_global(slave.blk.ravel()).reshape(slave.blk.shape)
    ns, nm = slave_glob.shape[1], master_glob.shape[1]
    owners = owner_ranges(comm, index_map)
    rows = slave_glob[pairs_s].ravel()
    D = sum_to_owners(comm, owners, rows, np.zeros_like(rows), D_pair.ravel())
    M = sum_to_owners(comm, owners, np.repeat(slave_glob[pairs_s], nm, axis=1).ravel(),
                       np.tile(master_glob, (1, ns)).ravel(), M_pair.ravel())
    nodes = slave_glob.ravel()
    area = sum_to_owners(comm, owners, nodes, np.zeros_like(nodes), slave.lumped.ravel())
    normal_values = np.repeat(slave.area[:, None] * -slave.normal, ns, axis=0)
    start, n_owned = index_map.local_range[0], index_map.size_local
    weight, lumped_area, normal = np.zeros(n_owned), np.zeros(n_owned), np.zeros((n_owned, 3))
    weight[D[0] - start] = D[2]
    lumped_area[area[0] - start] = area[2]
    summed = sum_to_owners(comm, owners, nodes, np.zeros_like(nodes), normal_values)
    normal[summed[0] - start] = summed[2]
    return weight, lumped_area, normal, M


def _max_edge(x: np.ndarray, comm: MPI.Comm) -> float:
    return comm.allreduce(float(diameters(x).max(initial=0.0)), op=MPI.MAX)


def _candidate_pairs(slave_x: np.ndarray, slave_normal: np.ndarray, master_x: np.ndarray,
                     search_distance: float | None) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs (slave, master) whose bounding boxes are within the search distance
    (``None``: each slave facet's own diameter, so graded meshes pair locally) and whose
    centroids lie closer along the slave facet's plane than the sum of their diameters
    (:func:`~contactqvi.contact.segments.diameters`): every point of a facet lies within its diameter of its vertices'
    mean, so other pairs cannot overlap in projection (two-body Hertz fine mesh,
    search distance 5 mm: 77 k of 266 k candidates kept, 13 k overlap)."""
    if len(slave_x) == 0 or len(master_x) == 0:
        return np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64)
    slave_edge, master_edge = diameters(slave_x), diameters(master_x)
    pad = slave_edge if search_distance is None else np.full(len(slave_x), search_distance)
    slave_c, master_c = slave_x.mean(axis=1), master_x.mean(axis=1)
    pairs_s, pairs_m = _near_centroids(slave_c, slave_edge + pad, master_c, master_edge)
    d, n = master_c[pairs_m] - slave_c[pairs_s], slave_normal[pairs_s]
    along = d - np.einsum("ij,ij->i", d, n)[:, None] * n
    near = np.einsum("ij,ij->i", along, along) <= (slave_edge[pairs_s] + master_edge[pairs_m]) ** 2
    pairs_s, pairs_m = pairs_s[near], pairs_m[near]
    lo_s, hi_s = slave_x.min(axis=1)[pairs_s], slave_x.max(axis=1)[pairs_s]
    lo_m, hi_m = master_x.min(axis=1)[pairs_m], master_x.max(axis=1)[pairs_m]
    padding = pad[pairs_s, None]
    near = np.all((hi_m >= lo_s - padding) & (lo_m <= hi_s + padding), axis=1)
    return pairs_s[near], pairs_m[near]


def _near_centroids(slave_c: np.ndarray, slave_r: np.ndarray, master_c: np.ndarray,
                    master_r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs (i, j) with |slave_c[i] - master_c[j]| <= slave_r[i] + master_r[j].

    Facets are binned by size (powers of two) and each pair of bins queried with its
    largest radius, so a graded mesh's large facets do not widen the small ones' search.
    """
    def bins(r: np.ndarray) -> np.ndarray:
        return np.floor(np.log2(np.maximum(r, 1e-300))).astype(np.int64)

    slave_bin, master_bin = bins(slave_r), bins(master_r)
    master_sets = []
    for b in np.unique(master_bin):
        idx = np.flatnonzero(master_bin == b)
        master_sets.append((idx, scipy.spatial.cKDTree(master_c[idx]), master_r[idx].max()))
    found_s, found_m = [np.empty(0, dtype=np.int64)], [np.empty(0, dtype=np.int64)]
    for b in np.unique(slave_bin):
        s_idx = np.flatnonzero(slave_bin == b)
        tree = scipy.spatial.cKDTree(slave_c[s_idx])
        for m_idx, master_tree, m_reach in master_sets:
            near = tree.sparse_distance_matrix(master_tree, float(slave_r[s_idx].max() + m_reach), output_type="ndarray")
            i, j = s_idx[near["i"]], m_idx[near["j"]]
            keep = near["v"] <= slave_r[i] + master_r[j]
            found_s.append(i[keep])
            found_m.append(j[keep])
    return np.concatenate(found_s), np.concatenate(found_m)
