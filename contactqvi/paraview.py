"""ParaView datasets: VTX (ADIOS2 BP4) and XDMF files written in parallel.

Every rank writes its own piece: the cells it owns and the points they use, as
one ADIOS2 block of one VTX file (:class:`VTXDatasetWriter`). Nothing is gathered:
ParaView's ``ADIOS2VTXReader`` appends the blocks into one unstructured grid that
holds every cell once, so volumes and integrals are those of a serial run. A
point on the boundary between two pieces is in both; the copy in the piece of a
rank that does not own it is flagged in ``vtkGhostType`` (1, a duplicate point),
as DOLFINx's own writer flags ghost points. A rank that owns no cell writes no
block. :func:`read_vtx` reads one step back on one rank, its blocks appended as
ParaView appends them (benchmarks and tests compare fields with it).

DOLFINx 0.9's ``VTXWriter`` writes the ghost cells of each rank as well (at lev 4
of the paper's body with shared-facet ghosts on 2 ranks: 1152 cells instead of
1024, and ParaView integrated 12.5 % too much volume), and holds point data (P1)
or cell data (DG0) but not both in one file; :func:`write_vtx` uses it only for
other spaces. XDMF from DOLFINx is written from owned entities only.

In parallel the ADIOS2 Python module must be MPI-enabled (Debian's
``python3-adios2-mpi``, picked under ``mpirun`` when installed).
"""

from __future__ import annotations

import dataclasses
import os
import pathlib
import re
import shutil
import typing
from xml.sax.saxutils import quoteattr

from mpi4py import MPI

import basix
import numpy as np

from dolfinx import fem, io
from dolfinx import mesh as dmesh
from dolfinx.cpp.io import get_vtk_cell_type, perm_vtk
from dolfinx.cpp.mesh import cell_num_vertices

from contactqvi.lifetime import unwind_together
from contactqvi.tables import atomic_path

__all__ = [
    "Dataset",
    "MeshPiece",
    "VTXDatasetWriter",
    "gather_pieces",
    "read_vtx",
    "write_vtx",
    "write_vtx_dataset",
    "write_xdmf",
]

#: ``vtkGhostType`` value of a point that another piece owns (vtkDataSetAttributes::DUPLICATEPOINT).
DUPLICATE_POINT = 1


@dataclasses.dataclass
class Dataset:
    """One rank's piece of an unstructured grid: what ParaView appends into one dataset.

    Attributes:
        points: (N, 3) point coordinates.
        cells: (C, k) point indices of each cell, in VTK's vertex order.
        cell_type: VTK cell type of all cells (DOLFINx's Lagrange types, e.g. 72
            hexahedron, 70 quadrilateral, or the linear 9 quadrilateral).
        point_data: name -> (N,) or (N, c) array.
        cell_data: name -> (C,) or (C, c) array.
        duplicate: (N,) bool, True at points that another piece owns (None: none).
    """

    points: np.ndarray
    cells: np.ndarray
    cell_type: int
    point_data: dict[str, np.ndarray] = dataclasses.field(default_factory=dict)
    cell_data: dict[str, np.ndarray] = dataclasses.field(default_factory=dict)
    duplicate: np.ndarray | None = None

    def cell_data_at_points(self, name: str) -> np.ndarray:
        """The cell field ``name`` at each point, from one cell that uses it: for a field that is
        the same in every cell around a point (a body's index)."""
        values = self.cell_data[name]
        at_points = np.empty((len(self.points), *values.shape[1:]), dtype=values.dtype)
        at_points[self.cells.ravel()] = np.repeat(values, self.cells.shape[1], axis=0)
        return at_points


def _is_nodal(V: fem.FunctionSpace) -> bool:
    """One dof (per block) at each vertex and nowhere else (P1/Q1, on a mesh of any degree), or
    the dofs of a quadratic Lagrange space on tetrahedra or hexahedra (P2, Q2): values at the mesh's
    nodes."""
    layout = V.dofmap.dof_layout
    vertices = cell_num_vertices(V.mesh.topology.cell_type)
    linear = layout.num_dofs == vertices and layout.num_entity_dofs(0) == 1
    element = V.ufl_element().basix_element
    return linear or (element.family == basix.ElementFamily.P and element.degree == 2
                      and V.mesh.topology.cell_name() in ("tetrahedron", "hexahedron"))


