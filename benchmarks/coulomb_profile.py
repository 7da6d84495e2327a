"""Where the time of a Coulomb solve goes (seed 000), and what it costs in elastic solves.

Each phase of :class:`~contactqvi.contact.scd_newton.SCDNewtonSolver` is a PETSc log
stage (``Timings.phase``); this script solves cases with PETSc's logging on and
tabulates, per phase, the wall time and the PETSc events that dominate it. On the
same mesh it then times the floor: one linear elastic solve A u = l (CG + GAMG with
the rigid-body near-nullspace, relative residual 1e-12), and reports the Coulomb
solve (everything after assembly, u0 = 0, ||y^|| <= 1e-12 ||y^0||) divided by it:

    python benchmarks/coulomb_profile.py --lev 7 --cases d1/L1
    mpirun -n 2 python benchmarks/coulomb_profile.py --lev 8 --repeat 3

With ``--repeat N`` each case is solved N times and the fastest Coulomb solve and the
fastest elastic solve are compared (run-to-run spread on this machine: about 10 %).

Rows are added to ``coulomb_profile.{json,md}`` in ``--output`` (same version, lev,
case and ranks replaced); ``--version`` names the code measured (rows of other
versions, e.g. the profile before a change, are kept beside).
"""

from __future__ import annotations

import time

from mpi4py import MPI
from petsc4py import PETSc

import benchlib
from contactqvi.contact import SCDNewtonSolver, build_contact_problem
from contactqvi.laws import Coulomb
from contactqvi.meshes import create_contact_body
from contactqvi.problems import coulomb as data

def profile(comm: MPI.Comm, lev: int, case: str, pc: str, version: str, repeat: int) -> dict:
    """One case: the fastest of ``repeat`` Coulomb solves (each from u0 = 0 with a new solver) with its
    phases, beside the fastest of ``repeat`` elastic solves on the same mesh."""
    geometry, load = case.split("/")
    msh, tags = create_contact_body(comm, lev, data.gap_function(geometry))
    problem = build_contact_problem(msh, tags, data.YOUNG, data.POISSON, data.tractions(load), Coulomb(data.FRICTION))
    u = problem.A.createVecRight()
    runs = []
    for _ in range(repeat):
        u.set(0.0)
        before = benchlib.event_totals()
        comm.Barrier()
        t0 = time.perf_counter()
        with SCDNewtonSolver(problem, {"pc": pc}, prefix="profile_") as solver:
            result = solver.solve(u)
        seconds = comm.allreduce(time.perf_counter() - t0, op=MPI.MAX)
        runs.append((seconds, result, benchlib.phases(comm, result.timings, before)))
        PETSc.garbage_cleanup(comm)
    seconds, result, phases = min(runs, key=lambda run: run[0])
    elastic = min((benchlib.elastic_solve(problem, "profile_elastic_") for _ in range(repeat)),
                  key=lambda e: e["seconds"])
    row = {"version": version, "lev": lev, "case": case, "mpi_size": comm.size, "status": str(result.status),
           "it": result.iterations, "krylov": result.inner_iterations, "n": problem.n_free, "repeat": repeat,
           "seconds": seconds, "elastic": elastic, "ratio": seconds / elastic["seconds"], "phases": phases,
           "peak_rss_mib": benchlib.peak_rss_mib(comm)}
    benchlib.release(comm, u, problem)
    return row


def markdown(rows: list[dict]) -> str:
    lines = ["## Coulomb solve against one elastic solve", "",
             "Coulomb: SCD Newton from u0 = 0 to ||y^|| <= 1e-12 ||y^0||, all phases after assembly. Elastic: "
             "A u = l by CG + GAMG (rigid-body near-nullspace) to 1e-12, set-up included. Wall seconds, largest "
             "rank, the fastest of `repeat` runs each; paper's Newton steps (Table 2) in parentheses.", "",
             "| version | lev | ranks | case | it / Krylov | Coulomb s | elastic Krylov / s | Coulomb ÷ elastic |",
             "|---|---|---|---|---|---|---|---|"]
    key = lambda r: (r["version"], r["lev"], r["mpi_size"], r["case"])  # noqa: E731
    for r in sorted((r for r in rows if "ratio" in r), key=key):
        paper = data.PAPER_TABLE2.get(r["lev"], {}).get(r["case"])
        lines.append(f"| {r['version']} | {r['lev']} | {r['mpi_size']} | {r['case']} | {r['it']} / {r['krylov']}"
                     f"{f' ({paper[0]})' if paper else ''} | {r['seconds']:.2f} | {r['elastic']['krylov']} / "
                     f"{r['elastic']['seconds']:.2f} | {r['ratio']:.2f} |")
    lines += ["", "## Coulomb solve by phase (PETSc log stages; wall seconds, largest rank)", "",
              "| version | lev | case | ranks | it / Krylov | phase | seconds | share "
              "| dominant PETSc events (count, s) |",
              "|---|---|---|---|---|---|---|---|---|"]
    for r in sorted(rows, key=lambda r: (r.get("version", ""), r["lev"], r["mpi_size"], r["case"])):
        total = sum(p["seconds"] for name, p in r["phases"].items() if name != "assembly")
        for name, p in r["phases"].items():
            events = ", ".join(f"{e} ({v['count']}, {v['seconds']:.2f})" for e, v in
                               sorted(p["events"].items(), key=lambda kv: -kv[1]["seconds"])[:3])
            share = "" if name == "assembly" else f"{p['seconds'] / total:.0%}"
            lines.append(f"| {r.get('version', '')} | {r['lev']} | {r['case']} | {r['mpi_size']} | {r['it']} / "
                         f"{r['krylov']} | {name} | {p['seconds']:.2f} | {share} | {events} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = benchlib.make_parser(__doc__)
    parser.add_argument("--lev", type=int, default=7)
    parser.add_argument("--cases", nargs="+", default=benchlib.CASES, choices=benchlib.CASES)
    parser.add_argument("--version", default="after", help="name of the code version measured")
    parser.add_argument("--repeat", type=int, default=1, help="solves per case; the fastest counts (both solves)")
    args, comm, out = benchlib.parse(parser)
    PETSc.Log.begin()
    rows = []
    for case in args.cases:
        rows.append(profile(comm, args.lev, case, args.pc, args.version, args.repeat))
        if comm.rank == 0:
            r = rows[-1]
            print(f"lev {args.lev} {case} ({comm.size} ranks): {r['it']} / {r['krylov']}, {r['seconds']:.2f} s, "
                  f"elastic {r['elastic']['seconds']:.2f} s, ratio {r['ratio']:.2f}", flush=True)
    merged = benchlib.merge_rows(out / "coulomb_profile.json", rows, ("version", "lev", "case", "mpi_size"))
    benchlib.emit(comm, out, "coulomb_profile", merged, markdown(merged))


if __name__ == "__main__":
    main()
