"""Entries of node-indexed quantities moved to the ranks that own the nodes.

A contact search works on the facets a rank owns, whose nodes may be ghosts there; the
mortar rows (:mod:`contactqvi.contact.mortar`) and their derivatives
(:mod:`contactqvi.contact.linearisation`) are summed on the owners of their row nodes,
and the positions of the master nodes a row couples to are fetched from theirs. Only the
entries a rank holds travel (``alltoall``), never a whole surface.
"""

from __future__ import annotations

from mpi4py import MPI

import numpy as np

__all__ = ["fetch_rows", "owner_ranges", "sum_to_owners"]


def owner_ranges(comm: MPI.Comm, index_map) -> np.ndarray:
    """Start of each rank's range of global node indices, and the total, (size + 1,)."""
    starts = comm.allgather(index_map.local_range[0])
    return np.array([*starts, index_map.size_global], dtype=np.int64)


def sum_to_owners(comm: MPI.Comm, owners: np.ndarray, rows: np.ndarray, cols: np.ndarray,
                  values: np.ndarray, width: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Send entries (row, col, value) to the owner of the global node ``row`` and sum duplicates there.

    Args:
        owners: :func:`owner_ranges`.
        rows: (E,) global node indices; cols: (E,) integers in [0, width).
        values: (E,) or (E, k): k values per entry, summed alike.
        width: bound of ``cols``; None: the number of global nodes (columns that are nodes).

    Returns the owned entries ``(rows, cols, values)``, unique (row, col) pairs sorted.
    """
    rows, cols = np.asarray(rows, dtype=np.int64), np.asarray(cols, dtype=np.int64)
    rank = np.searchsorted(owners, rows, side="right") - 1
    order = np.argsort(rank, kind="stable")
    bounds = np.searchsorted(rank[order], np.arange(comm.size + 1))
    send = [(rows[order[a:b]], cols[order[a:b]], values[order[a:b]]) for a, b in zip(bounds[:-1], bounds[1:])]
    received = comm.alltoall(send)
    rows = np.concatenate([part[0] for part in received])
    cols = np.concatenate([part[1] for part in received])
    values = np.concatenate([part[2] for part in received])
    width = np.int64(owners[-1] + 1 if width is None else width)  # one int64 key per (row, col)
    keys, inverse = np.unique(rows * width + cols, return_inverse=True)
    inverse = inverse.ravel()
    if values.ndim == 1:
        summed = np.bincount(inverse, weights=values, minlength=len(keys))
    else:
        summed = np.column_stack([np.bincount(inverse, weights=column, minlength=len(keys))
                                  for column in np.ascontiguousarray(values.T)])
    return keys // width, keys % width, summed


def fetch_rows(comm: MPI.Comm, index_map, x: np.ndarray, glob: np.ndarray) -> np.ndarray:
    """Rows of ``x`` (owned nodes first, any width) of the nodes with global indices ``glob``,
    fetched from their owners."""
    owners = owner_ranges(comm, index_map)
    rank = np.searchsorted(owners, glob, side="right") - 1
    order = np.argsort(rank, kind="stable")
    bounds = np.searchsorted(rank[order], np.arange(comm.size + 1))
    requests = comm.alltoall([glob[order[a:b]] for a, b in zip(bounds[:-1], bounds[1:])])
    start = index_map.local_range[0]
    replies = comm.alltoall([x[r - start] for r in requests])
    result = np.empty((len(glob), x.shape[1]))
    result[order] = np.concatenate(replies) if replies else np.empty((0, x.shape[1]))
    return result