def _vertex_weights(msh: dmesh.Mesh) -> np.ndarray:
    """(G, v) the P1/Q1 shape functions of a cell's vertices at its G geometry nodes: the values of
    a vertex function at the nodes of a curved (degree-2) cell."""
    coordinate = msh.ufl_domain().ufl_coordinate_element().basix_element
    linear = basix.create_element(basix.ElementFamily.P, coordinate.cell_type, 1)
    return linear.tabulate(0, coordinate.points)[0, :, :, 0]


def _is_cellwise(V: fem.FunctionSpace) -> bool:
    """One dof (per block) per cell: DG0."""
    return V.dofmap.dof_layout.num_dofs == 1


def _vtk_components(values: np.ndarray, bs: int, gdim: int) -> np.ndarray:
    """(n, bs) values as ParaView wants them: vectors of a 2D mesh padded to 3 components."""
    if bs == 1:
        return values[:, 0].copy()
    if bs == gdim == 2:
        return np.column_stack([values, np.zeros(len(values))])
    return values.copy()


class MeshPiece:
    """The owned cells of a mesh on this rank, in VTK order, and the nodes they use.

    Made once per mesh; :meth:`dataset` then takes the values of functions on it.
    Works on a rank that owns no cell (an empty piece). The cells of a degree-2 mesh are
    VTK's Lagrange cells of its geometry nodes (curved in ParaView), or with ``linear`` those
    of their vertices.

    Attributes:
        mesh: the mesh.
        nodes: (N,) local geometry node of each point of the piece.
        cells: (C, k) point indices of the owned cells, VTK vertex order.
        duplicate: (N,) True at nodes another rank owns.
        cell_type: VTK cell type.
    """

    def __init__(self, msh: dmesh.Mesh, linear: bool = False):
        self.mesh = msh
        tdim = msh.topology.dim
        n_cells = msh.topology.index_map(tdim).size_local
        dofmap = msh.geometry.dofmap  # a cell's vertices first, in both element layouts
        if linear:
            dofmap = dofmap[:, :cell_num_vertices(msh.topology.cell_type)]
        vtk_order = np.argsort(perm_vtk(msh.topology.cell_type, dofmap.shape[1]))
        cell_nodes = dofmap[:n_cells][:, vtk_order]
        self.nodes, cells = np.unique(cell_nodes.ravel(), return_inverse=True)
        self.cells = cells.reshape(n_cells, dofmap.shape[1]).astype(np.int64)
        self.duplicate = self.nodes >= msh.geometry.index_map().size_local
        self.cell_type = int(get_vtk_cell_type(msh.topology.cell_type, tdim))

    @property
    def points(self) -> np.ndarray:
        """(N, 3) coordinates of the points."""
        return self.mesh.geometry.x[self.nodes]

    def point_values(self, f: fem.Function) -> np.ndarray:
        """Values of a P1/Q1 (or P2) function of the mesh at the points, (N,) or (N, 3): a P2
        function on a mesh of degree 1 at its vertices."""
        V = f.function_space
        if V.mesh is not self.mesh or not _is_nodal(V):
            raise ValueError(f"MeshPiece: {f.name!r} is not a P1/Q1 or P2 function on the mesh")
        bs = V.dofmap.index_map_bs
        dofmap = self.mesh.geometry.dofmap
        nodes = min(V.dofmap.list.shape[1], dofmap.shape[1])  # vertices first, then edges, in both layouts
        at_cells = f.x.array.reshape(-1, bs)[V.dofmap.list[:, :nodes]]
        if dofmap.shape[1] > nodes:  # a P1 function on a curved mesh: also at the other nodes of its cells
            at_cells = np.einsum("gv,cvb->cgb", _vertex_weights(self.mesh), at_cells)
        at_nodes = np.empty((self.mesh.geometry.x.shape[0], bs))
        at_nodes[dofmap[:, :at_cells.shape[1]].ravel()] = at_cells.reshape(-1, bs)
        return _vtk_components(at_nodes[self.nodes], bs, self.mesh.geometry.dim)

    def cell_values(self, f: fem.Function) -> np.ndarray:
        """Values of a DG0 function of the mesh on the owned cells, (C,) or (C, c)."""
        V = f.function_space
        if V.mesh is not self.mesh or not _is_cellwise(V):
            raise ValueError(f"MeshPiece: {f.name!r} is not a DG0 function on the mesh")
        bs = V.dofmap.index_map_bs
        blocks = V.dofmap.list[: len(self.cells), 0]
        return _vtk_components(f.x.array.reshape(-1, bs)[blocks], bs, self.mesh.geometry.dim)

    def dataset(
        self,
        point_data: typing.Mapping[str, fem.Function] | None = None,
        cell_data: typing.Mapping[str, fem.Function] | None = None,
    ) -> Dataset:
        """This rank's piece with file name -> P1/Q1 (point) and DG0 (cell) functions. Not collective."""
        return Dataset(
            points=self.points,
            cells=self.cells,
            cell_type=self.cell_type,
            point_data={name: self.point_values(f) for name, f in (point_data or {}).items()},
            cell_data={name: self.cell_values(f) for name, f in (cell_data or {}).items()},
            duplicate=self.duplicate,
        )


