"""Where the time of a Coulomb solve goes (seed 000): per phase of the Newton step.

Each phase of :class:`~contactqvi.contact.scd_newton.SCDNewtonSolver` is a PETSc log
stage (``Timings.phase``); this script solves one case with PETSc's logging on and
tabulates, per phase, the wall time and the PETSc events that dominate it:

    python benchmarks/coulomb_profile.py --lev 7 --case d1/L1
    mpirun -n 2 python benchmarks/coulomb_profile.py --lev 8 --case d3/L2

Rows are added to ``coulomb_profile.{json,md}`` in ``--output`` (same lev, case and
ranks replaced).
"""

from __future__ import annotations

from mpi4py import MPI
from petsc4py import PETSc

import benchlib

from contactqvi.result import Timings

#: PETSc events reported inside the phases.
EVENTS = ("PCSetUp", "KSPSolve", "MatMatMultSym", "MatMatMultNum", "MatAXPY", "MatZeroRowsCol", "MatMult", "VecNorm")


def profile(comm: MPI.Comm, lev: int, case: str, pc: str) -> dict:
    PETSc.Log.begin()
    row = benchlib.run_coulomb_case(comm, lev, case, {"pc": pc}, prefix="profile_")
    phases = {}
    for name, seconds in row["timings"].items():
        stage = Timings._stages.get(name)
        events = {}
        if stage is not None:
            for event in EVENTS:
                info = PETSc.Log.Event(event).getPerfInfo(stage.id)
                count = comm.allreduce(info["count"], op=MPI.MAX)
                seconds_max = comm.allreduce(info["time"], op=MPI.MAX)
                if count:
                    events[event] = {"count": count, "seconds": seconds_max}
        phases[name] = {"seconds": comm.allreduce(seconds, op=MPI.MAX), "events": events}
    return {**{k: row[k] for k in ("lev", "case", "mpi_size", "status", "it", "krylov", "n", "peak_rss_mib")},
            "phases": phases}


def markdown(rows: list[dict]) -> str:
    lines = ["## Coulomb solve by phase (PETSc log stages; wall seconds, largest rank)", "",
             "| lev | case | ranks | it / Krylov | phase | seconds | share | dominant PETSc events (count, s) |",
             "|---|---|---|---|---|---|---|---|"]
    for r in sorted(rows, key=lambda r: (r["lev"], r["case"], r["mpi_size"])):
        total = sum(p["seconds"] for name, p in r["phases"].items() if name != "assembly")
        for name, p in r["phases"].items():
            events = ", ".join(f"{e} ({v['count']}, {v['seconds']:.2f})" for e, v in
                               sorted(p["events"].items(), key=lambda kv: -kv[1]["seconds"])[:3])
            share = "" if name == "assembly" else f"{p['seconds'] / total:.0%}"
            lines.append(f"| {r['lev']} | {r['case']} | {r['mpi_size']} | {r['it']} / {r['krylov']} | {name} "
                         f"| {p['seconds']:.2f} | {share} | {events} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = benchlib.make_parser(__doc__)
    parser.add_argument("--lev", type=int, default=7)
    parser.add_argument("--case", default="d1/L1", choices=benchlib.CASES)
    args, comm, out = benchlib.parse(parser)
    rows = benchlib.merge_rows(out / "coulomb_profile.json", [profile(comm, args.lev, args.case, args.pc)],
                               ("lev", "case", "mpi_size"))
    benchlib.emit(comm, out, "coulomb_profile", rows, markdown(rows))


if __name__ == "__main__":
    main()
