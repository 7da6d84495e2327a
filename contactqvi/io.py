"""Result output: ParaView files (VTX/XDMF), summary.json, solution.npz, optional PNGs.

Every file is written under a temporary name and renamed into place when
complete, so a failed run never leaves a half-written file that looks finished.
Only the explicit ``solution.npz``/plot output gathers data on rank 0.
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import pathlib
import shutil
import typing

from mpi4py import MPI

import numpy as np

from dolfinx import fem, io
from dolfinx import mesh as dmesh

__all__ = [
    "prepare_output_dir",
    "atomic_path",
    "write_summary",
    "markdown_table",
    "write_table",
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

    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
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


def write_vtx(path: str | os.PathLike, functions: list[fem.Function]) -> None:
    """Write functions sharing one element to a VTX (ADIOS2 BP4) directory for ParaView."""
    comm = functions[0].function_space.mesh.comm
    with atomic_path(comm, path) as tmp:
        with io.VTXWriter(comm, str(tmp), functions, engine="BP4") as writer:
            writer.write(0.0)


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