def gather_pieces(comm: MPI.Comm, piece: Dataset) -> Dataset | None:
    """The pieces of all ranks appended on rank 0 (None elsewhere), as ParaView appends them.

    For figures of small datasets only: it holds the whole dataset on rank 0.
    Collective.
    """
    pieces = comm.gather(piece, root=0)
    if comm.rank != 0:
        return None
    offsets = np.cumsum([0] + [len(p.points) for p in pieces[:-1]])

    def stack(name: str, kind: str) -> np.ndarray:
        return np.concatenate([getattr(p, kind)[name] for p in pieces])

    return Dataset(
        points=np.concatenate([p.points for p in pieces]).reshape(-1, 3),
        cells=np.concatenate([p.cells + offset for p, offset in zip(pieces, offsets)]),
        cell_type=piece.cell_type,
        point_data={name: stack(name, "point_data") for name in piece.point_data},
        cell_data={name: stack(name, "cell_data") for name in piece.cell_data},
        duplicate=np.concatenate([_duplicate(p) for p in pieces]),
    )


def _duplicate(piece: Dataset) -> np.ndarray:
    return np.zeros(len(piece.points), dtype=bool) if piece.duplicate is None else piece.duplicate


def _vtx_schema(point_names: typing.Iterable[str], cell_names: typing.Iterable[str]) -> str:
    """The ``vtk.xml`` attribute that tells ParaView's VTX reader what the arrays are."""

    def arrays(names: typing.Iterable[str]) -> str:
        return "".join(f"        <DataArray Name={quoteattr(name)} />\n" for name in names)

    return (
        '<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="0.1">\n  <UnstructuredGrid>\n'
        '    <Piece NumberOfPoints="NumberOfNodes" NumberOfCells="NumberOfCells">\n'
        '      <Points>\n        <DataArray Name="geometry" />\n      </Points>\n'
        '      <Cells>\n        <DataArray Name="connectivity" />\n        <DataArray Name="types" />\n      </Cells>\n'
        '      <PointData>\n        <DataArray Name="TIME">step</DataArray>\n'
        + arrays(["vtkGhostType", *point_names]) + "      </PointData>\n"
        "      <CellData>\n" + arrays(cell_names) + "      </CellData>\n"
        "    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n"
    )


