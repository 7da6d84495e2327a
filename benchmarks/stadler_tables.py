"""Reproduce the numerical results of seed 002 (Stadler 2004, Sect. 6) with contactqvi.friction.

The runs are those of ``stadler_runs.py`` (beside this script); this script writes them as
``results/stadler_<table>.json``/``.md`` for Q1 (``stadler_<table>_fd``, ``_p1`` for the
paper's finite differences and P1), the paper's numbers beside ours, and ``stadler_summary.md``:
the paper, Q1 and FD side by side, then every table written so far. Discretisations and why
their numbers differ: docs/friction.md.

Run: ``python benchmarks/stadler_tables.py [--discretisation q1|p1|fd] [--tables 6.1 ...] [--quick]``
(``--quick``: small grids, a smoke test; give it another ``--output``). PETSc options of the
solvers go on the command line under their prefixes (``-friction_ksp_view``, ``-uzawa_...``).
"""

from __future__ import annotations

import pathlib
import time
import typing

from mpi4py import MPI

from contactqvi import tables
from contactqvi.cli import make_parser, parse_args
from contactqvi.friction import DISCRETISATIONS
from contactqvi.problems.stadler import PAPER

from rows import read_table
from stadler_runs import TABLES, Cases

RESULTS = pathlib.Path(__file__).resolve().parent / "results"
LABELS = {"q1": "Q1", "p1": "P1", "fd": "FD"}


def table(header: typing.Sequence, rows: typing.Iterable[typing.Sequence]) -> str:
    return tables.markdown_table([str(h) for h in header], rows)


def words(values: typing.Iterable) -> str:
    return " ".join(f"{v:.3g}" if isinstance(v, float) else str(v) for v in values)


def md_6_1(data: dict, label: str) -> str:
    rows = [["paper SS", *data["paper_ss"]], [f"{label} SS", *data["ss"]], [f"{label} PDAS", *data["pdas"]]]
    changes = [[f"{g:.0e}", words(c)] for g, c in zip(data["gamma"], data["ss_changes_per_iteration"])]
    return (f"Example 1, N = {data['N']}: iterations of (SS) and (PDAS, sigma = 1).\n\n"
            f"{table(['gamma', *[f'{g:.0e}' for g in data['gamma']]], rows)}\n"
            f"Nodes changing set in iteration 2, 3, ... of (SS):\n\n{table(['gamma', 'changes'], changes)}")


def md_fig6_1(data: dict, label: str) -> str:
    rows = [[f"{g:.0e}", p, e] for g, p, e in zip(data["gamma"], data["paper_error"], data["error"])]
    return (f"Example 1, N = {data['N']}: |||y_gamma - y_bar|||, y_bar = y_1e16.\n\n"
            f"{table(['gamma', 'paper', label], rows)}\nfitted slope (gamma = 1e2..1e5): {data['slope_1e2_1e5']:.3f}\n")


def md_6_2(data: dict, label: str) -> str:
    header = ["k", *range(1, max(len(data["q"]), len(data["paper_q"])) + 1)]
    rows = [["paper", *data["paper_q"]], [label, *data["q"]]]
    return (f"Example 2, N = {data['N']}, (SS) with gamma = {data['gamma']:g}: q_lambda^k = ||lambda^k - lambda_gamma||"
            f" / ||lambda^(k-1) - lambda_gamma||.\n\n{table(header, rows)}")


def md_6_3(data: dict, label: str) -> str:
    rows = [["paper SS", *data["paper_ss"]], ["paper PDAS", *data["paper_pdas"]]]
    rows += [[f"{label} {m.upper()}, f reading {r}", *data[r][m]] for r in ("x1x2", "x1x1") for m in ("ss", "pdas")]
    return (f"Example 2, N = {data['N']}: iterations of (SS) and (PDAS, sigma = 1); 'div' = no solution found. "
            "Reading x1x2: f = 10(sin 4 pi x1 + cos 4 pi x2); x1x1: f = 10(sin 4 pi x1 + cos 4 pi x1).\n\n"
            f"{table(['gamma', *[f'{g:g}' for g in data['gamma']]], rows)}")  # fmt: skip


def md_alm(data: dict, label: str) -> str:
    parts = [f"N = {data['N']}: (ALM), inner (PDAS) iterations and d_lambda per step l."]
    for gamma, run in ((k, v) for k, v in data.items() if isinstance(v, dict) and "iter" in v):
        rows = [["paper #iter_PD", *run["paper"]["iter"]], [f"{label} #iter_PD", *run["iter"]],
                ["paper d_lambda", *run["paper"]["d"]], [f"{label} d_lambda", *run["d"]]]  # fmt: skip
        steps = max(len(run["iter"]), len(run["paper"]["iter"]))
        parts.append(f"gamma = {gamma}:\n\n{table(['l', *range(1, steps + 1)], rows)}")
    if "exact_alm_solves_to_1e_4" in data:
        rows = [[g, v["outer"], v["linear_solves"], v["status"]] for g, v in data["exact_alm_solves_to_1e_4"].items()]
        parts.append(f"Exact (ALM) until d_lambda < 1e-4 (paper: {PAPER['6.7']['exact_alm_system_solves']}):\n\n"
                     + table(["gamma", "ALM steps", "linear solves incl. initialisation", "status (max 50)"], rows))
    return "\n".join(parts)


