"""contactqvi (SCD semismooth* Newton) on a peer-benchmark case, writing the peers' result files.

    python benchmarks/peers/ours_contact.py CASE.toml --output DIR [--pc gamg|lu] [--rtol 1e-12] [--tol 0.1]
    mpirun -n 2 python benchmarks/peers/ours_contact.py CASE.toml --output DIR

The case is read by :func:`contactqvi.case.load_case` and solved along its load path by
:func:`contactqvi.contact.load_path.solve_load_path`, exactly as ``python -m contactqvi run``
does (without its ParaView output). The reference of ``peers_real.py`` is this driver with
``--pc lu --rtol 1e-12`` (exact Newton steps). Result fields: :mod:`common`.
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

from dolfinx import fem

sys.path.insert(0, str(pathlib.Path(__file__).parent))
import common  # noqa: E402

from contactqvi import tables  # noqa: E402
from contactqvi.case import load_case  # noqa: E402
from contactqvi.cli import setup_logging  # noqa: E402
from contactqvi.contact.load_path import contact_resultants, solve_load_path  # noqa: E402
from contactqvi.contact.postprocess import contact_summary  # noqa: E402
from contactqvi.linalg import default_options  # noqa: E402
from contactqvi.runner import PREFIX, build_problem  # noqa: E402


def _gather(u: fem.Function) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Owned node coordinates (N, 3) and values (N, 3) of a P1/Q1 vector function on rank 0."""
    V = u.function_space
    n_owned = V.dofmap.index_map.size_local
    x = V.tabulate_dof_coordinates()[:n_owned]
    values = u.x.array[: 3 * n_owned].reshape(n_owned, 3)
    xs, vs = V.mesh.comm.gather(x, root=0), V.mesh.comm.gather(values, root=0)
    return (np.vstack(xs), np.vstack(vs)) if V.mesh.comm.rank == 0 else (None, None)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("case")
    parser.add_argument("--output", required=True)
    parser.add_argument("--pc", default=None, help="Newton-step solver (default: the case's, else gamg)")
    parser.add_argument("--rtol", type=float, default=None,
                        help="||y^|| <= rtol ||y^0|| (default: the case's, else 1e-12)")
    parser.add_argument("--tol", type=float, default=None, help="Krylov tolerance of a Newton step (default 0.1)")
    args = parser.parse_args()
    setup_logging("WARNING")
    comm = MPI.COMM_WORLD
    case = load_case(args.case)
    parameters = dict(case.solver)
    from_rest = parameters.pop("start", "rest") == "rest"
    for name in ("pc", "rtol", "tol"):
        if getattr(args, name) is not None:
            parameters[name] = getattr(args, name)
    with default_options(PREFIX, case.petsc), build_problem(case, comm) as problem:
        u = problem.A.createVecRight()
        comm.Barrier()
        t0, c0 = time.perf_counter(), time.process_time()
        step_forces = []

        def record_force(index, step, u, result, state) -> None:
            forces = contact_resultants(problem, result)
            step_forces.append(np.sum(list(forces["pair_forces"].values()), axis=0).tolist() if case.bodies
                               else forces["contact_force"])

        results = solve_load_path(problem, case.steps, u, parameters, PREFIX, on_step=record_force,
                                  from_rest=from_rest)
        solve_time = comm.allreduce(time.perf_counter() - t0, op=MPI.MAX)
        solve_cpu = comm.allreduce(time.process_time() - c0, op=MPI.SUM)
        wall_time = comm.allreduce(common.clock(), op=MPI.MAX)
        peak = comm.allreduce(common.peak_memory_mib(), op=MPI.SUM)
        result = results[-1]
        displacement = problem.physical_displacement(u, fem.Function(problem.V))
        summary = contact_summary(problem, u, result, displacement=displacement)
        x, values = tables.gather_vertex_values(displacement)
        n_nodes = problem.V.dofmap.index_map.size_global
        # Between bodies: the force of the master bodies on the slave bodies (the obstacles' is zero).
        contact_force = (np.sum(list(summary["pair_forces"].values()), axis=0).tolist() if case.bodies
                         else summary["contact_force"])
        record = {
            "code": "contactqvi (SCD semismooth* Newton)",
            "case": str(pathlib.Path(args.case).resolve()),
            "status": "converged" if result.converged and len(results) == len(case.steps) else str(result.status),
            "dofs": 3 * n_nodes, "free_dofs": problem.n_free, "contact_nodes": problem.n_contact,
            "unknowns": 3 * n_nodes,
            "newton_iterations": sum(r.iterations for r in results),
            "newton_per_step": [r.iterations for r in results],
            "krylov_iterations": sum(r.inner_iterations for r in results),
            "wall_time": wall_time, "solve_time": solve_time, "solve_cpu_time": solve_cpu, "peak_memory_mib": peak,
            "contact_force": contact_force, "contact_force_per_step": step_forces,
            "pair_forces": summary["pair_forces"],
            "reactions": summary["reaction_forces"],
            "equilibrium_error": summary["equilibrium_error"],
            "settings": {"solver": {**parameters, "start": "rest" if from_rest else "contact"},
                         "petsc": dict(case.petsc), "mpi_size": comm.size},
            "threads": 1,
        }
        u.destroy()
    if comm.rank == 0:
        common.write_result(args.output, record, x, values)
        print(f"ours: {record['status']}, {record['newton_iterations']} Newton, {record['solve_time']:.2f} s, "
              f"contact force {np.array2string(np.asarray(record['contact_force']), precision=6)}")
    return 0 if record["status"] == "converged" else 1


if __name__ == "__main__":
    PETSc.Sys.pushErrorHandler("traceback")
    sys.exit(main())
