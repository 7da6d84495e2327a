"""Result output: ParaView files (VTX/XDMF), summary.json, solution.npz, optional PNGs.

Every file is written under a temporary name and renamed into place when
complete, so a failed run never leaves a half-written file that looks finished.

Parallel output holds every point and cell once, as a serial run's does.
DOLFINx 0.9's own ``VTXWriter`` writes each rank's ghost points and ghost cells
(at lev 4 of the paper's body on 2 ranks 1620 points and 1152 cells instead of
1377 and 1024, and ParaView integrated 12.5 % too much volume). :func:`write_vtx`
therefore gathers the owned points and cells on rank 0 (:func:`gather_dataset`)
and writes one VTX block there (:class:`VTXDatasetWriter`, with the ADIOS2
Python module, Debian's serial build), which also lets point data (P1) and cell
data (DG0) share one file and one file hold time steps. XDMF from DOLFINx is
written from owned entities only and needs no such care.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import logging
import os
import pathlib
import shutil
import typing
from xml.sax.saxutils import quoteattr

from mpi4py import MPI

import numpy as np

import dolfinx.plot
from dolfinx import fem, io
from dolfinx import mesh as dmesh

__all__ = [
    "prepare_output_dir",
    "atomic_path",
    "write_summary",
    "markdown_table",
    "write_table",
    "Dataset",
    "gather_dataset",
    "VTXDatasetWriter",
    "write_vtx_dataset",
    "read_vtx",
    "write_vtx",
    "write_xdmf",
    "read_xdmf_point_data",
    "gather_vertex_values",
    "write_solution_npz",
    "start_virtual_display",
]

logger = logging.getLogger(__name__)


def prepare_output_dir(comm: MPI.Comm, path: str | os.PathLike) -> pathlib.Path:
    """Create the output directory on rank 0 and return it on every rank."""
    out = pathlib.Path(path)
    error = None
    if comm.rank == 0:
        try:
            out.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            error = f"output: cannot create directory {str(out)!r}: {exc.strerror}"
    error = comm.bcast(error, root=0)
    if error:
        raise OSError(error)
    return out


@contextlib.contextmanager
def atomic_path(comm: MPI.Comm, path: str | os.PathLike) -> typing.Iterator[pathlib.Path]:
    """Yield a temporary sibling of ``path``; rename it to ``path`` on success (rank 0).

    Collective. On an exception the temporary file or directory is removed.
    """
    final = pathlib.Path(path)
    tmp = final.with_name(f".{final.name}.partial")
    ok = False
    try:
        yield tmp
        ok = True
    finally:
        comm.Barrier()
        if comm.rank == 0:
            if ok:
                if final.is_dir():
                    shutil.rmtree(final)
                os.replace(tmp, final)
            elif tmp.is_dir():
                shutil.rmtree(tmp, ignore_errors=True)
            else:
                tmp.unlink(missing_ok=True)
        comm.Barrier()


def _to_builtin(value: typing.Any) -> typing.Any:
    if isinstance(value, dict):
        return {str(k): _to_builtin(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_to_builtin(v) for v in value]
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, pathlib.Path):
        return str(value)
    return value


def write_summary(comm: MPI.Comm, path: str | os.PathLike, summary: dict[str, typing.Any]) -> None:
    """Write ``summary`` as JSON on rank 0, atomically (temporary file + rename)."""
    with atomic_path(comm, path) as tmp:
        if comm.rank == 0:
            tmp.write_text(json.dumps(_to_builtin(summary), indent=2, sort_keys=False) + "\n")


def markdown_table(header: typing.Sequence[str], rows: typing.Iterable[typing.Sequence[typing.Any]]) -> str:
    """A GitHub markdown table; floats in ``%.3g``, None as an en dash."""

    def cell(value: typing.Any) -> str:
        if value is None:
            return "\u2013"
        if isinstance(value, float):
            return f"{value:.3g}"
        return str(value)

    lines = ["| " + " | ".join(map(str, header)) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(cell(v) for v in row) + " |" for row in rows]
    return "\n".join(lines) + "\n"


def write_table(
    comm: MPI.Comm, stem: str | os.PathLike, data: dict[str, typing.Any], markdown: str, echo: bool = True
) -> None:
    """Write ``stem.json`` (``data``) and ``stem.md`` (``markdown``) atomically on rank 0.

    The one writer of every benchmark table; ``echo`` also prints the markdown.
    """
    stem = pathlib.Path(stem)
    write_summary(comm, stem.with_suffix(".json"), data)
    with atomic_path(comm, stem.with_suffix(".md")) as tmp:
        if comm.rank == 0:
            tmp.write_text(markdown)
    if echo and comm.rank == 0:
        print(markdown, flush=True)


@dataclasses.dataclass
class Dataset:
    """An unstructured grid held on one rank: what ParaView shows as one dataset.

    Attributes:
        points: (N, 3) point coordinates.
        cells: (C, k) point indices of each cell, in VTK's vertex order.
        cell_type: VTK cell type of all cells (DOLFINx's Lagrange types, e.g. 72
            hexahedron, 70 quadrilateral, or the linear 9 quadrilateral).
        point_data: name -> (N,) or (N, c) array.
        cell_data: name -> (C,) or (C, c) array.
    """

    points: np.ndarray
    cells: np.ndarray
    cell_type: int
    point_data: dict[str, np.ndarray] = dataclasses.field(default_factory=dict)
    cell_data: dict[str, np.ndarray] = dataclasses.field(default_factory=dict)


def _is_nodal(V: fem.FunctionSpace) -> bool:
    """One dof (per block) at each vertex and nowhere else: P1/Q1 on a degree-1 mesh."""
    layout, cmap = V.dofmap.dof_layout, V.mesh.geometry.cmap
    return cmap.degree == 1 and layout.num_dofs == cmap.dim and layout.num_entity_dofs(0) == 1


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


def gather_dataset(
    msh: dmesh.Mesh,
    point_data: typing.Mapping[str, fem.Function] | None = None,
    cell_data: typing.Mapping[str, fem.Function] | None = None,
) -> Dataset | None:
    """Gather the owned points and cells of ``msh`` and values on them on rank 0.

    Points are the mesh nodes in the global numbering (each once); cells are the
    owned cells of each rank in rank order, so a run on N ranks gives the same
    points, cells and integrals as a serial one (in another order).

    Args:
        msh: a mesh of degree 1.
        point_data: file name -> P1/Q1 function on ``msh`` (one value per node).
        cell_data: file name -> DG0 function on ``msh`` (one value per cell).

    Returns:
        The dataset on rank 0, None on the other ranks. Collective.
    """
    point_data, cell_data = dict(point_data or {}), dict(cell_data or {})
    comm = msh.comm
    if msh.geometry.cmap.degree != 1:
        raise ValueError("gather_dataset: the mesh must have degree 1")
    for name, f in point_data.items():
        if f.function_space.mesh is not msh or not _is_nodal(f.function_space):
            raise ValueError(f"gather_dataset: point data {name!r} is not a P1/Q1 function on the mesh")
    for name, f in cell_data.items():
        if f.function_space.mesh is not msh or not _is_cellwise(f.function_space):
            raise ValueError(f"gather_dataset: cell data {name!r} is not a DG0 function on the mesh")

    topology, cell_types, x = dolfinx.plot.vtk_mesh(msh)  # owned cells, local geometry nodes
    n_cells = len(cell_types)
    x_map = msh.geometry.index_map()
    n_nodes = x_map.size_local
    cells = x_map.local_to_global(topology.reshape(n_cells, -1)[:, 1:].ravel().astype(np.int32))
    cells = cells.reshape(n_cells, -1)
    gdim = msh.geometry.dim

    node_dof = np.zeros(x_map.size_local + x_map.num_ghosts, dtype=np.int32)
    local: dict[str, np.ndarray] = {}
    for name, f in point_data.items():
        V = f.function_space
        node_dof[msh.geometry.dofmap.ravel()] = V.dofmap.list.ravel()  # same vertex order in both maps
        bs = V.dofmap.index_map_bs
        local[name] = _vtk_components(f.x.array.reshape(-1, bs)[node_dof[:n_nodes]], bs, gdim)
    for name, f in cell_data.items():
        V = f.function_space
        bs = V.dofmap.index_map_bs
        local[name] = _vtk_components(f.x.array.reshape(-1, bs)[V.dofmap.list[:n_cells, 0]], bs, gdim)

    pieces = comm.gather((x[:n_nodes], cells, local), root=0)
    if comm.rank != 0:
        return None

    def stack(name: str) -> np.ndarray:
        return np.concatenate([piece[2][name] for piece in pieces])

    return Dataset(
        points=np.concatenate([piece[0] for piece in pieces]),
        cells=np.concatenate([piece[1] for piece in pieces]).astype(np.int64),
        cell_type=_vtk_cell_type(msh),
        point_data={name: stack(name) for name in point_data},
        cell_data={name: stack(name) for name in cell_data},
    )


def _vtk_cell_type(msh: dmesh.Mesh) -> int:
    from dolfinx.cpp.io import get_vtk_cell_type

    return int(get_vtk_cell_type(msh.topology.cell_type, msh.topology.dim))


def _vtx_schema(point_names: typing.Iterable[str], cell_names: typing.Iterable[str]) -> str:
    """The ``vtk.xml`` attribute that tells ParaView's VTX reader what the arrays are."""

    def arrays(names: typing.Iterable[str]) -> str:
        return "".join(f"        <DataArray Name={quoteattr(name)} />\n" for name in names)

    return (
        '<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="0.1">\n  <UnstructuredGrid>\n'
        '    <Piece NumberOfPoints="NumberOfNodes" NumberOfCells="NumberOfCells">\n'
        '      <Points>\n        <DataArray Name="geometry" />\n      </Points>\n'
        '      <Cells>\n        <DataArray Name="connectivity" />\n        <DataArray Name="types" />\n      </Cells>\n'
        '      <PointData>\n        <DataArray Name="TIME">step</DataArray>\n' + arrays(point_names) + "      </PointData>\n"
        "      <CellData>\n" + arrays(cell_names) + "      </CellData>\n"
        "    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n"
    )