def md_6_6(data: dict, label: str) -> str:
    paper, tail = data["paper"], data["tail"]
    rows = []
    for i, N in enumerate(data["N"]):
        rows += [[N, "paper", *[f"{c}{'*' * s}" for c, s in zip(paper["iter"][i], paper["pdas_used"][i])]],
                 [N, f"{label} SS", *data["ss"][i]], [N, f"{label} PDAS", *data["pdas"][i]]]  # fmt: skip
    grids = table(["N", *tail["neighbour_grids"]], [[f"{label} PDAS", *tail["neighbour_grids"].values()]])
    return (f"Example 3 ('*' in the paper: PDAS used because SS chatters).\n\n"
            f"{table(['N', '', *[f'{g:g}' for g in data['gamma']]], rows)}\nPDAS <= 8 everywhere: "
            f"{data['pdas_at_most_8']}. N = {tail['N']}, gamma = {tail['gamma']:g}: {tail['iterations']} iterations; "
            f"nodes changing set in iteration 2, 3, ...: {words(tail['changes'])}; min (g - |lambda|) on I: "
            f"{tail['min_g_minus_abs_lambda_on_I']:.2g}. Neighbouring grids:\n\n{grids}")  # fmt: skip


def md_uzawa(data: dict, label: str) -> str:
    examples, paper = (data["example1"], data["example2"]), data["paper"]["example1_N80"]
    runs = [[n + 1, g, paper.get(g) if n == 0 else None, r["iterations"], r["status"], r["final_d_lambda"]]
            for n, ex in enumerate(examples) for g, r in ex["runs"].items()]  # fmt: skip
    spectra = [[f"Example {n + 1}", *ex["spectra"].values()] for n, ex in enumerate(examples)]
    long_run = ", ".join(f"{k} {words([v])}" for k, v in examples[0]["long_run"].items())
    return (f"Uzawa from lambda^0 = 0 until d_lambda < 1e-4; Example 1: N = {data['example1_N']}, max 1000; "
            f"Example 2: N = {data['example2_N']}, max 400 (paper: {data['paper']['example2_gamma0.2']}).\n\n"
            f"{table(['example', 'gamma', 'paper', label, 'status', 'final d_lambda'], runs)}\n"
            "C_h (4.2) on Gamma_f and on the inactive set I of lambda_bar (power iteration). Uzawa with frozen sets is "
            "Richardson's iteration for C_h on I: stable iff gamma < 2/lambda_max(I).\n\n"
            f"{table(['', '|I|', 'lambda_max, Gamma_f', 'lambda_max, I', 'lambda_min, I'], spectra)}\n"
            f"Example 1 continued past the stopping test: {long_run}\n")  # fmt: skip


MARKDOWN = {"6.1": md_6_1, "fig6.1": md_fig6_1, "6.2": md_6_2, "6.3": md_6_3, "6.4": md_alm, "6.5": md_alm,
            "6.6": md_6_6, "6.7": md_alm, "uzawa": md_uzawa}  # fmt: skip


def _div(count: int | str) -> int | str:
    return count if isinstance(count, int) else "div"


def _uzawa_counts(data: dict) -> str:
    runs = data["example1"]["runs"]
    return words(r["iterations"] if r["status"].startswith("converged") else "no convergence"
                 for r in (runs[g] for g in PAPER_UZAWA))  # fmt: skip


