"""Shared pieces of the Coulomb benchmark scripts: machine record, memory, result files.

The rows of a table, a failed run's among them, and reading an earlier run's file back are
:mod:`rows`' (no MPI there, so scripts that start solver processes use it too); ``merge_rows``
is re-exported here.
"""

from __future__ import annotations

import argparse
import os
import pathlib
import platform
import resource
import time
import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

from contactqvi import tables
from rows import merge_rows  # noqa: F401 (the scripts call benchlib.merge_rows)
from contactqvi.cli import parse_args
from contactqvi.contact.driver import solve_level, solve_nested
from contactqvi.contact.scd_newton import PARAMETERS
from contactqvi.laws import Coulomb
from contactqvi.linalg import create_ksp, preset
from contactqvi.problems import coulomb as data
from contactqvi.result import Timings

#: The six cases of Tables 2 and 3 of seed 000.
CASES = [f"{g}/{l}" for g in ("d1", "d2", "d3") for l in ("L1", "L2")]
#: PETSc events reported inside the phases (:func:`phases`).
EVENTS = ("PCSetUp", "KSPSolve", "MatPtAPNumeric", "MatMatMultNum", "MatAXPY", "MatCopy", "MatZeroRowsCol",
          "MatMult", "VecNorm")


def make_parser(doc: str) -> argparse.ArgumentParser:
    """Parser of a benchmark script with the shared options ``--pc`` and ``--output``."""
    parser = argparse.ArgumentParser(description=doc.split("\n")[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter,
                                     epilog="Unknown options starting with '-' are passed to PETSc, under the "
                                            "script's options prefix (e.g. -bench_ksp_monitor).")
    PARAMETERS.add_arguments(parser, ["pc"])
    parser.set_defaults(pc="gamg")  # the rows name their solver (the solver's default is per problem)
    parser.add_argument("--output", default=str(pathlib.Path(__file__).parent / "results"))
    return parser


def parse(parser: argparse.ArgumentParser) -> tuple[argparse.Namespace, MPI.Comm, pathlib.Path]:
    """Parsed arguments (unknown ``-options`` go to PETSc, as in the demos), the communicator and the
    (created) output directory; quiet logging."""
    parser.set_defaults(log_level="WARNING")
    args = parse_args(parser)
    out = pathlib.Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    return args, MPI.COMM_WORLD, out


def machine(comm: MPI.Comm) -> dict:
    """Where a table was measured."""
    cpu = next((line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo") if line.startswith("model name")), "")
    memory_gib = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30
    return {"mpi_size": comm.size, "cpu": cpu, "cores": os.cpu_count(), "memory_gib": round(memory_gib, 1),
            "machine": platform.machine(), "petsc": ".".join(map(str, PETSc.Sys.getVersion()))}


def peak_rss_mib(comm: MPI.Comm, op: MPI.Op = MPI.MAX) -> float:
    """Peak resident memory so far (MiB, from the OS): the largest of any rank, or with
    ``op=MPI.SUM`` the ranks' peaks added (what the job needs at most)."""
    return comm.allreduce(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, op=op)


def emit(comm: MPI.Comm, out: pathlib.Path, name: str, rows: list[dict], markdown: str) -> None:
    """Write ``name.json`` (machine + rows) and ``name.md`` atomically on rank 0 and print the table."""
    tables.write_table(comm, out / name, {"machine": machine(comm), "rows": rows}, markdown)


def event_totals() -> dict[tuple[str, str], tuple[int, float]]:
    """(count, seconds) of every :data:`EVENTS` in every phase's stage so far (this rank)."""
    totals = {}
    for name, stage in Timings._stages.items():
        for event in EVENTS:
            info = PETSc.Log.Event(event).getPerfInfo(stage.id)
            totals[name, event] = (info["count"], info["time"])
    return totals


def phases(comm: MPI.Comm, timings: dict[str, float], before: dict[tuple[str, str], tuple[int, float]]) -> dict:
    """Wall time (largest rank) and the :data:`EVENTS` (count and seconds, largest rank) of every
    phase of ``timings`` (:class:`~contactqvi.result.Timings`, each phase a PETSc log stage)
    since ``before`` (:func:`event_totals`); PETSc's logging must be on (``PETSc.Log.begin()``)."""
    after = event_totals()
    out = {}
    for name, seconds in timings.items():
        events = {}
        for event in EVENTS if name in Timings._stages else ():
            count0, time0 = before.get((name, event), (0, 0.0))
            count = comm.allreduce(after[name, event][0] - count0, op=MPI.MAX)
            if count:
                events[event] = {"count": count,
                                 "seconds": comm.allreduce(after[name, event][1] - time0, op=MPI.MAX)}
        out[name] = {"seconds": comm.allreduce(seconds, op=MPI.MAX), "events": events}
    return out


def run_coulomb_case(
    comm: MPI.Comm,
    lev: int,
    case: str,
    parameters: dict[str, typing.Any],
    prefix: str,
    initial_levels: typing.Iterable[int] | None = None,
) -> dict:
    """Solve one case ``"d3/L2"`` of seed 000 at ``lev`` (nested from ``initial_levels``) and record it."""
    geometry, load = case.split("/")
    kwargs = dict(gap=data.gap_function(geometry), tractions=data.tractions(load), young=data.YOUNG,
                  poisson=data.POISSON, law=Coulomb(data.FRICTION), parameters=parameters, prefix=prefix)
    t0 = time.perf_counter()
    if initial_levels:
        solutions = solve_nested(comm, [*initial_levels, lev], **kwargs)
    else:
        solutions = [solve_level(comm, lev, **kwargs)]
    solution = solutions[-1]
    result = solution.result
    timings = result.timings
    row = {"lev": solution.lev, "case": case, "tol": parameters.get("tol", 0.1), "mpi_size": comm.size,
           "status": str(result.status), "it": result.iterations, "krylov": result.inner_iterations,
           "seconds": time.perf_counter() - t0, "solve_seconds": sum(v for k, v in timings.items() if k != "assembly"),
           "timings": timings, "p": solution.problem.n_contact, "n": solution.problem.n_free,
           "peak_rss_mib": peak_rss_mib(comm), "peak_rss_total_mib": peak_rss_mib(comm, MPI.SUM)}
    release(comm, *solutions)
    return row


def hertz_measures(problem, result) -> tuple[float, float, float]:
    """Hertz's P (N), a (m) and p0 (Pa) of a quarter model's contact ``result``: four times its total
    contact force, a = sqrt(A / pi) with A four times the summed D_ii of the nodes in contact, and
    the largest nodal pressure lambda_i / D_ii. Collective."""
    comm, touching = problem.comm, result.normal_force > 0.0
    force = 4.0 * comm.allreduce(float(result.normal_force.sum()), op=MPI.SUM)
    area = 4.0 * comm.allreduce(float(problem.contact_area[touching].sum()), op=MPI.SUM)
    p0 = comm.allreduce(float((result.normal_force / problem.contact_area).max(initial=0.0)), op=MPI.MAX)
    return force, float(np.sqrt(area / np.pi)), p0


def elastic_solve(problem, prefix: str) -> dict[str, float]:
    """The floor of a contact solve: one elastic solve A u = l of ``problem`` by CG + GAMG with
    the problem's near-nullspace (rigid-body modes of each body) and multigrid options to 1e-12,
    set-up included; Krylov iterations and wall seconds (largest rank). Leaves the
    near-nullspace on ``problem.A``."""
    nullspace = problem.near_nullspace()
    problem.A.setNearNullSpace(nullspace)
    ksp = create_ksp(problem.comm, prefix, preset("cg_gamg", **problem.multigrid_options), A=problem.A, rtol=1e-12)
    x = problem.A.createVecRight()
    problem.comm.Barrier()
    t0 = time.perf_counter()
    ksp.solve(problem.load, x)
    seconds = problem.comm.allreduce(time.perf_counter() - t0, op=MPI.MAX)
    result = {"krylov": ksp.getIterationNumber(), "seconds": seconds}
    release(problem.comm, ksp, x, nullspace)
    return result


def release(comm: MPI.Comm, *objects) -> None:
    """Destroy ``objects`` and the PETSc objects Python dropped meanwhile (collective).

    In parallel, petsc4py defers the destruction of garbage-collected objects to
    ``PETSc.garbage_cleanup``; a script that solves many problems in one process
    must call it, or the memory of every earlier problem stays allocated.
    """
    for obj in objects:
        obj.destroy()
    PETSc.garbage_cleanup(comm)
