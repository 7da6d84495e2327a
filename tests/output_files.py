"""Readers of the output files, for tests: VTX (ours or DOLFINx's, :func:`contactqvi.paraview.read_vtx`) and
XDMF point data."""

from __future__ import annotations

import os
import pathlib

import numpy as np

from contactqvi.paraview import read_vtx  # noqa: F401 (the tests import it from here)


def read_xdmf_point_data(path: str | os.PathLike) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Points (N, 3) and nodal fields by name of an XDMF file of ``write_xdmf``, read with meshio.

    DOLFINx writes one temporal collection per function and meshio's reader reads
    one collection, so each is read in turn (first time step). Scalar fields are
    (N,) arrays, vector fields (N, 3). Not collective.
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
