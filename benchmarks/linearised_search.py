"""The cost of the linearised mortar search (issue 45): a search with the derivatives of D, M and
the nodal normals (``mortar_coupling(..., linearised=True)``, docs/finite_strain.md Sect. 13)
against a plain one, on the two-body Hertz meshes (tetrahedra, the ball pressed 1e-3 of its
size into the block) and the distorted hexahedral pair of tests/test_linearisation.py.
Writes ``linearised_search.{json,md}`` to ``--output``; the fastest of ``--repeat`` searches.
Beside each ratio the ratio of the complex-step derivatives the forward mode replaced, read
from ``linearised_search_complex_step.json`` in ``--output`` (that implementation's run).
Runs serially or under ``mpirun``. Example:
    python benchmarks/linearised_search.py --meshes hertz_bodies_coarse hertz_bodies_medium
"""

from __future__ import annotations

import pathlib
import time

from mpi4py import MPI

import numpy as np

from dolfinx import fem

import benchlib
from rows import cell, read_table
from contactqvi.contact.mortar import mortar_coupling
from contactqvi.meshes import boundary_facets, read_gmsh, split_by_body

ROOT = pathlib.Path(__file__).resolve().parent.parent
MESHES = ("hertz_bodies_coarse", "hertz_bodies_medium", "hertz_bodies_fine", "hertz_bodies_hex_coarse")


def _measure(name: str, comm: MPI.Comm, repeat: int) -> dict:
    """The fastest plain and linearised search of the block's top (slave) against the ball."""
    msh, facet_tags, cell_tags = read_gmsh(ROOT / "meshes" / f"{name}.geo", comm)
    tags = split_by_body(msh, facet_tags, cell_tags)
    V = fem.functionspace(msh, ("Lagrange", 1, (3,)))
    x = V.tabulate_dof_coordinates()
    size = comm.allreduce(float(np.ptp(x[:, 0])) if len(x) else 0.0, op=MPI.MAX)
    displacement = np.zeros_like(x)
    displacement[x[:, 2] > 1e-9 * size, 2] = -1e-3 * size  # the ball into the block
    slave, master = boundary_facets(tags, "block.top"), boundary_facets(tags, "ball.sphere")
    seconds, rows = {}, 0
    for linearised in (False, True):
        best = np.inf
        for _ in range(repeat):
            comm.Barrier()
            start = time.perf_counter()
            coupling = mortar_coupling(V, slave, master, search_distance=1e-3 * size, displacement=displacement,
                                       linearised=linearised)
            best = min(best, comm.allreduce(time.perf_counter() - start, op=MPI.MAX))
        seconds[linearised] = best
        rows = comm.allreduce(len(coupling.slave_blk))
    return {"mesh": name, "dofs": 3 * V.dofmap.index_map.size_global, "slave_rows": rows,
            "plain_s": seconds[False], "linearised_s": seconds[True], "ratio": seconds[True] / seconds[False]}


def markdown(rows: list[dict]) -> str:
    lines = ["## The linearised mortar search against a plain one", "",
             "Fastest of the repeats, seconds (largest rank); the derivatives by forward-mode automatic "
             "differentiation (docs/finite_strain.md, Sect. 13); complex step: the ratio of the complex-step "
             "derivatives it replaced (linearised_search_complex_step.json).", "",
             "| mesh | dofs | slave rows | plain (s) | linearised (s) | ratio | complex step |",
             "|---|---|---|---|---|---|---|"]
    lines += [f"| {r['mesh']} | {r['dofs']} | {r['slave_rows']} | {cell(r, 'plain_s')} | {cell(r, 'linearised_s')} "
              f"| {cell(r, 'ratio', '.1f')} | {cell(r, 'complex_step_ratio', '.1f')} |" for r in rows]
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = benchlib.make_parser(__doc__)
    parser.add_argument("--meshes", nargs="+", default=list(MESHES), choices=MESHES)
    parser.add_argument("--repeat", type=int, default=3)
    args, comm, out = benchlib.parse(parser)
    earlier = read_table(out / "linearised_search_complex_step.json").get("rows", [])
    complex_step = {r["mesh"]: r["ratio"] for r in earlier}
    rows = [{**_measure(name, comm, args.repeat), "complex_step_ratio": complex_step.get(name)} for name in args.meshes]
    benchlib.emit(comm, out, "linearised_search", rows, markdown(rows))


if __name__ == "__main__":
    main()