class VTXDatasetWriter:
    """Writes :class:`Dataset` steps to one VTX (ADIOS2 BP4) directory from rank 0.

    ParaView opens it with ``ADIOS2VTXReader``; every :meth:`write` is one time
    step, all steps must have the same array names. The directory appears under
    its name when the writer is closed (collective) after at least one step; on an
    exception inside a ``with`` block it is removed.
    """

    def __init__(self, comm: MPI.Comm, path: str | os.PathLike):
        self.comm = comm
        self._atomic = atomic_path(comm, path)
        self._tmp = self._atomic.__enter__()
        self._engine = self._io = self._adios = None
        self._names: tuple[list[str], list[str]] | None = None

    def write(self, dataset: Dataset | None, t: float = 0.0) -> None:
        """Write one step (``dataset`` is used on rank 0 only). Collective."""
        if self.comm.rank == 0:
            self._write(dataset, t)
        self.comm.Barrier()

    def _write(self, dataset: Dataset, t: float) -> None:
        import adios2

        names = (list(dataset.point_data), list(dataset.cell_data))
        if self._engine is None:
            self._adios = adios2.Adios()
            self._io = self._adios.declare_io("contactqvi")
            self._io.set_engine("BP4")
            self._io.define_attribute("vtk.xml", _vtx_schema(*names))
            self._engine = self._io.open(str(self._tmp), adios2.bindings.Mode.Write)
            self._names = names
        elif names != self._names:
            raise ValueError(f"VTXDatasetWriter: arrays {names} differ from the first step's {self._names}")
        n_cells, n_per_cell = dataset.cells.shape
        connectivity = np.column_stack([np.full(n_cells, n_per_cell), dataset.cells]).astype(np.int64)
        arrays: dict[str, np.ndarray] = {
            "geometry": np.asarray(dataset.points, dtype=np.float64).reshape(-1, 3),
            "connectivity": connectivity,
            **dataset.point_data,
            **dataset.cell_data,
        }
        values = {"step": np.float64(t), "NumberOfNodes": np.uint32(len(dataset.points)),
                  "NumberOfCells": np.uint32(n_cells), "types": np.uint32(dataset.cell_type)}
        self._engine.begin_step()
        for name, value in values.items():
            array = np.array([value])
            self._engine.put(self._variable(name, array, single=True), array, adios2.bindings.Mode.Sync)
        for name, array in arrays.items():
            array = np.ascontiguousarray(array)
            self._engine.put(self._variable(name, array), array, adios2.bindings.Mode.Sync)
        self._engine.end_step()

    def _variable(self, name: str, array: np.ndarray, single: bool = False):
        variable = self._io.inquire_variable(name)
        if variable is None:
            if single:
                return self._io.define_variable(name, array)
            return self._io.define_variable(name, array, [], [], list(array.shape))
        if not single:
            variable.set_selection([[], list(array.shape)])  # a local array: count only
        return variable

    def close(self, ok: bool = True) -> None:
        """Finish the file (collective); ``ok=False`` or no step written discards it."""
        written = self.comm.bcast(self._engine is not None, root=0)
        if self._engine is not None:
            self._engine.close()
            self._engine = None
        if ok and written:
            self._atomic.__exit__(None, None, None)
        else:
            error = RuntimeError("VTXDatasetWriter: discarded")
            self._atomic.__exit__(type(error), error, None)

    def __enter__(self) -> VTXDatasetWriter:
        return self

    def __exit__(self, exc_type, *exc: object) -> None:
        self.close(ok=exc_type is None)


