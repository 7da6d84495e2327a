"""Readers of the output files, for tests: VTX (ours or DOLFINx's) and XDMF point data."""

from __future__ import annotations

import os
import pathlib
import re

import numpy as np

from contactqvi.paraview import Dataset


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
