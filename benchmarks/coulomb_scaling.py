"""MPI scaling of the Coulomb solve (seed 000): one case at one level, per number of ranks.

Run once per rank count; rows of other rank counts are kept and the speed-up is
taken against the 1-rank row of the same level and case:

    python benchmarks/coulomb_scaling.py --lev 8
    mpirun -n 2 python benchmarks/coulomb_scaling.py --lev 8

Writes ``coulomb_scaling.json`` / ``.md`` to ``--output``.
"""

from __future__ import annotations

import os

import benchlib


def markdown(rows: list[dict]) -> str:
    lines = ["## MPI scaling of the Coulomb solve (u0 = 0, tol = 0.1, stop at 1e-12)", "",
             "Solve = everything after assembly (gamma, approximation steps, Newton matrices, Krylov solves, "
             "line search). Speed-up against 1 rank, same level and case. Memory: peak resident memory of the "
             "largest rank and of all ranks added; B/dof = all ranks' peak / n (benchmarks/coulomb_memory.py "
             "splits it by phase).", "",
             "| lev | n | case | pc | ranks | it / Krylov | assembly s | solve s | speed-up | peak RSS / rank MiB "
             "| peak RSS total MiB | B/dof | PETSC_OPTIONS |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in sorted(rows, key=lambda r: (r["lev"], r["case"], r["pc"], r["mpi_size"])):
        serial = next((s for s in rows
                       if (s["lev"], s["case"], s["pc"], s["mpi_size"]) == (r["lev"], r["case"], r["pc"], 1)), None)
        speedup = f"{serial['solve_seconds'] / r['solve_seconds']:.2f}" if serial else "—"
        total = r.get("peak_rss_total_mib", r["peak_rss_mib"] if r["mpi_size"] == 1 else None)  # older rows
        memory = f"{total:.0f} | {total * 2**20 / r['n']:.0f}" if total else "— | —"
        lines.append(f"| {r['lev']} | {r['n']} | {r['case']} | {r['pc']} | {r['mpi_size']} | {r['it']} / {r['krylov']} "
                     f"| {r['timings']['assembly']:.1f} | {r['solve_seconds']:.1f} | {speedup} "
                     f"| {r['peak_rss_mib']:.0f} | {memory} | {r.get('petsc_options', '')} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = benchlib.make_parser(__doc__)
    parser.add_argument("--lev", type=int, default=8)
    parser.add_argument("--case", default="d3/L2", choices=benchlib.CASES)
    args, comm, out = benchlib.parse(parser)
    row = benchlib.run_coulomb_case(comm, args.lev, args.case, {"pc": args.pc}, "scaling_")
    row["pc"] = args.pc
    row["petsc_options"] = os.environ.get("PETSC_OPTIONS", "")  # e.g. -matptap_via allatonce (leaner, slower set-ups)
    rows = benchlib.merge_rows(out / "coulomb_scaling.json", [row], ("lev", "case", "pc", "mpi_size"))
    benchlib.emit(comm, out, "coulomb_scaling", rows, markdown(rows))


if __name__ == "__main__":
    main()