PAPER_UZAWA = PAPER["uzawa"]["example1_N80"]
#: The summary: (row, table, the paper's value, our value from the table's data).
SUMMARY: list[tuple[str, str, str, typing.Callable[[dict], typing.Any]]] = [
    ("6.1: SS, Ex. 1, N = 80, gamma = 1e2 ... 1e8", "6.1", words(PAPER["6.1"]["ss"]), lambda t: words(t["ss"])),
    ("Fig. 6.1: slope of the energy error of y_gamma over gamma = 1e2 ... 1e5", "fig6.1", "-0.99",
     lambda t: f"{t['slope_1e2_1e5']:.2f}"),
    ("6.2: q_lambda^k of SS, Ex. 2, N = 160, gamma = 50", "6.2", words(PAPER["6.2"]["q"]), lambda t: words(t["q"])),
    ("6.3: PDAS, Ex. 2, N = 160, gamma = 3 ... 1e10", "6.3", words(PAPER["6.3"]["pdas"]),
     lambda t: words(t["x1x2"]["pdas"])),
    ("6.3: SS, same gamma", "6.3", words(PAPER["6.3"]["ss"]), lambda t: words(map(_div, t["x1x2"]["ss"]))),
    *[(f"6.4: exact ALM, #iter_PD per step, gamma = {g}", "6.4", words(PAPER["6.4"][g]["iter"]),
       lambda t, g=g: words(t[g]["iter"])) for g in ("1e2", "1e4")],
    *[(f"6.5: inexact ALM, #iter_PD per step, gamma = {g}", "6.5", words(PAPER["6.5"][g]["iter"]),
       lambda t, g=g: words(t[g]["iter"])) for g in ("1e2", "1e4", "10^l")],
    ("6.5: d_lambda at l = 6, gamma = 10^l", "6.5", "1.14e-12", lambda t: f"{t['10^l']['d'][5]:.2e}"),
    ("6.6: PDAS, Ex. 3, N = 320, gamma = 5 ... 1e10", "6.6", words(PAPER["6.6"]["iter"][-1]),
     lambda t: words(t["pdas"][-1])),
    ("6.6: largest PDAS count, N = 20 ... 320", "6.6", "8",
     lambda t: max(c for row in t["pdas"] for c in row if isinstance(c, int))),
    ("6.7: inexact ALM, #iter_PD per step, gamma = 10^l", "6.7", words(PAPER["6.7"]["10^l"]["iter"]),
     lambda t: words(t["10^l"]["iter"])),
    ("6.7: exact ALM, system solves to d_lambda < 1e-4, gamma = 50", "6.7", "16",
     lambda t: t["exact_alm_solves_to_1e_4"]["50"]["linear_solves"]),
    ("Uzawa, Ex. 1, N = 80, gamma = 10, 20, 30", "uzawa", words(PAPER_UZAWA.values()), _uzawa_counts),
]  # fmt: skip


def stem(name: str, discretisation: str) -> str:
    return "stadler_" + name.replace(".", "_") + ("" if discretisation == "q1" else f"_{discretisation}")


def summary(out: pathlib.Path) -> str:
    """The paper beside Q1 and FD (from the JSON files in ``out``), then every table written so far."""

    def value(name: str, d: str, extract: typing.Callable[[dict], typing.Any]) -> typing.Any:
        data = read_table(out / f"{stem(name, d)}.json")
        return extract(data) if data else None

    rows = [[row, paper, value(name, "q1", f), value(name, "fd", f)] for row, name, paper, f in SUMMARY]
    parts = [out / f"{stem(name, d)}.md" for name in TABLES for d in DISCRETISATIONS]
    return (
        "# Seed 002 (Stadler 2004): paper vs contactqvi\n\nQ1: bilinear finite elements with a lumped boundary mass; "
        "FD: the paper's five-point finite differences (`contactqvi/friction/finite_differences.py`), same solvers. "
        "Counts: linear solves after the initialisation. Why the numbers differ: docs/friction.md.\n\n"
        f"{table(['', 'paper', 'Q1', 'FD'], rows)}\n" + "\n".join(p.read_text() for p in parts if p.is_file())
    )


def main(argv: list[str] | None = None) -> None:
    parser = make_parser(__doc__.split("\n")[0], str(RESULTS), petsc_example="-friction_ksp_view")
    parser.set_defaults(log_level="WARNING")
    parser.add_argument("--tables", nargs="*", default=list(TABLES), choices=list(TABLES))
    parser.add_argument("--discretisation", default="q1", choices=DISCRETISATIONS, help="q1/p1 FE or the paper's FD")
    parser.add_argument("--quick", action="store_true", help="small grids (a smoke test, not the paper's N)")
    args = parse_args(parser, argv)
    comm, label = MPI.COMM_WORLD, LABELS[args.discretisation]
    out = tables.prepare_output_dir(comm, args.output)
    with Cases(args.discretisation, args.quick) as cases:
        for name in args.tables:
            start = time.perf_counter()
            data = TABLES[name](cases)
            data.update(discretisation=args.discretisation, quick=args.quick, seconds=time.perf_counter() - start,
                        mpi_ranks=comm.size)  # fmt: skip
            title = f"## Seed 002 {'Table ' * name[0].isdigit()}{name}, {label}{' (quick)' * args.quick}"
            markdown = f"{title}\n\n{MARKDOWN[name](data, label)}\n"
            tables.write_table(comm, out / stem(name, args.discretisation), data, markdown)
    with tables.atomic_path(comm, out / "stadler_summary.md") as tmp:
        if comm.rank == 0:
            tmp.write_text(summary(out))


if __name__ == "__main__":
    main()