def write_vtx_dataset(comm: MPI.Comm, path: str | os.PathLike, dataset: Dataset | None, t: float = 0.0) -> None:
    """Write one :class:`Dataset` (given on rank 0) as a VTX directory. Collective."""
    with VTXDatasetWriter(comm, path) as writer:
        writer.write(dataset, t)


def read_vtx(path: str | os.PathLike, step: int = 0) -> Dataset:
    """Read one step of a VTX directory (ours or DOLFINx's) back into a :class:`Dataset`.

    The blocks DOLFINx's writer makes per rank are concatenated as ParaView does
    (their ghost points and cells included). Not collective: any rank may call it.
    """
    import re

    import adios2

    with adios2.FileReader(str(path)) as reader:
        schema = reader.read_attribute_string("vtk.xml")
        schema = schema if isinstance(schema, str) else schema[0]
        sections = {}
        for kind in ("PointData", "CellData"):
            section = re.search(f"<{kind}>(.*?)</{kind}>", schema, re.S)
            sections[kind] = re.findall(r'<DataArray Name="([^"]*)"\s*/>', section[1] if section else "")

        def blocks(name: str) -> list[np.ndarray]:
            n_blocks = len(reader.all_blocks_info(name)[step])
            return [reader.read(name, block_id=b, step_selection=[step, 1]) for b in range(n_blocks)]

        nodes = [int(n) for n in np.atleast_1d(reader.read("NumberOfNodes", step_selection=[step, 1]))]
        offsets = np.concatenate([[0], np.cumsum(nodes)[:-1]])
        connectivity = [c.reshape(-1, c.reshape(-1)[0] + 1)[:, 1:] + offset
                        for c, offset in zip(blocks("connectivity"), offsets)]
        types = int(np.atleast_1d(reader.read("types", step_selection=[step, 1]))[0])
        dataset = Dataset(
            points=np.concatenate(blocks("geometry")).reshape(-1, 3),
            cells=np.concatenate(connectivity),
            cell_type=types,
        )
        for name in sections["PointData"]:
            if name not in ("vtkOriginalPointIds", "vtkGhostType"):
                dataset.point_data[name] = np.concatenate(blocks(name))
        for name in sections["CellData"]:
            dataset.cell_data[name] = np.concatenate(blocks(name))
    return dataset