def read_vtx(path: str | os.PathLike, step: int = 0) -> Dataset:
    """Read one step (negative: from the end) of a VTX directory into one :class:`Dataset`, its blocks appended.

    The blocks (one per writing rank) are appended as ParaView's VTX reader
    appends them: point indices of a block's cells offset by the points of the
    blocks before it; ``vtkGhostType`` becomes ``duplicate``. Not collective.
    """
    import adios2

    with adios2.FileReader(str(path)) as reader:
        step = step % reader.num_steps()
        schema = reader.read_attribute_string("vtk.xml")
        schema = schema if isinstance(schema, str) else schema[0]
        sections = {}
        for kind in ("PointData", "CellData"):
            section = re.search(f"<{kind}>(.*?)</{kind}>", schema, re.S)
            sections[kind] = re.findall(r'<DataArray Name="([^"]*)"\s*/>', section[1] if section else "")

        def blocks(name: str) -> list[np.ndarray]:
            n_blocks = len(reader.all_blocks_info(name)[step])
            return [reader.read(name, block_id=b, step_selection=[step, 1]) for b in range(n_blocks)]

        geometry = [g.reshape(-1, 3) for g in blocks("geometry")]
        offsets = np.cumsum([0] + [len(g) for g in geometry[:-1]])
        connectivity = [c.reshape(-1, c.reshape(-1)[0] + 1)[:, 1:] + offset
                        for c, offset in zip(blocks("connectivity"), offsets)]
        types = int(np.atleast_1d(reader.read("types", step_selection=[step, 1]))[0])
        dataset = Dataset(points=np.concatenate(geometry), cells=np.concatenate(connectivity), cell_type=types)
        for name in sections["PointData"]:
            if name == "vtkGhostType":
                dataset.duplicate = np.concatenate(blocks(name)) != 0
            elif name != "vtkOriginalPointIds":
                dataset.point_data[name] = np.concatenate(blocks(name))
        for name in sections["CellData"]:
            dataset.cell_data[name] = np.concatenate(blocks(name))
    return dataset


def _adios(comm: MPI.Comm):
    """An ADIOS2 object on ``comm`` (MPI bindings) or a serial one for a single rank."""
    import adios2

    if adios2.bindings.is_built_with_mpi:
        return adios2.Adios(comm=comm)
    if comm.size > 1:
        raise RuntimeError("VTX output on several ranks needs the MPI-enabled ADIOS2 Python module "
                           "(Debian: python3-adios2-mpi), run under mpirun")
    return adios2.Adios()


