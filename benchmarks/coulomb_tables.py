"""Reproduce Tables 2, 3 and 4 of seed 000 (Coulomb friction, SCD semismooth* Newton).

Writes ``coulomb_table{2,3,4}.json`` and ``.md`` (ours beside the paper's numbers)
to ``--output``. Runs serially or under ``mpirun``. Examples:

    python benchmarks/coulomb_tables.py --levels 3 4 5 6 7              # default solver (GMRES + GAMG)
    python benchmarks/coulomb_tables.py --tables 2 --levels 3 4 5 --pc lu   # exact inner solves
    python benchmarks/coulomb_tables.py --pc paper                        # GMRES + ILU as in Sect. 7
    python benchmarks/coulomb_tables.py --approximation forward_backward  # the approximation step (6.17) alone
"""

from __future__ import annotations

import benchlib
from benchlib import CASES, run_coulomb_case
from contactqvi.contact.scd_newton import PARAMETERS
from contactqvi.meshes import contact_body_sizes
from contactqvi.problems import coulomb as data


def _markdown_table(title, rows, paper, note):
    cases = CASES
    lines = [f"## {title}", "", note, "",
             "| lev | p | n | " + " | ".join(cases) + " |", "|---|---|---|" + "---|" * len(cases)]
    for lev in sorted({r["lev"] for r in rows}):
        cells = []
        for case in cases:
            r = next((r for r in rows if r["lev"] == lev and r["case"] == case), None)
            ours = "—" if r is None else (f"{r['it']} / {r['krylov']}" if r["status"].startswith("converged") else r["status"])
            ref = paper.get(lev, {}).get(case)
            cells.append(f"{ours} ({ref[0]} / {ref[1]})" if ref else ours)
        sizes = contact_body_sizes(lev)
        lines.append(f"| {lev} | {sizes['p']} | {sizes['n']} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = benchlib.make_parser(__doc__)
    parser.add_argument("--levels", type=int, nargs="+", default=[3, 4, 5, 6, 7])
    parser.add_argument("--tables", type=int, nargs="+", default=[2, 3, 4], choices=[2, 3, 4])
    parser.add_argument("--table4-lev", type=int, default=6, help="level of the tol sweep (paper: 10)")
    PARAMETERS.add_arguments(parser, ["gamma_rule", "approximation", "tol_rule"])
    args, comm, out = benchlib.parse(parser)
    prefix = "bench_"
    tag = "".join(f"_{getattr(args, name)}" for name in ("pc", "gamma_rule", "approximation", "tol_rule")
                  if getattr(args, name) != parser.get_default(name))
    solver = {"tol": 0.1, "pc": args.pc, "gamma_rule": args.gamma_rule, "approximation": args.approximation,
              "tol_rule": args.tol_rule}
    solver_note = {
        "lu": "exact inner solves (LU)",
        "paper": "GMRES + ILU, tol = 0.1 on the left-preconditioned relative residual",
        "gamg": "FGMRES + GAMG set up once, coarse operators Galerkin-updated, tol = 0.1 on the unpreconditioned "
                "relative residual",
        "hypre": "FGMRES + BoomerAMG, tol = 0.1 on the unpreconditioned relative residual",
    }[args.pc]
    if args.tol_rule == "local":
        solver_note += ", Eisenstat-Walker once no contact node changes its kind"
    note = (f"Ours: Newton it / Krylov its, ({solver_note}, u0 = 0 unless nested), "
            "stop at ||y^|| <= 1e-12 ||y^0||; paper's it / gmres in parentheses. MPI ranks per row in the JSON.")

    def emit(name, rows, title, paper):
        """Rows of earlier runs (other levels) are kept."""
        rows = benchlib.merge_rows(out / f"{name}.json", rows, ("lev", "case", "tol"))
        benchlib.emit(comm, out, name, rows, _markdown_table(title, rows, paper, note))

    if 2 in args.tables:
        rows = []
        for lev in args.levels:
            for case in CASES:
                rows.append(run_coulomb_case(comm, lev, case, solver, prefix))
                if comm.rank == 0:
                    r = rows[-1]
                    print(f"table 2{tag}: lev {lev} {r['case']}: {r['status']} {r['it']} / {r['krylov']} "
                          f"in {r['seconds']:.1f} s", flush=True)
            emit(f"coulomb_table2{tag}", rows, f"Table 2{tag.replace('_', ' ')}", data.PAPER_TABLE2)
    if 3 in args.tables:
        rows = []
        coarsest = min(args.levels)
        for lev in [lev for lev in args.levels if lev > coarsest]:
            for case in CASES:
                rows.append(run_coulomb_case(comm, lev, case, solver, prefix, range(coarsest, lev)))
                if comm.rank == 0:
                    r = rows[-1]
                    print(f"table 3{tag}: lev {lev} {r['case']}: {r['status']} {r['it']} / {r['krylov']}", flush=True)
            emit(f"coulomb_table3{tag}", rows, f"Table 3{tag.replace('_', ' ')} (nested start from lev {coarsest})",
                 data.PAPER_TABLE3)
    if 4 in args.tables:
        rows = []
        for tol in sorted(data.PAPER_TABLE4, reverse=True):
            rows.append(run_coulomb_case(comm, args.table4_lev, "d3/L2", {**solver, "tol": tol}, prefix))
        lines = [f"## Table 4{tag.replace('_', ' ')}: d3/L2, u0 = 0, lev {args.table4_lev} (paper: lev 10)", "",
                 "| tol | ours it / Krylov | paper it / gmres (lev 10) |", "|---|---|---|"]
        lines += [f"| {r['tol']:g} | {r['it']} / {r['krylov']} | {data.PAPER_TABLE4[r['tol']][0]} / "
                  f"{data.PAPER_TABLE4[r['tol']][1]} |" for r in rows]
        benchlib.emit(comm, out, f"coulomb_table4{tag}", rows, "\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