def write_vtx(path: str | os.PathLike, functions: list[fem.Function], t: float = 0.0) -> None:
    """Write functions of one mesh to a VTX (ADIOS2 BP4) directory for ParaView.

    P1/Q1 functions become point data, DG0 functions cell data, in one dataset
    gathered on rank 0 (see the module docstring); the names are the functions'
    names. Other spaces (higher degree) go through DOLFINx's ``VTXWriter``, which
    in parallel repeats ghost cells (make such meshes with ``GhostMode.none``,
    :func:`contactqvi.meshes.cell_partitioner`). Collective.
    """
    msh = functions[0].function_space.mesh
    comm = msh.comm
    nodal = all(f.function_space.mesh is msh and (_is_nodal(f.function_space) or _is_cellwise(f.function_space))
                for f in functions)
    if nodal:
        dataset = gather_dataset(
            msh,
            {f.name: f for f in functions if _is_nodal(f.function_space)},
            {f.name: f for f in functions if not _is_nodal(f.function_space)},
        )
        write_vtx_dataset(comm, path, dataset, t)
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

    Both are written under temporary names; the .h5 is renamed first and the
    .xdmf (the file ParaView opens) last, so a complete .xdmf means complete data.
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


def read_xdmf_point_data(path: str | os.PathLike) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Points (N, 3) and nodal fields by name of an XDMF file from :func:`write_xdmf`, read with meshio.

    DOLFINx writes one temporal collection per function and meshio's reader reads
    one collection, so each is read in turn (first time step). Scalar fields are
    (N,) arrays, vector fields (N, 3). Not collective: any rank may call it.
    """
    import meshio

    with meshio.xdmf.TimeSeriesReader(str(pathlib.Path(path).with_suffix(".xdmf"))) as reader:
        points, _ = reader.read_points_cells()
        fields: dict[str, np.ndarray] = {}
        for grid in reader.domain:
            if grid.get("CollectionType") == "Temporal":
                reader.collection = list(grid)
                fields.update(reader.read_data(0)[1])
    return points, {name: v[:, 0] if v.ndim == 2 and v.shape[1] == 1 else v for name, v in fields.items()}


def gather_vertex_values(u: fem.Function) -> tuple[np.ndarray, np.ndarray] | tuple[None, None]:
    """Owned dof coordinates (N, 3) and values (N, bs) of a P1/Q1 function, gathered on rank 0.

    Rows are sorted lexicographically by coordinate, so serial and parallel runs
    give identical arrays. Returns ``(None, None)`` on other ranks.
    """
    V = u.function_space
    index_map, bs = V.dofmap.index_map, V.dofmap.index_map_bs
    n_owned = index_map.size_local
    x = V.tabulate_dof_coordinates()[:n_owned]
    values = u.x.array[: n_owned * bs].reshape(n_owned, bs)
    comm = V.mesh.comm
    xs, vs = comm.gather(x, root=0), comm.gather(values, root=0)
    if comm.rank != 0:
        return None, None
    x, values = np.vstack(xs), np.vstack(vs)
    keys = np.round(x / max(np.abs(x).max(), 1e-300), 10)  # immune to round-off in the coordinates
    order = np.lexsort((keys[:, 0], keys[:, 1], keys[:, 2]))
    return x[order], values[order]


def write_solution_npz(path: str | os.PathLike, u: fem.Function, **extra: np.ndarray) -> None:
    """Write ``x`` (N, 3) vertex coordinates and ``u`` (N, bs) or (N,) values on rank 0."""
    comm = u.function_space.mesh.comm
    x, values = gather_vertex_values(u)
    with atomic_path(comm, path) as tmp:
        if comm.rank == 0:
            with open(tmp, "wb") as fh:
                np.savez(fh, x=x, u=values[:, 0] if values.shape[1] == 1 else values, **extra)


def start_virtual_display() -> bool:
    """Make pyvista usable without a screen; False (and a logged reason) if impossible."""
    try:
        import pyvista

        if not os.environ.get("DISPLAY"):
            pyvista.start_xvfb()
        return True
    except Exception as exc:  # pyvista/xvfb failures must never end a solve
        logger.warning("no display for plotting (%s); PNGs are skipped", exc)
        return False
