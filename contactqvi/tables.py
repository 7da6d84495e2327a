"""Files of numbers: summary.json, benchmark tables (JSON + markdown), solution.npz.

Every file is written under a temporary name and renamed into place when
complete (:func:`atomic_path`), so a failed run never leaves a half-written file
that looks finished. Only ``solution.npz`` gathers a field on rank 0, and only up
to :data:`GATHER_MAX_NODES` nodes unless asked for; ParaView datasets are
written in parallel by :mod:`contactqvi.paraview`.
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

from dolfinx import fem

__all__ = [
    "GATHER_MAX_NODES",
    "atomic_path",
    "gather_vertex_values",
    "markdown_table",
    "prepare_output_dir",
    "to_builtin",
    "write_solution_npz",
    "write_summary",
    "write_table",
]

logger = logging.getLogger(__name__)

#: Most nodes whose values an output gathers on rank 0 (``solution.npz`` unless asked
#: for, figures): lev 8 of the paper's body has 70 785 nodes, lev 9 and up more.
GATHER_MAX_NODES = 100_000


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

    Collective. On an exception the temporary file or directory is removed, and the
    ranks that did not raise raise an :class:`OSError` too (a full disk seen by one rank
    must not leave the others in the next collective call).
    """
    final = pathlib.Path(path)
    tmp = final.with_name(f".{final.name}.partial")
    ok = False
    try:
        yield tmp
        ok = True
    finally:
        error = _finish(comm, tmp, final, comm.allreduce(ok, op=MPI.LAND))
    if error is not None:
        raise OSError(error)


def _finish(comm: MPI.Comm, tmp: pathlib.Path, final: pathlib.Path, keep: bool) -> str | None:
    """Rename ``tmp`` to ``final`` (``keep``) or remove it, on rank 0; the error on every rank, or None."""
    error = None
    if comm.rank == 0:
        try:
            if keep:
                if final.is_dir():
                    shutil.rmtree(final)
                os.replace(tmp, final)
            elif tmp.is_dir():
                shutil.rmtree(tmp, ignore_errors=True)
            else:
                tmp.unlink(missing_ok=True)
        except OSError as exc:
            error = f"cannot write {final}: {exc.strerror or exc}"
    error = comm.bcast(error, root=0)
    return f"writing {final} failed on another rank" if error is None and not keep else error


def to_builtin(value: typing.Any) -> typing.Any:
    """``value`` with numpy arrays and scalars, tuples and paths turned into JSON types."""
    if isinstance(value, dict):
        return {str(k): to_builtin(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_builtin(v) for v in value]
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
            tmp.write_text(json.dumps(to_builtin(summary), indent=2, sort_keys=False) + "\n")


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

    The one writer of every benchmark table; ``echo`` also prints the markdown. A missing directory
    of ``stem`` is made (a benchmark's ``--output``: it used to fail at the end of the run).
    """
    stem = pathlib.Path(stem)
    if comm.rank == 0:
        stem.parent.mkdir(parents=True, exist_ok=True)
    write_summary(comm, stem.with_suffix(".json"), data)
    with atomic_path(comm, stem.with_suffix(".md")) as tmp:
        if comm.rank == 0:
            tmp.write_text(markdown)
    if echo and comm.rank == 0:
        print(markdown, flush=True)


def gather_vertex_values(u: fem.Function) -> tuple[np.ndarray, np.ndarray] | tuple[None, None]:
    """Owned dof coordinates (N, 3) and values (N, bs) of a Lagrange function, gathered on rank 0.

    Rows are sorted lexicographically by coordinate, nodes at one point (two bodies
    touching there) by their index in the mesh input, so serial and parallel runs give
    identical arrays. Returns ``(None, None)`` on other ranks. For small problems,
    figures and tests: it holds the whole field on rank 0.
    """
    V = u.function_space
    index_map, bs = V.dofmap.index_map, V.dofmap.index_map_bs
    n_owned = index_map.size_local
    x = V.tabulate_dof_coordinates()[:n_owned]
    values = u.x.array[: n_owned * bs].reshape(n_owned, bs)
    comm = V.mesh.comm
    xs, vs, inputs = comm.gather(x, root=0), comm.gather(values, root=0), comm.gather(_input_index(V), root=0)
    if comm.rank != 0:
        return None, None
    x, values = np.vstack(xs), np.vstack(vs)
    keys = np.round(x / max(np.abs(x).max(), 1e-300), 10)  # immune to round-off in the coordinates
    order = np.lexsort((np.concatenate(inputs), keys[:, 0], keys[:, 1], keys[:, 2]))
    return x[order], values[order]


def _input_index(V: fem.FunctionSpace) -> np.ndarray:
    """Index in the mesh input of the node of each owned dof of a Lagrange space (the geometry's
    nodes, a cell's vertices first, with the same cell-local order); -1 at a dof with no node of
    its own (the edges of a quadratic space on a mesh of degree 1, which only one body holds)."""
    msh = V.mesh
    nodes = min(V.dofmap.list.shape[1], msh.geometry.dofmap.shape[1])
    inputs = np.asarray(msh.geometry.input_global_indices, dtype=np.int64)
    index = np.full(V.dofmap.index_map.size_local + V.dofmap.index_map.num_ghosts, -1, dtype=np.int64)
    index[V.dofmap.list[:, :nodes].ravel()] = inputs[msh.geometry.dofmap[:, :nodes].ravel()]
    return index[: V.dofmap.index_map.size_local]


def write_solution_npz(
    path: str | os.PathLike, u: fem.Function, force: bool = False, **extra: np.ndarray
) -> bool:
    """Write ``x`` (N, 3) vertex coordinates and ``u`` (N, bs) or (N,) values on rank 0.

    The field is gathered on rank 0, so the file is written only for at most
    :data:`GATHER_MAX_NODES` nodes, or when ``force`` is set. Collective.

    Returns:
        Whether the file was written.
    """
    V = u.function_space
    n_nodes = V.dofmap.index_map.size_global
    if n_nodes > GATHER_MAX_NODES and not force:
        logger.info("%s is skipped: %d nodes > %d (gathered on one rank)", path, n_nodes, GATHER_MAX_NODES)
        return False
    comm = V.mesh.comm
    x, values = gather_vertex_values(u)
    with atomic_path(comm, path) as tmp:
        if comm.rank == 0:
            with open(tmp, "wb") as fh:
                np.savez(fh, x=x, u=values[:, 0] if values.shape[1] == 1 else values, **extra)
    return True