class VTXDatasetWriter:
    """Writes :class:`Dataset` pieces, one per rank, to one VTX (ADIOS2 BP4) directory.

    ParaView opens it with ``ADIOS2VTXReader``; every :meth:`write` is one time
    step, all steps and ranks must have the same array names. The directory
    appears under its name when the writer is closed (collective) after at least
    one step; on an exception inside a ``with`` block it is removed.

    ``keep`` > 0 continues the file of an earlier run of the same output (a restart):
    its first ``keep`` steps are copied, each rank taking every size-th block, before
    the first new step. That file is ``path`` when the run ended (closed it) or its
    temporary sibling when the run was killed; it is kept, as ``.NAME.previous``, until
    the copy is complete. Steps after ``keep`` (written after the last checkpoint) are dropped.
    """

    def __init__(self, comm: MPI.Comm, path: str | os.PathLike, keep: int = 0):
        self.comm = comm
        self._atomic = atomic_path(comm, path)
        self._tmp = self._atomic.__enter__()
        self._engine = self._io = self._adios = None
        self._names: tuple[list[str], list[str]] | None = None
        self._keep = keep
        self._previous = self._tmp.with_name(f".{pathlib.Path(path).name}.previous")
        if keep > 0:
            self._set_aside(pathlib.Path(path))

    def write(self, piece: Dataset, t: float = 0.0) -> None:
        """Write this rank's piece as one block of a new time step. Collective."""
        from adios2 import bindings

        names = (list(piece.point_data), list(piece.cell_data))
        if self._names is None:
            if any(other != names for other in self.comm.allgather(names)):
                raise ValueError(f"VTXDatasetWriter: the ranks' arrays differ (rank {self.comm.rank}: {names})")
            self._adios = _adios(self.comm)
            self._io = self._adios.declare_io("contactqvi")
            self._io.set_engine("BP4")
            self._io.define_attribute("vtk.xml", _vtx_schema(*names))
            self._engine = self._io.open(str(self._tmp), bindings.Mode.Write)
            self._names = names
            if self._keep > 0:
                self._copy_steps()
        elif self.comm.allreduce(names != self._names, op=MPI.LOR):
            raise ValueError(f"VTXDatasetWriter: arrays {names} differ from the first step's {self._names}")
        self._engine.begin_step()
        self._put_value("step", np.float64(t))
        self._put_value("types", np.uint32(piece.cell_type))
        n_cells, n_per_cell = piece.cells.shape
        if n_cells > 0:  # a rank without cells writes no block
            self._put_value("NumberOfNodes", np.uint32(len(piece.points)), local=True)
            self._put_value("NumberOfCells", np.uint32(n_cells), local=True)
            ghost = (_duplicate(piece) * DUPLICATE_POINT).astype(np.uint8)
            arrays = {
                "geometry": np.asarray(piece.points, dtype=np.float64).reshape(-1, 3),
                "connectivity": np.column_stack([np.full(n_cells, n_per_cell), piece.cells]).astype(np.int64),
                "vtkGhostType": ghost,
                **piece.point_data,
                **piece.cell_data,
            }
            for name, array in arrays.items():
                self._put_array(name, np.ascontiguousarray(array))
        self._engine.end_step()

    def _put_value(self, name: str, value: np.generic, local: bool = False) -> None:
        from adios2 import bindings

        array = np.array([value])
        variable = self._io.inquire_variable(name)
        if variable is None:
            shape = [bindings.LocalValueDim] if local else []
            variable = self._io.define_variable(name, array, shape, [], [])
        self._engine.put(variable, array, bindings.Mode.Sync)

    def _put_array(self, name: str, array: np.ndarray) -> None:
        from adios2 import bindings

        variable = self._io.inquire_variable(name)
        if variable is None:
            variable = self._io.define_variable(name, array, [], [], list(array.shape))
        else:
            variable.set_selection([[], list(array.shape)])  # a local array: count only
        self._engine.put(variable, array, bindings.Mode.Sync)

    def _set_aside(self, path: pathlib.Path) -> None:
        """Move the earlier run's file to ``.NAME.previous`` (unless a restart left it there)."""
        error = None
        if self.comm.rank == 0 and not self._previous.is_dir():
            source = next((f for f in (self._tmp, path) if f.is_dir()), None)
            try:
                if source is None:
                    raise FileNotFoundError(f"no {path.name} of the earlier run in {path.parent} to continue")
                os.replace(source, self._previous)
            except OSError as exc:
                error = str(exc)
        error = self.comm.bcast(error, root=0)
        if error is not None:
            raise OSError(error)

    def _copy_steps(self) -> None:
        """Copy the first ``keep`` steps of ``.NAME.previous``, then remove it. Collective."""
        import adios2

        with adios2.FileReader(str(self._previous), comm=self.comm) as source:
            if source.num_steps() < self._keep:
                raise RuntimeError(f"{self._previous} holds {source.num_steps()} steps, the checkpoint {self._keep}")
            local = [name for name in source.available_variables() if name not in ("step", "types",
                                                                                     "NumberOfNodes", "NumberOfCells")]
            for step in range(self._keep):
                self._engine.begin_step()
                for name in ("step", "types"):
                    self._put_value(name, source.read(name, step_selection=[step, 1]).reshape(-1)[0])
                blocks = len(source.all_blocks_info("geometry")[step])
                for block in range(self.comm.rank, blocks, self.comm.size):
                    arrays = {name: source.read(name, block_id=block, step_selection=[step, 1]) for name in local}
                    self._put_value("NumberOfNodes", np.uint32(len(arrays["geometry"])), local=True)
                    self._put_value("NumberOfCells", np.uint32(len(arrays["connectivity"])), local=True)
                    for name, array in arrays.items():
                        self._put_array(name, np.ascontiguousarray(array))
                self._engine.end_step()
        self.comm.Barrier()
        if self.comm.rank == 0:
            shutil.rmtree(self._previous)

    def close(self, ok: bool = True) -> None:
        """Finish the file (collective); ``ok=False`` or no step written discards it."""
        written = self._engine is not None
        if written:
            self._engine.close()
            self._engine = None
        if ok and written:
            self._atomic.__exit__(None, None, None)
        else:
            error = RuntimeError("VTXDatasetWriter: discarded")
            self._atomic.__exit__(type(error), error, None)

    def __enter__(self) -> VTXDatasetWriter:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: object) -> None:
        unwind_together(exc)
        self.close(ok=exc_type is None)


def write_vtx_dataset(comm: MPI.Comm, path: str | os.PathLike, piece: Dataset, t: float = 0.0) -> None:
    """Write one step of each rank's piece as a VTX directory. Collective."""
    with VTXDatasetWriter(comm, path) as writer:
        writer.write(piece, t)


def write_vtx(path: str | os.PathLike, functions: list[fem.Function], t: float = 0.0) -> None:
    """Write functions of one mesh to a VTX (ADIOS2 BP4) directory for ParaView.

    P1/Q1 functions become point data, DG0 functions cell data, in one dataset
    written by the ranks in parallel (see the module docstring); the names are the
    functions' names. Other spaces (higher degree) go through DOLFINx's
    ``VTXWriter``, which in parallel repeats ghost cells (make such meshes with
    ``GhostMode.none``, :func:`contactqvi.meshes.cell_partitioner`). Collective.
    """
    msh = functions[0].function_space.mesh
    comm = msh.comm
    nodal = all(f.function_space.mesh is msh and (_is_nodal(f.function_space) or _is_cellwise(f.function_space))
                for f in functions)
    if nodal:
        piece = MeshPiece(msh).dataset(
            {f.name: f for f in functions if _is_nodal(f.function_space)},
            {f.name: f for f in functions if not _is_nodal(f.function_space)},
        )
        write_vtx_dataset(comm, path, piece, t)
        return
    with atomic_path(comm, path) as tmp:
        with io.VTXWriter(comm, str(tmp), functions, engine="BP4") as writer:
            writer.write(t)


def write_xdmf(
    path: str | os.PathLike,
    msh: dmesh.Mesh,
    functions: typing.Sequence[fem.Function] = (),
    meshtags: typing.Sequence[dmesh.MeshTags] = (),
) -> None:
    """Write a mesh, P1/DG0 functions and meshtags to ``path`` (.xdmf) and its .h5 file.

    Written in parallel by DOLFINx (owned entities only). Both files are written
    under temporary names; the .h5 is renamed first and the .xdmf (the file
    ParaView opens) last, so a complete .xdmf means complete data. Collective.
    """
    final = pathlib.Path(path).with_suffix(".xdmf")
    tmp = final.with_name(f".{final.stem}.partial.xdmf")
    comm = msh.comm
    try:
        with io.XDMFFile(comm, str(tmp), "w") as xdmf:
            xdmf.write_mesh(msh)
            for tags in meshtags:
                xdmf.write_meshtags(tags, msh.geometry)
            for f in functions:
                xdmf.write_function(f, 0.0)
        comm.Barrier()
        if comm.rank == 0:
            os.replace(tmp.with_suffix(".h5"), final.with_suffix(".h5"))
            tmp.write_text(tmp.read_text().replace(tmp.with_suffix(".h5").name, final.with_suffix(".h5").name))
            os.replace(tmp, final)
    finally:
        comm.Barrier()
        if comm.rank == 0:
            for leftover in (tmp, tmp.with_suffix(".h5")):
                leftover.unlink(missing_ok=True)
